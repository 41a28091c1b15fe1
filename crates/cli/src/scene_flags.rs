//! The flags that set a scene's render, shared by `render`, `bench` and `experiment`
//! (each adds its own sample counts, estimators and seeds), and their spelling in
//! messages: the library ([`frepray::Settings`]) names scene keys, the command line
//! names flags.

use std::path::Path;

/// Flags over a scene's `[render]` and `[camera]` settings, and the run's own.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct SceneFlags {
    /// Sampling techniques and samples of each (scenes), e.g. `light:1,bsdf:1`; names:
    /// bsdf, light-power (alias light), light-uniform, light-area, light-spatial,
    /// light-bvh (light-spatial's pmf from a light BVH, O(log n)), light-trained
    /// (trained per spatial cell in a pass before the render),
    /// light#k (MIS light k: area lights in file order, then the environment), light#*
    /// (every MIS light), environment, cosine; at most 32.
    #[arg(long)]
    pub techniques: Option<String>,
    /// Image width in pixels [the scene's; 512 for models].
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels [the scene's; 512 for models].
    #[arg(long)]
    pub height: Option<u32>,
    /// Maximum path depth (scenes, `path`).
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Minimum path depth (scenes): only light of paths with at least this many bounces
    /// reaches the image (0: all; camera-seen emitters are depth 0). With
    /// `--min-depth d --max-depth d` the image holds depth d alone, and the images of
    /// every depth sum to the full one [default: 0].
    #[arg(long)]
    pub min_depth: Option<u32>,
    /// Power heuristic exponent β (scenes, `--estimator power`) [default: 2].
    #[arg(long, allow_negative_numbers = true)]
    pub beta: Option<f64>,
    /// Cutoff heuristic threshold c (scenes, `--estimator cutoff`) [default: 0.5].
    #[arg(long, allow_negative_numbers = true)]
    pub cutoff: Option<f64>,
    /// Optimal-MIS ridge λ (scenes, `--estimator optimal-*`): the solve adds λ/N·tr(Â)/T to
    /// the diagonal [default: 0.1; 1 for optimal-uncorrelated].
    #[arg(long, allow_negative_numbers = true)]
    pub ridge: Option<f64>,
    /// Leave emitters seen directly by the camera out of the image (scenes), so that
    /// an error measures the estimators, not the camera's sampling of visible lights.
    #[arg(long)]
    pub hide_emitters: bool,
    /// Trace every camera ray through its pixel's centre (scenes; a diagnostic: no
    /// pixel-footprint variance, and the image converges to point samples).
    #[arg(long)]
    pub pixel_center: bool,
    /// Per-light mode (scenes): one MIS estimator per light (area lights, then the
    /// environment), each fed only the radiance of the light its draws reach; the pixel
    /// is their sum. Changes only the optimal estimators' result.
    #[arg(long)]
    pub per_light: bool,
    /// `light-trained`: cells per axis of the grid over the first hits whose cells
    /// each learn a light pmf (1: one pmf for the whole scene; at most 64) [default: 8].
    #[arg(long)]
    pub trained_grid: Option<u32>,
    /// `light-trained`: the uniform share ε of every cell's pmf,
    /// `P(k) = (1 − ε)·w_k/Σw + ε/L`, in (0, 1] [default: 0.1].
    #[arg(long)]
    pub trained_floor: Option<f64>,
    /// `light-trained`: camera rays per pixel of the training pass [default: 4].
    #[arg(long)]
    pub trained_spp: Option<u32>,
    /// Worker threads (0: one per core; at most 8 per core). The image does not depend
    /// on it.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// The memory a render may take, e.g. `512M`, `8G` [default: what the system has
    /// available]; a larger render is refused before anything runs, with its estimate.
    #[arg(long, value_name = "SIZE", value_parser = frepray::limits::parse_bytes)]
    pub max_memory: Option<u64>,
    /// How the CPU runs the samples (scenes): `per-ray`, one sample at a time through
    /// every stage, or `batched`, a tile's samples in batches stage by stage (`direct`
    /// and `path` without media, emitting objects or AOVs; other renders run per ray).
    /// The image is the same bit for bit.
    #[arg(long, value_name = "NAME", default_value = "per-ray", value_parser = parse_engine)]
    pub engine: frepray::Engine,
}

/// `--engine`'s value.
fn parse_engine(name: &str) -> Result<frepray::Engine, String> {
    frepray::Engine::parse(name)
        .ok_or_else(|| format!("unknown engine {name:?}: per-ray or batched"))
}

