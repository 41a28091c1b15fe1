//! The `lights` list of a scene file: area lights (sphere, rect, disk) and point / spot
//! lights as [`Light`] records, their powers, and the light-selection distributions.

use crate::check::{check_keys, number, unit, vec3};
use crate::data::{EnvMapTable, EnvironmentData, Light, LightData, LightKind};
use crate::desc::{ArrayDesc, ColorDesc, LightDesc};
use crate::distribution::Distribution1D;
use crate::error::{kp, SceneError, Seg};
use crate::locate::Source;
use glam::DVec3;
use std::f64::consts::PI;

/// Relative luminance Y of linear Rec. 709 RGB (ITU-R BT.709 weights).
pub(crate) fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// A sphere holding an area light: (centre, radius).
pub(crate) fn bounding_sphere(l: &Light) -> (DVec3, f64) {
    let (p0, e1, e2) = (
        DVec3::from_array(l.p0),
        DVec3::from_array(l.e1),
        DVec3::from_array(l.e2),
    );
    match l.kind {
        LightKind::Rect => (
            p0 + (e1 + e2) / 2.0,
            (e1 + e2).length().max((e1 - e2).length()) / 2.0,
        ),
        LightKind::Triangle => {
            let c = p0 + (e1 + e2) / 3.0;
            let r = [p0, p0 + e1, p0 + e2]
                .iter()
                .map(|v| v.distance(c))
                .fold(0.0, f64::max);
            (c, r)
        }
        _ => (p0, l.radius),
    }
}

/// The light-selection proxies of the objects whose material emits (`emission` per
/// material, empty when none does): each one's bounding sphere, which light techniques
/// sample by solid angle, with the material's radiance and, for selection, the power
/// π·A·L of the sphere's area A (an estimate: the surface's own area is not known in
/// closed form). An unbounded emitting object is an error at its `material`.
pub(crate) fn emitting_objects(
    src: &Source,
    objects: &[crate::data::ObjectData],
    emission: &[[f64; 3]],
    bounds: impl Fn(&crate::data::ObjectData) -> frep::Aabb,
) -> Result<Vec<Light>, SceneError> {
    let mut out = Vec::new();
    if emission.is_empty() {
        return Ok(out);
    }
    for (i, o) in objects.iter().enumerate() {
        let le = emission[o.material.index()];
        if le == [0.0; 3] {
            continue;
        }
        let b = bounds(o);
        if !b.is_finite() || b.is_empty() {
            return Err(src.at_value(
                &kp!["objects", i, "material"],
                format!(
                    "object '{}' emits but is unbounded: an emitting object must be bounded",
                    o.name
                ),
            ));
        }
        let (c, r) = ((b.lo + b.hi) / 2.0, b.extent().length() / 2.0);
        let area = 4.0 * PI * r * r;
        out.push(Light {
            kind: LightKind::Solid,
            p0: c.to_array(),
            e1: [0.0; 3],
            e2: [0.0; 3],
            radius: r,
            emission: le,
            two_sided: false,
            cos_falloff_start: 0.0,
            cos_falloff_end: 0.0,
            area,
            power: le.map(|x| PI * area * x),
            selection_pmf: 0.0,
        });
    }
    Ok(out)
}

