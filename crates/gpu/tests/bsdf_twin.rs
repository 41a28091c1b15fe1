//! The BSDF kernel against its CPU f32 twin and the f64 CPU BSDFs (GPU.md §9, "BSDF
//! eval/sample/pdf per material"), for every material kind, rough and smooth, and the
//! Henyey–Greenstein phase function at five g, 4096 (wo, wi, uc, u) each:
//!
//! - GPU = twin bit for bit on lavapipe (GPU.md §3.5) for f, pdf and every field of
//!   sample_f. No tolerance is needed for transcendentals: both sides use the same
//!   polynomial `gpu::bsdf::sincos` and only +, −, ×, ÷ and sqrt (correctly rounded on
//!   lavapipe and in Rust);
//! - twin = `render::bsdf` (f64) within the relative tolerances stated at
//!   [`twin_matches_the_f64_bsdfs`];
//! - the twin's own identities: a sample's pdf and f are `eval` at its direction, and its
//!   weight is f·|cos θi|/pdf, exactly (a phase sample: f = pdf = p at its drawn cos θ,
//!   near `eval` at its direction, and weight 1).

use crate::common;
use common::Rng;

use glam::{DVec2, DVec3, Vec2, Vec3};
use gpu::bsdf::{
    eval, sample_f, BsdfSample, GpuBsdf, BSDF_STRUCT_WGSL, BSDF_WGSL, COAT_TABLE_LEN, PHASE,
    SPECULAR, TRANSMISSION, VALID,
};
use gpu::{GpuOptions, Kernel};
use render::bsdf::microfacet::TrowbridgeReitz;
use render::bsdf::{
    Bsdf, Bxdf, CoatTable, ConductorBxdf, DielectricBxdf, DiffuseBxdf, HenyeyGreenstein,
    PlasticBxdf,
};

/// Triples per material.
const N: usize = 4096;

/// The shapes of random input this file's tests draw.
trait Inputs {
    fn dir(&mut self) -> Vec3;
    fn unit(&mut self) -> f32;
}

impl Inputs for Rng {
    /// A unit f32 direction, uniform on the sphere.
    fn dir(&mut self) -> Vec3 {
        let z = 1.0 - 2.0 * self.next();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * self.next();
        DVec3::new(r * phi.cos(), r * phi.sin(), z).as_vec3()
    }
    /// An f32 in [0, 1) with 24 bits, as the GPU sampler makes them.
    fn unit(&mut self) -> f32 {
        (self.next() * 16_777_216.0).floor() as f32 / 16_777_216.0
    }
}

/// One test input: wo, wi, uc, u.
#[derive(Clone, Copy)]
struct Triple {
    wo: Vec3,
    wi: Vec3,
    uc: f32,
    u: Vec2,
}

fn triples(seed: u64) -> Vec<Triple> {
    let mut rng = Rng(seed);
    (0..N)
        .map(|_| Triple {
            wo: rng.dir(),
            wi: rng.dir(),
            uc: rng.unit(),
            u: Vec2::new(rng.unit(), rng.unit()),
        })
        .collect()
}

/// The coats of the plastic cases.
struct Coats {
    rough: CoatTable,
    smooth: CoatTable,
}

fn coats() -> Coats {
    Coats {
        rough: CoatTable::new(1.5, 0.2),
        smooth: CoatTable::new(1.5, 0.0),
    }
}

/// The coat-albedo table of `render::bsdf::CoatTable` read back through `albedo` at its
/// nodes μ = (j/64)², where its interpolation returns entry j exactly.
fn coat_table(c: &CoatTable) -> Vec<f32> {
    (0..COAT_TABLE_LEN)
        .map(|j| c.albedo((j as f64 / 64.0).powi(2)) as f32)
        .collect()
}

