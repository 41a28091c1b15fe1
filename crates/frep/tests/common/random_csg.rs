//! Random CSG trees and rays for differential tests (`csg_differential.rs`, and the GPU
//! back end's tests, which include this file by path): depth ≤ 4; union, intersection
//! and difference, n-ary; spheres, ellipsoids, infinite cylinders and cones, axis and
//! rotated boxes, slabs, half-spaces and perturbed spheres; rays from inside and outside,
//! from far eyes, grazing a leaf's surface and through the edges where two leaves meet.
#![allow(dead_code)]

use frep::{Affine, PerturbedQuadric, Quadric, Ray, Shape};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// How far past its origin a grazing or edge ray meets its point.
pub const SPECIAL_T: f64 = 4.0;

pub fn unit(rng: &mut Pcg64) -> DVec3 {
    loop {
        let v = DVec3::new(
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        );
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

pub fn point(rng: &mut Pcg64, r: f64) -> DVec3 {
    DVec3::new(
        rng.gen_range(-r..r),
        rng.gen_range(-r..r),
        rng.gen_range(-r..r),
    )
}

pub fn plain(q: Quadric) -> Shape {
    Shape::Perturbed(PerturbedQuadric::new(q))
}

/// A random CSG tree and the world-space quadrics of its leaves (for grazing and edge
/// rays).
pub struct Tree3 {
    /// The tree.
    pub shape: Shape,
    /// Its leaves' quadrics in world space.
    pub quadrics: Vec<Quadric>,
}

pub struct Gen {
    rng: Pcg64,
    quadrics: Vec<Quadric>,
    perturbed: bool,
}

impl Gen {
    /// A generator of trees from a seed.
    pub fn new(seed: u64) -> Self {
        Self {
            rng: Pcg64::seed_from_u64(seed),
            quadrics: Vec::new(),
            perturbed: true,
        }
    }

    /// A generator of trees of plain quadrics only (plain spheres where the others have
    /// perturbed ones).
    pub fn plain(seed: u64) -> Self {
        Self {
            perturbed: false,
            ..Self::new(seed)
        }
    }
}

impl Gen {
    /// A tree of at most `depth` levels of CSG nodes.
    pub fn tree(&mut self, depth: usize) -> Tree3 {
        self.quadrics.clear();
        let shape = self.node(depth);
        Tree3 {
            shape,
            quadrics: std::mem::take(&mut self.quadrics),
        }
    }

    fn node(&mut self, depth: usize) -> Shape {
        let r = &mut self.rng;
        if depth == 0 || r.gen_bool(0.25) {
            return self.leaf();
        }
        let kind = r.gen_range(0..3);
        let n = if kind == 2 { 2 } else { r.gen_range(2..=4) };
        let parts: Vec<Shape> = (0..n).map(|_| self.node(depth - 1)).collect();
        match kind {
            0 => Shape::Union(parts),
            1 => Shape::Intersection(parts),
            _ => {
                let mut it = parts.into_iter();
                let (a, b) = (it.next().unwrap(), it.next().unwrap());
                Shape::Difference(Box::new(a), Box::new(b))
            }
        }
    }

    /// Keeps `q` (already in world space) and returns it as a plain part.
    fn keep(&mut self, q: Quadric) -> Shape {
        self.quadrics.push(q);
        plain(q)
    }

    fn leaf(&mut self) -> Shape {
        let r = &mut self.rng;
        let c = point(r, 1.0);
        match r.gen_range(0..10) {
            0 | 1 => {
                let rad = r.gen_range(0.2..1.0);
                self.keep(Quadric::sphere(c, rad))
            }
            2 => {
                let radii = DVec3::new(
                    r.gen_range(0.2..1.0),
                    r.gen_range(0.2..1.0),
                    r.gen_range(0.2..1.0),
                );
                // Rotated by a transform, which the build folds into the quadric.
                let (axis, angle) = (unit(r), r.gen_range(0.0..3.0));
                let m = Affine::rotate(axis, angle);
                let e = Quadric::ellipsoid(DVec3::ZERO, radii);
                let moved = Affine::translate(c);
                let whole = m.then(&moved);
                if let Some(q) = e.transformed(&whole) {
                    self.quadrics.push(q);
                }
                Shape::Transformed(whole, Box::new(plain(e)))
            }
            3 => {
                let (axis, rad) = (unit(r), r.gen_range(0.1..0.7));
                self.keep(Quadric::cylinder(c, axis, rad))
            }
            4 => {
                let (axis, angle) = (unit(r), r.gen_range(0.2..0.9));
                self.keep(Quadric::cone(c, axis, angle))
            }
            5 => {
                // A half-space through a point near the middle.
                let n = unit(r);
                self.keep(Quadric::plane(n, n.dot(c)))
            }
            6 => {
                // A slab between two parallel planes.
                let (n, w) = (unit(r), r.gen_range(0.05..0.8));
                let k = n.dot(c);
                let parts = vec![
                    self.keep(Quadric::plane(n, k + w)),
                    self.keep(Quadric::plane(-n, w - k)),
                ];
                Shape::Intersection(parts)
            }
            7 | 8 => {
                // A box as `box(..)` builds it (the slab test's form), or rotated (a
                // general polytope).
                let h = DVec3::new(
                    self.rng.gen_range(0.1..0.9),
                    self.rng.gen_range(0.1..0.9),
                    self.rng.gen_range(0.1..0.9),
                );
                let rot = self
                    .rng
                    .gen_bool(0.5)
                    .then(|| Affine::rotate(unit(&mut self.rng), self.rng.gen_range(0.1..3.0)));
                let mut faces = Vec::new();
                for (k, n) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
                    let (n, cn) = match &rot {
                        Some(m) => {
                            let n = (m.point(n) - m.point(DVec3::ZERO)).normalize();
                            (n, n.dot(c))
                        }
                        None => (n, n.dot(c)),
                    };
                    faces.push(self.keep(Quadric::plane(n, cn + h[k])));
                    faces.push(self.keep(Quadric::plane(-n, h[k] - cn)));
                }
                Shape::Intersection(faces)
            }
            _ => {
                // A sphere with a bump (the perturbed scan inside CSG).
                let rad = self.rng.gen_range(0.3..1.0);
                let bump = c + unit(&mut self.rng) * rad;
                let f = self.rng.gen_range(-2.0..4.0);
                let s = Quadric::sphere(c, rad);
                self.quadrics.push(s);
                if !self.perturbed {
                    return plain(s);
                }
                Shape::Perturbed(PerturbedQuadric::new(s).with(f, Quadric::sphere(bump, 0.4)))
            }
        }
    }
}

/// A point on q = 0 near `x` (Newton along the gradient), if found.
pub fn on_surface(q: &Quadric, mut x: DVec3) -> Option<DVec3> {
    for _ in 0..40 {
        let (v, g) = (q.eval(x), q.gradient(x));
        let gg = g.length_squared();
        if gg < 1e-12 {
            return None;
        }
        x -= g * (v / gg);
        if v.abs() < 1e-13 {
            return Some(x);
        }
    }
    None
}

/// A point where q1 = q2 = 0 near `x` (Gauss–Newton on both), if found.
pub fn on_edge(q1: &Quadric, q2: &Quadric, mut x: DVec3) -> Option<DVec3> {
    for _ in 0..60 {
        let (v1, v2) = (q1.eval(x), q2.eval(x));
        if v1.abs() < 1e-13 && v2.abs() < 1e-13 {
            return Some(x);
        }
        let (g1, g2) = (q1.gradient(x), q2.gradient(x));
        // Minimum-norm step of the 2×3 system J·dx = −v.
        let (a, b, d) = (g1.dot(g1), g1.dot(g2), g2.dot(g2));
        let det = a * d - b * b;
        if det.abs() < 1e-12 {
            return None;
        }
        let (l1, l2) = ((d * v1 - b * v2) / det, (a * v2 - b * v1) / det);
        x -= g1 * l1 + g2 * l2;
        if x.length() > 10.0 {
            return None;
        }
    }
    None
}

/// `n` random rays for a tree: a quarter from random points (inside or outside parts), a
/// quarter from far eyes, a quarter grazing a leaf's surface, a quarter through a point
/// where two leaves' surfaces meet (an edge of the CSG), each origin 4 before the point
/// (returned with the ray: where it is degenerate).
pub fn rays(rng: &mut Pcg64, t: &Tree3, n: usize) -> Vec<(Ray, Option<f64>)> {
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let k = out.len() % 4;
        let ray = match k {
            0 => {
                let o = point(rng, 3.0);
                Some(Ray::new(o, (point(rng, 1.5) - o).normalize()))
            }
            1 => {
                let o = unit(rng) * 6.0;
                Some(Ray::new(o, (point(rng, 1.5) - o).normalize()))
            }
            2 => {
                let q = &t.quadrics[rng.gen_range(0..t.quadrics.len())];
                on_surface(q, point(rng, 1.5)).map(|p| {
                    let g = q.gradient(p).normalize();
                    let v = unit(rng);
                    let mut d = (v - g * g.dot(v)).normalize();
                    // A ray tangent to a plane lies in it to rounding, where any answer
                    // is F's rounding (exact face rays: `rays_lying_in_a_surface_..`):
                    // tilt it by a thousandth.
                    if q.c[..6].iter().all(|&c| c == 0.0) {
                        d = (d + g * rng.gen_range(-1e-3..1e-3)).normalize();
                    }
                    Ray::new(p - SPECIAL_T * d, d)
                })
            }
            _ if t.quadrics.len() >= 2 => {
                let i = rng.gen_range(0..t.quadrics.len());
                let j = (i + rng.gen_range(1..t.quadrics.len())) % t.quadrics.len();
                on_edge(&t.quadrics[i], &t.quadrics[j], point(rng, 1.5)).map(|p| {
                    let d = unit(rng);
                    Ray::new(p - SPECIAL_T * d, d)
                })
            }
            _ => None,
        };
        match ray {
            // Grazing and edge rays meet their point at t = 4.
            Some(r) if r.o.is_finite() && r.d.is_finite() => {
                out.push((r, (k >= 2).then_some(SPECIAL_T)))
            }
            // Fall back to a random ray so that every tree gets its count.
            _ => {
                let o = point(rng, 3.0);
                out.push((Ray::new(o, (point(rng, 1.5) - o).normalize()), None))
            }
        }
    }
    out
}

