//! Scenes, analytic references and statistics shared by the integrator tests.

use frep::{PerturbedQuadric, Quadric, Shape, Solid};
use glam::{DVec2, DVec3};
use mis::Method;
use render::camera::Camera;
use render::color::Rgb;
use render::integrator::{IntegratorKind, RenderOptions};
use render::light::{AreaLight, Environment, Lights, Shape as LightShape};
use render::render_loop::{render, RenderStats};
use render::scene::{Object, Scene};
use render::{Image, Material, Technique, Texture};
use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;

pub const Z_BOUND: f64 = 4.5;

pub fn diffuse(r: Rgb) -> Material {
    Material::Diffuse {
        reflectance: Texture::Constant(r),
    }
}

pub fn object(shape: &Shape, material: usize) -> Object {
    Object {
        name: "test".into(),
        geometry: Solid::build(shape).unwrap().into(),
        material,
        to_local: None,
        interior: None,
        exterior: None,
    }
}

/// The half-space z ≤ 0 (its surface is the plane z = 0, normal +z).
pub fn floor() -> Shape {
    Shape::Perturbed(PerturbedQuadric::new(Quadric::plane(DVec3::Z, 0.0)))
}

pub fn ball(c: DVec3, r: f64) -> Shape {
    Shape::Perturbed(PerturbedQuadric::new(Quadric::sphere(c, r)))
}

pub const ALBEDO: Rgb = Rgb::new(0.8, 0.6, 0.4);
pub const SPHERE_C: DVec3 = DVec3::new(0.8, 0.1, 1.5);
pub const SPHERE_R: f64 = 0.3;
pub const SPHERE_L: Rgb = Rgb::new(6.0, 4.0, 2.0);
pub const RECT_CORNER: DVec3 = DVec3::new(-1.2, -0.4, 1.2);
pub const RECT_U: DVec3 = DVec3::new(0.0, 0.8, 0.0);
pub const RECT_V: DVec3 = DVec3::new(0.6, 0.0, 0.0);
pub const RECT_L: Rgb = Rgb::new(1.0, 2.0, 3.0);

/// A camera 1 above the floor looking straight down (the lights are behind it).
pub fn down_camera(n: u32) -> Camera {
    Camera::look_at(DVec3::new(0.0, 0.0, 1.0), DVec3::ZERO, DVec3::Y, 60.0, n, n)
}

/// A diffuse floor under a sphere light and/or a downward rectangle light.
pub fn lit_floor(sphere: bool, rect: bool, n: u32) -> Scene {
    let mut area = Vec::new();
    if sphere {
        let s = LightShape::Sphere {
            center: SPHERE_C,
            radius: SPHERE_R,
        };
        area.push(AreaLight::new(s, SPHERE_L));
    }
    if rect {
        let s = LightShape::Rect {
            corner: RECT_CORNER,
            edge_u: RECT_U,
            edge_v: RECT_V,
        };
        area.push(AreaLight::new(s, RECT_L));
    }
    Scene::new(
        down_camera(n),
        vec![diffuse(ALBEDO)],
        vec![object(&floor(), 0)],
        Lights::new(area, vec![], None, 3.0),
    )
}

/// Irradiance at x on the floor (normal +z) from a uniform sphere wholly above the
/// horizon: E = π L (r/d)² cos θ (the sphere acts as a point of intensity π r² L).
pub fn sphere_irradiance(x: DVec3) -> f64 {
    let v = SPHERE_C - x;
    let d2 = v.length_squared();
    PI * SPHERE_R * SPHERE_R / d2 * (v.z / d2.sqrt())
}

/// Irradiance at x (normal +z) from a polygon of unit radiance wholly above the horizon:
/// Lambert's formula E = ½ Σ_i Θ_i (n · (v_i × v_{i+1})/|v_i × v_{i+1}|), Θ_i the angle
/// between the unit vectors to consecutive vertices.
pub fn polygon_irradiance(x: DVec3, vertices: &[DVec3]) -> f64 {
    let m = vertices.len();
    let mut e = 0.0;
    for i in 0..m {
        let a = (vertices[i] - x).normalize();
        let b = (vertices[(i + 1) % m] - x).normalize();
        let c = a.cross(b);
        e += a.dot(b).clamp(-1.0, 1.0).acos() * c.z / c.length();
    }
    0.5 * e.abs()
}

pub fn rect_irradiance(x: DVec3) -> f64 {
    let v = [
        RECT_CORNER,
        RECT_CORNER + RECT_U,
        RECT_CORNER + RECT_U + RECT_V,
        RECT_CORNER + RECT_V,
    ];
    polygon_irradiance(x, &v)
}

/// Radiance of the floor at x: ρ/π · Σ L_light E_light.
pub fn floor_radiance(x: DVec3, sphere: bool, rect: bool) -> Rgb {
    let mut e = Rgb::ZERO;
    if sphere {
        e += SPHERE_L * sphere_irradiance(x);
    }
    if rect {
        e += RECT_L * rect_irradiance(x);
    }
    ALBEDO / PI * e
}

