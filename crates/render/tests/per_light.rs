//! Per-light mode (one MIS estimator per light, summed) against the plain mode, the
//! analytic image and the sum of single-light renders. The statistical bound is that of
//! `integrators.rs`: 4.5 standard errors of the mean over pixels.

use crate::common;

use common::*;
use mis::Method;
use render::integrator::{IntegratorKind, RenderOptions};
use render::render_loop::render;
use render::{Image, Technique};
use std::sync::atomic::AtomicBool;

/// Largest |a − b| / max(|a|, |b|, 1e-300).
fn max_rel(a: &Image, b: &Image) -> f64 {
    a.data()
        .iter()
        .zip(b.data())
        .map(|(x, y)| (x - y).abs() / x.abs().max(y.abs()).max(1e-300))
        .fold(0.0, f64::max)
}

fn per_light(o: RenderOptions, lights: u32) -> RenderOptions {
    RenderOptions {
        per_light: lights,
        ..o
    }
}

/// A heuristic weight depends only on the pdfs at the draw and every draw feeds
/// exactly one light's estimator, so with the heuristics per-light mode gives the plain
/// image up to the order of the additions (1e-9 relative); the optimal estimators do
/// differ (one α per light), or the mode would be a no-op.
#[test]
fn heuristics_are_unchanged_and_optimal_is_not() {
    let scene = lit_floor(true, true, 12);
    for m in [Method::Balance, Method::Power, Method::Cutoff] {
        let o = options(IntegratorKind::Direct, m, &MIX, 8, 3);
        let (plain, per) = (run(&scene, &o).0, run(&scene, &per_light(o, 2)).0);
        let rel = max_rel(&plain, &per);
        assert!(rel < 1e-9, "{m}: {rel:e}");
    }
    let o = options(IntegratorKind::Direct, Method::OptimalDirect, &MIX, 8, 3);
    let (plain, per) = (run(&scene, &o).0, run(&scene, &per_light(o, 2)).0);
    let rel = max_rel(&plain, &per);
    assert!(
        rel > 1e-6,
        "optimal-direct per light equals the plain image: {rel:e}"
    );
}

/// Per-light optimal estimators (and balance) with the new light techniques converge to
/// the analytic image of a floor under a sphere and a rectangle light, and to the sum of
/// two renders with one light each.
#[test]
fn per_light_converges_to_the_sum_of_single_light_renders() {
    let both = lit_floor(true, true, 16);
    let refs = |x, y| reference(&both.camera, x, y, true, true);
    let techs = [
        (Technique::Bsdf, 1),
        (Technique::LightUniform, 1),
        (Technique::LightSpatial, 1),
    ];
    // The paper's teaser pair: trained and uniform light selection.
    let teaser = [(Technique::LightTrained, 1), (Technique::LightUniform, 1)];
    for (set, m) in [
        (&techs[..], Method::Balance),
        (&techs[..], Method::OptimalDirect),
        (&techs[..], Method::OptimalProgressive),
        (&teaser[..], Method::Balance),
        (&teaser[..], Method::OptimalDirect),
    ] {
        let o = per_light(options(IntegratorKind::Direct, m, set, 128, 5), 2);
        let what = format!("{} {}", set[0].0.name(), m.name());
        let (z, rel) = check_against(&run(&both, &o).0, &refs, &what);
        println!("per-light {what:>34}: max |z| {z:.2}, relative se {rel:.2e}");
        assert!(rel < 0.01, "{what}: the check has no power ({rel})");
    }
    // The sum of single-light renders (balance, other seeds) as the reference.
    let one = |sphere: bool, seed: u64| {
        let s = lit_floor(sphere, !sphere, 16);
        let o = options(IntegratorKind::Direct, Method::Balance, &MIX, 128, seed);
        run(&s, &o).0
    };
    let (a, b) = (one(true, 7), one(false, 8));
    let sum = |x: u32, y: u32| a.rgb(x, y) + b.rgb(x, y);
    let o = per_light(
        options(
            IntegratorKind::Direct,
            Method::OptimalDirect,
            &techs,
            128,
            9,
        ),
        2,
    );
    let (z, _) = check_against(&run(&both, &o).0, &sum, "per-light vs the sum");
    println!("per-light vs the sum of single-light renders: max |z| {z:.2}");
}

/// Per-light mode is checked against the scene: a light count other than the scene's
/// is refused with both counts.
#[test]
fn per_light_count_must_match_the_scene() {
    let scene = lit_floor(true, true, 4);
    let o = per_light(
        options(IntegratorKind::Direct, Method::OptimalDirect, &MIX, 1, 0),
        3,
    );
    let e = render(&scene, &o, &AtomicBool::new(false), &|_, _| {})
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("3 lights") && e.contains("2 MIS lights"), "{e}");
    let o = options(
        IntegratorKind::Direct,
        Method::Balance,
        &[(Technique::Light(2), 1)],
        1,
        0,
    );
    let e = render(&scene, &o, &AtomicBool::new(false), &|_, _| {})
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("light#2") && e.contains("2 MIS lights"), "{e}");
}
