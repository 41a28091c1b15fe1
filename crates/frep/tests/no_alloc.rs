//! No allocation per ray: a counting global allocator (this test binary only) watches a
//! batch of rays through a perturbed quadric with many perturbations, expression solids
//! read from models/ (one large enough for per-segment tape simplification, one whose
//! polynomial parts fold into leaves along rays), Fidget's
//! tanglecube (a quartic, searched in Bernstein form) and a CSG of both kinds. After one warm-up batch (different rays) has grown each thread's scratch,
//! intersecting, testing inside and taking normals must not allocate at all.

use frep::perturbed::PerturbedQuadric;
use frep::quadric::Quadric;
use frep::read::read_file;
use frep::{Ray, Shape, Solid, Surface};
use glam::DVec3;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Counts allocations made by threads that have switched counting on.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static COUNT_HERE: Cell<bool> = const { Cell::new(false) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNT_HERE.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNT_HERE.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by this thread while running `f`.
fn allocations(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    COUNT_HERE.with(|c| c.set(true));
    f();
    COUNT_HERE.with(|c| c.set(false));
    ALLOCATIONS.load(Ordering::Relaxed) - before
}

fn model(path: &str) -> Shape {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path);
    read_file(&p).unwrap_or_else(|e| panic!("{e}")).shape
}

/// An ellipsoid with `n` bumps and dents on a Fibonacci lattice (as the benchmark).
fn bumpy(n: usize) -> PerturbedQuadric {
    let radii = DVec3::new(1.0, 0.7, 0.5);
    let base = Quadric::ellipsoid(DVec3::ZERO, radii);
    let mut pq = PerturbedQuadric::new(base);
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    for k in 0..n {
        let z = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let c = radii
            * DVec3::new(
                r * (golden * k as f64).cos(),
                r * (golden * k as f64).sin(),
                z,
            );
        let f = if k % 3 == 2 { -0.5 } else { 0.5 } * 0.08 * base.gradient(c).length();
        pq.push(f, Quadric::sphere(c, 0.08));
    }
    pq
}

/// A rod with a row of 3 × MAX_ACTIVE overlapping perturbations along its axis: rays
/// along it overflow the scan's fixed active set (chunks, then streaming).
fn rod() -> PerturbedQuadric {
    let n = 3 * frep::perturbed::MAX_ACTIVE;
    let half = 0.023 * n as f64;
    let radii = DVec3::new(half + 0.3, 0.5, 0.5);
    let mut pq = PerturbedQuadric::new(Quadric::ellipsoid(DVec3::ZERO, radii));
    for k in 0..n {
        let x = -half + 2.0 * half * (k as f64 + 0.5) / n as f64;
        let f = if k % 2 == 0 { -2e3 } else { 2e3 };
        pq.push(f, Quadric::sphere(DVec3::new(x, 0.0, 0.0), 0.06));
    }
    pq
}

/// `side`² rays from a pinhole at `eye` towards the solid's bounds, jittered by `shift`.
fn rays(s: &Solid, eye: DVec3, side: usize, shift: f64) -> Vec<Ray> {
    let b = s.bounds();
    let (c, r) = (b.center(), 0.5 * b.extent().length());
    let fwd = (c - eye).normalize();
    let right = fwd.cross(DVec3::Z).normalize();
    let up = right.cross(fwd);
    let half = r / (c - eye).length();
    let mut out = Vec::with_capacity(side * side);
    for j in 0..side {
        for i in 0..side {
            let x = ((i as f64 + shift) / side as f64 * 2.0 - 1.0) * half;
            let y = ((j as f64 + shift) / side as f64 * 2.0 - 1.0) * half;
            out.push(Ray::new(eye, fwd + x * right + y * up));
        }
    }
    out
}

#[test]
fn a_batch_of_rays_allocates_nothing() {
    // The counter sees what this thread allocates.
    assert_eq!(allocations(|| drop(std::hint::black_box(vec![1u8; 10]))), 1);
    let bumps = Shape::Perturbed(bumpy(1024));
    let blob = model("models/examples/smooth_blob.frep");
    let gyroid = model("models/canonical/s4_gyroid.hf");
    let csg = Shape::Difference(
        Box::new(Shape::Union(vec![bumps.clone(), gyroid.clone()])),
        Box::new(Shape::Transformed(
            frep::Affine::translate(DVec3::new(0.5, 0.0, 0.0)),
            Box::new(blob.clone()),
        )),
    );
    let eye = DVec3::new(0.6, -3.0, 1.2);
    for (name, shape) in [
        ("perturbed", bumps),
        ("blob", blob),
        ("gyroid", gyroid),
        ("csg", csg),
        // A quartic, searched in Bernstein form (frep::poly_trace).
        ("tanglecube", model("models/fidget/tanglecube.vm")),
    ] {
        let s = Solid::build(&shape).unwrap();
        let trace = |rays: &[Ray]| {
            let mut hits = 0;
            for ray in rays {
                if let Some(h) = s.intersect(ray, 0.0, f64::INFINITY) {
                    hits += 1;
                    // Walk on to the next crossing, and ask inside / value there too.
                    let p = ray.at(h.t);
                    std::hint::black_box((s.inside(p), s.normal(p)));
                    std::hint::black_box(s.intersect(ray, h.t + 1e-6, f64::INFINITY));
                }
            }
            hits
        };
        trace(&rays(&s, eye, 24, 0.25));
        let batch = rays(&s, eye, 40, 0.5);
        let mut hits = 0;
        let n = allocations(|| hits = trace(&batch));
        println!("{name}: {} rays, {hits} hits, {n} allocations", batch.len());
        assert!(batch.len() >= 1000 && hits > 100, "{name}: {hits} hits");
        assert_eq!(
            n,
            0,
            "{name}: {n} allocations in a batch of {} rays",
            batch.len()
        );
    }
    // Along the rod: every ray meets more perturbations than the active set holds.
    let s = Solid::build(&Shape::Perturbed(rod())).unwrap();
    let along = |k: usize, side: usize| {
        let (i, j) = (k % side, k / side);
        let off = |u: usize| 0.02 * (u as f64 / side as f64 - 0.5);
        Ray::new(
            DVec3::new(-2.8, off(i), off(j)),
            DVec3::new(1.0, 0.001, 0.0),
        )
    };
    let walk = |ray: &Ray| {
        let (mut t, mut n) = (0.0, 0);
        while let Some(h) = s.intersect(ray, t, f64::INFINITY) {
            t = h.t;
            n += 1;
        }
        n
    };
    (0..100).for_each(|k| {
        walk(&along(k, 10));
    });
    let mut crossings = 0;
    let n = allocations(|| crossings = (0..1024).map(|k| walk(&along(k, 32))).sum::<usize>());
    println!("rod: 1024 walks, {crossings} crossings, {n} allocations");
    assert!(
        crossings > 1024 * 2 * frep::perturbed::MAX_ACTIVE,
        "{crossings}"
    );
    assert_eq!(n, 0, "rod: {n} allocations");
}
