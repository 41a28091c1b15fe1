//! The `frepray` command end to end: pictures of every shared 3-D model and canonical
//! scene, `check` summaries, and clear errors on bad input.

use std::path::{Path, PathBuf};
use std::process::Command;

fn frepray() -> Command {
    Command::new(env!("CARGO_BIN_EXE_frepray"))
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Reads one channel of an EXR written by frepray.
fn channel(path: &Path, name: &str) -> Vec<f32> {
    let img = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    let layer = &img.layer_data[0];
    let ch = layer
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == name)
        .unwrap_or_else(|| panic!("{}: no channel {name}", path.display()));
    match &ch.sample_data {
        exr::prelude::FlatSamples::F32(v) => v.clone(),
        _ => panic!("channel {name} is not f32"),
    }
}

/// Every 3-D model renders, with the camera that frames its bounds: part of the image
/// is the object (finite depth, unit normals) and part is background.
#[test]
fn renders_every_model_framed() {
    let models = [
        "models/fidget/colonnade.vm",
        "models/fidget/tanglecube.vm",
        "models/canonical/s1_sphere.hf",
        "models/canonical/s2_csg.hf",
        "models/canonical/s3_blend.hf",
        "models/canonical/s4_gyroid.hf",
        "models/canonical/s5_twist.hf",
        "models/examples/bumpy_ball.frep",
        "models/examples/machined_part.frep",
        "models/examples/smooth_blob.frep",
        "models/examples/lattice.frep",
        "models/examples/capsule.hf",
        "models/examples/superellipsoid.hf",
    ];
    let dir = out_dir("models");
    for m in models {
        let input = root().join(m);
        let name = input.file_name().unwrap().to_string_lossy().to_string();
        for (look, chans) in [
            ("depth", vec!["depth"]),
            ("normals", vec!["normal.X", "normal.Y", "normal.Z"]),
        ] {
            let out = dir.join(format!("{name}.{look}.exr"));
            let st = frepray()
                .args(["render", "--quiet", "--width", "40", "--height", "32"])
                // One sample per pixel: each pixel's normal is one hit's, of unit length.
                .args(["--spp", "1", "--integrator", look, "-o"])
                .arg(&out)
                .arg(&input)
                .output()
                .unwrap();
            assert!(
                st.status.success(),
                "{m}: {}",
                String::from_utf8_lossy(&st.stderr)
            );
            let planes: Vec<Vec<f32>> = chans.iter().map(|c| channel(&out, c)).collect();
            assert_eq!(planes[0].len(), 40 * 32);
            if look == "depth" {
                // Depth is 0 where the ray misses (the AOV convention), > 0 on the model.
                let hits = planes[0].iter().filter(|d| **d > 0.0).count();
                let frac = hits as f64 / planes[0].len() as f64;
                assert!(
                    (0.05..0.95).contains(&frac),
                    "{m}: {frac} of the image is the object"
                );
                assert!(planes[0].iter().all(|d| d.is_finite() && *d >= 0.0));
            } else {
                for i in 0..planes[0].len() {
                    let n2: f32 = planes.iter().map(|p| p[i] * p[i]).sum();
                    assert!(n2 == 0.0 || (n2 - 1.0).abs() < 1e-4, "{m}: |n|² = {n2}");
                }
            }
        }
    }
}

/// Same picture at any thread count.
#[test]
fn thread_count_does_not_change_the_image() {
    let dir = out_dir("threads");
    let input = root().join("models/canonical/s4_gyroid.hf");
    let mut planes = vec![];
    for t in ["1", "2"] {
        let out = dir.join(format!("g{t}.exr"));
        let st = frepray()
            .args([
                "render",
                "--quiet",
                "--width",
                "32",
                "--height",
                "32",
                "--threads",
                t,
                "-o",
            ])
            .arg(&out)
            .arg(&input)
            .status()
            .unwrap();
        assert!(st.success());
        planes.push(channel(&out, "R"));
    }
    assert_eq!(planes[0], planes[1]);
}

