//! Render states over sample ranges: merging, serialisation and their errors.
//!
//! Two disjoint ranges rendered separately and merged must give the sums of one render of
//! their union: to 1e-12 relative (the additions happen in another order) for the
//! heuristics and the direct and uncorrelated optimal estimators, in `direct` and `path`.
//! The progressive estimators merge their moments and counts exactly and their estimate
//! validly but not identically (α of the second range comes from its own samples).

use mis::Method;
use render::integrator::{IntegratorKind, RenderOptions};
use render::render_loop::render_range;
use render::scene::{parse_scene, Scene, SceneFormat};
use render::{RenderState, Technique};
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// A small scene with two lights, a diffuse and a glossy sphere on a floor.
fn scene() -> Scene {
    let text = r#"
camera = { eye = [0, -5, 1.5], target = [0, 0, 0.5], fov = 40, resolution = [12, 9] }
materials.white = { type = "diffuse", reflectance = 0.7 }
materials.gold = { type = "conductor", metal = "copper", roughness = 0.2 }
objects = [
  { solid = "sphere([-0.6, 0, 0.5], 0.5)", material = "white" },
  { solid = "sphere([0.6, 0, 0.5], 0.5)", material = "gold" },
  { solid = "box(center = [0, 0, -0.05], size = [8, 8, 0.1])", material = "white" },
]
lights = [
  { type = "sphere", center = [1, -1, 3], radius = 0.3, power = 200 },
  { type = "rect", center = [-1, 0, 3], size = [0.6, 0.6], normal = [0, 0, -1], power = 100 },
]
"#;
    parse_scene(text, SceneFormat::Toml, Path::new("merge.toml"))
        .unwrap()
        .0
}

fn options(integrator: IntegratorKind, method: Method) -> RenderOptions {
    RenderOptions {
        integrator,
        method,
        techniques: vec![
            (Technique::Bsdf, 1),
            (Technique::LightPower, 1),
            (Technique::LightArea, 1),
        ],
        max_depth: 3,
        rr_depth: 1,
        seed: 17,
        tile_size: 5,
        threads: 2,
        scene_hash: 42,
        ..RenderOptions::default()
    }
}

fn run(scene: &Scene, o: &RenderOptions, samples: std::ops::Range<u32>) -> RenderState {
    render_range(scene, o, samples, &AtomicBool::new(false), &|_, _| {})
        .unwrap()
        .0
}

/// Largest |a − b| / max(|a|, |b|, 1e-300) over two slices.
fn max_rel(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / x.abs().max(y.abs()).max(1e-300))
        .fold(0.0, f64::max)
}

#[test]
fn two_ranges_merge_into_the_render_of_their_union() {
    let scene = scene();
    let exact = [
        Method::Balance,
        Method::Power,
        Method::OptimalDirect,
        Method::OptimalUncorrelated,
    ];
    // Per-light mode (2 lights) too: a block per depth and light.
    for (integrator, per_light) in [
        (IntegratorKind::Direct, 0),
        (IntegratorKind::Path, 0),
        (IntegratorKind::Direct, 2),
        (IntegratorKind::Path, 2),
    ] {
        for m in exact {
            let o = RenderOptions {
                per_light,
                ..options(integrator, m)
            };
            let whole = run(&scene, &o, 0..8);
            let mut a = run(&scene, &o, 0..3);
            let b = run(&scene, &o, 3..8);
            a.merge(&b).unwrap();
            assert_eq!(a.samples(), whole.samples());
            let rel = max_rel(a.data(), whole.data());
            assert!(rel < 1e-12, "{integrator} {m}: sums differ by {rel:e}");
            let (ia, iw) = (a.image(), whole.image());
            let rel = max_rel(ia.data(), iw.data());
            assert!(rel < 1e-12, "{integrator} {m}: images differ by {rel:e}");
            // Through the serialised form: bit for bit the same as in memory.
            let a2 = RenderState::from_bytes(&run(&scene, &o, 0..3).to_bytes()).unwrap();
            let mut a2 = a2;
            a2.merge(&RenderState::from_bytes(&b.to_bytes()).unwrap())
                .unwrap();
            assert!(
                a2 == a,
                "{integrator} {m}: the file round trip changed the sums"
            );
        }
    }
}

