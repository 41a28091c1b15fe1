//! The expression-tape kernels (GPU.md §6.2) against their CPU f32 twins, bit for bit on
//! lavapipe (GPU.md §3.5), and the twins against frep: point values equal to
//! `Bytecode::eval_f32`, intervals holding the point values, rays against frep's f64
//! interval tracer; and the tracer's loop budget (GPU.md §3.1, §9).
//!
//! Models: shipped ones (tanglecube.vm, s2_csg.hf, s3_blend.hf, bumpy_ball.frep,
//! machined_part.frep, table.frep: thin plates and legs; s4_gyroid.hf, s5_twist.hf and
//! smooth_blob.frep with sin, cos and atan2; lattice.frep with mod, exp and log;
//! capsule.hf, whose `if` on z becomes compare, and, or and not; superellipsoid.hf,
//! fractional powers as exp and log), and [`ELEMENTARY_BALL`]
//! with tan, asin, acos, atan, floor, ceil, round and x²⁰.

use crate::common;
use common::Rng;

use frep::bytecode::Bytecode;
use frep::expr::eval_nodes;
use frep::read::{read_file, read_str, Format};
use frep::{Aabb, Dual, Expr, ExprSurface, Node, Ray};
use glam::{DVec3, Vec3};
use gpu::tape::GpuTape;
use gpu::tape_trace::{TapeHit, TapeSolid, Traced, BUDGET};
use gpu::{Gpu, GpuOptions, Kernel};
use std::path::PathBuf;
use std::time::Instant;

/// The shapes of random input this file's tests draw.
trait Inputs {
    fn unit(&mut self) -> DVec3;
    fn in_box(&mut self, b: &Aabb) -> DVec3;
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
    fn in_box(&mut self, b: &Aabb) -> DVec3 {
        DVec3::new(
            self.range(b.lo.x, b.hi.x),
            self.range(b.lo.y, b.hi.y),
            self.range(b.lo.z, b.hi.z),
        )
    }
}

struct Model {
    name: &'static str,
    expr: Expr,
    bounds: Aabb,
    /// Whether it has operations the twin computes its own way, not libm's: sin, cos,
    /// atan2, exp, ln, tan, asin, acos, atan (polynomials) and mod (from a rounded
    /// quotient).
    polynomial: bool,
}

/// A ball wobbled by tan, asin, acos and atan, with triangle waves made of round,
/// floor and ceil (continuous, their steps cancelled by abs), and a steep x²⁰ term.
const ELEMENTARY_BALL: &str = "
let r2 = x^2 + y^2 + z^2
let tri(t) = abs(t - round(t)) + abs(t - floor(t) - 0.5) + abs(ceil(t) - t - 0.5)
let wobble = 0.03 * atan(4 * z) + 0.02 * asin(0.9 * cos(3 * y)) + 0.02 * acos(0.9 * sin(3 * x)) + 0.02 * tan(0.5 * z)
bounds([-1.3, -1.3, -1.3], [1.3, 1.3, 1.3])
output 1 - r2 + wobble + 0.05 * tri(3 * x) - 0.2 * (0.8 * x)^20
";

fn models() -> Vec<Model> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let files: [(&str, PathBuf, f64); 12] = [
        ("tanglecube", root.join("models/fidget/tanglecube.vm"), 5.0),
        ("s2_csg", root.join("models/canonical/s2_csg.hf"), 1.6),
        ("s3_blend", root.join("models/canonical/s3_blend.hf"), 1.6),
        (
            "bumpy_ball",
            root.join("models/examples/bumpy_ball.frep"),
            2.0,
        ),
        (
            "machined_part",
            root.join("models/examples/machined_part.frep"),
            2.0,
        ),
        ("table", root.join("scenes/models/table.frep"), 2.0),
        ("s4_gyroid", root.join("models/canonical/s4_gyroid.hf"), 1.6),
        ("s5_twist", root.join("models/canonical/s5_twist.hf"), 1.6),
        (
            "smooth_blob",
            root.join("models/examples/smooth_blob.frep"),
            2.0,
        ),
        ("lattice", root.join("models/examples/lattice.frep"), 1.2),
        ("capsule", root.join("models/examples/capsule.hf"), 1.5),
        (
            "superellipsoid",
            root.join("models/examples/superellipsoid.hf"),
            1.5,
        ),
    ];
    let elementary = ("elementary", PathBuf::new(), 1.3);
    files
        .into_iter()
        .chain([elementary])
        .map(|(name, path, r)| {
            let m = if name == "elementary" {
                read_str(ELEMENTARY_BALL, Format::Frep, "elementary.frep").unwrap()
            } else {
                read_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
            };
            let expr = Expr::new(&m.shape.to_tree().expect("a regular shape"));
            let domain = m
                .domain
                .unwrap_or(Aabb::new(DVec3::splat(-r), DVec3::splat(r)));
            let bounds = frep::bounds::expr_bounds(&expr, domain);
            assert!(!bounds.is_empty() && bounds.is_finite(), "{name}");
            let polynomial = matches!(
                name,
                "s4_gyroid"
                    | "s5_twist"
                    | "smooth_blob"
                    | "lattice"
                    | "superellipsoid"
                    | "elementary"
            );
            Model {
                name,
                expr,
                bounds,
                polynomial,
            }
        })
        .collect()
}

