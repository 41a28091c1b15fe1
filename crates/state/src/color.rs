//! RGB colour: linear Rec. 709 primaries, stored as `DVec3` (x = R, y = G, z = B).

use glam::DVec3;

/// A linear RGB triple (Rec. 709 primaries).
pub type Rgb = DVec3;

/// Relative luminance Y of linear Rec. 709 RGB (ITU-R BT.709 weights).
#[inline]
pub fn luminance(c: Rgb) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// The mean of the three channels (used where a strictly positive scalar is needed
/// whenever any channel is positive, e.g. sampling weights).
#[inline]
pub fn average(c: Rgb) -> f64 {
    (c.x + c.y + c.z) / 3.0
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value clamped to [0, 1].
#[inline]
pub fn srgb_encode(v: f64) -> f64 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// A linear value in [0, 1] as an 8-bit sRGB code (rounded to nearest).
#[inline]
pub fn srgb_u8(v: f64) -> u8 {
    (srgb_encode(v) * 255.0 + 0.5).floor() as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_known_codes() {
        assert_eq!(srgb_u8(0.0), 0);
        assert_eq!(srgb_u8(1.0), 255);
        assert_eq!(srgb_u8(2.0), 255);
        assert_eq!(srgb_u8(-1.0), 0);
        assert_eq!(srgb_u8(f64::NAN), 0);
        // 1.055·0.5^(1/2.4) − 0.055 = 0.735357 → 187.52 → 188.
        assert_eq!(srgb_u8(0.5), 188);
        // Linear segment: 12.92·0.002 = 0.02584 → 6.59 → 7.
        assert_eq!(srgb_u8(0.002), 7);
        // Continuity at the knee.
        let a = 12.92 * 0.003_130_8;
        let b = 1.055 * 0.003_130_8f64.powf(1.0 / 2.4) - 0.055;
        assert!((a - b).abs() < 1e-6);
    }

    #[test]
    fn luminance_of_white_is_one() {
        assert!((luminance(Rgb::ONE) - 1.0).abs() < 1e-12);
    }
}
