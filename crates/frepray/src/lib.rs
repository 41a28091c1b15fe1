//! # frepray — the library
//!
//! Everything the `frepray` command does, as calls: load a scene (a file, or a JSON value
//! such as a Python dict), render any range of samples into a [`RenderState`] (every
//! pixel's sums), merge states of disjoint ranges exactly, resolve the image, preview a
//! bare model, and run the estimator comparisons of the paper ([`experiment`]).
//! Crates below it: `scene` (files → one flat `SceneData`), `render` (the CPU back end),
//! `frep` (solids) and `mis` (estimators); the command-line front end is `frepray-cli`.
//!
//! ```
//! use frepray::{load_value, merge};
//! use std::path::Path;
//! let scene = load_value(
//!     serde_json::json!({
//!         "camera": { "eye": [0, -4, 1], "target": [0, 0, 0], "resolution": [16, 12] },
//!         "render": { "integrator": "direct", "estimator": "optimal-direct", "spp": 4 },
//!         "materials": { "white": { "type": "diffuse", "reflectance": 0.8 } },
//!         "objects": [{ "solid": "sphere([0, 0, 0], 1)", "material": "white" }],
//!         "lights": [{ "type": "sphere", "center": [0, -2, 3], "radius": 0.5, "power": 100 }]
//!     }),
//!     Path::new("."),
//! )
//! .unwrap();
//! let options = scene.options().unwrap();
//! // Samples 0..4 in one go, and as two ranges merged: the same sums.
//! let (whole, stats) = scene.render(&options, 0..4).unwrap();
//! assert_eq!(stats.samples, 16 * 12 * 4);
//! let parts = [scene.render(&options, 0..1).unwrap().0, scene.render(&options, 1..4).unwrap().0];
//! let merged = merge(parts).unwrap();
//! let (a, b) = (merged.image(), whole.image());
//! let centre = (a.rgb(8, 6), b.rgb(8, 6));
//! assert!((centre.0 - centre.1).abs().max_element() <= 1e-12 * centre.1.max_element());
//! assert!(centre.1.max_element() > 0.0); // the lit sphere
//! ```
#![warn(missing_docs)]

/// The examples of `docs/library.md`, run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../../../docs/library.md")]
pub struct LibraryGuide;

pub mod backend;
pub mod bench;
pub mod denoise;
pub mod experiment;
pub mod mesh_model;
pub mod model_info;
pub mod preview;
pub mod settings;
pub mod view;

pub use backend::{render_range_on, Backend, Rendered};
pub use mesh_model::{mesh_model, mesh_solid, ModelMesh};
pub use model_info::{info as model_info, ModelInfo};

/// The MIS estimators by name (`balance`, `power`, …, `optimal-direct`, …).
pub use mis::Method;
pub use render::integrator::{Aov, Engine, IntegratorKind, RenderOptions};
pub use render::{
    BlockDetail, Film, Image, PixelDetail, RenderState, RenderStats, StateHeader, Tonemap,
};
pub use scene::{
    LightKind, Overrides, RenderSettings, SceneData, SceneError, SceneFormat, ATTRIBUTE_PREFIX,
};
pub use settings::{Settings, Unused};

/// The limits a render is checked against before it starts: threads, memory (with an
/// estimate), sizes such as `512M`.
pub use render::limits;
/// Files written whole or not at all (a temporary file renamed into place).
pub use render::output::write_atomically;
/// 8-bit RGB PNG files, written and read.
pub use render::png_io;
/// Depth and normal images as PNG ([`value_png::Values`]).
pub use render::value_png;
/// A name that is not one of a list's (tone maps, techniques, AOVs).
pub use scene::UnknownName;
/// The technique list of the command line, `bsdf:2,light` (counts 1 when omitted).
pub use scene::{parse_technique_list, TechniqueDesc};

