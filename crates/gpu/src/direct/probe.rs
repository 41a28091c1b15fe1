//! The render kernels' nearest-hit query on a batch of rays (frame mode 3), for tests
//! that compare it with the CPU's intersectors.

use super::buffers::{bind, scene_buffers};
use super::pack::DirectScene;
use super::pipelines::kernels;
use crate::readback::read_back;
use crate::record::{draw_words, HIT_WORDS};
use crate::{Gpu, GpuError};
use scene::SceneData;
use state::{Host, RenderOptions};
use wgpu::util::DeviceExt;

/// One ray of [`probe`]: what the kernels' nearest-hit query found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    /// 0 miss, 1 hit, 2 overflow (a fixed capacity ran out: the renderer hands such
    /// samples to the CPU).
    pub status: u32,
    /// The ray parameter of the hit.
    pub t: f32,
    /// The outward unit normal there.
    pub normal: [f32; 3],
    /// Loop iterations the query took (GPU.md §3.1).
    pub loops: u32,
}

/// The nearest object hit of each ray `(origin, direction)` against the objects of
/// `data`, by the render kernels' own query (a ray batch, GPU.md §9). `host` is the CPU
/// renderer of the same scene (with the default options), for its tables.
pub fn probe(
    gpu: &Gpu,
    data: &SceneData,
    host: &dyn Host,
    rays: &[([f32; 3], [f32; 3])],
) -> Result<Vec<Probe>, GpuError> {
    let mut pack = DirectScene::packed(data, &RenderOptions::default(), host, Some(&gpu.kernels))?;
    let p = kernels(gpu, &pack)?;
    let scene = scene_buffers(gpu, &pack)?;
    let n = rays.len().max(1) as u32;
    pack.frame.slots = n;
    pack.frame.mode = 3;
    let d = &gpu.device;
    let vec4s = draw_words(pack.frame.n_tech) / 4;
    let mut input = vec![[0f32; 4]; n as usize * vec4s];
    for (i, (o, dir)) in rays.iter().enumerate() {
        input[i * vec4s] = [o[0], o[1], o[2], 0.0];
        input[i * vec4s + 1] = [dir[0], dir[1], dir[2], 0.0];
    }
    let draws = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("rays"),
        contents: bytemuck::cast_slice(&input),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let bytes = u64::from(n) * HIT_WORDS as u64 * 4;
    gpu.check_binding(bytes)?;
    let hits = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probe hits"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let loops = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("stats"),
        size: 16,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let readback = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probe readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let frame = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("frame"),
        contents: bytemuck::bytes_of(&pack.frame),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let group = bind(gpu, &p, &scene, &frame, [&hits, &draws, &loops]);
    let mut enc = d.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&p.trace);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(n.div_ceil(64), 1, 1);
    }
    enc.copy_buffer_to_buffer(&hits, 0, &readback, 0, bytes);
    gpu.queue.submit([enc.finish()]);
    let out = read_back(gpu, &readback, bytes)?;
    let v: &[f32] = bytemuck::cast_slice(&out);
    Ok(rays
        .iter()
        .enumerate()
        .map(|(i, _)| {
            let h = &v[i * HIT_WORDS..];
            Probe {
                status: h[2] as u32,
                t: h[0],
                normal: [h[4], h[5], h[6]],
                loops: h[3] as u32,
            }
        })
        .collect())
}
