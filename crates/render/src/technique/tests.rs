//! Every technique against its pdf, and irradiance from analytic configurations.

use super::*;
use crate::bsdf::{Bxdf, CoatTable, DiffuseBxdf, PlasticBxdf};
use crate::color::Rgb;
use crate::light::{AreaLight, EnvMap, Environment, Shape, TrainedSelection};
use crate::sampler::Sampler;
use crate::testutil::{sphere_chi2, SphereBins};
use frep::Ray;
use glam::DMat3;
use std::f64::consts::PI;

fn scene_lights() -> Lights {
    let (w, h) = (32, 16);
    let pixels = (0..w * h)
        .map(|i| Rgb::splat(if i % w < 8 && i / w < 5 { 4.0 } else { 0.1 }))
        .collect();
    Lights::new(
        vec![
            AreaLight::new(
                Shape::Sphere {
                    center: DVec3::new(1.0, 0.5, 2.0),
                    radius: 0.5,
                },
                Rgb::splat(5.0),
            ),
            AreaLight::new(
                Shape::Rect {
                    corner: DVec3::new(-2.0, -1.0, 1.5),
                    edge_u: DVec3::new(0.0, 1.0, 0.0),
                    edge_v: DVec3::new(1.0, 0.0, 0.0),
                },
                Rgb::splat(2.0),
            ),
            AreaLight::new(
                Shape::Disk {
                    center: DVec3::new(0.0, -1.0, 0.5),
                    normal: DVec3::new(0.0, 1.0, 0.0),
                    radius: 0.3,
                },
                Rgb::new(3.0, 1.0, 1.0),
            ),
        ],
        vec![],
        Some(Environment::Map(EnvMap::new(w, h, pixels, DMat3::IDENTITY))),
        3.0,
    )
}

/// Planar lights only, two of them overlapping as seen from the origin (so that the
/// pdfs must sum over lights behind lights).
fn planar_lights() -> Lights {
    let rect = |z: f64, s: f64, l: f64| {
        AreaLight::new(
            Shape::Rect {
                corner: DVec3::new(-s, -s, z),
                edge_u: DVec3::new(0.0, 2.0 * s, 0.0),
                edge_v: DVec3::new(2.0 * s, 0.0, 0.0),
            },
            Rgb::splat(l),
        )
    };
    let disk = AreaLight::new(
        Shape::Disk {
            center: DVec3::new(1.5, 0.0, 0.5),
            normal: DVec3::new(-1.0, 0.0, -0.2).normalize(),
            radius: 0.4,
        },
        Rgb::ONE,
    );
    Lights::new(
        vec![rect(1.0, 0.5, 2.0), rect(2.0, 1.5, 1.0), disk],
        vec![],
        None,
        3.0,
    )
}

/// A trained table over [−1, 1]³ in 2³ cells with uneven weights (light k of cell c
/// weighs (k + 1)² + c, one light 0 in every cell: the floor keeps it).
fn trained_table(lights: &Lights) -> TrainedSelection {
    let n = lights.count();
    let w: Vec<f64> = (0..8 * n)
        .map(|i| {
            let (c, k) = (i / n, i % n);
            if k == 1 {
                0.0
            } else {
                ((k + 1) * (k + 1) + c) as f64
            }
        })
        .collect();
    TrainedSelection::from_weights(DVec3::splat(-1.0), DVec3::ONE, 2, n, &w)
}

