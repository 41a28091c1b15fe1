//! Readers of `.frep`, HyperFun and Fidget files, and the `.vm` writer: valid input gives
//! the right function, malformed input a ReadError at the right line and column.

use frep::read::{read_file, read_str, write_vm, Format, Model, ReadError};
use frep::shape::Shape;
use frep::{BinaryOp, Expr, Tree, UnaryOp};
use rand::{Rng, SeedableRng};
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn shared(p: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/models")
        .join(p)
}

fn expr(m: &Model) -> Expr {
    Expr::new(&m.shape.to_tree().expect("a regular shape"))
}

/// A function of a point.
type Field = dyn Fn([f64; 3]) -> f64;

fn close(a: f64, b: f64) -> bool {
    (a.is_nan() && b.is_nan()) || a == b || (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()))
}

/// Random points in [-r, r]³ from a fixed seed.
fn points(n: usize, r: f64, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    (0..n)
        .map(|_| [0; 3].map(|_| rng.gen_range(-r..r)))
        .collect()
}

fn agree(m: &Model, f: impl Fn([f64; 3]) -> f64, r: f64, what: &str) {
    let e = expr(m);
    for p in points(400, r, 7) {
        let (got, want) = (e.eval(p), f(p));
        assert!(
            close(got, want),
            "{what} at {p:?}: read {got}, formula {want}"
        );
    }
}

fn err(text: &str, format: Format) -> ReadError {
    match read_str(text, format, "t") {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    }
}

/// Each case: input, expected line and column, and a piece of the message.
fn check_errors(format: Format, cases: &[(&str, usize, usize, &str)]) {
    for (text, line, col, msg) in cases {
        let e = err(text, format);
        assert_eq!(
            (e.line, e.column),
            (*line, *col),
            "position for {text:?}: {e}"
        );
        assert!(e.message.contains(msg), "message for {text:?}: {e}");
        assert!(
            e.to_string().starts_with(&format!("t:{line}:{col}: ")),
            "{e}"
        );
    }
}

fn norm(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

#[test]
fn fidget_models_load_and_negate() {
    for f in [
        "prospero.vm",
        "hi.vm",
        "quarter.vm",
        "colonnade.vm",
        "tanglecube.vm",
    ] {
        let t = std::time::Instant::now();
        let m = read_file(&shared(&format!("fidget/{f}"))).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            t.elapsed().as_secs_f64() < 5.0,
            "{f} took {:?}",
            t.elapsed()
        );
        let e = expr(&m);
        assert!(e.len() > 5, "{f}");
        assert!(e.eval([0.1, 0.2, 0.3]).is_finite(), "{f}");
    }
    let q = read_file(&shared("fidget/quarter.vm")).unwrap();
    agree(
        &q,
        |[x, y, _]| -(x.max(y).max(x * x + y * y - 0.5)),
        1.0,
        "quarter.vm",
    );
    let e = expr(&q);
    assert!(e.eval([-0.3, -0.3, 0.0]) > 0.0 && e.eval([0.3, 0.3, 0.0]) < 0.0);
    let t = read_file(&shared("fidget/tanglecube.vm")).unwrap();
    let tangle = |[x, y, z]: [f64; 3]| {
        -(x.powi(4) - 5.0 * x * x + y.powi(4) - 5.0 * y * y + z.powi(4) - 5.0 * z * z + 10.0)
    };
    agree(&t, tangle, 3.0, "tanglecube.vm");
}

#[test]
fn vm_reads_every_opcode() {
    let text = "# every opcode\nx var-x\ny var-y\nz var-z\nc const -0.25\n\
        a add x y\ns sub a z\nm mul s c\nd div m y\nmi min d x\nma max mi z\nn neg ma\nab abs n\n\
        sq square ab\nrt sqrt sq\nsi sin rt\nco cos si\nta tan co\nas asin c\nac acos c\nat atan x\n\
        t2 atan2 y x\nex exp c\nln ln ab\nfl floor d\nce ceil d\nro round d\nmo mod d c\n\
        cp compare x y\nan and cp z\nor or cp y\nno not cp\nre recip y\n\
        s1 add ta as\ns2 add s1 ac\ns3 add s2 at\ns4 add s3 t2\ns5 add s4 ex\ns6 add s5 ln\n\
        s7 add s6 fl\ns8 add s7 ce\ns9 add s8 ro\nsa add s9 mo\nsb add sa an\nsc add sb or\n\
        sd add sc no\nse add sd re\n";
    let m = read_str(text, Format::Vm, "ops.vm").unwrap();
    let f = |[x, y, z]: [f64; 3]| {
        let c = -0.25;
        let d = ((x + y - z) * c) / y;
        let ab = (-(d.min(x).max(z))).abs();
        let ta = (ab * ab).sqrt().sin().cos().tan();
        let cp = match x.partial_cmp(&y).unwrap() {
            std::cmp::Ordering::Less => -1.0,
            std::cmp::Ordering::Equal => 0.0,
            std::cmp::Ordering::Greater => 1.0,
        };
        let an = if cp == 0.0 { cp } else { z };
        let or = if cp != 0.0 { cp } else { y };
        let no = if cp == 0.0 { 1.0 } else { 0.0 };
        let s = ta
            + c.asin()
            + c.acos()
            + x.atan()
            + y.atan2(x)
            + c.exp()
            + ab.ln()
            + d.floor()
            + d.ceil()
            + d.round()
            + d.rem_euclid(c)
            + an
            + or
            + no
            + 1.0 / y;
        -s
    };
    agree(&m, f, 2.0, "every opcode");
}

