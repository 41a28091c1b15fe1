//! The HyperFun reader: the canonical scenes, the common library against its
//! definitions, the language core, and errors with positions.

use crate::common;
use common::*;

fn hf(text: &str) -> Model {
    read_str(text, Format::HyperFun, "t.hf").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

#[test]
fn hf_canonical_scenes_match_the_formulas() {
    let s3 = |p: [f64; 3]| {
        let a = norm([p[0] - 0.45, p[1], p[2]]) - 0.7;
        let b = norm([p[0] + 0.45, p[1], p[2]]) - 0.7;
        let h = (0.25 - (a - b).abs()).max(0.0) / 0.25;
        a.min(b) - h.powi(3) * 0.25 / 6.0
    };
    let s4 = |[x, y, z]: [f64; 3]| {
        let g = (3.0 * x).sin() * (3.0 * y).cos()
            + (3.0 * y).sin() * (3.0 * z).cos()
            + (3.0 * z).sin() * (3.0 * x).cos()
            - 0.2;
        g.max(norm([x, y, z]) - 1.4)
    };
    let s5 = |[x, y, z]: [f64; 3]| {
        let w = 1.2 * z;
        let (xt, yt) = (x * w.cos() + y * w.sin(), -x * w.sin() + y * w.cos());
        (xt.abs() - 0.35).max(yt.abs() - 0.35).max(z.abs() - 1.1)
    };
    let scenes: [(&str, &Field); 5] = [
        ("s1_sphere", &|p| norm(p) - 1.0),
        ("s2_csg", &|p| {
            (p[0].abs().max(p[1].abs()).max(p[2].abs()) - 0.9).max(-(norm(p) - 1.1))
        }),
        ("s3_blend", &s3),
        ("s4_gyroid", &s4),
        ("s5_twist", &s5),
    ];
    for (name, f) in scenes {
        let m = read_file(&root().join(format!("models/canonical/{name}.hf")))
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.name.as_deref(), Some(name));
        agree(&m, |p| -f(p), 1.6, name);
    }
}

/// Reads `m(x[3], a[1]) { BODY m = RESULT; }`.
fn hf_model(body: &str, result: &str) -> Model {
    hf(&format!("m(x[3], a[1])\n{{\n{body}\nm = {result};\n}}\n"))
}

/// Squared length of a point's components other than axis `k`, and of all three.
fn sq2(q: [f64; 3], k: usize) -> f64 {
    (0..3).filter(|&i| i != k).map(|i| q[i] * q[i]).sum()
}

fn sq3(q: [f64; 3]) -> f64 {
    q.iter().map(|v| v * v).sum()
}

/// The blend displacement of hfBlendUni/hfBlendInt with a0 = 0.5, a1 = 0.8, a2 = 0.9.
fn disp(p: [f64; 3]) -> f64 {
    0.5 / (1.0 + (p[0] / 0.8).powi(2) + (p[1] / 0.9).powi(2))
}

fn block(p: [f64; 3]) -> f64 {
    let c = [0.1, -0.2, 0.3];
    let s: Vec<f64> = (0..3)
        .map(|i| (p[i] - c[i]) * (c[i] + [0.5, 0.6, 0.7][i] - p[i]))
        .collect();
    let f = s[0] + s[1] - (s[0] * s[0] + s[1] * s[1]).sqrt();
    f + s[2] - (f * f + s[2] * s[2]).sqrt()
}

fn superell(q: [f64; 3]) -> f64 {
    let (xt, yt, zt) = ((q[0] / 0.6).abs(), (q[1] / 0.7).abs(), (q[2] / 0.8).abs());
    1.0 - (xt + yt).powi(4) - zt.powi(4)
}

/// HyperFun's inverse rotation of (u, v) by t.
fn rot(u: f64, v: f64, t: f64) -> (f64, f64) {
    (u * t.cos() + v * t.sin(), -u * t.sin() + v * t.cos())
}

