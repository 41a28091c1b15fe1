//! An occupancy grid over an expression solid's box: the cells where F may be zero.
//!
//! Built once per solid by interval arithmetic over an octree of the box (Keeter 2020,
//! §3: a cell whose interval F excludes 0 holds no surface), it lets a ray skip the
//! stretches of its segment that lie in empty cells and search only runs of occupied
//! ones. It is sound: a crossing needs a sign change, and across an empty cell F keeps
//! the sign its interval proves; two neighbouring empty cells share their boundary
//! points, so their signs agree. Every box is bounded grown by [`MARGIN`] of its side,
//! so that the walk along a ray (Amanatides & Woo 1987), which may put a point within
//! rounding of a cell face in the neighbouring cell, never skips a crossing: an empty
//! cell holds none within the margin around it either. (Before cell tapes the occupied
//! set was dilated by one cell instead, which searched three times the cells.)

use crate::dual::Dual;
use crate::expr::{
    eval_choices_lanes, eval_choices_nodes, eval_nodes, simplify_into, simplify_into_lane, Choice,
    Node, MAX_LANES,
};
use crate::interval::Interval;
use crate::lanes::Lanes;
use crate::ray::{Aabb, Ray};
use crate::tree::Var;
use glam::DVec3;

/// Cells per axis of a coarse grid (a power of two: the octree halves it each level).
pub const GRID: usize = 32;

/// Cells per axis of a fine grid, built where the coarse one's cost says it fits in
/// the build budget: smaller cells hold shorter tapes and less empty space (colonnade
/// and tanglecube rays 1.4–2× faster: docs/notebook/2026-11-30-fidget-occupancy-grid-and-cell-tapes.md),
/// at 8× the cell table (2 MiB).
pub const FINE_GRID: usize = 64;

/// Words of a coarse grid's bitset (one bit per cell).
pub const GRID_WORDS: usize = GRID * GRID * GRID / 64;

/// Node evaluations (tape length × boxes) a build may spend; past it the solid gets no
/// grid, and rays search their whole segment as before.
const BUILD_BUDGET: usize = 1 << 25;

/// Cells per axis of a block: the walk along a ray crosses a block with no occupied
/// cell in one step ([`Grid::blocks`]).
pub const BLOCK: usize = 4;

/// `floor(x)` clamped to `[0, last]`, as an index: the same value as
/// `(x.floor() as i64).clamp(0, last)` for every x (NaN gives 0), without `f64::floor`,
/// which x86-64's baseline (no SSE4.1 `roundsd`) turns into a call to a generic libm
/// routine (its share of a colonnade ray's instructions:
/// docs/notebook/2026-12-02-cpu-speed-round-10.md).
#[inline(always)]
fn floor_index(x: f64, last: i64) -> i64 {
    // Truncation saturates (NaN → 0); below zero it rounds up, so step down where it did.
    let t = x as i64;
    let t = if (t as f64) > x {
        t.saturating_sub(1)
    } else {
        t
    };
    t.clamp(0, last)
}

/// The bit of cell (x, y, z) of a grid of `n` cells per axis.
#[inline]
fn bit(n: usize, x: usize, y: usize, z: usize) -> usize {
    (z * n + y) * n + x
}

/// Nodes the cell tapes of one grid may hold in all; past it, cells keep the tape of
/// the octree node where the budget ran out (still exact, only longer).
const TAPE_BUDGET: usize = 1 << 20;

/// Empty cells keep their parent's tape when it is no longer than this.
const SHORT_TAPE: usize = 32;

/// Octree boxes are grown by this fraction of their side before they are bounded, so
/// that an empty cell holds no crossing, and a cell's tape equals F, also at points a
/// ray walk puts within rounding of its faces.
pub const MARGIN: f64 = 1e-4;

/// A grid as built: the occupancy bitset and each cell's tape.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Grid {
    /// One bit per cell ([`GRID_WORDS`] words; empty: no grid).
    pub words: Vec<u64>,
    /// One bit per cell, as `words`: set where the cell is empty and F > 0 all over it
    /// (inside the solid), clear where it is empty and F < 0, or occupied. A ray's run
    /// of occupied cells takes the sign at its ends from the empty cells beside it.
    pub inside: Vec<u64>,
    /// One bit per block of [`BLOCK`]³ cells (the block (x, y, z) at
    /// `bit(n / BLOCK, x, y, z)`): set where any of its cells is occupied. Across a
    /// clear block F keeps one sign (its cells are empty and share faces), so a ray
    /// crosses it in one step.
    pub blocks: Vec<u64>,
    /// Per cell, its tape as a range of `nodes` (empty: no cell tapes).
    pub cells: Vec<[u32; 2]>,
    /// The cell tapes, each root last; the first is the whole tape.
    pub nodes: Vec<Node>,
    /// Cells per axis ([`GRID`] or [`FINE_GRID`]; 0: no grid).
    pub n: usize,
}

