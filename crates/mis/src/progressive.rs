//! Unbiased optimal MIS: α from *earlier* samples, applied to new ones through the
//! control-variate form of the optimal weights (Kondapaneni et al. 2019, §5 and eq. 13).
//!
//! Iteration k contributes `F_k = Σ_i α_i + Σ_samples [f(X) − Σ_i α_i p_i(X)] / s(X)` with
//! α fixed before the iteration began, which is the multi-sample estimator with the optimal
//! weights `w_i = α_i p_i/f + (n_i p_i/s)(1 − Σ_k α_k p_k/f)` ([`crate::optimal_weight`]).
//! `E[F_k] = F` for *any* such α (every pdf integrates to 1 on the domain extended by the
//! failure points of [`crate::Moments`]), so the mean over iterations is unbiased; α only
//! decides the variance. A failed sample of technique t adds `−α_t/n_t`.
//!
//! The [`Schedule`] says when α is re-solved from all samples so far (`Â`, `b̂` as in
//! [`crate::Direct`], with the same decaying ridge). Iterations before the first solve use
//! α = 0 (balance). Re-solving at N = W, 2W, 4W, … costs O(log N) solves per pixel and
//! loses 1–10 % RMSE against re-solving every iteration; with the decaying ridge a first
//! solve after one iteration (W = 1) beat longer warm-ups in every measured case
//! (`docs/mis.md`). [`Schedule::Once`] is the full-weights estimator:
//! α trained on the first iterations, then fixed.

use std::sync::Arc;

use crate::linalg::{relative_ridge, solve};
use crate::{Estimator, Layout, Moments};

/// Words of a progressive estimator's block: `[N | Σ F_k (channels) | α (channels × T) |
/// moments]`.
pub(crate) fn block_len(layout: &Layout) -> usize {
    1 + layout.channels() * (1 + layout.techniques()) + Moments::len(layout)
}

/// When the progressive estimator re-solves α (after iteration N, counting from 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Schedule {
    /// α = 0 (balance) until N = `warmup`, then re-solve at N = W, 2W, 4W, … (W = max(warmup, 1)).
    Doubling {
        /// Balance-only iterations before the first solve.
        warmup: u64,
    },
    /// α = 0 until N = `warmup`, then re-solve after every iteration (costlier; for study).
    Every {
        /// Balance-only iterations before the first solve.
        warmup: u64,
    },
    /// Full weights: α = 0 until N = `after`, solve once, then keep α.
    Once {
        /// Training iterations.
        after: u64,
    },
    /// α given by the caller ([`Progressive::with_alpha`]), never re-solved.
    Fixed,
}

impl Schedule {
    /// Whether α is re-solved right after iteration `n` (n ≥ 1) completes.
    pub fn solves_at(self, n: u64) -> bool {
        match self {
            Schedule::Doubling { warmup } => {
                let w = warmup.max(1);
                n >= w && n.is_multiple_of(w) && (n / w).is_power_of_two()
            }
            Schedule::Every { warmup } => n >= warmup.max(1),
            Schedule::Once { after } => n == after.max(1),
            Schedule::Fixed => false,
        }
    }

    /// Whether some solve point ≤ `n` exists (α is no longer the warm-up's zero).
    fn started_by(self, n: u64) -> bool {
        match self {
            Schedule::Doubling { warmup } | Schedule::Every { warmup } => n >= warmup.max(1),
            Schedule::Once { after } => n >= after.max(1),
            Schedule::Fixed => false,
        }
    }
}

/// The parts of a progressive block.
struct Parts<'a> {
    n: &'a mut f64,
    acc: &'a mut [f64],
    alpha: &'a mut [f64],
    moments: Moments<&'a mut [f64]>,
}

fn parts<'a>(layout: &Layout, block: &'a mut [f64]) -> Parts<'a> {
    let (c, t) = (layout.channels(), layout.techniques());
    let (n, rest) = block.split_first_mut().expect("non-empty block");
    let (acc, rest) = rest.split_at_mut(c);
    let (alpha, m) = rest.split_at_mut(c * t);
    Parts {
        n,
        acc,
        alpha,
        moments: Moments::view_mut(layout, m),
    }
}

