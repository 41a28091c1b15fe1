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
                n >= w && n % w == 0 && (n / w).is_power_of_two()
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

/// Optimal MIS with α from earlier iterations: progressive, full weights, or a fixed α.
#[derive(Clone, Debug)]
pub struct Progressive {
    layout: Arc<Layout>,
    ridge: f64,
    schedule: Schedule,
    moments: Moments,
    /// α per channel (channel-major, length C·T) used for the current iteration.
    alpha: Vec<f64>,
    /// Σ_k α_ck per channel.
    alpha_sum: Vec<f64>,
    /// Σ over iterations of F_k per channel.
    acc: Vec<f64>,
    iterations: u64,
}

impl Progressive {
    /// An empty estimator with ridge λ = `ridge` ≥ 0 (`μ = (λ/N)·tr(Â)/T`) and a schedule.
    pub fn new(layout: Arc<Layout>, ridge: f64, schedule: Schedule) -> Progressive {
        assert!(
            ridge >= 0.0 && ridge.is_finite(),
            "ridge λ must be finite and ≥ 0"
        );
        let (t, c) = (layout.techniques(), layout.channels());
        Progressive {
            moments: Moments::new(&layout),
            alpha: vec![0.0; c * t],
            alpha_sum: vec![0.0; c],
            acc: vec![0.0; c],
            iterations: 0,
            layout,
            ridge,
            schedule,
        }
    }

    /// Full weights with α trained elsewhere (e.g. a pilot run: [`crate::Direct::alpha`]);
    /// `alpha` holds one length-T column per channel. Unbiased for any α.
    pub fn with_alpha(layout: Arc<Layout>, alpha: &[f64]) -> Progressive {
        let mut p = Progressive::new(layout, 0.0, Schedule::Fixed);
        assert_eq!(alpha.len(), p.alpha.len(), "one α column per channel");
        p.set_alpha(alpha);
        p
    }

    /// The α applied to the current iteration (channel-major).
    pub fn alpha(&self) -> &[f64] {
        &self.alpha
    }

    /// The re-solve schedule.
    pub fn schedule(&self) -> Schedule {
        self.schedule
    }

    fn set_alpha(&mut self, alpha: &[f64]) {
        self.alpha.copy_from_slice(alpha);
        let t = self.layout.techniques();
        for (s, col) in self.alpha_sum.iter_mut().zip(self.alpha.chunks_exact(t)) {
            *s = col.iter().sum();
        }
    }

    fn resolve(&mut self) {
        let mut alpha = vec![0.0; self.alpha.len()];
        solve(
            self.moments.matrix(),
            self.layout.techniques(),
            relative_ridge(self.ridge, self.iterations),
            self.moments.vectors(),
            &mut alpha,
        );
        self.set_alpha(&alpha);
    }
}

impl Estimator for Progressive {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    #[inline]
    fn add_sample(&mut self, technique: usize, f: &[f64], pdfs: &[f64]) {
        let t = self.layout.techniques();
        match self.moments.add(&self.layout, technique, f, pdfs) {
            Some(s) => {
                let inv = 1.0 / s;
                for ((acc, fc), al) in self.acc.iter_mut().zip(f).zip(self.alpha.chunks_exact(t)) {
                    let cv: f64 = al.iter().zip(pdfs).map(|(a, p)| a * p).sum();
                    *acc += (fc - cv) * inv;
                }
            }
            None => self.fail_residual(technique),
        }
    }

    fn add_failed(&mut self, technique: usize) {
        self.moments.add_failed(&self.layout, technique);
        self.fail_residual(technique);
    }

    fn end_iteration(&mut self) {
        for (acc, s) in self.acc.iter_mut().zip(&self.alpha_sum) {
            *acc += s;
        }
        self.iterations += 1;
        if self.schedule.solves_at(self.iterations) {
            self.resolve();
        }
    }

    fn iterations(&self) -> u64 {
        self.iterations
    }

    fn estimate(&self, out: &mut [f64]) {
        let n = self.iterations.max(1) as f64;
        for (o, a) in out.iter_mut().zip(&self.acc) {
            *o = a / n;
        }
    }

    /// Adds the sums; then α is re-solved from the merged `Â`, `b̂` if the schedule has
    /// started (for [`Schedule::Fixed`] both states must hold the same α).
    fn merge(&mut self, other: &Progressive) {
        self.layout.assert_same(&other.layout);
        assert_eq!(
            self.schedule, other.schedule,
            "cannot merge different schedules"
        );
        if self.schedule == Schedule::Fixed {
            assert_eq!(
                self.alpha, other.alpha,
                "cannot merge estimators with different fixed α"
            );
        }
        self.moments.merge(&other.moments);
        for (a, b) in self.acc.iter_mut().zip(&other.acc) {
            *a += b;
        }
        self.iterations += other.iterations;
        if self.schedule.started_by(self.iterations) {
            self.resolve();
        }
    }
}

impl Progressive {
    /// A failed sample of technique t: `[0 − α_t (1 − m_t)] / [n_t (1 − m_t)] = −α_t/n_t`.
    #[inline]
    fn fail_residual(&mut self, technique: usize) {
        let t = self.layout.techniques();
        let n = self.layout.counts()[technique];
        for (acc, al) in self.acc.iter_mut().zip(self.alpha.chunks_exact(t)) {
            *acc -= al[technique] / n;
        }
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
