//! The perturbed-quadric kernel (GPU.md §6.1) against its CPU f32 twin, frep's
//! `first_crossing_f32_gpu`, bit for bit on lavapipe (GPU.md §3.5); the twin against
//! frep's f64 scan; and the kernel's loop budget (GPU.md §3.1, §9).
//!
//! Four surfaces, 4 096 fixed rays each: random rays from outside, rays grazing the
//! base surface, rays aimed at the rims of perturbation supports, and rays starting
//! inside the bounds; the overflow surface adds rays along a row of 3·K overlapping
//! supports (resolved by halving the range) and rays through a cluster of more than K
//! supports around one point (which no halving separates: reported as overflow); the
//! plane (an unbounded base, and a half-space perturbation, an unbounded BVH item) has
//! rays from t = −∞ and to ∞, which the scan cuts into Cauchy-bounded sub-pieces.

use crate::common;
use common::Rng;

use frep::{PerturbedQuadric, PerturbedSurface, Quadric, Ray};
use glam::{DVec3, Vec3};
use gpu::layout::LAYOUT_WGSL;
use gpu::perturbed::{first_crossing, Crossing, PerturbedPack, PERTURBED_WGSL};
use gpu::FLOAT_WGSL;
use gpu::{GpuOptions, Kernel};
use std::sync::OnceLock;

/// The shapes of random input this file's tests draw.
trait Inputs {
    fn unit(&mut self) -> DVec3;
}

