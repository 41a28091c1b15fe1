//! The direct optimal-MIS estimator (Kondapaneni et al. 2019, §5): `Â` and `b̂` from the
//! same samples, `α̂ = Â⁻¹ b̂`, estimate `Σ_k α̂_k`.
//!
//! Consistent with O(1/N) bias (α̂ and the samples are correlated). With the ridge
//! `μ = (λ/N)·tr(Â)/T` ([`crate::linalg::relative_ridge`]) the solve is regularised and the
//! estimate uses the full form
//! `F = Σα + n·(b̂ − Âα)/N`, which equals `Σα` at λ = 0 and tends to the balance heuristic
//! as λ → ∞ (RESEARCH.md §2; the 1/N decay is this crate's, measured in `docs/mis.md`). State: `Â`, `b̂` and N — all sums, merged by addition.

use std::sync::Arc;

use crate::linalg::{relative_ridge, solve, SolveMethod};
use crate::{Estimator, Layout, Moments};

/// Optimal MIS, direct (correlated) estimator.
#[derive(Clone, Debug)]
pub struct Direct {
    layout: Arc<Layout>,
    ridge: f64,
    moments: Moments,
    iterations: u64,
}

impl Direct {
    /// An empty estimator with ridge λ = `ridge` ≥ 0 (`μ = (λ/N)·tr(Â)/T`).
    pub fn new(layout: Arc<Layout>, ridge: f64) -> Direct {
        assert!(
            ridge >= 0.0 && ridge.is_finite(),
            "ridge λ must be finite and ≥ 0"
        );
        let moments = Moments::new(&layout);
        Direct {
            layout,
            ridge,
            moments,
            iterations: 0,
        }
    }

    /// The accumulated sums `Â`, `b̂`.
    pub fn moments(&self) -> &Moments {
        &self.moments
    }

    /// Writes α̂ (one length-T column per channel) and reports how it was solved.
    pub fn alpha(&self, alpha: &mut [f64]) -> SolveMethod {
        solve(
            self.moments.matrix(),
            self.layout.techniques(),
            relative_ridge(self.ridge, self.iterations),
            self.moments.vectors(),
            alpha,
        )
    }
}

impl Estimator for Direct {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    #[inline]
    fn add_sample(&mut self, technique: usize, f: &[f64], pdfs: &[f64]) {
        self.moments.add(&self.layout, technique, f, pdfs);
    }

    fn add_failed(&mut self, technique: usize) {
        self.moments.add_failed(&self.layout, technique);
    }

    fn end_iteration(&mut self) {
        self.iterations += 1;
    }

    fn iterations(&self) -> u64 {
        self.iterations
    }

    fn estimate(&self, out: &mut [f64]) {
        if self.iterations == 0 {
            out.fill(0.0);
            return;
        }
        let mut alpha = vec![0.0; self.moments.vectors().len()];
        self.alpha(&mut alpha);
        let an = self.moments.matrix_times_counts(&self.layout);
        self.moments
            .full_form(&self.layout, &an, &alpha, self.iterations as f64, out);
    }

    fn merge(&mut self, other: &Direct) {
        self.layout.assert_same(&other.layout);
        self.moments.merge(&other.moments);
        self.iterations += other.iterations;
    }
}
