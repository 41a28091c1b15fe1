//! Point and interval evaluation rates, and value agreement.

use crate::args::Args;
use crate::{best_of, sig3, Model, Rng};
use fidget::jit::JitShape;
use fidget::shape::EzShape;
use fidget::vm::VmShape;
use frep::{Choice, Dual, Interval};
use std::error::Error;

/// Float-slice evaluation of a Fidget shape in batches; returns (best seconds, values).
macro_rules! fidget_slices {
    ($ty:ty, $shape:expr, $xs:expr, $ys:expr, $zs:expr, $args:expr) => {{
        let shape = $shape;
        let tape = shape.ez_float_slice_tape();
        let mut eval = <$ty>::new_float_slice_eval();
        let mut out = vec![0f32; $xs.len()];
        let b = $args.batch;
        let mut err = None;
        let (secs, ()) = best_of($args.reps, || {
            for (k, o) in out.chunks_mut(b).enumerate() {
                let r = k * b..(k * b + o.len());
                match eval.eval(&tape, &$xs[r.clone()], &$ys[r.clone()], &$zs[r]) {
                    Ok(v) => o.copy_from_slice(v),
                    Err(e) => err = Some(format!("{e:?}")),
                }
            }
        });
        if let Some(e) = err {
            return Err(format!("fidget float-slice evaluation failed: {e}").into());
        }
        (secs, out)
    }};
}

/// Largest |a − b| over values that are both numbers, and how many pairs disagree on
/// being NaN.
fn max_diff(a: impl Iterator<Item = f32>, b: &[f32]) -> (f32, usize) {
    let mut worst = 0f32;
    let mut nan = 0;
    for (x, &y) in a.zip(b) {
        match (x.is_nan(), y.is_nan()) {
            (true, true) => {}
            (false, false) => worst = worst.max((x - y).abs()),
            _ => nan += 1,
        }
    }
    (worst, nan)
}

fn diff_text((d, nan): (f32, usize), scale: f32) -> String {
    let mut s = format!("{d:.2e} (of max \\|F\\| {scale:.3})");
    if nan > 0 {
        s += &format!(", {nan} NaN mismatches");
    }
    s
}

/// Point evaluation at the same random points in [-1,1]³, one thread.
pub fn run(m: &Model, args: &Args) -> Result<Vec<String>, Box<dyn Error>> {
    let n = args.points;
    let mut rng = Rng::new(0x5eed_0001);
    let mut gen = || {
        (0..n)
            .map(|_| rng.range(-1.0, 1.0) as f32)
            .collect::<Vec<f32>>()
    };
    let (xs, ys, zs) = (gen(), gen(), gen());

    let vm = VmShape::new(&m.ctx, m.root)?;
    let jit = JitShape::new(&m.ctx, m.root)?;
    let (t_vm, v_vm) = fidget_slices!(VmShape, &vm, xs, ys, zs, args);
    let (t_jit, v_jit) = fidget_slices!(JitShape, &jit, xs, ys, zs, args);

    let expr = &m.expr;
    let mut out64 = vec![0f64; n];
    let mut s64: Vec<f64> = Vec::with_capacity(expr.len());
    let (t64, ()) = best_of(args.reps, || {
        for i in 0..n {
            out64[i] = expr.eval_with(xs[i] as f64, ys[i] as f64, zs[i] as f64, &mut s64);
        }
    });
    // The same points visited in Morton (Z-curve) order: neighbours in turn, as along a
    // ray or in a tile, so that min/max branches repeat and the branch predictor learns.
    let morton = |i: usize| {
        let q = |v: f32| (((v + 1.0) * 511.5) as u64).min(1023);
        let spread = |mut v: u64| {
            let mut r = 0u64;
            for b in 0..10 {
                r |= (v & 1) << (3 * b);
                v >>= 1;
            }
            r
        };
        spread(q(xs[i])) | spread(q(ys[i])) << 1 | spread(q(zs[i])) << 2
    };
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&i| morton(i));
    // Gathered into sorted arrays first, so that the timed loop reads memory in order.
    let pick = |v: &[f32]| order.iter().map(|&i| v[i] as f64).collect::<Vec<f64>>();
    let (mx, my, mz) = (pick(&xs), pick(&ys), pick(&zs));
    let mut sorted64 = vec![0f64; n];
    let (t64m, ()) = best_of(args.reps, || {
        for k in 0..n {
            sorted64[k] = expr.eval_with(mx[k], my[k], mz[k], &mut s64);
        }
    });
    let mut out64m = vec![0f64; n];
    for (k, &i) in order.iter().enumerate() {
        out64m[i] = sorted64[k];
    }
    let mut out32 = vec![0f32; n];
    let mut s32: Vec<f32> = Vec::with_capacity(expr.len());
    let (t32, ()) = best_of(args.reps, || {
        for i in 0..n {
            out32[i] = expr.eval_with(xs[i], ys[i], zs[i], &mut s32);
        }
    });

    let scale = v_jit
        .iter()
        .filter(|v| v.is_finite())
        .fold(0f32, |a, v| a.max(v.abs()));
    let rate = |t: f64| sig3(n as f64 / t / 1e6);
    let name = &m.name;
    let clauses = vm.size();
    let rows = vec![
        format!(
            "| {name} | Fidget VM, float slices of {} | {clauses} | {} | {} |",
            args.batch,
            rate(t_vm),
            diff_text(max_diff(v_vm.iter().copied(), &v_jit), scale)
        ),
        format!(
            "| {name} | Fidget JIT, float slices of {} | {clauses} | {} | (reference) |",
            args.batch,
            rate(t_jit)
        ),
        format!(
            "| {name} | frepray `Expr::eval_with` f64 | {} | {} | {} |",
            expr.len(),
            rate(t64),
            diff_text(max_diff(out64.iter().map(|&v| -(v as f32)), &v_jit), scale)
        ),
        format!(
            "| {name} | frepray `Expr::eval_with` f64, same points in Morton order | {} | {} | {} |",
            expr.len(),
            rate(t64m),
            diff_text(max_diff(out64m.iter().map(|&v| -(v as f32)), &v_jit), scale)
        ),
        format!(
            "| {name} | frepray `Expr::eval_with` f32 | {} | {} | {} |",
            expr.len(),
            rate(t32),
            diff_text(max_diff(out32.iter().map(|&v| -v), &v_jit), scale)
        ),
    ];
    for r in &rows {
        eprintln!("   {r}");
    }
    Ok(rows)
}

