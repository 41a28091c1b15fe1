//! `frepray`: render functionally defined scenes, check model files.

/// `println!` that ends the program quietly (status 0) when stdout is a closed pipe, as
/// in `frepray check … | head -1`, instead of panicking.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let mut o = std::io::stdout().lock();
        if let Err(e) = writeln!(o, $($arg)*) {
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                std::process::exit(0);
            }
            note!("warning: cannot write to stdout: {e}");
        }
    }};
}

/// `eprintln!` that never panics: a message that cannot be written (stderr closed, full,
/// or a log pipe that went away) is dropped, and the work it reports on — a finished
/// render, its output files — goes on.
macro_rules! note {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr().lock(), $($arg)*);
    }};
}

mod check;
mod denoised;
mod experiment_cmd;
mod interrupt;
mod merge_cmd;
mod mesh_cmd;
mod output;
mod scene_flags;
mod scene_render;
mod stage_plot;
mod view_cmd;

use clap::{Parser, Subcommand, ValueEnum};
use frepray::preview;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// frepray: a physically based renderer for functionally defined (FRep) scenes —
/// solids where F(x, y, z) ≥ 0 (perturbed quadrics, CSG, blends, HyperFun and Fidget
/// models) — with Monte Carlo light transport and optimal multiple importance sampling.
///
/// Exit status: 0 on success, 1 on an error, 128 + the signal when interrupted: 130 by
/// Ctrl-C, 143 by SIGTERM, 129 by SIGHUP (the partial result is written first; a second
/// signal quits at once; see `frepray render --help`).
#[derive(Parser)]
#[command(name = "frepray", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

// Negative numbers are values, so that `--seed -1` is refused as a negative seed
// rather than with clap's tip to write `-- -1` (which would make it the input file).
#[derive(Subcommand)]
enum Command {
    /// Render a scene (.toml, .json) or a bare model (.frep, .hf, .vm) to .png or .exr.
    #[command(allow_negative_numbers = true)]
    Render(RenderArgs),
    /// Measure MSamples/s and MRays/s of `direct` and `path` on a scene.
    #[command(allow_negative_numbers = true)]
    Bench(BenchArgs),
    /// Compare estimators against a reference: RMSE against samples and time, plots,
    /// Improvement / Speed Up / Overhead tables; resumable.
    #[command(allow_negative_numbers = true)]
    Experiment(experiment_cmd::ExperimentArgs),
    /// Merge render states (.state) of disjoint sample ranges of one render into one
    /// image (.png, .exr) or state.
    Merge(merge_cmd::MergeArgs),
    /// Validate a scene or model file and print a summary (scenes: resolution,
    /// objects, lights, settings; models: bounds, node count, perturbations), or print
    /// what made an image (.exr: its header's record of the render) or a state (.state).
    Check {
        /// The scene (.toml, .json), model (.frep, .hf, .vm), image (.exr) or state
        /// (.state) file.
        file: PathBuf,
    },
    /// Write a watertight triangle mesh of a model's surface (.obj or .stl), for 3-D
    /// printing and other tools: vertices on F = 0, about bounds / resolution apart.
    Mesh(mesh_cmd::MeshArgs),
    /// A live preview in the browser: a local page (127.0.0.1, a token in its URL) that
    /// renders progressively, re-renders when the scene or a file it names is saved,
    /// and inspects pixels (samples, standard error, the optimal estimators' α).
    View(view_cmd::ViewArgs),
    /// The GPU back end's adapters.
    Gpu {
        #[command(subcommand)]
        what: GpuCommand,
    },
}

