//! The environment kernel equals its CPU f32 twin bit for bit on lavapipe (GPU.md §3.5,
//! §9 "light sample/pdf"); the twin agrees with `render::light::Environment` (f64) to
//! f32 accuracy, and its samples' pdfs equal its pdf at the sampled directions.

use crate::common;
use common::Rng;

use glam::{DMat3, DVec2, DVec3};
use gpu::env::{self, GpuEnv, ENV_WGSL};
use gpu::light::{GPU_AREA_LIGHT_WGSL, LIGHT_WGSL};
use gpu::TRIG_WGSL;
use gpu::{GpuOptions, Kernel};
use render::light::{EnvMap, Environment};
use render::Rgb;

/// Cases per environment.
const N: usize = 8192;
/// f32 words per case: d (a unit direction), u, environment index.
const IN: usize = 6;
/// f32 words out per case: radiance(d), pdf(d), sampled wi, its pdf, ok, pdf(wi).
const OUT: usize = 10;

/// A 32 × 16 map with a bright pixel, smooth variation, a black row and a black column
/// (zero-probability cells), turned by `to_world`.
fn map_pixels(w: usize, h: usize) -> Vec<[f64; 3]> {
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let v = if x == 5 && y == 4 {
                80.0
            } else if y == 11 || x == 20 {
                0.0
            } else {
                0.2 + ((x * 7 + y * 3) % 11) as f64 * 0.3
            };
            [
                v,
                0.5 * v + 0.1 * (y as f64),
                if y < 8 { 1.0 } else { 0.25 },
            ]
        })
        .collect()
}

/// The environments tested, each as the GPU packs it and as `render` samples it (f64):
/// a dome, an upright map and a turned one.
fn environments(tables: &mut Vec<f32>) -> Vec<(GpuEnv, Environment, Option<scene::EnvMapTable>)> {
    let (w, h) = (32, 16);
    let pixels = map_pixels(w, h);
    let table = scene::EnvMapTable::new(w, h, pixels);
    let mut out = vec![(
        GpuEnv::constant([0.3, 0.5, 0.7]),
        Environment::Constant(Rgb::new(0.3, 0.5, 0.7)),
        None,
    )];
    for rot in [
        DMat3::IDENTITY,
        DMat3::from_rotation_x(0.4) * DMat3::from_rotation_z(1.1),
    ] {
        // Rounded to f32 first, so that both sides turn by the same matrix.
        let cols = rot
            .to_cols_array_2d()
            .map(|c| c.map(|v| f64::from(v as f32)));
        let g = GpuEnv::map(&table, &cols, tables);
        let m = EnvMap::from_table(&table, DMat3::from_cols_array_2d(&cols));
        out.push((g, Environment::Map(m), Some(table.clone())));
    }
    out
}

/// N cases per environment: a unit direction (some on the poles and the φ = 0 seam), u
/// (some at 0 and just below 1).
fn cases(n_env: usize) -> Vec<[f32; IN]> {
    let mut rng = Rng(17);
    (0..n_env * N)
        .map(|i| {
            let mut d = DVec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5);
            match i % 16 {
                0 => d = DVec3::new(0.0, 0.0, if i % 32 == 0 { 1.0 } else { -1.0 }),
                1 => d.y = 0.0,
                _ => {}
            }
            let d = d.normalize().as_vec3();
            let mut u = [rng.next() as f32, rng.next() as f32];
            if i % 16 == 2 {
                u = [0.0, 1.0f32.next_down()];
            }
            [d.x, d.y, d.z, u[0], u[1], f32::from_bits((i / N) as u32)]
        })
        .collect()
}

/// The twin's answer for one case, in the kernel's output order.
fn twin(envs: &[GpuEnv], buf: &[f32], c: &[f32; IN]) -> [f32; OUT] {
    let e = &envs[c[5].to_bits() as usize];
    let d = [c[0], c[1], c[2]];
    let mut o = [0.0; OUT];
    o[..3].copy_from_slice(&env::radiance(e, buf, d));
    o[3] = env::pdf(e, buf, d);
    if let Some((wi, pdf)) = env::sample(e, buf, [c[3], c[4]]) {
        o[4..7].copy_from_slice(&wi);
        o[7] = pdf;
        o[8] = 1.0;
        o[9] = env::pdf(e, buf, wi);
    }
    o
}

