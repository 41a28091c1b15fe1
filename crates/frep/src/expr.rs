//! The one internal representation: a deduplicated expression DAG in evaluation order.
//!
//! Every solid lowers to an [`Expr`]: a list of [`Node`]s in which each node refers only
//! to earlier ones and the last is the root, with equal subexpressions stored once
//! (hash-consing) and constant subexpressions folded. Evaluation is one pass over the
//! list with any [`Scalar`]: f64, f32, [`Interval`], [`Dual`].

use crate::dual::Dual;
use crate::interval::Interval;
use crate::lanes::Lanes;
use crate::scalar::Scalar;
use crate::tree::{BinaryOp, Tree, TreeOp, UnaryOp, Var};
use std::cell::RefCell;
// Node deduplication hashes every node of a model once or more: std's SipHash was 9 %
// of prospero.vm's setup. foldhash is seeded per process like std's (a crafted model
// cannot choose colliding keys ahead of a run) at a fraction of the cost.
use foldhash::HashMap;

thread_local! {
    /// Liveness, renumbering and output buffers reused by [`Expr::simplify`].
    static SIMPLIFY: RefCell<(Vec<bool>, Vec<u32>, Vec<Node>)> =
        const { RefCell::new((Vec::new(), Vec::new(), Vec::new())) };
}

/// Grows this thread's [`simplify_into`] buffers to a tape of `n` nodes, so that a
/// caller that reserves before its first query allocates nothing later.
pub(crate) fn reserve_simplify(n: usize) {
    SIMPLIFY.with_borrow_mut(|(live, remap, written)| {
        live.reserve(n.saturating_sub(live.len()));
        remap.reserve(n.saturating_sub(remap.len()));
        written.reserve(n.saturating_sub(written.len()));
    });
}

/// One node of an [`Expr`]; operands are indices of earlier nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum Node {
    /// A constant, stored as its bit pattern so that nodes hash.
    Const(u64),
    /// A coordinate.
    Var(Var),
    /// A one-argument operation.
    Unary(UnaryOp, u32),
    /// A two-argument operation.
    Binary(BinaryOp, u32, u32),
    /// An integer power.
    PowI(u32, i32),
}

/// Which operand of a min/max node decides its value over a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Choice {
    /// The first operand, everywhere in the box.
    Left,
    /// The second operand, everywhere in the box.
    Right,
    /// Either, depending on the point.
    Both,
}

/// A compiled, deduplicated expression of x, y, z (see the module docs).
#[derive(Clone, Debug)]
pub struct Expr {
    nodes: Vec<Node>,
}

/// Builds the node list with hash-consing and constant folding.
struct Builder {
    nodes: Vec<Node>,
    index: HashMap<Node, u32>,
}

