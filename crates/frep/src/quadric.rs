//! General quadrics: F(x) = x̃ᵀQx̃ with 10 coefficients, ≥ 0 inside.
//!
//! Coefficient order: `[xx, yy, zz, xy, yz, xz, x, y, z, 1]`, i.e.
//! F = c0·x² + c1·y² + c2·z² + c3·xy + c4·yz + c5·xz + c6·x + c7·y + c8·z + c9.
//! Along a ray a quadric is a quadratic in t, which is what makes the exact
//! intersection of perturbed quadrics possible (RESEARCH.md §4).

use crate::ray::Aabb;
use crate::transform::Affine;
use crate::tree::Tree;
use glam::{DMat3, DVec3};

/// A quadric function of x, y, z (see the module docs for the coefficient order).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Quadric {
    /// Coefficients `[xx, yy, zz, xy, yz, xz, x, y, z, 1]`.
    pub c: [f64; 10],
}

impl Quadric {
    /// A quadric from its 10 coefficients.
    pub const fn new(c: [f64; 10]) -> Self {
        Self { c }
    }

    /// Whether the inside F ≥ 0 is an ellipsoid (or empty): the quadratic part's matrix
    /// A is negative definite, so F is strictly concave and its superlevel sets are
    /// convex and bounded. Decided by −A's leading principal minors (Sylvester), each
    /// asked to exceed 1e-9 of the product of its diagonal entries, so that rounding
    /// never calls a nearly degenerate quadric (a long cylinder, a flat hyperboloid)
    /// convex: only false "no"s are possible.
    pub fn inside_is_convex(&self) -> bool {
        let c = &self.c;
        // −A, symmetric: diagonal −c0, −c1, −c2; off-diagonal −c3/2 (xy), −c4/2 (yz),
        // −c5/2 (xz).
        let (a, b, e) = (-c[0], -c[1], -c[2]);
        let (xy, yz, xz) = (-c[3] / 2.0, -c[4] / 2.0, -c[5] / 2.0);
        let m2 = a * b - xy * xy;
        let m3 = a * (b * e - yz * yz) - xy * (xy * e - yz * xz) + xz * (xy * yz - b * xz);
        let tol = 1e-9;
        a > 0.0 && b > 0.0 && e > 0.0 && m2 > tol * a * b && m3 > tol * a * b * e
    }

    /// Ball of radius r: 1 − |x − c|²/r² (normalised: 1 at the centre, whatever r).
    pub fn sphere(center: DVec3, r: f64) -> Self {
        Self::ellipsoid(center, DVec3::splat(r))
    }

    /// Axis-aligned ellipsoid: 1 − Σ ((x_k − c_k)/r_k)².
    pub fn ellipsoid(center: DVec3, radii: DVec3) -> Self {
        let w = DVec3::ONE / (radii * radii);
        let c = center;
        Self::new([
            -w.x,
            -w.y,
            -w.z,
            0.0,
            0.0,
            0.0,
            2.0 * w.x * c.x,
            2.0 * w.y * c.y,
            2.0 * w.z * c.z,
            1.0 - (w * c * c).element_sum(),
        ])
    }

    /// F = −(xᵀMx) − 2bᵀx… from a symmetric matrix form: F = xᵀAx + 2 bᵀx + k.
    pub fn from_matrix(a: [[f64; 3]; 3], b: DVec3, k: f64) -> Self {
        Self::new([
            a[0][0],
            a[1][1],
            a[2][2],
            a[0][1] + a[1][0],
            a[1][2] + a[2][1],
            a[0][2] + a[2][0],
            2.0 * b.x,
            2.0 * b.y,
            2.0 * b.z,
            k,
        ])
    }

    /// The symmetric matrix form (A, b, k) with F = xᵀAx + 2bᵀx + k.
    pub fn to_matrix(&self) -> ([[f64; 3]; 3], DVec3, f64) {
        let c = &self.c;
        (
            [
                [c[0], 0.5 * c[3], 0.5 * c[5]],
                [0.5 * c[3], c[1], 0.5 * c[4]],
                [0.5 * c[5], 0.5 * c[4], c[2]],
            ],
            DVec3::new(0.5 * c[6], 0.5 * c[7], 0.5 * c[8]),
            c[9],
        )
    }

