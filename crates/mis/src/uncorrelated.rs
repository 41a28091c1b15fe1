//! The uncorrelated optimal-MIS estimator (Kondapaneni et al. 2019, §5): `Â` and `b̂` from
//! independent sample sets, so that α̂ does not correlate with the `b̂` it multiplies.
//!
//! **Sample sets by iteration parity.** Iterations 0, 2, 4, … feed set A, iterations
//! 1, 3, 5, … set B; nothing is thrown away. The estimate crosses the sets both ways,
//! `α_AB` from `(Â_A/N_A) α = b̂_B/N_B` and `α_BA` likewise, each in the full form
//! `F_AB = Σα_AB + n·(b̂_B/N_B − Â_A α_AB/N_A)` (which is `Σα_AB` at λ = 0), and averages
//! them with weights N_B and N_A (the samples behind each `b̂`). While set B is still empty
//! (one iteration) the estimate is the balance heuristic on set A. Merging adds set to set
//! (runs are independent, so the sets stay independent). This object feeds the set with
//! fewer iterations (parity in a single run); a renderer's flat state ([`crate::Kernel`])
//! picks the set by the parity of the *global* sample index instead, so that two sample
//! ranges merge into exactly the sets of one run over their union. State: one flat block
//! `[N_A, N_B | moments A | moments B]`.

use std::sync::Arc;

use crate::linalg::{relative_ridge, solve, with_scratch};
use crate::{Estimator, Layout, Moments};

/// Words of an uncorrelated estimator's block: `[N_A, N_B | moments A | moments B]`.
pub(crate) fn block_len(layout: &Layout) -> usize {
    2 + 2 * Moments::len(layout)
}

/// The moments of set `k` (0 = A, 1 = B) of a block.
#[inline]
pub(crate) fn set_mut<'a>(
    layout: &Layout,
    block: &'a mut [f64],
    k: usize,
) -> Moments<&'a mut [f64]> {
    let m = Moments::len(layout);
    Moments::view_mut(layout, &mut block[2 + k * m..2 + (k + 1) * m])
}

fn set<'a>(layout: &Layout, block: &'a [f64], k: usize) -> Moments<&'a [f64]> {
    let m = Moments::len(layout);
    Moments::view(layout, &block[2 + k * m..2 + (k + 1) * m])
}

/// `F_XY`: α from `Â` of set `x` and `b̂` of set `y`, full form on `b̂_y`.
fn cross(layout: &Layout, ridge: f64, block: &[f64], x: usize, y: usize, out: &mut [f64]) {
    let t = layout.techniques();
    let (nx, ny) = (block[x], block[y]);
    let (sx, sy) = (set(layout, block, x), set(layout, block, y));
    let len = sy.vectors().len();
    with_scratch(2 * len + t, |buf| {
        let (rhs, rest) = buf.split_at_mut(len);
        let (alpha, an) = rest.split_at_mut(len);
        for (r, b) in rhs.iter_mut().zip(sy.vectors()) {
            *r = b * (nx / ny);
        }
        solve(sx.matrix(), t, relative_ridge(ridge, nx as u64), rhs, alpha);
        sx.matrix_times_counts_into(layout, an);
        for v in an.iter_mut() {
            *v *= ny / nx;
        }
        sy.full_form(layout, an, alpha, ny, out);
    });
}

/// The estimate of a block (module docs).
pub(crate) fn estimate(layout: &Layout, ridge: f64, block: &[f64], out: &mut [f64]) {
    let (na, nb) = (block[0], block[1]);
    if na == 0.0 || nb == 0.0 {
        // Balance on whichever set has data: the full form with α = 0.
        let k = usize::from(na == 0.0);
        let n = block[k];
        if n == 0.0 {
            out.fill(0.0);
            return;
        }
        let s = set(layout, block, k);
        let t = layout.techniques();
        with_scratch(s.vectors().len() + t, |zeros| {
            let (alpha, an) = zeros.split_at(s.vectors().len());
            s.full_form(layout, an, alpha, n, out);
        });
        return;
    }
    cross(layout, ridge, block, 0, 1, out);
    with_scratch(out.len(), |ba| {
        cross(layout, ridge, block, 1, 0, ba);
        for (o, v) in out.iter_mut().zip(ba.iter()) {
            *o = (nb * *o + na * v) / (na + nb);
        }
    });
}

/// Optimal MIS with `Â` and `b̂` from alternate iterations.
#[derive(Clone, Debug)]
pub struct Uncorrelated {
    layout: Arc<Layout>,
    ridge: f64,
    block: Vec<f64>,
}

impl Uncorrelated {
    /// An empty estimator with ridge λ = `ridge` ≥ 0 (`μ = (λ/N)·tr(Â)/T`).
    pub fn new(layout: Arc<Layout>, ridge: f64) -> Uncorrelated {
        assert!(
            ridge >= 0.0 && ridge.is_finite(),
            "ridge λ must be finite and ≥ 0"
        );
        let block = vec![0.0; block_len(&layout)];
        Uncorrelated {
            layout,
            ridge,
            block,
        }
    }

    /// The set the current iteration feeds (0 = A, 1 = B): the one with fewer iterations,
    /// A on ties — iteration parity in a single run, balanced again after a merge.
    #[inline]
    fn current(&self) -> usize {
        usize::from(self.block[1] < self.block[0])
    }
}

impl Estimator for Uncorrelated {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    #[inline]
    fn add_sample(&mut self, technique: usize, f: &[f64], pdfs: &[f64]) {
        let k = self.current();
        set_mut(&self.layout, &mut self.block, k).add(&self.layout, technique, f, pdfs);
    }

    fn add_failed(&mut self, technique: usize) {
        let k = self.current();
        set_mut(&self.layout, &mut self.block, k).add_failed(&self.layout, technique);
    }

    fn end_iteration(&mut self) {
        let k = self.current();
        self.block[k] += 1.0;
    }

    fn iterations(&self) -> u64 {
        (self.block[0] + self.block[1]) as u64
    }

    fn estimate(&self, out: &mut [f64]) {
        estimate(&self.layout, self.ridge, &self.block, out);
    }

    fn merge(&mut self, other: &Uncorrelated) {
        self.layout.assert_same(&other.layout);
        crate::block::add(&mut self.block, &other.block);
    }
}