impl Builder {
    fn push(&mut self, n: Node) -> u32 {
        if let Some(&i) = self.index.get(&n) {
            return i;
        }
        let i = self.nodes.len() as u32;
        self.nodes.push(n);
        self.index.insert(n, i);
        i
    }
    fn constant(&mut self, v: f64) -> u32 {
        // -0.0 and 0.0 are kept apart (atan2 tells them apart); NaN stays NaN.
        self.push(Node::Const(v.to_bits()))
    }
    fn const_of(&self, i: u32) -> Option<f64> {
        match self.nodes[i as usize] {
            Node::Const(b) => Some(f64::from_bits(b)),
            _ => None,
        }
    }
    fn unary(&mut self, op: UnaryOp, a: u32) -> u32 {
        if let Some(v) = self.const_of(a) {
            return self.constant(eval_unary(op, v));
        }
        if op == UnaryOp::Neg {
            if let Node::Unary(UnaryOp::Neg, inner) = self.nodes[a as usize] {
                return inner;
            }
        }
        self.push(Node::Unary(op, a))
    }
    fn binary(&mut self, op: BinaryOp, a: u32, b: u32) -> u32 {
        let (ca, cb) = (self.const_of(a), self.const_of(b));
        if let (Some(x), Some(y)) = (ca, cb) {
            return self.constant(eval_binary(op, x, y));
        }
        // Identities (a float pattern compares with ==, so 0.0 also matches −0.0).
        match (op, ca, cb) {
            (BinaryOp::Add, Some(0.0), _) => return b,
            (BinaryOp::Add | BinaryOp::Sub, _, Some(0.0)) => return a,
            (BinaryOp::Sub, Some(0.0), _) => return self.unary(UnaryOp::Neg, b),
            (BinaryOp::Mul, Some(1.0), _) => return b,
            (BinaryOp::Mul | BinaryOp::Div, _, Some(1.0)) => return a,
            (BinaryOp::Mul, Some(-1.0), _) => return self.unary(UnaryOp::Neg, b),
            (BinaryOp::Mul | BinaryOp::Div, _, Some(-1.0)) => return self.unary(UnaryOp::Neg, a),
            _ => {}
        }
        if a == b && matches!(op, BinaryOp::Min | BinaryOp::Max) {
            return a;
        }
        // a·a is a², the same value at a point (x·x both ways), but bounded over an
        // interval as a square ([−1, 2]² = [0, 4], where [−1, 2]·[−1, 2] = [−2, 4]).
        if a == b && op == BinaryOp::Mul {
            return self.unary(UnaryOp::Square, a);
        }
        // Commutative operations get a canonical operand order so that a+b and b+a merge.
        let (a, b) = match op {
            BinaryOp::Add | BinaryOp::Mul | BinaryOp::Min | BinaryOp::Max if b < a => (b, a),
            _ => (a, b),
        };
        self.push(Node::Binary(op, a, b))
    }
    fn powi(&mut self, a: u32, n: i32) -> u32 {
        match (self.const_of(a), n) {
            (Some(v), _) => self.constant(v.powi(n)),
            (_, 0) => self.constant(1.0),
            (_, 1) => a,
            (_, 2) => self.unary(UnaryOp::Square, a),
            _ => self.push(Node::PowI(a, n)),
        }
    }
    fn lower(&mut self, t: &Tree, memo: &mut HashMap<*const TreeOp, u32>) -> u32 {
        if let Some(&i) = memo.get(&t.ptr()) {
            return i;
        }
        // An explicit stack: models such as prospero.vm nest thousands of levels deep.
        let mut stack: Vec<(Tree, bool)> = vec![(t.clone(), false)];
        while let Some((n, expanded)) = stack.pop() {
            if memo.contains_key(&n.ptr()) {
                continue;
            }
            if !expanded {
                stack.push((n.clone(), true));
                match n.op() {
                    TreeOp::Unary(_, a) | TreeOp::PowI(a, _) => stack.push((a.clone(), false)),
                    TreeOp::Binary(_, a, b) => {
                        stack.push((b.clone(), false));
                        stack.push((a.clone(), false));
                    }
                    _ => {}
                }
                continue;
            }
            let id = match n.op() {
                TreeOp::Const(v) => self.constant(*v),
                TreeOp::Var(v) => self.push(Node::Var(*v)),
                TreeOp::Unary(op, a) => {
                    let a = memo[&a.ptr()];
                    self.unary(*op, a)
                }
                TreeOp::Binary(op, a, b) => {
                    let (a, b) = (memo[&a.ptr()], memo[&b.ptr()]);
                    self.binary(*op, a, b)
                }
                TreeOp::PowI(a, k) => {
                    let a = memo[&a.ptr()];
                    self.powi(a, *k)
                }
            };
            memo.insert(n.ptr(), id);
        }
        memo[&t.ptr()]
    }
}

fn eval_unary(op: UnaryOp, v: f64) -> f64 {
    apply_unary(op, v)
}

fn eval_binary(op: BinaryOp, a: f64, b: f64) -> f64 {
    apply_binary(op, a, b)
}

/// Writes node `n`'s value (narrowed where it is an R-function) to `scratch[i]`; the
/// slots before it hold its operands' values. Each operation stores its own result
/// into a slot sized beforehand ([`slots`]): joined into one value and pushed (which
/// may call the allocator), a wide scalar (`Dual<Interval, 1>` is 32 bytes) was
/// spilled to the stack in halves and reloaded whole, a store-forwarding stall on
/// every node.
#[inline(always)]
fn set_node<S: Scalar>(nodes: &[Node], i: usize, n: Node, scratch: &mut [S], x: S, y: S, z: S) {
    macro_rules! put {
        ($v:expr) => {{
            let v = $v;
            scratch[i] = v
        }};
    }
    match n {
        Node::Const(b) => put!(S::constant(f64::from_bits(b))),
        Node::Var(Var::X) => put!(x),
        Node::Var(Var::Y) => put!(y),
        Node::Var(Var::Z) => put!(z),
        Node::PowI(a, k) => put!(scratch[a as usize].powi(k)),
        Node::Unary(op, a) => {
            let a = scratch[a as usize];
            match op {
                UnaryOp::Neg => put!(-a),
                UnaryOp::Abs => put!(a.abs()),
                UnaryOp::Sqrt => put!(a.sqrt()),
                UnaryOp::Square => put!(a.square()),
                op => put!(apply_unary(op, a)),
            }
        }
        Node::Binary(op, a, b) => {
            let (u, w) = (scratch[a as usize], scratch[b as usize]);
            match op {
                BinaryOp::Add => put!(r_narrowed(nodes, n, u + w, scratch)),
                BinaryOp::Sub => put!(r_narrowed(nodes, n, u - w, scratch)),
                BinaryOp::Mul => put!(u * w),
                BinaryOp::Div => put!(u / w),
                BinaryOp::Min => put!(u.min(w)),
                BinaryOp::Max => put!(u.max(w)),
                op => put!(apply_binary(op, u, w)),
            }
        }
    }
}

