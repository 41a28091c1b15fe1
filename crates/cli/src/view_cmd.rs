//! `frepray view SCENE|MODEL`: a live preview in the browser ([`frepray::view`]).

use crate::scene_flags;
use std::path::PathBuf;

/// Arguments of `frepray view`.
#[derive(clap::Args)]
pub struct ViewArgs {
    /// A scene file (.toml or .json) or a model file (.frep, .hf or .vm); it and the
    /// files it names are watched, and a save restarts the render.
    input: PathBuf,
    /// The port on 127.0.0.1 (0: a free one).
    #[arg(long, default_value_t = 0)]
    port: u16,
    /// Also render every pass with rays through pixel centres, so that the inspector
    /// splits each pixel's variance into the footprint's and the directions' (the part
    /// MIS weights act on); twice the work.
    #[arg(long)]
    decompose: bool,
    /// Samples per pixel to render to [the scene's; 64 for models].
    #[arg(long)]
    spp: Option<u32>,
    /// MIS estimator (scenes); the page can switch it.
    #[arg(long = "estimator", value_name = "NAME")]
    estimator: Option<String>,
    /// Random seed (scenes).
    #[arg(long)]
    seed: Option<u64>,
    /// Scenes: direct, path, depth, normals or albedo.
    #[arg(long)]
    integrator: Option<String>,
    /// Extra channels the page can show (scenes), e.g. `depth,normal,albedo`.
    #[arg(long)]
    aovs: Option<String>,
    #[command(flatten)]
    scene: scene_flags::SceneFlags,
}

/// Serves the page until Ctrl-C.
pub fn run(args: ViewArgs) -> Result<(), String> {
    crate::set_threads(args.scene.threads)?;
    let mut settings = args.scene.settings()?;
    let o = &mut settings.overrides;
    o.spp = args.spp;
    o.estimator = args.estimator.clone();
    o.seed = args.seed;
    o.integrator = args.integrator.clone();
    o.aovs = scene_flags::aov_list(args.aovs.as_deref());
    let viewer = frepray::view::Viewer::bind(&args.input, settings, args.port, args.decompose)
        .map_err(|e| e.to_string())?;
    let stop = crate::stop_on_ctrl_c();
    note!("frepray view: open {}", viewer.url());
    out!("{}", viewer.url());
    viewer.run(&stop).map_err(|e| e.to_string())?;
    note!("frepray view: stopped");
    Ok(())
}
