//! Times the heightmap rays of `bench/fidget-compare` on one thread, for profiling a
//! model's ray queries without Fidget: an orthographic view down −z over [-h, h]³, one
//! ray per pixel of an N × N image (`Solid::inside` at its origin, else
//! `Solid::intersect`), the solid built before the clock starts.
//!
//! ```text
//! cargo run --release -p frep --example heightmap -- MODEL N H
//! valgrind --tool=callgrind --toggle-collect='frep::solid::Solid::intersect' \
//!   --toggle-collect='frep::solid::Solid::inside' target/release/examples/heightmap MODEL N H
//! ```

use frep::{Ray, Solid};
use glam::DVec3;
use std::error::Error;

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [path, n, h] = &args[..] else {
        return Err("usage: heightmap MODEL N H (N × N rays over [-H, H]³)".into());
    };
    let n: usize = n
        .parse()
        .map_err(|_| format!("N: expected a number, found '{n}'"))?;
    let h: f64 = h
        .parse()
        .map_err(|_| format!("H: expected a number, found '{h}'"))?;
    let model = frep::read::read_file(std::path::Path::new(path))?;
    let solid = Solid::build(&model.shape)?;
    let start = std::time::Instant::now();
    let (s, half) = (2.0 / n as f64, (n / 2) as f64);
    let mut hits = 0usize;
    for j in 0..n {
        for i in 0..n {
            let x = (i as f64 - half) * s * h;
            let y = (half - 1.0 - j as f64) * s * h;
            let o = DVec3::new(x, y, h);
            let hit = solid.inside(o)
                || solid
                    .intersect(&Ray::new(o, -DVec3::Z), 0.0, 2.0 * h)
                    .is_some();
            hits += usize::from(hit);
        }
    }
    let ms = start.elapsed().as_secs_f64() * 1e3;
    println!("{n}² rays: {hits} hits, {ms:.1} ms");
    Ok(())
}
