//! Emitting objects: a floor lit by an emitting FRep ball has the irradiance of a
//! sphere light (exact), for every estimator, with the ball reached both by BSDF
//! sampling and by the light techniques that sample directions toward its bounding
//! sphere; a non-convex emitter (a torus) gives one image for every estimator and for
//! BSDF sampling alone; the camera sees the emission; malformed uses are errors.

use crate::common::{
    check_against, estimators_agree_with_bsdf_sampling, options, reference, run, MIX, SPHERE_C,
    SPHERE_L, SPHERE_R,
};
use mis::Method;
use render::integrator::IntegratorKind;
use render::scene::{parse_scene, Scene, SceneFormat};
use std::path::Path;

fn scene(text: &str) -> Scene {
    parse_scene(text, SceneFormat::Toml, Path::new("emitting.toml"))
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

/// The floor of `common::lit_floor` (albedo 0.8, 0.6, 0.4; camera 1 above, looking
/// down) under an emitting ball where `lit_floor`'s sphere light is.
fn floor_under_ball(n: u32) -> Scene {
    let (c, r, l) = (SPHERE_C, SPHERE_R, SPHERE_L);
    scene(&format!(
        r#"
camera = {{ eye = [0, 0, 1], target = [0, 0, 0], up = [0, 1, 0], fov = 60, resolution = [{n}, {n}] }}
materials.floor = {{ type = "diffuse", reflectance = [0.8, 0.6, 0.4] }}
materials.lamp = {{ type = "diffuse", reflectance = 0, emission = [{}, {}, {}] }}
objects = [
  {{ solid = "box(center = [0, 0, -0.5], size = [8, 8, 1])", material = "floor" }},
  {{ solid = "sphere([{}, {}, {}], {r})", material = "lamp" }},
]
"#,
        l.x, l.y, l.z, c.x, c.y, c.z
    ))
}

/// The floor's radiance is ρ/π · L · π (r/d)² cos θ, the sphere light's, for every
/// estimator over BSDF, light-power and light-area sampling; the light techniques
/// sample the ball's bounding sphere (radius r√3), so many of their draws miss it.
#[test]
fn an_emitting_ball_lights_the_floor_as_a_sphere_light_does() {
    let s = floor_under_ball(16);
    assert_eq!(s.lights.area().len(), 1);
    assert!(s.lights.area()[0].proxy);
    let cam = s.camera;
    for m in [
        Method::Balance,
        Method::Power,
        Method::OptimalDirect,
        Method::OptimalProgressive,
    ] {
        let o = options(IntegratorKind::Direct, m, &MIX, 64, 21);
        let (film, _) = run(&s, &o);
        let (z, rel) = check_against(
            &film,
            &|x, y| reference(&cam, x, y, true, false),
            &format!("{m}"),
        );
        println!("{m}: |z| ≤ {z:.2}, relative se {rel:.1e}");
        assert!(rel < 0.01, "{m}: no power ({rel})");
    }
}

/// A torus lamp (concave: its proxy is crossed where the torus is not, and shadows
/// itself) over a floor, with `path`: every estimator agrees with BSDF sampling alone.
#[test]
fn every_estimator_agrees_on_a_torus_lamp() {
    let s = scene(
        r#"
camera = { eye = [0, -3, 2], target = [0, 0, 0.3], resolution = [12, 12] }
materials.floor = { type = "diffuse", reflectance = 0.7 }
materials.lamp = { type = "plastic", diffuse = 0.2, roughness = 0.3, emission = [4, 3, 2] }
objects = [
  { solid = "box(center = [0, 0, -0.5], size = [8, 8, 1])", material = "floor" },
  { solid = "rotate(axis = [1, 0, 0], angle = 35, torus(0.5, 0.12, center = [0, 0, 0.6]))", material = "lamp" },
]
"#,
    );
    estimators_agree_with_bsdf_sampling(
        &s,
        3,
        &[
            Method::Power,
            Method::OptimalDirect,
            Method::OptimalProgressive,
        ],
    );
}

/// The camera sees an emitting surface's radiance (plus what it reflects: here a black
/// lamp, so exactly the emission).
#[test]
fn the_camera_sees_the_emission() {
    let s = scene(
        r#"
camera = { eye = [0, -4, 0], target = [0, 0, 0], resolution = [9, 9], fov = 10 }
materials.lamp = { type = "diffuse", reflectance = 0, emission = [3, 2, 1] }
objects = [{ solid = "sphere([0, 0, 0], 1)", material = "lamp" }]
"#,
    );
    let o = options(IntegratorKind::Path, Method::OptimalDirect, &MIX, 4, 1);
    let (film, _) = run(&s, &o);
    assert_eq!(film.rgb(4, 4), glam::DVec3::new(3.0, 2.0, 1.0));
}

/// `emission` is checked and located; an unbounded emitter and per-light mode with an
/// emitter are errors.
#[test]
fn emission_errors_are_located() {
    let base = r#"
camera = { eye = [0, -4, 0], target = [0, 0, 0], resolution = [8, 8] }
materials.lamp = { type = "diffuse", emission = [3, 2, 1] }
objects = [{ solid = "sphere([0, 0, 0], 1)", material = "lamp" }]
"#;
    let err = |text: &str| {
        parse_scene(text, SceneFormat::Toml, Path::new("e.toml"))
            .err()
            .expect("an error")
    };
    let e = err(&base.replace("[3, 2, 1]", "-1"));
    assert_eq!(
        (e.line, e.key.as_str()),
        (3, "materials.lamp.emission"),
        "{e}"
    );
    let e = err(&base.replace("sphere([0, 0, 0], 1)", "plane([0, 0, 1], 0)"));
    assert_eq!((e.line, e.key.as_str()), (4, "objects[0].material"), "{e}");
    assert!(e.message.contains("must be bounded"), "{e}");
    let e = err(&format!("{base}render = {{ per_light = true }}\n"));
    assert!(e.message.contains("emitting objects"), "{e}");
    let e = err(&base.replace("\"diffuse\"", "\"interface\""));
    assert_eq!(e.key.as_str(), "materials.lamp.emission", "{e}");
}
