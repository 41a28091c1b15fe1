//! First pictures of a bare model: a camera that frames the model's bounds, a default
//! material and lighting around it, rendered by the normal render loop.
//!
//! This is the picture `frepray render MODEL` makes for a model file with no scene
//! around it: a warm diffuse material under a key point light (with shadows) from the
//! camera's upper left and a dim sky dome, drawn by the `direct` integrator with the
//! BSDF and environment techniques (balance heuristic); or the first hit's depth or
//! normal (the `depth` and `normals` integrators, with the same channel as an AOV).
//!
//! The camera frames what is visible: the solid's box when the solid is bounded, else
//! the box of its surface ([`view_box`]); it looks from one of the [`View`]s, through a
//! perspective or an orthographic lens ([`PreviewOptions`]).

use crate::Error;
use frep::bounds::surface_bounds;
pub use frep::bounds::DEFAULT_DOMAIN;
use frep::shape::Shape;
use frep::{Aabb, Expr, Solid, Surface};
use glam::DVec3;
use render::integrator::{Aov, IntegratorKind, RenderOptions};
use render::{RenderState, RenderStats, Technique};
use scene::{
    CameraData, CameraKind, EnvironmentData, Geometry, Light, LightData, MaterialData, MaterialId,
    ObjectData, RenderSettings, SceneData, SolidPool, TextureData, TextureId,
};
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

/// The side a model is seen from. With z up the front is −y (the camera of `front`
/// stands at −y looking along +y, x to the right); with x or y up the front is +z (the
/// camera stands at +z looking along −z). `top` looks down the up axis with the front
/// at the bottom of the image: for z-up models that is along −z with x right and y up,
/// the view Fidget gives its 2-D models (in the xy plane); so is `front` with `--up y`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum View {
    /// From the front-left-above diagonal (the default).
    #[default]
    Iso,
    /// From the front (z up: along +y).
    Front,
    /// From the back (z up: along −y).
    Back,
    /// From the left (z up: along +x).
    Left,
    /// From the right (z up: along −x).
    Right,
    /// From above, down the up axis (z up: along −z, x right, y up).
    Top,
    /// From below, up the up axis (z up: along +z, x right, −y up).
    Bottom,
}

impl View {
    /// The direction from the model to the camera and the image's up direction, for a
    /// model whose vertical axis is `up`.
    pub fn directions(self, up: DVec3) -> (DVec3, DVec3) {
        let front = if up.z.abs() > 0.5 {
            -DVec3::Y
        } else {
            DVec3::Z
        };
        // The image's right seen from the front.
        let right = (-front).cross(up).normalize();
        match self {
            View::Iso => ((0.55 * -right + front + 0.6 * up).normalize(), up),
            View::Front => (front, up),
            View::Back => (-front, up),
            View::Right => (right, up),
            View::Left => (-right, up),
            View::Top => (up, -front),
            View::Bottom => (-up, front),
        }
    }
}

/// How a bare model is pictured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreviewOptions {
    /// The model's vertical axis.
    pub up: Up,
    /// The side it is seen from.
    pub view: View,
    /// Parallel rays (the box fills the image the same at any distance) instead of a
    /// 30° perspective.
    pub orthographic: bool,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// What each pixel shows.
    pub look: Look,
    /// Samples per pixel.
    pub spp: u32,
}

impl Default for PreviewOptions {
    /// z up, iso view, perspective, 512 × 512, shaded, 4 samples per pixel (what
    /// `frepray render MODEL` does without options).
    fn default() -> Self {
        PreviewOptions {
            up: Up::Z,
            view: View::Iso,
            orthographic: false,
            width: 512,
            height: 512,
            look: Look::Shaded,
            spp: 4,
        }
    }
}

