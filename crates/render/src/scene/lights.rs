//! The `lights` list and the `environment` table of a scene file.

use super::build::{check_keys, number, rotation, vec3};
use super::desc::{ColorDesc, EnvironmentDesc, LightDesc};
use super::error::{kp, SceneError, Seg};
use super::locate::Source;
use crate::color::{luminance, Rgb};
use crate::light::{AreaLight, DeltaLight, EnvMap, Environment, Shape};
use glam::{DMat3, DVec3};
use std::path::Path;

/// A sphere holding a light's shape: (centre, radius).
pub(crate) fn bounding_sphere(s: &Shape) -> (DVec3, f64) {
    match *s {
        Shape::Sphere { center, radius } | Shape::Disk { center, radius, .. } => (center, radius),
        Shape::Rect {
            corner,
            edge_u,
            edge_v,
        } => (
            corner + (edge_u + edge_v) / 2.0,
            (edge_u + edge_v).length().max((edge_u - edge_v).length()) / 2.0,
        ),
    }
}

/// A constant, non-negative colour.
fn rgb(src: &Source, at: &[Seg], c: &ColorDesc) -> Result<Rgb, SceneError> {
    match c {
        ColorDesc::Rgb(a) => {
            for &x in a {
                number(src, at, x, 0.0, f64::INFINITY)?;
            }
            Ok(Rgb::from_array(*a))
        }
        ColorDesc::Checker(_) => Err(src.at_value(at, "a light's colour must be constant")),
    }
}

/// The emission from `direct` (radiance or intensity, key `name`) or from
/// `power` × `color`, where `unit_power` is the power of unit emission.
fn emission(
    src: &Source,
    at: &[Seg],
    name: &str,
    direct: &Option<ColorDesc>,
    l: &LightDesc,
    unit_power: f64,
) -> Result<Rgb, SceneError> {
    let key = |k: &str| [at.to_vec(), kp![k]].concat();
    let e = match (direct, l.power) {
        (Some(c), None) => {
            if l.color.is_some() {
                return Err(src.at_key(
                    &key("color"),
                    format!("color scales power; give it with power, not {name}"),
                ));
            }
            rgb(src, &key(name), c)?
        }
        (None, Some(p)) => {
            let p = number(src, &key("power"), p, 0.0, f64::INFINITY)?;
            let c = match &l.color {
                Some(c) => rgb(src, &key("color"), c)?,
                None => Rgb::ONE,
            };
            c * (p / unit_power)
        }
        (Some(_), Some(_)) => {
            return Err(src.at_key(
                &key("power"),
                format!("give either {name} or power, not both"),
            ))
        }
        (None, None) => return Err(src.at_key(at, format!("a light needs {name} or power"))),
    };
    if luminance(e) <= 0.0 {
        return Err(src.at_key(
            &key(if l.power.is_some() { "power" } else { name }),
            "the light emits nothing",
        ));
    }
    Ok(e)
}

fn require<T: Copy>(
    src: &Source,
    at: &[Seg],
    kind: &str,
    key: &str,
    v: Option<T>,
) -> Result<T, SceneError> {
    v.ok_or_else(|| src.at_key(at, format!("a {kind} light needs {key}")))
}

fn unit(src: &Source, at: &[Seg], v: [f64; 3]) -> Result<DVec3, SceneError> {
    let d = vec3(src, at, v)?;
    if d.length() == 0.0 {
        return Err(src.at_value(at, "expected a non-zero direction"));
    }
    Ok(d.normalize())
}