/// The cases: (name, GPU BSDF, CPU BxDF), and the table buffer. The phase functions'
/// GPU structs carry garbage in the fields kind 4 does not read (other code stores its
/// own data there).
fn cases(c: &Coats) -> (Vec<(&'static str, GpuBsdf, Bxdf<'_>)>, Vec<f32>) {
    let gold_eta = [0.143, 0.374, 1.442];
    let gold_k = [3.983, 2.385, 1.603];
    let conductor = |alpha: f64| {
        (
            GpuBsdf::conductor(gold_eta, gold_k, alpha),
            Bxdf::Conductor(ConductorBxdf {
                distrib: TrowbridgeReitz::isotropic(alpha),
                eta: DVec3::from_array(gold_eta),
                k: DVec3::from_array(gold_k),
            }),
        )
    };
    let dielectric = |eta: f64, alpha: f64| {
        (
            GpuBsdf::dielectric(eta, alpha),
            Bxdf::Dielectric(DielectricBxdf {
                distrib: TrowbridgeReitz::isotropic(alpha),
                eta,
            }),
        )
    };
    let rho = [0.6, 0.3, 0.1];
    let table = coat_table(&c.rough);
    fn plastic<'a>(
        name: &'static str,
        rho: [f64; 3],
        t: &'a CoatTable,
    ) -> (&'static str, GpuBsdf, Bxdf<'a>) {
        let alpha = t.distrib.alpha_x;
        (
            name,
            GpuBsdf::plastic(rho, t.eta, alpha, t.r_int, 0),
            Bxdf::Plastic(PlasticBxdf::new(DVec3::from_array(rho), t)),
        )
    }
    let r = [0.8, 0.5, 0.2];
    let (c1, b1) = conductor(0.3);
    let (c2, b2) = conductor(0.0);
    let (c3, b3) = conductor(0.05);
    let (d1, e1) = dielectric(1.5, 0.3);
    let (d2, e2) = dielectric(1.5, 0.0);
    let (d3, e3) = dielectric(1.33, 0.05);
    let phase = |name: &'static str, g: f64| {
        let mut m = GpuBsdf::phase(g);
        (m.delta, m.table, m.alpha_x, m.alpha_y, m.r_int) = (1, 7, 0.3, 0.2, 0.9);
        (m.rgb, m.k) = ([0.5, 2.0, -1.0, 3.0], [1.5, 0.25, 4.0, -2.0]);
        (name, m, Bxdf::Phase(HenyeyGreenstein { g }))
    };
    let v = vec![
        (
            "diffuse",
            GpuBsdf::diffuse(r),
            Bxdf::Diffuse(DiffuseBxdf {
                r: DVec3::from_array(r),
            }),
        ),
        ("conductor α 0.3", c1, b1),
        ("conductor smooth", c2, b2),
        ("conductor α 0.05", c3, b3),
        ("dielectric α 0.3", d1, e1),
        ("dielectric smooth", d2, e2),
        ("dielectric η 1.33 α 0.05", d3, e3),
        plastic("plastic α 0.2", rho, &c.rough),
        plastic("plastic smooth", rho, &c.smooth),
        phase("phase g 0", 0.0),
        phase("phase g 0.0005", 0.0005),
        phase("phase g 0.3", 0.3),
        phase("phase g −0.7", -0.7),
        phase("phase g 0.95", 0.95),
    ];
    (v, table)
}

/// The kernel's words per triple: f (3), pdf, then the sample's wi (3), pdf, f (3), eta,
/// weight (3), flags.
const OUT: usize = 16;

fn twin_words(m: &GpuBsdf, table: &[f32], t: &Triple) -> [u32; OUT] {
    let (f, pdf) = eval(m, table, t.wo, t.wi);
    let s = sample_f(m, table, t.wo, t.uc, t.u);
    let b = f32::to_bits;
    [
        b(f.x),
        b(f.y),
        b(f.z),
        b(pdf),
        b(s.wi.x),
        b(s.wi.y),
        b(s.wi.z),
        b(s.pdf),
        b(s.f.x),
        b(s.f.y),
        b(s.f.z),
        b(s.eta),
        b(s.weight.x),
        b(s.weight.y),
        b(s.weight.z),
        s.flags,
    ]
}