/// Each technique's samples follow its pdf (also `light-uniform`, `light-spatial` and
/// `light#k`, whose pdfs are mixtures over lights behind lights in scene B) (chi-square over 32 × 64 cells, 300 000
/// samples, significance 1e-3), its pdf integrates to the fraction of non-specular
/// samples it yields (1 for the light, environment and cosine techniques; quadrature
/// tolerance 3e-3 plus 4 binomial σ), and a sample's pdf equals pdf(wi). Scene A has
/// a sphere, a rectangle, a disk and an environment map; light-area sampling, whose
/// direction pdf is singular at a sphere's silhouette (see the light tests), is
/// checked on scene B of overlapping planar lights, with light sampling. Four tests
/// (each BSDF, the first and second half of the cases), so that they run in parallel.
fn techniques_match_pdfs(bsdf: usize, half: usize) {
    let a = scene_lights();
    let b = planar_lights();
    let cases = [
        (&a, Technique::Bsdf),
        (&a, Technique::LightPower),
        (&a, Technique::Environment),
        (&a, Technique::CosineHemisphere),
        (&b, Technique::LightArea),
        (&b, Technique::LightPower),
        (&a, Technique::LightUniform),
        (&b, Technique::LightUniform),
        (&a, Technique::LightSpatial),
        (&b, Technique::LightSpatial),
        (&a, Technique::Light(0)),
        (&a, Technique::Light(1)),
        (&a, Technique::Light(3)),
        (&b, Technique::Light(1)),
        (&a, Technique::LightTrained),
        (&b, Technique::LightTrained),
    ];
    let coat = CoatTable::new(1.5, 0.2);
    let bsdfs = [
        Bsdf::new(
            DVec3::Z,
            Bxdf::Plastic(PlasticBxdf::new(Rgb::splat(0.5), &coat)),
        ),
        Bsdf::new(
            DVec3::new(0.2, 0.1, 1.0).normalize(),
            Bxdf::Diffuse(DiffuseBxdf { r: Rgb::ONE }),
        ),
    ];
    let bsdf = &bsdfs[bsdf];
    let bins = SphereBins::new(32, 64);
    let n = 300_000;
    let m = cases.len() / 2;
    for &(lights, t) in &cases[half * m..(half + 1) * m] {
        let table = trained_table(lights);
        let ctx = ShadingPoint {
            p: DVec3::new(0.1, 0.0, 0.0),
            n: bsdf.frame.n,
            wo: DVec3::new(0.3, -0.4, 0.8).normalize(),
            bsdf,
            lights,
            trained: Some(&table),
        };
        let r = sphere_chi2(
            &bins,
            n,
            31,
            |u| {
                let s = t.sample(&ctx, u[0], DVec2::new(u[1], u[2]))?;
                if s.specular {
                    return None;
                }
                let pdf = t.pdf(&ctx, s.wi);
                assert!(
                    (s.pdf - pdf).abs() <= 1e-9 * pdf,
                    "{}: {} vs {pdf}",
                    t.name(),
                    s.pdf
                );
                Some(s.wi)
            },
            |w| t.pdf(&ctx, w),
        );
        let tol = 4.0 * (r.valid * (1.0 - r.valid) / n as f64).sqrt() + 3e-3;
        assert!(r.p_value > 1e-3, "{}: {r:?}", t.name());
        assert!((r.mass - r.valid).abs() < tol, "{}: {r:?}", t.name());
        if t != Technique::Bsdf {
            assert_eq!(r.valid, 1.0, "{}", t.name());
        }
    }
}

#[test]
fn techniques_match_pdfs_on_plastic_first_half() {
    techniques_match_pdfs(0, 0);
}

#[test]
fn techniques_match_pdfs_on_plastic_second_half() {
    techniques_match_pdfs(0, 1);
}

#[test]
fn techniques_match_pdfs_on_a_tilted_diffuse_first_half() {
    techniques_match_pdfs(1, 0);
}

#[test]
fn techniques_match_pdfs_on_a_tilted_diffuse_second_half() {
    techniques_match_pdfs(1, 1);
}

