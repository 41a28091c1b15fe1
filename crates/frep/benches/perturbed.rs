//! Rays per second through a perturbed ellipsoid as the number of perturbations grows.
//!
//! A 256×256 pinhole camera at distance 3 looks at the ellipsoid of semi-axes
//! (1, 0.7, 0.5) carrying N bumps and dents of fixed support radius 0.08 scattered over
//! its surface (deterministic positions). Each configuration traces every primary ray
//! with [`Surface::first_crossing`] on one thread and reports the best of three passes.
//! With the BVH over the supports the cost should grow far slower than N; the unculled
//! rows test every perturbation on every ray, for comparison.
//!
//! The supports overlap more as N grows (about 12 deep at 4096), so a ray meets more of
//! them. "met/ray" counts, per ray, the supports its path meets before the hit (or
//! before it leaves the ellipsoid's box), by brute force; "ns/met" is the time per ray
//! beyond N = 1's, per support met beyond N = 1's: flat where cost follows the
//! perturbations a ray meets, not N.
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

/// Semi-axes of the ellipsoid.
const RADII: DVec3 = DVec3::new(1.0, 0.7, 0.5);
/// Support radius of every perturbation.
const SUPPORT: f64 = 0.08;

/// The centres of N perturbations: a Fibonacci lattice on the ellipsoid's surface.
fn centres(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|k| {
            let z = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * k as f64;
            RADII * DVec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// N perturbations at [`centres`], alternating bumps and dents.
fn scene(n: usize) -> PerturbedQuadric {
    let base = Quadric::ellipsoid(DVec3::ZERO, RADII);
    let mut pq = PerturbedQuadric::new(base);
    for (k, c) in centres(n).into_iter().enumerate() {
        let grad = base.gradient(c).length();
        let f = if k % 3 == 2 { -0.5 } else { 0.5 } * SUPPORT * grad;
        pq.push(f, Quadric::sphere(c, SUPPORT));
    }
    pq
}

/// The mean number of supports (balls of radius [`SUPPORT`]) a ray's path meets before
/// its first crossing, or before it leaves the box of the ellipsoid grown by a support.
fn met_per_ray(s: &PerturbedSurface, rays: &[Ray], n: usize) -> f64 {
    let c = centres(n);
    let reach = RADII + DVec3::splat(SUPPORT);
    let total: usize = rays
        .iter()
        .map(|ray| {
            let end = s
                .first_crossing(ray, 0.0, f64::INFINITY)
                .unwrap_or_else(|| {
                    // The far end of the ray's passage through the grown box (slab test).
                    let (a, b) = ((-reach - ray.o) / ray.d, (reach - ray.o) / ray.d);
                    a.max(b).min_element().max(0.0)
                });
            c.iter()
                .filter(|&&c| {
                    // The nearest point of the segment [0, end] to the centre.
                    let t = (c - ray.o).dot(ray.d).clamp(0.0, end);
                    ray.at(t).distance_squared(c) < SUPPORT * SUPPORT
                })
                .count()
        })
        .sum();
    total as f64 / rays.len() as f64
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
    // that other builds on the machine cannot disturb (valgrind; docs/benchmarks.md and
    // docs/notebook/2026-11-21-perturbed-quadrics-scaling.md).
    if let Ok(n) = std::env::var("PERTURBED_ONE_PASS") {
        let s = PerturbedSurface::new(&scene(n.parse().expect("a count")));
        let hits = rays
            .iter()
            .filter(|r| black_box(s.first_crossing(r, 0.0, f64::INFINITY)).is_some())
            .count();
        println!("{hits} hits");
        return;
    }
    println!(
        "perturbed ellipsoid, {SIZE}x{SIZE} primary rays, one thread, support radius {SUPPORT}"
    );
    println!(
        "{:>6} {:>8} {:>14} {:>8} {:>16} {:>9} {:>7}",
        "N", "hits", "BVH Mrays/s", "nodes", "unculled Mrays/s", "met/ray", "ns/met"
    );
    let mut first = None;
    for n in [1, 16, 256, 4096] {
        let pq = scene(n);
        let s = PerturbedSurface::new(&pq);
        let (rate, hits) = measure(&s, &rays);
        let met = met_per_ray(&s, &rays, n);
        let unculled = if n <= 256 {
            let (u, uh) = measure(&PerturbedSurface::unculled(&pq), &rays);
            assert_eq!(uh, hits, "culling changed the image");
            format!("{:16.3}", u / 1e6)
        } else {
            format!("{:>16}", "-")
        };
        let (base, base_met) = *first.get_or_insert((rate, met));
        // Time per ray beyond N = 1's, per support met beyond N = 1's.
        let per_met = if met > base_met {
            format!("{:7.1}", (1e9 / rate - 1e9 / base) / (met - base_met))
        } else {
            format!("{:>7}", "-")
        };
        println!(
            "{n:>6} {hits:>8} {:>14.3} {:>8} {unculled} {met:>9.2} {per_met}   (cost ×{:.2} vs N = 1)",
            rate / 1e6,
            s.bvh().nodes().len(),
            base / rate
        );
    }
}