#[test]
fn bsdf_kernel_equals_its_twin_bit_for_bit() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let coats = coats();
    let (cases, table) = cases(&coats);
    let mats: Vec<GpuBsdf> = cases.iter().map(|c| c.1).collect();
    let ts = triples(1);
    let n = mats.len() * N;
    let input: Vec<u32> = (0..n)
        .flat_map(|i| {
            let t = ts[i / mats.len()];
            [
                t.wo.x, t.wo.y, t.wo.z, t.wi.x, t.wi.y, t.wi.z, t.uc, t.u.x, t.u.y,
            ]
            .map(f32::to_bits)
        })
        .collect();
    let src = format!(
        "{BSDF_STRUCT_WGSL}{BSDF_WGSL}
@group(0) @binding(0) var<storage, read> mats: array<GpuBsdf>;
@group(0) @binding(1) var<storage, read> tables: array<f32>;
@group(0) @binding(2) var<storage, read> inp: array<f32>;
@group(0) @binding(3) var<storage, read_write> out: array<u32>;
fn bsdf_table(i: u32) -> f32 {{ return tables[i]; }}
@compute @workgroup_size(64)
fn bsdf_test(@builtin(global_invocation_id) id: vec3<u32>) {{
    let i = id.x;
    if (9u * i >= arrayLength(&inp)) {{ return; }}
    let m = mats[i % arrayLength(&mats)];
    let r = 9u * i;
    let wo = vec3<f32>(inp[r], inp[r + 1u], inp[r + 2u]);
    let wi = vec3<f32>(inp[r + 3u], inp[r + 4u], inp[r + 5u]);
    let e = bsdf_eval(m, wo, wi);
    let s = bsdf_sample_f(m, wo, inp[r + 6u], vec2<f32>(inp[r + 7u], inp[r + 8u]));
    let o = {OUT}u * i;
    out[o] = bitcast<u32>(e.x);
    out[o + 1u] = bitcast<u32>(e.y);
    out[o + 2u] = bitcast<u32>(e.z);
    out[o + 3u] = bitcast<u32>(e.w);
    out[o + 4u] = bitcast<u32>(s.wi.x);
    out[o + 5u] = bitcast<u32>(s.wi.y);
    out[o + 6u] = bitcast<u32>(s.wi.z);
    out[o + 7u] = bitcast<u32>(s.pdf);
    out[o + 8u] = bitcast<u32>(s.f.x);
    out[o + 9u] = bitcast<u32>(s.f.y);
    out[o + 10u] = bitcast<u32>(s.f.z);
    out[o + 11u] = bitcast<u32>(s.eta);
    out[o + 12u] = bitcast<u32>(s.weight.x);
    out[o + 13u] = bitcast<u32>(s.weight.y);
    out[o + 14u] = bitcast<u32>(s.weight.z);
    out[o + 15u] = s.flags;
}}
"
    );
    let t0 = std::time::Instant::now();
    let k = Kernel::new(&g, &src, "bsdf_test", 3).unwrap();
    eprintln!("bsdf kernel compiled in {:.2?}", t0.elapsed());
    let out = k
        .run(
            &g,
            &[
                bytemuck::cast_slice(&mats),
                &table.iter().map(|f| f.to_bits()).collect::<Vec<_>>(),
                &input,
            ],
            OUT * n,
            [(n as u32).div_ceil(64), 1, 1],
        )
        .unwrap();
    let mut valid = vec![0usize; mats.len()];
    let mut bad = 0;
    for i in 0..n {
        let (name, m, _) = &cases[i % mats.len()];
        let want = twin_words(m, &table, &ts[i / mats.len()]);
        let got = &out[OUT * i..OUT * (i + 1)];
        if got != want {
            if bad < 5 {
                eprintln!(
                    "{name}, triple {}: GPU {got:08x?}\n twin {want:08x?}",
                    i / mats.len()
                );
            }
            bad += 1;
        }
        valid[i % mats.len()] += usize::from(want[15] & VALID != 0);
    }
    eprintln!(
        "{} triples, {bad} differ; valid samples per case: {valid:?}",
        n
    );
    assert_eq!(bad, 0, "{bad} of {n} triples differ between GPU and twin");
}

