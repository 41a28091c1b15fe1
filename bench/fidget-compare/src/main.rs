//! Side-by-side benchmark of frepray's FRep kernel (`frep`) against the `fidget` crate.
//!
//! For each Fidget `.vm` model given (default: colonnade and tanglecube from
//! `models/fidget`), it measures
//!
//! 1. point evaluation: the same pseudo-random points, Fidget's VM interpreter and JIT
//!    (float-slice evaluation in batches) against `frep::Expr::eval_with` over f64 and f32
//!    (one thread, scratch reused), and checks that frepray's value is −Fidget's;
//! 2. interval evaluation: the same random boxes, Fidget VM / JIT interval evaluators
//!    against frepray's `Interval` and `Dual<Interval, 1>` (what its ray intersector uses),
//!    plus the length of Fidget's tape after pruning min/max branches on such a box;
//! 3. a heightmap of the same view (orthographic, looking down −z over the model box):
//!    Fidget's voxel renderer (VM and JIT) against frepray casting one ray per pixel
//!    through `frep::Solid` (interval arithmetic, first crossing, with normals), at one
//!    thread and at all threads of the global rayon pool; depth PNGs of both and the
//!    pixel agreement;
//! 4. a profile of frepray's rays: interval / slope / point evaluations per ray, counted
//!    by a replica of `ExprSurface::first_crossing`, turned into time with the measured
//!    per-evaluation costs.
//!
//! Results are printed as Markdown tables and written to `<out>/results.md`.

mod args;
mod points;
mod profile;
mod render;

use args::Args;
use std::error::Error;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// One model, loaded by both systems.
pub struct Model {
    /// File stem (colonnade, tanglecube, …).
    pub name: String,
    /// Fidget's context and root node, read by `fidget::Context::from_text`.
    pub ctx: fidget::Context,
    /// Fidget's root node.
    pub root: fidget::context::Node,
    /// frepray's shape, read by `frep::read::read_file` (negated: F ≥ 0 inside).
    pub shape: frep::Shape,
    /// frepray's compiled expression of the whole shape.
    pub expr: frep::Expr,
    /// Half-size h of the view box [-h, h]³ (model units).
    pub half: f64,
}

/// Best (smallest) wall time of `reps` runs, in seconds, with the last run's result.
pub fn best_of<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..reps.max(1) {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(r);
    }
    (best, out.expect("at least one run"))
}

/// A rate or time with three significant digits (at least one decimal).
pub fn sig3(x: f64) -> String {
    if x >= 100.0 {
        format!("{x:.0}")
    } else if x >= 10.0 {
        format!("{x:.1}")
    } else if x >= 1.0 {
        format!("{x:.2}")
    } else {
        format!("{x:.3}")
    }
}

/// The 1-, 5- and 15-minute load averages (the machine is shared).
fn loadavg() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

/// A small deterministic generator (SplitMix64), so both systems see the same inputs.
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

fn load(path: &Path, half: f64) -> Result<Model, Box<dyn Error>> {
    let name = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("model")
        .to_string();
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let (ctx, root) = fidget::Context::from_text(file)
        .map_err(|e| format!("fidget cannot read {}: {e:?}", path.display()))?;
    let model = frep::read::read_file(path)?;
    let tree = model.shape.to_tree()?;
    let expr = frep::Expr::new(&tree);
    Ok(Model {
        name,
        ctx,
        root,
        shape: model.shape,
        expr,
        half,
    })
}

fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!(
        "{cpu}, {cores} hardware threads available, rayon global pool {} threads",
        rayon::current_num_threads()
    )
}

fn main() -> Result<(), Box<dyn Error>> {
    let args = Args::parse()?;
    std::fs::create_dir_all(&args.out)?;
    let mut md = String::new();
    writeln!(md, "Machine: {}", machine())?;
    writeln!(
        md,
        "Settings: {} points, batch {}, best of {} runs, image sizes {:?}\n",
        args.points, args.batch, args.reps, args.sizes
    )?;
    writeln!(md, "Load average at start: {}\n", loadavg())?;
    print!("{md}");

    let mut point_rows = Vec::new();
    let mut interval_rows = Vec::new();
    let mut render_rows = Vec::new();
    let mut profile_rows = Vec::new();
    for path in &args.models {
        let half = args.half_for(path);
        eprintln!("== {} (view box ±{half})", path.display());
        let m = load(path, half)?;
        eprintln!(
            "   frep expression: {} nodes; fidget context: {} nodes",
            m.expr.len(),
            m.ctx.len()
        );
        point_rows.extend(points::run(&m, &args)?);
        interval_rows.extend(points::intervals(&m, &args)?);
        for &n in &args.sizes {
            let r = render::run(&m, n, &args)?;
            render_rows.extend(r.rows);
            profile_rows.push(profile::run(&m, n, &r.frep_depth, &args)?);
        }
    }

    let mut tables = String::new();
    writeln!(
        tables,
        "### Point evaluation (1 thread, {} points in [-1,1]³)\n",
        args.points
    )?;
    writeln!(
        tables,
        "| model | evaluator | nodes / clauses | M evals/s | max abs diff vs Fidget JIT (frepray negated) |"
    )?;
    writeln!(tables, "| --- | --- | ---: | ---: | --- |")?;
    for r in &point_rows {
        writeln!(tables, "{r}")?;
    }
    writeln!(
        tables,
        "\n### Interval evaluation (1 thread, random boxes of side 2/64 in [-1,1]³)\n"
    )?;
    writeln!(tables, "| model | evaluator | M evals/s | note |")?;
    writeln!(tables, "| --- | --- | ---: | --- |")?;
    for r in &interval_rows {
        writeln!(tables, "{r}")?;
    }
    writeln!(
        tables,
        "\n### Heightmap of the same view (orthographic, down −z over [-h,h]³)\n"
    )?;
    writeln!(
        tables,
        "| model | size | renderer | threads | ms | M pixels/s | agreement with Fidget JIT |"
    )?;
    writeln!(tables, "| --- | ---: | --- | ---: | ---: | ---: | --- |")?;
    for r in &render_rows {
        writeln!(tables, "{r}")?;
    }
    writeln!(
        tables,
        "\n### Where frepray's ray time goes (1 thread, every {}-th pixel in x and y)\n",
        args.stride
    )?;
    writeln!(
        tables,
        "| model | size | segment evals per ray (time) | mean tape length per segment | point evals per ray (time) | Newton evals per ray (time) | simplifications per ray (time) | total |"
    )?;
    writeln!(
        tables,
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |"
    )?;
    for r in &profile_rows {
        writeln!(tables, "{r}")?;
    }
    writeln!(tables, "\nLoad average at end: {}", loadavg())?;
    print!("{tables}");
    md.push_str(&tables);
    let out = args.out.join("results.md");
    std::fs::write(&out, md)?;
    eprintln!("wrote {} and the PNGs beside it", out.display());
    Ok(())
}
