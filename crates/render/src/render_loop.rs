//! The render loop: tiles rendered in parallel (rayon), in passes of samples, with
//! progress, a stop flag and end-of-render statistics.
//!
//! **Determinism.** Sample `i` of pixel (x, y) draws from the stream (seed, pixel, i)
//! ([`crate::Sampler`]) and each pixel's samples run in index order on its own state, so
//! the image is the same bit for bit whatever the thread count or tile order
//! (DESIGN.md §4).
//!
//! **Passes.** The samples are rendered in passes of `pass_spp` per pixel; within a pass
//! every tile is one rayon task. Per-pixel state (sums, and the [`mis`] estimators of
//! `direct` and optimal `path`) stays in its tile across passes, so the progressive
//! optimal estimators see each pixel's iterations in order. The stop flag is read before
//! each tile: once set, the tiles not yet started are skipped and the render ends, and
//! each pixel's value is still the correct estimate from the samples it got (the pixels of
//! a stopped render hold 0, 1 or more passes). At the end each pixel's value is written
//! into the [`Film`] as one sample (its estimate), with the AOV means.
//!
//! **Statistics.** A *sample* is one iteration of a pixel: one camera ray with the draws
//! of every technique (DESIGN.md §4). Rays are counted exactly by kind (per tile, then
//! summed).

use crate::film::Film;
use crate::integrator::{Aov, Integrator, IntegratorKind, PixelState, RayCounts, RenderOptions};
use crate::scene::Scene;
use rayon::prelude::*;
use std::fmt;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// What a render did and how fast.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderStats {
    /// The integrator.
    pub integrator: IntegratorKind,
    /// Wall time of the render (passes and film assembly).
    pub wall: Duration,
    /// Samples (pixel iterations) rendered.
    pub samples: u64,
    /// Samples asked for (pixels × spp).
    pub samples_requested: u64,
    /// Rays traced, by kind.
    pub rays: RayCounts,
    /// Whether the stop flag ended the render early.
    pub stopped: bool,
    /// Worker threads.
    pub threads: usize,
}

impl RenderStats {
    fn per_second(&self, n: u64) -> f64 {
        let s = self.wall.as_secs_f64();
        if s > 0.0 {
            n as f64 / s / 1e6
        } else {
            0.0
        }
    }
    /// Millions of samples per second.
    pub fn msamples_per_s(&self) -> f64 {
        self.per_second(self.samples)
    }
    /// Millions of rays per second, all kinds.
    pub fn mrays_per_s(&self) -> f64 {
        self.per_second(self.rays.total())
    }
    /// Millions of (camera, secondary, shadow) rays per second.
    pub fn mrays_per_s_by_kind(&self) -> (f64, f64, f64) {
        (
            self.per_second(self.rays.camera),
            self.per_second(self.rays.secondary),
            self.per_second(self.rays.shadow),
        )
    }
}

impl fmt::Display for RenderStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (c, s, sh) = self.mrays_per_s_by_kind();
        write!(
            f,
            "{}: {:.3} s on {} threads, {} samples{} ({:.3} MSamples/s); rays: {:.3} MRays/s \
             (camera {} = {:.3} M/s, secondary {} = {:.3} M/s, shadow {} = {:.3} M/s)",
            self.integrator,
            self.wall.as_secs_f64(),
            self.threads,
            self.samples,
            if self.stopped { " (stopped)" } else { "" },
            self.msamples_per_s(),
            self.mrays_per_s(),
            self.rays.camera,
            c,
            self.rays.secondary,
            s,
            self.rays.shadow,
            sh
        )
    }
}

/// A rectangle of pixels with their states.
struct Tile {
    x0: u32,
    y0: u32,
    w: u32,
    h: u32,
    pixels: Vec<PixelState>,
    rays: RayCounts,
    samples: u64,
}

impl Tile {
    /// Samples `start..end` of every pixel, each pixel's in index order.
    fn render(&mut self, it: &Integrator, scene: &Scene, start: u32, end: u32) {
        for j in 0..self.h {
            for i in 0..self.w {
                let px = &mut self.pixels[(j * self.w + i) as usize];
                for s in start..end {
                    it.sample(
                        scene,
                        self.x0 + i,
                        self.y0 + j,
                        u64::from(s),
                        px,
                        &mut self.rays,
                    );
                }
            }
        }
        self.samples += u64::from(self.w * self.h) * u64::from(end - start);
    }
}

