//! A bounding volume hierarchy over boxes, for "which items can this ray segment meet?".
//!
//! Built top-down with the surface area heuristic evaluated over 16 centroid bins per
//! axis (Wald, "On fast construction of SAH-based bounding volume hierarchies", IRT
//! 2007), falling back to a median split when centroids coincide or the tree grows deep,
//! and flattened depth-first (first child follows its parent; pbrt-v4 §7.3.4), so that
//! the GPU can walk the same arrays. Items with a non-finite box (unbounded solids,
//! perturbations whose support is unbounded) are kept aside and reported by every query;
//! empty boxes are dropped. It serves the perturbations of one perturbed quadric and, at
//! scene level, the objects of a scene.

use crate::fixed::Fixed;
use crate::ray::{slab_f32, Aabb, Ray};
use glam::DVec3;

mod order;
mod wide;
pub use order::{EntryOrder, Queue};
pub use wide::WideNode;

/// The most items a leaf holds.
const MAX_LEAF: usize = 4;
/// SAH bins per axis.
const BINS: usize = 16;
/// Depth from which splits are forced to the median, keeping the tree within the
/// fixed traversal stack.
const MEDIAN_DEPTH: usize = 40;
/// Traversal stack size (MEDIAN_DEPTH plus log₂ of any realistic item count).
const STACK: usize = 80;

/// The pending node indices of a walk, never zeroed ([`Fixed`]: zeroing 80 words cost
/// more than a small BVH's whole walk); the median splits keep a walk within it.
struct Stack(Fixed<u32, STACK>);

impl Stack {
    #[inline(always)]
    fn new() -> Self {
        Self(Fixed::new())
    }
    #[inline(always)]
    fn push(&mut self, node: u32) {
        self.0.push_within(node);
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<usize> {
        self.0.pop().map(|n| n as usize)
    }
}

/// One node of the flattened tree.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct BvhNode {
    /// The box holding every item below.
    pub bounds: Aabb,
    /// Leaf: index of the first item in [`Bvh::order`]; interior: index of the second
    /// child (the first child is the next node).
    pub offset: u32,
    /// Leaf: number of items (> 0); interior: 0.
    pub count: u32,
    /// Interior: the split axis (0, 1, 2), used to visit the nearer child first.
    pub axis: u32,
}

/// The wide walk's lanes where no caller picks others: SSE2 on x86-64 (part of its
/// baseline), scalar ones elsewhere.
#[cfg(target_arch = "x86_64")]
type WideLanes = wide::Sse2;
#[cfg(not(target_arch = "x86_64"))]
type WideLanes = wide::Scalar;

/// A BVH over a set of boxes (see the module docs). Items are named by their index in
/// the slice given to [`Bvh::new`].
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<BvhNode>,
    wide: Vec<WideNode>,
    order: Vec<u32>,
    item_bounds: Vec<Aabb>,
    unbounded: Vec<u32>,
}

struct Build<'a> {
    boxes: &'a [Aabb],
    centroids: Vec<DVec3>,
    nodes: Vec<BvhNode>,
}

