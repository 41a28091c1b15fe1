//! The scene file schema: serde structs shared by the TOML and JSON forms
//! (docs/scene-format.md). Every struct rejects unknown keys; per-type checks (which
//! keys a material or light of a given `type` takes) happen when the scene is built.

use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;

/// A whole scene file.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneDescription {
    /// The camera.
    pub camera: CameraDesc,
    /// Integrator, samples and estimator.
    #[serde(default)]
    pub render: RenderDesc,
    /// Materials by name.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialDesc>,
    /// Participating media by name, which objects fill (`medium`) or sit in (`exterior`).
    #[serde(default)]
    pub media: BTreeMap<String, MediumDesc>,
    /// The solids.
    #[serde(default)]
    pub objects: Vec<ObjectDesc>,
    /// Area, point and spot lights.
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    /// Light from infinitely far away.
    pub environment: Option<EnvironmentDesc>,
    /// How the image is shown (PNG exposure and tone mapping).
    #[serde(default)]
    pub film: FilmDesc,
}

/// How a PNG shows the image; EXR files stay linear.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FilmDesc {
    /// Stops: PNG values are radiance × 2^exposure (default 0).
    pub exposure: Option<f64>,
    /// "clamp" (default), "reinhard" or "aces".
    pub tonemap: Option<String>,
}

/// A look-at camera, perspective or orthographic.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// "perspective" (default) or "orthographic".
    #[serde(rename = "type")]
    pub kind: Option<String>,
    /// Orthographic: the image's full height in scene units (default: what the field
    /// of view spans at the target's distance).
    pub scale: Option<f64>,
    /// Position of the pinhole.
    pub eye: [f64; 3],
    /// A point the camera looks at.
    pub target: [f64; 3],
    /// The image's up direction (default +z).
    pub up: Option<[f64; 3]>,
    /// Full vertical field of view in degrees (default 40).
    pub fov: Option<f64>,
    /// Width and height in pixels (default 320 × 240).
    pub resolution: Option<[u32; 2]>,
    /// Thin lens: the lens's radius in scene units (default 0, a pinhole).
    pub aperture: Option<f64>,
    /// Thin lens: the distance along the view direction that is in focus (default the
    /// target's distance).
    pub focus_distance: Option<f64>,
    /// A key of `media`: what the camera sits in (default: vacuum).
    pub medium: Option<String>,
}

/// Render settings; every key is optional.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    /// "direct", "path", "depth", "normals" or "albedo" (default "path").
    pub integrator: Option<String>,
    /// Samples (camera rays) per pixel (default 16).
    pub spp: Option<u32>,
    /// MIS estimator name, as `mis::Method` parses it (default "balance").
    pub estimator: Option<String>,
    /// Power-heuristic exponent.
    pub beta: Option<f64>,
    /// Cutoff-heuristic threshold.
    pub cutoff: Option<f64>,
    /// Ridge of the optimal solve.
    pub ridge: Option<f64>,
    /// Warm-up iterations of the progressive estimator.
    pub warmup: Option<u64>,
    /// Training iterations of the full-weights estimator.
    pub train: Option<u64>,
    /// Sampling techniques and their sample counts.
    pub techniques: Option<Vec<TechniqueDesc>>,
    /// Seed of the random streams (default 0).
    pub seed: Option<u64>,
    /// Longest path, in bounces (default 5).
    pub max_depth: Option<u32>,
    /// Only paths of at least this many bounces reach the image (default 0: all; with
    /// `min_depth = max_depth` one depth alone).
    pub min_depth: Option<u32>,
    /// Depth at which Russian roulette starts (default 3).
    pub rr_depth: Option<u32>,
    /// Whether emitters (area lights, the environment) seen directly by the camera are
    /// left out of the image, as Mitsuba's `hide_emitters` (default false).
    pub hide_emitters: Option<bool>,
    /// Extra output channels (AOVs) by name.
    pub aovs: Option<Vec<String>>,
    /// One MIS estimator per light instead of one for all (default false).
    pub per_light: Option<bool>,
    /// Cells per axis of `light-trained`'s grid (default 8).
    pub trained_grid: Option<u32>,
    /// The uniform share of `light-trained`'s pmfs, in (0, 1] (default 0.1).
    pub trained_floor: Option<f64>,
    /// Training rays per pixel of `light-trained` (default 4).
    pub trained_spp: Option<u32>,
}