/// Relative difference |a − b| / max(|a|, |b|) (0 where both are 0).
fn rel(a: f64, b: f64) -> f64 {
    let m = a.abs().max(b.abs());
    if m == 0.0 {
        0.0
    } else {
        (a - b).abs() / m
    }
}

/// f and pdf of the f64 BSDF.
fn cpu_eval(b: &Bsdf, wo: DVec3, wi: DVec3) -> [f64; 4] {
    let f = b.f(wo, wi);
    [f.x, f.y, f.z, b.pdf(wo, wi)]
}

/// The f64 problem's sensitivity to rounding: per value, the largest relative change
/// when one coordinate of wo or wi moves by δ = 2⁻²³ (one f32 ulp at 1).
fn sensitivity(b: &Bsdf, wo: DVec3, wi: DVec3, v: &[f64; 4]) -> [f64; 4] {
    let d = 1.0 / 8_388_608.0;
    let mut s = [0f64; 4];
    for k in 0..6 {
        for sign in [-1.0, 1.0] {
            let mut e = DVec3::ZERO;
            e[k % 3] = sign * d;
            let p = if k < 3 {
                cpu_eval(b, wo + e, wi)
            } else {
                cpu_eval(b, wo, wi + e)
            };
            for c in 0..4 {
                s[c] = s[c].max(rel(p[c], v[c]));
            }
        }
    }
    s
}

