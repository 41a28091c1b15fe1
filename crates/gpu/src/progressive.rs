//! The progressive optimal estimators' per-pixel sums on the GPU (GPU.md §8).
//!
//! Their Σ F needs the α solved from *earlier* samples (Kondapaneni et al. 2019, §5), so
//! their records are not plain sums of per-sample terms. The terms kernel writes each
//! sample's α-free terms (`state::LinearMis::Progressive`: `G`, `Q`, N and
//! the moments), and a sequential pass per pixel (`shaders/progressive.wgsl`) adds them
//! in sample order in f64 or double-float, applying α as `Σ F_c += G_c − Σ_i α_ci Q_i`.
//! Where a block's N reaches a point of its schedule, the pixel stops after that sample;
//! the CPU reads back the band's sums, re-solves those blocks' α with the `mis` crate
//! ([`mis::Kernel::resolve`], the CPU's own solve, in f64), uploads α, and the pass goes
//! on from where each pixel stopped. So the solves fall where a CPU render's fall (at
//! N = W, 2W, 4W, … per block), O(log N) round trips per band, and α never comes
//! from the sample it weights. α is applied in f32.

use crate::{Gpu, GpuError};

/// The pass (entry `progressive`); needs a prelude defining `Sum`, `sum_add` and
/// `sum_count` (the f64 and double-float preludes of this module).
pub const PROGRESSIVE_WGSL: &str = include_str!("shaders/progressive.wgsl");

/// The prelude of the f64 pass.
const F64_PRELUDE: &str = "alias Sum = f64;
fn sum_add(a: Sum, v: f32) -> Sum { return a + f64(v); }
fn sum_count(a: Sum) -> u32 { return u32(f32(a)); }
";

/// The prelude of the double-float pass (after [`crate::sums::DF_WGSL`]).
const DF_PRELUDE: &str = "alias Sum = vec2<f32>;
fn sum_add(a: Sum, v: f32) -> Sum { return df_add(a, v); }
fn sum_count(a: Sum) -> u32 { return u32(a.x); }
";

/// The pass, compiled: double-float, and f64 where the device has `SHADER_F64`.
pub(crate) struct Kernels {
    df: wgpu::ComputePipeline,
    f64: Option<wgpu::ComputePipeline>,
}

impl Kernels {
    /// Compiles the double-float pass, and the f64 one if `f64`.
    pub fn new(gpu: &Gpu, f64: bool) -> Result<Self, GpuError> {
        let df = [crate::sums::DF_WGSL, DF_PRELUDE, PROGRESSIVE_WGSL].join("\n");
        let df = crate::kernel::compute_pipeline(gpu, &df, "progressive", false)?;
        let f64 = match f64 {
            true => {
                let src = [F64_PRELUDE, PROGRESSIVE_WGSL].join("\n");
                Some(crate::kernel::compute_pipeline(
                    gpu,
                    &src,
                    "progressive",
                    false,
                )?)
            }
            false => None,
        };
        Ok(Self { df, f64 })
    }
}

/// Where α starts in a progressive block: after N and Σ F (3 channels).
const ALPHA_AT: usize = 4;

/// `schedule` as the pass's (kind, W).
fn schedule_words(schedule: mis::Schedule) -> [u32; 2] {
    let w = |n: u64| n.min(u64::from(u32::MAX)) as u32;
    match schedule {
        mis::Schedule::Doubling { warmup } => [0, w(warmup)],
        mis::Schedule::Every { warmup } => [1, w(warmup)],
        mis::Schedule::Once { after } => [2, w(after)],
        mis::Schedule::Fixed => [3, 0],
    }
}

/// Where the blocks lie in a record.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Blocks {
    /// The first block's word.
    pub first: u32,
    /// Blocks per record (depths × lights).
    pub count: u32,
    /// Words per block.
    pub words: u32,
    /// Techniques T.
    pub t: u32,
}

impl Blocks {
    /// α words per block (3 channels × T).
    fn alpha(&self) -> usize {
        3 * self.t as usize
    }
}

/// A render's progressive pass over a band's sums: α per block (f64 as solved, and the
/// f32 copy the pass reads), the pixels' cursors, and the pass's bindings.
pub(crate) struct ProgressiveSums {
    pipeline: wgpu::ComputePipeline,
    kernel: mis::Kernel,
    blocks: Blocks,
    stride: u32,
    params: wgpu::Buffer,
    alpha: wgpu::Buffer,
    cursor: wgpu::Buffer,
    cursor_r: wgpu::Buffer,
    group: wgpu::BindGroup,
    /// α of every block of the band, as solved.
    alpha64: Vec<f64>,
    /// The wave being added: pixels and sample indices.
    wave: (u32, u32),
}

