//! The classical MIS weighting functions (Veach 1997, §9.2): balance, power, maximum and
//! cutoff heuristics, as pure functions of the sample counts and the pdfs at one point.
//!
//! Every heuristic is written in terms of `q_k = n_k p_k(x)` (the *effective* densities),
//! so it serves the multi-sample model (`n_k` = samples per iteration) and the one-sample
//! model (`n_k` = selection probability `c_k`) alike. Where some `q_k > 0` the weights are
//! non-negative and sum to 1, which makes every multi-sample estimator built on them
//! unbiased (Veach 1997, Theorem 9.2); where all `q_k = 0` every weight is 0.

use crate::ParamError;
use std::fmt;

/// A heuristic weighting function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Heuristic {
    /// `w_i = q_i / Σ q_k` (Veach 1997, eq. 9.8): never much worse than any other weighting.
    Balance,
    /// `w_i = q_i^β / Σ q_k^β` (Veach 1997, eq. 9.13); β = 2 is the usual choice.
    Power {
        /// The exponent β > 0 (β = 1 is the balance heuristic, β → ∞ the maximum).
        beta: f64,
    },
    /// Weight 1 to the technique with the largest `q_k` (the first one on ties), 0 elsewhere.
    Maximum,
    /// Balance over the techniques with `q_k ≥ c · max_j q_j` (Veach 1997, eq. 9.12).
    Cutoff {
        /// The threshold c ∈ [0, 1] (c = 0 is balance); 0.5 is typical.
        c: f64,
    },
}

impl Heuristic {
    /// Checks the parameter: β finite and > 0, c in [0, 1].
    pub fn validate(&self) -> Result<(), ParamError> {
        match *self {
            Heuristic::Power { beta } if !(beta > 0.0 && beta.is_finite()) => {
                Err(ParamError::Beta(beta))
            }
            Heuristic::Cutoff { c } if !(0.0..=1.0).contains(&c) => Err(ParamError::Cutoff(c)),
            _ => Ok(()),
        }
    }

    /// The weight of technique `t` at a point where technique k has pdf `pdfs[k]` and
    /// `counts[k]` samples (or selection probability). O(T), no allocation.
    pub fn weight(&self, t: usize, counts: &[f64], pdfs: &[f64]) -> f64 {
        debug_assert_eq!(counts.len(), pdfs.len());
        let q = |k: usize| counts[k] * pdfs[k];
        let qt = q(t);
        if qt.is_nan() || qt <= 0.0 {
            return 0.0;
        }
        match *self {
            Heuristic::Balance => qt / counts.iter().zip(pdfs).map(|(n, p)| n * p).sum::<f64>(),
            Heuristic::Power { beta } => {
                // Normalise by the largest q so that q^β neither overflows nor underflows.
                let qs = counts.iter().zip(pdfs).map(|(n, p)| n * p);
                let max = qs.clone().fold(0.0, f64::max);
                let pow = |x: f64| {
                    if beta == 2.0 {
                        x * x
                    } else {
                        x.powf(beta)
                    }
                };
                pow(qt / max) / qs.map(|q| pow(q / max)).sum::<f64>()
            }
            Heuristic::Maximum => {
                let first_max = (0..pdfs.len()).all(|k| if k < t { q(k) < qt } else { q(k) <= qt });
                f64::from(u8::from(first_max))
            }
            Heuristic::Cutoff { c } => {
                let max = (0..pdfs.len()).map(q).fold(0.0, f64::max);
                let floor = c * max;
                if qt < floor {
                    return 0.0;
                }
                qt / (0..pdfs.len()).map(q).filter(|&v| v >= floor).sum::<f64>()
            }
        }
    }

