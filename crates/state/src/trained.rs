//! A trained light selection (`light-trained`; the `E` technique of Kondapaneni et al.'s
//! pbrt-v3 integrator): per cell of a regular grid over the shading points, a pmf over
//! the MIS lights ∝ each light's contribution measured in a training pass (visibility
//! included), mixed with a uniform floor so that no light has probability 0 (which
//! would bias any estimator that relies on this technique alone).
//!
//! The pass itself (camera rays, one light draw each, shadow rays) lives with the
//! integrators (`integrator/train.rs`); this module holds the table and its pmf.

use glam::DVec3;

/// Cells per axis of the training grid, by default (`scene::Training::grid`).
pub const TRAIN_GRID: usize = 8;

/// The uniform share ε of the trained pmf, `P(k) = (1 − ε)·w_k/Σw + ε/L`, by default
/// (`scene::Training::floor`).
pub const TRAIN_FLOOR: f64 = 0.1;

/// Per-cell light-selection pmfs learned from measured contributions (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct TrainedSelection {
    lo: DVec3,
    /// Cells per unit length, per axis.
    scale: DVec3,
    res: usize,
    lights: usize,
    /// `res³ × lights` probabilities, cell-major.
    pmf: Vec<f64>,
}

impl TrainedSelection {
    /// The table for a `res³` grid over the box `[lo, hi]` and `lights` MIS lights, from
    /// the measured contributions `weights` (`res³ × lights`, cell-major, non-negative):
    /// in each cell `P(k) = (1 − ε)·w_k/Σw + ε/L` with ε = [`TRAIN_FLOOR`], uniform where
    /// nothing was measured.
    pub fn from_weights(lo: DVec3, hi: DVec3, res: usize, lights: usize, weights: &[f64]) -> Self {
        Self::with_floor(lo, hi, res, lights, weights, TRAIN_FLOOR)
    }

    /// [`Self::from_weights`] with the uniform share ε = `floor`, in (0, 1].
    pub fn with_floor(
        lo: DVec3,
        hi: DVec3,
        res: usize,
        lights: usize,
        weights: &[f64],
        floor: f64,
    ) -> Self {
        assert_eq!(weights.len(), res * res * res * lights, "weights");
        assert!(lights > 0 && res > 0);
        assert!(floor > 0.0 && floor <= 1.0, "floor {floor}");
        let ext = (hi - lo).max(DVec3::splat(1e-12));
        let mut pmf = Vec::with_capacity(weights.len());
        let uniform = 1.0 / lights as f64;
        for w in weights.chunks_exact(lights) {
            let sum: f64 = w.iter().filter(|x| x.is_finite() && **x > 0.0).sum();
            for &x in w {
                let x = if x.is_finite() && x > 0.0 { x } else { 0.0 };
                pmf.push(if sum > 0.0 {
                    (1.0 - floor) * x / sum + floor * uniform
                } else {
                    uniform
                });
            }
        }
        Self {
            lo,
            scale: DVec3::splat(res as f64) / ext,
            res,
            lights,
            pmf,
        }
    }

    /// The number of MIS lights the table covers.
    pub fn lights(&self) -> usize {
        self.lights
    }

    /// The grid's low corner, cells per unit along each axis and cells per axis (what
    /// [`Self::cell`] reads), for another back end's copy of the table.
    pub fn grid(&self) -> (DVec3, DVec3, usize) {
        (self.lo, self.scale, self.res)
    }

    /// Every cell's pmf over the MIS lights, cell after cell ([`Self::cell`]'s order).
    pub fn table(&self) -> &[f64] {
        &self.pmf
    }

    /// The cell of point `p` (points outside the box go to the nearest cell).
    pub fn cell(&self, p: DVec3) -> usize {
        let q = ((p - self.lo) * self.scale).floor();
        let max = (self.res - 1) as f64;
        let c = |v: f64| {
            if v.is_nan() {
                0
            } else {
                v.clamp(0.0, max) as usize
            }
        };
        (c(q.z) * self.res + c(q.y)) * self.res + c(q.x)
    }

    /// The selection pmf over the MIS lights at point `p`.
    pub fn pmf(&self, p: DVec3) -> &[f64] {
        let c = self.cell(p);
        &self.pmf[c * self.lights..(c + 1) * self.lights]
    }
}