/// The twin against `render::bsdf` in f64 on the same inputs: directions widened exactly,
/// and η, α, ρ, η + i k rounded to f32 as the GPU holds them.
///
/// f and pdf: relative difference ≤ max(10⁻⁴, 2⁻²⁰/α²) + 8·s, with s the f64 function's own change
/// under a one-ulp (2⁻²³) move of one input coordinate ([`sensitivity`]). The twin's ~100
/// f32 operations each round by 2⁻²⁴; where the problem is well conditioned that gives
/// ~10⁻⁶, except near GGX's peak, where tan²θm from cos θm gives D a relative error up
/// to 2⁻²²/α² (10⁻⁴ at α = 0.05; the floor allows four times that); where it is not (GGX tails at small α, the transmission half vector
/// wi·η′ + wo near cancellation, back-facing and hemisphere cut-offs), input rounding alone
/// moves the f64 value by s, measured up to 3·10⁻³ for a 10⁻⁷ move (η 1.33, α 0.05).
///
/// sample_f: delta samples against the f64 sample (wi within 10⁻⁵, pdf, f, weight within
/// 10⁻⁴; they involve only Fresnel terms); non-delta samples: the same lobe as the f64
/// sample where uc is not within 10⁻⁵ of the lobe threshold, wi within 10⁻⁴ of the f64
/// direction where both exist (the twin and f64 may disagree on existence only for
/// grazing draws, |cos θi| < 10⁻³), and f, pdf against f64 `f`, `pdf` at the twin's wi
/// with the tolerance above (a twin sample is its eval there, exactly, by
/// [`twin_samples_agree_with_eval`]).
#[test]
fn twin_matches_the_f64_bsdfs() {
    let coats = coats();
    let (cases, table) = cases(&coats);
    let ts = triples(2);
    let mut report = Vec::new();
    for (name, m, bxdf) in &cases {
        let cpu = Bsdf {
            frame: render::frame::Frame::from_z(DVec3::Z),
            bxdf: f32_params(bxdf),
        };
        let (mut max_good, mut max_all, mut n_good, mut n_loose) = (0f64, 0f64, 0, 0);
        let (mut max_spec, mut skipped) = (0f64, 0);
        // GGX at small α: tan²θm = (1 − cos²θm)/cos²θm near the peak has absolute error
        // ~2⁻²³ in f32, and d ln D / d tan²θm is at most 2/α², so D's relative error
        // reaches 2⁻²²/α² (10⁻⁷/α²); four times that is allowed.
        let floor = 1e-4f64.max(if m.kind == gpu::bsdf::DIFFUSE || m.kind == PHASE {
            0.0
        } else {
            4.0 / 4_194_304.0 / f64::from(m.alpha_x).powi(2).max(1e-6)
        });
        let mut check = |wo: DVec3, wi: DVec3, got: [f64; 4], what: &str| {
            let want = cpu_eval(&cpu, wo, wi);
            let s = sensitivity(&cpu, wo, wi, &want);
            for c in 0..4 {
                let d = rel(got[c], want[c]);
                let tol = floor + 8.0 * s[c];
                assert!(
                    d <= tol,
                    "{name} {what}: wo {wo} wi {wi}: {got:?} vs {want:?} (rel {d:.2e}, s {:.2e})",
                    s[c]
                );
                max_all = max_all.max(d);
                if s[c] < 1e-5 {
                    max_good = max_good.max(d);
                    n_good += 1;
                } else {
                    n_loose += 1;
                }
            }
        };
        for t in &ts {
            let (wo, wi) = (t.wo.as_dvec3(), t.wi.as_dvec3());
            let (f, pdf) = eval(m, &table, t.wo, t.wi);
            check(wo, wi, [f.x, f.y, f.z, pdf].map(f64::from), "eval");
            let s = sample_f(m, &table, t.wo, t.uc, t.u);
            let c = cpu.sample_f(wo, f64::from(t.uc), DVec2::new(t.u.x.into(), t.u.y.into()));
            if near_threshold(bxdf, t, wo) {
                skipped += 1;
                continue;
            }
            let grazing = |w: DVec3| w.z.abs() < 1e-3;
            match c {
                None if s.flags == 0 => {}
                None => assert!(grazing(s.wi.as_dvec3()), "{name}: {s:?} where f64 has none"),
                Some(c) if s.flags == 0 => {
                    assert!(grazing(c.wi), "{name}: none where f64 has {c:?}")
                }
                Some(c) => {
                    assert_eq!(s.flags & SPECULAR != 0, c.specular, "{name}");
                    assert_eq!(s.flags & TRANSMISSION != 0, c.transmission, "{name}");
                    let dw = (s.wi.as_dvec3() - c.wi).abs().max_element();
                    if c.specular {
                        assert!(dw < 1e-5, "{name}: wi {} vs {}", s.wi, c.wi);
                        for (a, b) in [
                            (s.pdf.into(), c.pdf),
                            (s.f.x.into(), c.f.x),
                            (s.weight.x.into(), c.weight.x),
                            (s.weight.z.into(), c.weight.z),
                            (s.eta.into(), c.eta),
                        ] {
                            assert!(rel(a, b) < 1e-4, "{name}: {s:?} vs {c:?}");
                            max_spec = max_spec.max(rel(a, b));
                        }
                    } else {
                        assert!(dw < 1e-4, "{name}: wi {} vs {}", s.wi, c.wi);
                        assert!(rel(s.eta.into(), c.eta) < 1e-6, "{name}");
                        let got = [s.f.x, s.f.y, s.f.z, s.pdf].map(f64::from);
                        check(wo, s.wi.as_dvec3(), got, "sample");
                    }
                }
            }
        }
        assert!(skipped < N / 100, "{name}: {skipped} near a lobe threshold");
        report.push(format!(
            "{name}: max rel {max_good:.1e} where s < 1e-5 ({n_good} values), \
             {max_all:.1e} overall ({n_loose} values with s ≥ 1e-5); delta samples {max_spec:.1e}"
        ));
    }
    eprintln!("{}", report.join("\n"));
}

