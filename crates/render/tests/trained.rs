//! The trained light selection (`light-trained`): what it learns, and that its training
//! pass keeps renders deterministic and mergeable.

use crate::common;

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
        assert!((t.pmfs(p).iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
    println!(
        "P(sphere light) open {:.3}, hidden {:.3}",
        open.pmfs(p)[0],
        hidden.pmfs(p)[0]
    );
    assert!(open.pmfs(p)[0] > 0.2, "{:?}", open.pmfs(p));
    assert!(
        (hidden.pmfs(p)[0] - TRAIN_FLOOR / 2.0).abs() < 1e-3,
        "{:?}",
        hidden.pmfs(p)
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

/// The training's options change what is learned: with one grid cell every point gets
/// the same pmf (a global, visibility-weighted pmf: the hidden floor point no longer
/// learns its shadow, so the sphere light keeps over 3× the floor share); floor ε = 0.5
/// gives the hidden point exactly ε/2 for the sphere light; floor 1 is uniform; fewer
/// training rays learn a different table; the options travel through a state's header.
#[test]
fn training_options_change_what_is_learned() {
    let s = scene(true);
    let base = options(IntegratorKind::Direct, Method::Balance, &TRAINED, 1, 4);
    let with = |t: scene::Training| {
        let o = RenderOptions {
            training: t,
            ..base.clone()
        };
        trained_selection(&s, &o).unwrap().unwrap()
    };
    let d = scene::Training::default();
    assert_eq!(
        (d.grid as usize, d.floor),
        (render::light::TRAIN_GRID, TRAIN_FLOOR)
    );
    let (hidden, open) = (DVec3::new(0.5, 0.1, 0.0), DVec3::new(-0.9, -0.8, 0.0));
    let global = with(scene::Training { grid: 1, ..d });
    assert_eq!(global.pmfs(hidden), global.pmfs(open));
    let cells = with(d);
    assert_ne!(cells.pmfs(hidden), cells.pmfs(open));
    println!(
        "P(sphere light) at the hidden point: grid 8 {:.3}, grid 1 {:.3}",
        cells.pmfs(hidden)[0],
        global.pmfs(hidden)[0]
    );
    assert!(
        global.pmfs(hidden)[0] > 3.0 * cells.pmfs(hidden)[0],
        "{:?}",
        global.pmfs(hidden)
    );
    let half = with(scene::Training { floor: 0.5, ..d });
    assert!(
        (half.pmfs(hidden)[0] - 0.25).abs() < 1e-3,
        "{:?}",
        half.pmfs(hidden)
    );
    let uniform = with(scene::Training { floor: 1.0, ..d });
    for p in [hidden, open] {
        assert!(uniform.pmfs(p).iter().all(|&q| (q - 0.5).abs() < 1e-15));
    }
    assert_ne!(with(scene::Training { spp: 1, ..d }), cells);
    let o = RenderOptions {
        training: scene::Training {
            grid: 3,
            floor: 0.25,
            spp: 2,
        },
        ..base.clone()
    };
    // Through a state's bytes, and states trained differently refuse to merge.
    let state = render::RenderState::new(render::StateHeader::new(4, 4, &o), 0..1).unwrap();
    let back = render::RenderState::from_bytes(&state.to_bytes()).unwrap();
    assert_eq!(back.header().options().training, o.training);
    let mut plain = render::RenderState::new(render::StateHeader::new(4, 4, &base), 1..2).unwrap();
    assert!(plain.merge(&state).is_err());
    let bad = RenderOptions {
        training: scene::Training { floor: 0.0, ..d },
        ..base
    };
    let e = bad.validate().unwrap_err();
    assert!(
        matches!(
            e,
            render::integrator::OptionsError::Training {
                key: "trained_floor",
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().starts_with("trained_floor:"), "{e}");
}