/// The α of a block (channel-major).
pub(crate) fn alpha<'a>(layout: &Layout, block: &'a [f64]) -> &'a [f64] {
    let c = layout.channels();
    &block[1 + c..1 + c + c * layout.techniques()]
}

/// Adds one sample into a block.
#[inline]
pub(crate) fn add_sample(
    layout: &Layout,
    block: &mut [f64],
    technique: usize,
    f: &[f64],
    pdfs: &[f64],
) {
    add(layout, block, technique, f, pdfs, false)
}

/// [`add_sample`] for a sample whose `f` is 0 in every channel: `Â` only
/// ([`Moments::add_zero_valued`]), and the residual's `−α·p/s`; the same sums bit for bit.
#[inline(always)]
pub(crate) fn add_zero_valued(
    layout: &Layout,
    block: &mut [f64],
    technique: usize,
    f: &[f64],
    pdfs: &[f64],
) {
    add(layout, block, technique, f, pdfs, true)
}

#[inline(always)]
fn add(layout: &Layout, block: &mut [f64], k: usize, f: &[f64], pdfs: &[f64], zero: bool) {
    let mut p = parts(layout, block);
    let s = match zero {
        true => p.moments.add_zero_valued(layout, k, f, pdfs),
        false => p.moments.add(layout, k, f, pdfs),
    };
    match s {
        Some(s) => add_residual(layout.techniques(), &mut p, f, pdfs, 1.0 / s),
        None => fail_residual(layout, &mut p, k),
    }
}

/// The residual of a sample with pdf sum `1/inv`: `acc_c += (f_c − α_c·p)·inv`. Past
/// four techniques `α_c·p` runs over the pdfs that are not 0 (with one technique per
/// light, most are): α is finite (`solve`), so the terms left out are ±0, which leave
/// the sum as it is but for the sign of a zero sum, and `f_c − ±0` is the same unless
/// f_c is −0, which no radiance is.
#[inline(always)]
fn add_residual(t: usize, p: &mut Parts, f: &[f64], pdfs: &[f64], inv: f64) {
    let pdfs = &pdfs[..t];
    if t > 4 && t <= 64 {
        let mut nonzero = [0u8; 64];
        let (mut m, mut mask) = (0, crate::moments::nonzero_bits(pdfs));
        while mask != 0 {
            nonzero[m] = mask.trailing_zeros() as u8;
            mask &= mask - 1;
            m += 1;
        }
        let nonzero = &nonzero[..m];
        for (c, (acc, fc)) in p.acc.iter_mut().zip(f).enumerate() {
            let al = &p.alpha[c * t..][..t];
            let cv: f64 = nonzero
                .iter()
                .map(|&i| al[usize::from(i)] * pdfs[usize::from(i)])
                .sum();
            *acc += (fc - cv) * inv;
        }
        return;
    }
    for ((acc, fc), al) in p.acc.iter_mut().zip(f).zip(p.alpha.chunks_exact(t)) {
        let cv: f64 = al.iter().zip(pdfs).map(|(a, p)| a * p).sum();
        *acc += (fc - cv) * inv;
    }
}

/// Counts a failed sample of `technique` into a block.
pub(crate) fn add_failed(layout: &Layout, block: &mut [f64], technique: usize) {
    let mut p = parts(layout, block);
    p.moments.add_failed(layout, technique);
    fail_residual(layout, &mut p, technique);
}

/// A failed sample of technique t: `[0 − α_t (1 − m_t)] / [n_t (1 − m_t)] = −α_t/n_t`.
#[inline]
fn fail_residual(layout: &Layout, p: &mut Parts, technique: usize) {
    let t = layout.techniques();
    let n = layout.counts()[technique];
    for (acc, al) in p.acc.iter_mut().zip(p.alpha.chunks_exact(t)) {
        *acc -= al[technique] / n;
    }
}

/// Re-solves α from the block's moments.
fn resolve(layout: &Layout, ridge: f64, p: &mut Parts) {
    solve(
        p.moments.matrix(),
        layout.techniques(),
        relative_ridge(ridge, *p.n as u64),
        p.moments.vectors(),
        p.alpha,
    );
}

/// Re-solves a block's α from its moments and N ([`crate::Kernel::resolve`]).
pub(crate) fn resolve_block(layout: &Layout, ridge: f64, block: &mut [f64]) {
    resolve(layout, ridge, &mut parts(layout, block));
}

