//! `frepray experiment SCENE`: the estimator comparison of the paper, on a scene file.
//!
//! The flags, and the library's experiment driver ([`frepray::experiment`]) with its
//! scene renderer ([`SceneRenderer`]).

use crate::scene_flags::{load_options, SceneFlags};
use frepray::experiment::{self, ExperimentConfig, SceneRenderer};
use std::path::PathBuf;

/// The flags of `frepray experiment`.
#[derive(clap::Args)]
pub struct ExperimentArgs {
    /// The scene file (.toml or .json).
    scene: PathBuf,
    /// Estimators to compare (MIS names), comma-separated; each may bring its own
    /// techniques, `NAME@TECHNIQUE+TECHNIQUE`, e.g. `power@light-bvh+bsdf`.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "balance,power,optimal-direct"
    )]
    estimators: Vec<String>,
    /// Sample counts of the sweep, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16,32,64")]
    spp: Vec<u32>,
    /// Samples per pixel of the reference (aim for 16× the largest of the sweep or more).
    #[arg(long, default_value_t = 4096)]
    reference_spp: u32,
    /// Estimator that renders the reference [default: the baseline].
    #[arg(long)]
    reference_estimator: Option<String>,
    /// An EXR to use as the reference instead of rendering one.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Output folder (also the resume record).
    #[arg(short, long, default_value = "experiment")]
    out: PathBuf,
    /// First seed; repeat r uses seed + r.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Independent seeds per point: MSEs and times are averaged, and with two or more
    /// every figure gets a 95 % confidence interval.
    #[arg(long, default_value_t = experiment::DEFAULT_REPEATS)]
    repeats: u32,
    /// The estimator the tables compare against.
    #[arg(long, default_value = "balance")]
    baseline: String,
    /// Integrator: direct or path [default: the scene's].
    #[arg(long)]
    integrator: Option<String>,
    /// Also render every point with camera rays through pixel centres and split the
    /// variance into its pixel-footprint and direction parts (needs --repeats ≥ 2).
    #[arg(long)]
    decompose: bool,
    /// Add the best heuristic practice as baselines: balance and power over the
    /// experiment's techniques, over one technique per light (`light#*+bsdf`, scenes of
    /// at most 16 lights) and pbrt-v4's `light-bvh+bsdf` with the power heuristic.
    #[arg(long)]
    practice: bool,
    /// Compare at equal time instead of equal samples: every estimator renders the
    /// samples per pixel that fill this many processor seconds (calibrated from short
    /// renders of each), and --spp is not used.
    #[arg(long, value_name = "SECONDS", conflicts_with = "spp")]
    budget: Option<f64>,
    #[command(flatten)]
    flags: SceneFlags,
    /// Hide progress lines.
    #[arg(long)]
    quiet: bool,
}

/// Runs the experiment.
pub fn run(a: ExperimentArgs) -> Result<(), String> {
    crate::set_threads(a.flags.threads)?;
    let mut settings = a.flags.settings()?;
    settings.overrides.integrator = a.integrator.clone();
    // The estimators of the variants, for the warnings about flags they ignore.
    let methods = a
        .estimators
        .iter()
        .map(|e| experiment::variant::parse(e).map(|v| v.method.name().to_string()))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| format!("--estimators: {e}"))?;
    let (scene, base) = load_options(&a.scene, &settings, &methods)?;
    let err = |e: frepray::Error| e.to_string();
    let estimators = match a.practice {
        true => experiment::variant::with_practice(&scene, &a.estimators),
        false => a.estimators.clone(),
    };
    let mut cfg = ExperimentConfig::for_scene(
        &scene,
        &base,
        &a.scene,
        &a.out,
        &estimators,
        &a.baseline,
        a.reference_estimator.as_deref(),
    )
    .map_err(err)?;
    cfg.command_line = std::env::args().collect::<Vec<_>>().join(" ");
    cfg.spp = a.spp;
    cfg.reference_spp = a.reference_spp;
    cfg.reference = a.reference;
    cfg.seed = a.seed;
    cfg.repeats = a.repeats;
    cfg.decompose = a.decompose;
    cfg.budget = a.budget;
    let quiet = a.quiet;
    let note = |line: &str| {
        if !quiet {
            note!("{line}");
        }
    };
    let stop = crate::stop_on_ctrl_c();
    let mut r = SceneRenderer::new(&scene, base, &stop, &note);
    let summary = experiment::run(&cfg, &mut r, &note).map_err(|e| e.to_string())?;
    if summary.interrupted {
        note!("interrupted: rerun the same command to resume");
    } else {
        note!("results in {}", a.out.display());
    }
    Ok(())
}