fn tape(m: &Model) -> GpuTape {
    GpuTape::new(&Bytecode::compile(&m.expr).unwrap()).unwrap()
}

/// The interpreter's points and boxes, point or box i after `use_tape(which[i])`, over
/// [`TapeSolid::scene_wgsl`]: the source the render kernels use, one compiled kernel for
/// every model (compiling one per model took most of these tests' time on lavapipe).
fn interp_source(solids: &[TapeSolid]) -> String {
    format!(
        "@group(0) @binding(0) var<storage, read> tape: array<u32>;
@group(0) @binding(1) var<storage, read> input: array<f32>;
@group(0) @binding(2) var<storage, read> which: array<u32>;
@group(0) @binding(3) var<storage, read_write> out: array<u32>;
{}
@compute @workgroup_size(64)
fn points(@builtin(global_invocation_id) id: vec3<u32>) {{
    let i = id.x;
    if (3u * i >= arrayLength(&input)) {{ return; }}
    use_tape(which[i]);
    let f = eval_point(vec3<f32>(input[3u * i], input[3u * i + 1u], input[3u * i + 2u]));
    out[i] = bitcast<u32>(f);
}}
@compute @workgroup_size(64)
fn boxes(@builtin(global_invocation_id) id: vec3<u32>) {{
    let i = id.x;
    if (9u * i >= arrayLength(&input)) {{ return; }}
    let r = 9u * i;
    use_tape(which[i]);
    let x = vec4<f32>(input[r], input[r + 3u], input[r + 6u], input[r + 6u]);
    let y = vec4<f32>(input[r + 1u], input[r + 4u], input[r + 7u], input[r + 7u]);
    let z = vec4<f32>(input[r + 2u], input[r + 5u], input[r + 8u], input[r + 8u]);
    let v = eval_interval(x, y, z);
    for (var k = 0u; k < 4u; k++) {{ out[4u * i + k] = bitcast<u32>(v[k]); }}
}}
",
        TapeSolid::scene_wgsl(solids)
    )
}

fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// A box (lo, hi) with a direction d for dF/dt.
type TestBox = (Vec3, Vec3, Vec3);

/// Per model: 4 096 random points in the bounds and 4 096 boxes of four size classes
/// (0.3 to 1e-6 of the diagonal) with random directions.
fn samples(m: &Model, rng: &mut Rng) -> (Vec<[f32; 3]>, Vec<TestBox>) {
    let n = 4096;
    let pts = (0..n)
        .map(|_| rng.in_box(&m.bounds).as_vec3().into())
        .collect();
    let diag = m.bounds.extent().length();
    let boxes = (0..n)
        .map(|k| {
            let half = diag * [0.3, 0.03, 1e-3, 1e-6][k % 4] * rng.next();
            let c = rng.in_box(&m.bounds);
            let h = DVec3::new(rng.next(), rng.next(), rng.next()) * half;
            ((c - h).as_vec3(), (c + h).as_vec3(), rng.unit().as_vec3())
        })
        .collect();
    (pts, boxes)
}

fn box_interval(t: &GpuTape, &(lo, hi, d): &TestBox) -> [f32; 4] {
    let c = |k: usize| [lo[k], hi[k], d[k], d[k]];
    t.eval_interval(c(0), c(1), c(2))
}

/// F's tape with its constants rounded to f32, as the twin holds them: the function
/// whose derivative the twin's intervals enclose. (F's own derivative differs by the
/// constants' rounding, which an exact bound, such as a completed square's at a box
/// corner, does not cover.)
fn f32_constants(e: &Expr) -> Vec<Node> {
    e.nodes()
        .iter()
        .map(|n| match *n {
            Node::Const(b) => Node::Const(f64::from(f64::from_bits(b) as f32).to_bits()),
            n => n,
        })
        .collect()
}

/// ∇F at p in f64 by `nodes`.
fn gradient(nodes: &[Node], p: [f64; 3], scratch: &mut Vec<Dual<f64, 3>>) -> [f64; 3] {
    let v = |k: usize| Dual::<f64, 3>::var(p[k], k);
    eval_nodes(nodes, v(0), v(1), v(2), scratch).d
}

