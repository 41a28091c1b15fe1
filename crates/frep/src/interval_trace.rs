//! Ray intersection of any closed-form expression by interval arithmetic.
//!
//! The ray segment [t0, t1] is bounded with intervals (Mitchell 1990, "Robust ray
//! intersection with interval arithmetic"; Keeter 2020): if F over the segment excludes
//! 0 there is no crossing; if dF/dt excludes 0 (a [`Dual`] of intervals) F is monotonic
//! and crosses at most once, found by bisection on the sign; otherwise the segment is
//! split, left half first, so the first crossing is found first. Segments shorter than
//! a resolution `eps` (relative to the solid's size) are decided by the signs at their
//! ends: only a feature that enters and leaves within `eps` along the ray can be missed.
//!
//! **Cell tapes.** Where the solid has an occupancy grid ([`crate::occupancy`]) a ray
//! searches only runs of occupied cells, each with the tape simplified over its cells
//! (on colonnade.vm's 32³ grid, 23 nodes on average of 796), and point queries use the tape of the
//! cell they fall in: the same values bit for bit, a fraction of the work.
//!
//! **Polynomial leaves.** Where the tape has no min/max, its parts that are polynomials
//! of degree ≤ 2 are computed once per ray as polynomials along it
//! ([`crate::ray_tape`]), and every evaluation of the search reads them: the table
//! scene's blob evaluates 34 of its 70 nodes, and bounds its spheres by their exact
//! ranges.
//!
//! **Allocation.** A trace keeps its segment stack, the tapes it simplifies per segment
//! (stacked in one arena: a segment's tape never ends before those of the segments under
//! it) and its node values in thread-local vectors. They grow on a thread's first rays
//! and are reused after, so a warm thread traces without allocating
//! (crates/frep/tests/no_alloc.rs). What still allocates: [`Expr::simplify`] and the
//! one-off evaluations [`Expr::eval`], [`Expr::eval_f32`], [`Expr::gradient`] (a
//! fresh vector each), none of which tracing uses.

use crate::dual::Dual;
use crate::expr::{eval_choices_nodes, eval_nodes, simplify_into, Choice, Expr, Node};
use crate::interval::Interval;
use crate::occupancy::{self, GridView};
use crate::poly_trace;
use crate::ray::{Aabb, Ray};
use crate::ray_tape::{Plan, PlanView, RayTape};
use crate::surface::{outward, Surface};
use glam::DVec3;
use std::cell::{OnceCell, RefCell};
use std::sync::Arc;

/// Relative resolution along a ray: segments shorter than this times the bounds'
/// diagonal are decided by their end signs.
pub const RESOLUTION: f64 = 1e-7;

/// The most segments one trace bounds by intervals. Well-behaved functions need far
/// fewer; where intervals say nothing (`x/0`, `pow(f, 1e300)`: every bound infinite or
/// NaN) bisection would go on to the resolution, ~2^26 segments a ray. Past this budget
/// the segments left are decided by their end signs, as those below the resolution:
/// the time per ray is bounded, and only a crossing that enters and leaves within one
/// of those segments can be missed (docs/reliability.md).
pub const MAX_SEGMENTS: u32 = 1 << 12;

/// An expression solid ready for ray queries.
#[derive(Clone, Debug)]
pub struct ExprSurface {
    expr: Arc<Expr>,
    bounds: Aabb,
    eps: f64,
    grid: Arc<occupancy::Grid>,
    degree: Option<u8>,
    plan: Option<Arc<Plan>>,
}

/// An expression solid over a borrowed tape (root last): what [`ExprSurface`] and the
/// flat solids of [`crate::solid`] intersect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExprView<'a> {
    /// The nodes, in evaluation order.
    pub tape: &'a [Node],
    /// A box holding every point with F ≥ 0.
    pub bounds: Aabb,
    /// The resolution along rays ([`RESOLUTION`] × the bounds' diagonal).
    pub eps: f64,
    /// The occupancy grid over the bounds grown by `eps`, with a simplified tape per
    /// cell ([`crate::occupancy`]; [`GridView::NONE`]: none, every ray searches its
    /// whole segment with the whole tape).
    pub grid: GridView<'a>,
    /// The tape's degree when it is a polynomial of low degree
    /// ([`crate::poly_trace::degree`]): rays then search it in Bernstein form, not by
    /// intervals, and the grid is not used. None: by intervals.
    pub degree: Option<u8>,
    /// The tape's low-degree polynomial parts as leaves along a ray
    /// ([`crate::ray_tape`]): the search evaluates the rest. None: the whole tape.
    pub plan: Option<PlanView<'a>>,
}

