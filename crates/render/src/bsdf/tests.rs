//! Statistical tests of every BSDF and of the media's phase function: sampling against
//! pdf (chi-square), pdf mass (∫ p = 1 for the phase function), agreement of sample /
//! f / pdf, white furnace and reciprocity.

use super::microfacet::TrowbridgeReitz;
use super::*;
use crate::sampler::Sampler;
use crate::testutil::{sphere_chi2, SphereBins};
use crate::warp::uniform_sphere;

/// Gold (RGB fit at 650, 550, 450 nm, as in Mitsuba's `Au`).
const AU_ETA: Rgb = Rgb::new(0.143_119, 0.374_957, 1.442_48);
const AU_K: Rgb = Rgb::new(3.983_16, 2.385_72, 1.603_22);

struct Tables {
    smooth: CoatTable,
    rough: Vec<CoatTable>,
}

fn tables() -> Tables {
    Tables {
        smooth: CoatTable::new(1.5, 0.0),
        rough: [0.1, 0.3, 0.7]
            .iter()
            .map(|&a| CoatTable::new(1.5, a))
            .collect(),
    }
}

/// Every BSDF under test, with a name; `rho` is the diffuse/base reflectance.
fn configs(t: &Tables, rho: Rgb) -> Vec<(String, Bxdf<'_>)> {
    let mut v = vec![("diffuse".to_string(), Bxdf::Diffuse(DiffuseBxdf { r: rho }))];
    for a in [0.0, 0.1, 0.3, 0.7] {
        v.push((
            format!("conductor α={a}"),
            Bxdf::Conductor(ConductorBxdf {
                distrib: TrowbridgeReitz::isotropic(a),
                eta: AU_ETA,
                k: AU_K,
            }),
        ));
    }
    for (a, eta) in [
        (0.0, 1.5),
        (0.1, 1.5),
        (0.3, 1.5),
        (0.7, 1.5),
        (0.3, 1.0 / 1.33),
    ] {
        v.push((
            format!("dielectric α={a} η={eta:.3}"),
            Bxdf::Dielectric(DielectricBxdf {
                distrib: TrowbridgeReitz::isotropic(a),
                eta,
            }),
        ));
    }
    v.push((
        "plastic smooth".to_string(),
        Bxdf::Plastic(PlasticBxdf::new(rho, &t.smooth)),
    ));
    for c in &t.rough {
        v.push((
            format!("plastic α={}", c.distrib.alpha_x),
            Bxdf::Plastic(PlasticBxdf::new(rho, c)),
        ));
    }
    for g in [0.0, 0.7, -0.5, 0.95] {
        v.push((
            format!("Henyey-Greenstein g={g}"),
            Bxdf::Phase(HenyeyGreenstein { g }),
        ));
    }
    v
}

/// Outgoing directions: near-normal, oblique, grazing, and (for glass) from inside.
fn outgoing(b: &Bxdf) -> Vec<DVec3> {
    let mut v: Vec<DVec3> = [0.1f64, 0.8, 1.4]
        .iter()
        .map(|&t| DVec3::new(t.sin() * 0.8, t.sin() * 0.6, t.cos()))
        .collect();
    if matches!(b, Bxdf::Dielectric(_)) {
        v.push(DVec3::new(0.3, 0.1, -0.9).normalize());
        v.push(DVec3::new(-0.5, 0.0, -0.5).normalize());
    }
    v
}

/// Non-specular samples follow pdf: chi-square over 24 × 48 equal-area cells with
/// 200 000 draws, significance 1e-3; and ∫pdf over the sphere (quadrature) equals the
/// fraction of draws that yield a non-specular direction, within 4 binomial σ plus
/// 3e-3 of quadrature error.
#[test]
fn sampling_matches_pdf() {
    let t = tables();
    let bins = SphereBins::new(24, 48);
    let n = 200_000;
    for (name, b) in configs(&t, Rgb::new(0.8, 0.4, 0.1)) {
        for wo in outgoing(&b) {
            let r = sphere_chi2(
                &bins,
                n,
                17,
                |u| {
                    b.sample_f(wo, u[0], DVec2::new(u[1], u[2]))
                        .filter(|s| !s.specular)
                        .map(|s| s.wi)
                },
                |wi| b.pdf(wo, wi),
            );
            let tol = 4.0 * (r.valid * (1.0 - r.valid) / n as f64).sqrt() + 3e-3;
            assert!(r.p_value > 1e-3, "{name} wo {wo}: {r:?}");
            assert!((r.mass - r.valid).abs() < tol, "{name} wo {wo}: {r:?}");
        }
    }
}

