//! Integrators and the render loop against analytic values and each other.
//!
//! Statistical checks use fixed seeds. Pixels are independent estimates (independent
//! streams), so a mean over pixels of (estimate − reference) has standard error
//! `std / √P`; the bound is 4.5 standard errors (two-sided false-alarm probability 7e-6
//! per check for a correct renderer, so below 1e-3 over this file's checks).

use crate::common;

use common::*;
use glam::{DVec2, DVec3};
use mis::{Method, Params};
use render::bsdf::fresnel::fr_conductor;
use render::camera::Camera;
use render::color::Rgb;
use render::integrator::{Aov, IntegratorKind, RenderOptions};
use render::light::{DeltaLight, Environment, Lights};
use render::render_loop::{render, RenderStats};
use render::scene::Scene;
use render::{Image, Material, Sampler, Technique, Texture};
use std::f64::consts::PI;
use std::sync::atomic::{AtomicBool, Ordering};

/// Every technique alone (and `light#0` with `light#1`), every heuristic and every
/// optimal estimator give the analytic image of a diffuse floor under a sphere light and
/// a rectangle light (each pixel within the 4.5-standard-error bound of the module docs).
#[test]
fn every_technique_and_method_converges_to_the_analytic_image() {
    let scene = lit_floor(true, true, 16);
    let refs = |x, y| reference(&scene.camera, x, y, true, true);
    let mut sets: Vec<Vec<(Technique, u32)>> = [
        Technique::Bsdf,
        Technique::LightPower,
        Technique::LightUniform,
        Technique::LightArea,
        Technique::LightSpatial,
        Technique::LightBvh,
        Technique::LightTrained,
        Technique::CosineHemisphere,
    ]
    .into_iter()
    .map(|t| vec![(t, 2)])
    .collect();
    // One technique per light (each alone sees one light), combined by balance.
    sets.push(vec![(Technique::Light(0), 1), (Technique::Light(1), 1)]);
    for set in sets {
        let name = set
            .iter()
            .map(|(t, _)| t.name().into_owned())
            .collect::<Vec<_>>()
            .join("+");
        let o = options(IntegratorKind::Direct, Method::Balance, &set, 32, 11);
        let (z, rel) = check_against(&run(&scene, &o).0, &refs, &name);
        println!("{name:>22}: max |z| {z:.2}, relative se {rel:.2e}");
        assert!(rel < 0.05, "{name}: the check has no power ({rel})");
    }
    for m in Method::ALL {
        // The uncorrelated estimator is consistent with an O(1/N) bias through Â⁻¹
        // (measured here: +1.1e-3 at N = 128, +2.9e-4 at N = 512, i.e. 6.5 and 3.7
        // standard errors); at N = 2048 it is about 2 standard errors.
        let spp = if m == Method::OptimalUncorrelated {
            2048
        } else {
            128
        };
        let o = options(IntegratorKind::Direct, m, &MIX, spp, 12);
        let (z, rel) = check_against(&run(&scene, &o).0, &refs, m.name());
        println!("{:>22}: max |z| {z:.2}, relative se {rel:.2e}", m.name());
        assert!(rel < 0.01, "{m}: the check has no power ({rel})");
    }
}

/// Irradiance of a diffuse floor under one sphere light (E = πL sin²α cos θ) and under
/// one parallel rectangle (Lambert's polygon formula), through the `direct` integrator.
#[test]
fn floor_irradiance_under_sphere_and_rectangle() {
    for (sphere, rect) in [(true, false), (false, true)] {
        let scene = lit_floor(sphere, rect, 16);
        let o = options(IntegratorKind::Direct, Method::Power, &MIX, 64, 21);
        let refs = |x, y| reference(&scene.camera, x, y, sphere, rect);
        let (z, rel) = check_against(&run(&scene, &o).0, &refs, "irradiance");
        println!("sphere {sphere} rect {rect}: max |z| {z:.2}, relative se {rel:.2e}");
        assert!(rel < 2e-3, "relative standard error {rel}");
    }
}

