//! Solids ready for ray queries, built from a [`Shape`].
//!
//! Building folds every transform into its leaves (a moved quadric is a quadric; a moved
//! expression is an expression), bounds each leaf, and keeps min/max CSG as a tree whose
//! crossings combine exactly along the ray: each part reports its own crossings, and the
//! combined inside/outside state (any / all / a-and-not-b) flips only where it says so.

use crate::bounds::{expr_bounds, DEFAULT_DOMAIN};
use crate::expr::Expr;
use crate::interval_trace::ExprSurface;
use crate::ray::{Aabb, Ray};
use crate::shape::Shape;
use crate::surface::Surface;
use crate::transform::Affine;
use glam::DVec3;

/// A ray's first crossing of a solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: f64,
    /// Outward unit normal at the hit.
    pub normal: DVec3,
}

/// A solid ready for ray queries (see the module docs).
pub enum Solid {
    /// A solid with its own intersector.
    Leaf(Box<dyn Surface>),
    /// Inside any part.
    Union(Vec<Solid>, Aabb),
    /// Inside every part.
    Intersection(Vec<Solid>, Aabb),
    /// Inside the first part and outside the second.
    Difference(Box<Solid>, Box<Solid>, Aabb),
}

/// How a CSG node combines its parts' inside states.
#[derive(Clone, Copy)]
enum Rule {
    Any,
    All,
    FirstNotSecond,
}

impl Rule {
    fn apply(self, s: &[bool]) -> bool {
        match self {
            Rule::Any => s.iter().any(|&b| b),
            Rule::All => s.iter().all(|&b| b),
            Rule::FirstNotSecond => s[0] && !s[1],
        }
    }
}

impl Solid {
    /// Builds a solid from a shape. Expression leaves are bounded inside their declared
    /// domain, else inside ±[`DEFAULT_DOMAIN`].
    pub fn build(shape: &Shape) -> Result<Solid, String> {
        Self::build_moved(shape, &Affine::IDENTITY)
    }

    fn build_moved(shape: &Shape, m: &Affine) -> Result<Solid, String> {
        Ok(match shape {
            Shape::Function { tree, domain } => {
                let moved = m
                    .apply(tree)
                    .ok_or_else(|| format!("singular transform {m:?}"))?;
                let domain = domain.map(|d| transform_box(&d, m)).unwrap_or(Aabb::new(
                    DVec3::splat(-DEFAULT_DOMAIN),
                    DVec3::splat(DEFAULT_DOMAIN),
                ));
                let expr = Expr::new(&moved);
                let bounds = expr_bounds(&expr, domain);
                Solid::Leaf(Box::new(ExprSurface::new(expr, bounds)))
            }
            Shape::Perturbed(p) => {
                // A moved quadric is a quadric: the exact path survives any transform.
                let moved = p
                    .transformed(m)
                    .ok_or_else(|| format!("singular transform {m:?}"))?;
                Solid::Leaf(Box::new(moved.surface()))
            }
            Shape::Union(v) => {
                let parts = v
                    .iter()
                    .map(|s| Self::build_moved(s, m))
                    .collect::<Result<Vec<_>, _>>()?;
                let b = parts.iter().fold(Aabb::EMPTY, |b, p| b.union(&p.bounds()));
                let b = tighten(shape, m, b)?;
                Solid::Union(parts, b)
            }
            Shape::Intersection(v) => {
                let parts = v
                    .iter()
                    .map(|s| Self::build_moved(s, m))
                    .collect::<Result<Vec<_>, _>>()?;
                let b = parts
                    .iter()
                    .fold(Aabb::EVERYTHING, |b, p| b.intersection(&p.bounds()));
                let b = tighten(shape, m, b)?;
                Solid::Intersection(parts, b)
            }
            Shape::Difference(a, b) => {
                let (a, b) = (Self::build_moved(a, m)?, Self::build_moved(b, m)?);
                let bounds = tighten(shape, m, a.bounds())?;
                Solid::Difference(Box::new(a), Box::new(b), bounds)
            }
            Shape::Transformed(inner, s) => Self::build_moved(s, &inner.then(m))?,
        })
    }

