//! Reading a mapped buffer back to the CPU, shared by the kernels' hosts (`direct`,
//! `record`, `progressive`).

use crate::{Gpu, GpuError};

/// The first `bytes` bytes of `buffer` (usage `MAP_READ`), once the device has finished
/// the work submitted before.
pub(crate) fn read_back(gpu: &Gpu, buffer: &wgpu::Buffer, bytes: u64) -> Result<Vec<u8>, GpuError> {
    let run = |e: &dyn std::fmt::Display| GpuError::Run(e.to_string());
    let slice = buffer.slice(..bytes);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| run(&e))?;
    rx.recv().map_err(|e| run(&e))?.map_err(|e| run(&e))?;
    let out = slice.get_mapped_range().map_err(|e| run(&e))?.to_vec();
    buffer.unmap();
    Ok(out)
}