/// The twins without a GPU: point values equal `Bytecode::eval_f32` bit for bit, and every
/// f32 point value in a box (its 8 corners and 8 random points) lies in the box's
/// interval, as does the directional derivative dF/dt there (in f64, of F with the
/// twin's f32 constants).
#[test]
fn twin_equals_eval_f32_and_is_sound() {
    let mut rng = Rng(7);
    for m in models() {
        let t = tape(&m);
        let code = Bytecode::compile(&m.expr).unwrap();
        let (pts, boxes) = samples(&m, &mut rng);
        for p in &pts {
            let (twin, want) = (t.eval_point(*p), code.eval_f32(*p));
            // sin, cos, atan2, exp, ln, tan, asin, acos, atan are polynomials within a
            // few ulps of libm's.
            let close = m.polynomial && (twin - want).abs() <= 1e-5 * (1.0 + want.abs());
            assert!(
                same(twin, want) || close,
                "{}: at {p:?} twin {twin}, eval_f32 {want}",
                m.name
            );
        }
        let (mut values, mut derivs) = (0, 0);
        let (nodes32, mut duals) = (f32_constants(&m.expr), Vec::new());
        for b in &boxes {
            let (lo, hi, d) = *b;
            let iv = box_interval(&t, b);
            for j in 0..16 {
                let p: [f32; 3] = match j {
                    0..8 => [0, 1, 2].map(|k| if j >> k & 1 == 0 { lo[k] } else { hi[k] }),
                    _ => [0, 1, 2].map(|k| rng.range(lo[k] as f64, hi[k] as f64) as f32),
                };
                let v = t.eval_point(p);
                if !v.is_nan() && !iv[0].is_nan() {
                    assert!(
                        iv[0] <= v && v <= iv[1],
                        "{}: {v} at {p:?} outside {iv:?}",
                        m.name
                    );
                    values += 1;
                }
                let grad = gradient(&nodes32, p.map(f64::from), &mut duals);
                let dv = grad[0] * d.x as f64 + grad[1] * d.y as f64 + grad[2] * d.z as f64;
                if dv.is_finite() && !iv[2].is_nan() {
                    assert!(
                        iv[2] as f64 <= dv && dv <= iv[3] as f64,
                        "{}: dF/dt {dv} at {p:?} outside {iv:?}",
                        m.name
                    );
                    derivs += 1;
                }
            }
        }
        eprintln!(
            "{}: {} ops; {} points equal to eval_f32 (within 10⁻⁵ where polynomial); {values} values and {derivs} derivatives inside their intervals",
            m.name,
            t.len(),
            pts.len()
        );
    }
}

/// Points and boxes through the kernels, every model in one kernel: bit for bit the
/// twin's (all four interval bounds).
#[test]
fn interpreter_matches_its_twin() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let models = models();
    let solids: Vec<TapeSolid> = models
        .iter()
        .map(|m| TapeSolid::new(tape(m), &m.bounds))
        .collect();
    let src = interp_source(&solids);
    let start = Instant::now();
    // SAFETY: register numbers are below REG_COUNT (checked by Bytecode, the class holds
    // every tape's), the loop runs for the tape's length (`use_tape` reads it from the
    // binding's header), and the entry points stay within their arrays.
    let kp = unsafe { Kernel::new_unchecked(&g, &src, "points", 3) }.unwrap();
    let kb = unsafe { Kernel::new_unchecked(&g, &src, "boxes", 3) }.unwrap();
    let compile = start.elapsed();
    let mut rng = Rng(7);
    let (mut pts, mut boxes, mut which) = (Vec::new(), Vec::new(), Vec::new());
    for (k, m) in models.iter().enumerate() {
        let (p, b) = samples(m, &mut rng);
        assert_eq!(p.len(), b.len());
        which.extend(std::iter::repeat_n(k as u32, p.len()));
        pts.extend(p);
        boxes.extend(b);
    }
    let tape_words = TapeSolid::scene_words(&solids);
    let n = pts.len();
    let groups = [n.div_ceil(64) as u32, 1, 1];
    let words: Vec<u32> = pts.iter().flatten().map(|f| f.to_bits()).collect();
    let out = kp
        .run(&g, &[&tape_words, &words, &which], n, groups)
        .unwrap();
    for (i, p) in pts.iter().enumerate() {
        let k = which[i] as usize;
        let (gpu, twin) = (f32::from_bits(out[i]), solids[k].tape.eval_point(*p));
        assert!(
            same(gpu, twin),
            "{}: at {p:?} GPU {gpu}, twin {twin}",
            models[k].name
        );
    }
    let words: Vec<u32> = boxes
        .iter()
        .flat_map(|(lo, hi, d)| [lo.to_array(), hi.to_array(), d.to_array()])
        .flatten()
        .map(|f| f.to_bits())
        .collect();
    let out = kb
        .run(&g, &[&tape_words, &words, &which], 4 * boxes.len(), groups)
        .unwrap();
    for (i, b) in boxes.iter().enumerate() {
        let k = which[i] as usize;
        let twin = box_interval(&solids[k].tape, b);
        for c in 0..4 {
            let gpu = f32::from_bits(out[4 * i + c]);
            assert!(
                same(gpu, twin[c]),
                "{}: box {i} [{c}] GPU {gpu}, twin {}",
                models[k].name,
                twin[c]
            );
        }
    }
    eprintln!(
        "{} models: {n} points and {} boxes bit-identical; both pipelines {compile:?}",
        models.len(),
        boxes.len()
    );
}

/// The tracer, ray i after `use_tape(which[i])`, over [`TapeSolid::scene_wgsl`], as
/// [`interp_source`].
fn trace_source(solids: &[TapeSolid]) -> String {
    format!(
        "@group(0) @binding(0) var<storage, read> tape: array<u32>;
@group(0) @binding(1) var<storage, read> rays: array<f32>;
@group(0) @binding(2) var<storage, read> which: array<u32>;
@group(0) @binding(3) var<storage, read_write> out: array<u32>;
{}
@compute @workgroup_size(64)
fn trace(@builtin(global_invocation_id) id: vec3<u32>) {{
    let i = id.x;
    if (i >= arrayLength(&which)) {{ return; }}
    let r = 8u * i;
    loops = 0u;
    use_tape(which[i]);
    let o = vec3<f32>(rays[r], rays[r + 1u], rays[r + 2u]);
    let d = vec3<f32>(rays[r + 3u], rays[r + 4u], rays[r + 5u]);
    let h = trace_tape(o, d, rays[r + 6u], rays[r + 7u]);
    out[3u * i] = bitcast<u32>(h.t);
    out[3u * i + 1u] = h.status;
    out[3u * i + 2u] = loops;
}}
",
        TapeSolid::scene_wgsl(solids)
    )
}

