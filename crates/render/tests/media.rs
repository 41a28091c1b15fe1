//! Participating media inside solids: Beer's law through index-matched boundaries
//! (exact), the white furnace for every estimator with scattering media (isotropic and
//! forward-scattering, chromatic, index-matched and glass boundaries), and every
//! estimator converging to one reference on a lit medium, next-event estimation through
//! the boundary included.

use crate::common::{
    check_against, estimators_agree_with_bsdf_sampling, mean_se, options, run, Z_BOUND,
};
use glam::{DVec2, DVec3};
use mis::Method;
use render::integrator::IntegratorKind;
use render::scene::{parse_scene, Scene, SceneFormat};
use render::{Image, Technique};
use std::path::Path;

fn scene(text: &str) -> Scene {
    parse_scene(text, SceneFormat::Toml, Path::new("media.toml"))
        .unwrap()
        .0
}

const ENV: [(Technique, u32); 2] = [(Technique::Bsdf, 1), (Technique::Environment, 1)];

/// A ball of radius 1 at the origin seen from 4 away, filled with `medium`, bounded by
/// `material`, in a uniform environment of radiance `dome`.
fn ball_in_dome(medium: &str, material: &str, dome: f64, n: u32) -> Scene {
    scene(&format!(
        r#"
camera = {{ eye = [0, -4, 0], target = [0, 0, 0], fov = 34, resolution = [{n}, {n}] }}
materials.boundary = {material}
media.inside = {medium}
objects = [{{ solid = "sphere([0, 0, 0], 1)", material = "boundary", medium = "inside" }}]
environment = {{ radiance = {dome} }}
"#
    ))
}

/// A pure absorber (σ_a = 0.5, 0.25, 1) behind an index-matched boundary in a dome of
/// radiance 1: each pixel is the pixel's mean of exp(−σ_a · chord), the chord
/// 2√(1 − d²) of a ray passing the centre at distance d, by a 12 × 12 midpoint rule.
/// `direct` and `path` alike: the camera sees the dome through the transmittance.
#[test]
fn an_absorbing_ball_follows_beers_law() {
    let sigma = DVec3::new(0.5, 0.25, 1.0);
    let s = ball_in_dome(
        "{ sigma_a = [0.5, 0.25, 1.0], sigma_s = 0 }",
        r#"{ type = "interface" }"#,
        1.0,
        16,
    );
    let reference = |x: u32, y: u32| {
        let k = 12;
        let mut sum = DVec3::ZERO;
        for j in 0..k {
            for i in 0..k {
                let off = DVec2::new((i as f64 + 0.5) / k as f64, (j as f64 + 0.5) / k as f64);
                let r = s.camera.ray(x, y, off);
                let d2 = r.o.cross(r.d).length_squared();
                let chord = 2.0 * (1.0 - d2).max(0.0).sqrt();
                sum += DVec3::new(
                    (-sigma.x * chord).exp(),
                    (-sigma.y * chord).exp(),
                    (-sigma.z * chord).exp(),
                );
            }
        }
        sum / (k * k) as f64
    };
    for kind in [IntegratorKind::Direct, IntegratorKind::Path] {
        let o = options(kind, Method::Balance, &ENV, 64, 3);
        let (film, _) = run(&s, &o);
        let (z, rel) = check_against(&film, &reference, "Beer's law");
        println!("{kind:?}: |z| ≤ {z:.2}, relative se {rel:.1e}");
        // The centre pixel's chord is nearly the diameter: exp(−2σ).
        let c = film.rgb(8, 8);
        assert!((c.y - (-0.5f64).exp()).abs() < 0.02, "{c}");
    }
}

fn channel_values(film: &Image, c: usize) -> Vec<f64> {
    let mut v = Vec::new();
    for y in 0..film.height() {
        for x in 0..film.width() {
            v.push(film.rgb(x, y)[c]);
        }
    }
    v
}

