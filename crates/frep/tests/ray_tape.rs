//! Tapes restricted to rays ([`frep::ray_tape`]): the leaves are the tape's polynomial
//! parts, their bounds hold every value the search computes, and a search with leaves
//! finds the crossings of the search over the whole tape, on the blends of quadrics in
//! models/ and on the table scene's blob.

use crate::common;

use frep::interval_trace::{ExprSurface, ExprView};
use frep::ray_tape::{Plan, RayTape};
use frep::read::read_file;
use frep::solid::Solid;
use frep::{Aabb, Expr, LeafView};
use glam::DVec3;
use rand::{Rng, SeedableRng};

/// The glossy blob of scenes/table.toml: three spheres, blended (70 nodes).
const BLOB: &str = "
let a = sphere([0, 0, 0], 0.22)
let b = sphere([0.3, 0.1, 0.05], 0.18)
let c = sphere([0.1, 0.3, 0.12], 0.15)
bounds([-0.4, -0.4, -0.4], [0.7, 0.7, 0.5])
output blend_union(blend_union(a, b, 0.4, 0.5, 0.5), c, 0.4, 0.5, 0.5)
";

/// The expression leaves of a model file (or of `BLOB` for "blob").
fn solid(name: &str) -> Solid {
    let model = match name {
        "blob" => frep::read::read_str(BLOB, frep::read::Format::Frep, "blob.frep"),
        "metaballs" => frep::read::read_str(METABALLS, frep::read::Format::Frep, "metaballs.frep"),
        path => read_file(&common::model_file(path)),
    }
    .unwrap_or_else(|e| panic!("{e}"));
    Solid::build(&model.shape).unwrap()
}

/// Metaballs: a sum of Gaussians of the distance to four centres, minus a threshold
/// (the leaves are the squared distances, read by `exp`).
const METABALLS: &str = "
let g1 = exp(-8 * ((x - 0.3)^2 + y^2 + z^2))
let g2 = exp(-8 * ((x + 0.3)^2 + (y - 0.1)^2 + z^2))
let g3 = exp(-6 * (x^2 + (y + 0.35)^2 + (z - 0.1)^2))
let g4 = exp(-10 * (x^2 + y^2 + (z - 0.4)^2))
bounds([-1, -1, -0.8], [1, 1, 1])
output g1 + g2 + g3 + g4 - 0.6
";

/// The models whose expression solids get a plan: blends of quadrics by R-functions
/// with transcendental parts, Gaussians, a sphere written with a square root.
const MODELS: [&str; 4] = [
    "blob",
    "metaballs",
    "examples/smooth_blob.frep",
    "canonical/s1_sphere.hf",
];

/// Each model's expression views that have a plan.
fn planned<'s>(name: &str, s: &'s Solid) -> Vec<ExprView<'s>> {
    let views: Vec<ExprView> = (0..s.flat().leaves.len())
        .filter_map(|k| match s.flat().leaf(k) {
            LeafView::Expr(v) => v.plan.is_some().then_some(v),
            LeafView::Perturbed(_) => None,
        })
        .collect();
    assert!(!views.is_empty(), "{name}: no expression solid with a plan");
    views
}

/// The blob's plan keeps its blends and reads its spheres (and their scaled copies)
/// from leaves: fewer than half the nodes a ray. Tapes with min/max get no plan, nor do
/// tapes with little to fold, nor polynomials (the Bernstein search takes those).
#[test]
fn plans_fold_the_polynomial_parts() {
    let s = solid("blob");
    let v = planned("blob", &s)[0];
    let plan = v.plan.unwrap();
    assert_eq!(v.tape.len(), 70);
    assert!(plan.tape.len() <= 35, "{} nodes left", plan.tape.len());
    // a, b, c; a/0.5, b/0.5, c/0.5 and the sum of the first blend's two spheres.
    assert!((3..=10).contains(&plan.leaves.len()), "{:?}", plan.leaves);
    let (x, y, z) = (frep::Tree::x(), frep::Tree::y(), frep::Tree::z());
    let sphere = |c: f64| 1.0 - (x.clone() - c).square() - y.square() - z.square();
    let with_min = sphere(0.0).min(&sphere(0.5)).sqrt();
    assert!(Plan::new(Expr::new(&with_min).nodes()).is_none());
    assert!(Plan::new(Expr::new(&(x.clone() - 0.5).abs()).nodes()).is_none());
    let poly = sphere(0.0) * sphere(0.5);
    let b = Aabb::new(DVec3::splat(-2.0), DVec3::splat(2.0));
    assert!(ExprSurface::new(Expr::new(&poly), b).view().plan.is_none());
}

/// Along random rays, the leaves' F and dF/dt equal the whole tape's to rounding, and
/// the bounds of every segment hold the values and slopes computed at 40 points in it.
#[test]
fn leaves_equal_the_tape_and_their_bounds_hold_it() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
    for name in MODELS {
        let s = solid(name);
        for v in planned(name, &s) {
            let scale = v.bounds.extent().length();
            for ray in common::probe_rays(&v.bounds, 9).iter().step_by(7) {
                let t0 = rng.gen_range(0.0..1.0);
                let leaves = RayTape::new(v.plan.unwrap(), ray, t0).expect("finite leaves");
                let (a, b) = (t0 + rng.gen_range(0.0..2.0), t0 + rng.gen_range(2.0..4.0));
                let (bound, slope) = leaves.segment(a, b);
                for k in 0..=40 {
                    let t = a + (b - a) * k as f64 / 40.0;
                    let f = leaves.value(t);
                    let (g, dg) = leaves.value_slope(t);
                    let p = ray.at(t);
                    let (whole, dwhole) = (v.value(p), v.gradient(p).dot(ray.d));
                    let tol = 1e-10 * (1.0 + whole.abs() + scale * scale);
                    assert!((f - whole).abs() <= tol, "{name}: {f} vs {whole} at {t}");
                    assert_eq!(f, g, "{name}: value and value_slope at {t}");
                    assert!(
                        (dg - dwhole).abs() <= 1e-8 * (1.0 + dwhole.abs()),
                        "{name}: slope {dg} vs {dwhole} at {t}"
                    );
                    assert!(
                        bound.contains(f),
                        "{name}: {f} outside {bound:?} on [{a}, {b}]"
                    );
                    assert!(slope.contains(dg), "{name}: {dg} outside {slope:?}");
                }
            }
        }
    }
}

/// Every crossing along the rays, walked one after another, is the same with leaves as
/// over the whole tape (to 1e-9 of the solid's size), with the same normal.
#[test]
fn crossings_with_leaves_are_the_whole_tapes() {
    for (k, name) in MODELS.into_iter().enumerate() {
        let s = solid(name);
        let mut hits = 0;
        for v in planned(name, &s) {
            let whole = ExprView { plan: None, ..v };
            let rays = common::probe_rays(&v.bounds, 20 + k as u64);
            hits += common::same_crossings(name, v, whole, &rays, true);
        }
        println!("{name}: {hits} crossings");
        assert!(hits > 800, "{name}: {hits} crossings");
    }
}

/// A plain surface built from a tree gets the same plan as the flat solid.
#[test]
fn surfaces_and_solids_share_the_plan() {
    let model = frep::read::read_str(BLOB, frep::read::Format::Frep, "blob.frep").unwrap();
    let tree = model.shape.to_tree().unwrap();
    let s = solid("blob");
    let v = planned("blob", &s)[0];
    let surface = ExprSurface::new(Expr::new(&tree), v.bounds);
    assert_eq!(surface.view().plan, v.plan);
}
