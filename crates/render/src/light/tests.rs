//! Area-light sampling against pdfs, intersection, and selection.

use super::*;
use crate::testutil::{sphere_chi2, SphereBins};
use std::f64::consts::PI;

fn shapes() -> Vec<(&'static str, AreaLight)> {
    let l = Rgb::new(1.0, 2.0, 3.0);
    vec![
        (
            "sphere",
            AreaLight::new(
                Shape::Sphere {
                    center: DVec3::new(0.3, -0.2, 2.0),
                    radius: 0.8,
                },
                l,
            ),
        ),
        (
            "small sphere",
            AreaLight::new(
                Shape::Sphere {
                    center: DVec3::new(1.0, 0.0, 3.0),
                    radius: 0.05,
                },
                l,
            ),
        ),
        (
            "rect",
            AreaLight::new(
                Shape::Rect {
                    corner: DVec3::new(-1.0, -0.5, 1.0),
                    edge_u: DVec3::new(0.0, 1.5, 0.0),
                    edge_v: DVec3::new(2.0, 0.0, 0.3),
                },
                l,
            ),
        ),
        (
            "disk",
            AreaLight {
                two_sided: true,
                ..AreaLight::new(
                    Shape::Disk {
                        center: DVec3::new(0.0, 1.0, 1.0),
                        normal: DVec3::new(0.0, -1.0, -1.0).normalize(),
                        radius: 0.7,
                    },
                    l,
                )
            },
        ),
        (
            // About 0.9 sr from the test points, facing them: sampled by solid angle.
            "triangle",
            AreaLight::new(
                Shape::Triangle {
                    p0: DVec3::new(-0.8, -0.6, 1.2),
                    e1: DVec3::new(0.3, 1.6, -0.2),
                    e2: DVec3::new(1.9, 0.2, 0.4),
                },
                l,
            ),
        ),
    ]
}

/// Both samplings of every shape follow their pdfs (chi-square over 32 × 64 cells,
/// 300 000 samples, significance 1e-3) and the pdfs integrate to 1 over the sphere
/// (adaptive quadrature, 3e-3). The small sphere's cone is too small for direction
/// cells (see `small_cone_sampling`). Uniform-area sampling of a sphere is left to
/// `sphere_area_sampling`: its direction pdf has an integrable 1/√ singularity at
/// the silhouette that quadrature over direction cells cannot resolve.
#[test]
fn light_sampling_matches_pdf() {
    let bins = SphereBins::new(32, 64);
    let p = DVec3::new(0.1, 0.05, 0.0);
    for (name, l) in shapes() {
        let tol = 3e-3;
        if name == "small sphere" {
            continue; // see small_cone_sampling
        }
        let r = sphere_chi2(
            &bins,
            300_000,
            8,
            |u| l.sample_li(p, DVec2::new(u[0], u[1])).map(|s| s.wi),
            |w| l.pdf_li(p, w),
        );
        assert!(
            r.p_value > 1e-3 && (r.mass - 1.0).abs() < tol && r.valid == 1.0,
            "{name} li: {r:?}"
        );
        if matches!(l.shape, Shape::Sphere { .. }) {
            continue;
        }
        let r = sphere_chi2(
            &bins,
            300_000,
            9,
            |u| l.sample_area(p, DVec2::new(u[0], u[1])).map(|s| s.wi),
            |w| l.pdf_area(p, w),
        );
        assert!(
            r.p_value > 1e-3 && (r.mass - 1.0).abs() < tol && r.valid == 1.0,
            "{name} area: {r:?}"
        );
    }
}

