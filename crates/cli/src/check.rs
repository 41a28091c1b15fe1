//! `frepray check`: read a model, build it, and summarise it.

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

/// Reads, lowers and bounds `file`, printing what it found.
pub fn run(file: &Path) -> Result<(), String> {
    let model = frep::read::read_file(file).map_err(|e| e.to_string())?;
    let tree = model.shape.to_tree()?;
    let expr = Expr::new(&tree);
    let solid = Solid::build(&model.shape).map_err(|e| format!("{}: {e}", file.display()))?;
    let b = solid.bounds();
    let (quadrics, perts) = perturbations(&model.shape);
    println!("file:          {}", file.display());
    if let Some(n) = &model.name {
        println!("model:         {n}");
    }
    println!(
        "nodes:         {} (deduplicated expression DAG)",
        expr.len()
    );
    println!("perturbed quadrics: {quadrics}, perturbations: {perts}");
    if b.is_empty() {
        println!("bounds:        empty (F < 0 everywhere in the search domain)");
    } else {
        println!(
            "bounds:        [{:.6}, {:.6}, {:.6}] .. [{:.6}, {:.6}, {:.6}]",
            b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z
        );
    }
    Ok(())
}