/// `f_pdf` is `f` and `pdf` bit for bit, over the whole sphere of incident directions
/// (both hemispheres, grazing ones, and the mirror direction where ωo + ωi vanishes
/// for transmission), for every BSDF and outgoing direction, in the local frame and
/// through a [`Bsdf`]'s frame.
#[test]
fn f_pdf_is_f_and_pdf_bit_for_bit() {
    let t = tables();
    let s = Sampler::new(11);
    let bits = |(f, p): (Rgb, f64)| (f.to_array().map(f64::to_bits), p.to_bits());
    for (name, b) in configs(&t, Rgb::new(0.8, 0.4, 0.1)) {
        let n = DVec3::new(0.3, -0.5, 0.8).normalize();
        let bsdf = Bsdf::new(n, b);
        // Reflective BSDFs are two-sided: from below as well.
        let wos = outgoing(&b).into_iter().flat_map(|w| [w, -w]);
        for wo in wos {
            let mut wis: Vec<DVec3> = (0..4000)
                .map(|i| {
                    let st = s.stream(7, 0, i);
                    uniform_sphere(DVec2::new(st.get(0), st.get(1)))
                })
                .collect();
            wis.extend([
                -wo,
                DVec3::new(wo.x, wo.y, -wo.z),
                DVec3::new(1.0, 0.0, 0.0),
            ]);
            wis.push(DVec3::new(0.6, 0.8, 1e-12).normalize());
            for wi in wis {
                assert_eq!(
                    bits(b.f_pdf(wo, wi)),
                    bits((b.f(wo, wi), b.pdf(wo, wi))),
                    "{name}"
                );
                let (wo_w, wi_w) = (bsdf.frame.from_local(wo), bsdf.frame.from_local(wi));
                assert_eq!(
                    bits(bsdf.f_pdf(wo_w, wi_w)),
                    bits((bsdf.f(wo_w, wi_w), bsdf.pdf(wo_w, wi_w))),
                    "{name}"
                );
            }
        }
    }
}

/// A sample's f and pdf equal f(wo, wi) and pdf(wo, wi) (relative 1e-9), and its
/// weight is f |cos θi| / pdf; specular samples have pdf(wo, wi) = 0 for pure
/// delta BSDFs.
#[test]
fn sample_agrees_with_eval() {
    let t = tables();
    let s = Sampler::new(3);
    for (name, b) in configs(&t, Rgb::new(0.8, 0.4, 0.1)) {
        for wo in outgoing(&b) {
            for i in 0..20_000 {
                let st = s.stream(1, 2, i);
                let Some(x) = b.sample_f(wo, st.get(0), DVec2::new(st.get(1), st.get(2))) else {
                    continue;
                };
                assert!(x.pdf > 0.0 && (x.wi.length() - 1.0).abs() < 1e-9);
                if x.specular {
                    if b.is_pure_specular() {
                        assert_eq!(b.pdf(wo, x.wi), 0.0);
                    }
                    continue;
                }
                let (f, pdf) = (b.f(wo, x.wi), b.pdf(wo, x.wi));
                assert!(
                    (x.pdf - pdf).abs() <= 1e-9 * pdf,
                    "{name}: {} vs {pdf}",
                    x.pdf
                );
                assert!(
                    (x.f - f).abs().max_element() <= 1e-9 * f.max_element(),
                    "{name}"
                );
                // A phase function has no cosine factor.
                let cos = if matches!(b, Bxdf::Phase(_)) {
                    1.0
                } else {
                    x.wi.z.abs()
                };
                let w = f * cos / pdf;
                assert!((x.weight - w).abs().max_element() <= 1e-9 * w.max_element());
            }
        }
    }
}

/// Mean and standard error of the energy weight f|cos|/pdf (transmission scaled by
/// η′² to undo radiance compression) over `n` samples.
fn albedo(b: &Bxdf, wo: DVec3, n: u64, seed: u64) -> (Rgb, Rgb) {
    let s = Sampler::new(seed);
    let (mut sum, mut sum2) = (Rgb::ZERO, Rgb::ZERO);
    for i in 0..n {
        let st = s.stream(0, 0, i as u32);
        if let Some(x) = b.sample_f(wo, st.get(0), DVec2::new(st.get(1), st.get(2))) {
            let w = x.weight * (x.eta * x.eta);
            sum += w;
            sum2 += w * w;
        }
    }
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(Rgb::ZERO);
    (mean, sqrt3(var / n as f64))
}

fn sqrt3(v: Rgb) -> Rgb {
    Rgb::new(v.x.sqrt(), v.y.sqrt(), v.z.sqrt())
}

