//! Metal: GGX microfacet reflection with the conductor Fresnel term (Walter et al. 2007;
//! pbrt-v4 §9.6.3), sampled by visible normals (Heitz 2018).

use super::fresnel::fr_conductor;
use super::microfacet::TrowbridgeReitz;
use super::{reflect, same_hemisphere, BsdfSample};
use crate::color::Rgb;
use glam::{DVec2, DVec3};

/// A conductor with complex index η + i k per channel and GGX roughness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConductorBxdf {
    /// Microfacet distribution (mirror when effectively smooth).
    pub distrib: TrowbridgeReitz,
    /// Real part of the index of refraction.
    pub eta: Rgb,
    /// Absorption coefficient.
    pub k: Rgb,
}

impl ConductorBxdf {
    /// f = D(ωm) F(ωo·ωm) G(ωo, ωi) / (4 |cos θo| |cos θi|), ωm the half vector.
    pub fn f(&self, wo: DVec3, wi: DVec3) -> Rgb {
        if !same_hemisphere(wo, wi) || self.distrib.effectively_smooth() {
            return Rgb::ZERO;
        }
        let (co, ci) = (wo.z.abs(), wi.z.abs());
        let wm = wo + wi;
        if co == 0.0 || ci == 0.0 || wm.length_squared() == 0.0 {
            return Rgb::ZERO;
        }
        let wm = wm.normalize();
        let fr = fr_conductor(wo.dot(wm).abs(), self.eta, self.k);
        fr * (self.distrib.d(wm) * self.distrib.g(wo, wi) / (4.0 * co * ci))
    }
    /// Mirror reflection, or reflection about a visible normal.
    pub fn sample_f(&self, wo: DVec3, u: DVec2) -> Option<BsdfSample> {
        if self.distrib.effectively_smooth() {
            let wi = DVec3::new(-wo.x, -wo.y, wo.z);
            let c = wi.z.abs();
            let f = fr_conductor(c, self.eta, self.k) / c;
            return Some(BsdfSample::new(wi, f, 1.0, true, 1.0));
        }
        if wo.z == 0.0 {
            return None;
        }
        let wm = self.distrib.sample_wm(wo, u);
        let wi = reflect(wo, wm);
        if !same_hemisphere(wo, wi) {
            return None;
        }
        let pdf = self.distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs());
        let f = self.f(wo, wi);
        (pdf > 0.0).then(|| BsdfSample::new(wi, f, pdf, false, 1.0))
    }
    /// [`Self::f`] and [`Self::pdf`] at once, bit for bit: the half vector, D(ωm) and
    /// Λ(ωo) are computed once (D, a function of ωm's squared components, and |ωo·ωm|
    /// are the same at ±ωm, so the pdf's ωm flipped to +z changes neither).
    pub fn f_pdf(&self, wo: DVec3, wi: DVec3) -> (Rgb, f64) {
        if !same_hemisphere(wo, wi) || self.distrib.effectively_smooth() {
            return (Rgb::ZERO, 0.0);
        }
        let wm = wo + wi;
        if wm.length_squared() == 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        // Both z are non-zero here (their product is positive), so `f`'s zero-cosine
        // exit cannot apply.
        let (co, ci) = (wo.z.abs(), wi.z.abs());
        let wm = wm.normalize();
        let dist = &self.distrib;
        let (d, lo) = (dist.d(wm), dist.lambda(wo));
        let dot = wo.dot(wm).abs();
        let fr = fr_conductor(dot, self.eta, self.k);
        let f = fr * (d * (1.0 / (1.0 + lo + dist.lambda(wi))) / (4.0 * co * ci));
        let up = if wm.z < 0.0 { -wm } else { wm };
        let pdf = dist.d_visible_with(wo, up, d, lo) / (4.0 * dot);
        (f, pdf)
    }
    /// D_ωo(ωm) / (4 |ωo·ωm|).
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if !same_hemisphere(wo, wi) || self.distrib.effectively_smooth() {
            return 0.0;
        }
        let wm = wo + wi;
        if wm.length_squared() == 0.0 {
            return 0.0;
        }
        let mut wm = wm.normalize();
        if wm.z < 0.0 {
            wm = -wm;
        }
        self.distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs())
    }
}
