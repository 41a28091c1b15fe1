//! Symbolic values for executing programs whose result is a function of x, y, z.
//!
//! A [`Val`] is a known number, an expression tree, or a tree known to take only the
//! values 0 and 1 (a condition). Operations on numbers are computed at once; anything
//! touching a tree builds a tree. Conditions that depend on the coordinates become
//! 0/1-valued trees built from `compare`, and a choice between two values is
//! `or(and(c, a), and(not(c), b))`: `and(c, a)` is `a` where c ≠ 0 and 0 elsewhere, so
//! the sum picks `a` where c = 1 and `b` where c = 0, even where the other side is NaN
//! or infinite (it is never multiplied by 0). Conditions use only operations that are
//! exact on 0/1 values without rounding — `compare`, `max`, `min`, `not` — so that an
//! interval evaluation, which widens every sum and product outward, keeps a decided
//! condition a point (`1 − c` would widen 0 to a "maybe 0" everywhere, and with it make
//! every choice the hull of both sides).

use crate::expr::{Expr, Node};
use crate::tree::{BinaryOp, Tree, UnaryOp};

/// HyperFun's tolerance in comparisons and truth tests (`EPS` in its interpreter).
pub(crate) const EPS: f64 = 1e-6;

/// A value during symbolic execution.
#[derive(Clone, Debug)]
pub(crate) enum Val {
    /// A known number.
    Num(f64),
    /// A function of x, y, z.
    Tree(Tree),
    /// A function of x, y, z taking only the values 0 and 1.
    Cond(Tree),
}

impl Val {
    /// The value as a tree.
    pub fn tree(&self) -> Tree {
        match self {
            Val::Num(v) => Tree::constant(*v),
            Val::Tree(t) | Val::Cond(t) => t.clone(),
        }
    }
    /// The number, if known.
    pub fn num(&self) -> Option<f64> {
        match self {
            Val::Num(v) => Some(*v),
            _ => None,
        }
    }
    /// Whether two values are certainly the same (same number or same shared tree).
    pub fn same(&self, b: &Val) -> bool {
        match (self, b) {
            (Val::Num(x), Val::Num(y)) => x.to_bits() == y.to_bits(),
            (Val::Tree(x) | Val::Cond(x), Val::Tree(y) | Val::Cond(y)) => x.ptr() == y.ptr(),
            _ => false,
        }
    }
}

/// Applies a tree-building function; when every input is a number, the (small) result
/// is folded to a number.
pub(crate) fn apply(args: &[&Val], f: impl FnOnce(&[Tree]) -> Tree) -> Val {
    let trees: Vec<Tree> = args.iter().map(|v| v.tree()).collect();
    let t = f(&trees);
    if args.iter().all(|v| v.num().is_some()) {
        let e = Expr::new(&t);
        if let [Node::Const(b)] = e.nodes() {
            return Val::Num(f64::from_bits(*b));
        }
    }
    Val::Tree(t)
}

/// A unary operation.
pub(crate) fn unary(op: UnaryOp, a: &Val) -> Val {
    apply(&[a], |t| Tree::unary(op, t[0].clone()))
}

/// A binary operation.
pub(crate) fn binary(op: BinaryOp, a: &Val, b: &Val) -> Val {
    apply(&[a, b], |t| Tree::binary(op, t[0].clone(), t[1].clone()))
}

/// 1 where a < b, else 0 (also where either is NaN): max(compare(b, a), 0).
fn lt_tree(a: &Tree, b: &Tree) -> Tree {
    Tree::binary(BinaryOp::Compare, b.clone(), a.clone()).max(&Tree::constant(0.0))
}

/// 1 where a > b, else 0.
fn gt_tree(a: &Tree, b: &Tree) -> Tree {
    lt_tree(b, a)
}

/// 1 where the 0/1 value c is 0, else 0.
fn not_tree(c: &Tree) -> Tree {
    Tree::unary(UnaryOp::Not, c.clone())
}

/// A comparison, HyperFun's way (`=` and `/=` with tolerance [`EPS`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Cmp {
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
}

/// The comparison `a op b` as 1 or 0.
pub(crate) fn compare(op: Cmp, a: &Val, b: &Val) -> Val {
    if let (Some(x), Some(y)) = (a.num(), b.num()) {
        let r = match op {
            Cmp::Lt => x < y,
            Cmp::Le => x <= y,
            Cmp::Gt => x > y,
            Cmp::Ge => x >= y,
            Cmp::Eq => (x - y).abs() < EPS,
            Cmp::Ne => (x - y).abs() >= EPS,
        };
        return Val::Num(r as u8 as f64);
    }
    let (x, y) = (a.tree(), b.tree());
    let eps = Tree::constant(EPS);
    Val::Cond(match op {
        Cmp::Lt => lt_tree(&x, &y),
        Cmp::Ge => not_tree(&lt_tree(&x, &y)),
        Cmp::Gt => gt_tree(&x, &y),
        Cmp::Le => not_tree(&gt_tree(&x, &y)),
        Cmp::Eq => lt_tree(&(x - y).abs(), &eps),
        Cmp::Ne => not_tree(&lt_tree(&(x - y).abs(), &eps)),
    })
}