/// The BxDF with its parameters rounded to f32, as the GPU holds them.
fn f32_params<'a>(b: &Bxdf<'a>) -> Bxdf<'a> {
    let r = |x: f64| f64::from(x as f32);
    let rv = |v: DVec3| v.as_vec3().as_dvec3();
    let td = |d: TrowbridgeReitz| TrowbridgeReitz {
        alpha_x: r(d.alpha_x),
        alpha_y: r(d.alpha_y),
    };
    match *b {
        Bxdf::Diffuse(d) => Bxdf::Diffuse(DiffuseBxdf { r: rv(d.r) }),
        Bxdf::Conductor(c) => Bxdf::Conductor(ConductorBxdf {
            distrib: td(c.distrib),
            eta: rv(c.eta),
            k: rv(c.k),
        }),
        Bxdf::Dielectric(d) => Bxdf::Dielectric(DielectricBxdf {
            distrib: td(d.distrib),
            eta: r(d.eta),
        }),
        // The coat table and R_int stay f64 (rounding them is below the 10⁻⁴ floor).
        Bxdf::Plastic(p) => Bxdf::Plastic(PlasticBxdf {
            rho: rv(p.rho),
            coat: p.coat,
        }),
        Bxdf::Phase(h) => Bxdf::Phase(HenyeyGreenstein { g: r(h.g) }),
    }
}

/// Whether uc lies within 10⁻⁵ of the f64 lobe threshold the sample compares it with:
/// R/(R + T) at the normal (smooth glass) or the drawn microfacet normal (rough glass),
/// or the coat probability (plastic).
fn near_threshold(bxdf: &Bxdf, t: &Triple, wo: DVec3) -> bool {
    use render::bsdf::fresnel::fr_dielectric;
    let p = match bxdf {
        Bxdf::Dielectric(d) if d.distrib.effectively_smooth() => fr_dielectric(wo.z, d.eta),
        Bxdf::Dielectric(d) => {
            let wm = d
                .distrib
                .sample_wm(wo, DVec2::new(t.u.x.into(), t.u.y.into()));
            fr_dielectric(wo.dot(wm), d.eta)
        }
        Bxdf::Plastic(p) => {
            let e = p.coat.albedo(wo.z.abs());
            let d = (1.0 - e) * render::color::average(p.rho);
            e / (e + d)
        }
        _ => return false,
    };
    (f64::from(t.uc) - p).abs() < 1e-5
}

/// The twin's identities: a non-delta sample carries eval's f and pdf at its direction,
/// a delta sample of a pure-specular BSDF has eval pdf 0 there, and every weight is
/// f·(|cos θi|/pdf), bit for bit.
#[test]
fn twin_samples_agree_with_eval() {
    let coats = coats();
    let (cases, table) = cases(&coats);
    for (name, m, bxdf) in &cases {
        let mut valid = 0;
        for t in triples(3) {
            let s: BsdfSample = sample_f(m, &table, t.wo, t.uc, t.u);
            if s.flags & VALID == 0 {
                continue;
            }
            valid += 1;
            let (f, pdf) = eval(m, &table, t.wo, s.wi);
            if m.kind == PHASE {
                // p at the drawn cos θ, not at the rounded wo·wi: eval agrees within the
                // f32 cos θ's error (a few 2⁻²⁴) times |d ln p / d cos θ| = 3|g|/denom.
                let g = f64::from(m.eta);
                let denom = 1.0 + g * g + 2.0 * g * f64::from(t.wo.dot(s.wi));
                let tol = 1e-6 + 8.0 * 3.0 * g.abs() / denom / 16_777_216.0;
                assert!(
                    rel(s.pdf.into(), pdf.into()) <= tol,
                    "{name}: {s:?} vs {pdf}"
                );
                assert_eq!((s.f, s.weight), (Vec3::splat(s.pdf), Vec3::ONE), "{name}");
                assert!(s.pdf.is_finite() && (s.wi.length() - 1.0).abs() < 1e-5);
                continue;
            }
            if s.flags & SPECULAR == 0 {
                assert_eq!(s.pdf.to_bits(), pdf.to_bits(), "{name}: {s:?}");
                assert_eq!(s.f, f, "{name}: {s:?}");
            } else if bxdf.is_pure_specular() {
                assert_eq!((f, pdf), (Vec3::ZERO, 0.0), "{name}: {s:?}");
            }
            let w = s.f * (s.wi.z.abs() / s.pdf);
            assert_eq!(s.weight, w, "{name}: {s:?}");
            assert!(
                s.pdf > 0.0 && s.pdf.is_finite() && s.weight.is_finite(),
                "{name}: {s:?}"
            );
            assert!(
                ((s.wi.length() - 1.0).abs()) < 1e-5,
                "{name}: |wi| {}",
                s.wi.length()
            );
        }
        assert!(valid > N / 2, "{name}: {valid} valid samples");
    }
}