/// The twist angle of hfTwist*(x, -1, 1, 0.2, 1.5) at coordinate s.
fn twist(s: f64) -> f64 {
    let t = (s + 1.0) / 2.0;
    (1.0 - t) * 0.2 + t * 1.5
}

/// The scale of hfTaper*(x, -0.5, 0.5, 0.5, 2) at coordinate s.
fn taper(s: f64) -> f64 {
    let t = (s + 0.5).clamp(0.0, 1.0);
    (1.0 - t) * 0.5 + t * 2.0
}

#[test]
fn hf_library_matches_its_definitions() {
    // Each primitive as a function of q = p − c (c = (0.1, −0.2, 0.3)) and of p.
    type Prim = fn([f64; 3], [f64; 3]) -> f64;
    let prims: [(&str, Prim); 15] = [
        ("hfSphere(x, c, 0.8)", |q, _| 0.64 - sq3(q)),
        ("hfEllipsoid(x, c, 0.5, 0.7, 0.9)", |q, _| {
            1.0 - (q[0] / 0.5).powi(2) - (q[1] / 0.7).powi(2) - (q[2] / 0.9).powi(2)
        }),
        ("hfCylinderX(x, c, 0.4)", |q, _| 0.16 - sq2(q, 0)),
        ("hfCylinderY(x, c, 0.4)", |q, _| 0.16 - sq2(q, 1)),
        ("hfCylinderZ(x, c, 0.4)", |q, _| 0.16 - sq2(q, 2)),
        ("hfConeX(x, c, 0.5)", |q, _| q[0] * q[0] - sq2(q, 0) / 0.25),
        ("hfConeY(x, c, 0.5)", |q, _| q[1] * q[1] - sq2(q, 1) / 0.25),
        ("hfConeZ(x, c, 0.5)", |q, _| q[2] * q[2] - sq2(q, 2) / 0.25),
        ("hfTorusX(x, c, 0.7, 0.2)", |q, _| {
            0.04 - sq3(q) - 0.49 + 1.4 * sq2(q, 0).sqrt()
        }),
        ("hfTorusY(x, c, 0.7, 0.2)", |q, _| {
            0.04 - sq3(q) - 0.49 + 1.4 * sq2(q, 1).sqrt()
        }),
        ("hfTorusZ(x, c, 0.7, 0.2)", |q, _| {
            0.04 - sq3(q) - 0.49 + 1.4 * sq2(q, 2).sqrt()
        }),
        ("hfBlock(x, c, 0.5, 0.6, 0.7)", |_, p| block(p)),
        ("hfSuperell(x, c, 0.6, 0.7, 0.8, 0.5, 2)", |q, _| {
            superell(q)
        }),
        ("hfBlendUni(x[1], x[2], 0.5, 0.8, 0.9)", |_, p| {
            p[0] + p[1] + sq2(p, 2).sqrt() + disp(p)
        }),
        ("hfBlendInt(x[1], x[2], 0.5, 0.8, 0.9)", |_, p| {
            p[0] + p[1] - sq2(p, 2).sqrt() + disp(p)
        }),
    ];
    for (call, f) in prims {
        let m = hf_model("array c[3]; c = [0.1, -0.2, 0.3];", call);
        agree(
            &m,
            |p| f([p[0] - 0.1, p[1] + 0.2, p[2] - 0.3], p),
            1.5,
            call,
        );
    }
    // Space mappings overwrite the coordinate array with the inverse mapping.
    type Map = fn([f64; 3]) -> [f64; 3];
    let maps: [(&str, Map); 11] = [
        ("hfShift3D(x, 0.1, 0.2, 0.3)", |p| {
            [p[0] - 0.1, p[1] - 0.2, p[2] - 0.3]
        }),
        ("hfScale3D(x, 2, 0.5, 4)", |p| {
            [p[0] / 2.0, p[1] / 0.5, p[2] / 4.0]
        }),
        ("hfRotate3DX(x, 0.7)", |p| {
            let (a, b) = rot(p[1], p[2], 0.7);
            [p[0], a, b]
        }),
        ("hfRotate3DY(x, 0.7)", |p| {
            let (b, a) = rot(p[2], p[0], 0.7);
            [a, p[1], b]
        }),
        ("hfRotate3DZ(x, 0.7)", |p| {
            let (a, b) = rot(p[0], p[1], 0.7);
            [a, b, p[2]]
        }),
        ("hfTwistX(x, -1, 1, 0.2, 1.5)", |p| {
            let (a, b) = rot(p[1], p[2], twist(p[0]));
            [p[0], a, b]
        }),
        ("hfTwistY(x, -1, 1, 0.2, 1.5)", |p| {
            let (b, a) = rot(p[2], p[0], twist(p[1]));
            [a, p[1], b]
        }),
        ("hfTwistZ(x, -1, 1, 0.2, 1.5)", |p| {
            let (a, b) = rot(p[0], p[1], twist(p[2]));
            [a, b, p[2]]
        }),
        ("hfTaperX(x, -0.5, 0.5, 0.5, 2)", |p| {
            [p[0], p[1] / taper(p[0]), p[2] / taper(p[0])]
        }),
        ("hfTaperY(x, -0.5, 0.5, 0.5, 2)", |p| {
            [p[0] / taper(p[1]), p[1], p[2] / taper(p[1])]
        }),
        ("hfTaperZ(x, -0.5, 0.5, 0.5, 2)", |p| {
            [p[0] / taper(p[2]), p[1] / taper(p[2]), p[2]]
        }),
    ];
    for (call, f) in maps {
        for k in 0..3 {
            let m = hf_model(&format!("done = {call};"), &format!("x[{}] * done", k + 1));
            agree(&m, |p| f(p)[k], 1.5, &format!("{call} component {}", k + 1));
        }
    }
}