/// White furnace: the energy albedo ∫ f |cos θi| dωi (transmission scaled by η′²; ∫ p
/// for a phase function) of every BSDF, from 200 000 samples, satisfies, per channel (σ the standard error):
/// - always: albedo ≤ 1 + 4σ (+ 5e-4 for plastic: its coat albedo is tabulated);
/// - white diffuse and smooth glass are lossless sample by sample: |albedo − 1| < 1e-12;
/// - white plastic (ρ = 1) is lossless by construction: |albedo − 1| < 4σ + 5e-4;
/// - rough glass loses only what single-scattering GGX loses to masking (Heitz et
///   al. 2016, "Multiple-Scattering Microfacet BSDFs with the Smith Model"). These
///   lower bounds are regression bounds, set below the measured minima over the tested
///   directions (grazing and from inside included: 0.942, 0.730, 0.589), not derived:
///   albedo ≥ 0.90 (α = 0.1), 0.70 (α = 0.3), 0.55 (α = 0.7).
#[test]
fn white_furnace() {
    let t = tables();
    for (name, b) in configs(&t, Rgb::ONE) {
        let plastic = matches!(b, Bxdf::Plastic(_));
        let slack = if plastic { 5e-4 } else { 0.0 };
        for wo in outgoing(&b) {
            let (m, se) = albedo(&b, wo, 200_000, 5);
            for c in 0..3 {
                let (m, se) = (m[c], se[c]);
                assert!(m <= 1.0 + 4.0 * se + slack, "{name} wo {wo}: {m} ± {se}");
                match b {
                    Bxdf::Diffuse(_) => assert!((m - 1.0).abs() < 1e-12, "{name}: {m}"),
                    Bxdf::Plastic(_) => {
                        assert!(
                            (m - 1.0).abs() < 4.0 * se + slack,
                            "{name} wo {wo}: {m} ± {se}"
                        )
                    }
                    Bxdf::Dielectric(d) => {
                        let a = d.distrib.alpha_x;
                        let lower = match a {
                            a if a < 1e-3 => 1.0 - 1e-12,
                            a if a <= 0.1 => 0.90,
                            a if a <= 0.3 => 0.70,
                            _ => 0.55,
                        };
                        assert!(m >= lower, "{name} wo {wo}: {m} < {lower}");
                    }
                    Bxdf::Conductor(_) => assert!(m > 0.0),
                    // Sampled exactly: every weight is 1.
                    Bxdf::Phase(_) => assert!((m - 1.0).abs() < 1e-12, "{name}: {m}"),
                }
            }
        }
    }
}

/// Reciprocity (relative 1e-7: the two sides compute the generalised half vector from
/// different sums, which loses digits in near-degenerate refraction) at 20 000 random
/// direction pairs: f(wo, wi) = f(wi, wo)
/// for reflection, and for glass Veach's generalised form (thesis §5.2)
/// f(wo, wi) / n(wo)² = f(wi, wo) / n(wi)², n the index on each direction's side.
#[test]
fn reciprocity() {
    let t = tables();
    let s = Sampler::new(44);
    for (name, b) in configs(&t, Rgb::new(0.8, 0.4, 0.1)) {
        let eta = match b {
            Bxdf::Dielectric(d) => d.eta,
            _ => 1.0,
        };
        let n2 = |w: DVec3| if w.z > 0.0 { 1.0 } else { eta * eta };
        for i in 0..20_000 {
            let st = s.stream(0, 0, i as u32);
            let wo = uniform_sphere(DVec2::new(st.get(0), st.get(1)));
            let wi = uniform_sphere(DVec2::new(st.get(2), st.get(3)));
            let a = b.f(wo, wi) / n2(wo);
            let c = b.f(wi, wo) / n2(wi);
            let scale = a.max_element().max(c.max_element());
            assert!(
                (a - c).abs().max_element() <= 1e-7 * scale,
                "{name}: {a} vs {c}"
            );
        }
    }
}

/// Analytic spot checks: a smooth conductor's sample weight is F(cos θ) per channel,
/// and a smooth dielectric reflects with probability F.
#[test]
fn smooth_limits() {
    use super::fresnel::{fr_conductor, fr_dielectric};
    let wo = DVec3::new(0.6, 0.0, 0.8);
    let c = Bxdf::Conductor(ConductorBxdf {
        distrib: TrowbridgeReitz::isotropic(0.0),
        eta: AU_ETA,
        k: AU_K,
    });
    let x = c.sample_f(wo, 0.5, DVec2::splat(0.5)).unwrap();
    assert!(x.specular && x.wi == DVec3::new(-0.6, 0.0, 0.8));
    assert!(
        (x.weight - fr_conductor(0.8, AU_ETA, AU_K))
            .abs()
            .max_element()
            < 1e-12
    );
    let g = Bxdf::Dielectric(DielectricBxdf {
        distrib: TrowbridgeReitz::isotropic(0.0),
        eta: 1.5,
    });
    let f = fr_dielectric(0.8, 1.5);
    let r = g.sample_f(wo, f * 0.999, DVec2::ZERO).unwrap();
    assert!(r.specular && !r.wi.z.is_sign_negative() && (r.pdf - f).abs() < 1e-12);
    let t = g.sample_f(wo, f * 1.001, DVec2::ZERO).unwrap();
    // Snell: sin θt = sin θi / η.
    assert!(t.wi.z < 0.0 && ((1.0 - t.wi.z * t.wi.z).sqrt() - 0.6 / 1.5).abs() < 1e-12);
    assert!((t.pdf - (1.0 - f)).abs() < 1e-12 && t.eta == 1.5);
}
