//! Solids ready for ray queries, built from a [`Shape`].
//!
//! Building folds every transform into its leaves (a moved quadric is a quadric; a moved
//! expression is an expression), bounds each leaf, and keeps min/max CSG as a tree whose
//! crossings combine exactly along the ray: each part reports its own crossings, and the
//! combined inside/outside state (any / all / a-and-not-b) flips only where it says so.
//! The solid is its flat form ([`Flat`]): post-order CSG nodes, a leaf table and pools,
//! intersected in place. Combining crossings keeps each node's part states in fixed
//! arrays of [`MAX_PARTS`] on the stack, nesting at most [`MAX_DEPTH`] deep (wider nodes
//! are split at build, deeper ones are a build error), so no ray allocates.

use crate::bounds::{expr_bounds, DEFAULT_DOMAIN};
use crate::build_error::BuildError;
use crate::expr::Expr;
use crate::flat::{CsgNode, CsgOp, Flat, Leaf, LeafView, Span, MAX_DEPTH, MAX_PARTS};
use crate::interval_trace::ExprSurface;
use crate::perturbed::along::{positive_set, q_local};
use crate::quadric::Quadric;
use crate::ray::{Aabb, Ray};
use crate::shape::Shape;
use crate::surface::{outward, Surface};
use crate::transform::Affine;
use glam::DVec3;

mod conjunction;
use conjunction::{Conjunctions, Item};

/// A ray's first crossing of a solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: f64,
    /// Outward unit normal at the hit.
    pub normal: DVec3,
}

/// A solid ready for ray queries (see the module docs).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Solid {
    flat: Flat,
    /// The nodes that intersect planes only, derived from `flat` ([`Polytopes`]).
    #[cfg_attr(feature = "serde", serde(skip))]
    polytopes: Polytopes,
    /// Per CSG node, the size its crossings are located relative to ([`walk_scales`]).
    #[cfg_attr(feature = "serde", serde(skip))]
    scales: Vec<f64>,
    /// Per CSG node, whether its crossings are roots in closed form ([`exact_nodes`]).
    #[cfg_attr(feature = "serde", serde(skip))]
    exact: Vec<bool>,
    /// The differences of plain quadrics taken in closed form ([`conjunction`]).
    #[cfg_attr(feature = "serde", serde(skip))]
    conjunctions: Conjunctions,
    /// Per CSG node, its bounds grown as the queries grow them ([`QueryBoxes`]).
    #[cfg_attr(feature = "serde", serde(skip))]
    boxes: Vec<QueryBoxes>,
}

/// A node's bounds grown as each query grows them, computed once per solid instead of
/// on every query: the same boxes, so the same answers.
#[derive(Clone, Copy, Debug, PartialEq)]
struct QueryBoxes {
    /// [`Solid::inside_node`]'s: grown by 10⁻⁹·(1 + the largest side).
    inside: Aabb,
    /// [`Solid::conjunction_within`]'s: grown by 10⁻⁹·(1 + the largest coordinate's
    /// magnitude), where the bounds are finite.
    conjunction: Option<Aabb>,
    /// [`Solid::walk_range`]'s: grown by 10⁻⁹, where the bounds are finite.
    walk: Option<Aabb>,
}

impl QueryBoxes {
    fn new(b: &Aabb) -> Self {
        let pad = 1e-9 * (1.0 + b.extent().max_element());
        let conjunction = b.is_finite().then(|| {
            let pad = 1e-9 * (1.0 + b.lo.abs().max(b.hi.abs()).max_element());
            Aabb::new(b.lo - pad, b.hi + pad)
        });
        QueryBoxes {
            inside: Aabb::new(b.lo - pad, b.hi + pad),
            conjunction,
            walk: b.is_finite().then(|| Aabb::new(b.lo - 1e-9, b.hi + 1e-9)),
        }
    }
}

/// The CSG intersections whose parts are all plain planes (boxes, slabs, wedges):
/// their crossing is the ends of one interval along the ray, found without the leaves'
/// generic machinery ([`Solid::polytope_intersection`]).
#[derive(Clone, Debug, Default, PartialEq)]
struct Polytopes {
    /// Per CSG node, its planes in `planes` (count 0: not such a node).
    spans: Vec<Span>,
    /// The planes' quadrics (no quadratic terms), in part order.
    planes: Vec<Quadric>,
    /// Per CSG node, whether its planes are an axis-aligned box as `box(..)` builds it
    /// ([`is_axis_box`]), crossed by [`box_intersection`].
    boxes: Vec<bool>,
}

impl Polytopes {
    fn new(flat: &Flat) -> Self {
        let mut p = Self {
            spans: vec![Span::default(); flat.nodes.len()],
            planes: Vec::new(),
            boxes: vec![false; flat.nodes.len()],
        };
        for (i, node) in flat.nodes.iter().enumerate() {
            if node.op != CsgOp::Intersection {
                continue;
            }
            let plane = |&k: &u32| {
                let part = &flat.nodes[k as usize];
                if part.op != CsgOp::Leaf {
                    return None;
                }
                match flat.leaf(part.operands.first as usize) {
                    LeafView::Perturbed(v)
                        if v.perturbations.is_empty()
                            && v.base.c[..6].iter().all(|&c| c == 0.0) =>
                    {
                        Some(*v.base)
                    }
                    _ => None,
                }
            };
            let Some(planes) = flat.parts(i).iter().map(plane).collect::<Option<Vec<_>>>() else {
                continue;
            };
            p.boxes[i] = is_axis_box(&planes);
            let first = p.planes.len();
            p.planes.extend(planes);
            p.spans[i] = Span::since(first, p.planes.len());
        }
        p
    }

    /// Node i's planes, if it is an intersection of planes.
    #[inline]
    fn of(&self, i: usize) -> Option<&[Quadric]> {
        let span = self.spans[i];
        (span.count > 0).then(|| &self.planes[span.range()])
    }
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
    /// domain, else inside ±[`DEFAULT_DOMAIN`]. Errors for a singular transform, an
    /// expression the bytecode cannot hold, or CSG nested deeper than [`MAX_DEPTH`].
    pub fn build(shape: &Shape) -> Result<Solid, BuildError> {
        let mut flat = Flat::default();
        let (_, depth) = Self::build_moved(shape, &Affine::IDENTITY, &mut flat)?;
        if depth > MAX_DEPTH {
            return Err(BuildError::TooDeep(depth));
        }
        let polytopes = Polytopes::new(&flat);
        let scales = walk_scales(&flat);
        let conjunctions = Conjunctions::new(&flat);
        let exact = exact_nodes(&flat, &conjunctions);
        let boxes = flat
            .nodes
            .iter()
            .map(|n| QueryBoxes::new(&n.bounds))
            .collect();
        Ok(Solid {
            flat,
            polytopes,
            scales,
            exact,
            conjunctions,
            boxes,
        })
    }

