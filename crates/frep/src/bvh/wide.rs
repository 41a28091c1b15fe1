//! The binary BVH walked four boxes at a time: each wide node holds the (two to four)
//! grandchildren of a binary node, tested against the ray in one SIMD slab test (two
//! SSE2 pairs of f64 lanes on x86-64, part of its baseline; a loop elsewhere), as the
//! wide BVHs of Embree do (Wald et al., "Getting rid of packets", 2008; Dammertz et al.,
//! "Shallow bounding volume hierarchies for fast SIMD ray tracing of incoherent rays",
//! 2008).
//!
//! **SSE2 inlined, AVX where a caller picks it.** A walk is one call per ray, inlined with
//! the caller's closure, in SSE2's two pairs by default. An AVX walk ([`Avx`], four f64
//! lanes in one register) has to run in a function compiled for AVX: calling one from
//! inside the walk made every caller keep its closure in memory, small trees included (on
//! scenes/many-lights.toml 4 % more instructions; docs/notebook/2026-12-05-wide-bvh.md).
//! So the choice is the caller's, made above the closure: [`BvhRef::nearest_avx`] from a
//! function of the caller's own, compiled for AVX, picked at run time where the tree is
//! large (`render::light::Lights::intersect` from 16 wide nodes on: with 10 000 lights
//! 9–11 % fewer instructions a sample, the small scenes 0.1 % more). The lane tests are
//! a [`Lanes`] type, ready for batched stages too.
//!
//! **Same walk, bit for bit.** The wide walk offers the caller the same items in the same
//! order, with the same `t_max` each time, as the binary walk of [`BvhRef::walk`]:
//! - a child's box is skipped (a parent's box holds its children's, and the slab test is
//!   monotone in the planes: a box that the segment enters, its parent's is entered too);
//! - a lane's box is its node's rounded outward to f32, so it is entered wherever the
//!   node's is, perhaps also a little beyond: the walk may then go down a subtree the
//!   binary walk skips, but every item there fails its own (f64, exact) test, so nothing
//!   more is offered;
//! - the lanes are visited in the binary walk's order (nearer child first by the sign of
//!   the ray along each split axis), and a lane put aside for later is re-tested against
//!   the `t_max` of its turn: its entry parameter does not depend on `t_max`, so
//!   `entry ≤ t_max` then is the binary test's answer then;
//! - every lane's test is the binary one's arithmetic in f64 (`(plane − o)·(1/d)`, min and
//!   max per axis), whose answer does not depend on the order of the max/min chains for
//!   finite values. Rays with a non-finite `1/d` (an axis-parallel direction) or origin
//!   take the binary walk, whose NaN-ignoring test they need.
//!
//! The re-test at a lane's turn reads its entry against `t_max`: the binary walk's test
//! for the f32 box, which holds wherever the node's own does.
//!
//! Leaves are the binary tree's, with their items tested one by one as before.

use super::{BvhNode, BvhRef, Slab};
use crate::fixed::Fixed;

/// A lane's `next` for a binary leaf: this bit set on the leaf's binary node index.
const LEAF: u32 = 1 << 31;

/// The fewest binary nodes a tree has for a wide walk to pay: below, a few scalar box
/// tests cost less than the wide walk's setup (on scenes/many-lights.toml, its trees of
/// 3 and 7 nodes walked wide took 4 % more instructions; 30 lights, 17 nodes, 1 % fewer).
const MIN_NODES: usize = 9;

/// Pending lanes of a walk: up to three per wide level; the binary tree's median splits
/// keep its depth within about 80, so a wide walk within 40 levels.
const STACK: usize = 128;