/// The progressive estimators: N and the moments of every depth merge exactly; the
/// merged estimate is finite and near the single run's (within the noise of 8 spp).
#[test]
fn progressive_states_merge_their_moments_exactly() {
    let scene = scene();
    for m in [Method::OptimalProgressive, Method::OptimalFull] {
        let o = options(IntegratorKind::Direct, m);
        let whole = run(&scene, &o, 0..8);
        let mut a = run(&scene, &o, 0..4);
        a.merge(&run(&scene, &o, 4..8)).unwrap();
        let r = *a.record();
        let (c, t) = (3, 3);
        // Block: [N | Σ F (C) | α (C·T) | moments].
        let moments = r.depth_light(0, 0).start + 1 + c + c * t..r.depth_light(0, 0).end;
        let s = r.stride();
        for (pa, pw) in a.data().chunks_exact(s).zip(whole.data().chunks_exact(s)) {
            assert_eq!(pa[0], pw[0], "{m}: sample counts");
            assert_eq!(
                pa[r.depth_light(0, 0).start],
                pw[r.depth_light(0, 0).start],
                "{m}: N_d"
            );
            let rel = max_rel(&pa[moments.clone()], &pw[moments.clone()]);
            assert!(rel < 1e-12, "{m}: moments differ by {rel:e}");
        }
        let (ia, iw) = (a.image(), whole.image());
        assert!(ia.data().iter().all(|v| v.is_finite()));
        let mean = |d: &[f64]| d.iter().sum::<f64>() / d.len() as f64;
        let (ma, mw) = (mean(ia.data()), mean(iw.data()));
        assert!((ma - mw).abs() < 0.1 * mw.abs(), "{m}: {ma} vs {mw}");
    }
}

#[test]
fn mismatched_or_overlapping_states_are_refused() {
    let scene = scene();
    let o = options(IntegratorKind::Direct, Method::OptimalDirect);
    let mut a = run(&scene, &o, 0..2);
    let overlap = run(&scene, &o, 1..3);
    let e = a.clone().merge(&overlap).unwrap_err();
    assert!(matches!(e, render::Error::Overlap(..)), "{e}");
    assert!(e.to_string().contains("overlap"), "{e}");
    let other_seed = run(
        &scene,
        &RenderOptions {
            seed: 18,
            ..o.clone()
        },
        2..4,
    );
    let e = a.clone().merge(&other_seed).unwrap_err().to_string();
    assert!(e.contains("seed"), "{e}");
    let other_scene = run(
        &scene,
        &RenderOptions {
            scene_hash: 43,
            ..o.clone()
        },
        2..4,
    );
    assert!(a
        .clone()
        .merge(&other_scene)
        .unwrap_err()
        .to_string()
        .contains("scene_hash"));
    let other_method = run(
        &scene,
        &options(IntegratorKind::Direct, Method::Balance),
        2..4,
    );
    assert!(a
        .clone()
        .merge(&other_method)
        .unwrap_err()
        .to_string()
        .contains("estimator"));
    let per_light = run(
        &scene,
        &RenderOptions {
            per_light: 2,
            ..o.clone()
        },
        2..4,
    );
    assert!(a
        .clone()
        .merge(&per_light)
        .unwrap_err()
        .to_string()
        .contains("per_light"));
    // A gap is allowed: ranges need not be adjacent.
    a.merge(&run(&scene, &o, 5..6)).unwrap();
    assert_eq!(a.samples(), &[0..2, 5..6]);
}

#[test]
fn damaged_state_files_are_errors() {
    let scene = scene();
    let o = options(IntegratorKind::Path, Method::OptimalUncorrelated);
    let bytes = run(&scene, &o, 0..2).to_bytes();
    assert!(RenderState::from_bytes(&bytes).is_ok());
    let mut flipped = bytes.clone();
    let k = bytes.len() - 20;
    flipped[k] ^= 1;
    let e = RenderState::from_bytes(&flipped).unwrap_err().to_string();
    assert!(e.contains("checksum"), "{e}");
    let e = RenderState::from_bytes(&bytes[..bytes.len() - 3])
        .unwrap_err()
        .to_string();
    assert!(e.contains("bytes"), "{e}");
    let e = RenderState::from_bytes(b"PNG....").unwrap_err().to_string();
    assert!(e.contains("truncated") || e.contains("magic"), "{e}");
    let mut wrong = bytes.clone();
    wrong[..8].copy_from_slice(b"NOTSTATE");
    assert!(RenderState::from_bytes(&wrong)
        .unwrap_err()
        .to_string()
        .contains("magic"));
    let mut version = bytes;
    version[8] = 9;
    assert!(RenderState::from_bytes(&version)
        .unwrap_err()
        .to_string()
        .contains("version 9"));
}

/// `bytes` (a state file) with its header edited by `edit` and its records replaced by
/// `words` where given, with a valid checksum, as a crafted file would have.
fn craft(bytes: &[u8], edit: impl Fn(&mut serde_json::Value), words: Option<&[f64]>) -> Vec<u8> {
    let hlen = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let text = std::str::from_utf8(&bytes[16..16 + hlen]).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(text).unwrap();
    edit(&mut v);
    let text = v.to_string();
    let mut crafted = bytes[..12].to_vec();
    crafted.extend_from_slice(&(text.len() as u32).to_le_bytes());
    crafted.extend_from_slice(text.as_bytes());
    match words {
        None => crafted.extend_from_slice(&bytes[16 + hlen..bytes.len() - 8]),
        Some(w) => {
            crafted.extend_from_slice(&(w.len() as u64).to_le_bytes());
            for x in w {
                crafted.extend_from_slice(&x.to_le_bytes());
            }
        }
    }
    let hash = render::fnv1a(&crafted);
    crafted.extend_from_slice(&hash.to_le_bytes());
    crafted
}

