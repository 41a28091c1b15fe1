//! `frepray render SCENE.toml|.json`: light transport with the scene's settings, any of
//! them overridden on the command line.

use crate::output::{self, Format};
use render::integrator::{Aov, IntegratorKind, RenderOptions};
use render::render_loop;
use render::scene::{RenderSettings, Scene, SceneData};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Where a scene is rendered (the library's [`frepray::Backend`], for the command line).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    /// The CPU (every integrator and scene).
    #[default]
    Cpu,
    /// The GPU (wgpu; `direct` and `path`, with the limits docs/gpu.md lists).
    Gpu,
    /// The GPU where there is one and it can render the scene, else the CPU.
    Auto,
}

impl From<Backend> for frepray::Backend {
    fn from(b: Backend) -> Self {
        match b {
            Backend::Cpu => frepray::Backend::Cpu,
            Backend::Gpu => frepray::Backend::Gpu,
            Backend::Auto => frepray::Backend::Auto,
        }
    }
}

/// A render's result on either back end, with the GPU's own statistics.
type Rendered = (
    render::RenderState,
    render::RenderStats,
    Option<frepray::backend::GpuStats>,
);

/// Renders `samples` on `backend` (the library's [`frepray::render_range_on`]); `auto`
/// falls back to the CPU, saying why, where the GPU is missing or cannot render the
/// scene.
fn render_on(
    backend: Backend,
    data: &SceneData,
    scene: &Scene,
    opts: &RenderOptions,
    samples: Range<u32>,
    stop: &std::sync::atomic::AtomicBool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Rendered, String> {
    if backend == Backend::Gpu {
        if let Ok(g) = frepray::backend::shared_gpu() {
            note!("GPU: {}", g.info());
        }
    }
    let r = frepray::render_range_on(backend.into(), data, scene, opts, samples, stop, progress)
        .map_err(|e| e.to_string())?;
    if let Some(why) = &r.fallback {
        note!("note: --backend auto renders on the CPU: {why}");
    }
    Ok((r.state, r.stats, r.gpu))
}

/// The CPU's stage times, one line (all worker threads' time, summed).
fn cpu_line(s: &render::RenderStats) -> String {
    let st = s.rays.stages();
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    format!(
        "CPU stages ({} threads' time, summed): camera ray generation {:.1} ms, camera rays \
         {:.1} ms, shade {:.1} ms, shadow rays {:.1} ms, continuation rays {:.1} ms",
        s.threads,
        ms(st.generate),
        ms(st.camera),
        ms(st.shade),
        ms(st.shadow),
        ms(st.secondary)
    )
}

/// Command-line overrides of a scene's render settings, as given (see
/// [`Overrides::to_scene`]).
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// MIS heuristic or optimal estimator name.
    pub mis: Option<String>,
    /// Techniques as `name[:count],...`.
    pub techniques: Option<String>,
    /// Random seed.
    pub seed: Option<u64>,
    /// Integrator name.
    pub integrator: Option<String>,
    /// Image width.
    pub width: Option<u32>,
    /// Image height.
    pub height: Option<u32>,
    /// Path length limit.
    pub max_depth: Option<u32>,
    /// Shallowest path depth that reaches the image.
    pub min_depth: Option<u32>,
    /// Extra AOV channels, comma-separated.
    pub aovs: Option<String>,
    /// Worker threads (0: the global pool).
    pub threads: usize,
    /// Leave emitters seen directly by the camera out of the image.
    pub hide_emitters: bool,
    /// Camera rays through pixel centres (a diagnostic; `RenderOptions::pixel_center`).
    pub pixel_center: bool,
    /// Time the CPU's stages and print them (`RenderOptions::stage_times`).
    pub stage_times: bool,
    /// MIS parameters: power heuristic β, cutoff c, optimal-MIS ridge λ.
    pub beta: Option<f64>,
    /// Cutoff heuristic c.
    pub cutoff: Option<f64>,
    /// Optimal-MIS ridge λ (the solve uses λ/N · tr(Â)/T).
    pub ridge: Option<f64>,
    /// One MIS estimator per light.
    pub per_light: bool,
    /// Where to render.
    pub backend: Backend,
    /// `light-trained`'s grid cells per axis.
    pub trained_grid: Option<u32>,
    /// `light-trained`'s uniform floor.
    pub trained_floor: Option<f64>,
    /// `light-trained`'s training rays per pixel.
    pub trained_spp: Option<u32>,
}