/// Uniform-area sampling of a sphere seen from outside: the sampled points (p + dist·wi)
/// are uniform over the sphere (chi-square over 16 × 32 equal-area cells of the
/// sphere, 300 000 samples, significance 1e-3), and E[1/pdf(wi)] equals the solid
/// angle 2π(1 − cos θmax) of the cone the sphere subtends (within 4 standard errors),
/// which holds only if pdf is the density of the directions everywhere they occur.
#[test]
fn sphere_area_sampling() {
    let (center, radius) = (DVec3::new(0.3, -0.2, 2.0), 0.8);
    let l = AreaLight::new(Shape::Sphere { center, radius }, Rgb::ONE);
    let p = DVec3::new(0.1, 0.05, 0.0);
    let bins = SphereBins::new(16, 32);
    let n = 300_000u64;
    let mut counts = vec![0u64; 16 * 32];
    let (mut sum, mut sum2) = (0.0, 0.0);
    let s = crate::sampler::Sampler::new(10);
    for i in 0..n {
        let st = s.stream(0, 0, i as u32);
        let x = l.sample_area(p, DVec2::new(st.get(0), st.get(1))).unwrap();
        let q = p + x.wi * x.dist;
        assert!(((q - center).length() - radius).abs() < 1e-9);
        counts[bins.cell((q - center) / radius)] += 1;
        let v = 1.0 / l.pdf_area(p, x.wi);
        sum += v;
        sum2 += v * v;
    }
    let e = n as f64 / counts.len() as f64;
    let stat: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
    let pv = crate::testutil::chi2_pvalue(stat, counts.len() - 1);
    assert!(pv > 1e-3, "chi2 {stat} p {pv}");
    let mean = sum / n as f64;
    let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
    let omega = 2.0 * PI * (1.0 - (1.0 - radius * radius / p.distance_squared(center)).sqrt());
    assert!(
        (mean - omega).abs() < 4.0 * se && se < 0.01 * omega,
        "{mean} ± {se} vs {omega}"
    );
}

/// A sample's pdf equals the pdf of its direction; its point lies on the light at
/// `dist` along `wi`; its radiance is L where the light faces p, else 0.
#[test]
fn samples_are_consistent() {
    let p = DVec3::new(0.1, 0.05, 0.0);
    for (name, l) in shapes() {
        let mut lit = 0;
        for i in 0..2000 {
            let u = DVec2::new(
                (i as f64 + 0.5) / 2000.0,
                ((i * 769) % 2000) as f64 / 2000.0,
            );
            for (s, pdf) in [
                (
                    l.sample_li(p, u).unwrap(),
                    l.pdf_li(p, l.sample_li(p, u).unwrap().wi),
                ),
                (
                    l.sample_area(p, u).unwrap(),
                    l.pdf_area(p, l.sample_area(p, u).unwrap().wi),
                ),
            ] {
                assert!(
                    (s.pdf - pdf).abs() <= 1e-9 * pdf,
                    "{name}: {} vs {pdf}",
                    s.pdf
                );
                let (c, k) = l.crossings(p, s.wi);
                assert!(
                    c[..k].iter().flatten().any(|c| (c.t - s.dist).abs() < 1e-9),
                    "{name}: sampled point not on the light"
                );
                if s.radiance != Rgb::ZERO {
                    assert_eq!(s.radiance, l.radiance);
                    lit += 1;
                }
            }
        }
        assert!(lit > 0, "{name}");
    }
}

#[test]
fn area_and_power() {
    let s = shapes();
    assert!((s[0].1.area() - 4.0 * PI * 0.64).abs() < 1e-12);
    // |(2,0,0.3) × (0,1.5,0)| = 1.5·√(4.09).
    assert!((s[2].1.area() - 1.5 * 4.09f64.sqrt()).abs() < 1e-12);
    assert!((s[3].1.area() - PI * 0.49).abs() < 1e-12);
    // Two-sided disk emits twice π A L.
    assert!((s[3].1.power().x - 2.0 * PI * PI * 0.49).abs() < 1e-12);
    // A one-sided rect facing away emits nothing toward p.
    let r = AreaLight::new(
        Shape::Rect {
            corner: DVec3::new(-1.0, -1.0, 1.0),
            edge_u: DVec3::new(2.0, 0.0, 0.0),
            edge_v: DVec3::new(0.0, 2.0, 0.0),
        },
        Rgb::ONE,
    );
    let sm = r.sample_li(DVec3::ZERO, DVec2::splat(0.5)).unwrap();
    assert_eq!(sm.radiance, Rgb::ZERO);
    assert_eq!(sm.wi, DVec3::Z);
}

