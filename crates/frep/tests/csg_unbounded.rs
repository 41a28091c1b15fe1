//! CSG whose parts are unbounded (half-spaces, infinite cylinders): the walk from one
//! part crossing to the next must not skip crossings because a node's bounds are
//! infinite (issue: a hollow bowl cut by a half-space rendered mostly empty).

use crate::common;

use common::{read_str, Format};
use frep::ray::Ray;
use frep::solid::Solid;
use glam::DVec3;

fn solid(text: &str) -> Solid {
    let m = read_str(&format!("output {text}"), Format::Frep, "t.frep").unwrap();
    Solid::build(&m.shape).unwrap()
}

fn down(x: f64, y: f64) -> Ray {
    Ray::new(DVec3::new(x, y, 3.0), -DVec3::Z)
}

#[test]
fn a_bowl_cut_by_a_half_space_is_hit_inside() {
    let s = solid(
        "difference(sphere([0, 0, 0], 1), union(sphere([0, 0, 0], 0.9), plane([0, 0, -1], -0.5)))",
    );
    let h = s
        .intersect(&down(0.0, 0.0), 0.0, f64::INFINITY)
        .expect("a hit");
    assert!((h.t - 3.9).abs() < 1e-9, "{h:?}");
    assert!(s.occludes(&down(0.0, 0.0), 0.0, f64::INFINITY));
}

#[test]
fn a_pit_in_a_half_space_is_hit_at_its_floor() {
    let s = solid("difference(plane([0, 0, 1], 0), sphere([0, 0, 0], 0.5))");
    let h = s
        .intersect(&down(0.0, 0.0), 0.0, f64::INFINITY)
        .expect("a hit");
    assert!((h.t - 3.5).abs() < 1e-9, "{h:?}");
}
