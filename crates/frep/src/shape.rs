//! Shapes: the description of a solid that readers produce and renderers consume.
//!
//! A [`Shape`] keeps what the exact intersection paths need to know (a perturbed quadric
//! stays one; min/max CSG stays CSG so that crossings combine exactly along a ray) and
//! lowers to the single representation, an expression tree, with [`Shape::to_tree`].

use crate::build_error::BuildError;
use crate::csg;
use crate::perturbed::PerturbedQuadric;
use crate::ray::Aabb;
use crate::transform::Affine;
use crate::tree::Tree;

/// A solid (F ≥ 0 inside).
#[derive(Clone, Debug)]
pub enum Shape {
    /// Any closed-form expression, intersected by interval arithmetic. `domain`, when
    /// given, is a box known to hold the solid (a model's declared bounds).
    Function {
        /// F.
        tree: Tree,
        /// A box known to hold every point where F ≥ 0, if one was declared.
        domain: Option<Aabb>,
    },
    /// A perturbed quadric, intersected exactly.
    Perturbed(PerturbedQuadric),
    /// Union (max) of shapes.
    Union(Vec<Shape>),
    /// Intersection (min) of shapes.
    Intersection(Vec<Shape>),
    /// Difference (a \ b = min(a, −b)).
    Difference(Box<Shape>, Box<Shape>),
    /// A shape moved by an affine map.
    Transformed(Affine, Box<Shape>),
}

impl Shape {
    /// A function shape with no declared domain.
    pub fn function(tree: Tree) -> Self {
        Shape::Function { tree, domain: None }
    }

    /// The shape as one expression tree (F ≥ 0 inside). Fails only for a transform whose
    /// matrix is singular.
    pub fn to_tree(&self) -> Result<Tree, BuildError> {
        Ok(match self {
            Shape::Function { tree, .. } => tree.clone(),
            Shape::Perturbed(p) => p.to_tree(),
            Shape::Union(v) => fold(v, csg::union)?,
            Shape::Intersection(v) => fold(v, csg::intersection)?,
            Shape::Difference(a, b) => csg::difference(&a.to_tree()?, &b.to_tree()?),
            Shape::Transformed(m, s) => m
                .apply(&s.to_tree()?)
                .ok_or(BuildError::SingularTransform(*m))?,
        })
    }
}

fn fold(v: &[Shape], op: fn(&Tree, &Tree) -> Tree) -> Result<Tree, BuildError> {
    let mut it = v.iter();
    let first = it.next().ok_or(BuildError::EmptySetOperation)?;
    let mut acc = first.to_tree()?;
    for s in it {
        acc = op(&acc, &s.to_tree()?);
    }
    Ok(acc)
}