/// Point lights are added outside MIS: a floor under a point light of intensity I has
/// radiance ρ/π · I cos θ / d² whatever the techniques (none of which can see it).
#[test]
fn point_light_outside_mis() {
    let pos = DVec3::new(0.3, -0.2, 1.4);
    let intensity = Rgb::new(2.0, 1.0, 0.5);
    let scene = Scene::new(
        down_camera(12),
        vec![diffuse(ALBEDO)],
        vec![object(&floor(), 0)],
        Lights::new(
            vec![],
            vec![DeltaLight::Point {
                position: pos,
                intensity,
            }],
            None,
            3.0,
        ),
    );
    let refs = |x, y| {
        let k = 12;
        let mut sum = Rgb::ZERO;
        for j in 0..k {
            for i in 0..k {
                let off = DVec2::new((i as f64 + 0.5) / k as f64, (j as f64 + 0.5) / k as f64);
                let r = scene.camera.ray(x, y, off);
                let p = r.at(-r.o.z / r.d.z);
                let v = pos - p;
                let d2 = v.length_squared();
                sum += ALBEDO / PI * intensity * (v.z / d2.sqrt() / d2);
            }
        }
        sum / (k * k) as f64
    };
    for m in [Method::Balance, Method::OptimalDirect] {
        let o = options(IntegratorKind::Direct, m, &MIX, 16, 31);
        let (film, stats) = run(&scene, &o);
        let (z, rel) = check_against(&film, &refs, "point light");
        println!("point light, {m}: max |z| {z:.2}, relative se {rel:.2e}");
        assert!(rel < 1e-3, "{rel}");
        // One shadow ray per sample toward the point light; the techniques see nothing
        // to trace toward.
        assert_eq!(stats.rays.shadow, stats.rays.camera);
    }
}

