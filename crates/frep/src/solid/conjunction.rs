//! CSG nodes of plain quadrics in closed form: an intersection of plain quadrics (a
//! capped cylinder, a ball cut by planes), or such an intersection minus a plain quadric
//! or a union of them (a table top with its corners cut, a plate with holes), is the
//! intersection of quadrics' positive sets, the second part's complemented. Along a ray
//! each is at most two intervals whose ends are the quadratic's roots about the ray's
//! origin, so the node's crossings are roots in closed form ([`Solid::conjunction`]),
//! and the walk of [`Solid::combine`] (a state per part, the parts' crossings searched
//! one by one) is not needed.

use crate::flat::{CsgOp, Flat, Leaf, Span};

#[cfg(doc)]
use super::Solid;

/// The most quadrics a node taken in closed form gathers.
pub(super) const MAX_ITEMS: usize = 16;

/// Per CSG node, the quadrics (indices of [`Flat::quadrics`]) whose positive sets, each
/// complemented where its flag says, intersect to the node's inside set.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Conjunctions {
    /// Per CSG node, its items in `items` (count 0: not such a node).
    spans: Vec<Span>,
    /// The quadrics, in part order.
    items: Vec<Item>,
}

/// One quadric of a node in closed form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Item {
    /// Its index in [`Flat::quadrics`].
    pub quadric: u32,
    /// Whether the node takes its negative set (the second part of a difference).
    pub complemented: bool,
    /// Whether it is a plane (no quadratic terms): its expansion along a ray takes
    /// [`crate::perturbed::along::q_local_f64`]'s shortcut.
    pub plane: bool,
}

impl Conjunctions {
    /// The nodes of `flat` that take the closed form: intersections of plain quadrics,
    /// and differences of a plain quadric or an intersection of them minus a plain
    /// quadric or a union of them, at most [`MAX_ITEMS`] quadrics in all.
    pub(super) fn new(flat: &Flat) -> Self {
        // A plain quadric leaf's quadric.
        let plain = |i: u32| {
            let node = &flat.nodes[i as usize];
            if node.op != CsgOp::Leaf {
                return None;
            }
            match flat.leaves[node.operands.first as usize] {
                Leaf::Perturbed {
                    base,
                    perturbations: Span { count: 0, .. },
                    ..
                } => Some(base),
                _ => None,
            }
        };
        // The quadrics of node i joined by `op` (or i's own), or None.
        let gather = |i: u32, op: CsgOp| -> Option<Vec<u32>> {
            if let Some(q) = plain(i) {
                return Some(vec![q]);
            }
            let parts = flat.parts(i as usize);
            match flat.nodes[i as usize].op == op {
                true => parts.iter().map(|&p| plain(p)).collect(),
                false => None,
            }
        };
        let mut c = Conjunctions {
            spans: vec![Span::default(); flat.nodes.len()],
            items: Vec::new(),
        };
        for (i, node) in flat.nodes.iter().enumerate() {
            let (kept, cut) = match node.op {
                CsgOp::Intersection => match gather(i as u32, CsgOp::Intersection) {
                    Some(kept) => (kept, Vec::new()),
                    None => continue,
                },
                CsgOp::Difference => {
                    let parts = flat.parts(i);
                    match (
                        gather(parts[0], CsgOp::Intersection),
                        gather(parts[1], CsgOp::Union),
                    ) {
                        (Some(kept), Some(cut)) => (kept, cut),
                        _ => continue,
                    }
                }
                _ => continue,
            };
            if kept.len() + cut.len() > MAX_ITEMS {
                continue;
            }
            let first = c.items.len();
            let item = |q: u32, complemented: bool| Item {
                quadric: q,
                complemented,
                plane: flat.quadrics[q as usize].c[..6].iter().all(|&v| v == 0.0),
            };
            c.items.extend(kept.iter().map(|&q| item(q, false)));
            c.items.extend(cut.iter().map(|&q| item(q, true)));
            c.spans[i] = Span::since(first, c.items.len());
        }
        c
    }