/// Monte Carlo irradiance E = ∫ L cos θ dω at the origin (normal +z) with `n`
/// samples of technique `t`: (mean, standard error).
fn irradiance(lights: &Lights, t: Technique, n: u64, seed: u64) -> (f64, f64) {
    let table = trained_table(lights);
    let bsdf = Bsdf::new(DVec3::Z, Bxdf::Diffuse(DiffuseBxdf { r: Rgb::ONE }));
    let ctx = ShadingPoint {
        p: DVec3::ZERO,
        n: DVec3::Z,
        wo: DVec3::Z,
        bsdf: &bsdf,
        lights,
        trained: Some(&table),
    };
    let s = Sampler::new(seed);
    let (mut sum, mut sum2) = (0.0, 0.0);
    for i in 0..n {
        let st = s.stream(0, 0, i as u32);
        if let Some(x) = t.sample(&ctx, st.get(0), DVec2::new(st.get(1), st.get(2))) {
            let l = lights.radiance_along(&Ray::new(ctx.p, x.wi), 0.0, f64::INFINITY);
            let v = l.x * x.wi.z.max(0.0) / x.pdf;
            sum += v;
            sum2 += v * v;
        }
    }
    let mean = sum / n as f64;
    (mean, ((sum2 / n as f64 - mean * mean) / n as f64).sqrt())
}

/// Irradiance under a sphere light (E = π L sin²θ, θ the half-angle it subtends)
/// and under a parallel rectangle centred above the point (E = π L F, F the form
/// factor of a differential area to a parallel rectangle, sum of four corner terms
/// F = (1/2π)[X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))]), with light
/// (by power, uniform, spatial, `light#0`), light-area, BSDF and cosine sampling, 200 000 samples each: within 4 standard
/// errors (two-sided confidence 99.99 %), standard errors below 1 % of E.
#[test]
fn irradiance_matches_analytic() {
    let l = 3.0;
    let sphere = Lights::new(
        vec![AreaLight::new(
            Shape::Sphere {
                center: DVec3::new(0.0, 0.0, 2.0),
                radius: 1.0,
            },
            Rgb::splat(l),
        )],
        vec![],
        None,
        3.0,
    );
    let e_sphere = PI * l * 0.25;
    let (a, b, h) = (2.0, 1.0, 0.8);
    let rect = Lights::new(
        vec![AreaLight::new(
            Shape::Rect {
                corner: DVec3::new(-a / 2.0, -b / 2.0, h),
                edge_u: DVec3::new(0.0, b, 0.0),
                edge_v: DVec3::new(a, 0.0, 0.0),
            },
            Rgb::splat(l),
        )],
        vec![],
        None,
        3.0,
    );
    let corner = |x: f64, y: f64| {
        let (x, y) = (x / h, y / h);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
    };
    let e_rect = PI * l * 4.0 * corner(a / 2.0, b / 2.0);
    for (name, lights, exact) in [("sphere", &sphere, e_sphere), ("rect", &rect, e_rect)] {
        for t in [
            Technique::LightPower,
            Technique::LightUniform,
            Technique::LightSpatial,
            Technique::Light(0),
            Technique::LightTrained,
            Technique::LightArea,
            Technique::Bsdf,
            Technique::CosineHemisphere,
        ] {
            let (e, se) = irradiance(lights, t, 200_000, 77);
            assert!(
                (e - exact).abs() < 4.0 * se && se < 0.01 * exact,
                "{name} {}: {e} ± {se} vs {exact}",
                t.name()
            );
        }
    }
}

