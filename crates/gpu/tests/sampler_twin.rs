//! The GPU's random numbers are the CPU's, bit for bit: Philox4x32-10 in WGSL with 32-bit
//! operations only against `state::sampler`, over a grid of pixels, sample indices and
//! dimension blocks, with the seed's two halves both non-zero.

use crate::common;

use gpu::sampler::{unit_f32, PHILOX_WGSL};
use gpu::{GpuOptions, Kernel};
use render::Sampler;
use state::sampler::to_unit;

const SEED: u64 = 0x9e37_79b9_7f4a_7c15;
const W: u32 = 16;
const H: u32 = 8;
const INDICES: u32 = 4;
const BLOCKS: u32 = 4;

#[test]
fn philox_on_the_gpu_equals_the_cpu_bit_for_bit() {
    let Some(g) = common::gpu(GpuOptions {
        int64: false,
        ..GpuOptions::default()
    }) else {
        return;
    };
    let src = format!(
        "{PHILOX_WGSL}
@group(0) @binding(0) var<storage, read> key: array<u32>;
@group(0) @binding(1) var<storage, read_write> out: array<u32>;
@compute @workgroup_size(64)
fn draw(@builtin(global_invocation_id) id: vec3<u32>) {{
    let n = id.x;
    if (n >= {W}u * {H}u * {INDICES}u * {BLOCKS}u) {{ return; }}
    let block = n % {BLOCKS}u;
    let i = (n / {BLOCKS}u) % {INDICES}u;
    let x = (n / ({BLOCKS}u * {INDICES}u)) % {W}u;
    let y = n / ({BLOCKS}u * {INDICES}u * {W}u);
    let v = philox4x32_10(vec4<u32>(x, y, i, block), vec2<u32>(key[0], key[1]));
    for (var k = 0u; k < 4u; k = k + 1u) {{
        out[8u * n + k] = v[k];
        out[8u * n + 4u + k] = bitcast<u32>(philox_unit(v[k]));
    }}
}}
"
    );
    let k = Kernel::new(&g, &src, "draw", 1).unwrap();
    let n = (W * H * INDICES * BLOCKS) as usize;
    let key = [SEED as u32, (SEED >> 32) as u32];
    let out = k
        .run(&g, &[&key], 8 * n, [(n as u32).div_ceil(64), 1, 1])
        .unwrap();
    let sampler = Sampler::new(SEED);
    for y in 0..H {
        for x in 0..W {
            for i in 0..INDICES {
                let s = sampler.stream(x, y, i);
                for block in 0..BLOCKS {
                    let m = (((y * W + x) * INDICES + i) * BLOCKS + block) as usize;
                    let cpu = s.block_bits(block);
                    assert_eq!(
                        &out[8 * m..8 * m + 4],
                        &cpu,
                        "({x}, {y}) #{i} block {block}"
                    );
                    for (k, &bits) in cpu.iter().enumerate() {
                        let f = f32::from_bits(out[8 * m + 4 + k]);
                        assert_eq!(f, unit_f32(bits));
                        // The f32 value is the CPU's f64 value truncated to 24 bits.
                        let d = s.get(4 * block + k as u32);
                        assert_eq!(d, to_unit(bits));
                        assert!(f64::from(f) <= d && d - f64::from(f) < 1.0 / 16_777_216.0);
                    }
                }
            }
        }
    }
}