/// Closes an iteration: adds Σα, counts it, re-solves where the schedule says.
pub(crate) fn end_iteration(layout: &Layout, ridge: f64, schedule: Schedule, block: &mut [f64]) {
    let t = layout.techniques();
    let mut p = parts(layout, block);
    for (acc, al) in p.acc.iter_mut().zip(p.alpha.chunks_exact(t)) {
        *acc += al.iter().sum::<f64>();
    }
    *p.n += 1.0;
    if schedule.solves_at(*p.n as u64) {
        resolve(layout, ridge, &mut p);
    }
}

/// The estimate `Σ F_k / N` of a block.
pub(crate) fn estimate(layout: &Layout, block: &[f64], out: &mut [f64]) {
    let n = block[0].max(1.0);
    for (o, a) in out.iter_mut().zip(&block[1..1 + layout.channels()]) {
        *o = a / n;
    }
}

/// Merges block `b` into `a` (module docs): sums added, α re-solved if the schedule has
/// started; for [`Schedule::Fixed`] both must hold the same α.
pub(crate) fn merge(layout: &Layout, ridge: f64, schedule: Schedule, a: &mut [f64], b: &[f64]) {
    if schedule == Schedule::Fixed {
        assert_eq!(
            alpha(layout, a),
            alpha(layout, b),
            "cannot merge estimators with different fixed α"
        );
    }
    let alpha_range = {
        let c = layout.channels();
        1 + c..1 + c + c * layout.techniques()
    };
    for (k, (x, y)) in a.iter_mut().zip(b).enumerate() {
        if !alpha_range.contains(&k) {
            *x += y;
        }
    }
    let mut p = parts(layout, a);
    if schedule.started_by(*p.n as u64) {
        resolve(layout, ridge, &mut p);
    }
}

/// Optimal MIS with α from earlier iterations: progressive, full weights, or a fixed α.
#[derive(Clone, Debug)]
pub struct Progressive {
    layout: Arc<Layout>,
    ridge: f64,
    schedule: Schedule,
    block: Vec<f64>,
}

impl Progressive {
    /// An empty estimator with ridge λ = `ridge` ≥ 0 (`μ = (λ/N)·tr(Â)/T`) and a schedule.
    pub fn new(layout: Arc<Layout>, ridge: f64, schedule: Schedule) -> Progressive {
        assert!(
            ridge >= 0.0 && ridge.is_finite(),
            "ridge λ must be finite and ≥ 0"
        );
        let block = vec![0.0; block_len(&layout)];
        Progressive {
            layout,
            ridge,
            schedule,
            block,
        }
    }

    /// Full weights with α trained elsewhere (e.g. a pilot run: [`crate::Direct::alpha`]);
    /// `alpha` holds one length-T column per channel. Unbiased for any α.
    pub fn with_alpha(layout: Arc<Layout>, alpha: &[f64]) -> Progressive {
        let mut p = Progressive::new(layout, 0.0, Schedule::Fixed);
        let parts = parts(&p.layout, &mut p.block);
        assert_eq!(alpha.len(), parts.alpha.len(), "one α column per channel");
        parts.alpha.copy_from_slice(alpha);
        p
    }

    /// The α applied to the current iteration (channel-major).
    pub fn alpha(&self) -> &[f64] {
        alpha(&self.layout, &self.block)
    }

    /// The re-solve schedule.
    pub fn schedule(&self) -> Schedule {
        self.schedule
    }
}

impl Estimator for Progressive {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    #[inline]
    fn add_sample(&mut self, technique: usize, f: &[f64], pdfs: &[f64]) {
        add_sample(&self.layout, &mut self.block, technique, f, pdfs);
    }

    fn add_failed(&mut self, technique: usize) {
        add_failed(&self.layout, &mut self.block, technique);
    }

    fn end_iteration(&mut self) {
        end_iteration(&self.layout, self.ridge, self.schedule, &mut self.block);
    }

    fn iterations(&self) -> u64 {
        self.block[0] as u64
    }

    fn estimate(&self, out: &mut [f64]) {
        estimate(&self.layout, &self.block, out);
    }

