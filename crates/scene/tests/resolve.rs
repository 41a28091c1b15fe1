//! Resolution: a scene file and the same scene given as data resolve to equal
//! SceneData; errors in data name their key path; the distributions computed once are
//! right; overrides are validated like the file's own values.

use scene::{
    load, load_value, parse, parse_with, CameraKind, EnvironmentData, LightKind, Overrides,
    SceneData, SceneFormat, TechniqueDesc, TechniqueKind,
};
use serde_json::{json, Value};
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
    "point-lights.toml",
    "rooms.toml",
    "table.json",
    "table.toml",
    "textures.toml",
];

fn scene_files() -> Vec<PathBuf> {
    SCENES.iter().map(|n| scenes_dir().join(n)).collect()
}

/// The file's text as a JSON value (TOML converted), as a caller with a dict has it.
fn as_value(p: &Path) -> Value {
    let text = std::fs::read_to_string(p).unwrap();
    match SceneFormat::from_path(p).unwrap() {
        SceneFormat::Toml => toml::from_str(&text).unwrap(),
        SceneFormat::Json => serde_json::from_str(&text).unwrap(),
    }
}

fn load_file(p: &Path) -> SceneData {
    load(p).unwrap_or_else(|e| panic!("{e}")).0
}

#[test]
fn files_and_values_resolve_to_equal_scene_data() {
    let files = scene_files();
    assert!(files.len() >= 7, "{files:?}");
    for f in &files {
        let (data, settings) = load(f).unwrap_or_else(|e| panic!("{e}"));
        let (from_value, settings_v) =
            load_value(as_value(f), &scenes_dir()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(data, from_value, "{}", f.display());
        assert_eq!(settings, settings_v, "{}", f.display());
        // The same data serialises to the same JSON (what --dump-scene writes).
        assert_eq!(
            serde_json::to_value(&data).unwrap(),
            serde_json::to_value(&from_value).unwrap()
        );
        assert_eq!(data.solids.len(), data.objects.len());
    }
    // TOML files and their JSON twins resolve alike.
    let mut pairs = 0;
    for f in files.iter().filter(|f| f.extension().unwrap() == "toml") {
        let twin = f.with_extension("json");
        if twin.exists() {
            assert_eq!(load(f).unwrap(), load(&twin).unwrap(), "{}", f.display());
            pairs += 1;
        }
    }
    assert!(pairs >= 2);
    // A change anywhere makes them differ.
    let f = scenes_dir().join("table.toml");
    let mut v = as_value(&f);
    v["objects"][0]["transform"] = json!({ "translate": [0, 0, 1e-9] });
    let moved = load_value(v, &scenes_dir()).unwrap().0;
    assert_ne!(load_file(&f).solids, moved.solids);
}

#[track_caller]
fn value_error(v: Value, key: &str, message: &str) {
    let e = load_value(v, &scenes_dir()).expect_err("an error");
    assert_eq!(e.key, key, "{e}");
    assert!(e.message.contains(message), "{e}");
    assert_eq!((e.line, e.column, e.file.as_str()), (0, 0, ""), "{e}");
    assert!(e.to_string().starts_with(&format!("{key}: ")), "{e}");
}

fn base() -> Value {
    json!({
        "camera": {"eye": [0, -4, 1], "target": [0, 0, 1], "resolution": [64, 48]},
        "materials": {"white": {"type": "diffuse", "reflectance": 0.8}},
        "objects": [
            {"solid": "sphere([0, 0, 1], 1)", "material": "white"},
            {"solid": "let a = sphere([0, 0, 3], 1)\noutput a", "material": "white"}
        ],
        "lights": [{"type": "sphere", "center": [0, 0, 5], "radius": 0.5, "power": 10}]
    })
}

/// `camera.type = "orthographic"` with a `scale` (default: what the field of view spans
/// at the target); a perspective camera's resolved JSON is what it always was.
#[test]
fn orthographic_cameras_resolve_with_a_scale() {
    let mut v = base();
    let (d, _) = load_value(v.clone(), &scenes_dir()).unwrap();
    assert_eq!(
        (d.camera.kind, d.camera.scale),
        (CameraKind::Perspective, None)
    );
    let json = serde_json::to_value(&d).unwrap();
    assert!(json["camera"].get("type").is_none() && json["camera"].get("scale").is_none());
    v["camera"]["type"] = json!("orthographic");
    let (d, _) = load_value(v.clone(), &scenes_dir()).unwrap();
    assert_eq!(d.camera.kind, CameraKind::Orthographic);
    let want = 2.0 * 4.0 * 20f64.to_radians().tan();
    assert!((d.camera.scale.unwrap() - want).abs() < 1e-12);
    v["camera"]["scale"] = json!(3);
    let (d, _) = load_value(v.clone(), &scenes_dir()).unwrap();
    let json = serde_json::to_value(&d).unwrap();
    assert_eq!(
        (json["camera"]["type"].as_str(), d.camera.scale),
        (Some("orthographic"), Some(3.0))
    );
    let mut bad = v.clone();
    bad["camera"]["scale"] = json!(-1);
    value_error(bad, "camera.scale", "positive");
    let mut bad = v.clone();
    bad["camera"]["type"] = json!("fisheye");
    value_error(bad, "camera.type", "valid types: perspective, orthographic");
    let mut bad = v.clone();
    bad["camera"]["type"] = json!("perspective");
    value_error(bad, "camera.scale", "applies to an orthographic camera");
}

#[test]
fn errors_in_values_name_the_key_path() {
    assert!(load_value(base(), &scenes_dir()).is_ok());
    let mut v = base();
    v["objects"][1]["solid"] = json!(3);
    value_error(v, "objects[1].solid", "invalid type");
    let mut v = base();
    v["objects"][0]["material"] = json!("black");
    value_error(
        v,
        "objects[0].material",
        "unknown material \"black\"; defined: white",
    );
    let mut v = base();
    v["camera"]["zoom"] = json!(2);
    value_error(v, "camera.zoom", "unknown field `zoom`");
    let mut v = base();
    v["lights"][0]["radius"] = json!(-1);
    value_error(v, "lights[0].radius", "≥ 0");
    let mut v = base();
    v["materials"]["white"]["type"] = json!("velvet");
    value_error(v, "materials.white.type", "valid types: diffuse");
    let mut v = base();
    v["render"] = json!({"techniques": [{"technique": "environment"}]});
    value_error(v, "render.techniques", "needs an environment");
    // An error inside an inline solid keeps its place within the solid.
    let mut v = base();
    v["objects"][1]["solid"] = json!("let a = sphere([0, 0, 3], 1)\noutput b");
    value_error(v, "objects[1].solid", "in the solid, line 2");
    // A model file that is not there.
    let mut v = base();
    v["objects"][0] = json!({"model": "models/nope.frep", "material": "white"});
    value_error(v, "objects[0].model", "nope.frep");
}

/// Paths in a scene naming a device or a pipe are refused, not opened: a model at
/// `/dev/zero` was read until memory ran out, and a map or model at a FIFO with no
/// writer blocked resolution for ever.
#[cfg(unix)]
#[test]
fn models_and_maps_that_are_devices_or_pipes_are_refused() {
    let dir = std::env::temp_dir().join(format!("scene-special-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let zero = dir.join("zero.frep");
    let _ = std::fs::remove_file(&zero);
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let mut v = base();
    v["objects"][0] = json!({"model": zero, "material": "white"});
    value_error(v, "objects[0].model", "found a folder, device or pipe");
    let fifo = dir.join("fifo.exr");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        let mut v = base();
        v["environment"] = json!({"map": fifo});
        value_error(v, "environment.map", "found a folder, device or pipe");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn light_selection_cdf_sums_to_one() {
    for name in ["many-lights.toml", "environment.toml", "cornell.toml"] {
        let d = load_file(&scenes_dir().join(name));
        let by_power = d.lights.by_power.as_ref().unwrap();
        let n = d.lights.area.len() + usize::from(d.environment.is_some());
        assert_eq!(by_power.len(), n);
        assert_eq!((by_power.cdf[0], by_power.cdf[n]), (0.0, 1.0));
        assert!(by_power.cdf.windows(2).all(|w| w[0] <= w[1]));
        let total: f64 = (0..n).map(|i| by_power.pmf(i)).sum();
        assert!((total - 1.0).abs() < 1e-12, "{name}: {total}");
        // Each area light's pmf ∝ the luminance of its power.
        let lum = |p: [f64; 3]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
        let sum: f64 = by_power.func.iter().sum();
        for (i, l) in d.lights.area.iter().enumerate() {
            assert_eq!(l.selection_pmf, by_power.pmf(i));
            assert!((l.selection_pmf - lum(l.power) / sum).abs() < 1e-12);
            assert!(l.kind.has_area() && l.area > 0.0);
        }
        assert!(d.lights.delta.iter().all(|l| l.selection_pmf == 0.0));
        let Some(by_area) = d.lights.by_area.as_ref() else {
            assert!(d.lights.area.is_empty(), "{name}");
            continue;
        };
        let areas: f64 = d.lights.area.iter().map(|l| l.area).sum();
        for (i, l) in d.lights.area.iter().enumerate() {
            assert!((by_area.pmf(i) - l.area / areas).abs() < 1e-12);
        }
    }
    let p = load_file(&scenes_dir().join("point-lights.toml"));
    assert!(p.lights.by_power.is_none() && p.lights.area.is_empty());
    let kinds: Vec<LightKind> = p.lights.delta.iter().map(|l| l.kind).collect();
    assert_eq!(kinds, [LightKind::Point, LightKind::Point, LightKind::Spot]);
}

/// The environment map's table against a brute-force computation from its pixels:
/// weight average(L)·sin θ per pixel, the marginal ∝ row sums, the conditional of each
/// row ∝ its weights, and ∫ L dω by summing pixel solid angles.
#[test]
fn environment_cdf_matches_brute_force() {
    let d = load_file(&scenes_dir().join("environment.toml"));
    let Some(EnvironmentData::Map { map, .. }) = d.environment else {
        panic!("environment.toml has a map")
    };
    let t = &d.maps[map.index()];
    let (w, h) = (t.width, t.height);
    assert_eq!(t.pixels.len(), w * h);
    let pi = std::f64::consts::PI;
    let weight = |x: usize, y: usize| {
        let p = t.pixels[y * w + x];
        let theta = pi * (y as f64 + 0.5) / h as f64;
        (p[0] + p[1] + p[2]) / 3.0 * theta.sin()
    };
    let rows: Vec<f64> = (0..h).map(|y| (0..w).map(|x| weight(x, y)).sum()).collect();
    let total: f64 = rows.iter().sum();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
    let m = &t.distribution.marginal;
    let mut acc = 0.0;
    for (y, &row) in rows.iter().enumerate() {
        assert!(
            close(m.cdf[y], acc / total),
            "row {y}: {} {}",
            m.cdf[y],
            acc / total
        );
        assert!(close(m.pmf(y), row / total));
        acc += row;
        let c = &t.distribution.conditional[y];
        let mut a = 0.0;
        for x in 0..w {
            assert!(close(c.cdf[x], a / row), "({x}, {y})");
            a += weight(x, y);
        }
        assert_eq!(c.cdf[w], 1.0);
    }
    assert_eq!(m.cdf[h], 1.0);
    let mut integral = [0.0; 3];
    for y in 0..h {
        let band = (pi * y as f64 / h as f64).cos() - (pi * (y + 1) as f64 / h as f64).cos();
        for x in 0..w {
            for (c, i) in integral.iter_mut().enumerate() {
                *i += t.pixels[y * w + x][c] * 2.0 * pi / w as f64 * band;
            }
        }
    }
    for c in 0..3 {
        assert!(
            close(t.integral[c], integral[c]),
            "{:?} {integral:?}",
            t.integral
        );
    }
}

#[test]
fn overrides_are_validated_once_like_the_files_values() {
    let f = scenes_dir().join("cornell.toml");
    let text = std::fs::read_to_string(&f).unwrap();
    let o = Overrides {
        spp: Some(3),
        width: Some(10),
        techniques: Some(vec![TechniqueDesc {
            technique: "light-area".into(),
            samples: Some(2),
        }]),
        ..Default::default()
    };
    let (d, s) = parse_with(&text, SceneFormat::Toml, &f, &o).unwrap();
    assert_eq!((s.spp, d.camera.width), (3, 10));
    assert_eq!(s.techniques, vec![(TechniqueKind::LightArea, 2)]);
    let (plain, _) = parse(&text, SceneFormat::Toml, &f).unwrap();
    assert_eq!(d.camera.height, plain.camera.height);
    // A bad overridden value: the key path, no position in the file.
    let bad = Overrides {
        estimator: Some("optimal-guess".into()),
        ..Default::default()
    };
    let e = parse_with(&text, SceneFormat::Toml, &f, &bad).unwrap_err();
    assert_eq!((e.key.as_str(), e.line), ("render.estimator", 0), "{e}");
    assert!(e.message.contains("optimal-direct"), "{e}");
    let none = Overrides {
        techniques: Some(vec![TechniqueDesc {
            technique: "environment".into(),
            samples: None,
        }]),
        ..Default::default()
    };
    let e = parse_with(&text, SceneFormat::Toml, &f, &none).unwrap_err();
    assert_eq!(e.key, "render.techniques", "{e}");
}

/// Technique names: `light` is `light-power`; `light#k` names MIS light k and is
/// refused past the last, naming the count; `light#*` expands to one technique per MIS
/// light with the given count; a repeat (`light#0` twice through `light#*`) is refused.
#[test]
fn light_technique_names() {
    let f = scenes_dir().join("many-lights.toml");
    let text = std::fs::read_to_string(&f).unwrap();
    let with = |list: &str| {
        let o = Overrides {
            techniques: Some(scene::parse_technique_list(list).unwrap()),
            ..Default::default()
        };
        parse_with(&text, SceneFormat::Toml, &f, &o)
    };
    let (d, s) = with("light:2,light-uniform,light-spatial,light#1").unwrap();
    assert_eq!(
        s.techniques,
        vec![
            (TechniqueKind::LightPower, 2),
            (TechniqueKind::LightUniform, 1),
            (TechniqueKind::LightSpatial, 1),
            (TechniqueKind::Light(1), 1),
        ]
    );
    assert_eq!(TechniqueKind::LightPower.name(), "light-power");
    assert_eq!("light-power".parse(), Ok(TechniqueKind::LightPower));
    let n = d.lights.area.len() + usize::from(d.environment.is_some());
    assert!(n > 2, "{n}");
    let (_, s) = with("bsdf,light#*:3").unwrap();
    assert_eq!(s.techniques.len(), n + 1);
    assert_eq!(s.techniques[n], (TechniqueKind::Light(n as u32 - 1), 3));
    let e = with(&format!("light#{n}")).unwrap_err();
    assert!(e.message.contains(&format!("has {n} MIS lights")), "{e}");
    let e = with("light#0,light#*").unwrap_err();
    assert!(e.message.contains("twice"), "{e}");
    let e = with("light#x").unwrap_err();
    assert!(e.message.contains("light#k"), "{e}");
}

/// `trained_grid`, `trained_floor`, `trained_spp` and `min_depth`: defaults when left
/// out, read from the file or an override, and an out-of-range value is an error at its
/// key.
#[test]
fn training_and_min_depth_keys() {
    let f = scenes_dir().join("many-lights.toml");
    let text = std::fs::read_to_string(&f).unwrap();
    let with = |o: Overrides| parse_with(&text, SceneFormat::Toml, &f, &o);
    let (_, s) = with(Overrides::default()).unwrap();
    assert_eq!(s.training, scene::Training::default());
    assert_eq!(s.min_depth, 0);
    let (_, s) = with(Overrides {
        trained_grid: Some(1),
        trained_floor: Some(0.5),
        trained_spp: Some(16),
        integrator: Some("path".into()),
        min_depth: Some(2),
        ..Default::default()
    })
    .unwrap();
    let t = scene::Training {
        grid: 1,
        floor: 0.5,
        spp: 16,
    };
    assert_eq!((s.training, s.min_depth), (t, 2));
    let rooms = load(&scenes_dir().join("rooms.toml")).unwrap().1;
    assert_eq!(rooms.training.grid, 4);
    let in_file = text.replace("[render]\n", "[render]\ntrained_grid = 0\n");
    let e = parse_with(&in_file, SceneFormat::Toml, &f, &Overrides::default()).unwrap_err();
    assert_eq!(e.key, "render.trained_grid", "{e}");
    assert!(e.message.contains("1..=64"), "{e}");
    for (o, key) in [
        (
            Overrides {
                trained_floor: Some(0.0),
                ..Default::default()
            },
            "render.trained_floor",
        ),
        (
            Overrides {
                trained_spp: Some(0),
                ..Default::default()
            },
            "render.trained_spp",
        ),
        (
            // The scene's integrator is `direct`: one vertex.
            Overrides {
                min_depth: Some(2),
                ..Default::default()
            },
            "render.min_depth",
        ),
    ] {
        assert_eq!(with(o).unwrap_err().key, key);
    }
}

/// `array = {…}` repeats a light on a grid: copy (i, j, k) moved by (i, j, k)·step, in
/// x-fastest order after the lights before it, its emission and power scaled by one
/// factor from `power_range` (log-uniform, seeded: the same copies every time; without
/// a range, exact copies); errors name the array's key, with the file's line and column.
#[test]
fn light_arrays_repeat_a_light() {
    let mut v = base();
    v["lights"][0]["array"] = json!({"count": [3, 2, 1], "step": [1.5, -2, 0]});
    v["lights"].as_array_mut().unwrap().push(
        json!({"type": "disk", "center": [0, 0, 6], "radius": 0.2, "power": 4,
                     "array": {"count": [2, 1, 2], "step": [0, 0, 0.5],
                               "power_range": [0.5, 8], "seed": 3}}),
    );
    let (d, _) = load_value(v.clone(), &scenes_dir()).unwrap();
    let area = &d.lights.area;
    assert_eq!(area.len(), 6 + 4);
    let single = &load_value(base(), &scenes_dir()).unwrap().0.lights.area[0];
    for (k, l) in area[..6].iter().enumerate() {
        let (i, j) = ((k % 3) as f64, (k / 3) as f64);
        assert_eq!(l.p0, [1.5 * i, -2.0 * j, 5.0], "copy {k}");
        assert_eq!(
            (l.power, l.emission),
            (single.power, single.emission),
            "copy {k}"
        );
    }
    let first_disk = area[6].power[0] / area[6].emission[0];
    let mut factors = Vec::new();
    for (k, l) in area[6..].iter().enumerate() {
        assert_eq!(l.p0, [0.0, 0.0, 6.0 + 0.5 * (k / 2) as f64], "disk {k}");
        // Power and radiance scale together; the factors lie in the range.
        assert!((l.power[0] / l.emission[0] - first_disk).abs() < 1e-9 * first_disk);
        factors.push(l.power[0] / 4.0);
    }
    assert!(
        factors.iter().all(|&f| (0.5..=8.0).contains(&f)),
        "{factors:?}"
    );
    assert!(factors.windows(2).any(|w| w[0] != w[1]), "{factors:?}");
    assert_eq!(load_value(v.clone(), &scenes_dir()).unwrap().0, d, "seeded");
    let total: f64 = d.lights.area.iter().map(|l| l.selection_pmf).sum();
    assert!((total - 1.0).abs() < 1e-12);

    let with = |array: Value| {
        let mut v = base();
        v["lights"][0]["array"] = array;
        v
    };
    value_error(
        with(json!({"count": [3, 0, 1], "step": [1, 1, 1]})),
        "lights[0].array.count",
        "every count must be at least 1",
    );
    value_error(
        with(json!({"count": [1000, 1000, 2], "step": [1, 1, 1]})),
        "lights[0].array.count",
        "2000000 copies: a scene holds at most 1000000 lights",
    );
    value_error(
        with(json!({"count": [2, 1, 1], "step": [1, 1, 1], "power_range": [2, 1]})),
        "lights[0].array.power_range",
        "",
    );
    value_error(
        with(json!({"count": [2, 1, 1], "step": [1, 1, 1], "spacing": 2})),
        "lights[0].array.spacing",
        "unknown field `spacing`, expected one of `count`, `step`, `power_range`, `seed`",
    );
    // In a file: the line and column of the key.
    let text = "[camera]\neye = [0, -4, 1]\ntarget = [0, 0, 1]\n\n[[lights]]\ntype = \"sphere\"\n\
                center = [0, 0, 5]\nradius = 0.5\npower = 10\n\
                array = { count = [2, 0, 1], step = [1, 1, 1] }\n";
    let e = parse(text, SceneFormat::Toml, Path::new("a.toml")).expect_err("an error");
    assert_eq!(
        (e.line, e.key.as_str()),
        (10, "lights[0].array.count"),
        "{e}"
    );
    assert!(e.column > 1 && e.message.contains("at least 1"), "{e}");
}