thread_local! {
    static SCRATCH_D: RefCell<Vec<Dual<Interval, 1>>> = const { RefCell::new(Vec::new()) };
    static SCRATCH_F: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
    static SCRATCH_G: RefCell<Vec<Dual<f64, 3>>> = const { RefCell::new(Vec::new()) };
    static SCRATCH_T: RefCell<Vec<Dual<f64, 1>>> = const { RefCell::new(Vec::new()) };
    /// The segment stack, the arena of simplified tapes and the choices of one trace,
    /// kept per thread: once grown, tracing allocates nothing.
    static TRACE: RefCell<Trace> = const {
        RefCell::new(Trace { stack: Vec::new(), arena: Vec::new(), choices: Vec::new() })
    };
}

/// The reusable state of [`ExprView::trace`].
struct Trace {
    stack: Vec<Segment>,
    /// Simplified tapes, stacked: a segment's tape ends at or after the tapes of every
    /// segment below it on the stack, so popping a segment frees what lies past its tape.
    arena: Vec<Node>,
    choices: Vec<Choice>,
}

/// A ray segment [a, b] still to search, the inside predicate at its ends, and its tape
/// (None: the root tape; else a range of the arena).
#[derive(Clone, Copy)]
struct Segment {
    a: f64,
    b: f64,
    ia: bool,
    ib: bool,
    tape: Option<(u32, u32)>,
}

impl ExprSurface {
    /// A solid whose every point with F ≥ 0 lies in `bounds` (see [`crate::bounds`]).
    pub fn new(expr: Expr, bounds: Aabb) -> Self {
        let eps = resolution(&bounds);
        // A polynomial tape has no min/max for a cell to drop, and its rays do not search
        // by cells: it gets no grid.
        let degree = poly_trace::degree(expr.nodes()).map(|d| d as u8);
        let grid = match degree {
            Some(_) => occupancy::Grid::default(),
            None => occupancy::build(expr.nodes(), &grown(&bounds, eps)),
        };
        let grid = Arc::new(grid);
        let plan = match degree {
            Some(_) => None,
            None => Plan::new(expr.nodes()),
        };
        Self {
            expr: Arc::new(expr),
            bounds,
            eps,
            grid,
            degree,
            plan: plan.map(Arc::new),
        }
    }

    /// The expression.
    pub fn expr(&self) -> &Expr {
        &self.expr
    }

    /// The solid as a borrowed view.
    pub fn view(&self) -> ExprView<'_> {
        ExprView {
            tape: self.expr.nodes(),
            bounds: self.bounds,
            eps: self.eps,
            grid: self.grid.view(),
            degree: self.degree,
            plan: self.plan.as_deref().map(Plan::view),
        }
    }
}

/// The box rays search: the bounds grown by the resolution, so that a surface on a face
/// is not clipped away.
fn grown(bounds: &Aabb, eps: f64) -> Aabb {
    Aabb::new(bounds.lo - eps, bounds.hi + eps)
}

/// The resolution along rays for a solid with these bounds.
pub fn resolution(bounds: &Aabb) -> f64 {
    let diag = if bounds.is_finite() && !bounds.is_empty() {
        bounds.extent().length()
    } else {
        1.0
    };
    RESOLUTION * diag.max(1e-12)
}

/// Whether the point at t is inside (F ≥ 0; NaN counts as outside), by `tape`.
#[inline]
fn inside_at(tape: &[Node], ray: &Ray, t: f64) -> bool {
    value_at(tape, ray, t) >= 0.0
}

/// F and dF/dt over the segment [t0, t1] by `tape`, recording min/max choices.
fn segment(
    tape: &[Node],
    ray: &Ray,
    t0: f64,
    t1: f64,
    choices: &mut Vec<Choice>,
) -> (Interval, Interval) {
    let t = Interval::new(t0, t1);
    let c = |k: usize| {
        let v = Interval::point(ray.o[k]) + t * Interval::point(ray.d[k]);
        Dual::new(v, [Interval::point(ray.d[k])])
    };
    let r = SCRATCH_D.with_borrow_mut(|s| eval_choices_nodes(tape, c(0), c(1), c(2), s, choices));
    (r.v, r.d[0])
}

/// F at the point at t, by `tape`.
#[inline]
fn value_at(tape: &[Node], ray: &Ray, t: f64) -> f64 {
    let p = ray.at(t);
    SCRATCH_F.with_borrow_mut(|s| eval_nodes(tape, p.x, p.y, p.z, s))
}

/// ∇F at p by `tape`.
fn gradient_by(tape: &[Node], p: DVec3) -> DVec3 {
    let v = |k: usize| Dual::<f64, 3>::var(p[k], k);
    let r = SCRATCH_G.with_borrow_mut(|s| eval_nodes(tape, v(0), v(1), v(2), s));
    DVec3::from_array(r.d)
}

/// Finds the crossing in [a, b], where the inside predicate differs at the ends, by
/// [`newton_in`] on the tape.
fn refine(tape: &[Node], ray: &Ray, a: f64, b: f64, inside_a: bool, tol: f64) -> f64 {
    newton_in(a, b, inside_a, tol, |x| {
        let p = ray.at(x);
        let c = |k: usize| Dual::<f64, 1>::new(p[k], [ray.d[k]]);
        let r = SCRATCH_T.with_borrow_mut(|s| eval_nodes(tape, c(0), c(1), c(2), s));
        (r.v, r.d[0])
    })
}

