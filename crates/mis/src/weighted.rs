//! The multi-sample MIS estimator with a heuristic weighting function (Veach 1997, eq. 9.4):
//! `F̂ = (1/N) Σ_iterations Σ_i (1/n_i) Σ_j w_i(X_ij) f(X_ij) / p_i(X_ij)`.
//!
//! Unbiased whenever the weights sum to 1 where f ≠ 0 (Veach 1997, Theorem 9.2), which all
//! [`Heuristic`]s do. With the balance heuristic each term is simply `f / s`. A failed sample
//! adds nothing (its weight is 0): the lost mass of a defective pdf is covered by the other
//! techniques. State: one flat block `[N | Σ per channel]` ([`crate::Kernel`]).

use std::sync::Arc;

use crate::{Estimator, Heuristic, Layout};

/// Words of a heuristic estimator's block: `[N | sums (channels)]`.
pub(crate) fn block_len(layout: &Layout) -> usize {
    1 + layout.channels()
}

/// Adds one sample into a block (see [`Weighted`]).
#[inline]
pub(crate) fn add_sample(
    layout: &Layout,
    heuristic: Heuristic,
    block: &mut [f64],
    technique: usize,
    f: &[f64],
    pdfs: &[f64],
) {
    debug_assert_eq!(f.len(), layout.channels(), "one f value per channel");
    let Some(s) = layout.is_valid(technique, pdfs) else {
        return;
    };
    // w_t f / (n_t p_t); for balance w_t / (n_t p_t) = 1/s exactly.
    let scale = match heuristic {
        Heuristic::Balance => 1.0 / s,
        h => h.scale(technique, layout.counts(), pdfs),
    };
    if scale != 0.0 {
        for (sum, fc) in block[1..].iter_mut().zip(f) {
            *sum += fc * scale;
        }
    }
}

/// The estimate `Σ / N` of a block.
pub(crate) fn estimate(block: &[f64], out: &mut [f64]) {
    let n = block[0].max(1.0);
    for (o, s) in out.iter_mut().zip(&block[1..]) {
        *o = s / n;
    }
}

/// A heuristic multi-sample estimator (balance, power, maximum, cutoff).
#[derive(Clone, Debug)]
pub struct Weighted {
    layout: Arc<Layout>,
    heuristic: Heuristic,
    block: Vec<f64>,
}

impl Weighted {
    /// An empty estimator. Panics if the heuristic's parameter is out of range.
    pub fn new(layout: Arc<Layout>, heuristic: Heuristic) -> Weighted {
        if let Err(e) = heuristic.validate() {
            panic!("{e}");
        }
        let block = vec![0.0; block_len(&layout)];
        Weighted {
            layout,
            heuristic,
            block,
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
        add_sample(
            &self.layout,
            self.heuristic,
            &mut self.block,
            technique,
            f,
            pdfs,
        );
    }

    fn add_failed(&mut self, _technique: usize) {}

    fn end_iteration(&mut self) {
        self.block[0] += 1.0;
    }

    fn iterations(&self) -> u64 {
        self.block[0] as u64
    }

    fn estimate(&self, out: &mut [f64]) {
        estimate(&self.block, out);
    }

    fn merge(&mut self, other: &Weighted) {
        self.layout.assert_same(&other.layout);
        assert_eq!(
            self.heuristic, other.heuristic,
            "cannot merge different heuristics"
        );
        crate::block::add(&mut self.block, &other.block);
    }
}
