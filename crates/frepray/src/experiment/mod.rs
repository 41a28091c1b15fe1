//! `frepray experiment`: renders (or loads) a reference, then for each estimator and a
//! sweep of sample counts renders the scene, measures RMSE, relMSE and time, and writes
//! into the output folder:
//!
//! - `results.json`: every finished render and the averaged points, also the manifest
//!   that lets a rerun skip finished renders (rewritten whole after every render);
//! - `results.csv`: one line per (estimator, spp) point;
//! - `summary.md`: Improvement, Speed Up and Overhead against the baseline (DESIGN.md §4);
//! - `rmse_vs_spp.{png,svg}`, `rmse_vs_time.{png,svg}`: log-log plots;
//! - `reference.exr` (when rendered) and `images/EST-NNNNNspp-seedS.exr`: each image
//!   (R, G, B) with its per-pixel squared error (`error.R`, `error.G`, `error.B`).
//!
//! The renderer is abstract ([`Renderer`]), so that the driver is tested with a
//! synthetic one of known noise.

pub mod budget;
mod cpu_time;
pub mod decompose;
mod error;
mod exr_io;
mod manifest;
mod maps;
mod metrics;
mod plot;
mod report;
mod scene_renderer;
mod settings;
pub mod stats;
mod summarize;
#[cfg(test)]
mod tests;
pub mod variant;

pub use cpu_time::process_cpu_seconds;
pub use error::{ExperimentError, ImageError};
pub use manifest::{Comparison, Row};
pub use metrics::{measure, Metrics, REL_EPSILON, TRIM_FRACTION};
pub use scene_renderer::{canonical, to_image, SceneRenderer, REFERENCE_CHUNKS};
pub use settings::renderer_settings;
pub use summarize::{summarize, Measured};

use manifest::{Manifest, ReferenceInfo, ReferenceSource, RenderRecord, FORMAT};
use std::path::{Path, PathBuf};

/// A rendered image: linear RGB, unclamped (values may be negative), row by row from
/// the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels.
    pub rgb: Vec<[f64; 3]>,
}