/// Light selection: by power picks a light with probability ∝ its power, by area
/// ∝ its area; the nearest light is found along a ray.
#[test]
fn selection_and_intersection() {
    let a = AreaLight::new(
        Shape::Disk {
            center: DVec3::new(0.0, 0.0, 2.0),
            normal: -DVec3::Z,
            radius: 1.0,
        },
        Rgb::splat(1.0),
    );
    let b = AreaLight::new(
        Shape::Disk {
            center: DVec3::new(0.0, 0.0, 3.0),
            normal: -DVec3::Z,
            radius: 2.0,
        },
        Rgb::splat(0.5),
    );
    let lights = Lights::new(vec![a, b], vec![], None, 10.0);
    let ray = Ray::new(DVec3::ZERO, DVec3::Z);
    let h = lights.intersect(&ray, 0.0, f64::INFINITY).unwrap();
    assert_eq!((h.light, h.t), (0, 2.0));
    assert_eq!(lights.radiance_along(&ray, 0.0, 1.5), Rgb::ZERO);
    let h = lights.intersect(&ray, 2.5, f64::INFINITY).unwrap();
    assert_eq!(h.light, 1);
    // Powers π·π·1 and π·4π·0.5: b is chosen with probability 2/3.
    let n = 30_000;
    let mut picks_b = 0;
    for i in 0..n {
        let uc = (i as f64 + 0.5) / n as f64;
        let s = lights
            .sample_by_power(DVec3::ZERO, uc, DVec2::splat(0.3))
            .unwrap();
        picks_b += (s.light == Some(1)) as usize;
    }
    assert!((picks_b as f64 / n as f64 - 2.0 / 3.0).abs() < 1e-3);
    // Straight up, both disks lie along the direction: the pdf sums both.
    let pa = 4.0 / (PI * 1.0);
    let pb = 9.0 / (PI * 4.0);
    let expect = pa / 3.0 + pb * 2.0 / 3.0;
    assert!((lights.pdf_by_power(DVec3::ZERO, DVec3::Z) - expect).abs() < 1e-12);
    let expect = pa * 0.2 + pb * 0.8;
    assert!((lights.pdf_by_area(DVec3::ZERO, DVec3::Z) - expect).abs() < 1e-12);
}

/// Cone sampling of a small sphere (half-angle 0.9°), tested in the cone's own frame:
/// (1 − cos γ)/(1 − cos γmax) and the azimuth about the axis are uniform (chi-square
/// over 20 × 20 cells, 300 000 samples, significance 1e-3), every sample lies within
/// the cone, and pdf_li is 1/(2π(1 − cos γmax)) there, 0 just outside.
#[test]
fn small_cone_sampling() {
    let (center, radius) = (DVec3::new(1.0, 0.0, 3.0), 0.05);
    let l = AreaLight::new(Shape::Sphere { center, radius }, Rgb::ONE);
    let p = DVec3::new(0.1, 0.05, 0.0);
    let axis = (center - p).normalize();
    let frame = crate::frame::Frame::from_z(axis);
    let sin2 = radius * radius / p.distance_squared(center);
    let one_minus_cos_max = sin2 / (1.0 + (1.0 - sin2).sqrt());
    let pdf = 1.0 / (2.0 * PI * one_minus_cos_max);
    let n = 300_000u64;
    let mut counts = vec![0u64; 400];
    let s = crate::sampler::Sampler::new(12);
    for i in 0..n {
        let st = s.stream(0, 0, i as u32);
        let x = l.sample_li(p, DVec2::new(st.get(0), st.get(1))).unwrap();
        assert!((x.pdf - pdf).abs() < 1e-9 * pdf && (l.pdf_li(p, x.wi) - pdf).abs() < 1e-9 * pdf);
        let w = frame.to_local(x.wi);
        // 1 − cos γ from the transverse part, without cancellation.
        let s2 = w.x * w.x + w.y * w.y;
        let a = s2 / (1.0 + w.z) / one_minus_cos_max;
        assert!(a <= 1.0 + 1e-6, "outside the cone: {a}");
        let phi = w.y.atan2(w.x) / (2.0 * PI) + 0.5;
        let (ia, ip) = (
            ((a * 20.0) as usize).min(19),
            ((phi * 20.0) as usize).min(19),
        );
        counts[ia * 20 + ip] += 1;
    }
    let e = n as f64 / 400.0;
    let stat: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
    let pv = crate::testutil::chi2_pvalue(stat, 399);
    assert!(pv > 1e-3, "chi2 {stat} p {pv}");
    // Just outside the cone: pdf 0.
    let g = (1.0 - one_minus_cos_max * 1.01).acos();
    let out = frame.from_local(DVec3::new(g.sin(), 0.0, g.cos()));
    assert_eq!(l.pdf_li(p, out), 0.0);
}

