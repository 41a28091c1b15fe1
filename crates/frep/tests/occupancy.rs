//! The occupancy grid ([`frep::occupancy`]) changes where rays search, not what they
//! find: on shipped models (HyperFun, .frep and Fidget .vm), rays from several eyes and
//! grazing rays give the same hits with the grid as without it, and the grid is sound:
//! every crossing of a dense march lies in an occupied cell.

use crate::common;

use frep::interval_trace::ExprView;
use frep::occupancy::{FINE_GRID, GRID, MARGIN};
use frep::read::read_file;
use frep::solid::Solid;
use frep::{Aabb, LeafView};
use glam::DVec3;
use std::path::PathBuf;

fn path(p: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(p)
}

/// The models' expression leaves (each model here is one expression).
fn leaf_views(s: &Solid) -> Vec<ExprView<'_>> {
    (0..s.flat().leaves.len())
        .filter_map(|k| match s.flat().leaf(k) {
            LeafView::Expr(v) => Some(v),
            LeafView::Perturbed(_) => None,
        })
        .collect()
}

/// Whether a cell holding `p`, grown by the build's margin, is occupied.
fn occupied(v: &ExprView, p: DVec3) -> bool {
    let g = Aabb::new(v.bounds.lo - v.eps, v.bounds.hi + v.eps);
    let at = |p: DVec3| {
        let n = v.grid.n;
        let c = ((p - g.lo) / (g.hi - g.lo) * n as f64)
            .floor()
            .clamp(DVec3::ZERO, DVec3::splat(n as f64 - 1.0));
        let n = ((c.z as usize) * n + c.y as usize) * n + c.x as usize;
        v.grid.words[n / 64] >> (n % 64) & 1 == 1
    };
    let m = (g.hi - g.lo) / v.grid.n as f64 * MARGIN;
    (0..27).any(|k| {
        let o = DVec3::new(
            (k % 3) as f64 - 1.0,
            (k / 3 % 3) as f64 - 1.0,
            (k / 9) as f64 - 1.0,
        );
        at(p + o * m)
    })
}

#[test]
fn the_grid_changes_no_hit() {
    let models = [
        "models/canonical/s2_csg.hf",
        "models/canonical/s3_blend.hf",
        "models/canonical/s4_gyroid.hf",
        "models/canonical/s5_twist.hf",
        "models/examples/smooth_blob.frep",
        "models/examples/machined_part.frep",
        "models/fidget/quarter.vm",
    ];
    let mut total = (0, 0, 0);
    for m in models {
        let model = read_file(&path(m)).unwrap_or_else(|e| panic!("{m}: {e}"));
        let solid = Solid::build(&model.shape).unwrap();
        for v in leaf_views(&solid) {
            let n = v.grid.n;
            assert!(n == GRID || n == FINE_GRID, "{m}: no grid");
            assert_eq!(v.grid.words.len(), n * n * n / 64, "{m}");
            let full = v.grid.words.iter().map(|w| w.count_ones()).sum::<u32>() as usize;
            let plain = ExprView {
                grid: frep::occupancy::GridView::NONE,
                ..v
            };
            let b = v.bounds;
            let r = 0.5 * b.extent().length();
            let rays = common::eye_rays(&b);
            let mut hits = 0;
            for ray in &rays {
                // Walk every crossing along the ray, from each hit on.
                let mut t = 0.0;
                for _ in 0..16 {
                    let (g, p) = (v.trace(ray, t, 1e3, true), plain.trace(ray, t, 1e3, true));
                    match (g, p) {
                        (Some(g), Some(p)) => {
                            assert!((g.0 - p.0).abs() <= 1e-9 * r, "{m} {ray:?}: {g:?} vs {p:?}");
                            // Soundness: the crossing's cell is occupied (caps on the
                            // faces of the search box, where the solid is cut, excepted).
                            let q = ray.at(g.0);
                            let lo = (q - (b.lo - v.eps)).min_element();
                            let hi = ((b.hi + v.eps) - q).min_element();
                            let cap = lo.min(hi) <= 1e-9 * r;
                            assert!(cap || occupied(&v, q), "{m}: {g:?} in an empty cell");
                            hits += 1;
                            t = g.0 + v.eps;
                        }
                        (None, None) => break,
                        _ => panic!("{m} {ray:?} from {t}: grid {g:?} vs none {p:?}"),
                    }
                }
            }
            assert!(hits > 100, "{m}: {hits} hits");
            total = (total.0 + hits, total.1 + full, total.2 + n * n * n);
            println!(
                "{m}: {hits} crossings, {full} of {} cells occupied",
                n * n * n
            );
        }
    }
    println!("{total:?}");
}

