//! Differential tests of the CSG walk and of the fast paths added for speed, on random
//! CSG trees (depth ≤ 4; union, intersection and difference, n-ary; spheres, ellipsoids,
//! infinite cylinders and cones, axis and rotated boxes, slabs, half-spaces and perturbed
//! spheres, moved and rotated; nested and overlapping) and random rays (from inside and
//! outside, far eyes, grazing a part's surface, through the edges where two parts meet):
//!
//! - the closed-form walk ([`Solid`] of the tree) against a dense march of F: the list of
//!   its crossings predicts F's sign at every march sample;
//! - the closed-form walk against the general expression path (the same tree lowered to
//!   one expression, traced by intervals): the same crossings, beyond the latter's
//!   documented resolution (`interval_trace::RESOLUTION` of its bounds);
//! - early-out shadow rays: `occludes` equals `intersect(..).is_some()` on random
//!   stretches of each ray, on both paths;
//! - convex-solid skipping: a ray leaving a solid that calls itself convex never meets
//!   it again;
//! - the occupancy grid and its cell tapes: the expression path's crossings with the grid
//!   equal those without it, and each cell's tape evaluates as the whole tape;
//! - R-function interval narrowing: random R-function and blend trees' interval values
//!   over random boxes hold every point value inside them.
//!
//! Fixed seeds. `FREPRAY_CSG_TREES` sets the number of trees (the long run,
//! `scripts/long-test.sh`, sets hundreds of thousands); each test prints what it tried.

use crate::common;