/// A grid, borrowed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GridView<'a> {
    /// See [`Grid::words`].
    pub words: &'a [u64],
    /// See [`Grid::inside`].
    pub inside: &'a [u64],
    /// See [`Grid::blocks`].
    pub blocks: &'a [u64],
    /// See [`Grid::cells`].
    pub cells: &'a [[u32; 2]],
    /// See [`Grid::nodes`].
    pub nodes: &'a [Node],
    /// See [`Grid::n`].
    pub n: usize,
}

impl Grid {
    /// The grid, borrowed.
    pub fn view(&self) -> GridView<'_> {
        GridView {
            words: &self.words,
            inside: &self.inside,
            blocks: &self.blocks,
            cells: &self.cells,
            nodes: &self.nodes,
            n: self.n,
        }
    }
}

impl<'a> GridView<'a> {
    /// No grid: rays search their whole segment with the whole tape.
    pub const NONE: GridView<'static> = GridView {
        words: &[],
        inside: &[],
        blocks: &[],
        cells: &[],
        nodes: &[],
        n: 0,
    };

    /// Whether there is an occupancy bitset.
    #[inline]
    pub fn is_some(&self) -> bool {
        let w = self.n * self.n * self.n / 64;
        self.n > 0
            && self.words.len() == w
            && self.inside.len() == w
            && self.blocks.len() == block_words(self.n)
    }

    /// The cell holding `p` (clamped to the grid), for a grid over `b`.
    #[inline]
    fn cell_of(&self, b: &Aabb, p: DVec3) -> usize {
        let n = self.n;
        let c = (p - b.lo) / (b.hi - b.lo) * n as f64;
        let i = |x: f64| floor_index(x, n as i64 - 1) as usize;
        bit(n, i(c.x), i(c.y), i(c.z))
    }

    /// Whether a point in the cell holding `p` is inside (F ≥ 0) when that cell is
    /// empty, for a grid over `b` (`p` in `b`); None where it is occupied or there is
    /// no grid. Sound within [`MARGIN`] of the cell, as the emptiness itself.
    #[inline]
    pub fn known_inside(&self, b: &Aabb, p: DVec3) -> Option<bool> {
        if !self.is_some() {
            return None;
        }
        let k = self.cell_of(b, p);
        let get = |w: &[u64]| w[k / 64] >> (k % 64) & 1 == 1;
        (!get(self.words)).then(|| get(self.inside))
    }

    /// The tape of the cell holding `p`, for a grid over `b`; None when `p` lies
    /// outside `b` (grown by the margin) or the grid has no cell tapes.
    #[inline]
    pub fn tape_at(&self, b: &Aabb, p: DVec3) -> Option<&'a [Node]> {
        // Within the margin of the box, the edge cells' tapes still hold.
        let n = self.n;
        let m = (b.hi - b.lo) * (MARGIN / n as f64);
        if n == 0 || self.cells.len() != n * n * n || !Aabb::new(b.lo - m, b.hi + m).contains(p) {
            return None;
        }
        let [s, e] = self.cells[self.cell_of(b, p)];
        Some(&self.nodes[s as usize..e as usize])
    }
}

/// The occupancy grid of `tape` over `b` and, per cell, `tape` simplified over the cell
/// (Keeter 2020, §3.2: the min/max branches that interval arithmetic proves decided
/// over a box are dropped; each octree level simplifies its parent's tape, so the
/// tapes shrink as the boxes do). An empty grid when the box is not finite or the
/// build would exceed its budget.
pub fn build(tape: &[Node], b: &Aabb) -> Grid {
    build_with_margin(tape, b, MARGIN)
}

/// [`build`] with every box grown by `margin` of its side instead of [`MARGIN`]: the
/// emptiness, signs and cell tapes then hold that far around each cell (the GPU's f32
/// walk needs more room than f64 rounding; `margin` ≥ [`MARGIN`]).
pub fn build_with_margin(tape: &[Node], b: &Aabb, margin: f64) -> Grid {
    if !b.is_finite() || b.is_empty() || tape.is_empty() {
        return Grid::default();
    }
    let Some((coarse, spent)) = build_n(tape, b, GRID, margin) else {
        return Grid::default();
    };
    // The fine grid's octree has one more level, about 8× the coarse one's finest: try
    // it where that fits the budget, and keep the coarse grid where it does not.
    if spent.saturating_mul(8) <= BUILD_BUDGET {
        if let Some((fine, _)) = build_n(tape, b, FINE_GRID, margin) {
            return fine;
        }
    }
    coarse
}

/// [`build`] at `n` cells per axis and boxes grown by `margin`, with the node
/// evaluations it spent; None past the budget.
///
/// The octree's top [`SPLIT_LEVELS`] levels are evaluated here; the subtrees below them
/// are built in parallel (rayon's current pool), each into its own node arena starting
/// with the tape it inherits, and joined in a fixed order. Every octree box sees the
/// same tape as in a sequential walk, so the cells and their tapes do not depend on the
/// number of threads; so do the subtrees' shares of [`TAPE_BUDGET`] (in batches of
/// [`BATCH`], each an equal share of what the batches before it left).
fn build_n(tape: &[Node], b: &Aabb, n: usize, margin: f64) -> Option<(Grid, usize)> {
    build_split(tape, b, n, margin, SPLIT_LEVELS)
}