impl Overrides {
    /// The overrides as the scene crate applies them to the description.
    pub fn to_scene(&self) -> Result<scene::Overrides, String> {
        let list = |s: &str| -> Vec<String> {
            s.split(',')
                .map(str::trim)
                .filter(|x| !x.is_empty())
                .map(String::from)
                .collect()
        };
        Ok(scene::Overrides {
            spp: self.spp,
            estimator: self.mis.clone(),
            techniques: self
                .techniques
                .as_deref()
                .map(scene::parse_technique_list)
                .transpose()
                .map_err(|e| format!("--techniques: {e}"))?,
            seed: self.seed,
            integrator: self.integrator.clone(),
            width: self.width,
            height: self.height,
            max_depth: self.max_depth,
            min_depth: self.min_depth,
            aovs: self.aovs.as_deref().map(list),
            hide_emitters: self.hide_emitters,
            beta: self.beta,
            cutoff: self.cutoff,
            ridge: self.ridge,
            per_light: self.per_light,
            trained_grid: self.trained_grid,
            trained_floor: self.trained_floor,
            trained_spp: self.trained_spp,
        })
    }
}

/// The command-line flag that sets the value at an overridden scene key.
fn flag(key: &str) -> &'static str {
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
}

/// Loads a scene file with the overrides applied before it is resolved (so that they
/// are validated once, with the file's own values): the resolved data and settings.
/// An error about an overridden value names its flag.
pub fn resolve(input: &Path, o: &Overrides) -> Result<(SceneData, RenderSettings), String> {
    let so = o.to_scene()?;
    scene::load_with(input, &so).map_err(|e| match so.key_of(&e.key) {
        Some(k) => format!("{}: {e}", flag(k)),
        None => e.to_string(),
    })
}

/// Loads a scene file with overrides: the CPU scene and its render options.
pub fn load(input: &Path, o: &Overrides) -> Result<(Scene, RenderOptions), String> {
    let (data, settings) = resolve(input, o)?;
    let mut opts = RenderOptions::from_settings(&settings)?;
    opts.threads = o.threads;
    opts.pixel_center = o.pixel_center;
    opts.validate()?;
    Ok((Scene::from_data(&data), opts))
}

/// Parses a sample range `A..B` (samples A to B−1 of every pixel).
pub fn parse_samples(s: &str) -> Result<Range<u32>, String> {
    let bad = || format!("--samples {s:?}: expected START..END with START < END, e.g. 0..64");
    let (a, b) = s.split_once("..").ok_or_else(bad)?;
    let (a, b): (u32, u32) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if a >= b {
        return Err(bad());
    }
    Ok(a..b)
}

/// Writes the resolved scene as pretty JSON (`--dump-scene`).
pub fn dump(data: &SceneData, path: &Path) -> Result<(), String> {
    let json = serde_json::to_string_pretty(data).map_err(|e| e.to_string())?;
    std::fs::write(path, json + "\n").map_err(|e| format!("{}: {e}", path.display()))
}