impl Inputs for Rng {
    fn unit(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0;
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

/// One test surface: the solid, its base ellipsoid (centre, radii) and the supports'
/// spheres (centre, radius) for aiming at rims.
struct Case {
    name: &'static str,
    surface: PerturbedSurface,
    center: DVec3,
    radii: DVec3,
    supports: Vec<(DVec3, f64)>,
    /// Extra rays (o, d) particular to the case.
    extra: Vec<(DVec3, DVec3)>,
    /// An unbounded base (the plane y = 0, solid below): rays of their own.
    plane: bool,
}

fn case(
    name: &'static str,
    center: DVec3,
    radii: DVec3,
    perts: Vec<(f64, DVec3, f64)>,
    extra: Vec<(DVec3, DVec3)>,
) -> Case {
    let mut pq = PerturbedQuadric::new(Quadric::ellipsoid(center, radii));
    for &(f, c, r) in &perts {
        pq.push(f, Quadric::sphere(c, r));
    }
    Case {
        name,
        surface: pq.surface(),
        center,
        radii,
        supports: perts.iter().map(|&(_, c, r)| (c, r)).collect(),
        extra,
        plane: false,
    }
}

/// The plane y = 0 (solid below) with bumps and dents over [−2, 2]², and one
/// perturbation with an unbounded support (the half-space x ≤ −3: an unbounded BVH
/// item): the scan's unbounded pieces and Cauchy-bound sub-pieces.
fn plane_case(rng: &mut Rng) -> Case {
    let mut pq = PerturbedQuadric::new(Quadric::plane(DVec3::Y, 0.0));
    let mut supports = Vec::new();
    for _ in 0..40 {
        let c = DVec3::new(rng.range(-2.0, 2.0), 0.0, rng.range(-2.0, 2.0));
        let r = rng.range(0.2, 0.5);
        let sign = if rng.next() < 0.6 { 1.0 } else { -1.0 };
        pq.push(sign * r * rng.range(0.2, 1.0), Quadric::sphere(c, r));
        supports.push((c, r));
    }
    pq.push(-1e-3, Quadric::plane(DVec3::X, -3.0));
    Case {
        name: "plane, 40 bumps and dents and a half-space",
        surface: pq.surface(),
        center: DVec3::ZERO,
        radii: DVec3::splat(2.0),
        supports,
        extra: vec![],
        plane: true,
    }
}

/// Bumps (f > 0) and dents scattered over the base ellipsoid, f scaled by |∇F|·r so
/// that each moves the surface by a fraction of its radius (perturbed_march.rs).
fn scattered(rng: &mut Rng, radii: DVec3, count: usize, r: (f64, f64)) -> Vec<(f64, DVec3, f64)> {
    let base = Quadric::ellipsoid(DVec3::ZERO, radii);
    (0..count)
        .map(|_| {
            let c = radii * rng.unit();
            let r = rng.range(r.0, r.1);
            let sign = if rng.next() < 0.6 { 1.0 } else { -1.0 };
            let f = sign * base.gradient(c).length() * r * rng.range(0.1, 0.6);
            (f, c, r)
        })
        .collect()
}

fn cases() -> Vec<Case> {
    let mut rng = Rng(11);
    let sphere = DVec3::ONE;
    let few = vec![
        (0.8, DVec3::new(0.0, 1.0, 0.0), 0.4),
        (0.5, DVec3::new(1.0, 0.0, 0.0), 0.35),
        (1.2, DVec3::new(0.0, 0.0, 1.0), 0.5),
        (-0.7, DVec3::new(-1.0, 0.0, 0.0), 0.45),
        (-0.4, DVec3::new(0.0, -1.0, 0.0), 0.3),
        (-1.0, DVec3::new(0.6, 0.6, -0.53), 0.4),
    ];
    let radii = DVec3::new(1.0, 0.7, 0.5);
    let many = scattered(&mut rng, radii, 1000, (0.04, 0.12));
    // The overflow rod (perturbed_march.rs): a row of 3·K supports along the x axis,
    // pitch 0.046, radius 0.06, alternately hollowing and filling; and a cluster of
    // 40 > K supports of radius 0.2 around (0, 0.5, 0), on the rod's top.
    let k = frep::perturbed::GPU_ACTIVE;
    let count = 3 * k;
    let half = 0.023 * count as f64;
    let rod = DVec3::new(half + 0.3, 0.5, 0.5);
    let mut row: Vec<(f64, DVec3, f64)> = (0..count)
        .map(|i| {
            let x = -half + 2.0 * half * (i as f64 + 0.5) / count as f64;
            let f = if i % 2 == 0 { -2e3 } else { 2e3 };
            (f, DVec3::new(x, 0.01 * (i % 3) as f64, 0.0), 0.06)
        })
        .collect();
    let top = DVec3::new(0.0, 0.5, 0.0);
    for i in 0..40 {
        let f = if i % 2 == 0 { 3.0 } else { -2.0 };
        row.push((f, top + 0.01 * rng.unit(), 0.2));
    }
    let mut extra = Vec::new();
    for i in 0..256 {
        let tilt = 0.02 * (i as f64 / 256.0 - 0.5);
        let o = DVec3::new(-half - 0.6, 0.003 * (i % 5) as f64, tilt);
        extra.push((o, DVec3::new(1.0, tilt * 0.1, -tilt * 0.2).normalize()));
        let o = top
            + DVec3::new(
                0.05 * rng.range(-1.0, 1.0),
                1.5,
                0.05 * rng.range(-1.0, 1.0),
            );
        extra.push((o, (top + 0.05 * rng.unit() - o).normalize()));
    }
    vec![
        case(
            "sphere, 6 bumps and dents",
            DVec3::ZERO,
            sphere,
            few,
            vec![],
        ),
        case(
            "ellipsoid, 1 000 bumps and dents",
            DVec3::ZERO,
            radii,
            many,
            vec![],
        ),
        case(
            "rod, 96 in a row and 40 in a cluster",
            DVec3::ZERO,
            rod,
            row,
            extra,
        ),
        plane_case(&mut rng),
    ]
}

/// A ray: origin, direction, t_min, t_max (f32, as the kernel reads them).
type TestRay = [f32; 8];

fn ray(o: DVec3, d: DVec3, t_min: f32, t_max: f32) -> TestRay {
    let (o, d) = (o.as_vec3(), d.as_vec3());
    [o.x, o.y, o.z, d.x, d.y, d.z, t_min, t_max]
}

/// 4 096 rays for `c` (the case's extra rays replace as many of the random ones).
fn rays(c: &Case, seed: u64) -> Vec<TestRay> {
    const N: usize = 4096;
    let mut rng = Rng(seed);
    let size = c.radii.max_element();
    let on_base = |u: DVec3| c.center + c.radii * u;
    let normal = |p: DVec3| ((p - c.center) / (c.radii * c.radii)).normalize();
    let mut out: Vec<TestRay> = c
        .extra
        .iter()
        .map(|&(o, d)| ray(o, d, 0.0, f32::INFINITY))
        .collect();
    let n0 = out.len();
    if c.plane {
        // From above and below, aimed at the bumps or anywhere; t from 0 or from −∞
        // (left-unbounded pieces), to ∞ (right-unbounded ones) or 8.
        for i in 0..N {
            let o = DVec3::new(
                rng.range(-4.0, 4.0),
                rng.range(-1.0, 2.0),
                rng.range(-4.0, 4.0),
            );
            let d = if i % 2 == 0 {
                let (sc, sr) = c.supports[(rng.next() * c.supports.len() as f64) as usize];
                (sc + sr * rng.unit() - o).normalize()
            } else {
                rng.unit()
            };
            let t_min = if i % 3 == 0 { f32::NEG_INFINITY } else { 0.0 };
            let t_max = if i % 5 == 0 { 8.0 } else { f32::INFINITY };
            out.push(ray(o, d, t_min, t_max));
        }
        return out;
    }
    for i in n0..N {
        let t_max = if i % 7 == 0 {
            2.5 * size as f32
        } else {
            f32::INFINITY
        };
        let r = match i % 4 {
            // Random, from outside towards the object.
            0 => {
                let o = c.center + 3.0 * size * rng.unit();
                let aim = c.center + c.radii * rng.unit() * rng.next();
                ray(o, (aim - o).normalize(), 0.0, t_max)
            }
            // Grazing the base surface, up to 1e-3·size off it either way.
            1 => {
                let p = on_base(rng.unit());
                let n = normal(p);
                let t = n.cross(rng.unit()).normalize();
                let p = p + n * size * 1e-3 * rng.range(-1.0, 1.0);
                ray(p - 2.0 * size * t, t, 0.0, t_max)
            }
            // Through the rim of a support, where a breakpoint meets the surface.
            2 => {
                let (sc, sr) = c.supports[(rng.next() * c.supports.len() as f64) as usize];
                let aim = sc + sr * rng.unit();
                let o = aim + 2.0 * size * rng.unit();
                ray(o, (aim - o).normalize(), 0.0, t_max)
            }
            // From inside the bounds, t_min sometimes negative.
            _ => {
                let o = c.center + c.radii * 1.1 * rng.unit() * rng.next();
                let t_min = if i % 3 == 0 { -0.5 } else { 0.0 };
                ray(o, rng.unit(), t_min, t_max)
            }
        };
        out.push(r);
    }
    out
}

/// The kernel's results for one case: per ray (crossing, loop iterations).
struct GpuRun {
    rays: Vec<TestRay>,
    results: Vec<(Crossing, u32)>,
}

fn kernel_source() -> String {
    format!(
        "{LAYOUT_WGSL}
@group(0) @binding(0) var<storage, read> objects: array<GpuObject>;
@group(0) @binding(1) var<storage, read> quadrics: array<GpuQuadric>;
@group(0) @binding(2) var<storage, read> perturbations: array<GpuPerturbation>;
@group(0) @binding(3) var<storage, read> nodes: array<GpuBvhNode>;
@group(0) @binding(4) var<storage, read> items: array<GpuItemBox>;
@group(0) @binding(5) var<storage, read> rays: array<f32>;
@group(0) @binding(6) var<storage, read_write> out: array<u32>;
{FLOAT_WGSL}
{PERTURBED_WGSL}
@compute @workgroup_size(64)
fn trace(@builtin(global_invocation_id) id: vec3<u32>) {{
    let i = id.x;
    if (8u * i >= arrayLength(&rays)) {{ return; }}
    let r = 8u * i;
    loops = 0u;
    let o = vec3<f32>(rays[r], rays[r + 1u], rays[r + 2u]);
    let d = vec3<f32>(rays[r + 3u], rays[r + 4u], rays[r + 5u]);
    let h = perturbed_first_crossing(0u, o, d, rays[r + 6u], rays[r + 7u]);
    out[3u * i] = bitcast<u32>(h.t);
    out[3u * i + 1u] = h.status;
    out[3u * i + 2u] = loops;
}}
"
    )
}

/// Every case through the kernel, once per test binary (None without an adapter).
fn gpu_runs() -> &'static Option<Vec<GpuRun>> {
    static RUNS: OnceLock<Option<Vec<GpuRun>>> = OnceLock::new();
    RUNS.get_or_init(|| {
        let g = common::gpu(GpuOptions::default())?;
        // SAFETY: every index of the kernel is bounded by its capacities (K actives, 2·K
        // breaks, MAX_DEPTH + 1 frames, MAX_SPLITS pending chunks, degree ≤ 6) and every
        // loop by a count or a strictly shrinking interval.
        let k = unsafe { Kernel::new_unchecked(&g, &kernel_source(), "trace", 6) }.unwrap();
        let runs = cases()
            .iter()
            .enumerate()
            .map(|(ci, c)| {
                let pack = PerturbedPack::new(&c.surface.view());
                let rs = rays(c, 100 + ci as u64);
                let r_words: Vec<u32> = rs.iter().flatten().map(|f| f.to_bits()).collect();
                let start = std::time::Instant::now();
                let out = k
                    .run(
                        &g,
                        &[
                            bytemuck::cast_slice(std::slice::from_ref(&pack.object)),
                            bytemuck::cast_slice(&pack.quadrics),
                            bytemuck::cast_slice(&pack.perturbations),
                            bytemuck::cast_slice(&pack.nodes),
                            bytemuck::cast_slice(&pack.items),
                            &r_words,
                        ],
                        3 * rs.len(),
                        [(rs.len() as u32).div_ceil(64), 1, 1],
                    )
                    .unwrap();
                eprintln!("{}: {} rays in {:?}", c.name, rs.len(), start.elapsed());
                let results = (0..rs.len())
                    .map(|i| {
                        (
                            Crossing::from_kernel(out[3 * i + 1], out[3 * i]),
                            out[3 * i + 2],
                        )
                    })
                    .collect();
                GpuRun { rays: rs, results }
            })
            .collect();
        Some(runs)
    })
}

fn twin(c: &Case, r: &TestRay) -> Crossing {
    first_crossing(
        &c.surface.view(),
        Vec3::new(r[0], r[1], r[2]),
        Vec3::new(r[3], r[4], r[5]),
        r[6],
        r[7],
    )
}

/// Bit for bit: every ray's t (or miss, or overflow) from the kernel is the twin's.
#[test]
fn perturbed_kernel_equals_its_twin_bit_for_bit() {
    let Some(runs) = gpu_runs() else {
        return;
    };
    for (c, run) in cases().iter().zip(runs) {
        let (mut hits, mut misses, mut overflows) = (0, 0, 0);
        let mut differ = Vec::new();
        for (i, (r, &(gpu, _))) in run.rays.iter().zip(&run.results).enumerate() {
            let cpu = twin(c, r);
            let same = match (gpu, cpu) {
                (Crossing::Hit(a), Crossing::Hit(b)) => a.to_bits() == b.to_bits(),
                (a, b) => a == b,
            };
            if !same {
                differ.push(format!("ray {i} {r:?}: gpu {gpu:?}, cpu {cpu:?}"));
            }
            match cpu {
                Crossing::Hit(_) => hits += 1,
                Crossing::Miss => misses += 1,
                Crossing::Overflow => overflows += 1,
            }
        }
        println!(
            "{}: {} of {} identical ({hits} hits, {misses} misses, {overflows} overflows)",
            c.name,
            run.rays.len() - differ.len(),
            run.rays.len()
        );
        assert!(
            differ.is_empty(),
            "{}: {} differ:\n{}",
            c.name,
            differ.len(),
            differ[..differ.len().min(10)].join("\n")
        );
        if c.name.starts_with("rod") {
            // Rays along the row (even) meet more than K supports and are resolved by
            // halving; rays through the cluster (odd) overflow however they are halved.
            let k = frep::perturbed::GPU_ACTIVE;
            let (mut crowded, mut row_overflows, mut cluster_overflows) = (0, 0, 0);
            let mut hits_behind_overflow = 0;
            for (i, &(gpu, _)) in run.results[..c.extra.len()].iter().enumerate() {
                let r = &run.rays[i];
                let inv = [r[3], r[4], r[5]].map(|x| 1.0 / x);
                let mut met = 0;
                let o = [r[0], r[1], r[2]];
                c.surface
                    .view()
                    .bvh
                    .for_each_hit_f32(o, inv, 0.0, 10.0, |_| met += 1);
                let over = gpu == Crossing::Overflow;
                if i % 2 == 0 {
                    crowded += usize::from(met > k);
                    row_overflows += usize::from(over);
                } else {
                    cluster_overflows += usize::from(over);
                    // What the CPU finds by streaming where the kernel reports overflow:
                    // reading overflow as a miss would lose these hits.
                    let (o, d) = (Vec3::new(r[0], r[1], r[2]), Vec3::new(r[3], r[4], r[5]));
                    let streamed = c.surface.first_crossing_f32(o, d, r[6], r[7]);
                    hits_behind_overflow += usize::from(over && streamed.is_some());
                }
            }
            println!(
                "  row rays: {crowded} meet > K supports, {row_overflows} overflow; \
                 cluster rays: {cluster_overflows} overflow, {hits_behind_overflow} of them \
                 hits for the CPU's streaming"
            );
            assert!(crowded > 200 && row_overflows == 0 && cluster_overflows > 100);
            assert!(hits_behind_overflow > 100);
        }
        assert!(
            hits > 100 && misses > 100,
            "{}: {hits} hits, {misses} misses",
            c.name
        );
    }
}

/// The loop budget (GPU.md §3.1, §9): no invocation runs 30 000 loop iterations, far
/// from llvmpipe's silent cut at 65 535.
#[test]
fn perturbed_kernel_stays_within_the_loop_budget() {
    let Some(runs) = gpu_runs() else {
        return;
    };
    for (c, run) in cases().iter().zip(runs) {
        let loops: Vec<u32> = run.results.iter().map(|r| r.1).collect();
        let max = *loops.iter().max().unwrap();
        let mean = loops.iter().map(|&l| l as f64).sum::<f64>() / loops.len() as f64;
        println!(
            "{}: loop iterations per ray: max {max}, mean {mean:.0}",
            c.name
        );
        assert!(max > 0 && max < 30_000, "{}: {max}", c.name);
    }
}

/// Σ |c_k|·|m_k(p)| over a quadric's monomials: the magnitude its evaluation rounds
/// against.
fn magnitude(q: &Quadric, p: DVec3) -> f64 {
    let [x, y, z] = p.abs().to_array();
    let m = [x * x, y * y, z * z, x * y, y * z, x * z, x, y, z, 1.0];
    q.c.iter().zip(m).map(|(c, m)| c.abs() * m).sum()
}

/// The largest |F'| inside (a, b) (63 samples, f64; an end may be a piece boundary, where
/// a perturbation's term starts) in units of ε₃₂·M(p), M the magnitude the
/// f32 scan rounds F' against (Poly::add_cube_error, pointwise): the base's terms plus,
/// per perturbation acting at p, |f|·(q³ + 3·q_max²·mag(q)), q_max the largest q on the
/// ray (a piece's bound uses q's largest value over the piece). A sign change of F'
/// where this stays small lies within the f32 scan's rounding bound: a near-tangent ray.
fn relative_peak(view: &frep::PerturbedView, ray: &Ray, a: f64, b: f64) -> f64 {
    let q_max: Vec<f64> = view
        .perturbations
        .iter()
        .map(|pt| {
            let [a0, a1, a2] = pt.q.along(ray.o, ray.d);
            if a2 < 0.0 {
                (a0 - a1 * a1 / (4.0 * a2)).max(0.0)
            } else {
                f64::INFINITY
            }
        })
        .collect();
    (1..64)
        .map(|k| {
            let p = ray.at(a + (b - a) * k as f64 / 64.0);
            let mut m = magnitude(view.base, p);
            for (pt, &qm) in view.perturbations.iter().zip(&q_max) {
                let q = pt.q.eval(p);
                if q > 0.0 {
                    m += pt.f.abs() * (q * q * q + 3.0 * qm * qm * magnitude(&pt.q, p));
                }
            }
            view.value(p).abs() / (f64::from(f32::EPSILON) * m)
        })
        .fold(0.0, f64::max)
}

/// The twin (hence the kernel, equal to it bit for bit) against frep's f64 scan on the
/// same rays (o, d, t_min, t_max widened exactly to f64), rays reported as overflowing
/// left out. Asserted: the same hit or miss, and |Δt| ≤ 1e-4 × max(size, |t|) (f32
/// resolves t relative to |t|: the plane's rays from −∞ meet it up to 10⁴ units away),
/// except on near-tangent rays, those where |F'| stays within 2·10³·ε₃₂·M (2.4e-4 of M)
/// where the two disagree (M as in [`relative_peak`]): from the f64 crossing to the
/// next (at most to the f32 one) where the f32 scan answers later or misses, from the
/// f32 crossing to its next (at most to the f64 one) where it answers earlier or alone.
/// The f32 scan only counts signs beyond its rounding bound, 32·ε₃₂ times the piece's
/// coefficient magnitudes in Bernstein form, which exceed M by the growth of the power
/// form over a piece. Measured (these rays): sphere 8 flips, 13 near-tangent rays in all
/// (largest |F'| 3.4e2 ε₃₂·M), other |Δt| ≤ 2.1e-5 × max(size, |t|) over 3 292 hits;
/// ellipsoid 2 flips, 24 near-tangent (1.3e2), other |Δt| ≤ 9.4e-5 × … over 3 864; rod
/// 2 flips, 8 near-tangent (1.3e2), ≤ 7.2e-6 × … over 3 095; plane 3 flips, 9
/// near-tangent (1.4e2), ≤ 8.2e-5 × … over 3 379. The flips are rays grazing the base
/// surface within 1e-3 of its size.
#[test]
fn twin_agrees_with_the_f64_scan() {
    for (ci, c) in cases().iter().enumerate() {
        let view = c.surface.view();
        let size = c.radii.max_element();
        let (mut hits, mut flips, mut overflows, mut near, mut far) = (0, 0, 0, 0, 0);
        let mut from_infinity = 0;
        let (mut max_dt, mut max_peak) = (0.0f64, 0.0f64);
        for r in rays(c, 100 + ci as u64) {
            let ray = Ray::new(
                DVec3::new(r[0].into(), r[1].into(), r[2].into()),
                DVec3::new(r[3].into(), r[4].into(), r[5].into()),
            );
            let t64 = view.first_crossing(&ray, r[6].into(), r[7].into());
            let t32 = twin(c, &r);
            // t to f32 accuracy: |Δt| scales with |t| where that exceeds the size (the
            // plane's rays from −∞ meet it thousands of units away).
            let scale = t64.map_or(size, |t| t.abs().max(size));
            if t64.is_some_and(|t| t.abs() > 10.0 * size) {
                far += 1;
            }
            if r[6] == f32::NEG_INFINITY {
                from_infinity += 1;
            }
            // The f64 sliver [t, next crossing] the f32 scan skipped when it answers
            // later, or the f32 sliver when it answers earlier.
            let next64 = |t: f64| view.first_crossing(&ray, t, f64::INFINITY).unwrap_or(t);
            let next32 = |t: f32| match twin(c, &[r[0], r[1], r[2], r[3], r[4], r[5], t, r[7]]) {
                Crossing::Hit(n) => f64::from(n),
                _ => f64::from(t),
            };
            let (a, b, dt) = match (t32, t64) {
                (Crossing::Overflow, _) => {
                    overflows += 1;
                    continue;
                }
                (Crossing::Miss, None) => continue,
                (Crossing::Hit(a), Some(b)) => {
                    hits += 1;
                    let dt = (f64::from(a) - b).abs();
                    if f64::from(a) > b {
                        (b, next64(b).min(f64::from(a)), dt)
                    } else {
                        (f64::from(a), next32(a).min(b), dt)
                    }
                }
                (Crossing::Miss, Some(b)) => {
                    flips += 1;
                    (b, next64(b), f64::INFINITY)
                }
                (Crossing::Hit(a), None) => {
                    flips += 1;
                    (f64::from(a), next32(a), f64::INFINITY)
                }
            };
            if dt <= 1e-4 * scale {
                max_dt = max_dt.max(dt / scale);
                continue;
            }
            let peak = relative_peak(&view, &ray, a, b);
            max_peak = max_peak.max(peak);
            near += 1;
            assert!(
                peak <= 2e3,
                "{}: {r:?}: f32 {t32:?}, f64 {t64:?}; |F'| up to {peak:e} ε₃₂·M between",
                c.name
            );
        }
        println!(
            "{}: {hits} hits ({far} beyond 10 × the size; {from_infinity} rays from −∞), {flips} \
             flips, {overflows} overflows; {near} near-tangent (largest |F'| between \
             {max_peak:.2e} ε₃₂·M); other |Δt| ≤ {max_dt:.2e} × max(size, |t|)",
            c.name,
        );
        assert!(hits > 1000, "{hits}");
    }
}
