//! Rays and axis-aligned boxes.

use glam::DVec3;

/// A ray `o + t·d` (d need not be unit length; t is in units of d).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub o: DVec3,
    /// Direction.
    pub d: DVec3,
}

impl Ray {
    /// A ray from `o` along `d`.
    pub fn new(o: DVec3, d: DVec3) -> Self {
        Self { o, d }
    }
    /// The point at parameter t.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.o + self.d * t
    }
}

/// An axis-aligned box; `Aabb::EMPTY` has lo > hi.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Aabb {
    /// Lower corner.
    pub lo: DVec3,
    /// Upper corner.
    pub hi: DVec3,
}

impl Aabb {
    /// The empty box (identity of `union`).
    pub const EMPTY: Self = Self {
        lo: DVec3::splat(f64::INFINITY),
        hi: DVec3::splat(f64::NEG_INFINITY),
    };
    /// All of space.
    pub const EVERYTHING: Self = Self {
        lo: DVec3::splat(f64::NEG_INFINITY),
        hi: DVec3::splat(f64::INFINITY),
    };
    /// The box with corners `lo` and `hi`.
    pub fn new(lo: DVec3, hi: DVec3) -> Self {
        Self { lo, hi }
    }
    /// Whether the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.lo.x > self.hi.x || self.lo.y > self.hi.y || self.lo.z > self.hi.z
    }
    /// Whether every side is finite.
    pub fn is_finite(&self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }
    /// The smallest box holding both.
    pub fn union(&self, b: &Aabb) -> Aabb {
        Aabb::new(self.lo.min(b.lo), self.hi.max(b.hi))
    }
    /// The common part (possibly empty).
    pub fn intersection(&self, b: &Aabb) -> Aabb {
        Aabb::new(self.lo.max(b.lo), self.hi.min(b.hi))
    }
    /// Grows the box to hold `p`.
    pub fn include(&mut self, p: DVec3) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }
    /// The centre.
    pub fn center(&self) -> DVec3 {
        (self.lo + self.hi) * 0.5
    }
    /// hi − lo.
    pub fn extent(&self) -> DVec3 {
        self.hi - self.lo
    }
    /// Whether `p` is inside or on the box.
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.lo).all() && p.cmple(self.hi).all()
    }
    /// The box rounded outward to f32, `(lo, hi)`: the smallest f32 box holding it, so
    /// that culling by it stays conservative (GPU.md §5.1). −∞ and +∞ stay; NaN widens
    /// to infinity.
    pub fn outward_f32(&self) -> ([f32; 3], [f32; 3]) {
        let down = |v: f64| {
            let f = v as f32;
            if f.is_nan() {
                f32::NEG_INFINITY
            } else if f64::from(f) > v {
                f.next_down()
            } else {
                f
            }
        };
        let up = |v: f64| {
            let f = v as f32;
            if f.is_nan() {
                f32::INFINITY
            } else if f64::from(f) < v {
                f.next_up()
            } else {
                f
            }
        };
        (self.lo.to_array().map(down), self.hi.to_array().map(up))
    }
    /// The parameter range where the ray is inside the box, clipped to `[t0, t1]`
    /// (slab method, Kay & Kajiya 1986), or None.
    #[inline]
    pub fn clip(&self, ray: &Ray, t0: f64, t1: f64) -> Option<(f64, f64)> {
        let inv = ray.d.recip();
        let a = (self.lo - ray.o) * inv;
        let b = (self.hi - ray.o) * inv;
        // NaN (0·∞ when the origin lies on a slab of a ray parallel to it) must not
        // shrink the range: f64::max/min ignore a NaN operand.
        let near = a.min(b);
        let far = a.max(b);
        let lo = t0.max(near.x).max(near.y).max(near.z);
        let hi = t1.min(far.x).min(far.y).min(far.z);
        (lo <= hi).then_some((lo, hi))
    }
}

/// The slab test in f32, the GPU's (GPU.md §6.1): the range of [t0, t1] where the ray o +
/// t·d (with `inv` = 1/d per axis) is inside the box (lo, hi), or None. Per axis the
/// range narrows to [min(a, b), max(a, b)] with f32's `min`/`max`, which ignore a NaN
/// operand (0·∞, an origin on the slab of a parallel ray), as [`Aabb::clip`] does in f64.
/// The WGSL kernel repeats it operation for operation.
#[inline]
pub fn slab_f32(
    lo: [f32; 3],
    hi: [f32; 3],
    o: [f32; 3],
    inv: [f32; 3],
    t0: f32,
    t1: f32,
) -> Option<(f32, f32)> {
    let (mut near, mut far) = (t0, t1);
    for k in 0..3 {
        let a = (lo[k] - o[k]) * inv[k];
        let b = (hi[k] - o[k]) * inv[k];
        near = near.max(a.min(b));
        far = far.min(a.max(b));
    }
    (near <= far).then_some((near, far))
}
