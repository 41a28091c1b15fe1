//! Colour textures: constants and procedural checkers, usable for any colour parameter.

use crate::color::Rgb;
use glam::{DVec2, DVec3};

/// Where a texture is evaluated: the hit point and surface coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexCoord {
    /// The hit point (world space).
    pub p: DVec3,
    /// Surface parameters (0 where a surface has none, as for most FRep solids).
    pub uv: DVec2,
    /// The outward unit normal (0 where unknown): a solid checker is read a hair inside
    /// the surface, so that a surface lying on a cell boundary (a floor at z = 0) takes
    /// the cell behind it instead of flipping between two with the rounding of each hit.
    pub n: DVec3,
    /// The hit point in the object's own space (its transform undone; `p` where it has
    /// none), where pattern and image textures are read, so that they move with it.
    pub local: Option<(DVec3, DVec3)>,
}

impl TexCoord {
    /// The point and unit normal in the object's own space (module docs of `local`).
    pub fn local(&self) -> (DVec3, DVec3) {
        self.local.unwrap_or((self.p, self.n))
    }
}

/// The domain of a checker.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureSpace {
    /// Solid (3-D) checker over the hit point: cubes of side 1/scale.
    Point,
    /// 2-D checker over (u, v): squares of side 1/scale.
    Uv,
}

/// A colour that may vary over a surface.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// The same colour everywhere.
    Constant(Rgb),
    /// Alternating colours `a` and `b`, `scale` checks per unit length.
    Checker {
        /// Colour where the sum of the cell indices is even.
        a: Rgb,
        /// Colour where it is odd.
        b: Rgb,
        /// Checks per unit length.
        scale: f64,
        /// Point or uv domain.
        space: TextureSpace,
    },
    /// An image projected along the three axes and blended by the normal (triplanar
    /// mapping): the projection along axis i (onto the other two coordinates, `scale`
    /// repeats per unit, bilinear, repeating) weighs |n_i|^k / Σ_j |n_j|^k.
    Image {
        /// The image (linear RGB).
        image: std::sync::Arc<::scene::ImageTexture>,
        /// Repeats per unit length.
        scale: f64,
        /// The blend's sharpness k.
        sharpness: f64,
    },
    /// Colours `a` and `b` blended by a solid pattern of the hit point
    /// ([`crate::noise`]): `a` where it is 0, `b` where it is 1.
    Pattern {
        /// The pattern.
        pattern: crate::noise::Pattern,
        /// Colour at 0.
        a: Rgb,
        /// Colour at 1.
        b: Rgb,
        /// Pattern cells per unit length.
        scale: f64,
        /// Octaves of the fractal patterns.
        octaves: u32,
    },
}

impl From<Rgb> for Texture {
    fn from(c: Rgb) -> Self {
        Texture::Constant(c)
    }
}

impl Texture {
    /// The colour at `tc`.
    pub fn eval(&self, tc: &TexCoord) -> Rgb {
        match self {
            Texture::Constant(c) => *c,
            Texture::Checker { a, b, scale, space } => {
                let cells = match space {
                    TextureSpace::Point => {
                        // 1/1000 of a cell inward: below any visible detail, far above
                        // the rounding of a hit point.
                        let p = tc.p * *scale - tc.n * 1e-3;
                        p.floor().to_array().iter().sum::<f64>()
                    }
                    TextureSpace::Uv => (tc.uv * *scale).floor().to_array().iter().sum::<f64>(),
                };
                if cells.rem_euclid(2.0) < 0.5 {
                    *a
                } else {
                    *b
                }
            }
            Texture::Pattern {
                pattern,
                a,
                b,
                scale,
                octaves,
            } => {
                let t = pattern.value(tc.local().0 * *scale, *octaves);
                *a * (1.0 - t) + *b * t
            }
            Texture::Image {
                image,
                scale,
                sharpness,
            } => {
                let (p, n) = tc.local();
                triplanar(image, p * *scale, n, *sharpness)
            }
        }
    }
}

/// The image at (u, v) (one repeat per unit, v down the image's rows), bilinear between
/// pixel centres, repeating.
pub fn bilinear(img: &::scene::ImageTexture, u: f64, v: f64) -> Rgb {
    let (w, h) = (img.width as f64, img.height as f64);
    let (x, y) = (u.rem_euclid(1.0) * w - 0.5, v.rem_euclid(1.0) * h - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let at = |i: f64, j: f64| {
        let (i, j) = (i.rem_euclid(w) as usize, j.rem_euclid(h) as usize);
        let p = img.pixels[j * img.width + i];
        Rgb::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]))
    };
    let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1.0, y0) * fx;
    let bottom = at(x0, y0 + 1.0) * (1.0 - fx) + at(x0 + 1.0, y0 + 1.0) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// Triplanar mapping at `p` (already scaled) with normal `n` (module docs of
