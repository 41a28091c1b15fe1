//! Throughput of `direct` and `path` (MSamples/s, MRays/s by kind) on a built-in scene:
//! a perturbed ball and a floor under a sphere light, a rectangle light, a point light
//! and a dim dome, with the balance heuristic and optimal MIS.
//!
//! `cargo bench -p render --bench integrators [-- WIDTH SPP]` (default 160 × 120 pixels,
//! 16 spp), or `-- SCENE.toml [SPP]` for a scene file with its own `[render]` settings
//! (spp overridden when given). The CLI's `bench` command calls the same
//! [`render::render_loop::bench`].

use frep::{PerturbedQuadric, Quadric, Shape, Solid};
use glam::DVec3;
use mis::Method;
use render::camera::Camera;
use render::color::Rgb;
use render::integrator::RenderOptions;
use render::light::{AreaLight, DeltaLight, Environment, Lights, Shape as LightShape};
use render::render_loop::bench;
use render::scene::{load_scene, Object, Scene};
use render::{Material, Technique, Texture};

fn scene(width: u32) -> Scene {
    let height = width * 3 / 4;
    let camera = Camera::look_at(
        DVec3::new(0.0, -3.0, 1.4),
        DVec3::new(0.0, 0.0, 0.4),
        DVec3::Z,
        40.0,
        width,
        height,
    );
    let bumpy = PerturbedQuadric::new(Quadric::sphere(DVec3::new(0.0, 0.0, 0.6), 0.6))
        .with(0.8, Quadric::sphere(DVec3::new(0.3, -0.45, 0.9), 0.3))
        .with(-0.5, Quadric::sphere(DVec3::new(-0.35, -0.4, 0.5), 0.25));
    let floor = PerturbedQuadric::new(Quadric::plane(DVec3::Z, 0.0));
    let objects = vec![
        Object {
            name: "ball".into(),
            geometry: Solid::build(&Shape::Perturbed(bumpy)).expect("ball").into(),
            material: 0,
            to_local: None,
            interior: None,
            exterior: None,
        },
        Object {
            name: "floor".into(),
            geometry: Solid::build(&Shape::Perturbed(floor))
                .expect("floor")
                .into(),
            material: 1,
            to_local: None,
            interior: None,
            exterior: None,
        },
    ];
    let materials = vec![
        Material::plastic(Texture::Constant(Rgb::new(0.7, 0.3, 0.2)), 1.5, 0.2),
        Material::Diffuse {
            reflectance: Texture::Constant(Rgb::splat(0.6)),
        },
    ];
    let area = vec![
        AreaLight::new(
            LightShape::Sphere {
                center: DVec3::new(1.2, -0.5, 2.0),
                radius: 0.25,
            },
            Rgb::splat(20.0),
        ),
        AreaLight::new(
            LightShape::Rect {
                corner: DVec3::new(-1.6, -0.6, 2.2),
                edge_u: DVec3::new(0.0, 1.0, 0.0),
                edge_v: DVec3::new(0.8, 0.0, 0.0),
            },
            Rgb::new(4.0, 4.5, 5.0),
        ),
    ];
    let delta = vec![DeltaLight::Point {
        position: DVec3::new(0.5, -1.5, 1.5),
        intensity: Rgb::splat(1.0),
    }];
    let env = Some(Environment::Constant(Rgb::splat(0.1)));
    Scene::new(
        camera,
        materials,
        objects,
        Lights::new(area, delta, env, 3.0),
    )
}

fn main() {
    // `cargo bench` passes "--bench"; take scene files and numbers only.
    let args: Vec<String> = std::env::args().skip(1).collect();
    let nums: Vec<u32> = args.iter().filter_map(|a| a.parse().ok()).collect();
    if let Some(path) = args
        .iter()
        .find(|a| a.ends_with(".toml") || a.ends_with(".json"))
    {
        let (scene, settings) =
            load_scene(std::path::Path::new(path)).unwrap_or_else(|e| panic!("{e}"));
        let mut options = RenderOptions::from_settings(&settings).expect("settings");
        options.spp = nums.first().copied().unwrap_or(options.spp);
        for method in [options.method, Method::OptimalDirect] {
            let o = RenderOptions {
                method,
                ..options.clone()
            };
            for stats in bench(&scene, &o, &Default::default()).expect("valid options") {
                println!("{path}, {method}, {stats}");
            }
        }
        return;
    }
    let width = nums.first().copied().unwrap_or(160);
    let spp = nums.get(1).copied().unwrap_or(16);
    let scene = scene(width);
    for method in [Method::Balance, Method::OptimalDirect] {
        let options = RenderOptions {
            spp,
            method,
            techniques: vec![
                (Technique::Bsdf, 1),
                (Technique::LightPower, 1),
                (Technique::Environment, 1),
            ],
            ..RenderOptions::default()
        };
        for stats in bench(&scene, &options, &Default::default()).expect("valid options") {
            println!("{method}, {stats}");
        }
    }
}
