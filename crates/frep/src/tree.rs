//! Expression trees: the builder every solid, reader and CSG helper writes into.
//!
//! A [`Tree`] is an immutable, reference-counted expression of x, y, z. Cloning is cheap
//! and shares the subtree, so readers that name an intermediate value once and use it
//! many times build a DAG, not an exponentially large tree. [`crate::Expr`] lowers a tree
//! into the deduplicated form that is evaluated.

use std::ops::{Add, Div, Mul, Neg, Sub};
use std::sync::Arc;

/// A coordinate variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum Var {
    /// x.
    X,
    /// y.
    Y,
    /// z.
    Z,
}

/// A one-argument operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[allow(missing_docs)]
pub enum UnaryOp {
    Neg,
    Abs,
    Sqrt,
    Square,
    Exp,
    Ln,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Floor,
    Ceil,
    Round,
    /// 1 if the operand is 0, else 0 (Fidget's `not`).
    Not,
}

/// A two-argument operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[allow(missing_docs)]
pub enum BinaryOp {
    Add,
    Sub,
    Mul,
    Div,
    Min,
    Max,
    /// atan2(a, b), a the ordinate.
    Atan2,
    /// Euclidean remainder.
    Mod,
    /// −1, 0, 1 (Fidget's `compare`).
    Compare,
    /// a if a = 0 else b (Fidget's `and`).
    And,
    /// a if a ≠ 0 else b (Fidget's `or`).
    Or,
}

/// One node of a tree.
#[derive(Clone, Debug)]
pub enum TreeOp {
    /// A constant.
    Const(f64),
    /// A coordinate.
    Var(Var),
    /// A one-argument operation.
    Unary(UnaryOp, Tree),
    /// A two-argument operation.
    Binary(BinaryOp, Tree, Tree),
    /// An integer power.
    PowI(Tree, i32),
}

/// An expression of x, y, z (see the module docs).
#[derive(Clone, Debug)]
pub struct Tree(Arc<TreeOp>);

impl Tree {
    /// Wraps an operation.
    pub fn new(op: TreeOp) -> Self {
        Tree(Arc::new(op))
    }
    /// The operation at the root.
    pub fn op(&self) -> &TreeOp {
        &self.0
    }
    /// A key identifying this shared node (for memoised traversals).
    pub fn ptr(&self) -> *const TreeOp {
        Arc::as_ptr(&self.0)
    }
    /// x.
    pub fn x() -> Self {
        Self::new(TreeOp::Var(Var::X))
    }
    /// y.
    pub fn y() -> Self {
        Self::new(TreeOp::Var(Var::Y))
    }
    /// z.
    pub fn z() -> Self {
        Self::new(TreeOp::Var(Var::Z))
    }
    /// A constant.
    pub fn constant(v: f64) -> Self {
        Self::new(TreeOp::Const(v))
    }
    /// The value if this is a constant.
    pub fn as_const(&self) -> Option<f64> {
        match self.op() {
            TreeOp::Const(v) => Some(*v),
            _ => None,
        }
    }
    /// A unary operation.
    pub fn unary(op: UnaryOp, a: Tree) -> Self {
        Self::new(TreeOp::Unary(op, a))
    }
    /// A binary operation.
    pub fn binary(op: BinaryOp, a: Tree, b: Tree) -> Self {
        Self::new(TreeOp::Binary(op, a, b))
    }
    /// |self|.
    pub fn abs(&self) -> Self {
        Self::unary(UnaryOp::Abs, self.clone())
    }
    /// √self.
    pub fn sqrt(&self) -> Self {
        Self::unary(UnaryOp::Sqrt, self.clone())
    }
    /// self².
    pub fn square(&self) -> Self {
        Self::unary(UnaryOp::Square, self.clone())
    }
    /// selfⁿ.
    pub fn powi(&self, n: i32) -> Self {
        match n {
            1 => self.clone(),
            2 => self.square(),
            _ => Self::new(TreeOp::PowI(self.clone(), n)),
        }
    }
    /// e^self.
    pub fn exp(&self) -> Self {
        Self::unary(UnaryOp::Exp, self.clone())
    }
    /// ln self.
    pub fn ln(&self) -> Self {
        Self::unary(UnaryOp::Ln, self.clone())
    }
    /// sin self.
    pub fn sin(&self) -> Self {
        Self::unary(UnaryOp::Sin, self.clone())
    }
    /// cos self.
    pub fn cos(&self) -> Self {
        Self::unary(UnaryOp::Cos, self.clone())
    }
    /// tan self.
    pub fn tan(&self) -> Self {
        Self::unary(UnaryOp::Tan, self.clone())
    }
    /// asin self.
    pub fn asin(&self) -> Self {
        Self::unary(UnaryOp::Asin, self.clone())
    }
    /// acos self.
    pub fn acos(&self) -> Self {
        Self::unary(UnaryOp::Acos, self.clone())
    }
    /// atan self.
    pub fn atan(&self) -> Self {
        Self::unary(UnaryOp::Atan, self.clone())
    }
    /// atan2(self, x).
    pub fn atan2(&self, x: &Tree) -> Self {
        Self::binary(BinaryOp::Atan2, self.clone(), x.clone())
    }
    /// min(self, b).
    pub fn min(&self, b: &Tree) -> Self {
        Self::binary(BinaryOp::Min, self.clone(), b.clone())
    }
    /// max(self, b).
    pub fn max(&self, b: &Tree) -> Self {
        Self::binary(BinaryOp::Max, self.clone(), b.clone())
    }
    /// Substitutes expressions for x, y and z (how transforms are applied).
    pub fn remap(&self, x: &Tree, y: &Tree, z: &Tree) -> Tree {
        crate::Expr::new(self).substitute(x, y, z)
    }
}

