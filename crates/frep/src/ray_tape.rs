//! A tape restricted to one ray: its low-degree polynomial parts folded into leaves.
//!
//! Along a ray x = p + s·d every node that is a polynomial of x, y, z of degree ≤ 2 (a
//! plane, a sphere's or a quadric's function, an affine map of the coordinates) is a
//! polynomial of s of the same degree. A [`Plan`], made once per tape, finds the
//! largest such parts: its tape keeps the other nodes and reads each polynomial part
//! from a leaf slot. A ray then computes each leaf's three coefficients once
//! ([`RayTape::new`]), and every evaluation of the search (a segment's bounds, a point's
//! value, a Newton step) reads them instead of evaluating the part again: a blend of
//! three spheres (70 nodes) evaluates 34, leaf slots included, and each leaf is bounded
//! over a segment by its exact range (its ends and its vertex), where interval
//! arithmetic bounds the three squares apart and adds them.
//!
//! The leaves are the tape's parts up to the rounding of their coefficients, of the
//! order of the tape's own rounding, as in [`crate::poly_trace`]: the search sees one
//! function (leaf bounds are widened to hold the leaf's computed values), so the
//! decisions are consistent, and the crossings agree with the full tape's far within the
//! resolution (crates/frep/tests/ray_tape.rs).
//!
//! The R-functions' pattern `a + b ± √(a² + b²)` keeps its nodes, so that interval
//! bounds still narrow it ([`crate::scalar::Scalar::r_bound`]). Tapes with min/max nodes
//! get no plan: their search simplifies the tape per segment, which a leaf would hide.

use crate::dual::Dual;
use crate::expr::{eval_tail, r_pattern, Node};
use crate::interval::Interval;
use crate::ray::Ray;
use crate::scalar::Scalar;
use crate::tree::{BinaryOp, UnaryOp, Var};
use std::cell::{Cell, RefCell};

/// Coefficients of a leaf in s, lowest power first.
type Quad = [f64; 3];

/// The highest degree a leaf has.
const LEAF_DEGREE: usize = 2;

/// Plans save less than their per-ray cost below this many folded nodes.
const MIN_FOLDED: usize = 8;

/// Which nodes of a tape fold into leaves along a ray, and the tape that is left.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The folded nodes the leaves need, as a tape of their own (operands renumbered).
    parts: Vec<Node>,
    /// The leaves, as indices of `parts`: leaf k is slot k of `tape`.
    leaves: Vec<u32>,
    /// `leaves.len()` slots the leaves fill, then the nodes left, operands renumbered;
    /// the root last.
    tape: Vec<Node>,
}

/// A [`Plan`] borrowed, from an [`crate::ExprSurface`] or a solid's flat pools.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanView<'a> {
    /// The folded nodes the leaves need, as a tape of their own.
    pub parts: &'a [Node],
    /// The leaves, as indices of `parts`.
    pub leaves: &'a [u32],
    /// Leaf slots, then the nodes left; the root last.
    pub tape: &'a [Node],
}

