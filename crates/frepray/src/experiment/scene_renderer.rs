//! The experiment's renderer for a scene, on the CPU: every point of the sweep is one
//! render of the scene with the estimator, sample count and seed the driver asks for;
//! the reference renders in chunks merged as they finish, so that a stopped reference
//! keeps what it finished in a checkpoint that a rerun continues from. The command line,
//! Python and Ray all run experiments through it.

use super::{ExperimentConfig, ExperimentError, Image, Renderer};
use crate::{Error, RenderOptions, RenderState, Scene, StateHeader};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

/// Chunks of a reference render: an interrupted reference keeps the chunks it
/// finished (at most 1/`REFERENCE_CHUNKS` of its work is lost).
pub const REFERENCE_CHUNKS: u32 = 32;

/// Renders a [`Scene`] for the experiment driver ([`super::run`]).
pub struct SceneRenderer<'a> {
    scene: &'a Scene,
    base: RenderOptions,
    stop: &'a AtomicBool,
    note: &'a dyn Fn(&str),
}

/// The canonical spelling of an estimator or variant (`optimal_direct` →
/// `optimal-direct`, `power@light-bvh+bsdf` → `power@light-bvh:1+bsdf:1`), so that two
/// spellings are one point of the sweep.
pub fn canonical(estimator: &str) -> Result<String, Error> {
    super::variant::canonical(estimator)
}

impl ExperimentConfig {
    /// The configuration of an experiment on `scene` rendered with `base` (from
    /// [`Scene::options_with`]): the estimators, baseline and reference estimator
    /// spelled canonically, the images' size and the settings that change them recorded
    /// (so a rerun reuses renders only of the same scene and settings), and every
    /// render of the sweep checked against the memory limit before anything runs. The
    /// other fields keep [`ExperimentConfig::new`]'s defaults.
    pub fn for_scene(
        scene: &Scene,
        base: &RenderOptions,
        path: impl Into<PathBuf>,
        out_dir: impl Into<PathBuf>,
        estimators: &[String],
        baseline: &str,
        reference_estimator: Option<&str>,
    ) -> Result<Self, Error> {
        let variants = estimators
            .iter()
            .map(|e| canonical(e))
            .collect::<Result<Vec<_>, _>>()?;
        let reference = reference_estimator.map(canonical).transpose()?;
        let mut cfg = ExperimentConfig::new(path, out_dir);
        cfg.baseline = canonical(baseline)?;
        let (width, height) = scene.resolution();
        // Every variant is checked against the scene (its techniques) and the memory
        // limit before anything runs.
        for v in variants.iter().chain(&reference).chain([&cfg.baseline]) {
            let o = super::variant::options(scene, base, v)?;
            render::limits::check_memory(width, height, &o)?;
        }
        cfg.estimators = variants;
        cfg.reference_estimator = reference;
        // The hash of the resolved scene (in `base`) covers every file it reads (models,
        // environment maps), not only the scene text: editing a model invalidates
        // earlier renders.
        let base = RenderOptions {
            scene_hash: scene.hash(),
            ..base.clone()
        };
        cfg.renderer_settings = super::renderer_settings(&base, width, height);
        cfg.size = Some((width, height));
        Ok(cfg)
    }
}

impl<'a> SceneRenderer<'a> {
    /// Renders `scene` with `base`'s settings (the estimator, spp and seed come from
    /// the driver); setting `stop` ends the experiment with what finished; `note` gets
    /// the reference's progress lines.
    pub fn new(
        scene: &'a Scene,
        base: RenderOptions,
        stop: &'a AtomicBool,
        note: &'a dyn Fn(&str),
    ) -> Self {
        SceneRenderer {
            scene,
            base,
            stop,
            note,
        }
    }

    fn options(&self, estimator: &str, spp: u32, seed: u64) -> Result<RenderOptions, Error> {
        Ok(RenderOptions {
            spp,
            seed,
            ..super::variant::options(self.scene, &self.base, estimator)?
        })
    }

    /// One render of `o`: its image and wall time, or `None` if stopped.
    fn run(&self, o: &RenderOptions) -> Result<Option<(Image, f64)>, Error> {
        let (state, stats) = self.scene.render_with(o, 0..o.spp, self.stop, &|_, _| {})?;
        if stats.stopped {
            return Ok(None);
        }
        Ok(Some((to_image(&state), stats.wall.as_secs_f64())))
    }
}

/// The driver's image of a render state.
pub fn to_image(state: &RenderState) -> Image {
    let img = state.image();
    let (w, h) = (img.width(), img.height());
    let rgb = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| img.rgb(x, y).to_array())
        .collect();
    Image {
        width: w,
        height: h,
        rgb,
    }
}

impl Renderer for SceneRenderer<'_> {
    fn render(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, Error> {
        let o = self.options(estimator, spp, seed)?;
        self.run(&o)
    }

    fn render_pixel_centers(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
    ) -> Result<Option<(Image, f64)>, ExperimentError> {
        let o = RenderOptions {
            pixel_center: true,
            ..self.options(estimator, spp, seed)?
        };
        Ok(self.run(&o)?)
    }

    /// Renders the reference in [`REFERENCE_CHUNKS`] sample ranges merged as they
    /// finish; when stopped, the finished ones go to `checkpoint` (a render state),
    /// which a rerun continues from if it is a state of the same render.
    fn render_reference(
        &mut self,
        estimator: &str,
        spp: u32,
        seed: u64,
        checkpoint: &Path,
    ) -> Result<Option<(Image, f64)>, Error> {
        let o = RenderOptions {
            scene_hash: self.scene.hash(),
            ..self.options(estimator, spp, seed)?
        };
        let (width, height) = self.scene.resolution();
        let header = StateHeader::new(width, height, &o);
        let mut acc = RenderState::read(checkpoint).ok().filter(|s| {
            s.header() == &header
                && !s.is_partial()
                && matches!(s.samples(), [r] if r.start == 0 && r.end < spp)
        });
        let mut next = acc.as_ref().map_or(0, |s| s.samples()[0].end);
        if next > 0 {
            (self.note)(&format!(
                "reference: continuing from {next} of {spp} samples ({})",
                checkpoint.display()
            ));
        }
        let chunk = spp.div_ceil(REFERENCE_CHUNKS).max(1);
        let mut wall = 0.0;
        while next < spp {
            let end = next.saturating_add(chunk).min(spp);
            let (state, stats) = self
                .scene
                .render_with(&o, next..end, self.stop, &|_, _| {})?;
            wall += stats.wall.as_secs_f64();
            if stats.stopped {
                if let Some(s) = &acc {
                    s.write(checkpoint)?;
                    (self.note)(&format!(
                        "reference: {} of {spp} samples kept in {}",
                        s.samples()[0].end,
                        checkpoint.display()
                    ));
                }
                return Ok(None);
            }
            match &mut acc {
                None => acc = Some(state),
                Some(a) => a.merge(&state)?,
            }
            next = end;
        }
        let state = acc.expect("spp ≥ 1: at least one chunk");
        Ok(Some((to_image(&state), wall)))
    }
}