/// White furnace: a non-absorbing medium (σ_s = 1, 2, 0.5: chromatic) in a ball in a
/// dome of radiance 0.75 leaves the dome's radiance everywhere, behind an index-matched
/// boundary and behind smooth glass (η = 1.5), isotropic (g = 0) and forward-scattering
/// (g = 0.7), for every estimator (per-depth MIS of phase-function and environment
/// sampling at the medium's vertices); one vertex visibly loses light (power).
#[test]
fn white_furnace_with_scattering_media() {
    let dome = 0.75;
    for (material, g) in [
        (r#"{ type = "interface" }"#, 0.0),
        (r#"{ type = "interface" }"#, 0.7),
        (r#"{ type = "dielectric", eta = 1.5 }"#, 0.0),
    ] {
        let medium = format!("{{ sigma_a = 0, sigma_s = [1, 2, 0.5], g = {g} }}");
        let s = ball_in_dome(&medium, material, dome, 16);
        for m in [
            Method::Balance,
            Method::Power,
            Method::OptimalDirect,
            Method::OptimalProgressive,
            Method::OptimalFull,
        ] {
            let mut o = options(IntegratorKind::Path, m, &ENV, 256, 71);
            o.max_depth = 1000;
            o.rr_depth = 1000;
            let (film, stats) = run(&s, &o);
            for c in 0..3 {
                let (mean, se) = mean_se(&channel_values(&film, c));
                let z = (mean - dome) / se;
                println!(
                    "{material} g {g} {m} channel {c}: {mean:.5} ± {se:.1e} (z {z:.2}), {stats}"
                );
                assert!(
                    z.abs() < Z_BOUND,
                    "{material} g {g} {m} channel {c}: {mean} ± {se}"
                );
                // Power: a bias of 3 % of the dome would stand 4.5 standard errors out.
                assert!(se < 5e-3, "no power: {se}");
            }
        }
        let mut o = options(IntegratorKind::Path, Method::Balance, &ENV, 48, 72);
        o.max_depth = 1;
        let (mean, se) = mean_se(&channel_values(&run(&s, &o).0, 1));
        assert!(
            mean < dome - Z_BOUND * se,
            "one vertex should lose light: {mean}"
        );
    }
}

/// A lit scattering medium (σ_a = 0.2, 0.4, 0.1; σ_s = 1.5, 1, 2; g = 0.5) in an
/// index-matched ball on a diffuse floor under a sphere light: every estimator over
/// phase/BSDF, light and area sampling (next-event estimation through the boundary)
/// agrees with a reference from BSDF and phase sampling alone (which reaches the light
/// only by hitting it), per channel within Z_BOUND standard errors of the difference.
#[test]
fn every_estimator_converges_to_one_reference_in_a_medium() {
    let s = scene(
        r#"
camera = { eye = [0, -3.5, 1.2], target = [0, 0, 0.6], fov = 40, resolution = [12, 12] }
materials.none = { type = "interface" }
materials.floor = { type = "diffuse", reflectance = 0.6 }
media.smoke = { sigma_a = [0.2, 0.4, 0.1], sigma_s = [1.5, 1, 2], g = 0.5 }
objects = [
  { solid = "sphere([0, 0, 0.7], 0.7)", material = "none", medium = "smoke" },
  { solid = "box(center = [0, 0, -0.5], size = [6, 6, 1])", material = "floor" },
]
lights = [{ type = "sphere", center = [1.2, -0.8, 2.2], radius = 0.6, power = 60 }]
"#,
    );
    estimators_agree_with_bsdf_sampling(
        &s,
        4,
        &[
            Method::Balance,
            Method::Power,
            Method::OptimalDirect,
            Method::OptimalProgressive,
        ],
    );
}

const MEDIA_SCENE: &str = r#"
camera = { eye = [0, -4, 0], target = [0, 0, 0], resolution = [8, 8] }
materials.none = { type = "interface" }
media.milk = { albedo = [1, 0.5, 0], mean_free_path = [0.5, 1, 2], g = 0.3, scale = 2 }
media.ink = { sigma_a = [0.5, 0.25, 1.0], sigma_s = 0.1 }
objects = [{ solid = "sphere([0, 0, 0], 1)", material = "none", medium = "milk", exterior = "ink" }]
"#;

/// 1-based line and column of `needle` in `text`.
fn pos(text: &str, needle: &str) -> (usize, usize) {
    let i = text.find(needle).unwrap();
    let line = text[..i].matches('\n').count() + 1;
    let col = text[..i].rsplit('\n').next().unwrap().chars().count() + 1;
    (line, col)
}

/// Media resolve to σ_s and σ_t (albedo and mean free path converted, `scale` applied,
/// in the order of their names); objects refer to them; malformed media and unknown
/// names are errors at their line, column and key.
#[test]
fn media_resolve_and_report_their_errors() {
    let s = scene(MEDIA_SCENE);
    assert!(s.participating);
    // Names sorted: ink, milk.
    let (ink, milk) = (&s.media[0], &s.media[1]);
    assert_eq!(ink.sigma_t, DVec3::new(0.6, 0.35, 1.1));
    assert!(
        (ink.sigma_s(DVec3::ZERO) - DVec3::splat(0.1))
            .abs()
            .max_element()
            < 1e-15
    );
    // σ_t = scale / mfp = (4, 2, 1); σ_s = albedo · σ_t.
    assert_eq!(milk.sigma_t, DVec3::new(4.0, 2.0, 1.0));
    assert_eq!(milk.sigma_s(DVec3::ZERO), DVec3::new(4.0, 1.0, 0.0));
    assert_eq!(milk.g, 0.3);
    assert_eq!(
        (s.objects[0].interior, s.objects[0].exterior),
        (Some(1), Some(0))
    );
    let cases: [(&str, &str, &str, &str, &str); 6] = [
        (
            r#"medium = "milk""#,
            r#"medium = "cream""#,
            "\"cream\"",
            "objects[0].medium",
            r#"unknown medium "cream"; defined: ink, milk"#,
        ),
        (
            "g = 0.3",
            "g = 1.0",
            "1.0",
            "media.milk.g",
            "expected a number in [-0.99, 0.99]",
        ),
        (
            "sigma_s = 0.1 }",
            "sigma_s = 0.1, albedo = 0.5 }",
            "albedo = 0.5",
            "media.ink.albedo",
            "not both",
        ),
        (
            "mean_free_path = [0.5, 1, 2]",
            "mean_free_path = [0.5, 0, 2]",
            "[0.5, 0, 2]",
            "media.milk.mean_free_path",
            "must be positive",
        ),
        (
            "sigma_a = [0.5, 0.25, 1.0], sigma_s = 0.1",
            "sigma_a = [0.5, 0.25, 1.0]",
            "ink =",
            "media.ink",
            "needs sigma_s too",
        ),
        (
            "albedo = [1, 0.5, 0]",
            "albedo = { image = { file = \"x.png\" } }",
            "{ image",
            "media.milk.albedo",
            "an image needs a surface",
        ),
    ];
    for (from, to, at, key, msg) in cases {
        let text = MEDIA_SCENE.replace(from, to);
        let e = parse_scene(&text, SceneFormat::Toml, Path::new("m.toml"))
            .err()
            .unwrap_or_else(|| panic!("{to}: no error"));
        assert_eq!(
            (e.line, e.column, e.key.as_str()),
            (pos(&text, at).0, pos(&text, at).1, key),
            "{e}"
        );
        assert!(e.message.contains(msg), "{e}");
    }
}

/// A medium's albedo may vary from point to point (σ_t stays constant): a checker of
/// two equal colours renders bit for bit as that constant albedo, and a checker of 0.2
/// and 0.9 gives an image strictly between the two constant albedos' (each gap more
/// than 10 standard errors of the per-pixel differences).
#[test]
fn a_textured_albedo_scatters_by_the_point() {
    let ball = |albedo: &str| {
        ball_in_dome(
            &format!("{{ albedo = {albedo}, mean_free_path = 0.5, g = 0.3 }}"),
            r#"{ type = "interface" }"#,
            1.0,
            12,
        )
    };
    let render = |albedo: &str| {
        let mut o = options(IntegratorKind::Path, Method::Power, &ENV, 64, 13);
        o.max_depth = 64;
        run(&ball(albedo), &o).0
    };
    let constant = render("0.7");
    let same = render("{ checker = { a = 0.7, b = 0.7, scale = 4 } }");
    assert!(
        constant == same,
        "a checker of equal colours is that colour"
    );
    // Per-pixel differences: their spread bounds the noise of the mean difference.
    let diff = |a: &Image, b: &Image| {
        let d: Vec<f64> = channel_values(a, 1)
            .iter()
            .zip(channel_values(b, 1))
            .map(|(x, y)| x - y)
            .collect();
        mean_se(&d)
    };
    let (lo, hi) = (render("0.2"), render("0.9"));
    let mid = render("{ checker = { a = 0.2, b = 0.9, scale = 4 } }");
    let (above, above_se) = diff(&mid, &lo);
    let (below, below_se) = diff(&hi, &mid);
    println!(
        "checker − 0.2: {above:.4} ± {above_se:.1e}; 0.9 − checker: {below:.4} ± {below_se:.1e}"
    );
    assert!(above > 10.0 * above_se, "{above} ± {above_se}");
    assert!(below > 10.0 * below_se, "{below} ± {below_se}");
}

/// A camera inside a medium: at the centre of an index-matched ball of radius 2 filled
/// with an absorber, in a dome of radiance 1, every pixel is exp(−2σ_a) exactly (each
/// ray crosses 2 of absorber whatever its direction); `camera.medium` names the medium.
#[test]
fn a_camera_inside_a_medium_sees_through_it() {
    let s = scene(
        r#"
camera = { eye = [0, 0, 0], target = [0, 1, 0], fov = 60, resolution = [6, 4], medium = "ink" }
materials.none = { type = "interface" }
media.ink = { sigma_a = [0.5, 0.25, 1.0], sigma_s = 0 }
objects = [{ solid = "sphere([0, 0, 0], 2)", material = "none", medium = "ink" }]
environment = { radiance = 1 }
"#,
    );
    assert_eq!(s.camera_medium, Some(0));
    let o = options(IntegratorKind::Path, Method::Balance, &ENV, 4, 2);
    let film = run(&s, &o).0;
    let want = DVec3::new((-1.0f64).exp(), (-0.5f64).exp(), (-2.0f64).exp());
    for y in 0..4 {
        for x in 0..6 {
            let d = (film.rgb(x, y) - want).abs().max_element();
            assert!(d < 1e-6, "({x}, {y}): {} against {want}", film.rgb(x, y));
        }
    }
}

/// Media and emitting objects keep what users rely on: the same seed gives the same
/// image, bit for bit, on 1 and 2 threads and any tile size; two sample ranges merge into
/// the render of their union (to 10⁻¹², the additions in another order).
#[test]
fn media_renders_are_reproducible_and_ranges_merge() {
    use render::render_loop::render_range;
    use std::sync::atomic::AtomicBool;
    let s = scene(
        r#"
camera = { eye = [0, -4, 1.2], target = [0, 0, 0.5], fov = 40, resolution = [10, 8] }
materials.glass = { type = "dielectric", eta = 1.4 }
materials.none = { type = "interface" }
materials.floor = { type = "diffuse", reflectance = 0.6 }
materials.lamp = { type = "diffuse", reflectance = 0, emission = [5, 4, 3] }
media.milk = { albedo = [0.95, 0.9, 0.8], mean_free_path = 0.3, g = 0.4 }
media.smoke = { sigma_a = 0.1, sigma_s = [0.8, 1.2, 1.6] }
objects = [
  { solid = "sphere([-0.6, 0, 0.5], 0.5)", material = "glass", medium = "milk" },
  { solid = "sphere([0.6, 0, 0.5], 0.5)", material = "none", medium = "smoke" },
  { solid = "sphere([0, 0.8, 1.6], 0.2)", material = "lamp" },
  { solid = "box(center = [0, 0, -0.05], size = [6, 6, 0.1])", material = "floor" },
]
lights = [{ type = "sphere", center = [1, -1, 3], radius = 0.3, power = 150 }]
"#,
    );
    let run = |o: &render::integrator::RenderOptions, samples: std::ops::Range<u32>| {
        render_range(&s, o, samples, &AtomicBool::new(false), &|_, _| {})
            .unwrap()
            .0
    };
    for m in [Method::Power, Method::OptimalDirect] {
        let mut o = options(IntegratorKind::Path, m, &crate::common::MIX, 8, 23);
        o.max_depth = 6;
        o.threads = 1;
        o.tile_size = 8;
        let one = run(&o, 0..8);
        o.threads = 2;
        o.tile_size = 3;
        let two = run(&o, 0..8);
        assert!(
            one.image() == two.image(),
            "{m}: threads or tiles changed the image"
        );
        let mut a = run(&o, 0..3);
        a.merge(&run(&o, 3..8)).unwrap();
        let rel = a
            .data()
            .iter()
            .zip(two.data())
            .map(|(x, y)| (x - y).abs() / x.abs().max(y.abs()).max(1e-300))
            .fold(0.0, f64::max);
        assert!(rel < 1e-12, "{m}: merged ranges differ by {rel:e}");
        assert!(one.image().data().iter().any(|&v| v > 0.0));
    }
}

/// A point light hidden behind an emitting object, in a scene with media: its shadow
/// rays meet the emitter's surface, which blocks it (the emitter's own light arrives by
/// the techniques' draws, not again through the point light's shadow ray). Point lights
/// take no random numbers, so the render equals, bit for bit, the one without the light.
#[test]
fn a_point_light_behind_an_emitter_adds_nothing() {
    let text = |light: &str| {
        format!(
            r#"
camera = {{ eye = [0, -4, 1], target = [0, 0, 0.5], fov = 40, resolution = [8, 6] }}
materials.none = {{ type = "interface" }}
materials.floor = {{ type = "diffuse", reflectance = 0.6 }}
materials.lamp = {{ type = "diffuse", reflectance = 0, emission = [5, 4, 3] }}
media.smoke = {{ sigma_a = 0.1, sigma_s = [0.8, 1.2, 1.6] }}
objects = [
  {{ solid = "sphere([0.6, 0, 0.5], 0.5)", material = "none", medium = "smoke" }},
  {{ solid = "box(center = [0, 0, 3], size = [20, 20, 0.2])", material = "lamp" }},
  {{ solid = "box(center = [0, 0, -0.05], size = [6, 6, 0.1])", material = "floor" }},
]
{light}
"#
        )
    };
    let with = scene(&text(
        r#"lights = [{ type = "point", position = [0, 0, 4], power = 500 }]"#,
    ));
    let without = scene(&text(""));
    let o = options(
        IntegratorKind::Path,
        Method::Balance,
        &crate::common::MIX,
        4,
        7,
    );
    let (a, b) = (run(&with, &o).0, run(&without, &o).0);
    assert!(
        a.data() == b.data(),
        "the hidden point light changed the image"
    );
    assert!(a.data().iter().any(|&v| v > 0.0));
}