/// Light selection pmfs sum to 1 over the MIS lights at a point every light can reach:
/// uniform is 1/count, `One(k)` picks k, spatial gives the environment ½ and is 0 for a
/// one-sided light seen from behind, trained mixes its weights with the 0.1 floor; sampling picks lights with these probabilities
/// (30 000 stratified `uc`, within 1e-3).
#[test]
fn selection_pmfs() {
    let disk = |z: f64, normal: DVec3, l: f64| {
        AreaLight::new(
            Shape::Disk {
                center: DVec3::new(0.0, 0.0, z),
                normal,
                radius: 0.5,
            },
            Rgb::splat(l),
        )
    };
    let lights = Lights::new(
        vec![
            disk(2.0, -DVec3::Z, 1.0),
            disk(4.0, -DVec3::Z, 3.0),
            disk(-1.0, -DVec3::Z, 1.0), // below p, facing down: dark at p
        ],
        vec![],
        Some(Environment::Constant(Rgb::splat(0.1))),
        10.0,
    );
    let (p, n) = (DVec3::ZERO, DVec3::Z);
    assert_eq!(lights.count(), 4);
    // A trained table of one cell: weights 3, 1, 0, 0 → pmf 0.9·(3/4, 1/4, 0, 0) + 0.025.
    let table =
        TrainedSelection::from_weights(DVec3::splat(-1.0), DVec3::ONE, 1, 4, &[3.0, 1.0, 0.0, 0.0]);
    for sel in [
        Selection::Power,
        Selection::Uniform,
        Selection::Spatial,
        Selection::Bvh,
        Selection::One(2),
        Selection::Trained(&table),
    ] {
        let pm: Vec<f64> = (0..4).map(|k| lights.selection_pmf(sel, p, n, k)).collect();
        assert!(
            (pm.iter().sum::<f64>() - 1.0).abs() < 1e-12,
            "{sel:?}: {pm:?}"
        );
        let m = 30_000;
        let mut picks = [0usize; 4];
        for i in 0..m {
            let uc = (i as f64 + 0.5) / m as f64;
            if let Some(s) = lights.sample_selected(sel, p, n, uc, DVec2::new(0.3, 0.6)) {
                picks[s.light.unwrap_or(3)] += 1;
            }
        }
        for k in 0..4 {
            let f = picks[k] as f64 / m as f64;
            assert!(
                (f - pm[k]).abs() < 1e-3,
                "{sel:?} light {k}: {f} vs {}",
                pm[k]
            );
        }
        if sel == Selection::Uniform {
            assert!(pm.iter().all(|&x| x == 0.25));
        }
        if sel == Selection::Spatial {
            assert_eq!(pm[2], 0.0);
            assert_eq!(pm[3], 0.5);
            // Φ ∝ L, d² = 4 and 16, cos terms 1: importance 1/4 and 3/16.
            assert!((pm[0] / pm[1] - (1.0 / 4.0) / (3.0 / 16.0)).abs() < 1e-12);
        }
    }
    // Two lights compete where the third is dark: the light BVH's pmf is the spatial one.
    for k in 0..4 {
        let (s, b) = (
            lights.selection_pmf(Selection::Spatial, p, n, k),
            lights.selection_pmf(Selection::Bvh, p, n, k),
        );
        assert!((s - b).abs() < 1e-12, "light {k}: spatial {s}, BVH {b}");
    }
    assert_eq!(lights.selection_pmf(Selection::One(2), p, n, 2), 1.0);
    let trained: Vec<f64> = (0..4)
        .map(|k| lights.selection_pmf(Selection::Trained(&table), p, n, k))
        .collect();
    for (t, e) in trained.iter().zip([0.7, 0.25, 0.025, 0.025]) {
        assert!((t - e).abs() < 1e-12, "{trained:?}");
    }
    // Out of range: no sample, no density.
    assert!(lights
        .sample_selected(Selection::One(4), p, n, 0.5, DVec2::splat(0.5))
        .is_none());
    assert_eq!(lights.pdf_selected(Selection::One(4), p, n, DVec3::Z), 0.0);
}

