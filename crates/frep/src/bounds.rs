//! Bounding boxes of {F ≥ 0} for any expression, by interval octree refinement.
//!
//! A cell where the interval of F is wholly negative holds no part of the solid and is
//! dropped; the others are split until a depth limit, and the union of what remains is a
//! box guaranteed (up to the search domain) to hold the solid. The search is repeated
//! inside the box it found, which tightens it quickly for compact models.
//!
//! [`surface_bounds`] bounds the zero set {F = 0} instead (what a picture shows): cells
//! whose interval of F holds 0 are split to a fixed depth, and a deepest cell counts
//! where F changes sign among its corners and centre. Sampling, not intervals, decides
//! there because nested R-functions (`f1 + f2 + sqrt(f1² + f2²)`, HyperFun's `|`)
//! widen intervals so much that no cell of the search domain is ever proved empty.

use crate::expr::{
    eval_choices_lanes, eval_choices_nodes, eval_nodes, has_min_max, simplify_into_lane, Choice,
    Expr, Node, MAX_LANES,
};
use crate::interval::Interval;
use crate::lanes::Lanes;
use crate::ray::Aabb;
use glam::DVec3;

/// Boxes' bounds in one pass: eight, or four.
type Lanes8 = Lanes<Interval, 8>;
type Lanes4 = Lanes<Interval, 4>;

/// The evaluation scratch of the searches: one box, four and eight lanes, and the
/// octants' min/max choices (lane k: octant k).
#[derive(Default)]
struct Scratch {
    one: Vec<Interval>,
    four: Vec<Lanes4>,
    eight: Vec<Lanes8>,
    choices: Vec<[Choice; MAX_LANES]>,
    one_choices: Vec<Choice>,
}

impl Scratch {
    fn new(len: usize) -> Self {
        Self {
            one: Vec::with_capacity(len),
            ..Self::default()
        }
    }
}

/// The eight octants of `cell` (octant k lies on the high side of axis a where bit a of
/// k is set), with F's bound over those not inside `done`, found together in one pass
/// over `tape` in lanes ([`crate::lanes`]): every bound is the one-box evaluation's
/// bit for bit. The searches bound a cell's children together and then visit them one
/// by one as before, so what they find, and the budget they spend, are the same. An
/// octant inside `done` (which only grows) is skipped by its visit, so it is not
/// bounded; one the visit skips for another reason was bounded for nothing. With
/// `choices`, each bounded octant's min/max choices go to `scratch.choices`, in the
/// lane returned for it, for [`simplify_into_lane`].
fn octants(
    tape: &[Node],
    cell: &Aabb,
    done: &Aabb,
    scratch: &mut Scratch,
    choices: bool,
) -> ([Aabb; 8], [Option<(Interval, usize)>; 8]) {
    let c = cell.center();
    let subs: [Aabb; 8] = std::array::from_fn(|k| {
        let pick = |bit: usize, axis: usize| {
            if k >> bit & 1 == 0 {
                (cell.lo[axis], c[axis])
            } else {
                (c[axis], cell.hi[axis])
            }
        };
        let (x, y, z) = (pick(0, 0), pick(1, 1), pick(2, 2));
        Aabb::new(DVec3::new(x.0, y.0, z.0), DVec3::new(x.1, y.1, z.1))
    });
    let inside = |b: &Aabb| done.lo.cmple(b.lo).all() && done.hi.cmpge(b.hi).all();
    let (mut wanted, mut n) = ([0usize; 8], 0);
    for k in (0..8).filter(|&k| !inside(&subs[k])) {
        wanted[n] = k;
        n += 1;
    }
    let want = &wanted[..n];
    let mut v = [None; 8];
    // Coordinate k of the j-th box wanted (lanes past them repeat the last one).
    let axis = |k: usize| {
        move |j: usize| {
            let b = subs[want[j.min(want.len() - 1)]];
            Interval::new(b.lo[k], b.hi[k])
        }
    };
    macro_rules! in_lanes {
        ($lanes:ident, $scratch:expr) => {{
            let i = |k: usize| $lanes::new(std::array::from_fn(axis(k)));
            let r = match choices {
                true => {
                    let (x, y, z) = (i(0), i(1), i(2));
                    eval_choices_lanes(tape, x, y, z, $scratch, &mut scratch.choices)
                }
                false => eval_nodes(tape, i(0), i(1), i(2), $scratch),
            };
            for (j, &k) in want.iter().enumerate() {
                v[k] = Some((r.lane(j), j));
            }
        }};
    }
    match want.len() {
        5.. if !lanes_off() => in_lanes!(Lanes8, &mut scratch.eight),
        2.. if !lanes_off() => in_lanes!(Lanes4, &mut scratch.four),
        _ => {
            if choices {
                scratch.choices.clear();
                scratch
                    .choices
                    .resize(tape.len(), [Choice::Both; MAX_LANES]);
            }
            for (j, &k) in want.iter().enumerate() {
                let i = |a: usize| axis(a)(j);
                let (x, y, z) = (i(0), i(1), i(2));
                let r = match choices {
                    true => {
                        let one = &mut scratch.one_choices;
                        let r = eval_choices_nodes(tape, x, y, z, &mut scratch.one, one);
                        for (row, &c) in scratch.choices.iter_mut().zip(one.iter()) {
                            row[j] = c;
                        }
                        r
                    }
                    false => eval_nodes(tape, x, y, z, &mut scratch.one),
                };
                v[k] = Some((r, j));
            }
        }
    }
    (subs, v)
}