/// A state file whose header claims far more than its words hold — pixels, lights or
/// depths, with a valid checksum, as a crafted file would have — is an error before
/// anything is allocated for the claim (a 65 536 × 65 536 header once asked for 256 GiB
/// and aborted; `per_light` 10⁶ and `max_depth` 10⁵ did the same).
#[test]
fn a_header_claiming_more_than_the_file_holds_is_an_error() {
    let scene = scene();
    let o = options(IntegratorKind::Path, Method::OptimalUncorrelated);
    let bytes = run(&scene, &o, 0..1).to_bytes();
    let e = |edit: &dyn Fn(&mut serde_json::Value)| {
        RenderState::from_bytes(&craft(&bytes, edit, None))
            .unwrap_err()
            .to_string()
    };
    let big = e(&|v| {
        v["width"] = 65536.into();
        v["height"] = 65536.into();
    });
    assert!(
        big.contains("10800 words of stride 100; 65536×65536 pixels of stride 100 need"),
        "{big}"
    );
    let lights = e(&|v| v["per_light"] = 1_000_000.into());
    assert!(lights.contains("stride 96000004 need"), "{lights}");
    let depth = e(&|v| v["max_depth"] = 100_000.into());
    assert!(depth.contains("stride 3200004 need"), "{depth}");
    // Depths × lights past what a record can count: the options' error, not an overflow.
    let both = e(&|v| {
        v["per_light"] = u32::MAX.into();
        v["max_depth"] = 200_000_000.into();
    });
    assert!(
        both.contains("more than a pixel's record can hold"),
        "{both}"
    );
    // A header no render would have (checked as a render's options are).
    let none = e(&|v| v["techniques"] = serde_json::json!([]));
    assert!(
        none.contains("header: integrator path needs at least one technique"),
        "{none}"
    );
}

/// Sample counts that no render makes — NaN, negative, fractional, more than the ranges
/// hold — are errors naming the pixel.
#[test]
fn impossible_sample_counts_are_errors() {
    let scene = scene();
    for method in [
        Method::Balance,
        Method::OptimalUncorrelated,
        Method::OptimalDirect,
    ] {
        let o = options(IntegratorKind::Direct, method);
        let state = run(&scene, &o, 0..4);
        let bytes = state.to_bytes();
        let stride = state.record().stride();
        assert_eq!(RenderState::from_bytes(&bytes).unwrap(), state);
        let with = |at: usize, value: f64, partial: bool| {
            let mut w = state.data().to_vec();
            w[at] = value;
            RenderState::from_bytes(&craft(&bytes, |v| v["partial"] = partial.into(), Some(&w)))
        };
        // Pixel (1, 0): its N is word `stride`.
        for (n, partial) in [(f64::NAN, true), (-1.0, false), (2.5, true), (5.0, false)] {
            let e = with(stride, n, partial).unwrap_err().to_string();
            assert!(e.contains("pixel (1, 0) holds"), "{method:?} N = {n}: {e}");
        }
        // A MIS block counting more samples than its pixel, or NaN.
        let block = state.record().block_range(0).start;
        for n in [5.0, f64::NAN, -1.0] {
            let e = with(stride + block, n, false).unwrap_err().to_string();
            assert!(e.contains("pixel (1, 0), MIS block 0"), "{method:?}: {e}");
        }
        // What a stopped render leaves reads: pixel (0, 0) without samples.
        let mut w = state.data().to_vec();
        w[..stride].fill(0.0);
        let partial = craft(&bytes, |v| v["partial"] = true.into(), Some(&w));
        assert!(RenderState::from_bytes(&partial).is_ok());
    }
}