/// A camera that frames the box `b` seen from `view` (with `up` the model's vertical
/// axis). Perspective: 30° vertical field of view, far enough that the box's bounding
/// sphere fits the narrower field of view. Orthographic: the box's outline fills the
/// image (with a 5 % margin), the eye outside the box's bounding sphere.
pub fn camera(
    b: &Aabb,
    up: DVec3,
    view: View,
    orthographic: bool,
    width: u32,
    height: u32,
) -> CameraData {
    if view == View::Iso && !orthographic {
        return framing(b, up, width, height);
    }
    let fov = 30.0f64;
    let c = b.center();
    let r = (0.5 * b.extent().length()).max(1e-9);
    let aspect = width as f64 / height as f64;
    let (dir, vup) = view.directions(up);
    if orthographic {
        // The box's outline across and up the image.
        let right = (-dir).cross(vup).normalize();
        let screen_up = right.cross(-dir);
        let (mut w, mut h) = (0.0f64, 0.0f64);
        for k in 0..8 {
            let m = glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0);
            let p = DVec3::select(m, b.hi, b.lo) - c;
            w = w.max(2.0 * p.dot(right).abs());
            h = h.max(2.0 * p.dot(screen_up).abs());
        }
        let view_height = (1.05 * h.max(w / aspect)).max(1e-9);
        return CameraData {
            kind: CameraKind::Orthographic,
            scale: Some(view_height),
            ..look_at(c + dir * 2.0 * r, c, vup, fov, width, height)
        };
    }
    let half = (fov.to_radians() * 0.5).tan();
    let half_min = if aspect < 1.0 { half * aspect } else { half };
    let dist = r / half_min.atan().sin();
    look_at(c + dir * dist, c, vup, fov, width, height)
}

/// A perspective camera at `eye` looking at `target`.
fn look_at(eye: DVec3, target: DVec3, up: DVec3, fov: f64, width: u32, height: u32) -> CameraData {
    CameraData {
        kind: CameraKind::Perspective,
        scale: None,
        eye: eye.to_array(),
        target: target.to_array(),
        up: up.to_array(),
        fov,
        width,
        height,
        lens: None,
    }
}

/// A camera that frames a box: from the front-right-above diagonal (with `up` the
/// vertical axis), far enough that the box's bounding sphere fits the narrower field of
/// view.
pub fn framing(b: &Aabb, up: DVec3, width: u32, height: u32) -> CameraData {
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
    look_at(c + offset * dist, c, up, fov, width, height)
}

/// The base colour of the preview material (a warm grey).
const BASE: [f64; 3] = [0.85, 0.78, 0.62];

/// The preview scene of a solid seen by `cam`, framing the box `b`, as resolved data:
/// the solid in a diffuse material, a key point light above the camera's left shoulder at
/// twice the camera's distance from the box, and a dim constant sky; `up` is the image's
/// up direction (the model's vertical axis, except from the top and bottom). Rendered,
/// dumped or sent to the GPU as a scene file's data is.
pub fn scene_data(solid: Solid, cam: CameraData, b: &Aabb, up: DVec3) -> SceneData {
    let (c, r) = (b.center(), (0.5 * b.extent().length()).max(1e-9));
    let to_eye = DVec3::from_array(cam.eye) - c;
    let left = up.cross(to_eye).normalize_or_zero();
    let key = c + 2.0 * to_eye + to_eye.length() * (0.8 * up + 0.6 * left);
    // Irradiance at the model ≈ I/d²: aim for about 2.5 (a bright but unclipped white).
    let d2 = (key - c).length_squared();
    let sky = EnvironmentData::Constant {
        radiance: [0.25; 3],
    };
    let lights = LightData::new(
        vec![],
        vec![Light::point(key, DVec3::splat(2.5 * d2))],
        Some(&sky),
        &[],
        r,
    );
    let mut solids = SolidPool::default();
    let solid = solids.push(solid);
    SceneData {
        camera: cam,
        textures: vec![TextureData::Constant { rgb: BASE }],
        images: Default::default(),
        materials: vec![MaterialData::Diffuse {
            reflectance: TextureId(0),
        }],
        material_names: vec!["preview".into()],
        emission: vec![],
        roughness: vec![],
        solids,
        meshes: Default::default(),
        objects: vec![ObjectData {
            name: "model".into(),
            geometry: Geometry::Solid(solid),
            material: MaterialId(0),
            placement: None,
            interior: None,
            exterior: None,
        }],
        media: vec![],
        medium_names: vec![],
        camera_medium: None,
        lights,
        environment: Some(sky),
        maps: vec![],
        scene_radius: r,
        inputs: vec![],
    }
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

/// [`options`] as a scene file's settings would give them.
pub fn settings(look: Look, spp: u32, seed: u64) -> RenderSettings {
    let o = options(look, spp, seed);
    RenderSettings {
        integrator: o.integrator,
        spp,
        seed,
        method: o.method,
        params: o.params,
        techniques: o.techniques.iter().map(|&(t, n)| (t.kind(), n)).collect(),
        max_depth: o.max_depth,
        rr_depth: o.rr_depth,
        aovs: o.aovs.iter().map(|a| a.name().to_string()).collect(),
        ..RenderSettings::default()
    }
}

/// Renders the preview of `solid` at `width` × `height` with `spp` samples per pixel,
/// from the iso view in perspective, framing the solid's box ([`view_bounds`]; see
/// [`render_model`] for the surface's box, other views and the orthographic lens).
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
    let model = Model {
        view_box: ViewBox {
            bounds: view_bounds(&solid),
            clipped: [false; 3],
        },
        solid,
        planar: false,
    };
    let o = PreviewOptions {
        up,
        width,
        height,
        look,
        spp,
        ..PreviewOptions::default()
    };
    render_model(model, &o, stop, progress)
}

