//! Render settings read from a scene file's `[render]` table: what an integrator needs
//! besides the scene. Sampling techniques are named here by [`TechniqueKind`]; a
//! renderer maps each to its own implementation.

use crate::data::{LightKind, SceneData};
use crate::desc::RenderDesc;
use crate::error::{kp, SceneError};
use crate::locate::Source;
use std::borrow::Cow;
use std::fmt;
use std::str::FromStr;

/// Which image an integrator computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum IntegratorKind {
    /// Direct lighting: emission plus one bounce toward the lights, with MIS.
    Direct,
    /// Path tracing with MIS at every vertex.
    Path,
    /// Distance from the camera to the first hit.
    Depth,
    /// The first hit's normal, mapped to colour.
    Normals,
    /// The first hit's reflectance.
    Albedo,
}

impl IntegratorKind {
    /// Every kind, in the order of their names.
    pub const ALL: [IntegratorKind; 5] = [
        IntegratorKind::Direct,
        IntegratorKind::Path,
        IntegratorKind::Depth,
        IntegratorKind::Normals,
        IntegratorKind::Albedo,
    ];
    /// The name used in scene files and on the command line.
    pub const fn name(self) -> &'static str {
        match self {
            IntegratorKind::Direct => "direct",
            IntegratorKind::Path => "path",
            IntegratorKind::Depth => "depth",
            IntegratorKind::Normals => "normals",
            IntegratorKind::Albedo => "albedo",
        }
    }
}

impl fmt::Display for IntegratorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How a PNG maps linear radiance (after the exposure) to display values in [0, 1];
/// EXR files stay linear (as pbrt and Mitsuba keep them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Tonemap {
    /// Values above 1 clip to white (the default: what frepray always wrote).
    #[default]
    Clamp,
    /// v / (1 + v) per channel (Reinhard et al. 2002, eq. 3): nothing clips, highlights
    /// compress, mid-tones darken (0.5 becomes 1/3).
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve (2015), per channel: a toe and a soft
    /// shoulder; v = 1 becomes 0.80, white from v ≈ 7.2 (clamp: from v = 1).
    Aces,
}

impl Tonemap {
    /// Every curve, in the order of their names.
    pub const ALL: [Tonemap; 3] = [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::Aces];
    /// The name used in scene files and on the command line.
    pub const fn name(self) -> &'static str {
        match self {
            Tonemap::Clamp => "clamp",
            Tonemap::Reinhard => "reinhard",
            Tonemap::Aces => "aces",
        }
    }
    /// The display value of a linear value `v` (already scaled by the exposure); the
    /// PNG encoder clamps it to [0, 1] and applies the sRGB curve.
    pub fn apply(self, v: f64) -> f64 {
        match self {
            Tonemap::Clamp => v,
            Tonemap::Reinhard => {
                let v = v.max(0.0);
                v / (1.0 + v)
            }
            Tonemap::Aces => {
                let v = v.max(0.0);
                (v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14)
            }
        }
    }
}

impl fmt::Display for Tonemap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Tonemap {
    type Err = UnknownName;
    /// The curve named `s`; the error lists the valid names.
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        Tonemap::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| UnknownName {
                what: "tone mapping",
                name: s.to_string(),
                valid: names(&Tonemap::ALL, Tonemap::name),
            })
    }
}

fn names<T: Copy>(all: &[T], name: fn(T) -> &'static str) -> String {
    all.iter().map(|&t| name(t)).collect::<Vec<_>>().join(", ")
}

/// A name that is not one of its kind's (integrator, technique); lists the valid names.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown {what} {name:?}; valid names: {valid}")]
pub struct UnknownName {
    /// What was named ("integrator", "technique").
    pub what: &'static str,
    /// The name given.
    pub name: String,
    /// The valid names, comma-separated.
    pub valid: String,
}