fn area(b: &Aabb) -> f64 {
    if b.is_empty() {
        return 0.0;
    }
    let e = b.extent();
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

impl Build<'_> {
    /// Builds the subtree over `items` (reordered in place); returns its node index.
    fn node(&mut self, items: &mut [u32], start: usize, depth: usize) -> usize {
        let mut bounds = Aabb::EMPTY;
        let mut cb = Aabb::EMPTY;
        for &i in items.iter() {
            bounds = bounds.union(&self.boxes[i as usize]);
            cb.include(self.centroids[i as usize]);
        }
        let me = self.nodes.len();
        self.nodes.push(BvhNode {
            bounds,
            offset: start as u32,
            count: items.len() as u32,
            axis: 0,
        });
        if items.len() <= MAX_LEAF {
            return me;
        }
        let ext = cb.extent();
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = if ext[axis] <= 0.0 {
            // Every centroid coincides: split the list in half.
            items.len() / 2
        } else if depth >= MEDIAN_DEPTH {
            self.median(items, axis)
        } else {
            match self.sah(items, &bounds, &cb, axis) {
                Some(m) => m,
                None => return me,
            }
        };
        self.nodes[me].axis = axis as u32;
        self.nodes[me].count = 0;
        let (left, right) = items.split_at_mut(mid);
        self.node(left, start, depth + 1);
        let second = self.node(right, start + mid, depth + 1);
        self.nodes[me].offset = second as u32;
        me
    }

    fn median(&self, items: &mut [u32], axis: usize) -> usize {
        let mid = items.len() / 2;
        let c = &self.centroids;
        items.select_nth_unstable_by(mid, |&a, &b| {
            c[a as usize][axis].total_cmp(&c[b as usize][axis])
        });
        mid
    }

    /// The binned SAH split of `items` along `axis` (partitioned in place), or None when
    /// a leaf is cheaper (cost: 1 per item tested, 1 per node visited).
    fn sah(&self, items: &mut [u32], bounds: &Aabb, cb: &Aabb, axis: usize) -> Option<usize> {
        let (lo, ext) = (cb.lo[axis], cb.extent()[axis]);
        let bin = |c: DVec3| (((c[axis] - lo) / ext * BINS as f64) as usize).min(BINS - 1);
        let mut count = [0usize; BINS];
        let mut bb = [Aabb::EMPTY; BINS];
        for &i in items.iter() {
            let k = bin(self.centroids[i as usize]);
            count[k] += 1;
            bb[k] = bb[k].union(&self.boxes[i as usize]);
        }
        // Sweep from the right to get the area and count of every right part.
        let mut right_area = [0.0; BINS];
        let mut right_count = [0usize; BINS];
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for k in (1..BINS).rev() {
            acc = acc.union(&bb[k]);
            n += count[k];
            right_area[k] = area(&acc);
            right_count[k] = n;
        }
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        let mut best = (f64::INFINITY, 0);
        for k in 1..BINS {
            acc = acc.union(&bb[k - 1]);
            n += count[k - 1];
            if n == 0 || right_count[k] == 0 {
                continue;
            }
            let cost = area(&acc) * n as f64 + right_area[k] * right_count[k] as f64;
            if cost < best.0 {
                best = (cost, k);
            }
        }
        if best.0.is_infinite() {
            return Some(self.median(items, axis));
        }
        let split_cost = 1.0 + best.0 / area(bounds).max(f64::MIN_POSITIVE);
        if split_cost >= items.len() as f64 && items.len() <= 4 * MAX_LEAF {
            return None;
        }
        // Partition: bins below best.1 go left.
        let mut l = 0;
        for r in 0..items.len() {
            if bin(self.centroids[items[r] as usize]) < best.1 {
                items.swap(l, r);
                l += 1;
            }
        }
        Some(l)
    }
}

/// 1/d per axis, and the slab test of a box against `o + t·d`, t ∈ [t0, t1].
#[derive(Clone, Copy)]
struct Slab {
    o: DVec3,
    inv: DVec3,
    /// Whether o and 1/d are finite, so that no slab parameter is NaN and the near and
    /// far planes follow from d's signs ([`Slab::enter`]'s fast path).
    finite: bool,
    /// Which components of d are negative.
    neg: [bool; 3],
}

