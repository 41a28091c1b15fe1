//! Lights without area: point and spot lights (pbrt-v4 §12.1). A direction toward
//! them has probability zero under any other technique, so they are sampled on their
//! own, outside MIS.

use super::LightSample;
use crate::color::Rgb;
use glam::DVec3;
use std::f64::consts::PI;

/// A point or spot light, given by radiant intensity I (W/sr).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DeltaLight {
    /// Isotropic point light.
    Point {
        /// Position.
        position: DVec3,
        /// Radiant intensity.
        intensity: Rgb,
    },
    /// Spot light: full intensity within `cos_falloff_start` of the axis, falling off
    /// smoothly (smoothstep in cos θ) to zero at `cos_falloff_end`.
    Spot {
        /// Position.
        position: DVec3,
        /// Unit axis.
        direction: DVec3,
        /// Radiant intensity on the axis.
        intensity: Rgb,
        /// cos of the angle where the falloff starts.
        cos_falloff_start: f64,
        /// cos of the cone's total half-angle.
        cos_falloff_end: f64,
    },
}

fn smoothstep(x: f64, a: f64, b: f64) -> f64 {
    if a == b {
        return if x < a { 0.0 } else { 1.0 };
    }
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl DeltaLight {
    /// A spot light at `position` aimed at `target`, with total half-angle
    /// `cone_degrees` and full intensity within `falloff_start_degrees`.
    pub fn spot(
        position: DVec3,
        target: DVec3,
        intensity: Rgb,
        cone_degrees: f64,
        falloff_start_degrees: f64,
    ) -> Self {
        DeltaLight::Spot {
            position,
            direction: (target - position).normalize(),
            intensity,
            cos_falloff_start: falloff_start_degrees.min(cone_degrees).to_radians().cos(),
            cos_falloff_end: cone_degrees.to_radians().cos(),
        }
    }
    /// The light's position.
    pub fn position(&self) -> DVec3 {
        match *self {
            DeltaLight::Point { position, .. } | DeltaLight::Spot { position, .. } => position,
        }
    }
    /// Intensity emitted in unit direction `w` (from the light).
    pub fn intensity(&self, w: DVec3) -> Rgb {
        match *self {
            DeltaLight::Point { intensity, .. } => intensity,
            DeltaLight::Spot {
                direction,
                intensity,
                cos_falloff_start,
                cos_falloff_end,
                ..
            } => intensity * smoothstep(direction.dot(w), cos_falloff_end, cos_falloff_start),
        }
    }
    /// Illumination of point `p`: `radiance` holds I/d² (so that the contribution is
    /// f·|cos θ|·radiance), pdf is 1 and `delta` is set. None at the light's position.
    pub fn sample_li(&self, p: DVec3) -> Option<LightSample> {
        let v = self.position() - p;
        let d2 = v.length_squared();
        if d2 == 0.0 {
            return None;
        }
        let dist = d2.sqrt();
        let wi = v / dist;
        Some(LightSample {
            wi,
            dist,
            radiance: self.intensity(-wi) / d2,
            pdf: 1.0,
            delta: true,
            light: None,
        })
    }
    /// Emitted power: 4π I for a point light; for a spot light
    /// 2π I ((1 − cos_start) + (cos_start − cos_end)/2) (pbrt-v4 §12.1.2).
    pub fn power(&self) -> Rgb {
        match *self {
            DeltaLight::Point { intensity, .. } => 4.0 * PI * intensity,
            DeltaLight::Spot {
                intensity,
                cos_falloff_start,
                cos_falloff_end,
                ..
            } => {
                intensity
                    * (2.0 * PI)
                    * ((1.0 - cos_falloff_start) + (cos_falloff_start - cos_falloff_end) / 2.0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_square_and_spot_power() {
        let l = DeltaLight::Point {
            position: DVec3::new(0.0, 0.0, 2.0),
            intensity: Rgb::splat(8.0),
        };
        let s = l.sample_li(DVec3::ZERO).unwrap();
        assert_eq!(s.wi, DVec3::Z);
        assert_eq!(s.radiance, Rgb::splat(2.0));
        assert!(s.delta && s.pdf == 1.0 && s.dist == 2.0);
        assert!((l.power().x - 32.0 * PI).abs() < 1e-12);

        let spot = DeltaLight::spot(DVec3::ZERO, -DVec3::Z, Rgb::ONE, 40.0, 20.0);
        // Power by quadrature of ∫ I(ω) dω over the sphere.
        let n = 200_000;
        let q: f64 = (0..n)
            .map(|i| {
                let z = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                spot.intensity(DVec3::new((1.0 - z * z).sqrt(), 0.0, z)).x
            })
            .sum::<f64>()
            * 4.0
            * PI
            / n as f64;
        assert!(
            (q - spot.power().x).abs() < 1e-6,
            "{q} vs {}",
            spot.power().x
        );
        // Full intensity on the axis, none outside the cone.
        assert_eq!(spot.intensity(-DVec3::Z), Rgb::ONE);
        assert_eq!(spot.intensity(DVec3::X), Rgb::ZERO);
    }
}
