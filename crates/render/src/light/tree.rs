//! A light BVH: light selection ∝ importance at the shading point in O(log n) per draw
//! and per pmf (Conty Estevez & Kulla 2018; pbrt-v4's `BVHLightSampler`, §12.6.3).
//!
//! Every node bounds its lights by a bounding sphere, a cone of normals and their total
//! power; a draw descends from the root, choosing each child with probability ∝ its
//! [`importance_of`] at the shading point (p, n), and the pmf of a light is the product
//! of the probabilities along its path, which every light keeps as a bit trail. The same
//! importance bounds the single lights of `light-spatial` (which sums it over every light,
//! O(n)): with one light per leaf and both children's importances exact, the two agree
//! wherever only two lights compete.
//!
//! The tree is built by median splits of the lights' centres along the widest axis of
//! their bounds (pbrt-v4 splits by a surface-area-orientation cost; a median split keeps
//! the depth at ⌈log₂ n⌉, which bounds the trail to 64 levels for any count).

use super::importance_pair::importance_pair;
use super::select::{importance_of, ImportanceBounds};
use crate::distribution::ONE_MINUS_EPSILON;
use glam::DVec3;

/// One node: its bounds and power, and its children or its light.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: ImportanceBounds,
    /// Σ luminance of power of the lights below.
    phi: f64,
    /// Leaf: the light's index. Inner node: the second child's index (the first child
    /// follows its parent).
    index: u32,
    leaf: bool,
}

/// A light BVH over the area lights (module docs).
#[derive(Clone, Debug)]
pub struct LightTree {
    /// Unique per tree built (clones share it: they are equal), for [`Memo`].
    id: u64,
    nodes: Vec<Node>,
    /// Per light: the path from the root to its leaf, bit d set where it takes the second
    /// child at depth d, and the path's length.
    trails: Vec<(u64, u8)>,
}

impl LightTree {
    /// The tree over lights given by their importance bounds and the luminance of their
    /// power; None without a light.
    pub fn new(lights: &[(ImportanceBounds, f64)]) -> Option<LightTree> {
        if lights.is_empty() {
            return None;
        }
        static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let mut tree = LightTree {
            id: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            nodes: Vec::with_capacity(2 * lights.len()),
            trails: vec![(0, 0); lights.len()],
        };
        let mut order: Vec<usize> = (0..lights.len()).collect();
        tree.build(lights, &mut order, 0, 0);
        Some(tree)
    }