/// A constant, non-negative colour.
pub(crate) fn rgb(src: &Source, at: &[Seg], c: &ColorDesc) -> Result<DVec3, SceneError> {
    match c {
        ColorDesc::Rgb(a) => {
            for &x in a {
                number(src, at, x, 0.0, f64::INFINITY)?;
            }
            Ok(DVec3::from_array(*a))
        }
        ColorDesc::Checker(_) | ColorDesc::Pattern(_) | ColorDesc::Image(_) => {
            Err(src.at_value(at, "a light's colour must be constant"))
        }
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
) -> Result<DVec3, SceneError> {
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
                None => DVec3::ONE,
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

/// Which of a light's optional keys are given.
fn present(l: &LightDesc) -> [(&'static str, bool); 19] {
    [
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
        ("file", l.file.is_some()),
        ("transform", l.transform.is_some()),
    ]
}

fn light(src: &Source, i: usize, l: &LightDesc) -> Result<Light, SceneError> {
    let at = kp!["lights", i];
    let key = |k: &str| [at.clone(), kp![k]].concat();
    let present = present(l);
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
                "unknown light type {kind:?}; valid types: sphere, rect, disk, mesh, point, spot"
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
    let shape: (LightKind, DVec3, DVec3, DVec3, f64) = match kind {
        "sphere" => (
            LightKind::Sphere,
            vec3(
                src,
                &key("center"),
                require(src, &at, kind, "center", l.center)?,
            )?,
            DVec3::ZERO,
            DVec3::ZERO,
            radius(l)?,
        ),
        "disk" => {
            let center = vec3(
                src,
                &key("center"),
                require(src, &at, kind, "center", l.center)?,
            )?;
            let normal = unit(src, &key("normal"), l.normal.unwrap_or(down))?;
            (LightKind::Disk, center, normal, DVec3::ZERO, radius(l)?)
        }
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
                (LightKind::Rect, corner, edge_u, edge_v, 0.0)
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
                (
                    LightKind::Rect,
                    center - (w * u + h * v) / 2.0,
                    w * u,
                    h * v,
                    0.0,
                )
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
                let intensity = emission(src, &at, "intensity", &l.intensity, l, 4.0 * PI)?;
                return Ok(Light::point(position, intensity));
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
            // As pbrt-v4 §12.1.2: full intensity within the falloff start, smoothstep
            // to zero at the cone; power 2π I ((1 − cos_start) + (cos_start − cos_end)/2).
            let cos_falloff_start = start.min(cone).to_radians().cos();
            let cos_falloff_end = cone.to_radians().cos();
            let spread = (1.0 - cos_falloff_start) + (cos_falloff_start - cos_falloff_end) / 2.0;
            let intensity = emission(src, &at, "intensity", &l.intensity, l, (2.0 * PI) * spread)?;
            let axis = (target - position).normalize();
            return Ok(Light {
                cos_falloff_start,
                cos_falloff_end,
                power: (intensity * (2.0 * PI) * spread).to_array(),
                ..delta(LightKind::Spot, position, axis, intensity)
            });
        }
    };
    let (kind, p0, e1, e2, radius) = shape;
    let area = match kind {
        LightKind::Sphere => 4.0 * PI * radius * radius,
        LightKind::Rect => e1.cross(e2).length(),
        _ => PI * radius * radius,
    };
    let two_sided = l.two_sided.unwrap_or(false);
    let sides = if two_sided && kind != LightKind::Sphere {
        2.0
    } else {
        1.0
    };
    // Power Φ = π A L, twice when two-sided (pbrt-v4 §12.2).
    let unit_power = PI * area * sides;
    let radiance = emission(src, &at, "radiance", &l.radiance, l, unit_power)?;
    Ok(Light {
        kind,
        p0: p0.to_array(),
        e1: e1.to_array(),
        e2: e2.to_array(),
        radius,
        emission: radiance.to_array(),
        two_sided,
        cos_falloff_start: 0.0,
        cos_falloff_end: 0.0,
        area,
        power: (radiance * unit_power).to_array(),
        selection_pmf: 0.0,
    })
}

/// A point or spot light with its other fields zero.
fn delta(kind: LightKind, position: DVec3, axis: DVec3, intensity: DVec3) -> Light {
    Light {
        kind,
        p0: position.to_array(),
        e1: axis.to_array(),
        e2: [0.0; 3],
        radius: 0.0,
        emission: intensity.to_array(),
        two_sided: false,
        cos_falloff_start: 0.0,
        cos_falloff_end: 0.0,
        area: 0.0,
        power: [0.0; 3],
        selection_pmf: 0.0,
    }
}

impl Light {
    /// An isotropic point light at `position` of radiant intensity `intensity` (W/sr),
    /// with its power 4π I.
    pub fn point(position: DVec3, intensity: DVec3) -> Light {
        Light {
            power: (4.0 * PI * intensity).to_array(),
            ..delta(LightKind::Point, position, DVec3::ZERO, intensity)
        }
    }
}

impl LightData {
    /// The lights with their selection distributions (as a scene file's), for a scene of
    /// radius `scene_radius` built without a scene file (a model's preview).
    pub fn new(
        area: Vec<Light>,
        delta: Vec<Light>,
        environment: Option<&EnvironmentData>,
        maps: &[EnvMapTable],
        scene_radius: f64,
    ) -> LightData {
        select(area, delta, environment, maps, scene_radius)
    }
}

/// A mesh light's triangles (entry `i`), each an area light of the mesh's radiance
/// (with `power`, the whole mesh's power shared by area), appended to `out`; at most
/// `room` of them. Triangles without area are left out.
fn mesh_lights(
    src: &Source,
    base: &std::path::Path,
    i: usize,
    l: &LightDesc,
    room: usize,
    out: &mut Vec<Light>,
) -> Result<(), SceneError> {
    let at = kp!["lights", i];
    let key = |k: &str| [at.clone(), kp![k]].concat();
    let allowed = [
        "type",
        "file",
        "transform",
        "two_sided",
        "radiance",
        "power",
        "color",
    ];
    check_keys(src, &at, "a mesh light", &present(l), &allowed)?;
    if l.array.is_some() {
        return Err(src.at_key(&key("array"), "a mesh light takes no array"));
    }
    let file = require(src, &at, "mesh", "file", l.file.as_deref())?;
    let m = crate::meshes::read(
        src,
        base,
        &key("file"),
        file,
        &key("transform"),
        l.transform.as_ref(),
    )?;
    let triangles: Vec<(DVec3, DVec3, DVec3, f64)> = (0..m.len())
        .map(|k| {
            let [a, b, c] = m.triangle(k);
            (a, b - a, c - a, 0.5 * (b - a).cross(c - a).length())
        })
        .filter(|t| t.3 > 0.0)
        .collect();
    if triangles.is_empty() {
        return Err(src.at_value(&key("file"), "the mesh has no triangle with an area"));
    }
    if triangles.len() > room {
        return Err(src.at_value(
            &key("file"),
            format!(
                "{} triangles: a scene holds at most {MAX_LIGHTS} lights",
                triangles.len()
            ),
        ));
    }
    let two_sided = l.two_sided.unwrap_or(false);
    let sides = if two_sided { 2.0 } else { 1.0 };
    let total: f64 = triangles.iter().map(|t| t.3).sum();
    let radiance = emission(src, &at, "radiance", &l.radiance, l, PI * total * sides)?;
    out.extend(triangles.into_iter().map(|(p0, e1, e2, area)| Light {
        kind: LightKind::Triangle,
        p0: p0.to_array(),
        e1: e1.to_array(),
        e2: e2.to_array(),
        radius: 0.0,
        emission: radiance.to_array(),
        two_sided,
        cos_falloff_start: 0.0,
        cos_falloff_end: 0.0,
        area,
        power: (radiance * (PI * area * sides)).to_array(),
        selection_pmf: 0.0,
    }));
    Ok(())
}

/// The area lights and the point / spot lights, in file order; mesh files are read
/// relative to `base`.
pub(crate) fn lights(
    src: &Source,
    base: &std::path::Path,
    list: &[LightDesc],
) -> Result<(Vec<Light>, Vec<Light>), SceneError> {
    let (mut area, mut delta) = (Vec::new(), Vec::new());
    for (i, desc) in list.iter().enumerate() {
        let room = MAX_LIGHTS.saturating_sub(area.len() + delta.len());
        if desc.kind == "mesh" {
            mesh_lights(src, base, i, desc, room, &mut area)?;
            continue;
        }
        let l = light(src, i, desc)?;
        let out = if l.kind.has_area() {
            &mut area
        } else {
            &mut delta
        };
        match &desc.array {
            None if room == 0 => {
                return Err(src.at_key(
                    &kp!["lights", i],
                    format!("a scene holds at most {MAX_LIGHTS} lights"),
                ))
            }
            None => out.push(l),
            Some(a) => array(src, i, &l, a, room, out)?,
        }
    }
    Ok((area, delta))
}

/// The most lights a scene may hold (arrays included): past it, memory and the loading
/// time grow without bound.
pub const MAX_LIGHTS: usize = 1_000_000;

/// The copies of light `l` (entry `i`) that `array = {…}` asks for, appended to `out`;
/// at most `room` of them.
fn array(
    src: &Source,
    i: usize,
    l: &Light,
    a: &ArrayDesc,
    room: usize,
    out: &mut Vec<Light>,
) -> Result<(), SceneError> {
    let key = |k: &str| kp!["lights", i, "array", k];
    let mut copies: u64 = 1;
    for &n in &a.count {
        if n == 0 {
            return Err(src.at_value(&key("count"), "every count must be at least 1"));
        }
        copies = copies.saturating_mul(n);
    }
    if copies > room as u64 {
        return Err(src.at_value(
            &key("count"),
            format!("{copies} copies: a scene holds at most {MAX_LIGHTS} lights"),
        ));
    }
    let step = vec3(src, &key("step"), a.step)?;
    let [lo, hi] = a.power_range.unwrap_or([1.0, 1.0]);
    let lo = number(
        src,
        &key("power_range"),
        lo,
        f64::MIN_POSITIVE,
        f64::INFINITY,
    )?;
    let hi = number(src, &key("power_range"), hi, lo, f64::INFINITY)?;
    let seed = a.seed.unwrap_or(0);
    let [nx, ny, nz] = a.count;
    let mut index = 0u64;
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let offset = step * DVec3::new(x as f64, y as f64, z as f64);
                // Log-uniform in [lo, hi]: powers spread over orders of magnitude alike.
                let f = lo * (hi / lo).powf(unit_hash(seed, index));
                let scale = |c: [f64; 3]| c.map(|v| v * f);
                out.push(Light {
                    p0: (DVec3::from_array(l.p0) + offset).to_array(),
                    emission: scale(l.emission),
                    power: scale(l.power),
                    ..l.clone()
                });
                index += 1;
            }
        }
    }
    Ok(())
}