impl ProgressiveSums {
    /// The pass over `terms` into `state` (in place, f64 if `f64` else double-float) for
    /// bands of up to `pixels` pixels with records of `stride` words.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        gpu: &Gpu,
        kernels: &Kernels,
        kernel: mis::Kernel,
        blocks: Blocks,
        stride: u32,
        pixels: u32,
        terms: &wgpu::Buffer,
        state: &wgpu::Buffer,
        f64: bool,
    ) -> Self {
        let pipeline = match (f64, &kernels.f64) {
            (true, Some(p)) => p.clone(),
            _ => kernels.df.clone(),
        };
        let d = &gpu.device;
        use wgpu::BufferUsages as U;
        let buffer = |label, size: u64, usage| {
            d.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(4),
                usage,
                mapped_at_creation: false,
            })
        };
        let n_alpha = pixels as usize * blocks.count as usize * blocks.alpha();
        let params = buffer("progressive params", 40, U::STORAGE | U::COPY_DST);
        let alpha = buffer("alpha", 4 * n_alpha as u64, U::STORAGE | U::COPY_DST);
        let cursor_bytes = 8 * u64::from(pixels);
        let cursor = buffer(
            "cursors",
            cursor_bytes,
            U::STORAGE | U::COPY_SRC | U::COPY_DST,
        );
        let cursor_r = buffer("cursors readback", cursor_bytes, U::MAP_READ | U::COPY_DST);
        let layout = pipeline.get_bind_group_layout(0);
        let group = crate::bind_buffers(
            gpu,
            "progressive",
            &layout,
            [&params, terms, &alpha, state, &cursor],
        );
        Self {
            pipeline,
            kernel,
            blocks,
            stride,
            params,
            alpha,
            cursor,
            cursor_r,
            group,
            alpha64: vec![0.0; n_alpha],
            wave: (0, 0),
        }
    }

    /// Records the pass over a wave of `samples` sample indices of `pixels` pixels.
    pub fn encode(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        pixels: u32,
        samples: u32,
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let b = self.blocks;
        let [kind, w] = schedule_words(self.kernel.schedule().unwrap_or(mis::Schedule::Fixed));
        let p = [
            0,
            pixels,
            samples,
            self.stride,
            b.first,
            b.count,
            b.words,
            b.t,
            kind,
            w,
        ];
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::cast_slice(&p));
        enc.clear_buffer(&self.cursor, 0, Some(8 * u64::from(pixels)));
        self.wave = (pixels, samples);
        self.dispatch(enc, timestamps);
    }

    fn dispatch(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        crate::dispatch(enc, timestamps, &self.pipeline, &self.group, self.wave.0);
    }

    /// After the wave's submission: while pixels stopped at a solve, reads back their
    /// sums (`read_sums`: the band's sums as f64), re-solves the blocks whose N is at a
    /// point of the schedule, uploads α and runs the pass on from where they stopped.
    /// Returns the extra passes run.
    pub fn settle(
        &mut self,
        gpu: &Gpu,
        read_sums: &dyn Fn(usize) -> Result<Vec<f64>, GpuError>,
    ) -> Result<u32, GpuError> {
        let (pixels, samples) = self.wave;
        let (np, b) = (pixels as usize, self.blocks);
        let schedule = self.kernel.schedule().unwrap_or(mis::Schedule::Fixed);
        let mut rounds = 0;
        loop {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            enc.copy_buffer_to_buffer(&self.cursor, 0, &self.cursor_r, 0, 8 * np as u64);
            gpu.queue.submit([enc.finish()]);
            let bytes = crate::readback::read_back(gpu, &self.cursor_r, 8 * np as u64)?;
            let cursor: &[u32] = bytemuck::cast_slice(&bytes);
            let stopped: Vec<usize> = (0..np).filter(|&p| cursor[np + p] != 0).collect();
            if stopped.is_empty() {
                // A pixel stops only at a solve: none stopped, all are through.
                debug_assert!(cursor[..np].iter().all(|&j| j == samples));
                return Ok(rounds);
            }
            let pending = cursor[..np].iter().any(|&j| j < samples);
            let sums = read_sums(np * self.stride as usize)?;
            let mut block = vec![0.0; b.words as usize];
            for p in stopped {
                for k in 0..b.count as usize {
                    let w = p * self.stride as usize + (b.first + k as u32 * b.words) as usize;
                    let n = sums[w];
                    if !schedule.solves_at(n as u64) {
                        continue;
                    }
                    let alpha = (p * b.count as usize + k) * b.alpha();
                    let alpha = &mut self.alpha64[alpha..alpha + b.alpha()];
                    block.copy_from_slice(&sums[w..w + b.words as usize]);
                    block[ALPHA_AT..ALPHA_AT + b.alpha()].copy_from_slice(alpha);
                    self.kernel.resolve(&mut block);
                    alpha.copy_from_slice(&block[ALPHA_AT..ALPHA_AT + b.alpha()]);
                }
            }
            let a32: Vec<f32> = self.alpha64.iter().map(|&a| a as f32).collect();
            gpu.queue
                .write_buffer(&self.alpha, 0, bytemuck::cast_slice(&a32));
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            // Flags cleared; the cursors kept.
            enc.clear_buffer(&self.cursor, 4 * np as u64, Some(4 * np as u64));
            if pending {
                self.dispatch(&mut enc, None);
                rounds += 1;
            }
            gpu.queue.submit([enc.finish()]);
            if !pending {
                return Ok(rounds);
            }
        }
    }

    /// The band's records from its sums (`sums`, f64, `stride` words per pixel) with
    /// their α, added to `records` (which hold the CPU's samples, if any, of the same
    /// pixels): copied where a record is empty, else merged as two states merge
    /// ([`mis::Kernel::merge`]).
    pub fn add_to(&self, sums: Vec<f64>, records: &mut [f64]) {
        let band = Band {
            kernel: &self.kernel,
            blocks: self.blocks,
            stride: self.stride as usize,
        };
        band.add_to(sums, &self.alpha64, records);
    }

    /// α back to zero, for the next band.
    pub fn reset(&mut self, gpu: &Gpu) {
        self.alpha64.fill(0.0);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.alpha, 0, None);
        gpu.queue.submit([enc.finish()]);
    }
}

