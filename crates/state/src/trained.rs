//! A trained light selection (`light-trained`; the `E` technique of Kondapaneni et al.'s
//! pbrt-v3 integrator): per cell of a regular grid over the shading points, a pmf over
//! the MIS lights ∝ each light's contribution measured in a training pass (visibility
//! included), mixed with a uniform floor so that no light has probability 0 (which
//! would bias any estimator that relies on this technique alone).
//!
//! The table is sparse: a cell keeps only the lights measured there (at most one per
//! training draw that landed in it), so its memory grows with the training draws, not
//! with cells × lights, and its pmf and selection cost O(log m) for a cell of m such
//! lights: the pmf is a mixture of the uniform floor and the cell's measured shares, and
//! a selection picks between the two with the same random number (`uc < ε`: uniform,
//! else by the shares' cumulative sums), which gives each light exactly that pmf.
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
    floor: f64,
    /// Cell c's entries are `start[c]..start[c + 1]` (`res³ + 1` offsets).
    start: Vec<u32>,
    /// Per entry, in light order within its cell: the light, its measured weight, and
    /// the running sum of its cell's weights up to it over the cell's total (the last
    /// entry of a cell ends at 1).
    light: Vec<u32>,
    weight: Vec<f64>,
    cum: Vec<f64>,
    /// Per cell, the sum of its weights (0: no entries, a uniform pmf).
    sum: Vec<f64>,
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
        assert!(lights > 0);
        let draws = weights
            .iter()
            .enumerate()
            .map(|(i, &w)| (i / lights, i % lights, w));
        Self::from_draws(lo, hi, res, lights, floor, draws)
    }

    /// The table from measured contributions `(cell, light, value)` ([`Self::cell_of`]'s
    /// cells), summed per cell and light; values that are not finite and positive are
    /// left out. Memory and time grow with the draws, not with cells × lights.
    pub fn from_draws(
        lo: DVec3,
        hi: DVec3,
        res: usize,
        lights: usize,
        floor: f64,
        draws: impl IntoIterator<Item = (usize, usize, f64)>,
    ) -> Self {
        assert!(lights > 0 && res > 0);
        assert!(floor > 0.0 && floor <= 1.0, "floor {floor}");
        let cells = res * res * res;
        let mut kept: Vec<(usize, usize, f64)> = draws
            .into_iter()
            .filter(|&(c, k, w)| {
                assert!(c < cells && k < lights, "cell {c}, light {k}");
                w.is_finite() && w > 0.0
            })
            .collect();
        kept.sort_by_key(|&(c, k, _)| (c, k));
        let mut t = Self {
            lo,
            scale: DVec3::splat(res as f64) / (hi - lo).max(DVec3::splat(1e-12)),
            res,
            lights,
            floor,
            start: vec![0; cells + 1],
            light: Vec::new(),
            weight: Vec::new(),
            cum: Vec::new(),
            sum: vec![0.0; cells],
        };
        // Merge repeated (cell, light) pairs, then count each cell's entries.
        for (c, k, w) in kept {
            if t.light.last() == Some(&(k as u32)) && t.start[c + 1] > 0 {
                *t.weight.last_mut().unwrap() += w;
                continue;
            }
            t.light.push(k as u32);
            t.weight.push(w);
            t.start[c + 1] += 1;
        }
        for c in 0..cells {
            t.start[c + 1] += t.start[c];
        }
        for c in 0..cells {
            let (a, b) = (t.start[c] as usize, t.start[c + 1] as usize);
            t.sum[c] = t.weight[a..b].iter().sum();
            let mut run = 0.0;
            for w in &t.weight[a..b] {
                run += w;
                t.cum.push(run / t.sum[c]);
            }
        }
        t
    }

    /// The cell of point `p` in a `res³` grid over `[lo, hi]`, as a table built over that
    /// grid finds it ([`Self::cell`]), for the draws of [`Self::from_draws`].
    pub fn cell_of(lo: DVec3, hi: DVec3, res: usize, p: DVec3) -> usize {
        let scale = DVec3::splat(res as f64) / (hi - lo).max(DVec3::splat(1e-12));
        cell_in(lo, scale, res, p)
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

    /// The uniform share ε.
    pub fn floor(&self) -> f64 {
        self.floor
    }

    /// Cell c's entries are `offsets()[c]..offsets()[c + 1]` ([`Self::entry`]), for
    /// another back end's copy of the table.
    pub fn offsets(&self) -> &[u32] {
        &self.start
    }

    /// Entry `e` of cell `c`: its light, the running share of the cell's weight up to and
    /// including it, and its own share `w_k/Σw`.
    pub fn entry(&self, c: usize, e: usize) -> (u32, f64, f64) {
        (self.light[e], self.cum[e], self.weight[e] / self.sum[c])
    }

    /// Entries in all cells (the table's size).
    pub fn len(&self) -> usize {
        self.light.len()
    }

    /// Whether no cell measured any light (every pmf uniform).
    pub fn is_empty(&self) -> bool {
        self.light.is_empty()
    }

    /// The cell of point `p` (points outside the box go to the nearest cell).
    pub fn cell(&self, p: DVec3) -> usize {
        cell_in(self.lo, self.scale, self.res, p)
    }

    /// P(light k) at point `p`: `(1 − ε)·w_k/Σw + ε/L` in its cell, uniform in a cell
    /// that measured nothing; 0 for k past the lights.
    pub fn pmf(&self, p: DVec3, k: usize) -> f64 {
        if k >= self.lights {
            return 0.0;
        }
        let c = self.cell(p);
        let uniform = 1.0 / self.lights as f64;
        if self.sum[c] <= 0.0 {
            return uniform;
        }
        let (a, b) = (self.start[c] as usize, self.start[c + 1] as usize);
        let x = match self.light[a..b].binary_search(&(k as u32)) {
            Ok(i) => self.weight[a + i],
            Err(_) => 0.0,
        };
        (1.0 - self.floor) * x / self.sum[c] + self.floor * uniform
    }

    /// Every light's [`Self::pmf`] at `p`, in light order (O(L): for inspection).
    pub fn pmfs(&self, p: DVec3) -> Vec<f64> {
        (0..self.lights).map(|k| self.pmf(p, k)).collect()
    }

    /// The light that `uc` ∈ [0, 1) picks at point `p`: uniformly over the lights for
    /// `uc < ε` (or in a cell that measured nothing), else by the cell's running shares
    /// at `(uc − ε)/(1 − ε)`. Each light is picked with probability [`Self::pmf`].
    pub fn select(&self, p: DVec3, uc: f64) -> usize {
        let c = self.cell(p);
        let n = self.lights;
        let uniform = |u: f64| ((u * n as f64) as usize).min(n - 1);
        if self.sum[c] <= 0.0 {
            return uniform(uc);
        }
        if uc < self.floor {
            return uniform(uc / self.floor);
        }
        let u = (uc - self.floor) / (1.0 - self.floor);
        let (a, b) = (self.start[c] as usize, self.start[c + 1] as usize);
        // The first entry whose running share exceeds u (the last one if rounding
        // leaves u at or past the cell's final share).
        let i = self.cum[a..b].partition_point(|&s| s <= u).min(b - a - 1);
        self.light[a + i] as usize
    }
}

