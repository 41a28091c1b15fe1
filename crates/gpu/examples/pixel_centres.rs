//! The GPU tape tracer's CPU twin against frep's f64 tracer at the pixel centres of 27
//! views (9 azimuths × 3 elevations, 30° field of view) of a model: how many rays it
//! answers as frep does, how many it leaves to the CPU, and how many it would answer
//! wrongly (none is the goal). `VERBOSE=1` lists the disagreements.
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
    let surface = ExprSurface::new(expr.clone(), bounds);
    let view = surface.view();
    let (c, size) = (bounds.center(), bounds.extent().length());
    let h = 15f64.to_radians().tan();
    let (mut n, mut agree, mut undecided, mut false_hits, mut misses, mut t_off) =
        (0, 0, 0, 0, 0, 0);
    let mut max_loops = 0;
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
                    let twin = solid.trace(o, d, 0.0, f32::INFINITY);
                    max_loops = max_loops.max(twin.loops);
                    let ray = Ray::new(o.as_dvec3(), d.as_dvec3());
                    let want = view.trace(&ray, 0.0, f64::INFINITY, false).map(|h| h.0);
                    n += 1;
                    let wrong = match (twin.hit, want) {
                        (TapeHit::Undecided, _) => {
                            undecided += 1;
                            false
                        }
                        (TapeHit::Miss, None) => false,
                        (TapeHit::Hit(t), Some(w)) => {
                            let off = (t as f64 - w).abs() > 1e-3 * size.max(w);
                            t_off += off as usize;
                            off
                        }
                        (TapeHit::Hit(_), None) => {
                            false_hits += 1;
                            true
                        }
                        (TapeHit::Miss, Some(_)) => {
                            misses += 1;
                            true
                        }
                    };
                    agree += (!wrong && twin.hit != TapeHit::Undecided) as usize;
                    if wrong && std::env::var_os("VERBOSE").is_some() {
                        eprintln!("az {az} el {el} pixel ({i}, {j}): twin {:?}, frep {want:?}; o {o:?} d {d:?}", twin.hit);
                    }
                }
            }
        }
    }
    println!(
        "{path}: {n} rays: {agree} as frep, {undecided} undecided (for the CPU); wrong: \
         {false_hits} false hits, {misses} misses, {t_off} with t off by over 1e-3; \
         most loop iterations {max_loops}"
    );
}
