//! Rays against perturbed quadrics on the GPU (GPU.md §6.1): the WGSL port of frep's
//! exact piecewise-polynomial scan (RESEARCH.md §4), the object packed for it, and the
//! CPU f32 twin it equals bit for bit on lavapipe (GPU.md §3.5), frep's
//! [`PerturbedView::first_crossing_f32_gpu`].
//!
//! Both sides visit candidates in the same order, the order in which each piece sums
//! them: unbounded items first, then the BVH's items in ascending leaf position, which a
//! pre-order walk yields without sorting (the kernel's escape-index walk,
//! [`crate::layout::skip_nodes`]; frep's [`frep::BvhRef::for_each_hit_f32`]).
//!
//! The kernel keeps fixed capacities: K = [`frep::perturbed::GPU_ACTIVE`] active
//! perturbations; a range with more is halved, left first, at most
//! [`frep::perturbed::GPU_SPLITS`] times; a ray that still overflows is reported as
//! [`Crossing::Overflow`] (for a later overflow pass), never as a miss. Every loop
//! iteration of an invocation is counted (GPU.md §3.1: llvmpipe silently cuts an
//! invocation's loops after 65 535 iterations in all).

use crate::layout::{
    item_boxes, outward, skip_nodes, GpuBvhNode, GpuItemBox, GpuObject, GpuPerturbation, GpuQuadric,
};
use frep::PerturbedView;
use glam::Vec3;

/// The WGSL of `perturbed_first_crossing(object, o, d, t_min, t_max) -> ScanResult` and
/// its helpers. Needs `layout::LAYOUT_WGSL`, [`crate::FLOAT_WGSL`] and storage bindings named `objects`,
/// `quadrics`, `perturbations`, `nodes` and `items`; the private `loops` counts the
/// invocation's loop iterations.
pub const PERTURBED_WGSL: &str = include_str!("shaders/perturbed.wgsl");

/// One perturbed quadric in the flat scene's arrays (GPU.md §5.2): object 0, quadric 0,
/// perturbations from 0.
#[derive(Clone, Debug, PartialEq)]
pub struct PerturbedPack {
    /// The object (kind 1), its bounds rounded outward.
    pub object: GpuObject,
    /// The base quadric.
    pub quadrics: Vec<GpuQuadric>,
    /// The perturbations, indexed as frep's.
    pub perturbations: Vec<GpuPerturbation>,
    /// The BVH in the escape layout ([`skip_nodes`]).
    pub nodes: Vec<GpuBvhNode>,
    /// The item boxes in leaf order, then the unbounded items ([`item_boxes`]).
    pub items: Vec<GpuItemBox>,
}

impl PerturbedPack {
    /// Packs `view`, rounding coefficients to nearest and boxes outward (GPU.md §5.1).
    pub fn new(view: &PerturbedView) -> Self {
        let (lo, hi) = outward(&view.bounds);
        let object = GpuObject {
            kind: 1,
            unbounded: view.bvh.unbounded.len() as u32,
            lo,
            first_node: 0,
            hi,
            node_count: view.bvh.nodes.len() as u32,
            first_item: 0,
            item_count: view.bvh.order.len() as u32,
            first_op: 0,
            op_count: 0,
            ..GpuObject::default()
        };
        Self {
            object,
            quadrics: vec![GpuQuadric::from(view.base)],
            perturbations: view
                .perturbations
                .iter()
                .map(GpuPerturbation::from)
                .collect(),
            nodes: skip_nodes(&view.bvh),
            items: item_boxes(&view.bvh),
        }
    }
}

/// A ray's outcome, as the kernel reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Crossing {
    /// No sign change in (t_min, t_max).
    Miss,
    /// The first sign change.
    Hit(f32),
    /// More active perturbations than the kernel holds after its halvings: undecided.
    Overflow,
}

impl Crossing {
    /// The kernel's `ScanResult` (status 0 miss, 1 hit, 2 overflow; t as bits).
    pub fn from_kernel(status: u32, t_bits: u32) -> Self {
        match status {
            0 => Crossing::Miss,
            1 => Crossing::Hit(f32::from_bits(t_bits)),
            _ => Crossing::Overflow,
        }
    }
}

/// The CPU twin of `perturbed_first_crossing`: frep's f32 scan with the kernel's
/// capacities; where frep had to stream, the kernel reports [`Crossing::Overflow`].
pub fn first_crossing(view: &PerturbedView, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Crossing {
    match view.first_crossing_f32_gpu(o, d, t_min, t_max) {
        (_, true) => Crossing::Overflow,
        (Some(t), false) => Crossing::Hit(t),
        (None, false) => Crossing::Miss,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The WGSL's capacities are frep's.
    #[test]
    fn wgsl_capacities_are_freps() {
        let k = format!("const K: u32 = {}u;", frep::perturbed::GPU_ACTIVE);
        let s = format!("const MAX_SPLITS: u32 = {}u;", frep::perturbed::GPU_SPLITS);
        let d = format!("const MAX_DEPTH: u32 = {}u;", frep::poly::MAX_DEPTH);
        for c in [k, s, d] {
            assert!(PERTURBED_WGSL.contains(&c), "{c}");
        }
    }
}
