//! Bidirectional scattering distribution functions (pbrt-v4 ch. 9).
//!
//! A [`Bxdf`] works in the local shading frame (normal = +z); a [`Bsdf`] pairs it with
//! the frame built from the surface normal. Conventions (pbrt-v4): `wo` points toward
//! the viewer, `wi` toward the light, both away from the surface; `f(wo, wi)` is the
//! BSDF in radiance transport mode (transmission is divided by η², pbrt-v4 §9.5.2).
//! Reflective BSDFs are two-sided.

mod conductor;
mod dielectric;
mod diffuse;
pub mod fresnel;
pub mod microfacet;
mod phase;
mod plastic;

pub use conductor::ConductorBxdf;
pub use dielectric::DielectricBxdf;
pub use diffuse::DiffuseBxdf;
pub use phase::HenyeyGreenstein;
pub use plastic::{CoatTable, PlasticBxdf};

use crate::color::Rgb;
use crate::frame::Frame;
use glam::{DVec2, DVec3};

/// A direction drawn from a BSDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The sampled incident direction (toward the light).
    pub wi: DVec3,
    /// BSDF value f(wo, wi); for a specular sample, the delta lobe's coefficient.
    pub f: Rgb,
    /// Density in solid angle; for a specular sample, the discrete probability of the lobe.
    pub pdf: f64,
    /// f·|cos θi| / pdf, the Monte Carlo weight of the sample.
    pub weight: Rgb,
    /// Whether the sample comes from a delta (mirror or smooth refraction) lobe.
    pub specular: bool,
    /// Whether wi is on the other side of the surface from wo.
    pub transmission: bool,
    /// The relative index of refraction n(wi side)/n(wo side) (1 for reflection).
    pub eta: f64,
}

impl BsdfSample {
    /// A sample in local coordinates; the weight is computed from wi.z.
    pub fn new(wi: DVec3, f: Rgb, pdf: f64, specular: bool, eta: f64) -> Self {
        let weight = if pdf > 0.0 {
            f * (wi.z.abs() / pdf)
        } else {
            Rgb::ZERO
        };
        Self {
            wi,
            f,
            pdf,
            weight,
            specular,
            transmission: false,
            eta,
        }
    }
}

/// Whether two local directions lie on the same side of the surface.
#[inline]
pub fn same_hemisphere(a: DVec3, b: DVec3) -> bool {
    a.z * b.z > 0.0
}

/// Mirror reflection of `wo` about `n`.
#[inline]
pub fn reflect(wo: DVec3, n: DVec3) -> DVec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// Refraction of `wi` through an interface with normal `n` (pointing outside) and
/// relative index η = n_inside/n_outside (pbrt-v4 `Refract`); returns the transmitted
/// direction and the relative index n_t/n_i, or None under total internal reflection.
pub fn refract(wi: DVec3, n: DVec3, eta: f64) -> Option<(DVec3, f64)> {
    let mut cos_i = n.dot(wi);
    let (mut eta, mut n) = (eta, n);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wi / eta + (cos_i / eta - cos_t) * n, eta))
}

/// A BSDF in the local shading frame.
#[derive(Clone, Copy, Debug)]
pub enum Bxdf<'a> {
    /// Lambertian reflection.
    Diffuse(DiffuseBxdf),
    /// Rough or smooth metal.
    Conductor(ConductorBxdf),
    /// Rough or smooth glass.
    Dielectric(DielectricBxdf),
    /// Diffuse base under a dielectric coat.
    Plastic(PlasticBxdf<'a>),
    /// A medium's phase function (no cosine factor: see [`Bsdf::cos`]).
    Phase(HenyeyGreenstein),
}