/// The importance bound is positive wherever the light reaches the point (some of 64
/// stratified area samples carry radiance at a cosine above 1e-9), at 200 points around
/// every test shape: a zero would make `light-spatial` miss light (bias).
#[test]
fn importance_is_positive_where_light_arrives() {
    let s = shapes();
    let mut seen = 0;
    for (name, l) in &s {
        for i in 0..200 {
            let t = i as f64 * 0.731;
            let p = DVec3::new(
                2.0 * t.sin(),
                1.5 * (1.3 * t).cos(),
                2.0 - 3.0 * (0.7 * t).sin(),
            );
            let n = DVec3::new((0.3 * t).cos(), (0.9 * t).sin(), 0.5).normalize();
            let lit = (0..64).any(|j| {
                let u = DVec2::new((j % 8) as f64 / 8.0 + 0.06, (j / 8) as f64 / 8.0 + 0.06);
                l.sample_area(p, u)
                    .is_some_and(|x| x.radiance != Rgb::ZERO && x.wi.dot(n).abs() > 1e-9)
            });
            let imp = importance(l, p, n);
            if lit {
                seen += 1;
                assert!(imp > 0.0, "{name} at {p}: lit but importance 0");
            }
        }
    }
    assert!(seen > 100);
}

/// The light BVH changes no answer: over 60 lights of every shape (from `shapes()`,
/// scattered and scaled), rays from 400 points in 64 directions each meet the nearest
/// light the brute-force loop over all lights finds, and every selection's mixture pdf
/// (and light-area's) equals the brute-force sum over all lights to 1e-12 (relative),
/// grazing edges included; every crossing lies inside its light's box.
#[test]
fn light_bvh_answers_as_the_brute_force_loop() {
    let mut area = Vec::new();
    for k in 0..60 {
        let (_, l) = shapes()[k % 5];
        let off = DVec3::new(
            (k as f64 * 1.7).sin() * 4.0,
            (k as f64 * 2.3).cos() * 4.0,
            (k % 7) as f64 * 0.6 - 1.5,
        );
        let s = 0.3 + (k % 5) as f64 * 0.2;
        let shape = match l.shape {
            Shape::Sphere { center, radius } => Shape::Sphere {
                center: center * s + off,
                radius: radius * s,
            },
            Shape::Rect {
                corner,
                edge_u,
                edge_v,
            } => Shape::Rect {
                corner: corner * s + off,
                edge_u: edge_u * s,
                edge_v: edge_v * s,
            },
            Shape::Disk {
                center,
                normal,
                radius,
            } => Shape::Disk {
                center: center * s + off,
                normal,
                radius: radius * s,
            },
            Shape::Triangle { p0, e1, e2 } => Shape::Triangle {
                p0: p0 * s + off,
                e1: e1 * s,
                e2: e2 * s,
            },
        };
        area.push(AreaLight { shape, ..l });
    }
    let lights = Lights::new(
        area.clone(),
        vec![],
        Some(Environment::Constant(Rgb::splat(0.1))),
        10.0,
    );
    let table = TrainedSelection::from_weights(
        DVec3::splat(-6.0),
        DVec3::splat(6.0),
        2,
        61,
        &(0..8 * 61).map(|i| (i % 13) as f64).collect::<Vec<_>>(),
    );
    let sels = [
        Selection::Power,
        Selection::Uniform,
        Selection::Spatial,
        Selection::Trained(&table),
    ];
    let (mut hits, mut dense) = (0, 0);
    for i in 0..400 {
        let a = i as f64 * 0.37;
        let p = DVec3::new(5.0 * a.sin(), 5.0 * (1.3 * a).cos(), 2.0 * (0.7 * a).sin());
        let n = DVec3::new(a.cos(), 0.2, a.sin()).normalize();
        for j in 0..64 {
            let b = j as f64 * 0.61 + a;
            let wi = if j % 8 == 0 {
                // Straight at a light's edge: grazing the box.
                let l = &area[(i + j) % area.len()];
                let (q, _) = l.sample_point(DVec2::new(1.0, (j as f64 * 0.13).fract()));
                (q - p).normalize()
            } else {
                DVec3::new(b.sin() * (0.5 * b).cos(), (1.7 * b).cos(), (0.9 * b).sin()).normalize()
            };
            let ray = Ray::new(p, wi);
            let brute = area
                .iter()
                .enumerate()
                .filter_map(|(k, l)| l.intersect(&ray, 0.0, f64::INFINITY).map(|c| (k, c.t)))
                .min_by(|x, y| x.1.total_cmp(&y.1));
            let got = lights
                .intersect(&ray, 0.0, f64::INFINITY)
                .map(|h| (h.light, h.t));
            assert_eq!(got, brute, "p {p} wi {wi}");
            hits += got.is_some() as usize;
            for (k, l) in area.iter().enumerate() {
                let (c, m) = l.crossings(p, wi);
                for c in c[..m].iter().flatten() {
                    assert!(
                        l.bounds().contains(p + wi * c.t),
                        "light {k}: {c:?} outside its box"
                    );
                }
            }
            let by_area: f64 = area
                .iter()
                .enumerate()
                .map(|(k, l)| lights.by_area.as_ref().unwrap().pmf(k) * l.pdf_area(p, wi))
                .sum();
            let got = lights.pdf_by_area(p, wi);
            assert!(
                (got - by_area).abs() <= 1e-12 * by_area,
                "by area: {got} vs {by_area}"
            );
            for sel in sels {
                let total = if sel == Selection::Spatial {
                    lights.importance_total(p, n)
                } else {
                    0.0
                };
                let want: f64 = (0..lights.count())
                    .map(|k| {
                        let pm = lights.pmf_with(sel, p, n, k, total);
                        if pm > 0.0 {
                            pm * lights.pdf_one(p, k, wi)
                        } else {
                            0.0
                        }
                    })
                    .sum();
                let got = lights.pdf_selected(sel, p, n, wi);
                assert!(
                    (got - want).abs() <= 1e-12 * want,
                    "{sel:?}: {got} vs {want}"
                );
                dense += (want > 0.1) as usize;
            }
        }
    }
    assert!(hits > 2000 && dense > 2000, "{hits} hits, {dense} dense");
}

