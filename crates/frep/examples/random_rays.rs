//! Times random rays through a model's bounds on one thread, for profiling ray queries
//! at every angle (where `heightmap` casts axis-aligned rays): N rays from points on a
//! sphere around the bounds to random points inside them, seeded, nearest hits
//! (`Solid::intersect`) and then the same rays as shadow queries (`Solid::occludes`).
//!
//! ```text
//! cargo run --release -p frep --example random_rays -- MODEL N
//! valgrind --tool=callgrind --toggle-collect='frep::solid::Solid::intersect' \
//!   target/release/examples/random_rays MODEL N
//! ```

use frep::surface::Surface;
use frep::{Ray, Solid};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use std::error::Error;

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [path, n] = &args[..] else {
        return Err("usage: random_rays MODEL N".into());
    };
    let n: usize = n
        .parse()
        .map_err(|_| format!("N: expected a number, found '{n}'"))?;
    let model = frep::read::read_file(std::path::Path::new(path))?;
    let solid = Solid::build(&model.shape)?;
    let b = solid.bounds();
    let (c, r) = (0.5 * (b.lo + b.hi), (b.hi - b.lo).length());
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    let rays: Vec<Ray> = (0..n)
        .map(|_| {
            let u = DVec3::new(rng.gen(), rng.gen(), rng.gen());
            let target = b.lo + (b.hi - b.lo) * u;
            let dir = loop {
                let v = DVec3::new(rng.gen(), rng.gen(), rng.gen()) * 2.0 - 1.0;
                if v.length_squared() <= 1.0 && v.length_squared() > 1e-6 {
                    break v.normalize();
                }
            };
            let o = c + dir * r;
            Ray::new(o, (target - o).normalize())
        })
        .collect();
    let start = std::time::Instant::now();
    let hits: usize = rays
        .iter()
        .map(|ray| usize::from(solid.intersect(ray, 0.0, 4.0 * r).is_some()))
        .sum();
    let mid = start.elapsed().as_secs_f64() * 1e3;
    let occluded: usize = rays
        .iter()
        .map(|ray| usize::from(solid.occludes(ray, 0.0, 4.0 * r)))
        .sum();
    let end = start.elapsed().as_secs_f64() * 1e3;
    println!(
        "{n} rays: {hits} hits in {mid:.1} ms, {occluded} occluded in {:.1} ms",
        end - mid
    );
    Ok(())
}