/// A number in [0, 1) from a seed and an index (SplitMix64's finaliser, Steele et al.
/// 2014): the same copies on every machine.
fn unit_hash(seed: u64, index: u64) -> f64 {
    let mut z = seed.wrapping_add(index.wrapping_add(1).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// The environment's power for light selection: π r² ∫ L dω for a scene of radius `r`
/// (pbrt-v4 §12.5).
pub(crate) fn environment_power(e: &EnvironmentData, maps: &[EnvMapTable], r: f64) -> DVec3 {
    let integral = match e {
        EnvironmentData::Constant { radiance } => DVec3::from_array(*radiance) * (4.0 * PI),
        EnvironmentData::Map { map, .. } => DVec3::from_array(maps[map.index()].integral),
    };
    integral * (PI * r * r)
}

/// The lights with their selection distributions: ∝ luminance of power over the area
/// lights then the environment, and ∝ area over the area lights.
pub(crate) fn select(
    mut area: Vec<Light>,
    delta: Vec<Light>,
    env: Option<&EnvironmentData>,
    maps: &[EnvMapTable],
    scene_radius: f64,
) -> LightData {
    let mut power: Vec<f64> = area
        .iter()
        .map(|l| luminance(DVec3::from_array(l.power)))
        .collect();
    if let Some(e) = env {
        power.push(luminance(environment_power(e, maps, scene_radius)));
    }
    let by_power = (!power.is_empty()).then(|| Distribution1D::new(&power));
    if let Some(d) = &by_power {
        for (i, l) in area.iter_mut().enumerate() {
            l.selection_pmf = d.pmf(i);
        }
    }
    let areas: Vec<f64> = area.iter().map(|l| l.area).collect();
    let by_area = (!areas.is_empty()).then(|| Distribution1D::new(&areas));
    LightData {
        area,
        delta,
        by_power,
        by_area,
    }
}
