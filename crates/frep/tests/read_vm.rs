//! The Fidget `.vm` reader and writer: every opcode, every Fidget model, errors with
//! positions, and write-then-read round trips.

use crate::common;
use common::*;

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
        let m = read_file(&model_file(&format!("fidget/{f}"))).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            t.elapsed().as_secs_f64() < 5.0,
            "{f} took {:?}",
            t.elapsed()
        );
        let e = expr(&m);
        assert!(e.len() > 5, "{f}");
        assert!(e.eval([0.1, 0.2, 0.3]).is_finite(), "{f}");
    }
    let q = read_file(&model_file("fidget/quarter.vm")).unwrap();
    agree(
        &q,
        |[x, y, _]| -(x.max(y).max(x * x + y * y - 0.5)),
        1.0,
        "quarter.vm",
    );
    let e = expr(&q);
    assert!(e.eval([-0.3, -0.3, 0.0]) > 0.0 && e.eval([0.3, 0.3, 0.0]) < 0.0);
    let t = read_file(&model_file("fidget/tanglecube.vm")).unwrap();
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
