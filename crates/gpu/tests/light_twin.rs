//! The light kernel equals its CPU f32 twin bit for bit on lavapipe (GPU.md §3.5, §9
//! "light sample/pdf"); the twin agrees with `render::light::AreaLight` (f64) to f32
//! accuracy, and its samples' pdfs equal its pdf functions at the sampled directions.

use crate::common;
use common::Rng;

use glam::{DVec2, DVec3};
use gpu::light::{self, GpuAreaLight, Select, GPU_AREA_LIGHT_WGSL, IMPORTANCE_WORDS, LIGHT_WGSL};
use gpu::TRIG_WGSL;
use gpu::{GpuOptions, Kernel};
use render::light::{AreaLight, Shape};
use render::Rgb;

/// Cases per shape.
const N: usize = 4096;
/// f32 words per case: p, u, wi2, light index, uc, and a second normal nm for the
/// spatial selection's importance ([`medium_normal`]).
const IN: usize = 13;
/// f32 words out per case (the last two: the spatial selection's importance at p with
/// normal wi2, and with normal nm).
const OUT: usize = 28;

/// The shapes of random input this file's tests draw.
trait Inputs {
    fn vec(&mut self, s: f64) -> DVec3;
}

impl Inputs for Rng {
    fn vec(&mut self, s: f64) -> DVec3 {
        DVec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5) * (2.0 * s)
    }
}

fn r32(v: DVec3) -> DVec3 {
    v.as_vec3().as_dvec3()
}
fn a32(v: DVec3) -> [f32; 3] {
    v.as_vec3().to_array()
}
fn d64(v: [f32; 3]) -> DVec3 {
    DVec3::new(v[0].into(), v[1].into(), v[2].into())
}

/// Four lights of each shape (f64 geometry already rounded to f32), with their GPU
/// images: spheres, one-sided and two-sided rects, disks.
fn lights() -> Vec<(AreaLight, GpuAreaLight)> {
    let mut rng = Rng(11);
    let mut out = Vec::new();
    for shape in 0..3 {
        for k in 0..4 {
            let c = r32(rng.vec(1.0));
            let rad = Rgb::new(1.0 + rng.next(), 0.5 + rng.next(), 2.0 * rng.next());
            let two_sided = k % 2 == 1;
            let s = match shape {
                0 => Shape::Sphere {
                    center: c,
                    radius: f64::from((0.2 + 0.6 * rng.next()) as f32),
                },
                1 => Shape::Rect {
                    corner: c,
                    edge_u: r32(rng.vec(1.0)),
                    edge_v: r32(rng.vec(1.0)),
                },
                _ => Shape::Disk {
                    center: c,
                    normal: r32(rng.vec(1.0).normalize()),
                    radius: f64::from((0.3 + 0.7 * rng.next()) as f32),
                },
            };
            let mut l = AreaLight::new(s, rad);
            l.two_sided = two_sided;
            let rgb = a32(DVec3::new(rad.x, rad.y, rad.z));
            let area = l.area() as f32;
            let g = match s {
                Shape::Sphere { center, radius } => {
                    GpuAreaLight::sphere(a32(center), radius as f32, rgb, area)
                }
                Shape::Rect {
                    corner,
                    edge_u,
                    edge_v,
                } => {
                    GpuAreaLight::rect(a32(corner), a32(edge_u), a32(edge_v), two_sided, rgb, area)
                }
                Shape::Disk {
                    center,
                    normal,
                    radius,
                } => GpuAreaLight::disk(
                    a32(center),
                    a32(normal),
                    radius as f32,
                    two_sided,
                    rgb,
                    area,
                ),
                Shape::Triangle { .. } => unreachable!("the GPU refuses triangle lights"),
            };
            out.push((l, g));
        }
    }
    out
}

/// The distance from p to the light's surface (sphere), or to its plane.
fn clearance(l: &AreaLight, p: DVec3) -> f64 {
    match l.shape {
        Shape::Sphere { center, radius } => ((p - center).length() - radius).abs(),
        Shape::Rect {
            corner,
            edge_u,
            edge_v,
        } => (p - corner).dot(edge_u.cross(edge_v).normalize()).abs(),
        Shape::Disk { center, normal, .. } => (p - center).dot(normal).abs(),
        Shape::Triangle { p0, e1, e2 } => (p - p0).dot(e1.cross(e2).normalize()).abs(),
    }
}

