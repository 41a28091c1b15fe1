//! The compensated-sum check (GPU.md §3.2, §9 "compensated sums") for both precisions of
//! the per-pixel MIS sums, f64 (`SHADER_F64`) and double-float (f64 forced off), and the
//! double-float kernel against its CPU twin bit for bit (GPU.md §3.5).

use crate::common;
use common::Rng;

use gpu::sums::{df_add, df_value, Accumulate, Sums};
use gpu::{Gpu, GpuOptions};

/// Terms per pixel of the compensated-sum check: below llvmpipe's loop cap (GPU.md §3.1).
const TERMS: usize = 16_384;
/// Pixels of the check (one invocation each).
const PIXELS: usize = 64;

/// The terms of one pixel, by design (pixel % 4), all multiples of 2⁻⁴⁰ below 2²⁶ in
/// magnitude, so that the exact sum is an i128 count of 2⁻⁴⁰:
/// 0. 1 then tiny terms (1..7)·2⁻³⁰, each below half an f32 ulp of 1;
/// 1. ±2²⁴·(1..3) alternating with small terms k·2⁻¹⁰ (k < 2¹⁰), lost next to 2²⁴;
/// 2. k/2²⁴, k < 2²⁴ (GPU.md §3.2's measurement): sums to ~8 000 need 37 bits;
/// 3. ±m·2^e, m < 2¹², e ∈ [−28, 12]: up to 66 significant bits, beyond f64 and
///    double-float, so checked against their error bounds.
fn terms(pixel: usize, rng: &mut Rng) -> Vec<f32> {
    let p = pixel as i32;
    (0..TERMS)
        .map(|j| match pixel % 4 {
            0 if j == 0 => 1.0,
            0 => ((1 + (j + pixel) % 7) as f32) * (2f32).powi(-30),
            1 if j.is_multiple_of(2) => {
                let big = (1 + p % 3) as f32 * 16_777_216.0;
                if j.is_multiple_of(4) {
                    big
                } else {
                    -big
                }
            }
            1 => (rng.bits() % 1024) as f32 / 1024.0,
            2 => (rng.bits() % (1 << 24)) as f32 / 16_777_216.0,
            _ => {
                let m = (rng.bits() % 4096) as f32;
                let e = (rng.bits() % 41) as i32 - 28;
                let s = if rng.bits().is_multiple_of(2) {
                    1.0
                } else {
                    -1.0
                };
                s * m * (2f32).powi(e)
            }
        })
        .collect()
}

/// The exact sum in units of 2⁻⁴⁰ (every term is a multiple of it).
fn exact(ts: &[f32]) -> i128 {
    ts.iter()
        .map(|&x| {
            let v = f64::from(x) * 2f64.powi(40);
            assert_eq!(v.fract(), 0.0);
            v as i128
        })
        .sum()
}

/// The largest |partial sum|, for the error bounds.
fn max_partial(ts: &[f32]) -> f64 {
    let mut s = 0i128;
    let mut m = 0i128;
    for &x in ts {
        s += (f64::from(x) * 2f64.powi(40)) as i128;
        m = m.max(s.abs());
    }
    m as f64 * 2f64.powi(-40)
}

/// Runs the check on `g` and returns the largest relative error of designs 0–2
/// (required 0) and of design 3 (against its bound).
fn check(g: &Gpu, want_f64: bool) {
    let acc = Accumulate::new(g).unwrap();
    assert_eq!(acc.is_f64(), want_f64, "precision");
    let mut rng = Rng(3);
    let all: Vec<Vec<f32>> = (0..PIXELS).map(|p| terms(p, &mut rng)).collect();
    let flat: Vec<f32> = all.iter().flatten().copied().collect();
    let prev = if want_f64 {
        Sums::F64(vec![0.0; PIXELS])
    } else {
        Sums::DoubleFloat(vec![[0.0; 2]; PIXELS])
    };
    let got = acc.run(g, &prev, &flat, TERMS as u32, 1).unwrap().values();
    let mut naive_worst = [0f64; 4];
    let mut design3 = 0f64;
    for (p, ts) in all.iter().enumerate() {
        let want = exact(ts);
        let want_f = want as f64 * 2f64.powi(-40);
        let naive: f32 = ts.iter().sum();
        let nrel = (f64::from(naive) - want_f).abs() / want_f.abs().max(1e-300);
        naive_worst[p % 4] = naive_worst[p % 4].max(nrel);
        if p % 4 < 3 {
            // Exact: the sum fits in 53 bits, and in double-float's two 24-bit halves.
            let g_units = got[p] * 2f64.powi(40);
            assert_eq!(g_units.fract(), 0.0, "pixel {p}");
            assert_eq!(g_units as i128, want, "pixel {p}: {} vs {want_f}", got[p]);
        } else {
            let err = (got[p] - want_f).abs();
            let bound =
                TERMS as f64 * max_partial(ts) * 2f64.powi(if want_f64 { -53 } else { -47 });
            assert!(err <= bound, "pixel {p}: error {err:e} > bound {bound:e}");
            design3 = design3.max(err / max_partial(ts));
        }
    }
    eprintln!(
        "{}: designs 0–2 exact; naive f32 relative errors {naive_worst:?}; design 3 \
         error / max partial sum {design3:.2e}",
        if want_f64 { "f64" } else { "double-float" }
    );
    // The designs defeat naive f32 summation, so passing means the compensation ran.
    assert!(
        naive_worst[..3].iter().all(|&e| e > 1e-6),
        "{naive_worst:?}"
    );
}