/// Whether the searches bound octants one by one over the whole tape, as before lanes
/// and simplification (the tests' reference).
fn lanes_off() -> bool {
    #[cfg(test)]
    return tests::ONE_BY_ONE.get();
    #[cfg(not(test))]
    false
}

/// The box searched when a model declares none: HyperFun and Fidget models live well
/// inside it; anything that reaches its faces is clipped to it.
pub const DEFAULT_DOMAIN: f64 = 100.0;

/// A box holding every point of `domain` where F ≥ 0 (empty if there is none).
pub fn expr_bounds(expr: &Expr, domain: Aabb) -> Aabb {
    let mut scratch = Scratch::new(expr.len());
    // The tapes of the cells being searched, the whole one first: each cell's tape is
    // its parent's simplified over it ([`crate::expr::simplify_into`]), which gives the
    // same bounds there (a min or max decided over a box is decided over its parts).
    let mut arena = expr.nodes().to_vec();
    let simplifies = has_min_max(expr.nodes());
    let mut b = domain;
    let mut depth = START_DEPTH;
    // Each pass searches the previous result. When a pass no longer shrinks it while
    // it still reaches the domain's faces, the cells may be too coarse for interval
    // arithmetic to prove them empty (a twist couples the coordinates), so the next
    // pass goes deeper, within an evaluation budget.
    let mut deepened = false;
    for _ in 0..16 {
        let mut out = Aabb::EMPTY;
        let mut budget = BUDGET / expr.len().max(1);
        let mut pass = Pass {
            arena: &mut arena,
            scratch: &mut scratch,
            budget: &mut budget,
            simplifies,
        };
        refine(&mut pass, b, 0..expr.len(), None, depth, &mut out);
        if out.is_empty() {
            return out;
        }
        let shrunk = out.extent().max_element() < 0.9 * b.extent().max_element();
        if budget == 0 {
            // A pass cut short by the budget proves nothing beyond its start box.
            break;
        }
        b = out;
        if shrunk {
            deepened = false;
        } else {
            // Going deeper once more only pays if the last deepening helped.
            let touches = (0..3).any(|k| b.lo[k] <= domain.lo[k] || b.hi[k] >= domain.hi[k]);
            if !touches || deepened || depth >= MAX_DEPTH {
                break;
            }
            depth += 2;
            deepened = true;
        }
    }
    b
}

