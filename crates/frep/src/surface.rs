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
/// vanishes or is not finite).
pub fn outward(g: DVec3) -> DVec3 {
    let l = g.length();
    if l > 0.0 && l.is_finite() {
        -g / l
    } else {
        DVec3::Z
    }
}
