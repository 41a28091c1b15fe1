//! The one-sample MIS model (Veach 1997, §9.2.4): each sample first picks technique i with
//! probability `c_i`, draws X from `p_i`, and contributes `w_i(X) f(X) / (c_i p_i(X))`.
//!
//! Unbiased for weights that sum to 1 (Veach 1997, Theorem 9.4 with the `c_i` in place of
//! `n_i`); the balance heuristic is optimal among all weightings here (Theorem 9.5), and
//! its term is `f / Σ_k c_k p_k`. Optimal-MIS α does not apply to this model. State: one sum
//! per channel and the sample count (failed samples included), merged by addition.

use crate::Heuristic;

/// A one-sample MIS estimator with selection probabilities `c_i`.
#[derive(Clone, Debug, PartialEq)]
pub struct OneSample {
    probabilities: Vec<f64>,
    heuristic: Heuristic,
    sums: Vec<f64>,
    samples: u64,
}

impl OneSample {
    /// `probabilities` = `c_i` > 0 summing to 1 (to 1e-9); `channels` values of f per sample.
    pub fn new(probabilities: &[f64], heuristic: Heuristic, channels: usize) -> OneSample {
        assert!(
            probabilities.iter().all(|&c| c > 0.0),
            "selection probabilities must be > 0"
        );
        let total: f64 = probabilities.iter().sum();
        assert!(
            (total - 1.0).abs() < 1e-9,
            "selection probabilities sum to {total}, not 1"
        );
        if let Err(e) = heuristic.validate() {
            panic!("{e}");
        }
        assert!(channels >= 1, "at least one channel");
        OneSample {
            probabilities: probabilities.to_vec(),
            heuristic,
            sums: vec![0.0; channels],
            samples: 0,
        }
    }

    /// Picks a technique from a uniform `u ∈ [0, 1)`; returns it and `u` rescaled to [0, 1)
    /// within its slot, so the same number can drive the technique's own sampling.
    pub fn select(&self, u: f64) -> (usize, f64) {
        let mut lo = 0.0;
        let last = self.probabilities.len() - 1;
        for (i, &c) in self.probabilities.iter().enumerate() {
            if u < lo + c || i == last {
                return (i, ((u - lo) / c).clamp(0.0, 1.0 - f64::EPSILON / 2.0));
            }
            lo += c;
        }
        unreachable!("probabilities are not empty")
    }

    /// One sample drawn by the selected `technique`, with f per channel and all pdfs.
    pub fn add_sample(&mut self, technique: usize, f: &[f64], pdfs: &[f64]) {
        self.samples += 1;
        let (c, p) = (self.probabilities[technique], pdfs[technique]);
        if p.is_nan() || p <= 0.0 {
            return;
        }
        let scale = self.heuristic.weight(technique, &self.probabilities, pdfs) / (c * p);
        if scale != 0.0 && scale.is_finite() {
            for (sum, fc) in self.sums.iter_mut().zip(f) {
                *sum += fc * scale;
            }
        }
    }

    /// The selected technique produced no sample (it still counts).
    pub fn add_failed(&mut self) {
        self.samples += 1;
    }

    /// Samples so far, failed ones included.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// The mean per channel (0 before the first sample).
    pub fn estimate(&self, out: &mut [f64]) {
        let n = self.samples.max(1) as f64;
        for (o, s) in out.iter_mut().zip(&self.sums) {
            *o = s / n;
        }
    }

    /// Adds another state with the same probabilities and heuristic.
    pub fn merge(&mut self, other: &OneSample) {
        assert_eq!(
            self.probabilities, other.probabilities,
            "different probabilities"
        );
        assert_eq!(self.heuristic, other.heuristic, "different heuristics");
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            *a += b;
        }
        self.samples += other.samples;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn select_partitions_the_unit_interval() {
        let e = OneSample::new(&[0.25, 0.5, 0.25], Heuristic::Balance, 1);
        assert_eq!(e.select(0.0), (0, 0.0));
        assert_eq!(e.select(0.125), (0, 0.5));
        assert_eq!(e.select(0.5), (1, 0.5));
        assert_eq!(e.select(0.875), (2, 0.5));
        let (t, u) = e.select(1.0 - 1e-17);
        assert_eq!(t, 2);
        assert!(u < 1.0);
    }
}