/// The normal nm of case i: zero (a point inside a medium, which has none; the three
/// zeros with either sign, which all compare equal to 0) in three cases of four, else a
/// tiny non-zero normal, which still bounds the receiver's cosine.
fn medium_normal(i: usize) -> [f32; 3] {
    match (i / 4) % 4 {
        0 => [0.0; 3],
        1 => [-0.0, 0.0, -0.0],
        2 => [-0.0; 3],
        _ => [0.0, 0.0, 1.0 / 1_099_511_627_776.0],
    }
}

/// N cases per shape: a point p at least 0.2 from the light's surface or plane (spheres
/// seen from inside too), u, a direction wi2 toward a point near the light, uc, and the
/// normal [`medium_normal`].
fn cases(ls: &[(AreaLight, GpuAreaLight)]) -> Vec<[f32; IN]> {
    let mut rng = Rng(5);
    (0..3 * N)
        .map(|i| {
            let li = (i / N) * 4 + i % 4;
            let (l, _) = &ls[li];
            let c = l.bounds().center();
            let p = loop {
                let p = r32(c + rng.vec(2.5));
                if clearance(l, p) > 0.2 {
                    break p;
                }
            };
            let u = [rng.next() as f32, rng.next() as f32];
            let wi2 = a32((c + rng.vec(0.8) - p).normalize());
            let pa = a32(p);
            let nm = medium_normal(i);
            [
                pa[0],
                pa[1],
                pa[2],
                u[0],
                u[1],
                wi2[0],
                wi2[1],
                wi2[2],
                f32::from_bits(li as u32),
                rng.next() as f32,
                nm[0],
                nm[1],
                nm[2],
            ]
        })
        .collect()
}

fn sample_words(s: Option<light::Sample>) -> [f32; 6] {
    match s {
        None => [0.0; 6],
        Some(s) => [
            s.wi[0],
            s.wi[1],
            s.wi[2],
            s.dist,
            s.pdf,
            f32::from_bits(u32::from(s.emits) | 2),
        ],
    }
}

/// The twin's answer for one case, in the kernel's output order.
fn twin(ls: &[GpuAreaLight], sel: &[f32], area_off: u32, c: &[f32; IN]) -> [f32; OUT] {
    let l = &ls[c[8].to_bits() as usize];
    let p = [c[0], c[1], c[2]];
    let u = [c[3], c[4]];
    let wi2 = [c[5], c[6], c[7]];
    let mut o = [0.0; OUT];
    let sl = light::sample_li(l, p, u);
    o[0..6].copy_from_slice(&sample_words(sl));
    o[6..12].copy_from_slice(&sample_words(light::sample_area(l, p, u)));
    o[12] = light::pdf_li(l, p, wi2);
    o[13] = light::pdf_area(l, p, wi2);
    if let Some((t, n)) = light::intersect(l, p, wi2, 0.0, 1e30) {
        o[14..18].copy_from_slice(&[t, n[0], n[1], n[2]]);
    }
    o[18] = sl.map_or(0.0, |s| light::pdf_li(l, p, s.wi));
    let n = ls.len() as u32;
    for (k, how) in [Select::Table(0), Select::Uniform, Select::Table(area_off)]
        .into_iter()
        .enumerate()
    {
        let (i, pmf) = light::select(sel, how, n, c[9]);
        o[19 + 2 * k] = f32::from_bits(i);
        o[20 + 2 * k] = pmf;
    }
    let li = c[8].to_bits() as usize;
    let at = importance_off(ls.len()) + IMPORTANCE_WORDS * li;
    o[26] = light::importance(sel, at, p, wi2);
    o[27] = light::importance(sel, at, p, [c[10], c[11], c[12]]);
    o
}

const KERNEL: &str = "
@group(0) @binding(0) var<storage, read> lights: array<GpuAreaLight>;
@group(0) @binding(1) var<storage, read> cases: array<f32>;
@group(0) @binding(2) var<storage, read> sel_buf: array<f32>;
@group(0) @binding(3) var<storage, read_write> out: array<f32>;

fn put_sample(at: u32, s: LSample) {
    if (s.ok == 0u) { return; }
    out[at] = s.wi.x; out[at + 1u] = s.wi.y; out[at + 2u] = s.wi.z;
    out[at + 3u] = s.dist; out[at + 4u] = s.pdf; out[at + 5u] = bitcast<f32>(s.emits | 2u);
}