/// [`build_n`] with its top `levels` levels evaluated before the parallel subtrees (0:
/// one subtree, the whole octree on one thread).
fn build_split(
    tape: &[Node],
    b: &Aabb,
    n: usize,
    margin: f64,
    levels: usize,
) -> Option<(Grid, usize)> {
    use rayon::prelude::*;
    let geometry = Octree {
        lo: b.lo,
        hi: b.hi,
        cell: (b.hi - b.lo) / n as f64,
        n,
        margin,
        used: used_axes(tape),
    };
    // The top levels, breadth first: what they split becomes the parallel subtrees.
    let mut top = Builder::new(tape.to_vec(), TAPE_BUDGET);
    let mut frontier = vec![([0usize; 3], [n; 3], [0u32, tape.len() as u32])];
    for _ in 0..levels {
        let mut next = Vec::new();
        for (c, size, span) in frontier {
            if let Some(own) = top.node(&geometry, c, size, span) {
                next.extend(geometry.children(c, size, own));
            }
        }
        frontier = next;
        if top.spent > BUILD_BUDGET {
            return None;
        }
    }
    // The subtrees run in batches of a fixed size, in order: each of a batch may add an
    // equal share of the tape budget left after the batches before it, so the arenas
    // hold at most the budget in all, and the shares do not depend on the threads.
    let mut subtrees: Vec<Builder> = Vec::with_capacity(frontier.len());
    let (mut used, mut spent) = (top.nodes.len(), top.spent);
    for batch in frontier.chunks(BATCH) {
        let share = TAPE_BUDGET.saturating_sub(used) / batch.len();
        let budget = BUILD_BUDGET.saturating_sub(spent);
        let done: Vec<Builder> = batch
            .par_iter()
            .map(|&(c, size, span)| {
                let inherited = top.nodes[span[0] as usize..span[1] as usize].to_vec();
                let len = inherited.len() as u32;
                let mut sub = Builder::new(inherited, share);
                sub.walk(&geometry, c, size, [0, len], budget);
                sub
            })
            .collect();
        for sub in &done {
            used += sub.nodes.len() - sub.start;
            spent = spent.saturating_add(sub.spent);
        }
        if spent > BUILD_BUDGET {
            return None;
        }
        subtrees.extend(done);
    }
    let mut occupied = vec![false; n * n * n];
    let mut inside = vec![false; n * n * n];
    let mut cells = vec![[0u32; 2]; n * n * n];
    let mut leaves = |builder: &Builder, rebase: &dyn Fn([u32; 2]) -> [u32; 2]| {
        for leaf in &builder.leaves {
            let (c, size) = (leaf.corner, leaf.size);
            for z in c[2]..c[2] + size[2] {
                for y in c[1]..c[1] + size[1] {
                    for x in c[0]..c[0] + size[0] {
                        cells[bit(n, x, y, z)] = rebase(leaf.span);
                        inside[bit(n, x, y, z)] = leaf.excluded && leaf.positive;
                        // An occupied leaf is one cell, or a column along an axis F
                        // does not depend on.
                        occupied[bit(n, x, y, z)] = !leaf.excluded;
                    }
                }
            }
        }
    };
    leaves(&top, &|span| span);
    let mut nodes = std::mem::take(&mut top.nodes);
    for (sub, &(_, _, from)) in subtrees.iter().zip(&frontier) {
        // Spans into the inherited tape point to the parent's copy; the rest move to
        // where this arena's own nodes land.
        let (len, offset) = (from[1] - from[0], nodes.len() as u32);
        let rebase = |s: [u32; 2]| {
            if s[1] <= len {
                [from[0] + s[0], from[0] + s[1]]
            } else {
                [offset + s[0] - len, offset + s[1] - len]
            }
        };
        leaves(sub, &rebase);
        nodes.extend_from_slice(&sub.nodes[len as usize..]);
    }
    let bits = |set: &[bool]| {
        let mut words = vec![0u64; n * n * n / 64];
        for (n, _) in set.iter().enumerate().filter(|(_, o)| **o) {
            words[n / 64] |= 1 << (n % 64);
        }
        words
    };
    let m = n / BLOCK;
    let mut blocks = vec![0u64; block_words(n)];
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                if occupied[bit(n, x, y, z)] {
                    let k = bit(m, x / BLOCK, y / BLOCK, z / BLOCK);
                    blocks[k / 64] |= 1 << (k % 64);
                }
            }
        }
    }
    Some((
        Grid {
            words: bits(&occupied),
            inside: bits(&inside),
            blocks,
            cells,
            nodes,
            n,
        },
        spent,
    ))
}

/// Octree levels evaluated before the subtrees are built in parallel: up to 64
/// subtrees, enough to balance a few cores when the surface fills few of them.
const SPLIT_LEVELS: usize = 2;

/// Subtrees built at once, sharing what is left of [`TAPE_BUDGET`].
const BATCH: usize = 8;