use common::random_csg::{plain, point, rays, unit, Gen};
use frep::interval_trace::resolution;
use frep::occupancy::GridView;
use frep::{Expr, LeafView, Quadric, Ray, Shape, Solid, Surface};
use frep::{ExprView, Tree};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// How many trees to try: `FREPRAY_CSG_TREES`, else `default`.
fn trees(default: usize) -> usize {
    std::env::var("FREPRAY_CSG_TREES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Rays per tree.
const RAYS: usize = 100;
/// How far rays go: origins lie in [−3, 3]³ or on a sphere of radius 6, so rays stay well
/// inside the ±100 search domain the expression path caps unbounded solids at.
const T_MAX: f64 = 14.0;
/// March samples per ray.
const MARCH: usize = 200;

/// Every crossing of `s` on (t0, t1), walked from hit to hit (at most 64), each search
/// starting `step` past the last hit (0: from exactly there).
fn crossings(s: &Solid, ray: &Ray, t0: f64, t1: f64, step: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut t = t0;
    while out.len() < 64 {
        match s.intersect(ray, t, t1) {
            Some(h) => {
                assert!(h.t > t && h.t < t1, "{h:?} outside ({t}, {t1})");
                out.push(h.t);
                t = h.t + step;
            }
            None => break,
        }
    }
    out
}

/// Counts of what a run tried and found.
#[derive(Default, Debug)]
struct Tally {
    trees: usize,
    rays: usize,
    crossings: usize,
    march_samples: usize,
    /// March intervals whose crossing count is off by a touch (see [`check_march`]).
    touches: usize,
    expr_compared: usize,
    /// Disagreements with the expression path explained by its resolution: the closed
    /// form's crossings there come in a pair closer than it resolves.
    below_resolution: usize,
    occludes: usize,
    convex_rays: usize,
    grid_compared: usize,
    failures: Vec<String>,
    /// Disagreements within 10⁻⁴ of a grazing or edge ray's point (see [`Tally::fail`]).
    degenerate: usize,
    /// Disagreements on grazing or edge rays past their point (a walk continued from a
    /// crossing there, where the state it takes is rounding's choice).
    past_degenerate: usize,
    /// The current ray's grazing or edge point, if it has one.
    special: Option<f64>,
    /// The tree of the first disagreement.
    first_shape: Option<String>,
}

impl Tally {
    /// Records a disagreement over (a, b) on the ray. Within 10⁻⁴ of the point where a
    /// grazing ray touches a part or an edge ray meets two, it is counted as degenerate
    /// instead: there F is within rounding of 0 along the ray, and which side a path
    /// takes is rounding's choice (a walk continued from there may take the wrong side
    /// for the rest of the ray, so the ray is not compared further either way).
    fn fail_at(&mut self, (a, b): (f64, f64), what: String) {
        if self.special.is_some_and(|s| s > a - 1e-4 && s < b + 1e-4) {
            self.degenerate += 1;
        } else if self.special.is_some_and(|s| a > s) {
            self.past_degenerate += 1;
        } else {
            self.fail(what);
        }
    }

    fn fail(&mut self, what: String) {
        if self.failures.len() < 20 {
            self.failures.push(what);
        }
    }
}

/// The closed-form walk's crossings account for every sign change of F (evaluated point
/// by point from the expression) between march samples: between two samples of unlike
/// sign it reports an odd number of crossings, between two of like sign an even number.
/// An interval where the count is off is excused only when it holds a touch: a crossing
/// with F of one sign 10⁻⁷ to either side (a sliver narrower than the walk's nudge, or a
/// ray through an edge, which the walk reports where it shows and then steps past).
/// Samples within 10⁻⁷ of a crossing or where |F| is below its rounding are passed over.
/// The march covers the ray within `within` (the expression path's bounds, found by
/// intervals apart from the walk), outside which F < 0 and the walk must report nothing.
fn check_march(
    (f, within): (&Expr, &frep::Aabb),
    s: &Solid,
    ray: &Ray,
    c: &[f64],
    tally: &mut Tally,
    id: &str,
) {
    let span = if within.is_finite() {
        frep::Aabb::new(within.lo - 1e-3, within.hi + 1e-3).clip(ray, 0.0, T_MAX)
    } else {
        Some((0.0, T_MAX))
    };
    let Some((lo, hi)) = span else {
        if !c.is_empty() {
            tally.fail(format!(
                "{id}: crossings {c:?} outside the bounds {within:?}"
            ));
        }
        return;
    };
    if c.iter().any(|&x| x < lo || x > hi) {
        tally.fail(format!(
            "{id}: crossings {c:?} outside the bounds' span ({lo}, {hi})"
        ));
        return;
    }
    // One scratch for the whole march (`Expr::eval` allocates one per call).
    let scratch = std::cell::RefCell::new(Vec::with_capacity(f.len()));
    let at = |t: f64| {
        let p = ray.at(t);
        f.eval_with(p.x, p.y, p.z, &mut scratch.borrow_mut())
    };
    let touch = |t: f64| {
        let (a, b) = (at(t - 1e-7), at(t + 1e-7));
        a != 0.0 && b != 0.0 && (a > 0.0) == (b > 0.0)
    };
    let (mut prev, mut k) = ((lo, at(lo)), 0);
    for j in 1..=MARCH {
        let t = lo + (hi - lo) * j as f64 / MARCH as f64;
        let near = c.iter().any(|&x| (x - t).abs() < 1e-7);
        let v = at(t);
        if near || v.abs() < 1e-11 {
            continue;
        }
        tally.march_samples += 1;
        let from = k;
        while k < c.len() && c[k] < t {
            k += 1;
        }
        let flips = (prev.1 >= 0.0) != (v >= 0.0);
        if prev.1.abs() >= 1e-11 && flips != ((k - from) % 2 == 1) {
            if c[from..k].iter().any(|&x| touch(x)) {
                tally.touches += 1;
            } else {
                tally.fail_at(
                    (prev.0, t),
                    format!(
                        "{id}: F = {:e} at t = {} and {v:e} at {t}, but the walk reports {} \
                     crossings between (all: {c:?})",
                        prev.1,
                        prev.0,
                        k - from
                    ),
                );
                return;
            }
        }
        prev = (t, v);
    }
    // The walk's own idea of the start state agrees.
    let start = at(0.0);
    if start.abs() > 1e-11 && s.inside(ray.o) != (start >= 0.0) {
        tally.fail(format!(
            "{id}: inside(o) is {} but F(o) = {start}",
            start < 0.0
        ));
    }
}

/// The expression path finds the closed form's crossings, from the ray's start and from
/// a thousandth of its resolution past each crossing on, within 10⁻⁶. Where they
/// differ, the path with the earlier answer must have it within a sliver, a pair of its
/// crossings closer than the expression path's resolution `eps_t` (a feature it may
/// miss or, where F touches 0 to rounding, report by contract), and the ray is not
/// compared further.
fn check_expr(
    (e, f): (&Solid, &Expr),
    ray: &Ray,
    c: &[f64],
    eps_t: f64,
    tally: &mut Tally,
    id: &str,
) {
    let mut from = 0.0;
    for (k, &want) in c.iter().chain([&f64::INFINITY]).enumerate() {
        let got = e.intersect(ray, from, T_MAX).map(|h| h.t);
        tally.expr_compared += 1;
        let agree = match got {
            Some(g) => (g - want).abs() <= 1e-6,
            None => want == f64::INFINITY,
        };
        if !agree {
            let next = |t: f64| e.intersect(ray, t + 1e-3 * eps_t, T_MAX).map(|h| h.t);
            if sliver(c, k, got, eps_t, next, |t| touches(f, ray, t, eps_t)) {
                tally.below_resolution += 1;
            } else {
                let g = got.unwrap_or(T_MAX);
                tally.fail_at(
                    (g.min(want), g.max(want).min(T_MAX)),
                    format!(
                        "{id}: from {from}: expression path {got:?}, closed form {want} \
                     (crossings {c:?}, resolution {eps_t:e})"
                    ),
                );
            }
            return;
        }
        if want.is_finite() {
            // Past the root's refinement (10⁻⁵ of the resolution), which may find the
            // same root again from exactly where it lies.
            from = want + 1e-3 * eps_t;
        }
    }
}

/// Whether a disagreement at the closed form's crossing k (`c`, ∞ past its last) with
/// another path's answer `got` is a sliver below the resolution `eps_t`: the closed
/// form's crossing k pairs with its neighbour within 2·eps_t, or the other path's
/// answer pairs with that path's next crossing (`next`) within 2·eps_t, the earlier
/// answer being the one in the pair; or the earlier answer is where F only touches 0
/// (`touch`: no crossing of the other path near it).
fn sliver(
    c: &[f64],
    k: usize,
    got: Option<f64>,
    eps_t: f64,
    next: impl Fn(f64) -> Option<f64>,
    touch: impl Fn(f64) -> bool,
) -> bool {
    let want = c.get(k).copied().unwrap_or(f64::INFINITY);
    let g = got.unwrap_or(f64::INFINITY);
    let close = |a: f64, b: f64| (b - a).abs() <= 2.0 * eps_t;
    if want < g {
        (k + 1 < c.len() && close(c[k], c[k + 1]))
            || (k > 0 && close(c[k - 1], c[k]))
            || touch(want)
    } else {
        next(g).is_some_and(|g2| close(g, g2) && g2 <= want + 1e-6)
            || (k > 0 && close(c[k - 1], g))
            || (touch(g) && !c.iter().any(|&x| close(x, g)))
    }
}

/// Whether F only touches 0 at t (to rounding: a ray through a point where parts meet,
/// or grazing a part): it has one sign, not 0, 2·`eps_t` to either side.
fn touches(f: &Expr, ray: &Ray, t: f64, eps_t: f64) -> bool {
    let (a, b) = (
        f.eval(ray.at(t - 2.0 * eps_t).to_array()),
        f.eval(ray.at(t + 2.0 * eps_t).to_array()),
    );
    a != 0.0 && b != 0.0 && (a > 0.0) == (b > 0.0)
}

/// `occludes` is `intersect(..).is_some()` on the whole ray and on random stretches of it.
fn check_occludes(s: &Solid, ray: &Ray, rng: &mut Pcg64, tally: &mut Tally, id: &str) {
    let what = if matches!(s.flat().leaf(0), LeafView::Expr(_)) && s.flat().leaves.len() == 1 {
        "expression path"
    } else {
        "closed form"
    };
    for k in 0..4 {
        let (a, b) = if k == 0 {
            (0.0, T_MAX)
        } else {
            let a = rng.gen_range(0.0..T_MAX);
            (a, a + rng.gen_range(0.0..T_MAX - a))
        };
        tally.occludes += 1;
        let want = s.intersect(ray, a, b).is_some();
        if s.occludes(ray, a, b) != want {
            tally.fail(format!("{id}: {what}: occludes on ({a}, {b}) is {}", !want));
        }
    }
}

/// A solid that calls itself convex is never met again by a ray leaving it outward.
fn check_convex(s: &Solid, ray: &Ray, tally: &mut Tally, id: &str) {
    let mut t = 0.0;
    while let Some(h) = s.intersect(ray, t, T_MAX) {
        if ray.d.dot(h.normal) > 0.0 {
            tally.convex_rays += 1;
            if let Some(again) = s.intersect(ray, h.t + 1e-9, T_MAX) {
                tally.fail(format!(
                    "{id}: convex solid left at {} met again at {}",
                    h.t, again.t
                ));
            }
            return;
        }
        t = h.t;
    }
}

/// The expression path's leaf with its grid against itself without it: the same
/// crossings, beyond slivers below the resolution (as [`check_expr`]).
fn check_grid(v: &ExprView, f: &Expr, ray: &Ray, tally: &mut Tally, id: &str) {
    let none = ExprView {
        grid: GridView::NONE,
        ..*v
    };
    let eps_t = v.eps / ray.d.length();
    let walk = |w: &ExprView| {
        let mut out = Vec::new();
        let mut t = 0.0;
        while let Some((h, _)) = w.trace(ray, t, T_MAX, false).filter(|_| out.len() < 16) {
            out.push(h);
            t = h + 1e-3 * eps_t;
        }
        out
    };
    let (g, p) = (walk(v), walk(&none));
    tally.grid_compared += 1;
    for k in 0..=g.len().max(p.len()) {
        let (a, b) = (g.get(k).copied(), p.get(k).copied());
        let agree = match (a, b) {
            (Some(a), Some(b)) => (a - b).abs() <= 1e-9,
            (None, None) => return,
            _ => false,
        };
        if !agree {
            let next = |t: f64| p.iter().copied().find(|&x| x > t + 1e-3 * eps_t);
            if sliver(&g, k, b, eps_t, next, |t| touches(f, ray, t, eps_t)) {
                tally.below_resolution += 1;
            } else {
                let (x, y) = (a.unwrap_or(T_MAX), b.unwrap_or(T_MAX));
                tally.fail_at(
                    (x.min(y), x.max(y)),
                    format!("{id}: grid {g:?}, no grid {p:?}"),
                );
            }
            return;
        }
    }
}

/// The expression path of a tree: the whole tree lowered to one expression leaf.
fn expression_solid(shape: &Shape) -> Solid {
    let tree = shape.to_tree().expect("regular transforms");
    Solid::build(&Shape::function(tree)).expect("an expression solid")
}

fn expr_view(s: &Solid) -> ExprView<'_> {
    match s.flat().leaf(0) {
        LeafView::Expr(v) => v,
        LeafView::Perturbed(_) => panic!("an expression leaf"),
    }
}

fn run(seed: u64, n_trees: usize, grid_every: usize) -> Tally {
    let mut gen = Gen::new(seed);
    let mut rng = Pcg64::seed_from_u64(seed ^ 0x5eed);
    let mut tally = Tally::default();
    for i in 0..n_trees {
        let depth = 1 + i % 4;
        let t = gen.tree(depth);
        if t.quadrics.is_empty() {
            continue;
        }
        let id = format!("seed {seed} tree {i}");
        let closed = Solid::build(&t.shape).unwrap_or_else(|e| panic!("{id}: {e}"));
        let expr = expression_solid(&t.shape);
        let f = Expr::new(&t.shape.to_tree().unwrap());
        let eps_t = resolution(&expr.bounds());
        let convex = closed.is_convex();
        tally.trees += 1;
        let before = tally.failures.len();
        for (k, (ray, special)) in rays(&mut rng, &t, RAYS).iter().enumerate() {
            let id = format!("{id} ray {k} {ray:?}");
            tally.special = *special;
            let c = crossings(&closed, ray, 0.0, T_MAX, 1e-9);
            tally.rays += 1;
            tally.crossings += c.len();
            check_march((&f, &expr.bounds()), &closed, ray, &c, &mut tally, &id);
            check_expr((&expr, &f), ray, &c, eps_t, &mut tally, &id);
            check_occludes(&closed, ray, &mut rng, &mut tally, &id);
            check_occludes(&expr, ray, &mut rng, &mut tally, &id);
            if convex {
                check_convex(&closed, ray, &mut tally, &id);
            }
            if i % grid_every == 0 {
                check_grid(&expr_view(&expr), &f, ray, &mut tally, &id);
            }
        }
        if tally.failures.len() > before && tally.first_shape.is_none() {
            tally.first_shape = Some(format!("{id}: {:?}", t.shape));
        }
        if tally.failures.len() >= 20 {
            break;
        }
    }
    tally
}

fn report(name: &str, tally: &Tally) {
    println!("{name}: {tally:#?}");
    assert!(
        tally.failures.is_empty(),
        "{name}: {} disagreements, first: {:#?}",
        tally.failures.len(),
        tally.failures
    );
}

#[test]
fn random_csg_trees_agree_on_every_path() {
    random_trees(1);
}

/// The same with other trees and rays (a second test, so that the two halves of the
/// default 300 trees run in parallel).
#[test]
fn random_csg_trees_agree_on_every_path_second_seed() {
    random_trees(2);
}

fn random_trees(seed: u64) {
    let n = trees(300) / 2;
    let tally = run(seed, n, 5);
    report(&format!("random CSG trees, seed {seed}"), &tally);
    // What the run must have exercised to mean anything.
    assert!(tally.trees * 9 >= n * 8, "{tally:?}");
    assert!(tally.crossings * 2 > tally.rays, "{tally:?}");
    assert!(tally.convex_rays > 100, "{tally:?}");
    // Slivers below the expression path's resolution and degenerate rays are rare.
    assert!(tally.below_resolution * 20 < tally.rays, "{tally:?}");
    assert!(
        (tally.degenerate + tally.past_degenerate) * 1000 < tally.rays,
        "{tally:?}"
    );
}

/// The reproducers and the unbounded shapes they stand for, as trees: every
/// half-space combined with a bounded part, walked from above and from random points.
#[test]
fn unbounded_parts_in_every_position() {
    let ball = |r: f64| plain(Quadric::sphere(DVec3::ZERO, r));
    let up = plain(Quadric::plane(DVec3::Z, 0.0));
    let cut = plain(Quadric::plane(-DVec3::Z, -0.5));
    let shapes = [
        Shape::Difference(
            Box::new(ball(1.0)),
            Box::new(Shape::Union(vec![ball(0.9), cut.clone()])),
        ),
        Shape::Difference(Box::new(up.clone()), Box::new(ball(0.5))),
        Shape::Union(vec![up.clone(), ball(0.5)]),
        Shape::Intersection(vec![
            up.clone(),
            Shape::Difference(Box::new(ball(1.0)), Box::new(ball(0.8))),
        ]),
        Shape::Difference(
            Box::new(Shape::Union(vec![up, cut])),
            Box::new(Shape::Difference(Box::new(ball(1.0)), Box::new(ball(0.5)))),
        ),
    ];
    let mut rng = Pcg64::seed_from_u64(34);
    let mut tally = Tally::default();
    for (i, shape) in shapes.iter().enumerate() {
        let closed = Solid::build(shape).unwrap();
        let expr = expression_solid(shape);
        let f = Expr::new(&shape.to_tree().unwrap());
        let eps_t = resolution(&expr.bounds());
        for k in 0..400 {
            let ray = if k < 100 {
                let o = DVec3::new(rng.gen_range(-1.2..1.2), rng.gen_range(-1.2..1.2), 3.0);
                Ray::new(o, -DVec3::Z)
            } else {
                let o = point(&mut rng, 3.0);
                Ray::new(o, (point(&mut rng, 1.0) - o).normalize())
            };
            let id = format!("shape {i} {ray:?}");
            let c = crossings(&closed, &ray, 0.0, T_MAX, 0.0);
            tally.rays += 1;
            tally.crossings += c.len();
            check_march((&f, &expr.bounds()), &closed, &ray, &c, &mut tally, &id);
            check_expr((&expr, &f), &ray, &c, eps_t, &mut tally, &id);
            check_occludes(&closed, &ray, &mut rng, &mut tally, &id);
        }
    }
    report("unbounded parts", &tally);
}

/// One inside convention, F ≥ 0, on the closed-form paths: rays lying exactly in a box's
/// face, in a half-space's plane and on a cylinder's surface are inside there, as the
/// expression path and `inside` say, so they hit where they leave.
#[test]
fn rays_lying_in_a_surface_are_inside_it() {
    let cube: Vec<Shape> = [DVec3::X, DVec3::Y, DVec3::Z]
        .into_iter()
        .flat_map(|n| {
            [
                plain(Quadric::plane(n, 0.5)),
                plain(Quadric::plane(-n, 0.5)),
            ]
        })
        .collect();
    // The same planes in another order: the general polytope path, not the slab test.
    let mut reordered = cube.clone();
    reordered.reverse();
    let capped = Shape::Intersection(vec![
        plain(Quadric::cylinder(DVec3::ZERO, DVec3::X, 0.5)),
        plain(Quadric::plane(DVec3::X, 0.5)),
        plain(Quadric::plane(-DVec3::X, 0.5)),
    ]);
    // Along x in the face z = 0.5, on the edge y = z = 0.5, on the cylinder y² + z² = ¼.
    let in_face = Ray::new(DVec3::new(-0.2, 0.1, 0.5), DVec3::X);
    let on_edge = Ray::new(DVec3::new(-0.2, 0.5, 0.5), DVec3::X);
    let on_cylinder = Ray::new(DVec3::new(-0.2, 0.0, 0.5), DVec3::X);
    let cases = [
        (Shape::Intersection(cube.clone()), in_face, 0.7),
        (Shape::Intersection(cube), on_edge, 0.7),
        (Shape::Intersection(reordered), in_face, 0.7),
        (capped, on_cylinder, 0.7),
        (
            Shape::Intersection(vec![
                plain(Quadric::plane(DVec3::Z, 0.5)),
                plain(Quadric::sphere(DVec3::ZERO, 1.0)),
            ]),
            in_face,
            (1.0f64 - 0.01 - 0.25).sqrt() + 0.2,
        ),
    ];
    for (i, (shape, ray, t)) in cases.iter().enumerate() {
        let s = Solid::build(shape).unwrap();
        assert!(s.inside(ray.o), "case {i}");
        let h = s.intersect(ray, 0.0, 10.0);
        assert!(
            h.is_some_and(|h| (h.t - t).abs() < 1e-12),
            "case {i}: {h:?}, want {t}"
        );
        assert!(s.occludes(ray, 0.0, 10.0), "case {i}");
        let e = expression_solid(shape).intersect(ray, 0.0, 10.0);
        assert!(
            e.is_some_and(|h| (h.t - t).abs() < 1e-6),
            "case {i}: expression {e:?}"
        );
    }
}

/// R-function narrowing is sound: over random boxes, the interval value of random trees
/// of R-unions, R-intersections, R-differences and blends holds F at random points of the
/// box.
#[test]
fn r_function_intervals_hold_their_point_values() {
    use frep::csg::{blend_intersection, blend_union, r_difference, r_intersection, r_union};
    let mut rng = Pcg64::seed_from_u64(11);
    let n = trees(1500);
    let (mut boxes, mut points) = (0, 0);
    for i in 0..n {
        let t = r_tree(&mut rng, 1 + i % 4);
        let e = Expr::new(&t);
        for _ in 0..20 {
            let c = point(&mut rng, 1.5);
            let h = DVec3::new(
                rng.gen_range(0.0..0.6),
                rng.gen_range(0.0..0.6),
                rng.gen_range(0.0..0.6),
            ) * if rng.gen_bool(0.3) { 0.01 } else { 1.0 };
            let (lo, hi) = (c - h, c + h);
            let iv = e.eval_interval(lo.to_array(), hi.to_array());
            boxes += 1;
            for _ in 0..10 {
                let u = DVec3::new(rng.gen(), rng.gen(), rng.gen());
                let p = lo + (hi - lo) * u;
                let v = e.eval(p.to_array());
                points += 1;
                let slack = 1e-12 * (1.0 + v.abs());
                assert!(
                    v >= iv.lo - slack && v <= iv.hi + slack,
                    "tree {i}: F({p:?}) = {v} outside {iv:?} over {lo:?}..{hi:?}: {t:?}"
                );
            }
        }
    }
    println!("R-function narrowing: {n} trees, {boxes} boxes, {points} points");

    fn r_tree(rng: &mut Pcg64, depth: usize) -> Tree {
        if depth == 0 || rng.gen_bool(0.2) {
            let q = match rng.gen_range(0..4) {
                0 => Quadric::sphere(point(rng, 1.0), rng.gen_range(0.2..1.0)),
                1 => Quadric::cylinder(point(rng, 1.0), unit(rng), rng.gen_range(0.1..0.7)),
                2 => {
                    let n = unit(rng);
                    Quadric::plane(n, rng.gen_range(-0.5..0.5))
                }
                _ => Quadric::cone(point(rng, 1.0), unit(rng), rng.gen_range(0.2..0.9)),
            };
            return q.to_tree();
        }
        let (a, b) = (r_tree(rng, depth - 1), r_tree(rng, depth - 1));
        let alpha = rng.gen_range(-1.0..1.0);
        let (a0, a1, a2) = (
            rng.gen_range(0.0..1.0),
            rng.gen_range(0.1..2.0),
            rng.gen_range(0.1..2.0),
        );
        match rng.gen_range(0..5) {
            0 => r_union(&a, &b, alpha),
            1 => r_intersection(&a, &b, alpha),
            2 => r_difference(&a, &b, alpha),
            3 => blend_union(&a, &b, a0, a1, a2),
            _ => blend_intersection(&a, &b, a0, a1, a2),
        }
    }
}

/// Each cell's tape of the expression path equals the whole tape at random points of
/// random CSG trees' grids (bit for bit).
#[test]
fn random_trees_cell_tapes_equal_the_whole_tape() {
    use frep::expr::eval_nodes;
    let mut gen = Gen::new(4);
    let mut rng = Pcg64::seed_from_u64(44);
    let (mut n_points, mut shorter) = (0, 0);
    let n = trees(1500) / 5;
    for i in 0..n {
        let t = gen.tree(1 + i % 4);
        let expr = expression_solid(&t.shape);
        let v = expr_view(&expr);
        if !v.grid.is_some() {
            continue;
        }
        let g = frep::Aabb::new(v.bounds.lo - v.eps, v.bounds.hi + v.eps);
        let mut scratch = Vec::new();
        for _ in 0..200 {
            let p = point(&mut rng, 3.0);
            let tape = v.grid.tape_at(&g, p).unwrap_or(v.tape);
            shorter += usize::from(tape.len() < v.tape.len());
            let (a, b) = (
                eval_nodes(v.tape, p.x, p.y, p.z, &mut scratch),
                eval_nodes(tape, p.x, p.y, p.z, &mut scratch),
            );
            n_points += 1;
            assert_eq!(a.to_bits(), b.to_bits(), "tree {i} at {p:?}: {:?}", t.shape);
        }
    }
    println!("cell tapes: {n} trees, {n_points} points, {shorter} on a shorter tape");
    assert!(shorter > n_points / 10, "{shorter} of {n_points}");
}

/// The trees written in the frepray language (`to_frep`, what the GPU tests render) read
/// back as the same solids: the same F, bit for bit, at random points.
#[test]
fn random_trees_read_back_from_their_text() {
    use common::random_csg::to_frep;
    use common::{read_str, Format};
    let mut gen = Gen::new(9);
    let mut rng = Pcg64::seed_from_u64(99);
    for i in 0..200 {
        let t = gen.tree(1 + i % 4);
        let text = format!("output {}", to_frep(&t.shape));
        let m = read_str(&text, Format::Frep, "t.frep").unwrap_or_else(|e| panic!("{e}"));
        let (a, b) = (
            Solid::build(&t.shape).unwrap(),
            Solid::build(&m.shape).unwrap(),
        );
        for _ in 0..100 {
            let p = point(&mut rng, 2.0);
            assert_eq!(
                a.value(p).to_bits(),
                b.value(p).to_bits(),
                "tree {i} at {p:?}"
            );
        }
    }
}
