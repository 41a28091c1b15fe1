//! # frep — functionally defined solids
//!
//! The modelling kernel of frepray: solids are the sets where a function F of x, y, z is
//! ≥ 0 (the HyperFun / FRep convention), the surface is F = 0. Every solid lowers to one
//! representation, a deduplicated expression DAG ([`Expr`]), evaluated over f64, f32,
//! intervals or dual numbers; rays meet solids through one contract ([`Surface`]).
//! A built [`Solid`] is flat, inspectable data ([`flat`]): CSG nodes, a leaf table and
//! pools that a GPU can upload, intersected in place without allocating per ray; its
//! expressions also compile to register [`bytecode`], the GPU interpreter's reference.
//!
//! ```
//! use frep::{Expr, Tree};
//! // The unit ball: 1 − x² − y² − z² ≥ 0 inside.
//! let ball = 1.0 - (Tree::x().square() + Tree::y().square() + Tree::z().square());
//! let f = Expr::new(&ball);
//! assert_eq!(f.eval([0.0, 0.0, 0.0]), 1.0);
//! assert!(f.eval([2.0, 0.0, 0.0]) < 0.0);
//! let (_, grad) = f.gradient([1.0, 0.0, 0.0]);
//! assert_eq!(grad, [-2.0, 0.0, 0.0]);
//! ```
#![warn(missing_docs)]

pub mod bounds;
pub mod build_error;
pub mod bvh;
pub mod bytecode;
pub mod csg;
pub mod dual;
pub mod expr;
pub mod fixed;
pub mod flat;
pub mod interval;
pub mod interval_trace;
pub mod lanes;
pub mod mesh;
pub mod occupancy;
pub mod perturbed;
pub mod poly;
pub mod poly_trace;
pub mod quadric;
pub mod ray;
pub mod ray_tape;
pub mod read;
pub mod scalar;
pub mod shape;
pub mod solid;
pub mod surface;
pub mod transform;
pub mod tree;
pub mod triangles;

#[cfg(test)]
mod test_models;

pub use build_error::BuildError;
pub use bvh::{Bvh, BvhRef};
pub use bytecode::Bytecode;
pub use dual::Dual;
pub use expr::{Choice, Expr, Node};
pub use flat::{Flat, Leaf, LeafView};
pub use interval::Interval;
pub use interval_trace::{ExprSurface, ExprView};
pub use perturbed::{PerturbedQuadric, PerturbedSurface, PerturbedView};
pub use quadric::Quadric;
pub use ray::{Aabb, Ray};
pub use scalar::Scalar;
pub use shape::Shape;
pub use solid::{Hit, Solid};
pub use surface::Surface;
pub use transform::Affine;
pub use tree::{BinaryOp, Tree, TreeOp, UnaryOp, Var};
