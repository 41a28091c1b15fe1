//! One WGSL compute entry point over storage buffers: dispatched, waited for and read
//! back. The plumbing of kernel twins and tests (GPU.md §3.5, §9); the wavefront
//! integrator will chain such passes without reading back between them.

use crate::{Gpu, GpuError};
use wgpu::util::DeviceExt;

/// A compiled compute pipeline whose bind group 0 holds the input storage buffers at
/// bindings 0 … n−1 (read-only, `array<u32>`) and the output at binding n (read-write).
pub struct Kernel {
    pipeline: wgpu::ComputePipeline,
    inputs: usize,
}

impl Kernel {
    /// Compiles `entry` of the WGSL `source` with `inputs` input buffers. Shader errors
    /// are returned with naga's message.
    pub fn new(gpu: &Gpu, source: &str, entry: &str, inputs: usize) -> Result<Kernel, GpuError> {
        Self::build(gpu, source, entry, inputs, false)
    }

    /// [`Kernel::new`] without the bounds checks and loop bounding naga inserts
    /// (`ShaderRuntimeChecks::unchecked`), which cost up to 20× on private arrays on
    /// lavapipe (GPU.md §3.4).
    ///
    /// # Safety
    ///
    /// Every index of the kernel must be in bounds and every loop finite, by
    /// construction: nothing checks them at run time.
    pub unsafe fn new_unchecked(
        gpu: &Gpu,
        source: &str,
        entry: &str,
        inputs: usize,
    ) -> Result<Kernel, GpuError> {
        Self::build(gpu, source, entry, inputs, true)
    }

    fn build(
        gpu: &Gpu,
        source: &str,
        entry: &str,
        inputs: usize,
        unchecked: bool,
    ) -> Result<Kernel, GpuError> {
        let pipeline = compute_pipeline(gpu, source, entry, unchecked)?;
        Ok(Kernel { pipeline, inputs })
    }

    /// The compiled pipeline (its bind group 0 as [`Kernel::new`] describes), for
    /// callers that chain it with other passes.
    pub(crate) fn pipeline(&self) -> &wgpu::ComputePipeline {
        &self.pipeline
    }

    /// Runs the kernel on `workgroups` with the given inputs and an output of
    /// `output_words` u32 (zeroed), and reads the output back.
    pub fn run(
        &self,
        gpu: &Gpu,
        inputs: &[&[u32]],
        output_words: usize,
        workgroups: [u32; 3],
    ) -> Result<Vec<u32>, GpuError> {
        assert_eq!(inputs.len(), self.inputs, "one slice per input binding");
        let bytes = (output_words * 4) as u64;
        gpu.check_binding(bytes)?;
        let d = &gpu.device;
        let scope = d.push_error_scope(wgpu::ErrorFilter::Validation);
        let input_buffers: Vec<wgpu::Buffer> = inputs
            .iter()
            .map(|words| {
                // Empty bindings are invalid: give an empty input one word.
                let data: &[u32] = if words.is_empty() { &[0] } else { words };
                d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("input"),
                    contents: bytemuck::cast_slice(data),
                    usage: wgpu::BufferUsages::STORAGE,
                })
            })
            .collect();
        let size = bytes.max(4);
        let output = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("output"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = self.pipeline.get_bind_group_layout(0);
        let group = crate::bind_buffers(
            gpu,
            "kernel",
            &layout,
            input_buffers.iter().chain([&output]),
        );
        let mut encoder = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: None,
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(workgroups[0], workgroups[1], workgroups[2]);
        }
        encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, size);
        gpu.queue.submit([encoder.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Run(e.to_string()));
        }
        let (tx, rx) = std::sync::mpsc::channel();
        readback.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        d.poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Run(e.to_string()))?;
        rx.recv()
            .map_err(|e| GpuError::Run(e.to_string()))?
            .map_err(|e| GpuError::Run(e.to_string()))?;
        let view = readback
            .get_mapped_range(..)
            .map_err(|e| GpuError::Run(e.to_string()))?;
        let out = bytemuck::cast_slice::<u8, u32>(&view)[..output_words].to_vec();
        drop(view);
        readback.unmap();
        Ok(out)
    }
}

/// The compute pipeline of `entry` in the WGSL `source`, its layout taken from the
/// shader (`unchecked`: without naga's run-time checks, [`Kernel::new_unchecked`]'s
/// contract); a shader error is returned with naga's message.
pub(crate) fn compute_pipeline(
    gpu: &Gpu,
    source: &str,
    entry: &str,
    unchecked: bool,
) -> Result<wgpu::ComputePipeline, GpuError> {
    let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let desc = wgpu::ShaderModuleDescriptor {
        label: Some(entry),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    };
    let module = if unchecked && !gpu.info().checked {
        // SAFETY: `new_unchecked`'s caller guarantees in-bounds indexing and finite
        // loops; wgpu then skips the runtime checks only.
        unsafe {
            gpu.device
                .create_shader_module_trusted(desc, wgpu::ShaderRuntimeChecks::unchecked())
        }
    } else {
        gpu.device.create_shader_module(desc)
    };
    let pipeline = gpu
        .device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: None,
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
    match pollster::block_on(scope.pop()) {
        Some(e) => Err(GpuError::Run(format!("kernel {entry}: {e}"))),
        None => Ok(pipeline),
    }
}
