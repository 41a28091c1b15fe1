//! From a [`SceneDescription`] to [`SceneData`]: camera, textures and materials,
//! objects (solids read inline or from model files, transformed) and, via
//! [`crate::lights`] and [`crate::environment`], the lights; then the render settings.

use crate::check::{check_keys, number, transform, vec3};
use crate::data::{
    CameraData, CameraKind, Geometry, Lens, MaterialData, MaterialId, ObjectData, PatternKind,
    Placement, SceneData, TextureData, TextureId, TextureSpace,
};
use crate::desc::{CameraDesc, ColorDesc, MaterialDesc, ObjectDesc, SceneDescription};
use crate::environment::environment;
use crate::error::{kp, path_string, KeyPath, SceneError, Seg};
use crate::images::{read_image, ImagePool};
use crate::lights::{bounding_sphere, lights};
use crate::locate::{position_in_literal, Source};
use crate::media::medium_ref;
use crate::meshes::MeshPool;
use crate::settings::{settings, RenderSettings};
use crate::solids::SolidPool;
use frep::read::{read_file, read_str, Format};
use frep::{Aabb, Shape, Solid};
use std::path::Path;

/// Conductor presets: (name, η, k) per R, G, B channel, RGB fits of measured optical
/// constants (Palik's tables) as commonly used by RGB renderers.
pub const METALS: [(&str, [f64; 3], [f64; 3]); 4] = [
    ("gold", [0.143, 0.374, 1.442], [3.983, 2.385, 1.603]),
    ("copper", [0.200, 0.924, 1.102], [3.912, 2.452, 2.142]),
    ("aluminium", [1.657, 0.880, 0.521], [9.224, 6.270, 4.837]),
    ("silver", [0.155, 0.117, 0.138], [4.828, 3.122, 2.147]),
];

fn camera(src: &Source, c: &CameraDesc) -> Result<CameraData, SceneError> {
    let eye = vec3(src, &kp!["camera", "eye"], c.eye)?;
    let target = vec3(src, &kp!["camera", "target"], c.target)?;
    let up = vec3(src, &kp!["camera", "up"], c.up.unwrap_or([0.0, 0.0, 1.0]))?;
    let fov = number(
        src,
        &kp!["camera", "fov"],
        c.fov.unwrap_or(40.0),
        0.0,
        180.0,
    )?;
    if fov == 0.0 || fov == 180.0 {
        return Err(src.at_value(
            &kp!["camera", "fov"],
            "the field of view must lie strictly between 0 and 180 degrees",
        ));
    }
    let [w, h] = c.resolution.unwrap_or(crate::DEFAULT_RESOLUTION);
    if w == 0 || h == 0 {
        return Err(src.at_value(
            &kp!["camera", "resolution"],
            format!("the image must have pixels, found {w} × {h}"),
        ));
    }
    let forward = target - eye;
    if forward.length() == 0.0 || !forward.length().is_finite() {
        let why = if forward.length() == 0.0 {
            "the target is the eye"
        } else {
            "the target is too far from the eye"
        };
        return Err(src.at_value(&kp!["camera", "target"], why));
    }
    let side = forward.normalize().cross(up.normalize()).length();
    if side.is_nan() || side < 1e-9 {
        return Err(src.at_value(&kp!["camera", "up"], "up is parallel to the view direction"));
    }
    let kind = match c.kind.as_deref() {
        None | Some("perspective") => CameraKind::Perspective,
        Some("orthographic") => CameraKind::Orthographic,
        Some(other) => {
            return Err(src.at_value(
                &kp!["camera", "type"],
                format!("unknown camera type {other:?}; valid types: perspective, orthographic"),
            ))
        }
    };
    let scale = match (kind, c.scale) {
        (CameraKind::Perspective, None) => None,
        (CameraKind::Perspective, Some(_)) => {
            return Err(src.at_value(
                &kp!["camera", "scale"],
                "scale applies to an orthographic camera (type = \"orthographic\")",
            ))
        }
        (CameraKind::Orthographic, Some(v)) => Some(number(
            src,
            &kp!["camera", "scale"],
            v,
            f64::MIN_POSITIVE,
            f64::INFINITY,
        )?),
        (CameraKind::Orthographic, None) => {
            Some(2.0 * forward.length() * (fov.to_radians() / 2.0).tan())
        }
    };
    let lens = match (c.aperture, c.focus_distance) {
        (None | Some(0.0), None) => None,
        (None | Some(0.0), Some(_)) => {
            return Err(src.at_value(
                &kp!["camera", "focus_distance"],
                "focus_distance applies to a thin lens: give aperture (the lens's radius) too",
            ))
        }
        (Some(a), f) => {
            let radius = number(src, &kp!["camera", "aperture"], a, 0.0, f64::INFINITY)?;
            if kind == CameraKind::Orthographic {
                return Err(src.at_value(
                    &kp!["camera", "aperture"],
                    "a thin lens needs a perspective camera",
                ));
            }
            let focus_distance = match f {
                Some(f) => number(
                    src,
                    &kp!["camera", "focus_distance"],
                    f,
                    f64::MIN_POSITIVE,
                    f64::INFINITY,
                )?,
                None => forward.length(),
            };
            Some(Lens {
                radius,
                focus_distance,
            })
        }
    };
    Ok(CameraData {
        kind,
        scale,
        eye: eye.to_array(),
        target: target.to_array(),
        up: up.to_array(),
        fov,
        width: w,
        height: h,
        lens,
    })
}