/// Two to four binary nodes tested together: the grandchildren of one binary node (a
/// child that is a leaf stands for itself), in the binary tree's order (the first
/// child's, then the second's).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct WideNode {
    /// Lower corners, `lo[axis][lane]`, rounded down to f32 (two cache lines a node
    /// where f64 took four; tested in f64).
    lo: [[f32; 4]; 3],
    /// Upper corners, `hi[axis][lane]`, rounded up to f32.
    hi: [[f32; 4]; 3],
    /// Per lane: the wide node of the lane's grandchildren, or [`LEAF`] with the lane's
    /// binary node index (a leaf).
    next: [u32; 4],
    /// Lanes in use (2 to 4; unused lanes repeat lane 0's box and are masked off).
    len: u8,
    /// Per octant of the ray's direction (bit k: component k negative), the order to
    /// visit the lanes in, two bits a lane, first lowest ([`visit_order`]).
    order: [u8; 8],
}

impl WideNode {
    /// The wide nodes of a binary tree: node 0 holds the root's grandchildren (the root's
    /// own box need not be tested: a box inside it that the segment enters, it enters
    /// too). Empty for a tree of fewer than 9 nodes (`MIN_NODES`), walked as it is. Lanes name binary nodes by their index in `nodes`, wide nodes
    /// by their index in the result.
    pub fn build(nodes: &[BvhNode]) -> Vec<WideNode> {
        let mut out = Vec::new();
        if nodes.len() >= MIN_NODES {
            grandchildren(nodes, &mut out, 0);
        }
        // Boxes beyond f32's range: walked as a binary tree (NaN-free lanes need finite
        // corners).
        let finite = |w: &WideNode| w.lo.iter().chain(&w.hi).flatten().all(|v| v.is_finite());
        if !out.iter().all(finite) {
            out.clear();
        }
        out
    }
}

/// Appends the wide node over the grandchildren of interior binary node `b` (a child
/// that is a leaf stands for itself) and, depth first, those below; returns its index.
fn grandchildren(nodes: &[BvhNode], out: &mut Vec<WideNode>, b: u32) -> u32 {
    let x = &nodes[b as usize];
    let (first, second) = (b + 1, x.offset);
    let mut lanes = Vec::with_capacity(4);
    let mut axes = [x.axis as u8, 0, 0];
    for (g, c) in [first, second].into_iter().enumerate() {
        let child = &nodes[c as usize];
        if child.count > 0 {
            lanes.push(c);
        } else {
            lanes.extend([c + 1, child.offset]);
            axes[1 + g] = child.axis as u8;
        }
    }
    let split = if nodes[first as usize].count > 0 {
        1
    } else {
        2
    };
    node(nodes, out, &lanes, split, axes)
}

/// Appends the wide node over binary `lanes` (groups split at `split`, ordered by `axes`:
/// [`visit_order`]) and, depth first, those of its interior lanes; returns its index.
fn node(
    nodes: &[BvhNode],
    out: &mut Vec<WideNode>,
    lanes: &[u32],
    split: u8,
    axes: [u8; 3],
) -> u32 {
    let me = out.len();
    let (lo0, hi0) = nodes[lanes[0] as usize].bounds.outward_f32();
    let mut w = WideNode {
        lo: lo0.map(|v| [v; 4]),
        hi: hi0.map(|v| [v; 4]),
        next: [0; 4],
        len: lanes.len() as u8,
        order: [0; 8],
    };
    for (octant, order) in w.order.iter_mut().enumerate() {
        let neg = [0, 1, 2].map(|k| octant & (1 << k) != 0);
        let (lanes, n) = visit_order(lanes.len() as u8, split, axes, neg);
        *order = (0..n).map(|i| lanes[i] << (2 * i)).sum();
    }
    for (lane, &b) in lanes.iter().enumerate() {
        let (lo, hi) = nodes[b as usize].bounds.outward_f32();
        for k in 0..3 {
            w.lo[k][lane] = lo[k];
            w.hi[k][lane] = hi[k];
        }
    }
    out.push(w);
    for (lane, &b) in lanes.iter().enumerate() {
        let next = match nodes[b as usize].count {
            0 => grandchildren(nodes, out, b),
            _ => LEAF | b,
        };
        out[me].next[lane] = next;
    }
    me as u32
}

