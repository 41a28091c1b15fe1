//! A watertight triangle mesh of a solid's surface, for 3-D printing and other tools.
//!
//! Marching tetrahedra on a uniform grid of cubes over a box: each cube is cut into the
//! six tetrahedra of its Kuhn subdivision (all sharing the diagonal from its lowest to
//! its highest corner), so neighbouring cubes cut their common face along the same
//! diagonal and every face of a tetrahedron is shared with exactly one other. A
//! tetrahedron whose corners are not all of one side (inside: F ≥ 0) gets one or two
//! triangles between the crossings of its edges; since a crossing is named by its edge
//! and computed once, the triangles of neighbours share their vertices, and the mesh is
//! closed and manifold (every edge in exactly two triangles, once each way) whatever F
//! is. Each crossing is found on its edge by the Illinois method, so the vertices lie on
//! F = 0 to rounding while staying between the corners that bracket them.
//!
//! Only the cubes interval arithmetic cannot prove one-sided are visited: an octree over
//! the grid drops every box where F's interval excludes 0 and simplifies the tape for
//! its children (Keeter 2020, §3.2, as [`crate::occupancy`] does), so the cost follows
//! the surface's area, not the box's volume.

use crate::expr::Expr;
use crate::interval::Interval;
use crate::ray::Aabb;
use glam::DVec3;
use std::collections::HashMap;
use std::io::{self, Write};
use std::sync::atomic::{AtomicUsize, Ordering};

pub mod write;

/// The finest grid: cubes along the box's longest side.
pub const MAX_RESOLUTION: u32 = 4096;

/// Triangles a mesh may have: meshing holds about 120 bytes a triangle at its peak
/// (named crossings, their positions, the numbered mesh), so 20 million take ~2.4 GB.
pub const MAX_TRIANGLES: usize = 20_000_000;

/// A triangle mesh: vertices and counter-clockwise triangles seen from outside (normals
/// point out of the solid, towards F < 0).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

/// Why a mesh was not made.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshError {
    /// The box is empty or not finite.
    Bounds,
    /// A resolution of 0 or past [`MAX_RESOLUTION`].
    Resolution(u32),
    /// The mesh would pass `limit` triangles.
    TooLarge {
        /// The limit.
        limit: usize,
    },
}

impl std::fmt::Display for MeshError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MeshError::Bounds => write!(
                f,
                "the solid's bounds are empty or unbounded; nothing to mesh"
            ),
            MeshError::Resolution(r) => write!(
                f,
                "resolution {r}: expected 1 to {MAX_RESOLUTION} cubes along the longest side"
            ),
            MeshError::TooLarge { limit } => write!(
                f,
                "the mesh would pass {limit} triangles; choose a lower resolution"
            ),
        }
    }
}

impl std::error::Error for MeshError {}

/// The grid: `n` cubes of side `h` per axis from `lo`.
struct Grid {
    lo: DVec3,
    h: f64,
    n: [u32; 3],
}

impl Grid {
    /// The position of grid corner `c` (computed the same way wherever it is used, so a
    /// corner shared by cubes has one value of F).
    fn corner(&self, c: [u32; 3]) -> DVec3 {
        self.lo + DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * self.h
    }
    /// A corner's global number, the name of the crossings on its edges.
    fn id(&self, c: [u32; 3]) -> u64 {
        let (nx, ny) = (u64::from(self.n[0]) + 1, u64::from(self.n[1]) + 1);
        u64::from(c[0]) + nx * (u64::from(c[1]) + ny * u64::from(c[2]))
    }
}

/// What one subtree of the octree found: triangles named by their crossings' edges, and
/// the position of each crossing.
#[derive(Default)]
struct Part {
    triangles: Vec<[(u64, u64); 3]>,
    crossings: HashMap<(u64, u64), [f64; 3]>,
}

