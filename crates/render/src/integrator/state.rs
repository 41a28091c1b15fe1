//! Per-pixel accumulation and ray counters.

use super::{Combine, Integrator};
use crate::color::Rgb;
use mis::{AnyEstimator, Estimator};
use std::ops::AddAssign;

/// Rays traced, by kind: camera rays, secondary rays (nearest-hit queries that extend a
/// path) and shadow rays (any-hit visibility queries). Queries against the analytic area
/// lights alone are not counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Camera rays.
    pub camera: u64,
    /// Secondary (continuation) rays.
    pub secondary: u64,
    /// Shadow rays.
    pub shadow: u64,
}

impl RayCounts {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.camera + self.secondary + self.shadow
    }
}

impl AddAssign for RayCounts {
    fn add_assign(&mut self, o: RayCounts) {
        self.camera += o.camera;
        self.secondary += o.secondary;
        self.shadow += o.shadow;
    }
}

/// Everything one pixel has accumulated.
#[derive(Clone, Debug, Default)]
pub(crate) struct PixelState {
    /// Iterations (samples) N.
    pub iterations: u64,
    /// Σ of what is added outside MIS, and of heuristic-weighted draws in `path`.
    pub sum: Rgb,
    /// One estimator per depth (index 0: the first vertex), created when first reached.
    pub depths: Vec<AnyEstimator>,
    /// Σ of the first-hit AOVs: depth, normal (3), albedo (3).
    pub aov: [f64; 7],
}

impl PixelState {
    /// A draw of technique `k` at vertex `depth` with integrand `f` (throughput included)
    /// and every technique's pdf.
    #[inline]
    pub fn add_draw(&mut self, it: &Integrator, depth: usize, k: usize, f: Rgb, pdfs: &[f64]) {
        match &it.combine {
            Combine::Heuristic(h) => {
                // w_k f / (n_k p_k) (Veach 1997, eq. 9.4); a draw with own pdf 0 adds 0.
                let Some(s) = it.layout.is_valid(k, pdfs) else {
                    return;
                };
                let scale = match h {
                    mis::Heuristic::Balance => 1.0 / s,
                    h => {
                        let n = it.layout.counts();
                        h.weight(k, n, pdfs) / (n[k] * pdfs[k])
                    }
                };
                if scale != 0.0 {
                    self.sum += f * scale;
                }
            }
            Combine::Estimator => self.estimator(it, depth).add_sample(k, &f.to_array(), pdfs),
        }
    }

    /// Technique `k` produced no draw (or a delta-lobe draw) at vertex `depth`.
    #[inline]
    pub fn add_failed(&mut self, it: &Integrator, depth: usize, k: usize) {
        if let Combine::Estimator = it.combine {
            self.estimator(it, depth).add_failed(k);
        }
    }

    /// Closes the iteration of vertex `depth`'s estimator.
    #[inline]
    pub fn end_vertex(&mut self, it: &Integrator, depth: usize) {
        if let Combine::Estimator = it.combine {
            self.estimator(it, depth).end_iteration();
        }
    }

    fn estimator(&mut self, it: &Integrator, depth: usize) -> &mut AnyEstimator {
        while self.depths.len() <= depth {
            let e = it
                .method
                .build(&it.layout, &it.params)
                .expect("parameters validated with the options");
            self.depths.push(e);
        }
        &mut self.depths[depth]
    }

    /// The pixel value: `sum/N + Σ_d (N_d/N)·estimate_d` (module docs of
    /// [`crate::integrator`]); 0 before the first sample.
    pub fn value(&self) -> Rgb {
        if self.iterations == 0 {
            return Rgb::ZERO;
        }
        let n = self.iterations as f64;
        let mut v = self.sum / n;
        let mut out = [0.0; 3];
        for e in &self.depths {
            let nd = e.iterations();
            if nd > 0 {
                e.estimate(&mut out);
                v += Rgb::from_array(out) * (nd as f64 / n);
            }
        }
        v
    }

    /// The mean of AOV value `i` (see [`Self::aov`]).
    pub fn aov_mean(&self, i: usize) -> f64 {
        if self.iterations == 0 {
            0.0
        } else {
            self.aov[i] / self.iterations as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::{IntegratorKind, RenderOptions};
    use crate::technique::Technique;
    use mis::Method;

    /// `value = sum/N + Σ_d (N_d/N)·estimate_d`: a depth reached in half the iterations
    /// counts half, heuristic draws go to the sum.
    #[test]
    fn pixel_value_weights_each_depth_by_its_share_of_iterations() {
        let o = RenderOptions {
            integrator: IntegratorKind::Path,
            method: Method::OptimalDirect,
            techniques: vec![(Technique::Bsdf, 1)],
            ..RenderOptions::default()
        };
        let it = Integrator::new(&o).unwrap();
        let mut px = PixelState::default();
        assert_eq!(px.value(), Rgb::ZERO);
        for i in 0..4 {
            px.iterations += 1;
            px.sum += Rgb::splat(1.0);
            px.add_draw(&it, 0, 0, Rgb::new(2.0, 4.0, 6.0), &[2.0]);
            px.end_vertex(&it, 0);
            if i % 2 == 0 {
                px.add_draw(&it, 1, 0, Rgb::splat(3.0), &[1.5]);
                px.end_vertex(&it, 1);
            }
        }
        // One technique: the estimate of depth d is the mean of f/p over its iterations.
        let v = px.value();
        let expect = Rgb::splat(1.0) + Rgb::new(1.0, 2.0, 3.0) + Rgb::splat(2.0) * 0.5;
        assert!((v - expect).abs().max_element() < 1e-12, "{v} vs {expect}");
        // The same draws under the balance heuristic in `path` go straight to the sum.
        let it = Integrator::new(&RenderOptions {
            method: Method::Balance,
            ..o
        })
        .unwrap();
        let mut px = PixelState {
            iterations: 2,
            ..PixelState::default()
        };
        px.add_draw(&it, 0, 0, Rgb::splat(2.0), &[2.0]);
        px.add_draw(&it, 3, 0, Rgb::splat(4.0), &[0.0]);
        assert!(px.depths.is_empty());
        assert_eq!(px.value(), Rgb::splat(0.5));
    }
}
