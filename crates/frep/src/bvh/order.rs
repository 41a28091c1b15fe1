//! A BVH walked in ray order, for a caller that stops early (the perturbed quadric's
//! first-crossing scan): it asks for every item whose box the ray enters before some
//! parameter, and never opens the boxes that enter after it. A best-first walk: pending
//! nodes and items wait in a queue sorted by their entry parameter; a node whose nearer
//! child already enters before the limit descends into it directly.
//!
//! The queue is an array kept in descending order, popped from its end and filled by
//! insertion from the end. Pending entries are few (the front of the walk), and an
//! insertion has one unpredictable branch where a binary heap's sifts have several:
//! over the perturbed benchmark at 4096 perturbations, fewer mispredicted branches and
//! instructions than the heap (measured in
//! docs/notebook/2026-12-02-cpu-speed-round-9-perturbed-walk-and-scene-loading.md).

use super::{BvhRef, Slab};
use crate::fixed::Fixed;
use crate::ray::{Aabb, Ray};

/// Pending entries the queue holds; past it the walk reports [`EntryOrder::overflowed`]
/// and the caller falls back to an unordered query. 256 × 16 bytes of stack.
const QUEUE: usize = 256;

/// The storage of an [`EntryOrder`]'s queue, which the caller keeps
/// ([`EntryOrder::queue`]): held by value, 4 KiB would be copied whenever the walk moves.
pub type Queue = Fixed<(f64, u32), QUEUE>;

/// Tags of queue entries: an item's leaf position with this bit set, else a node index.
const ITEM: u32 = 1 << 31;

/// The items whose box the segment o + t·d, t ∈ [lo, hi], meets, handed out on demand
/// by [`next_before`](Self::next_before) up to a limit on the entry parameter (unbounded
/// items first, entering at lo).
pub struct EntryOrder<'a, 'h> {
    bvh: BvhRef<'a>,
    slab: Slab,
    lo: f64,
    hi: f64,
    unbounded: usize,
    queue: &'h mut Queue,
    overflowed: bool,
}

impl<'a, 'h> EntryOrder<'a, 'h> {
    /// Empty storage for [`new`](Self::new) (never written before the walk uses it).
    pub const fn queue() -> Queue {
        Fixed::new()
    }

    /// The walk of `bvh` along `ray` over [lo, hi], keeping its queue in `queue`.
    pub fn new(bvh: BvhRef<'a>, ray: &Ray, lo: f64, hi: f64, queue: &'h mut Queue) -> Self {
        let slab = Slab::new(ray);
        queue.clear();
        let mut walk = Self {
            bvh,
            slab,
            lo,
            hi,
            unbounded: 0,
            queue,
            overflowed: false,
        };
        if let Some(root) = bvh.nodes.first() {
            if let Some(t) = walk.enter(&root.bounds) {
                walk.push(t, 0);
            }
        }
        walk
    }

    /// Whether the queue ran out of room: the walk may then have lost items, and the
    /// caller must not trust it.
    pub fn overflowed(&self) -> bool {
        self.overflowed
    }

    /// The next item whose box the segment enters at or before `limit`, or None when
    /// every remaining one enters after it; items come in entry order, except that a
    /// leaf's or subtree's items already known to enter before `limit` come at once.
    /// Later calls may pass a larger limit and continue.
    pub fn next_before(&mut self, limit: f64) -> Option<usize> {
        if let Some(&i) = self.bvh.unbounded.get(self.unbounded) {
            self.unbounded += 1;
            return Some(i as usize);
        }
        loop {
            if self.queue.is_empty() || self.top().0 > limit {
                return None;
            }
            let (_, mut tag) = self.pop();
            // Down the tree without a round trip through the queue while the nearer child
            // enters before `limit`; the farther waits in the queue.
            loop {
                if tag & ITEM != 0 {
                    return Some(self.bvh.order[(tag & !ITEM) as usize] as usize);
                }
                let node = &self.bvh.nodes[tag as usize];
                if node.count > 0 {
                    let s = node.offset as usize;
                    let mut first = None;
                    for k in s..s + node.count as usize {
                        if let Some(t) = self.enter(&self.bvh.item_bounds[k]) {
                            if first.is_none() && t <= limit {
                                first = Some(k);
                            } else {
                                self.push(t, k as u32 | ITEM);
                            }
                        }
                    }
                    match first {
                        Some(k) => return Some(self.bvh.order[k] as usize),
                        None => break,
                    }
                }
                let (a, b) = (tag + 1, node.offset);
                let ea = self.enter(&self.bvh.nodes[a as usize].bounds);
                let eb = self.enter(&self.bvh.nodes[b as usize].bounds);
                let (near, far) = match (ea, eb) {
                    (Some(x), Some(y)) if x <= y => ((x, a), Some((y, b))),
                    (Some(x), Some(y)) => ((y, b), Some((x, a))),
                    (Some(x), None) => ((x, a), None),
                    (None, Some(y)) => ((y, b), None),
                    (None, None) => break,
                };
                if let Some((t, c)) = far {
                    self.push(t, c);
                }
                if near.0 > limit {
                    self.push(near.0, near.1);
                    break;
                }
                tag = near.1;
            }
        }
    }

    /// [`Slab::enter`] over [lo, hi].
    #[inline(always)]
    fn enter(&self, b: &Aabb) -> Option<f64> {
        self.slab.enter(b, self.lo, self.hi)
    }

    /// The nearest pending entry (the queue must not be empty).
    #[inline]
    fn top(&self) -> (f64, u32) {
        self.queue.at(self.queue.len() - 1)
    }

    /// Queues an entry, after (popped before) those of equal parameter.
    #[inline]
    fn push(&mut self, t: f64, tag: u32) {
        if !self.queue.insert_from_back((t, tag), 0, |p| p.0 < t) {
            self.overflowed = true;
        }
    }

    /// Takes the nearest pending entry (the queue must not be empty).
    #[inline]
    fn pop(&mut self) -> (f64, u32) {
        self.queue.pop().expect("a pending entry")
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

    /// Every item the unordered query reports comes out once, and a limit holds back
    /// exactly the items entering after it.
    #[test]
    fn items_entering_before_the_limit_come_first() {
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
            let mut queue = EntryOrder::queue();
            let mut walk = EntryOrder::new(bvh.as_ref(), &ray, lo, hi, &mut queue);
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
            // Everything entering by the limit came before the first None; nothing after.
            assert!(got[early..].iter().all(|&i| entry(i) > limit), "ray {k}");
            assert!(want
                .iter()
                .all(|&i| entry(i) > limit || got[..early].contains(&i)));
            got.sort_unstable();
            want.sort_unstable();
            assert_eq!(got, want, "ray {k}");
        }
    }
}
