//! What a GPU render did beyond [`state::RenderStats`]: its stage times, waves,
//! overflow fallbacks and where its sums were kept, and the one-line and per-stage
//! forms front ends print.

use std::time::Duration;

/// Times of a GPU render's stages, summed over its waves.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StageTimes {
    /// Camera rays: generation and nearest hit (GPU timestamps; zero without them).
    pub camera: Duration,
    /// The techniques' draws and pdfs (GPU).
    pub shade: Duration,
    /// Shadow rays (GPU).
    pub shadow: Duration,
    /// Continuation rays of `path` (GPU).
    pub secondary: Duration,
    /// Submission and read-back: the wall time from submitting a wave to having its
    /// results on the CPU, less the passes' GPU time (all of it without timestamps).
    pub readback: Duration,
    /// Adding the samples into the per-pixel records: where the sums are on the GPU,
    /// its terms and sums passes (timestamps) and the CPU's fallback samples and final
    /// read-back; otherwise the CPU adding every draw, fallbacks included.
    pub accumulate: Duration,
    /// Pipeline creation (shader compilation), before the first wave.
    pub setup: Duration,
}

/// Where a GPU render kept its per-pixel sums (GPU.md §8).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SumsOn {
    /// On the CPU: every draw read back and added by the CPU's accumulator
    /// (`FREPRAY_GPU_SUMS=off`, or terms past the loop budget).
    #[default]
    Cpu,
    /// On the GPU in f64 (`SHADER_F64`).
    GpuF64,
    /// On the GPU in double-float pairs of f32.
    GpuDoubleFloat,
}

impl std::fmt::Display for SumsOn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SumsOn::Cpu => "CPU",
            SumsOn::GpuF64 => "GPU, f64",
            SumsOn::GpuDoubleFloat => "GPU, double-float",
        })
    }
}

/// What a GPU render did, beyond [`state::RenderStats`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GpuStats {
    /// Stage times.
    pub stages: StageTimes,
    /// Waves.
    pub waves: u32,
    /// Samples the CPU rendered because the GPU could not answer a ray exactly (a fixed
    /// capacity or loop budget ran out, or f32 rounding left a hit or miss open).
    pub cpu_fallbacks: u64,
    /// The pixel (y·width + x) of each of those samples, in the order rendered.
    pub fallback_pixels: Vec<u32>,
    /// Where the per-pixel sums were kept.
    pub sums: SumsOn,
    /// The most loop iterations one invocation ran, per kernel: camera and
    /// continuation trace, shadow trace, shade (GPU.md §3.1: llvmpipe cuts an invocation's loops at 65 535).
    pub max_loops: [u32; 3],
}

impl GpuStats {
    /// The stages as (name, time), in pass order, for tables and stacked bars: the four
    /// passes (GPU timestamps), submission and read-back, accumulation.
    pub fn stage_parts(&self) -> [(&'static str, Duration); 6] {
        let s = &self.stages;
        [
            ("camera rays (GPU)", s.camera),
            ("shade (GPU)", s.shade),
            ("shadow rays (GPU)", s.shadow),
            ("continuation rays (GPU)", s.secondary),
            ("submit and read back (wall − passes)", s.readback),
            ("accumulate", s.accumulate),
        ]
    }
}

impl GpuStats {
    /// Where the sums were kept, the kernels' setup time, waves and loop counts: what
    /// a stage table leaves out.
    pub fn counters(&self) -> String {
        format!(
            "per-pixel sums on the {}; kernel setup {:.1} ms (excluded); {} waves; most loop \
             iterations per invocation (camera, shadow, shade) {:?}",
            self.sums,
            self.stages.setup.as_secs_f64() * 1e3,
            self.waves,
            self.max_loops
        )
    }
}

/// One line: the stage times and counters.
impl std::fmt::Display for GpuStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.stages;
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        write!(
            f,
            "GPU stages: camera rays {:.1} ms, shade {:.1} ms, shadow rays {:.1} ms, \
             continuation rays {:.1} ms (GPU timestamps); readback {:.1} ms, accumulate \
             {:.1} ms (sums on the {}); setup {:.1} ms; {} waves; {} samples rendered on \
             the CPU (rays the GPU could not answer exactly); most loop iterations per invocation {:?}",
            ms(s.camera),
            ms(s.shade),
            ms(s.shadow),
            ms(s.secondary),
            ms(s.readback),
            ms(s.accumulate),
            self.sums,
            ms(s.setup),
            self.waves,
            self.cpu_fallbacks,
            self.max_loops
        )
    }
}
