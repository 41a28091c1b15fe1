//! Tests of the power and Bernstein forms and of the first-sign-change search.

use super::*;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// The monic polynomial with the given roots (scaled by k).
fn from_roots(k: f64, roots: &[f64]) -> Poly<f64> {
    let mut p = Poly::new(&[k]);
    for &r in roots {
        p = p.mul(&Poly::new(&[-r, 1.0]));
    }
    p
}

/// The root error that rounding of the coefficients allows: a relative coefficient
/// error δ moves a root w of multiplicity m of k·Π(u − r) by about
/// (δ·Σ|c| / |k·Π_{r≠w}(w − r)|)^{1/m}; with δ·Σ|c|/|k| ≤ 2e-13 (degree ≤ 6, roots
/// in [−½, 1½]), plus 1e-12.
fn conditioning_tolerance(roots: &[f64], w: f64) -> f64 {
    let m = roots.iter().filter(|&&r| r == w).count() as i32;
    let prod: f64 = roots.iter().filter(|&&r| r != w).map(|r| w - r).product();
    1e-12 + (2e-13 / prod.abs()).powf(1.0 / m as f64)
}

#[test]
fn arithmetic_matches_direct_evaluation() {
    let p = Poly::new(&[1.0, -2.0, 0.5]);
    let q = Poly::new(&[0.3, 4.0]);
    for x in [-2.0, -0.3, 0.0, 0.7, 3.1] {
        let (pv, qv) = (p.eval(x), q.eval(x));
        assert!((p.add(&q).eval(x) - (pv + qv)).abs() < 1e-12);
        assert!((p.mul(&q).eval(x) - pv * qv).abs() < 1e-12);
        assert!((p.derivative().eval(x) - (-2.0 + x)).abs() < 1e-12);
        let mut c = Poly::new(&[0.25]);
        c.add_scaled_cube(-1.5, [1.0, -2.0, 0.5]);
        assert!((c.eval(x) - (0.25 - 1.5 * pv * pv * pv)).abs() < 1e-9 * (1.0 + pv.powi(3).abs()));
        assert!((p.shifted(0.4).eval(x) - p.eval(0.4 + x)).abs() < 1e-12);
        assert!((p.scaled(-1.7).eval(x) - p.eval(-1.7 * x)).abs() < 1e-12);
    }
    let piece = from_roots(2.0, &[0.1, 0.5, 0.9, 1.3, 2.0, -1.0]).on_interval(0.25, 1.75);
    for u in [0.0, 0.2, 0.5, 1.0] {
        let t = 0.25 + 1.5 * u;
        let direct = from_roots(2.0, &[0.1, 0.5, 0.9, 1.3, 2.0, -1.0]).eval(t);
        assert!((piece.eval(u) - direct).abs() < 1e-12);
    }
}

#[test]
fn bernstein_form_agrees_with_power_form_and_splits_consistently() {
    let mut rng = Pcg64::seed_from_u64(1);
    for n in 0..=MAX_DEGREE {
        let c: Vec<f64> = (0..=n).map(|_| rng.gen_range(-3.0..3.0)).collect();
        let p = Poly::new(&c);
        let b = p.to_bernstein();
        let (l, r) = b.split_half();
        for i in 0..=20 {
            let u = i as f64 / 20.0;
            assert!((b.eval(u) - p.eval(u)).abs() < 1e-12, "n={n} u={u}");
            assert!((l.eval(u) - p.eval(0.5 * u)).abs() < 1e-12);
            assert!((r.eval(u) - p.eval(0.5 + 0.5 * u)).abs() < 1e-12);
        }
        // Endpoint interpolation and the convex hull property.
        assert!((b.coeffs()[0] - p.eval(0.0)).abs() < 1e-12);
        assert!((b.coeffs()[n] - p.eval(1.0)).abs() < 1e-12);
    }
}

#[test]
fn cauchy_bound_holds_every_root() {
    let roots = [3.0, -40.0, 0.5, 120.0];
    let p = from_roots(-0.01, &roots);
    let r = p.cauchy_bound().unwrap();
    assert!(roots.iter().all(|x| x.abs() < r));
    assert_eq!(Poly::new(&[2.0, 0.0, 0.0]).cauchy_bound(), None);
}

