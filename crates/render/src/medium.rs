//! Participating media of constant extinction: the coefficients a ray's transmittance
//! and a scattering point's weight need (pbrt-v4 §11.1–11.2). What fills or surrounds
//! an object is named on the object ([`crate::scene::Object::interior`], `exterior`);
//! the integrator's walk through them is in `integrator/medium.rs`.
//!
//! σ_t is the same everywhere in a medium, so transmittance stays exp(−σ_t·d) and free
//! flights are drawn exactly; the albedo may vary from point to point (a texture read
//! in world space), which changes only how much of the extinction at a point scatters:
//! σ_s(p) = albedo(p)·σ_t.

use crate::color::Rgb;
use crate::texture::{TexCoord, Texture};
use glam::{DVec2, DVec3};

/// A medium: σ_t per RGB channel, the single-scattering albedo (a texture of the
/// point) and the Henyey–Greenstein asymmetry g of its phase function.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// Extinction coefficient σ_t = σ_a + σ_s.
    pub sigma_t: Rgb,
    /// σ_s/σ_t, in [0, 1].
    pub albedo: Texture,
    /// Phase-function asymmetry.
    pub g: f64,
}

impl Medium {
    /// The homogeneous medium of absorption `sigma_a` and scattering `sigma_s`.
    pub fn new(sigma_a: Rgb, sigma_s: Rgb, g: f64) -> Self {
        let sigma_t = sigma_a + sigma_s;
        let albedo = |s: f64, t: f64| if t > 0.0 { s / t } else { 0.0 };
        Self {
            sigma_t,
            albedo: Texture::Constant(Rgb::new(
                albedo(sigma_s.x, sigma_t.x),
                albedo(sigma_s.y, sigma_t.y),
                albedo(sigma_s.z, sigma_t.z),
            )),
            g,
        }
    }
    /// exp(−σ_t·d) per channel, for d ≥ 0 (d = ∞ allowed): 1 where σ_t = 0.
    #[inline]
    pub fn transmittance(&self, d: f64) -> Rgb {
        optical_transmittance(self.sigma_t, d)
    }
    /// σ_s at world point `p`: the albedo there times σ_t.
    #[inline]
    pub fn sigma_s(&self, p: DVec3) -> Rgb {
        let tc = TexCoord {
            p,
            n: DVec3::ZERO,
            uv: DVec2::ZERO,
            local: None,
        };
        self.albedo.eval(&tc) * self.sigma_t
    }
}

/// exp(−σ·d) per channel with 0·∞ read as 0 (an empty channel transmits fully).
#[inline]
pub fn optical_transmittance(sigma: Rgb, d: f64) -> Rgb {
    let one = |s: f64| if s == 0.0 { 1.0 } else { (-s * d).exp() };
    Rgb::new(one(sigma.x), one(sigma.y), one(sigma.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transmittance_is_beers_law_per_channel() {
        let m = Medium::new(Rgb::new(1.0, 0.0, 0.5), Rgb::new(0.0, 0.0, 0.5), 0.0);
        let t = m.transmittance(2.0);
        assert!((t.x - (-2.0f64).exp()).abs() < 1e-15);
        assert_eq!(t.y, 1.0);
        assert!((t.z - (-2.0f64).exp()).abs() < 1e-15);
        let inf = m.transmittance(f64::INFINITY);
        assert_eq!(inf, Rgb::new(0.0, 1.0, 0.0));
        assert_eq!(m.sigma_s(DVec3::ZERO), Rgb::new(0.0, 0.0, 0.5));
    }
}
