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
use render::{RenderState, StateHeader};
use std::path::{Path, PathBuf};
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
    /// Independent seeds per point: MSEs and times are averaged, and with two or more
    /// every figure gets a 95 % confidence interval.
    #[arg(long, default_value_t = experiment::DEFAULT_REPEATS)]
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
    /// Optimal-MIS ridge λ [default: 0.1; 1 for optimal-uncorrelated].
    #[arg(long, allow_negative_numbers = true)]
    ridge: Option<f64>,
    /// Power heuristic exponent β [default: 2].
    #[arg(long, allow_negative_numbers = true)]
    beta: Option<f64>,
    /// Cutoff heuristic threshold c [default: 0.5].
    #[arg(long, allow_negative_numbers = true)]
    cutoff: Option<f64>,
    /// Maximum path depth (`path`) [default: the scene's].
    #[arg(long)]
    max_depth: Option<u32>,
    /// Minimum path depth: only light of paths with at least this many bounces reaches
    /// the images, the reference's too; `--min-depth d --max-depth d` compares the
    /// estimators on depth d alone [default: the scene's, 0: all].
    #[arg(long)]
    min_depth: Option<u32>,
    /// Leave emitters seen directly by the camera out of the images, so that the error
    /// measures the estimators, not the camera's sampling of visible lights.
    #[arg(long)]
    hide_emitters: bool,
    /// Trace every camera ray, the reference's too, through its pixel's centre (no
    /// pixel-footprint variance: what MIS can act on, alone).
    #[arg(long)]
    pixel_center: bool,
    /// Also render every point with camera rays through pixel centres and split the
    /// variance into its pixel-footprint and direction parts (needs --repeats ≥ 2).
    #[arg(long)]
    decompose: bool,
    /// Per-light mode: one MIS estimator per light, summed.
    #[arg(long)]
    per_light: bool,
    /// How `light-trained` learns its pmfs.
    #[command(flatten)]
    trained: crate::TrainedArgs,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// The memory each render may take, as for `render` (`512M`, `8G`) [default: what
    /// the system has available]; checked for every estimator before anything runs.
    #[arg(long, value_name = "SIZE", value_parser = render::limits::parse_bytes)]
    max_memory: Option<u64>,
    /// Hide progress lines.
    #[arg(long)]
    quiet: bool,
}

/// Renders the scene for the driver.
struct SceneRenderer {
    scene: Scene,
    base: RenderOptions,
    stop: Arc<AtomicBool>,
    quiet: bool,
}

/// Chunks of a reference render: an interrupted reference keeps the chunks it
/// finished (at most 1/`REFERENCE_CHUNKS` of its work is lost).
const REFERENCE_CHUNKS: u32 = 32;

impl SceneRenderer {
    fn options(&self, estimator: &str, spp: u32, seed: u64) -> Result<RenderOptions, String> {
        Ok(RenderOptions {
            method: frepray::Method::from_str(estimator).map_err(|e| e.to_string())?,
            spp,
            seed,
            ..self.base.clone()
        })
    }

    /// One render of `o`: its image and wall time, or `None` if stopped.
    fn run(&self, o: &RenderOptions) -> Result<Option<(Image, f64)>, String> {
        let (state, stats) = render_loop::render(&self.scene, o, &self.stop, &|_, _| {})
            .map_err(|e| e.to_string())?;
        if stats.stopped {
            return Ok(None);
        }
        Ok(Some((to_image(&state), stats.wall.as_secs_f64())))
    }
}

/// The driver's image of a render state.
fn to_image(state: &RenderState) -> Image {
    let img = state.image();
    let (w, h) = (img.width(), img.height());
    let rgb = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| img.rgb(x, y).to_array())
        .collect();
    Image {
        width: w,
        height: h,
        rgb,
    }
}