/// The operands (a, b) and form (true: union) when node `n` computes the R-function
/// a + b ± √(a² + b²) from the nodes before it, as [`crate::csg`] builds it (operands of
/// each sum in either order).
#[inline]
pub(crate) fn r_pattern(nodes: &[Node], n: Node) -> Option<(u32, u32, bool)> {
    let Node::Binary(op @ (BinaryOp::Add | BinaryOp::Sub), s, r) = n else {
        return None;
    };
    let get = |i: u32| nodes.get(i as usize).copied();
    let (Some(Node::Binary(BinaryOp::Add, a, b)), Some(Node::Unary(UnaryOp::Sqrt, q))) =
        (get(s), get(r))
    else {
        return None;
    };
    let Some(Node::Binary(BinaryOp::Add, p, q)) = get(q) else {
        return None;
    };
    let (Some(Node::Unary(UnaryOp::Square, pa)), Some(Node::Unary(UnaryOp::Square, qa))) =
        (get(p), get(q))
    else {
        return None;
    };
    ((pa, qa) == (a, b) || (pa, qa) == (b, a)).then_some((a, b, op == BinaryOp::Add))
}

/// `v`, node `n`'s value, narrowed where `n` is an R-function ([`Scalar::r_bound`]);
/// for point types this is `v` and the test compiles away.
#[inline(always)]
fn r_narrowed<S: Scalar>(nodes: &[Node], n: Node, v: S, scratch: &[S]) -> S {
    if !S::R_BOUND {
        return v;
    }
    match r_pattern(nodes, n) {
        Some((a, b, union)) => S::r_bound(v, scratch[a as usize], scratch[b as usize], union),
        None => v,
    }
}

#[inline(always)]
fn apply_unary<S: Scalar>(op: UnaryOp, a: S) -> S {
    match op {
        UnaryOp::Neg => -a,
        UnaryOp::Abs => a.abs(),
        UnaryOp::Sqrt => a.sqrt(),
        UnaryOp::Square => a.square(),
        UnaryOp::Exp => a.exp(),
        UnaryOp::Ln => a.ln(),
        UnaryOp::Sin => a.sin(),
        UnaryOp::Cos => a.cos(),
        UnaryOp::Tan => a.tan(),
        UnaryOp::Asin => a.asin(),
        UnaryOp::Acos => a.acos(),
        UnaryOp::Atan => a.atan(),
        UnaryOp::Floor => a.floor(),
        UnaryOp::Ceil => a.ceil(),
        UnaryOp::Round => a.round(),
        UnaryOp::Not => a.not(),
    }
}

#[inline(always)]
fn apply_binary<S: Scalar>(op: BinaryOp, a: S, b: S) -> S {
    match op {
        BinaryOp::Add => a + b,
        BinaryOp::Sub => a - b,
        BinaryOp::Mul => a * b,
        BinaryOp::Div => a / b,
        BinaryOp::Min => a.min(b),
        BinaryOp::Max => a.max(b),
        BinaryOp::Atan2 => a.atan2(b),
        BinaryOp::Mod => a.modulo(b),
        BinaryOp::Compare => a.compare(b),
        BinaryOp::And => a.and(b),
        BinaryOp::Or => a.or(b),
    }
}

impl Expr {
    /// Lowers a tree: shared and equal subexpressions become one node, constants fold,
    /// and nodes that the root does not use are dropped.
    pub fn new(tree: &Tree) -> Self {
        let mut b = Builder {
            nodes: Vec::new(),
            index: HashMap::default(),
        };
        let root = b.lower(tree, &mut HashMap::default());
        Self::compact(b.nodes, root)
    }