type TestRay = [f32; 8];

/// |Δt| against frep's f64 tracer, relative to max(size, |t|): the f32 resolution
/// (2e-6 × diagonal) decides at most a segment that long, and the surface's slope along
/// grazing rays stretches that (measured up to 8.8e-5, table); GPU.md §9 asks ≤ 1e-3.
const TOLERANCE: f64 = 1e-3;

/// Rays: a half random from outside (aimed into the bounds), a quarter grazing the
/// surface (tangent at a point found by frep, nudged by up to 1e-4 × size), a quarter
/// from inside the bounds.
fn rays(m: &Model, rng: &mut Rng) -> Vec<TestRay> {
    let surface = ExprSurface::new(m.expr.clone(), m.bounds);
    let view = surface.view();
    let c = m.bounds.center();
    let size = m.bounds.extent().length();
    let mut out = Vec::new();
    let mk = |o: DVec3, d: DVec3, t0: f32, t1: f32| -> TestRay {
        let (o, d) = (o.as_vec3(), d.as_vec3());
        [o.x, o.y, o.z, d.x, d.y, d.z, t0, t1]
    };
    while out.len() < 2048 {
        let o = c + size * rng.unit();
        let d = (rng.in_box(&m.bounds) - o).normalize();
        out.push(mk(o, d, 0.0, f32::INFINITY));
    }
    while out.len() < 3072 {
        let o = c + size * rng.unit();
        let d = (rng.in_box(&m.bounds) - o).normalize();
        let Some((t, _)) = view.trace(&Ray::new(o, d), 0.0, f64::INFINITY, false) else {
            continue;
        };
        let p = o + t * d;
        let n = m.expr.gradient(p.to_array()).1;
        let n = DVec3::from_array(n).normalize_or_zero();
        if n == DVec3::ZERO {
            continue;
        }
        let tangent = n.cross(rng.unit()).normalize_or_zero();
        if tangent == DVec3::ZERO {
            continue;
        }
        let p = p + n * size * 1e-4 * rng.range(-1.0, 1.0);
        out.push(mk(p - size * tangent, tangent, 0.0, f32::INFINITY));
    }
    while out.len() < 4096 {
        let o = rng.in_box(&m.bounds);
        out.push(mk(o, rng.unit(), 0.0, (2.0 * size) as f32));
    }
    out
}

/// The largest |F| over the sliver (a, b) of the ray (63 samples, f64) in units of
/// ε₃₂·S(p), S the scale of the f32 evaluation's rounding at p: the ray point's own
/// rounding (|∇F|·(|o| + |t|·|d|)) plus every tape operation's (Σ |v| over the nodes, each
/// rounded by at most ε₃₂·|v|). Where this stays small the sliver lies within f32
/// rounding of F = 0: a near-tangent ray, which GPU.md §9 lets the f32 and f64 tracers
/// answer differently.
fn relative_peak(m: &Model, o: DVec3, d: DVec3, a: f64, b: f64) -> f64 {
    let n = m.expr.nodes().len();
    let mut scratch = Vec::new();
    (1..64)
        .map(|k| {
            let t = a + (b - a) * k as f64 / 64.0;
            let p = o + t * d;
            let v = eval_nodes(m.expr.nodes(), p.x, p.y, p.z, &mut scratch);
            let ops: f64 = scratch[..n].iter().map(|v| v.abs()).sum();
            let grad = DVec3::from_array(m.expr.gradient(p.to_array()).1).length();
            let scale = grad * (o.length() + t.abs() * d.length()) + ops;
            v.abs() / (f64::from(f32::EPSILON) * scale)
        })
        .fold(0.0, f64::max)
}

/// How far from F = 0, in units of [`relative_peak`]'s rounding scale, a sliver one
/// tracer skips and the other reports may reach and still count as near-tangent: within
/// one rounding scale. (Measured: the one such ray, bumpy_ball's ray 2319, grazes the
/// surface with |F| ≤ 1.0e-2 ε₃₂·S over a sliver 5.5e-6 long.)
const NEAR_TANGENT: f64 = 1.0;

/// Per model, 4 096 rays through the twin, searching the whole tape and walking the cells
/// with their tapes, against frep's f64 tracer (same bounds and
/// f64 resolution): the same hit or miss on every ray the twin decides but near-tangent
/// ones (the sliver between one tracer's crossing and its next crossing, which the other
/// skips, within [`NEAR_TANGENT`] × f32 rounding of F = 0: [`relative_peak`]), at most
/// 1 % undecided (left to the CPU), |Δt| within [`TOLERANCE`], loop counts within
/// [`BUDGET`].
#[test]
fn twin_traces_like_frep() {
    let mut rng = Rng(21);
    for m in models() {
        let whole = TapeSolid::new(tape(&m), &m.bounds);
        let walked = whole.clone().with_cells(m.expr.nodes()).unwrap();
        let rs = rays(&m, &mut rng);
        for (how, solid) in [("whole tape", whole), ("cells", walked)] {
            if how == "cells" && solid.walk.is_none() {
                continue;
            }
            twin_against_frep(&m, how, &solid, &rs);
        }
    }
}

