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
use crate::moments::{full_form_sized, matrix_times_counts_sized};
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
    // RGB with up to four techniques on the stack with constant sizes, so that the loops
    // unroll: once per pixel and depth, this was a fifth of optimal-direct's overhead over
    // balance at T = 3 and 16 spp (bench/overhead). The same operations: bit for bit.
    match (t, out.len()) {
        (2, 3) => estimate_in(
            layout,
            ridge,
            block,
            &m,
            2,
            &mut [0.0; 6],
            &mut [0.0; 2],
            out,
        ),
        (3, 3) => estimate_in(
            layout,
            ridge,
            block,
            &m,
            3,
            &mut [0.0; 9],
            &mut [0.0; 3],
            out,
        ),
        (4, 3) => estimate_in(
            layout,
            ridge,
            block,
            &m,
            4,
            &mut [0.0; 12],
            &mut [0.0; 4],
            out,
        ),
        _ => with_scratch(m.vectors().len() + t, |buf| {
            let (a, an) = buf.split_at_mut(m.vectors().len());
            estimate_in(layout, ridge, block, &m, t, a, an, out);
        }),
    }
}

/// [`estimate`] with scratch `a` (α̂) and `an` (`Â n`), inlined where `t` is a constant.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn estimate_in(
    layout: &Layout,
    ridge: f64,
    block: &[f64],
    m: &Moments<&[f64]>,
    t: usize,
    a: &mut [f64],
    an: &mut [f64],
    out: &mut [f64],
) {
    let n = block[0];
    solve(
        m.matrix(),
        t,
        relative_ridge(ridge, n as u64),
        m.vectors(),
        a,
    );
    matrix_times_counts_sized(m.matrix(), layout.counts(), t, an);
    full_form_sized(m.vectors(), layout.counts(), an, a, n, t, out);
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The sizes `estimate` unrolls (T = 2, 3, 4 with RGB) give bit for bit what the
    /// general code gives, with and without a ridge, singular blocks included.
    #[test]
    fn unrolled_sizes_equal_the_general_code() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        for t in 2..=4 {
            let layout = Layout::new(&(1..=t as u32).collect::<Vec<_>>(), 3);
            for (round, ridge) in [0.0, 0.5].into_iter().cycle().take(40).enumerate() {
                let mut block = vec![0.0; block_len(&layout)];
                let mut m = Moments::view_mut(&layout, &mut block[1..]);
                for _ in 0..rng.gen_range(1..20) {
                    let k = rng.gen_range(0..t);
                    let mut pdfs: Vec<f64> = (0..t).map(|_| rng.gen::<f64>()).collect();
                    if round % 3 == 0 {
                        // Techniques with no density anywhere: a singular Â.
                        pdfs[t - 1] = 0.0;
                    }
                    let f: Vec<f64> = (0..3).map(|_| rng.gen::<f64>() - 0.2).collect();
                    m.add(&layout, k, &f, &pdfs);
                }
                block[0] = rng.gen_range(1..30) as f64;
                let (mut fast, mut general) = ([0.0; 3], [0.0; 3]);
                estimate(&layout, ridge, &block, &mut fast);
                // The general code: the moments' own methods over sizes read at run time.
                let m = Moments::view(&layout, &block[1..]);
                let (mut a, mut an) = (vec![0.0; 3 * t], vec![0.0; t]);
                alpha(&layout, ridge, &block, &mut a);
                m.matrix_times_counts_into(&layout, &mut an);
                m.full_form(&layout, &an, &a, block[0], &mut general);
                assert_eq!(fast.map(f64::to_bits), general.map(f64::to_bits), "T = {t}");
            }
        }
    }
}