/// A slab test of the four lanes of a wide node: each lane's entry parameter and a mask
/// of the lanes whose box the segment meets ([`Slab::enter`] lane by lane).
pub(super) trait Lanes {
    /// The ray in the form the test wants (broadcast once per walk).
    type Ray: Copy;
    fn ray(slab: &Slab) -> Self::Ray;
    fn enter(node: &WideNode, ray: &Self::Ray, t0: f64, t1: f64) -> ([f64; 4], u32);
}

/// The lanes one at a time: the reference the SIMD tests equal, and the walk off x86-64.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
pub(super) struct Scalar;

impl Lanes for Scalar {
    type Ray = ([f64; 3], [f64; 3]);
    #[inline(always)]
    fn ray(slab: &Slab) -> Self::Ray {
        (slab.o.to_array(), slab.inv.to_array())
    }
    #[inline(always)]
    fn enter(node: &WideNode, (o, inv): &Self::Ray, t0: f64, t1: f64) -> ([f64; 4], u32) {
        let mut entry = [0.0; 4];
        let mut mask = 0;
        for (lane, entry) in entry.iter_mut().enumerate() {
            let (mut lo, mut hi) = (t0, t1);
            for k in 0..3 {
                let a = (f64::from(node.lo[k][lane]) - o[k]) * inv[k];
                let c = (f64::from(node.hi[k][lane]) - o[k]) * inv[k];
                lo = lo.max(a.min(c));
                hi = hi.min(a.max(c));
            }
            *entry = lo;
            mask |= u32::from(lo <= hi) << lane;
        }
        (entry, mask)
    }
}

/// Two SSE2 pairs (part of every x86-64).
#[cfg(target_arch = "x86_64")]
pub(super) struct Sse2;

#[cfg(target_arch = "x86_64")]
impl Lanes for Sse2 {
    type Ray = [std::arch::x86_64::__m128d; 6];
    #[inline(always)]
    fn ray(slab: &Slab) -> Self::Ray {
        use std::arch::x86_64::_mm_set1_pd;
        // SAFETY: SSE2 is part of the x86-64 baseline.
        unsafe {
            let (o, i) = (slab.o, slab.inv);
            [o.x, o.y, o.z, i.x, i.y, i.z].map(|v| _mm_set1_pd(v))
        }
    }
    #[inline(always)]
    fn enter(node: &WideNode, r: &Self::Ray, t0: f64, t1: f64) -> ([f64; 4], u32) {
        use std::arch::x86_64::{
            __m128d, _mm_cmple_pd, _mm_cvtps_pd, _mm_load_ps, _mm_max_pd, _mm_min_pd,
            _mm_movehl_ps, _mm_movemask_pd, _mm_mul_pd, _mm_set1_pd, _mm_storeu_pd, _mm_sub_pd,
        };
        let mut entry = [0.0; 4];
        let mut mask = 0;
        // SAFETY: SSE2 is part of the x86-64 baseline; each load reads one lane array
        // (four f32, 16-byte aligned: `WideNode` is `align(64)`, each array 16 bytes),
        // each store writes two of `entry`.
        unsafe {
            // Each corner array as f64 pairs: lanes 0 and 1, lanes 2 and 3.
            let pairs = |v: &[f32; 4]| -> [__m128d; 2] {
                let v = _mm_load_ps(v.as_ptr());
                [_mm_cvtps_pd(v), _mm_cvtps_pd(_mm_movehl_ps(v, v))]
            };
            let lo3 = [pairs(&node.lo[0]), pairs(&node.lo[1]), pairs(&node.lo[2])];
            let hi3 = [pairs(&node.hi[0]), pairs(&node.hi[1]), pairs(&node.hi[2])];
            for half in 0..2 {
                let (mut lo, mut hi) = (_mm_set1_pd(t0), _mm_set1_pd(t1));
                for k in 0..3 {
                    let a = _mm_mul_pd(_mm_sub_pd(lo3[k][half], r[k]), r[3 + k]);
                    let c = _mm_mul_pd(_mm_sub_pd(hi3[k][half], r[k]), r[3 + k]);
                    lo = _mm_max_pd(lo, _mm_min_pd(a, c));
                    hi = _mm_min_pd(hi, _mm_max_pd(a, c));
                }
                _mm_storeu_pd(&mut entry[2 * half], lo);
                mask |= (_mm_movemask_pd(_mm_cmple_pd(lo, hi)) as u32) << (2 * half);
            }
        }
        (entry, mask)
    }
}