/// Meshes the surface of the solid F ≥ 0 inside `bounds`, with `resolution` cubes along
/// the box's longest side (module docs). The box is padded by one cube on every side;
/// where the solid reaches past the box the mesh is cut there and closed by the box's
/// faces, so pass `min(F, box)` for a solid that is not inside `bounds`
/// ([`crate::csg::intersection`] with a box's function).
pub fn mesh(expr: &Expr, bounds: &Aabb, resolution: u32) -> Result<Mesh, MeshError> {
    mesh_limited(expr, bounds, resolution, MAX_TRIANGLES)
}

/// [`mesh`] with a limit on the triangles.
pub fn mesh_limited(
    expr: &Expr,
    bounds: &Aabb,
    resolution: u32,
    limit: usize,
) -> Result<Mesh, MeshError> {
    if bounds.is_empty() || !bounds.is_finite() || expr.is_empty() {
        return Err(MeshError::Bounds);
    }
    if resolution == 0 || resolution > MAX_RESOLUTION {
        return Err(MeshError::Resolution(resolution));
    }
    let extent = bounds.extent();
    let h = extent.max_element() / f64::from(resolution);
    if h.is_nan() || h <= 0.0 || !h.is_finite() {
        return Err(MeshError::Bounds);
    }
    // One cube of padding on each side, so a surface touching the box still closes.
    let cubes = |e: f64| ((e / h).ceil() as u32).clamp(1, MAX_RESOLUTION) + 2;
    let grid = Grid {
        lo: bounds.lo - DVec3::splat(h),
        h,
        n: [cubes(extent.x), cubes(extent.y), cubes(extent.z)],
    };
    let size = grid
        .n
        .iter()
        .max()
        .copied()
        .unwrap_or(1)
        .next_power_of_two();
    // The top of the octree, breadth first, until there are boxes for every thread.
    let mut frontier = vec![([0u32; 3], size, expr.clone())];
    while !frontier.is_empty() && frontier.len() < 64 && frontier[0].1 > 1 {
        let mut next = Vec::new();
        for (c, s, tape) in frontier {
            split(&grid, c, s, &tape, &mut |c, s, t| next.push((c, s, t)));
        }
        frontier = next;
    }
    use rayon::prelude::*;
    // Triangles made so far over every part: past the limit, every part stops.
    let made = AtomicUsize::new(0);
    let budget = Budget { made: &made, limit };
    let parts: Vec<Part> = frontier
        .par_iter()
        .map(|(c, s, tape)| {
            let mut part = Part::default();
            walk(&grid, *c, *s, tape, &mut part, &budget);
            part
        })
        .collect();
    if made.load(Ordering::Relaxed) > limit {
        return Err(MeshError::TooLarge { limit });
    }
    assemble(parts, limit)
}

/// Calls `child` with each child box of box (`c`, `s`) that may hold the surface, with the
/// tape simplified over it.
fn split(
    grid: &Grid,
    c: [u32; 3],
    s: u32,
    tape: &Expr,
    child: &mut dyn FnMut([u32; 3], u32, Expr),
) {
    let half = s / 2;
    let (mut scratch, mut choices) = (Vec::new(), Vec::new());
    for k in 0..8u32 {
        let cc = [
            c[0] + half * (k & 1),
            c[1] + half * ((k >> 1) & 1),
            c[2] + half * ((k >> 2) & 1),
        ];
        if (0..3).any(|a| cc[a] >= grid.n[a]) {
            continue;
        }
        let hi = [0, 1, 2].map(|a| (cc[a] + half).min(grid.n[a]));
        let (lo, hi) = (grid.corner(cc), grid.corner(hi));
        let i = |a: usize| Interval::new(lo[a], hi[a]);
        let v = tape.eval_choices(i(0), i(1), i(2), &mut scratch, &mut choices);
        // One-sided over the box (NaN bounds are not): no surface in it.
        if v.lo > 0.0 || v.hi < 0.0 {
            continue;
        }
        let t = tape.simplify(&choices).unwrap_or_else(|| tape.clone());
        child(cc, half, t);
    }
}

/// The triangles made by every part, against the limit.
struct Budget<'a> {
    made: &'a AtomicUsize,
    limit: usize,
}