impl Plan {
    /// The plan of `tape` (root last), or None where it would save little: no min/max
    /// nodes allowed, at least 8 nodes folded, and the root not itself a
    /// polynomial part (such tapes take [`crate::poly_trace`]).
    pub fn new(tape: &[Node]) -> Option<Plan> {
        let n = tape.len();
        if n == 0 || crate::expr::has_min_max(tape) {
            return None;
        }
        // The R-functions' inner nodes stay, so that their bound still narrows.
        let mut kept = vec![false; n];
        for &node in tape {
            if r_pattern(tape, node).is_none() {
                continue;
            }
            let Node::Binary(_, s, r) = node else {
                unreachable!("an R-function is a sum")
            };
            kept[s as usize] = true;
            kept[r as usize] = true;
            if let Node::Unary(_, q) = tape[r as usize] {
                kept[q as usize] = true;
                if let Node::Binary(_, p, q2) = tape[q as usize] {
                    kept[p as usize] = true;
                    kept[q2 as usize] = true;
                }
            }
        }
        // Each node's degree as a polynomial of x, y, z, where it is one that folds:
        // a constant, or degree 1 ..= LEAF_DEGREE (a node of degree 0 that is not a
        // constant, none after constant folding, stays).
        let mut degree: Vec<Option<usize>> = Vec::with_capacity(n);
        for (i, &node) in tape.iter().enumerate() {
            let d = |j: u32| degree[j as usize];
            let both = |a: u32, b: u32| d(a).zip(d(b));
            let k = match node {
                _ if kept[i] => None,
                Node::Const(_) => Some(0),
                Node::Var(_) => Some(1),
                Node::Unary(UnaryOp::Neg, a) => d(a),
                Node::Unary(UnaryOp::Square, a) => d(a).map(|k| 2 * k),
                Node::Binary(BinaryOp::Add | BinaryOp::Sub, a, b) => {
                    both(a, b).map(|(a, b)| a.max(b))
                }
                Node::Binary(BinaryOp::Mul, a, b) => both(a, b).map(|(a, b)| a + b),
                Node::Binary(BinaryOp::Div, a, b) if d(b) == Some(0) => d(a),
                Node::PowI(a, k @ 0..=2) => d(a).map(|d| d * k as usize),
                _ => None,
            };
            let folds = |k: usize| k <= LEAF_DEGREE && (k > 0 || matches!(node, Node::Const(_)));
            degree.push(k.filter(|&k| folds(k)));
        }
        if degree[n - 1].is_some() {
            return None;
        }
        // Leaves: folded nodes of degree ≥ 1 that a kept node reads; constants a kept
        // node reads stay constants.
        let mut leaf = vec![false; n];
        let mut read_by_kept = vec![false; n];
        for (i, &node) in tape.iter().enumerate() {
            if degree[i].is_none() {
                for j in operands(node) {
                    read_by_kept[j as usize] = true;
                    leaf[j as usize] = degree[j as usize].is_some_and(|k| k >= 1);
                }
            }
        }
        // The parts: folded nodes a leaf needs, found backward from the leaves.
        let mut needed = leaf.clone();
        for i in (0..n).rev() {
            if needed[i] {
                operands(tape[i]).for_each(|j| needed[j as usize] = true);
            }
        }
        let mut at = vec![u32::MAX; n];
        let mut parts = Vec::new();
        for i in (0..n).filter(|&i| needed[i]) {
            at[i] = parts.len() as u32;
            parts.push(renamed(tape[i], &at));
        }
        let leaves: Vec<u32> = (0..n).filter(|&i| leaf[i]).map(|i| at[i]).collect();
        // The tape left: leaf slots, then the kept nodes and the constants they read.
        let mut left: Vec<Node> = vec![Node::Const(0); leaves.len()];
        for (i, k) in (0..n).filter(|&i| leaf[i]).zip(0u32..) {
            at[i] = k;
        }
        for (i, &node) in tape.iter().enumerate() {
            let constant = matches!(node, Node::Const(_)) && read_by_kept[i];
            if (degree[i].is_none() || constant) && !leaf[i] {
                at[i] = left.len() as u32;
                left.push(renamed(node, &at));
            }
        }
        let folded = n - (left.len() - leaves.len());
        (folded >= MIN_FOLDED && !leaves.is_empty()).then_some(Plan {
            parts,
            leaves,
            tape: left,
        })
    }

    /// The plan borrowed.
    pub fn view(&self) -> PlanView<'_> {
        PlanView {
            parts: &self.parts,
            leaves: &self.leaves,
            tape: &self.tape,
        }
    }
}

/// `node` with its operands renumbered by `at`.
fn renamed(node: Node, at: &[u32]) -> Node {
    let r = |j: u32| at[j as usize];
    match node {
        Node::Unary(op, a) => Node::Unary(op, r(a)),
        Node::Binary(op, a, b) => Node::Binary(op, r(a), r(b)),
        Node::PowI(a, k) => Node::PowI(r(a), k),
        other => other,
    }
}