/// One sampling technique with its number of samples per camera sample.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TechniqueDesc {
    /// "bsdf", "light", "light-area", "environment" or "cosine".
    pub technique: String,
    /// n_i (default 1).
    pub samples: Option<u32>,
}

/// A material; `type` says which other keys apply.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// "diffuse", "conductor", "dielectric", "plastic" or "interface".
    #[serde(rename = "type")]
    pub kind: String,
    /// Diffuse reflectance.
    pub reflectance: Option<ColorDesc>,
    /// Plastic base colour.
    pub diffuse: Option<ColorDesc>,
    /// Conductor preset ("gold", "copper", "aluminium", "silver").
    pub metal: Option<String>,
    /// Index of refraction: a colour for conductors, a number otherwise.
    pub eta: Option<ColorDesc>,
    /// Conductor absorption.
    pub k: Option<ColorDesc>,
    /// GGX α: a number, or a pattern or checker texture (its first channel).
    pub roughness: Option<ColorDesc>,
    /// Emitted radiance of the surface (outward), making its objects lights.
    pub emission: Option<ColorDesc>,
}

/// An object: a solid (inline or from a model file), a transform and a material.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// Name for messages (default `objects[i]`).
    pub name: Option<String>,
    /// A `.frep` program or a single expression.
    pub solid: Option<String>,
    /// A `.frep`, `.hf` or `.vm` file, relative to the scene file.
    pub model: Option<String>,
    /// Transforms applied in order.
    pub transform: Option<TransformDesc>,
    /// A key of `materials`.
    pub material: String,
    /// A key of `media`: what fills the object (its inside, F ≥ 0).
    pub medium: Option<String>,
    /// A key of `media`: what surrounds the object (default: vacuum).
    pub exterior: Option<String>,
}

/// A homogeneous participating medium: `sigma_a` and `sigma_s`, or `albedo` and
/// `mean_free_path`, per RGB channel (a number means grey), with a Henyey–Greenstein
/// phase function of asymmetry `g`.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MediumDesc {
    /// Absorption coefficient σ_a (per unit length).
    pub sigma_a: Option<RgbDesc>,
    /// Scattering coefficient σ_s (per unit length).
    pub sigma_s: Option<RgbDesc>,
    /// Single-scattering albedo σ_s/σ_t in [0, 1]: a colour, a point-space checker or a
    /// pattern (read in world space at each scattering point).
    pub albedo: Option<ColorDesc>,
    /// Mean free path 1/σ_t (a length, > 0).
    pub mean_free_path: Option<RgbDesc>,
    /// Henyey–Greenstein asymmetry g in [−0.99, 0.99] (default 0: isotropic).
    pub g: Option<f64>,
    /// Multiplies σ_a and σ_s (divides the mean free path; default 1).
    pub scale: Option<f64>,
}

/// A light; `type` says which other keys apply.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// "sphere", "rect" (or "rectangle"), "disk", "point" or "spot".
    #[serde(rename = "type")]
    pub kind: String,
    /// Centre of a sphere, disk or rect.
    pub center: Option<[f64; 3]>,
    /// Radius of a sphere or disk.
    pub radius: Option<f64>,
    /// Emitting side of a disk or rect (default −z, facing down).
    pub normal: Option<[f64; 3]>,
    /// Width and height of a rect given by its centre.
    pub size: Option<[f64; 2]>,
    /// Corner of a rect given by its edges.
    pub corner: Option<[f64; 3]>,
    /// First edge of a rect.
    pub edge_u: Option<[f64; 3]>,
    /// Second edge of a rect.
    pub edge_v: Option<[f64; 3]>,
    /// Emitted radiance of an area light.
    pub radiance: Option<ColorDesc>,
    /// Radiant intensity of a point or spot light (W/sr).
    pub intensity: Option<ColorDesc>,
    /// Total emitted power in watts (instead of radiance / intensity).
    pub power: Option<f64>,
    /// Colour that scales `power` per channel (default white).
    pub color: Option<ColorDesc>,
    /// Whether a rect or disk emits on both sides.
    pub two_sided: Option<bool>,
    /// Position of a point or spot light.
    pub position: Option<[f64; 3]>,
    /// Axis of a spot light.
    pub direction: Option<[f64; 3]>,
    /// A point the spot light aims at (instead of `direction`).
    pub target: Option<[f64; 3]>,
    /// Total half-angle of a spot light's cone, degrees.
    pub cone: Option<f64>,
    /// Half-angle where a spot light starts to fall off, degrees (default `cone`).
    pub falloff_start: Option<f64>,
    /// Copies of the light on a grid, for scenes of many lights.
    pub array: Option<ArrayDesc>,
    /// A mesh light's file (.obj, .ply), relative to the scene file: every triangle
    /// emits.
    pub file: Option<String>,
    /// Transforms of a mesh light, applied in order.
    pub transform: Option<TransformDesc>,
}