/// The grid's box and cells.
struct Octree {
    lo: DVec3,
    hi: DVec3,
    cell: DVec3,
    n: usize,
    /// Boxes are bounded grown by this fraction of their side ([`MARGIN`] for the CPU).
    margin: f64,
    /// The axes F depends on: boxes are split along these only. Along another axis
    /// every box spans the grid, so that a model that does not depend on z (Fidget's
    /// prospero, text in the plane) costs a quadtree of columns, not an octree of cells.
    used: [bool; 3],
}

impl Octree {
    /// The children of the box at corner cell `c`, `size` cells wide per axis, all given
    /// the tape `own`: halved along each axis F depends on (eight children in an
    /// octree, four in a quadtree of columns).
    fn children(&self, c: [usize; 3], size: [usize; 3], own: [u32; 2]) -> Vec<OctBox> {
        let half = |k: usize| if self.used[k] { size[k] / 2 } else { 0 };
        let h = [half(0), half(1), half(2)];
        let size = [0, 1, 2].map(|k| if self.used[k] { h[k] } else { size[k] });
        (0..8)
            .filter(|&k: &usize| (0..3).all(|a| self.used[a] || k >> a & 1 == 0))
            .map(|k| {
                let d = [(k & 1) * h[0], (k >> 1 & 1) * h[1], (k >> 2 & 1) * h[2]];
                ([c[0] + d[0], c[1] + d[1], c[2] + d[2]], size, own)
            })
            .collect()
    }

    /// The box at corner cell `c`, `size` cells wide: its bounds grown by the margin as
    /// intervals, its corners and the margin.
    fn bounded(&self, c: [usize; 3], size: [usize; 3]) -> ([Interval; 3], DVec3, DVec3, DVec3) {
        let lo = self.lo + DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * self.cell;
        let cells = DVec3::new(size[0] as f64, size[1] as f64, size[2] as f64);
        let hi = if (0..3).all(|k| c[k] + size[k] == self.n) {
            self.hi
        } else {
            lo + self.cell * cells
        };
        let m = self.cell * (cells * self.margin);
        let iv = |k: usize| Interval::new(lo[k] - m[k], hi[k].max(lo[k]) + m[k]);
        ([iv(0), iv(1), iv(2)], lo, hi, m)
    }

    /// Whether a box `size` cells wide is a finest box: one cell along every axis F
    /// depends on.
    fn finest(&self, size: [usize; 3]) -> bool {
        (0..3).all(|k| !self.used[k] || size[k] == 1)
    }
}

/// The axes (x, y, z) that `tape` reads.
fn used_axes(tape: &[Node]) -> [bool; 3] {
    let mut used = [false; 3];
    for node in tape {
        match node {
            Node::Var(Var::X) => used[0] = true,
            Node::Var(Var::Y) => used[1] = true,
            Node::Var(Var::Z) => used[2] = true,
            _ => {}
        }
    }
    used
}

/// An octree box to evaluate: corner cell, size in cells per axis, the tape that holds
/// over it.
type OctBox = ([usize; 3], [usize; 3], [u32; 2]);

/// An octree box that is not split: empty (`excluded`, with F's sign) or a finest box.
#[derive(Debug, PartialEq)]
struct Leaf {
    corner: [usize; 3],
    size: [usize; 3],
    span: [u32; 2],
    excluded: bool,
    positive: bool,
}

/// One sequential walk over part of the octree, with its node arena and scratch.
struct Builder {
    nodes: Vec<Node>,
    /// Nodes this walk may add to its arena.
    tape_cap: usize,
    start: usize,
    scratch: Vec<Interval>,
    choices: Vec<Choice>,
    duals: Vec<Dual<Interval, 3>>,
    spent: usize,
    leaves: Vec<Leaf>,
    /// Scratch of the children's evaluation in lanes, and spent choice buffers.
    lanes: LaneScratch,
}

/// What [`Builder::children`] evaluates in: four or eight lanes, and the families of
/// children whose choices are still to be read.
#[derive(Default)]
struct LaneScratch {
    four: Vec<Lanes<Interval, 4>>,
    eight: Vec<Lanes<Interval, 8>>,
    families: Vec<Family>,
    /// Families all of whose children are decided, for reuse.
    free: Vec<u32>,
}

/// The choices of siblings bounded together (lane i: child i), and how many of them
/// are still to be decided.
#[derive(Default)]
struct Family {
    choices: Vec<[Choice; MAX_LANES]>,
    left: usize,
}