@compute @workgroup_size(64)
fn lights_case(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (13u * i >= arrayLength(&cases)) { return; }
    let c = 13u * i;
    let o = 28u * i;
    let l = lights[bitcast<u32>(cases[c + 8u])];
    let p = vec3<f32>(cases[c], cases[c + 1u], cases[c + 2u]);
    let u = vec2<f32>(cases[c + 3u], cases[c + 4u]);
    let wi2 = vec3<f32>(cases[c + 5u], cases[c + 6u], cases[c + 7u]);
    let sl = light_sample_li(l, p, u);
    put_sample(o, sl);
    put_sample(o + 6u, light_sample_area(l, p, u));
    out[o + 12u] = light_pdf_li(l, p, wi2);
    out[o + 13u] = light_pdf_area(l, p, wi2);
    let h = light_intersect(l, p, wi2, 0.0, 1e30);
    out[o + 14u] = h.x; out[o + 15u] = h.y; out[o + 16u] = h.z; out[o + 17u] = h.w;
    if (sl.ok != 0u) { out[o + 18u] = light_pdf_li(l, p, sl.wi); }
    let n = arrayLength(&lights);
    let area_off = 2u * n + 2u;
    for (var k = 0u; k < 3u; k++) {
        let s = light_select(select(0u, area_off, k == 2u), k != 1u, n, cases[c + 9u]);
        out[o + 19u + 2u * k] = s.x;
        out[o + 20u + 2u * k] = s.y;
    }
    // The importance records after both tables (n, cdf[n + 1], pmf[n] each).
    let imp = 2u * (2u * n + 2u) + 12u * bitcast<u32>(cases[c + 8u]);
    out[o + 26u] = light_importance(imp, p, wi2);
    let nm = vec3<f32>(cases[c + 10u], cases[c + 11u], cases[c + 12u]);
    out[o + 27u] = light_importance(imp, p, nm);
}
";

/// Where the importance records start: after the power and area tables.
fn importance_off(n: usize) -> usize {
    2 * (2 * n + 2)
}

fn tables(ls: &[(AreaLight, GpuAreaLight)]) -> (Vec<f32>, u32) {
    let power: Vec<f64> = ls
        .iter()
        .map(|(l, _)| render::color::luminance(l.power()))
        .collect();
    let area: Vec<f64> = ls.iter().map(|(l, _)| l.area()).collect();
    let mut sel = light::table(&scene::Distribution1D::new(&power));
    let off = sel.len() as u32;
    sel.extend(light::table(&scene::Distribution1D::new(&area)));
    assert_eq!(sel.len(), importance_off(ls.len()));
    for (l, _) in ls {
        sel.extend(light::importance_record(&state::LightBounds::from(l)));
    }
    (sel, off)
}

#[test]
fn light_kernel_equals_its_twin_bit_for_bit() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let ls = lights();
    let gl: Vec<GpuAreaLight> = ls.iter().map(|p| p.1).collect();
    let (sel, area_off) = tables(&ls);
    assert_eq!(area_off, 2 * gl.len() as u32 + 2);
    let cs = cases(&ls);
    let src = format!("{TRIG_WGSL}{GPU_AREA_LIGHT_WGSL}{LIGHT_WGSL}{KERNEL}");
    let k = Kernel::new(&g, &src, "lights_case", 3).unwrap();
    let c_words: Vec<u32> = cs.iter().flatten().map(|x| x.to_bits()).collect();
    let s_words: Vec<u32> = sel.iter().map(|x| x.to_bits()).collect();
    let out = k
        .run(
            &g,
            &[bytemuck::cast_slice(&gl), &c_words, &s_words],
            OUT * cs.len(),
            [(cs.len() as u32).div_ceil(64), 1, 1],
        )
        .unwrap();
    let mut differ = 0;
    for (i, c) in cs.iter().enumerate() {
        let want = twin(&gl, &sel, area_off, c);
        let got = &out[OUT * i..OUT * (i + 1)];
        let want_bits: Vec<u32> = want.iter().map(|x| x.to_bits()).collect();
        if got != &want_bits[..] {
            if differ < 5 {
                let got: Vec<f32> = got.iter().map(|&w| f32::from_bits(w)).collect();
                eprintln!("case {i} (shape {}): gpu {got:?}\n twin {want:?}", i / N);
            }
            differ += 1;
        }
    }
    assert_eq!(differ, 0, "{differ} of {} cases differ", cs.len());
}