#[test]
fn hf_language_core() {
    // Conditions on known values run; conditions on x lower to a select; loops unroll.
    let m = hf_model(
        "if x[1] > 0 then v = x[1]^2; else v = -x[2]; endif;\n\
         i = 0; acc = 0;\n\
         while i < 5 loop i = i + 1; acc = acc + i * x[3]; endloop;\n\
         array b[3]; b = [1, -2, 3.5]; b[1] = b[1] + 1;\n\
         if b[2] < 0 and not (b[1] = 1) then w = b[3]; else w = 0; endif;",
        "v + acc + w",
    );
    agree(
        &m,
        |[x, y, z]| if x > 0.0 { x * x } else { -y } + 15.0 * z + 3.5,
        1.0,
        "if/while/array",
    );
    // Set operators with the default ALPHA = 0, and ALPHA assigned.
    let f = |[x, y, _]: [f64; 3]| (x, y);
    let r = |a: f64, b: f64, al: f64, s: f64| {
        (a + b + s * (a * a + b * b - 2.0 * al * a * b).sqrt()) / (1.0 + al)
    };
    agree(
        &hf_model("", "x[1] | x[2]"),
        |p| {
            let (a, b) = f(p);
            r(a, b, 0.0, 1.0)
        },
        1.0,
        "|",
    );
    agree(
        &hf_model("", "x[1] & x[2]"),
        |p| {
            let (a, b) = f(p);
            r(a, b, 0.0, -1.0)
        },
        1.0,
        "&",
    );
    agree(
        &hf_model("", "x[1] \\ x[2]"),
        |p| {
            let (a, b) = f(p);
            r(a, -b, 0.0, -1.0)
        },
        1.0,
        "\\",
    );
    agree(
        &hf_model("alpha = 0.5;", "x[1] | ~x[2]"),
        |p| {
            let (a, b) = f(p);
            r(a, -b, 0.5, 1.0)
        },
        1.0,
        "ALPHA",
    );
    // Powers, built-ins and precedence (set operators bind like +).
    agree(
        &hf_model("", "x[1]^2^3 + x[2]^-2 + (x[3]^2 + 1)^0.5 - -x[1]^2"),
        |[x, y, z]| x.powi(6) + 1.0 / (y * y) + (z * z + 1.0).sqrt() - x * x,
        1.0,
        "powers",
    );
    agree(&hf_model("", "sinh(x[1]) + cosh(x[2]) + tanh(3*x[3]) + logd(2 + x[1]) + sign(x[2]) + int(3*x[3]) + frac(3*x[1]) + mod(7*x[1], 3)"), |[x, y, z]| {
        let hround = |v: f64| (v + 0.5).floor();
        x.sinh() + y.cosh() + (3.0 * z).tanh() + (2.0 + x).log10() + if y < 0.0 { -1.0 } else { 1.0 } + (3.0 * z).trunc() + (3.0 * x).fract() + hround(7.0 * x) % hround(3.0)
    }, 1.0, "built-ins");
    agree(
        &hf_model("", "x[1] + 1 | x[2]"),
        |[x, y, _]| r(x + 1.0, y, 0.0, 1.0),
        1.0,
        "precedence",
    );
    // Calls of another model of the file; the last model is the one read.
    let m = hf("ball(x[3], a[1]) { ball = a[1] - x[1]^2 - x[2]^2 - x[3]^2; }\n\
                Main(x[3], a[1]) { array q[1], xx[3]; q[1] = 2; xx[1] = x[1] - 1; xx[2] = x[2]; xx[3] = x[3];\n\
                MAIN = ball(xx, q) + ball(x, a); }");
    assert_eq!(m.name.as_deref(), Some("main"));
    agree(
        &m,
        |[x, y, z]| 2.0 - (x - 1.0).powi(2) - y * y - z * z - (x * x + y * y + z * z),
        1.0,
        "model call",
    );
}

