//! A scene ready to render: camera, objects (FRep solids with materials), lights,
//! environment and render settings.
//!
//! Objects sit in a BVH over their bounds ([`frep::Bvh`]); each object's solid answers
//! its own ray queries through the one intersection contract (DESIGN.md §4). Area
//! lights are analytic shapes kept in [`Lights`], which integrators query beside the
//! objects.
//!
//! Scenes are read and resolved by the [`scene`] crate into one flat
//! [`SceneData`]; [`Scene::from_data`] builds the CPU scene from it, reusing its
//! light-selection and environment distributions. [`load_scene`] / [`parse_scene`] do
//! both; a malformed file is a [`SceneError`] naming the file, line, column and key.
//!
//! ```
//! use render::scene::{parse_scene, SceneFormat, IntegratorKind};
//! use std::path::Path;
//! let text = r#"
//! camera = { eye = [0, -4, 0], target = [0, 0, 0], resolution = [64, 48] }
//! render = { integrator = "direct", estimator = "optimal-direct" }
//! materials.white = { type = "diffuse", reflectance = 0.8 }
//! objects = [{ solid = "sphere([0, 0, 0], 1)", material = "white" }]
//! lights = [{ type = "sphere", center = [0, 0, 3], radius = 0.5, power = 100 }]
//! "#;
//! let (scene, settings) = parse_scene(text, SceneFormat::Toml, Path::new("ball.toml")).unwrap();
//! assert_eq!(settings.integrator, IntegratorKind::Direct);
//! let centre = scene.camera.ray(32, 24, glam::DVec2::ZERO);
//! let hit = scene.intersect(&centre, 0.0, f64::INFINITY).unwrap();
//! assert!((hit.t - 3.0).abs() < 1e-6);
//! // An unknown material is reported where it is named.
//! let bad = text.replace(r#"material = "white""#, r#"material = "black""#);
//! let err = parse_scene(&bad, SceneFormat::Toml, Path::new("ball.toml")).err().unwrap();
//! assert_eq!((err.line, err.column, err.key.as_str()), (5, 57, "objects[0].material"));
//! ```

mod from_data;

pub use ::scene::parse_description;
pub use ::scene::LocalFrame;
pub use ::scene::{
    CameraDesc, CheckerDesc, ColorDesc, Emitters, EnvironmentDesc, IntegratorKind, LightDesc,
    MaterialDesc, ObjectDesc, Overrides, RenderDesc, RenderSettings, RgbDesc, RotateDesc,
    ScaleDesc, SceneData, SceneDescription, SceneError, SceneFormat, TechniqueDesc, TechniqueKind,
    TransformDesc, TransformStep, AOV_NAMES, METALS,
};

use crate::camera::Camera;
use crate::color::Rgb;
use crate::light::Lights;
use crate::material::{Material, RoughnessMap};
use crate::medium::Medium;
use crate::texture::TexCoord;
use frep::triangles::Triangles;
use frep::{Aabb, Bvh, Ray, Solid, Surface};
use glam::{DVec2, DVec3};
use std::path::Path;
use std::sync::Arc;

/// Parses scene text and builds the scene; `path` names the file in errors and anchors
/// relative model and map paths (it is not read).
pub fn parse_scene(
    text: &str,
    format: SceneFormat,
    path: &Path,
) -> Result<(Scene, RenderSettings), SceneError> {
    let (data, settings) = ::scene::parse(text, format, path)?;
    Ok((Scene::from_data(&data), settings))
}

/// Reads a scene file (`.toml` or `.json`) and builds the scene.
pub fn load_scene(path: &Path) -> Result<(Scene, RenderSettings), SceneError> {
    let (data, settings) = ::scene::load(path)?;
    Ok((Scene::from_data(&data), settings))
}

/// One solid or mesh with its material.
pub struct Object {
    /// Name, for messages.
    pub name: String,
    /// What it is made of (transforms already folded in).
    pub geometry: Geometry,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// From world space to the object's own (its transform undone), where it has a
    /// transform: where pattern and image textures are read.
    pub to_local: Option<LocalFrame>,
    /// Index into [`Scene::media`] of what fills it (None: vacuum).
    pub interior: Option<usize>,
    /// Index into [`Scene::media`] of what surrounds it (None: vacuum).
    pub exterior: Option<usize>,
}

impl Object {
    /// The solid, where the object is one.
    pub fn solid(&self) -> Option<&Solid> {
        match &self.geometry {
            Geometry::Solid(s) => Some(s),
            Geometry::Mesh(_) => None,
        }
    }
}

/// An object's geometry: a solid, or a triangle mesh (shared with the resolved scene).
/// A solid stays inline: ray queries read it on every hit test, without a pointer to
/// follow, and a scene holds few objects.
#[allow(clippy::large_enum_variant)]
pub enum Geometry {
    /// A solid (F ≥ 0 inside).
    Solid(Solid),
    /// A triangle mesh.
    Mesh(Arc<Triangles>),
}