/// Textures as they are resolved: the pool, the images they read (with their files),
/// and the folder relative image files are found in.
struct Textures<'a> {
    list: Vec<TextureData>,
    images: ImagePool,
    files: Vec<std::path::PathBuf>,
    base: &'a Path,
}

/// Adds a texture to the pool; `max` bounds every channel (1 for reflectances).
fn texture(
    src: &Source,
    at: &[Seg],
    c: &ColorDesc,
    max: f64,
    pool: &mut Textures,
) -> Result<TextureId, SceneError> {
    let t = texture_data(src, at, c, max, pool)?;
    pool.list.push(t);
    Ok(TextureId(pool.list.len() as u32 - 1))
}

/// A texture's `scale` (default 1): a positive number.
fn texture_scale(
    src: &Source,
    at: &[Seg],
    scale: Option<f64>,
    what: &str,
) -> Result<f64, SceneError> {
    let s = number(src, at, scale.unwrap_or(1.0), 0.0, f64::INFINITY)?;
    if s == 0.0 {
        return Err(src.at_value(at, format!("{what}'s scale must be positive")));
    }
    Ok(s)
}

fn texture_data(
    src: &Source,
    at: &[Seg],
    c: &ColorDesc,
    max: f64,
    pool: &mut Textures,
) -> Result<TextureData, SceneError> {
    let rgb = |at: &[Seg], a: &[f64; 3]| -> Result<[f64; 3], SceneError> {
        for &x in a {
            number(src, at, x, 0.0, max)?;
        }
        Ok(*a)
    };
    match c {
        ColorDesc::Rgb(a) => Ok(TextureData::Constant { rgb: rgb(at, a)? }),
        ColorDesc::Checker(k) => {
            let mut p = at.to_vec();
            p.push("checker".into());
            let sub = |key: &str| [p.clone(), kp![key]].concat();
            let scale = texture_scale(src, &sub("scale"), k.scale, "a checker")?;
            let space = match k.space.as_deref() {
                None | Some("point") => TextureSpace::Point,
                Some("uv") => TextureSpace::Uv,
                Some(s) => {
                    return Err(src.at_value(
                        &sub("space"),
                        format!("unknown checker space {s:?}; valid: point, uv"),
                    ))
                }
            };
            Ok(TextureData::Checker {
                a: rgb(&sub("a"), &k.a.0)?,
                b: rgb(&sub("b"), &k.b.0)?,
                scale,
                space,
            })
        }
        ColorDesc::Image(k) => {
            let mut p = at.to_vec();
            p.push("image".into());
            let sub = |key: &str| [p.clone(), kp![key]].concat();
            let scale = texture_scale(src, &sub("scale"), k.scale, "an image")?;
            let sharpness = number(
                src,
                &sub("sharpness"),
                k.sharpness.unwrap_or(4.0),
                1.0,
                64.0,
            )?;
            let full = pool.base.join(&k.file);
            let img = read_image(&full)
                .map_err(|m| src.at_value(&sub("file"), format!("{}: {m}", full.display())))?;
            pool.files.push(full);
            Ok(TextureData::Image {
                image: pool.images.push(img),
                scale,
                sharpness,
            })
        }
        ColorDesc::Pattern(k) => {
            let mut p = at.to_vec();
            p.push("pattern".into());
            let sub = |key: &str| [p.clone(), kp![key]].concat();
            let kind = PatternKind::ALL
                .into_iter()
                .find(|x| x.name() == k.kind)
                .ok_or_else(|| {
                    let names: Vec<&str> = PatternKind::ALL.iter().map(|x| x.name()).collect();
                    src.at_value(
                        &sub("kind"),
                        format!("unknown pattern {:?}; valid: {}", k.kind, names.join(", ")),
                    )
                })?;
            let scale = texture_scale(src, &sub("scale"), k.scale, "a pattern")?;
            let octaves = k.octaves.unwrap_or(5);
            if !(1..=12).contains(&octaves) {
                return Err(src.at_value(&sub("octaves"), "octaves must be 1 to 12"));
            }
            Ok(TextureData::Pattern {
                kind,
                a: rgb(&sub("a"), &k.a.0)?,
                b: rgb(&sub("b"), &k.b.0)?,
                scale,
                octaves,
            })
        }
    }
}