/// The truth of a value as 1 or 0 (non-zero beyond [`EPS`] is true).
pub(crate) fn truth(a: &Val) -> Val {
    match a {
        Val::Num(v) => Val::Num((v.abs() >= EPS) as u8 as f64),
        Val::Cond(_) => a.clone(),
        Val::Tree(t) => Val::Cond(not_tree(&lt_tree(&t.abs(), &Tree::constant(EPS)))),
    }
}

/// Logical and.
pub(crate) fn and(a: &Val, b: &Val) -> Val {
    let (a, b) = (truth(a), truth(b));
    match (a.num(), b.num()) {
        (Some(x), _) => {
            if x == 0.0 {
                a
            } else {
                b
            }
        }
        (_, Some(y)) => {
            if y == 0.0 {
                b
            } else {
                a
            }
        }
        _ => Val::Cond(a.tree().min(&b.tree())),
    }
}

/// Logical or.
pub(crate) fn or(a: &Val, b: &Val) -> Val {
    let (a, b) = (truth(a), truth(b));
    match (a.num(), b.num()) {
        (Some(x), _) => {
            if x == 0.0 {
                b
            } else {
                a
            }
        }
        (_, Some(y)) => {
            if y == 0.0 {
                a
            } else {
                b
            }
        }
        _ => Val::Cond(a.tree().max(&b.tree())),
    }
}

/// Logical not.
pub(crate) fn not(a: &Val) -> Val {
    match truth(a) {
        Val::Num(v) => Val::Num(1.0 - v),
        c => Val::Cond(not_tree(&c.tree())),
    }
}

/// `a` where the condition holds, else `b` (see the module docs).
pub(crate) fn select(cond: &Val, a: &Val, b: &Val) -> Val {
    let c = truth(cond);
    if let Some(v) = c.num() {
        return if v != 0.0 { a.clone() } else { b.clone() };
    }
    if a.same(b) {
        return a.clone();
    }
    let c = c.tree();
    let pick_a = Tree::binary(BinaryOp::And, c.clone(), a.tree());
    let pick_b = Tree::binary(BinaryOp::And, not_tree(&c), b.tree());
    Val::Tree(Tree::binary(BinaryOp::Or, pick_a, pick_b))
}

/// `t`ⁿ for an integer n, negative powers as a reciprocal.
pub(crate) fn powi_tree(t: &Tree, n: i64) -> Tree {
    match n {
        0 => Tree::constant(1.0),
        n if n > 0 => t.powi(n.min(i32::MAX as i64) as i32),
        n => 1.0 / t.powi((-n).min(i32::MAX as i64) as i32),
    }
}

/// `a ^ b`, HyperFun's way: an exponent within [`EPS`] above an integer is that
/// integer (repeated multiplication, reciprocal when negative), any other exponent is
/// exp(b·ln a). Errors (as HyperFun's) for 0 to a power ≤ 0 and for a negative base
/// to a fractional power, when both are known.
pub(crate) fn power(a: &Val, b: &Val) -> Result<Val, String> {
    let int_exp = b.num().filter(|e| e - e.floor() < EPS).map(|e| {
        let n = e.abs().round() as i64;
        if e < 0.0 {
            -n
        } else {
            n
        }
    });
    if let (Some(x), Some(e)) = (a.num(), b.num()) {
        if x.abs() < EPS {
            if e <= EPS {
                return Err(format!("expected a positive power of zero, found 0 ^ {e}"));
            }
            return Ok(Val::Num(0.0));
        }
        if let Some(n) = int_exp {
            return Ok(Val::Num(
                x.powi(n.clamp(i32::MIN as i64, i32::MAX as i64) as i32),
            ));
        }
        if x < 0.0 {
            return Err(format!(
                "expected a non-negative base for the fractional power {e}, found {x}"
            ));
        }
        return Ok(Val::Num((e * x.ln()).exp()));
    }
    let t = a.tree();
    Ok(Val::Tree(match int_exp {
        Some(n) => powi_tree(&t, n),
        None => (b.tree() * t.ln()).exp(),
    }))
}