/// Renders `scene` with `options`. `progress(done, total)` is called (from worker
/// threads) after each tile of each pass with the samples done so far; setting `stop`
/// ends the render after the tiles in flight (module docs). Errors on invalid options.
pub fn render(
    scene: &Scene,
    options: &RenderOptions,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Film, RenderStats), String> {
    let it = Integrator::new(options)?;
    let (width, height) = (scene.camera.width, scene.camera.height);
    let ts = options.tile_size;
    let mut tiles = Vec::new();
    for y0 in (0..height).step_by(ts as usize) {
        for x0 in (0..width).step_by(ts as usize) {
            let (w, h) = (ts.min(width - x0), ts.min(height - y0));
            tiles.push(Tile {
                x0,
                y0,
                w,
                h,
                pixels: (0..w * h).map(|_| it.pixel_state()).collect(),
                rays: RayCounts::default(),
                samples: 0,
            });
        }
    }
    let spp = options.spp;
    let pass = if options.pass_spp == 0 {
        spp.div_ceil(16)
    } else {
        options.pass_spp.min(spp)
    };
    let total = u64::from(width) * u64::from(height) * u64::from(spp);
    let done = AtomicU64::new(0);
    let started = Instant::now();
    let run = |tiles: &mut Vec<Tile>| -> usize {
        let mut start = 0;
        while start < spp && !stop.load(Ordering::Relaxed) {
            let end = (start + pass).min(spp);
            tiles.par_iter_mut().for_each(|tile| {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                tile.render(&it, scene, start, end);
                let n = u64::from(tile.w * tile.h) * u64::from(end - start);
                progress(done.fetch_add(n, Ordering::Relaxed) + n, total);
            });
            start = end;
        }
        rayon::current_num_threads()
    };
    let threads = if options.threads > 0 {
        rayon::ThreadPoolBuilder::new()
            .num_threads(options.threads)
            .build()
            .map_err(|e| format!("thread pool: {e}"))?
            .install(|| run(&mut tiles))
    } else {
        run(&mut tiles)
    };
    let names: Vec<&str> = options
        .aovs
        .iter()
        .flat_map(|a| a.channels().iter().copied())
        .collect();
    let mut film = Film::new(width, height, &names);
    let mut rays = RayCounts::default();
    let mut samples = 0;
    for t in &tiles {
        rays += t.rays;
        samples += t.samples;
        for j in 0..t.h {
            for i in 0..t.w {
                let px = &t.pixels[(j * t.w + i) as usize];
                if px.iterations == 0 {
                    continue;
                }
                let (x, y) = (t.x0 + i, t.y0 + j);
                film.add_sample(x, y, px.value());
                write_aovs(&mut film, &options.aovs, x, y, px);
            }
        }
    }
    let stats = RenderStats {
        integrator: options.integrator,
        wall: started.elapsed(),
        samples,
        samples_requested: total,
        rays,
        stopped: samples < total,
        threads,
    };
    Ok((film, stats))
}

fn write_aovs(film: &mut Film, aovs: &[Aov], x: u32, y: u32, px: &PixelState) {
    let mut channel = 0;
    for a in aovs {
        for k in 0..a.channels().len() {
            film.add_aov(x, y, channel, px.aov_mean(a.offset() + k));
            channel += 1;
        }
    }
}

/// Throughput of `direct` and `path` on `scene` with `options` otherwise unchanged, for
/// the CLI's `bench` command: one render each, no progress, the statistics in that order.
pub fn bench(scene: &Scene, options: &RenderOptions) -> Result<Vec<RenderStats>, String> {
    let stop = AtomicBool::new(false);
    [IntegratorKind::Direct, IntegratorKind::Path]
        .into_iter()
        .map(|integrator| {
            let o = RenderOptions {
                integrator,
                ..options.clone()
            };
            render(scene, &o, &stop, &|_, _| {}).map(|r| r.1)
        })
        .collect()
}
