//! Rays per second through a perturbed ellipsoid as the number of perturbations grows.
//!
//! A 256×256 pinhole camera at distance 3 looks at the ellipsoid of semi-axes
//! (1, 0.7, 0.5) carrying N bumps and dents of fixed support radius 0.08 scattered over
//! its surface (deterministic positions). Each configuration traces every primary ray
//! with [`Surface::first_crossing`] on one thread and reports the best of three passes.
//! With the BVH over the supports the cost should grow far slower than N; the unculled
//! rows test every perturbation on every ray, for comparison.
//!
//! Run: `cargo bench -p frep --bench perturbed`. With `PERTURBED_ONE_PASS=N` in the
//! environment it traces one untimed pass at N perturbations instead.

use frep::perturbed::{PerturbedQuadric, PerturbedSurface};
use frep::quadric::Quadric;
use frep::{Ray, Surface};
use glam::DVec3;
use std::hint::black_box;
use std::time::Instant;

const SIZE: usize = 256;

/// N perturbations on a Fibonacci lattice of the ellipsoid's surface, alternating bumps
/// and dents.
fn scene(n: usize) -> PerturbedQuadric {
    let radii = DVec3::new(1.0, 0.7, 0.5);
    let base = Quadric::ellipsoid(DVec3::ZERO, radii);
    let mut pq = PerturbedQuadric::new(base);
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    for k in 0..n {
        let z = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * k as f64;
        let c = radii * DVec3::new(r * phi.cos(), r * phi.sin(), z);
        let grad = base.gradient(c).length();
        let f = if k % 3 == 2 { -0.5 } else { 0.5 } * 0.08 * grad;
        pq.push(f, Quadric::sphere(c, 0.08));
    }
    pq
}

fn camera() -> Vec<Ray> {
    let eye = DVec3::new(0.6, 1.2, 2.6);
    let fwd = (-eye).normalize();
    let right = fwd.cross(DVec3::Y).normalize();
    let up = right.cross(fwd);
    let mut rays = Vec::with_capacity(SIZE * SIZE);
    for j in 0..SIZE {
        for i in 0..SIZE {
            let x = (i as f64 + 0.5) / SIZE as f64 * 2.0 - 1.0;
            let y = (j as f64 + 0.5) / SIZE as f64 * 2.0 - 1.0;
            rays.push(Ray::new(
                eye,
                (fwd + 0.42 * (x * right + y * up)).normalize(),
            ));
        }
    }
    rays
}

/// (rays per second, hits) for the best of three passes.
fn measure(s: &PerturbedSurface, rays: &[Ray]) -> (f64, usize) {
    let mut best = f64::INFINITY;
    let mut hits = 0;
    for _ in 0..3 {
        let start = Instant::now();
        hits = 0;
        for ray in rays {
            if black_box(s.first_crossing(black_box(ray), 0.0, f64::INFINITY)).is_some() {
                hits += 1;
            }
        }
        best = best.min(start.elapsed().as_secs_f64());
    }
    (rays.len() as f64 / best, hits)
}

fn main() {
    let rays = camera();
    // `PERTURBED_ONE_PASS=N`: one untimed pass at N perturbations, for instruction counts
    // that other builds on the machine cannot disturb (valgrind, docs/benchmarks.md).
    if let Ok(n) = std::env::var("PERTURBED_ONE_PASS") {
        let s = PerturbedSurface::new(&scene(n.parse().expect("a count")));
        let hits = rays
            .iter()
            .filter(|r| black_box(s.first_crossing(r, 0.0, f64::INFINITY)).is_some())
            .count();
        println!("{hits} hits");
        return;
    }
    println!("perturbed ellipsoid, {SIZE}x{SIZE} primary rays, one thread, support radius 0.08");
    println!(
        "{:>6} {:>8} {:>14} {:>8} {:>16}",
        "N", "hits", "BVH Mrays/s", "nodes", "unculled Mrays/s"
    );
    let mut first = None;
    for n in [1, 16, 256, 4096] {
        let pq = scene(n);
        let s = PerturbedSurface::new(&pq);
        let (rate, hits) = measure(&s, &rays);
        let unculled = if n <= 256 {
            let (u, uh) = measure(&PerturbedSurface::unculled(&pq), &rays);
            assert_eq!(uh, hits, "culling changed the image");
            format!("{:16.3}", u / 1e6)
        } else {
            format!("{:>16}", "-")
        };
        let base = *first.get_or_insert(rate);
        println!(
            "{n:>6} {hits:>8} {:>14.3} {:>8} {unculled}   (cost ×{:.2} vs N = 1)",
            rate / 1e6,
            s.bvh().nodes().len(),
            base / rate
        );
    }
}
