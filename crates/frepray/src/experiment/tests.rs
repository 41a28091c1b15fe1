//! The driver against a synthetic renderer of known noise: a smooth image plus
//! Gaussian noise of standard deviation σ_e / √spp per estimator e, taking
//! spp × τ_e seconds.

use super::*;
use std::cell::RefCell;
use std::fs;

const W: u32 = 64;
const H: u32 = 48;

fn truth(i: usize, c: usize) -> f64 {
    let (x, y) = ((i % W as usize) as f64, (i / W as usize) as f64);
    // Some negative values: the metrics must not clamp.
    0.6 + 0.5 * (0.1 * x + 0.7 * c as f64).sin() * (0.13 * y).cos() - 0.02 * c as f64
}

fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A standard normal variate from a hash of `key` (Box–Muller).
fn gauss(key: u64) -> f64 {
    let a = splitmix(key);
    let b = splitmix(a);
    let u1 = ((a >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    let u2 = (b >> 11) as f64 / (1u64 << 53) as f64;
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// (σ, seconds per sample) of each estimator.
fn params(est: &str) -> (f64, f64) {
    match est {
        "balance" => (0.5, 0.010),
        "optimal" => (0.1, 0.011),
        "power" => (0.3, 0.0105),
        _ => (1.0, 0.02),
    }
}

fn synthetic(est: &str, spp: u32, seed: u64) -> (Image, f64) {
    let (sigma, tau) = params(est);
    let tag = est.bytes().fold(0u64, |h, b| splitmix(h ^ b as u64));
    let base = splitmix(seed ^ splitmix(tag ^ splitmix(spp as u64)));
    let s = sigma / (spp as f64).sqrt();
    let n = (W * H) as usize;
    let rgb = (0..n)
        .map(|i| {
            let k = base.wrapping_add(3 * i as u64);
            [0, 1, 2].map(|c| truth(i, c) + s * gauss(k + c as u64))
        })
        .collect();
    let img = Image {
        width: W,
        height: H,
        rgb,
    };
    (img, spp as f64 * tau)
}

/// The synthetic renderer, counting its calls; stops (returns None) at call
/// `stop_at` (0-based) if set. Its processor clock reads 0 before a render and the
/// render's time after it (the driver reads it once each side), so that processor
/// times equal the synthetic times exactly.
#[derive(Default)]
struct Synth {
    calls: Vec<(String, u32, u64)>,
    stop_at: Option<usize>,
    clock: f64,
    after: std::cell::Cell<bool>,
    /// Relative spread of the render times (load on a shared machine), from the seed.
    time_jitter: f64,
}

impl Renderer for Synth {
    fn render(
        &mut self,
        est: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, crate::Error> {
        if self.stop_at == Some(self.calls.len()) {
            return Ok(None);
        }
        self.calls.push((est.to_string(), spp, seed));
        let (img, t) = synthetic(est, spp, seed);
        let tag = est
            .bytes()
            .fold(seed ^ spp as u64, |h, b| splitmix(h ^ b as u64));
        let t = t * (1.0 + self.time_jitter * gauss(tag).clamp(-2.0, 2.0));
        self.clock = t;
        Ok(Some((img, t)))
    }

    fn cpu_clock(&self) -> Option<f64> {
        let after = self.after.replace(!self.after.get());
        Some(if after { self.clock } else { 0.0 })
    }

    /// A quarter of the variance stays with rays through pixel centres (the
    /// directions' share), from noise independent of the jittered render's.
    fn render_pixel_centers(
        &mut self,
        est: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, ExperimentError> {
        self.calls.push((format!("{est} centred"), spp, seed));
        let (mut img, t) = synthetic(est, spp, seed ^ 0xC3A5_C85C_97CB_3127);
        for (i, p) in img.rgb.iter_mut().enumerate() {
            for (c, v) in p.iter_mut().enumerate() {
                *v = truth(i, c) + 0.5 * (*v - truth(i, c));
            }
        }
        Ok(Some((img, t)))
    }
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("frepray-exp-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    fs::create_dir_all(&d).unwrap();
    d
}

fn truth_image() -> Image {
    let rgb = (0..(W * H) as usize)
        .map(|i| [0, 1, 2].map(|c| truth(i, c)))
        .collect();
    Image {
        width: W,
        height: H,
        rgb,
    }
}

fn config(dir: &Path) -> ExperimentConfig {
    let mut c = ExperimentConfig::new("scenes/synthetic.toml", dir.join("out"));
    c.estimators = vec!["balance".into(), "optimal".into(), "power".into()];
    c.spp = vec![16, 1, 4, 4];
    c.reference_spp = 1024;
    c.seed = 7;
    c.repeats = 1;
    c.command_line = "frepray experiment scenes/synthetic.toml --spp 1,4,16".into();
    c
}

fn run_quiet(cfg: &ExperimentConfig, r: &mut Synth) -> Result<Summary, ExperimentError> {
    run(cfg, r, &|_| {})
}

fn read(path: &Path) -> String {
    fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn metrics_by_hand() {
    let img = Image {
        width: 2,
        height: 1,
        rgb: vec![[1.0, 2.0, -1.0], [0.0, 0.0, 0.0]],
    };
    let reference = Image {
        width: 2,
        height: 1,
        rgb: vec![[1.0, 1.0, 1.0], [0.0, 0.5, 0.0]],
    };
    let (m, err) = metrics::measure(&img, &reference).unwrap();
    assert_eq!(err, vec![[0.0, 1.0, 4.0], [0.0, 0.25, 0.0]]);
    assert_eq!(m.mse, 5.25 / 6.0);
    let rel = (1.0 / 1.01 + 4.0 / 1.01 + 0.25 / 0.26) / 6.0;
    assert!((m.relmse - rel).abs() < 1e-15);
    let small = Image {
        width: 1,
        height: 1,
        rgb: vec![[0.0; 3]],
    };
    assert!(metrics::measure(&small, &reference).is_err());
    let broken = Image {
        width: 2,
        height: 2,
        rgb: vec![[0.0; 3]; 3],
    };
    assert!(broken.validate().is_err());
}

/// Against an exact reference, MSE = σ²/spp: the estimate over n = 3·W·H values has
/// relative standard deviation √(2/n) ≈ 1.0 %; the test allows 5 of them. relMSE
/// likewise, with the weights 1/(ref² + ε).
#[test]
fn rmse_matches_known_noise() {
    let d = scratch("noise");
    let ref_path = d.join("truth.exr");
    exr_io::write(&ref_path, &truth_image(), None).unwrap();
    let mut cfg = config(&d);
    cfg.reference = Some(ref_path);
    let mut r = Synth::default();
    let s = run_quiet(&cfg, &mut r).unwrap();
    assert_eq!(r.calls.len(), 9, "no reference render when one is given");
    assert_eq!(s.rows.len(), 9);
    let n = (3 * W * H) as f64;
    let weights: Vec<f64> = truth_image()
        .rgb
        .iter()
        .flat_map(|p| p.map(|v| 1.0 / ((v as f32 as f64).powi(2) + metrics::REL_EPSILON)))
        .collect();
    let mean_w = weights.iter().sum::<f64>() / n;
    let mean_w2 = weights.iter().map(|w| w * w).sum::<f64>() / n;
    let bound = 5.0 * (2.0 / n).sqrt();
    let rel_bound = 5.0 * (2.0 * mean_w2 / n).sqrt() / mean_w;
    for row in &s.rows {
        let var = params(&row.estimator).0.powi(2) / row.spp as f64;
        assert!(
            (row.mse / var - 1.0).abs() < bound,
            "{} {}: MSE {} vs {var}",
            row.estimator,
            row.spp,
            row.mse
        );
        assert_eq!(row.rmse, row.mse.sqrt());
        assert!((row.relmse / (var * mean_w) - 1.0).abs() < rel_bound);
        assert_eq!(row.time_s, row.spp as f64 * params(&row.estimator).1);
    }
    fs::remove_dir_all(&d).unwrap();
}

/// Parses the "Every sample count" table of summary.md: (estimator, spp) →
/// (improvement, speed up, overhead in %).
fn summary_table(md: &str) -> Vec<(String, u32, f64, f64, f64)> {
    let body = md.split("## Every sample count").nth(1).unwrap();
    let body = body.split("## At the largest").next().unwrap();
    body.lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| Estimator"))
        .map(|l| {
            let f: Vec<&str> = l.split('|').map(str::trim).collect();
            // The value before any " [lo, hi]" interval or " %".
            let num = |s: &str| s.split(' ').next().unwrap().parse::<f64>().unwrap();
            (
                f[1].into(),
                f[2].parse().unwrap(),
                num(f[7]),
                num(f[10]),
                num(f[11]),
            )
        })
        .collect()
}

#[test]
fn summary_matches_csv() {
    let d = scratch("summary");
    let cfg = config(&d);
    let s = run_quiet(&cfg, &mut Synth::default()).unwrap();
    let out = &cfg.out_dir;
    let csv = read(&out.join("results.csv"));
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some(
            "estimator,spp,repeats,seeds,time_s,mse,rmse,relmse,mse_lo,mse_hi,relmse_lo,\
             relmse_hi,trimmed_mse,net_mse,cpu_s"
        )
    );
    // (estimator, spp) → (time, net MSE, net RMSE) from the CSV: the ratios use the
    // MSE less the reference's noise.
    let rows: Vec<(String, u32, f64, f64, f64)> = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 15);
            let x = |i: usize| f[i].parse::<f64>().unwrap();
            assert_eq!(x(14), x(4), "the synthetic processor clock is its time");
            (
                f[0].into(),
                f[1].parse().unwrap(),
                x(4),
                x(13),
                x(13).sqrt(),
            )
        })
        .collect();
    assert_eq!(rows.len(), 9);
    let md = read(&out.join("summary.md"));
    assert!(md.contains(&cfg.command_line));
    let table = summary_table(&md);
    assert_eq!(table.len(), 9);
    for (est, spp, imp, speed, over) in table {
        let m = rows.iter().find(|r| r.0 == est && r.1 == spp).unwrap();
        let b = rows
            .iter()
            .find(|r| r.0 == "balance" && r.1 == spp)
            .unwrap();
        let (imp_h, over_h, speed_h) = (b.4 / m.4, m.2 / b.2 - 1.0, (b.3 * b.2) / (m.3 * m.2));
        assert!(
            (imp - imp_h).abs() <= 5.1e-5,
            "{est} {spp}: {imp} vs {imp_h}"
        );
        assert!((speed - speed_h).abs() <= 5.1e-5);
        assert!((over - 100.0 * over_h).abs() <= 5.1e-3);
        // And the structure behind them: σ ratio and τ ratio of the synthetic renderer.
        let (sm, tm) = params(&est);
        let (sb, tb) = params("balance");
        assert!((over_h - (tm / tb - 1.0)).abs() < 1e-9);
        // Net of the reference's own noise (σ_b²/1024, which is 28 % of the optimal
        // estimator's measured MSE at 16 spp), the improvement is the σ ratio: each
        // net MSE has a relative standard deviation of about 2 % (the measured MSE's
        // 1.5 % on the 28 % more, and the noise estimate's), the improvement, a square
        // root of their ratio, about 1.5 %: the bound 10 % is over 6 of them.
        assert!(
            (imp_h / (sb / sm) - 1.0).abs() < 0.10,
            "{est} {spp}: {imp_h}"
        );
    }
    // The noise estimate from the reference's two halves: σ_b²/1024 per value, from the
    // mean of 3·64·48 squared differences (relative standard deviation √(2/9216) =
    // 1.5 %; bound 5 of them).
    let json: serde_json::Value = serde_json::from_str(&read(&out.join("results.json"))).unwrap();
    let noise = json["reference"]["noise_mse"].as_f64().unwrap();
    let truth = params("balance").0.powi(2) / 1024.0;
    assert!((noise / truth - 1.0).abs() < 0.075, "{noise} vs {truth}");
    // The final table: one row per estimator at the largest spp.
    let last = md
        .split("## At the largest sample count (16 spp)")
        .nth(1)
        .unwrap();
    assert_eq!(last.lines().filter(|l| l.starts_with("| ")).count(), 1 + 3);
    assert_eq!(s.comparisons.len(), 9);
    let base = s
        .comparisons
        .iter()
        .find(|c| c.estimator == "balance")
        .unwrap();
    assert_eq!(
        (base.improvement, base.overhead, base.speed_up),
        (Some(1.0), Some(0.0), Some(1.0))
    );
    fs::remove_dir_all(&d).unwrap();
}

#[test]
fn resume_skips_finished_renders() {
    let d = scratch("resume");
    let mut cfg = config(&d);
    cfg.repeats = 2;
    let mut r = Synth::default();
    let first = run_quiet(&cfg, &mut r).unwrap();
    // The reference in two independent halves, then the renders.
    assert_eq!(r.calls.len(), 2 + 3 * 3 * 2);
    assert_eq!(r.calls[0], ("balance".into(), 512, 7 ^ REFERENCE_SEED_MASK));
    assert_eq!(
        r.calls[1],
        ("balance".into(), 512, (7 ^ REFERENCE_SEED_MASK) + 1)
    );
    assert_eq!((first.rendered, first.reused), (19, 0));
    assert_eq!(first.rows[0].seeds, vec![7, 8]);

    let mut r = Synth::default();
    let again = run_quiet(&cfg, &mut r).unwrap();
    assert!(r.calls.is_empty(), "rerun rendered {:?}", r.calls);
    assert_eq!(again.rows, first.rows);
    assert_eq!((again.rendered, again.reused), (0, 19));

    // A missing image is rendered again, and only it.
    fs::remove_file(cfg.out_dir.join(image_file("optimal", 4, 8))).unwrap();
    let mut r = Synth::default();
    assert_eq!(run_quiet(&cfg, &mut r).unwrap().rows, first.rows);
    assert_eq!(r.calls, vec![("optimal".to_string(), 4, 8)]);

    // A new sample count renders only its points.
    cfg.spp.push(2);
    let mut r = Synth::default();
    let more = run_quiet(&cfg, &mut r).unwrap();
    assert_eq!(r.calls.len(), 6);
    assert!(r.calls.iter().all(|c| c.1 == 2));
    assert_eq!(more.rows.len(), 12);

    // Other renderer settings: everything again, reference included.
    cfg.renderer_settings = "integrator=path".into();
    let mut r = Synth::default();
    run_quiet(&cfg, &mut r).unwrap();
    assert_eq!(r.calls.len(), 2 + 4 * 3 * 2);
    fs::remove_dir_all(&d).unwrap();
}

#[test]
fn interrupted_then_resumed_equals_uninterrupted() {
    let d = scratch("interrupt");
    let whole = config(&d.join("whole"));
    run_quiet(&whole, &mut Synth::default()).unwrap();
    let mut cfg = config(&d.join("parts"));
    cfg.out_dir = d.join("parts/out");

    // Stopped during the reference: nothing measured, nothing to resume but the run.
    let mut r = Synth {
        stop_at: Some(0),
        ..Synth::default()
    };
    let s = run_quiet(&cfg, &mut r).unwrap();
    assert!(s.interrupted && s.rows.is_empty());

    // Stopped at the 6th call (the reference's two parts + 3 renders done), then resumed.
    let mut r = Synth {
        stop_at: Some(5),
        ..Synth::default()
    };
    let s = run_quiet(&cfg, &mut r).unwrap();
    assert!(s.interrupted);
    assert_eq!(s.rendered, 4);
    assert_eq!(s.rows.len(), 3, "the three estimators at 1 spp");
    let md = read(&cfg.out_dir.join("summary.md"));
    assert!(md.contains("Interrupted: 3 of 9 points"));
    assert!(cfg.out_dir.join("rmse_vs_spp.png").is_file());
    let mut r = Synth::default();
    let s = run_quiet(&cfg, &mut r).unwrap();
    assert!(!s.interrupted);
    assert_eq!(r.calls.len(), 11 - 5, "finished renders were redone");

    for f in ["results.csv", "summary.md"] {
        assert_eq!(
            read(&whole.out_dir.join(f)),
            read(&cfg.out_dir.join(f)),
            "{f}"
        );
    }
    let json = |dir: &Path| -> serde_json::Value {
        let mut v: serde_json::Value =
            serde_json::from_str(&read(&dir.join("results.json"))).unwrap();
        let renders = v["renders"].as_array_mut().unwrap();
        renders.sort_by_key(|r| r["file"].as_str().unwrap().to_string());
        v
    };
    let (a, b) = (json(&whole.out_dir), json(&cfg.out_dir));
    for key in [
        "results",
        "comparisons",
        "renders",
        "reference",
        "interrupted",
    ] {
        assert_eq!(a[key], b[key], "{key}");
    }
    fs::remove_dir_all(&d).unwrap();
}

#[test]
fn plots_and_images_are_written() {
    let d = scratch("files");
    let cfg = config(&d);
    let lines = RefCell::new(Vec::new());
    run(&cfg, &mut Synth::default(), &|l| {
        lines.borrow_mut().push(l.to_string())
    })
    .unwrap();
    let lines = lines.into_inner();
    let renders: Vec<&String> = lines
        .iter()
        .filter(|l| l.contains("rendering (ETA"))
        .collect();
    assert_eq!(renders.len(), 9);
    assert!(renders[0].contains("[1/9] balance 1 spp seed 7"));
    // After the reference the ETA is known: 9 renders of 1+4+16 spp at ~10 ms/sample.
    assert!(!renders[0].contains("ETA ?"), "{}", renders[0]);

    let out = &cfg.out_dir;
    for stem in ["rmse_vs_spp", "rmse_vs_time"] {
        let (w, h, rgb) = render::png_io::read_rgb8_file(out.join(format!("{stem}.png"))).unwrap();
        assert_eq!((w, h), plot::SIZE);
        let pixels = || rgb.chunks_exact(3);
        // Each estimator's colour is drawn, and so is dark text.
        for c in &plot::COLOURS[..3] {
            let c = [c.0, c.1, c.2];
            assert!(pixels().any(|p| p == c), "{stem}: colour {c:?} missing");
        }
        assert!(pixels().filter(|p| p.iter().all(|&v| v < 60)).count() > 500);
        let svg = read(&out.join(format!("{stem}.svg")));
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        for e in ["balance", "optimal", "power", "RMSE"] {
            assert!(svg.contains(e), "{stem}.svg lacks {e}");
        }
    }
    // Every image: R, G, B and the squared error against the reference, as written.
    let reference = exr_io::read(&out.join("reference.exr")).unwrap();
    for (est, spp) in [("balance", 1), ("optimal", 16), ("power", 4)] {
        let path = out.join(image_file(est, spp, 7));
        let exr = exr::prelude::read_first_flat_layer_from_file(&path).unwrap();
        let ch = |name: &str| -> Vec<f32> {
            let l = &exr.layer_data.channel_data.list;
            let c = l.iter().find(|c| c.name.eq(name)).unwrap();
            c.sample_data.values_as_f32().collect()
        };
        let (img, _) = synthetic(est, spp, 7);
        let (r, e) = (ch("R"), ch("error.B"));
        for i in [0, 77, (W * H - 1) as usize] {
            assert_eq!(r[i], img.rgb[i][0] as f32);
            let d = img.rgb[i][2] - reference.rgb[i][2];
            assert_eq!(e[i], (d * d) as f32);
        }
    }
    // Ratio maps of each estimator against the baseline, and the median pixel ratio: at
    // 1 spp (reference noise 1/1024 of the render's) the per-pixel squared-error ratio of
    // balance to optimal is (σ_b/σ_m)² = 25 times an F(3, 3) variate, whose median is 1;
    // the median of 3072 of them has a standard deviation of about 3 % (bound 15 %).
    let json: serde_json::Value = serde_json::from_str(&read(&out.join("results.json"))).unwrap();
    let cmp = json["comparisons"].as_array().unwrap();
    let median = |est: &str, spp: u64| {
        cmp.iter()
            .find(|c| c["estimator"] == est && c["spp"] == spp)
            .and_then(|c| c["median_pixel_ratio"].as_f64())
    };
    let m = median("optimal", 1).unwrap();
    assert!((m / 25.0 - 1.0).abs() < 0.15, "{m}");
    assert_eq!(median("balance", 1), None, "the baseline has no map");
    for spp in [1, 4, 16] {
        for est in ["optimal", "power"] {
            let stem = out.join(format!("maps/{est}-{spp:05}spp-vs-balance"));
            let map = exr_io::read(&stem.with_extension("exr")).unwrap();
            assert_eq!((map.width, map.height), (W, H));
            let (w, h, _) = render::png_io::read_rgb8_file(stem.with_extension("png")).unwrap();
            assert_eq!((w, h), (W, H));
        }
    }
    // Trimmed MSE: the worst 3 of 3072 pixels out, a little below the MSE.
    for r in json["results"].as_array().unwrap() {
        let (mse, trimmed) = (
            r["mse"].as_f64().unwrap(),
            r["trimmed_mse"].as_f64().unwrap(),
        );
        assert!(trimmed < mse && trimmed > 0.97 * mse, "{trimmed} vs {mse}");
    }
    // Nothing half-written left behind.
    let stray: Vec<_> = fs::read_dir(out)
        .unwrap()
        .chain(fs::read_dir(out.join("images")).unwrap())
        .chain(fs::read_dir(out.join("maps")).unwrap())
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(stray.is_empty(), "{stray:?}");
    fs::remove_dir_all(&d).unwrap();
}

#[test]
fn bad_input_is_an_error() {
    let d = scratch("bad");
    let garbage = d.join("garbage.exr");
    fs::write(&garbage, b"v/1\x01 this is not an EXR file at all").unwrap();
    let mut cfg = config(&d);
    cfg.reference = Some(garbage.clone());
    let e = run_quiet(&cfg, &mut Synth::default()).unwrap_err();
    assert!(
        matches!(&e, ExperimentError::File { path, .. } if path.ends_with("garbage.exr")),
        "{e}"
    );
    // A truncated real EXR.
    let good = d.join("good.exr");
    exr_io::write(&good, &truth_image(), None).unwrap();
    let bytes = fs::read(&good).unwrap();
    fs::write(&garbage, &bytes[..bytes.len() / 2]).unwrap();
    assert!(run_quiet(&cfg, &mut Synth::default()).is_err());
    cfg.reference = Some(d.join("missing.exr"));
    let e = run_quiet(&cfg, &mut Synth::default()).unwrap_err();
    assert!(e.to_string().contains("missing.exr"), "{e}");
    // A reference of another size than the renders.
    let small = Image {
        width: 3,
        height: 2,
        rgb: vec![[0.5; 3]; 6],
    };
    exr_io::write(&good, &small, None).unwrap();
    cfg.reference = Some(good);
    let e = run_quiet(&cfg, &mut Synth::default()).unwrap_err();
    assert!(
        matches!(
            &e,
            ExperimentError::Image {
                source: ImageError::Sizes { other: (3, 2), .. },
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("3x2"), "{e}");

    let bad = |f: &dyn Fn(&mut ExperimentConfig)| {
        let mut c = config(&d);
        f(&mut c);
        run_quiet(&c, &mut Synth::default()).unwrap_err()
    };
    assert!(matches!(
        bad(&|c| c.spp = vec![4, 0]),
        ExperimentError::NoSampleCounts
    ));
    assert!(matches!(
        bad(&|c| c.spp.clear()),
        ExperimentError::NoSampleCounts
    ));
    assert!(matches!(
        bad(&|c| c.repeats = 0),
        ExperimentError::NoRepeats
    ));
    assert!(matches!(
        bad(&|c| c.reference_spp = 0),
        ExperimentError::NoReferenceSamples
    ));
    assert!(matches!(
        bad(&|c| c.estimators.push("../evil".into())),
        ExperimentError::Name {
            what: "estimator",
            ..
        }
    ));
    assert!(matches!(
        bad(&|c| c.baseline = String::new()),
        ExperimentError::Name {
            what: "baseline",
            ..
        }
    ));
    // A corrupt manifest is reported, not overwritten.
    let c = config(&d);
    fs::create_dir_all(&c.out_dir).unwrap();
    fs::write(c.out_dir.join("results.json"), b"{ not json").unwrap();
    let e = run_quiet(&c, &mut Synth::default()).unwrap_err();
    assert!(
        matches!(&e, ExperimentError::File { path, .. } if path.ends_with("results.json")),
        "{e}"
    );
    assert_eq!(read(&c.out_dir.join("results.json")), "{ not json");
    fs::remove_dir_all(&d).unwrap();
}

/// A renderer that breaks its contract: wrong image size, NaN pixels.
struct Broken(bool);

impl Renderer for Broken {
    fn render(
        &mut self,
        est: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, crate::Error> {
        let (mut img, t) = synthetic(est, spp, seed);
        if self.0 && est == "optimal" {
            img.rgb[5] = [f64::NAN, 0.0, 0.0];
        } else if !self.0 && est == "optimal" {
            img.rgb.pop();
        }
        Ok(Some((img, t)))
    }
}

#[test]
fn broken_renders() {
    let d = scratch("broken");
    let cfg = config(&d);
    let e = run(&cfg, &mut Broken(false), &|_| {}).unwrap_err();
    assert!(
        matches!(&e, ExperimentError::Image { what, source: ImageError::Values { .. } }
            if what.contains("optimal")),
        "{e}"
    );
    // NaN pixels: the error is NaN, stored as null, shown as "—", and read back.
    let cfg = config(&d.join("nan"));
    let s = run(&cfg, &mut Broken(true), &|_| {}).unwrap();
    let row = s.rows.iter().find(|r| r.estimator == "optimal").unwrap();
    assert!(row.mse.is_nan());
    let c = s
        .comparisons
        .iter()
        .find(|c| c.estimator == "optimal")
        .unwrap();
    assert_eq!((c.improvement, c.speed_up), (None, None));
    assert!(read(&cfg.out_dir.join("summary.md")).contains("| — |"));
    let again = run(&cfg, &mut Broken(true), &|_| {}).unwrap();
    assert_eq!(again.rendered, 0);
    assert!(again
        .rows
        .iter()
        .find(|r| r.estimator == "optimal")
        .unwrap()
        .mse
        .is_nan());
    fs::remove_dir_all(&d).unwrap();
}

/// The decomposition recovers the synthetic renderer's split: rays through pixel
/// centres keep a quarter of the variance. The sums run over 3·64·48 values with 4
/// seeds each (3 degrees of freedom): relative standard deviation √(2/(3·9216)) = 0.85 %
/// per sum, 1.2 % for the ratio; bound 6 %.
#[test]
fn variance_decomposition() {
    let d = scratch("decompose");
    let mut cfg = config(&d);
    cfg.repeats = 4;
    cfg.spp = vec![4];
    cfg.decompose = true;
    let mut r = Synth::default();
    let s = run_quiet(&cfg, &mut r).unwrap();
    let centred = r.calls.iter().filter(|c| c.0.ends_with("centred")).count();
    assert_eq!(centred, 3 * 4, "each estimator and seed once more, centred");
    assert_eq!(s.rows.len(), 3);
    for r in &s.rows {
        let v = r.variance.expect("every point decomposed");
        assert!(
            (v.direction_share / 0.25 - 1.0).abs() < 0.06,
            "{}: {v:?}",
            r.estimator
        );
    }
    let md = read(&cfg.out_dir.join("summary.md"));
    assert!(md.contains("## Variance: pixel footprint and directions"));
    // A rerun reuses the centred renders.
    let mut r = Synth::default();
    let again = run_quiet(&cfg, &mut r).unwrap();
    assert!(r.calls.is_empty(), "{:?}", r.calls);
    assert_eq!(again.rows, s.rows);
    // One repeat cannot estimate a variance.
    cfg.repeats = 1;
    assert!(matches!(
        run_quiet(&cfg, &mut Synth::default()).unwrap_err(),
        ExperimentError::DecomposeNeedsRepeats
    ));
    fs::remove_dir_all(&d).unwrap();
}

/// At equal time: each estimator renders the samples that fill the budget, from its
/// calibrated cost (1 s buys balance 100 spp at 0.010 s each, optimal 90 at 0.011,
/// power 95 at 0.0105), and Improvement is the RMSE ratio at equal time: within its
/// 95 % interval of the model's √((σ_b²/n_b) / (σ_e²/n_e)), with the time overhead
/// near 0. A rerun of the same budget reuses the calibration and every render.
#[test]
fn budget_compares_at_equal_time() {
    let d = scratch("budget");
    let mut cfg = config(&d);
    cfg.budget = Some(1.0);
    cfg.repeats = 4;
    let mut r = Synth::default();
    let s = run_quiet(&cfg, &mut r).unwrap();
    // Per estimator and round: 1 and 4 spp, then about an eighth of the budget; then
    // one render of the whole budget.
    let calibrations = 3 * budget::CALIBRATION_ROUNDS as usize * 3 + 3;
    assert_eq!(r.calls.len(), 2 + calibrations + 3 * 4, "{:?}", r.calls);
    let spp = |e: &str| s.rows.iter().find(|row| row.estimator == e).unwrap().spp;
    assert_eq!(
        (spp("balance"), spp("optimal"), spp("power")),
        (100, 90, 95)
    );
    let model = |e: &str| {
        let ((sb, _), (se, _)) = (params("balance"), params(e));
        ((sb * sb / 100.0) / (se * se / f64::from(spp(e)))).sqrt()
    };
    for c in &s.comparisons {
        let [lo, hi] = c.improvement_ci.unwrap();
        let want = model(&c.estimator);
        assert!(
            lo <= want && want <= hi,
            "{}: [{lo}, {hi}] vs {want}",
            c.estimator
        );
        assert!(c.overhead.unwrap().abs() < 0.02, "{c:?}");
    }
    let md = read(&cfg.out_dir.join("summary.md"));
    assert!(
        md.contains("equal time") && md.contains("MSE ratio"),
        "{md}"
    );
    let mut again = Synth::default();
    let s2 = run_quiet(&cfg, &mut again).unwrap();
    assert!(again.calls.is_empty(), "{:?}", again.calls);
    assert_eq!(s2.rows, s.rows);
    cfg.budget = Some(0.0);
    assert!(matches!(
        run_quiet(&cfg, &mut Synth::default()),
        Err(ExperimentError::Budget(_))
    ));
    fs::remove_dir_all(&d).unwrap();
}

/// Speed Up's interval carries the timing noise: the same renders with render times
/// spread by load (20 %) give a wider interval than with exact times.
#[test]
fn speed_up_intervals_widen_with_timing_noise() {
    let width = |jitter: f64, name: &str| {
        let d = scratch(name);
        let mut cfg = config(&d);
        cfg.repeats = 4;
        let s = run_quiet(
            &cfg,
            &mut Synth {
                time_jitter: jitter,
                ..Synth::default()
            },
        )
        .unwrap();
        let c = s
            .comparisons
            .iter()
            .find(|c| c.estimator == "optimal" && c.spp == 16)
            .unwrap();
        let [lo, hi] = c.speed_up_ci.unwrap();
        fs::remove_dir_all(&d).unwrap();
        (hi / lo).ln()
    };
    let (exact, noisy) = (width(0.0, "exact-times"), width(0.2, "noisy-times"));
    assert!(noisy > 1.2 * exact, "{exact} vs {noisy}");
}
