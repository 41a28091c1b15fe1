//! Lambertian reflection: f = R/π (pbrt-v4 §9.2).

use super::{same_hemisphere, BsdfSample};
use crate::color::Rgb;
use crate::warp::cosine_hemisphere;
use glam::{DVec2, DVec3};
use std::f64::consts::FRAC_1_PI;

/// Ideal diffuse reflection with reflectance R ∈ [0, 1]³ (two-sided).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseBxdf {
    /// Hemispherical reflectance.
    pub r: Rgb,
}

impl DiffuseBxdf {
    /// f = R/π on the side of wo.
    pub fn f(&self, wo: DVec3, wi: DVec3) -> Rgb {
        if same_hemisphere(wo, wi) {
            self.r * FRAC_1_PI
        } else {
            Rgb::ZERO
        }
    }
    /// Cosine-weighted sampling on the side of wo.
    pub fn sample_f(&self, wo: DVec3, u: DVec2) -> Option<BsdfSample> {
        let mut wi = cosine_hemisphere(u);
        if wo.z < 0.0 {
            wi.z = -wi.z;
        }
        let pdf = wi.z.abs() * FRAC_1_PI;
        (pdf > 0.0).then(|| BsdfSample::new(wi, self.r * FRAC_1_PI, pdf, false, 1.0))
    }
    /// |cos θi|/π on the side of wo.
    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        if same_hemisphere(wo, wi) {
            wi.z.abs() * FRAC_1_PI
        } else {
            0.0
        }
    }
}
