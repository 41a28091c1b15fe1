//! An expression solid's per-cell tapes compiled for the GPU's interpreter: frep's
//! occupancy grid ([`frep::occupancy`]) simplifies the tape over each occupied cell
//! (Keeter 2020, §3.2: the min/max branches decided over the cell are dropped), and a ray
//! that searches a cell with the cell's tape evaluates a fraction of the whole. On the
//! GPU every evaluation counts against a loop budget (GPU.md §3.1), so a long tape leaves
//! rays undecided that its cell tapes would decide: Fidget's prospero (7 866
//! instructions) fits about 12 interval evaluations of the whole tape in the budget.
//!
//! Each distinct cell tape (cells that share a simplified tape share one range of the
//! grid's nodes) is compiled once to the kernels' register bytecode
//! ([`frep::Bytecode::compile_nodes`], then [`GpuTape`]); a cell maps to its tape's
//! index, and an empty cell to F's sign over it ([`NO_TAPE`], [`INSIDE`]). The tracer
//! walks the cells along a ray ([`crate::tape_trace`]).

use crate::tape::{GpuTape, Unsupported};
use frep::bytecode::BytecodeError;
use frep::occupancy::GridView;
use std::collections::HashMap;
use std::fmt;

/// No tape: an empty cell where F < 0 (F keeps its sign over it).
pub const NO_TAPE: u32 = u32::MAX;

/// No tape: an empty cell where F > 0.
pub const INSIDE: u32 = u32::MAX - 1;

/// An expression solid's cell tapes ([`Self::new`]).
#[derive(Clone, Debug)]
pub struct CellTapes {
    /// Cells per axis of the grid.
    pub n: usize,
    /// Per cell (the grid's order, `frep::occupancy::bit`), the index of its tape in
    /// `tapes`, or for an empty cell [`NO_TAPE`] (outside) or [`INSIDE`].
    pub cell: Vec<u32>,
    /// The distinct cell tapes.
    pub tapes: Vec<GpuTape>,
}

/// Why a cell tape cannot run on the GPU.
#[derive(Clone, Debug, PartialEq)]
pub enum CellTapeError {
    /// It needs more registers than the bytecode has.
    Bytecode(BytecodeError),
    /// It has an operation the kernels refuse.
    Tape(Unsupported),
}

impl fmt::Display for CellTapeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Bytecode(e) => write!(f, "a cell tape: {e}"),
            Self::Tape(e) => write!(f, "a cell tape: {e}"),
        }
    }
}

impl std::error::Error for CellTapeError {}

/// What the cell tapes hold, over the occupied cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellTapeStats {
    /// Cells with a tape.
    pub occupied: usize,
    /// Distinct tapes.
    pub tapes: usize,
    /// Mean instructions of an occupied cell's tape.
    pub mean_len: f64,
    /// The longest tape's instructions.
    pub max_len: usize,
    /// Words of all tapes (the kernel's binding).
    pub words: usize,
}

impl CellTapes {
    /// The cell tapes of `grid`; None where it has none (no grid, or cells without
    /// tapes of their own).
    pub fn new(grid: &GridView) -> Result<Option<Self>, CellTapeError> {
        let n = grid.n;
        if !grid.is_some() || grid.cells.len() != n * n * n {
            return Ok(None);
        }
        let mut by_range: HashMap<[u32; 2], u32> = HashMap::new();
        let mut tapes = Vec::new();
        let mut cell = Vec::with_capacity(grid.cells.len());
        for (c, &[s, e]) in grid.cells.iter().enumerate() {
            // Empty cells keep their parent's tape in the grid; F's sign there is the
            // grid's, and no ray evaluates in them.
            if grid.words[c / 64] >> (c % 64) & 1 == 0 {
                let inside = grid.inside[c / 64] >> (c % 64) & 1 == 1;
                cell.push(if inside { INSIDE } else { NO_TAPE });
                continue;
            }
            if s == e {
                // An occupied cell without a tape of its own: no walk by cell tapes.
                return Ok(None);
            }
            let k = match by_range.get(&[s, e]) {
                Some(&k) => k,
                None => {
                    let nodes = &grid.nodes[s as usize..e as usize];
                    let code =
                        frep::Bytecode::compile_nodes(nodes).map_err(CellTapeError::Bytecode)?;
                    tapes.push(GpuTape::new(&code).map_err(CellTapeError::Tape)?);
                    let k = tapes.len() as u32 - 1;
                    by_range.insert([s, e], k);
                    k
                }
            };
            cell.push(k);
        }
        Ok(Some(Self { n, cell, tapes }))
    }

