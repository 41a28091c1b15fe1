//! The flat scene as GPU structs (GPU.md §5): `#[repr(C)]`, plain old data, each a
//! multiple of 16 bytes (no `vec3` in shared structs), with a WGSL mirror of the same
//! fields ([`LAYOUT_WGSL`]) and a test that a kernel writing every field from its index
//! reads back into the Rust struct field for field.
//!
//! f64 → f32 (DESIGN.md §4: GPU geometry in f32): coefficients round to nearest; boxes
//! round outward, so that culling by a box stays conservative.

use bytemuck::{Pod, Zeroable};
use frep::bvh::BvhNode;
use frep::perturbed::Perturbation;
use frep::{Aabb, Quadric};

/// A quadric's coefficients `[xx, yy, zz, xy, yz, xz, x, y, z, 1]` (frep's order).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuQuadric {
    /// The coefficients.
    pub c: [f32; 10],
    /// Padding to 48 bytes.
    pub pad: [f32; 2],
}

/// A perturbation f·max(q, 0)³.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPerturbation {
    /// q's coefficients.
    pub q: [f32; 10],
    /// The form factor f.
    pub f: f32,
    /// Padding to 48 bytes.
    pub pad: f32,
}

/// A BVH node: leaf = `count` items from `offset`; interior = second child at `offset`,
/// the first child next (`count` 0), split axis in bits 30–31 of `count_axis`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBvhNode {
    /// Box minimum (rounded down).
    pub lo: [f32; 3],
    /// Leaf: first item; interior: second child.
    pub offset: u32,
    /// Box maximum (rounded up).
    pub hi: [f32; 3],
    /// Item count in bits 0–29, split axis in bits 30–31.
    pub count_axis: u32,
}

const _: () = assert!(size_of::<GpuQuadric>() == 48);
const _: () = assert!(size_of::<GpuPerturbation>() == 48);
const _: () = assert!(size_of::<GpuBvhNode>() == 32);

/// The WGSL structs mirroring these, field for field.
pub const LAYOUT_WGSL: &str = "
struct GpuQuadric { c: array<f32, 10>, pad: array<f32, 2> }
struct GpuPerturbation { q: array<f32, 10>, f: f32, pad: f32 }
struct GpuBvhNode { lo_x: f32, lo_y: f32, lo_z: f32, offset: u32, hi_x: f32, hi_y: f32, hi_z: f32, count_axis: u32 }
";

/// The largest f32 ≤ v (v itself when exact); −∞ stays −∞, NaN becomes −∞.
fn down(v: f64) -> f32 {
    let f = v as f32;
    if f64::from(f) > v {
        f.next_down()
    } else if f.is_nan() {
        f32::NEG_INFINITY
    } else {
        f
    }
}

/// The smallest f32 ≥ v; NaN becomes +∞.
fn up(v: f64) -> f32 {
    let f = v as f32;
    if f64::from(f) < v {
        f.next_up()
    } else if f.is_nan() {
        f32::INFINITY
    } else {
        f
    }
}

/// A box rounded outward to f32: (lo, hi).
pub fn outward(b: &Aabb) -> ([f32; 3], [f32; 3]) {
    (
        [down(b.lo.x), down(b.lo.y), down(b.lo.z)],
        [up(b.hi.x), up(b.hi.y), up(b.hi.z)],
    )
}

impl From<&Quadric> for GpuQuadric {
    fn from(q: &Quadric) -> Self {
        Self {
            c: q.c.map(|v| v as f32),
            pad: [0.0; 2],
        }
    }
}

impl From<&Perturbation> for GpuPerturbation {
    fn from(p: &Perturbation) -> Self {
        Self {
            q: p.q.c.map(|v| v as f32),
            f: p.f as f32,
            pad: 0.0,
        }
    }
}

impl From<&BvhNode> for GpuBvhNode {
    fn from(n: &BvhNode) -> Self {
        let (lo, hi) = outward(&n.bounds);
        Self {
            lo,
            offset: n.offset,
            hi,
            count_axis: (n.count & 0x3fff_ffff) | (n.axis << 30),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// Boxes round outward, never inward, and exact values stay.
    #[test]
    fn boxes_round_outward() {
        let b = Aabb::new(DVec3::new(0.1, -0.1, 1.0), DVec3::new(0.1, -0.1, 1.0));
        let (lo, hi) = outward(&b);
        for k in 0..3 {
            assert!(f64::from(lo[k]) <= b.lo[k] && f64::from(hi[k]) >= b.hi[k]);
            assert!(hi[k] == lo[k] || hi[k] == lo[k].next_up());
        }
        assert_eq!((lo[2], hi[2]), (1.0, 1.0));
        let inf = Aabb::new(DVec3::splat(f64::NEG_INFINITY), DVec3::splat(f64::INFINITY));
        assert_eq!(outward(&inf), ([f32::NEG_INFINITY; 3], [f32::INFINITY; 3]));
    }
}
