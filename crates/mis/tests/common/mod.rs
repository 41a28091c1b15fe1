//! A 1-D test problem with known answers, shared by the integration tests and the example.
//!
//! Domain [0, 1], three techniques: p₀ = 1 (uniform), p₁ = 2x (linear, optionally
//! defective: it fails with probability `fail`, so its pdf is (1 − fail)·2x), p₂ = 3(1 − x)².
#![allow(dead_code)]

use mis::{AnyEstimator, Estimator};
use rand::Rng;
use rand_pcg::Pcg64;

/// The test problem.
#[derive(Clone, Debug)]
pub struct Problem {
    /// Probability that technique 1 produces no sample.
    pub fail: f64,
}

/// A mixture-like integrand outside the span of the pdfs: 0.5 + 3x² + 0.3(1 − x)⁴.
pub fn mixture(x: f64) -> f64 {
    0.5 + 3.0 * x * x + 0.3 * (1.0 - x).powi(4)
}
/// ∫₀¹ [`mixture`].
pub const MIXTURE: f64 = 1.56;

/// A linear combination of the (proper) pdfs: 0.7 p₀ − 0.4 p₁ + 1.3 p₂, negative near x = 1.
pub fn linear(x: f64) -> f64 {
    0.7 - 0.4 * 2.0 * x + 1.3 * 3.0 * (1.0 - x) * (1.0 - x)
}
/// ∫₀¹ [`linear`].
pub const LINEAR: f64 = 1.6;

impl Problem {
    /// Proper pdfs.
    pub const PROPER: Problem = Problem { fail: 0.0 };

    /// The three pdfs at x (solid measure on [0, 1]).
    pub fn pdfs(&self, x: f64) -> [f64; 3] {
        [
            1.0,
            (1.0 - self.fail) * 2.0 * x,
            3.0 * (1.0 - x) * (1.0 - x),
        ]
    }

    /// A draw of technique t, or None if it failed.
    pub fn draw(&self, t: usize, rng: &mut Pcg64) -> Option<f64> {
        let u: f64 = rng.gen();
        match t {
            0 => Some(u),
            1 => {
                if rng.gen::<f64>() < self.fail {
                    None
                } else {
                    Some(u.sqrt())
                }
            }
            _ => Some(1.0 - (1.0 - u).cbrt()),
        }
    }

    /// One iteration: `counts[t]` draws of each technique, every sample fed to every
    /// estimator; `f(x, out)` writes the channels.
    pub fn iteration(
        &self,
        rng: &mut Pcg64,
        counts: &[u32],
        f: &dyn Fn(f64, &mut [f64]),
        estimators: &mut [AnyEstimator],
    ) {
        let channels = estimators[0].layout().channels();
        let mut fx = vec![0.0; channels];
        for (t, &n) in counts.iter().enumerate() {
            for _ in 0..n {
                match self.draw(t, rng) {
                    Some(x) => {
                        f(x, &mut fx);
                        let pdfs = self.pdfs(x);
                        for e in estimators.iter_mut() {
                            e.add_sample(t, &fx, &pdfs);
                        }
                    }
                    None => {
                        for e in estimators.iter_mut() {
                            e.add_failed(t);
                        }
                    }
                }
            }
        }
        for e in estimators.iter_mut() {
            e.end_iteration();
        }
    }
}

/// Mean, variance (unbiased) and standard error of a sample.
pub fn stats(v: &[f64]) -> (f64, f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    (mean, var, (var / n).sqrt())
}

/// Mean squared error against a reference.
pub fn mse(v: &[f64], reference: f64) -> f64 {
    v.iter()
        .map(|x| (x - reference) * (x - reference))
        .sum::<f64>()
        / v.len() as f64
}

/// A peak the pdfs do not follow: exp(−40(x − 0.7)²).
pub fn peak(x: f64) -> f64 {
    (-40.0 * (x - 0.7) * (x - 0.7)).exp()
}

/// ∫₀¹ [`peak`], by composite Simpson with 20 000 panels (error ≪ 1e-12).
pub fn peak_integral() -> f64 {
    let n = 20_000;
    let h = 1.0 / n as f64;
    let mut s = peak(0.0) + peak(1.0);
    for i in 1..n {
        s += peak(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}