impl SceneFlags {
    /// The library's settings of these flags (threads are left to the global pool,
    /// which [`crate::set_threads`] sizes).
    pub fn settings(&self) -> Result<frepray::Settings, String> {
        let techniques = self
            .techniques
            .as_deref()
            .map(frepray::parse_technique_list)
            .transpose()
            .map_err(|e| format!("--techniques: {e}"))?;
        Ok(frepray::Settings {
            overrides: frepray::Overrides {
                techniques,
                width: self.width,
                height: self.height,
                max_depth: self.max_depth,
                min_depth: self.min_depth,
                hide_emitters: self.hide_emitters,
                beta: self.beta,
                cutoff: self.cutoff,
                ridge: self.ridge,
                per_light: self.per_light,
                trained_grid: self.trained_grid,
                trained_floor: self.trained_floor,
                trained_spp: self.trained_spp,
                ..Default::default()
            },
            threads: 0,
            pixel_center: self.pixel_center,
            stage_times: false,
            max_memory: self.max_memory.unwrap_or(0),
            engine: self.engine,
        })
    }

    /// The flags that set a scene's light transport, with whether each is given (a
    /// bare model refuses them).
    pub fn transport_flags(&self) -> [(&'static str, bool); 10] {
        [
            ("--techniques", self.techniques.is_some()),
            ("--max-depth", self.max_depth.is_some()),
            ("--min-depth", self.min_depth.is_some()),
            ("--beta", self.beta.is_some()),
            ("--cutoff", self.cutoff.is_some()),
            ("--ridge", self.ridge.is_some()),
            ("--hide-emitters", self.hide_emitters),
            ("--pixel-center", self.pixel_center),
            ("--per-light", self.per_light),
            (
                "--trained-grid/--trained-floor/--trained-spp",
                self.trained_grid.is_some()
                    || self.trained_floor.is_some()
                    || self.trained_spp.is_some(),
            ),
        ]
    }
}

/// The command-line flag that sets the value at an overridden scene key.
pub fn flag(key: &str) -> String {
    match key {
        "render.spp" => "--spp",
        "render.estimator" => "--estimator",
        "render.techniques" => "--techniques",
        "render.seed" => "--seed",
        "render.integrator" => "--integrator",
        "camera.resolution" => "--width/--height",
        "render.max_depth" => "--max-depth",
        "render.min_depth" => "--min-depth",
        "render.aovs" => "--aovs",
        "render.hide_emitters" => "--hide-emitters",
        "render.beta" => "--beta",
        "render.cutoff" => "--cutoff",
        "render.ridge" => "--ridge",
        "render.per_light" => "--per-light",
        "render.trained_grid" => "--trained-grid",
        "render.trained_floor" => "--trained-floor",
        "render.trained_spp" => "--trained-spp",
        _ => "an override",
    }
    .to_string()
}

/// Loads a scene file with `settings`' overrides patched in before it is resolved (so
/// that they are validated once, with the file's own values); an error about an
/// overridden value names its flag.
pub fn load(input: &Path, settings: &frepray::Settings) -> Result<frepray::Scene, String> {
    let o = &settings.overrides;
    frepray::load_with(input, o).map_err(|e| match &e {
        frepray::Error::Scene(se) => match o.key_of(&se.key) {
            Some(k) => format!("{}: {e}", flag(k)),
            None => e.to_string(),
        },
        _ => e.to_string(),
    })
}

/// The scene and its render options for `settings`; prints a warning for each flag
/// that has no effect on this render, or on any render of an experiment's `sweep` of
/// estimators when there is one.
pub fn load_options(
    input: &Path,
    settings: &frepray::Settings,
    sweep: &[String],
) -> Result<(frepray::Scene, frepray::RenderOptions), String> {
    let scene = load(input, settings)?;
    let (options, mut unused) = scene.options_with(settings).map_err(|e| e.to_string())?;
    if !sweep.is_empty() {
        let methods = sweep
            .iter()
            .map(|e| e.parse::<frepray::Method>().map_err(|e| e.to_string()))
            .collect::<Result<Vec<_>, _>>()?;
        unused = frepray::settings::unused_in_sweep(&settings.overrides, &options, &methods);
    }
    for u in &unused {
        note!("warning: {}", u.message(flag));
    }
    Ok((scene, options))
}

/// `--aovs a,b,c` as a list (blanks and empty entries dropped).
pub fn aov_list(aovs: Option<&str>) -> Option<Vec<String>> {
    aovs.map(|s| {
        s.split(',')
            .map(str::trim)
            .filter(|x| !x.is_empty())
            .map(String::from)
            .collect()
    })
}