#[test]
fn hf_errors_have_positions() {
    let deep = format!(
        "m(x[3], a[1]) {{ m = {}x[1]{}; }}",
        "(".repeat(5000),
        ")".repeat(5000)
    );
    let deep_if = format!(
        "m(x[3], a[1]) {{ {} m = 1; {} }}",
        "if 1 then ".repeat(500),
        "endif; ".repeat(500)
    );
    check_errors(
        Format::HyperFun,
        &[
            (
                "m(x[3], a[1]) {\n  m = hfSphre(x, x, 1);\n}",
                2,
                7,
                "unknown function 'hfsphre'",
            ),
            ("m(x[3], a[1]) {\n  m = q + 1;\n}", 2, 7, "'q', unassigned"),
            (
                "m(x[3], a[1]) {\n  m = hfSphere(x, 1);\n}",
                2,
                7,
                "expected 3 arguments for hfSphere(x, center, R), found 2",
            ),
            (
                "m(x[3], a[1]) {\n  m = hfSphere(x, 2, 1);\n}",
                2,
                19,
                "expected an array name as argument 2",
            ),
            (
                "m(x[3], a[1]) {\n  m = 1.2.3;\n}",
                2,
                7,
                "malformed number '1.2.3'",
            ),
            (
                "m(x[3], a[1]) {\n  m = (x[1] + 1;\n}",
                2,
                16,
                "expected ')', found ';'",
            ),
            (
                "m(x[3], a[1]) {\n  m = x[1]];\n}",
                2,
                11,
                "expected ';', found ']'",
            ),
            (
                "m(x[3], a[1]) {\n  if x[1] > 0 then m = 1;\n}",
                3,
                1,
                "expected 'endif', found '}'",
            ),
            (
                "m(x[3], a[1]) {\n  m = 0;\n  while x[1] < 1 loop m = m + 1; endloop;\n}",
                3,
                3,
                "does not depend on x",
            ),
            (
                "m(x[3], a[1]) {\n  i = 0;\n  while 1 loop i = i + 1; endloop;\n  m = i;\n}",
                3,
                3,
                "within 1000000 iterations",
            ),
            (
                "m(x[3], a[1]) {\n  k = 1;\n}",
                3,
                1,
                "assignment to the model's name 'm'",
            ),
            (
                "m(x[3], a[1]) {\n  array b[2];\n  m = b[3];\n}",
                3,
                7,
                "index of 'b' in 1..2, found 3",
            ),
            ("m(x[3], a[1]) {\n  m = 1 / 0;\n}", 2, 9, "non-zero divisor"),
            (
                "m(x[3], a[1]) {\n  m = x[1] +",
                2,
                13,
                "expected an expression, found the end of the file",
            ),
            ("m(x[3], a[1]", 1, 13, "expected ')'"),
            ("m(x[3]) { m = 1; }", 1, 7, "expected ','"),
            (
                "m(x[3], a[1]) {\n  m = hfBlendUni(x[1], x[2], 1, 0, 1);\n}",
                2,
                7,
                "non-zero blend parameters",
            ),
            (
                "m(x[3], a[1]) { m = 1; }\nm(x[3], a[1]) { m = 2; }",
                2,
                1,
                "'m' defined twice",
            ),
            (
                "m(x[3], a[1]) {\n  m = x[1] $ 2;\n}",
                2,
                12,
                "found the character '$'",
            ),
            ("", 1, 1, "expected a model"),
            (&deep, 1, 220, "at most 200 levels of nesting"),
            (&deep_if, 1, 2010, "at most 200 levels of nesting"),
        ],
    );
}