/// The preview of a model with `o` as a scene: the camera of `o.view` (perspective or
/// orthographic) framing the model's [`ViewBox`], the scene of [`scene_data`] and the
/// settings of `o.look` ([`settings`]). It renders on either back end, and dumps, as a
/// scene file's scene does; its states carry no scene hash ([`crate::Scene::unhashed`]).
pub fn model_scene(model: Model, o: &PreviewOptions) -> Result<crate::Scene, Error> {
    if o.width == 0 || o.height == 0 || o.spp == 0 {
        return Err(Error::Invalid(
            "width, height and spp must be at least 1".into(),
        ));
    }
    let b = model.view_box.bounds;
    let up = o.up.vector();
    let cam = camera(&b, up, o.view, o.orthographic, o.width, o.height);
    let data = scene_data(model.solid, cam, &b, o.view.directions(up).1);
    Ok(crate::Scene::unhashed(data, settings(o.look, o.spp, 0)))
}

/// Renders the preview of a model with `o` ([`model_scene`]) on the CPU, through the
/// normal render loop (so the same picture at any thread count, and `stop` ends it
/// early with what it has).
pub fn render_model(
    model: Model,
    o: &PreviewOptions,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(RenderState, RenderStats), Error> {
    let scene = model_scene(model, o)?;
    scene.render_with(&options(o.look, o.spp, 0), 0..o.spp, stop, progress)
}

/// A bare model ready to picture: its solid and the box a view frames.
#[derive(Clone, Debug)]
pub struct Model {
    /// The solid.
    pub solid: Solid,
    /// What the camera frames ([`view_box`]).
    pub view_box: ViewBox,
    /// A 2-D model: F does not depend on z (Fidget's 2-D `.vm` files, drawn in the xy
    /// plane); shown from the top with parallel rays unless a view is asked for.
    pub planar: bool,
}

/// Whether F does not read z: a 2-D model (as Fidget's prospero), which the preview
/// shows from the top and `check` names as such.
pub fn is_planar(expr: &Expr) -> bool {
    !expr.nodes().contains(&frep::Node::Var(frep::Var::Z))
}

impl Model {
    /// The model of a shape: its solid and view box. Errors as [`Solid::build`].
    ///
    /// A 2-D model (F independent of z, as Fidget's 2-D `.vm` files, drawn in the xy
    /// plane) is an infinite prism: clipped to its box it has no caps, so that a view
    /// along z would see nothing. It is shown as a slab |z| ≤ h, the intersection with
    /// a plane pair 2h = 1/20 of its larger x or y extent thick, whose faces are real
    /// surfaces.
    pub fn new(shape: &Shape) -> Result<Model, frep::BuildError> {
        let solid = Solid::build(shape)?;
        let b = solid.bounds();
        let planar = shape.to_tree().is_ok_and(|t| is_planar(&Expr::new(&t)));
        if planar && !b.is_empty() && b.lo.x.is_finite() && b.hi.y.is_finite() {
            let e = b.extent();
            let h = (0.025 * e.x.max(e.y)).max(1e-6);
            let mut c = [0.0; 10];
            (c[2], c[9]) = (-1.0, h * h);
            let slab = Shape::Perturbed(frep::PerturbedQuadric::new(frep::Quadric::new(c)));
            let shape = Shape::Intersection(vec![shape.clone(), slab]);
            let solid = Solid::build(&shape)?;
            let mut view_box = view_box(&solid, &shape);
            // The plane pair's own box is unbounded: the slab's is known.
            let pad = 1e-3 * e.x.max(e.y);
            (view_box.bounds.lo.z, view_box.bounds.hi.z) = (-h - pad, h + pad);
            return Ok(Model {
                solid,
                view_box,
                planar,
            });
        }
        let view_box = view_box(&solid, shape);
        // A solid whose box is the whole search domain (intervals proved nothing) but
        // whose surface is bounded and F < 0 at the domain's corners is bounded by its
        // surface: rebuilt inside that box (with a margin), rays no longer search the
        // whole domain (nested R-unions took minutes a picture).
        let whole = solid.bounds().extent().min_element() >= 2.0 * DEFAULT_DOMAIN * (1.0 - 1e-9);
        if whole && view_box.clipped == [false; 3] {
            let corners_outside = (0..8).all(|k| {
                let m = glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0);
                let p = DVec3::select(
                    m,
                    DVec3::splat(DEFAULT_DOMAIN),
                    DVec3::splat(-DEFAULT_DOMAIN),
                );
                solid.value(p) < 0.0
            });
            if let (true, Ok(tree)) = (corners_outside, shape.to_tree()) {
                let b = view_box.bounds;
                let pad = 0.05 * b.extent();
                let bounded = Shape::Function {
                    tree,
                    domain: Some(Aabb::new(b.lo - pad, b.hi + pad)),
                };
                let solid = Solid::build(&bounded)?;
                return Ok(Model {
                    solid,
                    view_box,
                    planar,
                });
            }
        }
        Ok(Model {
            solid,
            view_box,
            planar,
        })
    }
}