const KERNEL: &str = "
@group(0) @binding(0) var<storage, read> envs: array<GpuEnv>;
@group(0) @binding(1) var<storage, read> cases: array<f32>;
@group(0) @binding(2) var<storage, read> sel_buf: array<f32>;
@group(0) @binding(3) var<storage, read_write> out: array<f32>;

@compute @workgroup_size(64)
fn env_case(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (6u * i >= arrayLength(&cases)) { return; }
    let c = 6u * i;
    let o = 10u * i;
    let e = envs[bitcast<u32>(cases[c + 5u])];
    let d = vec3<f32>(cases[c], cases[c + 1u], cases[c + 2u]);
    let r = env_radiance(e, d);
    out[o] = r.x; out[o + 1u] = r.y; out[o + 2u] = r.z;
    out[o + 3u] = env_pdf(e, d);
    let s = env_sample(e, vec2<f32>(cases[c + 3u], cases[c + 4u]));
    if (s.ok != 0u) {
        out[o + 4u] = s.wi.x; out[o + 5u] = s.wi.y; out[o + 6u] = s.wi.z;
        out[o + 7u] = s.pdf;
        out[o + 8u] = 1.0;
        out[o + 9u] = env_pdf(e, s.wi);
    }
}
";

#[test]
fn env_kernel_equals_its_twin_bit_for_bit() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let mut buf = Vec::new();
    let envs: Vec<GpuEnv> = environments(&mut buf).into_iter().map(|e| e.0).collect();
    let cs = cases(envs.len());
    let src = format!("{TRIG_WGSL}{GPU_AREA_LIGHT_WGSL}{LIGHT_WGSL}{ENV_WGSL}{KERNEL}");
    let k = Kernel::new(&g, &src, "env_case", 3).unwrap();
    let c_words: Vec<u32> = cs.iter().flatten().map(|x| x.to_bits()).collect();
    let b_words: Vec<u32> = buf.iter().map(|x| x.to_bits()).collect();
    let out = k
        .run(
            &g,
            &[bytemuck::cast_slice(&envs), &c_words, &b_words],
            OUT * cs.len(),
            [(cs.len() as u32).div_ceil(64), 1, 1],
        )
        .unwrap();
    let mut differ = 0;
    for (i, c) in cs.iter().enumerate() {
        let want = twin(&envs, &buf, c).map(f32::to_bits);
        let got = &out[OUT * i..OUT * (i + 1)];
        if got != want {
            if differ < 5 {
                let got: Vec<f32> = got.iter().map(|&w| f32::from_bits(w)).collect();
                eprintln!(
                    "case {i}: gpu {got:?}\n twin {:?}",
                    want.map(f32::from_bits)
                );
            }
            differ += 1;
        }
    }
    assert_eq!(differ, 0, "{differ} of {} cases differ", cs.len());
}