/// What `frepray gpu` does.
#[derive(clap::Subcommand)]
enum GpuCommand {
    /// List the adapters (index, name, backend, type, and whether each has the features
    /// frepray uses: f64, int64, subgroups, timestamps); `--gpu-options adapter=N`
    /// chooses one.
    List,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// A scene file (.toml or .json) or a model file (.frep, .hf or .vm).
    input: PathBuf,
    /// Output: .png (sRGB, display), .exr (linear, with AOV channels) or .state (scenes:
    /// every pixel's sums, for `frepray merge`); repeat the flag to write several files
    /// from one render.
    #[arg(short, long, required_unless_present = "dump_scene")]
    output: Vec<PathBuf>,
    /// Render samples START..END of every pixel (scenes) instead of 0..spp; states of
    /// disjoint ranges merge into the render of their union (`frepray merge`).
    #[arg(long, value_name = "START..END")]
    samples: Option<String>,
    /// Continue a stopped render (scenes): render what the partial state
    /// (`NAME.partial.state`, written when a render is interrupted) lacks and write the
    /// outputs of the whole render — bit for bit what the render would have given
    /// uninterrupted. Give the scene and options of the stopped render; on the CPU.
    #[arg(long, value_name = "NAME.partial.state", conflicts_with = "samples")]
    resume: Option<PathBuf>,
    /// Write the resolved scene (after overrides; a model's preview scene) as JSON to
    /// this file, for debugging and GPU tests; without -o nothing is rendered.
    #[arg(long, value_name = "FILE.json")]
    dump_scene: Option<PathBuf>,
    /// Scenes: direct, path, depth, normals or albedo. Models: shaded, depth or normals.
    #[arg(long)]
    integrator: Option<String>,
    /// Samples per pixel [scene's, or 4 for models].
    #[arg(long)]
    spp: Option<u32>,
    /// MIS estimator (scenes; the scene file's `estimator`): balance, power, maximum,
    /// cutoff (the heuristics), optimal-direct, optimal-uncorrelated,
    /// optimal-progressive, optimal-full. `--mis` is its older name.
    #[arg(long = "estimator", alias = "mis", value_name = "NAME")]
    estimator: Option<String>,
    /// Random seed (scenes): the same seed gives the same image at any thread count.
    #[arg(long)]
    seed: Option<u64>,
    /// Print the CPU's time per stage after the render (camera-ray generation, camera,
    /// shadow and continuation rays, shading), as `bench` does; the timers slow the
    /// render by a few per cent.
    #[arg(long)]
    stage_times: bool,
    /// Extra EXR channels (scenes), e.g. `depth,normal,albedo`.
    #[arg(long)]
    aovs: Option<String>,
    #[command(flatten)]
    scene: scene_flags::SceneFlags,
    /// A model's vertical axis (models).
    #[arg(long, value_enum, default_value_t = UpArg::Z)]
    up: UpArg,
    /// The side a model is seen from (models). With z up: front looks along +y, back
    /// along −y, left along +x, right along −x, top along −z (x right, y up: how Fidget
    /// shows its 2-D models), bottom along +z; with x or y up the front looks along −z
    /// [default: iso; a 2-D model (no z): top, with parallel rays].
    #[arg(long, value_enum)]
    view: Option<ViewArg>,
    /// Parallel rays instead of a 30° perspective (models): the model's outline fills
    /// the image.
    #[arg(long)]
    orthographic: bool,
    /// Where to render: cpu; gpu (wgpu: `direct` and `path` on scenes of quadrics, CSG
    /// of plain quadrics and one expression, area lights and rough materials, and a
    /// model's preview; docs/gpu.md); or auto (the GPU where it can, else the CPU).
    #[arg(long, value_enum, default_value_t = scene_render::Backend::Cpu)]
    backend: scene_render::Backend,
    /// GPU features, comma-separated, each `=on` or `=off` (a bare name: on): f64,
    /// int64, subgroups, sums (on where the adapter has them), checked (runtime bounds
    /// checks in the kernels, a diagnostic; off); and adapter=N, the N-th adapter of
    /// `frepray gpu list` [the `FREPRAY_GPU_*` variables; the first adapter].
    #[arg(long, value_name = "LIST")]
    gpu_options: Option<String>,
    /// On Ctrl-C, SIGTERM or SIGHUP, write the partial result to the -o names themselves instead of
    /// `NAME.partial.EXT` (which never replaces a finished file).
    #[arg(long)]
    overwrite_partial: bool,
    /// Also write a denoised copy here (.exr or .png; never one of the -o outputs):
    /// Intel Open Image Denoise, guided by the albedo and normal AOVs where the render
    /// has them (`--aovs albedo,normal`). For looking at, not measuring; the library
    /// comes from `pip install pyoidn` or $FREPRAY_OIDN (docs/denoise.md).
    #[arg(long, value_name = "FILE")]
    denoised: Option<PathBuf>,
    /// Hide the progress bar.
    #[arg(long)]
    quiet: bool,
    #[command(flatten)]
    film: output::FilmArgs,
}

/// A model's vertical axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum UpArg {
    /// x up.
    X,
    /// y up.
    Y,
    /// z up (Fidget's colonnade.vm is modelled z-up too).
    Z,
}

impl From<UpArg> for preview::Up {
    fn from(u: UpArg) -> Self {
        match u {
            UpArg::X => preview::Up::X,
            UpArg::Y => preview::Up::Y,
            UpArg::Z => preview::Up::Z,
        }
    }
}

