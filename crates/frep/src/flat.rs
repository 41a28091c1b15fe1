//! The flat form of a solid: plain, inspectable arrays that another back end can upload.
//!
//! A [`crate::Solid`] is this data and nothing else: CSG nodes with children before
//! parents (post-order, root last), a table of [`Leaf`]s, and pools that leaves and nodes
//! name by index ([`Span`]s, handles not owners): base quadrics, perturbations, BVH nodes
//! with their item order and boxes, expression tapes and their register bytecode
//! ([`crate::bytecode`]). Every element is `Copy`, so two builds compare with `==` and a
//! GPU mirrors them as structs of the same fields (GPU.md §5.2). The CPU intersects over
//! these arrays directly, through [`crate::PerturbedView`] and [`crate::ExprView`].

use crate::bvh::{BvhNode, BvhRef, WideNode};
use crate::expr::Node;
use crate::interval_trace::ExprView;
use crate::occupancy::GridView;
use crate::perturbed::{Perturbation, PerturbedView};
use crate::quadric::Quadric;
use crate::ray::Aabb;
use std::ops::Range;

/// The most parts one CSG node combines; wider unions and intersections are split into a
/// tree of nodes of at most this many parts (their crossings combine on the stack).
pub const MAX_PARTS: usize = 8;

/// The deepest CSG nesting a solid may have (leaves at depth 1): the CPU combines
/// crossings by recursion on the call stack and a GPU by an explicit stack of this size.
/// Deeper scenes are a build error.
pub const MAX_DEPTH: usize = 32;

/// The elements `first..first + count` of a pool.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Span {
    /// Index of the first element.
    pub first: u32,
    /// Number of elements.
    pub count: u32,
}

impl Span {
    /// The span of the elements from `first` to the pool's current length.
    pub(crate) fn since(first: usize, len: usize) -> Self {
        Self {
            first: first as u32,
            count: (len - first) as u32,
        }
    }
    /// As a range of indices.
    pub fn range(self) -> Range<usize> {
        self.first as usize..(self.first + self.count) as usize
    }
}

/// How a CSG node combines its parts' inside states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum CsgOp {
    /// A leaf: `operands.first` is its index in [`Flat::leaves`].
    Leaf,
    /// Inside any part.
    Union,
    /// Inside every part.
    Intersection,
    /// Inside the first part and outside the second.
    Difference,
}

/// One CSG node.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct CsgNode {
    /// The operation.
    pub op: CsgOp,
    /// Leaf: the leaf index (count 1). Otherwise the parts, as a span of
    /// [`Flat::children`] (node indices, each below this node's; 2 ..= [`MAX_PARTS`]).
    pub operands: Span,
    /// A box holding every inside point (may be infinite).
    pub bounds: Aabb,
}

/// A leaf of the CSG tree: one of a closed set of kinds, its data in the pools.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum Leaf {
    /// A perturbed quadric, intersected exactly. BVH node offsets and item indices are
    /// relative to the leaf's own spans (item k is `perturbations.first + k`).
    Perturbed {
        /// Index of the base quadric in [`Flat::quadrics`].
        base: u32,
        /// Its perturbations in [`Flat::perturbations`].
        perturbations: Span,
        /// Its BVH nodes in [`Flat::bvh_nodes`].
        bvh_nodes: Span,
        /// Its BVH's wide nodes in [`Flat::bvh_wide`].
        bvh_wide: Span,
        /// Its BVH item order and item boxes in [`Flat::bvh_order`] and
        /// [`Flat::bvh_item_bounds`].
        bvh_items: Span,
        /// Its items with unbounded supports in [`Flat::bvh_unbounded`].
        bvh_unbounded: Span,
        /// A box holding every inside point.
        bounds: Aabb,
    },
    /// Any other expression, intersected by interval arithmetic.
    Expr {
        /// Its node list in [`Flat::tapes`].
        tape: Span,
        /// Its register bytecode in [`Flat::bytecode`].
        code: Span,
        /// Registers the bytecode uses.
        registers: u32,
        /// A box holding every inside point.
        bounds: Aabb,
        /// Resolution along rays ([`crate::interval_trace::resolution`]).
        eps: f64,
        /// Its occupancy grid in [`Flat::grids`]: the occupancy bits, as many words
        /// of the empty cells' signs, then the block bits (empty: none).
        grid: Span,
        /// Its cells' tape ranges in [`Flat::grid_cells`] (relative to `cell_tapes`).
        grid_cells: Span,
        /// Its cell tapes in [`Flat::cell_tapes`].
        cell_tapes: Span,
        /// Its grid's cells per axis (0: no grid).
        grid_n: u32,
        /// Its degree as a polynomial of low degree ([`crate::poly_trace::degree`]).
        degree: Option<u8>,
        /// Its plan along rays ([`crate::ray_tape::Plan`]): the parts' tape and the
        /// tape left in [`Flat::plan_nodes`] (an empty tape: no plan), the leaves in
        /// [`Flat::plan_leaves`].
        plan_parts: Span,
        /// See `plan_parts`.
        plan_tape: Span,
        /// See `plan_parts`.
        plan_leaves: Span,
    },
}

