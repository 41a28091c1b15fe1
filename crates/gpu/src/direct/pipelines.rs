//! The kernels' WGSL assembled (the shared helpers, the scene's tape tracer, the
//! `direct` kernels), compiled into the trace, shade and prepare pipelines, and kept per
//! scene variant by [`Gpu`].

use super::pack::DirectScene;
use super::DIRECT_WGSL;
use crate::bsdf::{BSDF_STRUCT_WGSL, BSDF_WGSL};
use crate::env::ENV_WGSL;
use crate::layout::LAYOUT_WGSL;
use crate::light::{GPU_AREA_LIGHT_WGSL, LIGHT_WGSL};
use crate::noise::NOISE_WGSL;
use crate::perturbed::PERTURBED_WGSL;
use crate::quadric::QUADRIC_WGSL;
use crate::record::wave_consts_wgsl;
use crate::sampler::PHILOX_WGSL;
use crate::tape_trace::TapeSolid;
use crate::{Gpu, GpuError, FLOAT_WGSL, TRIG_WGSL};

impl DirectScene {
    /// What differs between the kernels of scenes: the tape tracer (`tape_wgsl`),
    /// `perturbed_scan`, the perturbed-quadric scan or, in a scene without perturbed
    /// quadrics, a stub that hands the ray to the CPU (never called there), and `MEDIA`,
    /// whether rays walk through media and index-matched boundaries. The scan is
    /// most of the trace kernel: without it llvmpipe compiles that kernel in 2.5 s
    /// instead of 17.5 s (scenes/cornell.toml). The key of the compiled kernels.
    pub fn variant_wgsl(&self) -> String {
        let scan = if self.leaves.iter().any(|o| o.kind == 1) {
            "fn perturbed_scan(oi: u32, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> ScanResult {
    return perturbed_first_crossing(oi, o, d, t_min, t_max);
}
"
        } else {
            "fn perturbed_scan(oi: u32, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> ScanResult {
    return ScanResult(2u, 0.0);
}
"
        };
        // Walks through media and index-matched boundaries (the trace kernel's loop,
        // which a scene without them never enters twice).
        let media = format!("const MEDIA: bool = {};\n", self.frame.media[2] != 0);
        self.tape_wgsl() + scan + &media
    }

    /// The WGSL that defines `use_tape`, `trace_tape` and `tape_normal`: the tape
    /// tracer with this scene's tapes, or stubs. The tracer's helpers share names with
    /// the perturbed scan's: the duplicates go, and its ε becomes `TAPE_EPS`.
    fn tape_wgsl(&self) -> String {
        if self.tapes.is_empty() {
            return "struct TraceResult { status: u32, t: f32 }
fn use_tape(k: u32) {}
fn trace_tape(o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> TraceResult { return TraceResult(0u, 0.0); }
fn tape_normal(p: vec3<f32>) -> vec3<f32> { return vec3<f32>(0.0, 0.0, 1.0); }
"
            .into();
        }
        let src = TapeSolid::scene_wgsl(&self.tapes)
            .replacen(FLOAT_WGSL, "", 1)
            .replacen(TRIG_WGSL, "", 1)
            .replacen("var<private> loops: u32;", "", 1)
            .replacen(
                "const MIN_POS: f32 = 0x1p-126f; // f32::MIN_POSITIVE",
                "",
                1,
            );
        let word = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
        let mut out = String::with_capacity(src.len());
        let mut rest = src.as_str();
        while let Some(i) = rest.find("EPS") {
            let whole = !word(rest[..i].chars().next_back()) && !word(rest[i + 3..].chars().next());
            out.push_str(&rest[..i]);
            out.push_str(if whole { "TAPE_EPS" } else { "EPS" });
            rest = &rest[i + 3..];
        }
        out.push_str(rest);
        out + "
// The outward normal −∇F/|∇F| by central differences of 10³ ε (the tape has no
// derivative code at points; F is smooth where a ray meets it). At a cap, a hit on the
// face of the box the tracer clips to (a solid its bounds cut, F ≥ 0 there: Fidget's
// prospero is a flat text extruded through its box), the face's outward normal, as
// frep's `face_normal`; ∇F there lies along the face and sent shading and shadow rays
// astray (rays down a letter's wall, each at the loop budget).
fn tape_normal(p: vec3<f32>) -> vec3<f32> {
    let glo = BLO - vec3<f32>(TAPE_EPS);
    let ghi = BHI + vec3<f32>(TAPE_EPS);
    var best = max(TAPE_EPS, 1e-6 * (1.0 + max(abs(p.x), max(abs(p.y), abs(p.z)))));
    var face = vec3<f32>(0.0, 0.0, 0.0);
    for (var k = 0u; k < 3u; k++) {
        loops++;
        let below = abs(p[k] - glo[k]);
        if (below <= best) {
            best = below;
            face = vec3<f32>(0.0, 0.0, 0.0);
            face[k] = -1.0;
        }
        let above = abs(ghi[k] - p[k]);
        if (above <= best) {
            best = above;
            face = vec3<f32>(0.0, 0.0, 0.0);
            face[k] = 1.0;
        }
    }
    if (any(face != vec3<f32>(0.0, 0.0, 0.0))) { return face; }
    let h = 500.0 * TAPE_EPS;
    var v: array<f32, 6>;
    for (var k = 0u; k < 6u; k++) {
        loops++;
        var q = p;
        q[k / 2u] += select(-h, h, (k & 1u) == 0u);
        v[k] = eval_point(q);
    }
    let g = vec3<f32>(v[0] - v[1], v[2] - v[3], v[4] - v[5]);
    let l = length(g);
    if (l > 0.0 && is_finite(l)) { return -g / l; }
    return vec3<f32>(0.0, 0.0, 1.0);
}
"
    }
}

