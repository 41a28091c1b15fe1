//! What an experiment compares: an estimator, and optionally its own sampling
//! techniques — `NAME[@TECHNIQUE+TECHNIQUE…]`, e.g. `power@light-bvh+bsdf` (pbrt-v4's
//! practice) or `balance@light#*+bsdf` (one technique per light) — so that a table sets
//! the optimal weights beside the best heuristic practice, not only beside the
//! heuristics on the same draws.
//!
//! [`PRACTICE`] is the set `--practice` adds: balance and power over the experiment's own
//! techniques, over one technique per light (scenes of at most [`PER_LIGHT_MAX`] MIS
//! lights), and pbrt-v4's light BVH with the BSDF under the power heuristic.

use crate::{Error, Method, RenderOptions, Scene};
use scene::{Emitters, TechniqueKind};

/// The variants `--practice` adds (module docs); those with `light#*` only where the
/// scene has at most [`PER_LIGHT_MAX`] MIS lights.
pub const PRACTICE: [&str; 5] = [
    "balance",
    "power",
    "balance@light#*+bsdf",
    "power@light#*+bsdf",
    "power@light-bvh+bsdf",
];

/// The most MIS lights for which `--practice` adds one technique per light.
pub const PER_LIGHT_MAX: usize = 16;

/// A parsed variant.
#[derive(Clone, Debug, PartialEq)]
pub struct Variant {
    /// The estimator.
    pub method: Method,
    /// Its techniques as given (name, samples), or None: the experiment's.
    pub techniques: Option<Vec<(String, u32)>>,
}

/// Parses `NAME[@T+T…]`, each T `technique[:samples]`.
pub fn parse(s: &str) -> Result<Variant, Error> {
    let (name, techs) = match s.split_once('@') {
        Some((n, t)) => (n, Some(t)),
        None => (s, None),
    };
    let method = name
        .parse::<Method>()
        .map_err(|e| Error::Invalid(format!("{s}: {e}")))?;
    let techniques = techs
        .map(|t| {
            if t.is_empty() {
                return Err(Error::Invalid(format!("{s}: no techniques after '@'")));
            }
            t.split('+')
                .map(|one| {
                    let (n, k) = match one.split_once(':') {
                        Some((n, k)) => (n, Some(k)),
                        None => (one, None),
                    };
                    let k = match k {
                        None => 1,
                        Some(k) => k.parse::<u32>().ok().filter(|&k| k >= 1).ok_or_else(|| {
                            Error::Invalid(format!(
                                "{s}: samples {k:?}: expected a whole number ≥ 1"
                            ))
                        })?,
                    };
                    if n != "light#*" {
                        n.parse::<TechniqueKind>()
                            .map_err(|e| Error::Invalid(format!("{s}: {e}")))?;
                    }
                    Ok((n.to_string(), k))
                })
                .collect::<Result<Vec<_>, Error>>()
        })
        .transpose()?;
    Ok(Variant { method, techniques })
}

/// The canonical spelling: the estimator's name, and each technique as `name:samples`.
pub fn canonical(s: &str) -> Result<String, Error> {
    let v = parse(s)?;
    Ok(match &v.techniques {
        None => v.method.name().to_string(),
        Some(t) => format!(
            "{}@{}",
            v.method.name(),
            t.iter()
                .map(|(n, k)| format!("{n}:{k}"))
                .collect::<Vec<_>>()
                .join("+")
        ),
    })
}

/// A file-name-safe label of a variant (letters, digits, `-`, `_`, `.`).
pub fn label(s: &str) -> String {
    s.replace('@', "_with_")
        .replace('+', "_")
        .replace(':', "x")
        .replace('#', "n")
        .replace('*', "all")
}

