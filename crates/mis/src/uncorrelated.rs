//! The uncorrelated optimal-MIS estimator (Kondapaneni et al. 2019, §5): `Â` and `b̂` from
//! independent sample sets, so that α̂ does not correlate with the `b̂` it multiplies.
//!
//! **Sample sets by iteration parity.** Iterations 0, 2, 4, … feed set A, iterations
//! 1, 3, 5, … set B; nothing is thrown away. The estimate crosses the sets both ways,
//! `α_AB` from `(Â_A/N_A) α = b̂_B/N_B` and `α_BA` likewise, each in the full form
//! `F_AB = Σα_AB + n·(b̂_B/N_B − Â_A α_AB/N_A)` (which is `Σα_AB` at λ = 0), and averages
//! them with weights N_B and N_A (the samples behind each `b̂`). While set B is still empty
//! (one iteration) the estimate is the balance heuristic on set A. Merging adds set to set
//! (runs are independent, so the sets stay independent); after a merge the next iteration
//! feeds whichever set has fewer iterations.

use std::sync::Arc;

use crate::linalg::{relative_ridge, solve};
use crate::{Estimator, Layout, Moments};

/// Optimal MIS with `Â` and `b̂` from alternate iterations.
#[derive(Clone, Debug)]
pub struct Uncorrelated {
    layout: Arc<Layout>,
    ridge: f64,
    sets: [Moments; 2],
    counts: [u64; 2],
}

impl Uncorrelated {
    /// An empty estimator with ridge λ = `ridge` ≥ 0 (`μ = (λ/N)·tr(Â)/T`).
    pub fn new(layout: Arc<Layout>, ridge: f64) -> Uncorrelated {
        assert!(
            ridge >= 0.0 && ridge.is_finite(),
            "ridge λ must be finite and ≥ 0"
        );
        let m = Moments::new(&layout);
        Uncorrelated {
            layout,
            ridge,
            sets: [m.clone(), m],
            counts: [0, 0],
        }
    }

    /// The set the current iteration feeds (0 = A, 1 = B): the one with fewer iterations,
    /// A on ties — iteration parity in a single run, balanced again after a merge.
    #[inline]
    fn current(&self) -> usize {
        usize::from(self.counts[1] < self.counts[0])
    }

    /// `F_XY`: α from `Â` of set `x` and `b̂` of set `y`, full form on `b̂_y`.
    fn cross(&self, x: usize, y: usize, out: &mut [f64]) {
        let t = self.layout.techniques();
        let (nx, ny) = (self.counts[x] as f64, self.counts[y] as f64);
        let rhs: Vec<f64> = self.sets[y]
            .vectors()
            .iter()
            .map(|b| b * (nx / ny))
            .collect();
        let mut alpha = vec![0.0; rhs.len()];
        let ridge = relative_ridge(self.ridge, self.counts[x]);
        solve(self.sets[x].matrix(), t, ridge, &rhs, &mut alpha);
        let an: Vec<f64> = self.sets[x]
            .matrix_times_counts(&self.layout)
            .iter()
            .map(|v| v * (ny / nx))
            .collect();
        self.sets[y].full_form(&self.layout, &an, &alpha, ny, out);
    }
}

impl Estimator for Uncorrelated {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    #[inline]
    fn add_sample(&mut self, technique: usize, f: &[f64], pdfs: &[f64]) {
        let set = self.current();
        self.sets[set].add(&self.layout, technique, f, pdfs);
    }

    fn add_failed(&mut self, technique: usize) {
        let set = self.current();
        self.sets[set].add_failed(&self.layout, technique);
    }

    fn end_iteration(&mut self) {
        let set = self.current();
        self.counts[set] += 1;
    }

    fn iterations(&self) -> u64 {
        self.counts[0] + self.counts[1]
    }

    fn estimate(&self, out: &mut [f64]) {
        let [na, nb] = self.counts;
        if na == 0 || nb == 0 {
            // Balance on whichever set has data: the full form with α = 0.
            let set = usize::from(na == 0);
            let n = self.counts[set];
            if n == 0 {
                out.fill(0.0);
                return;
            }
            let zero = vec![0.0; self.sets[set].vectors().len()];
            let t = vec![0.0; self.layout.techniques()];
            self.sets[set].full_form(&self.layout, &t, &zero, n as f64, out);
            return;
        }
        let mut ba = vec![0.0; out.len()];
        self.cross(0, 1, out);
        self.cross(1, 0, &mut ba);
        let (wa, wb) = (na as f64, nb as f64);
        for (o, v) in out.iter_mut().zip(&ba) {
            *o = (wb * *o + wa * v) / (wa + wb);
        }
    }

    fn merge(&mut self, other: &Uncorrelated) {
        self.layout.assert_same(&other.layout);
        for k in 0..2 {
            self.sets[k].merge(&other.sets[k]);
            self.counts[k] += other.counts[k];
        }
    }
}
