//! The light BVH on the GPU (`light-bvh`): the kernel's descent and pmf equal their CPU
//! f32 twins bit for bit on lavapipe (GPU.md §3.5), and the twins agree with
//! `render::light::LightTree` (f64) on the same tree: the same light drawn wherever `u`
//! is not within f32 rounding of a branch's boundary, and the same probabilities to f32
//! accuracy.

use crate::common;
use common::Rng;

use glam::DVec3;
use gpu::light::{self, GPU_AREA_LIGHT_WGSL, LIGHT_WGSL};
use gpu::TRIG_WGSL;
use gpu::{GpuOptions, Kernel};
use render::light::{ImportanceBounds, LightTree};

/// f32 words per case: p, n, u, a light k (bits).
const IN: usize = 8;
/// f32 words out per case: the light drawn (bits) and its probability, the pmf of k, the
/// pmf of the light drawn.
const OUT: usize = 4;
/// Cases per tree.
const N: usize = 4096;

const KERNEL: &str = "
@group(0) @binding(0) var<storage, read> cases: array<f32>;
@group(0) @binding(1) var<storage, read> sel_buf: array<f32>;
@group(0) @binding(2) var<storage, read_write> out: array<f32>;

// sel_buf: the trails' offset (bits), then the tree's records from word 1.
@compute @workgroup_size(64)
fn tree_case(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (8u * i >= arrayLength(&cases)) { return; }
    let c = 8u * i;
    let p = vec3<f32>(cases[c], cases[c + 1u], cases[c + 2u]);
    let n = vec3<f32>(cases[c + 3u], cases[c + 4u], cases[c + 5u]);
    let trails = bitcast<u32>(sel_buf[0]);
    let s = tree_sample(1u, p, n, cases[c + 6u]);
    out[4u * i] = s.x;
    out[4u * i + 1u] = s.y;
    out[4u * i + 2u] = tree_pmf(1u, trails, p, n, bitcast<u32>(cases[c + 7u]));
    var back = 0.0;
    if (bitcast<u32>(s.x) != 0xffffffffu) {
        back = tree_pmf(1u, trails, p, n, bitcast<u32>(s.x));
    }
    out[4u * i + 3u] = back;
}
";

fn r32(x: f64) -> f64 {
    f64::from(x as f32)
}

/// `count` lights with f32-exact bounds over a box of side 20: spheres (a full cone),
/// one- and two-sided planar lights, a few without power.
fn lights(count: usize, seed: u64) -> Vec<(ImportanceBounds, f64)> {
    let mut rng = Rng(seed);
    let mut v = |s: f64| DVec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
    (0..count)
        .map(|k| {
            let center = v(10.0).as_vec3().as_dvec3();
            let axis = v(1.0).normalize().as_vec3().as_dvec3();
            let radius = r32(0.01 + 0.5 * (k as f64 * 0.618).fract());
            let sphere = k % 3 == 0;
            let bounds = ImportanceBounds {
                center,
                radius,
                axis: if sphere { DVec3::Z } else { axis },
                cos_o: if sphere { -1.0 } else { 1.0 },
                two_sided: k % 3 == 2,
            };
            let phi = if k % 17 == 5 {
                0.0
            } else {
                r32(0.1 + 100.0 * (k as f64 * 0.414).fract())
            };
            (bounds, phi)
        })
        .collect()
}

/// N cases: a point inside or around the lights' box, a unit normal (zero, as at a
/// point inside a medium, in one case of four, with either sign), u, a light.
fn cases(count: usize, seed: u64) -> Vec<[f32; IN]> {
    let mut rng = Rng(seed);
    (0..N)
        .map(|i| {
            let p = DVec3::new(
                rng.range(-12.0, 12.0),
                rng.range(-12.0, 12.0),
                rng.range(-12.0, 12.0),
            )
            .as_vec3();
            let n = DVec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            )
            .normalize()
            .as_vec3();
            let n = match i % 8 {
                3 => glam::Vec3::ZERO,
                7 => glam::Vec3::new(-0.0, 0.0, -0.0),
                _ => n,
            };
            let u = rng.next() as f32;
            let k = ((rng.next() * count as f64) as u32).min(count as u32 - 1);
            [p.x, p.y, p.z, n.x, n.y, n.z, u, f32::from_bits(k)]
        })
        .collect()
}

/// The tree's words as the test kernel reads them (trails' offset first).
fn buffer(tree: &LightTree) -> Vec<f32> {
    let (words, trails) = light::tree_records(&tree.table());
    let mut buf = vec![f32::from_bits(1 + trails as u32)];
    buf.extend(words);
    buf
}

/// The twin's answer for one case, in the kernel's output order.
fn twin(buf: &[f32], c: &[f32; IN]) -> [f32; OUT] {
    let (p, n) = ([c[0], c[1], c[2]], [c[3], c[4], c[5]]);
    let trails = buf[0].to_bits() as usize;
    let s = light::tree_sample(buf, 1, p, n, c[6]);
    let k = c[7].to_bits() as usize;
    [
        f32::from_bits(s.map_or(u32::MAX, |s| s.0)),
        s.map_or(0.0, |s| s.1),
        light::tree_pmf(buf, 1, trails, p, n, k),
        s.map_or(0.0, |s| light::tree_pmf(buf, 1, trails, p, n, s.0 as usize)),
    ]
}