/// 2⁻²⁴.
const EPS: f64 = f32::EPSILON as f64 / 2.0;
/// The bound on an area pdf's relative error in units of 2⁻²⁴ κ.
const K: f64 = 200.0;
/// Predicted relative errors 2⁻²⁴ κ above this mean f32 cannot resolve the cosine (a
/// silhouette or grazing direction): such pdfs are counted, not compared.
const UNRESOLVED: f64 = 0.01;

/// Relative difference.
fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

/// The twin against the f64 lights of `render`, on the same (f32-rounded) geometry and
/// inputs. Positions are O(4) and every distance used is ≥ 0.2, so an f32 direction
/// carries ≲ 10 · 2⁻²⁴ · 4 / 0.2 ≈ 1.2e-5 error (bound 2e-5), and t likewise. An area
/// pdf t² / (A |cos θ|) is conditioned by the cosine: its relative error is compared
/// against `K · 2⁻²⁴ · κ` with κ = 1/|cos θ| for a rect or disk and κ = |p − c| /
/// (r cos² θ) for a sphere, whose r² cos² θ = r² − |f|² (f the line's offset from the
/// centre) carries ~r |p − c| ulp; K is measured and printed. Where 2⁻²⁴ κ exceeds
/// [`UNRESOLVED`] f32 cannot resolve cos θ at all: those pdfs are counted, not compared.
/// The cone's pdf has no cancellation (pbrt-v4 §6.2.4): κ = 1. Whether a direction
/// meets a light is ambiguous in f32 only within ~1e-5 of a rim or edge: such
/// disagreements are counted and must be rare.
#[test]
fn twin_matches_the_f64_lights() {
    let ls = lights();
    let gl: Vec<GpuAreaLight> = ls.iter().map(|p| p.1).collect();
    let (sel, area_off) = tables(&ls);
    let power: Vec<f64> = ls
        .iter()
        .map(|(l, _)| render::color::luminance(l.power()))
        .collect();
    let area: Vec<f64> = ls.iter().map(|(l, _)| l.area()).collect();
    let by_power = render::distribution::Distribution1D::new(&power);
    let by_area = render::distribution::Distribution1D::new(&area);
    let cs = cases(&ls);
    // |Δwi|, sample pdf and pdf-at-wi2 relative errors in units of 2⁻²⁴ κ, relative
    // errors of dist and t.
    let mut worst = [0f64; 4];
    let mut hit_disagree = [0usize; 3];
    let mut unresolved = 0;
    let mut sel_near = 0;
    let mut worst_imp = 0f64;
    for (i, c) in cs.iter().enumerate() {
        let li = c[8].to_bits() as usize;
        let (l64, l32) = (&ls[li].0, &gl[li]);
        let p = d64([c[0], c[1], c[2]]);
        let u = DVec2::new(c[3].into(), c[4].into());
        let wi2 = d64([c[5], c[6], c[7]]);
        let cos_at = |wi: DVec3| {
            l64.intersect(&frep::Ray::new(p, wi), 0.0, f64::INFINITY)
                .map_or(0.0, |x| x.n.dot(wi).abs())
        };
        // The condition of an area pdf at wi (see above).
        let kappa = |wi: DVec3| match l64.shape {
            Shape::Sphere { center, radius } => {
                (p - center).length() / (radius * cos_at(wi).powi(2))
            }
            _ => 1.0 / cos_at(wi),
        };
        let cone =
            matches!(l64.shape, Shape::Sphere { center, radius } if (p - center).length() > radius);
        for (k, (s32, s64)) in [
            (
                light::sample_li(l32, a32(p), [c[3], c[4]]),
                l64.sample_li(p, u),
            ),
            (
                light::sample_area(l32, a32(p), [c[3], c[4]]),
                l64.sample_area(p, u),
            ),
        ]
        .into_iter()
        .enumerate()
        {
            let (Some(s32), Some(s64)) = (s32, s64) else {
                panic!("case {i}: one side has no sample: {s32:?} vs {s64:?}");
            };
            worst[0] = worst[0].max((d64(s32.wi) - s64.wi).abs().max_element());
            worst[3] = worst[3].max(rel(s32.dist.into(), s64.dist));
            assert_eq!(s32.emits, s64.radiance != Rgb::ZERO, "case {i}: emits");
            let kap = if k == 0 && cone { 1.0 } else { kappa(s64.wi) };
            if EPS * kap > UNRESOLVED {
                unresolved += 1;
            } else {
                worst[1] = worst[1].max(rel(s32.pdf.into(), s64.pdf) / (EPS * kap));
            }
        }
        // Densities and crossings at an independent direction.
        for (k, (a, b)) in [
            (light::pdf_li(l32, a32(p), a32(wi2)), l64.pdf_li(p, wi2)),
            (light::pdf_area(l32, a32(p), a32(wi2)), l64.pdf_area(p, wi2)),
        ]
        .into_iter()
        .enumerate()
        {
            if (a > 0.0) != (b > 0.0) {
                hit_disagree[k] += 1;
            } else if b > 0.0 {
                let kap = if k == 0 && cone { 1.0 } else { kappa(wi2) };
                if EPS * kap > UNRESOLVED {
                    unresolved += 1;
                } else {
                    worst[2] = worst[2].max(rel(a.into(), b) / (EPS * kap));
                }
            }
        }
        let h32 = light::intersect(l32, a32(p), a32(wi2), 0.0, 1e30);
        let h64 = l64.intersect(&frep::Ray::new(p, wi2), 0.0, f64::INFINITY);
        match (h32, h64) {
            (Some((t, _)), Some(h)) => worst[3] = worst[3].max(rel(t.into(), h.t)),
            (None, None) => {}
            _ => hit_disagree[2] += 1,
        }
        // Selection: the same light unless uc is within 1e-6 of a CDF step.
        let uc = f64::from(c[9]);
        for (how, d) in [
            (Select::Table(0), &by_power),
            (Select::Table(area_off), &by_area),
        ] {
            let (i32_, pmf32) = light::select(&sel, how, gl.len() as u32, c[9]);
            let (i64_, pmf64, _) = d.sample_discrete(uc);
            if i32_ as usize != i64_ {
                sel_near += 1;
                continue;
            }
            assert!(rel(pmf32.into(), pmf64) < 1e-6, "case {i}: pmf");
        }
        // The spatial selection's importance: f32 against f64 within 10⁻⁴ of the
        // light's largest possible value Φ / r² (its terms are cosines and sines of
        // differences, bounded by 1; the cancellations are absolute, not relative).
        let imp32 = light::importance(
            &sel,
            importance_off(gl.len()) + IMPORTANCE_WORDS * li,
            a32(p),
            a32(wi2),
        );
        let imp64 = render::light::importance(l64, p, wi2);
        let b = l64.importance_bounds();
        let top = render::color::luminance(l64.power()) / (b.radius * b.radius);
        worst_imp = worst_imp.max((f64::from(imp32) - imp64).abs() / top);
        // And with the normal nm, zero in most cases (a medium point: no receiver cosine).
        let nm = [c[10], c[11], c[12]];
        let imp32 = light::importance(
            &sel,
            importance_off(gl.len()) + IMPORTANCE_WORDS * li,
            a32(p),
            nm,
        );
        let imp64 = render::light::importance(l64, p, d64(nm));
        worst_imp = worst_imp.max((f64::from(imp32) - imp64).abs() / top);
        let (iu, pu) = light::select(&sel, Select::Uniform, gl.len() as u32, c[9]);
        assert_eq!(
            iu as usize,
            ((uc * gl.len() as f64) as usize).min(gl.len() - 1)
        );
        assert_eq!(pu, 1.0 / gl.len() as f32);
    }
    eprintln!(
        "max |Δwi| {:.2e}; pdf relative error / (2⁻²⁴ κ): samples {:.1}, at wi2 {:.1}; \
         dist and t relative {:.2e}; hit/miss disagreements (pdf_li, pdf_area, \
         intersect) {hit_disagree:?} of {}; selection at a CDF step {sel_near}; pdfs \
         unresolved in f32 (2⁻²⁴ κ > {UNRESOLVED}) {unresolved}",
        worst[0],
        worst[1],
        worst[2],
        worst[3],
        cs.len()
    );
    assert!(worst[0] < 2e-5, "direction {:e}", worst[0]);
    assert!(worst[1] < K && worst[2] < K && worst[3] < 2e-5, "{worst:?}");
    assert!(hit_disagree.iter().all(|&k| k <= 3), "{hit_disagree:?}");
    assert!(unresolved <= cs.len() / 100, "{unresolved} unresolved");
    assert_eq!(sel_near, 0);
    eprintln!("importance: max |Δ| / (Φ / r²) {worst_imp:.2e}");
    assert!(worst_imp < 1e-4, "importance {worst_imp:e}");
}

