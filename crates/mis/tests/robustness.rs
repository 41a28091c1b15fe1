//! Merging, singular technique matrices, channels and signs, and the measured small-sample
//! behaviour of the direct estimator (tests/common holds the 1-D problem).

use crate::common;

use std::sync::Arc;

use common::*;
use mis::{AnyEstimator, Direct, Estimator, Layout, Method, Params, Progressive, SolveMethod};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1.0)
}

fn all_methods(layout: &Arc<Layout>) -> Vec<AnyEstimator> {
    Method::ALL
        .iter()
        .map(|m| m.build(layout, &Params::default()).unwrap())
        .collect()
}

#[test]
fn merging_two_halves_equals_the_whole_run() {
    let counts = [1, 2, 1];
    let layout = Layout::new(&counts, 2);
    let problem = Problem { fail: 0.3 };
    let f = |x: f64, o: &mut [f64]| {
        o[0] = mixture(x);
        o[1] = -peak(x);
    };
    let (mut r1, mut r2) = (Pcg64::seed_from_u64(5), Pcg64::seed_from_u64(5));
    let mut whole = all_methods(&layout);
    let (mut first, mut second) = (all_methods(&layout), all_methods(&layout));
    for _ in 0..10 {
        problem.iteration(&mut r1, &counts, &f, &mut whole);
        problem.iteration(&mut r2, &counts, &f, &mut first);
    }
    for _ in 0..10 {
        problem.iteration(&mut r1, &counts, &f, &mut whole);
        problem.iteration(&mut r2, &counts, &f, &mut second);
    }
    for (k, m) in Method::ALL.iter().enumerate() {
        let (a, b) = (first[k].estimate_vec(), second[k].estimate_vec());
        let mut merged = first[k].clone();
        merged.merge(&second[k]);
        assert_eq!(merged.iterations(), 20);
        let (got, want) = (merged.estimate_vec(), whole[k].estimate_vec());
        for c in 0..2 {
            if matches!(m, Method::OptimalProgressive | Method::OptimalFull) {
                // α differs between a split and a whole run; the sums still add exactly.
                assert!(close(got[c], (a[c] + b[c]) / 2.0, 1e-14), "{m}: {got:?}");
            } else {
                assert!(close(got[c], want[c], 1e-12), "{m}: {got:?} vs {want:?}");
            }
        }
        // Merging an empty state changes no bit.
        let mut same = whole[k].clone();
        same.merge(&Method::ALL[k].build(&layout, &Params::default()).unwrap());
        assert_eq!(same.estimate_vec(), want, "{m}");
    }
    // After a merge the progressive α is re-solved from all 20 iterations: the direct α.
    let (AnyEstimator::Progressive(p), AnyEstimator::Direct(d)) = (&first[6], &whole[4]) else {
        unreachable!()
    };
    let mut p = p.clone();
    let AnyEstimator::Progressive(q) = &second[6] else {
        unreachable!()
    };
    p.merge(q);
    let mut alpha = vec![0.0; 6];
    d.alpha(&mut alpha);
    for (x, y) in p.alpha().iter().zip(&alpha) {
        assert!(close(*x, *y, 1e-10), "{:?} vs {alpha:?}", p.alpha());
    }
}

/// Runs n iterations of a 4-technique problem: the three test techniques plus a fourth
/// with pdf `fourth(x)` drawn by `draw_fourth` (None = failed).
fn run_four(
    es: &mut [AnyEstimator],
    n: usize,
    seed: u64,
    f: fn(f64) -> f64,
    fourth: fn(f64) -> f64,
    draw_fourth: fn(&mut Pcg64) -> Option<f64>,
) {
    let p = Problem::PROPER;
    let mut r = Pcg64::seed_from_u64(seed);
    for _ in 0..n {
        for t in 0..4 {
            let x = if t < 3 {
                p.draw(t, &mut r)
            } else {
                draw_fourth(&mut r)
            };
            match x {
                Some(x) => {
                    let [a, b, c] = p.pdfs(x);
                    let pdfs = [a, b, c, fourth(x)];
                    es.iter_mut().for_each(|e| e.add_sample(t, &[f(x)], &pdfs));
                }
                None => es.iter_mut().for_each(|e| e.add_failed(t)),
            }
        }
        es.iter_mut().for_each(|e| e.end_iteration());
    }
}