/// Trees of 1, 10 and 300 lights.
const SIZES: [(usize, u64); 3] = [(1, 3), (10, 4), (300, 5)];

#[test]
fn light_tree_kernel_equals_its_twin_bit_for_bit() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let src = format!("{TRIG_WGSL}{GPU_AREA_LIGHT_WGSL}{LIGHT_WGSL}{KERNEL}");
    let k = Kernel::new(&g, &src, "tree_case", 2).unwrap();
    for (count, seed) in SIZES {
        let tree = LightTree::new(&lights(count, seed)).unwrap();
        let buf = buffer(&tree);
        let cs = cases(count, seed + 10);
        let c_words: Vec<u32> = cs.iter().flatten().map(|x| x.to_bits()).collect();
        let s_words: Vec<u32> = buf.iter().map(|x| x.to_bits()).collect();
        let out = k
            .run(
                &g,
                &[&c_words, &s_words],
                OUT * cs.len(),
                [(cs.len() as u32).div_ceil(64), 1, 1],
            )
            .unwrap();
        let mut differ = 0;
        for (i, c) in cs.iter().enumerate() {
            let want: Vec<u32> = twin(&buf, c).iter().map(|x| x.to_bits()).collect();
            let got = &out[OUT * i..OUT * (i + 1)];
            if got != &want[..] {
                if differ < 5 {
                    eprintln!("{count} lights, case {i}: gpu {got:x?}\n twin {want:x?}");
                }
                differ += 1;
            }
        }
        assert_eq!(
            differ,
            0,
            "{count} lights: {differ} of {} cases differ",
            cs.len()
        );
    }
}

/// The twin against the f64 tree it was written from. The nodes' bounds are rounded to
/// f32 and the importances computed in f32, whose cosines of differences cancel (as the
/// spatial selection's importance, `light_twin`): a probability is compared by its
/// absolute difference, within 10⁻⁴ (measured and printed). The light drawn is the f64
/// tree's unless `u` falls within 10⁻⁴ of a branch boundary (counted: they must be
/// rare); the pmf of the light drawn is the draw's own probability bit for bit, and the
/// pmfs of all lights sum to the f64 tree's sum (1 less the mass lost below nodes
/// whose children both have importance 0, where a draw finds no light).
#[test]
fn light_tree_twin_matches_the_f64_tree() {
    for (count, seed) in SIZES {
        let tree = LightTree::new(&lights(count, seed)).unwrap();
        let buf = buffer(&tree);
        let trails = buf[0].to_bits() as usize;
        let (mut worst, mut near, mut mass, mut lost) = (0f64, 0, 0f64, 0f64);
        for (i, c) in cases(count, seed + 10).iter().enumerate() {
            let (p32, n32) = ([c[0], c[1], c[2]], [c[3], c[4], c[5]]);
            let p = DVec3::new(c[0].into(), c[1].into(), c[2].into());
            let n = DVec3::new(c[3].into(), c[4].into(), c[5].into());
            let u = f64::from(c[6]);
            let s32 = light::tree_sample(&buf, 1, p32, n32, c[6]);
            let s64 = tree.sample(p, n, u);
            match (s32, s64) {
                (Some((k32, pm32)), Some((k64, pm64))) if k32 as usize == k64 => {
                    worst = worst.max((f64::from(pm32) - pm64).abs());
                    assert_eq!(
                        light::tree_pmf(&buf, 1, trails, p32, n32, k64).to_bits(),
                        pm32.to_bits(),
                        "case {i}: the drawn light's pmf"
                    );
                }
                (None, None) => {}
                (a, b) => {
                    // Only where u lies at a branch boundary: the f64 draw with u moved
                    // by 10⁻⁴ either way must reach the f32 draw.
                    let k32 = a.map(|s| s.0 as usize);
                    let moved = [u - 1e-4, u + 1e-4]
                        .map(|v| tree.sample(p, n, v.clamp(0.0, 1.0 - 1e-12)).map(|s| s.0));
                    assert!(
                        moved.contains(&k32),
                        "case {i}: f32 draws {a:?}, f64 {b:?}, f64 at u ± 1e-4 {moved:?}"
                    );
                    near += 1;
                }
            }
            let k = c[7].to_bits() as usize;
            let (a, b) = (
                light::tree_pmf(&buf, 1, trails, p32, n32, k),
                tree.pmf(p, n, k),
            );
            worst = worst.max((f64::from(a) - b).abs());
            if i % 64 == 0 {
                let sum32: f64 = (0..count)
                    .map(|k| f64::from(light::tree_pmf(&buf, 1, trails, p32, n32, k)))
                    .sum();
                let sum64: f64 = (0..count).map(|k| tree.pmf(p, n, k)).sum();
                mass = mass.max((sum32 - sum64).abs());
                lost = lost.max(1.0 - sum64);
            }
        }
        eprintln!(
            "{count} lights: pmf |Δ| {worst:.2e}, draws at a boundary {near} of {N}, \
             |Δ Σ pmf| {mass:.2e} (the f64 tree's mass lost below nodes whose children \
             both have importance 0: up to {lost:.2e})"
        );
        assert!(worst < 1e-4, "{count} lights: pmf |Δ| {worst:e}");
        assert!(
            near <= N / 200,
            "{count} lights: {near} draws at a boundary"
        );
        assert!(mass < 1e-4, "{count} lights: Σ pmf differs by {mass:e}");
    }
}