impl FromStr for IntegratorKind {
    type Err = UnknownName;
    /// The kind named `s`; the error lists the valid names.
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        IntegratorKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| UnknownName {
                what: "integrator",
                name: s.to_string(),
                valid: names(&IntegratorKind::ALL, IntegratorKind::name),
            })
    }
}

/// A sampling technique (DESIGN.md §4): draws a direction at a shading point and
/// reports its pdf for any direction.
///
/// The light techniques choose one of the scene's *MIS lights* and sample it. The MIS
/// lights are the area lights in the order of the scene file's `lights` list (point and
/// spot lights skipped: they are sampled outside MIS), then, last, the environment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TechniqueKind {
    /// Importance sampling of the BSDF.
    Bsdf,
    /// A light chosen ∝ power (area lights and the environment), then sampled
    /// (`light-power`, alias `light`).
    LightPower,
    /// A light chosen uniformly among the MIS lights, then sampled.
    LightUniform,
    /// A point uniform over the total area of the area lights.
    LightArea,
    /// A light chosen ∝ a bound on its unoccluded contribution at the shading point
    /// (pbrt-v4's `LightBounds::Importance`), then sampled.
    LightSpatial,
    /// [`TechniqueKind::LightSpatial`]'s selection ∝ importance, drawn from a BVH over the
    /// lights in O(log n) per draw and per pmf (pbrt-v4's `BVHLightSampler`), then
    /// sampled (`light-bvh`).
    LightBvh,
    /// A light chosen by a pmf learned per spatial cell from contributions measured in a
    /// training pass (visibility included), mixed with a uniform floor, then sampled.
    LightTrained,
    /// Light k alone (`light#k`, k the MIS light's index, 0-based), sampled as
    /// [`TechniqueKind::LightPower`] samples it.
    Light(u32),
    /// The environment's own sampling.
    Environment,
    /// Cosine-weighted directions about the normal.
    CosineHemisphere,
}

impl TechniqueKind {
    /// Every technique without a parameter, in the order of their names (`light#k` is
    /// one per light).
    pub const ALL: [TechniqueKind; 9] = [
        TechniqueKind::Bsdf,
        TechniqueKind::LightPower,
        TechniqueKind::LightUniform,
        TechniqueKind::LightArea,
        TechniqueKind::LightSpatial,
        TechniqueKind::LightBvh,
        TechniqueKind::LightTrained,
        TechniqueKind::Environment,
        TechniqueKind::CosineHemisphere,
    ];
    /// The name used in scene files and on the command line.
    pub fn name(self) -> Cow<'static, str> {
        Cow::Borrowed(match self {
            TechniqueKind::Bsdf => "bsdf",
            TechniqueKind::LightPower => "light-power",
            TechniqueKind::LightUniform => "light-uniform",
            TechniqueKind::LightArea => "light-area",
            TechniqueKind::LightSpatial => "light-spatial",
            TechniqueKind::LightBvh => "light-bvh",
            TechniqueKind::LightTrained => "light-trained",
            TechniqueKind::Light(k) => return Cow::Owned(format!("light#{k}")),
            TechniqueKind::Environment => "environment",
            TechniqueKind::CosineHemisphere => "cosine",
        })
    }
    /// Whether the technique samples a light (and so needs one).
    pub fn is_light(self) -> bool {
        !matches!(self, TechniqueKind::Bsdf | TechniqueKind::CosineHemisphere)
    }
}

impl fmt::Display for TechniqueKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

/// The valid technique names, for messages.
fn technique_names() -> String {
    let mut v: Vec<String> = TechniqueKind::ALL.iter().map(|t| t.name().into()).collect();
    v.insert(2, "light (= light-power)".into());
    let after = v
        .iter()
        .position(|n| n == "light-trained")
        .map_or(v.len(), |i| i + 1);
    v.insert(after, "light#k (MIS light k, 0-based)".into());
    v.insert(after + 1, "light#* (every MIS light)".into());
    v.join(", ")
}