    /// The first crossing in (t_min, t_max) with its outward normal.
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<Hit> {
        match self {
            Solid::Leaf(s) => {
                let (t, normal) = s.first_hit(ray, t_min, t_max)?;
                Some(Hit { t, normal })
            }
            Solid::Union(parts, b) => combine(parts, b, Rule::Any, ray, t_min, t_max),
            Solid::Intersection(parts, b) => combine(parts, b, Rule::All, ray, t_min, t_max),
            Solid::Difference(a, b, bounds) => {
                let parts = [a.as_ref(), b.as_ref()];
                combine_refs(&parts, bounds, Rule::FirstNotSecond, ray, t_min, t_max)
            }
        }
    }

    /// Whether p is inside (F ≥ 0).
    pub fn inside(&self, p: DVec3) -> bool {
        Surface::value(self, p) >= 0.0
    }
}

/// A CSG node's bounds from its parts can be infinite (half-spaces cut into a box);
/// then the whole node's expression is bounded by interval octree refinement, which
/// sees how the parts combine.
fn tighten(shape: &Shape, m: &Affine, from_parts: Aabb) -> Result<Aabb, String> {
    if from_parts.is_finite() || from_parts.is_empty() {
        return Ok(from_parts);
    }
    let tree = m
        .apply(&shape.to_tree()?)
        .ok_or_else(|| format!("singular transform {m:?}"))?;
    let domain = Aabb::new(DVec3::splat(-DEFAULT_DOMAIN), DVec3::splat(DEFAULT_DOMAIN));
    let b = expr_bounds(&Expr::new(&tree), domain.intersection(&from_parts));
    // What touches the search domain's faces may go on beyond it: keep it unbounded.
    let touches = (0..3).any(|k| b.lo[k] <= -DEFAULT_DOMAIN || b.hi[k] >= DEFAULT_DOMAIN);
    Ok(if touches { from_parts } else { b })
}

/// Bounding box of a box's image.
fn transform_box(b: &Aabb, m: &Affine) -> Aabb {
    let mut out = Aabb::EMPTY;
    for k in 0..8 {
        let c = DVec3::new(
            if k & 1 == 0 { b.lo.x } else { b.hi.x },
            if k & 2 == 0 { b.lo.y } else { b.hi.y },
            if k & 4 == 0 { b.lo.z } else { b.hi.z },
        );
        out.include(m.point(c));
    }
    out
}

fn combine(parts: &[Solid], b: &Aabb, rule: Rule, ray: &Ray, t0: f64, t1: f64) -> Option<Hit> {
    let refs: Vec<&Solid> = parts.iter().collect();
    combine_refs(&refs, b, rule, ray, t0, t1)
}

/// Walks the parts' crossings in order, flipping each part's state, until the combined
/// state flips. A part's next crossing is searched a hair past its last one so that a
/// root found to rounding is never found twice.
fn combine_refs(
    parts: &[&Solid],
    bounds: &Aabb,
    rule: Rule,
    ray: &Ray,
    t_min: f64,
    t_max: f64,
) -> Option<Hit> {
    let (lo, hi) = if bounds.is_finite() {
        let grown = Aabb::new(bounds.lo - 1e-9, bounds.hi + 1e-9);
        grown.clip(ray, t_min, t_max)?
    } else {
        (t_min, t_max)
    };
    let nudge = 1e-10 * bounds.extent().length().clamp(1.0, 1e12) / ray.d.length();
    // Each part's state at the start of the clipped range: a part may well be inside
    // there even though the combination is not.
    let start = ray.at(lo);
    let mut state: Vec<bool> = parts.iter().map(|p| p.inside(start)).collect();
    let mut combined = rule.apply(&state);
    let mut next: Vec<Option<Hit>> = parts.iter().map(|p| p.intersect(ray, lo, hi)).collect();
    loop {
        let (k, h) = next
            .iter()
            .enumerate()
            .filter_map(|(k, h)| h.map(|h| (k, h)))
            .min_by(|a, b| a.1.t.total_cmp(&b.1.t))?;
        state[k] = !state[k];
        let now = rule.apply(&state);
        if now != combined {
            let normal = match (rule, k) {
                (Rule::FirstNotSecond, 1) => -h.normal,
                _ => h.normal,
            };
            return Some(Hit { t: h.t, normal });
        }
        combined = now;
        next[k] = parts[k].intersect(ray, h.t + nudge.max(h.t.abs() * 1e-15), hi);
    }
}