/// [`pdfs`] finds the lights a direction crosses once for every light mixture; each
/// density is the one [`Technique::pdf`] gives alone, bit for bit, on directions drawn
/// by every technique (so that many cross lights, some two at once in scene B). So are
/// the densities from [`Lights::along`]'s single walk, whose nearest light is
/// [`Lights::intersect`]'s.
#[test]
fn shared_crossings_give_each_techniques_own_pdf() {
    let all = [
        Technique::Bsdf,
        Technique::LightPower,
        Technique::LightUniform,
        Technique::LightArea,
        Technique::LightSpatial,
        Technique::Light(1),
        Technique::LightTrained,
        Technique::Environment,
        Technique::CosineHemisphere,
    ];
    let bsdf = Bsdf::new(DVec3::Z, Bxdf::Diffuse(DiffuseBxdf { r: Rgb::ONE }));
    let (mut crossing, mut total) = (0, 0);
    for lights in [&scene_lights(), &planar_lights()] {
        let table = trained_table(lights);
        let ctx = ShadingPoint {
            p: DVec3::new(0.1, 0.0, 0.0),
            n: DVec3::Z,
            wo: DVec3::new(0.3, -0.4, 0.8).normalize(),
            bsdf: &bsdf,
            lights,
            trained: Some(&table),
        };
        let s = Sampler::new(5);
        let mut out = [0.0; 9];
        for i in 0..4000u32 {
            let r = s.stream(i, 0, 0);
            let t = all[i as usize % all.len()];
            let Some(d) = t.sample(&ctx, r.get(0), r.get_2d(1)) else {
                continue;
            };
            pdfs(&all, &ctx, d.wi, None, None, &mut out);
            for (k, t) in all.iter().enumerate() {
                assert_eq!(out[k].to_bits(), t.pdf(&ctx, d.wi).to_bits(), "{t:?}");
            }
            // One walk for Li and the pdfs: the same pdfs, and the nearest light the
            // nearest-hit query finds.
            let ray = Ray::new(ctx.p, d.wi);
            let along = lights.along(&ray, true);
            let mut shared = [0.0; 9];
            pdfs(&all, &ctx, d.wi, along.crossed(), None, &mut shared);
            assert_eq!(shared.map(f64::to_bits), out.map(f64::to_bits));
            // Sets whose pdfs all come from the list (`pdfs_listed`, without an
            // environment), with and without one technique per light.
            let bsdf_pdf = Some(Technique::Bsdf.pdf(&ctx, d.wi));
            for listable in [
                &[Technique::Bsdf, Technique::LightPower, Technique::LightArea][..],
                &[Technique::Light(1), Technique::Bsdf, Technique::Light(0)],
                &[
                    Technique::LightArea,
                    Technique::Light(2),
                    Technique::LightPower,
                ],
            ] {
                // NaN where nothing is written: every pdf must be.
                let mut own = [f64::NAN; 3];
                let map = one_light_map(listable);
                let one = map.as_ref().map_or(OneLight::None, OneLight::Map);
                let c = along.crossed();
                pdfs_known(one, listable, &ctx, d.wi, c, bsdf_pdf, &mut own);
                for (k, t) in listable.iter().enumerate() {
                    let want = t.pdf(&ctx, d.wi);
                    assert_eq!(own[k].to_bits(), want.to_bits(), "{t:?} of {listable:?}");
                }
            }
            // Without by-area pdfs in the list (no technique samples by area), the
            // power mixture's sum alone (`Lights::pdf_listed_mixtures`).
            let no_area = lights.along(&ray, false);
            let listable = [Technique::LightPower, Technique::Bsdf];
            let mut own = [f64::NAN; 2];
            let c = no_area.crossed();
            pdfs_known(OneLight::None, &listable, &ctx, d.wi, c, bsdf_pdf, &mut own);
            for (k, t) in listable.iter().enumerate() {
                assert_eq!(own[k].to_bits(), t.pdf(&ctx, d.wi).to_bits(), "{t:?}");
            }
            assert_eq!(along.nearest, lights.intersect(&ray, 0.0, f64::INFINITY));
            total += 1;
            crossing += usize::from(out[3] > 0.0);
        }
    }
    assert!(
        crossing > total / 4,
        "{crossing} of {total} directions cross a light"
    );
}

/// `one_light_map` gives each light's technique index and the other techniques', and
/// None without one-light techniques or where a light has two.
#[test]
fn one_light_map_finds_each_lights_technique() {
    use Technique::{Bsdf, Light, LightPower};
    let m = one_light_map(&[Light(2), Bsdf, Light(0), LightPower]).unwrap();
    assert_eq!(&*m.of_light, &[2, u32::MAX, 0]);
    assert_eq!(&*m.others, &[1, 3]);
    assert!(one_light_map(&[Bsdf, LightPower]).is_none());
    assert!(one_light_map(&[Light(1), Bsdf, Light(1)]).is_none());
}