impl FromStr for TechniqueKind {
    type Err = UnknownName;
    /// The technique named `s` (`light` is `light-power`; `light#k` is light k, not
    /// checked against a scene here); the error lists the valid names.
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        if s == "light" {
            return Ok(TechniqueKind::LightPower);
        }
        if let Some(k) = s.strip_prefix("light#").and_then(|k| k.parse().ok()) {
            return Ok(TechniqueKind::Light(k));
        }
        TechniqueKind::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| UnknownName {
                what: "technique",
                name: s.to_string(),
                valid: technique_names(),
            })
    }
}

/// Which kinds of light a scene has, as far as sampling techniques care.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Emitters {
    /// Whether there is an area light.
    pub area: bool,
    /// Whether there is an environment.
    pub environment: bool,
    /// The number of MIS lights: area lights and the environment (the `k` of
    /// `light#k` counts these).
    pub lights: usize,
}

impl From<&SceneData> for Emitters {
    fn from(d: &SceneData) -> Self {
        Emitters {
            area: !d.lights.area.is_empty(),
            environment: d.environment.is_some(),
            lights: d.lights.area.len() + usize::from(d.environment.is_some()),
        }
    }
}

/// The AOV names a scene file may ask for (first-hit depth, normal and albedo).
pub const AOV_NAMES: [&str; 3] = ["depth", "normal", "albedo"];

/// Everything an integrator needs besides the scene. The defaults are those of a scene
/// file that leaves a key out.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Which image to compute (default path tracing).
    pub integrator: IntegratorKind,
    /// Samples (camera rays) per pixel (default 16).
    pub spp: u32,
    /// How the techniques' samples are combined (default balance heuristic).
    pub method: mis::Method,
    /// The estimator's parameters (β, cutoff, ridge, warm-up, training).
    pub params: mis::Params,
    /// Each technique with n_i, its samples per camera sample, in file order (default
    /// BSDF and, when the scene has area lights or an environment, light sampling).
    pub techniques: Vec<(TechniqueKind, u32)>,
    /// Seed of the random streams (default 0).
    pub seed: u64,
    /// Longest path in bounces (default 5).
    pub max_depth: u32,
    /// Only paths of at least this many bounces reach the image (default 0: all).
    pub min_depth: u32,
    /// Bounce from which Russian roulette may end paths (default 3).
    pub rr_depth: u32,
    /// Leave emitters seen directly by the camera out of the image (default false).
    pub hide_emitters: bool,
    /// Extra output channels to write beside R, G, B, from [`AOV_NAMES`] (default none).
    pub aovs: Vec<String>,
    /// `[film] exposure`: PNG values are radiance × 2^exposure (default 0).
    pub exposure: f64,
    /// `[film] tonemap`: the PNG's curve (default clamp).
    pub tonemap: Tonemap,
    /// Per-light mode (`per_light = true`): the number of MIS lights, each of which gets
    /// its own MIS estimator (Kondapaneni et al. 2019: "the illumination from individual
    /// light sources is evaluated separately"); 0 (default): one estimator for all.
    pub per_light: u32,
    /// How `light-trained` is trained (`trained_grid`, `trained_floor`, `trained_spp`).
    pub training: crate::Training,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            integrator: IntegratorKind::Path,
            spp: 16,
            method: mis::Method::Balance,
            params: mis::Params::default(),
            techniques: vec![(TechniqueKind::Bsdf, 1), (TechniqueKind::LightPower, 1)],
            seed: 0,
            max_depth: 5,
            min_depth: 0,
            rr_depth: 3,
            hide_emitters: false,
            aovs: Vec::new(),
            exposure: 0.0,
            tonemap: Tonemap::Clamp,
            per_light: 0,
            training: crate::Training::default(),
        }
    }
}

