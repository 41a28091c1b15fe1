//! `frepray experiment SCENE`: the estimator comparison of the paper, on a scene file.
//!
//! Connects the experiment driver ([`frepray::experiment`]) to the CPU renderer: every
//! point of the sweep is one `render_loop::render` of the scene with the estimator,
//! sample count and seed the driver asks for.

use crate::scene_render::{self, Overrides};
use frepray::experiment::{self, ExperimentConfig, Image, Renderer};
use render::integrator::RenderOptions;
use render::render_loop;
use render::scene::Scene;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// The flags of `frepray experiment`.
#[derive(clap::Args)]
pub struct ExperimentArgs {
    /// The scene file (.toml or .json).
    scene: PathBuf,
    /// Estimators to compare (MIS names), comma-separated.
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
    /// Independent renders per point (their MSEs are averaged).
    #[arg(long, default_value_t = 1)]
    repeats: u32,
    /// The estimator the tables compare against.
    #[arg(long, default_value = "balance")]
    baseline: String,
    /// Sampling techniques and samples of each, e.g. `light:1,bsdf:1`.
    #[arg(long)]
    techniques: Option<String>,
    /// Integrator: direct or path [default: the scene's].
    #[arg(long)]
    integrator: Option<String>,
    /// Image width [default: the scene's].
    #[arg(long)]
    width: Option<u32>,
    /// Image height [default: the scene's].
    #[arg(long)]
    height: Option<u32>,
    /// Optimal-MIS ridge λ [default: 0.1].
    #[arg(long)]
    ridge: Option<f64>,
    /// Power heuristic exponent β [default: 2].
    #[arg(long)]
    beta: Option<f64>,
    /// Leave emitters seen directly by the camera out of the images, so that the error
    /// measures the estimators, not the camera's sampling of visible lights.
    #[arg(long)]
    hide_emitters: bool,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Hide progress lines.
    #[arg(long)]
    quiet: bool,
}

/// Renders the scene for the driver.
struct SceneRenderer {
    scene: Scene,
    base: RenderOptions,
    stop: Arc<AtomicBool>,
}

impl Renderer for SceneRenderer {
    fn render(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, String> {
        let o = RenderOptions {
            method: mis::Method::from_str(estimator).map_err(|e| e.to_string())?,
            spp,
            seed,
            ..self.base.clone()
        };
        let (state, stats) = render_loop::render(&self.scene, &o, &self.stop, &|_, _| {})
            .map_err(|e| e.to_string())?;
        if stats.stopped {
            return Ok(None);
        }
        let img = state.image();
        let (w, h) = (img.width(), img.height());
        let rgb = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| img.rgb(x, y).to_array())
            .collect();
        Ok(Some((
            Image {
                width: w,
                height: h,
                rgb,
            },
            stats.wall.as_secs_f64(),
        )))
    }
}

/// Runs the experiment.
pub fn run(a: ExperimentArgs) -> Result<(), String> {
    crate::set_threads(a.threads)?;
    let o = Overrides {
        techniques: a.techniques.clone(),
        integrator: a.integrator.clone(),
        width: a.width,
        height: a.height,
        hide_emitters: a.hide_emitters,
        ridge: a.ridge,
        beta: a.beta,
        ..Default::default()
    };
    let (scene, base) = scene_render::load(&a.scene, &o)?;
    // One spelling per estimator, so that "optimal_direct" and "optimal-direct" are
    // the same point of the sweep.
    let canon = |s: &str| {
        mis::Method::from_str(s)
            .map(|m| m.name().to_string())
            .map_err(|e| e.to_string())
    };
    let estimators = a
        .estimators
        .iter()
        .map(|s| canon(s))
        .collect::<Result<Vec<_>, _>>()?;
    let text = std::fs::read(&a.scene).map_err(|e| format!("{}: {e}", a.scene.display()))?;
    let mut cfg = ExperimentConfig::new(&a.scene, &a.out);
    cfg.command_line = std::env::args().collect::<Vec<_>>().join(" ");
    cfg.renderer_settings = format!(
        "integrator {} techniques {:?} max_depth {} rr_depth {} hide_emitters {} resolution {}x{} params {:?} scene-hash {:016x}",
        base.integrator,
        base.techniques.iter().map(|(t, n)| format!("{}:{n}", t.name())).collect::<Vec<_>>(),
        base.max_depth,
        base.rr_depth,
        base.hide_emitters,
        scene.camera.width,
        scene.camera.height,
        base.params,
        fnv1a(&text)
    );
    cfg.estimators = estimators;
    cfg.spp = a.spp;
    cfg.reference_spp = a.reference_spp;
    cfg.reference_estimator = a.reference_estimator.as_deref().map(canon).transpose()?;
    cfg.reference = a.reference;
    cfg.seed = a.seed;
    cfg.repeats = a.repeats;
    cfg.baseline = canon(&a.baseline)?;
    let mut r = SceneRenderer {
        scene,
        base,
        stop: crate::stop_on_ctrl_c(),
    };
    let quiet = a.quiet;
    let summary = experiment::run(&cfg, &mut r, &|line: &str| {
        if !quiet {
            eprintln!("{line}");
        }
    })?;
    if summary.interrupted {
        eprintln!("interrupted: rerun the same command to resume");
    } else {
        eprintln!("results in {}", a.out.display());
    }
    Ok(())
}

/// FNV-1a of the scene text: a change of the scene invalidates earlier renders.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ *b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}