#[test]
fn check_summarises_a_model() {
    let st = frepray()
        .arg("check")
        .arg(root().join("models/examples/bumpy_ball.frep"))
        .output()
        .unwrap();
    assert!(st.status.success());
    let text = String::from_utf8_lossy(&st.stdout);
    assert!(
        text.contains("perturbed quadrics: 1, perturbations: 3"),
        "{text}"
    );
    assert!(text.contains("bounds:"), "{text}");
    assert!(text.contains("dimensions:    3-D"), "{text}");
    // Which search its rays take: tanglecube is a quartic, colonnade is not a polynomial,
    // smooth_blob's ellipsoids fold into leaves along rays.
    for (m, want) in [
        (
            "fidget/tanglecube.vm",
            "expression solids: 1 polynomial (Bernstein search, degree 4), 0 by intervals",
        ),
        (
            "fidget/colonnade.vm",
            "expression solids: 0 polynomial (Bernstein search), 1 by intervals\n",
        ),
        (
            "examples/smooth_blob.frep",
            "1 by intervals (1 with polynomial leaves: 76 → 38 nodes a ray)",
        ),
    ] {
        let st = frepray()
            .arg("check")
            .arg(root().join(format!("models/{m}")))
            .output()
            .unwrap();
        assert!(st.status.success());
        let text = String::from_utf8_lossy(&st.stdout);
        assert!(text.contains(want), "{m}: {text}");
    }
}

