//! `frepray check`: read a model or a scene, build it, and summarise it.

use frep::{Expr, Shape, Solid, Surface};
use std::path::Path;

/// Number of perturbations in every perturbed quadric of a shape.
fn perturbations(s: &Shape) -> (usize, usize) {
    match s {
        Shape::Function { .. } => (0, 0),
        Shape::Perturbed(p) => (1, p.perturbations().len()),
        Shape::Union(v) | Shape::Intersection(v) => v
            .iter()
            .map(perturbations)
            .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1)),
        Shape::Difference(a, b) => {
            let (x, y) = (perturbations(a), perturbations(b));
            (x.0 + y.0, x.1 + y.1)
        }
        Shape::Transformed(_, s) => perturbations(s),
    }
}

/// The kinds of file `check` and `render` read, for messages.
pub const KINDS: &str = "a scene (.toml, .json) or a model (.frep, .hf, .vm)";

/// Checks `file` by its kind: a scene is resolved (models, maps and settings
/// validated), a model read, lowered and bounded; prints what it found.
pub fn run(file: &Path) -> Result<(), String> {
    let ext = file
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("toml" | "json") => scene(file),
        Some("frep" | "hf" | "vm") => model(file),
        _ => Err(format!(
            "{}: unknown kind of file; expected {KINDS}",
            file.display()
        )),
    }
}

/// Resolves a scene file and summarises it.
fn scene(file: &Path) -> Result<(), String> {
    let (data, settings) = crate::scene_render::resolve(file, &Default::default())?;
    out!("file:          {}", file.display());
    out!(
        "resolution:    {}×{}",
        data.camera.width,
        data.camera.height
    );
    out!(
        "objects:       {} ({} materials)",
        data.objects.len(),
        data.materials.len()
    );
    out!(
        "lights:        {} area, {} point/spot, environment: {}",
        data.lights.area.len(),
        data.lights.delta.len(),
        if data.environment.is_some() {
            "yes"
        } else {
            "no"
        }
    );
    out!(
        "render:        {} {} spp, {}",
        settings.integrator,
        settings.spp,
        settings.method.name()
    );
    Ok(())
}

/// Reads, lowers and bounds a model file.
fn model(file: &Path) -> Result<(), String> {
    let model = frep::read::read_file(file).map_err(|e| e.to_string())?;
    let tree = model.shape.to_tree()?;
    let expr = Expr::new(&tree);
    let solid = Solid::build(&model.shape).map_err(|e| format!("{}: {e}", file.display()))?;
    let b = solid.bounds();
    let (quadrics, perts) = perturbations(&model.shape);
    out!("file:          {}", file.display());
    if let Some(n) = &model.name {
        out!("model:         {n}");
    }
    out!(
        "nodes:         {} (deduplicated expression DAG)",
        expr.len()
    );
    out!("perturbed quadrics: {quadrics}, perturbations: {perts}");
    // A 2-D model (Fidget's prospero.vm): `render` shows it from the top.
    let planar = !expr.nodes().contains(&frep::Node::Var(frep::Var::Z));
    out!(
        "dimensions:    {}",
        match planar {
            true => "2-D (F does not depend on z; rendered from the top, parallel rays)",
            false => "3-D",
        }
    );
    // How rays search its expression solids: a polynomial of low degree in Bernstein
    // form, anything else by interval arithmetic.
    let flat = solid.flat();
    let degrees: Vec<Option<u8>> = (0..flat.leaves.len())
        .filter_map(|k| match flat.leaf(k) {
            frep::LeafView::Expr(v) => Some(v.degree),
            frep::LeafView::Perturbed(_) => None,
        })
        .collect();
    if !degrees.is_empty() {
        let poly: Vec<String> = degrees.iter().flatten().map(|d| d.to_string()).collect();
        let intervals = degrees.len() - poly.len();
        out!(
            "expression solids: {} polynomial (Bernstein search{}), {intervals} by intervals",
            poly.len(),
            match poly.is_empty() {
                true => String::new(),
                false => format!(", degree {}", poly.join(", ")),
            }
        );
    }
    if b.is_empty() {
        out!("bounds:        empty (F < 0 everywhere in the search domain)");
    } else {
        out!(
            "bounds:        [{:.6}, {:.6}, {:.6}] .. [{:.6}, {:.6}, {:.6}]",
            b.lo.x,
            b.lo.y,
            b.lo.z,
            b.hi.x,
            b.hi.y,
            b.hi.z
        );
    }
    Ok(())
}
