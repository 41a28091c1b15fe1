//! Scene files: every scene in scenes/ loads and is seen by its camera, TOML and JSON
//! forms agree, and malformed files are reported at the right line, column and key.

use glam::{DVec2, DVec3};
use render::color::luminance;
use render::light::Shape;
use render::scene::{
    load_scene, parse_scene, IntegratorKind, RenderSettings, Scene, SceneError, SceneFormat,
    TechniqueKind as Technique,
};
use render::Material;
use std::path::{Path, PathBuf};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

/// The scenes shipped in scenes/, named (not globbed: a user's own scene saved there
/// must not change what the tests check).
const SCENES: [&str; 10] = [
    "city.toml",
    "cornell.json",
    "cornell.toml",
    "environment.toml",
    "many-lights.toml",
    "materials.toml",
    "point-lights.toml",
    "table.json",
    "table.toml",
    "textures.toml",
];

fn scene_files() -> Vec<PathBuf> {
    SCENES.iter().map(|n| scenes_dir().join(n)).collect()
}

fn load(p: &Path) -> (Scene, RenderSettings) {
    load_scene(p).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_scene_loads_and_its_camera_sees_it() {
    let files = scene_files();
    for name in [
        "many-lights",
        "table",
        "cornell",
        "point-lights",
        "environment",
    ] {
        assert!(
            files.iter().any(|f| f.file_stem().unwrap() == name),
            "{name} is missing"
        );
    }
    for f in &files {
        let (scene, settings) = load(f);
        let cam = &scene.camera;
        let centre = cam.ray(cam.width / 2, cam.height / 2, DVec2::splat(0.5));
        assert!(
            scene.intersect(&centre, 1e-6, f64::INFINITY).is_some(),
            "{}: the centre pixel sees nothing",
            f.display()
        );
        // Most of a coarse grid of camera rays meets an object.
        let (nx, ny) = (16, 12);
        let hits = (0..nx * ny)
            .filter(|k| {
                let (x, y) = (k % nx, k / nx);
                let r = cam.ray(
                    (x * cam.width) / nx,
                    (y * cam.height) / ny,
                    DVec2::splat(0.5),
                );
                scene.intersect(&r, 1e-6, f64::INFINITY).is_some()
            })
            .count();
        assert!(
            hits * 2 > (nx * ny) as usize,
            "{}: {hits} hits",
            f.display()
        );
        // Every object is bounded, and no object holds the eye or a light.
        for o in &scene.objects {
            assert!(
                o.geometry.bounds().is_finite(),
                "{}: {}",
                f.display(),
                o.name
            );
            assert!(
                !o.solid().expect("a solid").inside(cam.eye),
                "{}: eye in {}",
                f.display(),
                o.name
            );
            // (An emitting object's proxy sits inside the object by design.)
            for l in scene.lights.area().iter().filter(|l| !l.proxy) {
                let c = match l.shape {
                    Shape::Sphere { center, .. } | Shape::Disk { center, .. } => center,
                    Shape::Rect {
                        corner,
                        edge_u,
                        edge_v,
                    } => corner + (edge_u + edge_v) / 2.0,
                    Shape::Triangle { p0, e1, e2 } => p0 + (e1 + e2) / 3.0,
                };
                assert!(
                    !o.solid().expect("a solid").inside(c),
                    "{}: light in {}",
                    f.display(),
                    o.name
                );
            }
        }
        assert!(settings.spp <= 16, "{}: keep spp small", f.display());
        assert!(cam.width * cam.height <= 320 * 240);
        settings.check_techniques(&scene).unwrap();
    }
}

#[test]
fn the_papers_scenes_have_what_they_promise() {
    let (s, st) = load(&scenes_dir().join("many-lights.toml"));
    assert!(s.lights.area().len() >= 8);
    let mut powers: Vec<i64> = s
        .lights
        .area()
        .iter()
        .map(|l| (luminance(l.power()) * 1e6) as i64)
        .collect();
    powers.sort();
    powers.dedup();
    assert!(powers.len() >= 5, "lights of different powers");
    assert!(st.techniques.len() >= 2);
    let (t, _) = load(&scenes_dir().join("table.toml"));
    assert_eq!(t.lights.area().len(), 1);
    assert!(t.lights.area()[0].area() > 2.0, "a large light");
    let (p, _) = load(&scenes_dir().join("point-lights.toml"));
    assert!(p.lights.area().is_empty() && p.lights.environment().is_none());
    assert_eq!(p.lights.delta().len(), 3);
    let (e, st) = load(&scenes_dir().join("environment.toml"));
    assert!(e.lights.environment().is_some());
    assert!(st.techniques.contains(&(Technique::Environment, 1)));
    // The introduction's materials: wax (a medium behind glass), a flame (an emitting
    // object among the lights), marble and leather (pattern textures).
    let (m, st) = load(&scenes_dir().join("materials.toml"));
    assert!(m.participating && m.media.len() == 1);
    assert_eq!(m.lights.area().iter().filter(|l| l.proxy).count(), 1);
    assert!(st.method.is_optimal());
    let patterns = m
        .materials
        .iter()
        .filter(|x| {
            matches!(
                x,
                Material::Plastic {
                    diffuse: render::Texture::Pattern { .. },
                    ..
                }
            )
        })
        .count();
    assert_eq!(patterns, 3, "table, marble, leather");
    let meta = std::fs::metadata(scenes_dir().join("sky.exr")).unwrap();
    assert!(meta.len() <= 200_000, "sky.exr is {} bytes", meta.len());
}

fn assert_same(a: &(Scene, RenderSettings), b: &(Scene, RenderSettings)) {
    assert_eq!(a.0.camera, b.0.camera);
    assert_eq!(a.0.materials, b.0.materials);
    assert_eq!(a.0.objects.len(), b.0.objects.len());
    for (x, y) in a.0.objects.iter().zip(&b.0.objects) {
        assert_eq!((&x.name, x.material), (&y.name, y.material));
        assert_eq!(x.geometry.bounds(), y.geometry.bounds());
    }
    assert_eq!(a.0.lights.area(), b.0.lights.area());
    assert_eq!(a.0.lights.delta(), b.0.lights.delta());
    assert_eq!(a.0.bounds(), b.0.bounds());
    assert_eq!(a.1, b.1);
}

#[test]
fn toml_and_json_forms_agree() {
    let mut pairs = 0;
    for f in scene_files() {
        let json = f.with_extension("json");
        if f.extension().unwrap() == "toml" && json.exists() {
            assert_same(&load(&f), &load(&json));
            pairs += 1;
        }
    }
    assert!(pairs >= 2, "{pairs} TOML/JSON pairs");
}

const BASE: &str = r#"[camera]
eye = [0, -4, 1]
target = [0, 0, 1]
fov = 40
resolution = [64, 48]

[render]
integrator = "direct"
spp = 8
estimator = "optimal-direct"
techniques = [{ technique = "bsdf", samples = 2 }, { technique = "light", samples = 1 }]

[materials.white]
type = "diffuse"
reflectance = 0.8

[[objects]]
solid = "sphere([0, 0, 1], 1)"
material = "white"

[[lights]]
type = "rect"
center = [0, 0, 3]
size = [1, 2]
color = [1, 0.5, 0.25]
power = 100
"#;

fn toml(text: &str) -> Result<(Scene, RenderSettings), SceneError> {
    parse_scene(text, SceneFormat::Toml, &scenes_dir().join("test.toml"))
}

/// 1-based line and column of the first `needle` in `text` (+ `shift` characters).
fn pos(text: &str, needle: &str, shift: usize) -> (usize, usize) {
    let i = text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not in text"));
    let line = text[..i].matches('\n').count() + 1;
    let col = text[..i].rsplit('\n').next().unwrap().chars().count() + 1 + shift;
    (line, col)
}

#[track_caller]
fn expect(
    r: Result<(Scene, RenderSettings), SceneError>,
    at: (usize, usize),
    key: &str,
    msg: &str,
) {
    let e = r.err().expect("an error");
    assert_eq!((e.line, e.column, e.key.as_str()), (at.0, at.1, key), "{e}");
    assert!(e.message.contains(msg), "{e}");
    assert!(
        e.to_string().contains(&format!(":{}:{}: ", at.0, at.1)),
        "{e}"
    );
}

#[test]
fn the_base_scene_builds_as_written() {
    let (s, st) = toml(BASE).unwrap();
    assert_eq!(st.integrator, IntegratorKind::Direct);
    assert_eq!(st.spp, 8);
    assert_eq!(st.method, mis::Method::OptimalDirect);
    assert_eq!(
        st.techniques,
        vec![(Technique::Bsdf, 2), (Technique::LightPower, 1)]
    );
    // Power 100 W × colour, per channel.
    let p = s.lights.area()[0].power();
    assert!((p - DVec3::new(100.0, 50.0, 25.0)).length() < 1e-9, "{p}");
    // The rect faces down (its default normal) and spans 1 × 2.
    let Shape::Rect {
        edge_u,
        edge_v,
        corner,
    } = s.lights.area()[0].shape
    else {
        panic!()
    };
    assert!((edge_u.cross(edge_v).normalize() + DVec3::Z).length() < 1e-12);
    assert!((edge_u.length() - 1.0).abs() < 1e-12 && (edge_v.length() - 2.0).abs() < 1e-12);
    assert!((corner + (edge_u + edge_v) / 2.0 - DVec3::new(0.0, 0.0, 3.0)).length() < 1e-12);
    assert_eq!(
        s.materials,
        vec![Material::Diffuse {
            reflectance: DVec3::splat(0.8).into()
        }]
    );
}

#[test]
fn transforms_apply_in_order() {
    let with = |t: &str| {
        let text = BASE.replace(
            "material = \"white\"",
            &format!("material = \"white\"\ntransform = {t}"),
        );
        let (s, _) = toml(&text).unwrap();
        s.objects[0].geometry.bounds()
    };
    // Scale 2 then move up 1: the ball (centre z = 1) ends at z = 3; the other way, z = 4.
    let a = with("[{ scale = 2 }, { translate = [0, 0, 1] }]");
    let b = with("[{ translate = [0, 0, 1] }, { scale = 2 }]");
    assert!(
        (a.center().z - 3.0).abs() < 1e-6 && (b.center().z - 4.0).abs() < 1e-6,
        "{a:?} {b:?}"
    );
    let r = with("{ rotate = { axis = [1, 0, 0], degrees = 90 } }");
    assert!(
        (r.center() - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-6,
        "{r:?}"
    );
}

#[test]
fn metal_presets_look_like_their_metals() {
    let r0 = |eta: f64, k: f64| ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
    for (name, eta, k) in render::scene::METALS {
        let r: Vec<f64> = (0..3).map(|c| r0(eta[c], k[c])).collect();
        assert!(r.iter().all(|&x| x > 0.3 && x < 1.0), "{name}: {r:?}");
        if name == "gold" || name == "copper" {
            assert!(r[0] > r[1] && r[1] > r[2] - 0.05, "{name}: {r:?}");
        }
    }
}

#[test]
fn malformed_toml_is_located() {
    let b = BASE;
    let case = |from: &str, to: &str| b.replacen(from, to, 1);
    // Unknown key.
    let t = case("fov = 40", "fov = 40\nzoom = 2");
    expect(
        toml(&t),
        pos(&t, "zoom", 0),
        "camera.zoom",
        "unknown field `zoom`",
    );
    // Wrong type.
    let t = case("fov = 40", "fov = \"wide\"");
    expect(
        toml(&t),
        pos(&t, "\"wide\"", 0),
        "camera.fov",
        "invalid type",
    );
    // Missing material.
    let t = case("material = \"white\"", "material = \"whit\"");
    expect(
        toml(&t),
        pos(&t, "\"whit\"", 0),
        "objects[0].material",
        "unknown material \"whit\"; defined: white",
    );
    // Missing model file.
    let t = case(
        "solid = \"sphere([0, 0, 1], 1)\"",
        "model = \"models/nope.frep\"",
    );
    expect(
        toml(&t),
        pos(&t, "\"models/nope", 0),
        "objects[0].model",
        "cannot read the file",
    );
    // Malformed inline solid: the column inside the string is kept.
    let t = case("sphere([0, 0, 1], 1)", "sphere([0, 0, 1], 1");
    let e = toml(&t).err().unwrap();
    let (l, c) = pos(&t, "sphere([0, 0, 1], 1\"", 0);
    assert_eq!((e.line, e.key.as_str()), (l, "objects[0].solid"), "{e}");
    assert!(e.column > c && e.column <= c + 21, "{e}");
    // Bad technique name, listing the valid ones.
    let t = case("\"light\"", "\"lights\"");
    expect(
        toml(&t),
        pos(&t, "\"lights\"", 0),
        "render.techniques[1].technique",
        "valid names: bsdf, light-power, light (= light-power), light-uniform, light-area, \
         light-spatial, light-bvh, light-trained, light#k (MIS light k, 0-based), light#* (every MIS \
         light), environment, cosine",
    );
    // Bad MIS name.
    let t = case("\"optimal-direct\"", "\"optimal\"");
    expect(
        toml(&t),
        pos(&t, "\"optimal\"", 0),
        "render.estimator",
        "valid names: balance",
    );
    // Negative and zero samples.
    let t = case("samples = 2", "samples = -2");
    expect(
        toml(&t),
        pos(&t, "-2", 0),
        "render.techniques[0].samples",
        "expected u32",
    );
    let t = case("spp = 8", "spp = 0");
    expect(toml(&t), pos(&t, "spp = 0", 6), "render.spp", "at least 1");
    // Zero resolution.
    let t = case("[64, 48]", "[64, 0]");
    expect(
        toml(&t),
        pos(&t, "[64, 0]", 0),
        "camera.resolution",
        "must have pixels",
    );
    // TOML syntax: an unclosed array runs on to the next table header.
    let t = case("[64, 48]", "[64, 48");
    expect(
        toml(&t),
        pos(&t, "[render]", 0),
        "",
        "missing comma between array elements",
    );
    let t = case("fov = 40", "fov = 40 = 2");
    assert_eq!(toml(&t).err().unwrap().line, 4);
    // Unknown material type, and a key that its type does not take.
    let t = case("type = \"diffuse\"", "type = \"velvet\"");
    expect(
        toml(&t),
        pos(&t, "\"velvet\"", 0),
        "materials.white.type",
        "valid types: diffuse, conductor",
    );
    let t = case("reflectance = 0.8", "reflectance = 0.8\neta = 1.3");
    expect(
        toml(&t),
        pos(&t, "eta", 0),
        "materials.white.eta",
        "takes no key \"eta\"",
    );
    // Degenerate camera, bad light, bad transform.
    let t = case("target = [0, 0, 1]", "target = [0, -4, 1]");
    expect(
        toml(&t),
        pos(&t, "[0, -4, 1]\nfov", 0),
        "camera.target",
        "the target is the eye",
    );
    let t = case("power = 100", "power = 100\nradiance = 3");
    expect(
        toml(&t),
        pos(&t, "power", 0),
        "lights[0].power",
        "either radiance or power",
    );
    let t = case(
        "material = \"white\"",
        "material = \"white\"\ntransform = [{ translate = [1, 0, 0], scale = 2 }]",
    );
    expect(
        toml(&t),
        pos(&t, "{ translate", 0),
        "objects[0].transform[0]",
        "exactly one of",
    );
    let t = case("[materials.white]", "[materials.white]\nroughness = 0.1\n[materials.glass]\ntype = \"dielectric\"\neta = [1.5, 1.6, 1.5]\n[materials.x]");
    assert!(toml(&t).is_err());
}

#[test]
fn errors_inside_solids_and_models_keep_their_position() {
    // A multi-line inline program with an error on its second line.
    let t = BASE.replace(
        "solid = \"sphere([0, 0, 1], 1)\"",
        "solid = \"\"\"\nlet b = sphere([0, 0, 1], 1)\noutput bb\n\"\"\"",
    );
    let e = toml(&t).err().unwrap();
    assert_eq!((e.line, e.column), pos(&t, "bb\n", 0), "{e}");
    // A malformed model file: its own file, line and column, and the scene's key.
    let dir = std::env::temp_dir().join(format!("scene-format-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("bad.frep"),
        "let a = 1\noutput sphere([0, 0, 0] 1)\n",
    )
    .unwrap();
    let t = BASE.replace("solid = \"sphere([0, 0, 1], 1)\"", "model = \"bad.frep\"");
    let e = parse_scene(&t, SceneFormat::Toml, &dir.join("s.toml"))
        .err()
        .unwrap();
    assert!(e.file.ends_with("bad.frep"), "{e}");
    assert_eq!((e.line, e.key.as_str()), (2, "objects[0].model"), "{e}");
    assert!(e.message.contains("s.toml:"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

fn json(text: &str) -> Result<(Scene, RenderSettings), SceneError> {
    parse_scene(text, SceneFormat::Json, Path::new("test.json"))
}

const JSON: &str = r#"{
  "camera": {"eye": [0, -4, 1], "target": [0, 0, 1], "resolution": [64, 48]},
  "materials": {"white": {"type": "diffuse", "reflectance": 0.8}},
  "objects": [
    {"solid": "sphere([0, 0, 1], 1)", "material": "white"},
    {"solid": "let a = sphere([0, 0, 3], 1)\noutput a", "material": "white"}
  ],
  "lights": [{"type": "point", "position": [0, 0, 5], "intensity": 10}]
}
"#;

#[test]
fn malformed_json_is_located() {
    let (s, st) = json(JSON).unwrap();
    assert_eq!(s.objects.len(), 2);
    // Only a delta light: the default techniques are BSDF sampling alone.
    assert_eq!(st.techniques, vec![(Technique::Bsdf, 1)]);
    let case = |from: &str, to: &str| JSON.replacen(from, to, 1);
    let t = case("\"resolution\"", "\"zoom\": 2, \"resolution\"");
    expect(
        json(&t),
        pos(&t, "\"zoom\"", 0),
        "camera.zoom",
        "unknown field `zoom`",
    );
    let t = case("[64, 48]", "[64, 0]");
    expect(
        json(&t),
        pos(&t, "[64, 0]", 0),
        "camera.resolution",
        "must have pixels",
    );
    let t = case(
        "\"materials\"",
        "\"render\": {\"aovs\": [\"depth\", \"depht\"]},\n  \"materials\"",
    );
    expect(
        json(&t),
        pos(&t, "\"depht\"", 0),
        "render.aovs[1]",
        "valid names: depth, normal, albedo",
    );
    let t = case("\"reflectance\": 0.8", "\"reflectance\": \"grey\"");
    expect(
        json(&t),
        pos(&t, "\"grey\"", 0),
        "materials.white.reflectance",
        "a colour",
    );
    let t = case("\"material\": \"white\"}\n", "\"material\": \"black\"}\n");
    expect(
        json(&t),
        pos(&t, "\"black\"", 0),
        "objects[1].material",
        "unknown material",
    );
    let t = case("\"intensity\": 10", "\"intensity\": -10");
    expect(json(&t), pos(&t, "-10", 0), "lights[0].intensity", "≥ 0");
    // Syntax: a trailing comma.
    let t = case("\"intensity\": 10}", "\"intensity\": 10,}");
    expect(json(&t), pos(&t, ",}", 1), "", "trailing comma");
    // An error on the second line of an escaped multi-line solid.
    let t = case("output a", "output b");
    expect(
        json(&t),
        pos(&t, "b\"", 0),
        "objects[1].solid",
        "in the solid",
    );
}

#[test]
fn unreadable_scene_files_are_errors() {
    let e = load_scene(Path::new("no/such/scene.toml")).err().unwrap();
    assert_eq!((e.line, e.column), (0, 0));
    assert!(
        e.to_string().starts_with("no/such/scene.toml: cannot read"),
        "{e}"
    );
    let e = load_scene(Path::new("scene.yaml")).err().unwrap();
    assert!(e.message.contains(".toml or .json"), "{e}");
}

/// Writes scenes/sky.exr, the procedural sky of scenes/environment.toml: a zenith-to-
/// horizon gradient, a dim ground and a sun of radius 3° at 35° elevation. Run with
/// `cargo test -p render --test render_tests -- --ignored generate_sky_map`.
#[test]
#[ignore]
fn generate_sky_map() {
    use exr::prelude::*;
    let (w, h) = (256usize, 128usize);
    let sun = {
        let (el, az) = (35f64.to_radians(), 200f64.to_radians());
        DVec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
    };
    let radiance = |x: usize, y: usize| -> DVec3 {
        let theta = std::f64::consts::PI * (y as f64 + 0.5) / h as f64;
        let phi = 2.0 * std::f64::consts::PI * (x as f64 + 0.5) / w as f64;
        let d = DVec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        );
        let zenith = DVec3::new(0.15, 0.3, 0.8);
        let horizon = DVec3::new(0.8, 0.85, 0.95);
        let mut l = if d.z >= 0.0 {
            horizon.lerp(zenith, d.z.sqrt())
        } else {
            DVec3::new(0.2, 0.17, 0.14) * 0.5
        };
        let angle = d.dot(sun).clamp(-1.0, 1.0).acos().to_degrees();
        if angle < 3.0 {
            l += DVec3::new(1.0, 0.92, 0.8) * 400.0;
        }
        l + DVec3::new(1.0, 0.9, 0.7) * 2.0 * (-angle / 8.0).exp()
    };
    let channels = SpecificChannels::rgb(|Vec2(x, y)| {
        let l = radiance(x, y);
        (f16::from_f64(l.x), f16::from_f64(l.y), f16::from_f64(l.z))
    });
    let layer = Layer::new(
        (w, h),
        LayerAttributes::named("sky"),
        Encoding::SMALL_LOSSLESS,
        channels,
    );
    Image::from_layer(layer)
        .write()
        .to_file(scenes_dir().join("sky.exr"))
        .unwrap();
}

/// Prints each scene as seen by its camera, one character per object (for eyeballing
/// a composition): `cargo test -p render --test render_tests -- --ignored --nocapture ascii`.
#[test]
#[ignore]
fn ascii_previews() {
    for f in scene_files() {
        let (scene, _) = load(&f);
        let cam = &scene.camera;
        println!("{}", f.display());
        for y in 0..24 {
            let line: String = (0..64)
                .map(|x| {
                    let r = cam.ray(x * cam.width / 64, y * cam.height / 24, DVec2::splat(0.5));
                    match scene.intersect(&r, 1e-6, f64::INFINITY) {
                        Some(h) => (b'a' + (h.object % 26) as u8) as char,
                        None if scene.lights.intersect(&r, 1e-6, f64::INFINITY).is_some() => '*',
                        None => '.',
                    }
                })
                .collect();
            println!("{line}");
        }
        for (i, o) in scene.objects.iter().enumerate() {
            println!("  {}: {}", (b'a' + (i % 26) as u8) as char, o.name);
        }
    }
}

/// The code blocks of docs/scene-format.md marked `toml` or `json`.
fn doc_blocks(lang: &str) -> Vec<String> {
    let doc = std::fs::read_to_string(scenes_dir().join("../docs/scene-format.md")).unwrap();
    let fence = format!("```{lang}\n");
    doc.split(&fence)
        .skip(1)
        .map(|b| b.split("```").next().unwrap().to_string())
        .collect()
}

#[test]
fn the_documented_examples_parse() {
    let here = scenes_dir().join("doc-example.toml");
    let toml_blocks = doc_blocks("toml");
    assert_eq!(toml_blocks.len(), 2);
    // The media example: a glass of milk and a box of smoke.
    let (m, _) =
        parse_scene(&toml_blocks[1], SceneFormat::Toml, &here).unwrap_or_else(|e| panic!("{e}"));
    assert!(m.participating && m.media.len() == 2);
    assert_eq!(
        m.objects.iter().map(|o| o.interior).collect::<Vec<_>>(),
        vec![Some(0), Some(1)]
    );
    let (s, st) =
        parse_scene(&toml_blocks[0], SceneFormat::Toml, &here).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((s.materials.len(), s.objects.len()), (6, 6));
    assert_eq!((s.lights.area().len(), s.lights.delta().len()), (4, 2));
    assert!(s.lights.environment().is_some());
    assert_eq!(st.method, mis::Method::OptimalProgressive);
    assert_eq!(st.techniques.len(), 5);
    assert_eq!(st.aovs, vec!["depth", "normal"]);
    for b in doc_blocks("json") {
        parse_scene(&b, SceneFormat::Json, &here.with_extension("json"))
            .unwrap_or_else(|e| panic!("{e}"));
    }
}

/// Truncated and corrupted scene texts give errors, never panics.
#[test]
fn damaged_files_are_errors_not_panics() {
    let mut texts: Vec<(String, SceneFormat)> = vec![(BASE.to_string(), SceneFormat::Toml)];
    texts.push((JSON.to_string(), SceneFormat::Json));
    for name in ["many-lights.toml", "cornell.json"] {
        let f = scenes_dir().join(name);
        let format = SceneFormat::from_path(&f).unwrap();
        texts.push((std::fs::read_to_string(f).unwrap(), format));
    }
    let mut errors = 0;
    for (text, format) in &texts {
        let here = scenes_dir().join("damaged.scene");
        let cuts: Vec<usize> = (1..24).map(|k| k * text.len() / 24).collect();
        for &cut in &cuts {
            let cut = (cut..text.len())
                .find(|&i| text.is_char_boundary(i))
                .unwrap();
            for damaged in [
                text[..cut].to_string(),
                format!(
                    "{}{}",
                    &text[..cut],
                    &text[cut..].replacen(|c: char| c.is_ascii_digit(), "-", 1)
                ),
                format!("{}{}", &text[..cut], &text[cut..].replacen(']', "", 1)),
                format!("{}{}", &text[..cut], &text[cut..].replacen('"', "", 1)),
            ] {
                if let Err(e) = parse_scene(&damaged, *format, &here) {
                    errors += 1;
                    assert!(
                        e.file.ends_with("damaged.scene") || e.file.contains(".frep"),
                        "{e}"
                    );
                    assert!(e.line >= 1 && e.column >= 1, "{e}");
                }
            }
        }
    }
    assert!(errors > 200, "{errors} errors");
}

/// The CPU scene built from resolved data agrees with the renderer's own formulas: each
/// light's power, and light selection recomputed by `Lights::new` from the scene radius.
#[test]
fn scenes_built_from_data_match_the_renderers_formulas() {
    use render::light::Lights;
    for f in scene_files() {
        let (data, _) = scene::load(&f).unwrap_or_else(|e| panic!("{e}"));
        let s = Scene::from_data(&data);
        let close =
            |a: DVec3, b: [f64; 3]| (a - DVec3::from_array(b)).length() <= 1e-12 * a.length();
        for (l, a) in data.lights.area.iter().zip(s.lights.area()) {
            assert!(close(a.power(), l.power), "{}", f.display());
            assert!((a.area() - l.area).abs() <= 1e-12 * l.area);
        }
        for (l, d) in data.lights.delta.iter().zip(s.lights.delta()) {
            assert!(close(d.power(), l.power), "{}", f.display());
        }
        let again = Lights::new(
            s.lights.area().to_vec(),
            s.lights.delta().to_vec(),
            s.lights.environment().cloned(),
            data.scene_radius,
        );
        let p = DVec3::new(0.1, 0.2, 0.3);
        for k in 0..64 {
            let z = -1.0 + (k as f64 + 0.5) / 32.0;
            let phi = k as f64 * 2.4;
            let r = (1.0 - z * z).sqrt();
            let wi = DVec3::new(r * phi.cos(), r * phi.sin(), z);
            assert_eq!(s.lights.pdf_by_power(p, wi), again.pdf_by_power(p, wi));
            assert_eq!(s.lights.pdf_by_area(p, wi), again.pdf_by_area(p, wi));
            assert_eq!(s.lights.pdf_environment(wi), again.pdf_environment(wi));
        }
    }
}

/// A thin lens: `aperture` (the lens's radius) with `focus_distance` (default the
/// target's distance); every ray of a pixel point, whatever its lens point, meets the
/// pinhole ray on the plane in focus; the lens's keys are checked where they stand.
#[test]
fn a_thin_lens_focuses_on_its_plane() {
    let lens = |keys: &str| BASE.replace("fov = 40\n", &format!("fov = 40\n{keys}\n"));
    let (s, _) = toml(&lens("aperture = 0.1\nfocus_distance = 3.0")).unwrap();
    assert_eq!(s.camera.lens(), Some((0.1, 3.0)));
    let (s, _) = toml(&lens("aperture = 0.1")).unwrap();
    assert_eq!(
        s.camera.lens(),
        Some((0.1, 4.0)),
        "default: the target's distance"
    );
    let eye = DVec3::new(0.0, -4.0, 1.0);
    let forward = DVec3::Y;
    for (x, y, off) in [
        (0, 0, DVec2::ZERO),
        (31, 20, DVec2::splat(0.5)),
        (63, 47, DVec2::new(0.9, 0.1)),
    ] {
        let pin = s.camera.ray(x, y, off);
        let focus = pin.o + pin.d * (4.0 / pin.d.dot(forward));
        for k in 0..16 {
            let u = DVec2::new((k % 4) as f64 / 4.0 + 0.1, (k / 4) as f64 / 4.0 + 0.05);
            let r = s.camera.ray_through_lens(x, y, off, u);
            assert!((r.d.length() - 1.0).abs() < 1e-12);
            assert!((r.o - eye).dot(forward).abs() < 1e-12, "on the lens plane");
            assert!((r.o - eye).length() <= 0.1 + 1e-12, "inside the lens");
            let t = (focus - r.o).dot(forward) / r.d.dot(forward);
            assert!(
                (r.o + r.d * t - focus).length() < 1e-9,
                "meets the focus point"
            );
        }
    }
    // No aperture: a pinhole, whatever the lens point.
    let (p, _) = toml(BASE).unwrap();
    assert_eq!(p.camera.lens(), None);
    let u = DVec2::new(0.3, 0.7);
    assert_eq!(p.camera.ray_through_lens(5, 6, u, u), p.camera.ray(5, 6, u));
    let t = lens("focus_distance = 3");
    expect(
        toml(&t),
        pos(&t, "focus_distance = 3", 17),
        "camera.focus_distance",
        "give aperture",
    );
    let t = lens("aperture = -1");
    expect(
        toml(&t),
        pos(&t, "aperture = -1", 11),
        "camera.aperture",
        "",
    );
    let t = lens("aperture = 0.1\nfocus_distance = 0");
    expect(
        toml(&t),
        pos(&t, "focus_distance = 0", 17),
        "camera.focus_distance",
        "",
    );
    let t = lens("aperture = 0.1\ntype = \"orthographic\"");
    expect(
        toml(&t),
        pos(&t, "aperture = 0.1", 11),
        "camera.aperture",
        "perspective",
    );
}
