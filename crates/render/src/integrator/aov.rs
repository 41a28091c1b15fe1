//! First-hit arbitrary output variables (AOVs): depth, normal and albedo, as extra film
//! channels beside any integrator or as the image of the `depth`, `normals` and `albedo`
//! integrators.
//!
//! The first hit is the nearest of objects and area lights along the camera ray. Depth is
//! the distance along the (unit) camera ray, the normal the outward unit normal there
//! (world space), and the albedo the BSDF's directional albedo toward the camera,
//! `ρ(ωo) = ∫ f_s(ωo, ω)|cos θ| dω`, estimated by one BSDF draw per sample (its weight
//! `f_s|cos|/pdf`; exact for Lambertian surfaces). All three are 0 where the ray escapes;
//! a light has albedo 0. Each is averaged over the pixel's samples. The albedo draw takes
//! its random numbers from dimensions of its own ([`super::dims`]), so that asking for
//! AOVs changes no other random number of the render.

use super::ray_log::RayLog;
use super::vertex::{Trace, Vertex};
use super::{Integrator, IntegratorKind, Pixel};
use crate::color::Rgb;
use crate::sampler::SampleStream;
use crate::scene::Scene;
use frep::Ray;
use state::dims::ALBEDO;
pub use state::Aov;

/// Depth, normal and albedo of a camera ray's first hit.
fn first_hit(scene: &Scene, t: &Trace, ray: &Ray, rng: &SampleStream) -> [f64; 7] {
    match t {
        // Walks end at a light, a surface or the escape, never in a medium.
        Trace::Escape | Trace::Medium { .. } => [0.0; 7],
        Trace::Light(l) => [l.t, l.n.x, l.n.y, l.n.z, 0.0, 0.0, 0.0],
        Trace::Surface(h) => {
            let v = Vertex::new(scene, h, -ray.d);
            let a = v
                .bsdf
                .sample_f(v.wo, rng.get(ALBEDO), rng.get_2d(ALBEDO + 1))
                .map_or(Rgb::ZERO, |s| s.weight);
            [h.t, h.n.x, h.n.y, h.n.z, a.x, a.y, a.z]
        }
    }
}

impl Integrator {
    /// Adds the first hit's AOVs to the pixel's sums.
    pub(crate) fn add_aovs(
        &self,
        scene: &Scene,
        t: &Trace,
        ray: &Ray,
        rng: &SampleStream,
        px: &mut Pixel,
    ) {
        px.add_aovs(&first_hit(scene, t, ray, rng));
    }

    /// One sample of the `depth`, `normals` or `albedo` integrator.
    pub(crate) fn aov_sample(
        &self,
        scene: &Scene,
        x: u32,
        y: u32,
        rng: &SampleStream,
        px: &mut Pixel,
        rays: &mut impl RayLog,
    ) {
        let (ray, t) = self.camera_trace(scene, x, y, rng, rays);
        let a = first_hit(scene, &t, &ray, rng);
        px.add(match self.kind {
            IntegratorKind::Depth => Rgb::splat(a[0]),
            IntegratorKind::Normals => Rgb::new(a[1], a[2], a[3]),
            _ => Rgb::new(a[4], a[5], a[6]),
        });
        px.add_aovs(&a);
    }
}
