//! The render loop: tiles rendered in parallel (rayon), in passes of samples, with
//! progress, a stop flag and end-of-render statistics.
//!
//! **Sample ranges.** A render sums samples `a..b` of every pixel into a [`RenderState`];
//! sample `i` of pixel (x, y) draws from the stream (seed, x, y, i) ([`crate::Sampler`]),
//! whatever the range it belongs to, so renders of disjoint ranges merge into the render
//! of their union ([`RenderState::merge`]).
//!
//! **Determinism.** Each pixel's samples run in index order on its own record, so the
//! state is the same bit for bit whatever the thread count or tile order (DESIGN.md §4).
//!
//! **Passes.** The samples are rendered in passes over the whole image, of 1, 1, 2, 4, …
//! samples per pixel doubling up to `pass_spp` (default spp/16), so that a stopped
//! render is the whole image at fewer samples; within a pass every tile is one rayon
//! task. Each tile's records stay with it across passes, so the
//! progressive optimal estimators see each pixel's iterations in order. The stop flag is
//! read before every sample (a relaxed atomic load, far below a sample's cost): once
//! set, each thread finishes the sample it is on and the render ends within one sample
//! at any `spp`; the state is then marked partial, and each pixel's estimate is still
//! correct for the whole samples it got (the pixels of a stopped render hold different
//! numbers of samples, 0 included). The batched engine ([`crate::integrator::Engine`])
//! reads the flag before each wave instead, so its render ends within one wave of up to
//! 64 samples per thread.
//!
//! **Statistics.** A *sample* is one iteration of a pixel: one camera ray with the draws
//! of every technique (DESIGN.md §4). Rays are counted exactly by kind (per tile, then
//! summed).

use crate::error::Error;
use crate::integrator::{Integrator, IntegratorKind, RayCounts, RenderOptions, Wave};
use crate::scene::Scene;
use rayon::prelude::*;
pub use state::RenderStats;
use state::{RenderState, StateHeader};
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

/// A rectangle of pixels with their records.
struct Tile {
    x0: u32,
    y0: u32,
    w: u32,
    h: u32,
    records: Vec<f64>,
    rays: RayCounts,
    samples: u64,
}

impl Tile {
    /// Samples `start..end` of every pixel, each pixel's in index order, until `stop`
    /// is set: it is read before every sample (before every wave by the batched
    /// engine), so that a pixel's record always holds whole samples and a stop takes
    /// effect within one sample (one wave). A pixel whose record
    /// already holds samples past `start` (a resumed render: `first` + its count N)
    /// starts after them. Returns the samples rendered.
    fn render(
        &mut self,
        it: &Integrator,
        scene: &Scene,
        (first, start, end): (u32, u32, u32),
        stop: &AtomicBool,
    ) -> u64 {
        let started = Instant::now();
        let n = if it.batched(scene) {
            self.render_waves(it, scene, (first, start, end), stop)
        } else {
            self.render_per_ray(it, scene, (first, start, end), stop)
        };
        self.samples += n;
        self.rays.busy_ns += started.elapsed().as_nanos() as u64;
        n
    }

    /// [`Self::render`] by the per-ray engine: each pixel's samples in turn.
    fn render_per_ray(
        &mut self,
        it: &Integrator,
        scene: &Scene,
        (first, start, end): (u32, u32, u32),
        stop: &AtomicBool,
    ) -> u64 {
        let stride = it.record.stride();
        let mut n = 0;
        'pixels: for (k, rec) in self.records.chunks_exact_mut(stride).enumerate() {
            let (i, j) = (k as u32 % self.w, k as u32 / self.w);
            let next = first.saturating_add(rec[0] as u32).max(start);
            for s in next..end {
                if stop.load(Ordering::Relaxed) {
                    break 'pixels;
                }
                it.sample(scene, self.x0 + i, self.y0 + j, s, rec, &mut self.rays);
                n += 1;
            }
        }
        n
    }

    /// [`Self::render`] by the batched engine: the samples in [`Wave`]s, sample index by
    /// sample index over the tile's pixels, so that a wave never holds two samples of
    /// one pixel and each pixel's samples run in index order; `stop` is read before each
    /// wave, so a stop takes effect within one wave ([`crate::integrator::Wave`]'s
    /// `BATCH` samples) and records still hold whole samples.
    fn render_waves(
        &mut self,
        it: &Integrator,
        scene: &Scene,
        (first, start, end): (u32, u32, u32),
        stop: &AtomicBool,
    ) -> u64 {
        let stride = it.record.stride();
        let next: Vec<u32> = self
            .records
            .chunks_exact(stride)
            .map(|rec| first.saturating_add(rec[0] as u32).max(start))
            .collect();
        let mut wave = Wave::new(it);
        let mut n = 0;
        for s in start..end {
            for (k, _) in next.iter().enumerate().filter(|&(_, &from)| s >= from) {
                let (i, j) = (k as u32 % self.w, k as u32 / self.w);
                wave.push(k, self.x0 + i, self.y0 + j, s);
                if wave.is_full() {
                    if stop.load(Ordering::Relaxed) {
                        return n;
                    }
                    n += it.run_wave(scene, &mut wave, &mut self.records, stride, &mut self.rays);
                }
            }
            if !wave.is_empty() {
                if stop.load(Ordering::Relaxed) {
                    return n;
                }
                n += it.run_wave(scene, &mut wave, &mut self.records, stride, &mut self.rays);
            }
        }
        n
    }
}