/// A root where p is tiny beside its largest coefficient: a uniform noise floor blurs
/// it to u = 0, per-coefficient bounds from the magnitudes of the terms find it.
#[test]
fn coefficient_error_bounds_keep_small_but_exact_features() {
    // p = 1e-12·(u − 1e-3) + u⁶: one root near u = 1e-3.
    let p = Poly::new(&[-1e-15, 1e-12, 0.0, 0.0, 0.0, 0.0, 1.0]);
    let b = p.to_bernstein();
    let blurred = b.scale(-1.0).first_negative().unwrap();
    assert!((blurred - 1e-3).abs() > 1e-4, "{blurred}");
    let mag = Poly::new(
        &p.coeffs()
            .iter()
            .map(|v| v.abs() * 32.0 * f64::EPSILON)
            .collect::<Vec<_>>(),
    );
    let err = mag.to_bernstein();
    assert_eq!(b.sign_after_zero_bounded(&err), -1.0);
    let u = b.scale(-1.0).first_negative_bounded(&err).unwrap();
    // The root (u ≈ 1e-3 − 1e-6): p changes sign within ±1e-13 of u.
    assert!(p.eval(u - 1e-13) < 0.0 && p.eval(u + 1e-13) > 0.0, "{u}");
    // The same bounds still read an exact double root as a touch.
    let touch = from_roots(1.0, &[0.3, 0.3]);
    let mag = Poly::new(
        &touch
            .coeffs()
            .iter()
            .map(|v| v.abs() * 32.0 * f64::EPSILON)
            .collect::<Vec<_>>(),
    );
    assert_eq!(
        touch
            .to_bernstein()
            .first_negative_bounded(&mag.to_bernstein()),
        None
    );
}

#[test]
fn first_sign_change_finds_simple_roots_and_ignores_tangencies() {
    let cases: &[(&[f64], Option<f64>)] = &[
        (&[0.3], Some(0.3)),
        (&[0.3, 0.31, 0.8], Some(0.3)),
        // A double root is a touch, not a crossing; the simple root after it counts.
        (&[0.37, 0.37, 0.8], Some(0.8)),
        (&[0.37, 0.37], None),
        (&[0.5, 0.5], None),
        // Roots exactly at the subdivision point and at the ends.
        (&[0.5, 0.75], Some(0.5)),
        // A root at u = 1 is not a change within [0, 1]: p is negative only after it.
        (&[1.0], None),
        (&[0.25, 0.25, 0.25], Some(0.25)),
        (&[-0.5, 1.5], None),
        // Two roots 1e-6 apart: an entry and exit, the first one is the crossing.
        (&[0.6, 0.6 + 1e-6, 0.9], Some(0.6)),
    ];
    for (roots, want) in cases {
        for k in [1.0, -1e-6, 1e6] {
            let b = from_roots(k, roots).to_bernstein();
            let got = b.first_sign_change();
            match (got, want) {
                (Some(g), Some(w)) => {
                    let tol = conditioning_tolerance(roots, *w);
                    assert!((g - w).abs() < tol, "{roots:?}: {g}")
                }
                (None, None) => {}
                _ => panic!("{roots:?} k={k}: got {got:?}, want {want:?}"),
            }
        }
    }
    // A root at u = 0 is not a change "after" 0; p ≡ 0 has none.
    assert_eq!(
        from_roots(1.0, &[0.0, 2.0])
            .to_bernstein()
            .first_sign_change(),
        None
    );
    assert_eq!(Poly::<f64>::zero().to_bernstein().first_sign_change(), None);
    // first_negative reports an already negative start at 0.
    assert_eq!(
        Poly::new(&[-1.0, 3.0]).to_bernstein().first_negative(),
        Some(0.0)
    );
}