/// The side a model is seen from ([`preview::View`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ViewArg {
    /// From the front-left-above diagonal.
    Iso,
    /// Along +y (z up).
    Front,
    /// Along −y (z up).
    Back,
    /// Along +x (z up).
    Left,
    /// Along −x (z up).
    Right,
    /// Down the up axis (z up: along −z, x right, y up).
    Top,
    /// Up the up axis (z up: along +z).
    Bottom,
}

impl From<ViewArg> for preview::View {
    fn from(v: ViewArg) -> Self {
        match v {
            ViewArg::Iso => preview::View::Iso,
            ViewArg::Front => preview::View::Front,
            ViewArg::Back => preview::View::Back,
            ViewArg::Left => preview::View::Left,
            ViewArg::Right => preview::View::Right,
            ViewArg::Top => preview::View::Top,
            ViewArg::Bottom => preview::View::Bottom,
        }
    }
}

#[derive(clap::Args)]
struct BenchArgs {
    /// The scene file (.toml or .json).
    scene: PathBuf,
    /// Samples per pixel [the scene's].
    #[arg(long)]
    spp: Option<u32>,
    /// MIS estimator, as for `render` (`--mis` is its older name) [the scene's].
    #[arg(long = "estimator", alias = "mis", value_name = "NAME")]
    estimator: Option<String>,
    #[command(flatten)]
    flags: scene_flags::SceneFlags,
    /// Back ends to measure, comma-separated: cpu, gpu (direct and path on each; the GPU's
    /// kernels are compiled by an untimed 1-spp render first).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "cpu")]
    backend: Vec<scene_render::Backend>,
    /// GPU features, comma-separated, each `=on` or `=off` (a bare name: on): f64,
    /// int64, subgroups, sums (on where the adapter has them), checked (runtime bounds
    /// checks in the kernels, a diagnostic; off); and adapter=N, the N-th adapter of
    /// `frepray gpu list` [the `FREPRAY_GPU_*` variables; the first adapter].
    #[arg(long, value_name = "LIST")]
    gpu_options: Option<String>,
    /// Also draw the stage times as stacked bars (the paper's Fig. 4–5) into this SVG
    /// file.
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<PathBuf>,
}

fn main() -> ExitCode {
    runtime_dir();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Gpu {
            what: GpuCommand::List,
        } => gpu_list(),
        Command::Render(args) => render(args),
        Command::Bench(args) => bench(args),
        Command::Experiment(args) => experiment_cmd::run(args),
        Command::Merge(args) => merge_cmd::run(args),
        Command::Mesh(args) => mesh_cmd::run(args),
        Command::View(args) => view_cmd::run(args),
        Command::Check { file } => check::run(&file),
    };
    let code = match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            note!("error: {e}");
            ExitCode::FAILURE
        }
    };
    match interrupt::exit_status() {
        Some(status) => ExitCode::from(status),
        None => code,
    }
}

/// Gives Mesa's Vulkan drivers a runtime directory where the session has none (a
/// container, a CI job, `ssh` without a login session): without one they print
/// "XDG_RUNTIME_DIR is invalid or not set" on every run that touches the GPU. A private
/// directory (mode 0700) under the temporary directory, made once per user; nothing
/// changes when it cannot be made. Run first in `main`, before any thread exists.
fn runtime_dir() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir()) {
        return;
    }
    use std::os::unix::fs::{DirBuilderExt, MetadataExt};
    // The real user id, from the owner of a file the process creates its own: /proc's.
    let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("frepray-runtime-{uid}"));
    // Made now, or by an earlier run; used only where it is this user's own.
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let ours = std::fs::metadata(&dir).is_ok_and(|m| m.is_dir() && m.uid() == uid);
    if ours {
        std::env::set_var("XDG_RUNTIME_DIR", &dir);
    }
}

/// `frepray gpu list`: the adapters, a line each, or why there are none.
fn gpu_list() -> Result<(), String> {
    let list = frepray::backend::gpu_adapters().map_err(|e| e.to_string())?;
    if list.is_empty() {
        return Err(
            "no GPU adapter found; on Linux without a GPU install Mesa's lavapipe \
                    (apt-get install mesa-vulkan-drivers libvulkan1)"
                .into(),
        );
    }
    for line in list {
        println!("{line}");
    }
    Ok(())
}