    /// Keeps the nodes reachable from `root`, in order, with `root` last.
    fn compact(nodes: Vec<Node>, root: u32) -> Self {
        let mut live = vec![false; nodes.len()];
        live[root as usize] = true;
        for i in (0..=root as usize).rev() {
            if !live[i] {
                continue;
            }
            match nodes[i] {
                Node::Unary(_, a) | Node::PowI(a, _) => live[a as usize] = true,
                Node::Binary(_, a, b) => {
                    live[a as usize] = true;
                    live[b as usize] = true;
                }
                _ => {}
            }
        }
        let mut remap = vec![u32::MAX; nodes.len()];
        let mut out = Vec::new();
        for i in 0..=root as usize {
            if !live[i] {
                continue;
            }
            remap[i] = out.len() as u32;
            out.push(match nodes[i] {
                Node::Unary(op, a) => Node::Unary(op, remap[a as usize]),
                Node::PowI(a, n) => Node::PowI(remap[a as usize], n),
                Node::Binary(op, a, b) => Node::Binary(op, remap[a as usize], remap[b as usize]),
                n => n,
            });
        }
        Expr { nodes: out }
    }

    /// The nodes in evaluation order; the last is the root.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always false: an expression has at least its root.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Rebuilds a tree (sharing preserved), to compose a compiled expression further.
    pub fn to_tree(&self) -> Tree {
        self.substitute(&Tree::x(), &Tree::y(), &Tree::z())
    }

    /// Rebuilds a tree with `x`, `y`, `z` put in place of the coordinates.
    pub fn substitute(&self, x: &Tree, y: &Tree, z: &Tree) -> Tree {
        let mut t: Vec<Tree> = Vec::with_capacity(self.nodes.len());
        for n in &self.nodes {
            let v = match *n {
                Node::Const(b) => Tree::constant(f64::from_bits(b)),
                Node::Var(Var::X) => x.clone(),
                Node::Var(Var::Y) => y.clone(),
                Node::Var(Var::Z) => z.clone(),
                Node::Unary(op, a) => Tree::unary(op, t[a as usize].clone()),
                Node::Binary(op, a, b) => {
                    Tree::binary(op, t[a as usize].clone(), t[b as usize].clone())
                }
                Node::PowI(a, k) => Tree::new(TreeOp::PowI(t[a as usize].clone(), k)),
            };
            t.push(v);
        }
        t.pop().expect("an expression has a root")
    }

    /// Evaluates at (x, y, z) over any [`Scalar`], using `scratch` for the node values.
    #[inline]
    pub fn eval_with<S: Scalar>(&self, x: S, y: S, z: S, scratch: &mut Vec<S>) -> S {
        eval_nodes(&self.nodes, x, y, z, scratch)
    }

    /// Evaluation over a box (intervals, or duals of intervals) that also records, for
    /// every min/max node, which operand decides the result over the whole box (Keeter
    /// 2020, "Massively Parallel Rendering of Complex Closed-Form Implicit Surfaces",
    /// §3: tape simplification). `choices` gets one entry per node.
    pub fn eval_choices<S: Scalar>(
        &self,
        x: S,
        y: S,
        z: S,
        scratch: &mut Vec<S>,
        choices: &mut Vec<Choice>,
    ) -> S {
        eval_choices_nodes(&self.nodes, x, y, z, scratch, choices)
    }

    /// The expression with every decided min/max replaced by its deciding operand and
    /// what no longer feeds the root dropped. Over the box the choices were recorded on,
    /// the result has exactly the same values as `self`. None when nothing was decided.
    pub fn simplify(&self, choices: &[Choice]) -> Option<Expr> {
        let mut out = Vec::new();
        simplify_into(&self.nodes, None, choices, &mut out).then_some(Expr { nodes: out })
    }

    /// F at a point, in f64.
    pub fn eval(&self, p: [f64; 3]) -> f64 {
        self.eval_with(p[0], p[1], p[2], &mut Vec::with_capacity(self.len()))
    }

    /// F at a point, in f32 (what the GPU computes).
    pub fn eval_f32(&self, p: [f32; 3]) -> f32 {
        self.eval_with(p[0], p[1], p[2], &mut Vec::with_capacity(self.len()))
    }