/// Model files and the solids built from them (the `frep` crate's): readers of
/// `.frep`, HyperFun `.hf` and Fidget `.vm`, the expression evaluator, the solid with
/// its bounds and grids.
pub mod model {
    pub use frep::read::{read_file, read_str, Format, Model, ReadError};
    pub use frep::{Expr, Solid, Surface};
}

/// The MIS estimators themselves (the `mis` crate's), for use outside a render: feed
/// samples of several techniques, get the combined estimate.
pub mod estimators {
    pub use mis::{
        Estimator, Layout, Method, Params, UnknownMethod, DEFAULT_TRAIN, DEFAULT_WARMUP,
    };
}

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

/// What can go wrong, typed by where it happened.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene file or value is malformed (file, line, column and key path inside).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Rendering or a render state failed.
    #[error(transparent)]
    Render(#[from] render::Error),
    /// A model file is malformed: its file, line and column, and what was expected.
    #[error(transparent)]
    Read(#[from] frep::read::ReadError),
    /// A model could not be built.
    #[error("{}: {source}", .path.display())]
    Model {
        /// The model file.
        path: PathBuf,
        /// What is wrong.
        source: Box<frep::BuildError>,
    },
    /// Invalid arguments (the message says which).
    #[error("{0}")]
    Invalid(String),
    /// The GPU back end: no adapter, a device limit, or a scene it does not cover
    /// (named).
    #[error(transparent)]
    Gpu(#[from] backend::GpuError),
}

impl From<render::integrator::OptionsError> for Error {
    fn from(e: render::integrator::OptionsError) -> Self {
        Error::Render(e.into())
    }
}

/// A resolved scene, ready to render on the CPU: the flat [`SceneData`], the settings of
/// its file (after overrides), and the renderer's own structures built from them.
pub struct Scene {
    data: SceneData,
    settings: RenderSettings,
    cpu: render::scene::Scene,
    hash: u64,
}

/// FNV-1a 64 of the resolved scene's JSON: it identifies the scene in render states, so
/// that states of different scenes (or image sizes) refuse to merge.
pub fn scene_hash(data: &SceneData) -> u64 {
    render::fnv1a(&serde_json::to_vec(data).expect("SceneData serialises"))
}

impl Scene {
    /// A scene from resolved data and settings.
    pub fn from_data(data: SceneData, settings: RenderSettings) -> Self {
        let hash = scene_hash(&data);
        Self::with_hash(data, settings, hash)
    }
    /// A scene whose render states carry no scene hash (0: unknown), for a picture that
    /// writes no state (a model's preview): hashing a large model's resolved data can
    /// cost more than its preview.
    pub fn unhashed(data: SceneData, settings: RenderSettings) -> Self {
        Self::with_hash(data, settings, 0)
    }
    fn with_hash(data: SceneData, settings: RenderSettings, hash: u64) -> Self {
        let cpu = render::scene::Scene::from_data(&data);
        Scene {
            data,
            settings,
            cpu,
            hash,
        }
    }
    /// The resolved scene.
    pub fn data(&self) -> &SceneData {
        &self.data
    }
    /// The file's render settings (after overrides).
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }
    /// The renderer's CPU scene.
    pub fn cpu(&self) -> &render::scene::Scene {
        &self.cpu
    }
    /// The scene's hash ([`scene_hash`]).
    pub fn hash(&self) -> u64 {
        self.hash
    }
    /// Image width and height.
    pub fn resolution(&self) -> (u32, u32) {
        (self.cpu.camera.width, self.cpu.camera.height)
    }
    /// The render options of the scene's settings (with the scene hash), to adjust and
    /// pass to [`Scene::render`]. Errors when the settings ask for techniques the scene
    /// cannot use.
    pub fn options(&self) -> Result<RenderOptions, Error> {
        let mut o = RenderOptions::from_settings(&self.settings)?;
        o.scene_hash = self.hash;
        o.validate()?;
        Ok(o)
    }
    /// `options` recording this scene's hash (so that its states merge only with its own).
    fn hashed(&self, options: &RenderOptions) -> RenderOptions {
        RenderOptions {
            scene_hash: self.hash,
            ..options.clone()
        }
    }
    /// Renders samples `samples` of every pixel (see [`Scene::render_with`]).
    pub fn render(
        &self,
        options: &RenderOptions,
        samples: Range<u32>,
    ) -> Result<(RenderState, RenderStats), Error> {
        self.render_with(options, samples, &AtomicBool::new(false), &|_, _| {})
    }
    /// Renders samples `samples` of every pixel into a new [`RenderState`], calling
    /// `progress(done, total)` as tiles finish; setting `stop` ends the render early
    /// with a partial state. The state records this scene's hash.
    pub fn render_with(
        &self,
        options: &RenderOptions,
        samples: Range<u32>,
        stop: &AtomicBool,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<(RenderState, RenderStats), Error> {
        let o = self.hashed(options);
        Ok(render::render_range(
            &self.cpu, &o, samples, stop, progress,
        )?)
    }
    /// Renders what a stopped render's `partial` state lacks (on the CPU), giving the
    /// state of the render that was never stopped, bit for bit ([`render::resume`]);
    /// `options` must be the stopped render's.
    pub fn resume(
        &self,
        options: &RenderOptions,
        partial: &RenderState,
        stop: &AtomicBool,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<(RenderState, RenderStats), Error> {
        let o = self.hashed(options);
        Ok(render::resume(&self.cpu, &o, partial, stop, progress)?)
    }
    /// [`Self::render_with`] on `backend`: the GPU's result carries its own statistics,
    /// and [`Backend::Auto`]'s CPU fallback says why it fell back.
    pub fn render_on(
        &self,
        backend: Backend,
        options: &RenderOptions,
        samples: Range<u32>,
        stop: &AtomicBool,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<Rendered, Error> {
        let o = self.hashed(options);
        render_range_on(backend, &self.data, &self.cpu, &o, samples, stop, progress)
    }
}

/// Loads a scene file (TOML or JSON; docs/scene-format.md).
pub fn load(path: impl AsRef<Path>) -> Result<Scene, Error> {
    load_with(path, &Overrides::default())
}

/// Loads a scene file with `overrides` patched into its description before it is
/// resolved (validated once, with the file's own values).
pub fn load_with(path: impl AsRef<Path>, overrides: &Overrides) -> Result<Scene, Error> {
    let (data, settings) = scene::load_with(path.as_ref(), overrides)?;
    Ok(Scene::from_data(data, settings))
}

/// A scene given as data (the JSON form of the schema; relative file names are taken
/// from `base_dir`). Errors name the key path of the offending value.
pub fn load_value(value: serde_json::Value, base_dir: &Path) -> Result<Scene, Error> {
    let (data, settings) = scene::load_value(value, base_dir)?;
    Ok(Scene::from_data(data, settings))
}

/// [`load_value`] with `overrides` patched into the description before it is resolved;
/// an error about an overridden value has no file position (it points at no text).
pub fn load_value_with(
    value: serde_json::Value,
    base_dir: &Path,
    overrides: &Overrides,
) -> Result<Scene, Error> {
    let mut d = scene::description_from_value(value)?;
    d.apply_overrides(overrides);
    let (data, settings) = scene::resolve(&d, base_dir).map_err(|e| overrides.blame(e))?;
    Ok(Scene::from_data(data, settings))
}

/// Adds render states of disjoint sample ranges of one render into one
/// ([`RenderState::merge`]); errors on none, or on states that do not fit together.
pub fn merge(states: impl IntoIterator<Item = RenderState>) -> Result<RenderState, Error> {
    let mut it = states.into_iter();
    let mut all = it
        .next()
        .ok_or_else(|| Error::Invalid("nothing to merge".into()))?;
    for s in it {
        all.merge(&s)?;
    }
    Ok(all)
}
