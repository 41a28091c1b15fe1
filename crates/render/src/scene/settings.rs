//! Render settings read from a scene file's `[render]` table: what an integrator needs
//! besides the scene.

use super::desc::RenderDesc;
use super::error::{kp, SceneError};
use super::locate::Source;
use super::Scene;
use crate::technique::Technique;
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

fn names<T: Copy>(all: &[T], name: fn(T) -> &'static str) -> String {
    all.iter().map(|&t| name(t)).collect::<Vec<_>>().join(", ")
}

impl FromStr for IntegratorKind {
    type Err = String;
    /// The kind named `s`; the error lists the valid names.
    fn from_str(s: &str) -> Result<Self, String> {
        IntegratorKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown integrator {s:?}; valid names: {}",
                    names(&IntegratorKind::ALL, IntegratorKind::name)
                )
            })
    }
}

/// The technique named `s` ([`Technique::name`]); the error lists the valid names.
pub fn parse_technique(s: &str) -> Result<Technique, String> {
    Technique::ALL
        .into_iter()
        .find(|t| t.name() == s)
        .ok_or_else(|| {
            format!(
                "unknown technique {s:?}; valid names: {}",
                names(&Technique::ALL, Technique::name)
            )
        })
}

/// The AOV names a scene file may ask for (first-hit depth, normal and albedo).
pub const AOV_NAMES: [&str; 3] = ["depth", "normal", "albedo"];

/// Everything an integrator needs besides the [`Scene`]. The defaults are those of a
/// scene file that leaves a key out.
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
    pub techniques: Vec<(Technique, u32)>,
    /// Seed of the random streams (default 0).
    pub seed: u64,
    /// Longest path in bounces (default 5).
    pub max_depth: u32,
    /// Bounce from which Russian roulette may end paths (default 3).
    pub rr_depth: u32,
    /// Leave emitters seen directly by the camera out of the image (default false).
    pub hide_emitters: bool,
    /// Extra output channels to write beside R, G, B, from [`AOV_NAMES`] (default none).
    pub aovs: Vec<String>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            integrator: IntegratorKind::Path,
            spp: 16,
            method: mis::Method::Balance,
            params: mis::Params::default(),
            techniques: vec![(Technique::Bsdf, 1), (Technique::LightPower, 1)],
            seed: 0,
            max_depth: 5,
            rr_depth: 3,
            hide_emitters: false,
            aovs: Vec::new(),
        }
    }
}

impl RenderSettings {
    /// Why the techniques cannot work in `scene`, if they cannot: light sampling needs an
    /// area light or an environment, area sampling an area light, environment sampling
    /// an environment (point and spot lights are sampled outside MIS).
    pub fn check_techniques(&self, scene: &Scene) -> Result<(), String> {
        let area = !scene.lights.area().is_empty();
        let env = scene.lights.environment().is_some();
        for &(t, _) in &self.techniques {
            let missing = match t {
                Technique::LightPower if !area && !env => "an area light or an environment",
                Technique::LightArea if !area => "an area light",
                Technique::Environment if !env => "an environment",
                _ => continue,
            };
            return Err(format!("technique {:?} needs {missing}", t.name()));
        }
        Ok(())
    }
}

/// Reads `[render]`; the techniques are checked against the built scene.
pub(crate) fn settings(
    src: &Source,
    r: &RenderDesc,
    scene: &Scene,
) -> Result<RenderSettings, SceneError> {
    let mut s = RenderSettings::default();
    if let Some(name) = &r.integrator {
        s.integrator = name
            .parse()
            .map_err(|e: String| src.at_value(&kp!["render", "integrator"], e))?;
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
    p.ridge = r.ridge.unwrap_or(p.ridge);
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
            .map_err(|e| src.at_value(&kp!["render", key], e))?;
    }
    match &r.techniques {
        Some(list) => {
            s.techniques.clear();
            if list.is_empty() {
                return Err(src.at_value(&kp!["render", "techniques"], "no techniques given"));
            }
            for (i, t) in list.iter().enumerate() {
                let at = kp!["render", "techniques", i, "technique"];
                let tech = parse_technique(&t.technique).map_err(|e| src.at_value(&at, e))?;
                if s.techniques.iter().any(|&(u, _)| u == tech) {
                    return Err(
                        src.at_value(&at, format!("technique {:?} given twice", t.technique))
                    );
                }
                let n = t.samples.unwrap_or(1);
                if n == 0 {
                    let at = kp!["render", "techniques", i, "samples"];
                    return Err(src.at_value(&at, "samples must be at least 1"));
                }
                s.techniques.push((tech, n));
            }
            s.check_techniques(scene)
                .map_err(|e| src.at_value(&kp!["render", "techniques"], e))?;
        }
        None => {
            s.techniques = vec![(Technique::Bsdf, 1)];
            if s.check_techniques_with(scene, Technique::LightPower) {
                s.techniques.push((Technique::LightPower, 1));
            }
        }
    }
    s.seed = r.seed.unwrap_or(s.seed);
    s.max_depth = r.max_depth.unwrap_or(s.max_depth);
    s.rr_depth = r.rr_depth.unwrap_or(s.rr_depth);
    s.hide_emitters = r.hide_emitters.unwrap_or(s.hide_emitters);
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

impl RenderSettings {
    fn check_techniques_with(&self, scene: &Scene, t: Technique) -> bool {
        let probe = RenderSettings {
            techniques: vec![(t, 1)],
            ..self.clone()
        };
        probe.check_techniques(scene).is_ok()
    }
}
