//! The shape of a multi-sample MIS problem: T techniques, `n_i` samples of technique i per
//! iteration, and the number of colour channels. Shared (behind an `Arc`) by every
//! per-pixel estimator so that the per-pixel state is only its sums.

use std::sync::Arc;

/// Techniques, their sample counts per iteration, and channels (Veach 1997, §9.2.2).
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    counts: Vec<f64>,
    channels: usize,
}

impl Layout {
    /// `counts[i]` = `n_i` ≥ 1 samples of technique i per iteration; `channels` ≥ 1 values
    /// of f per sample (e.g. 3 for RGB). Panics on an empty or zero count, or no channel.
    pub fn new(counts: &[u32], channels: usize) -> Arc<Layout> {
        assert!(!counts.is_empty(), "MIS needs at least one technique");
        assert!(
            counts.iter().all(|&n| n >= 1),
            "every technique needs n_i ≥ 1 samples per iteration (leave unused ones out)"
        );
        assert!(channels >= 1, "at least one channel");
        Arc::new(Layout {
            counts: counts.iter().map(|&n| f64::from(n)).collect(),
            channels,
        })
    }

    /// Number of techniques T.
    #[inline]
    pub fn techniques(&self) -> usize {
        self.counts.len()
    }

    /// Number of channels of f.
    #[inline]
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// `n_i` per technique, as f64.
    #[inline]
    pub fn counts(&self) -> &[f64] {
        &self.counts
    }

    /// The mixture density `s(x) = Σ_k n_k p_k(x)` (Kondapaneni et al. 2019, eq. 9).
    #[inline]
    pub fn mixture(&self, pdfs: &[f64]) -> f64 {
        debug_assert_eq!(pdfs.len(), self.counts.len(), "one pdf per technique");
        self.counts.iter().zip(pdfs).map(|(n, p)| n * p).sum()
    }

    /// Whether a sample of technique `t` with these pdfs carries information: its own pdf
    /// and the mixture are positive and finite. Otherwise it counts as a failed sample.
    #[inline]
    pub fn is_valid(&self, t: usize, pdfs: &[f64]) -> Option<f64> {
        let s = self.mixture(pdfs);
        (pdfs[t] > 0.0 && s.is_finite()).then_some(s)
    }

    /// Panics unless `other` describes the same problem (needed before a merge).
    pub(crate) fn assert_same(&self, other: &Layout) {
        assert!(
            self == other,
            "cannot merge estimators of different layouts"
        );
    }
}