/// The min/max choices behind a box's bound: of its own evaluation, or its lane of its
/// family's.
#[derive(Clone, Copy)]
enum Choices<'a> {
    One(&'a [Choice]),
    Lane(&'a [[Choice; MAX_LANES]], usize),
}

/// A box of the walk with its bound over it, its family and lane, when its parent
/// bounded it ([`Builder::children`]).
type Evaluated = (OctBox, Option<(Interval, u32, usize)>);

impl Builder {
    fn new(nodes: Vec<Node>, tape_cap: usize) -> Self {
        Self {
            start: nodes.len(),
            nodes,
            tape_cap,
            scratch: Vec::new(),
            choices: Vec::new(),
            duals: Vec::new(),
            spent: 0,
            leaves: Vec::new(),
            lanes: LaneScratch::default(),
        }
    }

    /// Depth first below box `c` until every box is a leaf, or until more than
    /// `budget` evaluations are spent. A box's children are bounded together, in lanes
    /// ([`Self::children`]), and then decided one by one in the order of a walk that
    /// bounds each on its own: the same boxes, bounds, tapes and budget, bit for bit.
    fn walk(&mut self, g: &Octree, c: [usize; 3], size: [usize; 3], span: [u32; 2], budget: usize) {
        let mut stack: Vec<Evaluated> = vec![((c, size, span), None)];
        while let Some(((c, size, span), pre)) = stack.pop() {
            let own = match pre {
                None => self.node(g, c, size, span),
                Some((v, f, lane)) => {
                    let family = &mut self.lanes.families[f as usize];
                    let choices = std::mem::take(&mut family.choices);
                    let own = self.decide(g, c, size, span, v, Choices::Lane(&choices, lane));
                    let family = &mut self.lanes.families[f as usize];
                    family.choices = choices;
                    family.left -= 1;
                    if family.left == 0 {
                        self.lanes.free.push(f);
                    }
                    own
                }
            };
            if let Some(own) = own {
                self.children(g, g.children(c, size, own), &mut stack);
            }
            if self.spent > budget {
                return;
            }
        }
    }

    /// Bounds the boxes `kids` (siblings, all with the same tape) in one pass of four or
    /// eight lanes and pushes each with its bound, family and lane onto `stack`, in
    /// order; other numbers of children one by one.
    fn children(&mut self, g: &Octree, kids: Vec<OctBox>, stack: &mut Vec<Evaluated>) {
        let span = kids[0].2;
        debug_assert!(kids.iter().all(|k| k.2 == span));
        let tape = &self.nodes[span[0] as usize..span[1] as usize];
        let boxes: Vec<[Interval; 3]> = kids.iter().map(|k| g.bounded(k.0, k.1).0).collect();
        let lanes = &mut self.lanes;
        let f = lanes.free.pop().unwrap_or_else(|| {
            lanes.families.push(Family::default());
            lanes.families.len() as u32 - 1
        });
        let family = &mut lanes.families[f as usize];
        family.left = kids.len();
        let choices = &mut family.choices;
        let mut bounds = [Interval::point(0.0); MAX_LANES];
        macro_rules! in_lanes {
            ($l:literal, $scratch:expr) => {{
                let lane = |a: usize| Lanes::<Interval, $l>(std::array::from_fn(|i| boxes[i][a]));
                let v = eval_choices_lanes(tape, lane(0), lane(1), lane(2), $scratch, choices);
                bounds[..$l].copy_from_slice(&v.0);
            }};
        }
        match kids.len() {
            8 => in_lanes!(8, &mut lanes.eight),
            4 => in_lanes!(4, &mut lanes.four),
            _ => {
                // Two children (a model of one axis) or one: a lane each, one by one.
                choices.clear();
                choices.resize(tape.len(), [Choice::Both; MAX_LANES]);
                for (k, b) in boxes.iter().enumerate() {
                    let (scratch, one) = (&mut self.scratch, &mut self.choices);
                    bounds[k] = eval_choices_nodes(tape, b[0], b[1], b[2], scratch, one);
                    for (n, &c) in one.iter().enumerate() {
                        choices[n][k] = c;
                    }
                }
            }
        }
        for (k, &kid) in kids.iter().enumerate() {
            stack.push((kid, Some((bounds[k], f, k))));
        }
    }

    /// Evaluates one box: records it as a leaf (None) or returns the tape its children
    /// inherit.
    fn node(
        &mut self,
        g: &Octree,
        c: [usize; 3],
        size: [usize; 3],
        span: [u32; 2],
    ) -> Option<[u32; 2]> {
        let (s, e) = (span[0] as usize, span[1] as usize);
        let [x, y, z] = g.bounded(c, size).0;
        let v = eval_choices_nodes(
            &self.nodes[s..e],
            x,
            y,
            z,
            &mut self.scratch,
            &mut self.choices,
        );
        let choices = std::mem::take(&mut self.choices);
        let own = self.decide(g, c, size, span, v, Choices::One(&choices));
        self.choices = choices;
        own
    }

    /// [`Self::node`] for a box whose bound `v` over the tape `span`, with its
    /// min/max `choices`, is known.
    fn decide(
        &mut self,
        g: &Octree,
        c: [usize; 3],
        size: [usize; 3],
        span: [u32; 2],
        v: Interval,
        choices: Choices,
    ) -> Option<[u32; 2]> {
        let (s, e) = (span[0] as usize, span[1] as usize);
        self.spent = self.spent.saturating_add(e - s);
        let (_, lo, hi, m) = g.bounded(c, size);
        let mut excluded = v.lo > 0.0 || v.hi < 0.0;
        let mut positive = v.lo > 0.0;
        // The tape over this box: the one it was given, simplified where it can be (an
        // empty box's tape only serves the sign at run ends: worth it when long).
        let mut own = span;
        let added = self.nodes.len() - self.start;
        if (!excluded || e - s > SHORT_TAPE) && added < self.tape_cap {
            let start = self.nodes.len();
            let simplified = match choices {
                Choices::One(c) => simplify_into(&[], Some(s..e), c, &mut self.nodes),
                Choices::Lane(c, k) => simplify_into_lane(&[], Some(s..e), c, k, &mut self.nodes),
            };
            if simplified {
                own = [start as u32, self.nodes.len() as u32];
            }
        }
        let widest = (0..3).filter(|&k| g.used[k]).map(|k| size[k]).max();
        if !excluded && widest.unwrap_or(0) <= MEAN_VALUE_SIZE {
            let tape = &self.nodes[own[0] as usize..own[1] as usize];
            self.spent = self.spent.saturating_add(4 * tape.len());
            let scratch = (&mut self.scratch, &mut self.duals);
            if let Some(sign) = mean_value_sign(tape, lo - m, hi.max(lo) + m, scratch) {
                (excluded, positive) = (true, sign);
            }
        }
        if excluded || g.finest(size) {
            self.leaves.push(Leaf {
                corner: c,
                size,
                span: own,
                excluded,
                positive,
            });
            return None;
        }
        Some(own)
    }
}

/// Words of the block bitset of a grid of `n` cells per axis.
pub fn block_words(n: usize) -> usize {
    (n / BLOCK).pow(3).div_ceil(64)
}

/// Boxes this many cells wide or less are also bounded by the mean-value form.
const MEAN_VALUE_SIZE: usize = 4;

/// The sign of F over [lo, hi] (true: positive) where the mean-value form F(c) +
/// ∇F(box)·(box − c) (Moore 1966, §6), c the box's centre, excludes 0; None where it
/// does not. Where F is smooth it is far tighter than the plain interval on small
/// boxes, which overestimates sums like x⁴ − 5x² by their whole range (the dependency
/// problem); both are enclosures, so either may exclude. F(c) is evaluated in plain
/// intervals: a dual number's value part takes the same interval operations, so it is
/// the same enclosure, without the three derivatives' work (measured on the table
/// scene's loading in
/// docs/notebook/2026-12-02-cpu-speed-round-9-perturbed-walk-and-scene-loading.md).
fn mean_value_sign(
    tape: &[Node],
    lo: DVec3,
    hi: DVec3,
    (points, scratch): (&mut Vec<Interval>, &mut Vec<Dual<Interval, 3>>),
) -> Option<bool> {
    let c = 0.5 * (lo + hi);
    let at = |k: usize| Interval::point(c[k]);
    let fc = eval_nodes(tape, at(0), at(1), at(2), points);
    let var = |k: usize| {
        let mut d = [Interval::point(0.0); 3];
        d[k] = Interval::point(1.0);
        Dual::new(Interval::new(lo[k], hi[k]), d)
    };
    let g = eval_nodes(tape, var(0), var(1), var(2), scratch).d;
    let mv = (0..3).fold(fc, |acc, k| {
        acc + g[k] * (Interval::new(lo[k], hi[k]) - Interval::point(c[k]))
    });
    (mv.lo > 0.0 || mv.hi < 0.0).then_some(mv.lo > 0.0)
}

/// Calls `visit(a, b, tape, known)` for each maximal run [a, b] of occupied cells with
/// one tape (None: no cell tapes) that the segment [t0, t1] of `ray` (inside `b`)
/// crosses, in order, until `visit` returns true. `known` holds whether F ≥ 0 at a and
/// at b where an empty cell borders the run there (its sign, [`Grid::inside`]), else
/// None.
pub fn runs<'g>(
    grid: GridView<'g>,
    b: &Aabb,
    ray: &Ray,
    t0: f64,
    t1: f64,
    mut visit: impl FnMut(f64, f64, Option<&'g [Node]>, [Option<bool>; 2]) -> bool,
) {
    let (words, inside) = (grid.words, grid.inside);
    let occupied = |n: usize| words[n / 64] >> (n % 64) & 1 == 1;
    let positive = |n: usize| inside[n / 64] >> (n % 64) & 1 == 1;
    let span = |n: usize| grid.cells.get(n).copied();
    let g = grid.n;
    let size = (b.hi - b.lo) / g as f64;
    let last = g as i64 - 1;
    let p = ray.at(t0);
    let mut c = [0i64; 3];
    let mut next = [f64::INFINITY; 3];
    let mut delta = [f64::INFINITY; 3];
    let mut step = [0i64; 3];
    for k in 0..3 {
        c[k] = floor_index((p[k] - b.lo[k]) / size[k], last);
        let d = ray.d[k];
        if d != 0.0 {
            step[k] = if d > 0.0 { 1 } else { -1 };
            let face = b.lo[k] + (c[k] + i64::from(d > 0.0)) as f64 * size[k];
            next[k] = (face - ray.o[k]) / d;
            delta[k] = size[k] / d.abs();
        }
    }
    let tape = |s: Option<[u32; 2]>| s.map(|[s, e]| &grid.nodes[s as usize..e as usize]);
    // The open run: where it starts, its cell tape and the sign known at its start.
    let mut start: Option<(f64, Option<[u32; 2]>, Option<bool>)> = None;
    // The sign of the last cell walked, when it was empty.
    let mut before = None;
    let mut t = t0;
    // The axis whose face comes first (the lowest on ties) and that face, by value: an
    // index found first and then loaded with waits on the comparisons.
    let first = |f: &[f64; 3]| {
        let (k, v) = if f[1] < f[0] { (1, f[1]) } else { (0, f[0]) };
        if f[2] < v {
            (2, f[2])
        } else {
            (k, v)
        }
    };
    let m = g / BLOCK;
    let clear = |c: &[i64; 3]| {
        let [x, y, z] = c.map(|v| v as usize / BLOCK);
        let k = bit(m, x, y, z);
        grid.blocks[k / 64] >> (k % 64) & 1 == 0
    };
    loop {
        let n = bit(g, c[0] as usize, c[1] as usize, c[2] as usize);
        // In a clear block the walk steps to the block's exit at once: its cells are
        // all empty, with this cell's sign. `far` holds, per axis, the face where the
        // walk would leave the block, by the same additions as cell by cell.
        let skip = clear(&c);
        let here = (skip || !occupied(n)).then(|| positive(n));
        let mut far = next;
        let mut rest = [0i64; 3];
        if skip {
            for j in 0..3 {
                if step[j] != 0 {
                    let r = c[j] % BLOCK as i64;
                    rest[j] = if step[j] > 0 { BLOCK as i64 - 1 - r } else { r };
                    for _ in 0..rest[j] {
                        far[j] += delta[j];
                    }
                }
            }
        }
        let (k, face) = first(&far);
        let exit = face.min(t1);
        match (here, start) {
            (None, None) => start = Some((t, span(n), before)),
            (None, Some((a, s, ka))) if s != span(n) => {
                if visit(a, t, tape(s), [ka, None]) {
                    return;
                }
                start = Some((t, span(n), None));
            }
            (Some(sign), Some((a, s, ka))) => {
                if visit(a, t, tape(s), [ka, Some(sign)]) {
                    return;
                }
                start = None;
            }
            _ => {}
        }
        before = here;
        if exit >= t1 {
            break;
        }
        if skip {
            // The other axes step over the faces they cross before the exit (within
            // the block: their own exits lie at or past it), and axis k to the
            // block's last cell.
            for j in (0..3).filter(|&j| j != k) {
                while next[j] < face {
                    c[j] += step[j];
                    next[j] += delta[j];
                }
            }
            c[k] += rest[k] * step[k];
            next[k] = face;
        }
        c[k] += step[k];
        if !(0..=last).contains(&c[k]) {
            break;
        }
        next[k] += delta[k];
        t = exit.max(t);
    }
    if let Some((a, s, ka)) = start {
        visit(a, t1, tape(s), [ka, None]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::read::read_file;

    /// `floor_index` is `floor` then the clamp, for every kind of f64: fractions on both
    /// sides of zero, integers, signed zeros, the ends of i64, infinities and NaN, and
    /// random values over many magnitudes.
    #[test]
    fn floor_index_is_the_floor_clamped() {
        use rand::{Rng, SeedableRng};
        let reference = |x: f64, last: i64| (x.floor() as i64).clamp(0, last);
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            -1.0,
            -1.5,
            1.0,
            63.0,
            63.999_999_999_999_99,
            64.0,
            -1e-300,
            1e-300,
            9.223_372_036_854_775e18,
            -9.223_372_036_854_775e18,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MAX,
            f64::MIN,
        ];
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        for _ in 0..100_000 {
            let x: f64 = rng.gen_range(-80.0..80.0);
            xs.push(x);
            xs.push(x * 10f64.powi(rng.gen_range(-20..20)));
        }
        for last in [0, 1, 31, 63, i64::MAX] {
            for &x in &xs {
                assert_eq!(
                    floor_index(x, last),
                    reference(x, last),
                    "x = {x:e}, last = {last}"
                );
            }
        }
    }

    /// The mean-value test's F(c) in plain intervals is the value part of the dual
    /// evaluation it replaced, bit for bit, on every expression model of the repository
    /// and the shared ones, at points and over boxes (so the grids, and the images, are the
    /// same).
    #[test]
    fn plain_intervals_are_the_dual_value_part() {
        use rand::{Rng, SeedableRng};
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        // Named, not listed from the folders: a file added there must not change the test.
        let models = [
            "models/fidget/colonnade.vm",
            "models/fidget/hi.vm",
            "models/fidget/prospero.vm",
            "models/fidget/quarter.vm",
            "models/fidget/tanglecube.vm",
            "models/canonical/s1_sphere.hf",
            "models/canonical/s2_csg.hf",
            "models/canonical/s3_blend.hf",
            "models/canonical/s4_gyroid.hf",
            "models/canonical/s5_twist.hf",
            "scenes/models/blob.frep",
        ];
        let mut rng = rand_pcg::Pcg64::seed_from_u64(13);
        let (mut points, mut duals, mut checked) = (Vec::new(), Vec::new(), 0);
        for m in models {
            let model = read_file(&root.join(m)).unwrap_or_else(|e| panic!("{m}: {e}"));
            let crate::Shape::Function { tree, .. } = &model.shape else {
                panic!("{m}: not one expression");
            };
            let expr = crate::expr::Expr::new(tree);
            for k in 0..400 {
                let lo = DVec3::new(
                    rng.gen_range(-1.5..1.5),
                    rng.gen_range(-1.5..1.5),
                    rng.gen_range(-1.5..1.5),
                );
                // Points at even k, boxes up to 0.5 wide at odd k.
                let w = if k % 2 == 0 {
                    0.0
                } else {
                    rng.gen_range(0.0..0.5)
                };
                let x = |a: usize| Interval::new(lo[a], lo[a] + w);
                let plain = eval_nodes(expr.nodes(), x(0), x(1), x(2), &mut points);
                let d = |a: usize| Dual::new(x(a), [Interval::point(0.0); 3]);
                let dual: Dual<Interval, 3> =
                    eval_nodes(expr.nodes(), d(0), d(1), d(2), &mut duals);
                let bits = |i: Interval| (i.lo.to_bits(), i.hi.to_bits());
                assert_eq!(bits(plain), bits(dual.v), "{m} at {lo} + {w}");
            }
            checked += 1;
        }
        assert!(checked >= 8, "{checked} models");
    }

    /// Splitting the octree into parallel subtrees changes no cell: on colonnade.vm
    /// (whose fine grid's subtrees add up to 46 000 nodes each) and a HyperFun blend, the
    /// occupancy, signs, blocks and every cell's tape are those of the octree walked as
    /// one subtree, and so is the evaluation count.
    #[test]
    fn parallel_subtrees_give_the_one_thread_grid() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        for m in ["models/fidget/colonnade.vm", "models/canonical/s3_blend.hf"] {
            let model = read_file(&root.join(m)).unwrap_or_else(|e| panic!("{m}: {e}"));
            let crate::Shape::Function { tree, .. } = &model.shape else {
                panic!("{m}: not one expression");
            };
            let expr = crate::expr::Expr::new(tree);
            let b =
                crate::bounds::expr_bounds(&expr, Aabb::new(DVec3::splat(-2.0), DVec3::splat(2.0)));
            for n in [GRID, FINE_GRID] {
                let (one, spent_one) = build_split(expr.nodes(), &b, n, MARGIN, 0).unwrap();
                let (split, spent_split) =
                    build_split(expr.nodes(), &b, n, MARGIN, SPLIT_LEVELS).unwrap();
                assert_eq!(spent_one, spent_split, "{m} {n}");
                assert_eq!(
                    (&one.words, &one.inside, &one.blocks),
                    (&split.words, &split.inside, &split.blocks),
                    "{m} {n}"
                );
                let tape = |g: &Grid, k: usize| {
                    let [s, e] = g.cells[k];
                    g.nodes[s as usize..e as usize].to_vec()
                };
                for k in 0..n * n * n {
                    assert!(tape(&one, k) == tape(&split, k), "{m} {n}: cell {k}");
                }
            }
        }
    }

    /// A walk that bounds each box's children together in lanes leaves the same leaves,
    /// tapes and spent evaluations, bit for bit, as one that bounds every box on its own
    /// (`Builder::node` box by box, the walk before lanes): the repository's expression
    /// models (octrees of eight children, the quadtrees of columns of Fidget's 2-D
    /// models with four) and a model of x alone (two), at both grid sizes.
    #[test]
    fn children_in_lanes_equal_boxes_one_by_one() {
        let mut trees: Vec<(&str, crate::Tree)> = crate::test_models::expression_models();
        let x = crate::Tree::x();
        trees.push(("x alone", 0.3 - (&x * &x)));
        for (name, tree) in &trees {
            let tape = crate::expr::Expr::new(tree).nodes().to_vec();
            for n in [GRID, FINE_GRID] {
                let b = Aabb::new(DVec3::splat(-1.2), DVec3::splat(1.2));
                let g = Octree {
                    lo: b.lo,
                    hi: b.hi,
                    cell: (b.hi - b.lo) / n as f64,
                    n,
                    margin: MARGIN,
                    used: used_axes(&tape),
                };
                let span = [0, tape.len() as u32];
                let mut lanes = Builder::new(tape.clone(), TAPE_BUDGET);
                lanes.walk(&g, [0; 3], [n; 3], span, usize::MAX);
                let mut one = Builder::new(tape.clone(), TAPE_BUDGET);
                let mut stack = vec![([0; 3], [n; 3], span)];
                while let Some((c, size, span)) = stack.pop() {
                    if let Some(own) = one.node(&g, c, size, span) {
                        stack.extend(g.children(c, size, own));
                    }
                }
                assert!(one.leaves.len() > 8, "{name}: {} leaves", one.leaves.len());
                assert_eq!(lanes.spent, one.spent, "{name} at {n}");
                assert!(lanes.nodes == one.nodes, "{name} at {n}: tapes differ");
                assert!(lanes.leaves == one.leaves, "{name} at {n}: leaves differ");
            }
        }
    }
}
