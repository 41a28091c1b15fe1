//! `direct` and `path`: one camera ray, then MIS of the techniques at each vertex
//! (Veach 1997, ch. 9; pbrt-v4 §13.4, path tracing with next-event estimation).
//!
//! `direct` is `path` stopped at the first vertex: the same draws from the same random
//! stream, so with an optimal method `path` at `max_depth = 1` gives `direct`'s image bit
//! for bit.
//!
//! **Path.** At vertex d the techniques' draws estimate the direct lighting of d with
//! integrand `β_d · f_s · |cos| · Li` (module docs of [`crate::integrator`]); the first
//! draw of the BSDF technique also extends the path (a nearest-hit ray; what it meets
//! gives its `Li` as well), so the path needs one secondary ray per vertex. The
//! throughput is multiplied by that draw's `f_s·|cos|/pdf`; after `rr_depth` vertices
//! Russian roulette ends the path with probability `q = max(0.05, 1 − max β)` and divides
//! β by `1 − q` otherwise (pbrt-v3 §14.5.1), and `max_depth` vertices at most are shaded.
//!
//! **Minimum depth.** With [`super::RenderOptions::min_depth`] the vertices shallower
//! than it are shaded as usual (same random numbers, same continuation) but add nothing, so a render
//! with `min_depth = max_depth = d` holds exactly the light of depth d: the per-depth
//! images sum to the full one, heuristics and optimal estimators alike (each depth has
//! its own estimator, which the others never touch).
//!
//! **Heuristic MIS** weights each draw by `w_k(ω) f/(n_k p_k)`, summed into the pixel.
//!
//! **Optimal MIS per depth.** The depth-d contributions of a pixel form one integral over
//! the path prefix X (sub-pixel position and the directions of vertices 1…d−1, drawn by
//! the prefix's own process with density q(X)) and the direction ω at vertex d:
//! `I_d = ∫∫ q(X) g(X, ω) dω dX`, `g = β_d(X) · f_s · |cos| · Li`. The techniques differ in
//! ω only, `P_i(X, ω) = q(X) p_i(ω | X)`, so with integrand `F = q g` the optimal-MIS sums
//! of Kondapaneni et al. (2019, eqs. 15–16) per draw are
//! `P_i P_k / S² = p_i p_k / s²` and `F P_i / S² = g p_i / s²`: exactly what a per-pixel,
//! per-depth [`mis`] estimator accumulates from `(g, p(ω | X))`. Every `P_i` integrates to
//! 1 over the paths that reach depth d, so `A·n = 1` and `Σα = I_d / P(reach d)` hold for
//! that population: each depth's estimator counts only the iterations whose path reached
//! a (not purely specular) vertex d, `N_d` of N, and the pixel value is
//! `Σ_d (N_d/N)·estimate_d + (outside-MIS sum)/N`. `N_d/N → P(reach d)`, so the value is
//! consistent for the direct and uncorrelated estimators (O(1/N) bias, as for `direct`)
//! and unbiased for the progressive and full-weights ones (each iteration that reaches d
//! contributes `Σα + Σ (g − α·p)/s` with α from earlier iterations, whose expectation is
//! `I_d / P(reach d)`). Iterations that do not reach d have contribution 0 for any α, so
//! the α minimising the variance is the optimum for the paths that do, which is what the
//! per-depth state estimates. Memory: one estimator per pixel for each depth reached.

use super::medium::{Flight, Walk};
use super::ray_log::RayLog;
use super::vertex::{emitted, trace, Trace, Vertex};
use super::{Integrator, IntegratorKind, Pixel, RayKind};
use crate::color::Rgb;
use crate::sampler::SampleStream;
use crate::scene::Scene;

/// Smallest roulette termination probability (pbrt-v3 §14.5.1).
pub(super) const RR_MIN_Q: f64 = 0.05;

impl Integrator {
    /// One iteration of `direct` or `path` for pixel (x, y).
    pub(crate) fn path_sample(
        &self,
        scene: &Scene,
        x: u32,
        y: u32,
        rng: &SampleStream,
        px: &mut Pixel,
        rays: &mut impl RayLog,
    ) {
        rays.begin(RayKind::Generate);
        let ray = self.camera_ray(scene, x, y, rng);
        rays.end(RayKind::Generate);
        let camera_emitters = !self.hide_emitters && self.min_depth == 0;
        rays.begin(RayKind::Camera);
        // Through media: the camera sees the walk's end through its transmittance, and
        // the first vertex is the free flight's stop.
        let (first, mut beta) = if scene.participating {
            let walk = Walk::new(scene, &ray, None, scene.camera_medium, None);
            rays.end(RayKind::Camera);
            if self.aovs {
                self.add_aovs(scene, &walk.end, &ray, rng, px);
            }
            if camera_emitters {
                px.add(walk.tr * emitted(scene, &walk.end, ray.d));
            }
            let (uc, u) = self.dims.flight(rng, 0);
            match walk.fly(scene, Rgb::ONE, uc, u) {
                Flight::Scatter { p, medium, weight } => (Trace::Medium { p, medium }, weight),
                Flight::Through(weight) => (walk.end, weight),
            }
        } else {
            let first = trace(scene, &ray, None);
            rays.end(RayKind::Camera);
            if self.aovs {
                self.add_aovs(scene, &first, &ray, rng, px);
            }
            if camera_emitters {
                px.add(emitted(scene, &first, ray.d));
            }
            (first, Rgb::ONE)
        };
        if matches!(first, Trace::Light(_) | Trace::Escape) || beta == Rgb::ZERO {
            return;
        }
        let mut at = first;
        let max_depth = match self.kind {
            IntegratorKind::Direct => 1,
            _ => self.max_depth as usize,
        };
        let mut wo = -ray.d;
        let mut depth = 0usize;
        while depth < max_depth {
            // Built in place (an Option<Vertex> returned was copied, ~250 bytes a vertex).
            let v = match at {
                Trace::Surface(ref h) => Vertex::new(scene, h, wo),
                Trace::Medium { p, medium } => Vertex::in_medium(scene, p, medium, wo),
                Trace::Light(_) | Trace::Escape => break,
            };
            let extend = depth + 1 < max_depth;
            px.mute = depth + 1 < self.min_depth as usize;
            let next = self.shade(scene, &v, beta, depth, extend, rng, px, rays);
            px.mute = false;
            let Some(next) = next else {
                break;
            };
            beta *= next.weight;
            if matches!(next.trace, Trace::Light(_) | Trace::Escape) {
                break;
            }
            if beta == Rgb::ZERO || !beta.is_finite() {
                break;
            }
            if depth + 1 >= self.rr_depth as usize {
                let q = (1.0 - beta.max_element()).max(RR_MIN_Q);
                if self.dims.roulette(rng, depth) < q {
                    break;
                }
                beta /= 1.0 - q;
            }
            at = next.trace;
            wo = -next.wi;
            depth += 1;
        }
    }
}
