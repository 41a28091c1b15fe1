//! The kernels' buffers: the packed scene's storage buffers, the sizes of a render's
//! bands and waves, the wave's records, stats and queues, and the passes' frame blocks,
//! bind groups and timestamp queries.

use super::pack::{DirectScene, Frame};
use super::pipelines::Pipelines;
use super::{SumsOn, WaveOptions, WAVE_DRAWS};
use crate::record::{draw_words, HIT_WORDS};
use crate::tape_trace::TapeSolid;
use crate::{Gpu, GpuError};
use state::{LinearRecord, Tally};
use wgpu::util::DeviceExt;

/// The scene's read-only buffers in binding order (1–9, then 14–15: CSG and tape).
pub(super) fn scene_buffers(gpu: &Gpu, pack: &DirectScene) -> Result<Vec<wgpu::Buffer>, GpuError> {
    let tape_words = TapeSolid::scene_words(&pack.tapes);
    Ok(vec![
        storage(gpu, "shapes", bytemuck::cast_slice(&pack.shapes))?,
        storage(gpu, "objects", bytemuck::cast_slice(&pack.leaves))?,
        storage(gpu, "quadrics", bytemuck::cast_slice(&pack.quadrics))?,
        storage(
            gpu,
            "perturbations",
            bytemuck::cast_slice(&pack.perturbations),
        )?,
        storage(gpu, "nodes", bytemuck::cast_slice(&pack.nodes))?,
        storage(gpu, "items", bytemuck::cast_slice(&pack.items))?,
        storage(gpu, "materials", bytemuck::cast_slice(&pack.materials))?,
        storage(gpu, "lights", bytemuck::cast_slice(&pack.lights))?,
        storage(gpu, "tables", bytemuck::cast_slice(&pack.tables))?,
        storage(gpu, "csg", bytemuck::cast_slice(&pack.csg))?,
        storage(gpu, "tape", bytemuck::cast_slice(&tape_words))?,
    ])
}

/// The bind group of one pass: its frame block, the scene, and the wave's hits, draws
/// and loop counters.
pub(super) fn bind(
    gpu: &Gpu,
    p: &Pipelines,
    scene: &[wgpu::Buffer],
    frame: &wgpu::Buffer,
    wave: [&wgpu::Buffer; 3],
) -> wgpu::BindGroup {
    let all = std::iter::once(frame)
        .chain(&scene[..9])
        .chain(wave)
        .chain(&scene[9..]);
    crate::bind_buffers(gpu, "direct", &p.layout, all)
}

/// A read-only storage buffer holding `bytes`, checked against the binding limit.
fn storage(gpu: &Gpu, label: &str, bytes: &[u8]) -> Result<wgpu::Buffer, GpuError> {
    gpu.check_binding(bytes.len() as u64)?;
    // Empty bindings are invalid: give an empty pool one zeroed 16-byte element.
    let data: &[u8] = if bytes.is_empty() { &[0; 128] } else { bytes };
    Ok(gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: data,
            usage: wgpu::BufferUsages::STORAGE,
        }))
}

/// The sizes every band and wave of a render shares.
pub(super) struct WaveShape {
    /// The image's width and pixels.
    pub(super) width: u32,
    pub(super) pixels: u32,
    /// Σ n_k draws per vertex.
    pub(super) n_draws: u32,
    /// Draw records per slot and depth: the techniques', the extra BSDF draw, and one
    /// per point or spot light.
    pub(super) nd1: u32,
    /// Vertex depths.
    pub(super) depths: u32,
    /// Draw records per slot over all depths.
    pub(super) per_slot_draws: u32,
    /// f32 words of a draw record ([`draw_words`]).
    pub(super) draw_words: u32,
    /// f64 words of a pixel's record.
    pub(super) stride: usize,
    /// The most pixels a band covers.
    pub(super) band: u32,
    /// The most sample indices a wave covers.
    pub(super) per_wave: u32,
    /// The most slots a wave holds (sized before the sums' limit on `per_wave`).
    pub(super) max_slots: u64,
}