    /// Infinite cylinder of radius r around the line through `point` along `axis`:
    /// r² − |x − p|² + ((x − p)·â)².
    pub fn cylinder(point: DVec3, axis: DVec3, r: f64) -> Self {
        let a = axis.normalize();
        // r² − (x−p)ᵀ(I −ââᵀ)(x−p)
        let m = outer(a, a);
        Self::from_line_form(point, sub3(m, identity()), r * r)
    }

    /// Infinite double cone with apex `apex`, axis `axis` and half-angle `half_angle` θ:
    /// tan²θ·h² − ρ², with h = (x−p)·â the height along the axis and
    /// ρ² = |x−p|² − h² the squared distance from it (zero where ρ = |h|·tanθ).
    pub fn cone(apex: DVec3, axis: DVec3, half_angle: f64) -> Self {
        let a = axis.normalize();
        let t2 = half_angle.tan().powi(2);
        // tan²θ·h² − (|x−p|² − h²) = (1 + tan²θ)·((x−p)·â)² − |x−p|²
        let m = add3(scale3(outer(a, a), 1.0 + t2), scale3(identity(), -1.0));
        Self::from_line_form(apex, m, 0.0)
    }

    /// Paraboloid opening along `axis` from `apex`: (x−p)·â − k·|x − p − ((x−p)·â)â|².
    pub fn paraboloid(apex: DVec3, axis: DVec3, k: f64) -> Self {
        let a = axis.normalize();
        let m = scale3(sub3(outer(a, a), identity()), k);
        let mut q = Self::from_line_form(apex, m, 0.0);
        // + â·(x − p)
        q.c[6] += a.x;
        q.c[7] += a.y;
        q.c[8] += a.z;
        q.c[9] -= a.dot(apex);
        q
    }

    /// Half-space n·x ≤ d (inside where d − n·x ≥ 0).
    pub fn plane(normal: DVec3, d: f64) -> Self {
        Self::new([
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -normal.x, -normal.y, -normal.z, d,
        ])
    }

    /// F = (x−p)ᵀM(x−p) + k for symmetric M.
    fn from_line_form(p: DVec3, m: [[f64; 3]; 3], k: f64) -> Self {
        let mp = DVec3::new(
            m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z,
            m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z,
            m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z,
        );
        Self::from_matrix(m, -mp, p.dot(mp) + k)
    }

    /// F at p.
    #[inline]
    pub fn eval(&self, p: DVec3) -> f64 {
        let c = &self.c;
        let (x, y, z) = (p.x, p.y, p.z);
        x * (c[0] * x + c[3] * y + c[5] * z + c[6])
            + y * (c[1] * y + c[4] * z + c[7])
            + z * (c[2] * z + c[8])
            + c[9]
    }

