//! What a front end sets over a scene's own settings: the overrides patched into its
//! description and the run's own options, into one validated [`RenderOptions`], with a
//! note of each override that the chosen integrator or estimator ignores. The command
//! line's flags and Python's keyword arguments both land here, so they are checked and
//! warned about alike.

use crate::{Error, Method, Overrides, RenderOptions, Scene};
use render::integrator::IntegratorKind;
use render::Technique;

/// Everything a front end may set for a render of a scene: the scene file's settings
/// to override, and the options no scene file holds.
#[derive(Clone, Debug, Default)]
pub struct Settings {
    /// Values patched into the scene's description before it is resolved ([`crate::load_with`]).
    pub overrides: Overrides,
    /// Worker threads (0: the global pool, one per core).
    pub threads: usize,
    /// Every camera ray through its pixel's centre (a diagnostic).
    pub pixel_center: bool,
    /// Time the CPU's stages (a few per cent slower).
    pub stage_times: bool,
    /// The memory a render may take in bytes (0: what the system has available).
    pub max_memory: u64,
    /// How the CPU runs the samples (the image is the same either way).
    pub engine: crate::Engine,
}

/// An override that has no effect on a render: the scene keys it sets and what they
/// apply with. Front ends name the keys their own way (`--beta`, `beta=`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unused {
    /// The scene keys, e.g. `["render.beta"]`.
    pub keys: &'static [&'static str],
    /// What the keys apply with, e.g. `estimator power`.
    pub applies: &'static str,
    /// The render's integrator and estimator, for the message.
    pub integrator: IntegratorKind,
    /// The render's estimator.
    pub estimator: Method,
}

impl Unused {
    /// The message with the keys spelled by `name` (a flag, a keyword): `NAME has no
    /// effect here (integrator direct, estimator balance); it applies with …`.
    pub fn message(&self, name: impl Fn(&str) -> String) -> String {
        let names: Vec<String> = self.keys.iter().map(|k| name(k)).collect();
        format!(
            "{} has no effect here (integrator {}, estimator {}); it applies with {}",
            names.join("/"),
            self.integrator,
            self.estimator.name(),
            self.applies
        )
    }
}

impl std::fmt::Display for Unused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message(str::to_string))
    }
}

/// The overrides in `o` that have no effect with `opts`' integrator, estimator and
/// techniques.
pub fn unused(o: &Overrides, opts: &RenderOptions) -> Vec<Unused> {
    let heuristic = matches!(
        opts.method,
        Method::Balance | Method::Power | Method::Maximum | Method::Cutoff
    );
    let mis = matches!(
        opts.integrator,
        IntegratorKind::Direct | IntegratorKind::Path
    );
    let trained = opts
        .techniques
        .iter()
        .any(|(t, _)| *t == Technique::LightTrained);
    let checks: [(&'static [&'static str], bool, &'static str); 7] = [
        (
            &["render.beta"],
            o.beta.is_some() && (!mis || opts.method != Method::Power),
            "estimator power",
        ),
        (
            &["render.cutoff"],
            o.cutoff.is_some() && (!mis || opts.method != Method::Cutoff),
            "estimator cutoff",
        ),
        (
            &["render.ridge"],
            o.ridge.is_some() && (!mis || heuristic),
            "an optimal estimator (optimal-*)",
        ),
        (
            &["render.max_depth"],
            o.max_depth.is_some() && opts.integrator != IntegratorKind::Path,
            "integrator path",
        ),
        (
            &["render.estimator"],
            o.estimator.is_some() && !mis,
            "integrator direct or path",
        ),
        (
            &["render.techniques"],
            o.techniques.is_some() && !mis,
            "integrator direct or path",
        ),
        (
            &[
                "render.trained_grid",
                "render.trained_floor",
                "render.trained_spp",
            ],
            (o.trained_grid.is_some() || o.trained_floor.is_some() || o.trained_spp.is_some())
                && !(mis && trained),
            "the light-trained technique",
        ),
    ];
    checks
        .into_iter()
        .filter(|c| c.1)
        .map(|(keys, _, applies)| Unused {
            keys,
            applies,
            integrator: opts.integrator,
            estimator: opts.method,
        })
        .collect()
}