impl WaveShape {
    /// The bands and waves of a render of `width × height` pixels: a wave's draws
    /// within [`WAVE_DRAWS`] (a half or a third of it where a draw record is longer than
    /// one of 8 techniques, so that a wave's draws stay within 40 MiB), a band's sums
    /// (pixels × stride f64 words, where the GPU keeps them: the record returned) within
    /// one binding.
    pub(super) fn new(
        gpu: &Gpu,
        acc: &Tally,
        pack: &DirectScene,
        how: &WaveOptions,
        (width, height): (u32, u32),
    ) -> (Self, Option<LinearRecord>) {
        let pixels = width * height;
        let nd1 = pack.frame.per_slot;
        let depths = pack.frame.max_depth;
        let per_slot_draws = nd1 * depths.max(1);
        let draw_words = draw_words(pack.frame.n_tech) as u32;
        let wave_draws = WAVE_DRAWS / draw_words.div_ceil(crate::record::draw_words(8) as u32);
        // The image in bands of consecutive pixels (raster order), each rendered through
        // all its samples before the next: the buffers hold one band's waves, whatever
        // the image's size.
        let stride = acc.stride();
        // Sums on the GPU: a band's (pixels × stride f64 words) within one binding.
        let linear = acc.linear().filter(|_| how.sums != SumsOn::Cpu);
        let sums_fit = if linear.is_some() {
            gpu.info().max_storage_binding / (stride as u64 * 8)
        } else {
            u64::MAX
        };
        let band = how
            .band_pixels
            .unwrap_or(u32::MAX)
            .min((wave_draws / per_slot_draws).max(1))
            .min(sums_fit.min(u64::from(u32::MAX)) as u32)
            .clamp(1, pixels);
        let per_wave = (wave_draws / (band * per_slot_draws)).max(1);
        let shape = Self {
            width,
            pixels,
            n_draws: pack.frame.n_draws,
            nd1,
            depths,
            per_slot_draws,
            draw_words,
            stride,
            band,
            per_wave,
            max_slots: u64::from(per_wave * band),
        };
        (shape, linear)
    }

    /// Bytes of the hit records of `slots` slots.
    pub(super) fn hit_bytes(&self, slots: u64) -> u64 {
        slots * HIT_WORDS as u64 * 4
    }

    /// Bytes of the draw records of `slots` slots.
    pub(super) fn draw_bytes(&self, slots: u64) -> u64 {
        slots * u64::from(self.per_slot_draws) * u64::from(self.draw_words) * 4
    }
}