/// The third header array `s[k]` exists only when the header declares it: without it,
/// `s` is an ordinary local (scalar or array); with it, `s` is the header's array.
#[test]
fn hf_s_is_reserved_only_when_the_header_declares_it() {
    let scalar = hf("m(x[3], a[1])\n{\n  s = x[1] * 2;\n  m = 1 - s * s - x[2] * x[2];\n}\n");
    agree(
        &scalar,
        |[x, y, _]| 1.0 - 4.0 * x * x - y * y,
        1.0,
        "s scalar",
    );
    let array = hf("m(x[3], a[1])\n{\n  array s[2];\n  s[1] = x[1];\n  s[2] = x[2];\n  m = 1 - s[1] * s[1] - s[2] * s[2];\n}\n");
    agree(&array, |[x, y, _]| 1.0 - x * x - y * y, 1.0, "s array");
    // Declared in the header, `s` is that array: a scalar assignment is refused.
    let e = read_str(
        "m(x[3], a[1], s[2])\n{\n  s = 1;\n  m = 1;\n}\n",
        Format::HyperFun,
        "t.hf",
    )
    .expect_err("s is the header's array");
    assert!(e.to_string().contains("'s'"), "{e}");
    let e = read_str(
        "m(x[3], a[1], s[2])\n{\n  array s[2];\n  m = 1;\n}\n",
        Format::HyperFun,
        "t.hf",
    )
    .expect_err("s is already in use");
    assert!(e.to_string().contains("already in use"), "{e}");
    // `x` and `a` are always the header's.
    for name in ["x", "a"] {
        let text = format!("m(x[3], a[1])\n{{\n  array {name}[2];\n  m = 1;\n}}\n");
        let e = read_str(&text, Format::HyperFun, "t.hf").expect_err("header name");
        assert!(e.to_string().contains("already in use"), "{e}");
    }
}