impl Slab {
    fn new(ray: &Ray) -> Self {
        let inv = ray.d.recip();
        Self {
            o: ray.o,
            inv,
            finite: inv.is_finite() && ray.o.is_finite(),
            neg: [ray.d.x < 0.0, ray.d.y < 0.0, ray.d.z < 0.0],
        }
    }
    /// The entry parameter when the segment meets the (non-empty) box (Kay & Kajiya
    /// 1986). NaN (0·∞, an origin on the slab of a parallel ray) never narrows the
    /// range. Where no parameter can be NaN, the near and far planes are picked by d's
    /// signs and compared without NaN guards: the same values, at about half the
    /// instructions of `f64::min`/`max` (the hottest loop of every BVH query).
    #[inline(always)]
    fn enter(&self, b: &Aabb, t0: f64, t1: f64) -> Option<f64> {
        let (mut lo, mut hi) = (t0, t1);
        if !self.finite {
            for k in 0..3 {
                let a = (b.lo[k] - self.o[k]) * self.inv[k];
                let c = (b.hi[k] - self.o[k]) * self.inv[k];
                lo = lo.max(a.min(c));
                hi = hi.min(a.max(c));
            }
            return (lo <= hi).then_some(lo);
        }
        #[cfg(target_arch = "x86_64")]
        {
            self.enter_sse2(b, t0, t1)
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self.enter_scalar(b, t0, t1)
        }
    }

    /// [`Self::enter`]'s fast path axis by axis: the near and far planes by d's signs.
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    #[inline(always)]
    fn enter_scalar(&self, b: &Aabb, t0: f64, t1: f64) -> Option<f64> {
        let (mut lo, mut hi) = (t0, t1);
        for k in 0..3 {
            let (n, f) = if self.neg[k] {
                (b.hi[k], b.lo[k])
            } else {
                (b.lo[k], b.hi[k])
            };
            let tn = (n - self.o[k]) * self.inv[k];
            let tf = (f - self.o[k]) * self.inv[k];
            if tn > lo {
                lo = tn;
            }
            if tf < hi {
                hi = tf;
            }
        }
        (lo <= hi).then_some(lo)
    }

    /// [`Self::enter_scalar`] with x and y in one SSE2 register (part of every x86-64).
    /// Both planes' parameters are computed and ordered by min/max: for a non-empty box
    /// and 1/d of either sign that is the sign-picked pair, value for value, and the
    /// bounds are narrowed in the same order with the same comparisons (`maxsd` keeps
    /// its second operand on a tie, as `if tn > lo` does), so the result is the same
    /// bit for bit (`sse2_slab_equals_the_scalar_one`).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn enter_sse2(&self, b: &Aabb, t0: f64, t1: f64) -> Option<f64> {
        use std::arch::x86_64::{
            _mm_cvtsd_f64, _mm_loadu_pd, _mm_max_pd, _mm_max_sd, _mm_min_pd, _mm_min_sd,
            _mm_mul_pd, _mm_set_sd, _mm_sub_pd, _mm_unpackhi_pd,
        };
        // SAFETY: SSE2 is part of the x86-64 baseline; each load reads the x and y of a
        // `DVec3` (three consecutive f64, `#[repr(C)]`).
        unsafe {
            let xy = |v: &DVec3| _mm_loadu_pd(&v.x);
            let (o, inv) = (xy(&self.o), xy(&self.inv));
            let a = _mm_mul_pd(_mm_sub_pd(xy(&b.lo), o), inv);
            let c = _mm_mul_pd(_mm_sub_pd(xy(&b.hi), o), inv);
            let (near, far) = (_mm_min_pd(a, c), _mm_max_pd(a, c));
            let az = (b.lo.z - self.o.z) * self.inv.z;
            let cz = (b.hi.z - self.o.z) * self.inv.z;
            let (nz, fz) = if self.neg[2] { (cz, az) } else { (az, cz) };
            // lo = tn > lo ? tn : lo, axis by axis in order x, y, z; hi likewise.
            let lo = _mm_max_sd(near, _mm_set_sd(t0));
            let lo = _mm_max_sd(_mm_unpackhi_pd(near, near), lo);
            let lo = _mm_max_sd(_mm_set_sd(nz), lo);
            let hi = _mm_min_sd(far, _mm_set_sd(t1));
            let hi = _mm_min_sd(_mm_unpackhi_pd(far, far), hi);
            let hi = _mm_min_sd(_mm_set_sd(fz), hi);
            let (lo, hi) = (_mm_cvtsd_f64(lo), _mm_cvtsd_f64(hi));
            (lo <= hi).then_some(lo)
        }
    }
}