/// `RenderState::read` refuses what is not a regular file at once — a FIFO (which would
/// block for ever) and `/dev/zero` (which never ends) — and reads no further than the
/// magic of a file of another kind; each error names the file.
#[test]
fn only_regular_state_files_are_read() {
    let d = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("state-read");
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let fifo = d.join("pipe.state");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        let e = RenderState::read(&fifo).unwrap_err().to_string();
        assert!(
            e.contains("pipe.state") && e.contains("not a regular file"),
            "{e}"
        );
    }
    let e = RenderState::read("/dev/zero").unwrap_err().to_string();
    assert!(
        e.contains("/dev/zero") && e.contains("not a regular file"),
        "{e}"
    );
    let other = d.join("image.state");
    std::fs::write(&other, vec![0x89u8; 1 << 20]).unwrap();
    let e = RenderState::read(&other).unwrap_err().to_string();
    assert!(e.contains("image.state") && e.contains("magic"), "{e}");
    // A real state still reads.
    let scene = scene();
    let o = options(IntegratorKind::Direct, Method::Balance);
    let state = run(&scene, &o, 0..1);
    let good = d.join("good.state");
    state.write(&good).unwrap();
    // Cut short: refused from its header and size, before the records are read.
    let bytes = state.to_bytes();
    let short = d.join("short.state");
    std::fs::write(&short, &bytes[..bytes.len() - 100]).unwrap();
    let e = RenderState::read(&short).unwrap_err().to_string();
    assert!(
        e.contains("short.state")
            && e.contains(&format!(
                "the file is {} bytes, its header says {}",
                bytes.len() - 100,
                bytes.len()
            )),
        "{e}"
    );
    // A (sparse) 275 GB file whose header says so: refused for the memory, unread.
    let huge = craft(
        &bytes,
        |v| {
            v["width"] = 65536.into();
            v["height"] = 65536.into();
        },
        Some(&[]),
    );
    let words = 65536u64 * 65536 * state.record().stride() as u64;
    let head_len = huge.len() - 16;
    let path = d.join("huge.state");
    {
        use std::io::Write as _;
        let mut f = std::fs::File::create(&path).unwrap();
        f.write_all(&huge[..head_len]).unwrap();
        f.write_all(&words.to_le_bytes()).unwrap();
        f.set_len(head_len as u64 + 16 + 8 * words).unwrap();
    }
    let e = RenderState::read(&path).unwrap_err().to_string();
    assert!(
        e.contains("huge.state")
            && e.contains("the state is 256.0 GiB")
            && e.contains("more than the"),
        "{e}"
    );
    std::fs::remove_file(&path).unwrap();
    assert_eq!(
        RenderState::read(&good).unwrap().to_bytes(),
        state.to_bytes()
    );
}

/// A render stopped part-way is the whole image at fewer samples (every pixel has at
/// least one after the first pass), and [`render::resume`] renders what it lacks into
/// the state of the render that was never stopped, bit for bit — for the heuristics and
/// every optimal estimator, the progressive ones included (each pixel's samples still
/// run in index order on its own record).
#[test]
fn a_stopped_render_resumes_to_the_uninterrupted_one() {
    use std::sync::atomic::{AtomicU64, Ordering};
    let scene = scene();
    let pixels = 12 * 9;
    for (integrator, method) in [
        (IntegratorKind::Direct, Method::Power),
        (IntegratorKind::Direct, Method::OptimalProgressive),
        (IntegratorKind::Path, Method::OptimalUncorrelated),
        (IntegratorKind::Path, Method::OptimalFull),
    ] {
        let mut o = options(integrator, method);
        o.spp = 32;
        let whole = run(&scene, &o, 3..35);
        // Stopped once about 40 % of the samples are in (mid-pass, mid-tile).
        let stop = AtomicBool::new(false);
        let seen = AtomicU64::new(0);
        let (partial, stats) = render_range(&scene, &o, 3..35, &stop, &|done, total| {
            seen.store(done, Ordering::Relaxed);
            if done * 10 >= total * 4 {
                stop.store(true, Ordering::Relaxed);
            }
        })
        .unwrap();
        assert!(partial.is_partial() && stats.stopped, "{method:?}");
        let counts: Vec<u64> = (0..9)
            .flat_map(|y| (0..12).map(move |x| (x, y)))
            .map(|(x, y)| partial.iterations(x, y))
            .collect();
        assert!(counts.iter().all(|&n| n >= 1), "{method:?}: {counts:?}");
        assert!(counts.iter().sum::<u64>() < 32 * pixels, "{method:?}");
        // Through a file, as `render --resume` reads it.
        let partial = RenderState::from_bytes(&partial.to_bytes()).unwrap();
        let (resumed, stats) =
            render::resume(&scene, &o, &partial, &AtomicBool::new(false), &|_, _| {}).unwrap();
        assert!(!resumed.is_partial() && !stats.stopped, "{method:?}");
        assert_eq!(
            stats.samples + counts.iter().sum::<u64>(),
            32 * pixels,
            "{method:?}"
        );
        assert_eq!(resumed, whole, "{method:?}: resumed ≠ uninterrupted");
        // A finished state has nothing to resume; another render's state is refused.
        let e = render::resume(&scene, &o, &whole, &AtomicBool::new(false), &|_, _| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("nothing to resume"), "{e}");
        let other = RenderOptions {
            seed: 18,
            ..o.clone()
        };
        let e = render::resume(
            &scene,
            &other,
            &partial,
            &AtomicBool::new(false),
            &|_, _| {},
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("seed is 17 here and 18 there"), "{e}");
    }
}