    /// Builds the subtree over `order` at depth `depth` with trail `trail`; returns its
    /// node index.
    fn build(
        &mut self,
        lights: &[(ImportanceBounds, f64)],
        order: &mut [usize],
        trail: u64,
        depth: u8,
    ) -> usize {
        let at = self.nodes.len();
        if let [k] = order {
            let (bounds, phi) = lights[*k];
            self.trails[*k] = (trail, depth);
            self.nodes.push(Node {
                bounds,
                phi,
                index: *k as u32,
                leaf: true,
            });
            return at;
        }
        // Median split along the widest axis of the centres (ties by index: the tree does
        // not depend on the sort's stability).
        let (lo, hi) = order.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &k| (lo.min(lights[k].0.center), hi.max(lights[k].0.center)),
        );
        let axis = (hi - lo).max_position();
        order.sort_by(|&a, &b| {
            let (ca, cb) = (lights[a].0.center[axis], lights[b].0.center[axis]);
            ca.total_cmp(&cb).then(a.cmp(&b))
        });
        let mid = order.len() / 2;
        self.nodes.push(Node {
            bounds: lights[order[0]].0,
            phi: 0.0,
            index: 0,
            leaf: false,
        });
        let (first, second) = order.split_at_mut(mid);
        let a = self.build(lights, first, trail, depth + 1);
        let b = self.build(lights, second, trail | 1 << depth, depth + 1);
        let (na, nb) = (self.nodes[a], self.nodes[b]);
        self.nodes[at] = Node {
            bounds: union(&na.bounds, &nb.bounds),
            phi: na.phi + nb.phi,
            index: b as u32,
            leaf: false,
        };
        at
    }

    /// The importance of node `i` at (p, n).
    #[inline]
    fn importance(&self, i: usize, p: DVec3, n: DVec3) -> f64 {
        let node = &self.nodes[i];
        importance_of(&node.bounds, node.phi, p, n)
    }

    /// The probabilities of the two children of inner node `i` at (p, n); None where
    /// neither can shine on p.
    #[inline]
    fn split(&self, i: usize, p: DVec3, n: DVec3) -> Option<[f64; 2]> {
        let (a, b) = (
            &self.nodes[i + 1],
            &self.nodes[self.nodes[i].index as usize],
        );
        let [wa, wb] = importance_pair((&a.bounds, a.phi), (&b.bounds, b.phi), p, n);
        let total = wa + wb;
        (total > 0.0 && total.is_finite()).then(|| [wa / total, wb / total])
    }

    /// A light drawn with `u` ∈ [0, 1) and its probability; None where no light can
    /// shine on (p, n).
    pub fn sample(&self, p: DVec3, n: DVec3, u: f64) -> Option<(usize, f64)> {
        MEMO.with_borrow_mut(|memo| {
            memo.start(self.id, p, n);
            let (mut i, mut u, mut pmf) = (0, u, 1.0);
            loop {
                let node = &self.nodes[i];
                if node.leaf {
                    // Below a split the leaf's importance is its branch's share, bit for
                    // bit (`importance_pair`): a branch taken has a positive one.
                    let shines = i != 0 || self.importance(i, p, n) > 0.0;
                    return shines.then_some((node.index as usize, pmf));
                }
                let [pa, pb] = memo.split(i, || self.split(i, p, n))?;
                if u < pa {
                    (u, pmf, i) = ((u / pa).min(ONE_MINUS_EPSILON), pmf * pa, i + 1);
                } else {
                    let next = node.index as usize;
                    (u, pmf, i) = (((u - pa) / pb).min(ONE_MINUS_EPSILON), pmf * pb, next);
                }
            }
        })
    }

    /// The probability that [`LightTree::sample`] draws light `k` at (p, n): the product
    /// of the same branch probabilities, bit for bit.
    pub fn pmf(&self, p: DVec3, n: DVec3, k: usize) -> f64 {
        let Some(&(trail, depth)) = self.trails.get(k) else {
            return 0.0;
        };
        MEMO.with_borrow_mut(|memo| {
            memo.start(self.id, p, n);
            let (mut i, mut pmf) = (0, 1.0);
            for d in 0..depth as usize {
                let Some([pa, pb]) = memo.split(i, || self.split(i, p, n)) else {
                    return 0.0;
                };
                if trail >> d & 1 == 0 {
                    (pmf, i) = (pmf * pa, i + 1);
                } else {
                    (pmf, i) = (pmf * pb, self.nodes[i].index as usize);
                }
            }
            // Below a split, a leaf of zero importance has a zero branch probability,
            // so `pmf` is 0 already; only a lone leaf (the root) needs the test.
            if depth > 0 || self.importance(i, p, n) > 0.0 {
                pmf
            } else {
                0.0
            }
        })
    }
}

impl LightTree {
    /// The tree as another back end reads it: the same nodes in the same order, and the
    /// lights' trails ([`state::LightTreeTable`]).
    pub fn table(&self) -> state::LightTreeTable {
        let nodes = self
            .nodes
            .iter()
            .map(|node| {
                let b = &node.bounds;
                state::LightTreeNode {
                    bounds: state::LightBounds {
                        center: b.center,
                        radius: b.radius,
                        axis: b.axis,
                        cos_o: b.cos_o,
                        two_sided: b.two_sided,
                        power: node.phi,
                    },
                    index: node.index,
                    leaf: node.leaf,
                }
            })
            .collect();
        state::LightTreeTable {
            nodes,
            trails: self.trails.clone(),
        }
    }
}

/// The branch probabilities of the nodes a thread visited in one tree at one shading
/// point, by node (a direct-mapped cache of [`MEMO_SLOTS`] entries). The draws at a
/// vertex descend the same tree from the same point many times — a light technique's
/// draw, then the pmf of the light it drew, and of the lights each other draw's direction
/// crosses — and their paths share their first levels or more: those nodes' importances
/// are evaluated once. The values are the ones the descent would compute, so results are
/// bit for bit the same.
struct Memo {
    /// The tree ([`LightTree`]'s id) and the point (p, n, as bits) the entries hold for.
    key: (u64, [u64; 6]),
    /// The entries' generation: entries of another generation are stale.
    generation: u32,
    /// Per slot: (generation, node, split).
    slots: [(u32, u32, Option<[f64; 2]>); MEMO_SLOTS],
}

/// Entries of [`Memo`] (a power of two: a node's slot is its index modulo it).
const MEMO_SLOTS: usize = 256;

