//! The per-sample record terms (GPU.md §8): the kernel equals its CPU twin bit for bit
//! on lavapipe (GPU.md §3.5), and the twin adds what the CPU's accumulator adds for the
//! same records (to f32 rounding), for every record that is a sum of per-sample terms:
//! the heuristics on `direct` (blocks) and on `path` (the outside sum), optimal-direct
//! and optimal-uncorrelated, per light, with AOVs and `min_depth`, and the AOV
//! integrators. The waves are synthetic: random statuses, flags, pdfs (a fifth zero)
//! and integrands, paths ending at random depths, a few overflowing slots.

use crate::common;

use common::Rng;
use gpu::direct::{add_slot, draw_words, DRAW_HEAD_WORDS, HIT_WORDS};
use gpu::record::{slot_terms, RecordParams, RecordTerms, TALLY_LIST};
use gpu::GpuOptions;
use render::integrator::{Accumulator, IntegratorKind, RayCounts, Record, RenderOptions};
use render::scene::Scene;
use render::Technique;
use std::path::Path;

/// A floor under three sphere lights (three MIS lights for per-light mode).
const SCENE: &str = r#"
[camera]
eye = [0, -4, 2]
target = [0, 0, 0]
up = [0, 0, 1]
fov = 40
resolution = [8, 4]

[materials.floor]
type = "diffuse"
reflectance = [0.5, 0.5, 0.5]

[[objects]]
solid = "box(center = [0, 0, -0.05], size = [6, 6, 0.1])"
material = "floor"

[[lights]]
type = "sphere"
center = [-1, 0, 2]
radius = 0.2
power = 50

[[lights]]
type = "sphere"
center = [1, 0, 2]
radius = 0.3
power = 80

[[lights]]
type = "sphere"
center = [0, 1, 2]
radius = 0.1
power = 20
"#;

/// The cases: a label and the options that differ from the defaults.
fn cases() -> Vec<(String, RenderOptions)> {
    let base = RenderOptions {
        techniques: vec![
            (Technique::Bsdf, 2),
            (Technique::LightPower, 1),
            (Technique::LightArea, 1),
        ],
        ..RenderOptions::default()
    };
    let mut out = Vec::new();
    for method in [
        mis::Method::Balance,
        mis::Method::Power,
        mis::Method::Maximum,
        mis::Method::Cutoff,
        mis::Method::OptimalDirect,
        mis::Method::OptimalUncorrelated,
        mis::Method::OptimalProgressive,
        mis::Method::OptimalFull,
    ] {
        for integrator in [IntegratorKind::Direct, IntegratorKind::Path] {
            let mut o = RenderOptions {
                method,
                integrator,
                // No solve within the test's samples: α stays 0, so that the CPU's Σ F
                // is the terms' Σ G (the progressive estimators).
                params: mis::Params {
                    warmup: 1000,
                    train: 1000,
                    ..mis::Params::default()
                },
                max_depth: if integrator == IntegratorKind::Path {
                    3
                } else {
                    1
                },
                ..base.clone()
            };
            out.push((format!("{} {integrator:?}", method.name()), o.clone()));
            if integrator == IntegratorKind::Path {
                o.min_depth = 2;
                out.push((format!("{} path, min depth 2", method.name()), o));
            }
        }
    }
    for method in [
        mis::Method::OptimalDirect,
        mis::Method::Balance,
        mis::Method::OptimalProgressive,
    ] {
        out.push((
            format!("{} per light, AOVs", method.name()),
            RenderOptions {
                method,
                per_light: 3,
                aovs: render::integrator::Aov::ALL.to_vec(),
                params: mis::Params {
                    warmup: 1000,
                    ..mis::Params::default()
                },
                ..base.clone()
            },
        ));
    }
    // Ten techniques, their pdfs over three vec4s of a draw record (T² moments).
    for method in [
        mis::Method::Balance,
        mis::Method::Power,
        mis::Method::OptimalDirect,
        mis::Method::OptimalProgressive,
    ] {
        out.push((
            format!("{} over ten techniques", method.name()),
            RenderOptions {
                method,
                techniques: vec![
                    (Technique::Bsdf, 1),
                    (Technique::LightPower, 1),
                    (Technique::LightArea, 1),
                    (Technique::LightUniform, 1),
                    (Technique::LightSpatial, 1),
                    (Technique::LightBvh, 1),
                    (Technique::CosineHemisphere, 1),
                    (Technique::Light(0), 1),
                    (Technique::Light(1), 2),
                    (Technique::Light(2), 1),
                ],
                params: mis::Params {
                    warmup: 1000,
                    train: 1000,
                    ..mis::Params::default()
                },
                ..base.clone()
            },
        ));
    }
    for integrator in [
        IntegratorKind::Depth,
        IntegratorKind::Normals,
        IntegratorKind::Albedo,
    ] {
        out.push((
            format!("{integrator:?}"),
            RenderOptions {
                integrator,
                aovs: render::integrator::Aov::ALL.to_vec(),
                ..base.clone()
            },
        ));
    }
    out
}