/// The render options of variant `s` on `scene`: `base` with its estimator and, where
/// it names some, its techniques (`light#*` one per MIS light), checked against the
/// scene.
pub fn options(scene: &Scene, base: &RenderOptions, s: &str) -> Result<RenderOptions, Error> {
    let v = parse(s)?;
    let mut o = RenderOptions {
        method: v.method,
        ..base.clone()
    };
    if let Some(list) = &v.techniques {
        let emitters = Emitters::from(scene.data());
        let mut kinds: Vec<(TechniqueKind, u32)> = Vec::new();
        for (name, k) in list {
            let ts: Vec<TechniqueKind> = if name == "light#*" {
                (0..emitters.lights as u32)
                    .map(TechniqueKind::Light)
                    .collect()
            } else {
                vec![name
                    .parse()
                    .map_err(|e| Error::Invalid(format!("{s}: {e}")))?]
            };
            for t in ts {
                if kinds.iter().any(|&(u, _)| u == t) {
                    return Err(Error::Invalid(format!(
                        "{s}: technique \"{t}\" given twice"
                    )));
                }
                kinds.push((t, *k));
            }
        }
        let mut settings = scene.settings().clone();
        settings.techniques = kinds.clone();
        settings
            .check_techniques(emitters)
            .map_err(|e| Error::Invalid(format!("{s}: {e}")))?;
        o.techniques = kinds.into_iter().map(|(t, n)| (t.into(), n)).collect();
    }
    o.validate()?;
    Ok(o)
}

/// The `--practice` variants for `scene` (module docs).
pub fn practice(scene: &Scene) -> Vec<String> {
    let lights = Emitters::from(scene.data()).lights;
    PRACTICE
        .iter()
        .filter(|v| !v.contains("light#*") || (1..=PER_LIGHT_MAX).contains(&lights))
        .map(|v| canonical(v).expect("the practice variants parse"))
        .collect()
}

/// `estimators` with the `--practice` variants for `scene` added after them (those not
/// already there, in any spelling).
pub fn with_practice(scene: &Scene, estimators: &[String]) -> Vec<String> {
    let mut out = estimators.to_vec();
    for v in practice(scene) {
        if !out.iter().any(|e| canonical(e).is_ok_and(|c| c == v)) {
            out.push(v);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variants_parse_and_spell_canonically() {
        assert_eq!(canonical("optimal_direct").unwrap(), "optimal-direct");
        assert_eq!(
            canonical("power@light-bvh+bsdf:2").unwrap(),
            "power@light-bvh:1+bsdf:2"
        );
        assert_eq!(
            label("balance@light#*:1+bsdf:1"),
            "balance_with_lightnallx1_bsdfx1"
        );
        for bad in [
            "nope",
            "power@",
            "power@light-bvh+",
            "power@bsdf:0",
            "power@what",
        ] {
            assert!(parse(bad).is_err(), "{bad}");
        }
    }

    /// On a scene of two lights: a variant's techniques replace the experiment's
    /// (`light#*` one per light), a technique the scene cannot serve is refused by name,
    /// and `--practice` adds the per-light variants (two lights ≤ 16).
    #[test]
    fn variants_resolve_against_the_scene() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let scene = crate::load(root.join("scenes/two-lights.toml")).unwrap();
        let base = scene.options().unwrap();
        let o = options(&scene, &base, "power@light#*+bsdf:2").unwrap();
        assert_eq!(o.method, Method::Power);
        let names: Vec<String> = o
            .techniques
            .iter()
            .map(|(t, n)| format!("{}:{n}", t.name()))
            .collect();
        assert_eq!(names, ["light#0:1", "light#1:1", "bsdf:2"]);
        assert_eq!(
            options(&scene, &base, "balance").unwrap().techniques,
            base.techniques
        );
        let e = options(&scene, &base, "power@environment+bsdf").unwrap_err();
        assert!(e.to_string().contains("environment"), "{e}");
        let p = practice(&scene);
        assert!(p.contains(&"balance@light#*:1+bsdf:1".to_string()), "{p:?}");
        assert!(p.contains(&"power@light-bvh:1+bsdf:1".to_string()), "{p:?}");
    }
}