impl From<Solid> for Geometry {
    fn from(s: Solid) -> Self {
        Geometry::Solid(s)
    }
}

impl Geometry {
    /// A box holding it.
    pub fn bounds(&self) -> Aabb {
        match self {
            Geometry::Solid(s) => s.bounds(),
            Geometry::Mesh(m) => m.bounds(),
        }
    }
    /// Whether it is known to be convex (never, for a mesh).
    pub fn is_convex(&self) -> bool {
        matches!(self, Geometry::Solid(s) if s.is_convex())
    }
    /// The nearest crossing in (t_min, t_max): t, the outward (front) normal and the
    /// surface parameters.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, DVec3, DVec2)> {
        match self {
            Geometry::Solid(s) => s
                .intersect(ray, t_min, t_max)
                .map(|h| (h.t, h.normal, DVec2::ZERO)),
            Geometry::Mesh(m) => m
                .intersect(ray, t_min, t_max)
                .map(|h| (h.t, h.normal, h.uv)),
        }
    }
    /// Whether its surface lies in (t_min, t_max) along the ray.
    #[inline]
    pub fn occludes(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        match self {
            Geometry::Solid(s) => s.occludes(ray, t_min, t_max),
            Geometry::Mesh(m) => m.occludes(ray, t_min, t_max),
        }
    }
}

impl From<&Scene> for Emitters {
    fn from(s: &Scene) -> Self {
        Emitters {
            area: !s.lights.area().is_empty(),
            environment: s.lights.environment().is_some(),
            lights: s.lights.count(),
        }
    }
}

/// The nearest surface a ray meets.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    /// Ray parameter.
    pub t: f64,
    /// The hit point.
    pub p: DVec3,
    /// Outward unit normal of the solid at p.
    pub n: DVec3,
    /// Index into [`Scene::objects`].
    pub object: usize,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Surface parameters (a mesh's interpolated texture coordinates; 0 on solids).
    pub uv: DVec2,
}

impl SurfaceHit {
    /// Where textures are evaluated (in world space; [`Scene::tex_coord`] adds the
    /// object's own space).
    pub fn tex_coord(&self) -> TexCoord {
        TexCoord {
            p: self.p,
            n: self.n,
            uv: self.uv,
            local: None,
        }
    }
}

/// A scene ready to render (see the module docs).
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// Materials, referred to by index.
    pub materials: Vec<Material>,
    /// The solids.
    pub objects: Vec<Object>,
    /// Area, point/spot and environment lights.
    pub lights: Lights,
    /// Participating media, referred to by index from the objects.
    pub media: Vec<Medium>,
    /// Emitted radiance per material (empty when no material emits): the surfaces of
    /// objects of such a material emit on their outside.
    pub emission: Vec<Rgb>,
    /// Per material, its roughness texture, if any (empty when none has one).
    pub roughness: Vec<Option<RoughnessMap>>,
    /// Whether rays must be walked through media and index-matched boundaries (some
    /// object names a medium or has an `interface` material, or the camera sits in a
    /// medium); else they never are.
    pub participating: bool,
    /// Index into [`Self::media`] of what the camera sits in (None: vacuum).
    pub camera_medium: Option<usize>,
    bvh: Bvh,
    bounds: Aabb,
    /// Per object, whether its solid is convex ([`Solid::is_convex`]).
    convex: Vec<bool>,
}

impl Scene {
    /// Assembles a scene and builds its BVH.
    pub fn new(
        camera: Camera,
        materials: Vec<Material>,
        objects: Vec<Object>,
        lights: Lights,
    ) -> Self {
        let boxes: Vec<Aabb> = objects.iter().map(|o| o.geometry.bounds()).collect();
        let bvh = Bvh::new(&boxes);
        let bounds = boxes
            .iter()
            .filter(|b| b.is_finite())
            .fold(Aabb::EMPTY, |a, b| a.union(b));
        let convex = objects.iter().map(|o| o.geometry.is_convex()).collect();
        let participating = objects.iter().any(|o| {
            o.interior.is_some()
                || o.exterior.is_some()
                || matches!(materials[o.material], Material::Interface)
        });
        Self {
            camera,
            materials,
            objects,
            lights,
            media: Vec::new(),
            emission: Vec::new(),
            roughness: Vec::new(),
            participating,
            camera_medium: None,
            bvh,
            bounds,
            convex,
        }
    }

    /// The scene with `media`, which its objects' `interior` and `exterior` index, and
    /// the camera in `camera_medium`.
    pub fn with_media(mut self, media: Vec<Medium>, camera_medium: Option<usize>) -> Self {
        self.media = media;
        self.camera_medium = camera_medium;
        self.participating |= camera_medium.is_some();
        self
    }

