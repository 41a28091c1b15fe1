//! `frepray render SCENE.toml|.json`: light transport with the scene's settings, any of
//! them overridden on the command line.

use crate::output::{self, Format};
use render::integrator::{Aov, RenderOptions};
use render::render_loop;
use render::scene::{load_scene, parse_technique, IntegratorKind, RenderSettings};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// Command-line overrides of a scene's render settings.
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
    /// Extra AOV channels, comma-separated.
    pub aovs: Option<String>,
    /// Worker threads (0: the global pool).
    pub threads: usize,
    /// Leave emitters seen directly by the camera out of the image.
    pub hide_emitters: bool,
    /// MIS parameters: power heuristic β, cutoff c, optimal-MIS ridge λ.
    pub beta: Option<f64>,
    /// Cutoff heuristic c.
    pub cutoff: Option<f64>,
    /// Optimal-MIS ridge λ (the solve uses λ/N · tr(Â)/T).
    pub ridge: Option<f64>,
}

/// Parses `bsdf:2,light` into techniques with sample counts (1 when omitted).
pub fn parse_techniques(s: &str) -> Result<Vec<(render::Technique, u32)>, String> {
    s.split(',')
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .map(|p| {
            let (name, n) = match p.split_once(':') {
                Some((name, n)) => {
                    let n: u32 = n
                        .parse()
                        .map_err(|_| format!("--techniques: '{n}' is not a sample count"))?;
                    (name, n)
                }
                None => (p, 1),
            };
            Ok((
                parse_technique(name).map_err(|e| format!("--techniques: {e}"))?,
                n,
            ))
        })
        .collect()
}

/// The scene's settings with the overrides applied, as render options.
pub fn options(settings: &RenderSettings, o: &Overrides) -> Result<RenderOptions, String> {
    let mut s = settings.clone();
    if let Some(n) = o.spp {
        s.spp = n;
    }
    if let Some(m) = &o.mis {
        s.method = mis::Method::from_str(m).map_err(|e| format!("--mis: {e}"))?;
    }
    if let Some(t) = &o.techniques {
        s.techniques = parse_techniques(t)?;
    }
    if let Some(seed) = o.seed {
        s.seed = seed;
    }
    if let Some(i) = &o.integrator {
        s.integrator = IntegratorKind::from_str(i).map_err(|e| format!("--integrator: {e}"))?;
    }
    if let Some(b) = o.beta {
        s.params.beta = b;
    }
    if let Some(c) = o.cutoff {
        s.params.cutoff = c;
    }
    if let Some(r) = o.ridge {
        if !(r >= 0.0 && r.is_finite()) {
            return Err(format!("--ridge {r}: expected a finite number ≥ 0"));
        }
        s.params.ridge = r;
    }
    if o.hide_emitters {
        s.hide_emitters = true;
    }
    if let Some(d) = o.max_depth {
        s.max_depth = d;
    }
    if let Some(a) = &o.aovs {
        s.aovs = a
            .split(',')
            .map(str::trim)
            .filter(|x| !x.is_empty())
            .map(String::from)
            .collect();
    }
    let mut opts = RenderOptions::from_settings(&s)?;
    opts.threads = o.threads;
    opts.validate()?;
    Ok(opts)
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

/// FNV-1a 64 of a file's bytes: the scene hash of the states it renders into.
fn file_hash(path: &Path) -> Result<u64, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    }))
}

/// Loads, renders (samples `0..spp`, or `samples`) and writes a scene; prints statistics.
pub fn run(
    input: &Path,
    outs: &[PathBuf],
    o: &Overrides,
    samples: Option<Range<u32>>,
    quiet: bool,
) -> Result<(), String> {
    let formats = outs
        .iter()
        .map(|p| output::format_for_scene(p))
        .collect::<Result<Vec<_>, _>>()?;
    let (mut scene, settings) = load_scene(input).map_err(|e| e.to_string())?;
    if let Some(w) = o.width {
        scene.camera.width = w;
    }
    if let Some(h) = o.height {
        scene.camera.height = h;
    }
    if scene.camera.width == 0 || scene.camera.height == 0 {
        return Err("--width and --height must be at least 1".into());
    }
    let mut opts = options(&settings, o)?;
    opts.scene_hash = file_hash(input)?;
    let samples = samples.unwrap_or(0..opts.spp);
    let mut check = settings.clone();
    check.techniques = opts.techniques.clone();
    check.check_techniques(&scene)?;
    if !formats.contains(&Format::Exr) && !opts.aovs.is_empty() {
        eprintln!(
            "note: AOV channels ({}) are only written to .exr",
            aov_list(&opts.aovs)
        );
    }

    let stop = crate::stop_on_ctrl_c();
    let bar = crate::progress_bar(quiet, "samples");
    let result = render_loop::render_range(&scene, &opts, samples, &stop, &|done, total| {
        bar.set_length(total);
        bar.set_position(done);
    });
    bar.finish_and_clear();
    let (state, stats) = result.map_err(|e| e.to_string())?;
    output::write_state(outs, &formats, &state)?;
    eprintln!("{stats}");
    eprintln!(
        "{}{} written",
        if stats.stopped {
            "interrupted: what was rendered is "
        } else {
            ""
        },
        output::list(outs)
    );
    Ok(())
}

/// Runs `direct` and `path` with the scene's settings and prints throughput.
pub fn bench(input: &Path, o: &Overrides) -> Result<(), String> {
    let (mut scene, settings) = load_scene(input).map_err(|e| e.to_string())?;
    if let Some(w) = o.width {
        scene.camera.width = w;
    }
    if let Some(h) = o.height {
        scene.camera.height = h;
    }
    let opts = options(&settings, o)?;
    let stats = render_loop::bench(&scene, &opts).map_err(|e| e.to_string())?;
    println!(
        "| scene | integrator | MIS | resolution | spp | time (s) | MSamples/s | MRays/s | camera | secondary | shadow |"
    );
    println!("| --- | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for s in &stats {
        let (c, sec, sh) = s.mrays_per_s_by_kind();
        println!(
            "| {} | {} | {} | {}×{} | {} | {:.2} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
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
    Ok(())
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
