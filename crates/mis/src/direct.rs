//! The direct optimal-MIS estimator (Kondapaneni et al. 2019, §5): `Â` and `b̂` from the
//! same samples, `α̂ = Â⁻¹ b̂`, estimate `Σ_k α̂_k`.
//!
//! Consistent with O(1/N) bias (α̂ and the samples are correlated). With the ridge
//! `μ = (λ/N)·tr(Â)/T` ([`crate::linalg::relative_ridge`]) the solve is regularised and the
//! estimate uses the full form
//! `F = Σα + n·(b̂ − Âα)/N`, which equals `Σα` at λ = 0 and tends to the balance heuristic
//! as λ → ∞ (RESEARCH.md §2; the 1/N decay is this crate's, measured in `docs/mis.md`). State: one flat block `[N | Â | b̂]`, all sums, merged by addition
//! ([`crate::Kernel`]).

use std::sync::Arc;

use crate::linalg::{relative_ridge, solve, with_scratch, SolveMethod};
use crate::{Estimator, Layout, Moments};

/// Words of a direct estimator's block: `[N | moments]`.
pub(crate) fn block_len(layout: &Layout) -> usize {
    1 + Moments::len(layout)
}

/// α̂ of a block (one length-T column per channel), and how it was solved.
pub(crate) fn alpha(layout: &Layout, ridge: f64, block: &[f64], alpha: &mut [f64]) -> SolveMethod {
    let m = Moments::view(layout, &block[1..]);
    solve(
        m.matrix(),
        layout.techniques(),
        relative_ridge(ridge, block[0] as u64),
        m.vectors(),
        alpha,
    )
}

/// The full-form estimate of a block.
pub(crate) fn estimate(layout: &Layout, ridge: f64, block: &[f64], out: &mut [f64]) {
    let n = block[0];
    if n == 0.0 {
        out.fill(0.0);
        return;
    }
    let m = Moments::view(layout, &block[1..]);
    let t = layout.techniques();
    with_scratch(m.vectors().len() + t, |buf| {
        let (a, an) = buf.split_at_mut(m.vectors().len());
        alpha(layout, ridge, block, a);
        m.matrix_times_counts_into(layout, an);
        m.full_form(layout, an, a, n, out);
    });
}

/// Optimal MIS, direct (correlated) estimator.
#[derive(Clone, Debug)]
pub struct Direct {
    layout: Arc<Layout>,
    ridge: f64,
    block: Vec<f64>,
}

impl Direct {
    /// An empty estimator with ridge λ = `ridge` ≥ 0 (`μ = (λ/N)·tr(Â)/T`).
    pub fn new(layout: Arc<Layout>, ridge: f64) -> Direct {
        assert!(
            ridge >= 0.0 && ridge.is_finite(),
            "ridge λ must be finite and ≥ 0"
        );
        let block = vec![0.0; block_len(&layout)];
        Direct {
            layout,
            ridge,
            block,
        }
    }

    /// The accumulated sums `Â`, `b̂`.
    pub fn moments(&self) -> Moments<&[f64]> {
        Moments::view(&self.layout, &self.block[1..])
    }

    /// Writes α̂ (one length-T column per channel) and reports how it was solved.
    pub fn alpha(&self, alpha_out: &mut [f64]) -> SolveMethod {
        alpha(&self.layout, self.ridge, &self.block, alpha_out)
    }
}

impl Estimator for Direct {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    #[inline]
    fn add_sample(&mut self, technique: usize, f: &[f64], pdfs: &[f64]) {
        Moments::view_mut(&self.layout, &mut self.block[1..]).add(&self.layout, technique, f, pdfs);
    }

    fn add_failed(&mut self, technique: usize) {
        Moments::view_mut(&self.layout, &mut self.block[1..]).add_failed(&self.layout, technique);
    }

    fn end_iteration(&mut self) {
        self.block[0] += 1.0;
    }

    fn iterations(&self) -> u64 {
        self.block[0] as u64
    }

    fn estimate(&self, out: &mut [f64]) {
        estimate(&self.layout, self.ridge, &self.block, out);
    }

    fn merge(&mut self, other: &Direct) {
        self.layout.assert_same(&other.layout);
        crate::block::add(&mut self.block, &other.block);
    }
}