/// A band's records as [`ProgressiveSums::add_to`] builds them from its sums.
struct Band<'a> {
    kernel: &'a mis::Kernel,
    blocks: Blocks,
    stride: usize,
}

impl Band<'_> {
    /// `sums` (`stride` words per pixel, α words unset) with α from `alpha` (3T words
    /// per block, pixel by pixel), added to `records`: copied where a record is empty,
    /// else merged as two states merge.
    fn add_to(&self, mut sums: Vec<f64>, alpha: &[f64], records: &mut [f64]) {
        let (s, b) = (self.stride, self.blocks);
        let block = |k: usize| {
            let w = (b.first + k as u32 * b.words) as usize;
            w..w + b.words as usize
        };
        for (p, (g, rec)) in sums
            .chunks_exact_mut(s)
            .zip(records.chunks_exact_mut(s))
            .enumerate()
        {
            for k in 0..b.count as usize {
                let a = (p * b.count as usize + k) * b.alpha();
                let w = block(k).start + ALPHA_AT;
                g[w..w + b.alpha()].copy_from_slice(&alpha[a..a + b.alpha()]);
            }
            if rec.iter().all(|&x| x == 0.0) {
                rec.copy_from_slice(g);
                continue;
            }
            let first = b.first as usize;
            for (x, y) in rec[..first].iter_mut().zip(&g[..first]) {
                *x += y;
            }
            for k in 0..b.count as usize {
                self.kernel.merge(&mut rec[block(k)], &g[block(k)]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    /// A band's record is the GPU's sums with their α where the CPU rendered nothing of
    /// the pixel, and the merge of the two states where it rendered samples after an
    /// overflow: every sum added, α re-solved from the merged moments.
    #[test]
    fn band_records_take_alpha_and_merge_the_cpu_samples() {
        let layout = Arc::new(mis::Layout::new(&[1, 1], 3));
        let kernel = mis::Kernel::new(
            mis::Method::OptimalProgressive,
            &layout,
            &mis::Params::default(),
        )
        .unwrap();
        let words = kernel.block_len();
        let blocks = Blocks {
            first: 4,
            count: 1,
            words: words as u32,
            t: 2,
        };
        let stride = 4 + words;
        // A record of samples `from..to`: the outside sums, then the block.
        let record = |from: u64, to: u64| {
            let mut r = vec![0.0; stride];
            for i in from..to {
                let x = (i as f64 + 0.5) / 8.0;
                r[0] += 1.0;
                r[1] += x;
                let b = &mut r[4..];
                kernel.add_sample(b, i, 0, &[1.0 + x, x, 2.0], &[1.0, 2.0 * x]);
                kernel.add_sample(b, i, 1, &[1.0 + x * x, x, 1.0], &[1.0, 2.0 * x]);
                kernel.end_iteration(b, i);
            }
            r
        };
        let band = Band {
            kernel: &kernel,
            blocks,
            stride,
        };
        let gpu = record(0, 6);
        let alpha = gpu[8..8 + 6].to_vec();
        assert!(alpha.iter().any(|&a| a != 0.0), "α solved by N = 4");
        let mut sums = gpu.clone();
        sums[8..8 + 6].fill(0.0);
        // No CPU sample: the GPU's record, α included.
        let mut out = vec![0.0; stride];
        band.add_to(sums.clone(), &alpha, &mut out);
        assert_eq!(out, gpu);
        // Two CPU samples: the two states merged.
        let cpu = record(6, 8);
        let mut out = cpu.clone();
        band.add_to(sums, &alpha, &mut out);
        let mut want = cpu.clone();
        for k in 0..4 {
            want[k] += gpu[k];
        }
        kernel.merge(&mut want[4..], &gpu[4..]);
        assert_eq!(out, want);
        assert_eq!(kernel.iterations(&out[4..]), 8);
    }
}
