//! The register bytecode against the expression DAG on every model frep reads: f32
//! values bit for bit, interval bounds that hold the point values, registers in range.

use crate::common;

use common::*;
use frep::bytecode::{Bytecode, MAX_REGISTERS};

/// Every model file under models/ that frep reads.
fn models() -> Vec<(PathBuf, Model)> {
    let mut out = Vec::new();
    let dirs = [
        root().join("models/examples"),
        root().join("models/canonical"),
        model_file("fidget"),
    ];
    for dir in dirs {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut paths: Vec<PathBuf> = entries.map(|e| e.unwrap().path()).collect();
        paths.sort();
        for p in paths {
            if let Ok(m) = read_file(&p) {
                out.push((p, m));
            }
        }
    }
    out
}

#[test]
fn bytecode_matches_the_expression_on_every_model() {
    let models = models();
    assert!(models.len() >= 10, "{} models", models.len());
    let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
    for (path, m) in &models {
        let e = expr(m);
        let code = Bytecode::compile(&e).unwrap_or_else(|err| panic!("{}: {err}", path.display()));
        let name = path.display();
        assert!(code.registers() <= MAX_REGISTERS, "{name}");
        assert!(Bytecode::from_words(code.words().to_vec(), code.registers()).is_ok());
        println!(
            "{name}: {} nodes, {} instructions, {} registers",
            e.len(),
            code.len(),
            code.registers()
        );
        let n = if e.len() > 2000 { 200 } else { 2000 };
        for _ in 0..n {
            let p = [0; 3].map(|_| rng.gen_range(-1.6f32..1.6));
            let (got, want) = (code.eval_f32(p), e.eval_f32(p));
            assert!(
                got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                "{name} at {p:?}: bytecode {got}, expression {want}"
            );
        }
        // Boxes of several sizes; every f32 point value inside lies in the bounds.
        for k in 0..n / 10 {
            let half = [0.5f32, 0.05, 0.001][k % 3];
            let c = [0; 3].map(|_| rng.gen_range(-1.5f32..1.5));
            let (lo, hi) = (c.map(|v| v - half), c.map(|v| v + half));
            let (a, b) = code.eval_interval(lo, hi);
            for _ in 0..8 {
                let p = [0, 1, 2].map(|i| rng.gen_range(lo[i]..=hi[i]));
                let v = code.eval_f32(p);
                if v.is_nan() || a.is_nan() || b.is_nan() {
                    continue;
                }
                assert!(a <= v && v <= b, "{name}: {v} at {p:?} outside [{a}, {b}]");
            }
        }
    }
}