/// The crossing in [a, b] of a function whose inside predicate (value ≥ 0) differs at
/// the ends, given its value and derivative `f(x)`: safeguarded Newton (a step that
/// leaves the bracket becomes a bisection), stopping when the bracket or the step is
/// below `tol`.
pub(crate) fn newton_in(
    mut a: f64,
    mut b: f64,
    inside_a: bool,
    tol: f64,
    mut f: impl FnMut(f64) -> (f64, f64),
) -> f64 {
    let mut x = 0.5 * (a + b);
    for _ in 0..100 {
        let (v, dv) = f(x);
        if (v >= 0.0) == inside_a {
            a = x;
        } else {
            b = x;
        }
        if b - a <= tol {
            return b;
        }
        let step = v / dv;
        let newton = x - step;
        // A step below the tolerance ends the search even when it lands on an end of
        // the bracket (x itself, just made an end): a bisection there would throw away
        // a converged iterate and start over from the middle.
        if step.is_finite() && step.abs() <= tol && newton >= a && newton <= b {
            return newton;
        }
        x = if step.is_finite() && newton > a && newton < b {
            newton
        } else {
            0.5 * (a + b)
        };
    }
    b
}

/// Grows `v`'s capacity to at least `n`.
pub(crate) fn at_least<T>(v: &mut Vec<T>, n: usize) {
    if v.capacity() < n {
        v.reserve(n - v.len());
    }
}

/// Grows this thread's scratch to a tape of `n` nodes, so that the shorter cell tapes a
/// ray meets first never leave a longer one to grow it later (nothing allocates once
/// warm).
fn reserve(n: usize) {
    SCRATCH_D.with_borrow_mut(|s| at_least(s, n));
    SCRATCH_G.with_borrow_mut(|s| at_least(s, n));
    SCRATCH_T.with_borrow_mut(|s| at_least(s, n));
    crate::poly_trace::reserve(n);
    crate::expr::reserve_simplify(n);
    TRACE.with_borrow_mut(|tr| {
        at_least(&mut tr.choices, n);
        at_least(&mut tr.arena, 2 * n);
    });
}

/// Expressions shorter than this are not worth simplifying per segment.
const SIMPLIFY_MIN_LEN: usize = 24;