/// The cell of `p` in the grid of low corner `lo`, `scale` cells per unit, `res` per
/// axis; points outside go to the nearest cell.
fn cell_in(lo: DVec3, scale: DVec3, res: usize, p: DVec3) -> usize {
    let q = ((p - lo) * scale).floor();
    let max = (res - 1) as f64;
    let c = |v: f64| {
        if v.is_nan() {
            0
        } else {
            v.clamp(0.0, max) as usize
        }
    };
    (c(q.z) * res + c(q.y)) * res + c(q.x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table of 4³ cells over 37 lights from 500 draws (some repeated, some zero or
    /// not finite), the floor 0.15.
    fn table() -> (TrainedSelection, Vec<f64>) {
        let (res, lights) = (4, 37);
        let cells = res * res * res;
        let mut dense = vec![0.0; cells * lights];
        let mut draws = Vec::new();
        let mut x = 12345u64;
        for i in 0..500 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Half the cells measure nothing.
            let c = ((x >> 33) as usize % (cells / 2)) * 2;
            let k = (x >> 13) as usize % lights;
            let w = match i % 50 {
                0 => f64::NAN,
                1 => 0.0,
                _ => ((x >> 40) % 1000) as f64 / 100.0,
            };
            if w.is_finite() && w > 0.0 {
                dense[c * lights + k] += w;
            }
            draws.push((c, k, w));
        }
        let t =
            TrainedSelection::from_draws(DVec3::splat(-1.0), DVec3::ONE, res, lights, 0.15, draws);
        (t, dense)
    }

    /// A point in cell c of the 4³ grid over [−1, 1]³.
    fn centre(c: usize) -> DVec3 {
        let (x, y, z) = (c % 4, c / 4 % 4, c / 16);
        DVec3::new(x as f64, y as f64, z as f64) * 0.5 - 0.75
    }

    /// The sparse pmf is the dense formula `(1 − ε)·w_k/Σw + ε/L` (uniform where nothing
    /// was measured), sums to 1 in every cell, and the table holds one entry per
    /// measured (cell, light), far fewer than cells × lights.
    #[test]
    fn pmf_is_the_dense_formula() {
        let (t, dense) = table();
        let lights = t.lights();
        for c in 0..64 {
            assert_eq!(t.cell(centre(c)), c);
            let w = &dense[c * lights..(c + 1) * lights];
            let sum: f64 = w.iter().sum();
            let mut total = 0.0;
            for (k, &x) in w.iter().enumerate() {
                let want = if sum > 0.0 {
                    (1.0 - 0.15) * x / sum + 0.15 / lights as f64
                } else {
                    1.0 / lights as f64
                };
                let got = t.pmf(centre(c), k);
                assert!(
                    (got - want).abs() <= 1e-15,
                    "cell {c} light {k}: {got} vs {want}"
                );
                total += got;
            }
            assert!((total - 1.0).abs() < 1e-12, "cell {c}: {total}");
        }
        assert_eq!(t.pmf(centre(0), lights), 0.0);
        let measured = dense.iter().filter(|&&w| w > 0.0).count();
        assert_eq!(t.len(), measured);
        assert!(measured < 500 && measured < 64 * lights / 4);
    }

    /// The probability of each selection equals its pmf: the set of uc ∈ [0, 1) that
    /// picks light k, measured on a grid of 2²⁰ midpoints, has measure P(k) to within
    /// the grid's resolution (each light's set is a union of at most two intervals).
    #[test]
    fn selection_probability_is_the_pmf() {
        let (t, _) = table();
        let m = 1 << 20;
        for c in [0, 2, 6, 1, 40] {
            let p = centre(c);
            let mut picks = vec![0usize; t.lights()];
            for i in 0..m {
                picks[t.select(p, (i as f64 + 0.5) / m as f64)] += 1;
            }
            for (k, &n) in picks.iter().enumerate() {
                let f = n as f64 / m as f64;
                assert!(
                    (f - t.pmf(p, k)).abs() <= 2.0 / m as f64,
                    "cell {c} light {k}: {f} vs {}",
                    t.pmf(p, k)
                );
            }
        }
        // uc just below 1 still picks a light with positive probability.
        let k = t.select(centre(0), 1.0 - f64::EPSILON);
        assert!(t.pmf(centre(0), k) > 0.0);
    }

    /// Memory grows with the draws: 10 000 lights over 8³ cells from 2 000 draws keep
    /// at most 2 000 entries (a dense table would hold 5.12 M pmfs).
    #[test]
    fn memory_grows_with_the_draws() {
        let draws = (0..2000).map(|i| (i * 7 % 512, i * 13 % 10_000, 1.0 + i as f64));
        let t =
            TrainedSelection::from_draws(DVec3::ZERO, DVec3::ONE, 8, 10_000, TRAIN_FLOOR, draws);
        assert!(t.len() <= 2000 && !t.is_empty());
        assert_eq!(t.offsets().len(), 513);
    }
}
