//! The CPU's random numbers on the GPU: Philox4x32-10 keyed by the seed, counter
//! `(x, y, sample index, dimension / 4)`, four 32-bit outputs per evaluation
//! (`state::sampler`, DESIGN.md §4). The WGSL computes the high half of 32 × 32-bit
//! products from 16-bit parts, so it needs no `SHADER_INT64` and gives the CPU's integers
//! on every adapter; a kernel turns them into f32 as `(u >> 8) · 2⁻²⁴`.

/// The WGSL source of `philox4x32_10(counter, key)`, `mulhi32` and `philox_unit`, to
/// prepend to kernels that draw random numbers.
pub const PHILOX_WGSL: &str = include_str!("shaders/philox.wgsl");

/// The f32 value the GPU makes of a 32-bit output: its top 24 bits times 2⁻²⁴.
pub fn unit_f32(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}
