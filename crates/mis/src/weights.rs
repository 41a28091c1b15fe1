//! Per-sample optimal MIS weights for a given α, for callers that need a weight per sample
//! (splatting, path reuse) rather than the estimators' sums.
//!
//! `w_i(x) = α_i p_i/f + (n_i p_i/s)(1 − Σ_k α_k p_k/f)` (Kondapaneni et al. 2019, eq. 13).
//! They sum to 1 over i wherever f ≠ 0 and s > 0, may be negative, and give the multi-sample
//! term `w_i f/(n_i p_i) = α_i/n_i + (f − Σ_k α_k p_k)/s` ([`optimal_contribution`]), which is
//! what [`crate::Progressive`] accumulates.

use crate::Layout;

/// The optimal weight of technique `t` at a sample with integrand value `f` (one channel,
/// `alpha` its length-T column). `None` where the weight is undefined: f = 0, or no
/// technique has positive density (use [`optimal_contribution`], which is finite there).
pub fn optimal_weight(
    layout: &Layout,
    alpha: &[f64],
    t: usize,
    f: f64,
    pdfs: &[f64],
) -> Option<f64> {
    let s = layout.mixture(pdfs);
    if f == 0.0 || !(s > 0.0 && s.is_finite()) {
        return None;
    }
    let cv: f64 = alpha.iter().zip(pdfs).map(|(a, p)| a * p).sum();
    let n = layout.counts()[t];
    Some(alpha[t] * pdfs[t] / f + n * pdfs[t] / s * (1.0 - cv / f))
}

/// `w_t f / (n_t p_t) = α_t/n_t + (f − Σ_k α_k p_k)/s`: one sample's term of the
/// multi-sample estimator with optimal weights. 0 for a failed sample (own pdf 0): on the
/// failure point of [`crate::Moments`] the two parts cancel.
pub fn optimal_contribution(layout: &Layout, alpha: &[f64], t: usize, f: f64, pdfs: &[f64]) -> f64 {
    let Some(s) = layout.is_valid(t, pdfs) else {
        return 0.0;
    };
    let cv: f64 = alpha.iter().zip(pdfs).map(|(a, p)| a * p).sum();
    alpha[t] / layout.counts()[t] + (f - cv) / s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn optimal_weights_sum_to_one_and_match_the_contribution() {
        let layout = Layout::new(&[1, 2, 3], 1);
        let alpha = [0.7, -1.2, 0.4];
        for (f, pdfs) in [
            (1.5, [0.3, 1.1, 0.2]),
            (-0.4, [2.0, 0.0, 0.5]),
            (3.0, [0.0, 0.0, 0.1]),
        ] {
            let w: Vec<f64> = (0..3)
                .map(|t| optimal_weight(&layout, &alpha, t, f, &pdfs).unwrap())
                .collect();
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14, "{w:?}");
            for t in 0..3 {
                let n = layout.counts()[t];
                let c = optimal_contribution(&layout, &alpha, t, f, &pdfs);
                if pdfs[t] > 0.0 {
                    assert!(
                        (c - w[t] * f / (n * pdfs[t])).abs() < 1e-13,
                        "{t}: {c} vs {w:?}"
                    );
                } else {
                    assert_eq!(c, 0.0);
                    assert_eq!(w[t], 0.0);
                }
            }
        }
        assert_eq!(
            optimal_weight(&layout, &alpha, 0, 0.0, &[1.0, 1.0, 1.0]),
            None
        );
        assert_eq!(optimal_weight(&layout, &alpha, 0, 1.0, &[0.0; 3]), None);
        // α = 0 gives the balance heuristic.
        let w = optimal_weight(&layout, &[0.0; 3], 1, 2.0, &[1.0, 1.0, 1.0]).unwrap();
        assert!((w - 2.0 / 6.0).abs() < 1e-15);
    }
}
