//! Bands and waves: the render's setup (sizes, buffers, bind groups, the sums on the
//! GPU), each wave's passes encoded and submitted, its tally, timestamps and records
//! read back and added, each band's sums taken into the state, and the render's
//! statistics.

use super::accumulate::add_slot;
use super::buffers::{map_read, WaveBuffers, WavePasses, WaveShape};
use super::pack::DirectScene;
use super::pipelines::{kernels, Pipelines};
use super::{GpuStats, SumsOn};
use crate::readback::read_back;
use crate::record::{draw_words, GpuSums, WaveTally, HIT_WORDS};
use crate::{Gpu, GpuError};
use scene::SceneData;
use state::{Host, RayCounts, RenderOptions, RenderState, RenderStats, StateHeader};
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What a GPU render renders: samples `samples` of every pixel of the scene resolved as
/// `data`, with `options`; `host` is the CPU renderer of the same scene and options (its
/// tables, and the samples the GPU cannot finish: [`Host`]).
#[derive(Clone)]
pub struct RenderJob<'a> {
    /// The resolved scene.
    pub data: &'a SceneData,
    /// The CPU renderer of the same scene and options.
    pub host: &'a dyn Host,
    /// The render options.
    pub options: &'a RenderOptions,
    /// The sample range of every pixel.
    pub samples: Range<u32>,
}

/// Renders `job` on `gpu` into a [`RenderState`] that merges with CPU ones.
/// `progress(done, total)` is called after each wave; `stop` is read between waves (a
/// stopped render keeps its whole waves and is marked partial). Errors, before any
/// work, on what the GPU back end does not implement ([`GpuError::Unsupported`]).
pub fn render_range(
    gpu: &Gpu,
    job: &RenderJob,
    stop: &AtomicBool,
    progress: &dyn Fn(u64, u64),
) -> Result<(RenderState, RenderStats, GpuStats), GpuError> {
    let how = WaveOptions::for_device(gpu);
    render_range_with(gpu, job, stop, progress, &how)
}

/// How [`render_range_with`] runs its waves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WaveOptions {
    /// Where the per-pixel sums are kept: on the CPU, or on the GPU in f64 (where the
    /// device has it, else double-float) or double-float. The GPU falls back to the
    /// CPU's sums for records whose terms pass the loop budget (bands shrink so that
    /// their sums fit one binding);
    /// [`GpuStats::sums`] says where they were kept.
    pub sums: SumsOn,
    /// The most pixels a band covers (the image is rendered in bands of consecutive
    /// pixels, each through all its samples); None: as many as a wave of one sample
    /// index may hold ([`WAVE_DRAWS`](super::WAVE_DRAWS) draws).
    pub band_pixels: Option<u32>,
}

impl WaveOptions {
    /// The device's choice ([`GpuOptions`](crate::GpuOptions)' `f64` and `sums`),
    /// bands as large as a wave allows.
    pub fn for_device(gpu: &Gpu) -> Self {
        let sums = match (gpu.info().sums, gpu.info().f64) {
            (false, _) => SumsOn::Cpu,
            (true, true) => SumsOn::GpuF64,
            (true, false) => SumsOn::GpuDoubleFloat,
        };
        Self {
            sums,
            band_pixels: None,
        }
    }
}

/// [`render_range`] with the waves run as `how` says.
pub fn render_range_with(
    gpu: &Gpu,
    job: &RenderJob,
    stop: &AtomicBool,
    progress: &dyn Fn(u64, u64),
    how: &WaveOptions,
) -> Result<(RenderState, RenderStats, GpuStats), GpuError> {
    // A device error (validation, memory) becomes this render's error, not a panic of
    // wgpu's default handler.
    let invalid = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let memory = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let out = render_waves(gpu, job, stop, progress, how);
    let errors = [memory.pop(), invalid.pop()].map(pollster::block_on);
    match errors.into_iter().flatten().next() {
        Some(e) => Err(GpuError::Run(e.to_string())),
        None => out,
    }
}

fn render_waves(
    gpu: &Gpu,
    job: &RenderJob,
    stop: &AtomicBool,
    progress: &dyn Fn(u64, u64),
    how: &WaveOptions,
) -> Result<(RenderState, RenderStats, GpuStats), GpuError> {
    let samples = job.samples.clone();
    let o = RenderOptions {
        spp: samples.end.saturating_sub(samples.start),
        ..job.options.clone()
    };
    let (mut waves, mut totals) = Waves::new(gpu, job.data, job.host, &o, &samples, how)?;
    let pixels = waves.shape.pixels;
    let mut base = 0;
    while base < pixels {
        let band_len = waves.shape.band.min(pixels - base);
        waves.render_band(&mut totals, base, band_len, &samples, stop, progress)?;
        if stop.load(Ordering::Relaxed) {
            break;
        }
        base += band_len;
    }
    waves.finish(totals, &o)
}