    /// Node i's quadrics and whether each is complemented, where it takes the closed
    /// form.
    #[inline]
    pub(super) fn of(&self, i: usize) -> Option<&[Item]> {
        let s = self.spans[i];
        (s.count > 0).then(|| &self.items[s.range()])
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::{Rule, Solid};
    use crate::flat::CsgOp;
    use crate::perturbed::PerturbedQuadric;
    use crate::quadric::Quadric;
    use crate::ray::Ray;
    use crate::shape::Shape;
    use crate::transform::Affine;
    use glam::DVec3;
    use rand::{Rng, SeedableRng};

    /// A plain quadric as a shape.
    pub(in crate::solid) fn q(q: Quadric) -> Shape {
        Shape::Perturbed(PerturbedQuadric::new(q))
    }

    /// The half-space n·p ≤ d as a shape.
    pub(in crate::solid) fn plane(n: DVec3, d: f64) -> Shape {
        q(Quadric::plane(n.normalize(), d))
    }

    /// The box |x| ≤ h.x, |y| ≤ h.y, |z| ≤ h.z as six planes.
    pub(in crate::solid) fn slab_box(h: DVec3) -> Shape {
        Shape::Intersection(
            [DVec3::X, DVec3::Y, DVec3::Z]
                .iter()
                .zip(h.to_array())
                .flat_map(|(&a, h)| [plane(a, h), plane(-a, h)])
                .collect(),
        )
    }

    /// Differences of plain quadrics take the closed form; it must walk the same
    /// crossings, with the same normals, as the general combine, and answer shadow
    /// rays as it does: a table top with its corners cut (a box minus four cylinders),
    /// a ball minus two balls, a capped cylinder minus a tilted cylinder, a half ball (a
    /// ball minus a half-space) and a rotated plate with a hole; 2 000 rays each, walked
    /// from crossing to crossing.
    #[test]
    fn differences_walk_as_the_general_combine() {
        let cut = |a: Shape, b: Shape| Shape::Difference(Box::new(a), Box::new(b));
        let column = |x: f64, y: f64| q(Quadric::cylinder(DVec3::new(x, y, 0.0), DVec3::Z, 0.25));
        let tilted = DVec3::new(0.2, 1.0, 0.3).normalize();
        let shapes = [
            cut(
                slab_box(DVec3::new(1.0, 0.6, 0.2)),
                Shape::Union(vec![
                    column(1.0, 0.6),
                    column(-1.0, 0.6),
                    column(1.0, -0.6),
                    column(-1.0, -0.6),
                ]),
            ),
            cut(
                q(Quadric::sphere(DVec3::ZERO, 1.0)),
                Shape::Union(vec![
                    q(Quadric::sphere(DVec3::new(0.6, 0.2, 0.0), 0.5)),
                    q(Quadric::sphere(DVec3::new(-0.3, -0.5, 0.4), 0.45)),
                ]),
            ),
            cut(
                Shape::Intersection(vec![
                    q(Quadric::cylinder(DVec3::ZERO, DVec3::Z, 0.8)),
                    plane(DVec3::Z, 0.6),
                    plane(-DVec3::Z, 0.6),
                ]),
                q(Quadric::cylinder(DVec3::new(0.1, 0.0, 0.0), tilted, 0.3)),
            ),
            cut(
                q(Quadric::sphere(DVec3::ZERO, 1.0)),
                plane(DVec3::new(0.3, -0.2, 1.0), 0.1),
            ),
            Shape::Transformed(
                Affine::rotate(DVec3::new(1.0, 1.0, 0.0), 0.7),
                Box::new(cut(
                    slab_box(DVec3::new(1.2, 0.9, 0.15)),
                    q(Quadric::cylinder(DVec3::ZERO, DVec3::Z, 0.4)),
                )),
            ),
        ];
        let crossings =
            walk_as_the_general_combine(&shapes, CsgOp::Difference, Rule::FirstNotSecond, 8);
        assert!(crossings > 8000, "{crossings} crossings");
    }

    /// Walks 2 000 random rays through each shape, whose root is a node of `op` taken in
    /// closed form, crossing by crossing from each crossing on, against the general walk
    /// of `rule`: the same crossings (within 10⁻⁹), normals and shadow answers. Returns
    /// how many crossings it compared.
    pub(in crate::solid) fn walk_as_the_general_combine(
        shapes: &[Shape],
        op: CsgOp,
        rule: Rule,
        seed: u64,
    ) -> usize {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let mut crossings = 0;
        for (j, shape) in shapes.iter().enumerate() {
            let s = Solid::build(shape).unwrap();
            let root = s.root();
            assert_eq!(s.flat.nodes[root].op, op, "shape {j}");
            assert!(
                s.conjunctions.of(root).is_some(),
                "shape {j}: not in closed form"
            );
            let general = |ray: &Ray, t0: f64| s.combine(root, rule, ray, t0, 50.0);
            for _ in 0..2000 {
                let o = DVec3::from_array([(); 3].map(|_| rng.gen_range(-3.0..3.0)));
                let aim = DVec3::from_array([(); 3].map(|_| rng.gen_range(-0.8..0.8)));
                let ray = Ray::new(o, (aim - o).normalize());
                let mut t = 0.0;
                for _ in 0..8 {
                    let (got, want) = (s.intersect(&ray, t, 50.0), general(&ray, t));
                    assert_eq!(
                        s.occludes(&ray, t, 50.0),
                        want.is_some(),
                        "shape {j} {ray:?} from {t}: shadow"
                    );
                    match (got, want) {
                        (Some(g), Some(w)) => {
                            assert!(
                                (g.t - w.t).abs() < 1e-9,
                                "shape {j} {ray:?}: {g:?} vs {w:?}"
                            );
                            assert!(
                                (g.normal - w.normal).length() < 1e-9,
                                "shape {j}: {g:?} vs {w:?}"
                            );
                            crossings += 1;
                            t = g.t + 1e-9;
                        }
                        (None, None) => break,
                        _ => panic!("shape {j} {ray:?} from {t}: {got:?} vs {want:?}"),
                    }
                }
            }
        }
        crossings
    }
}