/// Every sample's pdf is the pdf function at the sampled direction: sample_li's pdf is
/// pdf_li(wi) and sample_area's is pdf_area(wi) (a point sampled on a rim or edge is
/// found again), and no sample is lost.
#[test]
fn twin_sample_pdfs_equal_the_pdf_functions() {
    let ls = lights();
    let cs = cases(&ls);
    for (i, c) in cs.iter().enumerate() {
        let l = &ls[c[8].to_bits() as usize].1;
        let p = [c[0], c[1], c[2]];
        // Also the corners of [0, 1)²: rims and edges.
        let top = 1.0 - f32::EPSILON / 2.0;
        for u in [
            [c[3], c[4]],
            [0.0, 0.0],
            [top, top],
            [top, c[4]],
            [c[3], 0.0],
        ] {
            let s = light::sample_li(l, p, u).unwrap_or_else(|| panic!("case {i} {u:?}: none"));
            assert_eq!(
                s.pdf,
                light::pdf_li(l, p, s.wi),
                "case {i} {u:?}: sample_li"
            );
            let s = light::sample_area(l, p, u).unwrap_or_else(|| panic!("case {i} {u:?}: none"));
            assert_eq!(
                s.pdf,
                light::pdf_area(l, p, s.wi),
                "case {i} {u:?}: sample_area"
            );
        }
    }
}