    /// `w_t / q_t`: the factor of `f` in technique t's term `w_t f / (n_t p_t)` of the
    /// multi-sample estimator (Veach 1997, eq. 9.4); 0 where `w_t` is. The power heuristic
    /// with β = 2 takes `x_k = q_k / max` through one reciprocal, and `w_t / q_t =
    /// x_t² / (Σ x_k² · q_t) = x_t / (max · Σ x_k²)`: two divisions where
    /// [`Self::weight`] then `/ q_t` takes T + 2 (each draw of every scene under the power
    /// heuristic pays them; docs/notebook/2026-12-02-cpu-speed-round-10.md).
    #[inline]
    pub fn scale(&self, t: usize, counts: &[f64], pdfs: &[f64]) -> f64 {
        debug_assert_eq!(counts.len(), pdfs.len());
        let qt = counts[t] * pdfs[t];
        if qt.is_nan() || qt <= 0.0 {
            return 0.0;
        }
        if let Heuristic::Power { beta: 2.0 } = *self {
            let qs = counts.iter().zip(pdfs).map(|(n, p)| n * p);
            let max = qs.clone().fold(0.0, f64::max);
            // Past the normal range 1/max would overflow: the general form below.
            if max >= f64::MIN_POSITIVE && max.is_finite() {
                let r = 1.0 / max;
                let sum = qs.map(|q| (q * r) * (q * r)).sum::<f64>();
                return qt * r * r / sum;
            }
        }
        self.weight(t, counts, pdfs) / qt
    }

    /// All T weights at one point into `out` (they sum to 1 where any `q_k > 0`).
    pub fn weights(&self, counts: &[f64], pdfs: &[f64], out: &mut [f64]) {
        for (t, w) in out.iter_mut().enumerate() {
            *w = self.weight(t, counts, pdfs);
        }
    }
}