/// A number given as a colour with equal channels (a dielectric's η).
fn scalar(src: &Source, at: &[Seg], c: &ColorDesc, lo: f64) -> Result<f64, SceneError> {
    match c {
        ColorDesc::Rgb([a, b, c]) if a == b && b == c => number(src, at, *a, lo, f64::INFINITY),
        _ => Err(src.at_value(at, "expected a number")),
    }
}

/// A material and, where its roughness is a texture, that texture (α in its first
/// channel; the material's `roughness` is then 0 and unused).
fn material(
    src: &Source,
    name: &String,
    m: &MaterialDesc,
    pool: &mut Textures,
) -> Result<(MaterialData, Option<TextureId>), SceneError> {
    let at = kp!["materials", name];
    let key = |k: &str| [at.clone(), kp![k]].concat();
    let present = [
        ("emission", m.emission.is_some()),
        ("reflectance", m.reflectance.is_some()),
        ("diffuse", m.diffuse.is_some()),
        ("metal", m.metal.is_some()),
        ("eta", m.eta.is_some()),
        ("k", m.k.is_some()),
        ("roughness", m.roughness.is_some()),
    ];
    let allowed: &[&str] = match m.kind.as_str() {
        "diffuse" => &["type", "reflectance", "emission"],
        "conductor" => &["type", "metal", "eta", "k", "roughness", "emission"],
        "dielectric" => &["type", "eta", "roughness", "emission"],
        "plastic" => &["type", "diffuse", "eta", "roughness", "emission"],
        "interface" => &["type"],
        other => {
            return Err(src.at_value(&key("type"), format!("unknown material type {other:?}; valid types: diffuse, conductor, dielectric, plastic, interface")))
        }
    };
    check_keys(
        src,
        &at,
        &format!("a {} material", m.kind),
        &present,
        allowed,
    )?;
    let (roughness, roughness_map) = match &m.roughness {
        None => (0.0, None),
        Some(ColorDesc::Rgb([a, b, c])) if a == b && b == c => {
            (number(src, &key("roughness"), *a, 0.0, 1.0)?, None)
        }
        Some(ColorDesc::Rgb(_)) => {
            return Err(src.at_value(
                &key("roughness"),
                "roughness is one number (or a pattern or checker texture)",
            ))
        }
        Some(ColorDesc::Image(_)) => {
            return Err(src.at_value(
                &key("roughness"),
                "roughness may be a number, a pattern or a checker (not an image)",
            ))
        }
        Some(c) => (0.0, Some(texture(src, &key("roughness"), c, 1.0, pool)?)),
    };
    let grey = ColorDesc::Rgb([0.5; 3]);
    let eta = |default: f64| match &m.eta {
        Some(e) => scalar(src, &key("eta"), e, f64::MIN_POSITIVE),
        None => Ok(default),
    };
    let data = match m.kind.as_str() {
        "interface" => MaterialData::Interface,
        "diffuse" => MaterialData::Diffuse {
            reflectance: texture(
                src,
                &key("reflectance"),
                m.reflectance.as_ref().unwrap_or(&grey),
                1.0,
                pool,
            )?,
        },
        "dielectric" => MaterialData::Dielectric {
            eta: eta(1.5)?,
            roughness,
        },
        "plastic" => MaterialData::Plastic {
            diffuse: texture(
                src,
                &key("diffuse"),
                m.diffuse.as_ref().unwrap_or(&grey),
                1.0,
                pool,
            )?,
            eta: eta(1.5)?,
            roughness,
        },
        _ => {
            let (eta, k) = match (&m.metal, &m.eta, &m.k) {
                (Some(metal), None, None) => {
                    let (_, e, k) =
                        METALS.iter().find(|(n, _, _)| n == metal).ok_or_else(|| {
                            let names: Vec<&str> = METALS.iter().map(|m| m.0).collect();
                            src.at_value(
                                &key("metal"),
                                format!(
                                    "unknown metal {metal:?}; valid names: {}",
                                    names.join(", ")
                                ),
                            )
                        })?;
                    (
                        texture(src, &key("eta"), &ColorDesc::Rgb(*e), f64::INFINITY, pool)?,
                        texture(src, &key("k"), &ColorDesc::Rgb(*k), f64::INFINITY, pool)?,
                    )
                }
                (None, Some(e), Some(k)) => (
                    texture(src, &key("eta"), e, f64::INFINITY, pool)?,
                    texture(src, &key("k"), k, f64::INFINITY, pool)?,
                ),
                (Some(_), _, _) => {
                    let extra = if m.eta.is_some() { "eta" } else { "k" };
                    return Err(src.at_key(&key(extra), "give either metal or eta and k, not both"));
                }
                _ => return Err(src.at_key(&at, "a conductor needs metal, or eta and k")),
            };
            MaterialData::Conductor { eta, k, roughness }
        }
    };
    Ok((data, roughness_map))
}

