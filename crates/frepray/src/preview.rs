//! First pictures of a bare model: a camera that frames the model's bounds, a default
//! material and lighting around it, rendered by the normal render loop.
//!
//! This is the picture `frepray render MODEL` makes for a model file with no scene
//! around it: a warm diffuse material under a key point light (with shadows) from the
//! camera's upper left and a dim sky dome, drawn by the `direct` integrator with the
//! BSDF and environment techniques (balance heuristic); or the first hit's depth or
//! normal (the `depth` and `normals` integrators, with the same channel as an AOV).

use crate::Error;
use frep::{Aabb, Solid, Surface};
use glam::DVec3;
use render::integrator::{Aov, IntegratorKind, RenderOptions};
use render::light::{DeltaLight, Environment, Lights};
use render::scene::{Object, Scene};
use render::{Camera, Material, Rgb, Technique, Texture};
use render::{RenderState, RenderStats};
use std::sync::atomic::AtomicBool;

/// The vertical axis of a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Up {
    /// x up.
    X,
    /// y up.
    Y,
    /// z up (the default; Fidget's colonnade.vm is modelled z-up too).
    Z,
}

impl Up {
    /// The axis as a vector.
    pub fn vector(self) -> DVec3 {
        match self {
            Up::X => DVec3::X,
            Up::Y => DVec3::Y,
            Up::Z => DVec3::Z,
        }
    }
}

/// What each pixel shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Look {
    /// Diffuse shading under a key light and a sky dome.
    Shaded,
    /// Distance along the camera ray (as R, G, B and EXR channel `depth`; 0 where the
    /// ray misses).
    Depth,
    /// Outward unit normal (as R, G, B and EXR channels `normal.X`, `normal.Y`,
    /// `normal.Z`; 0 where the ray misses).
    Normals,
}

/// A camera that frames a box: from the front-right-above diagonal (with `up` the
/// vertical axis), far enough that the box's bounding sphere fits the narrower field of
/// view.
pub fn framing(b: &Aabb, up: DVec3, width: u32, height: u32) -> Camera {
    let fov = 30.0f64;
    let c = b.center();
    let r = (0.5 * b.extent().length()).max(1e-9);
    let aspect = width as f64 / height as f64;
    let half = (fov.to_radians() * 0.5).tan();
    let half_min = if aspect < 1.0 { half * aspect } else { half };
    let dist = r / half_min.atan().sin();
    // Right, front and up in a right-handed frame around `up`.
    let front = if up.z.abs() > 0.5 {
        -DVec3::Y
    } else {
        DVec3::Z
    };
    let right = front.cross(up).normalize();
    let offset = (0.55 * right + front + 0.6 * up).normalize();
    Camera::look_at(c + offset * dist, c, up, fov, width, height)
}

/// The base colour of the preview material (a warm grey).
const BASE: Rgb = Rgb::new(0.85, 0.78, 0.62);

/// The preview scene of a solid seen by `cam`: the solid in a diffuse material, a key
/// point light above the camera's left shoulder at twice the camera's distance, and a
/// dim constant sky; `up` is the model's vertical axis.
pub fn scene(solid: Solid, cam: Camera, up: DVec3) -> Scene {
    let b = view_bounds(&solid);
    let (c, r) = (b.center(), (0.5 * b.extent().length()).max(1e-9));
    let to_eye = cam.eye - c;
    let left = up.cross(to_eye).normalize_or_zero();
    let key = c + 2.0 * to_eye + to_eye.length() * (0.8 * up + 0.6 * left);
    // Irradiance at the model ≈ I/d²: aim for about 2.5 (a bright but unclipped white).
    let d2 = (key - c).length_squared();
    let lights = Lights::new(
        vec![],
        vec![DeltaLight::Point {
            position: key,
            intensity: Rgb::splat(2.5 * d2),
        }],
        Some(Environment::Constant(Rgb::splat(0.25))),
        r,
    );
    let material = Material::Diffuse {
        reflectance: Texture::Constant(BASE),
    };
    Scene::new(
        cam,
        vec![material],
        vec![Object {
            name: "model".into(),
            solid,
            material: 0,
        }],
        lights,
    )
}

/// The render options of a look: `direct` with BSDF and environment draws under the
/// balance heuristic, or the `depth` / `normals` integrator with its channel as an AOV.
pub fn options(look: Look, spp: u32, seed: u64) -> RenderOptions {
    let base = RenderOptions {
        spp,
        seed,
        ..RenderOptions::default()
    };
    match look {
        Look::Shaded => RenderOptions {
            integrator: IntegratorKind::Direct,
            techniques: vec![(Technique::Bsdf, 1), (Technique::Environment, 1)],
            ..base
        },
        Look::Depth => RenderOptions {
            integrator: IntegratorKind::Depth,
            techniques: vec![],
            aovs: vec![Aov::Depth],
            ..base
        },
        Look::Normals => RenderOptions {
            integrator: IntegratorKind::Normals,
            techniques: vec![],
            aovs: vec![Aov::Normal],
            ..base
        },
    }
}

/// Renders the preview of `solid` at `width` × `height` with `spp` samples per pixel:
/// framing, scene and options as above, through the normal render loop (so the same
/// seed gives the same picture at any thread count, and `stop` ends it early with what
/// it has).
#[allow(clippy::too_many_arguments)]
pub fn render(
    solid: Solid,
    up: Up,
    width: u32,
    height: u32,
    look: Look,
    spp: u32,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(RenderState, RenderStats), Error> {
    let cam = framing(&view_bounds(&solid), up.vector(), width, height);
    let scene = scene(solid, cam, up.vector());
    let o = options(look, spp, 0);
    Ok(render::render(&scene, &o, stop, progress)?)
}

/// Reads a model file (.frep, .hf, .vm) and builds its solid.
pub fn load_model(path: &std::path::Path) -> Result<Solid, Error> {
    let model = frep::read::read_file(path).map_err(|e| Error::Model {
        path: path.into(),
        message: e.to_string(),
    })?;
    Solid::build(&model.shape).map_err(|message| Error::Model {
        path: path.into(),
        message,
    })
}

/// A box that always has some extent (a point or flat model still gets a view).
pub fn view_bounds(solid: &Solid) -> Aabb {
    let b = solid.bounds();
    if b.is_empty() || !b.is_finite() {
        return Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
    }
    let pad = (b.extent().max_element() * 1e-3).max(1e-6);
    Aabb::new(b.lo - pad, b.hi + pad)
}
