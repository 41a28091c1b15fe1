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

/// An item's box in leaf order (rounded outward) and the item's index: perturbation
/// `item` of the object (GPU.md §5.2, from `Bvh::order` and `Bvh::item_bounds`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuItemBox {
    /// Box minimum (rounded down).
    pub lo: [f32; 3],
    /// The item's index.
    pub item: u32,
    /// Box maximum (rounded up).
    pub hi: [f32; 3],
    /// Padding to 32 bytes.
    pub pad: u32,
}

/// One object of the flat scene (GPU.md §5.2). For a perturbed quadric (`kind` 1):
/// bounds `lo`/`hi` of {F' ≥ 0} rounded outward; nodes `first_node ..` (`node_count`, in
/// the escape layout of [`skip_nodes`]); items `first_item ..` (`item_count` in leaf
/// order, then `unbounded` more with non-finite boxes, offered to every query);
/// `first_op` the base quadric's index, `op_count` the first perturbation's index.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuObject {
    /// 0 quadric, 1 perturbed quadric, 2 expression.
    pub kind: u32,
    /// The material's index.
    pub material: u32,
    /// Flags (none yet).
    pub flags: u32,
    /// Items after the leaf-ordered ones that every query is offered.
    pub unbounded: u32,
    /// Bounds minimum (rounded down).
    pub lo: [f32; 3],
    /// First BVH node.
    pub first_node: u32,
    /// Bounds maximum (rounded up).
    pub hi: [f32; 3],
    /// BVH node count.
    pub node_count: u32,
    /// First item box.
    pub first_item: u32,
    /// Leaf-ordered item boxes.
    pub item_count: u32,
    /// Tape start, or the base quadric's index (kinds 0 and 1).
    pub first_op: u32,
    /// Tape length, or the first perturbation's index (kind 1).
    pub op_count: u32,
}

const _: () = assert!(size_of::<GpuItemBox>() == 32);
const _: () = assert!(size_of::<GpuObject>() == 64);
const _: () = assert!(size_of::<GpuQuadric>() == 48);
const _: () = assert!(size_of::<GpuPerturbation>() == 48);
const _: () = assert!(size_of::<GpuBvhNode>() == 32);

/// The WGSL structs mirroring these, field for field.
pub const LAYOUT_WGSL: &str = "
struct GpuQuadric { c: array<f32, 10>, pad: array<f32, 2> }
struct GpuPerturbation { q: array<f32, 10>, f: f32, pad: f32 }
struct GpuBvhNode { lo_x: f32, lo_y: f32, lo_z: f32, offset: u32, hi_x: f32, hi_y: f32, hi_z: f32, count_axis: u32 }
struct GpuItemBox { lo_x: f32, lo_y: f32, lo_z: f32, item: u32, hi_x: f32, hi_y: f32, hi_z: f32, pad: u32 }
struct GpuObject { kind: u32, material: u32, flags: u32, unbounded: u32, lo_x: f32, lo_y: f32, lo_z: f32, first_node: u32, hi_x: f32, hi_y: f32, hi_z: f32, node_count: u32, first_item: u32, item_count: u32, first_op: u32, op_count: u32 }
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

/// A box rounded outward to f32: (lo, hi), as frep's f32 path rounds it
/// ([`Aabb::outward_f32`]), so that GPU and CPU twin cull by the same boxes.
pub fn outward(b: &Aabb) -> ([f32; 3], [f32; 3]) {
    let r = (
        [down(b.lo.x), down(b.lo.y), down(b.lo.z)],
        [up(b.hi.x), up(b.hi.y), up(b.hi.z)],
    );
    debug_assert!(b.is_empty() || r == b.outward_f32());
    r
}

