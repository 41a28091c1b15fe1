//! The `direct` and `path` integrators on the GPU: the resolved scene packed into
//! buffers, wavefront kernels (shaders/direct_*.wgsl: camera rays with their nearest hits,
//! the techniques' draws with every pdf, shadow rays, the paths' continuation rays), and
//! the CPU's per-pixel records filled from them (GPU.md §7–§8, first version).
//!
//! **Bands and waves.** The image is rendered in bands of consecutive pixels, each
//! through all its samples before the next, so that the buffers hold one band whatever
//! the image's size. A wave is m sample indices of every pixel of a band (m × band
//! slots, at most [`WAVE_DRAWS`] draws over all depths). Its passes (the camera trace, then per depth
//! shade, shadow rays and, but at the last depth, the continuation trace) run in one
//! submission without a CPU wait.
//!
//! **Sums.** Two more passes of the same submission keep the per-pixel sums on the GPU
//! ([`crate::record`]): each slot's f32 terms, then the sums in f64 (`SHADER_F64`) or
//! double-float, pixel by pixel in sample order; only a small tally (ray counts,
//! overflowing slots) is read back per wave, and the sums once at the end, into the
//! same [`RenderState`](state::RenderState) as the CPU's. The progressive estimators'
//! second pass applies α and stops each pixel where its schedule re-solves α, which the
//! CPU does between passes ([`crate::progressive`]). Otherwise (`FREPRAY_GPU_SUMS=off`;
//! sums too large for one binding or the loop budget) the hits and draws are read back
//! and added by [`state::Tally`], the CPU integrator's own
//! bookkeeping, in f64.
//! Either way the optimal estimators' solves are the CPU's and a GPU sample range
//! merges with a CPU one.
//!
//! **Same numbers, not the same image.** The kernels draw the CPU's random numbers
//! (`state::sampler`, truncated to 24 bits) in the CPU's dimension layout, Russian
//! roulette included, so a GPU render follows the CPU's paths closely, but in f32:
//! images agree statistically (GPU.md §9), tested by `tests/direct_image.rs`.
//!
//! **Overflow.** A ray whose perturbed-quadric scan runs past its fixed capacity
//! (K = 32 active perturbations after 4 halvings), whose tape trace stays undecided, or
//! whose CSG spans overflow, is never taken as a miss: the CPU renders that whole sample
//! instead, and the statistics count it.
//!
//! **Scope.** Objects that are one perturbed or plain quadric, a CSG tree (boxes,
//! capped cylinders, unions, differences: by inside spans along the ray, the nodes in
//! post-order from the root; a perturbed or expression part's spans from its crossings
//! found one by one, as frep's `Solid::combine` finds them), or an expression solid (any
//! number per scene, within the device's storage binding: their tapes share one
//! interpreter, GPU.md §6.2); diffuse, conductor, dielectric and plastic materials
//! rough or smooth (delta lobes outside MIS, as the CPU), with constant or point-space checker colours; sphere,
//! rectangle and disk lights, point and spot lights, a constant or mapped environment
//! ([`crate::env`]); the techniques `bsdf`, `light`, `light-uniform`, `light-area`,
//! `light-spatial`, `light-trained` (the table the CPU trained), `light#k`,
//! `environment` and `cosine`; every MIS method, per light too; AOVs and the AOV integrators;
//! participating media inside solids behind `interface` or other boundaries, the camera
//! inside one too (walks through boundaries, free flights and phase-function vertices, as
//! `render::integrator::medium`; docs/gpu.md); `path` up to depth
//! [`MAX_GPU_DEPTH`]. Anything else is a
//! [`GpuError::Unsupported`](crate::GpuError::Unsupported) naming it, before any work.
//!
//! **Rooms.** `pack` turns the scene into the kernels' structs ([`DirectScene`]),
//! `pipelines` assembles and compiles the kernels' WGSL (kept by [`Gpu`](crate::Gpu)),
//! `buffers` makes the storage buffers and bind groups, `probe` runs the nearest-hit
//! query on a ray batch ([`probe()`]), `waves` runs bands and waves ([`render_range`]),
//! and `accumulate` adds read-back waves to the records on the CPU ([`add_slot`]).

mod accumulate;
mod buffers;
mod pack;
pub(crate) mod pipelines;
mod probe;
mod waves;

pub use crate::record::{draw_words, DRAW_HEAD_WORDS, HIT_WORDS};
pub use crate::stats::{GpuStats, StageTimes, SumsOn};
pub use accumulate::add_slot;
pub use pack::{DirectScene, GpuMaterial, GpuShape, GpuTexture, INTERFACE, NO_MEDIUM, TEX_SLOTS};
pub use probe::{probe, Probe};
pub use waves::{render_range, render_range_with, RenderJob, WaveOptions};

/// The WGSL of the three kernels (without the helpers they include and the wave records'
/// constants, [`crate::record::wave_consts_wgsl`]), by stage: the bindings and record
/// layout, random numbers and frames, shapes, CSG, the scene query and normals, lights
/// and pdfs, the trace kernel, the shade and prepare kernels.
pub const DIRECT_WGSL: &str = concat!(
    include_str!("../shaders/direct_bindings.wgsl"),
    "\n",
    include_str!("../shaders/direct_sampling.wgsl"),
    "\n",
    include_str!("../shaders/direct_shapes.wgsl"),
    "\n",
    include_str!("../shaders/direct_csg.wgsl"),
    "\n",
    include_str!("../shaders/direct_scene.wgsl"),
    "\n",
    include_str!("../shaders/direct_lights.wgsl"),
    "\n",
    include_str!("../shaders/direct_trace.wgsl"),
    "\n",
    include_str!("../shaders/direct_shade.wgsl"),
);

/// At most this many draws (slots × draws per slot) per wave: 40 MiB of draw records.
pub const WAVE_DRAWS: u32 = 1 << 19;

/// Techniques the kernels can hold: as many as a render may list.
pub const MAX_GPU_TECHNIQUES: usize = crate::record::MAX_DRAW_TECHNIQUES;

/// The deepest `path` the GPU renders (a uniform block per depth and pass).
pub const MAX_GPU_DEPTH: u32 = 64;
