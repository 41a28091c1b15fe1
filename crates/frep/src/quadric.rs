//! General quadrics: F(x) = x̃ᵀQx̃ with 10 coefficients, ≥ 0 inside.
//!
//! Coefficient order: `[xx, yy, zz, xy, yz, xz, x, y, z, 1]`, i.e.
//! F = c0·x² + c1·y² + c2·z² + c3·xy + c4·yz + c5·xz + c6·x + c7·y + c8·z + c9.
//! Along a ray a quadric is a quadratic in t, which is what makes the exact
//! intersection of perturbed quadrics possible (RESEARCH.md §4).

use crate::tree::Tree;
use glam::DVec3;

/// A quadric function of x, y, z (see the module docs for the coefficient order).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quadric {
    /// Coefficients `[xx, yy, zz, xy, yz, xz, x, y, z, 1]`.
    pub c: [f64; 10],
}

impl Quadric {
    /// A quadric from its 10 coefficients.
    pub const fn new(c: [f64; 10]) -> Self {
        Self { c }
    }

    /// Ball of radius r: r² − |x − c|².
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

    /// Infinite double cone with apex `apex`, axis `axis` and half-angle `half_angle`:
    /// ((x−p)·â)²·cos²θ − |x−p|²·sin²θ... scaled as ((x−p)·â)² − tan²θ·|x − p − ((x−p)·â)â|².
    pub fn cone(apex: DVec3, axis: DVec3, half_angle: f64) -> Self {
        let a = axis.normalize();
        let t2 = half_angle.tan().powi(2);
        // ((x−p)·â)²(1 + t²) − t²|x−p|²
        let m = add3(scale3(outer(a, a), 1.0 + t2), scale3(identity(), -t2));
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
        Self::new([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -normal.x, -normal.y, -normal.z, d])
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

    /// The quadric as an expression tree.
    pub fn to_tree(&self) -> Tree {
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
