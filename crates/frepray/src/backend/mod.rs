//! Where a render runs: the CPU, the GPU (wgpu; `direct` and `path`, docs/gpu.md lists
//! what it covers), or the GPU where it can and the CPU otherwise. Both back ends fill
//! the same [`RenderState`], so ranges rendered on either merge.

use crate::{Error, RenderOptions, RenderState, RenderStats, SceneData};
use render::render_loop;
use std::ops::Range;
use std::sync::atomic::AtomicBool;

#[cfg(feature = "gpu")]
pub use gpu::direct::GpuStats;
#[cfg(feature = "gpu")]
pub use gpu::{Gpu, GpuError, GpuInfo, GpuOptions};
#[cfg(not(feature = "gpu"))]
mod no_gpu;
#[cfg(not(feature = "gpu"))]
pub use no_gpu::{Gpu, GpuError, GpuInfo, GpuStats};

/// Where a scene is rendered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Backend {
    /// The CPU (every integrator and scene).
    #[default]
    Cpu,
    /// The GPU: an error, naming what is missing, where there is no adapter or the GPU
    /// back end does not cover the scene or options.
    Gpu,
    /// The GPU where there is one and it covers the scene, else the CPU.
    Auto,
}

impl Backend {
    /// The names, as `"cpu"`, `"gpu"`, `"auto"`.
    pub const fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::Gpu => "gpu",
            Backend::Auto => "auto",
        }
    }
}

impl std::str::FromStr for Backend {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "cpu" => Ok(Backend::Cpu),
            "gpu" => Ok(Backend::Gpu),
            "auto" => Ok(Backend::Auto),
            _ => Err(format!("backend {s:?}: expected cpu, gpu or auto")),
        }
    }
}

/// A render's result on either back end.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The samples' per-pixel sums.
    pub state: RenderState,
    /// Samples, rays, time.
    pub stats: RenderStats,
    /// The GPU's own statistics (stage times, waves, samples it left to the CPU) where
    /// it rendered.
    pub gpu: Option<GpuStats>,
    /// Why [`Backend::Auto`] rendered on the CPU.
    pub fallback: Option<String>,
}

/// The options the process's GPU opens with, when set before it opens.
#[cfg(feature = "gpu")]
static GPU_OPTIONS: std::sync::OnceLock<GpuOptions> = std::sync::OnceLock::new();

/// The process's GPU, opened once, with the options of [`configure_gpu`] or else
/// `GpuOptions::from_env` (`FREPRAY_GPU_*`): its compiled kernels are kept for every
/// later render (compiling them takes minutes on lavapipe).
#[cfg(feature = "gpu")]
pub fn shared_gpu() -> Result<&'static Gpu, GpuError> {
    static GPU: std::sync::OnceLock<Result<Gpu, GpuError>> = std::sync::OnceLock::new();
    GPU.get_or_init(|| Gpu::new(GPU_OPTIONS.get_or_init(GpuOptions::from_env)))
        .as_ref()
        .map_err(Clone::clone)
}

/// Sets the options the process's GPU opens with, over the environment's
/// (`FREPRAY_GPU_*`): `list` as [`GpuOptions::with`] reads it, e.g. `f64=off,checked`.
/// An error once the GPU has opened with other options (it opens once per process).
#[cfg(feature = "gpu")]
pub fn configure_gpu(list: &str) -> Result<GpuOptions, Error> {
    let want = GpuOptions::from_env()
        .with(list)
        .map_err(|e| Error::Invalid(e.to_string()))?;
    let have = *GPU_OPTIONS.get_or_init(|| want);
    if have != want {
        return Err(Error::Invalid(format!(
            "GPU options {list:?}: the GPU has already opened with {have:?} (once per process)"
        )));
    }
    Ok(have)
}

/// The GPU adapters the environment offers, a line each (`N: name (backend, type);
/// f64 …`): N is what `adapter=N` of [`configure_gpu`] names.
#[cfg(feature = "gpu")]
pub fn gpu_adapters() -> Result<Vec<String>, Error> {
    Ok(gpu::adapters().iter().map(ToString::to_string).collect())
}

/// There are no adapters to list in a build without the `gpu` feature.
#[cfg(not(feature = "gpu"))]
pub fn gpu_adapters() -> Result<Vec<String>, Error> {
    Err(Error::Gpu(GpuError::NotBuilt))
}

/// Without the GPU back end there is nothing to configure.
#[cfg(not(feature = "gpu"))]
pub fn configure_gpu(list: &str) -> Result<(), Error> {
    let _ = list;
    Err(Error::Gpu(GpuError::NotBuilt))
}

/// There is no GPU in a build without the `gpu` feature.
#[cfg(not(feature = "gpu"))]
pub fn shared_gpu() -> Result<&'static Gpu, GpuError> {
    Err(GpuError::NotBuilt)
}

/// Renders on the GPU, as [`render_range_on`] does ([`GpuError::NotBuilt`] without the
/// `gpu` feature).
fn gpu_range(
    data: &SceneData,
    scene: &render::scene::Scene,
    options: &RenderOptions,
    samples: Range<u32>,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(RenderState, RenderStats, GpuStats), GpuError> {
    let g = shared_gpu()?;
    #[cfg(feature = "gpu")]
    {
        let host = render::integrator::CpuHost::new(scene, options)
            .map_err(|e| GpuError::Unsupported(e.to_string()))?;
        let job = gpu::direct::RenderJob {
            data,
            host: &host,
            options,
            samples,
        };
        gpu::direct::render_range(g, &job, stop, progress)
    }
    #[cfg(not(feature = "gpu"))]
    {
        let _ = (g, data, scene, options, samples, stop, progress);
        Err(GpuError::NotBuilt)
    }
}

/// Whether `auto` may fall back to the CPU after this error: no adapter, a scene the
/// GPU does not cover, or no GPU back end built in.
fn may_fall_back(e: &GpuError) -> bool {
    #[cfg(feature = "gpu")]
    return matches!(e, GpuError::NoAdapter(_) | GpuError::Unsupported(_));
    #[cfg(not(feature = "gpu"))]
    matches!(e, GpuError::NotBuilt)
}

/// Renders samples `samples` of `scene` (built from `data`) with `options` on
/// `backend`, calling `progress(done, total)` as work finishes; setting `stop` ends the
/// render early with a partial state.
pub fn render_range_on(
    backend: Backend,
    data: &SceneData,
    scene: &render::scene::Scene,
    options: &RenderOptions,
    samples: Range<u32>,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Rendered, Error> {
    let mut fallback = None;
    if backend != Backend::Cpu {
        match gpu_range(data, scene, options, samples.clone(), stop, progress) {
            Ok((state, stats, g)) => {
                return Ok(Rendered {
                    state,
                    stats,
                    gpu: Some(g),
                    fallback: None,
                })
            }
            Err(e) if backend == Backend::Gpu => return Err(Error::Gpu(e)),
            Err(e) if may_fall_back(&e) => fallback = Some(e.to_string()),
            Err(e) => return Err(Error::Gpu(e)),
        }
    }
    let (state, stats) = render_loop::render_range(scene, options, samples, stop, progress)?;
    Ok(Rendered {
        state,
        stats,
        gpu: None,
        fallback,
    })
}