impl fmt::Display for Heuristic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Heuristic::Balance => write!(f, "balance"),
            Heuristic::Power { beta } => write!(f, "power (β = {beta})"),
            Heuristic::Maximum => write!(f, "maximum"),
            Heuristic::Cutoff { c } => write!(f, "cutoff (c = {c})"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [Heuristic; 6] = [
        Heuristic::Balance,
        Heuristic::Power { beta: 2.0 },
        Heuristic::Power { beta: 3.5 },
        Heuristic::Maximum,
        Heuristic::Cutoff { c: 0.5 },
        Heuristic::Cutoff { c: 1.0 },
    ];

    #[test]
    fn weights_sum_to_one_wherever_a_pdf_is_positive() {
        let counts = [1.0, 2.0, 4.0];
        let cases: [[f64; 3]; 7] = [
            [1.0, 0.5, 0.25], // all q equal: ties everywhere
            [3.0, 0.0, 0.1],
            [0.0, 0.0, 7.0],
            [1e-300, 1e-300, 0.0],
            [1e200, 3e199, 1e150],
            [0.2, 0.9, 0.4],
            [0.0, 1.0, 0.0],
        ];
        let mut w = [0.0; 3];
        for h in ALL {
            for pdfs in &cases {
                h.weights(&counts, pdfs, &mut w);
                let sum: f64 = w.iter().sum();
                assert!((sum - 1.0).abs() < 1e-14, "{h}: {pdfs:?} → {w:?}");
                for (k, &wk) in w.iter().enumerate() {
                    assert!((0.0..=1.0).contains(&wk));
                    if pdfs[k] == 0.0 {
                        assert_eq!(wk, 0.0, "zero pdf must get zero weight");
                    }
                }
            }
            h.weights(&counts, &[0.0; 3], &mut w);
            assert_eq!(w, [0.0; 3], "{h}: no pdf, no weight");
        }
    }

    /// `scale` is `weight / q_t`: within 4 ulps for the power heuristic with β = 2 (its
    /// own two-division form; where that weight underflows, both are negligible), bit for
    /// bit for the others, over pdfs spread across the whole range of f64, the subnormal
    /// and infinite ones included, and 0 where q_t is.
    #[test]
    fn scale_is_the_weight_over_q() {
        use rand::{Rng, SeedableRng};
        let counts = [1.0, 2.0, 0.5];
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let special = [
            0.0,
            1e-310,
            f64::MIN_POSITIVE,
            1e-300,
            1.0,
            1e300,
            f64::INFINITY,
        ];
        let mut cases = Vec::new();
        for a in special {
            for b in special {
                cases.push([a, b, 0.25]);
            }
        }
        for _ in 0..20_000 {
            cases.push([0; 3].map(|_| {
                if rng.gen_bool(0.1) {
                    0.0
                } else {
                    rng.gen_range(0.0..1.0) * 10f64.powi(rng.gen_range(-300..300))
                }
            }));
        }
        for h in ALL {
            for pdfs in &cases {
                for t in 0..3 {
                    let q = counts[t] * pdfs[t];
                    let w = h.weight(t, &counts, pdfs);
                    let want = if q > 0.0 && w != 0.0 { w / q } else { 0.0 };
                    let got = h.scale(t, &counts, pdfs);
                    if want.is_nan() {
                        // An infinite pdf: no weight (callers reject these draws first).
                        assert!(got.is_nan(), "{h}, t = {t}, {pdfs:?}: {got:e}");
                    } else if q > 0.0 && w < 1e-290 && h == (Heuristic::Power { beta: 2.0 }) {
                        // w (the reference) loses its digits as x_t² underflows, where
                        // the two-division form keeps them: both weights must be tiny.
                        assert!(got * q <= 1e-290, "{h}, t = {t}, {pdfs:?}: {got:e}");
                    } else if h == (Heuristic::Power { beta: 2.0 }) {
                        let tol = 4.0 * f64::EPSILON * want.abs();
                        assert!(
                            (got - want).abs() <= tol || got == want,
                            "{h}, t = {t}, {pdfs:?}: {got:e} against {want:e}"
                        );
                    } else {
                        assert_eq!(got.to_bits(), want.to_bits(), "{h}, t = {t}, {pdfs:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn heuristics_match_hand_computed_weights() {
        let counts = [1.0, 1.0, 2.0];
        let pdfs = [1.0, 3.0, 1.0]; // q = 1, 3, 2
        let mut w = [0.0; 3];
        Heuristic::Balance.weights(&counts, &pdfs, &mut w);
        assert_eq!(w, [1.0 / 6.0, 0.5, 1.0 / 3.0]);
        Heuristic::Power { beta: 2.0 }.weights(&counts, &pdfs, &mut w);
        let e = [1.0 / 14.0, 9.0 / 14.0, 4.0 / 14.0];
        assert!(w.iter().zip(e).all(|(a, b)| (a - b).abs() < 1e-15), "{w:?}");
        Heuristic::Power { beta: 1.0 }.weights(&counts, &pdfs, &mut w);
        assert!((w[1] - 0.5).abs() < 1e-15);
        Heuristic::Maximum.weights(&counts, &pdfs, &mut w);
        assert_eq!(w, [0.0, 1.0, 0.0]);
        // c = 0.5: floor 1.5, techniques 1 and 2 survive: 3/5, 2/5.
        Heuristic::Cutoff { c: 0.5 }.weights(&counts, &pdfs, &mut w);
        assert_eq!(w, [0.0, 0.6, 0.4]);
        Heuristic::Cutoff { c: 0.0 }.weights(&counts, &pdfs, &mut w);
        assert_eq!(w, [1.0 / 6.0, 0.5, 1.0 / 3.0]);
    }

    #[test]
    fn parameters_are_validated() {
        assert!(Heuristic::Power { beta: 0.0 }.validate().is_err());
        assert!(Heuristic::Power {
            beta: f64::INFINITY
        }
        .validate()
        .is_err());
        assert!(Heuristic::Cutoff { c: 1.5 }.validate().is_err());
        assert!(Heuristic::Cutoff { c: f64::NAN }.validate().is_err());
        assert!(ALL.iter().all(|h| h.validate().is_ok()));
    }
}