/// Memory and copying are bounded: 200 arrays of a million elements took gigabytes, and a
/// branch on the coordinates inside a loop copied a million-element array at every
/// iteration (80 s). Both stop at the limit of four million variables and array
/// elements made or copied, with an error at the declaration or the branch.
#[test]
fn arrays_made_or_copied_are_bounded() {
    let arrays: String = (0..200)
        .map(|i| format!("  array b{i}[1000000];\n"))
        .collect();
    let many = format!("m(x[3], a[1])\n{{\n{arrays}  m = x[1];\n}}\n");
    let copied = "m(x[3], a[1])\n{\n  array b[1000000];\n  i = 0;\n  m = x[1];\n  \
                  while i < 1000 loop\n    if x[1] > 0 then m = m + 1; endif;\n    \
                  i = i + 1;\n  endloop;\n}\n";
    for (text, line) in [(many.as_str(), 7), (copied, 7)] {
        let t = std::time::Instant::now();
        let e = read_str(text, Format::HyperFun, "t.hf").unwrap_err();
        assert!(e.message.contains("at most 4000000 variables"), "{e}");
        assert_eq!(e.line, line, "{e}");
        assert!(t.elapsed().as_secs_f64() < 5.0, "took {:?}", t.elapsed());
    }
    // A million-element array with a branch outside any loop is fine.
    hf("m(x[3], a[1])\n{\n  array b[1000000];\n  m = x[1];\n  if x[2] > 0 then m = x[2]; endif;\n}\n");
}

/// hfTorusZ and hfBlock are written so that each coordinate appears once: their interval
/// over a box is the exact range. The torus is r0² − d_z² − (ρ − R)², separable in ρ
/// and d_z; the block (α = 0) is the R-intersection, non-decreasing in each operand, of
/// three slabs (e/2)² − (p − v − e/2)², one per coordinate: its range runs from its
/// value at the slabs' least values to that at their greatest.
#[test]
fn torus_and_block_are_bounded_exactly() {
    let torus = hf_model(
        "array c[3]; c = [0.1, -0.2, 0.3];",
        "hfTorusZ(x, c, 0.7, 0.2)",
    );
    let block = hf_model(
        "array c[3]; c = [0.1, -0.2, 0.3];",
        "hfBlock(x, c, 0.5, 0.6, 0.7)",
    );
    let (te, be) = (expr(&torus), expr(&block));
    let c = [0.1, -0.2, 0.3];
    let mut rng = rand_pcg::Pcg64::seed_from_u64(31);
    let r = |f: f64, g: f64| f + g - (f * f + g * g).sqrt();
    for k in 0..500 {
        let lo: [f64; 3] = std::array::from_fn(|i| c[i] + rng.gen_range(-1.0..0.8));
        let hi: [f64; 3] = std::array::from_fn(|i| lo[i] + rng.gen_range(0.0..0.4));
        // Torus: ρ over the (x, y) rectangle about c, then (ρ − R)² and d_z².
        let d = |i: usize| (lo[i] - c[i], hi[i] - c[i]);
        let rho = rho_range(d(0), d(1));
        let (ring, h) = (sq_range(rho.0, rho.1, 0.7), sq_range(d(2).0, d(2).1, 0.0));
        let want = (0.04 - ring.1 - h.1, 0.04 - ring.0 - h.0);
        let got = te.eval_interval(lo, hi);
        assert!(
            (got.lo - want.0).abs() <= 1e-12 && (got.hi - want.1).abs() <= 1e-12,
            "torus, box {k}: {got:?} against {want:?}"
        );
        // Block: each slab's range, then the R-intersections at both ends.
        let e = [0.5, 0.6, 0.7];
        let slab = |i: usize| {
            let (a, b) = sq_range(lo[i], hi[i], c[i] + e[i] / 2.0);
            (e[i] * e[i] / 4.0 - b, e[i] * e[i] / 4.0 - a)
        };
        let (s0, s1, s2) = (slab(0), slab(1), slab(2));
        let want = (r(r(s0.0, s1.0), s2.0), r(r(s0.1, s1.1), s2.1));
        let got = be.eval_interval(lo, hi);
        assert!(
            (got.lo - want.0).abs() <= 1e-12 && (got.hi - want.1).abs() <= 1e-12,
            "block, box {k}: {got:?} against {want:?}"
        );
    }
}
