//! Helpers shared by the reader and ray tests.
#![allow(dead_code, unused_imports)]

pub mod random_csg;

pub use frep::read::{read_file, read_str, write_vm, Format, Model, ReadError};
pub use frep::shape::Shape;
pub use frep::{BinaryOp, Expr, Tree, UnaryOp};
pub use rand::{Rng, SeedableRng};
pub use std::path::PathBuf;

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

pub fn model_file(p: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../models")
        .join(p)
}

pub fn expr(m: &Model) -> Expr {
    Expr::new(&m.shape.to_tree().expect("a regular shape"))
}

/// A function of a point.
pub type Field = dyn Fn([f64; 3]) -> f64;

pub fn close(a: f64, b: f64) -> bool {
    (a.is_nan() && b.is_nan()) || a == b || (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()))
}

/// Random points in [-r, r]³ from a fixed seed.
pub fn points(n: usize, r: f64, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    (0..n)
        .map(|_| [0; 3].map(|_| rng.gen_range(-r..r)))
        .collect()
}

pub fn agree(m: &Model, f: impl Fn([f64; 3]) -> f64, r: f64, what: &str) {
    let e = expr(m);
    for p in points(400, r, 7) {
        let (got, want) = (e.eval(p), f(p));
        assert!(
            close(got, want),
            "{what} at {p:?}: read {got}, formula {want}"
        );
    }
}

pub fn err(text: &str, format: Format) -> ReadError {
    match read_str(text, format, "t") {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    }
}

/// Each case: input, expected line and column, and a piece of the message.
pub fn check_errors(format: Format, cases: &[(&str, usize, usize, &str)]) {
    for (text, line, col, msg) in cases {
        let e = err(text, format);
        assert_eq!(
            (e.line, e.column),
            (*line, *col),
            "position for {text:?}: {e}"
        );
        assert!(e.message.contains(msg), "message for {text:?}: {e}");
        assert!(
            e.to_string().starts_with(&format!("t:{line}:{col}: ")),
            "{e}"
        );
    }
}

pub fn norm(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

/// Rays at a box from three eyes around it, each through a 24² grid spanning the box:
/// the views the ray tests walk crossing by crossing.
pub fn eye_rays(b: &frep::Aabb) -> Vec<frep::Ray> {
    use glam::DVec3;
    let (c, r) = (b.center(), 0.5 * b.extent().length());
    let mut rays = Vec::new();
    for eye in [
        DVec3::new(0.6, -3.0, 1.2),
        DVec3::new(-2.0, 1.0, -0.5),
        DVec3::new(0.1, 0.2, 3.0),
    ] {
        let eye = c + eye * r;
        let fwd = (c - eye).normalize();
        let right = fwd.cross(DVec3::new(0.1, 0.2, 1.0)).normalize();
        let up = right.cross(fwd);
        for j in 0..24 {
            for i in 0..24 {
                let x = (i as f64 + 0.5) / 12.0 - 1.0;
                let y = (j as f64 + 0.5) / 12.0 - 1.0;
                rays.push(frep::Ray::new(eye, fwd + 0.6 * (x * right + y * up)));
            }
        }
    }
    rays
}

/// The range of |w − m| for w over [a, b].
pub fn dist_range(a: f64, b: f64, m: f64) -> (f64, f64) {
    let (da, db) = ((a - m).abs(), (b - m).abs());
    let lo = if a <= m && m <= b { 0.0 } else { da.min(db) };
    (lo, da.max(db))
}

/// The range of (w − m)² for w over [a, b].
pub fn sq_range(a: f64, b: f64, m: f64) -> (f64, f64) {
    let (lo, hi) = dist_range(a, b, m);
    (lo * lo, hi * hi)
}

/// The range of the distance from the z axis over the rectangle [x0, x1] × [y0, y1].
pub fn rho_range((x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> (f64, f64) {
    let (x, y) = (dist_range(x0, x1, 0.0), dist_range(y0, y1, 0.0));
    (x.0.hypot(y.0), x.1.hypot(y.1))
}

/// Rays at the box: from three eyes through a 24² grid ([`eye_rays`]), grazing rays
/// through random points on a sphere around it, and rays from random points inside.
pub fn probe_rays(b: &frep::Aabb, seed: u64) -> Vec<frep::Ray> {
    use glam::DVec3;
    use rand::{Rng, SeedableRng};
    let (c, r) = (b.center(), 0.5 * b.extent().length());
    let mut rays = eye_rays(b);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut point =
        |s: f64| c + s * r * DVec3::from_array([(); 3].map(|_| rng.gen_range(-1.0..1.0)));
    for _ in 0..400 {
        let (o, at) = (point(2.0), point(0.8));
        rays.push(frep::Ray::new(o, at - o));
        let (o, at) = (point(0.5), point(1.0));
        rays.push(frep::Ray::new(o, at - o));
    }
    rays
}

/// Walks every crossing along `rays` (from 0, then a resolution past each crossing, 16 at
/// most) with two searches of one solid, `a` and `b`, and asserts they agree: the same t
/// within 10⁻⁹ of the solid's size, the same normal, and, with `shadow`, the same
/// answer to the shadow query from each start. Returns how many crossings it compared.
pub fn same_crossings(
    name: &str,
    a: frep::interval_trace::ExprView<'_>,
    b: frep::interval_trace::ExprView<'_>,
    rays: &[frep::Ray],
    shadow: bool,
) -> usize {
    let r = 0.5 * a.bounds.extent().length();
    let mut hits = 0;
    for ray in rays {
        let mut t = 0.0;
        for _ in 0..16 {
            let (p, q) = (a.trace(ray, t, 1e3, true), b.trace(ray, t, 1e3, true));
            match (p, q) {
                (Some(p), Some(q)) => {
                    assert!(
                        (p.0 - q.0).abs() <= 1e-9 * r,
                        "{name} {ray:?} from {t}: {p:?} vs {q:?}"
                    );
                    assert!(p.1.dot(q.1) > 1.0 - 1e-9, "{name}: normals {p:?} {q:?}");
                    if shadow {
                        assert_eq!(
                            a.crosses(ray, t, 1e3),
                            b.crosses(ray, t, 1e3),
                            "{name} {ray:?} from {t}: shadow query"
                        );
                    }
                    hits += 1;
                    t = p.0 + a.eps;
                }
                (None, None) => break,
                _ => panic!("{name} {ray:?} from {t}: {p:?} vs {q:?}"),
            }
        }
    }
    hits
}