    /// Bounds of F over the box `lo..hi`.
    pub fn eval_interval(&self, lo: [f64; 3], hi: [f64; 3]) -> Interval {
        let i = |k: usize| Interval::new(lo[k], hi[k]);
        self.eval_with(i(0), i(1), i(2), &mut Vec::with_capacity(self.len()))
    }

    /// F and ∇F at a point.
    pub fn gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let v = |k: usize| Dual::<f64, 3>::var(p[k], k);
        let r = self.eval_with(v(0), v(1), v(2), &mut Vec::with_capacity(self.len()));
        (r.v, r.d)
    }
}

/// Evaluates the node list `nodes` (root last) at (x, y, z), using `scratch` for the
/// node values: [`Expr::eval_with`] over a borrowed tape.
#[inline]
pub fn eval_nodes<S: Scalar>(nodes: &[Node], x: S, y: S, z: S, scratch: &mut Vec<S>) -> S {
    let scratch = slots(scratch, nodes.len());
    for (i, n) in nodes.iter().enumerate() {
        set_node(nodes, i, *n, scratch, x, y, z);
    }
    *scratch.last().expect("an expression has a root")
}

/// Evaluates `nodes` from index `start` on, where `scratch[..start]` holds the values of
/// the nodes before it (leaves filled by the caller, [`crate::ray_tape`]); no node from
/// `start` on may read a coordinate.
#[inline]
pub(crate) fn eval_tail<S: Scalar>(nodes: &[Node], start: usize, scratch: &mut [S]) -> S {
    let scratch = &mut scratch[..nodes.len()];
    let zero = S::constant(0.0);
    for (i, n) in nodes.iter().enumerate().skip(start) {
        set_node(nodes, i, *n, scratch, zero, zero, zero);
    }
    scratch[nodes.len() - 1]
}

/// The first `n` values of `scratch`, grown to hold them (grown once per thread in
/// practice). What they held before is never read: a node's operands precede it.
#[inline]
fn slots<S: Scalar>(scratch: &mut Vec<S>, n: usize) -> &mut [S] {
    if scratch.len() < n {
        scratch.resize(n, S::constant(0.0));
    }
    &mut scratch[..n]
}

/// [`Expr::eval_choices`] over a borrowed tape.
pub fn eval_choices_nodes<S: Scalar>(
    nodes: &[Node],
    x: S,
    y: S,
    z: S,
    scratch: &mut Vec<S>,
    choices: &mut Vec<Choice>,
) -> S {
    let scratch = slots(scratch, nodes.len());
    // Every node but a decided min/max keeps `Both`: filled at once, not pushed per node.
    choices.clear();
    choices.resize(nodes.len(), Choice::Both);
    for (i, n) in nodes.iter().enumerate() {
        match *n {
            Node::Binary(op @ (BinaryOp::Min | BinaryOp::Max), a, b) => {
                (scratch[i], choices[i]) = choose(op, scratch[a as usize], scratch[b as usize]);
            }
            node => set_node(nodes, i, node, scratch, x, y, z),
        }
    }
    *scratch.last().expect("an expression has a root")
}

/// Whether `nodes` hold a min or max: a node whose choice over a box can be decided,
/// which tape simplification needs.
pub fn has_min_max(nodes: &[Node]) -> bool {
    nodes
        .iter()
        .any(|n| matches!(n, Node::Binary(BinaryOp::Min | BinaryOp::Max, ..)))
}

/// The most lanes [`eval_choices_lanes`] records choices for: an octree box's children.
pub const MAX_LANES: usize = 8;

/// A min/max node's value over a box and which operand decides it there.
#[inline(always)]
fn choose<S: Scalar>(op: BinaryOp, u: S, w: S) -> (S, Choice) {
    let a_low = u.less(w) == Some(true);
    let b_low = w.less(u) == Some(true);
    match (op, a_low, b_low) {
        (BinaryOp::Min, true, _) | (BinaryOp::Max, _, true) => (u, Choice::Left),
        (BinaryOp::Min, _, true) | (BinaryOp::Max, true, _) => (w, Choice::Right),
        _ => (apply_binary(op, u, w), Choice::Both),
    }
}