impl ExprView<'_> {
    /// The tape that equals F at p: its cell's where the grid has one, else the whole.
    #[inline]
    fn tape_at(&self, p: DVec3) -> &[Node] {
        let grown = grown(&self.bounds, self.eps);
        self.grid.tape_at(&grown, p).unwrap_or(self.tape)
    }

    /// F at p.
    pub fn value(&self, p: DVec3) -> f64 {
        let tape = self.tape_at(p);
        SCRATCH_F.with_borrow_mut(|s| eval_nodes(tape, p.x, p.y, p.z, s))
    }

    /// ∇F at p.
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        gradient_by(self.tape_at(p), p)
    }

    /// The first crossing in (t_min, t_max) and, when `normal`, the outward normal there
    /// (from the tape simplified for the hit's segment: same values there, a fraction of
    /// the nodes; else +z). Allocates nothing once this thread's scratch has grown.
    pub fn trace(&self, ray: &Ray, t_min: f64, t_max: f64, normal: bool) -> Option<(f64, DVec3)> {
        let want = match normal {
            true => Want::Normal,
            false => Want::Crossing,
        };
        self.search(ray, t_min, t_max, want)
    }

    /// Whether [`Self::trace`] finds a crossing in (t_min, t_max) (a shadow ray's
    /// question): the same search, stopped where it would refine the crossing, so the
    /// answer is the same without the Newton steps and the normal.
    pub fn crosses(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        self.search(ray, t_min, t_max, Want::Any).is_some()
    }

    /// [`Self::trace`] for `want`; with [`Want::Any`] the t returned is only somewhere in
    /// the segment that holds the first crossing.
    fn search(&self, ray: &Ray, t_min: f64, t_max: f64, want: Want) -> Option<(f64, DVec3)> {
        let normal = want == Want::Normal;
        // Outside the bounds F < 0, so crossings lie inside them; widen a little so that
        // a surface on the box face is not clipped away.
        let grown = grown(&self.bounds, self.eps);
        let (t0, t1) = grown.clip(ray, t_min, t_max)?;
        if t1 <= t0 || !t1.is_finite() || !t0.is_finite() {
            return None;
        }
        let eps_t = self.eps / ray.d.length().max(f64::MIN_POSITIVE);
        // Crossings are located to 1e-5 of the resolution (1e-12 of the solid's size).
        let tol = eps_t * 1e-5;
        let root = self.tape;
        // Where the range was clipped by the grown bounds, F < 0 is known outside them:
        // a solid cut by its search domain is capped at the domain's faces. A ray that
        // enters the bounds inside the solid crosses there; one that leaves them inside
        // it crosses there unless F crosses first. (The segments below carry the true
        // signs of F at the ends, so that a crossing inside is found between them.)
        // (From the grid where the ends lie in empty cells, whose signs it knows; from
        // the polynomial along the segment where the tape is one, which it computes.)
        reserve(root.len());
        let along = self
            .degree
            .and_then(|deg| poly_trace::Along::new(root, deg as usize, ray, t0, t1));
        let inside = |t: f64| {
            let p = ray.at(t);
            self.grid
                .known_inside(&grown, p)
                .unwrap_or_else(|| self.value(p) >= 0.0)
        };
        let (ia, ib) = match &along {
            Some(along) => along.end_signs(),
            None => (inside(t0), inside(t1)),
        };
        let cap = |t: f64| {
            let n = match normal {
                true => face_normal(&grown, ray.at(t)),
                false => DVec3::Z,
            };
            Some((t, n))
        };
        if t0 > t_min && ia {
            return cap(t0);
        }
        // F along this ray with its polynomial parts as leaves, where the tape has them.
        // Computed at the first evaluation: a ray through empty cells only needs none.
        let leaves = self.plan.map(|plan| Leaves {
            plan,
            ray,
            t0,
            tape: OnceCell::new(),
        });
        let search = Search {
            root,
            ray,
            eps_t,
            tol,
            want,
            leaves: leaves.as_ref(),
        };
        if let Some(along) = along {
            return match along.first_crossing((ia, ib), eps_t, tol) {
                None if t1 < t_max && ib => cap(t1),
                None => None,
                Some(t) => Some((
                    t,
                    match normal {
                        true => outward(gradient_by(root, ray.at(t))),
                        false => DVec3::Z,
                    },
                )),
            };
        }
        let inner = TRACE.with_borrow_mut(|tr| {
            let mut visits = 0u32;
            if !self.grid.is_some() {
                return search.run(tr, (t0, t1), (ia, ib), &mut visits);
            }
            // Only runs of occupied cells can hold a crossing; F keeps its sign between.
            // Each run is searched with its cells' tape, which equals F there. The signs
            // at a run's ends come from the empty cells beside it, or from the run
            // before where two meet (both tapes equal F there), else from its tape.
            let mut found = None;
            let mut last_end = (t0, ia);
            occupancy::runs(self.grid, &grown, ray, t0, t1, |a, b, tape, known| {
                let search = Search {
                    root: tape.unwrap_or(root),
                    // A tape with leaves has no min/max: every cell's tape is the whole.
                    leaves: search
                        .leaves
                        .filter(|_| tape.is_none_or(|t| t.len() == root.len())),
                    ..search
                };
                let ia = match known[0] {
                    Some(s) => s,
                    None if a == last_end.0 => last_end.1,
                    None => search.inside(a),
                };
                let ib = match known[1] {
                    Some(s) => s,
                    None if b == t1 => ib,
                    None => search.inside(b),
                };
                last_end = (b, ib);
                found = search.run(tr, (a, b), (ia, ib), &mut visits);
                found.is_some()
            });
            found
        });
        match inner {
            None if t1 < t_max && ib => cap(t1),
            found => found,
        }
    }
}

/// What a search returns: the first crossing, with or without its normal, or only
/// whether there is one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Want {
    Crossing,
    Normal,
    Any,
}

/// A ray's [`RayTape`], made when the search first evaluates F.
struct Leaves<'a> {
    plan: PlanView<'a>,
    ray: &'a Ray,
    t0: f64,
    tape: OnceCell<Option<RayTape<'a>>>,
}

impl Leaves<'_> {
    /// The ray's leaves; None where their coefficients are not finite.
    fn get(&self) -> Option<&RayTape<'_>> {
        self.tape
            .get_or_init(|| {
                let plan = self.plan;
                crate::ray_tape::reserve(plan.parts.len().max(plan.tape.len()));
                RayTape::new(plan, self.ray, self.t0)
            })
            .as_ref()
    }
}

/// One ray's search of a segment by subdivision (the loop of [`ExprView::trace`]).
#[derive(Clone, Copy)]
struct Search<'a, 'l> {
    root: &'a [Node],
    ray: &'a Ray,
    eps_t: f64,
    tol: f64,
    want: Want,
    /// `root` along this ray with its polynomial parts as leaves, where it has them:
    /// every evaluation of the search reads it instead.
    leaves: Option<&'l Leaves<'a>>,
}

impl Search<'_, '_> {
    /// Whether F ≥ 0 at t, by the root tape.
    fn inside(&self, t: f64) -> bool {
        match self.leaves.and_then(Leaves::get) {
            Some(l) => l.value(t) >= 0.0,
            None => inside_at(self.root, self.ray, t),
        }
    }

