//! The noise patterns' kernel (`shaders/noise.wgsl`) equals its CPU f32 twin
//! (`gpu::noise`) bit for bit on lavapipe (GPU.md §3.5), and the twin agrees with
//! `render::noise`'s f64 patterns to f32 accuracy.

use crate::common;
use common::Rng;

use gpu::noise::{pattern_value, NOISE_WGSL};
use gpu::{GpuOptions, Kernel, TRIG_WGSL};
use render::noise::Pattern;

/// f32 words per case: the point, the pattern's code, its octaves (bits).
const IN: usize = 5;

/// 6 000 cases: every pattern with 1–8 octaves at points in a box of half-width 4
/// (a third), 64 (a third) and 3 000 (a sixth: far from the origin, negative lattice
/// coordinates), and at lattice points and a hair off them (a sixth).
fn cases() -> Vec<[f32; IN]> {
    let mut rng = Rng(11);
    (0..6000u32)
        .map(|i| {
            let half = match i % 6 {
                0 | 1 => 4.0,
                2 | 3 => 64.0,
                4 => 3000.0,
                _ => 0.0,
            };
            let mut p = [0.0; 3].map(|_: f64| rng.range(-half, half) as f32);
            if half == 0.0 {
                let off = if i % 12 == 5 { 0.0 } else { 1e-6 };
                p = [0; 3].map(|_| (rng.range(-20.0, 20.0).round() + off) as f32);
            }
            let kind = (i / 6) % 5;
            let octaves = 1 + (i / 30) % 8;
            [
                p[0],
                p[1],
                p[2],
                f32::from_bits(kind),
                f32::from_bits(octaves),
            ]
        })
        .collect()
}

const KERNEL: &str = "
var<private> loops: u32;
@group(0) @binding(0) var<storage, read> perm_in: array<u32>;
@group(0) @binding(1) var<storage, read> cases: array<f32>;
@group(0) @binding(2) var<storage, read_write> out: array<f32>;

fn noise_perm(i: u32) -> u32 { return perm_in[i]; }

@compute @workgroup_size(64)
fn noise_case(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (5u * i >= arrayLength(&cases)) { return; }
    let c = 5u * i;
    let p = vec3<f32>(cases[c], cases[c + 1u], cases[c + 2u]);
    out[i] = pattern_value(bitcast<u32>(cases[c + 3u]), p, bitcast<u32>(cases[c + 4u]));
}
";

fn twin(c: &[f32; IN]) -> f32 {
    pattern_value(c[3].to_bits(), [c[0], c[1], c[2]], c[4].to_bits())
}

#[test]
fn noise_kernel_equals_its_twin_bit_for_bit() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let cs = cases();
    let src = format!("{TRIG_WGSL}{NOISE_WGSL}{KERNEL}");
    let k = Kernel::new(&g, &src, "noise_case", 2).unwrap();
    let perm: Vec<u32> = scene::PERLIN_PERM.iter().map(|&x| u32::from(x)).collect();
    let words: Vec<u32> = cs.iter().flatten().map(|x| x.to_bits()).collect();
    let out = k
        .run(
            &g,
            &[&perm, &words],
            cs.len(),
            [(cs.len() as u32).div_ceil(64), 1, 1],
        )
        .unwrap();
    let mut differ = 0;
    for (i, c) in cs.iter().enumerate() {
        let want = twin(c);
        if out[i] != want.to_bits() {
            if differ < 5 {
                eprintln!("case {i} {c:?}: gpu {} twin {want}", f32::from_bits(out[i]));
            }
            differ += 1;
        }
    }
    assert_eq!(differ, 0, "{differ} of {} cases differ", cs.len());
}

/// The twin against `render::noise` (f64) at the same points, where f32 can resolve
/// them (|p| ≤ 64, octave points below 2 048): noise, fBm and turbulence within 2·10⁻⁵,
/// marble and wood (which multiply the noise by 6 and 1.2 inside a sine and a fraction
/// of 4r) within 2·10⁻⁴, except wood within 10⁻³ of a ring's edge, where f32 may fall
/// on the other side (counted, at most 1 %). Every value lies in [0, 1].
#[test]
fn twin_matches_the_f64_patterns() {
    let cs = cases();
    let (mut worst, mut edges, mut compared) = ([0.0f64; 5], 0, 0);
    for c in &cs {
        let v = twin(c);
        assert!((0.0..=1.0).contains(&v), "{c:?}: {v}");
        let p = glam::DVec3::new(c[0].into(), c[1].into(), c[2].into());
        if p.abs().max_element() > 64.0 {
            continue;
        }
        let kind = c[3].to_bits() as usize;
        let octaves = c[4].to_bits();
        let pattern = [
            Pattern::Noise,
            Pattern::Fbm,
            Pattern::Turbulence,
            Pattern::Marble,
            Pattern::Wood,
        ][kind];
        let want = pattern.value(p, octaves);
        let err = (f64::from(v) - want).abs();
        if kind == 4 && !(1e-3..=1.0 - 1e-3).contains(&want) {
            edges += 1;
            continue;
        }
        compared += 1;
        worst[kind] = worst[kind].max(err);
    }
    eprintln!("worst |twin − f64| per pattern {worst:?}; {edges} wood cases at a ring's edge of {compared}");
    for (k, &w) in worst.iter().enumerate() {
        let bound = if k < 3 { 2e-5 } else { 2e-4 };
        assert!(w <= bound, "pattern {k}: {w} > {bound}");
    }
    assert!(edges * 100 <= compared, "{edges} at ring edges");
}