/// `array = { count = [nx, ny, nz], step = [dx, dy, dz], power_range = [a, b], seed }`:
/// the light repeated nx·ny·nz times, copy (i, j, k) moved by (i·dx, j·dy, k·dz), its
/// emission scaled by a factor drawn log-uniformly from [a, b] per copy (default 1).
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ArrayDesc {
    /// Copies along x, y and z (each ≥ 1).
    pub count: [u64; 3],
    /// Offset between neighbouring copies along each axis.
    pub step: [f64; 3],
    /// The range of the per-copy emission factor (0 < a ≤ b; default [1, 1]).
    pub power_range: Option<[f64; 2]>,
    /// Seed of the per-copy factors (default 0).
    pub seed: Option<u64>,
}

/// A constant dome or a lat-long EXR map.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentDesc {
    /// Constant radiance from every direction.
    pub radiance: Option<ColorDesc>,
    /// A lat-long EXR file, relative to the scene file.
    pub map: Option<String>,
    /// Multiplies the map (default 1).
    pub scale: Option<f64>,
    /// A rotation of the map (its +z is up before rotation).
    pub rotate: Option<RotateDesc>,
}

/// A colour: an RGB triple (a number means grey) or a checker texture.
#[derive(Clone, Debug, PartialEq)]
pub enum ColorDesc {
    /// A constant colour.
    Rgb([f64; 3]),
    /// `{ checker = { a, b, scale, space } }`.
    Checker(CheckerDesc),
    /// `{ pattern = { kind, a, b, scale, octaves } }`: solid noise, marble, wood.
    Pattern(PatternDesc),
    /// `{ image = { file, scale, sharpness } }`: a PNG or EXR projected triplanarly.
    Image(ImageDesc),
}

/// An image texture: a PNG or EXR file projected onto the surface along the three axes.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImageDesc {
    /// The image (.png: sRGB; .exr: linear), relative to the scene file.
    pub file: String,
    /// Image repeats per unit length (default 1).
    pub scale: Option<f64>,
    /// Blend sharpness k ≥ 1: each axis's weight ∝ |n_axis|^k (default 4).
    pub sharpness: Option<f64>,
}

/// A procedural solid texture: colours `a` and `b` blended by a pattern of the hit point.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PatternDesc {
    /// "noise", "fbm", "turbulence", "marble" or "wood".
    pub kind: String,
    /// Colour where the pattern is 0.
    pub a: RgbDesc,
    /// Colour where the pattern is 1.
    pub b: RgbDesc,
    /// Pattern cells per unit length (default 1).
    pub scale: Option<f64>,
    /// Octaves of the fractal patterns (default 5, at most 12).
    pub octaves: Option<u32>,
}

/// A constant colour: [r, g, b], or a number for grey.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbDesc(pub [f64; 3]);

struct RgbVisitor;