/// The box a view of a model frames, and the axes along which its surface was clipped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewBox {
    /// The box (with a little padding, and some extent along every axis).
    pub bounds: Aabb,
    /// Axes (x, y, z) along which the surface reaches the ±[`DEFAULT_DOMAIN`] search
    /// domain (an unbounded surface, such as a half-space's plane): the box spans only
    /// ± the extent of the bounded axes (at least 1) around the origin along them.
    pub clipped: [bool; 3],
}

/// The box that frames what is visible of a solid built from `shape`. A solid bounded
/// inside the ±[`DEFAULT_DOMAIN`] search domain: its box ([`view_bounds`]). Otherwise
/// (a half-space; a complement; nested R-functions whose intervals never prove a cell
/// empty, so that the solid's box is the whole domain) the box of its surface, the zero
/// set of F ([`frep::bounds::surface_bounds`]); where that reaches the domain's faces
/// the surface is unbounded there and is searched again with those axes clipped to
/// ±s around the origin, s the largest coordinate of the bounded axes (at least 1).
pub fn view_box(solid: &Solid, shape: &Shape) -> ViewBox {
    let b = solid.bounds();
    let reaches = |b: &Aabb| {
        let d = DEFAULT_DOMAIN * (1.0 - 1e-9);
        [0, 1, 2].map(|k| b.lo[k] <= -d || b.hi[k] >= d)
    };
    let fallback = ViewBox {
        bounds: view_bounds(solid),
        clipped: [false; 3],
    };
    if b.is_empty() || (b.is_finite() && reaches(&b) == [false; 3]) {
        return fallback;
    }
    let Ok(tree) = shape.to_tree() else {
        return fallback;
    };
    let expr = Expr::new(&tree);
    let domain = Aabb::new(DVec3::splat(-DEFAULT_DOMAIN), DVec3::splat(DEFAULT_DOMAIN));
    let mut s = surface_bounds(&expr, domain.intersection(&b));
    if s.is_empty() {
        return fallback;
    }
    let clipped = reaches(&s);
    if clipped != [false; 3] {
        let scale = (0..3)
            .filter(|&k| !clipped[k])
            .map(|k| s.lo[k].abs().max(s.hi[k].abs()))
            .fold(1.0f64, f64::max);
        let mut clip = s;
        for k in (0..3).filter(|&k| clipped[k]) {
            (clip.lo[k], clip.hi[k]) = (-scale, scale);
        }
        let again = surface_bounds(&expr, clip);
        s = if again.is_empty() { clip } else { again };
    }
    ViewBox {
        bounds: padded(&s),
        clipped,
    }
}