    /// ∇F at p (2(Qx̃)_xyz, RESEARCH.md §4).
    #[inline]
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        let c = &self.c;
        DVec3::new(
            2.0 * c[0] * p.x + c[3] * p.y + c[5] * p.z + c[6],
            2.0 * c[1] * p.y + c[3] * p.x + c[4] * p.z + c[7],
            2.0 * c[2] * p.z + c[4] * p.y + c[5] * p.x + c[8],
        )
    }

    /// F along the ray o + t·d as `[a0, a1, a2]`: F = a0 + a1·t + a2·t².
    #[inline]
    pub fn along(&self, o: DVec3, d: DVec3) -> [f64; 3] {
        let c = &self.c;
        let a2 = c[0] * d.x * d.x
            + c[1] * d.y * d.y
            + c[2] * d.z * d.z
            + c[3] * d.x * d.y
            + c[4] * d.y * d.z
            + c[5] * d.x * d.z;
        let a1 = 2.0 * (c[0] * o.x * d.x + c[1] * o.y * d.y + c[2] * o.z * d.z)
            + c[3] * (o.x * d.y + o.y * d.x)
            + c[4] * (o.y * d.z + o.z * d.y)
            + c[5] * (o.x * d.z + o.z * d.x)
            + c[6] * d.x
            + c[7] * d.y
            + c[8] * d.z;
        [self.eval(o), a1, a2]
    }

    /// The quadratic part xᵀAx as a matrix (symmetric).
    pub fn quadratic_part(&self) -> DMat3 {
        let (a, _, _) = self.to_matrix();
        DMat3::from_cols_array_2d(&a)
    }

    /// dᵀAd: the t² coefficient of [`along`](Self::along), which depends on the
    /// direction only.
    #[inline]
    pub fn curvature_along(&self, d: DVec3) -> f64 {
        let c = &self.c;
        c[0] * d.x * d.x
            + c[1] * d.y * d.y
            + c[2] * d.z * d.z
            + c[3] * d.x * d.y
            + c[4] * d.y * d.z
            + c[5] * d.x * d.z
    }

    /// The centre and peak value of a quadric whose quadratic part A is negative
    /// definite: c = −A⁻¹b, F(c) = k + bᵀc (F = xᵀAx + 2bᵀx + k, so F(c + y) = yᵀAy +
    /// F(c)). None when A is not negative definite (Sylvester's criterion on −A, with a
    /// relative margin of 1e-12: a nearly degenerate ellipsoid counts as unbounded).
    pub fn peak(&self) -> Option<(DVec3, f64)> {
        let (a, b, k) = self.to_matrix();
        let am = self.quadratic_part();
        // Leading minors of −A, each required to exceed rounding of its size (so that a
        // cylinder's or cone's zero determinant never passes as a tiny positive one).
        let norm = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let tol = 1e-12;
        let m1 = -a[0][0];
        let m2 = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        let m3 = -am.determinant();
        if !(m1 > tol * norm && m2 > tol * norm * norm && m3 > tol * norm * norm * norm) {
            return None;
        }
        let c = -(am.inverse() * b);
        Some((c, k + b.dot(c)))
    }

    /// A box holding {F ≥ 0}. For negative definite A the set is the ellipsoid
    /// (x−c)ᵀ(−A)(x−c) ≤ F(c), whose half-extent along axis k is √(F(c)·(−A⁻¹)_kk)
    /// (the support function of an ellipsoid); the box is widened by a few ulps so that
    /// rounding never makes it too small, and is [`Aabb::EMPTY`] when F(c) < 0. Where
    /// F does not depend on some coordinate axes (an axis-aligned cylinder, a slab
    /// between two parallel planes, as `cylinder(z, …)` builds them) and is such an
    /// ellipsoid in the others, the box is that ellipsoid's there and unbounded along
    /// the free axes. Any other quadric gives [`Aabb::EVERYTHING`].
    pub fn support_bounds(&self) -> Aabb {
        let (c, peak, diag) = match self.peak() {
            Some((c, peak)) => {
                let inv = -self.quadratic_part().inverse();
                (
                    c,
                    peak,
                    DVec3::new(inv.x_axis.x, inv.y_axis.y, inv.z_axis.z),
                )
            }
            None => match self.free_axes_peak() {
                Some(v) => v,
                None => return Aabb::EVERYTHING,
            },
        };
        if peak < 0.0 {
            return Aabb::EMPTY;
        }
        // Free axes (diag +∞) stay unbounded, a peak of 0 included.
        let half = diag.map(|v| match v {
            f64::INFINITY => v,
            _ => (v * peak).max(0.0).sqrt(),
        });
        let pad = (half + c.abs()) * 1e-12 + DVec3::splat(f64::MIN_POSITIVE);
        let half = half + pad;
        if half.is_nan() || !c.is_finite() {
            return Aabb::EVERYTHING;
        }
        Aabb::new(c - half, c + half)
    }

    /// [`Self::peak`] for a quadric that does not depend on one or two coordinate axes
    /// (their rows of A and their entries of b exactly zero) and whose quadratic part in
    /// the others is negative definite: the centre (0 along the free axes), the peak
    /// value, and the diagonal of −A⁻¹ in the bound axes (+∞ along the free ones, so
    /// that the box is unbounded there). None for any other quadric.
    fn free_axes_peak(&self) -> Option<(DVec3, f64, DVec3)> {
        let (a, b, k) = self.to_matrix();
        let free = |i: usize| a[i].iter().all(|&v| v == 0.0) && b[i] == 0.0;
        let bound: Vec<usize> = (0..3).filter(|&i| !free(i)).collect();
        let norm = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let tol = 1e-12;
        let mut c = DVec3::ZERO;
        let mut diag = DVec3::INFINITY;
        match bound[..] {
            [i] => {
                // a·x² + 2b·x + k: centre −b/a, peak k + b·c, half-extent² peak/(−a).
                let ai = a[i][i];
                let definite = -ai > tol * norm;
                if !definite {
                    return None;
                }
                c[i] = -b[i] / ai;
                diag[i] = -1.0 / ai;
            }
            [i, j] => {
                // The 2×2 block's inverse, [[a_jj, −a_ij], [−a_ij, a_ii]] / det.
                let (aii, aij, ajj) = (a[i][i], a[i][j], a[j][j]);
                let det = aii * ajj - aij * aij;
                if !(-aii > tol * norm && det > tol * norm * norm) {
                    return None;
                }
                c[i] = -(ajj * b[i] - aij * b[j]) / det;
                c[j] = -(aii * b[j] - aij * b[i]) / det;
                diag[i] = -ajj / det;
                diag[j] = -aii / det;
            }
            _ => return None,
        }
        Some((c, k + b.dot(c), diag))
    }

    /// F∘A⁻¹: the quadric moved by the affine map `a`, again a quadric. With A⁻¹x = Mx + t
    /// and F = yᵀAy + 2bᵀy + k: A' = MᵀAM, b' = Mᵀ(At + b), k' = F(t). None for a
    /// singular map.
    pub fn transformed(&self, a: &Affine) -> Option<Quadric> {
        let inv = a.inverse()?;
        let (m, t) = (inv.m, inv.t);
        let (am, b, _) = self.to_matrix();
        let am = DMat3::from_cols_array_2d(&am);
        let a2 = m.transpose() * am * m;
        let b2 = m.transpose() * (am * t + b);
        let k2 = self.eval(t);
        let a2 = a2.to_cols_array_2d();
        // Symmetrise exactly: the off-diagonal sums are what the coefficients hold.
        let sym = [
            [
                a2[0][0],
                0.5 * (a2[0][1] + a2[1][0]),
                0.5 * (a2[0][2] + a2[2][0]),
            ],
            [
                0.5 * (a2[0][1] + a2[1][0]),
                a2[1][1],
                0.5 * (a2[1][2] + a2[2][1]),
            ],
            [
                0.5 * (a2[0][2] + a2[2][0]),
                0.5 * (a2[1][2] + a2[2][1]),
                a2[2][2],
            ],
        ];
        Some(Self::from_matrix(sym, b2, k2))
    }

    /// The quadric as an expression tree. Without cross terms it is written with its
    /// squares completed, K + Σ a_k·(x_k − h_k)², so that each coordinate appears once:
    /// interval arithmetic then bounds each term exactly (the monomial form's a·x² + b·x
    /// counts x twice and widens with |x|·width; Moore 1966, the dependency problem),
    /// and a point far from the origin is not evaluated by cancelling large terms.
    pub fn to_tree(&self) -> Tree {
        if self.c[3..6].iter().all(|&c| c == 0.0) {
            return self.completed_tree();
        }
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let terms = [
            x.square(),
            y.square(),
            z.square(),
            &x * &y,
            &y * &z,
            &x * &z,
            x.clone(),
            y.clone(),
            z.clone(),
        ];
        let mut e = Tree::constant(self.c[9]);
        for (k, t) in terms.into_iter().enumerate() {
            if self.c[k] != 0.0 {
                e = e + self.c[k] * t;
            }
        }
        e
    }

    /// [`Quadric::to_tree`] for a quadric without cross terms: a_k·x_k² + b_k·x_k is
    /// a_k·(x_k − h_k)² − a_k·h_k² with h_k = −b_k / (2·a_k); equal a_k (a sphere, a
    /// circular cylinder) share one product. A coordinate whose vertex lies so far out
    /// that a_k·h_k² dwarfs the coefficients keeps its monomials.
    fn completed_tree(&self) -> Tree {
        let c = &self.c;
        let vars = [Tree::x(), Tree::y(), Tree::z()];
        let mut k = c[9];
        // Squares grouped by their coefficient, in axis order; linear terms apart.
        let mut groups: Vec<(f64, Tree)> = Vec::new();
        let mut linear: Vec<Tree> = Vec::new();
        for (i, v) in vars.iter().enumerate() {
            let (a, b) = (c[i], c[6 + i]);
            if a == 0.0 {
                if b != 0.0 {
                    linear.push(b * v);
                }
                continue;
            }
            let h = -b / (2.0 * a);
            // A vertex far out (a nearly flat parabola: a tiny next to b) would make K'
            // and a·(x − h)² huge and cancelling; such a coordinate keeps a·x² + b·x.
            if (a * h * h).abs() > 1e6 * (c[9].abs() + a.abs() + b.abs()) {
                linear.push(a * v.square() + b * v);
                continue;
            }
            k -= a * h * h;
            let sq = if h == 0.0 {
                v.square()
            } else {
                (v - h).square()
            };
            match groups.iter_mut().find(|(g, _)| *g == a) {
                Some((_, t)) => *t = &*t + &sq,
                None => groups.push((a, sq)),
            }
        }
        let mut e = Tree::constant(k);
        for (a, t) in groups {
            e = e + a * t;
        }
        for t in linear {
            e = e + t;
        }
        e
    }
}

