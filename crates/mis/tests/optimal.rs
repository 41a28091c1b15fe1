//! Optimal-MIS estimators on 1-D integrals with known answers (tests/common).
//!
//! Statistical assertions use a fixed seed; "within 4.5 se" bounds fail by chance with
//! probability < 1e-5 each under the normal approximation, and variance-ratio bounds leave
//! at least 5 standard deviations of the ratio's sampling error (relative sd √(2/R)).

use crate::common;

use std::sync::Arc;

use common::*;
use mis::linalg::{packed_index, packed_len, solve};
use mis::{
    AnyEstimator, Direct, Estimator, Layout, Method, Params, Progressive, Schedule, SolveMethod,
    Uncorrelated,
};
use rand::SeedableRng;
use rand_pcg::Pcg64;

fn rng(seed: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seed)
}

fn build(method: Method, layout: &Arc<Layout>) -> AnyEstimator {
    method.build(layout, &Params::default()).unwrap()
}

/// `reps` independent runs of `n` iterations; the estimates of channel 0 per estimator.
fn repeat(
    problem: &Problem,
    counts: &[u32],
    f: fn(f64) -> f64,
    n: u64,
    reps: usize,
    seed: u64,
    make: &dyn Fn() -> Vec<AnyEstimator>,
) -> Vec<Vec<f64>> {
    let mut r = rng(seed);
    let mut out = vec![Vec::with_capacity(reps); make().len()];
    for _ in 0..reps {
        let mut es = make();
        for _ in 0..n {
            problem.iteration(&mut r, counts, &|x, o| o[0] = f(x), &mut es);
        }
        for (k, e) in es.iter().enumerate() {
            out[k].push(e.estimate_vec()[0]);
        }
    }
    out
}

#[test]
fn identity_a_n_is_one_so_sum_alpha_is_f() {
    // Exact A and b by midpoint quadrature (200 000 cells), n = (1, 2, 1).
    let p = Problem::PROPER;
    let counts = [1.0, 2.0, 1.0];
    let cells = 200_000;
    let mut a = vec![0.0; packed_len(3)];
    let mut b = vec![0.0; 6];
    for j in 0..cells {
        let x = (j as f64 + 0.5) / cells as f64;
        let pd = p.pdfs(x);
        let s: f64 = pd.iter().zip(counts).map(|(p, n)| p * n).sum();
        for i in 0..3 {
            for k in 0..=i {
                a[packed_index(i, k)] += pd[i] * pd[k] / s / cells as f64;
            }
            b[i] += mixture(x) * pd[i] / s / cells as f64;
            b[3 + i] += linear(x) * pd[i] / s / cells as f64;
        }
    }
    for i in 0..3 {
        let an: f64 = (0..3).map(|k| a[packed_index(i, k)] * counts[k]).sum();
        assert!((an - 1.0).abs() < 1e-9, "(A n)_{i} = {an}");
    }
    let mut alpha = [0.0; 6];
    assert_eq!(solve(&a, 3, 0.0, &b, &mut alpha), SolveMethod::Cholesky);
    let sum = |c: usize| alpha[3 * c..3 * c + 3].iter().sum::<f64>();
    assert!((sum(0) - MIXTURE).abs() < 1e-8, "Σα = {}", sum(0));
    assert!((sum(1) - LINEAR).abs() < 1e-8, "Σα = {}", sum(1));
    // f = 0.7 p₀ − 0.4 p₁ + 1.3 p₂ gives α = (0.7, −0.4, 1.3) exactly.
    for (got, want) in alpha[3..].iter().zip([0.7, -0.4, 1.3]) {
        assert!((got - want).abs() < 1e-7, "{alpha:?}");
    }
}

#[test]
fn failed_samples_keep_a_n_equal_to_one() {
    // Technique 1 fails 30 % of the time: ∫p₁ = 0.7, yet Â n / N estimates 1 because each
    // failure adds 1/n₁² to Â₁₁. 2000 runs of 20 iterations; mean within 4.5 se of 1.
    let problem = Problem { fail: 0.3 };
    let counts = [1, 2, 1];
    let layout = Layout::new(&counts, 1);
    let mut r = rng(11);
    let mut an = vec![Vec::new(); 3];
    for _ in 0..2000 {
        let mut es = vec![AnyEstimator::Direct(Direct::new(layout.clone(), 0.0))];
        for _ in 0..20 {
            problem.iteration(&mut r, &counts, &|x, o| o[0] = mixture(x), &mut es);
        }
        let AnyEstimator::Direct(d) = &es[0] else {
            unreachable!()
        };
        for (i, v) in d.moments().matrix_times_counts(&layout).iter().enumerate() {
            an[i].push(v / 20.0);
        }
    }
    for (i, v) in an.iter().enumerate() {
        let (mean, _, se) = stats(v);
        assert!((mean - 1.0).abs() < 4.5 * se, "(Â n/N)_{i}: {mean} ± {se}");
    }
}

#[test]
fn zero_variance_when_f_is_a_combination_of_the_pdfs() {
    let counts = [1, 2, 1];
    let layout = Layout::new(&counts, 1);
    let exact = Params {
        ridge: Some(0.0),
        ..Params::default()
    };
    let mut r = rng(3);
    let mut worst: f64 = 0.0;
    for n in [1, 2, 5] {
        for _ in 0..300 {
            let mut es = vec![
                Method::OptimalDirect.build(&layout, &exact).unwrap(),
                AnyEstimator::Progressive(Progressive::with_alpha(
                    layout.clone(),
                    &[0.7, -0.4, 1.3],
                )),
            ];
            for _ in 0..n {
                Problem::PROPER.iteration(&mut r, &counts, &|x, o| o[0] = linear(x), &mut es);
            }
            for e in &es {
                worst = worst.max((e.estimate_vec()[0] - LINEAR).abs());
            }
        }
    }
    assert!(worst < 1e-11, "largest error {worst:e}");
    // With the default ridge the estimate is no longer exact, but its variance is a tiny
    // fraction of balance's (measured ratio 2.4e-4 at N = 16; bound 2e-3).
    let runs = repeat(&Problem::PROPER, &counts, linear, 16, 2000, 4, &|| {
        vec![
            build(Method::Balance, &layout),
            build(Method::OptimalDirect, &layout),
        ]
    });
    let ratio = stats(&runs[1]).1 / stats(&runs[0]).1;
    println!("ridge 0.1, N = 16: var(direct)/var(balance) = {ratio:.2e}");
    assert!(ratio < 2e-3, "{ratio}");
}