/// The tree in the frepray language (`quadric(..)` leaves, as they are in world space),
/// for scenes that name it as an object's `solid`.
pub fn to_frep(shape: &Shape) -> String {
    let q = |q: &Quadric| {
        let c: Vec<String> = q.c.iter().map(|v| format!("{v:e}")).collect();
        format!("quadric([{}])", c.join(", "))
    };
    let list = |v: &[Shape]| v.iter().map(to_frep).collect::<Vec<_>>().join(", ");
    match shape {
        Shape::Perturbed(p) if p.perturbations().is_empty() => q(p.base()),
        Shape::Perturbed(p) => {
            let terms: Vec<String> = p
                .perturbations()
                .iter()
                .map(|t| format!("{:e} * {}^3", t.f, q(&t.q)))
                .collect();
            format!("perturb({}, {})", q(p.base()), terms.join(", "))
        }
        Shape::Union(v) => format!("union({})", list(v)),
        Shape::Intersection(v) => format!("intersection({})", list(v)),
        Shape::Difference(a, b) => format!("difference({}, {})", to_frep(a), to_frep(b)),
        Shape::Transformed(m, s) => match &**s {
            Shape::Perturbed(p) if p.perturbations().is_empty() => {
                q(&p.base().transformed(m).expect("a regular transform"))
            }
            _ => panic!("only moved quadrics are written"),
        },
        Shape::Function { .. } => panic!("trees hold no expressions"),
    }
}