/// A buffer the CPU maps to read what the GPU copied into it.
pub(super) fn map_read(gpu: &Gpu, label: &str, size: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The buffers the kernels read and write: the scene's, a wave's records, and the
/// stats and queues with the queued passes' indirect arguments.
pub(super) struct WaveBuffers {
    /// The scene's read-only buffers (`scene_buffers`).
    pub(super) scene: Vec<wgpu::Buffer>,
    /// The wave's hit records.
    pub(super) hits: wgpu::Buffer,
    /// The wave's draw records.
    pub(super) draws: wgpu::Buffer,
    /// Loop maxima, the three queues' lengths and indirect arguments, then the shadow
    /// queue's entries (a draw each), the live queue's and the continuation queue's (a
    /// slot each).
    pub(super) stats: wgpu::Buffer,
    /// The queued passes' indirect arguments (shadow, shade, continuation at 0, 16, 32),
    /// copied out of `stats` (a buffer bound for storage cannot also drive a dispatch).
    pub(super) args: wgpu::Buffer,
}

impl WaveBuffers {
    /// The buffers for waves of `shape`; sets where the queues start in `pack`'s frame.
    pub(super) fn new(
        gpu: &Gpu,
        pack: &mut DirectScene,
        shape: &WaveShape,
    ) -> Result<Self, GpuError> {
        let d = &gpu.device;
        let scene = scene_buffers(gpu, pack)?;
        let max_slots = shape.max_slots;
        let draw_bytes = shape.draw_bytes(max_slots);
        gpu.check_binding(draw_bytes)?;
        let rw = |label, size| {
            d.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let hits = rw("hits", shape.hit_bytes(max_slots));
        let draws = rw("draws", draw_bytes);
        let live_at = 16 + max_slots * u64::from(shape.nd1);
        let stats_bytes = (live_at + 2 * max_slots) * 4;
        pack.frame.wave = [live_at as u32, (live_at + max_slots) as u32, 0, 0];
        gpu.check_binding(stats_bytes)?;
        let stats = rw("stats and queues", stats_bytes);
        let args = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("queued dispatches"),
            size: 48,
            usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self {
            scene,
            hits,
            draws,
            stats,
            args,
        })
    }
}

/// One pass of a wave: its stage (0 camera, 1 shade, 2 shadow, 3 continuation), depth
/// and frame mode (0 camera, 1 shadow, 2 continuation).
pub(super) type Pass = (usize, u32, u32);

/// The passes of a wave with their frame blocks, bind groups and timestamp queries.
pub(super) struct WavePasses {
    /// The camera trace, then per depth shade, shadow and (but the last) the
    /// continuation.
    pub(super) passes: Vec<Pass>,
    /// One uniform block per (depth, frame mode).
    pub(super) frames: Vec<wgpu::Buffer>,
    /// Their bind groups.
    pub(super) groups: Vec<wgpu::BindGroup>,
    /// Two timestamps per pass, and for the terms and sums passes, where the device has
    /// them; their resolve buffer and its readback.
    pub(super) timestamps: Option<wgpu::QuerySet>,
    pub(super) ts_buf: wgpu::Buffer,
    pub(super) ts_read: wgpu::Buffer,
    /// Nanoseconds per timestamp tick.
    pub(super) period: f64,
}

impl WavePasses {
    /// The passes of waves `depths` deep, bound to `buffers` with a frame block each.
    pub(super) fn new(gpu: &Gpu, p: &Pipelines, buffers: &WaveBuffers, depths: u32) -> Self {
        let d = &gpu.device;
        let n_frames = 3 * depths.max(1) as usize;
        let frames: Vec<wgpu::Buffer> = (0..n_frames)
            .map(|_| {
                d.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("frame"),
                    size: size_of::<Frame>() as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            })
            .collect();
        let wave = [&buffers.hits, &buffers.draws, &buffers.stats];
        let groups: Vec<wgpu::BindGroup> = frames
            .iter()
            .map(|f| bind(gpu, p, &buffers.scene, f, wave))
            .collect();
        let mut passes: Vec<Pass> = vec![(0, 0, 0)];
        for depth in 0..depths {
            passes.push((1, depth, 0));
            passes.push((2, depth, 1));
            if depth + 1 < depths {
                passes.push((3, depth, 2));
            }
        }
        let n_queries = 2 * (passes.len() as u32 + 2);
        let timestamps = gpu.info().timestamps.then(|| {
            d.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("stages"),
                ty: wgpu::QueryType::Timestamp,
                count: n_queries,
            })
        });
        let ts_bytes = 8 * u64::from(n_queries);
        let ts_buf = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps"),
            size: ts_bytes,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let ts_read = map_read(gpu, "timestamps readback", ts_bytes);
        let period = f64::from(gpu.queue.get_timestamp_period());
        Self {
            passes,
            frames,
            groups,
            timestamps,
            ts_buf,
            ts_read,
            period,
        }
    }

    /// Pass `q`'s timestamp writes (queries 2q and 2q + 1), where there are any.
    pub(super) fn writes(&self, q: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.timestamps
            .as_ref()
            .map(|qs| wgpu::ComputePassTimestampWrites {
                query_set: qs,
                beginning_of_pass_write_index: Some(2 * q),
                end_of_pass_write_index: Some(2 * q + 1),
            })
    }
}
