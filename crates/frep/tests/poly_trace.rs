//! Polynomial tapes searched in Bernstein form ([`frep::poly_trace`]) find what the
//! interval search finds: on Fidget's tanglecube.vm and on hand-written quartics and
//! sextics (a torus, a heart, nested spheres whose rays cross four times), every
//! crossing along rays from several eyes, grazing rays and rays from inside is the same
//! with the polynomial search as with the interval search.

use crate::common;

use frep::interval_trace::{ExprSurface, ExprView};
use frep::read::read_file;
use frep::solid::Solid;
use frep::tree::Tree;
use frep::{Aabb, Expr, LeafView, Ray};
use glam::DVec3;
use std::path::PathBuf;

/// Walks every crossing along `rays` with both searches; returns how many it compared.
fn compare(name: &str, v: ExprView<'_>, rays: &[Ray]) -> usize {
    assert!(v.degree.is_some(), "{name}: not taken as a polynomial");
    let interval = ExprView { degree: None, ..v };
    common::same_crossings(name, v, interval, rays, false)
}

#[test]
fn tanglecube_crossings_are_the_interval_searchs() {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/fidget/tanglecube.vm");
    let model = read_file(&p).unwrap_or_else(|e| panic!("{e}"));
    let solid = Solid::build(&model.shape).unwrap();
    let mut n = 0;
    for k in 0..solid.flat().leaves.len() {
        if let LeafView::Expr(v) = solid.flat().leaf(k) {
            assert_eq!(v.degree, Some(4), "tanglecube is a quartic");
            n += compare("tanglecube.vm", v, &common::probe_rays(&v.bounds, 1));
        }
    }
    assert!(n > 1500, "{n} crossings");
}

#[test]
fn quartic_and_sextic_crossings_are_the_interval_searchs() {
    let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
    let (x2, y2, z2) = (x.square(), y.square(), z.square());
    let r2 = x2.clone() + y2.clone() + z2.clone();
    // A torus (R = 1, r = 0.35), F ≥ 0 inside: 4R²(x² + y²) − (|p|² + R² − r²)².
    let torus = 4.0 * (x2.clone() + y2.clone()) - (r2.clone() + (1.0 - 0.35 * 0.35)).square();
    // A heart (Taubin), negated: x²z³ + 9/80·y²z³ − (x² + 9/4·y² + z² − 1)³.
    let heart = x2.clone() * z.powi(3) + 9.0 / 80.0 * y2.clone() * z.powi(3)
        - (x2.clone() + 2.25 * y2.clone() + z2.clone() - 1.0).powi(3);
    // Between spheres of radius 0.5 and 1 (a shell): rays through the middle cross it
    // four times; −(|p|² − 0.25)(|p|² − 1) ≥ 0.
    let shell = -((r2.clone() - 0.25) * (r2.clone() - 1.0));
    let cases = [
        (
            "torus",
            torus,
            Aabb::new(DVec3::new(-1.4, -1.4, -0.4), DVec3::new(1.4, 1.4, 0.4)),
        ),
        (
            "heart",
            heart,
            Aabb::new(DVec3::splat(-1.5), DVec3::splat(1.5)),
        ),
        (
            "shell",
            shell,
            Aabb::new(DVec3::splat(-1.05), DVec3::splat(1.05)),
        ),
    ];
    for (k, (name, tree, bounds)) in cases.into_iter().enumerate() {
        let s = ExprSurface::new(Expr::new(&tree), bounds);
        let n = compare(name, s.view(), &common::probe_rays(&bounds, 2 + k as u64));
        println!("{name}: {n} crossings");
        assert!(n > 500, "{name}: {n} crossings");
    }
}

/// x/0 is a polynomial by its operations, but its coefficients are infinite: the ray
/// is left to the interval search, which finds the sign change at x = 0 (the
/// polynomial's hull, all infinities and NaN, would have missed it).
#[test]
fn polynomials_with_infinite_coefficients_are_left_to_intervals() {
    let tree = Tree::x() / 0.0;
    let bounds = Aabb::new(DVec3::splat(-2.0), DVec3::splat(2.0));
    let s = ExprSurface::new(Expr::new(&tree), bounds);
    let v = s.view();
    assert_eq!(v.degree, Some(1));
    let ray = Ray::new(DVec3::new(-3.0, 0.1, 0.2), DVec3::new(1.0, 0.05, 0.0));
    let (t, _) = v
        .trace(&ray, 0.0, 1e3, false)
        .expect("the sign change at x = 0");
    assert!(ray.at(t).x.abs() <= 1e-6, "crossing at {:?}", ray.at(t));
}
