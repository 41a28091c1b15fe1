//! The additive sufficient statistics of optimal MIS: the technique matrix `Â` and the
//! contribution vectors `b̂` (one per channel), kept as plain sums over samples.
//!
//! For every sample X (Kondapaneni et al. 2019, eqs. 15–16):
//! `Â_ik += p_i(X) p_k(X) / s(X)²` and `b̂_ci += f_c(X) p_i(X) / s(X)²`, with
//! `s = Σ_k n_k p_k`. Divided by the iteration count N they estimate
//! `A_ik = ∫ p_i p_k / s` and `b_i = ∫ f p_i / s`. Sums rather than means, so that two
//! states merge by addition (threads, tiles, separate runs).
//!
//! **Failed samples.** A technique t that produces no sample (or a sample with zero own
//! pdf) has lost probability mass `1 − m_t`. Treat the failure as a point `⊥_t` of an
//! extended domain where `p_t = 1 − m_t`, every other pdf is 0 and f = 0: every pdf then
//! integrates to 1 again, so `A·n = 1` and `Σα = F` hold. At that point `s = n_t(1 − m_t)`
//! and the sample adds exactly `1/n_t²` to `Â_tt` and nothing else — the unknown mass
//! cancels.

use crate::linalg::{packed_index, packed_len};
use crate::Layout;

/// Sums `Â` (packed symmetric) and `b̂` (channel-major), for one problem layout.
#[derive(Clone, Debug, PartialEq)]
pub struct Moments {
    t: usize,
    /// `[Â packed (T(T+1)/2) | b̂ (channels × T)]`.
    data: Vec<f64>,
}

impl Moments {
    /// Zero sums for a layout.
    pub fn new(layout: &Layout) -> Moments {
        let t = layout.techniques();
        Moments {
            t,
            data: vec![0.0; packed_len(t) + layout.channels() * t],
        }
    }

    /// Adds one sample of technique `t`; returns its mixture density `s`, or `None` when the
    /// sample is counted as failed (own pdf zero, or `s` not finite). O(T²/2 + C·T).
    #[inline]
    pub fn add(&mut self, layout: &Layout, t: usize, f: &[f64], pdfs: &[f64]) -> Option<f64> {
        debug_assert_eq!(f.len(), layout.channels(), "one f value per channel");
        debug_assert!(pdfs.iter().all(|&p| p >= 0.0), "pdfs must be non-negative");
        let Some(s) = layout.is_valid(t, pdfs) else {
            self.add_failed(layout, t);
            return None;
        };
        let inv = 1.0 / s;
        let (a, b) = self.data.split_at_mut(packed_len(self.t));
        let mut idx = 0;
        for i in 0..self.t {
            let qi = pdfs[i] * inv * inv;
            for &pj in &pdfs[..=i] {
                a[idx] += qi * pj;
                idx += 1;
            }
        }
        for (fc, bc) in f.iter().zip(b.chunks_exact_mut(self.t)) {
            for (bi, &pi) in bc.iter_mut().zip(pdfs) {
                *bi += fc * pi * inv * inv;
            }
        }
        Some(s)
    }

    /// Counts a failed sample of technique `t`: `Â_tt += 1/n_t²` (see the module docs).
    #[inline]
    pub fn add_failed(&mut self, layout: &Layout, t: usize) {
        let n = layout.counts()[t];
        self.data[packed_index(t, t)] += 1.0 / (n * n);
    }

    /// Adds another state's sums.
    pub fn merge(&mut self, other: &Moments) {
        assert_eq!(
            self.data.len(),
            other.data.len(),
            "moments of different sizes"
        );
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            *a += b;
        }
    }

    /// `Â`, packed symmetric (see [`crate::linalg::packed_index`]).
    #[inline]
    pub fn matrix(&self) -> &[f64] {
        &self.data[..packed_len(self.t)]
    }

    /// `b̂`, one length-T column per channel.
    #[inline]
    pub fn vectors(&self) -> &[f64] {
        &self.data[packed_len(self.t)..]
    }

    /// `Â n` (length T): its mean over iterations estimates `A n = 1`.
    pub fn matrix_times_counts(&self, layout: &Layout) -> Vec<f64> {
        let a = self.matrix();
        let n = layout.counts();
        (0..self.t)
            .map(|i| (0..self.t).map(|k| a[packed_index(i, k)] * n[k]).sum())
            .collect()
    }

    /// The full-form estimate `Σα + n·(b̂ − Âα)/N` per channel (Kondapaneni et al. 2019,
    /// eq. 13 with the sums of this state), for α from anywhere; α = 0 gives the balance
    /// heuristic `Σ f/s / N`. `an` = [`Moments::matrix_times_counts`].
    pub fn full_form(
        &self,
        layout: &Layout,
        an: &[f64],
        alpha: &[f64],
        iterations: f64,
        out: &mut [f64],
    ) {
        let n = layout.counts();
        for ((o, b), al) in out
            .iter_mut()
            .zip(self.vectors().chunks_exact(self.t))
            .zip(alpha.chunks_exact(self.t))
        {
            let nb: f64 = n.iter().zip(b).map(|(x, y)| x * y).sum();
            let an_alpha: f64 = an.iter().zip(al).map(|(x, y)| x * y).sum();
            let sum: f64 = al.iter().sum();
            *o = sum + (nb - an_alpha) / iterations;
        }
    }
}