/// The slots of one wave: slot s is pixel `base + s % band_len` of the band's
/// `band_len` pixels, at sample index `start + s / band_len`.
#[derive(Clone, Copy, Debug)]
struct WaveSlots {
    base: u32,
    band_len: u32,
    start: u32,
    slots: u32,
}

/// What a render has done so far.
struct Totals {
    state: RenderState,
    stats: GpuStats,
    rays: RayCounts,
    /// Slots rendered, of `total`.
    done: u64,
    total: u64,
    started: Instant,
}

/// What one wave read back: its records (where the CPU adds them), its tally (where
/// the GPU keeps the sums) and the time its passes took by their timestamps.
struct WaveRead {
    hits: Vec<u8>,
    draws: Vec<u8>,
    tally: Option<WaveTally>,
    passes_time: Duration,
}

/// One render's waves: the packed scene, kernels, sizes and buffers every band and
/// wave uses, and the sums on the GPU where they are kept there.
struct Waves<'a> {
    gpu: &'a Gpu,
    host: &'a dyn Host,
    pack: DirectScene,
    kernels: Arc<Pipelines>,
    shape: WaveShape,
    buffers: WaveBuffers,
    sums: Option<GpuSums>,
    /// Where the CPU adds the records: the hits' and draws' readbacks.
    readbacks: Option<(wgpu::Buffer, wgpu::Buffer)>,
    /// The loop maxima's readback.
    loops_r: wgpu::Buffer,
    passes: WavePasses,
}

impl<'a> Waves<'a> {
    /// The render's setup: the scene packed, the kernels, the sizes, buffers and bind
    /// groups, and the sums on the GPU where the record is a sum of per-sample terms
    /// and fits (else every wave's hits and draws are read back and added by the CPU).
    fn new(
        gpu: &'a Gpu,
        data: &SceneData,
        host: &'a dyn Host,
        o: &RenderOptions,
        samples: &Range<u32>,
        how: &WaveOptions,
    ) -> Result<(Self, Totals), GpuError> {
        let acc = host.tally();
        let mut pack = DirectScene::packed(data, o, host, Some(&gpu.kernels))?;
        let started = Instant::now();
        let kernels = kernels(gpu, &pack)?;
        let mut stats = GpuStats::default();
        let (w, h) = (data.camera.width, data.camera.height);
        let header = StateHeader::new(w, h, o);
        let state = RenderState::new(header, samples.clone())
            .map_err(|e| GpuError::Unsupported(e.to_string()))?;
        let (mut shape, linear) = WaveShape::new(gpu, acc, &pack, how, (w, h));
        let buffers = WaveBuffers::new(gpu, &mut pack, &shape)?;
        let sums = match linear {
            Some(linear) => GpuSums::new(
                gpu,
                &linear,
                acc.kernel(),
                shape.band,
                shape.max_slots as u32,
                (shape.n_draws, shape.nd1, shape.depths),
                &buffers.hits,
                &buffers.draws,
                how.sums == SumsOn::GpuF64,
            )?,
            None => None,
        };
        stats.sums = match &sums {
            None => SumsOn::Cpu,
            Some(s) if s.is_f64() => SumsOn::GpuF64,
            Some(_) => SumsOn::GpuDoubleFloat,
        };
        if let Some(s) = &sums {
            shape.per_wave = shape.per_wave.min(s.max_samples);
        }
        let readbacks = sums.is_none().then(|| {
            (
                map_read(gpu, "hits readback", shape.hit_bytes(shape.max_slots)),
                map_read(gpu, "draws readback", shape.draw_bytes(shape.max_slots)),
            )
        });
        let loops_r = map_read(gpu, "stats readback", 16);
        let passes = WavePasses::new(gpu, &kernels, &buffers, shape.depths);
        stats.stages.setup = started.elapsed();
        let totals = Totals {
            state,
            stats,
            rays: RayCounts::default(),
            done: 0,
            total: u64::from(shape.pixels) * u64::from(o.spp),
            started,
        };
        let waves = Self {
            gpu,
            host,
            pack,
            kernels,
            shape,
            buffers,
            sums,
            readbacks,
            loops_r,
            passes,
        };
        Ok((waves, totals))
    }