fn light(
    src: &Source,
    i: usize,
    l: &LightDesc,
) -> Result<Result<AreaLight, DeltaLight>, SceneError> {
    let at = kp!["lights", i];
    let key = |k: &str| [at.clone(), kp![k]].concat();
    let present = [
        ("center", l.center.is_some()),
        ("radius", l.radius.is_some()),
        ("normal", l.normal.is_some()),
        ("size", l.size.is_some()),
        ("corner", l.corner.is_some()),
        ("edge_u", l.edge_u.is_some()),
        ("edge_v", l.edge_v.is_some()),
        ("radiance", l.radiance.is_some()),
        ("intensity", l.intensity.is_some()),
        ("power", l.power.is_some()),
        ("color", l.color.is_some()),
        ("two_sided", l.two_sided.is_some()),
        ("position", l.position.is_some()),
        ("direction", l.direction.is_some()),
        ("target", l.target.is_some()),
        ("cone", l.cone.is_some()),
        ("falloff_start", l.falloff_start.is_some()),
    ];
    let kind = l.kind.as_str();
    let emit = ["type", "radiance", "power", "color"];
    let allowed: Vec<&str> = match kind {
        "sphere" => [&["center", "radius"][..], &emit].concat(),
        "rect" | "rectangle" => [
            &[
                "center",
                "size",
                "normal",
                "corner",
                "edge_u",
                "edge_v",
                "two_sided",
            ][..],
            &emit,
        ]
        .concat(),
        "disk" => [&["center", "radius", "normal", "two_sided"][..], &emit].concat(),
        "point" => vec!["type", "position", "intensity", "power", "color"],
        "spot" => vec![
            "type",
            "position",
            "direction",
            "target",
            "cone",
            "falloff_start",
            "intensity",
            "power",
            "color",
        ],
        _ => {
            return Err(src.at_value(
                &key("type"),
                format!(
                    "unknown light type {kind:?}; valid types: sphere, rect, disk, point, spot"
                ),
            ))
        }
    };
    check_keys(src, &at, &format!("a {kind} light"), &present, &allowed)?;
    let radius = |l: &LightDesc| -> Result<f64, SceneError> {
        let r = number(
            src,
            &key("radius"),
            require(src, &at, kind, "radius", l.radius)?,
            0.0,
            f64::INFINITY,
        )?;
        if r == 0.0 {
            return Err(src.at_value(&key("radius"), "the radius must be positive"));
        }
        Ok(r)
    };
    let down = [0.0, 0.0, -1.0];
    let shape = match kind {
        "sphere" => Shape::Sphere {
            center: vec3(
                src,
                &key("center"),
                require(src, &at, kind, "center", l.center)?,
            )?,
            radius: radius(l)?,
        },
        "disk" => Shape::Disk {
            center: vec3(
                src,
                &key("center"),
                require(src, &at, kind, "center", l.center)?,
            )?,
            normal: unit(src, &key("normal"), l.normal.unwrap_or(down))?,
            radius: radius(l)?,
        },
        "rect" | "rectangle" => match (l.corner, l.center) {
            (Some(c), None) => {
                if l.size.is_some() || l.normal.is_some() {
                    let k = if l.size.is_some() { "size" } else { "normal" };
                    return Err(src.at_key(
                        &key(k),
                        "a rect by corner takes edge_u and edge_v, not size or normal",
                    ));
                }
                let corner = vec3(src, &key("corner"), c)?;
                let edge_u = vec3(
                    src,
                    &key("edge_u"),
                    require(src, &at, kind, "edge_u", l.edge_u)?,
                )?;
                let edge_v = vec3(
                    src,
                    &key("edge_v"),
                    require(src, &at, kind, "edge_v", l.edge_v)?,
                )?;
                if edge_u.cross(edge_v).length() == 0.0 {
                    return Err(src.at_value(
                        &key("edge_v"),
                        "the edges are parallel: the rect has no area",
                    ));
                }
                Shape::Rect {
                    corner,
                    edge_u,
                    edge_v,
                }
            }
            (None, Some(c)) => {
                if l.edge_u.is_some() || l.edge_v.is_some() {
                    let k = if l.edge_u.is_some() {
                        "edge_u"
                    } else {
                        "edge_v"
                    };
                    return Err(
                        src.at_key(&key(k), "a rect by center takes size and normal, not edges")
                    );
                }
                let center = vec3(src, &key("center"), c)?;
                let [w, h] = require(src, &at, kind, "size", l.size)?;
                let w = number(src, &key("size"), w, f64::MIN_POSITIVE, f64::INFINITY)?;
                let h = number(src, &key("size"), h, f64::MIN_POSITIVE, f64::INFINITY)?;
                let n = unit(src, &key("normal"), l.normal.unwrap_or(down))?;
                // Edges u, v with u × v = n: u ⟂ n, v = n × u.
                let helper = if n.z.abs() < 0.9 { DVec3::Z } else { DVec3::X };
                let u = helper.cross(n).normalize();
                let v = n.cross(u);
                Shape::Rect {
                    corner: center - (w * u + h * v) / 2.0,
                    edge_u: w * u,
                    edge_v: h * v,
                }
            }
            (Some(_), Some(_)) => {
                return Err(src.at_key(&key("corner"), "give either center or corner, not both"))
            }
            (None, None) => {
                return Err(src.at_key(
                    &at,
                    "a rect light needs center (with size) or corner (with edge_u, edge_v)",
                ))
            }
        },
        _ => {
            let position = vec3(
                src,
                &key("position"),
                require(src, &at, kind, "position", l.position)?,
            )?;
            if kind == "point" {
                let probe = DeltaLight::Point {
                    position,
                    intensity: Rgb::ONE,
                };
                let intensity = emission(src, &at, "intensity", &l.intensity, l, probe.power().x)?;
                return Ok(Err(DeltaLight::Point {
                    position,
                    intensity,
                }));
            }
            let target = match (l.direction, l.target) {
                (Some(d), None) => position + unit(src, &key("direction"), d)?,
                (None, Some(t)) => {
                    let t = vec3(src, &key("target"), t)?;
                    if t == position {
                        return Err(
                            src.at_value(&key("target"), "the target is the light's position")
                        );
                    }
                    t
                }
                (Some(_), Some(_)) => {
                    return Err(
                        src.at_key(&key("target"), "give either direction or target, not both")
                    )
                }
                (None, None) => {
                    return Err(src.at_key(&at, "a spot light needs direction or target"))
                }
            };
            let cone = number(
                src,
                &key("cone"),
                require(src, &at, kind, "cone", l.cone)?,
                0.0,
                180.0,
            )?;
            if cone == 0.0 {
                return Err(src.at_value(&key("cone"), "the cone angle must be positive"));
            }
            let start = number(
                src,
                &key("falloff_start"),
                l.falloff_start.unwrap_or(cone),
                0.0,
                cone,
            )?;
            let probe = DeltaLight::spot(position, target, Rgb::ONE, cone, start);
            let intensity = emission(src, &at, "intensity", &l.intensity, l, probe.power().x)?;
            return Ok(Err(DeltaLight::spot(
                position, target, intensity, cone, start,
            )));
        }
    };
    let mut probe = AreaLight::new(shape, Rgb::ONE);
    probe.two_sided = l.two_sided.unwrap_or(false);
    let radiance = emission(src, &at, "radiance", &l.radiance, l, probe.power().x)?;
    Ok(Ok(AreaLight { radiance, ..probe }))
}