/// Reads a model file (.frep, .hf, .vm) and builds its solid.
pub fn load_model(path: &std::path::Path) -> Result<Solid, Error> {
    Ok(load(path)?.solid)
}

/// Reads a model file (.frep, .hf, .vm): its solid and view box ([`Model::new`]).
pub fn load(path: &std::path::Path) -> Result<Model, Error> {
    let model = frep::read::read_file(path)?;
    Model::new(&model.shape).map_err(|source| Error::Model {
        path: path.into(),
        source: Box::new(source),
    })
}

/// The solid's box with a little padding, always with some extent (a point or flat
/// model still gets a view); ±1 for an empty or unbounded solid.
pub fn view_bounds(solid: &Solid) -> Aabb {
    let b = solid.bounds();
    if b.is_empty() || !b.is_finite() {
        return Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
    }
    padded(&b)
}

fn padded(b: &Aabb) -> Aabb {
    let pad = (b.extent().max_element() * 1e-3).max(1e-6);
    Aabb::new(b.lo - pad, b.hi + pad)
}

#[cfg(test)]
mod tests {
    use super::*;
    use frep::read::{read_str, Format};
    use glam::DVec2;

    /// The camera the renderer makes of `c`.
    fn cpu(c: CameraData) -> render::Camera {
        render::Camera::from_data(&c)
    }