/// Each cell's tape equals the whole tape at every point of the cell (bit for bit: a
/// decided min/max returns the operand it was proven to return), an empty cell's sign
/// is F's sign all over it, and `inside` is F ≥ 0 within the model's bounds.
#[test]
fn cell_tapes_equal_the_whole_tape() {
    use frep::expr::eval_nodes;
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    for m in [
        "models/canonical/s2_csg.hf",
        "models/canonical/s3_blend.hf",
        "models/examples/machined_part.frep",
        "models/fidget/colonnade.vm",
        "models/fidget/quarter.vm",
    ] {
        let model = read_file(&path(m)).unwrap_or_else(|e| panic!("{m}: {e}"));
        let solid = Solid::build(&model.shape).unwrap();
        for v in leaf_views(&solid) {
            let (whole, cells) = (v.tape.len(), v.grid.cells.len());
            let n = v.grid.n;
            assert_eq!(cells, n * n * n, "{m}: no cell tapes");
            let g = Aabb::new(v.bounds.lo - v.eps, v.bounds.hi + v.eps);
            let (mut shorter, mut scratch, mut known) = (0, Vec::new(), [0, 0]);
            for _ in 0..20_000 {
                let u = DVec3::new(rng.gen(), rng.gen(), rng.gen());
                // Points in the box and a little around it.
                let p = g.lo + (g.hi - g.lo) * (u * 1.2 - 0.1);
                let tape = v.grid.tape_at(&g, p).unwrap_or(v.tape);
                shorter += usize::from(tape.len() < whole);
                let exact = eval_nodes(v.tape, p.x, p.y, p.z, &mut scratch);
                let by_cell = eval_nodes(tape, p.x, p.y, p.z, &mut scratch);
                assert_eq!(exact.to_bits(), by_cell.to_bits(), "{m} at {p:?}");
                assert_eq!(v.value(p).to_bits(), exact.to_bits(), "{m} at {p:?}");
                // An empty cell's sign is F's sign at every point of it.
                if g.contains(p) {
                    if let Some(inside) = v.grid.known_inside(&g, p) {
                        assert_eq!(inside, exact >= 0.0, "{m}: empty cell's sign at {p:?}");
                        known[usize::from(inside)] += 1;
                    }
                }
                // A model's domain caps it, for `inside` as for rays.
                let within = frep::Surface::bounds(&solid).contains(p);
                assert_eq!(solid.inside(p), exact >= 0.0 && within, "{m} at {p:?}");
            }
            println!("{m}: {shorter} of 20000 points on a shorter tape than {whole} nodes");
            println!("{m}: {known:?} points in empty cells known outside, inside");
            assert!(known[0] > 1000, "{m}: few points in empty cells outside");
            assert!(shorter > 2_000, "{m}: cell tapes simplify almost nothing");
        }
    }
}