#[test]
fn compensated_sums_are_exact_in_f64() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    if !g.info().f64 {
        eprintln!("skipped: the adapter has no SHADER_F64 (the double-float test covers it)");
        return;
    }
    check(&g, true);
}

#[test]
fn compensated_sums_are_exact_in_double_float() {
    let Some(g) = common::gpu(GpuOptions {
        f64: false,
        ..GpuOptions::default()
    }) else {
        return;
    };
    check(&g, false);
}

/// The CPU twin alone passes the same exactness (no GPU needed).
#[test]
fn double_float_twin_is_exact_on_the_cpu() {
    let mut rng = Rng(3);
    for p in 0..PIXELS {
        let ts = terms(p, &mut rng);
        let s = ts.iter().fold([0.0f32; 2], |a, &v| df_add(a, v));
        if p % 4 < 3 {
            assert_eq!(df_value(s), exact(&ts) as f64 * 2f64.powi(-40), "pixel {p}");
        }
    }
}

/// MIS-like per-pixel state: 15 sums (GPU.md §8), 64 samples of terms in (0, 1] of
/// mixed magnitude, added to a nonzero previous state.
fn mis_batch(rng: &mut Rng, pixels: usize) -> (Vec<f32>, Vec<[f32; 2]>) {
    let terms = (0..pixels * 64 * 15)
        .map(|_| (rng.next() * 2f64.powi(-((rng.bits() % 20) as i32))) as f32)
        .collect();
    let prev = (0..pixels * 15)
        .map(|_| {
            let v = rng.next() * 100.0;
            let hi = v as f32;
            [hi, (v - f64::from(hi)) as f32]
        })
        .collect();
    (terms, prev)
}

#[test]
fn double_float_kernel_equals_its_twin_bit_for_bit() {
    let Some(g) = common::gpu(GpuOptions {
        f64: false,
        ..GpuOptions::default()
    }) else {
        return;
    };
    let pixels = 256;
    let (terms, prev) = mis_batch(&mut Rng(9), pixels);
    let acc = Accumulate::new(&g).unwrap();
    let Sums::DoubleFloat(got) = acc
        .run(&g, &Sums::DoubleFloat(prev.clone()), &terms, 64, 15)
        .unwrap()
    else {
        panic!("double-float expected");
    };
    for p in 0..pixels {
        for k in 0..15 {
            let want = (0..64).fold(prev[p * 15 + k], |a, j| {
                df_add(a, terms[(p * 64 + j) * 15 + k])
            });
            let g = got[p * 15 + k];
            assert_eq!(
                [g[0].to_bits(), g[1].to_bits()],
                [want[0].to_bits(), want[1].to_bits()],
                "pixel {p} sum {k}: {g:?} vs {want:?}"
            );
        }
    }
}

#[test]
fn f64_kernel_equals_the_cpu_sum_bit_for_bit() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    if !g.info().f64 {
        eprintln!("skipped: the adapter has no SHADER_F64");
        return;
    }
    let pixels = 256;
    let (terms, prev) = mis_batch(&mut Rng(10), pixels);
    let prev: Vec<f64> = prev.iter().map(|&x| df_value(x)).collect();
    let acc = Accumulate::new(&g).unwrap();
    let Sums::F64(got) = acc
        .run(&g, &Sums::F64(prev.clone()), &terms, 64, 15)
        .unwrap()
    else {
        panic!("f64 expected");
    };
    for p in 0..pixels {
        for k in 0..15 {
            let want = (0..64).fold(prev[p * 15 + k], |a, j| {
                a + f64::from(terms[(p * 64 + j) * 15 + k])
            });
            assert_eq!(
                got[p * 15 + k].to_bits(),
                want.to_bits(),
                "pixel {p} sum {k}"
            );
        }
    }
}