/// Sets the global thread pool's size (0 keeps one thread per core); refuses more
/// than [`frepray::limits::max_threads`].
pub fn set_threads(n: usize) -> Result<(), String> {
    frepray::limits::check_threads(n).map_err(|e| e.to_string())?;
    if n > 0 {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// Sets `--gpu-options` for the process's GPU, when given.
fn configure_gpu(list: Option<&str>) -> Result<(), String> {
    match list {
        Some(l) => frepray::backend::configure_gpu(l)
            .map(|_| ())
            .map_err(|e| format!("--gpu-options: {e}")),
        None => Ok(()),
    }
}

/// A flag that Ctrl-C, SIGTERM and SIGHUP set, so that a render stops and keeps what it
/// has ([`interrupt`]).
pub fn stop_on_ctrl_c() -> Arc<AtomicBool> {
    interrupt::stop_flag()
}

/// A progress bar (hidden when `quiet`).
pub fn progress_bar(quiet: bool, unit: &str) -> indicatif::ProgressBar {
    if quiet {
        return indicatif::ProgressBar::hidden();
    }
    let template = format!("{{bar:40}} {{pos}}/{{len}} {unit}  {{elapsed}} (eta {{eta}})");
    indicatif::ProgressBar::new(0)
        .with_style(indicatif::ProgressStyle::with_template(&template).expect("a valid template"))
}

fn render(args: RenderArgs) -> Result<(), String> {
    set_threads(args.scene.threads)?;
    if scene_render::is_scene(&args.input) {
        let model_only = [
            ("--view", args.view.is_some()),
            ("--orthographic", args.orthographic),
            ("--up", args.up != UpArg::Z),
        ];
        if let Some((flag, _)) = model_only.iter().find(|(_, set)| *set) {
            return Err(format!(
                "{flag} applies to model files (.frep, .hf, .vm); {} is a scene (its \
                 [camera] sets the view: type = \"orthographic\" for parallel rays)",
                args.input.display()
            ));
        }
        configure_gpu(args.gpu_options.as_deref())?;
        let mut settings = args.scene.settings()?;
        let o = &mut settings.overrides;
        o.spp = args.spp;
        o.estimator = args.estimator.clone();
        o.seed = args.seed;
        o.integrator = args.integrator.clone();
        o.aovs = scene_flags::aov_list(args.aovs.as_deref());
        settings.stage_times = args.stage_times;
        let samples = args
            .samples
            .as_deref()
            .map(scene_render::parse_samples)
            .transpose()?;
        return scene_render::run(&args, &settings, samples);
    }
    let is_model = args
        .input
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["frep", "hf", "vm"].contains(&e.to_ascii_lowercase().as_str()));
    if !is_model {
        return Err(format!(
            "{}: unknown kind of file; expected {}",
            args.input.display(),
            check::KINDS
        ));
    }
    let scene_only = [
        ("--estimator", args.estimator.is_some()),
        ("--seed", args.seed.is_some()),
        ("--aovs", args.aovs.is_some()),
        ("--stage-times", args.stage_times),
        ("--samples", args.samples.is_some()),
        ("--resume", args.resume.is_some()),
    ];
    let transport = args.scene.transport_flags();
    if let Some((flag, _)) = scene_only.iter().chain(&transport).find(|(_, set)| *set) {
        return Err(format!(
            "{flag} applies to scene files (.toml, .json); {} is a model (name it as an \
             object's `model` in a scene for the full set of options)",
            args.input.display()
        ));
    }
    configure_gpu(args.gpu_options.as_deref())?;
    if let Some(d) = &args.dump_scene {
        output::check_writable(d)?;
    }
    let look = match args.integrator.as_deref() {
        None | Some("shaded") => preview::Look::Shaded,
        Some("depth") => preview::Look::Depth,
        Some("normals") => preview::Look::Normals,
        Some(other) => {
            return Err(format!(
                "--integrator {other}: a model is shown with shaded, depth or normals"
            ))
        }
    };
    let (width, height) = (
        args.scene.width.unwrap_or(512),
        args.scene.height.unwrap_or(512),
    );
    let formats = args
        .output
        .iter()
        .map(|p| {
            let f = output::format_for_model(p)?;
            output::check_writable(p)?;
            Ok(f)
        })
        .collect::<Result<Vec<_>, String>>()?;
    if args.denoised.is_some() && output::model_values(look).is_some() {
        return Err("--denoised applies to shaded renders, not depth or normals".into());
    }
    let denoised = denoised::Denoised::prepare(args.denoised.as_deref(), &args.output)?;
    if width == 0 || height == 0 {
        return Err("--width and --height must be at least 1".into());
    }
    let spp = args.spp.unwrap_or(4);
    if spp == 0 {
        return Err("--spp must be at least 1".into());
    }
    let film = args.film.over(frepray::Film::default())?;
    let limit = frepray::RenderOptions {
        max_memory: args.scene.max_memory.unwrap_or(0),
        ..preview::options(look, spp, 0)
    };
    frepray::limits::check_memory(width, height, &limit).map_err(|e| e.to_string())?;
    let start = std::time::Instant::now();
    let model = preview::load(&args.input).map_err(|e| e.to_string())?;
    let setup = start.elapsed();
    let clipped: Vec<&str> = ["x", "y", "z"]
        .into_iter()
        .zip(model.view_box.clipped)
        .filter_map(|(a, c)| c.then_some(a))
        .collect();
    if !clipped.is_empty() {
        let b = model.view_box.bounds;
        note!(
            "note: the surface is unbounded along {} (it reaches the ±{} search domain); \
             the view shows [{:.3}, {:.3}] × [{:.3}, {:.3}] × [{:.3}, {:.3}]",
            clipped.join(", "),
            preview::DEFAULT_DOMAIN,
            b.lo.x,
            b.hi.x,
            b.lo.y,
            b.hi.y,
            b.lo.z,
            b.hi.z
        );
    }
    // A 2-D model is seen as Fidget shows it: from the top, parallel rays.
    let (view, orthographic) = match args.view {
        Some(v) => (v, args.orthographic),
        None if model.planar => {
            if !args.quiet {
                note!(
                    "note: a 2-D model (F does not depend on z): seen from the top with parallel rays \
                     (--view chooses another side)"
                );
            }
            (ViewArg::Top, true)
        }
        None => (ViewArg::Iso, args.orthographic),
    };
    let stop = stop_on_ctrl_c();
    let bar = progress_bar(args.quiet, "samples");
    let o = preview::PreviewOptions {
        up: args.up.into(),
        view: view.into(),
        orthographic,
        width,
        height,
        look,
        spp,
    };
    let scene = preview::model_scene(model, &o).map_err(|e| e.to_string())?;
    if let Some(path) = &args.dump_scene {
        scene_render::dump(scene.data(), path)?;
        note!("resolved scene written to {}", path.display());
        if args.output.is_empty() {
            return Ok(());
        }
    }
    if args.backend == scene_render::Backend::Gpu {
        if let Ok(g) = frepray::backend::shared_gpu() {
            note!("GPU: {}", g.info());
        }
    }
    let result = scene.render_on(
        args.backend.into(),
        &preview::options(look, spp, 0),
        0..spp,
        &stop,
        &|done, total| {
            bar.set_length(total);
            bar.set_position(done);
        },
    );
    bar.finish_and_clear();
    let r = result.map_err(|e| e.to_string())?;
    if let Some(why) = &r.fallback {
        note!("note: --backend auto renders on the CPU: {why}");
    }
    if let Some(g) = &r.gpu {
        note!("{g}");
    }
    let (state, stats) = (r.state, r.stats);
    note!(
        "{}: setup {:.2} s; {stats}",
        args.input.display(),
        setup.as_secs_f64()
    );
    let outs: Vec<PathBuf> = if stats.stopped {
        args.output
            .iter()
            .map(|p| output::partial_path(p, args.overwrite_partial))
            .collect()
    } else {
        args.output.clone()
    };
    let mut image = state.image();
    output::describe_render(&mut image, &args.input, &stats, r.gpu.is_some());
    output::write_all(&outs, &formats, &image, &film, output::model_values(look))?;
    note!(
        "{}{} written",
        if stats.stopped {
            "interrupted: what was rendered is "
        } else {
            ""
        },
        output::list(&outs)
    );
    match (&denoised, stats.stopped) {
        (Some(d), false) => d.write(&image, &film),
        (Some(_), true) => {
            note!("note: interrupted: no denoised copy");
            Ok(())
        }
        (None, _) => Ok(()),
    }
}

fn bench(args: BenchArgs) -> Result<(), String> {
    set_threads(args.flags.threads)?;
    configure_gpu(args.gpu_options.as_deref())?;
    let mut settings = args.flags.settings()?;
    settings.overrides.spp = args.spp;
    settings.overrides.estimator = args.estimator.clone();
    scene_render::bench(&args.scene, &settings, &args.backend, args.plot.as_deref())
}