/// [`twin_traces_like_frep`] for one model's `solid`.
fn twin_against_frep(m: &Model, how: &str, solid: &TapeSolid, rs: &[TestRay]) {
    {
        // frep's tracer as solids use it (occupancy grid included).
        let surface = ExprSurface::new(m.expr.clone(), m.bounds);
        let view = surface.view();
        let size = m.bounds.extent().length();
        let (mut hits, mut undecided, mut flips, mut max_dt, mut max_loops) = (0, 0, 0, 0f64, 0);
        let (mut near, mut max_peak, mut grazing_undecided) = (0, 0f64, 0);
        for (i, r) in rs.iter().enumerate() {
            let (o, d) = (Vec3::new(r[0], r[1], r[2]), Vec3::new(r[3], r[4], r[5]));
            let twin = solid.trace(o, d, r[6], r[7]);
            max_loops = max_loops.max(twin.loops);
            let ray = Ray::new(o.as_dvec3(), d.as_dvec3());
            let want = view
                .trace(&ray, r[6] as f64, r[7] as f64, false)
                .map(|h| h.0);
            match (twin.hit, want) {
                (TapeHit::Undecided, _) => {
                    undecided += 1;
                    grazing_undecided += (2048..3072).contains(&i) as usize;
                }
                (TapeHit::Hit(t), Some(w)) => {
                    hits += 1;
                    max_dt = max_dt.max((t as f64 - w).abs() / size.max(w.abs()));
                }
                (TapeHit::Miss, None) => {}
                (got, want) => {
                    // The sliver one tracer reports and the other skips: from its crossing
                    // to that tracer's next.
                    let (o64, d64) = (o.as_dvec3(), d.as_dvec3());
                    let (a, b) = match (got, want) {
                        (TapeHit::Hit(a), _) => {
                            let next = match solid.trace(o, d, a, r[7]).hit {
                                TapeHit::Hit(n) => n,
                                _ => r[7].min(a + size as f32),
                            };
                            (f64::from(a), f64::from(next))
                        }
                        (_, Some(b)) => {
                            let next = view.trace(&ray, b, r[7] as f64, false);
                            (b, next.map_or((r[7] as f64).min(b + size), |h| h.0))
                        }
                        _ => unreachable!("an agreeing pair"),
                    };
                    let peak = relative_peak(m, o64, d64, a, b);
                    if peak <= NEAR_TANGENT {
                        near += 1;
                    } else {
                        flips += 1;
                    }
                    max_peak = max_peak.max(peak);
                    eprintln!(
                        "{}, {how}: ray {i} {r:?}: twin {got:?}, frep {want:?}; |F| up to {peak:.2e} ε₃₂·S over ({a}, {b})",
                        m.name
                    );
                }
            }
        }
        eprintln!(
            "{}, {how}: {} rays, {hits} hits, {flips} flips against f64 and {near} near-tangent (|F| up to {max_peak:.2e} ε₃₂·S), {undecided} undecided (for the CPU; {grazing_undecided} of them of the 1 024 grazing), max |Δt|/max(size, t) {max_dt:.2e}, max loops {max_loops}",
            m.name,
            rs.len()
        );
        assert!(max_loops <= BUDGET, "{max_loops}");
        // Every ray the twin decides agrees with frep; the ones it leaves to the CPU are
        // few (rays whose signs lie within f32 rounding of F = 0 near their crossing).
        assert_eq!(flips, 0, "{}", m.name);
        assert!(
            (undecided - grazing_undecided) * 100 <= rs.len(),
            "{}: {undecided} undecided",
            m.name
        );
        assert!(max_dt < TOLERANCE, "{}: {max_dt:e}", m.name);
    }
}

/// The same rays through the kernel, every model in one kernel (a scene's expression
/// solids, `TapeSolid::scene_wgsl`, each ray after `use_tape(k)`: the one interpreter
/// runs each tape for its own length), each model as the renderer packs it: walked cell
/// by cell with the cells' tapes where it has a walk grid (`TapeSolid::with_cells`),
/// else searched with its whole tape (tanglecube, a polynomial; the whole-tape search
/// of the others is the walk's search of one run, and the padded spheres of
/// `loop_budget_is_kept_and_reported` take it too). Outcome, t and loop count bit for
/// bit the twin's.
#[test]
fn tracer_matches_its_twin() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let models = models();
    let mut solids: Vec<TapeSolid> = Vec::new();
    let mut names: Vec<String> = Vec::new();
    let mut rng = Rng(21);
    let (mut all, mut which): (Vec<TestRay>, Vec<u32>) = (Vec::new(), Vec::new());
    for m in &models {
        let whole = TapeSolid::new(tape(m), &m.bounds);
        let walked = whole.clone().with_cells(m.expr.nodes()).unwrap();
        let rs = rays(m, &mut rng);
        let (solid, name) = match walked.walk {
            Some(_) => (walked, format!("{} (cells)", m.name)),
            None => (whole, m.name.to_string()),
        };
        which.extend(std::iter::repeat_n(solids.len() as u32, rs.len()));
        all.extend(rs);
        solids.push(solid);
        names.push(name);
    }
    let out = run_rays(&g, &solids, &all, &which, "every model");
    let mut undecided = vec![0usize; solids.len()];
    for (i, r) in all.iter().enumerate() {
        let k = which[i] as usize;
        let twin = checked_trace(&solids[k], r, &out, i, &names[k]);
        undecided[k] += usize::from(twin.hit == TapeHit::Undecided);
    }
    let lengths: Vec<usize> = solids.iter().map(|s| s.tape.len()).collect();
    let walked = solids.iter().filter(|s| s.walk.is_some()).count();
    eprintln!(
        "{} rays over {} solids, {walked} walked by cells (tapes of {lengths:?} \
         instructions; undecided {undecided:?}) bit-identical to their twins",
        all.len(),
        solids.len()
    );
    assert!(lengths.iter().any(|&n| n != lengths[0]));
    assert!(
        walked >= 8 && walked < solids.len(),
        "{walked} solids walked"
    );
}