impl<'de> Visitor<'de> for RgbVisitor {
    type Value = RgbDesc;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a colour: a number or [r, g, b]")
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<RgbDesc, E> {
        Ok(RgbDesc([v; 3]))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<RgbDesc, E> {
        self.visit_f64(v as f64)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<RgbDesc, E> {
        self.visit_f64(v as f64)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<RgbDesc, A::Error> {
        Ok(RgbDesc(triple(seq, &self)?))
    }
}

impl<'de> Deserialize<'de> for RgbDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(RgbVisitor)
    }
}

/// A checker texture.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CheckerDesc {
    /// Colour of even cells.
    pub a: RgbDesc,
    /// Colour of odd cells.
    pub b: RgbDesc,
    /// Checks per unit length (default 1).
    pub scale: Option<f64>,
    /// "point" (3-D cells, default) or "uv".
    pub space: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TextureWrap {
    checker: Option<CheckerDesc>,
    pattern: Option<PatternDesc>,
    image: Option<ImageDesc>,
}

struct ColorVisitor;

impl<'de> Visitor<'de> for ColorVisitor {
    type Value = ColorDesc;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(
            "a colour: a number, [r, g, b], { checker = { a, b, scale } }, \
             { pattern = { kind, a, b, scale } } or { image = { file, scale } }",
        )
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<ColorDesc, E> {
        Ok(ColorDesc::Rgb([v; 3]))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<ColorDesc, E> {
        self.visit_f64(v as f64)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<ColorDesc, E> {
        self.visit_f64(v as f64)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ColorDesc, A::Error> {
        Ok(ColorDesc::Rgb(triple(seq, &self)?))
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<ColorDesc, A::Error> {
        let w = TextureWrap::deserialize(de::value::MapAccessDeserializer::new(map))?;
        match (w.checker, w.pattern, w.image) {
            (Some(c), None, None) => Ok(ColorDesc::Checker(c)),
            (None, Some(p), None) => Ok(ColorDesc::Pattern(p)),
            (None, None, Some(i)) => Ok(ColorDesc::Image(i)),
            _ => Err(de::Error::custom(
                "a texture is { checker = {…} }, { pattern = {…} } or { image = {…} }, exactly one",
            )),
        }
    }
}

/// Exactly three numbers from a sequence.
fn triple<'de, A: SeqAccess<'de>>(
    mut seq: A,
    exp: &dyn de::Expected,
) -> Result<[f64; 3], A::Error> {
    let mut v = [0.0; 3];
    for (i, slot) in v.iter_mut().enumerate() {
        *slot = seq
            .next_element()?
            .ok_or_else(|| de::Error::invalid_length(i, exp))?;
    }
    if seq.next_element::<de::IgnoredAny>()?.is_some() {
        return Err(de::Error::invalid_length(4, exp));
    }
    Ok(v)
}

impl<'de> Deserialize<'de> for ColorDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ColorVisitor)
    }
}

/// A scale factor: one number for all axes, or one per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScaleDesc(pub [f64; 3]);

struct ScaleVisitor;

impl<'de> Visitor<'de> for ScaleVisitor {
    type Value = ScaleDesc;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a scale: a number or [sx, sy, sz]")
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<ScaleDesc, E> {
        Ok(ScaleDesc([v; 3]))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<ScaleDesc, E> {
        self.visit_f64(v as f64)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<ScaleDesc, E> {
        self.visit_f64(v as f64)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ScaleDesc, A::Error> {
        Ok(ScaleDesc(triple(seq, &self)?))
    }
}

impl<'de> Deserialize<'de> for ScaleDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ScaleVisitor)
    }
}

/// A rotation about an axis through the origin (right-handed).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RotateDesc {
    /// The axis.
    pub axis: [f64; 3],
    /// The angle in degrees.
    pub degrees: f64,
}

/// One transform step; exactly one key may be given.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TransformStep {
    /// Move by an offset.
    pub translate: Option<[f64; 3]>,
    /// Rotate about an axis through the origin.
    pub rotate: Option<RotateDesc>,
    /// Scale about the origin.
    pub scale: Option<ScaleDesc>,
}

/// One transform step, or a list of them applied first to last.
#[derive(Clone, Debug, PartialEq)]
pub struct TransformDesc {
    /// The steps in order.
    pub steps: Vec<TransformStep>,
    /// Whether the file gave a list (for key paths: `transform[1]` vs `transform`).
    pub list: bool,
}

struct TransformVisitor;

impl<'de> Visitor<'de> for TransformVisitor {
    type Value = TransformDesc;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a transform ({ translate | rotate | scale = … }) or a list of them")
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<TransformDesc, A::Error> {
        let step = TransformStep::deserialize(de::value::MapAccessDeserializer::new(map))?;
        Ok(TransformDesc {
            steps: vec![step],
            list: false,
        })
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<TransformDesc, A::Error> {
        let steps = Vec::<TransformStep>::deserialize(de::value::SeqAccessDeserializer::new(seq))?;
        Ok(TransformDesc { steps, list: true })
    }
}

impl<'de> Deserialize<'de> for TransformDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(TransformVisitor)
    }
}