/// A shared leaf that stands in for children taken out during a drop.
static LEAF: std::sync::LazyLock<Tree> = std::sync::LazyLock::new(|| Tree::constant(0.0));

impl TreeOp {
    /// Moves the non-leaf children out, leaving shared leaves in their place.
    fn take_children(&mut self, out: &mut Vec<Tree>) {
        let mut take = |t: &mut Tree| {
            if matches!(
                t.op(),
                TreeOp::Unary(..) | TreeOp::Binary(..) | TreeOp::PowI(..)
            ) {
                out.push(std::mem::replace(t, LEAF.clone()));
            }
        };
        match self {
            TreeOp::Unary(_, a) | TreeOp::PowI(a, _) => take(a),
            TreeOp::Binary(_, a, b) => {
                take(a);
                take(b);
            }
            TreeOp::Const(_) | TreeOp::Var(_) => {}
        }
    }
}

impl Drop for TreeOp {
    /// Drops deep trees iteratively: a recursive drop of a model thousands of
    /// operations deep would overflow the stack.
    fn drop(&mut self) {
        let mut stack = Vec::new();
        self.take_children(&mut stack);
        while let Some(t) = stack.pop() {
            if let Ok(mut op) = Arc::try_unwrap(t.0) {
                op.take_children(&mut stack);
            }
        }
    }
}

impl From<f64> for Tree {
    fn from(v: f64) -> Self {
        Tree::constant(v)
    }
}

macro_rules! tree_binop {
    ($tr:ident, $m:ident, $op:expr) => {
        impl $tr<Tree> for Tree {
            type Output = Tree;
            fn $m(self, b: Tree) -> Tree {
                Tree::binary($op, self, b)
            }
        }
        impl $tr<&Tree> for &Tree {
            type Output = Tree;
            fn $m(self, b: &Tree) -> Tree {
                Tree::binary($op, self.clone(), b.clone())
            }
        }
        impl $tr<Tree> for &Tree {
            type Output = Tree;
            fn $m(self, b: Tree) -> Tree {
                Tree::binary($op, self.clone(), b)
            }
        }
        impl $tr<&Tree> for Tree {
            type Output = Tree;
            fn $m(self, b: &Tree) -> Tree {
                Tree::binary($op, self, b.clone())
            }
        }
        impl $tr<f64> for Tree {
            type Output = Tree;
            fn $m(self, b: f64) -> Tree {
                Tree::binary($op, self, Tree::constant(b))
            }
        }
        impl $tr<f64> for &Tree {
            type Output = Tree;
            fn $m(self, b: f64) -> Tree {
                Tree::binary($op, self.clone(), Tree::constant(b))
            }
        }
        impl $tr<Tree> for f64 {
            type Output = Tree;
            fn $m(self, b: Tree) -> Tree {
                Tree::binary($op, Tree::constant(self), b)
            }
        }
        impl $tr<&Tree> for f64 {
            type Output = Tree;
            fn $m(self, b: &Tree) -> Tree {
                Tree::binary($op, Tree::constant(self), b.clone())
            }
        }
    };
}

tree_binop!(Add, add, BinaryOp::Add);
tree_binop!(Sub, sub, BinaryOp::Sub);
tree_binop!(Mul, mul, BinaryOp::Mul);
tree_binop!(Div, div, BinaryOp::Div);

impl Neg for Tree {
    type Output = Tree;
    fn neg(self) -> Tree {
        Tree::unary(UnaryOp::Neg, self)
    }
}

impl Neg for &Tree {
    type Output = Tree;
    fn neg(self) -> Tree {
        Tree::unary(UnaryOp::Neg, self.clone())
    }
}