/// Whether a `.frep` text has an `output` statement (else it is one expression).
fn has_output(text: &str) -> bool {
    text.lines().any(|l| {
        let code = l.split('#').next().unwrap_or("");
        code.match_indices("output").any(|(i, _)| {
            let word = |c: char| c.is_alphanumeric() || c == '_';
            !code[..i].chars().next_back().is_some_and(word)
                && !code[i + 6..].chars().next().is_some_and(word)
        })
    })
}

fn shape(src: &Source, base: &Path, i: usize, o: &ObjectDesc) -> Result<Shape, SceneError> {
    match (&o.solid, &o.model) {
        (Some(text), None) => {
            let at = kp!["objects", i, "solid"];
            let program = has_output(text);
            let full = if program {
                text.clone()
            } else {
                format!("output\n{text}")
            };
            let label = format!("{} ({})", src.file, path_string(&at));
            read_str(&full, Format::Frep, &label)
                .map(|m| m.shape)
                .map_err(|e| {
                    let span = src.locate(&at).value;
                    let line = if program {
                        e.line
                    } else {
                        e.line.saturating_sub(1)
                    };
                    if !src.has_text {
                        let message = match line {
                            0 => format!("in the solid: {}", e.message),
                            _ => format!(
                                "in the solid, line {line}, column {}: {}",
                                e.column, e.message
                            ),
                        };
                        return src.at_value(&at, message);
                    }
                    let off = if line == 0 {
                        span.start
                    } else {
                        span.start + position_in_literal(&src.text[span.clone()], line, e.column)
                    };
                    src.error_at(off, &at, format!("in the solid: {}", e.message))
                })
        }
        (None, Some(file)) => {
            let at = kp!["objects", i, "model"];
            let full = base.join(file);
            read_file(&full).map(|m| m.shape).map_err(|e| {
                if e.line == 0 {
                    src.at_value(&at, format!("{}: {}", full.display(), e.message))
                } else {
                    let here = src.at_value(&at, "");
                    let of = match here.line {
                        0 => here.key.clone(),
                        _ => format!("{}:{}:{}", here.file, here.line, here.column),
                    };
                    SceneError {
                        file: e.file,
                        line: e.line,
                        column: e.column,
                        key: here.key,
                        message: format!("{} (model of {of})", e.message),
                    }
                }
            })
        }
        (Some(_), Some(_)) => Err(src.at_key(
            &kp!["objects", i, "model"],
            "give either solid or model, not both",
        )),
        (None, None) => Err(src.at_value(
            &kp!["objects", i],
            "an object needs solid (inline) or model (a file)",
        )),
    }
}