/// Loads, renders (samples `0..spp`, or `samples`) and writes a scene; prints
/// statistics. With `dump_to`, the resolved scene is also written there as JSON (and
/// nothing is rendered without outputs).
#[allow(clippy::too_many_arguments)]
pub fn run(
    input: &Path,
    outs: &[PathBuf],
    dump_to: Option<&Path>,
    o: &Overrides,
    samples: Option<Range<u32>>,
    resume: Option<&Path>,
    quiet: bool,
    max_memory: u64,
    overwrite_partial: bool,
    film: &output::FilmArgs,
) -> Result<(), String> {
    let start = std::time::Instant::now();
    let formats = output::check_scene_outputs(outs)?;
    if resume.is_some() && o.backend == Backend::Gpu {
        return Err(
            "--resume renders on the CPU (the GPU renders whole waves of samples, not each \
             pixel from where it stopped); leave out --backend gpu"
                .into(),
        );
    }
    let resume_from = resume
        .map(|p| render::RenderState::read(p).map_err(|e| e.to_string()))
        .transpose()?;
    if let Some(d) = dump_to {
        output::check_writable(d)?;
    }
    let (data, settings) = resolve(input, o)?;
    output::check_not_inputs(outs, input, &data.inputs)?;
    let film = film.over(render::Film {
        exposure: settings.exposure,
        tonemap: settings.tonemap,
    })?;
    let mut opts = RenderOptions::from_settings(&settings)?;
    opts.threads = o.threads;
    opts.pixel_center = o.pixel_center;
    opts.stage_times = o.stage_times;
    opts.max_memory = max_memory;
    opts.validate()?;
    warn_unused(o, &opts);
    if let Some(path) = dump_to {
        dump(&data, path)?;
        note!("resolved scene written to {}", path.display());
        if outs.is_empty() {
            return Ok(());
        }
    }
    opts.scene_hash = frepray::scene_hash(&data);
    let samples = samples.unwrap_or(0..opts.spp);
    let (width, height) = (data.camera.width, data.camera.height);
    render::limits::check_memory(width, height, &opts).map_err(|e| e.to_string())?;
    let scene = Scene::from_data(&data);
    // What a render waits for before its first sample (Mitsuba's "Loading scene" line).
    let load = start.elapsed();
    if !formats.contains(&Format::Exr) && !opts.aovs.is_empty() {
        note!(
            "note: AOV channels ({}) are only written to .exr",
            aov_list(&opts.aovs)
        );
    }

    let stop = crate::stop_on_ctrl_c();
    let bar = crate::progress_bar(quiet, "samples");
    let progress = |done, total| {
        bar.set_length(total);
        bar.set_position(done);
    };
    let result = match &resume_from {
        Some(partial) => {
            if o.backend == Backend::Auto {
                note!("note: --resume renders on the CPU");
            }
            let pixels = u64::from(width) * u64::from(height);
            let have: u64 = (0..height)
                .flat_map(|y| (0..width).map(move |x| (x, y)))
                .map(|(x, y)| partial.iterations(x, y))
                .sum();
            let r = partial.samples();
            let want = r.first().map_or(0, |r| u64::from(r.end - r.start)) * pixels;
            note!("resuming: {have} of {want} samples rendered before");
            render_loop::resume(&scene, &opts, partial, &stop, &progress)
                .map(|(s, st)| (s, st, None))
                .map_err(|e| match resume {
                    Some(p) => format!("--resume {}: {e}", p.display()),
                    None => e.to_string(),
                })
        }
        None => render_on(o.backend, &data, &scene, &opts, samples, &stop, &progress),
    };
    bar.finish_and_clear();
    let (state, stats, g) = result?;
    note!(
        "scene: loaded in {:.3} s (parsing, solids with their bounds and grids, lights, materials)",
        load.as_secs_f64()
    );
    note!("{stats}");
    if let Some(g) = &g {
        note!("{g}");
    } else if opts.stage_times {
        note!("{}", cpu_line(&stats));
    }
    let (mut outs, mut formats) = (outs.to_vec(), formats);
    if stats.stopped {
        // A state to resume from, beside the outputs asked for.
        if !formats.contains(&Format::State) {
            outs.push(outs[0].with_extension("state"));
            formats.push(Format::State);
        }
        outs = outs
            .iter()
            .map(|p| output::partial_path(p, overwrite_partial))
            .collect();
    }
    output::write_state(&outs, &formats, &state, &film)?;
    if stats.stopped {
        let at = formats
            .iter()
            .position(|f| *f == Format::State)
            .unwrap_or(0);
        note!(
            "interrupted: what was rendered is {} written; `frepray render {} --resume {} -o …` \
             with the same options renders the rest",
            output::list(&outs),
            input.display(),
            outs[at].display()
        );
    } else {
        note!("{} written", output::list(&outs));
    }
    Ok(())
}