    /// Adds the sums; then α is re-solved from the merged `Â`, `b̂` if the schedule has
    /// started (for [`Schedule::Fixed`] both states must hold the same α).
    fn merge(&mut self, other: &Progressive) {
        self.layout.assert_same(&other.layout);
        assert_eq!(
            self.schedule, other.schedule,
            "cannot merge different schedules"
        );
        merge(
            &self.layout,
            self.ridge,
            self.schedule,
            &mut self.block,
            &other.block,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedules_solve_where_documented() {
        let points = |s: Schedule| (1..=40).filter(|&n| s.solves_at(n)).collect::<Vec<_>>();
        assert_eq!(points(Schedule::Doubling { warmup: 4 }), vec![4, 8, 16, 32]);
        assert_eq!(points(Schedule::Doubling { warmup: 3 }), vec![3, 6, 12, 24]);
        assert_eq!(
            points(Schedule::Doubling { warmup: 0 }),
            vec![1, 2, 4, 8, 16, 32]
        );
        assert_eq!(points(Schedule::Every { warmup: 38 }), vec![38, 39, 40]);
        assert_eq!(points(Schedule::Once { after: 5 }), vec![5]);
        assert!(points(Schedule::Fixed).is_empty());
    }

    /// The residual over the nonzero pdfs (T > 4) and the zero-valued short path give
    /// bit for bit the dense sums of `add_sample` as written for every T, failed
    /// samples, zero pdfs of either sign and zero-valued draws included (T = 3, 5, 11,
    /// 64, and 65 past the sparse loop).
    #[test]
    fn sparse_residuals_equal_the_dense_sums() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
        for t in [3, 5, 11, 64, 65] {
            let layout = Layout::new(&(1..=t as u32).collect::<Vec<_>>(), 3);
            let alpha: Vec<f64> = (0..3 * t).map(|_| rng.gen::<f64>() - 0.4).collect();
            let mut fast = vec![0.0; block_len(&layout)];
            let mut dense = fast.clone();
            parts(&layout, &mut fast).alpha.copy_from_slice(&alpha);
            parts(&layout, &mut dense).alpha.copy_from_slice(&alpha);
            for i in 0..400 {
                let k = rng.gen_range(0..t);
                let mut pdfs: Vec<f64> = (0..t)
                    .map(|_| match rng.gen_range(0..4) {
                        0 => 0.0,
                        1 => -0.0,
                        _ => rng.gen::<f64>() * 2.0,
                    })
                    .collect();
                if i % 9 == 0 {
                    pdfs[k] = 0.0; // a failed sample
                }
                let zero = i % 3 == 0;
                let f: Vec<f64> = (0..3)
                    .map(|_| if zero { 0.0 } else { rng.gen::<f64>() })
                    .collect();
                if zero {
                    add_zero_valued(&layout, &mut fast, k, &f, &pdfs);
                } else {
                    add_sample(&layout, &mut fast, k, &f, &pdfs);
                }
                // `add_sample` before the sparse residual, every sum dense.
                let mut p = parts(&layout, &mut dense);
                match p.moments.add(&layout, k, &f, &pdfs) {
                    Some(s) => {
                        let inv = 1.0 / s;
                        for ((acc, fc), al) in p.acc.iter_mut().zip(&f).zip(p.alpha.chunks_exact(t))
                        {
                            let cv: f64 = al.iter().zip(&pdfs).map(|(a, p)| a * p).sum();
                            *acc += (fc - cv) * inv;
                        }
                    }
                    None => fail_residual(&layout, &mut p, k),
                }
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast), bits(&dense), "T = {t}");
        }
    }

    #[test]
    fn fixed_alpha_follows_the_control_variate_form_by_hand() {
        // T = 2, n = (1, 1), one channel, α = (0.5, 0.25).
        let layout = Layout::new(&[1, 1], 1);
        let mut e = Progressive::with_alpha(layout, &[0.5, 0.25]);
        // Technique 0: f = 2, pdfs (1, 3): s = 4, residual (2 − 0.5 − 0.75)/4 = 0.1875.
        e.add_sample(0, &[2.0], &[1.0, 3.0]);
        // Technique 1 failed: −α_1/n_1 = −0.25.
        e.add_failed(1);
        e.end_iteration();
        assert_eq!(e.estimate_vec(), vec![0.75 + 0.1875 - 0.25]);
    }
}