thread_local! {
    static MEMO: std::cell::RefCell<Memo> = const {
        std::cell::RefCell::new(Memo {
            key: (u64::MAX, [0; 6]),
            generation: 1,
            slots: [(0, 0, None); MEMO_SLOTS],
        })
    };
}

impl Memo {
    /// Keeps the entries if they are for this tree and point; else forgets them.
    #[inline]
    fn start(&mut self, tree: u64, p: DVec3, n: DVec3) {
        let key = (tree, [p.x, p.y, p.z, n.x, n.y, n.z].map(f64::to_bits));
        if self.key != key {
            self.key = key;
            self.generation = self.generation.wrapping_add(1);
            if self.generation == 0 {
                // Wrapped: no entry may look current.
                self.slots = [(0, 0, None); MEMO_SLOTS];
                self.generation = 1;
            }
        }
    }

    /// The split at node `node`: the entry where it holds it, else `compute`'s, recorded.
    #[inline]
    fn split(
        &mut self,
        node: usize,
        compute: impl FnOnce() -> Option<[f64; 2]>,
    ) -> Option<[f64; 2]> {
        let slot = &mut self.slots[node % MEMO_SLOTS];
        if slot.0 == self.generation && slot.1 == node as u32 {
            return slot.2;
        }
        let s = compute();
        *slot = (self.generation, node as u32, s);
        s
    }
}

/// Bounds of two nodes together: the sphere around both spheres, the cone around both
/// cones (pbrt-v4 `DirectionCone::Union`), two-sided if either is.
fn union(a: &ImportanceBounds, b: &ImportanceBounds) -> ImportanceBounds {
    let (center, radius) = sphere_union(a.center, a.radius, b.center, b.radius);
    let (axis, cos_o) = cone_union(a.axis, a.cos_o, b.axis, b.cos_o);
    ImportanceBounds {
        center,
        radius,
        axis,
        cos_o,
        two_sided: a.two_sided || b.two_sided,
    }
}

/// The smallest sphere around two spheres.
fn sphere_union(ca: DVec3, ra: f64, cb: DVec3, rb: f64) -> (DVec3, f64) {
    let d = (cb - ca).length();
    if d + rb <= ra {
        return (ca, ra);
    }
    if d + ra <= rb {
        return (cb, rb);
    }
    let r = (d + ra + rb) / 2.0;
    // Grown by a few ulps: the enclosure must hold after rounding.
    let c = ca + (cb - ca) * ((r - ra) / d);
    (c, r * (1.0 + 4.0 * f64::EPSILON))
}

/// The cone around two cones given by axis and cos of half-angle (pbrt-v4
/// `DirectionCone::Union`).
fn cone_union(wa: DVec3, cos_a: f64, wb: DVec3, cos_b: f64) -> (DVec3, f64) {
    let theta_a = cos_a.clamp(-1.0, 1.0).acos();
    let theta_b = cos_b.clamp(-1.0, 1.0).acos();
    let theta_d = angle_between(wa, wb);
    if (theta_d + theta_b).min(std::f64::consts::PI) <= theta_a {
        return (wa, cos_a);
    }
    if (theta_d + theta_a).min(std::f64::consts::PI) <= theta_b {
        return (wb, cos_b);
    }
    let theta_o = (theta_a + theta_d + theta_b) / 2.0;
    if theta_o >= std::f64::consts::PI {
        return (wa, -1.0);
    }
    let theta_r = theta_o - theta_a;
    let wr = wa.cross(wb);
    if wr.length_squared() == 0.0 {
        return (wa, -1.0);
    }
    // wa rotated by θr about wr (Rodrigues; wr ⟂ wa).
    let k = wr.normalize();
    let w = wa * theta_r.cos() + k.cross(wa) * theta_r.sin();
    // Widened by a little: the enclosure must hold after rounding.
    (
        w.normalize(),
        (theta_o + 1e-9).min(std::f64::consts::PI).cos(),
    )
}

/// The angle between two unit vectors, accurate near 0 and π (pbrt-v4 `AngleBetween`).
fn angle_between(a: DVec3, b: DVec3) -> f64 {
    if a.dot(b) < 0.0 {
        std::f64::consts::PI - 2.0 * ((a + b).length() / 2.0).clamp(-1.0, 1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).clamp(-1.0, 1.0).asin()
    }
}

#[cfg(test)]
mod tests;