/// The area lights and the point / spot lights, in file order.
pub(crate) fn lights(
    src: &Source,
    list: &[LightDesc],
) -> Result<(Vec<AreaLight>, Vec<DeltaLight>), SceneError> {
    let (mut area, mut delta) = (Vec::new(), Vec::new());
    for (i, l) in list.iter().enumerate() {
        match light(src, i, l)? {
            Ok(a) => area.push(a),
            Err(d) => delta.push(d),
        }
    }
    Ok((area, delta))
}

/// Reads the R, G, B channels of a lat-long EXR map, times `scale`.
fn read_map(file: &Path, scale: f64, to_world: DMat3) -> Result<EnvMap, String> {
    let image = exr::prelude::read_first_flat_layer_from_file(file).map_err(|e| e.to_string())?;
    let layer = &image.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let channel = |name: &str| -> Result<Vec<f32>, String> {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.eq_case_insensitive(name))
            .map(|c| c.sample_data.values_as_f32().collect())
            .ok_or_else(|| format!("the image has no channel {name}"))
    };
    let (r, g, b) = (channel("R")?, channel("G")?, channel("B")?);
    if w == 0 || h == 0 {
        return Err("the image is empty".into());
    }
    let mut pixels = Vec::with_capacity(w * h);
    for i in 0..w * h {
        let p = Rgb::new(r[i] as f64, g[i] as f64, b[i] as f64) * scale;
        if !(p.is_finite() && p.min_element() >= 0.0) {
            return Err(format!(
                "pixel ({}, {}) is negative or not finite",
                i % w,
                i / w
            ));
        }
        pixels.push(p);
    }
    Ok(EnvMap::new(w, h, pixels, to_world))
}

/// The environment: a constant dome or a map read beside the scene file (`base`).
pub(crate) fn environment(
    src: &Source,
    base: &Path,
    e: &EnvironmentDesc,
) -> Result<Environment, SceneError> {
    let at = kp!["environment"];
    let key = |k: &str| kp!["environment", k];
    match (&e.radiance, &e.map) {
        (Some(c), None) => {
            let present = [("scale", e.scale.is_some()), ("rotate", e.rotate.is_some())];
            check_keys(src, &at, "a constant environment", &present, &["radiance"])?;
            Ok(Environment::Constant(rgb(src, &key("radiance"), c)?))
        }
        (None, Some(file)) => {
            let scale = number(
                src,
                &key("scale"),
                e.scale.unwrap_or(1.0),
                0.0,
                f64::INFINITY,
            )?;
            let mut to_world = DMat3::IDENTITY;
            if let Some(r) = &e.rotate {
                to_world = rotation(src, &key("rotate"), r)?.m;
            }
            let full = base.join(file);
            let map = read_map(&full, scale, to_world)
                .map_err(|m| src.at_value(&key("map"), format!("{}: {m}", full.display())))?;
            Ok(Environment::Map(map))
        }
        (Some(_), Some(_)) => Err(src.at_key(&key("map"), "give either radiance or map, not both")),
        (None, None) => Err(src.at_key(&at, "an environment needs radiance or map")),
    }
}
