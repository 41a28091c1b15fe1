//! Plastic: a diffuse base under a smooth or GGX-rough dielectric coat, after
//! Mitsuba's `plastic` / `roughplastic` (Jakob; Weidlich & Wilkie 2007).
//!
//! f = f_coat + f_base with
//! - f_coat = D F(ωo·ωm) G / (4 cos θo cos θi), the coat's microfacet reflection
//!   (a mirror of reflectance F(cos θo) when smooth);
//! - f_base = ρ t(μo) t(μi) / (π η² (1 − ρ R_int)), light refracted into the coat
//!   (t = 1 − E_coat, E_coat the coat's directional albedo), bounced diffusely any
//!   number of times under an interface of internal reflectance R_int, and refracted out.
//!
//! R_int is set to 1 − 2∫t(μ)μ dμ / η², which equals the internal diffuse Fresnel
//! reflectance for a smooth coat (since η²(1 − F_dr,int) = 1 − F_dr,ext) and keeps
//! the total albedo E_coat + t ρ(1 − R_int)/(1 − ρ R_int) ≤ 1, with equality at ρ = 1.

use super::fresnel::fr_dielectric;
use super::microfacet::TrowbridgeReitz;
use super::{reflect, same_hemisphere, BsdfSample};
use crate::color::{average, Rgb};
use crate::warp::cosine_hemisphere;
use glam::{DVec2, DVec3};
use std::f64::consts::FRAC_1_PI;

/// Table size of the coat albedo over √μ.
const TABLE: usize = 64;

/// The coat's directional albedo E_coat(μ) and internal reflectance, precomputed once
/// per (η, α) by quadrature over visible normals.
#[derive(Clone, Debug, PartialEq)]
pub struct CoatTable {
    /// The coat's microfacet distribution.
    pub distrib: TrowbridgeReitz,
    /// Relative index of the coat.
    pub eta: f64,
    /// E_coat at μ = (j/TABLE)², j = 0..=TABLE (empty when smooth: E = F exactly).
    albedo: Vec<f64>,
    /// Internal diffuse reflectance R_int.
    pub r_int: f64,
}

impl CoatTable {
    /// The table for a coat of index η and GGX roughness α.
    pub fn new(eta: f64, alpha: f64) -> Self {
        let distrib = TrowbridgeReitz::isotropic(alpha);
        let mut t = Self {
            distrib,
            eta,
            albedo: Vec::new(),
            r_int: 0.0,
        };
        if !distrib.effectively_smooth() {
            // E(μ) = E_{ωm ~ D_ωo}[F(ωo·ωm) G(ωo,ωi)/G1(ωo)], midpoint rule on 48².
            const K: usize = 48;
            t.albedo = (0..=TABLE)
                .map(|j| {
                    let mu = ((j as f64 / TABLE as f64).powi(2)).max(1e-5);
                    let wo = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                    let g1 = distrib.g1(wo);
                    let mut sum = 0.0;
                    for a in 0..K {
                        for b in 0..K {
                            let u = DVec2::new(
                                (a as f64 + 0.5) / K as f64,
                                (b as f64 + 0.5) / K as f64,
                            );
                            let wm = distrib.sample_wm(wo, u);
                            let wi = reflect(wo, wm);
                            if wi.z > 0.0 {
                                sum += fr_dielectric(wo.dot(wm), eta) * distrib.g(wo, wi) / g1;
                            }
                        }
                    }
                    (sum / (K * K) as f64).min(1.0)
                })
                .collect();
        }
        // R_int = 1 − 2∫₀¹ t(μ) μ dμ / η² (midpoint rule).
        const M: usize = 4096;
        let s: f64 = (0..M)
            .map(|i| {
                let mu = (i as f64 + 0.5) / M as f64;
                t.transmittance(mu) * mu
            })
            .sum::<f64>()
            / M as f64;
        t.r_int = 1.0 - 2.0 * s / (eta * eta);
        t
    }
    /// E_coat(μ): the fraction of light from direction μ = cos θ reflected by the coat.
    pub fn albedo(&self, mu: f64) -> f64 {
        let mu = mu.abs().min(1.0);
        if self.albedo.is_empty() {
            return fr_dielectric(mu, self.eta);
        }
        let x = mu.sqrt() * TABLE as f64;
        let j = (x as usize).min(TABLE - 1);
        let f = x - j as f64;
        self.albedo[j] * (1.0 - f) + self.albedo[j + 1] * f
    }
    /// t(μ) = 1 − E_coat(μ).
    pub fn transmittance(&self, mu: f64) -> f64 {
        1.0 - self.albedo(mu)
    }
}

