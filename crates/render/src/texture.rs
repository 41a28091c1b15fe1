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
                let t = pattern.value(tc.p * *scale, *octaves);
                *a * (1.0 - t) + *b * t
            }
        }
    }
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
