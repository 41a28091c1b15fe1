//! PNG views of images whose colour channels hold values, not radiance: the `depth`
//! integrator's distances and the `normals` integrator's unit normals. The EXR keeps
//! the values; the PNG shows them:
//!
//! - depth as grey, nearest surface white and farthest 20 % grey (linearly between;
//!   Fidget's heightmaps are shown near-bright too), rays that escape black;
//! - normals as colours, `(n + 1)/2` per axis (the normal-map convention, stored
//!   linearly, without the sRGB curve), rays that escape black.
//!
//! Pixels average their samples, and an escaped sample counts 0, so a silhouette pixel
//! holds a shortened value: its depth reads nearer and its normal greyer than the
//! surface's.

use crate::image::Image;
use scene::IntegratorKind;

/// What an image's colour channels hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Values {
    /// Distance along the camera ray, in every channel (0: escaped).
    Depth,
    /// The world-space unit normal's x, y, z (0: escaped).
    Normals,
}

impl Values {
    /// What the integrator's image holds, or None for radiance and albedo (colours).
    pub fn of(kind: IntegratorKind) -> Option<Values> {
        match kind {
            IntegratorKind::Depth => Some(Values::Depth),
            IntegratorKind::Normals => Some(Values::Normals),
            _ => None,
        }
    }

    /// 8-bit RGB, row by row, as the module docs say.
    pub fn rgb8(self, img: &Image) -> Vec<u8> {
        let c = img.channels();
        let byte = |v: f64| (v.clamp(0.0, 1.0) * 255.0 + 0.5).floor() as u8;
        match self {
            Values::Depth => {
                let hit = |d: f64| d.is_finite() && d > 0.0;
                let (near, far) = img
                    .data()
                    .chunks_exact(c)
                    .map(|p| p[0])
                    .filter(|&d| hit(d))
                    .fold((f64::INFINITY, 0.0f64), |(a, b), d| (a.min(d), b.max(d)));
                let span = far - near;
                img.data()
                    .chunks_exact(c)
                    .flat_map(|p| {
                        let d = p[0];
                        let g = if !hit(d) {
                            0.0
                        } else if span > 0.0 {
                            1.0 - 0.8 * (d - near) / span
                        } else {
                            1.0
                        };
                        [byte(g); 3]
                    })
                    .collect()
            }
            Values::Normals => img
                .data()
                .chunks_exact(c)
                .flat_map(|p| {
                    let escaped = p[..3].iter().all(|&v| v == 0.0);
                    [0, 1, 2].map(|k| {
                        if escaped || !p[k].is_finite() {
                            0
                        } else {
                            byte(0.5 * (p[k] + 1.0))
                        }
                    })
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Rgb;

    #[test]
    fn depth_is_grey_near_white_far_dim_escaped_black() {
        let mut img = Image::new(4, 1, &[]);
        for (x, d) in [(0, 2.0), (1, 4.0), (2, 0.0), (3, 3.0)] {
            img.set_rgb(x, 0, Rgb::splat(d));
        }
        let b = Values::Depth.rgb8(&img);
        assert_eq!(b.len(), 12);
        assert_eq!(&b[0..3], &[255; 3]);
        assert_eq!(&b[3..6], &[51; 3]); // 0.2 · 255
        assert_eq!(&b[6..9], &[0; 3]);
        assert_eq!(&b[9..12], &[153; 3]); // 0.6 · 255
    }

    #[test]
    fn normals_are_half_plus_half_n_escaped_black() {
        let mut img = Image::new(2, 1, &[]);
        img.set_rgb(0, 0, Rgb::new(1.0, 0.0, -1.0));
        let b = Values::Normals.rgb8(&img);
        assert_eq!(b, vec![255, 128, 0, 0, 0, 0]);
    }

    #[test]
    fn colour_integrators_hold_no_values() {
        assert_eq!(Values::of(IntegratorKind::Direct), None);
        assert_eq!(Values::of(IntegratorKind::Albedo), None);
        assert_eq!(Values::of(IntegratorKind::Depth), Some(Values::Depth));
    }
}
