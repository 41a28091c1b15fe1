//! An occupancy grid over an expression solid's box: the cells where F may be zero.
//!
//! Built once per solid by interval arithmetic over an octree of the box (Keeter 2020,
//! §3: a cell whose interval F excludes 0 holds no surface), it lets a ray skip the
//! stretches of its segment that lie in empty cells and search only runs of occupied
//! ones. It is sound: a crossing needs a sign change, and across an empty cell F keeps
//! the sign its interval proves; two neighbouring empty cells share their boundary
//! points, so their signs agree. The occupied set is dilated by one cell so that the
//! walk along a ray (Amanatides & Woo 1987), which may put a point within rounding of a
//! cell face in the neighbouring cell, never skips an occupied cell.

use crate::expr::{eval_nodes, Node};
use crate::interval::Interval;
use crate::ray::{Aabb, Ray};
use glam::DVec3;

/// Cells per axis (a power of two: the octree halves it each level).
pub const GRID: usize = 32;

/// Words of a grid's bitset (one bit per cell).
pub const GRID_WORDS: usize = GRID * GRID * GRID / 64;

/// Node evaluations (tape length × boxes) a build may spend; past it the solid gets no
/// grid, and rays search their whole segment as before.
const BUILD_BUDGET: usize = 1 << 25;

/// The bit of cell (x, y, z).
#[inline]
fn bit(x: usize, y: usize, z: usize) -> usize {
    (z * GRID + y) * GRID + x
}

/// The occupancy bitset of `tape` over `b` ([`GRID_WORDS`] words), or an empty vector
/// when the box is not finite or the build would exceed its budget.
pub fn build(tape: &[Node], b: &Aabb) -> Vec<u64> {
    if !b.is_finite() || b.is_empty() || tape.is_empty() {
        return Vec::new();
    }
    let mut occupied = vec![false; GRID * GRID * GRID];
    let mut scratch = Vec::new();
    let mut spent = 0usize;
    let cell = (b.hi - b.lo) / GRID as f64;
    // Octree nodes: (corner cell, size in cells).
    let mut stack = vec![([0usize; 3], GRID)];
    while let Some((c, size)) = stack.pop() {
        spent += tape.len();
        if spent > BUILD_BUDGET {
            return Vec::new();
        }
        let lo = b.lo + DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * cell;
        let hi = if c.iter().all(|&k| k + size == GRID) {
            b.hi
        } else {
            lo + cell * size as f64
        };
        let iv = |k: usize| Interval::new(lo[k], hi[k].max(lo[k]));
        let v = eval_nodes(tape, iv(0), iv(1), iv(2), &mut scratch);
        if v.lo > 0.0 || v.hi < 0.0 {
            continue;
        }
        if size == 1 {
            occupied[bit(c[0], c[1], c[2])] = true;
            continue;
        }
        let h = size / 2;
        for k in 0..8 {
            let d = [(k & 1) * h, (k >> 1 & 1) * h, (k >> 2 & 1) * h];
            stack.push(([c[0] + d[0], c[1] + d[1], c[2] + d[2]], h));
        }
    }
    let mut words = vec![0u64; GRID_WORDS];
    for z in 0..GRID {
        for y in 0..GRID {
            for x in 0..GRID {
                let near = |a: usize| a.saturating_sub(1)..=(a + 1).min(GRID - 1);
                let any = near(z).any(|k| near(y).any(|j| near(x).any(|i| occupied[bit(i, j, k)])));
                if any {
                    let n = bit(x, y, z);
                    words[n / 64] |= 1 << (n % 64);
                }
            }
        }
    }
    words
}

/// Calls `visit(a, b)` for each maximal run [a, b] of occupied cells that the segment
/// [t0, t1] of `ray` (inside `b`) crosses, in order, until `visit` returns true.
pub fn runs(
    words: &[u64],
    b: &Aabb,
    ray: &Ray,
    t0: f64,
    t1: f64,
    mut visit: impl FnMut(f64, f64) -> bool,
) {
    let occupied = |c: [i64; 3]| {
        let n = bit(c[0] as usize, c[1] as usize, c[2] as usize);
        words[n / 64] >> (n % 64) & 1 == 1
    };
    let size = (b.hi - b.lo) / GRID as f64;
    let last = GRID as i64 - 1;
    let p = ray.at(t0);
    let mut c = [0i64; 3];
    let mut next = [f64::INFINITY; 3];
    let mut delta = [f64::INFINITY; 3];
    let mut step = [0i64; 3];
    for k in 0..3 {
        c[k] = (((p[k] - b.lo[k]) / size[k]).floor() as i64).clamp(0, last);
        let d = ray.d[k];
        if d != 0.0 {
            step[k] = if d > 0.0 { 1 } else { -1 };
            let face = b.lo[k] + (c[k] + i64::from(d > 0.0)) as f64 * size[k];
            next[k] = (face - ray.o[k]) / d;
            delta[k] = size[k] / d.abs();
        }
    }
    let mut start: Option<f64> = None;
    let mut t = t0;
    loop {
        let k = (0..3).fold(0, |m, k| if next[k] < next[m] { k } else { m });
        let exit = next[k].min(t1);
        match (occupied(c), start) {
            (true, None) => start = Some(t),
            (false, Some(a)) => {
                if visit(a, t) {
                    return;
                }
                start = None;
            }
            _ => {}
        }
        if exit >= t1 {
            break;
        }
        c[k] += step[k];
        if !(0..=last).contains(&c[k]) {
            break;
        }
        next[k] += delta[k];
        t = exit.max(t);
    }
    if let Some(a) = start {
        visit(a, t1);
    }
}
