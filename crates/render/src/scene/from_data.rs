//! The CPU scene from a resolved [`SceneData`]: camera, materials (textures looked up
//! in the pool, plastic coats tabulated), lights with the distributions computed at
//! resolution, and one [`Solid`] built per object.

use super::{Geometry, Object, Scene};
use crate::camera::Camera;
use crate::color::Rgb;
use crate::distribution::Distribution1D;
use crate::light::{AreaLight, DeltaLight, EnvMap, Environment, Lights, Shape};
use crate::material::{Material, RoughnessMap};
use crate::medium::Medium;
use crate::texture::{Texture, TextureSpace};
use ::scene::{EnvironmentData, Light, LightKind, MaterialData, SceneData, TextureData, TextureId};
use glam::{DMat3, DVec3};

fn v3(a: [f64; 3]) -> DVec3 {
    DVec3::from_array(a)
}

fn texture(data: &SceneData, id: TextureId) -> Texture {
    match data.textures[id.index()] {
        TextureData::Constant { rgb } => Texture::Constant(v3(rgb)),
        TextureData::Checker { a, b, scale, space } => Texture::Checker {
            a: v3(a),
            b: v3(b),
            scale,
            space: match space {
                ::scene::TextureSpace::Point => TextureSpace::Point,
                ::scene::TextureSpace::Uv => TextureSpace::Uv,
            },
        },
        TextureData::Image {
            image,
            scale,
            sharpness,
        } => Texture::Image {
            image: data.images.image(image).clone(),
            scale,
            sharpness,
        },
        TextureData::Pattern {
            kind,
            a,
            b,
            scale,
            octaves,
        } => Texture::Pattern {
            pattern: match kind {
                ::scene::PatternKind::Noise => crate::noise::Pattern::Noise,
                ::scene::PatternKind::Fbm => crate::noise::Pattern::Fbm,
                ::scene::PatternKind::Turbulence => crate::noise::Pattern::Turbulence,
                ::scene::PatternKind::Marble => crate::noise::Pattern::Marble,
                ::scene::PatternKind::Wood => crate::noise::Pattern::Wood,
            },
            a: v3(a),
            b: v3(b),
            scale,
            octaves,
        },
    }
}

fn material(data: &SceneData, m: &MaterialData) -> Material {
    match *m {
        MaterialData::Diffuse { reflectance } => Material::Diffuse {
            reflectance: texture(data, reflectance),
        },
        MaterialData::Conductor { eta, k, roughness } => Material::Conductor {
            eta: texture(data, eta),
            k: texture(data, k),
            roughness,
        },
        MaterialData::Dielectric { eta, roughness } => Material::Dielectric { eta, roughness },
        MaterialData::Interface => Material::Interface,
        MaterialData::Plastic {
            diffuse,
            eta,
            roughness,
        } => Material::plastic(texture(data, diffuse), eta, roughness),
    }
}

fn area_light(l: &Light) -> AreaLight {
    AreaLight::from_data(l).unwrap_or_else(|| unreachable!("{:?} is not an area light", l.kind))
}

impl AreaLight {
    /// The area light a resolved scene's light describes (None for point and spot
    /// lights).
    pub fn from_data(l: &Light) -> Option<AreaLight> {
        let shape = match l.kind {
            LightKind::Sphere => Shape::Sphere {
                center: v3(l.p0),
                radius: l.radius,
            },
            LightKind::Rect => Shape::Rect {
                corner: v3(l.p0),
                edge_u: v3(l.e1),
                edge_v: v3(l.e2),
            },
            LightKind::Disk => Shape::Disk {
                center: v3(l.p0),
                normal: v3(l.e1),
                radius: l.radius,
            },
            LightKind::Triangle => Shape::Triangle {
                p0: v3(l.p0),
                e1: v3(l.e1),
                e2: v3(l.e2),
            },
            LightKind::Solid => Shape::Sphere {
                center: v3(l.p0),
                radius: l.radius,
            },
            LightKind::Point | LightKind::Spot => return None,
        };
        Some(AreaLight {
            shape,
            radiance: Rgb::from_array(l.emission),
            two_sided: l.two_sided,
            proxy: l.kind == LightKind::Solid,
        })
    }
}

fn delta_light(l: &Light) -> DeltaLight {
    match l.kind {
        LightKind::Point => DeltaLight::Point {
            position: v3(l.p0),
            intensity: v3(l.emission),
        },
        LightKind::Spot => DeltaLight::Spot {
            position: v3(l.p0),
            direction: v3(l.e1),
            intensity: v3(l.emission),
            cos_falloff_start: l.cos_falloff_start,
            cos_falloff_end: l.cos_falloff_end,
        },
        k => unreachable!("{k:?} is not a point or spot light"),
    }
}

fn environment(data: &SceneData, e: &EnvironmentData) -> Environment {
    match e {
        EnvironmentData::Constant { radiance } => Environment::Constant(v3(*radiance)),
        EnvironmentData::Map { map, to_world } => Environment::Map(EnvMap::from_table(
            &data.maps[map.index()],
            DMat3::from_cols_array_2d(to_world),
        )),
    }
}

/// The CPU scene of `data` (see the module docs).
impl Camera {
    /// The camera of a resolved scene's data.
    pub fn from_data(c: &::scene::CameraData) -> Camera {
        let camera = match (c.kind, c.scale) {
            (::scene::CameraKind::Orthographic, Some(h)) => {
                Camera::orthographic(v3(c.eye), v3(c.target), v3(c.up), h, c.width, c.height)
            }
            _ => Camera::look_at(v3(c.eye), v3(c.target), v3(c.up), c.fov, c.width, c.height),
        };
        match c.lens {
            Some(l) => camera.with_lens(l.radius, l.focus_distance),
            None => camera,
        }
    }
}

pub(super) fn build(data: &SceneData) -> Scene {
    let camera = Camera::from_data(&data.camera);
    let materials: Vec<Material> = data.materials.iter().map(|m| material(data, m)).collect();
    let roughness = data
        .roughness
        .iter()
        .zip(&materials)
        .map(|(t, m)| t.map(|t| RoughnessMap::new(texture(data, t), m)))
        .collect();
    let objects = data
        .objects
        .iter()
        .map(|o| Object {
            name: o.name.clone(),
            geometry: match o.geometry {
                ::scene::Geometry::Solid(s) => Geometry::Solid(data.solids.solid(s).clone()),
                ::scene::Geometry::Mesh(m) => Geometry::Mesh(data.meshes.mesh(m).clone()),
            },
            material: o.material.index(),
            to_local: o.placement.and_then(|p| p.local_frame()),
            interior: o.interior.map(|m| m.index()),
            exterior: o.exterior.map(|m| m.index()),
        })
        .collect();
    let l = &data.lights;
    let lights = Lights::from_parts(
        l.area.iter().map(area_light).collect(),
        l.delta.iter().map(delta_light).collect(),
        data.environment.as_ref().map(|e| environment(data, e)),
        l.by_power.as_ref().map(Distribution1D::from),
        l.by_area.as_ref().map(Distribution1D::from),
    );
    let media = data
        .media
        .iter()
        .map(|m| Medium {
            sigma_t: v3(m.sigma_t),
            albedo: texture(data, m.albedo),
            g: m.g,
        })
        .collect();
    let emission = data.emission.iter().map(|&e| v3(e)).collect();
    Scene::new(camera, materials, objects, lights)
        .with_media(media, data.camera_medium.map(|m| m.index()))
        .with_emission(emission)
        .with_roughness(roughness)
}