/// The operands of a node.
fn operands(node: Node) -> impl Iterator<Item = u32> {
    let (a, b) = match node {
        Node::Unary(_, a) | Node::PowI(a, _) => (Some(a), None),
        Node::Binary(_, a, b) => (Some(a), Some(b)),
        _ => (None, None),
    };
    a.into_iter().chain(b)
}

thread_local! {
    /// The parts' coefficients of the ray being traced.
    static PARTS: RefCell<Vec<Quad>> = const { RefCell::new(Vec::new()) };
    /// A leaf buffer to reuse: a [`RayTape`] takes it and gives it back when dropped.
    static SPARE: Cell<Vec<Quad>> = const { Cell::new(Vec::new()) };
    static SCRATCH_D: RefCell<Vec<Dual<Interval, 1>>> = const { RefCell::new(Vec::new()) };
    static SCRATCH_F: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
    static SCRATCH_T: RefCell<Vec<Dual<f64, 1>>> = const { RefCell::new(Vec::new()) };
}

/// p·q for polynomials whose degrees add up to at most 2.
#[inline]
fn mul(p: &Quad, q: &Quad) -> Quad {
    [
        p[0] * q[0],
        p[0] * q[1] + p[1] * q[0],
        p[0] * q[2] + p[1] * q[1] + p[2] * q[0],
    ]
}

/// One ray's leaves: F along the ray as the plan's tape over leaf polynomials of
/// s = t − t0.
pub struct RayTape<'p> {
    tape: &'p [Node],
    t0: f64,
    leaves: Vec<Quad>,
}

impl Drop for RayTape<'_> {
    fn drop(&mut self) {
        SPARE.set(std::mem::take(&mut self.leaves));
    }
}

impl<'p> RayTape<'p> {
    /// The leaves of `plan` along `ray` from t0. None where a coefficient is not
    /// finite: the leaves say nothing there, and the search takes the whole tape.
    /// Allocates nothing once this thread has traced a ray with as many leaves.
    pub fn new(plan: PlanView<'p>, ray: &Ray, t0: f64) -> Option<Self> {
        let (p, d) = (ray.at(t0), ray.d);
        let mut leaves = SPARE.take();
        leaves.clear();
        PARTS.with_borrow_mut(|c| {
            if c.len() < plan.parts.len() {
                c.resize(plan.parts.len(), [0.0; 3]);
            }
            for (i, &node) in plan.parts.iter().enumerate() {
                let s = |j: u32| c[j as usize];
                c[i] = match node {
                    Node::Const(b) => [f64::from_bits(b), 0.0, 0.0],
                    Node::Var(x) => {
                        let k = match x {
                            Var::X => 0,
                            Var::Y => 1,
                            Var::Z => 2,
                        };
                        [p[k], d[k], 0.0]
                    }
                    Node::Unary(UnaryOp::Neg, a) => s(a).map(|c| -c),
                    Node::Unary(UnaryOp::Square, a) => mul(&s(a), &s(a)),
                    Node::Binary(BinaryOp::Add, a, b) => {
                        let (a, b) = (s(a), s(b));
                        std::array::from_fn(|k| a[k] + b[k])
                    }
                    Node::Binary(BinaryOp::Sub, a, b) => {
                        let (a, b) = (s(a), s(b));
                        std::array::from_fn(|k| a[k] - b[k])
                    }
                    Node::Binary(BinaryOp::Mul, a, b) => mul(&s(a), &s(b)),
                    Node::Binary(BinaryOp::Div, a, b) => {
                        let q = s(b)[0];
                        s(a).map(|c| c / q)
                    }
                    Node::PowI(_, 0) => [1.0, 0.0, 0.0],
                    Node::PowI(a, 1) => s(a),
                    Node::PowI(a, _) => mul(&s(a), &s(a)),
                    _ => unreachable!("a node a plan folds"),
                };
            }
            leaves.extend(plan.leaves.iter().map(|&i| c[i as usize]));
        });
        let tape = Self {
            tape: plan.tape,
            t0,
            leaves,
        };
        let finite = tape.leaves.iter().flatten().all(|c| c.is_finite());
        finite.then_some(tape)
    }