impl Bvh {
    /// Builds the hierarchy over `boxes`; item k is `boxes[k]`.
    pub fn new(boxes: &[Aabb]) -> Self {
        let mut finite = Vec::new();
        let mut unbounded = Vec::new();
        for (k, b) in boxes.iter().enumerate() {
            if b.is_empty() {
                continue;
            }
            if b.is_finite() {
                finite.push(k as u32);
            } else {
                unbounded.push(k as u32);
            }
        }
        let mut build = Build {
            boxes,
            centroids: boxes.iter().map(Aabb::center).collect(),
            nodes: Vec::with_capacity(2 * finite.len() / MAX_LEAF + 1),
        };
        if !finite.is_empty() {
            build.node(&mut finite, 0, 0);
        }
        Self {
            wide: WideNode::build(&build.nodes),
            nodes: build.nodes,
            item_bounds: finite.iter().map(|&i| boxes[i as usize]).collect(),
            order: finite,
            unbounded,
        }
    }

    /// The flattened nodes, root first (empty when no item has a finite box).
    pub fn nodes(&self) -> &[BvhNode] {
        &self.nodes
    }

    /// The wide nodes ([`WideNode::build`]).
    pub fn wide(&self) -> &[WideNode] {
        &self.wide
    }

    /// Item indices in leaf order: a leaf holds `order[offset..offset + count]`.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// The items' boxes in leaf order (`item_bounds()[k]` is the box of `order()[k]`).
    pub fn item_bounds(&self) -> &[Aabb] {
        &self.item_bounds
    }

    /// Items whose box is not finite; every query reports them.
    pub fn unbounded(&self) -> &[u32] {
        &self.unbounded
    }

    /// The box of every finite item together.
    pub fn bounds(&self) -> Aabb {
        self.as_ref().bounds()
    }

    /// The arrays, borrowed.
    pub fn as_ref(&self) -> BvhRef<'_> {
        BvhRef {
            nodes: &self.nodes,
            wide: &self.wide,
            order: &self.order,
            item_bounds: &self.item_bounds,
            unbounded: &self.unbounded,
        }
    }

    /// Calls `visit(item)` for every item whose box the segment o + t·d, t ∈ [t_min,
    /// t_max], meets (and every unbounded item), nearer subtrees first.
    pub fn for_each_hit(&self, ray: &Ray, t_min: f64, t_max: f64, visit: impl FnMut(usize)) {
        self.as_ref().for_each_hit(ray, t_min, t_max, visit)
    }

    /// Appends to `out` the items [`for_each_hit`](Self::for_each_hit) visits.
    pub fn collect(&self, ray: &Ray, t_min: f64, t_max: f64, out: &mut Vec<u32>) {
        self.for_each_hit(ray, t_min, t_max, |i| out.push(i as u32));
    }

    /// Closest-hit traversal: see [`BvhRef::nearest`].
    pub fn nearest(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        hit: impl FnMut(usize, f64) -> Option<f64>,
    ) -> Option<(usize, f64)> {
        self.as_ref().nearest(ray, t_min, t_max, hit)
    }

    /// Any-hit traversal: see [`BvhRef::any_hit`].
    pub fn any_hit(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        hit: impl FnMut(usize) -> bool,
    ) -> bool {
        self.as_ref().any_hit(ray, t_min, t_max, hit)
    }

    /// Calls `visit(item)` for every item whose box holds `p` (and every unbounded item).
    pub fn for_each_containing(&self, p: DVec3, visit: impl FnMut(usize)) {
        self.as_ref().for_each_containing(p, visit)
    }
}

/// A BVH's flattened arrays, borrowed ([`Bvh`]'s, or a range of a flat solid's pools):
/// every query walks these and allocates nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhRef<'a> {
    /// The nodes, root first ([`Bvh::nodes`]).
    pub nodes: &'a [BvhNode],
    /// The same tree four boxes at a time ([`WideNode::build`]; empty: walked as a
    /// binary tree).
    pub wide: &'a [WideNode],
    /// Item indices in leaf order ([`Bvh::order`]).
    pub order: &'a [u32],
    /// The items' boxes in leaf order ([`Bvh::item_bounds`]).
    pub item_bounds: &'a [Aabb],
    /// Items with non-finite boxes ([`Bvh::unbounded`]).
    pub unbounded: &'a [u32],
}