    /// Appends the nodes of `shape` moved by `m`; returns the root's index and depth.
    fn build_moved(shape: &Shape, m: &Affine, flat: &mut Flat) -> Result<(u32, usize), BuildError> {
        let leaf = |flat: &mut Flat, k: u32, bounds: Aabb| {
            push_node(flat, CsgOp::Leaf, Span { first: k, count: 1 }, bounds)
        };
        Ok(match shape {
            Shape::Function { tree, domain } => {
                let moved = m.apply(tree).ok_or(BuildError::SingularTransform(*m))?;
                let domain = domain.map(|d| transform_box(&d, m)).unwrap_or(Aabb::new(
                    DVec3::splat(-DEFAULT_DOMAIN),
                    DVec3::splat(DEFAULT_DOMAIN),
                ));
                let expr = Expr::new(&moved);
                let bounds = expr_bounds(&expr, domain);
                let k = flat.push_expr(&ExprSurface::new(expr, bounds))?;
                (leaf(flat, k, bounds), 1)
            }
            Shape::Perturbed(p) => {
                // A moved quadric is a quadric: the exact path survives any transform.
                let moved = p
                    .transformed(m)
                    .ok_or(BuildError::SingularTransform(*m))?
                    .surface();
                let k = flat.push_perturbed(&moved);
                (leaf(flat, k, moved.bounds()), 1)
            }
            Shape::Union(v) | Shape::Intersection(v) => {
                let union = matches!(shape, Shape::Union(_));
                let (op, fold): (_, fn(&Aabb, &Aabb) -> Aabb) = match union {
                    true => (CsgOp::Union, Aabb::union),
                    false => (CsgOp::Intersection, Aabb::intersection),
                };
                let start = match union {
                    true => Aabb::EMPTY,
                    false => Aabb::EVERYTHING,
                };
                // Nested unions (intersections) are one: their parts join this node's, so
                // that chains such as union(a, union(b, …)) do not nest deep.
                let mut nested = Vec::with_capacity(v.len());
                for s in v {
                    same_op_parts(s, m, union, &mut nested);
                }
                let mut parts = Vec::with_capacity(nested.len());
                for (s, m) in nested {
                    parts.push(Self::build_moved(s, &m, flat)?);
                }
                if parts.len() == 1 {
                    return Ok(parts[0]);
                }
                // Groups of at most MAX_PARTS under nodes of their own, until one is left.
                while parts.len() > MAX_PARTS {
                    let mut grouped = Vec::with_capacity(parts.len().div_ceil(MAX_PARTS));
                    for group in parts.chunks(MAX_PARTS) {
                        if let [one] = group {
                            grouped.push(*one);
                            continue;
                        }
                        grouped.push(interior(flat, op, group, start, fold, None));
                    }
                    parts = grouped;
                }
                let b = parts
                    .iter()
                    .fold(start, |b, &(i, _)| fold(&b, &flat.nodes[i as usize].bounds));
                let b = tighten(shape, m, b)?;
                interior(flat, op, &parts, start, fold, Some(b))
            }
            Shape::Difference(a, b) => {
                let parts = [
                    Self::build_moved(a, m, flat)?,
                    Self::build_moved(b, m, flat)?,
                ];
                let bounds = tighten(shape, m, flat.nodes[parts[0].0 as usize].bounds)?;
                let keep = |b: &Aabb, _: &Aabb| *b;
                interior(flat, CsgOp::Difference, &parts, bounds, keep, Some(bounds))
            }
            Shape::Transformed(inner, s) => Self::build_moved(s, &inner.then(m), flat)?,
        })
    }

    /// The flat arrays (see [`crate::flat`]).
    pub fn flat(&self) -> &Flat {
        &self.flat
    }

    fn root(&self) -> usize {
        self.flat.nodes.len() - 1
    }

    /// The first crossing in (t_min, t_max) with its outward normal.
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<Hit> {
        self.intersect_node(self.root(), ray, t_min, t_max)
    }

    /// Whether the solid is convex as built: an intersection of planes (a box, a slab
    /// stack, any convex polytope) or one quadric without perturbations whose inside is
    /// an ellipsoid ([`Quadric::inside_is_convex`]). A ray leaving a convex solid's
    /// surface outward (d · n > 0, n the outward normal where it starts) never meets it
    /// again, so a renderer need not ask (false only means "not known to be convex").
    pub fn is_convex(&self) -> bool {
        let root = self.root();
        if self.polytopes.of(root).is_some() {
            return true;
        }
        let node = &self.flat.nodes[root];
        node.op == CsgOp::Leaf
            && matches!(
                self.flat.leaf(node.operands.first as usize),
                LeafView::Perturbed(v) if v.perturbations.is_empty() && v.base.inside_is_convex()
            )
    }

    /// Whether there is a crossing in (t_min, t_max): `intersect(..).is_some()` (a
    /// shadow ray's question), which a solid of one leaf answers without refining the
    /// crossing or computing its normal.
    pub fn occludes(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        self.occludes_node(self.root(), ray, t_min, t_max)
    }

    /// `intersect_node(i, ..).is_some()`, answered with less work where the CSG walk's
    /// outcome is known early. A node's state changes only where a part is crossed, so a
    /// node none of whose parts is crossed is not crossed either. A union crossed by
    /// some part is crossed when every part starts outside (its first crossing then
    /// enters). A difference whose first part is not crossed is crossed iff it starts
    /// inside the first part and the second part is crossed. Otherwise the walk runs.
    /// Parts are asked in turn, without normals; start states only where needed.
    fn occludes_node(&self, i: usize, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        let node = &self.flat.nodes[i];
        let crossed = |p: u32, lo: f64, hi: f64| self.occludes_node(p as usize, ray, lo, hi);
        match node.op {
            CsgOp::Leaf => match self.flat.leaf(node.operands.first as usize) {
                LeafView::Perturbed(ref s) => s.crosses(ray, t_min, t_max),
                LeafView::Expr(ref s) => s.crosses(ray, t_min, t_max),
            },
            CsgOp::Union => {
                let Some((lo, hi)) = self.walk_range(i, ray, t_min, t_max) else {
                    return false;
                };
                let parts = self.flat.parts(i);
                if !parts.iter().any(|&p| crossed(p, lo, hi)) {
                    return false;
                }
                let start = ray.at(lo);
                if parts.iter().all(|&p| !self.inside_node(p as usize, start)) {
                    return true;
                }
                self.intersect_node(i, ray, t_min, t_max).is_some()
            }
            CsgOp::Difference if self.conjunctions.of(i).is_some() => {
                self.intersect_node(i, ray, t_min, t_max).is_some()
            }
            CsgOp::Difference => {
                let Some((lo, hi)) = self.walk_range(i, ray, t_min, t_max) else {
                    return false;
                };
                let parts = self.flat.parts(i);
                let (first, second) = (parts[0], parts[1]);
                if !crossed(first, lo, hi) {
                    return self.inside_node(first as usize, ray.at(lo)) && crossed(second, lo, hi);
                }
                self.intersect_node(i, ray, t_min, t_max).is_some()
            }
            CsgOp::Intersection => self.intersect_node(i, ray, t_min, t_max).is_some(),
        }
    }

    /// Whether p is inside: F ≥ 0 within the bounds (grown by rounding). Outside them
    /// nothing is evaluated: F < 0 there, or the bounds are a model's domain, which caps
    /// the solid for ray queries too ([`crate::interval_trace`]).
    pub fn inside(&self, p: DVec3) -> bool {
        self.inside_node(self.root(), p)
    }

    /// Whether p is inside node i, as [`Self::inside`]: outside the node's bounds
    /// nothing is evaluated (a CSG walk asks every part's state where the ray enters,
    /// and most parts lie far from there).
    fn inside_node(&self, i: usize, p: DVec3) -> bool {
        if !self.boxes[i].inside.contains(p) {
            return false;
        }
        self.value_node(i, p) >= 0.0
    }