/// A technique the scene cannot serve ([`RenderSettings::check_techniques`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TechniqueError {
    /// `light#k` with k past the scene's MIS lights.
    #[error(
        "technique \"{technique}\": the scene has {lights} MIS light{} (area lights, then the \
         environment), numbered from 0",
        if *.lights == 1 { "" } else { "s" }
    )]
    NoSuchLight {
        /// The technique.
        technique: TechniqueKind,
        /// The scene's MIS lights.
        lights: usize,
    },
    /// A technique that samples what the scene does not have.
    #[error("technique \"{technique}\" needs {missing}")]
    Needs {
        /// The technique.
        technique: TechniqueKind,
        /// What it needs: "an area light or an environment", "an area light", "an
        /// environment".
        missing: &'static str,
    },
}

impl RenderSettings {
    /// Why the techniques cannot work in `scene`, if they cannot: light sampling needs an
    /// area light or an environment, area sampling an area light, environment sampling
    /// an environment (point and spot lights are sampled outside MIS).
    pub fn check_techniques(&self, scene: impl Into<Emitters>) -> Result<(), TechniqueError> {
        let Emitters {
            area,
            environment: env,
            lights,
        } = scene.into();
        for &(t, _) in &self.techniques {
            if let TechniqueKind::Light(k) = t {
                if k as usize >= lights {
                    return Err(TechniqueError::NoSuchLight {
                        technique: t,
                        lights,
                    });
                }
                continue;
            }
            let missing = match t {
                TechniqueKind::LightPower
                | TechniqueKind::LightUniform
                | TechniqueKind::LightSpatial
                | TechniqueKind::LightBvh
                | TechniqueKind::LightTrained
                    if !area && !env =>
                {
                    "an area light or an environment"
                }
                TechniqueKind::LightArea if !area => "an area light",
                TechniqueKind::Environment if !env => "an environment",
                _ => continue,
            };
            return Err(TechniqueError::Needs {
                technique: t,
                missing,
            });
        }
        Ok(())
    }
}

/// Reads `[film]`: the exposure (a finite number of stops) and the tone mapping.
pub(crate) fn film(
    src: &Source,
    f: &crate::desc::FilmDesc,
    s: &mut RenderSettings,
) -> Result<(), SceneError> {
    if let Some(e) = f.exposure {
        s.exposure = crate::check::number(
            src,
            &kp!["film", "exposure"],
            e,
            f64::NEG_INFINITY,
            f64::INFINITY,
        )?;
    }
    if let Some(t) = &f.tonemap {
        s.tonemap = t
            .parse()
            .map_err(|e: UnknownName| src.at_value(&kp!["film", "tonemap"], e.to_string()))?;
    }
    Ok(())
}

