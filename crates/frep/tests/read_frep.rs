//! The frepray `.frep` syntax: the documented examples, the shapes each construct
//! builds, and errors with positions.

use crate::common;
use common::*;

/// The code blocks marked `frep` in docs/frep-syntax.md.
fn doc_examples() -> Vec<String> {
    let doc = std::fs::read_to_string(root().join("docs/frep-syntax.md")).unwrap();
    let mut out = Vec::new();
    let mut cur: Option<String> = None;
    for line in doc.lines() {
        match (&mut cur, line.trim_start()) {
            (None, "```frep") => cur = Some(String::new()),
            (Some(_), "```") => out.push(cur.take().unwrap()),
            (Some(s), _) => {
                s.push_str(line);
                s.push('\n');
            }
            _ => {}
        }
    }
    out
}

#[test]
fn frep_doc_and_example_files_load() {
    let examples = doc_examples();
    assert!(examples.len() >= 5, "found {} examples", examples.len());
    for (i, text) in examples.iter().enumerate() {
        let m = read_str(text, Format::Frep, &format!("doc example {i}"))
            .unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert!(expr(&m).eval([0.05, 0.1, 0.2]).is_finite(), "{text}");
    }
    // The shipped examples, named (a user's own model saved there is not tested).
    for name in ["bumpy_ball", "machined_part", "smooth_blob"] {
        let path = root()
            .join("models/examples")
            .join(name)
            .with_extension("frep");
        let m = read_file(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(m.domain.is_some(), "{path:?} declares bounds");
    }
}

fn frep(text: &str) -> Model {
    read_str(text, Format::Frep, "t.frep").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

#[test]
fn frep_builds_the_right_shapes() {
    // The bumpy ball stays a perturbed quadric with its two perturbations.
    let m = frep(doc_examples().iter().find(|t| t.contains("bumpy")).unwrap());
    let Shape::Perturbed(pq) = &m.shape else {
        panic!("{:?}", m.shape)
    };
    assert_eq!(pq.perturbations().len(), 2);
    assert_eq!(
        (pq.perturbations()[0].f, pq.perturbations()[1].f),
        (0.4, -0.8)
    );
    agree(
        &m,
        |p| pq.eval(glam::DVec3::from_array(p)),
        1.5,
        "bumpy ball",
    );
    // Exact CSG keeps its structure; R-functions and arithmetic lower to functions.
    let m = frep("let a = sphere([0,0,0], 1)\nlet b = plane(z, 0.5)\noutput difference(a, b)");
    assert!(matches!(m.shape, Shape::Difference(..)));
    agree(
        &m,
        |[x, y, z]| (1.0 - x * x - y * y - z * z).min(-(0.5 - z)),
        1.5,
        "difference",
    );
    let m = frep("output r_union(sphere([0,0,0], 1), x, alpha = 0.5)");
    assert!(matches!(m.shape, Shape::Function { .. }));
    agree(
        &m,
        |[x, y, z]| {
            let a = 1.0 - x * x - y * y - z * z;
            (a + x + (a * a + x * x - a * x).sqrt()) / 1.5
        },
        1.5,
        "r_union",
    );
    // Quadric arithmetic stays a quadric; transforms move the solid.
    let m = frep("let q = 2 * ellipsoid([0,0,0], [1, 2, 3]) - 1\noutput q");
    assert!(matches!(m.shape, Shape::Perturbed(_)));
    agree(
        &m,
        |[x, y, z]| 2.0 * (1.0 - x * x - y * y / 4.0 - z * z / 9.0) - 1.0,
        2.0,
        "quadric arithmetic",
    );
    let m = frep("output rotate_z(90, translate([1, 0, 0], sphere([0,0,0], 0.5)))");
    assert!(matches!(m.shape, Shape::Transformed(..)));
    let e = expr(&m);
    // The ball of radius 0.5 about (1, 0, 0) is now about (0, 1, 0).
    assert!(e.eval([0.0, 1.0, 0.0]) > 0.0 && e.eval([1.0, 0.0, 0.0]) < 0.0);
    assert!(e.eval([0.0, 1.5, 0.0]).abs() < 1e-12 && e.eval([-0.5, 1.0, 0.0]).abs() < 1e-12);
    let m = frep("let s = scale([2, 1, 1], sphere([0,0,0], 1))\nlet t = affine([2,0,0, 0,1,0, 0,0,1], [0,0,1], sphere([0,0,0], 1))\noutput union(s, t)");
    agree(
        &m,
        |[x, y, z]| {
            (1.0 - x * x / 4.0 - y * y - z * z).max(1.0 - x * x / 4.0 - y * y - (z - 1.0).powi(2))
        },
        2.0,
        "scale/affine",
    );
    // Functions, named arguments, powers, bounds.
    let m = frep("let ring(r, w) = w^2 - (sqrt(x^2 + y^2) - r)^2 - z^2\nbounds([-2,-2,-1], [2,2,1])\noutput ring(w = 0.2, r = 1)");
    assert_eq!(m.name, None);
    let d = m.domain.unwrap();
    assert_eq!((d.lo.x, d.hi.z), (-2.0, 1.0));
    assert!(matches!(
        m.shape,
        Shape::Function {
            domain: Some(_),
            ..
        }
    ));
    agree(
        &m,
        |[x, y, z]| 0.04 - ((x * x + y * y).sqrt() - 1.0).powi(2) - z * z,
        2.0,
        "user function",
    );
    agree(
        &frep("output x^-2 + -y^2 + pow(2, 3) + min(x, y, z) + mod(x, 0.3)"),
        |[x, y, z]| 1.0 / (x * x) - y * y + 8.0 + x.min(y).min(z) + x.rem_euclid(0.3),
        2.0,
        "math",
    );
}

#[test]
fn frep_errors_have_positions() {
    let deep = format!("output {}x{}", "(".repeat(3000), ")".repeat(3000));
    let unary = format!("output {}x", "-".repeat(3000));
    let recursive = "let f(a) = f(a) + 1\noutput f(x)";
    check_errors(
        Format::Frep,
        &[
            (
                "let a = 1\noutput a",
                2,
                8,
                "expected a solid, found a number",
            ),
            (
                "output union(sphere([0,0,0], 1), 2)",
                1,
                34,
                "expected a solid, found a number",
            ),
            ("output spere([0,0,0], 1)", 1, 8, "unknown function 'spere'"),
            ("let a = b + 1\noutput a", 1, 9, "undefined name 'b'"),
            (
                "output sphere([0,0,0], 1, 2)",
                1,
                27,
                "expected at most 2 arguments for sphere(center, radius)",
            ),
            (
                "output sphere([0,0,0])",
                1,
                8,
                "expected an argument 'radius'",
            ),
            (
                "output sphere(centre = [0,0,0], radius = 1)",
                1,
                24,
                "found 'centre'",
            ),
            (
                "output sphere([0,0,0], radius = 1, radius = 2)",
                1,
                45,
                "found 'radius' twice",
            ),
            (
                "output sphere(1, 1)",
                1,
                15,
                "expected a list of 3 numbers, found a number",
            ),
            ("output sphere([0,0], 1)", 1, 15, "found a list of 2"),
            ("let a = 1.2.3", 1, 9, "malformed number '1.2.3'"),
            (
                "output sphere([0,0,0], 1",
                1,
                25,
                "expected ')', found the end of the file",
            ),
            (
                "output (x + y))",
                1,
                15,
                "expected 'let', 'bounds' or 'output', found ')'",
            ),
            (
                "let a =",
                1,
                8,
                "expected an expression, found the end of the file",
            ),
            ("let a = x", 1, 5, "expected an 'output' statement"),
            ("let x = 1\noutput x", 1, 5, "'x', a coordinate"),
            (
                "let a = x\nlet a = y\noutput a",
                2,
                5,
                "'a', already defined",
            ),
            ("output x^0.5", 1, 9, "expected a whole-number exponent"),
            (
                "output perturb(sphere([0,0,0], 1), sphere([1,0,0], 1))",
                1,
                36,
                "expected a perturbation term f * q^3, found a quadric",
            ),
            ("output scale(0, sphere([0,0,0], 1))", 1, 8, "singular"),
            ("output x\noutput y", 2, 1, "found a second"),
            ("output [1, x]", 1, 12, "expected a number in a list"),
            ("output x + [1, 2]", 1, 10, "found a list"),
            (&deep, 1, 208, "at most 200 levels of nesting"),
            (&unary, 1, 208, "at most 200 levels of nesting"),
            (recursive, 1, 12, "nested at most 200 deep"),
        ],
    );
}

#[test]
fn read_file_reports_unreadable_files() {
    let e = read_file(&root().join("models/no_such_model.frep")).unwrap_err();
    assert_eq!((e.line, e.column), (0, 0));
    assert!(e.message.contains("cannot read"), "{e}");
    let e = read_file(&root().join("docs/frep-syntax.md")).unwrap_err();
    assert_eq!((e.line, e.column), (0, 0));
    assert!(e.message.contains(".frep, .hf or .vm"), "{e}");
}

/// A model path naming a device, pipe or folder is refused before it is opened:
/// `/dev/zero` reports length 0 and then never ends (read, it filled memory), and a FIFO
/// blocks the reader for ever. Scenes name model files, so a scene could do either.
#[cfg(unix)]
#[test]
fn read_file_refuses_devices_pipes_and_folders() {
    let dir = std::env::temp_dir().join(format!("frep-read-special-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let zero = dir.join("zero.frep");
    let _ = std::fs::remove_file(&zero);
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let folder = dir.join("folder.vm");
    std::fs::create_dir_all(&folder).unwrap();
    for p in [&zero, &folder] {
        let e = read_file(p).unwrap_err();
        assert_eq!((e.line, e.column), (0, 0));
        assert!(e.message.contains("found a folder, device or pipe"), "{e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A solid bound by `let` and used many times in arithmetic is lowered to a tree once:
/// this 51 kB model (like one `fuzz/run.sh frep` found) took 16 s when every `-b`
/// lowered `b` again, quadratic in the file; now about 30 ms.
#[test]
fn a_solid_used_many_times_is_lowered_once() {
    let b = format!(
        "let b = rotate_z(30, sphere([0, 0, 0], 1) {})\n",
        "+ x * 0.001 ".repeat(3000)
    );
    let g = format!("let g = {}\noutput g\n", vec!["-b"; 3000].join(" + "));
    let t = std::time::Instant::now();
    let m = frep(&(b + &g));
    assert!(t.elapsed().as_secs_f64() < 5.0, "took {:?}", t.elapsed());
    assert!(expr(&m).eval([0.0, 0.0, 0.0]).is_finite());
}

/// Work grows without bound in a few lines when a function calls another twice per level
/// or a solid is copied into a union with itself level after level: 2^25 calls ran for
/// minutes, 2^22 parts took seconds and memory (found while fuzzing). Evaluation has a work
/// limit (a million steps for a small file) and says so.
#[test]
fn exponential_models_stop_at_the_work_limit() {
    let calls: String = (1..26)
        .map(|i| format!("let f{i}(t) = f{}(t) * f{}(t)\n", i - 1, i - 1))
        .collect();
    let calls = format!("let f0(t) = t + 1\n{calls}output f25(x)\n");
    let parts: String = (1..40)
        .map(|i| format!("let s{i} = union(s{}, s{})\n", i - 1, i - 1))
        .collect();
    let parts = format!("let s0 = sphere([0, 0, 0], 1)\n{parts}output s39\n");
    let nested = format!(
        "let f(s) = {}s{}\noutput {}sphere([0, 0, 0], 1){}\n",
        "rotate_z(1, ".repeat(100),
        ")".repeat(100),
        "f(".repeat(150),
        ")".repeat(150)
    );
    for text in [calls, parts, nested] {
        let t = std::time::Instant::now();
        let e = read_str(&text, Format::Frep, "t.frep").unwrap_err();
        assert!(e.message.contains("within 1000000 steps"), "{e}");
        assert!(t.elapsed().as_secs_f64() < 5.0, "took {:?}", t.elapsed());
    }
}

/// A recursive function whose body nests deeply overflowed the stack (found by fuzzing:
/// 200 calls of a body 40 levels deep). Nesting through expressions and calls together
/// is capped, within the 2 MB stack of a spawned thread.
#[test]
fn deep_recursion_through_nested_bodies_is_an_error() {
    for k in [40, 190] {
        let text = format!(
            "let post(h) = intersection(cylinder(z, 0.1), {}post(1.5))\noutput post(1)\n",
            "-".repeat(k)
        );
        let e = std::thread::Builder::new()
            .stack_size(2 << 20)
            .spawn(move || read_str(&text, Format::Frep, "t.frep").unwrap_err())
            .unwrap()
            .join()
            .unwrap();
        assert!(e.message.contains("nested at most 1000 deep in all"), "{e}");
    }
}

/// `torus` is r² − (ρ − R)² − h², ρ the distance from its axis and h the height along
/// it, at every point and for any axis; about a coordinate axis each coordinate appears
/// once, so its interval over a box is the exact range (ρ's and h's ranges over the box
/// are exact, and F is monotone in each of (ρ − R)² and h²).
#[test]
fn torus_is_bounded_exactly_about_a_coordinate_axis() {
    use glam::DVec3;
    let (big, r) = (0.8, 0.25);
    for (axis, a) in [
        ("z", DVec3::Z),
        ("x", DVec3::X),
        ("[0, -1, 0]", -DVec3::Y),
        ("[1, 2, 2]", DVec3::new(1.0, 2.0, 2.0) / 3.0),
    ] {
        let c = DVec3::new(0.1, -0.2, 0.3);
        let m = frep(&format!(
            "output torus({big}, {r}, center = [0.1, -0.2, 0.3], axis = {axis})"
        ));
        agree(
            &m,
            |p| {
                let d = DVec3::from_array(p) - c;
                let h = d.dot(a);
                let rho = (d - h * a).length();
                r * r - (rho - big).powi(2) - h * h
            },
            1.5,
            axis,
        );
    }
    let m = frep(&format!("output torus({big}, {r})"));
    let e = expr(&m);
    let mut rng = rand_pcg::Pcg64::new(0xcafe, 0xf00d);
    use rand::Rng;
    for k in 0..500 {
        let lo = DVec3::new(
            rng.gen_range(-1.2..1.0),
            rng.gen_range(-1.2..1.0),
            rng.gen_range(-0.5..0.4),
        );
        let hi = lo
            + DVec3::new(
                rng.gen_range(0.0..0.4),
                rng.gen_range(0.0..0.4),
                rng.gen_range(0.0..0.3),
            );
        // ρ over the box's (x, y) rectangle, then (ρ − R)² and z².
        let rho = rho_range((lo.x, hi.x), (lo.y, hi.y));
        let (ring, h) = (sq_range(rho.0, rho.1, big), sq_range(lo.z, hi.z, 0.0));
        let (min, max) = (r * r - ring.1 - h.1, r * r - ring.0 - h.0);
        let got = e.eval_interval(lo.to_array(), hi.to_array());
        let tol = 1e-12;
        assert!(
            (got.lo - min).abs() <= tol && (got.hi - max).abs() <= tol,
            "box {k} {lo} – {hi}: {got:?}, exact [{min}, {max}]"
        );
    }
}