    fn intersect_node(&self, i: usize, ray: &Ray, t_min: f64, t_max: f64) -> Option<Hit> {
        let node = &self.flat.nodes[i];
        let rule = match node.op {
            CsgOp::Leaf => {
                let (t, normal) = match self.flat.leaf(node.operands.first as usize) {
                    LeafView::Perturbed(ref s) => {
                        let t = s.first_crossing(ray, t_min, t_max)?;
                        (t, outward(s.gradient(ray.at(t))))
                    }
                    LeafView::Expr(ref s) => s.trace(ray, t_min, t_max, true)?,
                };
                return Some(Hit { t, normal });
            }
            CsgOp::Union => Rule::Any,
            CsgOp::Intersection => {
                if let Some(planes) = self.polytopes.of(i) {
                    if ray.o.is_finite() && ray.d.is_finite() {
                        return if self.polytopes.boxes[i] {
                            box_intersection(planes, ray, t_min, t_max)
                        } else {
                            polytope_intersection(planes, ray, t_min, t_max)
                        };
                    }
                }
                if let Some(items) = self.conjunctions.of(i) {
                    return self.conjunction_within(i, items, ray, t_min, t_max);
                }
                Rule::All
            }
            CsgOp::Difference => {
                if let Some(items) = self.conjunctions.of(i) {
                    return self.conjunction_within(i, items, ray, t_min, t_max);
                }
                Rule::FirstNotSecond
            }
        };
        self.combine(i, rule, ray, t_min, t_max)
    }

    /// The range a CSG walk over node i covers: (t_min, t_max) clipped to the node's
    /// bounds grown by 10⁻⁹ (None where the ray misses them), its start moved on by a
    /// [`nudge`]. The walk takes each part's state where it starts; a ray continued from
    /// a crossing starts on a part's surface, where F ≈ 0 says nothing, and a nudge on
    /// the state is the one the walk goes on with.
    #[inline]
    fn walk_range(&self, i: usize, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, f64)> {
        let (lo, hi) = match &self.boxes[i].walk {
            Some(b) => b.clip(ray, t_min, t_max)?,
            None => (t_min, t_max),
        };
        let lo = if lo.is_finite() {
            lo + nudge(self.scales[i], ray, lo)
        } else {
            lo
        };
        (lo < hi).then_some((lo, hi))
    }

    /// Walks the parts' crossings of node i in order, updating each part's state, until
    /// the combined state flips. A part whose roots are in closed form ([`exact_nodes`])
    /// flips at each and is searched again from it; any other part is searched again a
    /// [`nudge`] past its last crossing, so that a root found to a tolerance is never
    /// found twice, and takes the state F's sign gives it there. States and pending
    /// crossings live in fixed arrays (at most [`MAX_PARTS`] parts per node).
    fn combine(&self, i: usize, rule: Rule, ray: &Ray, t_min: f64, t_max: f64) -> Option<Hit> {
        let parts = self.flat.parts(i);
        let (lo, hi) = self.walk_range(i, ray, t_min, t_max)?;
        let scale = self.scales[i];
        // Each part's state at the start of the clipped range: a part may well be inside
        // there even though the combination is not.
        let start = ray.at(lo);
        let n = parts.len();
        let mut state = [false; MAX_PARTS];
        let mut next: [Option<Hit>; MAX_PARTS] = [None; MAX_PARTS];
        for (k, &p) in parts.iter().enumerate() {
            state[k] = self.inside_node(p as usize, start);
            next[k] = self.intersect_node(p as usize, ray, lo, hi);
        }
        let combined = rule.apply(&state[..n]);
        loop {
            let t = next[..n]
                .iter()
                .filter_map(|h| h.map(|h| h.t))
                .min_by(f64::total_cmp)?;
            let from = t + nudge(scale, ray, t);
            let mut batch = [0usize; MAX_PARTS];
            let (mut m, mut changed, mut sliver) = (0, None::<(usize, Hit)>, None);
            for k in 0..n {
                let Some(h) = next[k].filter(|h| h.t <= from) else {
                    continue;
                };
                let part = parts[k] as usize;
                let inside = if self.exact[part] {
                    // Roots in closed form, the same whatever the search starts from:
                    // each one flips the state, in order, and the next is searched from
                    // it exactly, so that none is skipped.
                    if h.t > t {
                        continue;
                    }
                    !state[k]
                } else {
                    // Where a root is only found to a tolerance, the next search starts
                    // a nudge on, and the part's state is taken where that search
                    // starts (as its own walk takes it): a blind flip would be wrong
                    // for the rest of the walk after a second crossing inside the
                    // nudge (a sliver, or parts meeting at an edge).
                    self.inside_node(part, ray.at(self.resume_at(part, ray, from)))
                };
                batch[m] = k;
                m += 1;
                if inside != state[k] {
                    state[k] = inside;
                    if changed.is_none_or(|(_, c): (usize, Hit)| h.t < c.t) {
                        changed = Some((k, h));
                    }
                } else if sliver.is_none() {
                    // Crossed and back within the nudge: a sliver of the part, which
                    // is the node's crossing where it would show (as the part alone
                    // reports it, and as `occludes` answers).
                    let mut probe = state;
                    probe[k] = !probe[k];
                    if rule.apply(&probe[..n]) != combined {
                        sliver = Some((k, h));
                    }
                }
            }
            let hit = changed
                .filter(|_| rule.apply(&state[..n]) != combined)
                .or(sliver);
            if let Some((k, h)) = hit {
                let normal = match (rule, k) {
                    (Rule::FirstNotSecond, 1) => -h.normal,
                    _ => h.normal,
                };
                return Some(Hit { t: h.t, normal });
            }
            for &k in &batch[..m] {
                let part = parts[k] as usize;
                let start = if self.exact[part] { t } else { from };
                next[k] = self.intersect_node(part, ray, start, hi);
            }
        }
    }

    /// Where a walk resuming part i's crossings from `from` takes its state: there for
    /// a leaf; a nudge on for a CSG node, where its own walk starts ([`Self::walk_range`]).
    #[inline]
    fn resume_at(&self, i: usize, ray: &Ray, from: f64) -> f64 {
        match self.flat.nodes[i].op {
            CsgOp::Leaf => from,
            _ => from + nudge(self.scales[i], ray, from),
        }
    }