    /// Cells, tapes and lengths ([`CellTapeStats`]).
    pub fn stats(&self) -> CellTapeStats {
        let lens: Vec<usize> = self
            .cell
            .iter()
            .filter(|&&k| k < INSIDE)
            .map(|&k| self.tapes[k as usize].len())
            .collect();
        CellTapeStats {
            occupied: lens.len(),
            tapes: self.tapes.len(),
            mean_len: lens.iter().sum::<usize>() as f64 / lens.len().max(1) as f64,
            max_len: self.tapes.iter().map(GpuTape::len).max().unwrap_or(0),
            words: self.tapes.iter().map(|t| t.words().len()).sum(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use frep::{bounds::expr_bounds, Aabb, Expr, ExprSurface};
    use glam::DVec3;

    /// Fidget's colonnade and prospero: every occupied cell gets a tape, much shorter
    /// than the whole; at points spread over 2 000 occupied cells the cell's tape gives
    /// F as the whole tape does (the kernels' f32 interpreter twin): bit for bit, but
    /// where a min/max the cell dropped ties within f32 rounding (within 10⁻⁵).
    #[test]
    fn cell_tapes_are_short_and_equal_the_whole_tape_in_their_cells() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        for (name, half) in [("colonnade", 5.0), ("prospero", 1.0)] {
            let path = root.join(format!("models/fidget/{name}.vm"));
            let model = frep::read::read_file(&path).unwrap();
            let frep::Shape::Function { tree, .. } = &model.shape else {
                panic!("{name}: not one expression");
            };
            let e = Expr::new(tree);
            let b = expr_bounds(&e, Aabb::new(DVec3::splat(-half), DVec3::splat(half)));
            let whole = GpuTape::new(&frep::Bytecode::compile(&e).unwrap()).unwrap();
            let s = ExprSurface::new(e, b);
            let view = s.view();
            let cells = CellTapes::new(&view.grid).unwrap().expect("a grid");
            let st = cells.stats();
            eprintln!("{name}: whole tape {} instructions; {st:?}", whole.len());
            assert!(st.occupied > 0 && st.max_len <= whole.len());
            assert!(st.mean_len * 4.0 < whole.len() as f64, "{st:?}");
            // The grid lies over the bounds grown by ε (interval_trace's `grown`).
            let lo = view.bounds.lo - view.eps;
            let size = (view.bounds.hi + view.eps - lo) / cells.n as f64;
            let n = cells.n;
            let (mut points, mut exact) = (0usize, 0usize);
            // About 2 000 occupied cells of each model, spread over the grid.
            let stride = (st.occupied / 2000).max(1);
            let occupied = cells.cell.iter().enumerate().filter(|(_, &k)| k < INSIDE);
            for (c, &k) in occupied.step_by(stride) {
                let at = DVec3::new((c % n) as f64, ((c / n) % n) as f64, (c / (n * n)) as f64);
                for j in 0..8 {
                    // Points at (j-dependent) fractions of the cell, inside it.
                    let f = DVec3::new(
                        0.1 + 0.8 * ((j * 5 + c) % 9) as f64 / 8.0,
                        0.1 + 0.8 * ((j * 3 + c) % 7) as f64 / 6.0,
                        0.1 + 0.8 * (j % 4) as f64 / 3.0,
                    );
                    let p = (lo + (at + f) * size).as_vec3().to_array();
                    let (a, w) = (cells.tapes[k as usize].eval_point(p), whole.eval_point(p));
                    points += 1;
                    exact += usize::from(a.to_bits() == w.to_bits());
                    assert!(
                        (a - w).abs() <= 1e-5 * (1.0 + w.abs()),
                        "{name}: cell {c} at {p:?}: {a} against {w}"
                    );
                }
            }
            eprintln!("{name}: {exact} of {points} points bit for bit");
            assert!(
                points > 1000 && exact * 100 >= points * 99,
                "{exact} of {points}"
            );
        }
    }
}
