//! # gpu — the GPU back end on wgpu
//!
//! The same renderer as the CPU's, on `wgpu` 30 with WGSL compute shaders, reading the same
//! resolved scene (`scene::SceneData`) and returning the same per-pixel sums
//! (`state::RenderState`), so that a GPU sample range merges with a CPU one
//! (../shared/GPU.md; DESIGN.md §2–§3). It holds GPU.md §12's steps 1–4: the kernel
//! twins, and the wavefront `direct` and `path` integrators ([`direct`], behind
//! `frepray render --backend gpu`); docs/gpu.md says what they cover, what they measured
//! and where they depart from GPU.md:
//!
//! - [`Gpu`]: adapter choice with the features frepray uses (f64, int64, subgroups,
//!   timestamps), each of which can be forced off ([`GpuOptions`], or the environment
//!   variables `FREPRAY_GPU_F64=off`, `FREPRAY_GPU_INT64=off`,
//!   `FREPRAY_GPU_SUBGROUPS=off`; `FREPRAY_GPU_SUMS=off` keeps the per-pixel sums on
//!   the CPU), and a clear error, never a panic, where there is no
//!   adapter or a device limit is too small;
//! - [`Kernel`]: one WGSL compute entry point over storage buffers, dispatched and read
//!   back (with [`Kernel::new_unchecked`], bounds checks off: GPU.md §3.4), for kernel
//!   twins and tests;
//! - [`layout`]: the flat scene's objects, quadrics, perturbations, BVH nodes (also in the
//!   escape layout) and item boxes as `#[repr(C)]`
//!   structs with their WGSL mirrors;
//! - [`quadric`]: rays against plain quadrics in WGSL, with the CPU f32 twin they equal
//!   bit for bit on lavapipe (GPU.md §3.5);
//! - [`perturbed`]: rays against perturbed quadrics in WGSL (frep's exact scan, GPU.md
//!   §6.1), equal bit for bit on lavapipe to frep's f32 twin, with overflow reported;
//! - [`tape`], [`tape_trace`]: expression tapes (frep's bytecode) in WGSL, at points and
//!   as outward-rounded intervals with dF/dt, and rays against expression solids (GPU.md
//!   §6.2), equal bit for bit on lavapipe to their CPU f32 twins;
//! - [`bsdf`]: BSDF evaluation and sampling of every material kind (diffuse, conductor,
//!   dielectric, plastic; rough and smooth) in WGSL, equal bit for bit on lavapipe to
//!   their CPU f32 twin;
//! - [`sampler`]: the CPU's random numbers (Philox4x32-10, `state::sampler`) in WGSL with
//!   32-bit operations only, equal bit for bit on every adapter;
//! - [`light`]: area lights (sphere, rect, disk) in WGSL: crossings, area and cone
//!   sampling with their pdfs, and light selection, equal bit for bit on lavapipe to
//!   their CPU f32 twins;
//! - [`mod@env`]: the environment light (a constant dome or a lat-long map) in WGSL:
//!   radiance lookup, importance sampling and its pdf, equal bit for bit on lavapipe to
//!   its CPU f32 twin;
//! - [`sums`]: per-pixel MIS sums in f64 where the device has `SHADER_F64`, else in
//!   laundered double-float (GPU.md §3.2, §8), exact on the compensated-sum check;
//! - [`record`]: each sample's terms of its pixel's record (what the CPU's accumulator
//!   adds), equal bit for bit on lavapipe to their CPU f32 twin, so that the integrators
//!   keep the per-pixel sums on the GPU;
//! - [`progressive`]: the progressive optimal estimators' sums, α applied in sample
//!   order by a pass per pixel that stops where the CPU must re-solve α;
//! - [`direct`]: the scene packed into buffers and the `direct` and `path` integrators
//!   (camera, shade, shadow and continuation passes per wave), their samples summed into
//!   a `state::RenderState` on the GPU.
//!
//! On machines without a GPU, tests run on Mesa's lavapipe (`mesa-vulkan-drivers`). They
//! skip, saying so, where no adapter exists, unless `FREPRAY_REQUIRE_GPU=1` (set by
//! `scripts/test.sh`), where a missing adapter fails them (GPU.md §11.1).
//!
//! ```no_run
//! let gpu = gpu::Gpu::new(&gpu::GpuOptions::from_env()).unwrap();
//! println!("{}", gpu.info());
//! ```
#![warn(missing_docs)]

mod adapter;
pub mod bsdf;
pub mod cell_tapes;
pub mod direct;
pub mod elementary;
pub mod env;
mod kernel;
pub mod layout;
pub mod light;
pub mod noise;
pub mod perturbed;
pub mod progressive;
pub mod quadric;
pub mod r_bound;
mod readback;
pub mod record;
pub mod sampler;
pub mod stats;
pub mod sums;
pub mod tape;
pub mod tape_trace;

pub use adapter::{adapters, AdapterSummary, Gpu, GpuError, GpuInfo, GpuOptionError, GpuOptions};

/// WGSL float helpers the kernels share (`inf`, `nan`, `is_nan`, `is_finite`, and `rmin`,
/// `rmax` as Rust's f32 `min`/`max`): prepend once to a kernel that uses
/// [`perturbed::PERTURBED_WGSL`] or a tape ([`tape_trace::TapeSolid::scene_wgsl`] includes it).
pub const FLOAT_WGSL: &str = include_str!("shaders/float.wgsl");

/// The trigonometric polynomials the kernels share (`sincos_small`, `env_atan01`,
/// `env_atan2`): the lights, the environment and the expression tapes' `sin`, `cos` and
/// `atan2`; their Rust twins are [`light::sincos_small`], [`env::atan01`], [`env::atan2`].
pub const TRIG_WGSL: &str = include_str!("shaders/trig.wgsl");

pub use kernel::Kernel;

/// Workgroups (x, y) of 64 invocations for `n` invocations of a kernel that reads its
/// index as `id.x + id.y · groups.x · 64`: split over y past the 65 535 a dimension may
/// hold.
pub(crate) fn workgroups(n: u32) -> (u32, u32) {
    let g = n.div_ceil(64);
    if g <= 65_535 {
        (g, 1)
    } else {
        (65_535, g.div_ceil(65_535))
    }
}

/// One compute pass of `pipeline` over `n` invocations (bind group 0: `group`), with
/// the pass's timestamp writes if any.
pub(crate) fn dispatch(
    enc: &mut wgpu::CommandEncoder,
    timestamps: Option<wgpu::ComputePassTimestampWrites>,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    n: u32,
) {
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: None,
        timestamp_writes: timestamps,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    let (gx, gy) = workgroups(n);
    pass.dispatch_workgroups(gx, gy, 1);
}

/// A bind group of whole buffers at bindings 0, 1, … in order.
pub(crate) fn bind_buffers<'a>(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: impl IntoIterator<Item = &'a wgpu::Buffer>,
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .into_iter()
        .enumerate()
        .map(|(k, b)| wgpu::BindGroupEntry {
            binding: k as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// An f64 vector and a fourth word as the kernels' vec4<f32>.
pub(crate) fn f4(v: [f64; 3], w: f64) -> [f32; 4] {
    [v[0] as f32, v[1] as f32, v[2] as f32, w as f32]
}
