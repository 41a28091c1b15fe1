//! `frepray render SCENE.toml|.json` and `frepray bench`: light transport with the
//! scene's settings, any of them overridden on the command line.

use crate::output::{self, Format};
use crate::scene_flags::load_options;
use crate::RenderArgs;
use frepray::{Aov, Settings};
use std::ops::Range;
use std::path::Path;

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

/// The CPU's stage times, one line (all worker threads' time, summed).
fn cpu_line(s: &frepray::RenderStats) -> String {
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
pub fn dump(data: &frepray::SceneData, path: &Path) -> Result<(), String> {
    let json = serde_json::to_string_pretty(data).map_err(|e| e.to_string())?;
    std::fs::write(path, json + "\n").map_err(|e| format!("{}: {e}", path.display()))
}

/// Loads, renders (samples `0..spp`, or `samples`) and writes a scene; prints
/// statistics. With `--dump-scene`, the resolved scene is also written as JSON (and
/// nothing is rendered without outputs).
pub fn run(
    args: &RenderArgs,
    settings: &Settings,
    samples: Option<Range<u32>>,
) -> Result<(), String> {
    let (input, outs, quiet) = (&args.input, &args.output, args.quiet);
    let start = std::time::Instant::now();
    let formats = output::check_scene_outputs(outs)?;
    if args.resume.is_some() && args.backend == Backend::Gpu {
        return Err(
            "--resume renders on the CPU (the GPU renders whole waves of samples, not each \
             pixel from where it stopped); leave out --backend gpu"
                .into(),
        );
    }
    let resume_from = args
        .resume
        .as_deref()
        .map(|p| frepray::RenderState::read(p).map_err(|e| e.to_string()))
        .transpose()?;
    if let Some(d) = &args.dump_scene {
        output::check_writable(d)?;
    }
    let (scene, opts) = load_options(input, settings, &[])?;
    output::check_not_inputs(outs, input, &scene.data().inputs)?;
    if args.denoised.is_some() && frepray::value_png::Values::of(opts.integrator).is_some() {
        return Err(format!(
            "--denoised applies to light transport (direct, path), not {}",
            opts.integrator
        ));
    }
    let denoised = crate::denoised::Denoised::prepare(args.denoised.as_deref(), outs)?;
    let film = args.film.over(frepray::Film {
        exposure: scene.settings().exposure,
        tonemap: scene.settings().tonemap,
    })?;
    if let Some(path) = &args.dump_scene {
        dump(scene.data(), path)?;
        note!("resolved scene written to {}", path.display());
        if outs.is_empty() {
            return Ok(());
        }
    }
    let samples = samples.unwrap_or(0..opts.spp);
    let (width, height) = scene.resolution();
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
            if args.backend == Backend::Auto {
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
            scene
                .resume(&opts, partial, &stop, &progress)
                .map(|(state, stats)| frepray::Rendered {
                    state,
                    stats,
                    gpu: None,
                    fallback: None,
                })
                .map_err(|e| match &args.resume {
                    Some(p) => format!("--resume {}: {e}", p.display()),
                    None => e.to_string(),
                })
        }
        None => {
            if args.backend == Backend::Gpu {
                if let Ok(g) = frepray::backend::shared_gpu() {
                    note!("GPU: {}", g.info());
                }
            }
            scene
                .render_on(args.backend.into(), &opts, samples, &stop, &progress)
                .map_err(|e| e.to_string())
        }
    };
    bar.finish_and_clear();
    let r = result?;
    if let Some(why) = &r.fallback {
        note!("note: --backend auto renders on the CPU: {why}");
    }
    let (state, stats) = (r.state, r.stats);
    note!(
        "scene: loaded in {:.3} s (parsing, solids with their bounds and grids, lights, materials)",
        load.as_secs_f64()
    );
    note!("{stats}");
    if let Some(g) = &r.gpu {
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
            .map(|p| output::partial_path(p, args.overwrite_partial))
            .collect();
    }
    let on_gpu = r.gpu.is_some();
    output::write_state(&outs, &formats, &state, &film, &|img| {
        output::describe_render(img, input, &stats, on_gpu)
    })?;
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
        if let Some(d) = &denoised {
            let mut image = state.image();
            output::describe_render(&mut image, input, &stats, on_gpu);
            d.write(&image, &film)?;
        }
    }
    Ok(())
}

/// Runs `direct` and `path` with the scene's settings on each back end
/// ([`frepray::bench::bench`]) and prints throughput and stage tables.
pub fn bench(
    input: &Path,
    settings: &Settings,
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
    let (scene, opts) = load_options(input, settings, &[])?;
    if backends.contains(&Backend::Gpu) {
        let g = frepray::backend::shared_gpu().map_err(|e| e.to_string())?;
        note!("GPU: {}", g.info());
    }
    let stop = crate::stop_on_ctrl_c();
    let backends: Vec<frepray::Backend> = backends.iter().map(|&b| b.into()).collect();
    let rows = frepray::bench::bench(&scene, &opts, &backends, &stop).map_err(|e| e.to_string())?;
    let (width, height) = scene.resolution();
    out!(
        "| scene | backend | integrator | MIS | resolution | spp | time (s) | MSamples/s | MRays/s | camera | secondary | shadow |"
    );
    out!("| --- | --- | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for r in &rows {
        let s = &r.stats;
        let (c, sec, sh) = s.mrays_per_s_by_kind();
        out!(
            "| {} | {} | {} | {} | {}×{} | {} | {:.2} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
            input.file_name().unwrap_or_default().to_string_lossy(),
            r.backend.name(),
            r.integrator,
            opts.method.name(),
            width,
            height,
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
    for r in &rows {
        let parts = r.stage_parts();
        let on = if r.gpu.is_some() { "GPU" } else { "CPU" };
        stage_table(&format!("{on} stage ({})", r.integrator), &parts);
        out!("");
        match &r.gpu {
            Some(g) => out!("{}", g.counters()),
            None => out!(
                "CPU time of {} worker threads, summed; one query of each kind in {} timed",
                r.stats.threads,
                frepray::bench::TIMED_EVERY
            ),
        }
        bars.push((format!("{on} {}", r.integrator), parts));
    }
    if let Some(p) = plot {
        use std::io::Write;
        let name = input.file_name().unwrap_or_default().to_string_lossy();
        let title = format!("Stage times, {name} ({} spp)", opts.spp);
        let svg = crate::stage_plot::svg(&title, &bars);
        frepray::write_atomically(p, |w| w.write_all(svg.as_bytes()))
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