/// A box holding the zero set {F = 0} of `expr` inside `domain`, for framing a view:
/// the deepest cells (32³ per pass) where interval arithmetic allows a zero and F
/// changes sign among the cell's corners and centre; passes repeat inside the box found
/// while it shrinks along some axis. Cells without a sampled sign change count only when no cell has
/// one (a surface smaller than a cell). Empty when F has one sign over the domain.
/// Not conservative (a feature thinner than a cell may be cut off), unlike
/// [`expr_bounds`].
pub fn surface_bounds(expr: &Expr, domain: Aabb) -> Aabb {
    let mut search = SurfaceSearch {
        expr,
        scratch: Scratch::new(expr.len()),
        points: Vec::with_capacity(expr.len()),
        sure: Aabb::EMPTY,
        maybe: Aabb::EMPTY,
        budget: 0,
    };
    let mut b = domain;
    for _ in 0..16 {
        search.sure = Aabb::EMPTY;
        search.maybe = Aabb::EMPTY;
        search.budget = BUDGET / expr.len().max(1);
        search.refine(b, None, SURFACE_DEPTH);
        if search.budget == 0 {
            // Cut short: what was not searched is kept whole.
            return search.sure.union(&search.maybe);
        }
        let next = if search.sure.is_empty() {
            search.maybe
        } else {
            search.sure
        };
        if next.is_empty() {
            return next;
        }
        // Along any axis: an unbounded surface (a plane) still tightens across itself.
        let shrunk = next.extent().cmplt(0.9 * b.extent()).any();
        b = next;
        if !shrunk {
            break;
        }
    }
    b
}

/// One pass of [`surface_bounds`]: the boxes of cells with and without a sampled sign
/// change, and the node evaluations left.
struct SurfaceSearch<'a> {
    expr: &'a Expr,
    scratch: Scratch,
    points: Vec<f64>,
    sure: Aabb,
    maybe: Aabb,
    budget: usize,
}

impl SurfaceSearch<'_> {
    /// One cell, with F's bound `v` over it when its parent found it ([`octants`]).
    fn refine(&mut self, cell: Aabb, v: Option<Interval>, depth: u32) {
        if self.sure.lo.cmple(cell.lo).all() && self.sure.hi.cmpge(cell.hi).all() {
            return;
        }
        if self.budget == 0 {
            self.maybe = self.maybe.union(&cell);
            return;
        }
        self.budget -= 1;
        let i = |k: usize| Interval::new(cell.lo[k], cell.hi[k]);
        let v = v.unwrap_or_else(|| self.expr.eval_with(i(0), i(1), i(2), &mut self.scratch.one));
        if v.lo > 0.0 || v.hi < 0.0 {
            return;
        }
        if depth == 0 {
            let (mut inside, mut outside) = (false, false);
            for k in 0..9 {
                let p = if k == 8 {
                    cell.center()
                } else {
                    DVec3::select(
                        glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
                        cell.hi,
                        cell.lo,
                    )
                };
                let f = self.expr.eval_with(p.x, p.y, p.z, &mut self.points);
                inside |= f >= 0.0;
                outside |= f < 0.0;
            }
            if inside && outside {
                self.sure = self.sure.union(&cell);
            } else {
                self.maybe = self.maybe.union(&cell);
            }
            return;
        }
        let (subs, vs) = octants(
            self.expr.nodes(),
            &cell,
            &self.sure,
            &mut self.scratch,
            false,
        );
        for (sub, v) in subs.into_iter().zip(vs) {
            self.refine(sub, v.map(|v| v.0), depth - 1);
        }
    }
}

/// Tapes shorter than this are not simplified per cell: their simplification costs
/// more than it saves (Fidget's quarter.vm, 12 nodes; as `interval_trace`'s segments).
const SIMPLIFY_MIN_LEN: usize = 24;

/// Octree depth of a pass of [`surface_bounds`] (32³ cells at most: where intervals
/// prune nothing, a pass evaluates every cell of every level).
const SURFACE_DEPTH: u32 = 5;
/// Octree depth of the first pass (64³ cells at most).
const START_DEPTH: u32 = 6;
/// Deepest octree tried when passes stop shrinking the box.
const MAX_DEPTH: u32 = 12;
/// Node evaluations one pass may spend (a fraction of a second for any expression).
const BUDGET: usize = 5_000_000;