#[test]
fn vm_errors_have_positions() {
    check_errors(
        Format::Vm,
        &[
            ("x var-x\ny frob x\n", 2, 3, "unknown opcode 'frob'"),
            (
                "x var-x\ny add x\n",
                2,
                8,
                "expected 2 arguments for 'add', found 1",
            ),
            (
                "x var-x\ny neg x x\n",
                2,
                9,
                "expected 1 argument for 'neg', found 2",
            ),
            ("x var-x\n  y mul x q\n", 2, 11, "undefined name 'q'"),
            ("c const 1.2.3\n", 1, 9, "expected a number, found '1.2.3'"),
            (
                "c const\n",
                1,
                8,
                "expected 1 argument for 'const', found 0",
            ),
            ("x\n", 1, 2, "expected an opcode after 'x'"),
            (
                "# nothing here\n\n",
                2,
                1,
                "expected at least one instruction",
            ),
            ("", 1, 1, "expected at least one instruction"),
        ],
    );
}

/// A random expression using every operation (the generator draws each op in turn).
fn random_tree(rng: &mut rand_pcg::Pcg64, depth: u32, k: &mut usize) -> Tree {
    use BinaryOp as B;
    use UnaryOp as U;
    const UN: [U; 16] = [
        U::Neg,
        U::Abs,
        U::Sqrt,
        U::Square,
        U::Exp,
        U::Ln,
        U::Sin,
        U::Cos,
        U::Tan,
        U::Asin,
        U::Acos,
        U::Atan,
        U::Floor,
        U::Ceil,
        U::Round,
        U::Not,
    ];
    const BI: [B; 11] = [
        B::Add,
        B::Sub,
        B::Mul,
        B::Div,
        B::Min,
        B::Max,
        B::Atan2,
        B::Mod,
        B::Compare,
        B::And,
        B::Or,
    ];
    if depth == 0 {
        return match rng.gen_range(0..4) {
            0 => Tree::x(),
            1 => Tree::y(),
            2 => Tree::z(),
            _ => Tree::constant(rng.gen_range(-2.0..2.0)),
        };
    }
    *k += 1;
    let a = random_tree(rng, depth - 1, k);
    match *k % 3 {
        0 => Tree::unary(UN[(*k / 3) % UN.len()], a),
        1 => Tree::binary(BI[(*k / 3) % BI.len()], a, random_tree(rng, depth - 1, k)),
        _ => a.powi([-3, -1, 0, 3, 5, 6, 7][(*k / 3) % 7]),
    }
}

#[test]
fn vm_writer_round_trips_every_operation() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    let mut k = 0;
    let mut compared = 0;
    for _ in 0..60 {
        let e = Expr::new(&random_tree(&mut rng, 5, &mut k));
        let text = write_vm(&e);
        assert!(!text.contains("pow"), "{text}");
        let back =
            expr(&read_str(&text, Format::Vm, "w.vm").unwrap_or_else(|er| panic!("{er}\n{text}")));
        for p in points(40, 1.5, k as u64) {
            let (a, b) = (e.eval(p), back.eval(p));
            assert!(close(a, b), "{a} vs {b} at {p:?} for\n{text}");
            compared += a.is_finite() as usize;
        }
    }
    assert!(
        compared > 1000,
        "too few finite values compared: {compared}"
    );
    // The sign flips to Fidget's convention in the file and back on reading.
    let ball = Expr::new(&(1.0 - Tree::x().square()));
    let text = write_vm(&ball);
    assert!(
        text.trim_end().lines().last().unwrap().contains(" neg "),
        "{text}"
    );
}

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
    let mut n = 0;
    for entry in std::fs::read_dir(root().join("models/examples")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "frep") {
            let m = read_file(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(m.domain.is_some(), "{path:?} declares bounds");
            n += 1;
        }
    }
    assert!(n >= 3);
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