/// The polynomial sin and cos against libm's f64, over the whole turn.
#[test]
fn sincos_is_within_an_ulp_or_two() {
    let mut worst = 0f64;
    for k in 0..=65_536u32 {
        let u = k as f32 / 65_536.0;
        let (s, c) = light::sincos_2pi(u);
        let a = std::f64::consts::TAU * f64::from(u);
        worst = worst.max(
            (f64::from(s) - a.sin())
                .abs()
                .max((f64::from(c) - a.cos()).abs()),
        );
    }
    eprintln!("sincos_2pi: max abs error {worst:.2e}");
    assert!(worst < 2.0 * f64::from(f32::EPSILON), "{worst:e}");
}

#[test]
fn area_light_layout() {
    let Some(g) = common::gpu(GpuOptions::default()) else {
        return;
    };
    let src = format!(
        "{GPU_AREA_LIGHT_WGSL}
@group(0) @binding(0) var<storage, read_write> out: array<GpuAreaLight>;
@compute @workgroup_size(1)
fn fill() {{
    var v: GpuAreaLight;
    v.shape = 100u; v.two_sided = 101u; v.pad0 = 102u; v.pad1 = 103u;
    v.radiance = vec4<f32>(4.0, 5.0, 6.0, 7.0);
    v.p0 = vec4<f32>(8.0, 9.0, 10.0, 11.0);
    v.e1 = vec4<f32>(12.0, 13.0, 14.0, 15.0);
    v.e2 = vec4<f32>(16.0, 17.0, 18.0, 19.0);
    out[0] = v;
    out[1] = v;
}}"
    );
    let k = Kernel::new(&g, &src, "fill", 0).unwrap();
    let out = k.run(&g, &[], 40, [1, 1, 1]).unwrap();
    let ls: &[GpuAreaLight] = bytemuck::cast_slice(&out);
    let want = GpuAreaLight {
        shape: 100,
        two_sided: 101,
        pad: [102, 103],
        radiance: [4.0, 5.0, 6.0, 7.0],
        p0: [8.0, 9.0, 10.0, 11.0],
        e1: [12.0, 13.0, 14.0, 15.0],
        e2: [16.0, 17.0, 18.0, 19.0],
    };
    assert_eq!(std::mem::size_of::<GpuAreaLight>(), 80);
    assert_eq!(ls, &[want, want]);
}