/// The plastic BSDF: diffuse reflectance ρ under a coat (two-sided).
#[derive(Clone, Copy, Debug)]
pub struct PlasticBxdf<'a> {
    /// Diffuse reflectance of the base, clamped to [0, 1].
    pub rho: Rgb,
    /// The coat.
    pub coat: &'a CoatTable,
}

impl<'a> PlasticBxdf<'a> {
    /// ρ clamped to [0, 1] under `coat`.
    pub fn new(rho: Rgb, coat: &'a CoatTable) -> Self {
        Self {
            rho: rho.clamp(Rgb::ZERO, Rgb::ONE),
            coat,
        }
    }
    fn base(&self, mu_o: f64, mu_i: f64) -> Rgb {
        let c = self.coat;
        let k = c.transmittance(mu_o) * c.transmittance(mu_i) * FRAC_1_PI / (c.eta * c.eta);
        k * self.rho / (Rgb::ONE - self.rho * c.r_int)
    }
    fn coat_f(&self, wo: DVec3, wi: DVec3) -> f64 {
        let d = &self.coat.distrib;
        let wm = wo + wi;
        if d.effectively_smooth() || wm.length_squared() == 0.0 {
            return 0.0;
        }
        let wm = wm.normalize();
        let fr = fr_dielectric(wo.dot(wm).abs(), self.coat.eta);
        d.d(wm) * d.g(wo, wi) * fr / (4.0 * wo.z.abs() * wi.z.abs())
    }
    fn coat_pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        let d = &self.coat.distrib;
        let wm = wo + wi;
        if d.effectively_smooth() || wm.length_squared() == 0.0 {
            return 0.0;
        }
        let mut wm = wm.normalize();
        if wm.z < 0.0 {
            wm = -wm;
        }
        d.pdf(wo, wm) / (4.0 * wo.dot(wm).abs())
    }
    /// Probability of sampling the coat: E_coat / (E_coat + t·mean(ρ)).
    fn p_coat(&self, mu_o: f64) -> f64 {
        let e = self.coat.albedo(mu_o);
        let d = (1.0 - e) * average(self.rho);
        if e + d > 0.0 {
            e / (e + d)
        } else {
            1.0
        }
    }
    /// f_coat + f_base on the side of wo (the coat term is a delta lobe when smooth).
    pub fn f(&self, wo: DVec3, wi: DVec3) -> Rgb {
        if !same_hemisphere(wo, wi) {
            return Rgb::ZERO;
        }
        self.base(wo.z.abs(), wi.z.abs()) + Rgb::splat(self.coat_f(wo, wi))
    }
    /// Chooses the coat with probability `p_coat`, else the cosine-weighted base.
    pub fn sample_f(&self, wo: DVec3, uc: f64, u: DVec2) -> Option<BsdfSample> {
        let pc = self.p_coat(wo.z.abs());
        let smooth = self.coat.distrib.effectively_smooth();
        let wi = if uc < pc {
            if smooth {
                let wi = DVec3::new(-wo.x, -wo.y, wo.z);
                let f = fr_dielectric(wo.z.abs(), self.coat.eta) / wi.z.abs();
                return Some(BsdfSample::new(wi, Rgb::splat(f), pc, true, 1.0));
            }
            let wm = self.coat.distrib.sample_wm(wo, u);
            let wi = reflect(wo, wm);
            if !same_hemisphere(wo, wi) {
                return None;
            }
            wi
        } else {
            let mut wi = cosine_hemisphere(u);
            if wo.z < 0.0 {
                wi.z = -wi.z;
            }
            wi
        };
        let pdf = self.pdf(wo, wi);
        (pdf > 0.0).then(|| BsdfSample::new(wi, self.f(wo, wi), pdf, false, 1.0))
    }
    /// p_coat · pdf_coat + (1 − p_coat) |cos θi|/π (the delta part excluded).
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if !same_hemisphere(wo, wi) {
            return 0.0;
        }
        let pc = self.p_coat(wo.z.abs());
        pc * self.coat_pdf(wo, wi) + (1.0 - pc) * wi.z.abs() * FRAC_1_PI
    }
}