/// A leaf's data, borrowed from the pools.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LeafView<'a> {
    /// A perturbed quadric.
    Perturbed(PerturbedView<'a>),
    /// An expression.
    Expr(ExprView<'a>),
}

/// The flat arrays of a solid (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Flat {
    /// CSG nodes, children before parents; the root is last.
    pub nodes: Vec<CsgNode>,
    /// The parts of every interior node, as node indices.
    pub children: Vec<u32>,
    /// The leaves.
    pub leaves: Vec<Leaf>,
    /// Base quadrics of perturbed leaves.
    pub quadrics: Vec<Quadric>,
    /// Perturbations of perturbed leaves.
    pub perturbations: Vec<Perturbation>,
    /// BVH nodes over perturbation supports ([`crate::Bvh::nodes`]).
    pub bvh_nodes: Vec<BvhNode>,
    /// The same BVHs' wide nodes ([`crate::bvh::WideNode::build`]): CPU walks only.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub bvh_wide: Vec<WideNode>,
    /// BVH item order ([`crate::Bvh::order`]).
    pub bvh_order: Vec<u32>,
    /// BVH item boxes in leaf order ([`crate::Bvh::item_bounds`]).
    pub bvh_item_bounds: Vec<Aabb>,
    /// BVH items with non-finite boxes ([`crate::Bvh::unbounded`]).
    pub bvh_unbounded: Vec<u32>,
    /// Expression tapes ([`crate::Expr::nodes`]).
    pub tapes: Vec<Node>,
    /// Register bytecode of the tapes ([`crate::bytecode::Bytecode::words`]).
    pub bytecode: Vec<u32>,
    /// Expression leaves' occupancy grids ([`crate::occupancy`]), three bitsets each
    /// (occupied cells, the empty cells' signs, the blocks holding occupied cells).
    pub grids: Vec<u64>,
    /// Per cell of each occupancy grid, its tape's range in the leaf's `cell_tapes`.
    pub grid_cells: Vec<[u32; 2]>,
    /// The cell tapes of every occupancy grid ([`crate::occupancy::Grid::nodes`]).
    pub cell_tapes: Vec<Node>,
    /// The expression leaves' plans along rays ([`crate::ray_tape`]): their parts'
    /// tapes and the tapes left. CPU searches only.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub plan_nodes: Vec<Node>,
    /// The plans' leaves, as indices of their parts.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub plan_leaves: Vec<u32>,
}

impl Flat {
    /// Appends a perturbed leaf; returns its index.
    pub(crate) fn push_perturbed(&mut self, s: &crate::PerturbedSurface) -> u32 {
        use crate::Surface;
        let bvh = s.bvh();
        let base = self.quadrics.len() as u32;
        self.quadrics.push(*s.base());
        let p0 = self.perturbations.len();
        self.perturbations.extend_from_slice(s.perturbations());
        let n0 = self.bvh_nodes.len();
        self.bvh_nodes.extend_from_slice(bvh.nodes());
        let w0 = self.bvh_wide.len();
        self.bvh_wide.extend_from_slice(bvh.wide());
        let i0 = self.bvh_order.len();
        self.bvh_order.extend_from_slice(bvh.order());
        self.bvh_item_bounds.extend_from_slice(bvh.item_bounds());
        let u0 = self.bvh_unbounded.len();
        self.bvh_unbounded.extend_from_slice(bvh.unbounded());
        self.leaves.push(Leaf::Perturbed {
            base,
            perturbations: Span::since(p0, self.perturbations.len()),
            bvh_nodes: Span::since(n0, self.bvh_nodes.len()),
            bvh_wide: Span::since(w0, self.bvh_wide.len()),
            bvh_items: Span::since(i0, self.bvh_order.len()),
            bvh_unbounded: Span::since(u0, self.bvh_unbounded.len()),
            bounds: s.bounds(),
        });
        self.leaves.len() as u32 - 1
    }

