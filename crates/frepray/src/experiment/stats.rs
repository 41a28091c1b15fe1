//! Confidence intervals over the seeds of a point: a few independent renders per
//! estimator and sample count, each giving one MSE. An image's MSE averages thousands
//! of pixels, so over seeds it is close to normal and Student's t applies; ratios of two
//! estimators' mean MSEs (the renders of one seed share it, so they are paired) get the
//! delta method on their logarithm (e.g. Casella & Berger, *Statistical Inference*,
//! §5.5.4), which keeps the interval positive.

/// The two-sided 95 % quantile of Student's t with `dof` degrees of freedom
/// (t₀.₉₇₅; tabulated to 30, then the normal's 1.96 plus the 1/dof correction).
pub fn t975(dof: usize) -> f64 {
    const T: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match dof {
        0 => f64::NAN,
        d if d <= 30 => T[d - 1],
        d => 1.959_964 + 2.4 / d as f64,
    }
}

/// The mean of `x` (NaN when empty).
pub fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

/// The sample covariance of paired `x`, `y` (n − 1 in the denominator).
fn covariance(x: &[f64], y: &[f64]) -> f64 {
    let (mx, my) = (mean(x), mean(y));
    x.iter()
        .zip(y)
        .map(|(a, b)| (a - mx) * (b - my))
        .sum::<f64>()
        / (x.len() as f64 - 1.0)
}

/// The 95 % interval of the mean of `x`: `mean ± t·s/√k`; `None` below two values or
/// where a value is not finite.
pub fn mean_ci(x: &[f64]) -> Option<[f64; 2]> {
    let k = x.len();
    if k < 2 || x.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let half = t975(k - 1) * (covariance(x, x) / k as f64).sqrt();
    let m = mean(x);
    Some([m - half, m + half])
}

/// The 95 % interval of `mean(a) / mean(b)` for paired positive samples, by the delta
/// method on `ln mean(a) − ln mean(b)`:
/// `Var ≈ (s²_a/ā² + s²_b/b̄² − 2 s_ab/(ā b̄)) / k`, with t on k − 1 degrees of freedom.
/// `None` below two pairs or where a mean is not finite and positive.
pub fn ratio_ci(a: &[f64], b: &[f64]) -> Option<[f64; 2]> {
    let k = a.len();
    if k < 2 || b.len() != k || a.iter().chain(b).any(|v| !v.is_finite()) {
        return None;
    }
    let (ma, mb) = (mean(a), mean(b));
    if !(ma > 0.0 && mb > 0.0) {
        return None;
    }
    let var = (covariance(a, a) / (ma * ma) + covariance(b, b) / (mb * mb)
        - 2.0 * covariance(a, b) / (ma * mb))
        / k as f64;
    let half = t975(k - 1) * var.max(0.0).sqrt();
    let r = (ma / mb).ln();
    Some([(r - half).exp(), (r + half).exp()])
}

/// The median of `x` (NaN values last; NaN when empty).
pub fn median(x: &mut [f64]) -> f64 {
    if x.is_empty() {
        return f64::NAN;
    }
    x.sort_by(|a, b| a.total_cmp(b));
    let n = x.len();
    if n % 2 == 1 {
        x[n / 2]
    } else {
        0.5 * (x[n / 2 - 1] + x[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic uniform stream (splitmix64).
    struct Rng(u64);
    impl Rng {
        fn uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The MSE of one "image" of `pixels` independent Monte Carlo estimates of
    /// ∫₀¹ x² dx = 1/3 from `n` uniform samples each, against the exact value.
    fn image_mse(rng: &mut Rng, pixels: usize, n: usize) -> f64 {
        (0..pixels)
            .map(|_| {
                let est = (0..n).map(|_| rng.uniform().powi(2)).sum::<f64>() / n as f64;
                (est - 1.0 / 3.0).powi(2)
            })
            .sum::<f64>()
            / pixels as f64
    }

    #[test]
    fn t_quantiles() {
        assert_eq!(t975(1), 12.706);
        assert_eq!(t975(3), 3.182);
        assert!((t975(60) - 2.000).abs() < 0.002, "{}", t975(60));
        assert!((t975(1000) - 1.962).abs() < 0.001);
        assert!(t975(0).is_nan());
    }

    #[test]
    fn intervals_by_hand() {
        // mean 2, s² = 1, k = 3: 2 ± 4.303/√3.
        let ci = mean_ci(&[1.0, 2.0, 3.0]).unwrap();
        let half = 4.303 / 3f64.sqrt();
        assert!((ci[0] - (2.0 - half)).abs() < 1e-12 && (ci[1] - (2.0 + half)).abs() < 1e-12);
        assert!(mean_ci(&[1.0]).is_none());
        assert!(mean_ci(&[1.0, f64::NAN]).is_none());
        // Exactly proportional pairs: the ratio is known without error.
        let ci = ratio_ci(&[2.0, 4.0, 6.0], &[1.0, 2.0, 3.0]).unwrap();
        assert!(
            (ci[0] - 2.0).abs() < 1e-12 && (ci[1] - 2.0).abs() < 1e-12,
            "{ci:?}"
        );
        assert!(ratio_ci(&[1.0, 2.0], &[0.0, 0.0]).is_none());
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
    }

    /// The intervals cover the true value at their nominal 95 % on a 1-D integral with a
    /// known answer: ∫₀¹ x² dx by n uniform samples has MSE Var(x²)/n = (1/5 − 1/9)/n =
    /// 4/(45n). 2000 experiments of 4 seeds, each seed an image of 256 pixel estimates:
    /// the share that covers must lie in [0.93, 0.97] (the binomial standard deviation
    /// at 0.95 is 0.0049; ±4σ allows for t's approximation of the slightly skewed MSE).
    /// The ratio interval pairs an n-sample and a 2n-sample estimator (true ratio 2).
    #[test]
    fn intervals_cover_at_their_nominal_rate() {
        let (experiments, seeds, pixels, n) = (2000, 4, 256, 8);
        let truth = 4.0 / (45.0 * n as f64);
        let mut rng = Rng(12345);
        let (mut cover_mean, mut cover_ratio) = (0, 0);
        for _ in 0..experiments {
            let a: Vec<f64> = (0..seeds).map(|_| image_mse(&mut rng, pixels, n)).collect();
            let b: Vec<f64> = (0..seeds)
                .map(|_| image_mse(&mut rng, pixels, 2 * n))
                .collect();
            let m = mean_ci(&a).unwrap();
            cover_mean += usize::from(m[0] <= truth && truth <= m[1]);
            let r = ratio_ci(&a, &b).unwrap();
            cover_ratio += usize::from(r[0] <= 2.0 && 2.0 <= r[1]);
        }
        let (cm, cr) = (
            cover_mean as f64 / experiments as f64,
            cover_ratio as f64 / experiments as f64,
        );
        println!("coverage: mean {cm:.4}, ratio {cr:.4}");
        assert!((0.93..=0.97).contains(&cm), "mean interval covers {cm}");
        assert!((0.93..=0.97).contains(&cr), "ratio interval covers {cr}");
    }
}