/// An object's geometry as resolved: a solid, or a triangle mesh.
// One per object, moved once into its pool: the variants' sizes do not matter.
#[allow(clippy::large_enum_variant)]
enum Built {
    Solid(Solid),
    Mesh(frep::triangles::Triangles),
}

/// Whether object `o` names a mesh file (.obj, .ply) as its model.
fn is_mesh(o: &ObjectDesc) -> bool {
    o.model.as_deref().is_some_and(|m| {
        Path::new(m)
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(frep::read::is_mesh_extension)
    })
}

/// Reads object `i`'s mesh file and moves it by the object's transform.
fn mesh(
    src: &Source,
    base: &Path,
    i: usize,
    o: &ObjectDesc,
) -> Result<frep::triangles::Triangles, SceneError> {
    if o.solid.is_some() {
        return Err(src.at_key(
            &kp!["objects", i, "model"],
            "give either solid or model, not both",
        ));
    }
    crate::meshes::read(
        src,
        base,
        &kp!["objects", i, "model"],
        o.model.as_deref().unwrap_or_default(),
        &kp!["objects", i, "transform"],
        o.transform.as_ref(),
    )
}

/// The material index of object `i`, its shape (transform folded in) and its solid's
/// bounds (the solid is built once here to check it), or its mesh.
fn object(
    src: &Source,
    base: &Path,
    i: usize,
    o: &ObjectDesc,
    names: &[&String],
) -> Result<(MaterialId, Built), SceneError> {
    let material = names
        .iter()
        .position(|n| **n == o.material)
        .ok_or_else(|| {
            let defined: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
            let list = if defined.is_empty() {
                "none".to_string()
            } else {
                defined.join(", ")
            };
            src.at_value(
                &kp!["objects", i, "material"],
                format!("unknown material {:?}; defined: {list}", o.material),
            )
        })?;
    let material = MaterialId(material as u32);
    if is_mesh(o) {
        return Ok((material, Built::Mesh(mesh(src, base, i, o)?)));
    }
    let mut shape = shape(src, base, i, o)?;
    let tp: KeyPath = kp!["objects", i, "transform"];
    if let Some(t) = &o.transform {
        shape = Shape::Transformed(transform(src, &tp, t)?, Box::new(shape));
    }
    let solid = Solid::build(&shape).map_err(|e| src.at_value(&tp, e.to_string()))?;
    Ok((material, Built::Solid(solid)))
}