    /// Band `base..base + band_len` through `samples` (until `stop`), then its sums on
    /// the GPU into its pixels' records, and zero sums for the next band.
    fn render_band(
        &mut self,
        t: &mut Totals,
        base: u32,
        band_len: u32,
        samples: &Range<u32>,
        stop: &AtomicBool,
        progress: &dyn Fn(u64, u64),
    ) -> Result<(), GpuError> {
        self.pack.frame.pixels = band_len;
        self.pack.frame.wave[2] = base;
        let mut start = samples.start;
        while start < samples.end && !stop.load(Ordering::Relaxed) {
            let m = self.shape.per_wave.min(samples.end - start);
            self.render_wave(t, base, band_len, start, m)?;
            progress(t.done, t.total);
            start += m;
        }
        if let Some(sums) = self.sums.as_mut() {
            let time = Instant::now();
            let stride = self.shape.stride;
            let range = base as usize * stride..(base + band_len) as usize * stride;
            sums.add_to(self.gpu, &mut t.state.data_mut()[range])?;
            sums.reset(self.gpu);
            t.stats.stages.accumulate += time.elapsed();
        }
        Ok(())
    }

    /// One wave: sample indices `start..start + m` of the band's `band_len` pixels from
    /// `base`, encoded, submitted, read back and added to the records.
    fn render_wave(
        &mut self,
        t: &mut Totals,
        base: u32,
        band_len: u32,
        start: u32,
        m: u32,
    ) -> Result<(), GpuError> {
        let slots = m * band_len;
        self.write_frames(start, slots);
        let (enc, run) = self.encode_wave(band_len, start, m, slots);
        let t0 = Instant::now();
        self.gpu.queue.submit([enc.finish()]);
        let read = self.read_wave(t, slots, run)?;
        t.stats.stages.readback += t0.elapsed().saturating_sub(read.passes_time);
        let t1 = Instant::now();
        let wave = WaveSlots {
            base,
            band_len,
            start,
            slots,
        };
        if let Some(tally) = read.tally {
            self.add_tally(t, tally, &wave);
        }
        if self.readbacks.is_some() {
            self.add_on_cpu(t, &read.hits, &read.draws, &wave);
        }
        t.stats.stages.accumulate += t1.elapsed();
        t.stats.waves += 1;
        t.done += u64::from(slots);
        Ok(())
    }

    /// The wave's frame blocks: one per (depth, pass mode).
    fn write_frames(&mut self, start: u32, slots: u32) {
        self.pack.frame.sample = start;
        self.pack.frame.slots = slots;
        for (k, f) in self.passes.frames.iter().enumerate() {
            self.pack.frame.depth = (k / 3) as u32;
            self.pack.frame.mode = (k % 3) as u32;
            self.gpu
                .queue
                .write_buffer(f, 0, bytemuck::bytes_of(&self.pack.frame));
        }
    }

    /// The wave's commands: its passes, the sums' terms and sums passes, the
    /// timestamps' resolve and the records' copies for the CPU; with how many passes
    /// ran.
    fn encode_wave(
        &mut self,
        band_len: u32,
        start: u32,
        m: u32,
        slots: u32,
    ) -> (wgpu::CommandEncoder, usize) {
        let b = &self.buffers;
        let mut enc = self.gpu.device.create_command_encoder(&Default::default());
        // Draw records of slots no shade pass visits stay zero (status 0: no vertex),
        // and the queues start empty.
        let db = self.shape.draw_bytes(u64::from(slots));
        if self.shape.depths > 0 {
            enc.clear_buffer(&b.draws, 0, Some(db));
        }
        enc.clear_buffer(&b.stats, 16, Some(48));
        self.encode_passes(&mut enc, slots);
        let passes = &self.passes;
        let n = passes.passes.len() as u32;
        if let Some(sums) = self.sums.as_mut() {
            sums.encode(self.gpu, &mut enc, band_len, start, m, &|k| {
                passes.writes(n + k)
            });
        }
        // The passes run: the wave's, and the terms and sums passes.
        let run = passes.passes.len() + if self.sums.is_some() { 2 } else { 0 };
        if let Some(qs) = &passes.timestamps {
            enc.resolve_query_set(qs, 0..2 * run as u32, &passes.ts_buf, 0);
            enc.copy_buffer_to_buffer(&passes.ts_buf, 0, &passes.ts_read, 0, 16 * run as u64);
        }
        if let Some((hits_r, draws_r)) = &self.readbacks {
            let hb = self.shape.hit_bytes(u64::from(slots));
            enc.copy_buffer_to_buffer(&b.hits, 0, hits_r, 0, hb);
            if self.shape.depths > 0 {
                enc.copy_buffer_to_buffer(&b.draws, 0, draws_r, 0, db);
            }
        }
        (enc, run)
    }

