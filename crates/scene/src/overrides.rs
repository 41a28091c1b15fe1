//! Overrides of a scene's settings (command-line flags, later Python arguments): they
//! patch the [`SceneDescription`] before it is resolved, so that an overridden value
//! is validated once, by the same code and with the same messages as one in the file.

use crate::desc::{SceneDescription, TechniqueDesc};
use crate::error::{kp, SceneError};

/// Values that replace a scene's own; `None` (or `false`) keeps the scene's.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// `render.spp`.
    pub spp: Option<u32>,
    /// `render.estimator`: an MIS heuristic or optimal estimator name.
    pub estimator: Option<String>,
    /// `render.techniques`.
    pub techniques: Option<Vec<TechniqueDesc>>,
    /// `render.seed`.
    pub seed: Option<u64>,
    /// `render.integrator`.
    pub integrator: Option<String>,
    /// The first entry of `camera.resolution`.
    pub width: Option<u32>,
    /// The second entry of `camera.resolution`.
    pub height: Option<u32>,
    /// `render.max_depth`.
    pub max_depth: Option<u32>,
    /// `render.min_depth`.
    pub min_depth: Option<u32>,
    /// `render.aovs`.
    pub aovs: Option<Vec<String>>,
    /// Sets `render.hide_emitters` when true.
    pub hide_emitters: bool,
    /// `render.beta`.
    pub beta: Option<f64>,
    /// `render.cutoff`.
    pub cutoff: Option<f64>,
    /// `render.ridge`.
    pub ridge: Option<f64>,
    /// Sets `render.per_light` when true.
    pub per_light: bool,
    /// `render.trained_grid`.
    pub trained_grid: Option<u32>,
    /// `render.trained_floor`.
    pub trained_floor: Option<f64>,
    /// `render.trained_spp`.
    pub trained_spp: Option<u32>,
}

impl SceneDescription {
    /// Replaces the values that `o` sets.
    pub fn apply_overrides(&mut self, o: &Overrides) {
        let r = &mut self.render;
        set(&mut r.spp, &o.spp);
        set(&mut r.estimator, &o.estimator);
        set(&mut r.techniques, &o.techniques);
        set(&mut r.seed, &o.seed);
        set(&mut r.integrator, &o.integrator);
        set(&mut r.max_depth, &o.max_depth);
        set(&mut r.min_depth, &o.min_depth);
        set(&mut r.aovs, &o.aovs);
        set(&mut r.beta, &o.beta);
        set(&mut r.cutoff, &o.cutoff);
        set(&mut r.ridge, &o.ridge);
        set(&mut r.trained_grid, &o.trained_grid);
        set(&mut r.trained_floor, &o.trained_floor);
        set(&mut r.trained_spp, &o.trained_spp);
        if o.hide_emitters {
            r.hide_emitters = Some(true);
        }
        if o.per_light {
            r.per_light = Some(true);
        }
        if o.width.is_some() || o.height.is_some() {
            let [w, h] = self.camera.resolution.unwrap_or(crate::DEFAULT_RESOLUTION);
            self.camera.resolution = Some([o.width.unwrap_or(w), o.height.unwrap_or(h)]);
        }
    }
}

fn set<T: Clone>(to: &mut Option<T>, from: &Option<T>) {
    if from.is_some() {
        to.clone_from(from);
    }
}

impl Overrides {
    /// The key paths (as [`SceneError::key`] writes them) whose values this sets.
    pub fn keys(&self) -> Vec<&'static str> {
        let given = [
            ("render.spp", self.spp.is_some()),
            ("render.estimator", self.estimator.is_some()),
            ("render.techniques", self.techniques.is_some()),
            ("render.seed", self.seed.is_some()),
            ("render.integrator", self.integrator.is_some()),
            (
                "camera.resolution",
                self.width.is_some() || self.height.is_some(),
            ),
            ("render.max_depth", self.max_depth.is_some()),
            ("render.min_depth", self.min_depth.is_some()),
            ("render.aovs", self.aovs.is_some()),
            ("render.hide_emitters", self.hide_emitters),
            ("render.beta", self.beta.is_some()),
            ("render.cutoff", self.cutoff.is_some()),
            ("render.ridge", self.ridge.is_some()),
            ("render.per_light", self.per_light),
            ("render.trained_grid", self.trained_grid.is_some()),
            ("render.trained_floor", self.trained_floor.is_some()),
            ("render.trained_spp", self.trained_spp.is_some()),
        ];
        given.iter().filter(|g| g.1).map(|g| g.0).collect()
    }

    /// The overridden key that an error at `key` concerns, if any.
    pub fn key_of(&self, key: &str) -> Option<&'static str> {
        self.keys().into_iter().find(|k| {
            key.strip_prefix(k)
                .is_some_and(|rest| rest.is_empty() || rest.starts_with(['.', '[']))
        })
    }

    /// An error about an overridden value loses the file position, which points at a
    /// value that was replaced; errors elsewhere are kept.
    pub fn blame(&self, e: SceneError) -> SceneError {
        match self.key_of(&e.key) {
            Some(_) => SceneError {
                file: String::new(),
                line: 0,
                column: 0,
                ..e
            },
            None => e,
        }
    }
}

/// Parses `bsdf:2,light` (the command-line form) into techniques with sample counts
/// (1 when omitted); names are checked when the scene is resolved. A count that is not
/// a number is an error at `render.techniques`.
pub fn parse_technique_list(s: &str) -> Result<Vec<TechniqueDesc>, SceneError> {
    s.split(',')
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .map(|p| {
            let (name, n) = match p.split_once(':') {
                Some((name, n)) => {
                    let n: u32 = n.trim().parse().map_err(|_| {
                        SceneError::at_key(
                            "",
                            &kp!["render", "techniques"],
                            format!("'{n}' is not a sample count"),
                        )
                    })?;
                    (name.trim(), Some(n))
                }
                None => (p, None),
            };
            Ok(TechniqueDesc {
                technique: name.to_string(),
                samples: n,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::desc::CameraDesc;

    #[test]
    fn overrides_patch_and_blame() {
        let mut d = SceneDescription {
            camera: CameraDesc {
                resolution: Some([10, 20]),
                ..Default::default()
            },
            ..Default::default()
        };
        let o = Overrides {
            spp: Some(3),
            width: Some(7),
            hide_emitters: true,
            techniques: Some(parse_technique_list("bsdf:2, light").unwrap()),
            ..Default::default()
        };
        d.apply_overrides(&o);
        assert_eq!(d.camera.resolution, Some([7, 20]));
        assert_eq!(
            (d.render.spp, d.render.hide_emitters),
            (Some(3), Some(true))
        );
        assert_eq!(d.render.techniques.as_ref().unwrap()[0].samples, Some(2));
        assert_eq!(d.render.techniques.as_ref().unwrap()[1].samples, None);
        assert!(parse_technique_list("bsdf:x").is_err());
        assert_eq!(
            o.key_of("render.techniques[1].technique"),
            Some("render.techniques")
        );
        assert_eq!(o.key_of("render.spp"), Some("render.spp"));
        assert_eq!(o.key_of("render.seed"), None);
        assert_eq!(o.key_of("render.sppx"), None);
        let e = SceneError {
            file: "s.toml".into(),
            line: 3,
            column: 1,
            key: "render.spp".into(),
            message: "no".into(),
        };
        assert_eq!(o.blame(e).to_string(), "render.spp: no");
    }
}