    const R_UNION: &str = "m(x[3], a[1]) {
            b1 = 0.36 - (x[1] - 1)^2 - x[2]^2 - x[3]^2;
            b2 = 0.36 - x[1]^2 - x[2]^2 - x[3]^2;
            b3 = 0.36 - (x[1] + 1)^2 - x[2]^2 - x[3]^2;
            b4 = 0.36 - x[1]^2 - (x[2] - 1)^2 - x[3]^2;
            b5 = 0.36 - x[1]^2 - (x[2] + 1)^2 - x[3]^2;
            b6 = 0.36 - x[1]^2 - x[2]^2 - (x[3] - 1)^2;
            m = ((((b1 | b2) | b3) | b4) | b5) | b6;
        }";

    fn hf(text: &str) -> Model {
        Model::new(&read_str(text, Format::HyperFun, "test.hf").unwrap().shape).unwrap()
    }

    /// Six balls joined by HyperFun's R-union `|` (f1 + f2 + √(f1² + f2²)), nested, and
    /// the same with `alpha = 0.5`, where intervals prove no cell of the search domain
    /// empty, so the solid's box is ±100 (a dot in the picture): the view frames the
    /// surface.
    #[test]
    fn r_function_csg_is_framed_by_its_surface() {
        let solid = |text: &str| {
            Solid::build(&read_str(text, Format::HyperFun, "t.hf").unwrap().shape).unwrap()
        };
        // Narrowed by the α = 0 R-functions' monotonicity (frep's `Scalar::r_bound`),
        // intervals bound this union tightly themselves.
        assert!(view_bounds(&solid(R_UNION)).extent().max_element() < 3.6);
        // With α = 0.5 (not narrowed; the same zero set) intervals prove no cell of the
        // domain empty: the solid's box is the domain, and framing needs the surface.
        let r_union = R_UNION.replace("m = (", "alpha = 0.5;\n            m = (");
        assert!(view_bounds(&solid(&r_union)).extent().min_element() > 100.0);
        let m = hf(&r_union);
        // The model is rebuilt inside its surface's box (plus 5 %).
        assert!(
            m.solid.bounds().extent().max_element() < 3.6,
            "{:?}",
            m.solid.bounds()
        );
        let b = m.view_box.bounds;
        let want = Aabb::new(DVec3::new(-1.6, -1.6, -0.6), DVec3::new(1.6, 1.6, 1.6));
        assert!(
            (b.lo - want.lo).abs().max_element() < 0.15
                && (b.hi - want.hi).abs().max_element() < 0.15,
            "{b:?}"
        );
        assert_eq!(m.view_box.clipped, [false; 3]);
        // A bounded solid keeps its own box.
        let ball = hf("b(x[3], a[1]) { b = 1 - x[1]^2 - x[2]^2 - x[3]^2; }");
        assert_eq!(ball.view_box.bounds, view_bounds(&ball.solid));
    }

    /// A half-space's plane is unbounded: the view clips it to ±1 around the origin and
    /// the camera stands a few units away (not 660).
    #[test]
    fn a_half_space_is_clipped_around_the_origin() {
        let m = hf("h(x[3], a[1]) { h = 0.5 - x[3]; }");
        assert_eq!(m.view_box.clipped, [true, true, false]);
        let b = m.view_box.bounds;
        assert!(
            (b.lo.x + 1.0).abs() < 0.01 && (b.hi.y - 1.0).abs() < 0.01,
            "{b:?}"
        );
        assert!(
            (b.center().z - 0.5).abs() < 0.05 && b.extent().z < 0.1,
            "{b:?}"
        );
        let cam = cpu(camera(&b, DVec3::Z, View::Iso, false, 64, 64));
        let d = (cam.eye - b.center()).length();
        assert!(d > 2.0 && d < 10.0, "{d}");
    }

    /// A 2-D model (no z) is a slab with real faces: seen from the top, orthographic
    /// rays hit its cap.
    #[test]
    fn a_2d_model_is_a_slab_seen_from_the_top() {
        let shape = read_str(
            "_0 var-x\n_1 var-y\n_2 square _0\n_3 square _1\n_4 add _2 _3\n_5 const 0.25\n_6 sub _4 _5\n",
            Format::Vm,
            "disc.vm",
        )
        .unwrap()
        .shape;
        let m = Model::new(&shape).unwrap();
        assert!(m.planar);
        let b = m.view_box.bounds;
        assert!(b.extent().z < 0.06 && b.extent().x > 0.99, "{b:?}");
        let cam = cpu(camera(&b, DVec3::Z, View::Top, true, 16, 16));
        let hit = m
            .solid
            .intersect(&cam.ray(8, 8, DVec2::ZERO), 0.0, f64::INFINITY);
        let n = hit.expect("the cap").normal;
        assert!((n - DVec3::Z).length() < 1e-9, "{n:?}");
    }

    /// Each view looks along its documented axis; top (z up) shows x right and y up,
    /// as Fidget shows 2-D models; the orthographic lens sends parallel rays and fits
    /// the box's outline.
    #[test]
    fn views_look_along_their_axes() {
        let b = Aabb::new(DVec3::new(-2.0, -1.0, -0.5), DVec3::new(2.0, 1.0, 0.5));
        let along = [
            (View::Front, DVec3::Y),
            (View::Back, -DVec3::Y),
            (View::Left, DVec3::X),
            (View::Right, -DVec3::X),
            (View::Top, -DVec3::Z),
            (View::Bottom, DVec3::Z),
        ];
        for (view, d) in along {
            for ortho in [false, true] {
                let cam = cpu(camera(&b, DVec3::Z, view, ortho, 40, 20));
                assert!((cam.forward() - d).length() < 1e-12, "{view:?}");
            }
        }
        let top = cpu(camera(&b, DVec3::Z, View::Top, true, 40, 20));
        let (tl, br) = (top.ray(0, 0, DVec2::ZERO).o, top.ray(39, 19, DVec2::ONE).o);
        assert!(tl.x < 0.0 && tl.y > 0.0 && br.x > 0.0 && br.y < 0.0);
        // The 4 × 2 outline in a 2:1 image: 5 % margin on both axes.
        assert!((br.x - tl.x - 4.2).abs() < 1e-9 && (tl.y - br.y - 2.1).abs() < 1e-9);
        assert!(top.eye.z > b.hi.z);
        let d = top.ray(5, 7, DVec2::new(0.5, 0.5)).d;
        assert_eq!(d, top.forward());
        // y up: front looks along −z with x right and y up, as Fidget's 2-D view.
        let front = cpu(camera(&b, DVec3::Y, View::Front, true, 40, 20));
        assert!((front.forward() + DVec3::Z).length() < 1e-12);
        let tl = front.ray(0, 0, DVec2::ZERO).o;
        assert!(tl.x < 0.0 && tl.y > 0.0);
    }
}