/// Resolves a description; relative files are looked up in `base`.
pub(crate) fn resolve_source(
    src: &Source,
    base: &Path,
    d: &SceneDescription,
) -> Result<(SceneData, RenderSettings), SceneError> {
    let camera = camera(src, &d.camera)?;
    let names: Vec<&String> = d.materials.keys().collect();
    let mut pool = Textures {
        list: Vec::new(),
        images: ImagePool::default(),
        files: Vec::new(),
        base,
    };
    let (materials, mut roughness): (Vec<_>, Vec<_>) = d
        .materials
        .iter()
        .map(|(n, m)| material(src, n, m, &mut pool))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .unzip();
    if roughness.iter().all(Option::is_none) {
        roughness.clear();
    }
    let (media, medium_names) = crate::media::media(src, d, &mut |at, c| {
        let id = texture(src, at, c, 1.0, &mut pool)?;
        Ok((id, pool.list[id.index()].clone()))
    })?;
    let Textures {
        list: textures,
        images,
        files: image_files,
        ..
    } = pool;
    let mut emission = Vec::with_capacity(d.materials.len());
    for (name, m) in &d.materials {
        emission.push(match &m.emission {
            Some(c) => crate::lights::rgb(src, &kp!["materials", name, "emission"], c)?.to_array(),
            None => [0.0; 3],
        });
    }
    if emission.iter().all(|e| *e == [0.0; 3]) {
        emission.clear();
    }
    let mut solids = SolidPool::default();
    let mut meshes = MeshPool::default();
    let mut objects = Vec::with_capacity(d.objects.len());
    for (i, o) in d.objects.iter().enumerate() {
        let (material, built) = object(src, base, i, o, &names)?;
        let placement = match &o.transform {
            Some(t) => {
                let a = transform(src, &kp!["objects", i, "transform"], t)?;
                let r = |k: usize| a.m.row(k).to_array();
                let (r0, r1, r2) = (r(0), r(1), r(2));
                Some(Placement {
                    m: [
                        r0[0], r0[1], r0[2], r1[0], r1[1], r1[2], r2[0], r2[1], r2[2],
                    ],
                    t: a.t.to_array(),
                })
            }
            None => None,
        };
        objects.push(ObjectData {
            name: o.name.clone().unwrap_or_else(|| format!("objects[{i}]")),
            geometry: match built {
                Built::Solid(s) => Geometry::Solid(solids.push(s)),
                Built::Mesh(m) => Geometry::Mesh(meshes.push(m)),
            },
            material,
            placement,
            interior: medium_ref(
                src,
                &kp!["objects", i, "medium"],
                o.medium.as_ref(),
                &medium_names,
            )?,
            exterior: medium_ref(
                src,
                &kp!["objects", i, "exterior"],
                o.exterior.as_ref(),
                &medium_names,
            )?,
        });
    }
    let (mut area, delta) = lights(src, base, &d.lights)?;
    area.extend(crate::lights::emitting_objects(
        src,
        &objects,
        &emission,
        |o| match o.geometry {
            Geometry::Solid(s) => solids.bounds(s),
            Geometry::Mesh(m) => meshes.mesh(m).bounds(),
        },
    )?);
    let mut maps = Vec::new();
    let env = match &d.environment {
        Some(e) => Some(environment(src, base, e, &mut maps)?),
        None => None,
    };
    // The scene's extent sets the environment's share of light selection.
    let mut b = objects
        .iter()
        .map(|o| match o.geometry {
            Geometry::Solid(s) => solids.bounds(s),
            Geometry::Mesh(m) => meshes.mesh(m).bounds(),
        })
        .filter(Aabb::is_finite)
        .fold(Aabb::EMPTY, |a, b| a.union(&b));
    for l in &area {
        let (c, r) = bounding_sphere(l);
        b = b.union(&Aabb::new(c - r, c + r));
    }
    for l in &delta {
        b.include(glam::DVec3::from_array(l.p0));
    }
    let scene_radius = if b.is_empty() {
        1.0
    } else {
        (b.extent().length() / 2.0).max(1e-3)
    };
    let lights = crate::lights::select(area, delta, env.as_ref(), &maps, scene_radius);
    let data = SceneData {
        camera,
        textures,
        images,
        materials,
        material_names: names.into_iter().cloned().collect(),
        roughness,
        emission,
        solids,
        meshes,
        objects,
        camera_medium: medium_ref(
            src,
            &kp!["camera", "medium"],
            d.camera.medium.as_ref(),
            &medium_names,
        )?,
        media,
        medium_names,
        lights,
        environment: env,
        maps,
        scene_radius,
        inputs: d
            .objects
            .iter()
            .filter_map(|o| o.model.as_ref())
            .chain(d.lights.iter().filter_map(|l| l.file.as_ref()))
            .chain(d.environment.as_ref().and_then(|e| e.map.as_ref()))
            .map(|f| base.join(f))
            .chain(image_files)
            .collect(),
    };
    let mut settings = settings(src, &d.render, &data)?;
    crate::settings::film(src, &d.film, &mut settings)?;
    Ok((data, settings))
}