/// [`eval_choices_nodes`] over `L` ≤ [`MAX_LANES`] boxes in one pass ([`crate::lanes`]):
/// lane i's value, and its choices `choices[node][i]`, are those of the one-box
/// evaluation bit for bit ([`simplify_into_lane`] reads them).
pub fn eval_choices_lanes<S: Scalar, const L: usize>(
    nodes: &[Node],
    x: Lanes<S, L>,
    y: Lanes<S, L>,
    z: Lanes<S, L>,
    scratch: &mut Vec<Lanes<S, L>>,
    choices: &mut Vec<[Choice; MAX_LANES]>,
) -> Lanes<S, L> {
    const { assert!(L <= MAX_LANES) };
    let scratch = slots(scratch, nodes.len());
    choices.clear();
    choices.resize(nodes.len(), [Choice::Both; MAX_LANES]);
    for (i, n) in nodes.iter().enumerate() {
        match *n {
            Node::Binary(op @ (BinaryOp::Min | BinaryOp::Max), a, b) => {
                let (u, w) = (scratch[a as usize], scratch[b as usize]);
                let (v, c) = (&mut scratch[i].0, &mut choices[i]);
                for (l, (v, c)) in v.iter_mut().zip(c).enumerate() {
                    (*v, *c) = choose(op, u.0[l], w.0[l]);
                }
            }
            node => set_node(nodes, i, node, scratch, x, y, z),
        }
    }
    *scratch.last().expect("an expression has a root")
}

/// [`Expr::simplify`] appending to `out`: the tape is `tape`, or when `tape` is None the
/// nodes `out[range]` already in `out` (so that simplified tapes can stack up in one
/// reused arena). Returns false, appending nothing, when no choice is decided. Reuses
/// thread-local liveness buffers: no allocation once `out` and they have grown.
pub fn simplify_into(
    tape: &[Node],
    range: Option<std::ops::Range<usize>>,
    choices: &[Choice],
    out: &mut Vec<Node>,
) -> bool {
    simplify_by(tape, range, |i| choices[i], out)
}

/// [`simplify_into`] with lane `lane`'s choices of [`eval_choices_lanes`].
pub fn simplify_into_lane(
    tape: &[Node],
    range: Option<std::ops::Range<usize>>,
    choices: &[[Choice; MAX_LANES]],
    lane: usize,
    out: &mut Vec<Node>,
) -> bool {
    simplify_by(tape, range, |i| choices[i][lane], out)
}