/// The four lanes in one AVX register. Only for walks compiled for AVX (the
/// `#[target_feature]` walks of [`BvhRef`], picked at run time by their callers): its
/// operations are inlined there.
#[cfg(target_arch = "x86_64")]
pub(super) struct Avx;

#[cfg(target_arch = "x86_64")]
impl Lanes for Avx {
    type Ray = [std::arch::x86_64::__m256d; 6];
    #[inline(always)]
    fn ray(slab: &Slab) -> Self::Ray {
        use std::arch::x86_64::_mm256_set1_pd;
        // SAFETY: only called where the walk is compiled for AVX and the CPU has it.
        unsafe {
            let (o, i) = (slab.o, slab.inv);
            [o.x, o.y, o.z, i.x, i.y, i.z].map(|v| _mm256_set1_pd(v))
        }
    }
    #[inline(always)]
    fn enter(node: &WideNode, r: &Self::Ray, t0: f64, t1: f64) -> ([f64; 4], u32) {
        use std::arch::x86_64::{
            _mm256_cmp_pd, _mm256_cvtps_pd, _mm256_max_pd, _mm256_min_pd, _mm256_movemask_pd,
            _mm256_mul_pd, _mm256_set1_pd, _mm256_storeu_pd, _mm256_sub_pd, _mm_load_ps,
            _CMP_LE_OQ,
        };
        let mut entry = [0.0; 4];
        // SAFETY: only called where the walk is compiled for AVX and the CPU has it; each
        // load reads one lane array (four f32, 16-byte aligned: `WideNode` is
        // `align(64)`, each array 16 bytes), the store writes `entry`.
        unsafe {
            let (mut lo, mut hi) = (_mm256_set1_pd(t0), _mm256_set1_pd(t1));
            for k in 0..3 {
                let a = _mm256_cvtps_pd(_mm_load_ps(node.lo[k].as_ptr()));
                let c = _mm256_cvtps_pd(_mm_load_ps(node.hi[k].as_ptr()));
                // Sse2's operations, four lanes at once (`minpd`/`maxpd` alike).
                let a = _mm256_mul_pd(_mm256_sub_pd(a, r[k]), r[3 + k]);
                let c = _mm256_mul_pd(_mm256_sub_pd(c, r[k]), r[3 + k]);
                lo = _mm256_max_pd(lo, _mm256_min_pd(a, c));
                hi = _mm256_min_pd(hi, _mm256_max_pd(a, c));
            }
            _mm256_storeu_pd(entry.as_mut_ptr(), lo);
            let mask = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LE_OQ>(lo, hi)) as u32;
            (entry, mask)
        }
    }
}

/// The order to visit the lanes of a wide node in: `len` lanes, those below `split`
/// from the binary node's first child, its groups nearer first by the sign of the ray
/// along the binary node's axis, each group's two lanes likewise by its child's axis
/// (`axes`: the node's and its children's; `neg`: which components of the direction are
/// negative), as the binary walk visits them.
fn visit_order(len: u8, split: u8, axes: [u8; 3], neg: [bool; 3]) -> ([u8; 4], usize) {
    let group = |start: u8, end: u8, axis: u8| -> Vec<u8> {
        match end - start {
            2 if neg[axis as usize] => vec![start + 1, start],
            2 => vec![start, start + 1],
            _ => vec![start],
        }
    };
    let (a, b) = (group(0, split, axes[1]), group(split, len, axes[2]));
    let lanes: Vec<u8> = match (len, neg[axes[0] as usize]) {
        (1, _) => vec![0],
        (_, true) => b.into_iter().chain(a).collect(),
        (_, false) => a.into_iter().chain(b).collect(),
    };
    let mut order = [0; 4];
    order[..lanes.len()].copy_from_slice(&lanes);
    (order, lanes.len())
}

