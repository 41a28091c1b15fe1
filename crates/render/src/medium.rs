//! Homogeneous participating media: the coefficients a ray's transmittance and a
//! scattering point's weight need (pbrt-v4 §11.1–11.2). What fills or surrounds an
//! object is named on the object ([`crate::scene::Object::interior`], `exterior`); the
//! integrator's walk through them is in `integrator/medium.rs`.

use crate::color::Rgb;

/// A homogeneous medium: σ_s, σ_t = σ_a + σ_s per RGB channel, and the
/// Henyey–Greenstein asymmetry g of its phase function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Medium {
    /// Scattering coefficient σ_s.
    pub sigma_s: Rgb,
    /// Extinction coefficient σ_t = σ_a + σ_s.
    pub sigma_t: Rgb,
    /// Phase-function asymmetry.
    pub g: f64,
}

impl Medium {
    /// The medium of absorption `sigma_a` and scattering `sigma_s`.
    pub fn new(sigma_a: Rgb, sigma_s: Rgb, g: f64) -> Self {
        Self {
            sigma_s,
            sigma_t: sigma_a + sigma_s,
            g,
        }
    }
    /// exp(−σ_t·d) per channel, for d ≥ 0 (d = ∞ allowed): 1 where σ_t = 0.
    #[inline]
    pub fn transmittance(&self, d: f64) -> Rgb {
        optical_transmittance(self.sigma_t, d)
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
    }
}