    /// [`Self::conjunction`] for node i, none where the ray's range misses the node's
    /// bounds (grown by 10⁻⁹ of their size and place, beyond the slab test's rounding):
    /// its crossings lie in them, and most rays a CSG walk asks of a thin part (a
    /// table's leg) pass it by.
    #[inline]
    fn conjunction_within(
        &self,
        i: usize,
        items: &[Item],
        ray: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<Hit> {
        if let Some(b) = &self.boxes[i].conjunction {
            b.clip(ray, t_min, t_max)?;
        }
        self.conjunction(items, ray, t_min, t_max)
    }

    /// The first crossing in (t_min, t_max) of the intersection of the positive sets of
    /// the quadrics `items` ([`conjunction`]; a complemented one's negative set, as a
    /// difference takes its second part), in closed form: along the ray each set is
    /// at most two open intervals, the roots of the quadratic about the ray's origin (as
    /// the leaves themselves find them), and the crossing is the first end of their
    /// intersection in range, with the normal of the quadric that makes it (reversed
    /// where complemented).
    fn conjunction(&self, items: &[Item], ray: &Ray, t_min: f64, t_max: f64) -> Option<Hit> {
        const N: usize = conjunction::MAX_ITEMS;
        let (o, d) = (ray.o.to_array(), ray.d.to_array());
        // `q_local_f64`'s plane shortcut, its test on the ray made once.
        let finite = o.iter().chain(&d).all(|v| v.is_finite());
        // Intersecting k sets leaves at most k + 1 intervals; each end remembers the
        // item whose root it is.
        let mut set = [(f64::NEG_INFINITY, f64::INFINITY, 0u8, 0u8); N + 2];
        let mut n = 1;
        // The box of the stretch the set spans (its intervals are in order), taken at
        // the first hole with a reach: the set only shrinks, so it stays a bound.
        let mut stretch = None;
        for (k, item) in items.iter().enumerate().take(N) {
            if let Some((lo, hi)) = &item.reach {
                let b = stretch.get_or_insert_with(|| stretch_box(&set[..n], o, d));
                if let Some((slo, shi)) = b {
                    if (0..3).any(|a| shi[a] < lo[a] || slo[a] > hi[a]) {
                        continue;
                    }
                }
            }
            let c = &self.flat.quadrics[item.quadric as usize].c;
            let mut a = match item.plane && finite {
                true => {
                    let ([x, y, z], [u, v, w]) = (o, d);
                    [
                        x * c[6] + y * c[7] + z * c[8] + c[9],
                        c[6] * u + c[7] * v + c[8] * w,
                        0.0,
                    ]
                }
                false => q_local(c, o, d),
            };
            if item.complemented {
                a = a.map(|v| -v);
            }
            let (pos, m) = positive_set(a);
            let cut = |(a, b, ka, kb): (f64, f64, u8, u8), (c, e): (f64, f64)| {
                let (lo, klo) = if c > a { (c, k as u8) } else { (a, ka) };
                let (hi, khi) = if e < b { (e, k as u8) } else { (b, kb) };
                (lo < hi).then_some((lo, hi, klo, khi))
            };
            let mut len = 0;
            if m == 1 {
                // A convex set: each interval is cut in place.
                for j in 0..n {
                    if let Some(v) = cut(set[j], pos[0]) {
                        set[len] = v;
                        len += 1;
                    }
                }
            } else {
                // Two intervals split at most the one interval holding the gap between
                // them: the intervals are read from a copy, written in order.
                let from = set;
                for &v in &from[..n] {
                    for &w in &pos[..m] {
                        if let Some(c) = cut(v, w).filter(|_| len < set.len()) {
                            set[len] = c;
                            len += 1;
                        }
                    }
                }
            }
            n = len;
            if n == 0 {
                return None;
            }
        }
        // The first interval end in range, and the item that makes it.
        let (t, k) = set[..n]
            .iter()
            .flat_map(|&(a, b, ka, kb)| [(a, ka), (b, kb)])
            .filter(|&(t, _)| t > t_min && t < t_max && t.is_finite())
            .min_by(|x, y| x.0.total_cmp(&y.0))?;
        let item = items[k as usize];
        let normal = outward(self.flat.quadrics[item.quadric as usize].gradient(ray.at(t)));
        Some(Hit {
            t,
            normal: if item.complemented { -normal } else { normal },
        })
    }

    fn value_node(&self, i: usize, p: DVec3) -> f64 {
        let node = &self.flat.nodes[i];
        let parts = self.flat.parts(i);
        let v = |k: &u32| self.value_node(*k as usize, p);
        match node.op {
            CsgOp::Leaf => {
                let k = node.operands.first as usize;
                // A plain quadric is its base's value (no perturbation adds to it),
                // without assembling the leaf's view: CSG walks ask this of every part.
                if let Leaf::Perturbed {
                    base,
                    perturbations: Span { count: 0, .. },
                    ..
                } = self.flat.leaves[k]
                {
                    return self.flat.quadrics[base as usize].eval(p);
                }
                match self.flat.leaf(k) {
                    LeafView::Perturbed(ref s) => s.value(p),
                    LeafView::Expr(ref s) => s.value(p),
                }
            }
            CsgOp::Union => parts.iter().map(v).fold(f64::NEG_INFINITY, f64::max),
            CsgOp::Intersection => {
                // A polytope (a box, a slab): its planes' values in part order, the same
                // minimum as the parts' without a call per part.
                if let Some(planes) = self.polytopes.of(i) {
                    return planes
                        .iter()
                        .map(|q| q.eval(p))
                        .fold(f64::INFINITY, f64::min);
                }
                parts.iter().map(v).fold(f64::INFINITY, f64::min)
            }
            CsgOp::Difference => v(&parts[0]).min(-v(&parts[1])),
        }
    }

    fn gradient_node(&self, i: usize, p: DVec3) -> DVec3 {
        let node = &self.flat.nodes[i];
        let parts = self.flat.parts(i);
        // The gradient of min/max is the active part's.
        let pick = |max: bool| {
            let best = parts.iter().max_by(|a, b| {
                let (x, y) = (
                    self.value_node(**a as usize, p),
                    self.value_node(**b as usize, p),
                );
                if max {
                    x.total_cmp(&y)
                } else {
                    y.total_cmp(&x)
                }
            });
            best.map_or(DVec3::ZERO, |&k| self.gradient_node(k as usize, p))
        };
        match node.op {
            CsgOp::Leaf => match self.flat.leaf(node.operands.first as usize) {
                LeafView::Perturbed(ref s) => s.gradient(p),
                LeafView::Expr(ref s) => s.gradient(p),
            },
            CsgOp::Union => pick(true),
            CsgOp::Intersection => pick(false),
            CsgOp::Difference => {
                let (a, b) = (parts[0] as usize, parts[1] as usize);
                if self.value_node(a, p) <= -self.value_node(b, p) {
                    self.gradient_node(a, p)
                } else {
                    -self.gradient_node(b, p)
                }
            }
        }
    }
}

/// The parts of `s` moved by `m` as parts of a union (`union`) or intersection: `s`
/// itself, or, when it is (a moved) node of the same kind, its parts, recursively.
fn same_op_parts<'a>(s: &'a Shape, m: &Affine, union: bool, out: &mut Vec<(&'a Shape, Affine)>) {
    let (mut inner, mut moved) = (s, *m);
    while let Shape::Transformed(a, c) = inner {
        moved = a.then(&moved);
        inner = c;
    }
    match (inner, union) {
        (Shape::Union(v), true) | (Shape::Intersection(v), false) => {
            for c in v {
                same_op_parts(c, &moved, union, out);
            }
        }
        _ => out.push((s, *m)),
    }
}

/// Appends a node; returns its index.
/// The box of the ray's points from the first interval's start to the last one's end
/// (`set` in order), or None where an end is not finite.
#[inline]
fn stretch_box(
    set: &[(f64, f64, u8, u8)],
    o: [f64; 3],
    d: [f64; 3],
) -> Option<([f64; 3], [f64; 3])> {
    let (t0, t1) = (set.first()?.0, set.last()?.1);
    if !(t0.is_finite() && t1.is_finite()) {
        return None;
    }
    let (mut lo, mut hi) = ([0.0; 3], [0.0; 3]);
    for a in 0..3 {
        let (p, q) = (o[a] + t0 * d[a], o[a] + t1 * d[a]);
        (lo[a], hi[a]) = (p.min(q), p.max(q));
    }
    Some((lo, hi))
}

fn push_node(flat: &mut Flat, op: CsgOp, operands: Span, bounds: Aabb) -> u32 {
    flat.nodes.push(CsgNode {
        op,
        operands,
        bounds,
    });
    flat.nodes.len() as u32 - 1
}

/// Appends an interior node over `parts` (node index, depth); its bounds are `bounds`, or
/// the parts' bounds folded from `start`. Returns (index, depth).
fn interior(
    flat: &mut Flat,
    op: CsgOp,
    parts: &[(u32, usize)],
    start: Aabb,
    fold: impl Fn(&Aabb, &Aabb) -> Aabb,
    bounds: Option<Aabb>,
) -> (u32, usize) {
    let b = bounds.unwrap_or_else(|| {
        parts
            .iter()
            .fold(start, |b, &(i, _)| fold(&b, &flat.nodes[i as usize].bounds))
    });
    let first = flat.children.len();
    flat.children.extend(parts.iter().map(|&(i, _)| i));
    let span = Span {
        first: first as u32,
        count: parts.len() as u32,
    };
    let depth = 1 + parts.iter().map(|&(_, d)| d).max().unwrap_or(0);
    (push_node(flat, op, span, b), depth)
}

/// A CSG node's bounds from its parts can be infinite (half-spaces cut into a box);
/// then the whole node's expression is bounded by interval octree refinement, which
/// sees how the parts combine.
fn tighten(shape: &Shape, m: &Affine, from_parts: Aabb) -> Result<Aabb, BuildError> {
    if from_parts.is_finite() || from_parts.is_empty() {
        return Ok(from_parts);
    }
    let tree = m
        .apply(&shape.to_tree()?)
        .ok_or(BuildError::SingularTransform(*m))?;
    let domain = Aabb::new(DVec3::splat(-DEFAULT_DOMAIN), DVec3::splat(DEFAULT_DOMAIN));
    let b = expr_bounds(&Expr::new(&tree), domain.intersection(&from_parts));
    // What touches the search domain's faces may go on beyond it: keep it unbounded.
    let touches = (0..3).any(|k| b.lo[k] <= -DEFAULT_DOMAIN || b.hi[k] >= DEFAULT_DOMAIN);
    Ok(if touches { from_parts } else { b })
}

/// Per CSG node, the size its crossings are located relative to: the extent of its
/// bounds where they are finite; else the largest such size among its parts, or 0 for
/// a leaf without finite bounds (a plane, a cylinder: roots in closed form, rounded
/// relative to where they are, which [`nudge`] adds). Never the extent of an infinite
/// box, which would push the next search past whole parts.
fn walk_scales(flat: &Flat) -> Vec<f64> {
    let mut scales: Vec<f64> = Vec::with_capacity(flat.nodes.len());
    for (i, node) in flat.nodes.iter().enumerate() {
        let s = if node.bounds.is_finite() {
            node.bounds.extent().length()
        } else if node.op == CsgOp::Leaf {
            0.0
        } else {
            // Post order: parts come before their node.
            flat.parts(i)
                .iter()
                .map(|&p| scales[p as usize])
                .fold(0.0, f64::max)
        };
        scales.push(s);
    }
    scales
}

/// Per CSG node, whether its crossings are roots in closed form, computed about the ray's
/// origin whatever the search starts from, so that a search from a root never finds it
/// again nor skips the next: a plain quadric (no perturbations), or a node of plain
/// quadrics that [`conjunction`] takes (intersections, boxes and polytopes, and
/// differences of them).
fn exact_nodes(flat: &Flat, conjunctions: &Conjunctions) -> Vec<bool> {
    (0..flat.nodes.len())
        .map(|i| {
            let node = &flat.nodes[i];
            let plain = node.op == CsgOp::Leaf
                && matches!(
                    flat.leaves[node.operands.first as usize],
                    Leaf::Perturbed {
                        perturbations: Span { count: 0, .. },
                        ..
                    }
                );
            plain || conjunctions.of(i).is_some()
        })
        .collect()
}

/// How far past a crossing at t a CSG walk searches the crossed part again, in t: 10⁻¹⁰
/// of the largest of the node's size (`scale`, [`walk_scales`]), the crossing's distance
/// from the origin and 1, over |d| — past the rounding of a root located to 10⁻¹² of its leaf's
/// size or to f64 rounding where it is, short of any feature the renderer resolves.
#[inline]
fn nudge(scale: f64, ray: &Ray, t: f64) -> f64 {
    let at = ray.at(t).abs().max_element();
    // |d|'s largest component, not its length: the same within √3, without a root.
    1e-10 * scale.max(at).max(1.0) / ray.d.abs().max_element()
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

/// [`Solid::conjunction`] for an intersection of planes, bit for bit (the same
/// expansions along the ray as `q_local_f64`'s plane shortcut, o and d finite; the same
/// roots as `positive_set`'s linear case; ties kept by the earlier part): each plane
/// cuts the one interval where every part is positive, and the crossing is its first
/// end in (t_min, t_max).
fn polytope_intersection(planes: &[Quadric], ray: &Ray, t_min: f64, t_max: f64) -> Option<Hit> {
    let [x, y, z] = ray.o.to_array();
    let [u, v, w] = ray.d.to_array();
    let (mut lo, mut hi, mut klo, mut khi) = (f64::NEG_INFINITY, f64::INFINITY, 0, 0);
    for (k, q) in planes.iter().enumerate() {
        let c = &q.c;
        let a0 = x * c[6] + y * c[7] + z * c[8] + c[9];
        let a1 = c[6] * u + c[7] * v + c[8] * w;
        let (s, e) = if a1 == 0.0 {
            // Parallel to the plane: inside it all along (F ≥ 0, a face included) or
            // never.
            if a0 >= 0.0 {
                continue;
            }
            return None;
        } else {
            let r = -a0 / a1;
            if a1 > 0.0 {
                (r, f64::INFINITY)
            } else {
                (f64::NEG_INFINITY, r)
            }
        };
        if s > lo {
            (lo, klo) = (s, k);
        }
        if e < hi {
            (hi, khi) = (e, k);
        }
        // Never NaN: a NaN root fails both comparisons above.
        if lo >= hi {
            return None;
        }
    }
    first_usable_end(planes, ray, t_min, t_max, (lo, klo), (hi, khi))
}

/// The hit of a convex polytope whose crossing along the ray is the interval (lo, hi),
/// entered by plane `klo` and left by `khi`: its first end inside (t_min, t_max), with
/// that plane's outward normal.
#[inline]
fn first_usable_end(
    planes: &[Quadric],
    ray: &Ray,
    t_min: f64,
    t_max: f64,
    (lo, klo): (f64, usize),
    (hi, khi): (f64, usize),
) -> Option<Hit> {
    let usable = |t: f64| t > t_min && t < t_max && t.is_finite();
    let (t, k) = if usable(lo) {
        (lo, klo)
    } else if usable(hi) {
        (hi, khi)
    } else {
        return None;
    };
    Some(Hit {
        t,
        normal: outward(planes[k].gradient(ray.at(t))),
    })
}

/// Whether `planes` are six planes, two per axis in x, y, z order: first b − x_k ≥ 0
/// (coefficient −1 on axis k), then x_k + b′ ≥ 0 (+1), every other coefficient zero.
/// That is how `box(..)` builds a box, moved or not; the coefficients ±1 make
/// [`box_intersection`] agree with [`polytope_intersection`] bit for bit.
fn is_axis_box(planes: &[Quadric]) -> bool {
    planes.len() == 6
        && planes.iter().enumerate().all(|(j, q)| {
            let (axis, a) = (j / 2, if j % 2 == 0 { -1.0 } else { 1.0 });
            q.c[..6].iter().all(|&c| c == 0.0)
                && (0..3).all(|k| q.c[6 + k] == if k == axis { a } else { 0.0 })
        })
}

/// [`polytope_intersection`] for the planes of an axis-aligned box ([`is_axis_box`]),
/// as a slab test (Kay and Kajiya 1986): per axis, the sign of the direction says which
/// plane the ray enters by. With the coefficients ±1 the general loop's plane values
/// reduce to b − x and x + b′ exactly (the zero terms add nothing), its roots to the
/// quotients below, and its ties to the same plane indices, so the hits are its own.
fn box_intersection(planes: &[Quadric], ray: &Ray, t_min: f64, t_max: f64) -> Option<Hit> {
    let planes: &[Quadric; 6] = planes.try_into().ok()?;
    let (o, d) = (ray.o.to_array(), ray.d.to_array());
    let mut slabs = Slabs {
        lo: (f64::NEG_INFINITY, 0),
        hi: (f64::INFINITY, 0),
    };
    // The axes one after another, written out: as a loop with its early return the
    // compiler kept it rolled, at about three times the instructions.
    slabs.axis(planes, o, d, 0)?;
    slabs.axis(planes, o, d, 1)?;
    slabs.axis(planes, o, d, 2)?;
    // lo only grows and hi only shrinks, so one test at the end is the general loop's
    // test after every plane.
    if slabs.lo.0 >= slabs.hi.0 {
        return None;
    }
    first_usable_end(planes, ray, t_min, t_max, slabs.lo, slabs.hi)
}

/// The range [`box_intersection`] narrows, with the planes that bound it.
struct Slabs {
    lo: (f64, usize),
    hi: (f64, usize),
}

impl Slabs {
    /// Narrows the range by the slab of `axis`; None where the ray never crosses it.
    #[inline(always)]
    fn axis(&mut self, planes: &[Quadric; 6], o: [f64; 3], d: [f64; 3], axis: usize) -> Option<()> {
        let (x, u) = (o[axis], d[axis]);
        let (upper, lower) = (planes[2 * axis].c[9], planes[2 * axis + 1].c[9]);
        if u == 0.0 {
            // Parallel to both planes: inside both (F ≥ 0: a face counts) or never
            // crossing.
            return (upper - x >= 0.0 && x + lower >= 0.0).then_some(());
        }
        // The general loop's −a0/a1: −(b − x)/(−u) and −(x + b′)/u.
        let (t_upper, t_lower) = ((upper - x) / u, -(x + lower) / u);
        let (enter, leave) = if u > 0.0 {
            ((t_lower, 2 * axis + 1), (t_upper, 2 * axis))
        } else {
            ((t_upper, 2 * axis), (t_lower, 2 * axis + 1))
        };
        if enter.0 > self.lo.0 {
            self.lo = enter;
        }
        if leave.0 < self.hi.0 {
            self.hi = leave;
        }
        Some(())
    }
}

impl Surface for Solid {
    fn value(&self, p: DVec3) -> f64 {
        self.value_node(self.root(), p)
    }

    fn gradient(&self, p: DVec3) -> DVec3 {
        self.gradient_node(self.root(), p)
    }

    fn first_crossing(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        self.intersect(ray, t_min, t_max).map(|h| h.t)
    }

    fn first_hit(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, DVec3)> {
        self.intersect(ray, t_min, t_max).map(|h| (h.t, h.normal))
    }

    fn bounds(&self) -> Aabb {
        self.flat.nodes[self.root()].bounds
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

    /// The half-space n · x ≤ d (n unit) as a plain plane part.
    fn plane(n: DVec3, d: f64) -> Shape {
        use crate::perturbed::PerturbedQuadric;
        Shape::Perturbed(PerturbedQuadric::new(Quadric::plane(n, d)))
    }

    /// The six planes of the cube [−½, ½]³.
    fn unit_cube_planes() -> Vec<Shape> {
        [DVec3::X, DVec3::Y, DVec3::Z]
            .into_iter()
            .flat_map(|n| [plane(n, 0.5), plane(-n, 0.5)])
            .collect()
    }

    /// A scale, a rotation and a translation, none trivial.
    fn scaled_rotated_moved() -> Affine {
        Affine::scale(DVec3::new(2.0, 0.5, 1.0))
            .then(&Affine::rotate(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7))
            .then(&Affine::translate(DVec3::new(0.3, -0.2, 0.1)))
    }

    /// Which solids call themselves convex: polytopes and ellipsoids (moved, rotated,
    /// scaled) do; cylinders, cones, hyperboloids, perturbed spheres, unions, differences
    /// and expressions do not. Every convex one is checked: 3000 rays from points on its
    /// surface, leaving outward (d · n > 0), never meet it again.
    #[test]
    fn convex_solids_are_never_met_again_by_rays_leaving_them() {
        use crate::perturbed::PerturbedQuadric;
        use rand::{Rng, SeedableRng};
        let q = |q: Quadric| Shape::Perturbed(PerturbedQuadric::new(q));
        let (cube, moved) = (unit_cube_planes(), scaled_rotated_moved());
        let ball = q(Quadric::sphere(DVec3::new(0.1, 0.2, -0.3), 0.8));
        let convex = [
            Shape::Intersection(cube.clone()),
            Shape::Transformed(moved, Box::new(Shape::Intersection(cube.clone()))),
            ball.clone(),
            q(Quadric::ellipsoid(DVec3::ZERO, DVec3::new(1.0, 0.2, 3.0))),
            Shape::Transformed(moved, Box::new(ball.clone())),
        ];
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let not_convex = [
            q(Quadric::cylinder(DVec3::ZERO, DVec3::Z, 0.5)),
            q(Quadric::cone(DVec3::ZERO, DVec3::Z, 0.4)),
            q(Quadric::new([
                1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0,
            ])),
            Shape::Perturbed(
                PerturbedQuadric::new(Quadric::sphere(DVec3::ZERO, 1.0))
                    .with(0.5, Quadric::sphere(DVec3::X, 0.3)),
            ),
            Shape::Union(vec![ball.clone(), Shape::Intersection(cube.clone())]),
            Shape::Difference(Box::new(Shape::Intersection(cube)), Box::new(ball)),
            Shape::function(1.0 - (x.clone().square() + y.square() + z.square())),
        ];
        for shape in &not_convex {
            assert!(!Solid::build(shape).unwrap().is_convex(), "{shape:?}");
        }
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        for shape in &convex {
            let s = Solid::build(shape).unwrap();
            assert!(s.is_convex(), "{shape:?}");
            let mut left = 0;
            while left < 3000 {
                // A surface point: the first hit of a ray from outside at the centre.
                let c = s.bounds().center();
                let dir = DVec3::new(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                );
                let Some(dir) = dir.try_normalize() else {
                    continue;
                };
                let ray = Ray::new(c - dir * 20.0, dir);
                let Some(hit) = s.intersect(&ray, 0.0, f64::INFINITY) else {
                    continue;
                };
                let p = ray.at(hit.t);
                let d = DVec3::new(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                );
                let Some(d) = d.try_normalize().filter(|d| d.dot(hit.normal) > 1e-3) else {
                    continue;
                };
                let scale = 1.0 + p.abs().max_element();
                let leaving = Ray::new(p + hit.normal * (1e-7 * scale), d);
                assert!(
                    s.intersect(&leaving, 0.0, f64::INFINITY).is_none(),
                    "{shape:?}: {leaving:?} leaves and meets the solid again"
                );
                left += 1;
            }
        }
    }

    /// An axis-aligned box, the same box moved, a rotated and scaled one, and a wedge of
    /// three tilted planes (unbounded): the polytopes the tests below walk, with whether
    /// each takes the box path ([`box_intersection`]).
    fn polytope_shapes() -> [(Shape, bool); 4] {
        let (cube, moved) = (unit_cube_planes(), scaled_rotated_moved());
        let wedge = vec![
            plane(DVec3::new(1.0, 1.0, 0.0).normalize(), 0.4),
            plane(DVec3::new(-1.0, 0.5, 0.2).normalize(), 0.3),
            plane(DVec3::new(0.1, -0.3, 1.0).normalize(), 0.6),
        ];
        let shifted = Affine::translate(DVec3::new(0.17, -0.11, 0.23));
        [
            (Shape::Intersection(cube.clone()), true),
            (
                Shape::Transformed(shifted, Box::new(Shape::Intersection(cube.clone()))),
                true,
            ),
            (
                Shape::Transformed(moved, Box::new(Shape::Intersection(cube))),
                false,
            ),
            (Shape::Intersection(wedge), false),
        ]
    }

    /// A polytope's value from its planes is its parts' minimum bit for bit: a box, a
    /// moved box and a wedge, at random points inside and outside.
    #[test]
    fn polytope_values_are_their_parts_minimum() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(13);
        for (shape, _) in &polytope_shapes() {
            let s = Solid::build(shape).unwrap();
            let root = s.root();
            assert!(s.polytopes.spans[root].count >= 3);
            let mut inside = 0;
            for _ in 0..4000 {
                let p = DVec3::new(
                    rng.gen_range(-2.0..2.0),
                    rng.gen_range(-2.0..2.0),
                    rng.gen_range(-2.0..2.0),
                );
                let parts = s.flat.parts(root).iter();
                let want = parts
                    .map(|&k| s.value_node(k as usize, p))
                    .fold(f64::INFINITY, f64::min);
                assert_eq!(s.value(p).to_bits(), want.to_bits(), "{p}");
                inside += usize::from(want >= 0.0);
            }
            assert!(inside > 20 && inside < 3980, "{inside} inside");
        }
    }

    /// The planes-only paths give the general closed form's hits bit for bit (t and
    /// normal), and the box path the plane loop's: an axis-aligned box, the same box
    /// moved, a rotated and scaled one, and a wedge of three tilted planes (unbounded),
    /// on rays from outside, from inside, along faces, parallel to them and through the
    /// cube's edges and corners.
    #[test]
    fn polytopes_equal_the_general_closed_form() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(12);
        for (shape, boxed) in &polytope_shapes() {
            let s = Solid::build(shape).unwrap();
            let root = s.root();
            assert!(s.polytopes.spans[root].count >= 3);
            assert_eq!(s.polytopes.boxes[root], *boxed);
            let mut hits = 0;
            for k in 0..4000 {
                let mut o = DVec3::new(
                    rng.gen_range(-3.0..3.0),
                    rng.gen_range(-3.0..3.0),
                    rng.gen_range(-3.0..3.0),
                );
                if k % 5 == 0 {
                    o *= 0.1;
                }
                let mut d = DVec3::new(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                );
                if k % 7 == 0 {
                    d.x = 0.0; // parallel to the cube's x faces
                    o.x = 0.5;
                }
                if k % 11 == 0 {
                    d.y = 0.0; // parallel to the y faces, between them or not
                }
                if k % 13 == 0 {
                    d.z = 0.0;
                    o.z = [0.5, -0.5, 1.1, 0.1][k / 13 % 4];
                }
                if k % 17 == 0 {
                    // Through an edge or a corner of the cube: two or three slabs
                    // entered at the same t, where the first plane in order gives the
                    // normal.
                    let s = if k / 17 % 2 == 0 { 1.0 } else { -1.0 };
                    let corner = k / 34 % 2 == 0;
                    o = DVec3::new(-2.0 * s, -2.0 * s, if corner { -2.0 * s } else { 0.1 });
                    d = DVec3::new(s, s, if corner { s } else { 0.0 });
                }
                let ray = Ray::new(o, d.normalize());
                let t_min = if k % 3 == 0 { 0.5 } else { 0.0 };
                let fast = s.intersect(&ray, t_min, 10.0);
                let items = s.conjunctions.of(root).unwrap();
                let general = s.conjunction(items, &ray, t_min, 10.0);
                let bits = |h: Option<Hit>| {
                    h.map(|h| (h.t.to_bits(), h.normal.to_array().map(f64::to_bits)))
                };
                assert_eq!(bits(fast), bits(general), "ray {k}: {ray:?}");
                let planes = s.polytopes.of(root).unwrap();
                let looped = polytope_intersection(planes, &ray, t_min, 10.0);
                assert_eq!(bits(fast), bits(looped), "ray {k}: {ray:?}");
                hits += usize::from(fast.is_some());
            }
            assert!(hits > 500, "{hits} hits");
        }
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

    /// Intersections of plain quadrics take the closed form; it must walk the same
    /// crossings, with the same normals, as the general combine: boxes (rotated), capped
    /// cylinders, a ball cut by planes, and an empty intersection, 2 000 rays each,
    /// walked from crossing to crossing.
    #[test]
    fn plain_intersections_walk_as_the_general_combine() {
        use super::conjunction::tests::{plane, q, slab_box};
        use crate::quadric::Quadric;
        let axis = DVec3::new(0.2, 1.0, 0.3).normalize();
        let shapes = [
            slab_box(DVec3::new(1.0, 0.5, 0.2)),
            Shape::Transformed(
                Affine::rotate(DVec3::new(1.0, 1.0, 0.0), 0.7),
                Box::new(slab_box(DVec3::new(0.3, 1.2, 0.8))),
            ),
            Shape::Intersection(vec![
                q(Quadric::cylinder(DVec3::ZERO, axis, 0.4)),
                plane(axis, 1.0),
                plane(-axis, 0.5),
            ]),
            Shape::Intersection(vec![
                q(Quadric::sphere(DVec3::ZERO, 1.0)),
                plane(DVec3::new(1.0, 0.3, 0.0), 0.2),
                plane(DVec3::new(-0.2, -1.0, 0.4), 0.5),
            ]),
            Shape::Intersection(vec![plane(DVec3::X, -0.1), plane(-DVec3::X, -0.1)]),
        ];
        let crossings = conjunction::tests::walk_as_the_general_combine(
            &shapes,
            CsgOp::Intersection,
            Rule::All,
            5,
        );
        assert!(crossings > 3000, "{crossings}");
    }

    /// The flat form: children before parents, each leaf once in the table and its
    /// data in the pools, and equal builds equal.
    #[test]
    fn flat_form_is_post_order_and_comparable() {
        use crate::perturbed::PerturbedQuadric;
        use crate::quadric::Quadric;
        let pq = PerturbedQuadric::new(Quadric::sphere(DVec3::ZERO, 1.0))
            .with(0.5, Quadric::sphere(DVec3::X, 0.3))
            .with(-0.5, Quadric::sphere(DVec3::Y, 0.3));
        let shape = Shape::Difference(
            Box::new(Shape::Union(vec![
                Shape::Perturbed(pq),
                ball(DVec3::new(0.0, 0.0, 1.0), 0.5),
            ])),
            Box::new(ball(DVec3::new(1.0, 0.0, 0.0), 0.4)),
        );
        let (a, b) = (Solid::build(&shape).unwrap(), Solid::build(&shape).unwrap());
        assert_eq!(a, b);
        let f = a.flat();
        assert_eq!(f.leaves.len(), 3);
        assert_eq!(f.quadrics.len(), 1);
        assert_eq!(f.perturbations.len(), 2);
        assert!(!f.tapes.is_empty() && !f.bytecode.is_empty());
        for (i, n) in f.nodes.iter().enumerate() {
            assert!(f.parts(i).iter().all(|&c| (c as usize) < i));
            assert_eq!(n.op == CsgOp::Leaf, f.parts(i).is_empty());
        }
        assert_eq!(f.nodes.last().unwrap().op, CsgOp::Difference);
        assert!(matches!(f.leaves[0], crate::flat::Leaf::Perturbed { .. }));
    }

    /// A union of 40 balls in a row (inside the default domain) splits into nodes of at most MAX_PARTS parts, a
    /// chain of 100 nested unions stays shallow, and the crossings are those of the
    /// balls; CSG nested deeper than MAX_DEPTH is an error, not a panic.
    #[test]
    fn wide_and_deep_csg() {
        let balls: Vec<Shape> = (0..40)
            .map(|k| ball(DVec3::new(k as f64 * 2.4, 0.0, 0.0), 1.0))
            .collect();
        let chain = balls
            .iter()
            .rev()
            .cloned()
            .reduce(|acc, b| Shape::Union(vec![b, acc]))
            .unwrap();
        for shape in [Shape::Union(balls.clone()), chain] {
            let s = Solid::build(&shape).unwrap();
            let f = s.flat();
            assert!((0..f.nodes.len()).all(|i| f.parts(i).len() <= MAX_PARTS));
            let ray = Ray::new(DVec3::new(-5.0, 0.0, 0.0), DVec3::X);
            let mut t = 0.0;
            let mut got = vec![];
            while let Some(h) = s.intersect(&ray, t, 200.0) {
                got.push(h.t);
                t = h.t + 1e-9;
            }
            assert_eq!(got.len(), 80);
            for (k, t) in got.iter().enumerate() {
                let want = 5.0 + (k / 2) as f64 * 2.4 + if k % 2 == 0 { -1.0 } else { 1.0 };
                assert!((t - want).abs() < 1e-8, "{k}: {t} vs {want}");
            }
        }
        let mut deep = ball(DVec3::ZERO, 1.0);
        for k in 0..2 * MAX_DEPTH {
            let other = ball(DVec3::new(0.1 * k as f64, 0.0, 0.0), 1.0);
            deep = match k % 2 {
                0 => Shape::Union(vec![deep, other]),
                _ => Shape::Intersection(vec![deep, other]),
            };
        }
        let err = Solid::build(&deep).unwrap_err();
        assert_eq!(err, BuildError::TooDeep(2 * MAX_DEPTH + 1));
        assert!(err.to_string().contains("nested"), "{err}");
    }

    /// A solid's leaves, intersected in place over the pools, give what the owning
    /// surfaces give, bit for bit.
    /// A CSG solid's value is its leaves' values combined, bit for bit, where plain
    /// quadric leaves take their base's value directly (no view is assembled) and a
    /// perturbed leaf goes through its view: a union of two plain quadrics and a
    /// perturbed one minus a plain cylinder, at 2 000 points.
    #[test]
    fn plain_leaves_value_as_their_surfaces() {
        use crate::perturbed::PerturbedQuadric;
        use rand::{Rng, SeedableRng};
        let plain = [
            PerturbedQuadric::new(Quadric::ellipsoid(DVec3::ZERO, DVec3::new(1.0, 0.6, 0.4))),
            PerturbedQuadric::new(Quadric::sphere(DVec3::new(0.8, 0.1, 0.2), 0.5)),
        ];
        let bumpy = PerturbedQuadric::new(Quadric::sphere(DVec3::new(-0.7, 0.0, 0.1), 0.45))
            .with(0.5, Quadric::sphere(DVec3::new(-0.7, 0.4, 0.1), 0.2));
        let hole = PerturbedQuadric::new(Quadric::cylinder(DVec3::ZERO, DVec3::Z, 0.2));
        let shape = Shape::Difference(
            Box::new(Shape::Union(vec![
                Shape::Perturbed(plain[0].clone()),
                Shape::Perturbed(plain[1].clone()),
                Shape::Perturbed(bumpy.clone()),
            ])),
            Box::new(Shape::Perturbed(hole.clone())),
        );
        let solid = Solid::build(&shape).unwrap();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
        for _ in 0..2000 {
            let p = DVec3::new(rng.gen(), rng.gen(), rng.gen()) * 3.0 - 1.5;
            let union = [&plain[0], &plain[1], &bumpy]
                .map(|s| s.surface().value(p))
                .into_iter()
                .fold(f64::NEG_INFINITY, f64::max);
            let want = union.min(-hole.surface().value(p));
            assert_eq!(solid.value(p).to_bits(), want.to_bits(), "at {p:?}");
        }
    }

    #[test]
    fn flat_leaves_match_their_surfaces() {
        use crate::perturbed::PerturbedQuadric;
        use crate::quadric::Quadric;
        let mut pq =
            PerturbedQuadric::new(Quadric::ellipsoid(DVec3::ZERO, DVec3::new(1.0, 0.7, 0.5)));
        for k in 0..60 {
            let a = k as f64 * 2.4;
            let c = DVec3::new(a.cos(), 0.7 * a.sin(), 0.5 * (0.4 * a).sin());
            pq.push(
                if k % 3 == 0 { -30.0 } else { 50.0 },
                Quadric::sphere(c, 0.25),
            );
        }
        let gyroid = (3.0 * Tree::x()).sin() * (3.0 * Tree::y()).cos()
            + (3.0 * Tree::y()).sin() * (3.0 * Tree::z()).cos()
            + (3.0 * Tree::z()).sin() * (3.0 * Tree::x()).cos();
        let ball = 1.2 - (Tree::x().square() + Tree::y().square() + Tree::z().square());
        let expr = gyroid.min(&ball);
        let shapes = [Shape::Perturbed(pq.clone()), Shape::function(expr.clone())];
        let solids = shapes.map(|s| Solid::build(&s).unwrap());
        let e = Expr::new(&expr);
        let surfaces: [Box<dyn Surface>; 2] = [
            Box::new(pq.surface()),
            Box::new(ExprSurface::new(e.clone(), solids[1].bounds())),
        ];
        for (solid, surface) in solids.iter().zip(&surfaces) {
            let mut hits = 0;
            for k in 0..300 {
                let u = k as f64 * 0.37;
                let o = DVec3::new(2.0 * u.cos(), 1.5 * (0.7 * u).sin(), 2.0 * u.sin());
                let ray = Ray::new(o, -o + 0.3 * DVec3::new(u.sin(), 0.2, u.cos()));
                let got = solid.intersect(&ray, 0.0, f64::INFINITY);
                let want = surface.first_hit(&ray, 0.0, f64::INFINITY);
                assert_eq!(got.map(|h| (h.t, h.normal)), want, "ray {k}");
                hits += got.is_some() as usize;
                let p = ray.at(0.5);
                assert_eq!(solid.value(p).to_bits(), surface.value(p).to_bits());
            }
            assert!(hits > 100, "{hits} hits");
        }
    }
}