/// Ray i (`r`) of a kernel run whose words are `out`: the kernel's outcome asserted equal,
/// bit for bit, to `solid`'s twin (`what` names the solid); the twin's returned.
fn checked_trace(solid: &TapeSolid, r: &TestRay, out: &[u32], i: usize, what: &str) -> Traced {
    let (o, d) = (Vec3::new(r[0], r[1], r[2]), Vec3::new(r[3], r[4], r[5]));
    let twin = solid.trace(o, d, r[6], r[7]);
    let gpu = Traced::from_kernel(out[3 * i + 1], out[3 * i], out[3 * i + 2]);
    assert!(
        same_trace(&gpu, &twin),
        "{what}: ray {i} {r:?}: GPU {gpu:?}, twin {twin:?}"
    );
    twin
}

/// Equal outcomes, t bit for bit, equal flags and loop counts.
fn same_trace(a: &Traced, b: &Traced) -> bool {
    let hit = match (a.hit, b.hit) {
        (TapeHit::Hit(x), TapeHit::Hit(y)) => x.to_bits() == y.to_bits(),
        (x, y) => x == y,
    };
    hit && a.loops == b.loops
}

/// Traces ray i of `rs` through solid `which[i]` in the kernel.
fn run_rays(g: &Gpu, solids: &[TapeSolid], rs: &[TestRay], which: &[u32], name: &str) -> Vec<u32> {
    let start = Instant::now();
    // SAFETY: registers below REG_COUNT (checked by Bytecode, the class holds every
    // tape's), stack indices below STACK (checked before each push), every loop bounded
    // by BUDGET; `use_tape` sets tape_base and tape_ops to a tape of the binding.
    let k = unsafe { Kernel::new_unchecked(g, &trace_source(solids), "trace", 3) }.unwrap();
    let compile = start.elapsed();
    let words: Vec<u32> = rs.iter().flatten().map(|f| f.to_bits()).collect();
    let start = Instant::now();
    let out = k
        .run(
            g,
            &[&TapeSolid::scene_words(solids), &words, which],
            3 * rs.len(),
            [(rs.len() as u32).div_ceil(64), 1, 1],
        )
        .unwrap();
    eprintln!(
        "{name}: pipeline {compile:?}, {} rays in {:?}",
        rs.len(),
        start.elapsed()
    );
    out
}

/// The unit sphere padded with `terms` negligible terms 1e-30·(x + k)², 4 ops each.
fn padded_sphere(terms: usize) -> Expr {
    use frep::Tree;
    let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
    let mut t = Tree::constant(1.0) - x.square() - y.square() - z.square();
    for k in 1..=terms {
        t = t + (x.clone() + k as f64).square() * 1e-30;
    }
    Expr::new(&t)
}

/// The loop budget (GPU.md §3.1): a tape too long for the two end signs within the
/// budget leaves every ray undecided (never a miss); a tape leaving a few dozen
/// evaluations leaves some undecided and answers the rest as a shorter tape would. GPU
/// and twin agree, and no invocation passes [`BUDGET`].
#[test]
fn loop_budget_is_kept_and_reported() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
    let mut rng = Rng(5);
    let cases = [(800, false), (20_000, true)];
    let solids: Vec<TapeSolid> = cases
        .iter()
        .map(|&(terms, _)| {
            let e = padded_sphere(terms);
            TapeSolid::new(
                GpuTape::new(&Bytecode::compile(&e).unwrap()).unwrap(),
                &bounds,
            )
        })
        .collect();
    let per = 512;
    let all: Vec<TestRay> = (0..cases.len() * per)
        .map(|i| {
            let d = rng.unit().as_vec3();
            if i % 2 == 0 {
                // From the centre (inside): a crossing by end signs.
                [0.0, 0.0, 0.0, d.x, d.y, d.z, 0.0, 4.0]
            } else {
                let o = (3.0 * rng.unit()).as_vec3();
                let d = (rng.in_box(&bounds).as_vec3() * 0.5 - o).normalize();
                [o.x, o.y, o.z, d.x, d.y, d.z, 0.0, f32::INFINITY]
            }
        })
        .collect();
    let which: Vec<u32> = (0..all.len()).map(|i| (i / per) as u32).collect();
    let out_all = run_rays(&g, &solids, &all, &which, "padded spheres");
    for (c, &(_, want_all_undecided)) in cases.iter().enumerate() {
        let (solid, rs) = (&solids[c], &all[c * per..(c + 1) * per]);
        let out = &out_all[3 * c * per..3 * (c + 1) * per];
        let (mut undecided, mut max_loops) = (0, 0);
        for (i, r) in rs.iter().enumerate() {
            let twin = checked_trace(solid, r, out, i, "padded sphere");
            let (o, d) = (Vec3::new(r[0], r[1], r[2]), Vec3::new(r[3], r[4], r[5]));
            assert!(twin.loops <= BUDGET, "{}", twin.loops);
            max_loops = max_loops.max(twin.loops);
            undecided += (twin.hit == TapeHit::Undecided) as usize;
            match twin.hit {
                TapeHit::Undecided => {}
                // The unit sphere: from inside, a hit at 1; from outside, at |o| − 1
                // along the line through the centre's nearest point, or none.
                TapeHit::Hit(t) if i % 2 == 0 => assert!((t - 1.0).abs() < 1e-4, "ray {i}: {t}"),
                TapeHit::Hit(t) => {
                    let (o, d) = (o.as_dvec3(), d.as_dvec3());
                    let b = o.dot(d);
                    let want = -b - (b * b - o.length_squared() + 1.0).sqrt();
                    assert!(
                        (t as f64 - want).abs() < 1e-4,
                        "ray {i}: {t} against {want}"
                    );
                }
                // Every ray from outside aims at a point inside the sphere.
                TapeHit::Miss => panic!("ray {i} missed"),
            }
        }
        eprintln!(
            "{} ops: {undecided} undecided of {}, max loops {max_loops}",
            solid.tape.len(),
            rs.len()
        );
        assert!(undecided > 0);
        assert_eq!(undecided == rs.len(), want_all_undecided);
    }
}

