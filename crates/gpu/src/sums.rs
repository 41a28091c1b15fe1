//! Per-pixel MIS sums on the GPU (GPU.md §8): each pixel keeps S sums (`mis::Moments`'
//! Â and b̂, the heuristics' sums, AOVs) to which every sample adds one f32 term per sum.
//! Where the device has `SHADER_F64` they are f64 (`sums_f64.wgsl`; f32 → f64 and `+`
//! are exact, GPU.md §3.3); otherwise double-float pairs (hi, lo) of f32 grown by TwoSum
//! (Knuth, TAOCP vol. 2 §4.2.2; Møller 1965) in `sums.wgsl`, laundered so that the
//! compiler cannot fold the compensation away (GPU.md §3.2). [`df_add`] is the CPU twin
//! of the double-float kernel, equal to it bit for bit on lavapipe.
//!
//! A double-float sum of f32 terms is exact while the exact sum needs at most 48
//! significant bits and no renormalisation rounds; in general each [`df_add`] errs by at
//! most about 2⁻⁴⁷ |hi| (the rounding of `p.y + acc.y`), so n terms stay within about
//! n · 2⁻⁴⁷ of the largest partial sum.

use crate::{Gpu, GpuError, Kernel};

/// Double-float addition (`opaque`, `two_sum`, `df_add`), for kernels that bind
/// `params: array<u32>` with `params[0] == 0`.
pub const DF_WGSL: &str = include_str!("shaders/df.wgsl");
/// The double-float kernel (entry `accumulate_df`).
pub const SUMS_WGSL: &str = concat!(
    include_str!("shaders/df.wgsl"),
    include_str!("shaders/sums.wgsl")
);
/// The f64 kernel (entry `accumulate_f64`; needs `SHADER_F64`).
pub const SUMS_F64_WGSL: &str = include_str!("shaders/sums_f64.wgsl");

/// Pixels per workgroup of both kernels.
pub const WORKGROUP: u32 = 64;

/// s + e = a + b exactly with s = fl(a + b) (TwoSum; the kernel's `two_sum`).
pub fn two_sum(a: f32, b: f32) -> [f32; 2] {
    let s = a + b;
    let bb = s - a;
    [s, (a - (s - bb)) + (b - bb)]
}

/// (hi, lo) + v, renormalised: the kernel's `df_add`, operation for operation.
pub fn df_add(acc: [f32; 2], v: f32) -> [f32; 2] {
    let p = two_sum(acc[0], v);
    two_sum(p[0], p[1] + acc[1])
}

/// The value of a double-float pair (exact in f64).
pub fn df_value(x: [f32; 2]) -> f64 {
    f64::from(x[0]) + f64::from(x[1])
}

/// Per-pixel sums after a batch of samples, in the precision the device used.
#[derive(Clone, Debug, PartialEq)]
pub enum Sums {
    /// f64 sums (`SHADER_F64`).
    F64(Vec<f64>),
    /// Double-float pairs (hi, lo).
    DoubleFloat(Vec<[f32; 2]>),
}

impl Sums {
    /// Every sum as f64 (exact for both kinds).
    pub fn values(&self) -> Vec<f64> {
        match self {
            Sums::F64(v) => v.clone(),
            Sums::DoubleFloat(v) => v.iter().map(|&x| df_value(x)).collect(),
        }
    }
}

/// The accumulation kernel for the device: f64 where it has `SHADER_F64` (and the
/// options allowed it), double-float otherwise.
pub struct Accumulate {
    kernel: Kernel,
    f64: bool,
}

impl Accumulate {
    /// Compiles the kernel the device's precision calls for.
    pub fn new(gpu: &Gpu) -> Result<Accumulate, GpuError> {
        Self::with_f64(gpu, gpu.info().f64)
    }

    /// Compiles the f64 kernel if `f64` (the device must have `SHADER_F64`), else the
    /// double-float one.
    pub fn with_f64(gpu: &Gpu, f64: bool) -> Result<Accumulate, GpuError> {
        let kernel = if f64 {
            Kernel::new(gpu, SUMS_F64_WGSL, "accumulate_f64", 3)?
        } else {
            Kernel::new(gpu, SUMS_WGSL, "accumulate_df", 3)?
        };
        Ok(Accumulate { kernel, f64 })
    }

    /// Whether the sums are f64.
    pub fn is_f64(&self) -> bool {
        self.f64
    }

    /// The compiled pipeline (bindings: params, terms, prev, state).
    pub(crate) fn pipeline(&self) -> &wgpu::ComputePipeline {
        self.kernel.pipeline()
    }

    /// `prev` (S sums per pixel, [`Sums::F64`] or [`Sums::DoubleFloat`] as
    /// [`Self::is_f64`]) plus `terms[(pixel · samples + sample) · s + k]`, each sum in
    /// sample order. Each invocation loops `samples · s` times: keep that far below
    /// llvmpipe's 65 535 (GPU.md §3.1).
    pub fn run(
        &self,
        gpu: &Gpu,
        prev: &Sums,
        terms: &[f32],
        samples: u32,
        s: u32,
    ) -> Result<Sums, GpuError> {
        let pixels = terms.len() / (samples as usize * s as usize);
        assert_eq!(
            terms.len(),
            pixels * samples as usize * s as usize,
            "whole pixels"
        );
        assert!(
            u64::from(samples) * u64::from(s) < 30_000,
            "loop budget (GPU.md §3.1)"
        );
        let params = [0u32, pixels as u32, samples, s];
        let prev_words: Vec<u32> = match (prev, self.f64) {
            (Sums::F64(v), true) => v.iter().flat_map(|x| split(x.to_bits())).collect(),
            (Sums::DoubleFloat(v), false) => v.iter().flatten().map(|x| x.to_bits()).collect(),
            _ => return Err(GpuError::Run("sums of the other precision".into())),
        };
        assert_eq!(
            prev_words.len(),
            2 * pixels * s as usize,
            "S sums per pixel"
        );
        let terms: Vec<u32> = terms.iter().map(|x| x.to_bits()).collect();
        let groups = (pixels as u32).div_ceil(WORKGROUP);
        let out = self.kernel.run(
            gpu,
            &[&params, &terms, &prev_words],
            prev_words.len(),
            [groups, 1, 1],
        )?;
        Ok(if self.f64 {
            Sums::F64(
                out.chunks(2)
                    .map(|w| f64::from_bits(u64::from(w[0]) | u64::from(w[1]) << 32))
                    .collect(),
            )
        } else {
            Sums::DoubleFloat(
                out.chunks(2)
                    .map(|w| [f32::from_bits(w[0]), f32::from_bits(w[1])])
                    .collect(),
            )
        })
    }
}

fn split(x: u64) -> [u32; 2] {
    [x as u32, (x >> 32) as u32]
}