/// What one pass of [`expr_bounds`] works in.
struct Pass<'a> {
    /// The cells' tapes, the whole one first.
    arena: &'a mut Vec<Node>,
    scratch: &'a mut Scratch,
    /// Cells the pass may still evaluate.
    budget: &'a mut usize,
    /// Whether the tape has a min or max, so that simplification can shorten it.
    simplifies: bool,
}

/// One cell of a pass of [`expr_bounds`] with its tape `pass.arena[tape]`, and F's bound
/// `v` over it when its parent found it ([`octants`]).
fn refine(
    pass: &mut Pass,
    cell: Aabb,
    tape: std::ops::Range<usize>,
    v: Option<Interval>,
    depth: u32,
    out: &mut Aabb,
) {
    // Cells already inside the result cannot grow it.
    if out.lo.cmple(cell.lo).all() && out.hi.cmpge(cell.hi).all() {
        return;
    }
    if *pass.budget == 0 {
        // Out of budget: keep the cell whole, which stays conservative.
        *out = out.union(&cell);
        return;
    }
    *pass.budget -= 1;
    let i = |k: usize| Interval::new(cell.lo[k], cell.hi[k]);
    let nodes = &pass.arena[tape.clone()];
    let v = v.unwrap_or_else(|| eval_nodes(nodes, i(0), i(1), i(2), &mut pass.scratch.one));
    if v.hi < 0.0 {
        return;
    }
    if depth == 0 || v.lo >= 0.0 {
        *out = out.union(&cell);
        return;
    }
    let simplify = pass.simplifies && tape.len() >= SIMPLIFY_MIN_LEN && !lanes_off();
    let (subs, vs) = octants(nodes, &cell, out, pass.scratch, simplify);
    if !simplify {
        for (sub, v) in subs.into_iter().zip(vs) {
            refine(pass, sub, tape.clone(), v.map(|v| v.0), depth - 1, out);
        }
        return;
    }
    // Each octant's tape, simplified by its choices (where any is decided) before the
    // visits reuse the choices' scratch; dropped after the visits.
    let mark = pass.arena.len();
    let tapes: [std::ops::Range<usize>; 8] = std::array::from_fn(|k| {
        let start = pass.arena.len();
        let arena = &mut *pass.arena;
        match vs[k] {
            Some((_, j))
                if simplify_into_lane(&[], Some(tape.clone()), &pass.scratch.choices, j, arena) =>
            {
                start..arena.len()
            }
            _ => tape.clone(),
        }
    });
    for ((sub, v), t) in subs.into_iter().zip(vs).zip(tapes) {
        refine(pass, sub, t, v.map(|v| v.0), depth - 1, out);
    }
    pass.arena.truncate(mark);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Tree;

    thread_local! {
        /// Set: [`octants`] bounds the octants one by one, as the searches did before
        /// lanes.
        pub(super) static ONE_BY_ONE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }

    /// Both searches find, with the octants bounded in lanes, the boxes they find with
    /// the octants bounded one by one, bit for bit: every expression model of the
    /// repository (the budget runs out on the longest), in the default domain and in a
    /// small one.
    #[test]
    fn lanes_find_the_same_boxes() {
        let bits = |b: Aabb| [b.lo.to_array(), b.hi.to_array()].map(|v| v.map(f64::to_bits));
        for (m, tree) in crate::test_models::expression_models() {
            let e = Expr::new(&tree);
            for d in [DEFAULT_DOMAIN, 1.3] {
                let domain = Aabb::new(DVec3::splat(-d), DVec3::splat(d));
                let found = |one: bool| {
                    ONE_BY_ONE.set(one);
                    let r = (expr_bounds(&e, domain), surface_bounds(&e, domain));
                    ONE_BY_ONE.set(false);
                    r
                };
                let (lanes, one) = (found(false), found(true));
                assert!(!lanes.0.is_empty() && !lanes.1.is_empty(), "{m}: {lanes:?}");
                assert_eq!(bits(lanes.0), bits(one.0), "{m} in ±{d}: solid");
                assert_eq!(bits(lanes.1), bits(one.1), "{m} in ±{d}: surface");
            }
        }
    }

    #[test]
    fn ball_bounds_are_tight_and_conservative() {
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let ball = 0.25 - ((x - 1.0).square() + (y + 2.0).square() + z.square());
        let d = Aabb::new(DVec3::splat(-DEFAULT_DOMAIN), DVec3::splat(DEFAULT_DOMAIN));
        let b = expr_bounds(&Expr::new(&ball), d);
        let want = Aabb::new(DVec3::new(0.5, -2.5, -0.5), DVec3::new(1.5, -1.5, 0.5));
        assert!(
            b.lo.cmple(want.lo).all() && b.hi.cmpge(want.hi).all(),
            "{b:?}"
        );
        assert!((b.extent() - want.extent()).max_element() < 0.1, "{b:?}");
    }

    /// A twisted bar: intervals cannot prove big cells empty (x and y are coupled
    /// through the twist), so the search must go deeper than its first pass.
    #[test]
    fn twisted_bar_is_bounded_tightly() {
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let w = 1.2 * &z;
        let xt = &x * w.cos() + &y * w.sin();
        let yt = -(&x * w.sin()) + &y * w.cos();
        let bar = -((xt.abs() - 0.35)
            .max(&(yt.abs() - 0.35))
            .max(&(z.abs() - 1.1)));
        let d = Aabb::new(DVec3::splat(-DEFAULT_DOMAIN), DVec3::splat(DEFAULT_DOMAIN));
        let b = expr_bounds(&Expr::new(&bar), d);
        // The bar's cross-section has half-diagonal 0.35·√2 ≈ 0.495.
        assert!(
            b.hi.x >= 0.49 && b.hi.x < 1.0 && b.lo.y <= -0.49 && b.lo.y > -1.0,
            "{b:?}"
        );
        assert!(b.hi.z >= 1.1 && b.hi.z < 1.3, "{b:?}");
    }

    /// Eight balls joined by nested R-unions: narrowed by the R-functions' monotonicity
    /// ([`crate::Scalar::r_bound`]; without it no cell of the ±100 domain was proved
    /// empty and the solid's box was the whole domain), intervals bound the solid
    /// tightly, and the zero set's box is tight.
    #[test]
    fn nested_r_unions_have_a_tight_surface_box() {
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let ball = |cx: f64| 0.36 - ((&x - cx).square() + y.square() + z.square());
        let mut f = ball(-1.75);
        for k in 1..8 {
            let g = ball(-1.75 + 0.5 * k as f64);
            f = &f + &g + (f.square() + g.square()).sqrt();
        }
        let e = Expr::new(&f);
        let d = Aabb::new(DVec3::splat(-DEFAULT_DOMAIN), DVec3::splat(DEFAULT_DOMAIN));
        let want = Aabb::new(DVec3::new(-2.35, -0.6, -0.6), DVec3::new(2.35, 0.6, 0.6));
        let solid = expr_bounds(&e, d);
        assert!(
            solid.lo.cmple(want.lo + 0.05).all() && solid.hi.cmpge(want.hi - 0.05).all(),
            "{solid:?}"
        );
        assert!(
            (solid.extent() - want.extent()).max_element() < 0.2,
            "{solid:?}"
        );
        let b = surface_bounds(&e, d);
        assert!(
            b.lo.cmple(want.lo + 0.05).all() && b.hi.cmpge(want.hi - 0.05).all(),
            "{b:?}"
        );
        assert!((b.extent() - want.extent()).max_element() < 0.2, "{b:?}");
        // The complement has the same surface; a function of one sign has none.
        assert!((surface_bounds(&Expr::new(&-f), d).extent() - b.extent()).length() < 1e-9);
        assert!(surface_bounds(&Expr::new(&(-1.0 - x.square())), d).is_empty());
    }

    #[test]
    fn nothing_inside_gives_empty() {
        let f = -1.0 - Tree::x().square();
        let d = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        assert!(expr_bounds(&Expr::new(&f), d).is_empty());
    }
}