/// Warns about overrides that do not apply to the chosen estimator or integrator.
fn warn_unused(o: &Overrides, opts: &RenderOptions) {
    use frepray::Method;
    let optimal = !matches!(
        opts.method,
        Method::Balance | Method::Power | Method::Maximum | Method::Cutoff
    );
    let mis = matches!(
        opts.integrator,
        IntegratorKind::Direct | IntegratorKind::Path
    );
    let unused = [
        (
            "--beta",
            o.beta.is_some() && (!mis || opts.method != Method::Power),
            "--estimator power",
        ),
        (
            "--cutoff",
            o.cutoff.is_some() && (!mis || opts.method != Method::Cutoff),
            "--estimator cutoff",
        ),
        (
            "--ridge",
            o.ridge.is_some() && (!mis || !optimal),
            "an optimal estimator (--estimator optimal-*)",
        ),
        (
            "--max-depth",
            o.max_depth.is_some() && opts.integrator != IntegratorKind::Path,
            "--integrator path",
        ),
        (
            "--estimator",
            o.mis.is_some() && !mis,
            "--integrator direct or path",
        ),
        (
            "--techniques",
            o.techniques.is_some() && !mis,
            "--integrator direct or path",
        ),
        (
            "--trained-grid/--trained-floor/--trained-spp",
            (o.trained_grid.is_some() || o.trained_floor.is_some() || o.trained_spp.is_some())
                && !(mis
                    && opts
                        .techniques
                        .iter()
                        .any(|(t, _)| *t == render::Technique::LightTrained)),
            "the light-trained technique",
        ),
    ];
    for (flag, _, applies) in unused.iter().filter(|u| u.1) {
        note!(
            "warning: {flag} has no effect here (integrator {}, estimator {}); it applies with {applies}",
            opts.integrator,
            opts.method.name()
        );
    }
}