/// A smooth conductor floor under a constant dome reflects `F(cos θ)·L` (delta lobe,
/// outside MIS), whether or not the technique list holds the BSDF technique.
#[test]
fn mirror_floor_reflects_the_dome() {
    let (eta, k) = (Rgb::new(0.2, 0.9, 1.1), Rgb::new(3.9, 2.4, 2.2));
    let dome = Rgb::new(1.0, 0.7, 0.4);
    let mirror = Material::Conductor {
        eta: Texture::Constant(eta),
        k: Texture::Constant(k),
        roughness: 0.0,
    };
    let cam = Camera::look_at(
        DVec3::new(0.0, -2.0, 1.0),
        DVec3::ZERO,
        DVec3::Z,
        40.0,
        12,
        12,
    );
    let scene = Scene::new(
        cam,
        vec![mirror],
        vec![object(&floor(), 0)],
        Lights::new(vec![], vec![], Some(Environment::Constant(dome)), 3.0),
    );
    let refs = |x, y| {
        let n = 12;
        let mut sum = Rgb::ZERO;
        for j in 0..n {
            for i in 0..n {
                let off = DVec2::new((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                let r = scene.camera.ray(x, y, off);
                sum += if r.d.z < 0.0 {
                    fr_conductor(-r.d.z, eta, k) * dome
                } else {
                    dome
                };
            }
        }
        sum / (n * n) as f64
    };
    for techniques in [
        vec![(Technique::Bsdf, 2), (Technique::Environment, 1)],
        vec![(Technique::Environment, 1)],
    ] {
        let o = options(
            IntegratorKind::Direct,
            Method::OptimalDirect,
            &techniques,
            8,
            41,
        );
        let (z, _) = check_against(&run(&scene, &o).0, &refs, "mirror");
        println!("mirror, {} techniques: max |z| {z:.2}", techniques.len());
    }
}

/// White furnace: albedo-1 diffuse surfaces inside a constant dome have the dome's
/// radiance everywhere; `path` reproduces it (with roulette from the second vertex) for
/// heuristic and optimal per-depth MIS, while stopping at one vertex visibly loses the
/// light of the concave crease (the check has power).
#[test]
fn white_furnace() {
    let dome = 0.75;
    let scene = furnace(24, dome);
    let values = |film: &Image| -> Vec<f64> {
        let mut v = Vec::new();
        for y in 0..film.height() {
            for x in 0..film.width() {
                v.push(film.rgb(x, y).x);
            }
        }
        v
    };
    for m in [
        Method::Balance,
        Method::Power,
        Method::OptimalDirect,
        Method::OptimalProgressive,
        Method::OptimalFull,
    ] {
        let mut o = options(IntegratorKind::Path, m, &ENV_MIX, 64, 51);
        o.max_depth = 64;
        o.rr_depth = 1;
        let (film, stats) = run(&scene, &o);
        let (mean, se) = mean_se(&values(&film));
        let z = (mean - dome) / se;
        println!("furnace {m}: mean {mean:.6} ± {se:.2e} (z {z:.2}), {stats}");
        assert!(z.abs() < Z_BOUND, "{m}: mean {mean} vs {dome}, z {z}");
        assert!(se < 2e-3, "{m}: no power ({se})");
        assert!(stats.rays.secondary > stats.rays.camera / 4);
    }
    let mut o = options(IntegratorKind::Path, Method::Balance, &ENV_MIX, 64, 52);
    o.max_depth = 1;
    let (mean, se) = mean_se(&values(&run(&scene, &o).0));
    println!("furnace, one vertex: mean {mean:.6} ± {se:.2e}");
    assert!(
        mean < dome - Z_BOUND * se,
        "one vertex should lose light: {mean}"
    );
}

/// `path` with one vertex is `direct`: bit for bit with the same seed for an optimal
/// method (same draws, same estimator), to rounding for a heuristic (weights applied
/// per draw instead of in the estimator), and statistically with different seeds.
#[test]
fn path_of_depth_one_is_direct() {
    let scene = ball_on_floor(16);
    for m in [
        Method::OptimalDirect,
        Method::OptimalProgressive,
        Method::Balance,
    ] {
        let mut o = options(IntegratorKind::Direct, m, &MIX, 8, 61);
        let direct = run(&scene, &o).0;
        o.integrator = IntegratorKind::Path;
        o.max_depth = 1;
        let path = run(&scene, &o).0;
        if m.is_optimal() {
            assert!(path == direct, "{m}: path ≠ direct");
        } else {
            for y in 0..16 {
                for x in 0..16 {
                    let (a, b) = (path.rgb(x, y), direct.rgb(x, y));
                    assert!((a - b).abs().max_element() <= 1e-12 * b.abs().max_element());
                }
            }
        }
    }
    let mut o = options(IntegratorKind::Path, Method::Power, &MIX, 64, 62);
    o.max_depth = 1;
    let path = run(&scene, &o).0;
    o.integrator = IntegratorKind::Direct;
    o.seed = 63;
    let direct = run(&scene, &o).0;
    let (z, _) = check_against(&path, &|x, y| direct.rgb(x, y), "path vs direct");
    println!("path(1) vs direct, different seeds: max |z| {z:.2}");
}

/// Same seed, same image, bit for bit, on 1 and 3 threads (separate rayon pools), for
/// the sequential progressive estimator in `path`, for `direct` and with AOVs.
#[test]
fn images_do_not_depend_on_threads() {
    let furnace = furnace(13, 1.0);
    let lit = ball_on_floor(13);
    for (scene, integrator, method) in [
        (&furnace, IntegratorKind::Path, Method::OptimalProgressive),
        (&lit, IntegratorKind::Path, Method::Power),
        (&lit, IntegratorKind::Direct, Method::OptimalDirect),
    ] {
        let mut o = options(integrator, method, &MIX, 6, 71);
        o.techniques.push((Technique::Environment, 1));
        o.tile_size = 4;
        o.pass_spp = 2;
        o.aovs = vec![Aov::Albedo, Aov::Depth, Aov::Normal];
        let films: Vec<(Image, RenderStats)> = [1, 3]
            .into_iter()
            .map(|threads| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| run(scene, &o))
            })
            .collect();
        assert_eq!(films[0].1.threads, 1);
        assert_eq!(films[1].1.threads, 3);
        assert!(
            films[0].0 == films[1].0,
            "{integrator} {method}: images differ"
        );
        // The same rays (their timings are wall-clock and differ).
        let counts = |r: &render::integrator::RayCounts| (r.camera, r.secondary, r.shadow);
        assert_eq!(counts(&films[0].1.rays), counts(&films[1].1.rays));
        // The `threads` option gives the same image too.
        o.threads = 2;
        assert!(run(scene, &o).0 == films[0].0);
    }
}