/// The pixel's exact value: the floor radiance averaged over the pixel (box filter),
/// by a 12 × 12 midpoint rule of the smooth analytic radiance.
pub fn reference(cam: &Camera, x: u32, y: u32, sphere: bool, rect: bool) -> Rgb {
    let k = 12;
    let mut sum = Rgb::ZERO;
    for j in 0..k {
        for i in 0..k {
            let off = DVec2::new((i as f64 + 0.5) / k as f64, (j as f64 + 0.5) / k as f64);
            let r = cam.ray(x, y, off);
            let t = -r.o.z / r.d.z;
            sum += floor_radiance(r.at(t), sphere, rect);
        }
    }
    sum / (k * k) as f64
}

/// Renders `0..spp` and resolves the image.
pub fn run(scene: &Scene, o: &RenderOptions) -> (Image, RenderStats) {
    let (state, stats) = render(scene, o, &AtomicBool::new(false), &|_, _| {}).unwrap();
    (state.image(), stats)
}

/// Mean and standard error of a list of independent values.
pub fn mean_se(d: &[f64]) -> (f64, f64) {
    let n = d.len() as f64;
    let m = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// Per channel: the mean over pixels of (film − reference) is within Z_BOUND standard
/// errors of 0; returns the largest |z| and the largest relative standard error.
pub fn check_against(film: &Image, refs: &dyn Fn(u32, u32) -> Rgb, what: &str) -> (f64, f64) {
    let (mut zmax, mut rel) = (0.0f64, 0.0f64);
    for c in 0..3 {
        let mut d = Vec::new();
        let mut level = 0.0;
        for y in 0..film.height() {
            for x in 0..film.width() {
                let r = refs(x, y)[c];
                d.push(film.rgb(x, y)[c] - r);
                level += r;
            }
        }
        let (m, se) = mean_se(&d);
        let z = m / se;
        level /= d.len() as f64;
        assert!(
            z.abs() < Z_BOUND,
            "{what}, channel {c}: mean difference {m:e} is {z:.2} standard errors ({se:e})"
        );
        zmax = zmax.max(z.abs());
        rel = rel.max(se / level);
    }
    (zmax, rel)
}

pub fn options(
    integrator: IntegratorKind,
    method: Method,
    techniques: &[(Technique, u32)],
    spp: u32,
    seed: u64,
) -> RenderOptions {
    RenderOptions {
        integrator,
        method,
        techniques: techniques.to_vec(),
        spp,
        seed,
        ..RenderOptions::default()
    }
}

pub const MIX: [(Technique, u32); 3] = [
    (Technique::Bsdf, 1),
    (Technique::LightPower, 1),
    (Technique::LightArea, 1),
];

/// Two white balls, overlapping: a concave solid (paths bounce in the crease).
pub fn furnace(n: u32, dome: f64) -> Scene {
    let shape = Shape::Union(vec![
        ball(DVec3::new(-0.35, 0.0, 0.0), 0.5),
        ball(DVec3::new(0.35, 0.0, 0.0), 0.5),
        ball(DVec3::new(0.0, 0.3, 0.45), 0.4),
    ]);
    let cam = Camera::look_at(
        DVec3::new(0.0, -3.0, 0.6),
        DVec3::new(0.0, 0.0, 0.1),
        DVec3::Z,
        32.0,
        n,
        n,
    );
    Scene::new(
        cam,
        vec![diffuse(Rgb::ONE)],
        vec![object(&shape, 0)],
        Lights::new(
            vec![],
            vec![],
            Some(Environment::Constant(Rgb::splat(dome))),
            2.0,
        ),
    )
}

pub const ENV_MIX: [(Technique, u32); 2] = [(Technique::Bsdf, 1), (Technique::Environment, 1)];

/// A scene with indirect light: a ball on the floor under both lights.
pub fn ball_on_floor(n: u32) -> Scene {
    let mut s = lit_floor(true, true, n);
    let materials = vec![diffuse(ALBEDO), diffuse(Rgb::new(0.3, 0.7, 0.5))];
    let objects = vec![
        object(&floor(), 0),
        object(&ball(DVec3::new(0.1, 0.0, 0.2), 0.2), 1),
    ];
    let lights = std::mem::replace(&mut s.lights, Lights::new(vec![], vec![], None, 1.0));
    let cam = Camera::look_at(
        DVec3::new(0.0, -1.2, 0.9),
        DVec3::new(0.0, 0.0, 0.1),
        DVec3::Z,
        50.0,
        n,
        n,
    );
    Scene::new(cam, materials, objects, lights)
}

/// `path` at `max_depth` with each of `methods` over [`MIX`] (256 spp) agrees with BSDF
/// sampling alone (4096 spp, the balance heuristic over one technique), per channel
/// within [`Z_BOUND`] standard errors of the difference, each image's relative
/// standard error below 5 % (power).
pub fn estimators_agree_with_bsdf_sampling(scene: &Scene, max_depth: u32, methods: &[Method]) {
    let mut o = options(
        IntegratorKind::Path,
        Method::Balance,
        &[(Technique::Bsdf, 1)],
        4096,
        5,
    );
    o.max_depth = max_depth;
    let (reference, _) = run(scene, &o);
    for &m in methods {
        let mut o = options(IntegratorKind::Path, m, &MIX, 256, 11);
        o.max_depth = max_depth;
        let (film, _) = run(scene, &o);
        let (z, rel) = check_against(&film, &|x, y| reference.rgb(x, y), &format!("{m}"));
        println!("{m}: |z| ≤ {z:.2}, relative se {rel:.1e}");
        assert!(rel < 0.05, "{m}: no power ({rel})");
    }
}
