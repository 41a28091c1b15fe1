//! The GPU tape tracer's CPU twin against frep's f64 tracer at the pixel centres of 27
//! views (9 azimuths × 3 elevations, 30° field of view) of a model: how many rays it
//! answers as frep does, how many it leaves to the CPU, and how many it would answer
//! wrongly (none is the goal), searching the whole tape and walking the cells with
//! their tapes ([`TapeSolid::with_cells`]). `VERBOSE=1` lists the disagreements.
//!
//! `cargo run --release -p gpu --example pixel_centres -- MODEL [RESOLUTION]`
use frep::bytecode::Bytecode;
use frep::read::read_file;
use frep::{Aabb, Expr, ExprSurface, Ray};
use glam::DVec3;
use gpu::tape::GpuTape;
use gpu::tape_trace::{TapeHit, TapeSolid};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: pixel_centres MODEL [RESOLUTION]");
        std::process::exit(2);
    };
    let res: usize = args.get(2).map_or(48, |s| s.parse().expect("a resolution"));
    let m = read_file(std::path::Path::new(path)).unwrap_or_else(|e| panic!("{e}"));
    let expr = Expr::new(&m.shape.to_tree().expect("a regular shape"));
    let cube = Aabb::new(DVec3::splat(-2.0), DVec3::splat(2.0));
    let bounds = frep::bounds::expr_bounds(&expr, m.domain.unwrap_or(cube));
    let code = Bytecode::compile(&expr).expect("a tape");
    let solid = TapeSolid::new(GpuTape::new(&code).expect("GPU operations"), &bounds);
    let walked = solid.clone().with_cells(expr.nodes()).expect("cell tapes");
    if walked.walk.is_none() {
        println!("{path}: no walk grid (a polynomial, or no grid)");
    }
    let solids = [("whole tape", solid), ("cells", walked)];
    let surface = ExprSurface::new(expr.clone(), bounds);
    let view = surface.view();
    let (c, size) = (bounds.center(), bounds.extent().length());
    let h = 15f64.to_radians().tan();
    let mut stats = [Stats::default(); 2];
    for az in (0..360).step_by(40) {
        for el in [-20.0f64, 15.0, 50.0] {
            let (a, e) = ((az as f64).to_radians(), el.to_radians());
            let eye = c + 1.5 * size * DVec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin());
            let fwd = (c - eye).normalize();
            let right = fwd.cross(DVec3::Z).normalize();
            let up = right.cross(fwd);
            for j in 0..res {
                for i in 0..res {
                    let u = ((i as f64 + 0.5) / res as f64 * 2.0 - 1.0) * h;
                    let v = (1.0 - (j as f64 + 0.5) / res as f64 * 2.0) * h;
                    let (o, d) = (
                        eye.as_vec3(),
                        (fwd + u * right + v * up).normalize().as_vec3(),
                    );
                    let ray = Ray::new(o.as_dvec3(), d.as_dvec3());
                    let want = view.trace(&ray, 0.0, f64::INFINITY, false).map(|h| h.0);
                    for ((name, solid), st) in solids.iter().zip(&mut stats) {
                        let twin = solid.trace(o, d, 0.0, f32::INFINITY);
                        if st.add(twin, want, size) && std::env::var_os("VERBOSE").is_some() {
                            eprintln!("{name}: az {az} el {el} pixel ({i}, {j}): twin {:?}, frep {want:?}; o {o:?} d {d:?}", twin.hit);
                        }
                    }
                }
            }
        }
    }
    for ((name, _), st) in solids.iter().zip(&stats) {
        let Stats {
            n,
            agree,
            undecided,
            false_hits,
            misses,
            t_off,
            max_loops,
            loops,
        } = *st;
        println!(
            "{path}, {name}: {n} rays: {agree} as frep, {undecided} undecided (for the CPU); \
             wrong: {false_hits} false hits, {misses} misses, {t_off} with t off by over \
             1e-3; loop iterations {:.0} on average, {max_loops} at most",
            loops as f64 / n.max(1) as f64
        );
    }
}

/// One tracer's outcomes against frep's.
#[derive(Clone, Copy, Default)]
struct Stats {
    n: usize,
    agree: usize,
    undecided: usize,
    false_hits: usize,
    misses: usize,
    t_off: usize,
    max_loops: u32,
    loops: u64,
}

impl Stats {
    /// Counts one ray; true where the twin answered wrongly.
    fn add(&mut self, twin: gpu::tape_trace::Traced, want: Option<f64>, size: f64) -> bool {
        self.max_loops = self.max_loops.max(twin.loops);
        self.loops += u64::from(twin.loops);
        self.n += 1;
        let wrong = match (twin.hit, want) {
            (TapeHit::Undecided, _) => {
                self.undecided += 1;
                false
            }
            (TapeHit::Miss, None) => false,
            (TapeHit::Hit(t), Some(w)) => {
                let off = (t as f64 - w).abs() > 1e-3 * size.max(w);
                self.t_off += off as usize;
                off
            }
            (TapeHit::Hit(_), None) => {
                self.false_hits += 1;
                true
            }
            (TapeHit::Miss, Some(_)) => {
                self.misses += 1;
                true
            }
        };
        self.agree += (!wrong && twin.hit != TapeHit::Undecided) as usize;
        wrong
    }
}