/// Interval evaluation on the same random boxes of side 2/64 in [-1,1]³ (a 32-voxel tile
/// of a 1024³ render), one thread, and how much of each tape the box's min/max choices
/// leave (both systems prune the same way: Keeter 2020, §3).
pub fn intervals(m: &Model, args: &Args) -> Result<Vec<String>, Box<dyn Error>> {
    let n = (args.points / 10).max(1000);
    let side = 2.0 / 64.0;
    let mut rng = Rng::new(0x5eed_0002);
    let boxes: Vec<[f64; 3]> = (0..n)
        .map(|_| [0, 1, 2].map(|_| rng.range(-1.0, 1.0 - side)))
        .collect();
    let fi =
        |b: &[f64; 3], k: usize| fidget::types::Interval::new(b[k] as f32, (b[k] + side) as f32);

    let vm = VmShape::new(&m.ctx, m.root)?;
    let jit = JitShape::new(&m.ctx, m.root)?;
    let mut sink = 0f32;
    let timed = |name: &str, secs: f64| format!("{name} | {}", sig3(n as f64 / secs / 1e6));

    let tape = vm.ez_interval_tape();
    let mut ev = VmShape::new_interval_eval();
    let (t_vm, ()) = best_of(args.reps, || {
        for b in &boxes {
            let (v, _) = ev
                .eval(&tape, fi(b, 0), fi(b, 1), fi(b, 2))
                .expect("interval eval");
            sink += v.upper();
        }
    });
    // How long Fidget's tape is after pruning the min/max branches that the box decides.
    let sample = n.min(2000);
    let mut pruned = 0usize;
    for b in boxes.iter().take(sample) {
        let (_, trace) = ev.eval(&tape, fi(b, 0), fi(b, 1), fi(b, 2))?;
        pruned += match trace {
            Some(tr) => vm.ez_simplify(tr)?.size(),
            None => vm.size(),
        };
    }
    let mean_pruned = pruned as f64 / sample as f64;

    let jtape = jit.ez_interval_tape();
    let mut jev = JitShape::new_interval_eval();
    let (t_jit, ()) = best_of(args.reps, || {
        for b in &boxes {
            let (v, _) = jev
                .eval(&jtape, fi(b, 0), fi(b, 1), fi(b, 2))
                .expect("interval eval");
            sink += v.upper();
        }
    });

    let expr = &m.expr;
    let ii = |b: &[f64; 3], k: usize| Interval::new(b[k], b[k] + side);
    let mut si: Vec<Interval> = Vec::with_capacity(expr.len());
    let (t_i, ()) = best_of(args.reps, || {
        for b in &boxes {
            sink += expr.eval_with(ii(b, 0), ii(b, 1), ii(b, 2), &mut si).hi as f32;
        }
    });
    // A ray segment looking down −z, as the intersector evaluates it: value and slope,
    // recording the min/max choices.
    let dual = |b: &[f64; 3], k: usize| {
        let d = if k == 2 { -1.0 } else { 0.0 };
        Dual::new(ii(b, k), [Interval::point(d)])
    };
    let mut sd: Vec<Dual<Interval, 1>> = Vec::with_capacity(expr.len());
    let mut choices: Vec<Choice> = Vec::with_capacity(expr.len());
    let (t_d, ()) = best_of(args.reps, || {
        for b in &boxes {
            let v = expr.eval_choices(dual(b, 0), dual(b, 1), dual(b, 2), &mut sd, &mut choices);
            sink += v.v.hi as f32;
        }
    });
    std::hint::black_box(sink);
    // frepray's simplified length on the same boxes.
    let mut frep_pruned = 0usize;
    for b in boxes.iter().take(sample) {
        expr.eval_choices(ii(b, 0), ii(b, 1), ii(b, 2), &mut si, &mut choices);
        frep_pruned += expr.simplify(&choices).map_or(expr.len(), |e| e.len());
    }
    let frep_mean_pruned = frep_pruned as f64 / sample as f64;

    let name = &m.name;
    let rows = vec![
        format!(
            "| {name} | {} | full tape of {} clauses; pruned on such a box: mean {mean_pruned:.0} clauses |",
            timed("Fidget VM interval (f32)", t_vm),
            vm.size()
        ),
        format!("| {name} | {} | full tape |", timed("Fidget JIT interval (f32)", t_jit)),
        format!(
            "| {name} | {} | full expression of {} nodes; simplified on such a box: mean {frep_mean_pruned:.0} nodes |",
            timed("frepray `Interval` (f64), `eval_with`", t_i),
            expr.len()
        ),
        format!(
            "| {name} | {} | value and slope along −z with min/max choices, as the ray intersector evaluates a segment |",
            timed("frepray `Dual<Interval, 1>` (f64), `eval_choices`", t_d)
        ),
    ];
    for r in &rows {
        eprintln!("   {r}");
    }
    Ok(rows)
}