impl Renderer for SceneRenderer {
    fn render(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, String> {
        let o = self.options(estimator, spp, seed)?;
        self.run(&o)
    }

    fn render_pixel_centers(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, String> {
        let o = RenderOptions {
            pixel_center: true,
            ..self.options(estimator, spp, seed)?
        };
        self.run(&o)
    }

    /// Renders the reference in [`REFERENCE_CHUNKS`] sample ranges merged as they
    /// finish; when stopped, the finished ones go to `checkpoint` (a render state),
    /// which a rerun continues from if it is a state of the same render.
    fn render_reference(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
        checkpoint: &Path,
    ) -> Result<Option<(Image, f64)>, String> {
        let o = self.options(estimator, spp, seed)?;
        let header = StateHeader::new(self.scene.camera.width, self.scene.camera.height, &o);
        let mut acc = RenderState::read(checkpoint).ok().filter(|s| {
            s.header() == &header
                && !s.is_partial()
                && matches!(s.samples(), [r] if r.start == 0 && r.end < spp)
        });
        let mut next = acc.as_ref().map_or(0, |s| s.samples()[0].end);
        if next > 0 && !self.quiet {
            note!(
                "reference: continuing from {next} of {spp} samples ({})",
                checkpoint.display()
            );
        }
        let chunk = spp.div_ceil(REFERENCE_CHUNKS).max(1);
        let mut wall = 0.0;
        while next < spp {
            let end = next.saturating_add(chunk).min(spp);
            let (state, stats) =
                render_loop::render_range(&self.scene, &o, next..end, &self.stop, &|_, _| {})
                    .map_err(|e| e.to_string())?;
            wall += stats.wall.as_secs_f64();
            if stats.stopped {
                if let Some(s) = &acc {
                    s.write(checkpoint).map_err(|e| e.to_string())?;
                    if !self.quiet {
                        note!(
                            "reference: {} of {spp} samples kept in {}",
                            s.samples()[0].end,
                            checkpoint.display()
                        );
                    }
                }
                return Ok(None);
            }
            match &mut acc {
                None => acc = Some(state),
                Some(a) => a.merge(&state).map_err(|e| e.to_string())?,
            }
            next = end;
        }
        let state = acc.expect("spp ≥ 1: at least one chunk");
        Ok(Some((to_image(&state), wall)))
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
        per_light: a.per_light,
        ridge: a.ridge,
        beta: a.beta,
        cutoff: a.cutoff,
        max_depth: a.max_depth,
        min_depth: a.min_depth,
        trained_grid: a.trained.trained_grid,
        trained_floor: a.trained.trained_floor,
        trained_spp: a.trained.trained_spp,
        ..Default::default()
    };
    let (data, settings) = scene_render::resolve(&a.scene, &o)?;
    let mut base = RenderOptions::from_settings(&settings)?;
    base.pixel_center = a.pixel_center;
    base.max_memory = a.max_memory.unwrap_or(0);
    base.validate()?;
    // The hash of the resolved scene covers every file it reads (models, environment
    // maps), not only the scene text: editing a model invalidates earlier renders.
    base.scene_hash = frepray::scene_hash(&data);
    let scene = Scene::from_data(&data);
    // One spelling per estimator, so that "optimal_direct" and "optimal-direct" are
    // the same point of the sweep.
    let canon = |s: &str| {
        frepray::Method::from_str(s)
            .map(|m| m.name().to_string())
            .map_err(|e| e.to_string())
    };
    let estimators = a
        .estimators
        .iter()
        .map(|s| canon(s))
        .collect::<Result<Vec<_>, _>>()?;
    // Every render of the sweep (and the reference) against the memory limit, before
    // anything is rendered or written.
    let reference = a.reference_estimator.as_deref().map(canon).transpose()?;
    for e in estimators.iter().chain(&reference) {
        let o = RenderOptions {
            method: frepray::Method::from_str(e).map_err(|e| e.to_string())?,
            ..base.clone()
        };
        render::limits::check_memory(scene.camera.width, scene.camera.height, &o)
            .map_err(|e| e.to_string())?;
    }
    let mut cfg = ExperimentConfig::new(&a.scene, &a.out);
    cfg.command_line = std::env::args().collect::<Vec<_>>().join(" ");
    cfg.renderer_settings =
        frepray::experiment::renderer_settings(&base, scene.camera.width, scene.camera.height);
    cfg.size = Some((scene.camera.width, scene.camera.height));
    cfg.estimators = estimators;
    cfg.spp = a.spp;
    cfg.reference_spp = a.reference_spp;
    cfg.reference_estimator = reference;
    cfg.reference = a.reference;
    cfg.seed = a.seed;
    cfg.repeats = a.repeats;
    cfg.decompose = a.decompose;
    cfg.baseline = canon(&a.baseline)?;
    let mut r = SceneRenderer {
        scene,
        base,
        stop: crate::stop_on_ctrl_c(),
        quiet: a.quiet,
    };
    let quiet = a.quiet;
    let summary = experiment::run(&cfg, &mut r, &|line: &str| {
        if !quiet {
            note!("{line}");
        }
    })?;
    if summary.interrupted {
        note!("interrupted: rerun the same command to resume");
    } else {
        note!("results in {}", a.out.display());
    }
    Ok(())
}
