//! A BVH walked in ray order: items by the parameter at which the segment enters their
//! box, so that a caller which stops early (a first-hit scan) never opens the boxes
//! behind its answer. Pending nodes and items wait in a binary min-heap keyed by their
//! entry (the "ordered traversal" of Wald et al., "Interactive Rendering with Coherent
//! Ray Tracing", 2001, with a heap instead of a two-child sort, since the scan asks for
//! items up to a moving parameter rather than for the nearest hit).

use super::{BvhRef, Slab};
use crate::ray::Ray;
use std::mem::MaybeUninit;

/// Pending entries the heap holds; past it the walk reports [`EntryOrder::overflowed`]
/// and the caller falls back to an unordered query. 256 × 16 bytes of stack.
const HEAP: usize = 256;

/// Tags of heap entries: an item's leaf position with this bit set, else a node index.
const ITEM: u32 = 1 << 31;

/// The items whose box the segment o + t·d, t ∈ [lo, hi], meets, in ascending order of
/// entry parameter (unbounded items first, entering at lo), handed out on demand by
/// [`next_before`](Self::next_before).
pub struct EntryOrder<'a> {
    bvh: BvhRef<'a>,
    slab: Slab,
    lo: f64,
    hi: f64,
    unbounded: usize,
    heap: [MaybeUninit<(f64, u32)>; HEAP],
    len: usize,
    overflowed: bool,
}

impl<'a> EntryOrder<'a> {
    /// The walk of `bvh` along `ray` over [lo, hi]; nothing is visited yet.
    pub fn new(bvh: BvhRef<'a>, ray: &Ray, lo: f64, hi: f64) -> Self {
        let mut walk = Self {
            bvh,
            slab: Slab::new(ray),
            lo,
            hi,
            unbounded: 0,
            heap: [const { MaybeUninit::uninit() }; HEAP],
            len: 0,
            overflowed: false,
        };
        if let Some(root) = bvh.nodes.first() {
            if let Some(t) = walk.slab.enter(&root.bounds, lo, hi) {
                walk.push(t, 0);
            }
        }
        walk
    }

    /// Whether the heap ran out of room: the walk may then have lost items, and the
    /// caller must not trust it.
    pub fn overflowed(&self) -> bool {
        self.overflowed
    }

    /// The next item (in entry order) whose box the segment enters at or before
    /// `limit`, or None when every remaining one enters after it. Later calls may pass
    /// a larger limit and continue.
    pub fn next_before(&mut self, limit: f64) -> Option<usize> {
        if let Some(&i) = self.bvh.unbounded.get(self.unbounded) {
            self.unbounded += 1;
            return Some(i as usize);
        }
        loop {
            if self.len == 0 || self.top().0 > limit {
                return None;
            }
            let (_, tag) = self.pop();
            if tag & ITEM != 0 {
                return Some(self.bvh.order[(tag & !ITEM) as usize] as usize);
            }
            let node = &self.bvh.nodes[tag as usize];
            if node.count > 0 {
                let s = node.offset as usize;
                for k in s..s + node.count as usize {
                    if let Some(t) = self.slab.enter(&self.bvh.item_bounds[k], self.lo, self.hi) {
                        self.push(t, k as u32 | ITEM);
                    }
                }
            } else {
                for child in [tag + 1, node.offset] {
                    let b = &self.bvh.nodes[child as usize].bounds;
                    if let Some(t) = self.slab.enter(b, self.lo, self.hi) {
                        self.push(t, child);
                    }
                }
            }
        }
    }

    #[inline]
    fn at(&self, k: usize) -> (f64, u32) {
        // SAFETY: slots below `len` were written by `push` or moved there by `pop`.
        unsafe { self.heap[k].assume_init() }
    }

    #[inline]
    fn top(&self) -> (f64, u32) {
        self.at(0)
    }

    fn push(&mut self, t: f64, tag: u32) {
        if self.len == HEAP {
            self.overflowed = true;
            return;
        }
        let mut k = self.len;
        self.len += 1;
        while k > 0 {
            let parent = (k - 1) / 2;
            let p = self.at(parent);
            if p.0 <= t {
                break;
            }
            self.heap[k] = MaybeUninit::new(p);
            k = parent;
        }
        self.heap[k] = MaybeUninit::new((t, tag));
    }

    fn pop(&mut self) -> (f64, u32) {
        let top = self.top();
        self.len -= 1;
        let last = self.at(self.len);
        let n = self.len;
        let mut k = 0;
        loop {
            let mut c = 2 * k + 1;
            if c >= n {
                break;
            }
            if c + 1 < n && self.at(c + 1).0 < self.at(c).0 {
                c += 1;
            }
            let child = self.at(c);
            if child.0 >= last.0 {
                break;
            }
            self.heap[k] = MaybeUninit::new(child);
            k = c;
        }
        if n > 0 {
            self.heap[k] = MaybeUninit::new(last);
        }
        top
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

    /// Every item the unordered query reports comes out once, in ascending entry order,
    /// and a limit holds back exactly the items entering after it.
    #[test]
    fn items_come_in_entry_order() {
        let mut rng = Pcg64::seed_from_u64(5);
        let mut boxes: Vec<Aabb> = (0..300)
            .map(|_| {
                let c = DVec3::new(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                );
                let r = DVec3::splat(rng.gen_range(0.01..0.2));
                Aabb::new(c - r, c + r)
            })
            .collect();
        boxes.push(Aabb::EVERYTHING);
        let bvh = Bvh::new(&boxes);
        for k in 0..200 {
            let o = DVec3::new(3.0 * (k as f64).cos(), 0.5, 3.0 * (k as f64).sin());
            let d = DVec3::new(rng.gen_range(-0.3..0.3), rng.gen_range(-0.3..0.3), 0.0) - o;
            let ray = Ray::new(o, d);
            let (lo, hi) = (0.2, 1.5);
            let mut want = Vec::new();
            bvh.for_each_hit(&ray, lo, hi, |i| want.push(i));
            let limit = 0.6;
            let mut walk = EntryOrder::new(bvh.as_ref(), &ray, lo, hi);
            let mut got = Vec::new();
            while let Some(i) = walk.next_before(limit) {
                got.push(i);
            }
            let early = got.len();
            while let Some(i) = walk.next_before(f64::INFINITY) {
                got.push(i);
            }
            assert!(!walk.overflowed());
            let entry = |i: usize| boxes[i].clip(&ray, lo, hi).map_or(lo, |r| r.0);
            assert!(
                got[1..].windows(2).all(|w| entry(w[0]) <= entry(w[1])),
                "ray {k}"
            );
            assert!(got[..early].iter().all(|&i| entry(i) <= limit));
            assert!(got[early..].iter().all(|&i| entry(i) > limit));
            got.sort_unstable();
            want.sort_unstable();
            assert_eq!(got, want, "ray {k}");
        }
    }
}
