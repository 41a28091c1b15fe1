//! What is wrong with a render's options: each case with the values that make it wrong,
//! so that a front end can word it or act on it.

use crate::options::MAX_TECHNIQUES;
use scene::IntegratorKind;

/// Render options that cannot run ([`crate::RenderOptions::validate`],
/// [`crate::Tally::new`]) or do not fit the scene (`render::integrator`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OptionsError {
    /// No samples per pixel.
    #[error("spp must be at least 1")]
    ZeroSpp,
    /// Tiles of no pixels.
    #[error("tile size must be at least 1")]
    ZeroTileSize,
    /// An integrator that combines techniques, without one.
    #[error("integrator {0} needs at least one technique")]
    NoTechniques(IntegratorKind),
    /// More than [`MAX_TECHNIQUES`] techniques (the number given).
    #[error("at most {MAX_TECHNIQUES} techniques, got {0}")]
    TooManyTechniques(usize),
    /// A technique with no draws per vertex (its name).
    #[error("technique {0} needs at least 1 draw")]
    ZeroDraws(String),
    /// A technique listed twice (its name).
    #[error("technique {0} listed twice")]
    TechniqueTwice(String),
    /// An AOV listed twice (its name).
    #[error("AOV {0} listed twice")]
    AovTwice(&'static str),
    /// An AOV name that is none of depth, normal, albedo.
    #[error("unknown AOV {0:?}; valid names: depth, normal, albedo")]
    UnknownAov(String),
    /// A setting of the `light-trained` training pass out of range.
    #[error("{key}: {message}")]
    Training {
        /// The setting's key in a scene file.
        key: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// A minimum depth below which nothing is shaded: the image would be black.
    #[error(
        "min_depth {min_depth} exceeds the deepest vertex {deepest} ({}): the image would be \
         black",
        if *.integrator == IntegratorKind::Direct { "direct shades one vertex" } else { "max_depth" }
    )]
    MinDepth {
        /// The minimum depth asked for.
        min_depth: u32,
        /// The deepest vertex the integrator shades.
        deepest: u32,
        /// The integrator.
        integrator: IntegratorKind,
    },
    /// A heuristic's or estimator's parameter out of range.
    #[error(transparent)]
    Params(#[from] mis::ParamError),
    /// More MIS blocks per pixel than a record can address.
    #[error(
        "{depths} depths × {lights} lights of MIS estimators are more than a pixel's record \
         can hold"
    )]
    RecordTooLarge {
        /// Vertex depths with blocks.
        depths: usize,
        /// Blocks per depth.
        lights: usize,
    },
    /// More random dimensions per sample than 32 bits address.
    #[error(
        "{draws} draws per vertex at depth {max_depth} need {needed} random dimensions per \
         sample; at most {} are available",
        u32::MAX
    )]
    TooManyDimensions {
        /// Draws per vertex.
        draws: u64,
        /// The maximum depth.
        max_depth: u32,
        /// The dimensions a sample would need.
        needed: u64,
    },
    /// Per-light mode for another number of lights than the scene has.
    #[error("per-light mode for {per_light} lights, but the scene has {lights} MIS lights")]
    PerLightMismatch {
        /// The number the options give.
        per_light: usize,
        /// The scene's MIS lights.
        lights: usize,
    },
    /// Per-light mode in a scene with emitting objects, whose light is not a domain of
    /// directions of its own (their proxies have no surface).
    #[error(
        "per-light mode does not take emitting objects (materials with `emission`); \
         render without --per-light"
    )]
    PerLightEmittingObjects,
    /// `light#k` with k past the scene's MIS lights.
    #[error(
        "technique {technique}: the scene has {lights} MIS light{} (area lights, then the \
         environment), numbered from 0",
        if *.lights == 1 { "" } else { "s" }
    )]
    NoSuchLight {
        /// The technique's name.
        technique: String,
        /// The scene's MIS lights.
        lights: usize,
    },
    /// A byte size that does not read ([`crate::limits::parse_bytes`]).
    #[error("{0:?}: expected a size such as 512M, 4G or 1073741824")]
    BadSize(String),
}