/// Renders samples `0..options.spp` of `scene` (see [`render_range`]).
pub fn render(
    scene: &Scene,
    options: &RenderOptions,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(RenderState, RenderStats), Error> {
    render_range(scene, options, 0..options.spp, stop, progress)
}

/// Renders samples `samples` of every pixel of `scene` with `options` (whose `spp` is
/// ignored) into a new [`RenderState`]. `progress(done, total)` is called (from worker
/// threads) after each tile of each pass with the samples done so far; setting `stop`
/// ends the render within one sample of each thread (module docs). Errors on invalid options or
/// an empty range.
pub fn render_range(
    scene: &Scene,
    options: &RenderOptions,
    samples: Range<u32>,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(RenderState, RenderStats), Error> {
    render_into(scene, options, samples, None, stop, progress)
}

/// Renders the samples a stopped render's `partial` state lacks — each pixel from where it
/// stopped to the end of the state's range — into a copy of it: the result is bit for bit
/// the state of the render that was not stopped, since each pixel's samples still run in
/// index order on its own record. `options` must describe the same render (the state's
/// header, scene hash included); its `spp` is ignored. Errors on a state that is not
/// partial, holds several ranges (a merge) or does not match `options`.
pub fn resume(
    scene: &Scene,
    options: &RenderOptions,
    partial: &RenderState,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(RenderState, RenderStats), Error> {
    let range = match partial.samples() {
        [r] => r.clone(),
        r => {
            return Err(Error::Resume(format!(
                "a state to resume holds the one sample range of a stopped render, not {}",
                if r.is_empty() {
                    "none".to_string()
                } else {
                    format!("{} ranges (a merge)", r.len())
                }
            )))
        }
    };
    if !partial.is_partial() {
        return Err(Error::Resume(format!(
            "nothing to resume: the state holds all of samples {}..{}",
            range.start, range.end
        )));
    }
    let (width, height) = (scene.camera.width, scene.camera.height);
    let mine = StateHeader::new(width, height, options);
    if *partial.header() != mine {
        return Err(Error::Mismatch(partial.header().difference(&mine)));
    }
    render_into(scene, options, range, Some(partial), stop, progress)
}

/// [`render_range`], continuing `from`'s records where given ([`resume`]).
fn render_into(
    scene: &Scene,
    options: &RenderOptions,
    samples: Range<u32>,
    from: Option<&RenderState>,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(RenderState, RenderStats), Error> {
    if samples.is_empty() {
        return Err(Error::EmptyRange(samples));
    }
    let o = RenderOptions {
        spp: samples.end - samples.start,
        ..options.clone()
    };
    let mut it = Integrator::new(&o)?;
    it.prepare(scene)?;
    let (width, height) = (scene.camera.width, scene.camera.height);
    crate::limits::check_threads(o.threads)?;
    crate::limits::check_memory(width, height, &o)?;
    let mut state = RenderState::new(StateHeader::new(width, height, &o), samples.clone())?;
    let stride = it.record.stride();
    let ts = o.tile_size;
    let mut tiles = Vec::new();
    let mut before = 0;
    for y0 in (0..height).step_by(ts as usize) {
        for x0 in (0..width).step_by(ts as usize) {
            let (w, h) = (ts.min(width - x0), ts.min(height - y0));
            let mut records = crate::limits::zeroed((w * h) as usize * stride, "a tile's records")?;
            if let Some(from) = from {
                let row = w as usize * stride;
                for j in 0..h as usize {
                    let at = ((y0 as usize + j) * width as usize + x0 as usize) * stride;
                    records[j * row..(j + 1) * row].copy_from_slice(&from.data()[at..at + row]);
                }
                before += records
                    .iter()
                    .step_by(stride)
                    .map(|&n| n as u64)
                    .sum::<u64>();
            }
            tiles.push(Tile {
                x0,
                y0,
                w,
                h,
                records,
                rays: RayCounts::new(o.stage_times),
                samples: 0,
            });
        }
    }
    let spp = o.spp;
    let cap = if o.pass_spp == 0 {
        spp.div_ceil(16)
    } else {
        o.pass_spp.min(spp)
    };
    let total = u64::from(width) * u64::from(height) * u64::from(spp);
    let done = AtomicU64::new(before);
    let started = Instant::now();
    let run = |tiles: &mut Vec<Tile>| -> usize {
        let mut start = samples.start;
        while start < samples.end && !stop.load(Ordering::Relaxed) {
            let end = start
                .saturating_add(pass_len(start - samples.start, cap))
                .min(samples.end);
            tiles.par_iter_mut().for_each(|tile| {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                let n = tile.render(&it, scene, (samples.start, start, end), stop);
                progress(done.fetch_add(n, Ordering::Relaxed) + n, total);
            });
            start = end;
        }
        rayon::current_num_threads()
    };
    let threads = if o.threads > 0 {
        rayon::ThreadPoolBuilder::new()
            .num_threads(o.threads)
            .build()
            .map_err(|e| Error::ThreadPool(e.to_string()))?
            .install(|| run(&mut tiles))
    } else {
        run(&mut tiles)
    };
    let mut rays = RayCounts::default();
    let mut count = 0;
    let data = state.data_mut();
    for t in &tiles {
        rays += t.rays;
        count += t.samples;
        let row = t.w as usize * stride;
        for j in 0..t.h as usize {
            let at = ((t.y0 as usize + j) * width as usize + t.x0 as usize) * stride;
            data[at..at + row].copy_from_slice(&t.records[j * row..(j + 1) * row]);
        }
    }
    let stopped = before + count < total;
    if stopped {
        state.set_partial();
    }
    let stats = RenderStats {
        integrator: o.integrator,
        wall: started.elapsed(),
        samples: count,
        samples_requested: total - before,
        rays,
        stopped,
        threads,
    };
    Ok((state, stats))
}

/// The samples per pixel of the pass that starts `done` samples into a render: 1, 1, 2,
/// 4, … doubling up to `cap`, so that a stopped render is the whole image at fewer
/// samples (after the first pass, every pixel has one) rather than finished tiles
/// beside black ones, and the passes stay few.
fn pass_len(done: u32, cap: u32) -> u32 {
    done.max(1).min(cap.max(1))
}

/// Throughput of `direct` and `path` on `scene` with `options` otherwise unchanged, for
/// the CLI's `bench` command: one render each, no progress, the statistics in that order
/// (a set `stop` ends the render in flight and skips the rest), each with the stage
/// times ([`RayCounts::stages`]) of a second, timed render of the same samples.
pub fn bench(
    scene: &Scene,
    options: &RenderOptions,
    stop: &AtomicBool,
) -> Result<Vec<RenderStats>, Error> {
    let mut out = Vec::new();
    for integrator in [IntegratorKind::Direct, IntegratorKind::Path] {
        if stop.load(Ordering::Relaxed) {
            break;
        }
        let o = RenderOptions {
            integrator,
            ..options.clone()
        };
        let mut stats = render(scene, &o, stop, &|_, _| {})?.1;
        // The stages from a second, timed render of the same samples (the timers slow a
        // render by a few per cent, so the throughput comes from the untimed one).
        let timed = RenderOptions {
            stage_times: true,
            ..o
        };
        if !stop.load(Ordering::Relaxed) {
            let t = render(scene, &timed, stop, &|_, _| {})?.1;
            if t.rays.total() == stats.rays.total() {
                stats.rays.timed_ns = t.rays.timed_ns;
                stats.rays.busy_ns = t.rays.busy_ns;
                stats.rays.timing = true;
            }
        }
        out.push(stats);
    }
    Ok(out)
}