    /// The scene with the materials' emitted radiance (one per material; empty: none
    /// emits). The objects that emit need their proxies among the lights
    /// ([`crate::light::AreaLight::proxy`]) for light techniques to reach them.
    pub fn with_emission(mut self, emission: Vec<Rgb>) -> Self {
        if emission.iter().all(|e| *e == Rgb::ZERO) {
            self.emission = Vec::new();
        } else {
            self.emission = emission;
        }
        self
    }

    /// The scene with roughness textures (one entry per material, or empty).
    pub fn with_roughness(mut self, roughness: Vec<Option<RoughnessMap>>) -> Self {
        self.roughness = roughness;
        self
    }

    /// The BSDF of `hit`'s material there, its roughness textured where it is.
    #[inline(always)]
    pub fn bsdf(&self, hit: &SurfaceHit) -> crate::bsdf::Bsdf<'_> {
        let m = &self.materials[hit.material];
        let tc = self.tex_coord(hit);
        if let Some(Some(map)) = self.roughness.get(hit.material) {
            return m.bsdf_rough(&tc, hit.n, map);
        }
        m.bsdf(&tc, hit.n)
    }

    /// Whether some object's surface emits (then light reaching a point is found by
    /// nearest-hit rays: an object in the way may be the light).
    #[inline]
    pub fn has_emitting_objects(&self) -> bool {
        !self.emission.is_empty()
    }

    /// Radiance leaving `hit` toward the origin of a ray along `d`: its material's
    /// emission on the outside (`d` against the outward normal), else 0.
    #[inline]
    pub fn surface_emission(&self, hit: &SurfaceHit, d: DVec3) -> Rgb {
        match self.emission.get(hit.material) {
            Some(&le) if d.dot(hit.n) < 0.0 => le,
            _ => Rgb::ZERO,
        }
    }

    /// Builds the CPU scene from resolved data: textures looked up, plastic coats
    /// tabulated, one solid built per object, the resolved light distributions reused.
    pub fn from_data(data: &SceneData) -> Self {
        from_data::build(data)
    }

    /// Where textures are evaluated at `hit`, with the point and normal in its
    /// object's own space where the object has a transform.
    pub fn tex_coord(&self, hit: &SurfaceHit) -> TexCoord {
        TexCoord {
            local: self.objects[hit.object]
                .to_local
                .map(|f| f.apply(hit.p, hit.n)),
            ..hit.tex_coord()
        }
    }

    /// The union of the finite object bounds (empty if there is none).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The object a ray from a point of object `object`'s surface (outward normal `n`)
    /// along `wi` cannot meet again: that object, when it is convex and the ray leaves
    /// it outward (`wi · n > 0`; the ray's origin moved off the surface along n, as
    /// secondary rays' are); else None. Queries may skip it
    /// ([`Self::intersect_skipping`], [`Self::occluded_skipping`]): a diffuse floor's
    /// shadow rays no longer test the floor.
    pub fn left_behind(&self, object: usize, n: DVec3, wi: DVec3) -> Option<usize> {
        (self.convex[object] && wi.dot(n) > 0.0).then_some(object)
    }

    /// The nearest object surface in (t_min, t_max).
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<SurfaceHit> {
        self.intersect_skipping(ray, t_min, t_max, None)
    }

    /// [`Self::intersect`] without object `skip` ([`Self::left_behind`]).
    pub fn intersect_skipping(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        skip: Option<usize>,
    ) -> Option<SurfaceHit> {
        let (mut normal, mut uv) = (DVec3::ZERO, DVec2::ZERO);
        let (k, t) = self.bvh.nearest(ray, t_min, t_max, |i, t_max| {
            if Some(i) == skip {
                return None;
            }
            let (t, n, st) = self.objects[i].geometry.intersect(ray, t_min, t_max)?;
            (normal, uv) = (n, st);
            Some(t)
        })?;
        // `normal` belongs to the last accepted hit, which is the nearest: `nearest`
        // only accepts hits below the shrinking t_max.
        Some(SurfaceHit {
            t,
            p: ray.at(t),
            n: normal,
            object: k,
            material: self.objects[k].material,
            uv,
        })
    }

    /// Whether any object surface lies in (t_min, t_max) (shadow rays).
    pub fn occluded(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        self.occluded_skipping(ray, t_min, t_max, None)
    }

    /// [`Self::occluded`] without object `skip` ([`Self::left_behind`]).
    pub fn occluded_skipping(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        skip: Option<usize>,
    ) -> bool {
        self.bvh.any_hit(ray, t_min, t_max, |i| {
            Some(i) != skip && self.objects[i].geometry.occludes(ray, t_min, t_max)
        })
    }
}