impl Bxdf<'_> {
    /// f(wo, wi) of the non-delta part.
    pub fn f(&self, wo: DVec3, wi: DVec3) -> Rgb {
        match self {
            Bxdf::Diffuse(b) => b.f(wo, wi),
            Bxdf::Conductor(b) => b.f(wo, wi),
            Bxdf::Dielectric(b) => b.f(wo, wi),
            Bxdf::Plastic(b) => b.f(wo, wi),
            Bxdf::Phase(b) => b.f(wo, wi),
        }
    }
    /// Draws wi given wo from `uc` (lobe choice) and `u`; None when no direction results.
    pub fn sample_f(&self, wo: DVec3, uc: f64, u: DVec2) -> Option<BsdfSample> {
        match self {
            Bxdf::Diffuse(b) => b.sample_f(wo, u),
            Bxdf::Conductor(b) => b.sample_f(wo, u),
            Bxdf::Dielectric(b) => b.sample_f(wo, uc, u),
            Bxdf::Plastic(b) => b.sample_f(wo, uc, u),
            Bxdf::Phase(b) => b.sample_f(wo, u),
        }
    }
    /// Density in solid angle of `sample_f` producing the non-specular direction wi.
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        match self {
            Bxdf::Diffuse(b) => b.pdf(wo, wi),
            Bxdf::Conductor(b) => b.pdf(wo, wi),
            Bxdf::Dielectric(b) => b.pdf(wo, wi),
            Bxdf::Plastic(b) => b.pdf(wo, wi),
            Bxdf::Phase(b) => b.pdf(wo, wi),
        }
    }
    /// `(f(wo, wi), pdf(wo, wi))` bit for bit, sharing what the two have in common.
    pub fn f_pdf(&self, wo: DVec3, wi: DVec3) -> (Rgb, f64) {
        match self {
            Bxdf::Diffuse(b) => (b.f(wo, wi), b.pdf(wo, wi)),
            Bxdf::Conductor(b) => b.f_pdf(wo, wi),
            Bxdf::Dielectric(b) => (b.f(wo, wi), b.pdf(wo, wi)),
            Bxdf::Plastic(b) => (b.f(wo, wi), b.pdf(wo, wi)),
            Bxdf::Phase(b) => {
                let p = b.pdf(wo, wi);
                (Rgb::splat(p), p)
            }
        }
    }
    /// Whether the BSDF has a delta lobe (samples flagged `specular`).
    pub fn has_specular(&self) -> bool {
        match self {
            Bxdf::Diffuse(_) | Bxdf::Phase(_) => false,
            Bxdf::Conductor(b) => b.distrib.effectively_smooth(),
            Bxdf::Dielectric(b) => b.distrib.effectively_smooth() || b.eta == 1.0,
            Bxdf::Plastic(b) => b.coat.distrib.effectively_smooth(),
        }
    }
    /// Whether the BSDF is nothing but delta lobes (f and pdf are 0 everywhere).
    pub fn is_pure_specular(&self) -> bool {
        match self {
            Bxdf::Plastic(_) | Bxdf::Diffuse(_) | Bxdf::Phase(_) => false,
            _ => self.has_specular(),
        }
    }
}

/// A BSDF at a surface point: a local [`Bxdf`] and its shading frame.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf<'a> {
    /// The shading frame (n = shading normal).
    pub frame: Frame,
    /// The local scattering function.
    pub bxdf: Bxdf<'a>,
}

impl<'a> Bsdf<'a> {
    /// The BSDF with shading normal `n` (unit length).
    pub fn new(n: DVec3, bxdf: Bxdf<'a>) -> Self {
        Self {
            frame: Frame::from_z(n),
            bxdf,
        }
    }
    /// The phase function at a medium point, its frame about `wo` (any frame serves).
    pub fn phase(g: f64, wo: DVec3) -> Self {
        Self::new(wo, Bxdf::Phase(HenyeyGreenstein { g }))
    }
    /// The projection factor of the integrand for wi at shading normal `n`: |cos θi|
    /// at a surface, 1 at a medium point (a phase function integrates over the sphere
    /// without one).
    #[inline]
    pub fn cos(&self, n: DVec3, wi: DVec3) -> f64 {
        if matches!(self.bxdf, Bxdf::Phase(_)) {
            1.0
        } else {
            wi.dot(n).abs()
        }
    }
    /// f(wo, wi) in world space.
    pub fn f(&self, wo: DVec3, wi: DVec3) -> Rgb {
        self.bxdf
            .f(self.frame.to_local(wo), self.frame.to_local(wi))
    }
    /// Density in solid angle of sampling wi given wo (world space).
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        self.bxdf
            .pdf(self.frame.to_local(wo), self.frame.to_local(wi))
    }
    /// `(self.f(wo, wi), self.pdf(wo, wi))` bit for bit, the directions taken to the
    /// local frame once (an integrator needs both at every MIS draw).
    pub fn f_pdf(&self, wo: DVec3, wi: DVec3) -> (Rgb, f64) {
        self.bxdf
            .f_pdf(self.frame.to_local(wo), self.frame.to_local(wi))
    }
    /// Draws an incident direction (world space).
    pub fn sample_f(&self, wo: DVec3, uc: f64, u: DVec2) -> Option<BsdfSample> {
        let wo_l = self.frame.to_local(wo);
        if wo_l.z == 0.0 {
            return None;
        }
        let s = self.bxdf.sample_f(wo_l, uc, u)?;
        if s.pdf <= 0.0 || s.wi.z == 0.0 || !s.pdf.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi: self.frame.from_local(s.wi),
            transmission: s.wi.z * wo_l.z < 0.0,
            ..s
        })
    }
}

#[cfg(test)]
mod tests;