/// The twin against `render`'s f64 environment on the same (f32-rounded) rotation:
/// - radiance(d): the same pixel, except for directions within 1e-5 of a pixel's edge in
///   u or v (counted; f32 may round them into the neighbour);
/// - pdf(d): relative error below 2e-5 away from those edges (the tables are f32);
/// - sample(u): the f32 CDFs carry ~2⁻²⁴ absolute error, which a cell of CDF width w
///   among n turns into Δv ≈ 2⁻²⁴/(w n) (and Δu likewise): the direction is compared
///   within π Δv + 2π Δu sin θ + 1e-6, the pdf within 2e-5 + π Δv |cot θ| (relative),
///   with Δ taken as 8 × 2⁻²⁴/(w n); a u within 1e-6 of a CDF value may pick the
///   neighbouring cell in f32 (counted);
/// - the pdf at a sampled direction equals the sample's pdf (relative 2e-5) except near
///   cell edges, where f32 may find the neighbouring cell: at most 1 % of the samples.
#[test]
fn twin_matches_the_f64_environment() {
    let mut buf = Vec::new();
    let envs = environments(&mut buf);
    let cs = cases(envs.len());
    let (mut edges, mut split, mut resampled, mut sampled) = (0, 0, 0, 0);
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-30);
    let near_edge = |x: f64, n: u32| {
        let f = x * f64::from(n);
        (f - f.round()).abs() < 1e-5 * f64::from(n)
    };
    // The cell u falls in, its CDF width, and whether u is within 1e-6 of a CDF value.
    let cell = |d: &scene::Distribution1D, u: f64| {
        let i = d.cdf.partition_point(|&c| c <= u).max(1) - 1;
        let i = i.min(d.func.len() - 1);
        let tie = d.cdf.iter().any(|&c| (c - u).abs() < 1e-6);
        (i, d.cdf[i + 1] - d.cdf[i], tie)
    };
    const EPS: f64 = f32::EPSILON as f64 / 2.0;
    // Cases 0–2 of every 16 sit on poles, the seam or u's ends on purpose: their edges
    // are skipped, not counted.
    let mut random = 0;
    for (i, c) in cs.iter().enumerate() {
        let chosen = i % 16 < 3;
        random += usize::from(!chosen);
        let (g, e64, table) = &envs[c[5].to_bits() as usize];
        let d = DVec3::new(c[0].into(), c[1].into(), c[2].into());
        let (u, v, _) = env::uv(g, [c[0], c[1], c[2]]);
        let edge =
            g.kind == env::MAP && (near_edge(u.into(), g.width) || near_edge(v.into(), g.height));
        let r32 = env::radiance(g, &buf, [c[0], c[1], c[2]]).map(f64::from);
        let r64 = e64.radiance(d).to_array();
        let p32 = f64::from(env::pdf(g, &buf, [c[0], c[1], c[2]]));
        let p64 = e64.pdf(d);
        if edge {
            edges += usize::from(!chosen);
        } else {
            for k in 0..3 {
                assert!(
                    rel(r32[k], r64[k]) < 1e-6,
                    "radiance {r32:?} vs {r64:?} at {d}"
                );
            }
            assert!(rel(p32, p64) < 2e-5, "pdf {p32} vs {p64} at {d}");
        }
        let u2 = DVec2::new(c[3].into(), c[4].into());
        let s32 = env::sample(g, &buf, [c[3], c[4]]);
        let s64 = e64.sample(u2);
        let (Some((w32, pdf32)), Some((w64, pdf64))) = (s32, s64) else {
            assert_eq!(s32.is_some(), s64.is_some(), "sample at {u2}");
            continue;
        };
        sampled += usize::from(!chosen);
        let w32 = DVec3::new(w32[0].into(), w32[1].into(), w32[2].into());
        let (mut dv, mut du) = (0.0, 0.0);
        if let Some(t) = table {
            let dist = &t.distribution;
            let (row, wv, tv) = cell(&dist.marginal, u2.y);
            let (_, wu, tu) = cell(&dist.conditional[row], u2.x);
            if tv || tu {
                split += usize::from(!chosen);
                continue;
            }
            dv = 8.0 * EPS / (wv * f64::from(g.height));
            du = 8.0 * EPS / (wu * f64::from(g.width));
        }
        // sin θ in the map's frame (the dome's is the scene's).
        let sin64 = match table {
            Some(_) => f64::from(env::uv(g, w64.as_vec3().to_array()).2),
            None => (1.0 - w64.z * w64.z).max(0.0).sqrt(),
        };
        let cot = (1.0 - sin64 * sin64).max(0.0).sqrt() / sin64.max(1e-12);
        let dir_tol = std::f64::consts::PI * dv + std::f64::consts::TAU * du * sin64 + 1e-6;
        assert!(
            (w32 - w64).length() < dir_tol,
            "sample at {u2}: {w32} vs {w64} (tolerance {dir_tol})"
        );
        let pdf_tol = 2e-5 + std::f64::consts::PI * dv * cot;
        assert!(
            rel(pdf32.into(), pdf64) < pdf_tol,
            "sample pdf {pdf32} vs {pdf64} (tolerance {pdf_tol})"
        );
        let again = env::pdf(g, &buf, w32.as_vec3().to_array());
        if rel(again.into(), pdf32.into()) > 2e-5 {
            resampled += usize::from(!chosen);
        }
    }
    eprintln!(
        "{edges} directions near a pixel edge, {split} of {sampled} samples at a CDF value, \
         {resampled} samples whose pdf at their direction differs"
    );
    assert!(edges * 100 < random, "{edges} edge directions");
    assert!(split * 100 < sampled, "{split} samples at CDF values");
    assert!(
        resampled * 100 < sampled,
        "{resampled} samples' pdfs differ"
    );
}
