//! What a back end that shades on its own (the GPU) takes from the CPU renderer of the
//! same scene and options (GPU.md §8): the records' bookkeeping, the tables the CPU
//! computes in f64 (a plastic coat's albedo, the area lights' importance bounds, the
//! trained light selection), and the samples it could not finish. The CPU back end
//! implements it (`render::integrator::CpuHost`), so that the two back ends stand side
//! by side on this crate and neither imports the other.

use crate::counts::RayCounts;
use crate::tally::Tally;
use crate::trained::TrainedSelection;
use glam::DVec3;

/// A plastic coat's directional albedo at the cosines asked for, and its internal
/// diffuse reflectance (`render::bsdf::CoatTable`).
#[derive(Clone, Debug, PartialEq)]
pub struct CoatAlbedo {
    /// E_coat(μ) at each μ asked for.
    pub albedo: Vec<f64>,
    /// R_int.
    pub r_int: f64,
}

/// What the spatial light selection's importance reads of an area light
/// (`render::light::ImportanceBounds`, pbrt-v4 §12.6.3): its bounding sphere, its normal
/// cone, and the luminance of its power.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    /// Centre of the bounding sphere.
    pub center: DVec3,
    /// Its radius.
    pub radius: f64,
    /// Axis of the normal cone.
    pub axis: DVec3,
    /// cos θo.
    pub cos_o: f64,
    /// Whether the cone counts on both sides.
    pub two_sided: bool,
    /// Luminance of the emitted power.
    pub power: f64,
}

/// One node of a light BVH (`render::light::LightTree`, Conty Estevez & Kulla 2018):
/// the bounds of the lights below it with their total power, and its light (a leaf) or
/// its second child's index (an inner node, whose first child follows it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightTreeNode {
    /// The bounds and the luminance of the power of the lights below.
    pub bounds: LightBounds,
    /// A leaf's light, or an inner node's second child.
    pub index: u32,
    /// Whether the node is a leaf.
    pub leaf: bool,
}

/// A light BVH over the area lights as another back end reads it: its nodes in depth-first
/// order (the root first), and per light the path to its leaf (bit d set where it takes
/// the second child at depth d) with the path's length.
#[derive(Clone, Debug, PartialEq)]
pub struct LightTreeTable {
    /// The nodes.
    pub nodes: Vec<LightTreeNode>,
    /// Per light: (trail, depth).
    pub trails: Vec<(u64, u8)>,
}

/// The CPU renderer of one scene and one set of render options, as another back end
/// sees it.
pub trait Host: Sync {
    /// The records' bookkeeping of this render.
    fn tally(&self) -> &Tally;
    /// The light selection trained for this render (`light-trained`), if it has one.
    fn trained(&self) -> Option<&TrainedSelection>;
    /// The albedo table of a plastic coat of index `eta` and GGX roughness `alpha`, at
    /// the cosines `mu`.
    fn coat_albedo(&self, eta: f64, alpha: f64, mu: &[f64]) -> CoatAlbedo;
    /// The importance bounds of an area light of the scene's data (None for a light
    /// that is not an area light).
    fn light_bounds(&self, light: &scene::Light) -> Option<LightBounds>;
    /// The light BVH of `light-bvh` over the scene's area lights, in their order (None
    /// without an area light).
    fn light_tree(&self) -> Option<LightTreeTable>;
    /// Renders sample `index` of pixel (x, y) on the CPU into its record `rec`, for the
    /// samples the other back end could not finish (a ray past a fixed capacity).
    fn cpu_sample(&self, x: u32, y: u32, index: u32, rec: &mut [f64], rays: &mut RayCounts);
}