/// A triangle's solid angle (Van Oosterom & Strackee) is what uniform directions find
/// (4π × the fraction of a 640 × 640 stratified grid of directions that meet it, within
/// 4 binomial standard errors, a bound the stratified grid only tightens), and the
/// light sampling of the test triangle is the spherical one: every draw meets the
/// triangle at density 1/Ω.
#[test]
fn triangle_solid_angle_and_its_sampling() {
    let (_, l) = shapes().into_iter().find(|s| s.0 == "triangle").unwrap();
    let Shape::Triangle { p0, e1, e2 } = l.shape else {
        unreachable!()
    };
    let p = DVec3::new(0.1, 0.05, 0.0);
    let omega = super::area::spherical_triangle_area([p0, p0 + e1, p0 + e2], p).unwrap();
    let side = 640;
    let n = side * side;
    let hits = (0..n)
        .filter(|k| {
            let u = DVec2::new((k % side) as f64 + 0.5, (k / side) as f64 + 0.5) / side as f64;
            l.crossings(p, crate::warp::uniform_sphere(u)).1 > 0
        })
        .count();
    let f = hits as f64 / n as f64;
    let sigma = 4.0 * PI * (f * (1.0 - f) / n as f64).sqrt();
    assert!(
        (4.0 * PI * f - omega).abs() < 4.0 * sigma,
        "{} vs {omega}",
        4.0 * PI * f
    );
    for i in 0..1000 {
        let u = DVec2::new(
            (i as f64 + 0.5) / 1000.0,
            ((i * 613) % 1000) as f64 / 1000.0,
        );
        let s = l.sample_li(p, u).unwrap();
        assert!((s.pdf * omega - 1.0).abs() < 1e-12, "{}", s.pdf);
    }
}
