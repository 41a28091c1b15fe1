//! `frepray mesh MODEL -o model.obj|.stl`: a watertight mesh of a model's surface
//! ([`frepray::mesh_model`]).

use crate::output;
use std::path::{Path, PathBuf};

/// Arguments of `frepray mesh`.
#[derive(clap::Args)]
pub struct MeshArgs {
    /// The model file (.frep, .hf or .vm).
    model: PathBuf,
    /// Output: .obj (Wavefront, shared vertices) or .stl (binary); repeatable.
    #[arg(short, long, required = true)]
    output: Vec<PathBuf>,
    /// Cubes of the grid along the longest side of the model's bounds (the mesh's
    /// vertices are about bounds / resolution apart; up to 4096).
    #[arg(long, default_value_t = 256)]
    resolution: u32,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Obj,
    Stl,
}

fn kind(p: &Path) -> Result<Kind, String> {
    match p
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("obj") => Ok(Kind::Obj),
        Some("stl") => Ok(Kind::Stl),
        _ => Err(format!(
            "{}: unknown mesh format; expected .obj or .stl",
            p.display()
        )),
    }
}

/// Meshes the model and writes every output whole or not at all.
pub fn run(args: MeshArgs) -> Result<(), String> {
    let kinds = args
        .output
        .iter()
        .map(|p| kind(p))
        .collect::<Result<Vec<_>, _>>()?;
    for p in &args.output {
        output::check_writable(p)?;
    }
    output::check_not_inputs(&args.output, &args.model, &[])?;
    crate::set_threads(args.threads)?;
    let start = std::time::Instant::now();
    let m = frepray::mesh_model(&args.model, args.resolution).map_err(|e| e.to_string())?;
    let (lo, hi) = m.bounds;
    note!(
        "{}: {} vertices, {} triangles, closed; cubes of {:.6} over [{:.4}, {:.4}, {:.4}] .. \
         [{:.4}, {:.4}, {:.4}], {:.2} s",
        args.model.display(),
        m.mesh.vertices.len(),
        m.mesh.triangles.len(),
        m.cube,
        lo[0],
        lo[1],
        lo[2],
        hi[0],
        hi[1],
        hi[2],
        start.elapsed().as_secs_f64()
    );
    for (p, k) in args.output.iter().zip(kinds) {
        frepray::write_atomically(p, |w| match k {
            Kind::Obj => m.mesh.write_obj(w),
            Kind::Stl => m.mesh.write_stl(w),
        })
        .map_err(|e| format!("{}: {e}", p.display()))?;
    }
    note!("{} written", output::list(&args.output));
    Ok(())
}
