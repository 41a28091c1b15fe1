//! Everything a render needs besides the scene ([`RenderOptions`]), as either back end
//! takes it.

use crate::aov::Aov;
use crate::options_error::OptionsError;
use crate::technique::Technique;
use mis::{Method, Params};
use scene::{IntegratorKind, RenderSettings};

/// At most this many techniques. Each costs a pdf evaluation for every draw of every
/// technique (O(T²) per vertex) and, for the optimal estimators, `T(T+1)/2 + 3T` words
/// of state per pixel and depth (at 32: 624 words, 4.9 KiB; docs/render-state.md).
pub const MAX_TECHNIQUES: usize = 32;

/// Whether the integrator draws techniques and combines them by MIS.
pub const fn uses_mis(kind: IntegratorKind) -> bool {
    matches!(kind, IntegratorKind::Direct | IntegratorKind::Path)
}

/// Everything a render needs besides the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// The integrator.
    pub integrator: IntegratorKind,
    /// Samples (iterations) per pixel.
    pub spp: u32,
    /// Seed of the random streams (DESIGN.md §4: the image depends on it alone).
    pub seed: u64,
    /// How the techniques' draws are combined.
    pub method: Method,
    /// The method's parameters.
    pub params: Params,
    /// The techniques with their draws per iteration `n_i` ≥ 1, each at most once.
    pub techniques: Vec<(Technique, u32)>,
    /// Maximum number of scattering vertices of `path` (1: direct lighting only; 0: only
    /// what the camera sees directly).
    pub max_depth: u32,
    /// Only light carried by paths of at least this many scattering vertices reaches the
    /// image (pbrt-style minimum depth; 0: all). Emitters seen by the camera have depth
    /// 0, the direct lighting of the d-th vertex (its MIS draws, delta lights and delta
    /// lobes) depth d; with `min_depth = max_depth = d` the image holds depth d alone, and
    /// the images of depths 0…D sum to the image of `max_depth = D`. Shallower vertices
    /// still draw (the same random numbers) and extend the path; they add nothing.
    pub min_depth: u32,
    /// Russian roulette is played after this many vertices.
    pub rr_depth: u32,
    /// Leave emitters (area lights, environment) seen directly by the camera out of the
    /// image, as Mitsuba's `hide_emitters`: their pixels then carry no emitter noise.
    pub hide_emitters: bool,
    /// Extra film channels.
    pub aovs: Vec<Aov>,
    /// Trace every camera ray through its pixel's centre instead of a uniform point of
    /// the pixel (a diagnostic: the variance left is the directions' alone, without the
    /// pixel footprint's; the image converges to point samples, not pixel averages).
    pub pixel_center: bool,
    /// How `light-trained` is trained: grid, floor, training rays per pixel
    /// (`integrator/train.rs`).
    pub training: scene::Training,
    /// Per-light mode: 0 for one MIS estimator per pixel and depth; n (the scene's
    /// number of MIS lights, `render::light::Lights::count`) for one per pixel, depth
    /// and light, each fed only the radiance of the light its draws reach (module docs).
    pub per_light: u32,
    /// Tile side in pixels.
    pub tile_size: u32,
    /// Samples per pixel per pass (0: spp/16 rounded up). The progress callback acts
    /// between tiles of a pass, the stop flag between samples.
    pub pass_spp: u32,
    /// Worker threads (0: the current rayon pool); at most
    /// [`crate::limits::max_threads`].
    pub threads: usize,
    /// The memory a render may take, in bytes (0: what the system has available;
    /// [`crate::limits`]).
    pub max_memory: u64,
    /// A hash of the scene, recorded in the [`crate::RenderState`] so that states of
    /// different scenes refuse to merge (0: unknown).
    pub scene_hash: u64,
    /// Time the render's stages ([`crate::RayCounts::stages`]; `frepray bench` does). Off by
    /// default: the timers cost a few per cent on small scenes.
    pub stage_times: bool,
    /// How the CPU runs the samples ([`Engine`]); the image is the same either way.
    pub engine: Engine,
}