/// Thin and singular shapes as expressions (the tape path, not the exact quadrics): a
/// fin 2.5 mm thick, a needle 2.5 mm across, and a double cone (half-angle 30°) with
/// its apex at the origin, each within the cube of half-size 1.
fn thin_shapes() -> Vec<(&'static str, Expr)> {
    use frep::Tree;
    let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
    let one = Tree::constant(1.0);
    let slab = |v: &Tree| one.clone() - v.abs();
    let fin = (Tree::constant(0.00125) - x.abs())
        .min(&slab(&y))
        .min(&slab(&z));
    let needle = (Tree::constant(0.00125) - (x.square() + y.square()).sqrt()).min(&slab(&z));
    let (c2, s2) = (0.75, 0.25); // cos² 30°, sin² 30°
    let cone = (z.square() * c2 - (x.square() + y.square()) * s2).min(&slab(&z));
    vec![
        ("fin", Expr::new(&fin)),
        ("needle", Expr::new(&needle)),
        ("cone", Expr::new(&cone)),
    ]
}

/// Camera rays through the pixel centres of 27 views (9 azimuths × 3 elevations) of
/// `res`² pixels, 30° field of view, from 1.5 diagonals away, aimed at the centre.
fn pixel_centre_rays(bounds: &Aabb, res: usize) -> Vec<TestRay> {
    let c = bounds.center();
    let r = 1.5 * bounds.extent().length();
    let h = 15f64.to_radians().tan();
    let mut out = Vec::new();
    for az in (0..360).step_by(40) {
        for el in [-20.0f64, 15.0, 50.0] {
            let (a, e) = ((az as f64).to_radians(), el.to_radians());
            let eye = c + r * DVec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin());
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
                    out.push([o.x, o.y, o.z, d.x, d.y, d.z, 0.0, f32::INFINITY]);
                }
            }
        }
    }
    out
}

/// The tracer never answers wrongly (an f32 value's sign once gave colonnade false hits
/// on near-zero sheets and misses where the budget ran low): at the pixel centres of 27
/// views of colonnade.vm, a fin and a needle 2.5 mm thick and a double cone's apex,
/// searched with the whole tape and walked by cells, and of prospero.vm walked by cells,
/// every ray the twin decides has frep's f64 outcome, and t within [`TOLERANCE`]; the
/// rest are counted (the CPU traces them). Walked by cells, prospero leaves at most 1 %
/// of them undecided (its whole tape fits a dozen evaluations in the loop budget, and
/// left 63 % so).
#[test]
fn pixel_centres_are_never_answered_wrongly() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let cube = Aabb::new(DVec3::splat(-2.0), DVec3::splat(2.0));
    let fidget = |name: &'static str, whole_too: bool| {
        let m = read_file(&root.join(format!("models/fidget/{name}.vm"))).unwrap();
        let e = Expr::new(&m.shape.to_tree().unwrap());
        (name, e, m.domain.unwrap_or(cube), whole_too)
    };
    let mut shapes = vec![fidget("colonnade", true)];
    shapes.extend(thin_shapes().into_iter().map(|(n, e)| (n, e, cube, true)));
    shapes.push(fidget("prospero", false));
    let mut rng = Rng(8);
    for (name, expr, domain, whole_too) in shapes {
        let bounds = frep::bounds::expr_bounds(&expr, domain);
        let whole = TapeSolid::new(
            GpuTape::new(&Bytecode::compile(&expr).unwrap()).unwrap(),
            &bounds,
        );
        let walked = whole.clone().with_cells(expr.nodes()).unwrap();
        let surface = ExprSurface::new(expr.clone(), bounds);
        let view = surface.view();
        let size = bounds.extent().length();
        let mut rs = pixel_centre_rays(&bounds, 16);
        if name == "needle" {
            // Too thin for pixel centres: rays through points of its axis.
            rs = (0..4096)
                .map(|_| {
                    let p = DVec3::new(0.0, 0.0, rng.range(-0.9, 0.9));
                    let o = p - 3.0 * rng.unit();
                    let (o, d) = (o.as_vec3(), (p - o).normalize().as_vec3());
                    [o.x, o.y, o.z, d.x, d.y, d.z, 0.0, f32::INFINITY]
                })
                .collect();
        }
        let want: Vec<Option<f64>> = rs
            .iter()
            .map(|r| {
                let ray = Ray::new(
                    DVec3::new(r[0] as f64, r[1] as f64, r[2] as f64),
                    DVec3::new(r[3] as f64, r[4] as f64, r[5] as f64),
                );
                view.trace(&ray, 0.0, f64::INFINITY, false).map(|h| h.0)
            })
            .collect();
        let solids = [("whole tape", &whole), ("cells", &walked)];
        for (how, solid) in solids.into_iter().skip(usize::from(!whole_too)) {
            let (mut hits, mut undecided, mut wrong) = (0, 0, 0);
            for (r, &want) in rs.iter().zip(&want) {
                let (o, d) = (Vec3::new(r[0], r[1], r[2]), Vec3::new(r[3], r[4], r[5]));
                let twin = solid.trace(o, d, r[6], r[7]).hit;
                let ok = match (twin, want) {
                    (TapeHit::Undecided, _) => {
                        undecided += 1;
                        true
                    }
                    (TapeHit::Miss, None) => true,
                    (TapeHit::Hit(t), Some(w)) => {
                        hits += 1;
                        (t as f64 - w).abs() <= TOLERANCE * size.max(w)
                    }
                    _ => false,
                };
                if !ok {
                    wrong += 1;
                    eprintln!("{name}, {how}: ray {r:?}: twin {twin:?}, frep {want:?}");
                }
            }
            eprintln!(
                "{name}, {how}: {} pixel centres, {hits} hits, {wrong} wrong, {undecided} undecided (for the CPU)",
                rs.len()
            );
            assert_eq!(wrong, 0, "{name}, {how}");
            if name == "prospero" {
                assert!(solid.walk.is_some());
                assert!(undecided * 100 <= rs.len(), "{undecided} of {}", rs.len());
            }
        }
    }
}