/// The optimal-MIS test of issue "Optimal MIS": a convex diffuse ball under a constant
/// dome, techniques BSDF + environment. The integrand ρL·cos/π is ρL times the BSDF pdf,
/// so optimal MIS (direct estimator, no ridge) is exact on every object pixel, while the
/// balance heuristic is noisy.
#[test]
fn optimal_mis_is_noiseless_when_f_is_a_pdf_multiple() {
    let (rho, dome) = (Rgb::new(0.7, 0.5, 0.3), Rgb::new(1.0, 0.8, 0.6));
    let n = 24;
    let cam = Camera::look_at(
        DVec3::new(0.0, -3.0, 0.0),
        DVec3::ZERO,
        DVec3::Z,
        24.0,
        n,
        n,
    );
    let scene = Scene::new(
        cam,
        vec![diffuse(rho)],
        vec![object(&ball(DVec3::ZERO, 0.5), 0)],
        Lights::new(vec![], vec![], Some(Environment::Constant(dome)), 1.0),
    );
    // Object pixels: all four corner rays pass within 0.98 r of the centre.
    let inside = |x: u32, y: u32| {
        [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
            .iter()
            .all(|&(u, v)| {
                let r = scene.camera.ray(x, y, DVec2::new(u, v));
                r.o.cross(r.d).length() < 0.98 * 0.5
            })
    };
    let spread = |film: &Image| -> (f64, f64, usize) {
        let (mut worst, mut rel_std, mut count) = (0.0f64, 0.0f64, 0);
        for c in 0..3 {
            let mut v = Vec::new();
            for y in 0..n {
                for x in 0..n {
                    if inside(x, y) {
                        v.push(film.rgb(x, y)[c]);
                        let exact = rho[c] * dome[c];
                        worst = worst.max((film.rgb(x, y)[c] - exact).abs() / exact);
                    }
                }
            }
            let (m, se) = mean_se(&v);
            rel_std = rel_std.max(se * (v.len() as f64).sqrt() / m);
            count = v.len();
        }
        (worst, rel_std, count)
    };
    let mut o = options(
        IntegratorKind::Direct,
        Method::OptimalDirect,
        &ENV_MIX,
        8,
        81,
    );
    o.params = Params {
        ridge: Some(0.0),
        ..Params::default()
    };
    let (worst, rel_std, count) = spread(&run(&scene, &o).0);
    println!("optimal-direct: {count} object pixels, worst relative error {worst:e}, relative std {rel_std:e}");
    assert!(count > 100);
    assert!(worst < 1e-9 && rel_std < 1e-9, "{worst} {rel_std}");
    o.method = Method::Balance;
    let (worst, rel_std, _) = spread(&run(&scene, &o).0);
    println!("balance: worst relative error {worst:e}, relative std {rel_std:e}");
    assert!(rel_std > 1e-3, "{rel_std}");
}

/// The stop flag, set by the progress callback after the first tile, ends the render:
/// one tile holds the first pass's sample (one per pixel, whatever `pass_spp`; bit for
/// bit the render of that many samples), every other pixel none. Progress counts up to the total in a full render.
#[test]
fn stop_keeps_what_was_rendered_and_progress_reaches_the_total() {
    let scene = ball_on_floor(12);
    let mut o = options(
        IntegratorKind::Path,
        Method::OptimalProgressive,
        &MIX,
        8,
        91,
    );
    o.tile_size = 4;
    o.pass_spp = 2;
    o.threads = 1;
    let stop = AtomicBool::new(false);
    let (film, stats) = render(&scene, &o, &stop, &|_, _| {
        stop.store(true, Ordering::Relaxed)
    })
    .unwrap();
    assert!(stats.stopped);
    assert_eq!(stats.samples, 16);
    let short = run(
        &scene,
        &RenderOptions {
            spp: 1,
            ..o.clone()
        },
    )
    .0;
    let mut rendered = 0;
    for y in 0..12 {
        for x in 0..12 {
            if film.iterations(x, y) > 0 {
                rendered += 1;
                assert_eq!(film.rgb(x, y), short.rgb(x, y));
            } else {
                assert_eq!(film.rgb(x, y), Rgb::ZERO);
            }
        }
    }
    assert_eq!(rendered, 16);
    // Stopped before it starts: nothing rendered.
    let (film, stats) = render(&scene, &o, &AtomicBool::new(true), &|_, _| {}).unwrap();
    assert_eq!(stats.samples, 0);
    assert_eq!(film.iterations(5, 5), 0);
    assert!(film.is_partial());
    // A full render: progress is reported per tile and ends at the total.
    let calls = std::sync::Mutex::new(Vec::new());
    o.threads = 2;
    let (_, stats) = render(&scene, &o, &AtomicBool::new(false), &|d, t| {
        calls.lock().unwrap().push((d, t))
    })
    .unwrap();
    let calls = calls.into_inner().unwrap();
    // 9 tiles × 5 passes (1, 1, 2, 2, 2 samples: doubling up to pass_spp).
    assert_eq!(calls.len(), 9 * 5);
    assert_eq!(calls.iter().map(|c| c.0).max(), Some(12 * 12 * 8));
    assert!(calls.iter().all(|c| c.1 == 12 * 12 * 8));
    assert!(!stats.stopped && stats.samples == 12 * 12 * 8);
}

/// Ray counts are exact where they can be predicted, and the first-hit AOVs are right:
/// looking straight down at a diffuse floor from height 1, depth = 1/cos at each sample's
/// position in the pixel, normal = +z,
/// albedo = ρ; the AOV integrators agree with the AOV channels of `direct` bit for bit.
#[test]
fn ray_counts_and_aovs() {
    let scene = lit_floor(true, true, 8);
    let mut o = options(IntegratorKind::Direct, Method::Balance, &MIX, 4, 101);
    o.aovs = vec![Aov::Depth, Aov::Normal, Aov::Albedo];
    let (film, stats) = run(&scene, &o);
    assert_eq!(stats.rays.camera, 8 * 8 * 4);
    assert_eq!(stats.rays.secondary, 0);
    assert_eq!(
        stats.rays.timed_ns, [0; 4],
        "timers run only when asked for"
    );
    assert!(stats.rays.shadow > 0 && stats.rays.shadow <= 8 * 8 * 4 * 3);
    assert_eq!(stats.samples, 8 * 8 * 4);
    assert_eq!(film.aov_names().len(), 7);
    let (d, nz, ar) = (
        film.aov_index("depth").unwrap(),
        film.aov_index("normal.Z").unwrap(),
        film.aov_index("albedo.R").unwrap(),
    );
    for y in 0..8 {
        for x in 0..8 {
            assert_eq!(film.aov(x, y, nz), 1.0);
            assert!((film.aov(x, y, ar) - ALBEDO.x).abs() < 1e-12);
            // The mean of 1/cos over the pixel's four sample positions (dimensions 0
            // and 1 of each sample's stream, `state::dims`).
            let depth = (0..4)
                .map(|i| {
                    let u = Sampler::new(101).stream(x, y, i).get_2d(0);
                    1.0 / -scene.camera.ray(x, y, u).d.z
                })
                .sum::<f64>()
                / 4.0;
            let got = film.aov(x, y, d);
            assert!(
                (got - depth).abs() < 1e-12 * depth,
                "({x}, {y}): {got} vs {depth}"
            );
        }
    }
    for (kind, channel) in [
        (IntegratorKind::Depth, d),
        (IntegratorKind::Normals, nz),
        (IntegratorKind::Albedo, ar),
    ] {
        o.integrator = kind;
        let (image, stats) = run(&scene, &o);
        assert_eq!(stats.rays.total(), stats.rays.camera);
        for y in 0..8 {
            for x in 0..8 {
                let v = image.rgb(x, y);
                let c = if kind == IntegratorKind::Normals {
                    v.z
                } else {
                    v.x
                };
                assert_eq!(c as f32, film.aov(x, y, channel) as f32);
            }
        }
    }
    let mut o = options(IntegratorKind::Path, Method::Balance, &MIX, 4, 101);
    o.max_depth = 3;
    o.stage_times = true;
    let stats = run(&ball_on_floor(8), &o).1;
    assert_eq!(stats.rays.camera, 8 * 8 * 4);
    assert!(stats.rays.secondary > 0);
    // Stage times: every kind traced was timed, and the stages share out the workers'
    // busy time, which the threads' wall time bounds.
    let st = stats.rays.stages();
    let stages = [st.generate, st.camera, st.secondary, st.shadow];
    assert!(stages.iter().all(|d| !d.is_zero()), "{st:?}");
    let busy = std::time::Duration::from_nanos(stats.rays.busy_ns);
    assert!(stages.iter().sum::<std::time::Duration>() + st.shade >= busy);
    assert!(
        busy <= stats.wall * stats.threads as u32,
        "{busy:?} vs {stats:?}"
    );
}

/// A smooth glass ball (purely specular: every draw outside MIS) inside a constant dome
/// transmits and reflects the dome's radiance exactly (the η² of entering and leaving
/// cancel); only roulette adds noise.
#[test]
fn glass_ball_furnace() {
    let dome = 0.5;
    let glass = Material::Dielectric {
        eta: 1.5,
        roughness: 0.0,
    };
    let cam = Camera::look_at(
        DVec3::new(0.0, -3.0, 0.0),
        DVec3::ZERO,
        DVec3::Z,
        24.0,
        16,
        16,
    );
    let scene = Scene::new(
        cam,
        vec![glass],
        vec![object(&ball(DVec3::ZERO, 0.5), 0)],
        Lights::new(
            vec![],
            vec![],
            Some(Environment::Constant(Rgb::splat(dome))),
            1.0,
        ),
    );
    for m in [Method::Balance, Method::OptimalDirect] {
        let mut o = options(IntegratorKind::Path, m, &ENV_MIX, 16, 111);
        o.max_depth = 64;
        o.rr_depth = 2;
        let (film, stats) = run(&scene, &o);
        let v: Vec<f64> = (0..16 * 16).map(|i| film.rgb(i % 16, i / 16).y).collect();
        let (mean, se) = mean_se(&v);
        println!("glass furnace {m}: mean {mean:.6} ± {se:.2e}, {stats}");
        assert!((mean - dome).abs() < Z_BOUND * se.max(1e-12), "{m}: {mean}");
        assert!(se < 2e-3, "{se}");
        // Purely specular: no draw of the techniques needs a shadow ray.
        assert_eq!(stats.rays.shadow, 0);
    }
}

/// With indirect light (a ball on the floor, four vertices, roulette from the second),
/// the per-depth optimal estimators of `path` agree with the power heuristic's image.
#[test]
fn path_optimal_per_depth_agrees_with_heuristic() {
    let scene = ball_on_floor(16);
    let mut o = options(IntegratorKind::Path, Method::Power, &MIX, 192, 121);
    o.max_depth = 4;
    o.rr_depth = 2;
    let heuristic = run(&scene, &o).0;
    for (m, seed) in [
        (Method::OptimalDirect, 122),
        (Method::OptimalProgressive, 123),
    ] {
        o.method = m;
        o.seed = seed;
        let (film, stats) = run(&scene, &o);
        let (z, rel) = check_against(&film, &|x, y| heuristic.rgb(x, y), m.name());
        println!("path {m} vs power: max |z| {z:.2}, relative se {rel:.2e}; {stats}");
        assert!(rel < 0.01, "{rel}");
        assert!(stats.rays.secondary > stats.rays.camera);
    }
}

/// `hide_emitters` blacks out exactly the pixels whose camera ray meets an emitter (here
/// the dome) and leaves every other pixel bit-identical.
#[test]
fn hide_emitters_only_hides_what_the_camera_sees() {
    let scene = furnace(12, 0.75);
    let o = options(IntegratorKind::Path, Method::Balance, &ENV_MIX, 4, 5);
    let hidden = RenderOptions {
        hide_emitters: true,
        ..o.clone()
    };
    let (a, _) = run(&scene, &o);
    let (b, _) = run(&scene, &hidden);
    let (mut sky, mut object) = (0, 0);
    for y in 0..12 {
        for x in 0..12 {
            let (u, v) = (a.rgb(x, y), b.rgb(x, y));
            if u == Rgb::splat(0.75) {
                // Every sample of this pixel saw the dome directly.
                sky += 1;
                assert_eq!(v, Rgb::ZERO, "pixel ({x}, {y})");
            } else if v == u {
                object += 1;
            } else {
                // Mixed pixels: the object's part is kept, the dome's part is gone.
                assert!(
                    v.max_element() < u.max_element(),
                    "pixel ({x}, {y}): {u} -> {v}"
                );
            }
        }
    }
    assert!(sky > 10 && object > 10, "sky {sky}, object {object}");
}
