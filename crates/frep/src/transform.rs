//! Affine transforms of solids.
//!
//! A solid F moved by an affine map A is F∘A⁻¹: the inverse is applied to the
//! coordinates, so transforming never changes F's sign convention or its values.

use crate::tree::Tree;
use glam::{DMat3, DVec3};

/// x ↦ M·x + t.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    /// Linear part.
    pub m: DMat3,
    /// Translation.
    pub t: DVec3,
}

impl Default for Affine {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Affine {
    /// The identity.
    pub const IDENTITY: Self = Self {
        m: DMat3::IDENTITY,
        t: DVec3::ZERO,
    };
    /// A translation by t.
    pub fn translate(t: DVec3) -> Self {
        Self {
            m: DMat3::IDENTITY,
            t,
        }
    }
    /// A scale by s along each axis.
    pub fn scale(s: DVec3) -> Self {
        Self {
            m: DMat3::from_diagonal(s),
            t: DVec3::ZERO,
        }
    }
    /// A rotation by `angle` radians about `axis` (right-handed).
    pub fn rotate(axis: DVec3, angle: f64) -> Self {
        Self {
            m: DMat3::from_axis_angle(axis.normalize(), angle),
            t: DVec3::ZERO,
        }
    }
    /// First `self`, then `next`.
    pub fn then(&self, next: &Affine) -> Affine {
        Affine {
            m: next.m * self.m,
            t: next.m * self.t + next.t,
        }
    }
    /// The inverse map, or None when M is singular.
    pub fn inverse(&self) -> Option<Affine> {
        let det = self.m.determinant();
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let mi = self.m.inverse();
        Some(Affine {
            m: mi,
            t: -(mi * self.t),
        })
    }
    /// Maps a point.
    pub fn point(&self, p: DVec3) -> DVec3 {
        self.m * p + self.t
    }
    /// F∘A⁻¹: the solid `f` moved by this map. None when the map is singular.
    pub fn apply(&self, f: &Tree) -> Option<Tree> {
        let inv = self.inverse()?;
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let coord = |row: usize| {
            let r = inv.m.row(row);
            let mut e = Tree::constant(inv.t[row]);
            for (k, v) in [&x, &y, &z].iter().enumerate() {
                if r[k] != 0.0 {
                    e = e + r[k] * *v;
                }
            }
            e
        };
        Some(f.remap(&coord(0), &coord(1), &coord(2)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Expr;

    #[test]
    fn moved_ball_is_centred_at_the_image_of_the_origin() {
        let ball = 1.0 - (Tree::x().square() + Tree::y().square() + Tree::z().square());
        let a = Affine::scale(DVec3::new(2.0, 1.0, 1.0))
            .then(&Affine::rotate(DVec3::Z, std::f64::consts::FRAC_PI_2))
            .then(&Affine::translate(DVec3::new(1.0, 2.0, 3.0)));
        let e = Expr::new(&a.apply(&ball).unwrap());
        let c = a.point(DVec3::ZERO);
        assert!((e.eval(c.to_array()) - 1.0).abs() < 1e-12);
        // The x semi-axis (length 2) now points along +y.
        let tip = a.point(DVec3::X);
        assert!((tip - DVec3::new(1.0, 4.0, 3.0)).length() < 1e-12);
        assert!(e.eval(tip.to_array()).abs() < 1e-12);
        assert!(Affine::scale(DVec3::new(0.0, 1.0, 1.0))
            .apply(&ball)
            .is_none());
    }
}