/// `GpuBsdf` agrees with its WGSL mirror: a kernel writes every field from its index (u32
/// fields as 100 + index, f32 fields as the index) and the bytes read back are the Rust
/// struct with those values (GPU.md §5.1).
#[test]
fn bsdf_struct_layout() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    assert_eq!(std::mem::size_of::<GpuBsdf>(), 64);
    let src = format!(
        "{BSDF_STRUCT_WGSL}
@group(0) @binding(0) var<storage, read_write> out: array<GpuBsdf>;
@compute @workgroup_size(1)
fn fill() {{
    var v: GpuBsdf;
    v.kind = 100u; v.delta = 101u; v.table = 102u; v.zero = 103u;
    v.alpha_x = 4.0; v.alpha_y = 5.0; v.eta = 6.0; v.r_int = 7.0;
    v.rgb = vec4<f32>(8.0, 9.0, 10.0, 11.0);
    v.k = vec4<f32>(12.0, 13.0, 14.0, 15.0);
    out[0] = v;
    out[1] = v;
}}"
    );
    let k = Kernel::new(&g, &src, "fill", 0).unwrap();
    let out = k.run(&g, &[], 32, [1, 1, 1]).unwrap();
    let got: &[GpuBsdf] = bytemuck::cast_slice(&out);
    let want = GpuBsdf {
        kind: 100,
        delta: 101,
        table: 102,
        zero: 103,
        alpha_x: 4.0,
        alpha_y: 5.0,
        eta: 6.0,
        r_int: 7.0,
        rgb: [8.0, 9.0, 10.0, 11.0],
        k: [12.0, 13.0, 14.0, 15.0],
    };
    assert_eq!(got, &[want, want]);
}

/// `GpuBsdf::from_material` reads each scene material with its textures evaluated at the
/// hit (here texture i is the colour (i, i + 1, i + 2)/10) into the constructors' structs.
#[test]
fn bsdf_from_scene_materials() {
    use scene::{MaterialData, TextureId};
    let rgb = |t: TextureId| [0.0, 1.0, 2.0].map(|k| (f64::from(t.0) + k) / 10.0);
    let cases = [
        (
            MaterialData::Diffuse {
                reflectance: TextureId(1),
            },
            GpuBsdf::diffuse([0.1, 0.2, 0.3]),
        ),
        (
            MaterialData::Conductor {
                eta: TextureId(2),
                k: TextureId(3),
                roughness: 0.2,
            },
            GpuBsdf::conductor([0.2, 0.3, 0.4], [0.3, 0.4, 0.5], 0.2),
        ),
        (
            MaterialData::Dielectric {
                eta: 1.5,
                roughness: 0.0,
            },
            GpuBsdf::dielectric(1.5, 0.0),
        ),
        (
            MaterialData::Plastic {
                diffuse: TextureId(9),
                eta: 1.4,
                roughness: 0.1,
            },
            GpuBsdf::plastic([0.9, 1.0, 1.1], 1.4, 0.1, 0.6, 65),
        ),
    ];
    for (m, want) in cases {
        assert_eq!(GpuBsdf::from_material(&m, rgb, (0.6, 65)), want, "{m:?}");
    }
    let p = GpuBsdf::plastic([0.9, 1.0, 1.1], 1.4, 0.1, 0.6, 65);
    assert_eq!(
        (p.rgb[2], p.delta, p.table),
        (1.0, 0, 65),
        "ρ clamped, rough coat"
    );
    assert_eq!(
        GpuBsdf::dielectric(1.0, 0.3).delta,
        1,
        "η = 1 is a delta lobe"
    );
}