/// Runs `direct` and `path` with the scene's settings and prints throughput; both are
/// checked against the memory limit (`max_memory`, 0: the available memory) first.
pub fn bench(
    input: &Path,
    o: &Overrides,
    max_memory: u64,
    backends: &[Backend],
    plot: Option<&Path>,
) -> Result<(), String> {
    if let Some(p) = plot {
        let svg = p.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg"));
        if !svg {
            return Err(format!(
                "{}: --plot writes an SVG drawing; name it .svg",
                p.display()
            ));
        }
        output::check_writable(p)?;
    }
    let (data, _) = resolve(input, o)?;
    let (scene, mut opts) = load(input, o)?;
    opts.max_memory = max_memory;
    for integrator in [IntegratorKind::Direct, IntegratorKind::Path] {
        let o = RenderOptions {
            integrator,
            ..opts.clone()
        };
        render::limits::check_memory(scene.camera.width, scene.camera.height, &o)
            .map_err(|e| e.to_string())?;
    }
    let stop = crate::stop_on_ctrl_c();
    let mut rows: Vec<(&str, render::RenderStats)> = Vec::new();
    let mut stages = Vec::new();
    for &b in backends {
        if b == Backend::Cpu {
            let stats = render_loop::bench(&scene, &opts, &stop).map_err(|e| e.to_string())?;
            rows.extend(stats.into_iter().map(|s| ("cpu", s)));
            continue;
        }
        let g = frepray::backend::shared_gpu().map_err(|e| e.to_string())?;
        note!("GPU: {}", g.info());
        for integrator in [IntegratorKind::Direct, IntegratorKind::Path] {
            let o = RenderOptions {
                integrator,
                ..opts.clone()
            };
            let on_gpu = |r: Range<u32>| {
                frepray::render_range_on(
                    frepray::Backend::Gpu,
                    &data,
                    &scene,
                    &o,
                    r,
                    &stop,
                    &|_, _| {},
                )
                .map_err(|e| e.to_string())
            };
            // A first 1-spp render compiles the kernels: not timed (GPU.md §10).
            on_gpu(0..1)?;
            let r = on_gpu(0..o.spp)?;
            rows.push(("gpu", r.stats));
            stages.extend(r.gpu.map(|g| (integrator, g)));
        }
    }
    out!(
        "| scene | backend | integrator | MIS | resolution | spp | time (s) | MSamples/s | MRays/s | camera | secondary | shadow |"
    );
    out!("| --- | --- | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for (backend, s) in &rows {
        let (c, sec, sh) = s.mrays_per_s_by_kind();
        out!(
            "| {} | {backend} | {} | {} | {}×{} | {} | {:.2} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
            input.file_name().unwrap_or_default().to_string_lossy(),
            s.integrator,
            opts.method.name(),
            scene.camera.width,
            scene.camera.height,
            opts.spp,
            s.wall.as_secs_f64(),
            s.msamples_per_s(),
            s.mrays_per_s(),
            c,
            sec,
            sh
        );
    }
    let mut bars = Vec::new();
    for (_, s) in rows.iter().filter(|r| r.0 == "cpu") {
        let st = s.rays.stages();
        let parts = [
            ("camera ray generation", st.generate),
            ("camera rays", st.camera),
            ("shade (sampling, BSDFs, lights, MIS)", st.shade),
            ("shadow rays", st.shadow),
            ("continuation rays", st.secondary),
        ];
        stage_table(&format!("CPU stage ({})", s.integrator), &parts);
        out!("");
        out!(
            "CPU time of {} worker threads, summed; one query of each kind in {} timed \
             (render::integrator::RayCounts)",
            s.threads,
            render::integrator::TIMED_EVERY
        );
        bars.push((format!("CPU {}", s.integrator), parts.to_vec()));
    }
    for (integrator, g) in &stages {
        let parts = g.stage_parts();
        stage_table(&format!("GPU stage ({integrator})"), &parts);
        out!("");
        out!("{}", g.counters());
        bars.push((format!("GPU {integrator}"), parts.to_vec()));
    }
    if let Some(p) = plot {
        use std::io::Write;
        let name = input.file_name().unwrap_or_default().to_string_lossy();
        let title = format!("Stage times, {name} ({} spp)", opts.spp);
        let svg = crate::stage_plot::svg(&title, &bars);
        render::output::write_atomically(p, |w| w.write_all(svg.as_bytes()))
            .map_err(|e| format!("{}: {e}", p.display()))?;
        note!("{} written", p.display());
    }
    Ok(())
}

/// A stage breakdown as a table: each stage's time and share.
fn stage_table(title: &str, parts: &[(&str, std::time::Duration)]) {
    let total: f64 = parts.iter().map(|p| p.1.as_secs_f64()).sum();
    out!("");
    out!("| {title} | ms | % |");
    out!("| --- | ---: | ---: |");
    for (name, d) in parts {
        let ms = d.as_secs_f64() * 1e3;
        out!(
            "| {name} | {ms:.1} | {:.1} |",
            100.0 * d.as_secs_f64() / total.max(1e-12)
        );
    }
}

fn aov_list(a: &[Aov]) -> String {
    a.iter().map(|x| x.name()).collect::<Vec<_>>().join(", ")
}

/// Whether a path names a scene file rather than a model.
pub fn is_scene(path: &Path) -> bool {
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref(),
        Some("toml" | "json")
    )
}