    /// The first crossing in [a, b], whose ends are inside as (ia, ib); `visits`
    /// counts segments against [`MAX_SEGMENTS`] over every call of one trace.
    fn run(
        &self,
        tr: &mut Trace,
        (a, b): (f64, f64),
        (ia, ib): (bool, bool),
        visits: &mut u32,
    ) -> Option<(f64, DVec3)> {
        let Self {
            root,
            ray,
            eps_t,
            tol,
            want,
            leaves,
        } = *self;
        if want == Want::Any && ia != ib {
            // F changes sign over [a, b]: the subdivision below would find a crossing
            // (a half with unequal end signs is never excluded, and is decided by its
            // signs once monotone, at the resolution or past the budget).
            return Some((a, DVec3::Z));
        }
        let leaves = leaves.and_then(Leaves::get);
        let Trace {
            stack,
            arena,
            choices,
        } = tr;
        stack.clear();
        arena.clear();
        stack.push(Segment {
            a,
            b,
            ia,
            ib,
            tape: None,
        });
        while let Some(Segment { a, b, ia, ib, tape }) = stack.pop() {
            *visits += 1;
            arena.truncate(tape.map_or(0, |(_, e)| e as usize));
            let nodes = match tape {
                None => root,
                Some((s, e)) => &arena[s as usize..e as usize],
            };
            let (v, slope) = match leaves {
                Some(l) => l.segment(a, b),
                None => segment(nodes, ray, a, b, choices),
            };
            if v.lo > 0.0 || v.hi < 0.0 {
                continue;
            }
            if slope.lo > 0.0 || slope.hi < 0.0 || b - a <= eps_t || *visits > MAX_SEGMENTS {
                // Monotonic (at most one crossing), below resolution or past the
                // budget: decided by the signs at the ends.
                if ia != ib {
                    if want == Want::Any {
                        return Some((a, DVec3::Z));
                    }
                    let t = match leaves {
                        Some(l) => newton_in(a, b, ia, tol, |x| l.value_slope(x)),
                        None => refine(nodes, ray, a, b, ia, tol),
                    };
                    let n = match want {
                        Want::Normal => outward(gradient_by(nodes, ray.at(t))),
                        _ => DVec3::Z,
                    };
                    return Some((t, n));
                }
                continue;
            }
            // The mean-value form F(m) + F'([a,b])·([a,b] − m) is far tighter than
            // the plain interval on short segments (Moore 1966, §6).
            let m = 0.5 * (a + b);
            let fm = match leaves {
                Some(l) => l.value(m),
                None => value_at(nodes, ray, m),
            };
            let mv = Interval::point(fm) + slope * Interval::new(a - m, b - m);
            if ia == ib && (mv.lo > 0.0 || mv.hi < 0.0) {
                continue;
            }
            // Both halves lie in this segment, so its min/max choices hold there too.
            let mut half = tape;
            if nodes.len() >= SIMPLIFY_MIN_LEN && leaves.is_none() {
                let start = arena.len();
                let range = tape.map(|(s, e)| s as usize..e as usize);
                if simplify_into(root, range, choices, arena) {
                    half = Some((start as u32, arena.len() as u32));
                }
            }
            let im = fm >= 0.0;
            // Around m the mean-value form keeps F at fm's sign over a gap that holds no
            // crossing (an interval Newton step); the halves shrink to what lies beyond.
            let (dl, dr) = gap(fm, slope);
            let (l, r) = (m - dl, m + dr);
            if r < b || im != ib {
                stack.push(Segment {
                    a: if r < b { r } else { m },
                    b,
                    ia: im,
                    ib,
                    tape: half,
                });
            }
            if l > a || im != ia {
                stack.push(Segment {
                    a,
                    b: if l > a { l } else { m },
                    ia,
                    ib: im,
                    tape: half,
                });
            }
        }
        None
    }
}

/// How far F keeps the sign of `fm`, its value at a segment's midpoint m, to the left
/// and to the right of m, by the mean-value form fm + F'·(t − m) with F' in `slope`
/// (the slope's enclosure over the segment); 0 where it may not. Shortened by a tenth
/// for the rounding of fm.
fn gap(fm: f64, slope: Interval) -> (f64, f64) {
    // Left of m F ≥ fm − s_hi·(m − t) and ≤ fm − s_lo·(m − t); right of m likewise with
    // the bounds swapped.
    let reach = |margin: f64, rate: f64| {
        if margin > 0.0 && rate > 0.0 {
            0.9 * margin / rate
        } else if margin > 0.0 && rate <= 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    };
    if fm > 0.0 {
        (reach(fm, slope.hi), reach(fm, -slope.lo))
    } else if fm < 0.0 {
        (reach(-fm, -slope.lo), reach(-fm, slope.hi))
    } else {
        (0.0, 0.0)
    }
}