    /// Appends an expression leaf with its bytecode; returns its index.
    pub(crate) fn push_expr(&mut self, s: &crate::ExprSurface) -> Result<u32, crate::BuildError> {
        let v = s.view();
        let code = crate::bytecode::Bytecode::compile(s.expr())?;
        let t0 = self.tapes.len();
        self.tapes.extend_from_slice(v.tape);
        let c0 = self.bytecode.len();
        self.bytecode.extend_from_slice(code.words());
        let g0 = self.grids.len();
        // The occupancy bits, the signs of the empty cells, the clear blocks.
        self.grids.extend_from_slice(v.grid.words);
        self.grids.extend_from_slice(v.grid.inside);
        self.grids.extend_from_slice(v.grid.blocks);
        let gc0 = self.grid_cells.len();
        self.grid_cells.extend_from_slice(v.grid.cells);
        let ct0 = self.cell_tapes.len();
        self.cell_tapes.extend_from_slice(v.grid.nodes);
        let plan = v.plan.unwrap_or(crate::ray_tape::PlanView {
            parts: &[],
            leaves: &[],
            tape: &[],
        });
        let p0 = self.plan_nodes.len();
        self.plan_nodes.extend_from_slice(plan.parts);
        let p1 = self.plan_nodes.len();
        self.plan_nodes.extend_from_slice(plan.tape);
        let l0 = self.plan_leaves.len();
        self.plan_leaves.extend_from_slice(plan.leaves);
        self.leaves.push(Leaf::Expr {
            tape: Span::since(t0, self.tapes.len()),
            code: Span::since(c0, self.bytecode.len()),
            registers: code.registers() as u32,
            bounds: v.bounds,
            eps: v.eps,
            grid: Span::since(g0, self.grids.len()),
            grid_cells: Span::since(gc0, self.grid_cells.len()),
            cell_tapes: Span::since(ct0, self.cell_tapes.len()),
            grid_n: v.grid.n as u32,
            degree: v.degree,
            plan_parts: Span::since(p0, p1),
            plan_tape: Span::since(p1, self.plan_nodes.len()),
            plan_leaves: Span::since(l0, self.plan_leaves.len()),
        });
        Ok(self.leaves.len() as u32 - 1)
    }

    /// Leaf `k`'s data, borrowed from the pools.
    #[inline(always)]
    pub fn leaf(&self, k: usize) -> LeafView<'_> {
        match self.leaves[k] {
            Leaf::Perturbed {
                base,
                perturbations,
                bvh_nodes,
                bvh_wide,
                bvh_items,
                bvh_unbounded,
                bounds,
            } => LeafView::Perturbed(PerturbedView {
                base: &self.quadrics[base as usize],
                perturbations: &self.perturbations[perturbations.range()],
                bvh: BvhRef {
                    nodes: &self.bvh_nodes[bvh_nodes.range()],
                    wide: &self.bvh_wide[bvh_wide.range()],
                    order: &self.bvh_order[bvh_items.range()],
                    item_bounds: &self.bvh_item_bounds[bvh_items.range()],
                    unbounded: &self.bvh_unbounded[bvh_unbounded.range()],
                },
                bounds,
            }),
            Leaf::Expr {
                tape,
                bounds,
                eps,
                grid,
                grid_cells,
                cell_tapes,
                grid_n,
                degree,
                plan_parts,
                plan_tape,
                plan_leaves,
                ..
            } => {
                // The occupancy bits, the signs (as many words) and the blocks.
                let words = &self.grids[grid.range()];
                let w = (grid_n as usize).pow(3) / 64;
                let (occupied, rest) = words.split_at(w.min(words.len()));
                let (signs, blocks) = rest.split_at(w.min(rest.len()));
                LeafView::Expr(ExprView {
                    tape: &self.tapes[tape.range()],
                    bounds,
                    eps,
                    grid: GridView {
                        words: occupied,
                        inside: signs,
                        blocks,
                        cells: &self.grid_cells[grid_cells.range()],
                        nodes: &self.cell_tapes[cell_tapes.range()],
                        n: grid_n as usize,
                    },
                    degree,
                    plan: (plan_tape.count > 0).then(|| crate::ray_tape::PlanView {
                        parts: &self.plan_nodes[plan_parts.range()],
                        leaves: &self.plan_leaves[plan_leaves.range()],
                        tape: &self.plan_nodes[plan_tape.range()],
                    }),
                })
            }
        }
    }

    /// The parts of node `i` (empty for a leaf).
    #[inline]
    pub fn parts(&self, i: usize) -> &[u32] {
        match self.nodes[i].op {
            CsgOp::Leaf => &[],
            _ => &self.children[self.nodes[i].operands.range()],
        }
    }
}