impl BvhRef<'_> {
    /// The box of every finite item together.
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds)
    }

    /// Calls `visit(item)` for every item whose box the segment o + t·d, t ∈ [t_min,
    /// t_max], meets (and every unbounded item), nearer subtrees first.
    pub fn for_each_hit(&self, ray: &Ray, t_min: f64, t_max: f64, mut visit: impl FnMut(usize)) {
        self.nearest(ray, t_min, t_max, |i, _| {
            visit(i);
            None
        });
    }

    /// Whether the wide walk can test its boxes in AVX's four f64 lanes here: the tree
    /// has wide nodes and the CPU has AVX. A caller that calls [`Self::nearest_avx`]
    /// then — from a function of its own, compiled for AVX, so that its closure is
    /// inlined there and its other callers keep theirs in registers — gets the same
    /// offers, bit for bit (the lanes' arithmetic is SSE2's).
    pub fn has_avx_walk(&self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            !self.wide.is_empty() && std::arch::is_x86_feature_detected!("avx")
        }
        #[cfg(not(target_arch = "x86_64"))]
        false
    }

    /// [`Self::nearest`] with the wide nodes tested in AVX lanes ([`Self::has_avx_walk`]).
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    pub unsafe fn nearest_avx(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        hit: impl FnMut(usize, f64) -> Option<f64>,
    ) -> Option<(usize, f64)> {
        self.nearest_with::<wide::Avx>(ray, t_min, t_max, hit)
    }

    /// Closest-hit traversal: `hit(item, t_max)` returns the item's hit parameter if it
    /// has one below the current `t_max`, which then shrinks to it, so farther subtrees
    /// are skipped. Returns the nearest (item, t) found. Unbounded items go first.
    pub fn nearest(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        hit: impl FnMut(usize, f64) -> Option<f64>,
    ) -> Option<(usize, f64)> {
        self.nearest_with::<WideLanes>(ray, t_min, t_max, hit)
    }

    /// [`Self::nearest`] with the wide nodes tested in lanes `L`.
    #[inline(always)]
    fn nearest_with<L: wide::Lanes>(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        mut hit: impl FnMut(usize, f64) -> Option<f64>,
    ) -> Option<(usize, f64)> {
        let mut best = None;
        self.walk::<L>(ray, t_min, t_max, |i, t_max| {
            if let Some(t) = hit(i as usize, *t_max) {
                if t <= *t_max {
                    *t_max = t;
                    best = Some((i as usize, t));
                }
            }
            false
        });
        best
    }

    /// Any-hit traversal (shadow rays): whether `hit(item)` holds for some item whose box
    /// the segment meets; stops at the first that does.
    pub fn any_hit(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        mut hit: impl FnMut(usize) -> bool,
    ) -> bool {
        let mut found = false;
        self.walk::<WideLanes>(ray, t_min, t_max, |i, _| {
            found = hit(i as usize);
            found
        });
        found
    }

    /// The traversal both queries share: `offer(item, &mut t_max)` for each item met,
    /// nearer subtrees first, unbounded items before all; it may shrink t_max, and
    /// stops the walk by returning true. Four boxes at a time where the tree has its
    /// wide nodes and the ray a finite slab (the same offers, bit for bit: `bvh/wide.rs`).
    #[inline(always)]
    fn walk<L: wide::Lanes>(
        &self,
        ray: &Ray,
        t_min: f64,
        mut t_max: f64,
        mut offer: impl FnMut(u32, &mut f64) -> bool,
    ) {
        for &i in self.unbounded {
            if offer(i, &mut t_max) {
                return;
            }
        }
        if self.nodes.is_empty() {
            return;
        }
        let slab = Slab::new(ray);
        if self.wide.is_empty() || !slab.finite {
            self.walk_binary(&slab, t_min, t_max, offer)
        } else {
            self.walk_wide::<L>(&slab, t_min, t_max, &mut offer)
        }
    }

    /// The finite items' part of [`Self::walk`] over the binary nodes (at least one),
    /// one box at a time.
    #[inline(always)]
    fn walk_binary(
        &self,
        slab: &Slab,
        t_min: f64,
        mut t_max: f64,
        mut offer: impl FnMut(u32, &mut f64) -> bool,
    ) {
        let neg = slab.neg;
        let mut stack = Stack::new();
        let mut cur = 0usize;
        loop {
            let node = &self.nodes[cur];
            if slab.enter(&node.bounds, t_min, t_max).is_some() {
                if node.count > 0 {
                    let s = node.offset as usize;
                    for k in s..s + node.count as usize {
                        if slab.enter(&self.item_bounds[k], t_min, t_max).is_some()
                            && offer(self.order[k], &mut t_max)
                        {
                            return;
                        }
                    }
                } else {
                    let (first, second) = (cur + 1, node.offset as usize);
                    let (near, far) = if neg[node.axis as usize] {
                        (second, first)
                    } else {
                        (first, second)
                    };
                    stack.push(far as u32);
                    cur = near;
                    continue;
                }
            }
            let Some(next) = stack.pop() else {
                return;
            };
            cur = next;
        }
    }

    /// The GPU's walk (GPU.md §6.1): calls `visit(item)` for every unbounded item, then
    /// for every item whose box, and every ancestor's box, rounded outward to f32
    /// ([`Aabb::outward_f32`]) meets o + t·d for t ∈ [t0, t1] by the f32 slab test
    /// ([`slab_f32`], `inv` = 1/d), in pre-order: first child before second, so items come
    /// in ascending leaf position, the order the WGSL kernel's escape-index walk yields.
    pub fn for_each_hit_f32(
        &self,
        o: [f32; 3],
        inv: [f32; 3],
        t0: f32,
        t1: f32,
        mut visit: impl FnMut(usize),
    ) {
        for &i in self.unbounded {
            visit(i as usize);
        }
        if self.nodes.is_empty() {
            return;
        }
        let meets = |b: &Aabb| {
            let (lo, hi) = b.outward_f32();
            slab_f32(lo, hi, o, inv, t0, t1).is_some()
        };
        let mut stack = Stack::new();
        let mut cur = 0usize;
        loop {
            let node = &self.nodes[cur];
            if meets(&node.bounds) {
                if node.count > 0 {
                    let s = node.offset as usize;
                    for k in s..s + node.count as usize {
                        if meets(&self.item_bounds[k]) {
                            visit(self.order[k] as usize);
                        }
                    }
                } else {
                    stack.push(node.offset);
                    cur += 1;
                    continue;
                }
            }
            let Some(next) = stack.pop() else {
                return;
            };
            cur = next;
        }
    }

    /// Calls `visit(item)` for every item whose box holds `p` (and every unbounded item).
    pub fn for_each_containing(&self, p: DVec3, mut visit: impl FnMut(usize)) {
        for &i in self.unbounded {
            visit(i as usize);
        }
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = Stack::new();
        let mut cur = 0usize;
        loop {
            let node = &self.nodes[cur];
            if node.bounds.contains(p) {
                if node.count > 0 {
                    let s = node.offset as usize;
                    for k in s..s + node.count as usize {
                        if self.item_bounds[k].contains(p) {
                            visit(self.order[k] as usize);
                        }
                    }
                } else {
                    stack.push(node.offset);
                    cur += 1;
                    continue;
                }
            }
            let Some(next) = stack.pop() else {
                return;
            };
            cur = next;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    pub(super) fn random_boxes(rng: &mut Pcg64, n: usize) -> Vec<Aabb> {
        (0..n)
            .map(|_| {
                let c = DVec3::new(
                    rng.gen_range(-5.0..5.0),
                    rng.gen_range(-5.0..5.0),
                    rng.gen_range(-5.0..5.0),
                );
                let h = DVec3::new(
                    rng.gen_range(0.0..0.4),
                    rng.gen_range(0.0..0.4),
                    rng.gen_range(0.0..0.4),
                );
                Aabb::new(c - h, c + h)
            })
            .collect()
    }

    /// A ray from [-8, 8]³ in a direction from [-1, 1]³, parallel to the xz plane with
    /// probability `parallel` (axis-parallel slabs: 1/d = ∞).
    pub(super) fn random_ray(rng: &mut Pcg64, parallel: f64) -> Ray {
        let o = DVec3::new(
            rng.gen_range(-8.0..8.0),
            rng.gen_range(-8.0..8.0),
            rng.gen_range(-8.0..8.0),
        );
        let mut d = DVec3::new(
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        );
        if rng.gen_bool(parallel) {
            d.y = 0.0;
        }
        Ray::new(o, d)
    }

    /// The brute-force answer: every box the segment meets.
    fn brute(boxes: &[Aabb], ray: &Ray, t0: f64, t1: f64) -> Vec<u32> {
        let slab = Slab::new(ray);
        (0..boxes.len() as u32)
            .filter(|&i| {
                !boxes[i as usize].is_empty() && slab.enter(&boxes[i as usize], t0, t1).is_some()
            })
            .collect()
    }

    /// The SSE2 slab test gives the scalar one's answer bit for bit: 200 000 random
    /// boxes (some flat, some with a face through the origin) against random rays of
    /// either direction along each axis and random segments (±0 included).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn sse2_slab_equals_the_scalar_one() {
        let mut rng = Pcg64::seed_from_u64(21);
        let bits = |r: Option<f64>| r.map(f64::to_bits);
        for k in 0..200_000 {
            let a = DVec3::new(rng.gen_range(-2.0..2.0), rng.gen_range(-2.0..2.0), 0.0);
            let e = DVec3::new(rng.gen_range(0.0..1.0), rng.gen_range(0.0..1.0), 1.0);
            let e = if k % 5 == 0 { e.with_x(0.0) } else { e };
            let b = Aabb::new(a, a + e);
            // Origins on a face's plane make a parameter ±0, where ties with t0 = ±0
            // show which operand each comparison keeps.
            let mut o = DVec3::new(rng.gen_range(-2.0..2.0), rng.gen_range(-2.0..2.0), 0.5);
            match k % 4 {
                0 => o.x = a.x,
                1 => o.y = b.hi.y,
                2 => o.z = 0.0,
                _ => {}
            }
            let d = DVec3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            );
            let slab = Slab::new(&Ray::new(o, d));
            if !slab.finite {
                continue;
            }
            let (t0, t1) = match k % 6 {
                0 | 3 => (0.0, f64::INFINITY),
                1 => (-0.0, rng.gen_range(0.0..3.0)),
                4 => (rng.gen_range(-1.0..0.0), 0.0),
                5 => (rng.gen_range(-1.0..0.0), -0.0),
                _ => (rng.gen_range(-1.0..1.0), rng.gen_range(0.0..3.0)),
            };
            assert_eq!(
                bits(slab.enter_sse2(&b, t0, t1)),
                bits(slab.enter_scalar(&b, t0, t1)),
                "{o} {d} {b:?} {t0} {t1}"
            );
        }
    }

    #[test]
    fn ray_queries_match_brute_force() {
        let mut rng = Pcg64::seed_from_u64(11);
        for n in [0, 1, 3, 17, 500, 3000] {
            let mut boxes = random_boxes(&mut rng, n);
            if n > 3 {
                boxes[1] = Aabb::EVERYTHING;
                boxes[2] = Aabb::EMPTY;
                // Many boxes with the same centre exercise the degenerate split.
                for b in boxes.iter_mut().skip(3).take(40) {
                    *b = Aabb::new(DVec3::splat(1.0), DVec3::splat(1.5));
                }
            }
            let bvh = Bvh::new(&boxes);
            for _ in 0..300 {
                let ray = random_ray(&mut rng, 0.2);
                let (t0, t1) = (
                    rng.gen_range(-2.0..5.0),
                    if rng.gen_bool(0.3) {
                        f64::INFINITY
                    } else {
                        rng.gen_range(5.0..20.0)
                    },
                );
                let mut got = Vec::new();
                bvh.collect(&ray, t0, t1, &mut got);
                got.sort_unstable();
                let want = brute(&boxes, &ray, t0, t1);
                assert_eq!(got, want, "n={n}");
                // Any-hit for "an odd item": the same answer, and nothing offered once
                // one held.
                let (mut held, mut late) = (false, 0);
                let any = bvh.any_hit(&ray, t0, t1, |i| {
                    late += usize::from(held);
                    held |= i % 2 == 1;
                    i % 2 == 1
                });
                assert_eq!(any, want.iter().any(|i| i % 2 == 1), "n={n}");
                assert_eq!(late, 0, "n={n}");
            }
            for _ in 0..100 {
                let p = DVec3::new(
                    rng.gen_range(-6.0..6.0),
                    rng.gen_range(-6.0..6.0),
                    rng.gen_range(-6.0..6.0),
                );
                let mut got = Vec::new();
                bvh.for_each_containing(p, |i| got.push(i as u32));
                got.sort_unstable();
                let want: Vec<u32> = (0..n as u32)
                    .filter(|&i| boxes[i as usize].contains(p))
                    .collect();
                assert_eq!(got, want);
            }
        }
    }

    #[test]
    fn nearest_returns_the_closest_item_hit() {
        // Unit cubes along +x; the "hit" of a box is its entry parameter.
        let boxes: Vec<Aabb> = (0..200)
            .map(|k| {
                let c = DVec3::new(3.0 * k as f64, 0.0, 0.0);
                Aabb::new(c - DVec3::splat(0.5), c + DVec3::splat(0.5))
            })
            .collect();
        let bvh = Bvh::new(&boxes);
        let bx = &boxes;
        let slab_hit = |ray: Ray| {
            let slab = Slab::new(&ray);
            move |i: usize, t_max: f64| slab.enter(&bx[i], 0.0, t_max)
        };
        let ray = Ray::new(DVec3::new(100.0, 0.1, 0.2), DVec3::X);
        let mut tested = 0;
        let hit = slab_hit(ray);
        let (i, t) = bvh
            .nearest(&ray, 0.0, f64::INFINITY, |i, tm| {
                tested += 1;
                hit(i, tm)
            })
            .unwrap();
        assert_eq!(i, 34);
        assert!((t - (101.5 - 100.0)).abs() < 1e-12);
        // Front-to-back order with shrinking t_max tests only a few items.
        assert!(tested < 10, "{tested} items tested");
        let back = Ray::new(DVec3::new(100.0, 0.1, 0.2), -DVec3::X);
        let hit = slab_hit(back);
        assert_eq!(bvh.nearest(&back, 0.0, f64::INFINITY, hit).unwrap().0, 33);
    }

    #[test]
    fn tree_is_well_formed() {
        let mut rng = Pcg64::seed_from_u64(12);
        let boxes = random_boxes(&mut rng, 4096);
        let bvh = Bvh::new(&boxes);
        let mut seen = vec![false; boxes.len()];
        for node in bvh.nodes() {
            if node.count > 0 {
                let s = node.offset as usize;
                for k in s..s + node.count as usize {
                    let i = bvh.order()[k] as usize;
                    assert!(!seen[i]);
                    seen[i] = true;
                    assert_eq!(node.bounds.union(&boxes[i]), node.bounds);
                    assert_eq!(bvh.item_bounds()[k], boxes[i]);
                }
            }
        }
        assert!(seen.iter().all(|&s| s));
        // SAH keeps it shallow: far fewer nodes than items, leaves of ≤ 16 items.
        assert!(bvh.nodes().len() < boxes.len());
        assert!(bvh.nodes().iter().all(|n| n.count as usize <= 4 * MAX_LEAF));
    }
}
