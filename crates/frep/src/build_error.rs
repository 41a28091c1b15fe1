//! Why a shape does not build into a solid ([`crate::Solid::build`],
//! [`crate::Shape::to_tree`]).

use crate::bytecode::BytecodeError;
use crate::transform::Affine;
use std::fmt;

/// A shape that cannot become a solid or an expression tree.
#[derive(Clone, Debug, PartialEq)]
pub enum BuildError {
    /// A transform whose matrix has no inverse.
    SingularTransform(Affine),
    /// A union or intersection of no shapes.
    EmptySetOperation,
    /// CSG nested deeper than [`crate::flat::MAX_DEPTH`] (the depth found).
    TooDeep(usize),
    /// An expression the bytecode cannot hold.
    Bytecode(BytecodeError),
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::SingularTransform(m) => write!(f, "singular transform {m:?}"),
            BuildError::EmptySetOperation => write!(f, "a set operation needs at least one shape"),
            BuildError::TooDeep(depth) => write!(
                f,
                "CSG nested {depth} deep; at most {} levels are supported",
                crate::flat::MAX_DEPTH
            ),
            BuildError::Bytecode(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for BuildError {}

impl From<BytecodeError> for BuildError {
    fn from(e: BytecodeError) -> Self {
        BuildError::Bytecode(e)
    }
}