/// The walk crosses a block with no occupied cell in one step ([`frep::occupancy::BLOCK`]):
/// it reports the same runs, with the same tapes and end signs, as the cell-by-cell
/// walk (every block marked occupied), on perspective rays from three eyes, rays along
/// the axes (the heightmap's) and along the diagonals; and a block is marked exactly
/// where one of its cells is occupied.
#[test]
fn clear_blocks_change_no_run() {
    use frep::occupancy::{runs, BLOCK};
    use frep::Ray;
    for m in [
        "models/canonical/s2_csg.hf",
        "models/canonical/s4_gyroid.hf",
        "models/examples/machined_part.frep",
        "models/fidget/colonnade.vm",
    ] {
        let model = read_file(&path(m)).unwrap_or_else(|e| panic!("{m}: {e}"));
        let solid = Solid::build(&model.shape).unwrap();
        for v in leaf_views(&solid) {
            let (n, k) = (v.grid.n, v.grid.n / BLOCK);
            let mut clear = 0;
            for (x, y, z) in (0..k * k * k).map(|i| (i % k, i / k % k, i / (k * k))) {
                let any = (0..BLOCK * BLOCK * BLOCK).any(|j| {
                    let c = [x, y, z].map(|c| c * BLOCK);
                    let (cx, cy, cz) = (c[0] + j % BLOCK, c[1] + j / BLOCK % BLOCK, c[2] + j / 16);
                    let i = (cz * n + cy) * n + cx;
                    v.grid.words[i / 64] >> (i % 64) & 1 == 1
                });
                let i = (z * k + y) * k + x;
                assert_eq!(
                    v.grid.blocks[i / 64] >> (i % 64) & 1 == 1,
                    any,
                    "{m}: block"
                );
                clear += usize::from(!any);
            }
            let every = vec![u64::MAX; v.grid.blocks.len()];
            let walked = frep::occupancy::GridView {
                blocks: &every,
                ..v.grid
            };
            let g = Aabb::new(v.bounds.lo - v.eps, v.bounds.hi + v.eps);
            let (c, r) = (g.center(), 0.5 * g.extent().length());
            let mut rays = common::eye_rays(&g);
            for i in 0..40 {
                for j in 0..40 {
                    let (u, w) = (
                        (i as f64 + 0.37) / 20.0 - 1.0,
                        (j as f64 + 0.61) / 20.0 - 1.0,
                    );
                    for (o, d) in [
                        (DVec3::new(u, w, 2.0), -DVec3::Z),
                        (DVec3::new(-2.0, u, w), DVec3::X),
                        (DVec3::new(u, -2.0, w), DVec3::Y),
                        (DVec3::new(u, w, -2.0), DVec3::ONE),
                    ] {
                        rays.push(Ray::new(c + o * r, d));
                    }
                }
            }
            let (mut total, mut runs_seen) = (0, 0);
            for ray in &rays {
                let Some((t0, t1)) = g.clip(ray, 0.0, f64::INFINITY) else {
                    continue;
                };
                let record = |grid| {
                    let mut out = Vec::new();
                    runs(grid, &g, ray, t0, t1, |a, b, tape, known| {
                        out.push((a, b, tape.map(|t: &[frep::Node]| t.as_ptr()), known));
                        false
                    });
                    out
                };
                let (fast, slow) = (record(v.grid), record(walked));
                assert_eq!(fast, slow, "{m}: {ray:?}");
                total += 1;
                runs_seen += fast.len();
            }
            println!(
                "{m}: {clear} of {} blocks clear; {total} rays, {runs_seen} runs",
                k * k * k
            );
            assert!(
                clear > 0 && runs_seen > 1000,
                "{m}: {clear} clear, {runs_seen} runs"
            );
        }
    }
}

/// The grid is built in parallel (its octree's subtrees in rayon's current pool) and is
/// the same, arena layout included, at any number of threads.
#[test]
fn the_grid_is_the_same_at_any_thread_count() {
    for m in [
        "models/canonical/s2_csg.hf",
        "models/examples/smooth_blob.frep",
        "models/canonical/s4_gyroid.hf",
        "models/fidget/colonnade.vm",
    ] {
        let model = read_file(&path(m)).unwrap_or_else(|e| panic!("{m}: {e}"));
        let build = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| Solid::build(&model.shape).unwrap())
        };
        let one = build(1);
        let grids = |s: &Solid| -> Vec<frep::occupancy::Grid> {
            leaf_views(s)
                .iter()
                .map(|v| frep::occupancy::Grid {
                    words: v.grid.words.to_vec(),
                    inside: v.grid.inside.to_vec(),
                    blocks: v.grid.blocks.to_vec(),
                    cells: v.grid.cells.to_vec(),
                    nodes: v.grid.nodes.to_vec(),
                    n: v.grid.n,
                })
                .collect()
        };
        assert!(grids(&one).iter().any(|g| g.n > 0), "{m}: no grid");
        for threads in [2, 3] {
            assert!(
                grids(&build(threads)) == grids(&one),
                "{m}: {threads} threads"
            );
        }
    }
}