/// [`simplify_into`] with node i's choice `choice(i)`.
#[inline(always)]
fn simplify_by(
    tape: &[Node],
    range: Option<std::ops::Range<usize>>,
    choice: impl Fn(usize) -> Choice,
    out: &mut Vec<Node>,
) -> bool {
    let n = match &range {
        Some(r) => r.len(),
        None => tape.len(),
    };
    if !(0..n).any(|i| choice(i) != Choice::Both) {
        return false;
    }
    // The source borrowed once (it may lie in `out`) and the nodes written to a buffer
    // of their own, appended at the end; the buffers taken out of the thread-local
    // cell, whose lengths and addresses were reloaded from it on every node. Pushing
    // onto the vector read from, with the buffers in the cell, cost 1.8 % more of a
    // bare model's setup (prospero, colonnade).
    let src: &[Node] = match &range {
        Some(r) => &out[r.clone()],
        None => tape,
    };
    let (mut live, mut remap, mut written) = SIMPLIFY.with_borrow_mut(std::mem::take);
    // Backward: what the root still needs, following only the chosen operands.
    live.clear();
    live.resize(n, false);
    live[n - 1] = true;
    for i in (0..n).rev() {
        if !live[i] {
            continue;
        }
        match (src[i], choice(i)) {
            (Node::Binary(_, a, _), Choice::Left) => live[a as usize] = true,
            (Node::Binary(_, _, b), Choice::Right) => live[b as usize] = true,
            (Node::Binary(_, a, b), _) => {
                live[a as usize] = true;
                live[b as usize] = true;
            }
            (Node::Unary(_, a) | Node::PowI(a, _), _) => live[a as usize] = true,
            _ => {}
        }
    }
    // Forward: copy what is live; a decided min/max is its chosen operand.
    remap.clear();
    remap.resize(n, u32::MAX);
    written.clear();
    for i in 0..n {
        if !live[i] {
            continue;
        }
        remap[i] = match (src[i], choice(i)) {
            (Node::Binary(_, a, _), Choice::Left) => remap[a as usize],
            (Node::Binary(_, _, b), Choice::Right) => remap[b as usize],
            (nd, _) => {
                written.push(match nd {
                    Node::Unary(op, a) => Node::Unary(op, remap[a as usize]),
                    Node::PowI(a, k) => Node::PowI(remap[a as usize], k),
                    Node::Binary(op, a, b) => {
                        Node::Binary(op, remap[a as usize], remap[b as usize])
                    }
                    other => other,
                });
                written.len() as u32 - 1
            }
        };
    }
    // Every live node is reachable from the root through chosen operands, so the
    // root's image is the last node written.
    debug_assert_eq!(remap[n - 1] as usize, written.len() - 1);
    out.extend_from_slice(&written);
    SIMPLIFY.with_borrow_mut(|b| *b = (live, remap, written));
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere() -> Tree {
        1.0 - (Tree::x().square() + Tree::y().square() + Tree::z().square())
    }

    /// A product of a value with itself is that value's square: one node, and bounded
    /// as a square over an interval.
    #[test]
    fn self_products_are_squares() {
        let d = Tree::x() - 0.5;
        let (prod, sq) = (Expr::new(&(&d * &d)), Expr::new(&d.square()));
        assert_eq!(prod.nodes(), sq.nodes());
        let r = prod.eval_interval([-0.5, 0.0, 0.0], [2.5, 0.0, 0.0]);
        assert!(r.lo == 0.0 && r.hi >= 4.0 && r.hi < 4.0 + 1e-12, "{r:?}");
    }

    #[test]
    fn dedup_and_fold() {
        let x = Tree::x();
        // (x + 1·2) + (x + 2): the two sums are one node.
        let a = &x + (Tree::constant(1.0) * 2.0);
        let b = &x + 2.0;
        let e = Expr::new(&(a * b));
        // x, 2, x+2, (x+2)·(x+2)
        assert_eq!(e.len(), 4, "{:?}", e.nodes());
        assert_eq!(e.eval([1.0, 0.0, 0.0]), 9.0);
    }

    #[test]
    fn sphere_values_and_gradient() {
        let e = Expr::new(&sphere());
        assert_eq!(e.eval([0.0, 0.0, 0.0]), 1.0);
        assert_eq!(e.eval([1.0, 0.0, 0.0]), 0.0);
        let (v, g) = e.gradient([0.5, -0.25, 2.0]);
        assert_eq!(v, 1.0 - 0.25 - 0.0625 - 4.0);
        assert_eq!(g, [-1.0, 0.5, -4.0]);
        let i = e.eval_interval([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]);
        assert!(i.lo <= -2.0 && i.hi >= 1.0 && i.hi < 1.0 + 1e-9);
    }

    #[test]
    fn roundtrip_tree_keeps_values() {
        let t = (Tree::x().sin() * Tree::y().atan2(&Tree::z())).max(&sphere()) / 3.0;
        let e = Expr::new(&t);
        let e2 = Expr::new(&e.to_tree());
        assert_eq!(e.nodes(), e2.nodes());
        let p = [0.3, -0.7, 0.2];
        assert_eq!(e.eval(p), e2.eval(p));
        assert!((e.eval_f32([0.3, -0.7, 0.2]) as f64 - e.eval(p)).abs() < 1e-6);
    }

    #[test]
    fn simplify_keeps_values_inside_the_box() {
        let (x, y) = (Tree::x(), Tree::y());
        // min(x, 5 + y²) over x ∈ [-1, 1]: always x.  max(that, y − 10): always the min.
        let t = x.min(&(5.0 + y.square())).max(&(&y - 10.0)) + x.sin();
        let e = Expr::new(&t);
        let (mut s, mut c) = (vec![], vec![]);
        let b = Interval::new(-1.0, 1.0);
        e.eval_choices(b, b, b, &mut s, &mut c);
        let simple = e.simplify(&c).expect("both choices are decided");
        assert!(simple.len() < e.len(), "{} vs {}", simple.len(), e.len());
        for i in 0..50 {
            let p = [-1.0 + i as f64 * 0.04, 0.3 - i as f64 * 0.01, 0.0];
            assert_eq!(simple.eval(p), e.eval(p));
        }
    }

    #[test]
    fn deep_chain_does_not_overflow_the_stack() {
        let mut t = Tree::x();
        for k in 0..200_000 {
            t = t + (k % 7) as f64;
        }
        let e = Expr::new(&t);
        assert_eq!(
            e.eval([0.0; 3]),
            (0..200_000).map(|k| (k % 7) as f64).sum::<f64>()
        );
    }
}