/// prospero.vm walked by cells on the GPU (a 64³ grid, 2 087 cell tapes in the `tape`
/// binding): the kernel equals its twin bit for bit at pixel centres of 27 views.
#[test]
fn prospero_walk_matches_its_twin() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let m = read_file(&root.join("models/fidget/prospero.vm")).unwrap();
    let expr = Expr::new(&m.shape.to_tree().unwrap());
    let cube = Aabb::new(DVec3::splat(-2.0), DVec3::splat(2.0));
    let bounds = frep::bounds::expr_bounds(&expr, m.domain.unwrap_or(cube));
    let solid = TapeSolid::new(
        GpuTape::new(&Bytecode::compile(&expr).unwrap()).unwrap(),
        &bounds,
    )
    .with_cells(expr.nodes())
    .unwrap();
    let rs = pixel_centre_rays(&bounds, 8);
    let out = run_rays(
        &g,
        std::slice::from_ref(&solid),
        &rs,
        &vec![0; rs.len()],
        "prospero",
    );
    let mut hits = 0;
    for (i, r) in rs.iter().enumerate() {
        let twin = checked_trace(&solid, r, &out, i, "prospero");
        hits += usize::from(matches!(twin.hit, TapeHit::Hit(_)));
    }
    eprintln!(
        "prospero walked: {} rays ({hits} hits) bit-identical to the twin",
        rs.len()
    );
    assert!(hits > 0);
}

/// Rays that start exactly on the unit sphere (F = 0 at the origin of the window, an open
/// sign that moves the window's start in by ε) and head inside: the answer is the exit,
/// not a crossing at the moved start; and rays from inside whose window ends exactly on
/// the surface (t_max there, the end moved in) have no crossing in (t_min, t_max).
#[test]
fn windows_starting_or_ending_on_the_surface_are_not_crossings() {
    let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
    let solid = TapeSolid::new(
        GpuTape::new(&Bytecode::compile(&padded_sphere(0)).unwrap()).unwrap(),
        &bounds,
    );
    let mut rng = Rng(12);
    let starts = [
        Vec3::X,
        Vec3::Y,
        Vec3::Z,
        Vec3::NEG_X,
        Vec3::NEG_Y,
        Vec3::NEG_Z,
    ];
    for (k, o) in starts.iter().cycle().take(600).enumerate() {
        // Inward: a direction with d·o < 0; the exit is at t = −2·o·d.
        let mut d = rng.unit().as_vec3();
        if d.dot(*o) > -0.1 {
            d = (d - 1.5 * o).normalize();
        }
        let exit = -2.0 * o.dot(d);
        match solid.trace(*o, d, 0.0, f32::INFINITY).hit {
            TapeHit::Hit(t) => assert!(
                (t - exit).abs() < 1e-4,
                "ray {k}: {t} against the exit {exit}"
            ),
            TapeHit::Undecided => {}
            TapeHit::Miss => panic!("ray {k} from {o} along {d} missed its exit {exit}"),
        }
        // From the centre to exactly the surface point o: no crossing before t_max = 1.
        let hit = solid.trace(Vec3::ZERO, *o, 0.0, 1.0).hit;
        assert!(
            matches!(hit, TapeHit::Miss | TapeHit::Undecided),
            "{o}: {hit:?}"
        );
    }
}