impl Surface for Solid {
    fn value(&self, p: DVec3) -> f64 {
        match self {
            Solid::Leaf(s) => s.value(p),
            Solid::Union(v, _) => v
                .iter()
                .map(|s| s.value(p))
                .fold(f64::NEG_INFINITY, f64::max),
            Solid::Intersection(v, _) => v.iter().map(|s| s.value(p)).fold(f64::INFINITY, f64::min),
            Solid::Difference(a, b, _) => a.value(p).min(-b.value(p)),
        }
    }

    fn gradient(&self, p: DVec3) -> DVec3 {
        // The gradient of min/max is the active part's.
        let pick = |v: &[Solid], max: bool| {
            let best = v.iter().max_by(|a, b| {
                let (x, y) = (a.value(p), b.value(p));
                if max {
                    x.total_cmp(&y)
                } else {
                    y.total_cmp(&x)
                }
            });
            best.map_or(DVec3::ZERO, |s| s.gradient(p))
        };
        match self {
            Solid::Leaf(s) => s.gradient(p),
            Solid::Union(v, _) => pick(v, true),
            Solid::Intersection(v, _) => pick(v, false),
            Solid::Difference(a, b, _) => {
                if a.value(p) <= -b.value(p) {
                    a.gradient(p)
                } else {
                    -b.gradient(p)
                }
            }
        }
    }

    fn first_crossing(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        self.intersect(ray, t_min, t_max).map(|h| h.t)
    }

    fn bounds(&self) -> Aabb {
        match self {
            Solid::Leaf(s) => s.bounds(),
            Solid::Union(_, b) | Solid::Intersection(_, b) | Solid::Difference(_, _, b) => *b,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Tree;

    fn ball(c: DVec3, r: f64) -> Shape {
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        Shape::function(r * r - ((x - c.x).square() + (y - c.y).square() + (z - c.z).square()))
    }

    /// Span logic along the x axis through two overlapping balls, [-2, 0.5] and [-0.5, 2]
    /// for union / intersection / difference, checked against the analytic crossings.
    #[test]
    fn csg_spans_along_a_line() {
        let a = ball(DVec3::new(-0.75, 0.0, 0.0), 1.25);
        let b = ball(DVec3::new(0.75, 0.0, 0.0), 1.25);
        let ray = Ray::new(DVec3::new(-5.0, 0.0, 0.0), DVec3::X);
        let cases: [(Shape, &[f64]); 4] = [
            (Shape::Union(vec![a.clone(), b.clone()]), &[-2.0, 2.0]),
            (
                Shape::Intersection(vec![a.clone(), b.clone()]),
                &[-0.5, 0.5],
            ),
            (
                Shape::Difference(Box::new(a.clone()), Box::new(b.clone())),
                &[-2.0, -0.5],
            ),
            (
                Shape::Difference(Box::new(b.clone()), Box::new(a.clone())),
                &[0.5, 2.0],
            ),
        ];
        for (i, (shape, want)) in cases.iter().enumerate() {
            let s = Solid::build(shape).unwrap();
            let mut t = 0.0;
            let mut got = vec![];
            while let Some(h) = s.intersect(&ray, t, 100.0) {
                got.push(h.t - 5.0);
                // Normals point out: against the ray on entry, along it on exit.
                let entering = got.len() % 2 == 1;
                assert_eq!(h.normal.x < 0.0, entering, "case {i} at {}", h.t - 5.0);
                t = h.t + 1e-9;
            }
            assert_eq!(got.len(), want.len(), "case {i}: {got:?}");
            for (g, w) in got.iter().zip(want.iter()) {
                assert!((g - w).abs() < 1e-8, "case {i}: {got:?} vs {want:?}");
            }
        }
    }

    #[test]
    fn transforms_move_the_crossings() {
        let s = Shape::Transformed(
            Affine::translate(DVec3::new(0.0, 0.0, 2.0)),
            Box::new(Shape::Transformed(
                Affine::scale(DVec3::new(1.0, 1.0, 3.0)),
                Box::new(ball(DVec3::ZERO, 1.0)),
            )),
        );
        let s = Solid::build(&s).unwrap();
        let ray = Ray::new(DVec3::new(0.0, 0.0, 10.0), -DVec3::Z);
        let h = s.intersect(&ray, 0.0, f64::INFINITY).unwrap();
        assert!((h.t - 5.0).abs() < 1e-8, "{h:?}");
        assert!((h.normal - DVec3::Z).length() < 1e-6);
    }
}