    /// The wave's passes: the camera trace, then per depth shade, shadow and (but the
    /// last) the continuation, each queued pass dispatched from its queue's length.
    fn encode_passes(&self, enc: &mut wgpu::CommandEncoder, slots: u32) {
        let (p, b) = (&self.kernels, &self.buffers);
        for (q, &(stage, depth, mode)) in self.passes.passes.iter().enumerate() {
            let group = &self.passes.groups[3 * depth as usize + mode as usize];
            let pipe = if stage == 1 { &p.shade } else { &p.trace };
            if stage > 1 || (stage == 1 && depth > 0) {
                // The queued passes: their dispatch from their queue's length. (Byte
                // offsets in `stats`: the shadow, live and continuation queues' args at
                // 20, 36 and 52.)
                {
                    let mut pass = enc.begin_compute_pass(&Default::default());
                    pass.set_pipeline(&p.prepare);
                    pass.set_bind_group(0, group, &[]);
                    pass.dispatch_workgroups(1, 1, 1);
                }
                let (from, to) = match stage {
                    1 => (36, 16),
                    2 => (20, 0),
                    _ => (52, 32),
                };
                enc.copy_buffer_to_buffer(&b.stats, from, &b.args, to, 12);
            }
            match stage {
                // Empty shadow and continuation queues for the shade pass to fill.
                1 => {
                    enc.clear_buffer(&b.stats, 16, Some(4));
                    enc.clear_buffer(&b.stats, 48, Some(4));
                }
                // An empty live queue for the continuations' new vertices.
                3 => enc.clear_buffer(&b.stats, 32, Some(4)),
                _ => {}
            }
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: None,
                timestamp_writes: self.passes.writes(q as u32),
            });
            pass.set_pipeline(pipe);
            pass.set_bind_group(0, group, &[]);
            match stage {
                0 => {
                    let (gx, gy) = crate::workgroups(slots);
                    pass.dispatch_workgroups(gx, gy, 1);
                }
                // Depth 0: every slot's draws, in slot order (coherent rays).
                1 if depth == 0 => {
                    let (gx, gy) = crate::workgroups(slots * self.shape.nd1);
                    pass.dispatch_workgroups(gx, gy, 1);
                }
                // The live slots' draws, the shadow rays and the continuations queued
                // by the pass before, and no other.
                1 => pass.dispatch_workgroups_indirect(&b.args, 16),
                2 => pass.dispatch_workgroups_indirect(&b.args, 0),
                _ => pass.dispatch_workgroups_indirect(&b.args, 32),
            }
        }
    }

    /// The submitted wave's records (where the CPU adds them), its tally and the
    /// progressive estimators' solves within it (where the GPU keeps the sums), and its
    /// `run` passes' times.
    fn read_wave(&mut self, t: &mut Totals, slots: u32, run: usize) -> Result<WaveRead, GpuError> {
        let gpu = self.gpu;
        let (mut hits, mut draws, mut tally) = (Vec::new(), Vec::new(), None);
        if let Some((hits_r, draws_r)) = &self.readbacks {
            hits = read_back(gpu, hits_r, self.shape.hit_bytes(u64::from(slots)))?;
            if self.shape.depths > 0 {
                draws = read_back(gpu, draws_r, self.shape.draw_bytes(u64::from(slots)))?;
            }
        }
        if let Some(sums) = self.sums.as_mut() {
            tally = Some(sums.tally(gpu, slots)?);
            // The progressive estimators' solves within the wave.
            let time = Instant::now();
            sums.settle(gpu)?;
            t.stats.stages.accumulate += time.elapsed();
        }
        let passes_time = self.read_timestamps(&mut t.stats, run)?;
        Ok(WaveRead {
            hits,
            draws,
            tally,
            passes_time,
        })
    }

    /// The `run` passes' times by their timestamps, added to their stages' (zero
    /// without timestamps).
    fn read_timestamps(&self, stats: &mut GpuStats, run: usize) -> Result<Duration, GpuError> {
        let mut passes_time = Duration::ZERO;
        if self.passes.timestamps.is_none() {
            return Ok(passes_time);
        }
        let ts = read_back(self.gpu, &self.passes.ts_read, 16 * run as u64)?;
        let t: &[u64] = bytemuck::cast_slice(&ts);
        for q in 0..run {
            let ns = t[2 * q + 1].saturating_sub(t[2 * q]) as f64 * self.passes.period;
            let span = Duration::from_nanos(ns as u64);
            passes_time += span;
            match self.passes.passes.get(q).map_or(4, |p| p.0) {
                0 => stats.stages.camera += span,
                1 => stats.stages.shade += span,
                2 => stats.stages.shadow += span,
                3 => stats.stages.secondary += span,
                _ => stats.stages.accumulate += span,
            }
        }
        Ok(passes_time)
    }

    /// A wave's tally where the GPU keeps the sums: its rays counted, and its
    /// overflowing slots' samples rendered by the CPU into the records to which the
    /// GPU's sums are added at the end (their rays counted there).
    fn add_tally(&self, t: &mut Totals, tally: WaveTally, wave: &WaveSlots) {
        let WaveSlots {
            base,
            band_len,
            start,
            ..
        } = *wave;
        t.rays.camera += tally.camera;
        t.rays.shadow += tally.shadow;
        t.rays.secondary += tally.secondary;
        let (w, stride) = (self.shape.width, self.shape.stride);
        let data_words = t.state.data_mut();
        for slot in tally.overflow {
            let pix = base + slot % band_len;
            let index = start + slot / band_len;
            let rec = &mut data_words[pix as usize * stride..(pix as usize + 1) * stride];
            t.stats.cpu_fallbacks += 1;
            t.stats.fallback_pixels.push(pix);
            self.host
                .cpu_sample(pix % w, pix / w, index, rec, &mut t.rays);
        }
    }

    /// A read-back wave's hits and draws added to its pixels' records by the CPU
    /// ([`add_slot`]); a slot that overflowed has its whole sample rendered by the CPU
    /// (its rays counted there).
    fn add_on_cpu(&self, t: &mut Totals, hit_data: &[u8], draw_data: &[u8], wave: &WaveSlots) {
        let WaveSlots {
            base,
            band_len,
            start,
            slots,
        } = *wave;
        // (An empty Vec<u8> need not be aligned for f32.)
        fn words(v: &[u8]) -> &[f32] {
            if v.is_empty() {
                &[]
            } else {
                bytemuck::cast_slice(v)
            }
        }
        let s = &self.shape;
        let (w, stride, nd1, depths, n_draws) = (s.width, s.stride, s.nd1, s.depths, s.n_draws);
        let (hv, dv) = (words(hit_data), words(draw_data));
        let t_count = self.host.tally().techniques.len();
        let words = draw_words(t_count as u32);
        let mut pdfs = vec![0.0f64; (depths * n_draws) as usize * t_count];
        let data_words = t.state.data_mut();
        for slot in 0..slots as usize {
            let pix = base as usize + slot % band_len as usize;
            let index = start + slot as u32 / band_len;
            let (x, y) = (pix as u32 % w, pix as u32 / w);
            let rec = &mut data_words[pix * stride..(pix + 1) * stride];
            let hw = &hv[slot * HIT_WORDS..(slot + 1) * HIT_WORDS];
            // The draws of vertex `depth`, the extra draw last.
            let vertex = |depth: u32| {
                let at = ((depth * slots) as usize + slot) * nd1 as usize * words;
                &dv[at..at + nd1 as usize * words]
            };
            let overflow = hw[3] == 2.0
                || (0..depths).any(|k| vertex(k).chunks_exact(words).any(|d| d[7] == 12.0));
            if overflow {
                t.stats.cpu_fallbacks += 1;
                t.stats.fallback_pixels.push(pix as u32);
                self.host.cpu_sample(x, y, index, rec, &mut t.rays);
                continue;
            }
            add_slot(
                self.host.tally(),
                rec,
                index,
                hw,
                &vertex,
                n_draws,
                depths,
                &mut pdfs,
                &mut t.rays,
            );
        }
    }

    /// The render's end: the loop maxima read back, the state marked partial if it
    /// stopped early, and the statistics.
    fn finish(
        self,
        mut t: Totals,
        o: &RenderOptions,
    ) -> Result<(RenderState, RenderStats, GpuStats), GpuError> {
        let gpu = self.gpu;
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&self.buffers.stats, 0, &self.loops_r, 0, 16);
        gpu.queue.submit([enc.finish()]);
        let l = read_back(gpu, &self.loops_r, 16)?;
        let l: &[u32] = bytemuck::cast_slice(&l);
        t.stats.max_loops = [l[0], l[1], l[2]];
        if t.done < t.total {
            t.state.set_partial();
        }
        let render_stats = RenderStats {
            integrator: o.integrator,
            wall: t.started.elapsed(),
            samples: t.done,
            samples_requested: t.total,
            rays: t.rays,
            stopped: t.done < t.total,
            threads: 0,
        };
        Ok((t.state, render_stats, t.stats))
    }
}