fn outer(a: DVec3, b: DVec3) -> [[f64; 3]; 3] {
    [
        [a.x * b.x, a.x * b.y, a.x * b.z],
        [a.y * b.x, a.y * b.y, a.y * b.z],
        [a.z * b.x, a.z * b.y, a.z * b.z],
    ]
}

fn identity() -> [[f64; 3]; 3] {
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
}

fn scale3(m: [[f64; 3]; 3], s: f64) -> [[f64; 3]; 3] {
    m.map(|r| r.map(|v| v * s))
}

fn add3(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut o = a;
    for i in 0..3 {
        for j in 0..3 {
            o[i][j] += b[i][j];
        }
    }
    o
}

fn sub3(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    add3(a, scale3(b, -1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    fn unit(rng: &mut Pcg64) -> DVec3 {
        loop {
            let v = DVec3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            );
            let l = v.length();
            if l > 0.1 && l < 1.0 {
                return v / l;
            }
        }
    }

    /// An orthonormal pair perpendicular to `a`.
    fn frame(a: DVec3) -> (DVec3, DVec3) {
        let a = a.normalize();
        let u = a.any_orthonormal_vector();
        (u, a.cross(u))
    }

    /// (name, quadric, surface parametrisation, an inside point, an outside point).
    type Case = (
        &'static str,
        Quadric,
        Box<dyn Fn(f64, f64) -> DVec3>,
        DVec3,
        DVec3,
    );

    /// Each helper with a parametrised surface point, an inside and an outside point.
    fn shapes() -> Vec<Case> {
        let c = DVec3::new(0.3, -0.2, 0.5);
        let axis = DVec3::new(1.0, 2.0, -0.5).normalize();
        let (u, v) = frame(axis);
        let radii = DVec3::new(0.5, 1.5, 0.8);
        let theta = 0.4f64;
        vec![
            (
                "sphere",
                Quadric::sphere(c, 0.7),
                Box::new(move |s, w| {
                    c + 0.7 * DVec3::new(s.cos() * w.sin(), s.sin() * w.sin(), w.cos())
                }),
                c + DVec3::splat(0.3),
                c + DVec3::new(0.0, 0.71, 0.0),
            ),
            (
                "ellipsoid",
                Quadric::ellipsoid(c, radii),
                Box::new(move |s, w| {
                    c + radii * DVec3::new(s.cos() * w.sin(), s.sin() * w.sin(), w.cos())
                }),
                c + DVec3::new(0.45, 0.0, 0.0),
                c + DVec3::new(0.0, 0.0, 0.81),
            ),
            (
                "cylinder",
                Quadric::cylinder(c, axis, 0.6),
                Box::new(move |s, w| c + 0.6 * (s.cos() * u + s.sin() * v) + 10.0 * w * axis),
                c + 100.0 * axis + 0.59 * u,
                c - 3.0 * axis + 0.61 * v,
            ),
            (
                "cone",
                Quadric::cone(c, axis, theta),
                Box::new(move |s, w| {
                    c + w * 3.0 * (axis + theta.tan() * (s.cos() * u + s.sin() * v))
                }),
                c + 2.0 * axis + 0.9 * theta.tan() * 2.0 * u,
                c + 2.0 * axis + 1.1 * theta.tan() * 2.0 * v,
            ),
            (
                "paraboloid",
                Quadric::paraboloid(c, axis, 2.0),
                Box::new(move |s, w| {
                    let rho = 2.0 * w.abs();
                    c + 2.0 * rho * rho * axis + rho * (s.cos() * u + s.sin() * v)
                }),
                c + 0.5 * axis + 0.49 * u,
                c + 0.5 * axis + 0.51 * u,
            ),
            (
                "plane",
                Quadric::plane(axis, 0.25),
                Box::new(move |s, w| 0.25 * axis + 5.0 * (s * u + w * v)),
                0.2 * axis + u,
                0.3 * axis - 4.0 * v,
            ),
        ]
    }

    #[test]
    fn helpers_vanish_on_their_surface_and_are_positive_inside() {
        let mut rng = Pcg64::seed_from_u64(3);
        for (name, q, surf, inside, outside) in shapes() {
            for _ in 0..200 {
                let p = surf(rng.gen_range(-3.2..3.2), rng.gen_range(-1.0..1.0));
                let scale = 1.0 + p.length_squared();
                assert!(
                    q.eval(p).abs() < 1e-12 * scale,
                    "{name}: F = {} at {p}",
                    q.eval(p)
                );
            }
            assert!(q.eval(inside) > 0.0, "{name} inside");
            assert!(q.eval(outside) < 0.0, "{name} outside");
        }
    }

    #[test]
    fn gradient_and_along_match_finite_differences() {
        let mut rng = Pcg64::seed_from_u64(4);
        for (name, q, ..) in shapes() {
            for _ in 0..50 {
                let p = DVec3::new(
                    rng.gen_range(-2.0..2.0),
                    rng.gen_range(-2.0..2.0),
                    rng.gen_range(-2.0..2.0),
                );
                let h = 1e-6;
                let fd = DVec3::new(
                    q.eval(p + DVec3::X * h) - q.eval(p - DVec3::X * h),
                    q.eval(p + DVec3::Y * h) - q.eval(p - DVec3::Y * h),
                    q.eval(p + DVec3::Z * h) - q.eval(p - DVec3::Z * h),
                ) / (2.0 * h);
                assert!(
                    (q.gradient(p) - fd).length() < 1e-7,
                    "{name}: {} vs {fd}",
                    q.gradient(p)
                );
                let d = unit(&mut rng) * 1.7;
                let a = q.along(p, d);
                assert_eq!(a[2], q.curvature_along(d));
                for t in [-1.3, 0.0, 0.4, 2.5] {
                    let direct = q.eval(p + t * d);
                    assert!(
                        (a[0] + t * (a[1] + t * a[2]) - direct).abs()
                            < 1e-12 * (1.0 + direct.abs())
                    );
                }
            }
        }
    }

    #[test]
    fn support_bounds_are_tight_boxes_of_the_positive_set() {
        let mut rng = Pcg64::seed_from_u64(5);
        // A rotated, translated ellipsoid: the box must hold every surface point and be
        // touched on every face (its extreme points lie on the surface).
        let a = Affine::rotate(DVec3::new(1.0, 1.0, 0.3), 0.8)
            .then(&Affine::translate(DVec3::new(0.5, -1.0, 2.0)));
        let radii = DVec3::new(0.3, 1.2, 0.7);
        let q = Quadric::ellipsoid(DVec3::ZERO, radii)
            .transformed(&a)
            .unwrap();
        let b = q.support_bounds();
        assert!(b.is_finite());
        let mut seen = Aabb::EMPTY;
        for _ in 0..200_000 {
            let p = a.point(radii * unit(&mut rng));
            assert!(q.eval(p).abs() < 1e-12);
            assert!(b.contains(p), "{p} outside {b:?}");
            seen.include(p);
        }
        assert!(
            (seen.lo - b.lo).abs().max_element() < 2e-3,
            "{seen:?} vs {b:?}"
        );
        assert!(
            (seen.hi - b.hi).abs().max_element() < 2e-3,
            "{seen:?} vs {b:?}"
        );
        // Axis-aligned: exact.
        let s = Quadric::sphere(DVec3::new(1.0, 2.0, 3.0), 0.5).support_bounds();
        assert!((s.lo - DVec3::new(0.5, 1.5, 2.5)).abs().max_element() < 1e-11);
        assert!((s.hi - DVec3::new(1.5, 2.5, 3.5)).abs().max_element() < 1e-11);
        // Axis-aligned cylinders and slabs: bounded across their free axes only.
        let cyl = Quadric::cylinder(DVec3::new(1.5, 0.9, 7.0), DVec3::Z, 0.25).support_bounds();
        let want = (DVec3::new(1.25, 0.65, 0.0), DVec3::new(1.75, 1.15, 0.0));
        for k in 0..2 {
            assert!((cyl.lo[k] - want.0[k]).abs() < 1e-11, "{cyl:?}");
            assert!((cyl.hi[k] - want.1[k]).abs() < 1e-11, "{cyl:?}");
        }
        assert_eq!((cyl.lo.z, cyl.hi.z), (f64::NEG_INFINITY, f64::INFINITY));
        let mut slab = Quadric::new([0.0; 10]);
        (slab.c[0], slab.c[6], slab.c[9]) = (-1.0, 2.0, -0.75); // 0.25 − (x − 1)²
        let b = slab.support_bounds();
        assert!(
            (b.lo.x - 0.5).abs() < 1e-11 && (b.hi.x - 1.5).abs() < 1e-11,
            "{b:?}"
        );
        assert!(
            b.lo.y == f64::NEG_INFINITY && b.hi.z == f64::INFINITY,
            "{b:?}"
        );
        // An elliptic cylinder along y, turned about its axis (a cross term x·z): the
        // box holds every surface point and is touched on its x and z faces.
        let turn =
            Affine::rotate(DVec3::Y, 0.7).then(&Affine::translate(DVec3::new(0.2, 5.0, -1.0)));
        let mut ell = Quadric::new([0.0; 10]);
        (ell.c[0], ell.c[2], ell.c[9]) = (-1.0 / 0.09, -1.0 / 0.64, 1.0); // x²/0.3² + z²/0.8² ≤ 1
        let ell = ell.transformed(&turn).unwrap();
        let b = ell.support_bounds();
        assert!(
            b.lo.y == f64::NEG_INFINITY && b.hi.y == f64::INFINITY,
            "{b:?}"
        );
        let mut seen = Aabb::EMPTY;
        for _ in 0..100_000 {
            let a: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
            let y = rng.gen_range(-10.0..10.0);
            let p = turn.point(DVec3::new(0.3 * a.cos(), y, 0.8 * a.sin()));
            assert!(ell.eval(p).abs() < 1e-12);
            assert!(b.contains(p), "{p} outside {b:?}");
            seen.include(p);
        }
        for k in [0, 2] {
            assert!((seen.lo[k] - b.lo[k]).abs() < 2e-3, "{seen:?} vs {b:?}");
            assert!((seen.hi[k] - b.hi[k]).abs() < 2e-3, "{seen:?} vs {b:?}");
        }
        // A cylinder of negative radius² holds nothing.
        let mut none = Quadric::cylinder(DVec3::ZERO, DVec3::X, 1.0);
        none.c[9] = -0.1;
        assert!(none.support_bounds().is_empty());
        // Nothing positive: empty. Unbounded positive sets: everything.
        let mut none = Quadric::sphere(DVec3::ZERO, 1.0);
        none.c[9] = -0.1;
        assert!(none.support_bounds().is_empty());
        let (_, cyl, ..) = &shapes()[2];
        assert_eq!(cyl.support_bounds(), Aabb::EVERYTHING);
        assert_eq!(
            Quadric::plane(DVec3::X, 0.0).support_bounds(),
            Aabb::EVERYTHING
        );
        let outside_ball = Quadric::new(Quadric::sphere(DVec3::ZERO, 1.0).c.map(|v| -v));
        assert_eq!(outside_ball.support_bounds(), Aabb::EVERYTHING);
    }

    #[test]
    fn transformed_quadric_is_the_quadric_moved_by_the_map() {
        let mut rng = Pcg64::seed_from_u64(6);
        let a = Affine::scale(DVec3::new(2.0, 0.5, 1.5))
            .then(&Affine::rotate(DVec3::new(0.2, 1.0, 0.4), 1.1))
            .then(&Affine::translate(DVec3::new(-1.0, 0.3, 0.8)));
        for (name, q, ..) in shapes() {
            let moved = q.transformed(&a).unwrap();
            for _ in 0..100 {
                let p = DVec3::new(
                    rng.gen_range(-2.0..2.0),
                    rng.gen_range(-2.0..2.0),
                    rng.gen_range(-2.0..2.0),
                );
                let want = q.eval(p);
                assert!(
                    (moved.eval(a.point(p)) - want).abs() < 1e-12 * (1.0 + want.abs()),
                    "{name}"
                );
            }
            let back = moved.transformed(&a.inverse().unwrap()).unwrap();
            for k in 0..10 {
                assert!(
                    (back.c[k] - q.c[k]).abs() < 1e-12,
                    "{name}: {back:?} vs {q:?}"
                );
            }
        }
        let singular = Affine::scale(DVec3::new(1.0, 0.0, 1.0));
        assert_eq!(
            Quadric::sphere(DVec3::ZERO, 1.0).transformed(&singular),
            None
        );
    }

    /// Without cross terms the tree completes its squares: its value is the quadric's
    /// to rounding, and its interval over a box is the quadric's exact range there (the
    /// sum of one univariate quadratic per coordinate, whose extremes lie at the box's
    /// ends or the vertex: 27 candidate points). The monomial form fails the second on
    /// boxes away from the origin, where a·x² + b·x cancels wide intervals.
    #[test]
    fn axis_aligned_trees_bound_boxes_exactly() {
        let mut rng = Pcg64::seed_from_u64(12);
        let mut v = |lo: f64, hi: f64| rng.gen_range(lo..hi);
        // A nearly flat parabola in x (vertex at −5·10¹²) keeps its value.
        let flat = Quadric::new([1e-13, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.5, 2.0, 0.3]);
        let flat_tree = crate::Expr::new(&flat.to_tree());
        for k in 0..400 {
            let c = DVec3::new(v(-5.0, 5.0), v(-5.0, 5.0), v(-5.0, 5.0));
            let q = match k % 4 {
                0 => Quadric::sphere(c, v(0.05, 2.0)),
                1 => Quadric::ellipsoid(c, DVec3::new(v(0.1, 2.0), v(0.1, 2.0), v(0.1, 2.0))),
                2 => Quadric::cylinder(c, DVec3::Z, v(0.05, 2.0)),
                _ => Quadric::paraboloid(c, DVec3::Y, v(0.1, 3.0)),
            };
            let e = crate::Expr::new(&q.to_tree());
            let scale = 1.0 + q.c.iter().map(|x| x.abs()).sum::<f64>() * 100.0;
            let (got, want) = (flat_tree.eval(c.to_array()), flat.eval(c));
            assert!((got - want).abs() <= 1e-13 * scale, "flat: {got} vs {want}");
            let lo = c + DVec3::new(v(-2.0, 1.0), v(-2.0, 1.0), v(-2.0, 1.0));
            let hi = lo + DVec3::new(v(0.0, 1.0), v(0.0, 1.0), v(0.0, 1.0));
            for _ in 0..20 {
                let p = lo + (hi - lo) * DVec3::new(v(0.0, 1.0), v(0.0, 1.0), v(0.0, 1.0));
                let (got, want) = (e.eval(p.to_array()), q.eval(p));
                assert!(
                    (got - want).abs() <= 1e-13 * scale,
                    "case {k}: {got} vs {want}"
                );
            }
            // Each coordinate's candidates: the box's ends and the vertex −b/(2a) within.
            let cand = |i: usize| {
                let (a, b) = (q.c[i], q.c[6 + i]);
                let h = if a != 0.0 { -b / (2.0 * a) } else { lo[i] };
                [lo[i], hi[i], h.clamp(lo[i], hi[i])]
            };
            let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
            for x in cand(0) {
                for y in cand(1) {
                    for z in cand(2) {
                        let f = q.eval(DVec3::new(x, y, z));
                        (min, max) = (min.min(f), max.max(f));
                    }
                }
            }
            let r = e.eval_interval(lo.to_array(), hi.to_array());
            let tol = 1e-12 * scale;
            assert!(
                r.lo <= min + tol && r.hi >= max - tol,
                "case {k}: {r:?} misses [{min}, {max}]"
            );
            assert!(
                r.lo >= min - tol && r.hi <= max + tol,
                "case {k}: {r:?} wider than [{min}, {max}]"
            );
        }
    }
}
