//! `frepray mesh`: a watertight triangle mesh of a model file's surface, for 3-D
//! printing and other tools ([`frep::mesh`]: marching tetrahedra on the interval
//! octree, vertices on F = 0).

use crate::Error;
use frep::mesh::Mesh;
use frep::{Expr, Solid, Surface};
use std::path::Path;

pub use frep::mesh::{MAX_RESOLUTION, MAX_TRIANGLES};

/// A model's mesh and how it was made.
#[derive(Clone, Debug)]
pub struct ModelMesh {
    /// The mesh (counter-clockwise triangles seen from outside).
    pub mesh: Mesh,
    /// The box meshed: the solid's bounds as the renderer finds them.
    pub bounds: ([f64; 3], [f64; 3]),
    /// The side of the grid's cubes.
    pub cube: f64,
}

/// Reads a model file (.frep, .hf, .vm) and meshes its surface with `resolution` cubes
/// along the longest side of its bounds. A solid that reaches past its bounds (an
/// unbounded model, such as a gyroid, meshed over its search domain) is cut there and
/// closed by the box's faces, so the mesh is always closed.
pub fn mesh_model(path: &Path, resolution: u32) -> Result<ModelMesh, Error> {
    let model = |source| Error::Model {
        path: path.into(),
        source: Box::new(source),
    };
    let file = frep::read::read_file(path)?;
    let tree = file.shape.to_tree().map_err(model)?;
    let bounds = Solid::build(&file.shape).map_err(model)?.bounds();
    if bounds.is_empty() {
        return Err(Error::Invalid(format!(
            "{}: the solid is empty (F < 0 everywhere in its search domain); nothing to mesh",
            path.display()
        )));
    }
    mesh_solid(&Expr::new(&tree), &bounds, resolution)
        .map_err(|e| Error::Invalid(format!("{}: {e}", path.display())))
}

/// Meshes the solid `expr` ≥ 0 within `bounds` (cut and closed by the box where it
/// reaches past it) with `resolution` cubes along the box's longest side.
pub fn mesh_solid(
    expr: &Expr,
    bounds: &frep::Aabb,
    resolution: u32,
) -> Result<ModelMesh, frep::mesh::MeshError> {
    let boxed = frep::csg::intersection(&expr.to_tree(), &frep::csg::box_tree(bounds));
    let mesh = frep::mesh::mesh(&Expr::new(&boxed), bounds, resolution)?;
    Ok(ModelMesh {
        mesh,
        bounds: (bounds.lo.to_array(), bounds.hi.to_array()),
        cube: bounds.extent().max_element() / f64::from(resolution.max(1)),
    })
}
