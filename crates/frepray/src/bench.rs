//! Throughput of a scene's `direct` and `path` renders on each back end: the rows of
//! `frepray bench` (MSamples/s, MRays/s by kind of ray) and each render's stage times
//! (the paper's Fig. 4–5), for the command line and Python alike.

use crate::{Backend, Error, IntegratorKind, RenderOptions, RenderStats, Scene};
use std::ops::Range;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// One measured render.
#[derive(Clone, Debug)]
pub struct BenchRow {
    /// Where it ran ([`Backend::Cpu`] or [`Backend::Gpu`]).
    pub backend: Backend,
    /// Its integrator.
    pub integrator: IntegratorKind,
    /// Samples, rays and time (the CPU's stage times from a second, timed render of the
    /// same samples: the timers slow a render by a few per cent).
    pub stats: RenderStats,
    /// The GPU's own statistics, where it ran there.
    pub gpu: Option<crate::backend::GpuStats>,
}

impl BenchRow {
    /// The render's time per stage, with the stages' names: the CPU's summed over its
    /// worker threads, the GPU's from its timestamp queries.
    pub fn stage_parts(&self) -> Vec<(&'static str, Duration)> {
        if let Some(g) = &self.gpu {
            return g.stage_parts().to_vec();
        }
        let st = self.stats.rays.stages();
        vec![
            ("camera ray generation", st.generate),
            ("camera rays", st.camera),
            ("shade (sampling, BSDFs, lights, MIS)", st.shade),
            ("shadow rays", st.shadow),
            ("continuation rays", st.secondary),
        ]
    }
}

/// One CPU render in [`render::integrator::TIMED_EVERY`] queries of each kind is timed
/// for the stage times.
pub const TIMED_EVERY: u64 = render::integrator::TIMED_EVERY;

/// Renders `scene` with `direct` and with `path` (`options` otherwise unchanged) on each
/// of `backends` (`cpu`, `gpu`; `auto` is refused: a measurement names its back end)
/// and returns the rows in that order. Both integrators are checked against the memory
/// limit first. On the GPU, a first 1-spp render compiles the kernels and is not timed
/// (GPU.md §10). A set `stop` ends the measurement with the rows finished.
pub fn bench(
    scene: &Scene,
    options: &RenderOptions,
    backends: &[Backend],
    stop: &AtomicBool,
) -> Result<Vec<BenchRow>, Error> {
    if backends.contains(&Backend::Auto) {
        return Err(Error::Invalid(
            "bench measures a named back end: cpu or gpu, not auto".into(),
        ));
    }
    let (width, height) = scene.resolution();
    let per = |integrator| RenderOptions {
        integrator,
        scene_hash: scene.hash(),
        ..options.clone()
    };
    let kinds = [IntegratorKind::Direct, IntegratorKind::Path];
    for k in kinds {
        render::limits::check_memory(width, height, &per(k))?;
    }
    let mut rows = Vec::new();
    for &backend in backends {
        if backend == Backend::Cpu {
            let stats = render::render_loop::bench(scene.cpu(), &per(kinds[0]), stop)?;
            rows.extend(stats.into_iter().map(|stats| BenchRow {
                backend,
                integrator: stats.integrator,
                stats,
                gpu: None,
            }));
            continue;
        }
        for integrator in kinds {
            let o = per(integrator);
            let on_gpu = |r: Range<u32>| scene.render_on(Backend::Gpu, &o, r, stop, &|_, _| {});
            on_gpu(0..1)?;
            let r = on_gpu(0..o.spp)?;
            rows.push(BenchRow {
                backend,
                integrator,
                stats: r.stats,
                gpu: r.gpu,
            });
        }
    }
    Ok(rows)
}