/// The overrides in `o` that have no effect with any of `estimators` (an experiment's
/// sweep), each reported with the first of them.
pub fn unused_in_sweep(o: &Overrides, opts: &RenderOptions, estimators: &[Method]) -> Vec<Unused> {
    let each: Vec<Vec<Unused>> = estimators
        .iter()
        .map(|&method| {
            unused(
                o,
                &RenderOptions {
                    method,
                    ..opts.clone()
                },
            )
        })
        .collect();
    match each.split_first() {
        None => unused(o, opts),
        Some((first, rest)) => first
            .iter()
            .filter(|u| rest.iter().all(|r| r.iter().any(|v| v.keys == u.keys)))
            .cloned()
            .collect(),
    }
}

impl Scene {
    /// The render options of the scene's settings with the run's own in `s` (threads,
    /// pixel centres, stage times, memory), validated and checked against the thread
    /// and memory limits, and the overrides of `s` that have no effect on them. The
    /// scene must have been loaded with `s.overrides` ([`crate::load_with`]).
    pub fn options_with(&self, s: &Settings) -> Result<(RenderOptions, Vec<Unused>), Error> {
        let mut o = RenderOptions::from_settings(self.settings())?;
        o.scene_hash = self.hash();
        o.threads = s.threads;
        o.pixel_center = s.pixel_center;
        o.stage_times = s.stage_times;
        o.max_memory = s.max_memory;
        o.engine = s.engine;
        o.validate()?;
        render::limits::check_threads(o.threads)?;
        let (width, height) = self.resolution();
        render::limits::check_memory(width, height, &o)?;
        let unused = unused(&s.overrides, &o);
        Ok((o, unused))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        crate::load_value(
            serde_json::json!({
                "camera": { "eye": [0, -4, 1], "target": [0, 0, 0], "resolution": [4, 3] },
                "render": { "integrator": "direct", "estimator": "balance", "spp": 2 },
                "materials": { "white": { "type": "diffuse", "reflectance": 0.8 } },
                "objects": [{ "solid": "sphere([0, 0, 0], 1)", "material": "white" }],
                "lights": [{ "type": "sphere", "center": [0, -2, 3], "radius": 0.5, "power": 100 }]
            }),
            std::path::Path::new("."),
        )
        .unwrap()
    }

    #[test]
    fn overrides_the_render_ignores_are_named() {
        let s = Settings {
            overrides: Overrides {
                beta: Some(3.0),
                ridge: Some(0.5),
                max_depth: Some(4),
                trained_spp: Some(2),
                ..Default::default()
            },
            threads: 1,
            pixel_center: true,
            ..Default::default()
        };
        let (o, unused) = scene().options_with(&s).unwrap();
        assert_eq!((o.threads, o.pixel_center), (1, true));
        let keys: Vec<&str> = unused.iter().flat_map(|u| u.keys.iter().copied()).collect();
        assert_eq!(
            keys,
            [
                "render.beta",
                "render.ridge",
                "render.max_depth",
                "render.trained_grid",
                "render.trained_floor",
                "render.trained_spp"
            ]
        );
        assert_eq!(
            unused[0].to_string(),
            "render.beta has no effect here (integrator direct, estimator balance); it \
             applies with estimator power"
        );
        let flag = |k: &str| format!("--{}", k.trim_start_matches("render.").replace('_', "-"));
        assert!(unused[3]
            .message(flag)
            .starts_with("--trained-grid/--trained-floor/--trained-spp has no effect"));
    }

    #[test]
    fn overrides_that_apply_are_not_named() {
        let mut s = Settings::default();
        s.overrides.beta = Some(3.0);
        s.overrides.estimator = Some("power".into());
        let sc = crate::load_value(
            serde_json::json!({
                "camera": { "eye": [0, -4, 1], "target": [0, 0, 0], "resolution": [4, 3] },
                "render": { "integrator": "direct", "estimator": "power", "beta": 3, "spp": 2 },
                "materials": { "white": { "type": "diffuse", "reflectance": 0.8 } },
                "objects": [{ "solid": "sphere([0, 0, 0], 1)", "material": "white" }],
                "lights": [{ "type": "sphere", "center": [0, -2, 3], "radius": 0.5, "power": 100 }]
            }),
            std::path::Path::new("."),
        )
        .unwrap();
        let (o, unused) = sc.options_with(&s).unwrap();
        assert_eq!(o.method, Method::Power);
        assert!(unused.is_empty(), "{unused:?}");
        // Invalid run options are refused, as the scene's are.
        s.threads = usize::MAX;
        assert!(sc.options_with(&s).is_err());
    }
}
