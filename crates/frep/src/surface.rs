//! The one intersection contract every solid honours.
//!
//! A ray meets a solid at the first t in (t_min, t_max) where F changes sign: never a
//! miss of a sign change, whatever the feature size (DESIGN.md §4). Exact
//! piecewise-polynomial root finding serves perturbed quadrics; interval arithmetic
//! over ray segments serves every other expression; CSG combines crossings of its parts.

use crate::ray::{Aabb, Ray};
use glam::DVec3;

/// A solid that rays can be intersected with.
pub trait Surface: Send + Sync {
    /// F at p (≥ 0 inside, 0 on the surface).
    fn value(&self, p: DVec3) -> f64;
    /// ∇F at p.
    fn gradient(&self, p: DVec3) -> DVec3;
    /// The first t in (t_min, t_max) where F changes sign along the ray, or None.
    fn first_crossing(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64>;
    /// The first crossing with the outward normal there.
    fn first_hit(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, DVec3)> {
        let t = self.first_crossing(ray, t_min, t_max)?;
        Some((t, self.normal(ray.at(t))))
    }
    /// Whether F changes sign anywhere in (t_min, t_max) (shadow rays).
    fn any_crossing(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        self.first_crossing(ray, t_min, t_max).is_some()
    }
    /// A box holding every point where F ≥ 0 (may be infinite for unbounded solids).
    fn bounds(&self) -> Aabb;
    /// The outward unit normal at p: −∇F/|∇F| since F ≥ 0 inside.
    fn normal(&self, p: DVec3) -> DVec3 {
        outward(self.gradient(p))
    }
}

/// The outward unit normal −g/|g| for a gradient g of F ≥ 0 inside (+z where g
/// vanishes or is not finite). A gradient of length exactly 1 (a box's faces, planes
/// with unit normals) is its own normal: −g, the same bits as −g/√1, without the root
/// and the division, which every hit waits on.
#[inline]
pub fn outward(g: DVec3) -> DVec3 {
    let l2 = g.length_squared();
    if l2 == 1.0 {
        return -g;
    }
    let l = l2.sqrt();
    if l > 0.0 && l.is_finite() {
        -g / l
    } else {
        DVec3::Z
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// `outward` before its fast path for unit gradients.
    fn reference(g: DVec3) -> DVec3 {
        let l = g.length();
        if l > 0.0 && l.is_finite() {
            -g / l
        } else {
            DVec3::Z
        }
    }

    /// The unit-gradient path gives the general formula's bits: on every ±1 axis vector
    /// with every sign of zero in the other components (a box's faces), on normalised
    /// random vectors (many of length² exactly 1), and on random, tiny, huge, zero,
    /// infinite and NaN gradients.
    #[test]
    fn unit_gradients_are_their_own_normal() {
        let bits = |v: DVec3| v.to_array().map(f64::to_bits);
        let mut cases = Vec::new();
        for axis in 0..3 {
            for one in [1.0, -1.0] {
                for zeros in 0..4 {
                    let zero = |bit: i32| if zeros & bit == 0 { 0.0 } else { -0.0 };
                    let mut g = [one; 3];
                    g[(axis + 1) % 3] = zero(1);
                    g[(axis + 2) % 3] = zero(2);
                    cases.push(DVec3::from_array(g));
                }
            }
        }
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let mut unit = 0;
        for _ in 0..100_000 {
            let g = DVec3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            );
            let n = g.normalize();
            unit += usize::from(n.length_squared() == 1.0);
            cases.extend([g, n, g * 1e-160, g * 1e160]);
        }
        assert!(unit > 10_000, "{unit} random unit vectors of length² 1");
        cases.extend([
            DVec3::ZERO,
            DVec3::INFINITY,
            DVec3::NAN,
            DVec3::new(0.0, 1.0, f64::NAN),
        ]);
        for g in cases {
            assert_eq!(bits(outward(g)), bits(reference(g)), "{g:?}");
        }
    }
}
