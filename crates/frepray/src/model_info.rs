//! What `frepray check` says of a model file: its size as an expression, its perturbed
//! quadrics, how rays search its expression solids, whether it is 2-D, and its bounds.

use crate::Error;
use frep::shape::Shape;
use frep::{Expr, LeafView, Solid, Surface};
use std::path::Path;

/// A model file's summary ([`info`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ModelInfo {
    /// The model's name, where the file gives one.
    pub name: Option<String>,
    /// Nodes of the deduplicated expression DAG.
    pub nodes: usize,
    /// Perturbed quadrics, and their perturbations in all.
    pub perturbed: (usize, usize),
    /// The polynomial degree of each expression solid searched in Bernstein form.
    pub polynomial_degrees: Vec<u8>,
    /// Expression solids searched by interval arithmetic.
    pub by_intervals: usize,
    /// Of those, the ones whose low-degree polynomial parts fold into leaves along a
    /// ray ([`frep::ray_tape`]): their nodes, and the nodes a ray evaluates.
    pub with_leaves: Vec<(usize, usize)>,
    /// F does not depend on z (a 2-D model, as Fidget's prospero.vm).
    pub planar: bool,
    /// The solid's bounds (lowest and highest corner), None where F < 0 everywhere in
    /// the search domain.
    pub bounds: Option<([f64; 3], [f64; 3])>,
}

/// Reads, lowers and bounds a model file (.frep, .hf, .vm) and summarises it.
pub fn info(path: &Path) -> Result<ModelInfo, Error> {
    let model = |source| Error::Model {
        path: path.into(),
        source: Box::new(source),
    };
    let file = frep::read::read_file(path)?;
    let tree = file.shape.to_tree().map_err(model)?;
    let expr = Expr::new(&tree);
    let solid = Solid::build(&file.shape).map_err(model)?;
    let flat = solid.flat();
    let degrees: Vec<Option<u8>> = (0..flat.leaves.len())
        .filter_map(|k| match flat.leaf(k) {
            LeafView::Expr(v) => Some(v.degree),
            LeafView::Perturbed(_) => None,
        })
        .collect();
    let polynomial_degrees: Vec<u8> = degrees.iter().flatten().copied().collect();
    let with_leaves = (0..flat.leaves.len())
        .filter_map(|k| match flat.leaf(k) {
            LeafView::Expr(v) => v.plan.map(|p| (v.tape.len(), p.tape.len())),
            LeafView::Perturbed(_) => None,
        })
        .collect();
    let b = solid.bounds();
    Ok(ModelInfo {
        name: file.name.clone(),
        nodes: expr.len(),
        perturbed: perturbations(&file.shape),
        by_intervals: degrees.len() - polynomial_degrees.len(),
        with_leaves,
        polynomial_degrees,
        planar: crate::preview::is_planar(&expr),
        bounds: (!b.is_empty()).then(|| (b.lo.to_array(), b.hi.to_array())),
    })
}

/// Perturbed quadrics of a shape, and their perturbations in all.
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summarises_the_bumpy_ball_and_a_2d_model() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let ball = info(&root.join("models/examples/bumpy_ball.frep")).unwrap();
        assert_eq!(ball.perturbed, (1, 3));
        assert!(!ball.planar && ball.bounds.is_some());
        let hi = info(&root.join("models/fidget/hi.vm")).unwrap();
        assert!(hi.planar && hi.perturbed == (0, 0) && hi.by_intervals == 1);
        // A blend of quadrics: its spheres and their scaled copies fold into leaves.
        let blob = info(&root.join("models/examples/smooth_blob.frep")).unwrap();
        assert_eq!(blob.with_leaves.len(), 1);
        let (all, left) = blob.with_leaves[0];
        assert!(all == blob.nodes && left <= all / 2, "{all} → {left}");
        let cube = info(&root.join("models/fidget/tanglecube.vm")).unwrap();
        assert_eq!(cube.polynomial_degrees, vec![4]);
    }
}
