//! Glass: specular or GGX rough reflection and transmission through a dielectric
//! interface (Walter et al. 2007, "Microfacet Models for Refraction through Rough
//! Surfaces"; pbrt-v4 §9.5 and §9.7).

use super::fresnel::fr_dielectric;
use super::microfacet::TrowbridgeReitz;
use super::{reflect, refract, same_hemisphere, BsdfSample};
use crate::color::Rgb;
use glam::{DVec2, DVec3};

/// A dielectric interface with relative index η = n_inside/n_outside (+z is outside).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricBxdf {
    /// Microfacet distribution (smooth: delta lobes).
    pub distrib: TrowbridgeReitz,
    /// Relative index of refraction.
    pub eta: f64,
}

impl DielectricBxdf {
    /// The generalised half vector (Walter et al. 2007, eq. 16), facing +z, and the
    /// relative index of the event; None for degenerate or back-facing configurations.
    fn half_vector(&self, wo: DVec3, wi: DVec3) -> Option<(DVec3, f64, bool)> {
        let (co, ci) = (wo.z, wi.z);
        let reflect = ci * co > 0.0;
        let etap = if reflect {
            1.0
        } else if co > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let wm = wi * etap + wo;
        if ci == 0.0 || co == 0.0 || wm.length_squared() == 0.0 {
            return None;
        }
        let mut wm = wm.normalize();
        if wm.z < 0.0 {
            wm = -wm;
        }
        // Discard back-facing microfacets.
        if wm.dot(wi) * ci < 0.0 || wm.dot(wo) * co < 0.0 {
            return None;
        }
        Some((wm, etap, reflect))
    }

    /// Reflection D F G / |4 cos θo cos θi|; transmission
    /// D (1−F) G |ωi·ωm ωo·ωm| / (|cos θi cos θo| (ωi·ωm + ωo·ωm/η′)²) / η′².
    pub fn f(&self, wo: DVec3, wi: DVec3) -> Rgb {
        if self.eta == 1.0 || self.distrib.effectively_smooth() {
            return Rgb::ZERO;
        }
        let Some((wm, etap, is_reflect)) = self.half_vector(wo, wi) else {
            return Rgb::ZERO;
        };
        let fr = fr_dielectric(wo.dot(wm), self.eta);
        let dg = self.distrib.d(wm) * self.distrib.g(wo, wi);
        let v = if is_reflect {
            dg * fr / (4.0 * wi.z * wo.z).abs()
        } else {
            let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2) * wi.z * wo.z;
            dg * (1.0 - fr) * (wi.dot(wm) * wo.dot(wm) / denom).abs() / (etap * etap)
        };
        Rgb::splat(v)
    }

    /// Chooses reflection with probability R/(R+T), then mirrors or refracts about the
    /// normal (smooth) or a sampled visible microfacet normal (rough).
    pub fn sample_f(&self, wo: DVec3, uc: f64, u: DVec2) -> Option<BsdfSample> {
        if self.eta == 1.0 || self.distrib.effectively_smooth() {
            let r = fr_dielectric(wo.z, self.eta);
            let t = 1.0 - r;
            if uc < r / (r + t) {
                let wi = DVec3::new(-wo.x, -wo.y, wo.z);
                let f = Rgb::splat(r / wi.z.abs());
                Some(BsdfSample::new(wi, f, r / (r + t), true, 1.0))
            } else {
                let (wi, etap) = refract(wo, DVec3::Z, self.eta)?;
                let f = Rgb::splat(t / wi.z.abs() / (etap * etap));
                Some(BsdfSample::new(wi, f, t / (r + t), true, etap))
            }
        } else {
            let wm = self.distrib.sample_wm(wo, u);
            let r = fr_dielectric(wo.dot(wm), self.eta);
            let t = 1.0 - r;
            let pdf_wm = self.distrib.pdf(wo, wm);
            if uc < r / (r + t) {
                let wi = reflect(wo, wm);
                if !same_hemisphere(wo, wi) {
                    return None;
                }
                let pdf = pdf_wm / (4.0 * wo.dot(wm).abs()) * r / (r + t);
                let f = Rgb::splat(
                    self.distrib.d(wm) * self.distrib.g(wo, wi) * r / (4.0 * wi.z * wo.z).abs(),
                );
                (pdf > 0.0).then(|| BsdfSample::new(wi, f, pdf, false, 1.0))
            } else {
                let (wi, etap) = refract(wo, wm, self.eta)?;
                if same_hemisphere(wo, wi) || wi.z == 0.0 {
                    return None;
                }
                let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
                let dwm_dwi = wi.dot(wm).abs() / denom;
                let pdf = pdf_wm * dwm_dwi * t / (r + t);
                let ft = self.distrib.d(wm)
                    * self.distrib.g(wo, wi)
                    * t
                    * (wi.dot(wm) * wo.dot(wm) / (wi.z * wo.z * denom)).abs()
                    / (etap * etap);
                (pdf > 0.0).then(|| BsdfSample::new(wi, Rgb::splat(ft), pdf, false, etap))
            }
        }
    }

    /// The density of the non-delta samples of [`Self::sample_f`].
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if self.eta == 1.0 || self.distrib.effectively_smooth() {
            return 0.0;
        }
        let Some((wm, etap, is_reflect)) = self.half_vector(wo, wi) else {
            return 0.0;
        };
        let r = fr_dielectric(wo.dot(wm), self.eta);
        let t = 1.0 - r;
        let pdf_wm = self.distrib.pdf(wo, wm);
        if is_reflect {
            pdf_wm / (4.0 * wo.dot(wm).abs()) * r / (r + t)
        } else {
            let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
            pdf_wm * wi.dot(wm).abs() / denom * t / (r + t)
        }
    }
}