/// The compiled kernels, kept by [`Gpu`] for every later render.
pub(crate) struct Pipelines {
    /// Entry `trace`: camera, shadow and continuation rays, and probes (by frame mode).
    pub(super) trace: wgpu::ComputePipeline,
    /// Entry `shade`: one draw of a vertex.
    pub(super) shade: wgpu::ComputePipeline,
    /// Entry `prepare`: a queued pass's indirect dispatch.
    pub(super) prepare: wgpu::ComputePipeline,
    /// Their bind group's layout (bindings 0–14).
    pub(super) layout: wgpu::BindGroupLayout,
}

/// The whole source of the kernels: the shared helpers, the scene's variant
/// ([`DirectScene::variant_wgsl`]), the wave records' constants ([`wave_consts_wgsl`]),
/// then [`DIRECT_WGSL`].
fn kernel_source(variant_wgsl: &str) -> String {
    [
        FLOAT_WGSL,
        TRIG_WGSL,
        NOISE_WGSL,
        LAYOUT_WGSL,
        PERTURBED_WGSL,
        QUADRIC_WGSL,
        PHILOX_WGSL,
        BSDF_STRUCT_WGSL,
        BSDF_WGSL,
        GPU_AREA_LIGHT_WGSL,
        LIGHT_WGSL,
        ENV_WGSL,
        variant_wgsl,
        &wave_consts_wgsl(),
        DIRECT_WGSL,
    ]
    .join("\n")
}

/// The bind group's entries: the frame block (0), the read-only scene (1–9), the wave's
/// hits, draws and stats (10–12), then CSG nodes and tapes (13–14).
fn layout_entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let mut entries = vec![entry(0, wgpu::BufferBindingType::Uniform)];
    for b in 1..=9 {
        entries.push(entry(
            b,
            wgpu::BufferBindingType::Storage { read_only: true },
        ));
    }
    for b in 10..=12 {
        entries.push(entry(
            b,
            wgpu::BufferBindingType::Storage { read_only: false },
        ));
    }
    for b in 13..=14 {
        entries.push(entry(
            b,
            wgpu::BufferBindingType::Storage { read_only: true },
        ));
    }
    entries
}

/// Compiles the kernels with `variant_wgsl` (validation errors become [`GpuError::Run`]).
fn compile(gpu: &Gpu, variant_wgsl: &str) -> Result<Pipelines, GpuError> {
    let d = &gpu.device;
    let need = 14u32;
    let have = d.limits().max_storage_buffers_per_shader_stage;
    if have < need {
        return Err(GpuError::Limit {
            limit: "max_storage_buffers_per_shader_stage",
            have: u64::from(have),
            need: u64::from(need),
        });
    }
    let source = kernel_source(variant_wgsl);
    let scope = d.push_error_scope(wgpu::ErrorFilter::Validation);
    let entries = layout_entries();
    let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("direct"),
        entries: &entries,
    });
    let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("direct"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let desc = wgpu::ShaderModuleDescriptor {
        label: Some("direct"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    };
    let module = if gpu.info().checked {
        d.create_shader_module(desc)
    } else {
        // SAFETY: every index of the kernels is bounded by construction (fixed arrays
        // with guarded counters, buffers sized from the packed scene and the wave) and
        // every loop is bounded; GPU.md §3.4 measured naga's checks at up to 20× on
        // lavapipe. `GpuOptions::checked` compiles them with the checks, and a test
        // renders so and compares.
        unsafe { d.create_shader_module_trusted(desc, wgpu::ShaderRuntimeChecks::unchecked()) }
    };
    // A pipeline and the validation error of making it. Error scopes are per thread.
    let make = |entry: &str| {
        let scope = d.push_error_scope(wgpu::ErrorFilter::Validation);
        let p = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pl),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
        (p, pollster::block_on(scope.pop()))
    };
    // Each on a thread of its own: lavapipe compiles a pipeline on the calling thread.
    let ([trace, shade, prepare], error) = std::thread::scope(|s| {
        let others = ["trace", "prepare"].map(|e| s.spawn(move || make(e)));
        let shade = make("shade");
        let [trace, prepare] =
            others.map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)));
        let error = [&trace, &shade, &prepare]
            .into_iter()
            .find_map(|(_, e)| e.as_ref().map(ToString::to_string));
        ([trace.0, shade.0, prepare.0], error)
    });
    if let Some(e) = pollster::block_on(scope.pop())
        .map(|e| e.to_string())
        .or(error)
    {
        return Err(GpuError::Run(format!("direct kernels: {e}")));
    }
    Ok(Pipelines {
        trace,
        shade,
        prepare,
        layout,
    })
}

/// The kernels for `pack`'s variant, compiled on first use and kept by `gpu`.
pub(super) fn kernels(
    gpu: &Gpu,
    pack: &DirectScene,
) -> Result<std::sync::Arc<Pipelines>, GpuError> {
    let variant = pack.variant_wgsl();
    gpu.kernels.get_or_make(&variant, || compile(gpu, &variant))
}