impl BvhRef<'_> {
    /// [`Self::walk`] over the wide nodes with lane tests `L` (see the module docs), for
    /// a ray whose `slab` is finite.
    #[inline(always)]
    pub(super) fn walk_wide<L: Lanes>(
        &self,
        slab: &Slab,
        t_min: f64,
        mut t_max: f64,
        offer: &mut impl FnMut(u32, &mut f64) -> bool,
    ) {
        if self.wide.is_empty() {
            return;
        }
        let ray = L::ray(slab);
        let octant = slab
            .neg
            .iter()
            .enumerate()
            .map(|(k, &n)| usize::from(n) << k)
            .sum::<usize>();
        let mut stack: Fixed<(f64, u32), STACK> = Fixed::new();
        // What to take now: a wide node, or a leaf (LEAF set); the root's grandchildren
        // first.
        let mut next = 0u32;
        loop {
            if next & LEAF == 0 {
                let node = &self.wide[next as usize];
                let (entry, mask) = L::enter(node, &ray, t_min, t_max);
                let mask = mask & ((1 << node.len) - 1);
                if mask & mask.wrapping_sub(1) == 0 && mask != 0 {
                    // One lane met (the common case): taken at once.
                    next = node.next[mask.trailing_zeros() as usize];
                    continue;
                }
                // The lanes met go on the stack, farthest in order first.
                let order = node.order[octant];
                for i in (0..node.len).rev() {
                    let lane = usize::from((order >> (2 * i)) & 3);
                    if mask & (1 << lane) != 0 {
                        stack.push_within((entry[lane], node.next[lane]));
                    }
                }
            } else {
                let leaf = &self.nodes[(next & !LEAF) as usize];
                let s = leaf.offset as usize;
                for k in s..s + leaf.count as usize {
                    if slab.enter(&self.item_bounds[k], t_min, t_max).is_some()
                        && offer(self.order[k], &mut t_max)
                    {
                        return;
                    }
                }
            }
            // The binary walk's test of a box put aside, at its turn (those just put
            // aside pass it: t_max has not changed since).
            next = loop {
                match stack.pop() {
                    None => return,
                    Some((e, n)) if e <= t_max => break n,
                    Some(_) => {}
                }
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::Bvh;
    use crate::ray::Aabb;
    use glam::DVec3;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// Every lane test equals the scalar one bit for bit (entries and masks), on the
    /// nodes of random trees against random finite rays and segments.
    #[test]
    fn simd_lanes_equal_the_scalar_lanes() {
        let mut rng = Pcg64::seed_from_u64(5);
        let boxes = super::super::tests::random_boxes(&mut rng, 2000);
        let bvh = Bvh::new(&boxes);
        let mut checked = 0;
        for _ in 0..2000 {
            let ray = super::super::tests::random_ray(&mut rng, 0.0);
            let slab = Slab::new(&ray);
            let (t0, t1) = (rng.gen_range(-2.0..2.0), rng.gen_range(2.0..30.0));
            for node in &bvh.wide {
                let want = Scalar::enter(node, &Scalar::ray(&slab), t0, t1);
                let bits = |(e, m): ([f64; 4], u32)| (e.map(f64::to_bits), m);
                #[cfg(target_arch = "x86_64")]
                {
                    assert_eq!(
                        bits(Sse2::enter(node, &Sse2::ray(&slab), t0, t1)),
                        bits(want)
                    );
                    if std::arch::is_x86_feature_detected!("avx") {
                        // SAFETY: the CPU has AVX.
                        let avx = unsafe { avx_enter(node, &slab, t0, t1) };
                        assert_eq!(bits(avx), bits(want));
                    }
                }
                checked += 1;
            }
        }
        assert!(checked > 100_000);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn avx_enter(node: &WideNode, slab: &Slab, t0: f64, t1: f64) -> ([f64; 4], u32) {
        Avx::enter(node, &Avx::ray(slab), t0, t1)
    }

    /// What a walk offers: (item, t_max at the offer), in order.
    fn offers(
        walk: impl FnOnce(&mut dyn FnMut(u32, &mut f64) -> bool),
        hit_at: &dyn Fn(u32) -> Option<f64>,
        stop: Option<u32>,
    ) -> Vec<(u32, u64)> {
        let mut seen = Vec::new();
        walk(&mut |i, t_max: &mut f64| {
            seen.push((i, t_max.to_bits()));
            if let Some(t) = hit_at(i).filter(|&t| t <= *t_max) {
                *t_max = t;
            }
            Some(i) == stop
        });
        seen
    }

    /// The wide walk offers the binary walk's items in its order with its `t_max`, bit
    /// for bit, with every lane test, for nearest-hit walks (t_max shrinking at each
    /// hit), any-hit walks stopped at an item, and plain visits, on trees of 0 to 3000
    /// boxes (degenerate splits and 16-item leaves included).
    #[test]
    fn wide_walks_offer_what_the_binary_walk_offers() {
        let mut rng = Pcg64::seed_from_u64(17);
        for n in [0, 1, 3, 5, 17, 500, 3000] {
            let mut boxes = super::super::tests::random_boxes(&mut rng, n);
            for b in boxes.iter_mut().skip(3).take(40) {
                *b = Aabb::new(DVec3::splat(1.0), DVec3::splat(1.5));
            }
            let bvh = Bvh::new(&boxes);
            let r = bvh.as_ref();
            // Small trees are walked as binary trees.
            assert_eq!(bvh.wide.is_empty(), bvh.nodes.len() < MIN_NODES, "n={n}");
            if bvh.wide.is_empty() {
                continue;
            }
            for case in 0..400 {
                let ray = super::super::tests::random_ray(&mut rng, 0.0);
                let slab = Slab::new(&ray);
                let t1 = if case % 3 == 0 {
                    f64::INFINITY
                } else {
                    rng.gen_range(5.0..20.0)
                };
                // An item's "hit" at its box's entry, past a random part of its boxes.
                let hit_at = |i: u32| {
                    let b = &boxes[i as usize];
                    slab.enter(b, 0.0, f64::INFINITY).filter(|_| i % 3 != 1)
                };
                let stop = (case % 4 == 1).then(|| rng.gen_range(0..n.max(1) as u32));
                let binary = offers(|f| r.walk_binary(&slab, 0.0, t1, f), &hit_at, stop);
                let scalar = offers(
                    |f| r.walk_wide::<Scalar>(&slab, 0.0, t1, &mut |i, t| f(i, t)),
                    &hit_at,
                    stop,
                );
                assert_eq!(scalar, binary, "n={n} case {case}");
                #[cfg(target_arch = "x86_64")]
                {
                    let sse2 = offers(
                        |f| r.walk_wide::<Sse2>(&slab, 0.0, t1, &mut |i, t| f(i, t)),
                        &hit_at,
                        stop,
                    );
                    assert_eq!(sse2, binary, "n={n} case {case}");
                    if std::arch::is_x86_feature_detected!("avx") {
                        // SAFETY: the CPU has AVX.
                        let avx = unsafe { avx_offers(r, &slab, t1, &hit_at, stop) };
                        assert_eq!(avx, binary, "n={n} case {case}");
                    }
                }
            }
        }
    }

    /// [`offers`] of the wide walk in AVX lanes, compiled for AVX as its callers are.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn avx_offers(
        r: BvhRef<'_>,
        slab: &Slab,
        t1: f64,
        hit_at: &dyn Fn(u32) -> Option<f64>,
        stop: Option<u32>,
    ) -> Vec<(u32, u64)> {
        offers(
            |f| r.walk_wide::<Avx>(slab, 0.0, t1, &mut |i, t| f(i, t)),
            hit_at,
            stop,
        )
    }
}