/// A synthetic wave for `p` (its `slots` set): hit records and draw records.
fn wave(rng: &mut Rng, p: &RecordParams, lights: u32) -> (Vec<f32>, Vec<f32>) {
    let slots = p.slots as usize;
    let mut hits = vec![0f32; slots * HIT_WORDS];
    let words = draw_words(p.n_tech);
    let mut draws = vec![0f32; p.max_depth as usize * slots * p.per_slot as usize * words];
    let value = |rng: &mut Rng, zero: f64| {
        if rng.next() < zero {
            0.0
        } else {
            rng.range(0.0, 3.0) as f32
        }
    };
    for slot in 0..slots {
        let h = &mut hits[slot * HIT_WORDS..(slot + 1) * HIT_WORDS];
        h[3] = if rng.next() < 0.03 { 2.0 } else { 1.0 };
        for w in (12..15).chain(32..39) {
            h[w] = value(rng, 0.3);
        }
        let len = (rng.next() * f64::from(p.max_depth + 1)) as u32;
        for d in 0..p.max_depth {
            for j in 0..p.per_slot {
                let at = ((d * p.slots + slot as u32) * p.per_slot + j) as usize * words;
                let r = &mut draws[at..at + words];
                if d >= len {
                    r[7] = if rng.next() < 0.002 { 12.0 } else { 0.0 };
                    continue;
                }
                let statuses = [1.0, 2.0, 4.0, 4.0, 4.0, 5.0, 6.0, 7.0];
                r[7] = statuses[(rng.next() * statuses.len() as f64) as usize];
                if rng.next() < 0.002 {
                    r[7] = 12.0;
                }
                for x in &mut r[8..11] {
                    *x = value(rng, 0.1);
                }
                let mut flags = u32::from(rng.next() < 0.05);
                if j == 0 && rng.next() < 0.05 {
                    flags |= 2;
                }
                let light = (rng.next() * f64::from(lights + 1)) as u32;
                flags |= 4 * light;
                r[11] = flags as f32;
                for t in 0..p.n_tech as usize {
                    r[DRAW_HEAD_WORDS + t] = value(rng, 0.2);
                }
            }
        }
    }
    (hits, draws)
}

struct Case {
    label: String,
    acc: Accumulator,
    p: RecordParams,
    hits: Vec<f32>,
    draws: Vec<f32>,
}