#[test]
fn proportional_pdfs_use_the_minimum_norm_solution() {
    // Technique 3 duplicates the uniform technique: Â is exactly singular. At λ = 0 the
    // pseudo-inverse splits α evenly between the twins and stays exact for f in the span.
    let layout = Layout::new(&[1, 1, 1, 1], 1);
    let exact = Params {
        ridge: Some(0.0),
        ..Params::default()
    };
    let uniform = |r: &mut Pcg64| Some(r.gen::<f64>());
    for (f, reference, tol) in [
        (linear as fn(f64) -> f64, LINEAR, 1e-10f64),
        (mixture, MIXTURE, 0.05),
    ] {
        let mut es: Vec<AnyEstimator> = Method::ALL
            .iter()
            .flat_map(|m| {
                [
                    m.build(&layout, &exact).unwrap(),
                    m.build(&layout, &Params::default()).unwrap(),
                ]
            })
            .collect();
        run_four(&mut es, 64, 9, f, |_| 1.0, uniform);
        for e in &es {
            let v = e.estimate_vec()[0];
            assert!(v.is_finite() && (v - reference).abs() < 0.3, "{v}");
        }
        let AnyEstimator::Direct(d) = &es[8] else {
            unreachable!()
        };
        let mut alpha = [0.0; 4];
        assert_eq!(d.alpha(&mut alpha), SolveMethod::PseudoInverse);
        assert!(
            (alpha[0] - alpha[3]).abs() < 1e-9 * alpha[0].abs().max(1.0),
            "{alpha:?}"
        );
        assert!(
            (d.estimate_vec()[0] - reference).abs() < tol,
            "{}",
            d.estimate_vec()[0]
        );
    }
}

#[test]
fn a_technique_that_never_fires_changes_nothing_at_zero_ridge() {
    // Technique 3 has pdf 0 everywhere and always fails: Â is block diagonal, α₃ = 0 and the
    // other α are those of the three-technique problem on the same samples.
    let four = Layout::new(&[1, 1, 1, 1], 1);
    let three = Layout::new(&[1, 1, 1], 1);
    let mut with = vec![
        AnyEstimator::Direct(Direct::new(four.clone(), 0.0)),
        Method::OptimalDirect
            .build(&four, &Params::default())
            .unwrap(),
    ];
    run_four(&mut with, 32, 21, peak, |_| 0.0, |_| None);
    let mut without = vec![AnyEstimator::Direct(Direct::new(three, 0.0))];
    let mut r = Pcg64::seed_from_u64(21);
    for _ in 0..32 {
        // The same random stream: run_four draws techniques 0..3 and nothing for the fourth.
        Problem::PROPER.iteration(&mut r, &[1, 1, 1], &|x, o| o[0] = peak(x), &mut without);
    }
    let (a, b) = (with[0].estimate_vec()[0], without[0].estimate_vec()[0]);
    assert!(close(a, b, 1e-12), "{a} vs {b}");
    let c = with[1].estimate_vec()[0];
    assert!(c.is_finite() && (c - peak_integral()).abs() < 0.1, "{c}");
}

#[test]
fn zero_integrand_and_no_samples_give_exact_zeros() {
    let layout = Layout::new(&[1, 2, 1], 1);
    let mut es = all_methods(&layout);
    let mut r = Pcg64::seed_from_u64(1);
    for _ in 0..8 {
        Problem { fail: 0.3 }.iteration(&mut r, &[1, 2, 1], &|_, o| o[0] = 0.0, &mut es);
    }
    for e in &es {
        assert_eq!(e.estimate_vec(), vec![0.0]);
    }
    // Every technique fails every time: Â is diagonal from failures only, b̂ = 0.
    let mut es = all_methods(&layout);
    for _ in 0..4 {
        for e in es.iter_mut() {
            for t in [0, 1, 1, 2] {
                e.add_failed(t);
            }
            e.end_iteration();
        }
    }
    for e in &es {
        assert_eq!(e.estimate_vec(), vec![0.0]);
    }
}

#[test]
fn channels_share_a_and_negative_values_are_kept() {
    // Channels (mixture, peak, −mixture) in one estimator equal three one-channel runs on
    // the same samples; the negated channel is the exact negation (nothing clamped).
    let counts = [1, 2, 1];
    let multi = Layout::new(&counts, 3);
    let single = Layout::new(&counts, 1);
    let fs: [fn(f64) -> f64; 3] = [mixture, peak, |x| -mixture(x)];
    let mut m = all_methods(&multi);
    let mut r = Pcg64::seed_from_u64(77);
    for _ in 0..12 {
        Problem { fail: 0.3 }.iteration(
            &mut r,
            &counts,
            &|x, o| fs.iter().zip(o).for_each(|(f, v)| *v = f(x)),
            &mut m,
        );
    }
    for (c, f) in fs.iter().enumerate() {
        let mut s = all_methods(&single);
        let mut r = Pcg64::seed_from_u64(77);
        for _ in 0..12 {
            Problem { fail: 0.3 }.iteration(&mut r, &counts, &|x, o| o[0] = f(x), &mut s);
        }
        for (k, e) in s.iter().enumerate() {
            let (a, b) = (m[k].estimate_vec()[c], e.estimate_vec()[0]);
            assert!(
                close(a, b, 1e-13),
                "{}: channel {c}: {a} vs {b}",
                Method::ALL[k]
            );
        }
    }
    for e in &m {
        let v = e.estimate_vec();
        assert_eq!(v[2], -v[0]);
        assert!(v[2] < 0.0);
    }
}

