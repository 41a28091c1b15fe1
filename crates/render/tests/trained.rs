//! The trained light selection (`light-trained`): what it learns, and that its training
//! pass keeps renders deterministic and mergeable.

#[path = "integrators/common.rs"]
#[allow(dead_code)]
mod common;

use common::*;
use glam::DVec3;
use mis::Method;
use render::integrator::{trained_selection, IntegratorKind, RenderOptions};
use render::light::TRAIN_FLOOR;
use render::render_loop::render_range;
use render::scene::Scene;
use render::Technique;
use std::sync::atomic::AtomicBool;

const TRAINED: [(Technique, u32); 2] = [(Technique::LightTrained, 1), (Technique::LightUniform, 1)];

/// The floor under a sphere and a rectangle light, with a ball between the sphere light
/// and the floor around (0.5, 0.1) when `occluder`.
fn scene(occluder: bool) -> Scene {
    let mut s = lit_floor(true, true, 24);
    if occluder {
        let lights = s.lights.clone();
        s = Scene::new(
            down_camera(24),
            vec![diffuse(ALBEDO)],
            vec![
                object(&floor(), 0),
                object(&ball(DVec3::new(0.8, 0.1, 0.9), 0.45), 0),
            ],
            lights,
        );
    }
    s
}

/// The trained pmf includes visibility: at a floor point the ball hides from the sphere
/// light (light 0), the sphere light gets only the floor share ε/2 (within 1e-3), while
/// without the ball it gets more than 0.2; every pmf sums to 1.
#[test]
fn training_learns_visibility() {
    let o = options(IntegratorKind::Direct, Method::Balance, &TRAINED, 1, 4);
    let p = DVec3::new(0.5, 0.1, 0.0);
    let open = trained_selection(&scene(false), &o).unwrap().unwrap();
    let hidden = trained_selection(&scene(true), &o).unwrap().unwrap();
    for t in [&open, &hidden] {
        assert!((t.pmf(p).iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
    println!(
        "P(sphere light) open {:.3}, hidden {:.3}",
        open.pmf(p)[0],
        hidden.pmf(p)[0]
    );
    assert!(open.pmf(p)[0] > 0.2, "{:?}", open.pmf(p));
    assert!(
        (hidden.pmf(p)[0] - TRAIN_FLOOR / 2.0).abs() < 1e-3,
        "{:?}",
        hidden.pmf(p)
    );
    // No trained technique, no training.
    let plain = options(IntegratorKind::Direct, Method::Balance, &MIX, 1, 4);
    assert!(trained_selection(&scene(false), &plain).unwrap().is_none());
}

/// The training pass depends on the seed alone: one thread or two give the same state
/// bit for bit, and two sample ranges merge into the render of their union (1e-12).
#[test]
fn trained_renders_are_deterministic_and_merge() {
    let s = scene(true);
    let o = RenderOptions {
        tile_size: 7,
        ..options(
            IntegratorKind::Direct,
            Method::OptimalDirect,
            &TRAINED,
            8,
            9,
        )
    };
    let run = |threads, r: std::ops::Range<u32>| {
        let o = RenderOptions {
            threads,
            ..o.clone()
        };
        render_range(&s, &o, r, &AtomicBool::new(false), &|_, _| {})
            .unwrap()
            .0
    };
    let whole = run(1, 0..8);
    assert!(whole == run(2, 0..8), "thread count changed the state");
    let mut a = run(2, 0..3);
    a.merge(&run(2, 3..8)).unwrap();
    let rel = a
        .data()
        .iter()
        .zip(whole.data())
        .map(|(x, y)| (x - y).abs() / x.abs().max(y.abs()).max(1e-300))
        .fold(0.0, f64::max);
    assert!(rel < 1e-12, "{rel:e}");
}