/// What the experiment renders with.
pub trait Renderer {
    /// Renders with the named estimator (e.g. "balance", "optimal-direct") at `spp`
    /// samples per pixel and the given seed; returns the image and the render time in
    /// seconds, or `None` if stopped (Ctrl-C).
    fn render(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, crate::Error>;

    /// Renders the reference like [`Renderer::render`], keeping what a stopped render
    /// got in `checkpoint` and continuing from it when it holds samples of the same
    /// render (so an interrupted reference is not restarted). The default has no
    /// checkpoints.
    fn render_reference(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
        checkpoint: &Path,
    ) -> Result<Option<(Image, f64)>, crate::Error> {
        let _ = checkpoint;
        self.render(estimator, spp, seed)
    }

    /// A clock of processor seconds that advances with the work of renders (read
    /// before and after each): equal-time comparisons use it, since on a shared machine
    /// it counts less of the others' load than wall time. Default: this process's
    /// processor time, where the platform tells.
    fn cpu_clock(&self) -> Option<f64> {
        cpu_time::process_cpu_seconds()
    }

    /// Renders like [`Renderer::render`] with every camera ray through its pixel's
    /// centre, for the variance decomposition ([`ExperimentConfig::decompose`]). The
    /// default cannot.
    fn render_pixel_centers(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, ExperimentError> {
        let _ = (estimator, spp, seed);
        Err(ExperimentError::NoPixelCenters)
    }
}

/// The checkpoint of an interrupted reference render, in the output folder (its first
/// part; the second is [`REFERENCE_CHECKPOINT_2`]).
pub const REFERENCE_CHECKPOINT: &str = "reference.partial.state";

/// The checkpoint of the reference's second part.
pub const REFERENCE_CHECKPOINT_2: &str = "reference-2.partial.state";

/// What to run.
#[derive(Clone, Debug)]
pub struct ExperimentConfig {
    /// The scene file: a rerun reuses finished renders only for the same scene.
    pub scene: PathBuf,
    /// The command line, written at the top of `summary.md`.
    pub command_line: String,
    /// Anything else that changes the images (integrator, resolution, depth, a hash of
    /// the scene's content…): a rerun reuses finished renders only if it is the same.
    pub renderer_settings: String,
    /// The estimators to compare; the baseline is added in front if missing.
    pub estimators: Vec<String>,
    /// The sample counts (sorted and deduplicated before use).
    pub spp: Vec<u32>,
    /// Samples per pixel of a rendered reference.
    pub reference_spp: u32,
    /// The estimator of a rendered reference (`None`: the baseline).
    pub reference_estimator: Option<String>,
    /// An EXR (channels R, G, B) to load as the reference instead of rendering one.
    pub reference: Option<PathBuf>,
    /// The output folder (created if missing).
    pub out_dir: PathBuf,
    /// The seed of the first repeat; repeat r uses `seed + r`, a rendered reference
    /// `seed ^` [`REFERENCE_SEED_MASK`] (and that plus one for its second part).
    pub seed: u64,
    /// Independent seeds per point; MSE, relMSE and time are averaged over them, and
    /// with two or more each gets a 95 % interval.
    pub repeats: u32,
    /// The estimator the others are compared against.
    pub baseline: String,
    /// The size of the renders (width, height), when known: a given reference of
    /// another size is refused before anything is rendered.
    pub size: Option<(u32, u32)>,
    /// Also render every point with camera rays through pixel centres and split each
    /// pixel's variance into the pixel footprint's part and the directions' part
    /// ([`decompose`]); needs two or more repeats.
    pub decompose: bool,
    /// Compare at equal time instead of equal samples: each estimator renders the
    /// samples per pixel that fill this many processor seconds ([`budget`]), and `spp`
    /// is not used.
    pub budget: Option<f64>,
}

/// XORed into the seed for a rendered reference, so that its noise is independent of
/// the measured renders'.
pub const REFERENCE_SEED_MASK: u64 = 0x9E37_79B9_7F4A_7C15;

/// Seeds per point by default: two seeds' MSEs differ by up to 3.9× on glossy scenes
/// (docs/results.md), so one cannot resolve a few per cent; four give a t interval on
/// three degrees of freedom.
pub const DEFAULT_REPEATS: u32 = 4;

impl ExperimentConfig {
    /// Defaults: balance against itself, 1 to 64 spp in powers of two, a reference of
    /// 4096 spp, seed 0, [`DEFAULT_REPEATS`] seeds per point.
    pub fn new(scene: impl Into<PathBuf>, out_dir: impl Into<PathBuf>) -> Self {
        Self {
            scene: scene.into(),
            command_line: String::new(),
            renderer_settings: String::new(),
            estimators: vec!["balance".into()],
            spp: vec![1, 2, 4, 8, 16, 32, 64],
            reference_spp: 4096,
            reference_estimator: None,
            reference: None,
            out_dir: out_dir.into(),
            seed: 0,
            repeats: DEFAULT_REPEATS,
            baseline: "balance".into(),
            size: None,
            decompose: false,
            budget: None,
        }
    }
}

/// What a run did.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// The complete points, ordered by spp then estimator.
    pub rows: Vec<Row>,
    /// Each point against the baseline at the same spp.
    pub comparisons: Vec<Comparison>,
    /// Renders done by this run (the reference included).
    pub rendered: usize,
    /// Finished renders reused from an earlier run (the reference included).
    pub reused: usize,
    /// Whether the renderer was stopped; a rerun of the same command resumes.
    pub interrupted: bool,
}

/// An estimator name, or a variant (`NAME@TECHNIQUES`, [`variant`]): its label
/// becomes part of file names.
fn check_name(what: &'static str, name: &str) -> Result<(), ExperimentError> {
    let label = variant::label(name);
    let ok = !name.is_empty()
        && label.len() <= 128
        && label
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
        && !name.starts_with('.');
    if ok {
        Ok(())
    } else {
        Err(ExperimentError::Name {
            what,
            name: name.to_string(),
        })
    }
}

/// The validated sweep.
struct Plan {
    estimators: Vec<String>,
    spp: Vec<u32>,
    seeds: Vec<u64>,
}

impl Plan {
    fn new(cfg: &ExperimentConfig) -> Result<Plan, ExperimentError> {
        check_name("baseline", &cfg.baseline)?;
        let mut estimators = vec![cfg.baseline.clone()];
        for e in &cfg.estimators {
            check_name("estimator", e)?;
            if !estimators.contains(e) {
                estimators.push(e.clone());
            }
        }
        if let Some(e) = &cfg.reference_estimator {
            check_name("reference estimator", e)?;
        }
        let mut spp = cfg.spp.clone();
        spp.sort_unstable();
        spp.dedup();
        // At equal time the budget chooses the sample counts.
        if cfg.budget.is_none() && (spp.is_empty() || spp[0] == 0) {
            return Err(ExperimentError::NoSampleCounts);
        }
        if cfg.repeats == 0 {
            return Err(ExperimentError::NoRepeats);
        }
        if cfg.decompose && cfg.repeats < 2 {
            return Err(ExperimentError::DecomposeNeedsRepeats);
        }
        if cfg.reference.is_none() && cfg.reference_spp == 0 {
            return Err(ExperimentError::NoReferenceSamples);
        }
        let seeds = (0..cfg.repeats as u64)
            .map(|r| cfg.seed.wrapping_add(r))
            .collect();
        Ok(Plan {
            estimators,
            spp,
            seeds,
        })
    }
}

/// The path made absolute where possible, as text.
fn absolute(p: &Path) -> String {
    std::fs::canonicalize(p)
        .or_else(|_| std::path::absolute(p))
        .unwrap_or_else(|_| p.to_path_buf())
        .display()
        .to_string()
}

/// `1h02m`, `3m05s`, `12.3s` or `0.012s`.
fn duration(s: f64) -> String {
    if !s.is_finite() {
        return "?".into();
    }
    let t = s.round() as u64;
    if t >= 3600 {
        format!("{}h{:02}m", t / 3600, t % 3600 / 60)
    } else if t >= 60 {
        format!("{}m{:02}s", t / 60, t % 60)
    } else if s >= 1.0 {
        format!("{s:.1}s")
    } else {
        format!("{s:.3}s")
    }
}

/// Seconds left for `todo`, from the seconds per sample of the finished renders
/// `(estimator, spp, seconds)`: of the same estimator where there are some, else of
/// all; `None` before any.
fn eta(todo: &[(String, u32, u64)], done: &[(&str, u32, f64)]) -> Option<f64> {
    let rate = |est: Option<&str>| {
        let (t, n) = done
            .iter()
            .filter(|r| est.is_none_or(|e| r.0 == e) && r.2.is_finite())
            .fold((0.0, 0.0), |(t, n), r| (t + r.2, n + r.1 as f64));
        (n > 0.0).then(|| t / n)
    };
    let all = rate(None)?;
    Some(
        todo.iter()
            .map(|(e, spp, _)| *spp as f64 * rate(Some(e)).unwrap_or(all))
            .sum(),
    )
}

/// The (spp, seed) of each part of a rendered reference of `spp` samples from `seed`:
/// two independent halves, so that their difference estimates the reference's noise;
/// one part at 1 spp.
fn reference_parts(spp: u32) -> Vec<(u32, u64)> {
    if spp >= 2 {
        vec![(spp.div_ceil(2), 0), (spp / 2, 1)]
    } else {
        vec![(spp, 0)]
    }
}

/// Renders the reference in its parts (each continued from its checkpoint), averages
/// them weighted by their samples and estimates its noise: with parts A and B of n_A and
/// n_B samples, a value's variance is c/n, so `E (A − B)² = c (1/n_A + 1/n_B)` and the
/// whole's is `c/(n_A + n_B)`. `None` if stopped.
fn render_reference(
    renderer: &mut dyn Renderer,
    out: &Path,
    estimator: &str,
    spp: u32,
    seed: u64,
    progress: &dyn Fn(&str),
) -> Result<Option<(Image, ReferenceInfo)>, ExperimentError> {
    let checkpoints = [REFERENCE_CHECKPOINT, REFERENCE_CHECKPOINT_2];
    let mut parts = Vec::new();
    let mut time = 0.0;
    for (k, &(n, offset)) in reference_parts(spp).iter().enumerate() {
        let s = seed.wrapping_add(offset);
        progress(&format!("reference: {estimator} {n} spp seed {s}"));
        let Some((img, t)) =
            renderer.render_reference(estimator, n, s, &out.join(checkpoints[k]))?
        else {
            return Ok(None);
        };
        img.validate()
            .map_err(ExperimentError::image("reference"))?;
        progress(&format!(
            "reference: part {} done in {}",
            k + 1,
            duration(t)
        ));
        time += t;
        parts.push((n as f64, img));
    }
    for c in checkpoints {
        let _ = std::fs::remove_file(out.join(c));
    }
    let (na, first) = &parts[0];
    let mut img = first.clone();
    let mut noise = None;
    if let Some((nb, second)) = parts.get(1) {
        if (second.width, second.height) != (first.width, first.height) {
            return Err(ExperimentError::Image {
                what: "reference".into(),
                source: ImageError::Sizes {
                    image: (first.width, first.height),
                    what: "reference's other part",
                    other: (second.width, second.height),
                },
            });
        }
        let mut diff = 0.0;
        for (a, b) in img.rgb.iter_mut().zip(&second.rgb) {
            for c in 0..3 {
                diff += (a[c] - b[c]).powi(2);
                a[c] = (na * a[c] + nb * b[c]) / (na + nb);
            }
        }
        let e = diff / (3 * img.rgb.len()) as f64;
        noise = Some(e / ((1.0 / na + 1.0 / nb) * (na + nb)));
    }
    let img = img.rounded_to_f32();
    let info = ReferenceInfo {
        source: ReferenceSource::Rendered {
            estimator: estimator.to_string(),
            spp,
            seed,
            parts: parts.len() as u32,
        },
        width: img.width,
        height: img.height,
        fingerprint: img.fingerprint(),
        time_s: Some(time),
        noise_mse: noise,
    };
    Ok(Some((img, info)))
}

/// The image file of a render, relative to the output folder.
fn image_file(estimator: &str, spp: u32, seed: u64) -> String {
    format!(
        "images/{}-{spp:05}spp-seed{seed}.exr",
        variant::label(estimator)
    )
}

/// Runs the experiment of `cfg` with `renderer`, reporting a line per render to
/// `progress`. A stopped render ends the run early with `interrupted` set, after
/// writing every output for what is finished; a rerun of the same configuration
/// skips the finished renders.
pub fn run(
    cfg: &ExperimentConfig,
    renderer: &mut dyn Renderer,
    progress: &dyn Fn(&str),
) -> Result<Summary, ExperimentError> {
    let plan = Plan::new(cfg)?;
    let out = &cfg.out_dir;
    std::fs::create_dir_all(out.join("images"))
        .map_err(ExperimentError::io("create", &out.join("images")))?;
    let manifest_path = out.join("results.json");
    let mut old = Manifest::load(&manifest_path)?;
    let scene = absolute(&cfg.scene);
    if let Some(m) = &old {
        if m.scene != scene || m.renderer != cfg.renderer_settings {
            progress(&format!(
                "{} holds results of another scene or renderer settings: starting afresh",
                manifest_path.display()
            ));
            old = None;
        }
    }
    let mut summary = Summary {
        rows: vec![],
        comparisons: vec![],
        rendered: 0,
        reused: 0,
        interrupted: false,
    };

    // The reference, always at f32 precision (see Image::rounded_to_f32).
    let (reference, ref_info) = match &cfg.reference {
        Some(path) => {
            let img = exr_io::read(path)?;
            if let Some((w, h)) = cfg.size.filter(|&s| s != (img.width, img.height)) {
                return Err(ExperimentError::ReferenceSize {
                    path: path.clone(),
                    found: (img.width, img.height),
                    wanted: (w, h),
                });
            }
            let info = ReferenceInfo {
                source: ReferenceSource::File {
                    path: absolute(path),
                },
                width: img.width,
                height: img.height,
                fingerprint: img.fingerprint(),
                time_s: None,
                noise_mse: None,
            };
            (img, info)
        }
        None => {
            let estimator = cfg.reference_estimator.as_ref().unwrap_or(&cfg.baseline);
            let (spp, seed) = (cfg.reference_spp, cfg.seed ^ REFERENCE_SEED_MASK);
            let source = ReferenceSource::Rendered {
                estimator: estimator.clone(),
                spp,
                seed,
                parts: reference_parts(spp).len() as u32,
            };
            let path = out.join("reference.exr");
            let reuse = old
                .as_ref()
                .filter(|m| m.reference.source == source && path.is_file())
                .and_then(|m| {
                    let img = exr_io::read(&path).ok()?;
                    (img.fingerprint() == m.reference.fingerprint)
                        .then(|| (img, m.reference.clone()))
                });
            if let Some(r) = reuse {
                progress(&format!("reference: reusing {}", path.display()));
                summary.reused += 1;
                r
            } else {
                let Some((img, info)) =
                    render_reference(renderer, out, estimator, spp, seed, progress)?
                else {
                    summary.interrupted = true;
                    progress("interrupted while rendering the reference: rerun to continue it");
                    return Ok(summary);
                };
                exr_io::write(&path, &img, None)?;
                summary.rendered += 1;
                (img, info)
            }
        }
    };
    // At equal time: the samples each estimator's budget buys (kept from an earlier run
    // of the same budget and estimators, so that its renders are reused).
    let budget = match cfg.budget {
        None => None,
        Some(seconds) => {
            let same = |b: &&budget::Budget| {
                b.seconds == seconds
                    && plan.estimators.iter().all(|e| b.spp(e).is_some())
                    && b.estimators.len() == plan.estimators.len()
            };
            match old.as_ref().and_then(|m| m.budget.as_ref()).filter(same) {
                Some(b) => Some(b.clone()),
                None => {
                    progress(&format!(
                        "budget: calibrating {} estimator(s) for {seconds} s a render",
                        plan.estimators.len()
                    ));
                    let seed = cfg.seed;
                    match budget::calibrate(renderer, &plan.estimators, seconds, seed, progress)? {
                        Some(b) => Some(b),
                        None => {
                            summary.interrupted = true;
                            progress("interrupted while calibrating the budget: rerun to continue");
                            return Ok(summary);
                        }
                    }
                }
            }
        }
    };
    // The points to render: every sample count of every estimator, or at equal time
    // each estimator's own.
    let sweep: Vec<(String, u32)> = match &budget {
        Some(b) => plan
            .estimators
            .iter()
            .map(|e| (e.clone(), b.spp(e).expect("calibrated")))
            .collect(),
        None => plan
            .spp
            .iter()
            .flat_map(|&n| plan.estimators.iter().map(move |e| (e.clone(), n)))
            .collect(),
    };
    let spp_list: Vec<u32> = {
        let mut v: Vec<u32> = sweep.iter().map(|p| p.1).collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    // Renders measured against another reference are stale.
    let (renders, centered) = match old {
        Some(m)
            if m.reference.source == ref_info.source
                && m.reference.fingerprint == ref_info.fingerprint =>
        {
            (m.renders, m.centered)
        }
        Some(_) => {
            progress("the reference changed: earlier renders will be redone");
            (vec![], vec![])
        }
        None => (vec![], vec![]),
    };
    let mut manifest = Manifest {
        format: FORMAT,
        command: cfg.command_line.clone(),
        scene,
        renderer: cfg.renderer_settings.clone(),
        baseline: cfg.baseline.clone(),
        reference: ref_info,
        interrupted: false,
        renders,
        results: vec![],
        comparisons: vec![],
        centered,
        budget: budget.clone(),
    };
    let refresh = |m: &mut Manifest| {
        let noise = m.reference.noise_mse;
        let mut rows = report::rows(m, &plan.estimators, &spp_list, &plan.seeds, noise);
        rows.retain(|r| sweep.contains(&(r.estimator.clone(), r.spp)));
        m.comparisons = match &budget {
            Some(_) => report::compare_at_budget(m, &rows, &cfg.baseline, noise),
            None => report::compare(m, &rows, &cfg.baseline, noise),
        };
        m.results = rows;
    };
    refresh(&mut manifest);
    manifest.save(&manifest_path)?;

    // Seeds outside, estimators inside: the renders of one point interleave with the
    // other estimators', so that a change of load hits all of them alike.
    let mut todo = Vec::new();
    for &spp in &spp_list {
        for &seed in &plan.seeds {
            for e in &plan.estimators {
                if !sweep.contains(&(e.clone(), spp)) {
                    continue;
                }
                let file = image_file(e, spp, seed);
                if manifest.find(e, spp, seed).is_some() && out.join(&file).is_file() {
                    summary.reused += 1;
                } else {
                    todo.push((e.clone(), spp, seed));
                }
            }
        }
    }
    if summary.reused > 0 {
        progress(&format!("reusing {} finished render(s)", summary.reused));
    }
    for (k, (est, spp, seed)) in todo.iter().enumerate() {
        let head = format!("[{}/{}] {est} {spp} spp seed {seed}", k + 1, todo.len());
        let mut done: Vec<(&str, u32, f64)> = manifest
            .renders
            .iter()
            .map(|r| (r.estimator.as_str(), r.spp, r.time_s))
            .collect();
        if let (ReferenceSource::Rendered { estimator, spp, .. }, Some(t)) =
            (&manifest.reference.source, manifest.reference.time_s)
        {
            done.push((estimator, *spp, t));
        }
        let left = eta(&todo[k..], &done).map_or("?".into(), duration);
        progress(&format!("{head}: rendering (ETA {left})"));
        let cpu0 = renderer.cpu_clock();
        let rendered = renderer.render(est, *spp, *seed)?;
        let cpu_s = cpu0.zip(renderer.cpu_clock()).map(|(a, b)| b - a);
        let Some((img, time_s)) = rendered else {
            summary.interrupted = true;
            progress(&format!("{head}: interrupted"));
            break;
        };
        let (m, err) = metrics::measure(&img, &reference).map_err(ExperimentError::image(&head))?;
        let file = image_file(est, *spp, *seed);
        exr_io::write(&out.join(&file), &img, Some(&err))?;
        manifest.upsert(RenderRecord {
            estimator: est.clone(),
            spp: *spp,
            seed: *seed,
            file,
            time_s,
            mse: m.mse,
            rmse: m.mse.sqrt(),
            relmse: m.relmse,
            trimmed_mse: m.trimmed_mse,
            cpu_s,
            nonfinite: m.nonfinite,
        });
        refresh(&mut manifest);
        manifest.save(&manifest_path)?;
        summary.rendered += 1;
        let warn = if m.nonfinite > 0 {
            format!(" ({} non-finite values)", m.nonfinite)
        } else {
            String::new()
        };
        progress(&format!(
            "{head}: done in {}, RMSE {:.4e}, relMSE {:.4e}{warn}",
            duration(time_s),
            m.mse.sqrt(),
            m.relmse
        ));
    }

    if cfg.decompose && !summary.interrupted {
        let stopped =
            decompose::render_missing(renderer, out, &mut manifest, &plan, &sweep, progress)?;
        summary.interrupted |= stopped;
        manifest.save(&manifest_path)?;
    }
    if cfg.decompose {
        decompose::fill(out, &mut manifest.results)?;
    }
    let points: Vec<(String, u32)> = manifest
        .results
        .iter()
        .map(|r| (r.estimator.clone(), r.spp))
        .collect();
    let medians = maps::write(out, &points, &plan.seeds, &cfg.baseline, &reference)?;
    for c in &mut manifest.comparisons {
        c.median_pixel_ratio = medians.get(&(c.estimator.clone(), c.spp)).copied();
    }
    manifest.interrupted = summary.interrupted;
    manifest.save(&manifest_path)?;
    report::write_csv(&out.join("results.csv"), &manifest.results)?;
    let done = if summary.interrupted {
        format!(
            "Interrupted: {} of {} points complete; rerun the command to resume.",
            manifest.results.len(),
            sweep.len()
        )
    } else {
        "Complete.".to_string()
    };
    let md = report::summary_markdown(&manifest, &manifest.results, &manifest.comparisons, &done);
    report::write_text(&out.join("summary.md"), &md)?;
    plot::write_all(out, &manifest.results, &plan.estimators)?;
    summary.rows = manifest.results;
    summary.comparisons = manifest.comparisons;
    Ok(summary)
}