/// A malformed model names file, line and column, exits non-zero, writes nothing.
#[test]
fn malformed_input_is_a_clear_error() {
    let dir = out_dir("bad");
    let bad = dir.join("bad.vm");
    std::fs::write(&bad, "_x var-x\n_y frobnicate _x\n").unwrap();
    let out = dir.join("never.png");
    for args in [vec!["check"], vec!["render", "-o", out.to_str().unwrap()]] {
        let st = frepray().args(&args).arg(&bad).output().unwrap();
        assert!(!st.status.success());
        let err = String::from_utf8_lossy(&st.stderr);
        assert!(err.contains("bad.vm:2:"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    assert!(!out.exists());
    // An unknown output format is refused before any work.
    let st = frepray()
        .args(["render", "-o"])
        .arg(dir.join("x.jpg"))
        .arg(root().join("models/canonical/s1_sphere.hf"))
        .output()
        .unwrap();
    assert!(!st.status.success());
    assert!(String::from_utf8_lossy(&st.stderr).contains("expected a .png or .exr"));
}

/// One render, several outputs: the PNG and the EXR show the same film.
#[test]
fn several_outputs_from_one_render() {
    let dir = out_dir("multi");
    let (exr, png) = (dir.join("m.exr"), dir.join("m.png"));
    let st = frepray()
        .args(["render", "--quiet", "--width", "24", "--height", "16", "-o"])
        .arg(&exr)
        .arg("-o")
        .arg(&png)
        .arg(root().join("models/canonical/s2_csg.hf"))
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    assert_eq!(channel(&exr, "R").len(), 24 * 16);
    assert!(std::fs::metadata(&png).unwrap().len() > 0);
}

/// A scene file renders through the light-transport path with overrides, and a bad
/// override is a clear error.
#[test]
fn renders_a_scene_with_overrides() {
    let dir = out_dir("scene");
    let out = dir.join("cornell.exr");
    let st = frepray()
        .args([
            "render", "--quiet", "--width", "16", "--height", "12", "--spp", "2",
        ])
        .args([
            "--estimator",
            "optimal-direct",
            "--integrator",
            "direct",
            "--aovs",
            "depth",
            "-o",
        ])
        .arg(&out)
        .arg(root().join("scenes/cornell.toml"))
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(
        err.contains("MSamples/s") && err.contains("shadow"),
        "{err}"
    );
    // Start-up is reported too, as a time.
    let load = err
        .lines()
        .find_map(|l| l.strip_prefix("scene: loaded in "))
        .and_then(|l| l.split(' ').next()?.parse::<f64>().ok());
    assert!(load.is_some_and(|t| (0.0..600.0).contains(&t)), "{err}");
    let depth = channel(&out, "depth");
    assert!(depth.iter().any(|d| d.is_finite() && *d > 0.0));
    // `--mis`, the older name of `--estimator`, is still taken.
    let bad = frepray()
        .args(["render", "--quiet", "--mis", "optimal-guess", "-o"])
        .arg(dir.join("never.exr"))
        .arg(root().join("scenes/cornell.toml"))
        .output()
        .unwrap();
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("optimal-direct"),
        "lists the valid names: {err}"
    );
    assert!(!dir.join("never.exr").exists());
}

/// A render split into sample ranges in separate processes and merged through state
/// files gives the sums of one render of the union (1e-12 relative), and the merged
/// image equals the whole render's; merging a range twice is refused.
#[test]
fn split_render_merges_through_state_files() {
    let dir = out_dir("split");
    let scene = root().join("scenes/many-lights.toml");
    let render = |range: Option<&str>, outs: &[&str]| {
        let mut c = frepray();
        c.args([
            "render", "--quiet", "--width", "20", "--height", "14", "--spp", "6",
        ])
        .args(["--estimator", "optimal-direct"]);
        if let Some(r) = range {
            c.args(["--samples", r]);
        }
        for o in outs {
            c.arg("-o").arg(dir.join(o));
        }
        let st = c.arg(&scene).output().unwrap();
        assert!(
            st.status.success(),
            "{}",
            String::from_utf8_lossy(&st.stderr)
        );
    };
    render(Some("0..2"), &["a.state"]);
    render(Some("2..6"), &["b.state"]);
    render(None, &["whole.state", "whole.exr"]);
    let st = frepray()
        .arg("merge")
        .arg(dir.join("a.state"))
        .arg(dir.join("b.state"))
        .arg("-o")
        .arg(dir.join("merged.state"))
        .arg("-o")
        .arg(dir.join("merged.exr"))
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let merged = frepray::RenderState::read(dir.join("merged.state")).unwrap();
    let whole = frepray::RenderState::read(dir.join("whole.state")).unwrap();
    assert_eq!(merged.samples(), std::slice::from_ref(&(0..6)));
    for (a, b) in merged.data().iter().zip(whole.data()) {
        assert!((a - b).abs() <= 1e-12 * a.abs().max(b.abs()), "{a} vs {b}");
    }
    for c in ["R", "G", "B"] {
        let (m, w) = (
            channel(&dir.join("merged.exr"), c),
            channel(&dir.join("whole.exr"), c),
        );
        for (a, b) in m.iter().zip(&w) {
            assert!(
                (a - b).abs() <= 1e-6 * a.abs().max(b.abs()),
                "{c}: {a} vs {b}"
            );
        }
    }
    let twice = frepray()
        .arg("merge")
        .arg(dir.join("a.state"))
        .arg(dir.join("a.state"))
        .arg("-o")
        .arg(dir.join("never.exr"))
        .output()
        .unwrap();
    assert!(!twice.status.success());
    assert!(String::from_utf8_lossy(&twice.stderr).contains("overlap"));
    assert!(!dir.join("never.exr").exists());

    // Each EXR records in its header how it was made, and `check` prints it.
    let read = |name: &str| frepray::Image::read_exr(dir.join(name)).unwrap();
    let (w, m) = (read("whole.exr"), read("merged.exr"));
    let at = |img: &frepray::Image, name: &str| {
        img.attribute(&format!("frepray.{name}"))
            .unwrap_or_else(|| panic!("no attribute frepray.{name}"))
            .to_string()
    };
    let settings: serde_json::Value = serde_json::from_str(&at(&w, "settings")).unwrap();
    assert_eq!(settings["estimator"], "optimal-direct");
    assert_eq!(
        (settings["width"].as_u64(), settings["seed"].as_u64()),
        (Some(20), Some(whole.header().seed))
    );
    assert_eq!(at(&w, "settings"), at(&m, "settings"));
    assert_eq!(
        at(&w, "scene_hash"),
        format!("{:016x}", whole.header().scene_hash)
    );
    assert_ne!(whole.header().scene_hash, 0);
    assert_eq!(
        (at(&w, "samples"), at(&m, "samples")),
        ("0..6".into(), "0..6".into())
    );
    assert_eq!(at(&w, "backend"), "cpu");
    assert!(at(&w, "input").ends_with("many-lights.toml"));
    assert_eq!(at(&w, "samples_rendered"), (20 * 14 * 6).to_string());
    assert!(at(&w, "statistics").contains("1680 samples"));
    assert_eq!(
        w.attribute("software"),
        Some(concat!("frepray ", env!("CARGO_PKG_VERSION")))
    );
    let from = at(&m, "merged_from");
    assert!(
        from.contains("a.state") && from.contains("b.state"),
        "{from}"
    );
    assert_eq!(m.attribute("frepray.statistics"), None);
    let o = frepray()
        .arg("check")
        .arg(dir.join("whole.exr"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        text.contains("size:          20×14") && text.contains("frepray.estimator: optimal-direct"),
        "{text}"
    );
}

/// `--dump-scene` writes the resolved scene (overrides applied) as JSON and, without
/// `-o`, renders nothing; an invalid override is reported against its flag.
#[test]
fn dumps_the_resolved_scene_as_json() {
    let dir = out_dir("dump");
    let json = dir.join("cornell.json");
    let st = frepray()
        .args(["render", "--quiet", "--width", "8", "--dump-scene"])
        .arg(&json)
        .arg(root().join("scenes/cornell.toml"))
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["camera"]["width"], 8);
    let objects = v["objects"].as_array().unwrap();
    assert!(!objects.is_empty());
    assert_eq!(v["solids"].as_array().unwrap().len(), objects.len());
    let materials = v["materials"].as_array().unwrap().len() as u64;
    assert!(objects
        .iter()
        .all(|o| o["material"].as_u64().unwrap() < materials));
    let cdf = v["lights"]["by_power"]["cdf"].as_array().unwrap();
    assert_eq!(cdf.last().unwrap().as_f64(), Some(1.0));
    assert!(
        std::fs::read_dir(&dir).unwrap().count() == 1,
        "only the dump"
    );
    let bad = frepray()
        .args(["render", "--quiet", "--spp", "0", "--dump-scene"])
        .arg(dir.join("never.json"))
        .arg(root().join("scenes/cornell.toml"))
        .output()
        .unwrap();
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("--spp: render.spp: spp must be at least 1"),
        "{err}"
    );
    assert!(!dir.join("never.json").exists());
}

/// `frepray check … | head -1`: a closed stdout ends the program quietly, no panic.
#[test]
fn a_closed_stdout_is_not_a_panic() {
    let mut child = frepray()
        .arg("check")
        .arg(root().join("models/examples/bumpy_ball.frep"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Close the reading end before the model is parsed and the summary printed.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(out.status.code(), Some(0), "{err}");
}

/// A half-space is framed around its plane (and says it is clipped), not from 660
/// units away; a 2-D Fidget-style model seen from the top through the orthographic lens
/// fills its outline (the disc covers π/4 of its square); `--view` and
/// `--orthographic` are refused for scenes.
#[test]
fn views_of_unbounded_and_2d_models() {
    let dir = out_dir("views");
    let half = dir.join("half.hf");
    std::fs::write(&half, "half(x[3], a[1]) { half = -x[3]; }\n").unwrap();
    let o = frepray()
        .arg("render")
        .arg(&half)
        .args([
            "--width",
            "16",
            "--height",
            "16",
            "--integrator",
            "depth",
            "-o",
        ])
        .arg(dir.join("half.exr"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("unbounded along x, y"), "{err}");
    let depth = channel(&dir.join("half.exr"), "depth");
    // Every ray that looks down hits the plane a few units away.
    let hits: Vec<f32> = depth.iter().copied().filter(|&d| d > 0.0).collect();
    assert!(hits.len() > depth.len() / 2, "{depth:?}");
    assert!(hits.iter().all(|&d| d < 30.0), "{hits:?}");

    let disc = dir.join("disc.vm");
    std::fs::write(
        &disc,
        "_0 var-x\n_1 var-y\n_2 square _0\n_3 square _1\n_4 add _2 _3\n_5 const 0.25\n_6 sub _4 _5\n",
    )
    .unwrap();
    let o = frepray()
        .arg("render")
        .arg(&disc)
        .args(["--view", "top", "--orthographic", "--integrator", "normals"])
        .args(["--width", "40", "--height", "40", "-o"])
        .arg(dir.join("disc.exr"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let nz = channel(&dir.join("disc.exr"), "normal.Z");
    let cap = nz.iter().filter(|&&z| z > 0.999).count() as f64 / nz.len() as f64;
    // π/4 of the outline, which fills 1/1.05² of the image.
    let want = std::f64::consts::FRAC_PI_4 / 1.05f64.powi(2);
    assert!((cap - want).abs() < 0.05, "{cap} vs {want}");
    // Without a view, a 2-D model is seen so by default, and `check` says it is 2-D.
    let o = frepray()
        .arg("render")
        .arg(&disc)
        .args([
            "--integrator",
            "normals",
            "--width",
            "40",
            "--height",
            "40",
            "-o",
        ])
        .arg(dir.join("disc-default.exr"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && err.contains("a 2-D model"), "{err}");
    assert_eq!(channel(&dir.join("disc-default.exr"), "normal.Z"), nz);
    let o = frepray().arg("check").arg(&disc).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("dimensions:    2-D"), "{text}");

    let o = frepray()
        .arg("render")
        .arg(root().join("scenes/cornell.toml"))
        .args(["--view", "top", "-o"])
        .arg(dir.join("scene.png"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("--view applies to model files"),
        "{err}"
    );
}

/// `--exposure` and `--tonemap` change the PNG, never the EXR; a scene's
/// `[film] exposure` is its default; clipping is reported.
#[test]
fn exposure_and_tone_mapping_shape_the_png_only() {
    let dir = out_dir("exposure");
    let scene = root().join("scenes/cornell.toml");
    let render = |name: &str, extra: &[&str]| {
        let o = frepray()
            .arg("render")
            .arg(&scene)
            .args(["--width", "24", "--height", "18", "--spp", "2"])
            .args(extra)
            .arg("-o")
            .arg(dir.join(format!("{name}.png")))
            .arg("-o")
            .arg(dir.join(format!("{name}.exr")))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{err}");
        let png = std::fs::read(dir.join(format!("{name}.png"))).unwrap();
        (png, channel(&dir.join(format!("{name}.exr")), "R"), err)
    };
    let (plain, plain_r, _) = render("plain", &[]);
    let (dark, dark_r, _) = render("dark", &["--exposure", "-3"]);
    let (soft, soft_r, soft_err) = render("soft", &["--tonemap", "reinhard"]);
    assert_eq!(plain_r, dark_r);
    assert_eq!(plain_r, soft_r);
    assert_ne!(plain, dark);
    assert_ne!(plain, soft);
    assert!(!soft_err.contains("clip"), "{soft_err}");
    let (blown, _, err) = render("blown", &["--exposure", "8"]);
    assert!(err.contains("% of pixels clip"), "{err}");
    assert_ne!(blown, plain);
    // The scene's own [film] exposure is the default, and the flag overrides it.
    let text = std::fs::read_to_string(&scene).unwrap();
    let film = dir.join("film.toml");
    let text = text.replace("[camera]", "[film]\nexposure = -3\n\n[camera]");
    let text = text.replace(
        "\"models/",
        &format!("\"{}/scenes/models/", root().display()),
    );
    std::fs::write(&film, text).unwrap();
    let o = frepray()
        .arg("render")
        .arg(&film)
        .args(["--width", "24", "--height", "18", "--spp", "2", "-o"])
        .arg(dir.join("film.png"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read(dir.join("film.png")).unwrap(), dark);
}

/// `depth` and `normals` renders write a PNG beside the EXR (scenes and models): at one
/// sample per pixel, black exactly where the EXR says the ray escaped, depth as grey
/// from white (nearest) to 20 % (farthest), normals as (n + 1)/2.
#[test]
fn depth_and_normals_write_png_views() {
    let dir = out_dir("values-png");
    for input in ["scenes/cornell.toml", "models/examples/bumpy_ball.frep"] {
        for integrator in ["depth", "normals"] {
            let (png, exr) = (dir.join("v.png"), dir.join("v.exr"));
            let o = frepray()
                .arg("render")
                .arg(root().join(input))
                .args(["--integrator", integrator, "--spp", "1", "--quiet"])
                .args(["--width", "24", "--height", "18", "-o"])
                .arg(&png)
                .arg("-o")
                .arg(&exr)
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(o.status.success(), "{input} {integrator}: {err}");
            let (w, h, img) = frepray::png_io::read_rgb8_file(&png).unwrap();
            assert_eq!((w, h), (24, 18));
            let rgb: Vec<Vec<f32>> = ["R", "G", "B"].map(|c| channel(&exr, c)).to_vec();
            let (near, far) = rgb[0]
                .iter()
                .filter(|&&d| d > 0.0)
                .fold((f32::MAX, 0f32), |(a, b), &d| (a.min(d), b.max(d)));
            for (i, p) in img.chunks_exact(3).enumerate() {
                let v = [rgb[0][i], rgb[1][i], rgb[2][i]];
                let escaped = v.iter().all(|&c| c == 0.0);
                assert_eq!(p == [0, 0, 0], escaped, "{input} {integrator} pixel {i}");
                if escaped {
                    continue;
                }
                let want = if integrator == "depth" {
                    let g = 1.0 - 0.8 * (v[0] - near) / (far - near);
                    [g; 3]
                } else {
                    v.map(|n| 0.5 * (n + 1.0))
                };
                for c in 0..3 {
                    let d = (f32::from(p[c]) / 255.0 - want[c]).abs();
                    assert!(
                        d <= 1.0 / 255.0,
                        "{input} {integrator} pixel {i}: {p:?} {want:?}"
                    );
                }
            }
        }
    }
}

/// `--backend gpu` refuses, before any work and naming the feature, a scene the GPU back
/// end does not cover (a power beyond ±255; a triangle mesh; a mesh light; AOVs in a
/// scene with media), exiting non-zero; `--backend auto`
/// renders it on the CPU and says why; without any adapter both say what to install.
#[test]
fn gpu_backend_refuses_by_name_and_auto_falls_back() {
    let d = out_dir("gpu-backend");
    std::fs::write(
        d.join("tri.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 0 1 0.5\nf 1 2 3\n",
    )
    .unwrap();
    let head = "[camera]\neye = [0, -4, 1]\ntarget = [0, 0, 0]\n\n\
         [materials.clay]\ntype = \"diffuse\"\nreflectance = 0.5\n\n";
    let lamp = "[[lights]]\ntype = \"sphere\"\ncenter = [2, -2, 3]\nradius = 0.3\npower = 100\n";
    let ball = "[[objects]]\nsolid = \"sphere([0, 0, 0], 1)\"\nmaterial = \"clay\"\n\n";
    // (scene, what the GPU refuses by name)
    let cases = [
        (
            format!(
                "{head}[[objects]]\nsolid = \"sphere([0, 0, 0], 1) - 0.05 * (0.5 * x)^300\"\n\
                 material = \"clay\"\n\n{lamp}"
            ),
            "PowI",
        ),
        (
            format!("{head}[[objects]]\nmodel = \"tri.obj\"\nmaterial = \"clay\"\n\n{lamp}"),
            "triangle mesh",
        ),
        (
            format!(
                "{head}{ball}[[lights]]\ntype = \"mesh\"\nfile = \"tri.obj\"\npower = 50\n\
                 transform = [{{ translate = [0, 0, 2] }}]\n"
            ),
            "mesh lights",
        ),
        (
            // Media render on the GPU, but for AOVs (the CPU's first hit is a walk's end).
            format!(
                "{head}[render]\naovs = [\"depth\"]\n\n[media.smoke]\nsigma_a = 0.1\nsigma_s = 1\n\n\
                 [materials.none]\ntype = \"interface\"\n\n\
                 [[objects]]\nsolid = \"sphere([0, 0, 0], 1)\"\nmaterial = \"none\"\n\
                 medium = \"smoke\"\n\n{lamp}"
            ),
            "AOVs in a scene with participating media",
        ),
    ];
    let small = ["--width", "16", "--height", "12", "--spp", "1", "--quiet"];
    for (k, (text, refused)) in cases.iter().enumerate() {
        let scene = d.join(format!("scene{k}.toml"));
        std::fs::write(&scene, text).unwrap();
        let gpu = frepray()
            .args(["render", scene.to_str().unwrap(), "--backend", "gpu", "-o"])
            .arg(d.join("g.exr"))
            .args(small)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&gpu.stderr);
        assert!(!gpu.status.success());
        assert!(
            err.contains(refused) || err.contains("no GPU adapter"),
            "{err}"
        );
        assert!(!d.join("g.exr").exists());
        let auto = frepray()
            .args(["render", scene.to_str().unwrap(), "--backend", "auto", "-o"])
            .arg(d.join("a.exr"))
            .args(small)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&auto.stderr);
        assert!(auto.status.success(), "{err}");
        assert!(err.contains("--backend auto renders on the CPU"), "{err}");
        assert!(d.join("a.exr").exists());
        std::fs::remove_file(d.join("a.exr")).unwrap();
    }
}

/// A bare model's preview is a scene like any other: `--dump-scene` writes its resolved
/// data (the model, its material, key light and sky), and it renders on the GPU, where
/// its image agrees with the CPU's (same seed: the channel means within 2 %), or is
/// refused naming what is missing; `--backend auto` falls back to the CPU for a model
/// the GPU does not cover (`exp`), and says why.
#[test]
fn bare_models_render_on_either_backend() {
    let d = out_dir("model-backend");
    let model = d.join("ball.frep");
    std::fs::write(&model, "output sphere([0, 0, 0], 1)\n").unwrap();
    let small = ["--width", "16", "--height", "16", "--spp", "4"];
    let run = |backend: &str, out: &Path, extra: &[&str]| {
        frepray()
            .args([
                "render",
                model.to_str().unwrap(),
                "--backend",
                backend,
                "-o",
            ])
            .arg(out)
            .args(small)
            .args(extra)
            .output()
            .unwrap()
    };
    let dump = d.join("ball.json");
    let cpu = run(
        "cpu",
        &d.join("c.exr"),
        &["--dump-scene", dump.to_str().unwrap()],
    );
    assert!(
        cpu.status.success(),
        "{}",
        String::from_utf8_lossy(&cpu.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&dump).unwrap()).unwrap();
    assert_eq!(json["objects"][0]["name"], "model");
    assert_eq!(json["lights"]["delta"][0]["kind"], "point");
    assert_eq!(
        json["environment"]["radiance"],
        serde_json::json!([0.25, 0.25, 0.25])
    );
    let gpu = run("gpu", &d.join("g.exr"), &[]);
    let err = String::from_utf8_lossy(&gpu.stderr);
    if gpu.status.success() {
        for c in ["R", "G", "B"] {
            let mean = |p: &Path| {
                let v = channel(p, c);
                v.iter().map(|&x| f64::from(x)).sum::<f64>() / v.len() as f64
            };
            let (a, b) = (mean(&d.join("c.exr")), mean(&d.join("g.exr")));
            assert!(
                a > 0.05 && (a - b).abs() <= 0.02 * a,
                "{c}: CPU {a}, GPU {b}"
            );
        }
    } else {
        assert!(err.contains("no GPU adapter"), "{err}");
        assert!(!d.join("g.exr").exists());
    }
    let wavy = d.join("wavy.frep");
    std::fs::write(
        &wavy,
        "output sphere([0, 0, 0], 1) - 0.05 * (0.5 * x)^300\n",
    )
    .unwrap();
    let auto = frepray()
        .args(["render", wavy.to_str().unwrap(), "--backend", "auto", "-o"])
        .arg(d.join("a.png"))
        .args(small)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&auto.stderr);
    assert!(auto.status.success(), "{err}");
    assert!(err.contains("--backend auto renders on the CPU"), "{err}");
    assert!(d.join("a.png").exists());
}

/// `render --stage-times` prints the CPU's stage times after the render, and the image is
/// the one a render without timers writes, byte for byte.
#[test]
fn render_stage_times() {
    let dir = out_dir("stage-times");
    let scene = root().join("scenes/many-lights.toml");
    let run = |extra: &[&str], out: &Path| {
        let o = frepray()
            .arg("render")
            .arg(&scene)
            .args(["--spp", "2", "--width", "32", "--height", "24", "-o"])
            .arg(out)
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    let (timed, plain) = (dir.join("timed.exr"), dir.join("plain.exr"));
    let err = run(&["--stage-times"], &timed);
    let line = err
        .lines()
        .find(|l| l.starts_with("CPU stages"))
        .unwrap_or_else(|| panic!("no stage line in:\n{err}"));
    for stage in [
        "camera ray generation",
        "camera rays",
        "shade",
        "shadow rays",
    ] {
        assert!(line.contains(stage), "{line}");
    }
    assert!(!run(&[], &plain).contains("CPU stages"));
    // The same pixels (the headers record each render's own statistics).
    let pixels = |p: &Path| frepray::Image::read_exr(p).unwrap().data().to_vec();
    assert_eq!(pixels(&timed), pixels(&plain));
}

/// Without a runtime directory (a container, a CI job), `frepray` makes a private one
/// under the temporary directory and hands it to Mesa's Vulkan drivers, which otherwise
/// print "XDG_RUNTIME_DIR is invalid or not set" on every run that touches the GPU.
#[test]
fn a_private_runtime_directory_is_made_where_there_is_none() {
    use std::os::unix::fs::PermissionsExt;
    let tmp = out_dir("runtime-dir");
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let out = frepray()
        .env_remove("XDG_RUNTIME_DIR")
        .env("TMPDIR", &tmp)
        .arg("check")
        .arg(root().join("scenes/cornell.toml"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let made: Vec<_> = std::fs::read_dir(&tmp)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(made.len(), 1, "{made:?}");
    let name = made[0].file_name().unwrap().to_string_lossy().into_owned();
    assert!(name.starts_with("frepray-runtime-"), "{name}");
    let mode = std::fs::metadata(&made[0]).unwrap().permissions().mode();
    assert_eq!(mode & 0o777, 0o700, "{mode:o}");
    // A runtime directory that exists is left as it is.
    let own = tmp.join("own");
    std::fs::create_dir_all(&own).unwrap();
    let out = frepray()
        .env("XDG_RUNTIME_DIR", &own)
        .env("TMPDIR", &own)
        .arg("check")
        .arg(root().join("scenes/cornell.toml"))
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(std::fs::read_dir(&own).unwrap().count(), 0);
}

/// `frepray gpu list` prints the adapters (lavapipe in CI), and `--gpu-options
/// adapter=N` past them is an error that lists them; a non-number is an error naming the
/// option. Without any adapter, the list says how to get one.
#[test]
fn gpu_adapters_are_listed_and_chosen_by_index() {
    let list = frepray().args(["gpu", "list"]).output().unwrap();
    let out = String::from_utf8_lossy(&list.stdout);
    let err = String::from_utf8_lossy(&list.stderr);
    if !list.status.success() {
        assert!(err.contains("no GPU adapter found"), "{err}");
        return;
    }
    let first = out.lines().next().unwrap_or_default();
    assert!(first.starts_with("0: ") && first.contains("f64 "), "{out}");
    let count = out.lines().count();
    let scene = root().join("scenes/cornell.toml");
    let d = out_dir("gpu-adapter");
    let render = |options: &str| {
        frepray()
            .args(["render", scene.to_str().unwrap(), "--backend", "gpu"])
            .args([
                "--gpu-options",
                options,
                "--width",
                "8",
                "--height",
                "6",
                "-o",
            ])
            .arg(d.join("x.exr"))
            .output()
            .unwrap()
    };
    let past = render(&format!("adapter={count}"));
    let err = String::from_utf8_lossy(&past.stderr);
    assert!(!past.status.success());
    assert!(
        err.contains(&format!(
            "GPU adapter {count} asked for; the adapters are: 0: "
        )),
        "{err}"
    );
    let bad = render("adapter=first");
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        !bad.status.success() && err.contains("adapter=first"),
        "{err}"
    );
    assert!(!d.join("x.exr").exists());
}

/// `frepray mesh` writes a closed mesh of a model as OBJ and STL (the same triangles),
/// its vertices on the model's surface; bad outputs and resolutions are clear errors
/// that write nothing.
#[test]
fn meshes_a_model_to_obj_and_stl() {
    let dir = out_dir("mesh");
    let model = root().join("models/examples/bumpy_ball.frep");
    let (obj, stl) = (dir.join("ball.obj"), dir.join("ball.stl"));
    let o = frepray()
        .args(["mesh", "--resolution", "24", "-o"])
        .arg(&obj)
        .arg("-o")
        .arg(&stl)
        .arg(&model)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&obj).unwrap();
    let vertices: Vec<[f64; 3]> = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let faces = text.lines().filter(|l| l.starts_with("f ")).count();
    assert!(faces > 1000, "{faces} triangles");
    assert_eq!(
        std::fs::metadata(&stl).unwrap().len(),
        84 + 50 * faces as u64
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains(&format!("{} vertices, {faces} triangles", vertices.len())),
        "{stderr}"
    );
    let f = frepray::model::read_file(&model)
        .unwrap()
        .shape
        .to_tree()
        .unwrap();
    let f = frepray::model::Expr::new(&f);
    for v in &vertices {
        let (value, g) = f.gradient(*v);
        let g = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        assert!(value.abs() / g < 1e-9, "{v:?}: F = {value}");
    }
    for (args, want) in [
        (vec!["--resolution", "0"], "resolution 0"),
        (vec!["--resolution", "24"], "unknown mesh format"),
    ] {
        let bad = if want.contains("format") {
            dir.join("x.ply")
        } else {
            dir.join("x.obj")
        };
        let o = frepray()
            .arg("mesh")
            .args(&args)
            .arg("-o")
            .arg(&bad)
            .arg(&model)
            .output()
            .unwrap();
        assert!(!o.status.success());
        assert!(
            String::from_utf8_lossy(&o.stderr).contains(want),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(!bad.exists());
    }
}