    /// F and dF/dt over [a, b].
    pub fn segment(&self, a: f64, b: f64) -> (Interval, Interval) {
        let (sa, sb) = (a - self.t0, b - self.t0);
        let r = SCRATCH_D.with_borrow_mut(|s| {
            let s = slots(s, self.tape.len());
            for (slot, q) in s.iter_mut().zip(&self.leaves) {
                *slot = leaf_bounds(q, sa, sb);
            }
            eval_tail(self.tape, self.leaves.len(), s)
        });
        (r.v, r.d[0])
    }

    /// F at t.
    pub fn value(&self, t: f64) -> f64 {
        let u = t - self.t0;
        SCRATCH_F.with_borrow_mut(|s| {
            let s = slots(s, self.tape.len());
            for (slot, q) in s.iter_mut().zip(&self.leaves) {
                *slot = q[0] + u * (q[1] + u * q[2]);
            }
            eval_tail(self.tape, self.leaves.len(), s)
        })
    }

    /// F and dF/dt at t.
    pub fn value_slope(&self, t: f64) -> (f64, f64) {
        let u = t - self.t0;
        let r = SCRATCH_T.with_borrow_mut(|s| {
            let s = slots(s, self.tape.len());
            for (slot, q) in s.iter_mut().zip(&self.leaves) {
                *slot = Dual::new(q[0] + u * (q[1] + u * q[2]), [q[1] + 2.0 * u * q[2]]);
            }
            eval_tail(self.tape, self.leaves.len(), s)
        });
        (r.v, r.d[0])
    }
}

/// Grows this thread's scratch to a plan of `n` nodes in all (nothing allocates once
/// warm).
pub(crate) fn reserve(n: usize) {
    use crate::interval_trace::at_least;
    PARTS.with_borrow_mut(|s| at_least(s, n));
    SCRATCH_D.with_borrow_mut(|s| at_least(s, n));
    SCRATCH_F.with_borrow_mut(|s| at_least(s, n));
    SCRATCH_T.with_borrow_mut(|s| at_least(s, n));
    let mut spare = SPARE.take();
    at_least(&mut spare, n);
    SPARE.set(spare);
}

/// The first `n` slots of `scratch`, grown to hold them.
#[inline]
fn slots<S: Scalar>(scratch: &mut Vec<S>, n: usize) -> &mut [S] {
    if scratch.len() < n {
        scratch.resize(n, S::constant(0.0));
    }
    &mut scratch[..n]
}

/// Bounds of q(s) = q0 + q1·s + q2·s² and of q'(s) over [sa, sb]: the exact ranges of
/// the polynomial (its values at the ends and at its vertex where that lies inside),
/// widened by a bound on the rounding of Horner's rule at any s of the segment (Higham,
/// "Accuracy and Stability of Numerical Algorithms", §5.1: |error| ≤ γ_{2n} Σ|q_k||s|^k),
/// so that every value [`RayTape::value`] computes lies inside.
#[inline]
fn leaf_bounds(q: &Quad, sa: f64, sb: f64) -> Dual<Interval, 1> {
    let at = |s: f64| q[0] + s * (q[1] + s * q[2]);
    let (va, vb) = (at(sa), at(sb));
    let (mut lo, mut hi) = (va.min(vb), va.max(vb));
    let vertex = -q[1] / (2.0 * q[2]);
    if vertex > sa && vertex < sb {
        let v = at(vertex);
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let m = sa.abs().max(sb.abs());
    let err = 8.0 * f64::EPSILON * (q[0].abs() + m * (q[1].abs() + m * q[2].abs())) + TINY;
    let (da, db) = (q[1] + 2.0 * sa * q[2], q[1] + 2.0 * sb * q[2]);
    let derr = 8.0 * f64::EPSILON * (q[1].abs() + 2.0 * m * q[2].abs()) + TINY;
    Dual::new(
        Interval::new(lo - err, hi + err),
        [Interval::new(da.min(db) - derr, da.max(db) + derr)],
    )
}

/// The least subnormal, so that a zero bound widens too.
const TINY: f64 = f64::from_bits(1);