/// Meshes the cubes of box (`c`, `s`) into `part`, depth first; stops once every
/// part's triangles together pass the limit.
fn walk(grid: &Grid, c: [u32; 3], s: u32, tape: &Expr, part: &mut Part, budget: &Budget) {
    if budget.made.load(Ordering::Relaxed) > budget.limit {
        return;
    }
    if s == 1 {
        let before = part.triangles.len();
        cube(grid, c, tape, part);
        budget
            .made
            .fetch_add(part.triangles.len() - before, Ordering::Relaxed);
        return;
    }
    split(grid, c, s, tape, &mut |cc, hs, t| {
        walk(grid, cc, hs, &t, part, budget)
    });
}

/// The six tetrahedra of a cube's Kuhn subdivision, as corner numbers (bit a of a
/// corner number: +1 along axis a): the paths from corner 0 to corner 7 along the axes
/// in each order.
const TETRAHEDRA: [[usize; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// Marching tetrahedra in cube `c`.
fn cube(grid: &Grid, c: [u32; 3], tape: &Expr, part: &mut Part) {
    let mut scratch = Vec::new();
    let corner = |k: usize| {
        [
            c[0] + (k & 1) as u32,
            c[1] + ((k >> 1) & 1) as u32,
            c[2] + ((k >> 2) & 1) as u32,
        ]
    };
    let pos: [DVec3; 8] = std::array::from_fn(|k| grid.corner(corner(k)));
    let f: [f64; 8] =
        std::array::from_fn(|k| tape.eval_with(pos[k].x, pos[k].y, pos[k].z, &mut scratch));
    // NaN counts as outside, as the renderer's F ≥ 0 test does.
    let inside: [bool; 8] = std::array::from_fn(|k| f[k] >= 0.0);
    if inside.iter().all(|&b| b) || inside.iter().all(|&b| !b) {
        return;
    }
    let ids: [u64; 8] = std::array::from_fn(|k| grid.id(corner(k)));
    for tet in TETRAHEDRA {
        let (ins, outs): (Vec<usize>, Vec<usize>) = tet.iter().partition(|&&k| inside[k]);
        if ins.is_empty() || outs.is_empty() {
            continue;
        }
        // Crossings as (inside corner, outside corner), in a cyclic order around the
        // in-side corners: one triangle, or a quad of two.
        let crossings: Vec<(usize, usize)> = match (ins.len(), outs.len()) {
            (1, 3) => outs.iter().map(|&o| (ins[0], o)).collect(),
            (3, 1) => ins.iter().map(|&i| (i, outs[0])).collect(),
            _ => vec![
                (ins[0], outs[0]),
                (ins[0], outs[1]),
                (ins[1], outs[1]),
                (ins[1], outs[0]),
            ],
        };
        // Outward orientation, decided on the edges' midpoints (never degenerate): the
        // normal points from the inside corners towards the outside ones.
        let mid = |(i, o): (usize, usize)| (pos[i] + pos[o]) * 0.5;
        let (a, b, d) = (mid(crossings[0]), mid(crossings[1]), mid(crossings[2]));
        let centre = |ks: &[usize]| ks.iter().map(|&k| pos[k]).sum::<DVec3>() / ks.len() as f64;
        let flip = (b - a).cross(d - a).dot(centre(&outs) - centre(&ins)) < 0.0;
        let mut key = |(i, o): (usize, usize)| {
            let k = (ids[i].min(ids[o]), ids[i].max(ids[o]));
            part.crossings
                .entry(k)
                .or_insert_with(|| crossing(tape, pos[i], f[i], pos[o], f[o]).to_array());
            k
        };
        let ks: Vec<(u64, u64)> = crossings.into_iter().map(&mut key).collect();
        let mut emit = |t: [(u64, u64); 3]| {
            part.triangles
                .push(if flip { [t[0], t[2], t[1]] } else { t });
        };
        emit([ks[0], ks[1], ks[2]]);
        if ks.len() == 4 {
            emit([ks[0], ks[2], ks[3]]);
        }
    }
}

/// The point of F = 0 on the edge from `a` (F = `fa` ≥ 0) to `b` (F = `fb` < 0): false
/// position with the Illinois modification (the retained end's value halved when it
/// is kept twice), which keeps the root bracketed and converges superlinearly.
fn crossing(tape: &Expr, a: DVec3, fa: f64, b: DVec3, fb: f64) -> DVec3 {
    if !fb.is_finite() || !fa.is_finite() {
        return (a + b) * 0.5;
    }
    let mut scratch = Vec::new();
    let (mut t0, mut f0, mut t1, mut f1) = (0.0f64, fa, 1.0f64, fb);
    let mut side = 0;
    for _ in 0..48 {
        let t = if f0 == f1 {
            0.5 * (t0 + t1)
        } else {
            (t0 * f1 - t1 * f0) / (f1 - f0)
        };
        if !(t > t0 && t < t1) || (t1 - t0) < 1e-15 {
            break;
        }
        let p = a + (b - a) * t;
        let ft = tape.eval_with(p.x, p.y, p.z, &mut scratch);
        if ft == 0.0 || !ft.is_finite() {
            return p;
        }
        if ft > 0.0 {
            (t0, f0) = (t, ft);
            if side == 1 {
                f1 *= 0.5;
            }
            side = 1;
        } else {
            (t1, f1) = (t, ft);
            if side == -1 {
                f0 *= 0.5;
            }
            side = -1;
        }
    }
    // The end whose |F| is smaller.
    let t = if f0.abs() <= f1.abs() { t0 } else { t1 };
    a + (b - a) * t
}

/// Numbers the crossings in the order the triangles first name them (the parts come in
/// a fixed order, so the mesh does not depend on the threads).
fn assemble(parts: Vec<Part>, limit: usize) -> Result<Mesh, MeshError> {
    let total: usize = parts.iter().map(|p| p.triangles.len()).sum();
    if total > limit {
        return Err(MeshError::TooLarge { limit });
    }
    let mut index: HashMap<(u64, u64), u32> = HashMap::new();
    let mut mesh = Mesh {
        vertices: Vec::new(),
        triangles: Vec::with_capacity(total),
    };
    for part in &parts {
        for t in &part.triangles {
            let tri = t.map(|k| {
                *index.entry(k).or_insert_with(|| {
                    mesh.vertices.push(part.crossings[&k]);
                    (mesh.vertices.len() - 1) as u32
                })
            });
            mesh.triangles.push(tri);
        }
    }
    Ok(mesh)
}

impl Mesh {
    /// The enclosed volume (divergence theorem; positive when the triangles face out).
    pub fn volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| DVec3::from(self.vertices[i as usize]));
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Whether the mesh is closed and consistently oriented: every edge is in exactly
    /// two triangles, once in each direction.
    pub fn is_watertight(&self) -> bool {
        // Per undirected edge: uses along (low → high) and against.
        let mut edges: HashMap<(u32, u32), [u32; 2]> = HashMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let e = edges.entry((a.min(b), a.max(b))).or_default();
                e[usize::from(a > b)] += 1;
            }
        }
        edges.values().all(|&e| e == [1, 1])
    }

    /// V − E + F: 2 for a closed surface of a ball, 0 for a torus, 2 − 2g in general.
    pub fn euler_characteristic(&self) -> i64 {
        let mut edges = std::collections::HashSet::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.insert((a.min(b), a.max(b)));
            }
        }
        self.vertices.len() as i64 - edges.len() as i64 + self.triangles.len() as i64
    }

    /// Writes the mesh as Wavefront OBJ (`v` and `f` lines).
    pub fn write_obj(&self, w: &mut dyn Write) -> io::Result<()> {
        write::obj(self, w)
    }

    /// Writes the mesh as binary STL (f32 coordinates, a facet normal per triangle).
    pub fn write_stl(&self, w: &mut dyn Write) -> io::Result<()> {
        write::stl(self, w)
    }
}