fn build() -> Vec<Case> {
    let (data, _) = scene::parse(SCENE, scene::SceneFormat::Toml, Path::new("record.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    let scene = Scene::from_data(&data);
    let mut rng = Rng(7);
    cases()
        .into_iter()
        .map(|(label, o)| {
            let acc = Accumulator::new(&scene, &o).unwrap_or_else(|e| panic!("{label}: {e}"));
            let linear = acc.linear().expect("a linear record");
            let n_draws: u32 = acc.counts.iter().sum();
            // Vertex depths as the `direct` kernels record them.
            let depths = match o.integrator {
                IntegratorKind::Path => o.max_depth,
                _ => 1,
            };
            // The techniques' draws, the extra draw and one point light.
            let mut p = RecordParams::new(&linear, n_draws, n_draws + 2, depths);
            (p.pixels, p.samples) = (5, 4);
            p.slots = p.pixels * p.samples;
            p.start = 3;
            let (hits, draws) = wave(&mut rng, &p, linear.record.lights as u32);
            Case {
                label,
                acc,
                p,
                hits,
                draws,
            }
        })
        .collect()
}

/// The twin's terms of every slot, at the kernel's offsets, and its tally.
fn twin(c: &Case) -> (Vec<f32>, Vec<RecordSlot>) {
    let p = &c.p;
    let mut terms = vec![0f32; (p.pixels * p.samples * p.stride) as usize];
    let mut tallies = Vec::new();
    for slot in 0..p.slots {
        let at = ((slot % p.pixels) * p.samples + slot / p.pixels) * p.stride;
        let out = &mut terms[at as usize..(at + p.stride) as usize];
        tallies.push(slot_terms(p, slot, &c.hits, &c.draws, out));
    }
    (terms, tallies)
}

type RecordSlot = gpu::record::SlotTally;

/// The kernel against its twin, bit for bit, and the tally's counts and overflow list.
#[test]
fn kernel_equals_the_twin() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let kernel = RecordTerms::new(&g).unwrap();
    for c in build() {
        let (terms, tally) = kernel.run(&g, &c.p, &c.hits, &c.draws).unwrap();
        let (want, slots) = twin(&c);
        let differ = terms
            .iter()
            .zip(&want)
            .filter(|(a, b)| a.to_bits() != b.to_bits())
            .count();
        assert_eq!(
            differ,
            0,
            "{}: {differ} of {} terms differ",
            c.label,
            want.len()
        );
        let sum = |f: fn(&RecordSlot) -> u32| slots.iter().map(f).sum::<u32>();
        assert_eq!(
            tally[1..4],
            [sum(|s| s.camera), sum(|s| s.shadow), sum(|s| s.secondary)],
            "{}: ray counts",
            c.label
        );
        let mut list = tally[TALLY_LIST..TALLY_LIST + tally[0] as usize].to_vec();
        list.sort_unstable();
        let want: Vec<u32> = (0..c.p.slots)
            .filter(|&s| slots[s as usize].overflow)
            .collect();
        assert_eq!(list, want, "{}: overflow list", c.label);
    }
}

/// The twin's terms, summed per pixel in f64, against the CPU's accumulator on the same
/// records: every word within 2·10⁻⁶ of its magnitude (the terms are f32 and non-negative,
/// so no sum cancels), the same ray counts and the same overflowing slots.
#[test]
fn twin_adds_what_the_cpu_accumulator_adds() {
    for c in build() {
        let p = &c.p;
        let stride = p.stride as usize;
        let (terms, slots) = twin(&c);
        let mut ours = vec![0f64; p.pixels as usize * stride];
        for (k, t) in terms.iter().enumerate() {
            let pixel = k / stride / p.samples as usize;
            ours[pixel * stride + k % stride] += f64::from(*t);
        }
        let mut cpu = vec![0f64; p.pixels as usize * stride];
        let mut rays = RayCounts::default();
        let t = c.acc.techniques.len();
        let mut pdfs = vec![0f64; (p.max_depth * p.n_draws) as usize * t];
        for slot in 0..p.slots {
            let hw = &c.hits[slot as usize * HIT_WORDS..(slot as usize + 1) * HIT_WORDS];
            let words = draw_words(p.n_tech);
            let per = p.per_slot as usize * words;
            let vertex = |d: u32| {
                let at = (d * p.slots + slot) as usize * per;
                &c.draws[at..at + per]
            };
            let overflow = hw[3] == 2.0
                || (0..p.max_depth).any(|d| vertex(d).chunks(words).any(|r| r[7] == 12.0));
            assert_eq!(overflow, slots[slot as usize].overflow, "{}", c.label);
            if overflow {
                continue;
            }
            let pixel = (slot % p.pixels) as usize;
            let rec = &mut cpu[pixel * stride..(pixel + 1) * stride];
            let index = p.start + slot / p.pixels;
            add_slot(
                &c.acc,
                rec,
                index,
                hw,
                &vertex,
                p.n_draws,
                p.max_depth,
                &mut pdfs,
                &mut rays,
            );
        }
        let sum = |f: fn(&RecordSlot) -> u32| u64::from(slots.iter().map(f).sum::<u32>());
        assert_eq!(
            [rays.camera, rays.shadow, rays.secondary],
            [sum(|s| s.camera), sum(|s| s.shadow), sum(|s| s.secondary)],
            "{}: ray counts",
            c.label
        );
        // The progressive records' α words hold the terms' Q (checked against the CPU's
        // α in tests/direct_image.rs, where α is applied); the CPU's α is 0 here.
        let r = c.acc.record;
        let alpha_word = |k: usize| {
            let w = k % stride;
            p.code == 5
                && w >= Record::AOV + r.aov
                && (w - Record::AOV - r.aov) % r.block >= 4
                && (w - Record::AOV - r.aov) % r.block < 4 + 3 * t
        };
        let mut nonzero = 0;
        for (k, (a, b)) in ours.iter().zip(&cpu).enumerate() {
            if alpha_word(k) {
                assert_eq!(*b, 0.0, "{}: α before any solve", c.label);
                continue;
            }
            nonzero += usize::from(*b != 0.0);
            assert!(
                (a - b).abs() <= 2e-6 * b.abs(),
                "{}: word {} of pixel {}: {a} against the CPU's {b}",
                c.label,
                k % stride,
                k / stride
            );
        }
        // The case exercised its record: a good part of its words were written (with
        // min depth 2 not those of depth 1).
        assert!(
            nonzero * 4 > cpu.len(),
            "{}: {nonzero} of {} words",
            c.label,
            cpu.len()
        );
    }
}
