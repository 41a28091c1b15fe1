//! The multi-sample MIS estimator with a heuristic weighting function (Veach 1997, eq. 9.4):
//! `F̂ = (1/N) Σ_iterations Σ_i (1/n_i) Σ_j w_i(X_ij) f(X_ij) / p_i(X_ij)`.
//!
//! Unbiased whenever the weights sum to 1 where f ≠ 0 (Veach 1997, Theorem 9.2), which all
//! [`Heuristic`]s do. With the balance heuristic each term is simply `f / s`. A failed sample
//! adds nothing (its weight is 0): the lost mass of a defective pdf is covered by the other
//! techniques. State: one sum per channel and the iteration count.

use std::sync::Arc;

use crate::{Estimator, Heuristic, Layout};

/// A heuristic multi-sample estimator (balance, power, maximum, cutoff).
#[derive(Clone, Debug)]
pub struct Weighted {
    layout: Arc<Layout>,
    heuristic: Heuristic,
    sums: Vec<f64>,
    iterations: u64,
}

impl Weighted {
    /// An empty estimator. Panics if the heuristic's parameter is out of range.
    pub fn new(layout: Arc<Layout>, heuristic: Heuristic) -> Weighted {
        if let Err(e) = heuristic.validate() {
            panic!("{e}");
        }
        let sums = vec![0.0; layout.channels()];
        Weighted {
            layout,
            heuristic,
            sums,
            iterations: 0,
        }
    }

    /// The weighting function.
    pub fn heuristic(&self) -> Heuristic {
        self.heuristic
    }
}

impl Estimator for Weighted {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    #[inline]
    fn add_sample(&mut self, technique: usize, f: &[f64], pdfs: &[f64]) {
        debug_assert_eq!(f.len(), self.sums.len(), "one f value per channel");
        let Some(s) = self.layout.is_valid(technique, pdfs) else {
            return;
        };
        // w_t f / (n_t p_t); for balance w_t / (n_t p_t) = 1/s exactly.
        let scale = match self.heuristic {
            Heuristic::Balance => 1.0 / s,
            h => {
                let n = self.layout.counts();
                h.weight(technique, n, pdfs) / (n[technique] * pdfs[technique])
            }
        };
        if scale != 0.0 {
            for (sum, fc) in self.sums.iter_mut().zip(f) {
                *sum += fc * scale;
            }
        }
    }

    fn add_failed(&mut self, _technique: usize) {}

    fn end_iteration(&mut self) {
        self.iterations += 1;
    }

    fn iterations(&self) -> u64 {
        self.iterations
    }

    fn estimate(&self, out: &mut [f64]) {
        let n = self.iterations.max(1) as f64;
        for (o, s) in out.iter_mut().zip(&self.sums) {
            *o = s / n;
        }
    }

    fn merge(&mut self, other: &Weighted) {
        self.layout.assert_same(&other.layout);
        assert_eq!(
            self.heuristic, other.heuristic,
            "cannot merge different heuristics"
        );
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            *a += b;
        }
        self.iterations += other.iterations;
    }
}
