//! Measures RMSE relative to the balance heuristic, at equal samples, for every estimator
//! and a range of ridges and warm-ups, on the 1-D three-technique problem of the tests.
//! The numbers behind the defaults and the tables in `docs/mis.md`.
//!
//! `cargo run --release -p mis --example small_sample [repetitions]`

#[path = "../tests/common/mod.rs"]
mod common;

use common::{mixture, mse, peak, peak_integral, Problem, MIXTURE};
use mis::{
    AnyEstimator, Direct, Estimator, Layout, Method, Params, Progressive, Schedule, Uncorrelated,
};
use rand::SeedableRng;
use rand_pcg::Pcg64;
use std::sync::Arc;

fn candidates(layout: &Arc<Layout>, n: u64) -> Vec<(String, AnyEstimator)> {
    let p = Params::default();
    let mut v: Vec<(String, AnyEstimator)> = vec![
        ("balance".into(), Method::Balance.build(layout, &p).unwrap()),
        ("power".into(), Method::Power.build(layout, &p).unwrap()),
    ];
    let direct = |ridge: f64| AnyEstimator::Direct(Direct::new(layout.clone(), ridge));
    for ridge in [0.0, 0.03, 0.1, 0.3, 1.0] {
        v.push((format!("direct λ={ridge}"), direct(ridge)));
    }
    // The library divides λ by N; λ·N gives a constant relative ridge, for comparison.
    for ridge in [1e-3, 1e-2] {
        v.push((format!("direct fixed {ridge}"), direct(ridge * n as f64)));
    }
    for ridge in [0.0, 0.1, 1.0] {
        v.push((
            format!("uncorr λ={ridge}"),
            AnyEstimator::Uncorrelated(Uncorrelated::new(layout.clone(), ridge)),
        ));
    }
    let mut schedules = vec![
        ("prog every W=1".to_string(), Schedule::Every { warmup: 1 }),
        ("prog every W=2".to_string(), Schedule::Every { warmup: 2 }),
    ];
    for w in [1, 2, 4, 8] {
        schedules.push((format!("prog dbl W={w}"), Schedule::Doubling { warmup: w }));
    }
    for w in [2, 4, 8, 16] {
        schedules.push((format!("full W={w}"), Schedule::Once { after: w }));
    }
    for (name, schedule) in schedules {
        for ridge in [0.0, 0.1] {
            v.push((
                format!("{name} λ={ridge}"),
                AnyEstimator::Progressive(Progressive::new(layout.clone(), ridge, schedule)),
            ));
        }
    }
    v
}

fn table(title: &str, problem: &Problem, f: fn(f64) -> f64, reference: f64, reps: usize) {
    let ns = [1u64, 2, 3, 4, 6, 8, 16, 32, 64];
    let layout = Layout::new(&[1, 1, 1], 1);
    let names: Vec<String> = candidates(&layout, 1).into_iter().map(|(n, _)| n).collect();
    // results[n][estimator] = estimates over repetitions
    let mut rmse = vec![vec![0.0; names.len()]; ns.len()];
    for (ni, &n) in ns.iter().enumerate() {
        let mut est = vec![Vec::with_capacity(reps); names.len()];
        let mut rng = Pcg64::seed_from_u64(0x5eed + n);
        for _ in 0..reps {
            let mut es: Vec<AnyEstimator> =
                candidates(&layout, n).into_iter().map(|(_, e)| e).collect();
            for _ in 0..n {
                problem.iteration(&mut rng, &[1, 1, 1], &|x, o| o[0] = f(x), &mut es);
            }
            for (k, e) in es.iter().enumerate() {
                est[k].push(e.estimate_vec()[0]);
            }
        }
        for k in 0..names.len() {
            rmse[ni][k] = mse(&est[k], reference).sqrt();
        }
    }
    println!("\n## {title} — RMSE / RMSE(balance), {reps} repetitions\n");
    print!("| estimator |");
    for n in ns {
        print!(" N={n} |");
    }
    println!();
    print!("|---|");
    for _ in ns {
        print!("---|");
    }
    println!();
    for (k, name) in names.iter().enumerate() {
        print!("| {name} |");
        for row in &rmse {
            if k == 0 {
                print!(" {:.3e} |", row[0]);
            } else {
                print!(" {:.3} |", row[k] / row[0]);
            }
        }
        println!();
    }
}

fn main() {
    let reps: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_000);
    println!("(balance row: absolute RMSE)");
    table(
        "mixture integrand, proper pdfs",
        &Problem::PROPER,
        mixture,
        MIXTURE,
        reps,
    );
    table(
        "peak exp(−40(x−0.7)²), proper pdfs",
        &Problem::PROPER,
        peak,
        peak_integral(),
        reps,
    );
    table(
        "mixture integrand, technique 1 fails 30 %",
        &Problem { fail: 0.3 },
        mixture,
        MIXTURE,
        reps,
    );
}