#[test]
fn optimal_variance_is_below_balance_on_mixtures() {
    // 4000 paired runs at N = 16; measured ratios 0.06–0.84 (docs/mis.md). Bound 0.95:
    // the largest measured ratio lies 5 sd (relative sd √(2/4000) = 2.2 %) below it.
    type Case = (&'static str, Problem, fn(f64) -> f64, u64);
    let cases: [Case; 3] = [
        ("mixture", Problem::PROPER, mixture, 16),
        ("peak", Problem::PROPER, peak, 16),
        ("mixture, 30 % failures", Problem { fail: 0.3 }, mixture, 16),
    ];
    let layout = Layout::new(&[1, 1, 1], 1);
    let methods = [
        Method::OptimalDirect,
        Method::OptimalProgressive,
        Method::OptimalFull,
    ];
    for (seed, (name, problem, f, n)) in cases.into_iter().enumerate() {
        let runs = repeat(&problem, &[1, 1, 1], f, n, 4000, 100 + seed as u64, &|| {
            let mut v = vec![build(Method::Balance, &layout)];
            v.extend(methods.iter().map(|&m| build(m, &layout)));
            v
        });
        let balance = stats(&runs[0]).1;
        for (k, m) in methods.iter().enumerate() {
            let ratio = stats(&runs[k + 1]).1 / balance;
            println!("{name}, N = {n}: var({m})/var(balance) = {ratio:.3}");
            assert!(ratio < 0.95, "{name}: {m} variance ratio {ratio}");
        }
    }
}

#[test]
fn uncorrelated_beats_balance_given_enough_iterations() {
    // MSE (bias included) at N = 64 with λ = 1; measured ratios 0.26–0.69, bound 0.9.
    let layout = Layout::new(&[1, 1, 1], 1);
    for (seed, (problem, f, reference)) in [
        (Problem::PROPER, mixture as fn(f64) -> f64, MIXTURE),
        (Problem::PROPER, peak, peak_integral()),
        (Problem { fail: 0.3 }, mixture, MIXTURE),
    ]
    .into_iter()
    .enumerate()
    {
        let runs = repeat(
            &problem,
            &[1, 1, 1],
            f,
            64,
            2000,
            200 + seed as u64,
            &|| {
                vec![
                    build(Method::Balance, &layout),
                    AnyEstimator::Uncorrelated(Uncorrelated::new(layout.clone(), 1.0)),
                ]
            },
        );
        let ratio = mse(&runs[1], reference) / mse(&runs[0], reference);
        println!("uncorrelated λ = 1, N = 64: MSE ratio {ratio:.3}");
        assert!(ratio < 0.9, "{ratio}");
    }
}

#[test]
fn progressive_and_full_weights_are_unbiased() {
    // 20 000 runs of only 3 iterations each, where a biased α would show most; with and
    // without failed samples, n = (1, 2, 1). Mean within 4.5 se of the exact integral.
    let counts = [1, 2, 1];
    let layout = Layout::new(&counts, 1);
    for (seed, problem) in [Problem::PROPER, Problem { fail: 0.3 }]
        .into_iter()
        .enumerate()
    {
        for (f, reference) in [
            (mixture as fn(f64) -> f64, MIXTURE),
            (peak, peak_integral()),
        ] {
            let runs = repeat(&problem, &counts, f, 3, 20_000, 300 + seed as u64, &|| {
                let p = |ridge, schedule| {
                    AnyEstimator::Progressive(Progressive::new(layout.clone(), ridge, schedule))
                };
                vec![
                    build(Method::OptimalProgressive, &layout),
                    build(Method::OptimalFull, &layout),
                    p(0.0, Schedule::Every { warmup: 1 }),
                    p(0.0, Schedule::Once { after: 1 }),
                    AnyEstimator::Progressive(Progressive::with_alpha(
                        layout.clone(),
                        &[2.0, -1.0, 0.5],
                    )),
                ]
            });
            for (k, v) in runs.iter().enumerate() {
                let (mean, _, se) = stats(v);
                assert!(
                    (mean - reference).abs() < 4.5 * se,
                    "estimator {k}, fail {}: {mean} ± {se} vs {reference}",
                    problem.fail
                );
            }
        }
    }
}

#[test]
fn direct_is_consistent() {
    // Bias O(1/N): at N = 256 the mean of 400 runs is within 4.5 se + 1e-3 of F.
    let layout = Layout::new(&[1, 1, 1], 1);
    let runs = repeat(
        &Problem { fail: 0.3 },
        &[1, 1, 1],
        peak,
        256,
        400,
        7,
        &|| {
            vec![
                build(Method::OptimalDirect, &layout),
                AnyEstimator::Direct(Direct::new(layout.clone(), 0.0)),
            ]
        },
    );
    for v in &runs {
        let (mean, _, se) = stats(v);
        assert!(
            (mean - peak_integral()).abs() < 4.5 * se + 1e-3,
            "{mean} ± {se}"
        );
    }
}