/// Reads `[render]`; the techniques are checked against the resolved scene.
pub(crate) fn settings(
    src: &Source,
    r: &RenderDesc,
    scene: &SceneData,
) -> Result<RenderSettings, SceneError> {
    let mut s = RenderSettings::default();
    if let Some(name) = &r.integrator {
        s.integrator = name
            .parse()
            .map_err(|e: UnknownName| src.at_value(&kp!["render", "integrator"], e.to_string()))?;
    }
    if let Some(spp) = r.spp {
        if spp == 0 {
            return Err(src.at_value(&kp!["render", "spp"], "spp must be at least 1"));
        }
        s.spp = spp;
    }
    if let Some(name) = &r.estimator {
        s.method = name.parse().map_err(|e: mis::UnknownMethod| {
            src.at_value(&kp!["render", "estimator"], e.to_string())
        })?;
    }
    let p = &mut s.params;
    p.beta = r.beta.unwrap_or(p.beta);
    p.cutoff = r.cutoff.unwrap_or(p.cutoff);
    p.ridge = r.ridge.or(p.ridge);
    p.warmup = r.warmup.unwrap_or(p.warmup);
    p.train = r.train.unwrap_or(p.train);
    let d = mis::Params::default();
    let each = [
        ("beta", mis::Params { beta: p.beta, ..d }),
        (
            "cutoff",
            mis::Params {
                cutoff: p.cutoff,
                ..d
            },
        ),
        (
            "ridge",
            mis::Params {
                ridge: p.ridge,
                ..d
            },
        ),
    ];
    for (key, one) in each {
        one.validate()
            .map_err(|e| src.at_value(&kp!["render", key], e.to_string()))?;
    }
    match &r.techniques {
        Some(list) => {
            s.techniques.clear();
            if list.is_empty() {
                return Err(src.at_value(&kp!["render", "techniques"], "no techniques given"));
            }
            let lights = Emitters::from(scene).lights as u32;
            for (i, t) in list.iter().enumerate() {
                let at = kp!["render", "techniques", i, "technique"];
                // `light#*`: one `light#k` per MIS light.
                let techs: Vec<TechniqueKind> = if t.technique == "light#*" {
                    (0..lights).map(TechniqueKind::Light).collect()
                } else {
                    vec![t
                        .technique
                        .parse()
                        .map_err(|e: UnknownName| src.at_value(&at, e.to_string()))?]
                };
                let n = t.samples.unwrap_or(1);
                if n == 0 {
                    let at = kp!["render", "techniques", i, "samples"];
                    return Err(src.at_value(&at, "samples must be at least 1"));
                }
                for tech in techs {
                    if s.techniques.iter().any(|&(u, _)| u == tech) {
                        return Err(src.at_value(&at, format!("technique \"{tech}\" given twice")));
                    }
                    s.techniques.push((tech, n));
                }
            }
            s.check_techniques(scene)
                .map_err(|e| src.at_value(&kp!["render", "techniques"], e.to_string()))?;
        }
        None => {
            s.techniques = vec![(TechniqueKind::Bsdf, 1)];
            if Emitters::from(scene) != Emitters::default() {
                s.techniques.push((TechniqueKind::LightPower, 1));
            }
        }
    }
    s.seed = r.seed.unwrap_or(s.seed);
    s.max_depth = r.max_depth.unwrap_or(s.max_depth);
    if let Some(m) = r.min_depth {
        let deepest = match s.integrator {
            IntegratorKind::Direct => 1,
            _ => s.max_depth,
        };
        if m > deepest {
            return Err(src.at_value(
                &kp!["render", "min_depth"],
                format!(
                    "min_depth {m} exceeds the deepest bounce {deepest} (max_depth, or 1 for \
                     direct): the image would be black"
                ),
            ));
        }
        s.min_depth = m;
    }
    s.rr_depth = r.rr_depth.unwrap_or(s.rr_depth);
    s.hide_emitters = r.hide_emitters.unwrap_or(s.hide_emitters);
    if r.per_light == Some(true) {
        let n = Emitters::from(scene).lights;
        if n == 0 {
            return Err(src.at_value(
                &kp!["render", "per_light"],
                "per-light mode needs an area light or an environment",
            ));
        }
        if scene.lights.area.iter().any(|l| l.kind == LightKind::Solid) {
            return Err(src.at_value(
                &kp!["render", "per_light"],
                "per-light mode does not take emitting objects (materials with `emission`)",
            ));
        }
        s.per_light = n as u32;
    }
    let t = &mut s.training;
    t.grid = r.trained_grid.unwrap_or(t.grid);
    t.floor = r.trained_floor.unwrap_or(t.floor);
    t.spp = r.trained_spp.unwrap_or(t.spp);
    t.validate()
        .map_err(|(key, e)| src.at_value(&kp!["render", key], e))?;
    if let Some(aovs) = &r.aovs {
        for (i, a) in aovs.iter().enumerate() {
            let at = kp!["render", "aovs", i];
            if !AOV_NAMES.contains(&a.as_str()) {
                let valid = AOV_NAMES.join(", ");
                return Err(src.at_value(&at, format!("unknown AOV {a:?}; valid names: {valid}")));
            }
            if aovs[..i].contains(a) {
                return Err(src.at_value(&at, format!("AOV {a:?} given twice")));
            }
        }
        s.aovs = aovs.clone();
    }
    Ok(s)
}