/// [`Texture::Image`]); where the normal is unknown (0), the z projection.
pub fn triplanar(img: &::scene::ImageTexture, p: DVec3, n: DVec3, k: f64) -> Rgb {
    let w = DVec3::new(n.x.abs().powf(k), n.y.abs().powf(k), n.z.abs().powf(k));
    let sum = w.x + w.y + w.z;
    if sum.is_nan() || sum <= 0.0 {
        return bilinear(img, p.x, -p.y);
    }
    let w = w / sum;
    // Each projection reads the image with its v axis down the rows: the up axis of
    // the plane it is seen in runs up the image.
    let mut c = Rgb::ZERO;
    if w.x > 0.0 {
        c += bilinear(img, p.y, -p.z) * w.x;
    }
    if w.y > 0.0 {
        c += bilinear(img, p.x, -p.z) * w.y;
    }
    if w.z > 0.0 {
        c += bilinear(img, p.x, -p.y) * w.z;
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checker_alternates() {
        let (a, b) = (Rgb::ONE, Rgb::ZERO);
        let t = Texture::Checker {
            a,
            b,
            scale: 2.0,
            space: TextureSpace::Point,
        };
        let at = |x, y, z| {
            t.eval(&TexCoord {
                p: DVec3::new(x, y, z),
                ..TexCoord::default()
            })
        };
        assert_eq!(at(0.1, 0.1, 0.1), a);
        assert_eq!(at(0.6, 0.1, 0.1), b);
        assert_eq!(at(0.6, 0.6, 0.1), a);
        assert_eq!(at(-0.1, 0.1, 0.1), b);
        assert_eq!(at(-0.6, -0.1, 0.1), b);
        assert_eq!(at(-0.6, 0.1, 0.1), a);
        let u = Texture::Checker {
            a,
            b,
            scale: 4.0,
            space: TextureSpace::Uv,
        };
        let tc = |x, y| TexCoord {
            p: DVec3::splat(0.1),
            uv: DVec2::new(x, y),
            n: DVec3::Z,
            local: None,
        };
        assert_eq!(u.eval(&tc(0.1, 0.1)), a);
        assert_eq!(u.eval(&tc(0.3, 0.1)), b);
        assert_eq!(Texture::from(Rgb::X).eval(&tc(5.0, 5.0)), Rgb::X);
    }

    /// A floor on a cell boundary (z = 0, normal +z): hit points a rounding error above
    /// or below it take the same cell, the one behind the surface; without the normal
    /// they would alternate (the salt-and-pepper floors of the shipped scenes).
    #[test]
    fn a_surface_on_a_cell_boundary_takes_one_cell() {
        let t = Texture::Checker {
            a: Rgb::ONE,
            b: Rgb::ZERO,
            scale: 2.0,
            space: TextureSpace::Point,
        };
        let at = |z: f64, n: DVec3| {
            t.eval(&TexCoord {
                p: DVec3::new(0.1, 0.1, z),
                n,
                ..TexCoord::default()
            })
        };
        for z in [-1e-12, -1e-16, 0.0, 1e-16, 1e-12] {
            assert_eq!(at(z, DVec3::Z), Rgb::ZERO, "z = {z}");
            assert_eq!(at(z, -DVec3::Z), Rgb::ONE, "z = {z}, facing down");
        }
        // Without a normal the rounding picks the cell: the flip this avoids.
        assert_ne!(at(-1e-16, DVec3::ZERO), at(1e-16, DVec3::ZERO));
    }
}

#[cfg(test)]
mod pattern_tests {
    use super::*;
    use crate::noise::Pattern;

    /// A pattern texture blends its colours by the pattern's value at the scaled point.
    #[test]
    fn patterns_blend_their_colours() {
        let t = Texture::Pattern {
            pattern: Pattern::Marble,
            a: Rgb::ZERO,
            b: Rgb::new(1.0, 0.5, 0.25),
            scale: 3.0,
            octaves: 4,
        };
        let p = DVec3::new(0.3, -1.2, 0.7);
        let v = Pattern::Marble.value(p * 3.0, 4);
        let c = t.eval(&TexCoord {
            p,
            ..TexCoord::default()
        });
        assert!((c - Rgb::new(1.0, 0.5, 0.25) * v).abs().max_element() < 1e-15);
    }
}

#[cfg(test)]
mod image_tests {
    use super::*;
    use ::scene::ImageTexture;

    /// A 4 × 2 image of distinct colours.
    fn image() -> ImageTexture {
        ImageTexture {
            width: 4,
            height: 2,
            pixels: (0..8).map(|i| [i as f32, (i * i) as f32, 1.0]).collect(),
        }
    }

    /// Bilinear lookups return pixel values at pixel centres and repeat with period 1.
    #[test]
    fn bilinear_hits_pixel_centres_and_repeats() {
        let img = image();
        for j in 0..2 {
            for i in 0..4 {
                let (u, v) = ((i as f64 + 0.5) / 4.0, (j as f64 + 0.5) / 2.0);
                let want = img.pixels[j * 4 + i];
                for shift in [0.0, 1.0, -3.0] {
                    let c = bilinear(&img, u + shift, v - shift);
                    assert!(
                        (c - Rgb::new(want[0] as f64, want[1] as f64, 1.0))
                            .abs()
                            .max_element()
                            < 1e-9
                    );
                }
            }
        }
    }

    /// On a plane facing an axis, triplanar mapping is that axis's planar projection;
    /// on any normal its weights sum to 1 (a uniform image stays uniform).
    #[test]
    fn triplanar_is_planar_on_planes_and_a_partition_of_unity() {
        let img = image();
        let p = DVec3::new(0.3, 1.7, -0.6);
        assert_eq!(triplanar(&img, p, DVec3::Z, 4.0), bilinear(&img, p.x, -p.y));
        assert_eq!(
            triplanar(&img, p, -DVec3::X, 4.0),
            bilinear(&img, p.y, -p.z)
        );
        let flat = ImageTexture {
            width: 3,
            height: 3,
            pixels: vec![[0.25, 0.5, 0.75]; 9],
        };
        for n in [
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(-0.3, 0.1, 0.9),
            DVec3::ONE,
        ] {
            let c = triplanar(&flat, p, n.normalize(), 4.0);
            assert!(
                (c - Rgb::new(0.25, 0.5, 0.75)).abs().max_element() < 1e-6,
                "{c}"
            );
        }
    }
}