/// The outward normal of the face of `b` nearest to `p` (a point on its boundary).
fn face_normal(b: &Aabb, p: DVec3) -> DVec3 {
    let mut best = (f64::INFINITY, DVec3::Z);
    for k in 0..3 {
        let unit = DVec3::AXES[k];
        for (d, n) in [
            ((p[k] - b.lo[k]).abs(), -unit),
            ((b.hi[k] - p[k]).abs(), unit),
        ] {
            if d < best.0 {
                best = (d, n);
            }
        }
    }
    best.1
}

impl Surface for ExprSurface {
    fn value(&self, p: DVec3) -> f64 {
        self.view().value(p)
    }

    fn gradient(&self, p: DVec3) -> DVec3 {
        self.view().gradient(p)
    }

    fn first_crossing(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        self.view().trace(ray, t_min, t_max, false).map(|(t, _)| t)
    }

    fn first_hit(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, DVec3)> {
        self.view().trace(ray, t_min, t_max, true)
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bounds::expr_bounds;
    use crate::Tree;
    use rand::{Rng, SeedableRng};

    /// Over the gap `gap` claims around a segment's midpoint, a quadratic keeps the sign
    /// of its value there, for 20 000 random quadratics and segments (the slope's
    /// enclosure its exact range over the segment); and the gap is not empty where the
    /// slope is small against the value.
    #[test]
    fn the_gap_keeps_the_midpoint_sign() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let mut wide = 0;
        for _ in 0..20_000 {
            let c: [f64; 3] = [
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-2.0..2.0),
                rng.gen_range(-3.0..3.0),
            ];
            let f = |t: f64| c[0] + t * (c[1] + t * c[2]);
            let (a, b) = (rng.gen_range(-1.0..0.0), rng.gen_range(0.0..1.0));
            let m = 0.5 * (a + b);
            let (sa, sb) = (c[1] + 2.0 * c[2] * a, c[1] + 2.0 * c[2] * b);
            let slope = Interval::new(sa.min(sb), sa.max(sb));
            let fm = f(m);
            let (dl, dr) = gap(fm, slope);
            let (l, r) = ((m - dl).max(a), (m + dr).min(b));
            wide += usize::from(r - l > 0.25 * (b - a));
            for k in 0..=50 {
                let t = l + (r - l) * k as f64 / 50.0;
                assert!(
                    f(t) * fm > 0.0 || fm == 0.0,
                    "{c:?} on [{a}, {b}] at {t}: {} vs {fm}",
                    f(t)
                );
            }
        }
        assert!(
            wide > 5_000,
            "{wide} gaps wider than a quarter of their segment"
        );
    }

    fn surface(t: &Tree) -> ExprSurface {
        let e = Expr::new(t);
        let b = expr_bounds(&e, Aabb::new(DVec3::splat(-4.0), DVec3::splat(4.0)));
        ExprSurface::new(e, b)
    }

    /// The first sign change by a dense march plus bisection (the reference).
    fn march(s: &ExprSurface, ray: &Ray, t0: f64, t1: f64, n: usize) -> Option<f64> {
        let inside = |t: f64| s.value(ray.at(t)) >= 0.0;
        let mut prev = inside(t0);
        for k in 1..=n {
            let t = t0 + (t1 - t0) * k as f64 / n as f64;
            let cur = inside(t);
            if cur != prev {
                // Plain bisection: the reference shares no code with the intersector.
                let (mut a, mut b) = (t0 + (t1 - t0) * (k - 1) as f64 / n as f64, t);
                for _ in 0..60 {
                    let m = 0.5 * (a + b);
                    if inside(m) == prev {
                        a = m;
                    } else {
                        b = m;
                    }
                }
                return Some(b);
            }
            prev = cur;
        }
        None
    }

    #[test]
    fn sphere_analytic_hit() {
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let s = surface(&(1.0 - (x.square() + y.square() + z.square())));
        let ray = Ray::new(DVec3::new(-3.0, 0.5, 0.0), DVec3::X);
        let t = s.first_crossing(&ray, 0.0, f64::INFINITY).unwrap();
        assert!((t - (3.0 - 0.75f64.sqrt())).abs() < 1e-9, "{t}");
        // From inside, the exit.
        let t2 = s.first_crossing(&ray, t + 1e-6, f64::INFINITY).unwrap();
        assert!((t2 - (3.0 + 0.75f64.sqrt())).abs() < 1e-9, "{t2}");
        assert!(s.first_crossing(&ray, t2 + 1e-6, f64::INFINITY).is_none());
        let n = s.normal(ray.at(t));
        assert!((n - DVec3::new(-0.75f64.sqrt(), 0.5, 0.0)).length() < 1e-6);
    }

    /// Gyroid-in-a-ball and a thin shell against a dense march: same hit or miss on
    /// every ray and |Δt| below the march's bracket.
    #[test]
    fn agrees_with_dense_march() {
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let r2 = x.square() + y.square() + z.square();
        let g = (3.0 * &x).sin() * (3.0 * &y).cos()
            + (3.0 * &y).sin() * (3.0 * &z).cos()
            + (3.0 * &z).sin() * (3.0 * &x).cos()
            - 0.2;
        let gyroid = g.min(&(1.96 - &r2));
        // A shell 0.004 thick: 1.0 ≤ r² ≤ 1.008.
        let shell = (&r2 - 1.0).min(&(1.008 - &r2));
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        for (name, t) in [("gyroid", gyroid), ("shell", shell)] {
            let s = surface(&t);
            let mut hits = 0;
            for _ in 0..300 {
                let o = DVec3::new(rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0), 3.0);
                let target = DVec3::new(rng.gen_range(-1.2..1.2), rng.gen_range(-1.2..1.2), 0.0);
                let ray = Ray::new(o, target - o);
                let got = s.first_crossing(&ray, 0.0, 2.0);
                let want = march(&s, &ray, 0.0, 2.0, 40_000);
                match (got, want) {
                    (Some(a), Some(b)) => {
                        hits += 1;
                        assert!((a - b).abs() < 2.0 / 40_000.0, "{name}: {a} vs {b}");
                    }
                    (None, None) => {}
                    _ => panic!("{name}: {got:?} vs march {want:?} for {ray:?}"),
                }
            }
            assert!(hits > 50, "{name}: only {hits} hits");
        }
    }

    /// R-function CSG (Rvachev's `|` and `&`, and a blend): intervals over a box far from
    /// the surface exclude 0 once narrowed by the R-functions' monotonicity, and every
    /// ray's first crossing (from outside and from inside the bounds) agrees with a dense
    /// march, on a blend of three balls (the table scene's blob) and an R-CSG part.
    #[test]
    fn r_function_models_agree_with_dense_march() {
        use crate::csg::{blend_union, r_intersection, r_union};
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let ball = |c: [f64; 3], r: f64| {
            r * r - ((&x - c[0]).square() + (&y - c[1]).square() + (&z - c[2]).square())
        };
        let blob = blend_union(
            &blend_union(
                &ball([0.0; 3], 0.22),
                &ball([0.3, 0.1, 0.05], 0.18),
                0.4,
                0.5,
                0.5,
            ),
            &ball([0.1, 0.3, 0.12], 0.15),
            0.4,
            0.5,
            0.5,
        );
        let part = r_intersection(
            &r_union(&ball([0.0; 3], 0.5), &ball([0.4, 0.0, 0.0], 0.3), 0.0),
            &(0.35 - z.square()),
            0.0,
        );
        // Far from both (the box [0.9, 1.1]³): narrowed, the value excludes 0.
        for t in [&blob, &part] {
            let e = Expr::new(t);
            let b = Interval::new(0.9, 1.1);
            let v = crate::expr::eval_nodes(e.nodes(), b, b, b, &mut Vec::new());
            assert!(v.hi < 0.0, "{v:?}");
        }
        let mut rng = rand_pcg::Pcg64::seed_from_u64(8);
        for (name, t) in [("blob", blob), ("part", part)] {
            let s = surface(&t);
            let mut hits = 0;
            for k in 0..300 {
                let o = if k % 3 == 0 {
                    DVec3::new(rng.gen_range(-0.2..0.2), rng.gen_range(-0.2..0.2), 0.0)
                } else {
                    DVec3::new(rng.gen_range(-2.0..2.0), rng.gen_range(-2.0..2.0), 2.0)
                };
                let target = DVec3::new(rng.gen_range(-0.6..0.6), rng.gen_range(-0.6..0.6), 0.0);
                let ray = Ray::new(o, (target - o).normalize());
                let got = s.first_crossing(&ray, 0.0, 4.0);
                let want = march(&s, &ray, 0.0, 4.0, 40_000);
                match (got, want) {
                    (Some(a), Some(b)) => {
                        hits += 1;
                        assert!((a - b).abs() < 4.0 / 40_000.0, "{name}: {a} vs {b}");
                    }
                    (None, None) => {}
                    _ => panic!("{name}: {got:?} vs march {want:?} for {ray:?}"),
                }
            }
            assert!(hits > 100, "{name}: only {hits} hits");
        }
    }

    /// A model that does not depend on z gets its grid as a quadtree of columns: a disc
    /// union (min/max, in the plane) has the fine grid, each column one occupancy and one
    /// tape along z, and every ray's first crossing agrees with a dense march.
    #[test]
    fn planar_models_get_a_grid_of_columns() {
        let (x, y) = (Tree::x(), Tree::y());
        let disc = |a: f64, b: f64, r: f64| r * r - ((&x - a).square() + (&y - b).square());
        let t = disc(0.0, 0.0, 0.5)
            .max(&disc(0.6, 0.2, 0.25))
            .min(&(0.45 - (&x + 0.3).abs()).max(&disc(-0.5, -0.5, 0.2)));
        let s = surface(&t);
        let g = s.grid.view();
        assert_eq!(
            g.n,
            occupancy::FINE_GRID,
            "a planar model gets the fine grid"
        );
        let n = g.n;
        let (mut occupied, mut columns) = (0, 0);
        for yx in 0..n * n {
            let at = |z: usize| z * n * n + yx;
            let occ = |k: usize| g.words[k / 64] >> (k % 64) & 1 == 1;
            assert!((0..n).all(|z| occ(at(z)) == occ(at(0)) && g.cells[at(z)] == g.cells[at(0)]));
            occupied += usize::from(occ(at(0)));
            columns += 1;
        }
        assert!(
            occupied > 50 && occupied < columns / 2,
            "{occupied} of {columns}"
        );
        let mut rng = rand_pcg::Pcg64::seed_from_u64(21);
        let mut hits = 0;
        for k in 0..300 {
            let o = DVec3::new(rng.gen_range(-2.0..2.0), rng.gen_range(-2.0..2.0), 2.0);
            // Down the columns, steep and oblique.
            let target = if k % 2 == 0 {
                DVec3::new(o.x, o.y, -2.0) + 0.05 * DVec3::new(rng.gen(), rng.gen(), 0.0)
            } else {
                DVec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), -1.0)
            };
            let ray = Ray::new(o, (target - o).normalize());
            let got = s.first_crossing(&ray, 0.0, 5.0);
            let want = march(&s, &ray, 0.0, 5.0, 40_000);
            match (got, want) {
                (Some(a), Some(b)) => {
                    hits += 1;
                    assert!((a - b).abs() < 5.0 / 40_000.0, "{a} vs {b}");
                }
                (None, None) => {}
                _ => panic!("{got:?} vs march {want:?} for {ray:?}"),
            }
        }
        assert!(hits > 60, "only {hits} hits");
    }

    /// Fidget's prospero (text in the plane, 7 592 nodes), which had no grid (its octree
    /// ran past the build budget): with its grid of columns, rays from the top and
    /// oblique ones find the crossings of the whole tape searched without a grid.
    #[test]
    fn prospero_gets_a_grid_and_the_same_hits() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let model = crate::read::read_file(&root.join("models/fidget/prospero.vm")).unwrap();
        let crate::Shape::Function { tree, .. } = &model.shape else {
            panic!("prospero: not one expression");
        };
        let e = Expr::new(tree);
        let b = expr_bounds(&e, Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)));
        let s = ExprSurface::new(e, b);
        let with = s.view();
        assert_eq!(with.grid.n, occupancy::FINE_GRID);
        let without = ExprView {
            grid: GridView::default(),
            ..with
        };
        let mut rng = rand_pcg::Pcg64::seed_from_u64(34);
        let mut hits = 0;
        for k in 0..160 {
            let o = DVec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), 1.0);
            let d = if k % 2 == 0 {
                -DVec3::Z
            } else {
                DVec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), -1.0).normalize()
            };
            let ray = Ray::new(o, d);
            let got = with.trace(&ray, 0.0, 3.0, false).map(|(t, _)| t);
            let want = without.trace(&ray, 0.0, 3.0, false).map(|(t, _)| t);
            match (got, want) {
                (Some(a), Some(b)) => {
                    hits += 1;
                    assert!((a - b).abs() < 1e-9, "{a} vs {b} for {ray:?}");
                }
                (None, None) => {}
                _ => panic!("{got:?} with the grid, {want:?} without, for {ray:?}"),
            }
        }
        assert!(hits > 20, "only {hits} hits");
    }

    /// A half-space (its solid cut by the search domain) is hit at its plane, not
    /// missed for the domain's far face; a prism cut by its declared domain is capped
    /// there, entering and leaving.
    #[test]
    fn solids_cut_by_their_domain_are_hit_and_capped() {
        use crate::{Shape, Solid};
        let half = Solid::build(&Shape::function(0.5 - Tree::z())).unwrap();
        for d in [-DVec3::Z, DVec3::new(0.1, 0.2, -1.0).normalize()] {
            let r = Ray::new(DVec3::new(0.0, 0.0, 5.0), d);
            let h = half.intersect(&r, 0.0, f64::INFINITY).expect("the plane");
            assert!(
                (r.at(h.t).z - 0.5).abs() < 1e-9 && h.normal.z > 0.999,
                "{h:?}"
            );
        }
        let disc = 0.25 - Tree::x().square() - Tree::y().square();
        let domain = Some(Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)));
        let prism = Solid::build(&Shape::Function { tree: disc, domain }).unwrap();
        let down = Ray::new(DVec3::new(0.1, 0.0, 3.0), -DVec3::Z);
        let h = prism.intersect(&down, 0.0, f64::INFINITY).expect("the cap");
        assert!(
            (down.at(h.t).z - 1.0).abs() < 1e-3 && h.normal == DVec3::Z,
            "{h:?}"
        );
        let up = Ray::new(DVec3::new(0.1, 0.0, 0.0), DVec3::Z);
        let h = prism
            .intersect(&up, 0.0, f64::INFINITY)
            .expect("the cap, leaving");
        assert!((up.at(h.t).z - 1.0).abs() < 1e-3, "{h:?}");
    }
}
