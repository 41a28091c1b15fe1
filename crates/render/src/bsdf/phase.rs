//! The Henyey–Greenstein phase function as a [`super::Bxdf`], so that a scattering
//! point inside a medium is shaded by the same techniques and MIS code as a surface
//! (pbrt-v4 §11.3.1; its sampling, `SampleHenyeyGreenstein`, inverts the CDF exactly).
//!
//! Conventions as for BSDFs: `wo` points back toward the viewer, `wi` toward the
//! light, so forward scattering (g > 0) favours `wi ≈ −wo`: p = (1 − g²) /
//! (4π (1 + g² + 2g cos θ)^{3/2}) with cos θ = wo·wi (pbrt-v4's form). A phase
//! function has no cosine factor; the integrator leaves it out at medium vertices.

use super::BsdfSample;
use crate::color::Rgb;
use crate::warp::spherical_direction;
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// Henyey–Greenstein scattering with asymmetry g ∈ (−1, 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HenyeyGreenstein {
    /// Mean cosine of the scattering angle (0: isotropic).
    pub g: f64,
}

impl HenyeyGreenstein {
    /// The density for `cos θ = wo·wi`.
    #[inline]
    pub fn p(&self, cos_theta: f64) -> f64 {
        let g = self.g;
        let denom = 1.0 + g * g + 2.0 * g * cos_theta;
        (1.0 - g * g) / (4.0 * PI * denom * denom.max(0.0).sqrt())
    }
    /// p(wo, wi), equal for every channel.
    pub fn f(&self, wo: DVec3, wi: DVec3) -> Rgb {
        Rgb::splat(self.p(wo.dot(wi)))
    }
    /// The density of [`Self::sample_f`]: p itself.
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        self.p(wo.dot(wi))
    }
    /// Draws wi with density p (weight exactly 1), in the frame where `wo` is +z or any
    /// other: the direction is built about wo.
    pub fn sample_f(&self, wo: DVec3, u: DVec2) -> Option<BsdfSample> {
        let g = self.g;
        let cos_theta = if g.abs() < 1e-3 {
            1.0 - 2.0 * u.x
        } else {
            let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x);
            -(1.0 + g * g - s * s) / (2.0 * g)
        }
        .clamp(-1.0, 1.0);
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let frame = crate::frame::Frame::from_z(wo);
        let wi = frame.from_local(spherical_direction(sin_theta, cos_theta, u.y));
        let pdf = self.p(cos_theta);
        (pdf > 0.0 && pdf.is_finite()).then(|| BsdfSample {
            wi,
            f: Rgb::splat(pdf),
            pdf,
            weight: Rgb::ONE,
            specular: false,
            transmission: false,
            eta: 1.0,
        })
    }
}