#[test]
fn small_sample_direct_versus_balance() {
    // docs/mis.md: without a ridge the direct estimator is ~3× worse than balance at N = 1 on
    // the peak and ~2× at N = 2–4 with failed samples; with the default ridge it is below
    // balance at every N. 10 000 paired runs per N; bounds 1.5 and 1.0 (measured 1.79–2.98
    // and ≤ 0.94).
    let layout = Layout::new(&[1, 1, 1], 1);
    let exact = Params {
        ridge: Some(0.0),
        ..Params::default()
    };
    for (problem, f, reference, bad_n) in [
        (Problem::PROPER, peak as fn(f64) -> f64, peak_integral(), 1),
        (Problem { fail: 0.3 }, mixture, MIXTURE, 2),
    ] {
        for n in [1, 2, 4, 8] {
            let mut r = Pcg64::seed_from_u64(1000 + n);
            let mut v = vec![Vec::new(); 3];
            for _ in 0..10_000 {
                let mut es = vec![
                    Method::Balance.build(&layout, &exact).unwrap(),
                    Method::OptimalDirect.build(&layout, &exact).unwrap(),
                    Method::OptimalDirect
                        .build(&layout, &Params::default())
                        .unwrap(),
                ];
                for _ in 0..n {
                    problem.iteration(&mut r, &[1, 1, 1], &|x, o| o[0] = f(x), &mut es);
                }
                for (k, e) in es.iter().enumerate() {
                    v[k].push(e.estimate_vec()[0]);
                }
            }
            let rmse: Vec<f64> = v.iter().map(|x| mse(x, reference).sqrt()).collect();
            let (plain, ridged) = (rmse[1] / rmse[0], rmse[2] / rmse[0]);
            println!(
                "fail {}, N = {n}: direct λ=0 {plain:.3}, λ=0.1 {ridged:.3}",
                problem.fail
            );
            if n == bad_n {
                assert!(plain > 1.5, "{plain}");
            }
            assert!(ridged < 1.0, "N = {n}: {ridged}");
        }
    }
}

#[test]
fn progressive_with_alpha_matches_per_sample_weights() {
    // The control-variate accumulation equals Σ w_t f/(n_t p_t) with explicit weights.
    let layout = Layout::new(&[2, 1, 1], 1);
    let alpha = [0.3, 0.9, -0.2];
    let mut e = Progressive::with_alpha(layout.clone(), &alpha);
    let mut by_weights = 0.0;
    let mut r = Pcg64::seed_from_u64(8);
    let problem = Problem { fail: 0.3 };
    for _ in 0..50 {
        for (t, &n) in [2u32, 1, 1].iter().enumerate() {
            for _ in 0..n {
                match problem.draw(t, &mut r) {
                    Some(x) => {
                        let pdfs = problem.pdfs(x);
                        e.add_sample(t, &[mixture(x)], &pdfs);
                        let w = mis::optimal_weight(&layout, &alpha, t, mixture(x), &pdfs).unwrap();
                        by_weights += w * mixture(x) / (f64::from(n) * pdfs[t]);
                    }
                    None => e.add_failed(t),
                }
            }
        }
        e.end_iteration();
    }
    assert!(close(e.estimate_vec()[0], by_weights / 50.0, 1e-12));
}

#[test]
fn uncorrelated_default_ridge_stays_near_balance() {
    // docs/mis.md: at λ = 0.1 the uncorrelated estimator is 2.5–6× worse than balance at
    // N = 2–4 (its Â from half the iterations is near singular); its own default, λ = 1,
    // stays within 1.16× at every N. 4000 paired runs per N; bounds 1.3 (default) and 2
    // (λ = 0.1, which must still fail it: the test guards the choice, not just the code).
    let layout = Layout::new(&[1, 1, 1], 1);
    let shared = Params {
        ridge: Some(mis::DEFAULT_RIDGE),
        ..Params::default()
    };
    for (problem, f, reference) in [
        (Problem::PROPER, mixture as fn(f64) -> f64, MIXTURE),
        (Problem { fail: 0.3 }, mixture, MIXTURE),
    ] {
        for n in [2, 3] {
            let mut r = Pcg64::seed_from_u64(2000 + n);
            let mut v = vec![Vec::new(); 3];
            for _ in 0..4_000 {
                let mut es = vec![
                    Method::Balance.build(&layout, &Params::default()).unwrap(),
                    Method::OptimalUncorrelated
                        .build(&layout, &Params::default())
                        .unwrap(),
                    Method::OptimalUncorrelated.build(&layout, &shared).unwrap(),
                ];
                for _ in 0..n {
                    problem.iteration(&mut r, &[1, 1, 1], &|x, o| o[0] = f(x), &mut es);
                }
                for (k, e) in es.iter().enumerate() {
                    v[k].push(e.estimate_vec()[0]);
                }
            }
            let rmse: Vec<f64> = v.iter().map(|x| mse(x, reference).sqrt()).collect();
            let (default, shared) = (rmse[1] / rmse[0], rmse[2] / rmse[0]);
            println!(
                "fail {}, N = {n}: uncorrelated default {default:.3}, λ=0.1 {shared:.3}",
                problem.fail
            );
            assert!(default < 1.3, "N = {n}: {default}");
            assert!(shared > 2.0, "N = {n}: {shared}");
        }
    }
}