/// Random products of linear factors (roots in and around [0, 1], with clusters):
/// the first odd-multiplicity root in (0, 1) is known exactly.
#[test]
fn random_polynomials_match_their_known_first_crossing() {
    let mut rng = Pcg64::seed_from_u64(7);
    let mut f32_checked = 0;
    for _ in 0..20_000 {
        let n = rng.gen_range(1..=MAX_DEGREE);
        let mut roots: Vec<f64> = (0..n).map(|_| rng.gen_range(-0.5..1.5)).collect();
        if n >= 2 && rng.gen_bool(0.3) {
            let sign = if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
            roots[1] = roots[0] + sign * rng.gen_range(1e-4..1e-3);
        }
        // Roots closer than 1e-4 make dips below f64 rounding: indistinguishable from
        // a double root (the tangency cases above cover those).
        let close = (0..n).any(|i| (0..i).any(|j| (roots[i] - roots[j]).abs() < 1e-4));
        if close {
            continue;
        }
        let k = if rng.gen_bool(0.5) { 1.0 } else { -1.0 } * 10f64.powf(rng.gen_range(-4.0..4.0));
        let p = from_roots(k, &roots);
        let mut inside: Vec<f64> = roots
            .iter()
            .copied()
            .filter(|r| *r > 1e-9 && *r < 1.0)
            .collect();
        inside.sort_by(f64::total_cmp);
        let want = inside.first().copied();
        let got = p.to_bernstein().first_sign_change();
        match (got, want) {
            (Some(g), Some(w)) => {
                let tol = conditioning_tolerance(&roots, w);
                assert!((g - w).abs() < tol, "{roots:?}: got {g} want {w}")
            }
            (None, None) => {}
            _ => panic!("{roots:?}: got {got:?}, want {want:?}"),
        }
        // The f32 path agrees wherever the bumps of p on either side of the first
        // root stand well above f32 rounding (1e-3 of the largest coefficient).
        if let Some(w) = want {
            let b = p.to_bernstein();
            let big = b.coeffs().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let mut pts: Vec<f64> = roots.iter().copied().chain([0.0, 1.0]).collect();
            pts.sort_by(f64::total_cmp);
            let k = pts.iter().position(|&r| r == w).unwrap();
            let bump = |a: f64, c: f64| p.eval(0.5 * (a + c)).abs();
            if bump(pts[k - 1], w).min(bump(w, pts[k + 1])) > 1e-3 * big {
                let c: Vec<f32> = p.coeffs().iter().map(|&v| v as f32).collect();
                let g32 = Poly::new(&c).to_bernstein().first_sign_change().unwrap();
                assert!(
                    (g32 as f64 - w).abs() < 1e-3,
                    "{roots:?}: f32 {g32} want {w}"
                );
                f32_checked += 1;
            }
        }
    }
    assert!(f32_checked > 5_000, "{f32_checked}");
}

/// Scaling by a long piece keeps zero coefficients zero where h^k overflows f32 (a cubed
/// linear q_i has none above degree 3); 0·∞ = NaN used to end the scan as a miss.
#[test]
fn scaling_keeps_zero_coefficients_where_the_power_overflows() {
    let mut p = Poly::<f32>::quadratic([1.0, -2.0, 0.0]);
    p.add_scaled_cube(1e-3, [2.0, 0.5, 0.0]);
    let s = p.scaled(1e7);
    assert!(s.coeffs()[..4].iter().all(|v| v.is_finite()), "{s:?}");
    assert_eq!(&s.coeffs()[4..], &[0.0; 3]);
    let b = s.to_bernstein();
    assert!(b.coeffs().iter().all(|v| v.is_finite()), "{b:?}");
}

/// The root refinement stops once Newton's step is under the tolerance, also where that
/// step lands on the bracket's end (it once bisected ~50 times back to the root from
/// there), and still answers within the conditioning tolerance on the far side of the
/// root: random polynomials of degree 2 to 6 falling through one simple root in (0, 1),
/// the other roots outside [0, 1], in Bernstein form.
#[test]
fn refinement_stops_at_convergence() {
    let mut rng = Pcg64::seed_from_u64(41);
    let mut worst = 0;
    for k in 0..20_000 {
        let n = 2 + k % 5;
        let w: f64 = rng.gen_range(0.01..0.99);
        let mut roots = vec![w];
        for _ in 1..n {
            let r: f64 = rng.gen_range(1.05..3.0);
            roots.push(if rng.gen_bool(0.5) { r } else { 1.0 - r });
        }
        let p = from_roots(1.0, &roots);
        // Falling through w: positive at 0.
        let p = p.scale(p.eval(0.0).signum() * rng.gen_range(0.01..100.0));
        let b = p.to_bernstein();
        let (u, steps) = refine_counted(&b.b, n, 0.0, 1.0);
        assert!(
            (u - w).abs() <= conditioning_tolerance(&roots, w),
            "degree {n}, root {w}: {u}"
        );
        worst = worst.max(steps);
    }
    assert!(worst <= 12, "{worst} steps");
    // The case that bisected 46 times (a perturbed ellipsoid's piece, 2026-12-01).
    let b = Bernstein::new(&[
        0.020160946359353393,
        -0.01812259884988346,
        -0.00697730659552015,
    ]);
    let (u, steps) = refine_counted(&b.b, 2, 0.0, 1.0);
    assert!(
        (u - 0.33633973260234107).abs() <= 1e-15 && steps <= 8,
        "{u} in {steps} steps"
    );
}