/// How the CPU back end runs a render's samples. Both give the same image bit for bit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Engine {
    /// One sample at a time through every stage (the reference).
    #[default]
    PerRay,
    /// A tile's samples in batches, stage by stage over the whole batch (camera rays,
    /// draws, lights along the draws, shadow and continuation rays, pdfs, records),
    /// vertex by vertex: the GPU back end's pipeline shape. `direct` and `path` without
    /// media, emitting objects or AOVs; other renders run per ray, and so do the
    /// vertices with a delta lobe.
    Batched,
}

impl Engine {
    /// The engine named `per-ray` or `batched`.
    pub fn parse(name: &str) -> Option<Engine> {
        match name {
            "per-ray" => Some(Engine::PerRay),
            "batched" => Some(Engine::Batched),
            _ => None,
        }
    }

    /// The engine's name, as [`Engine::parse`] reads it.
    pub fn name(self) -> &'static str {
        match self {
            Engine::PerRay => "per-ray",
            Engine::Batched => "batched",
        }
    }
}

impl Default for RenderOptions {
    /// `direct`, 16 spp, balance heuristic over one BSDF and one light draw, depth 5 with
    /// roulette after 3, 16-pixel tiles.
    fn default() -> Self {
        Self {
            integrator: IntegratorKind::Direct,
            spp: 16,
            seed: 0,
            method: Method::Balance,
            params: Params::default(),
            techniques: vec![(Technique::Bsdf, 1), (Technique::LightPower, 1)],
            max_depth: 5,
            min_depth: 0,
            rr_depth: 3,
            hide_emitters: false,
            aovs: Vec::new(),
            pixel_center: false,
            training: scene::Training::default(),
            per_light: 0,
            tile_size: 16,
            pass_spp: 0,
            threads: 0,
            max_memory: 0,
            scene_hash: 0,
            stage_times: false,
            engine: Engine::PerRay,
        }
    }
}

impl RenderOptions {
    /// The options of a scene file's `[render]` table, with the loop's own settings (tile
    /// size, passes, threads) at their defaults. Errors on an AOV name other than
    /// `depth`, `normal` or `albedo`.
    pub fn from_settings(s: &RenderSettings) -> Result<Self, OptionsError> {
        Ok(Self {
            integrator: s.integrator,
            spp: s.spp,
            seed: s.seed,
            method: s.method,
            params: s.params,
            techniques: s.techniques.iter().map(|&(t, n)| (t.into(), n)).collect(),
            max_depth: s.max_depth,
            min_depth: s.min_depth,
            rr_depth: s.rr_depth,
            hide_emitters: s.hide_emitters,
            aovs: s.aovs.iter().map(|a| a.parse()).collect::<Result<_, _>>()?,
            per_light: s.per_light,
            training: s.training,
            ..Self::default()
        })
    }

    /// Checks the options: spp, tile size, techniques (non-empty for MIS integrators,
    /// counts ≥ 1, none twice, at most [`MAX_TECHNIQUES`]), method parameters, AOVs once.
    pub fn validate(&self) -> Result<(), OptionsError> {
        if self.spp == 0 {
            return Err(OptionsError::ZeroSpp);
        }
        if self.tile_size == 0 {
            return Err(OptionsError::ZeroTileSize);
        }
        if uses_mis(self.integrator) && self.techniques.is_empty() {
            return Err(OptionsError::NoTechniques(self.integrator));
        }
        if self.techniques.len() > MAX_TECHNIQUES {
            return Err(OptionsError::TooManyTechniques(self.techniques.len()));
        }
        for (i, (t, n)) in self.techniques.iter().enumerate() {
            if *n == 0 {
                return Err(OptionsError::ZeroDraws(t.name().into_owned()));
            }
            if self.techniques[..i].iter().any(|(u, _)| u == t) {
                return Err(OptionsError::TechniqueTwice(t.name().into_owned()));
            }
        }
        for (i, a) in self.aovs.iter().enumerate() {
            if self.aovs[..i].contains(a) {
                return Err(OptionsError::AovTwice(a.name()));
            }
        }
        self.training
            .validate()
            .map_err(|(key, message)| OptionsError::Training { key, message })?;
        let deepest = match self.integrator {
            IntegratorKind::Direct => 1,
            _ => self.max_depth,
        };
        if uses_mis(self.integrator) && self.min_depth > deepest {
            return Err(OptionsError::MinDepth {
                min_depth: self.min_depth,
                deepest,
                integrator: self.integrator,
            });
        }
        Ok(self.params.validate()?)
    }
}