/// frep's BVH in the escape layout of the stack-free walk (GPU.md §6.1, after
/// DGriffin91/bevy_mod_bvh): the same pre-order nodes (first child next), where an
/// interior node's `offset` is its escape index, the node after its subtree, in place of
/// its second child. A walk goes to i + 1 after a leaf or a hit interior node and to the
/// escape index after a missed interior node; it visits leaves, hence items, in
/// ascending leaf position, as [`frep::BvhRef::for_each_hit_f32`] does.
pub fn skip_nodes(bvh: &frep::BvhRef) -> Vec<GpuBvhNode> {
    let nodes = bvh.nodes;
    let mut escape = vec![0u32; nodes.len()];
    // A second child comes after its parent: fill from the back.
    for i in (0..nodes.len()).rev() {
        escape[i] = if nodes[i].count > 0 {
            i as u32 + 1
        } else {
            escape[nodes[i].offset as usize]
        };
    }
    nodes
        .iter()
        .zip(&escape)
        .map(|(n, &esc)| {
            let mut g = GpuBvhNode::from(n);
            if n.count == 0 {
                g.offset = esc;
            }
            g
        })
        .collect()
}

/// The item boxes in leaf order (`order`, `item_bounds`), then the unbounded items with
/// infinite boxes.
pub fn item_boxes(bvh: &frep::BvhRef) -> Vec<GpuItemBox> {
    let leaf = bvh.order.iter().zip(bvh.item_bounds).map(|(&i, b)| {
        let (lo, hi) = outward(b);
        GpuItemBox {
            lo,
            item: i,
            hi,
            pad: 0,
        }
    });
    let unbounded = bvh.unbounded.iter().map(|&i| GpuItemBox {
        lo: [f32::NEG_INFINITY; 3],
        item: i,
        hi: [f32::INFINITY; 3],
        pad: 0,
    });
    leaf.chain(unbounded).collect()
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

    /// The escape layout walked stack-free visits exactly the items of frep's f32 walk,
    /// in the same order.
    #[test]
    fn escape_walk_equals_the_stack_walk() {
        let boxes: Vec<Aabb> = (0..300)
            .map(|k| {
                let u = k as f64;
                let c = DVec3::new((0.37 * u).sin(), (0.71 * u).cos(), (1.13 * u).sin()) * 3.0;
                let h = DVec3::splat(0.1 + 0.3 * (0.5 + 0.5 * (2.3 * u).sin()));
                if k % 97 == 5 {
                    Aabb::EVERYTHING
                } else {
                    Aabb::new(c - h, c + h)
                }
            })
            .collect();
        let bvh = frep::Bvh::new(&boxes);
        let r = bvh.as_ref();
        let (nodes, items) = (skip_nodes(&r), item_boxes(&r));
        let n_leaf = r.order.len();
        let mut walked = 0;
        for k in 0..200 {
            let u = k as f32;
            let o = [
                4.0 * (0.3 * u).cos(),
                1.7 * (0.9 * u).sin(),
                4.0 * (0.3 * u).sin(),
            ];
            let d = [-o[0] + (1.1 * u).sin(), -o[1], -o[2] + (0.7 * u).cos()];
            let inv = d.map(|v| 1.0 / v);
            let (t0, t1) = (0.1 * (k % 3) as f32, 0.5 + (k % 5) as f32 * 0.2);
            let mut want = Vec::new();
            r.for_each_hit_f32(o, inv, t0, t1, |i| want.push(i as u32));
            let mut got: Vec<u32> = items[n_leaf..].iter().map(|b| b.item).collect();
            let mut i = 0;
            while i < nodes.len() {
                let n = &nodes[i];
                let count = n.count_axis & 0x3fff_ffff;
                let hit = frep::ray::slab_f32(n.lo, n.hi, o, inv, t0, t1).is_some();
                if hit && count > 0 {
                    for b in &items[n.offset as usize..(n.offset + count) as usize] {
                        if frep::ray::slab_f32(b.lo, b.hi, o, inv, t0, t1).is_some() {
                            got.push(b.item);
                        }
                    }
                }
                i = if hit || count > 0 {
                    i + 1
                } else {
                    n.offset as usize
                };
            }
            assert_eq!(got, want, "ray {k}");
            walked += want.len();
        }
        assert!(walked > 1000, "{walked}");
    }

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
