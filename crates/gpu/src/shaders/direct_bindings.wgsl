// The wavefront `direct` and `path` integrators (GPU.md §7, first version): kernels over
// one wave of slots, a slot being one pixel at one sample index, per vertex depth d.
// Every pass after the camera's and the first shade runs over a queue the pass before
// filled (atomics and an indirect dispatch written by `prepare`, GPU.md §7.4), not over
// every slot:
//
//   trace (mode 0)  one invocation per slot: camera ray → nearest object or area light →
//                   hit point, outward normal, material; the emitter seen directly goes
//                   to the outside-MIS sum.
//   shade           one invocation per (slot at depth 0, live slot after it; draw
//                   j ≤ Σ n_k): the draw of its
//                   technique at the vertex (dimensions of state::dims),
//                   every technique's pdf in its direction, β·f_s·|cos| and the nearest
//                   light's emission along it, a shadow ray (queued) where both are
//                   non-zero. The draw that extends the path (the BSDF technique's first,
//                   or the extra draw j = Σ n_k without one) writes the continuation ray
//                   (queued), β after it and Russian roulette (render::integrator::path).
//   trace (mode 1)  one invocation per queued shadow ray: its any-hit query.
//   trace (mode 2)  one invocation per queued continuation: its nearest hit, which gives
//                   the extending draw its Li and the path its next vertex (the slot
//                   joins the next depth's live queue).
//
// The wave's draws are then added to the per-pixel records: on the GPU (gpu::record) or
// by the CPU (state::Tally).
// Trace is one entry point for both modes so that the costly intersectors compile once.
// Every loop iteration counts against `loops` (GPU.md §3.1); the maximum per invocation
// and kernel goes to stats[mode].
//
// Needs FLOAT_WGSL, LAYOUT_WGSL, PERTURBED_WGSL, QUADRIC_WGSL, PHILOX_WGSL,
// BSDF_STRUCT_WGSL, BSDF_WGSL, GPU_AREA_LIGHT_WGSL, LIGHT_WGSL, ENV_WGSL before it.

struct Frame {
    width: u32, height: u32, pixels: u32, slots: u32,
    sample: u32, n_shapes: u32, seed_lo: u32, seed_hi: u32,
    n_tech: u32, n_draws: u32, n_lights: u32, power_off: u32,
    area_off: u32, flags: u32, mode: u32, zero: u32,
    depth: u32, max_depth: u32, rr_depth: u32, stride: u32,
    carry: u32, n_delta: u32, per_slot: u32, spatial_off: u32,
    eye: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    forward: vec4<f32>,
    tech: array<vec4<u32>, 8>,
    count: array<vec4<u32>, 8>,
    env: GpuEnv,
    // The trained selection's table in sel_buf (0xffffffff: none; lo.xyz, scale.xyz,
    // then res³ pmfs over `z` lights), its cells per axis, the lights it covers.
    trained: vec4<u32>,
    // Where the live and continuation queues' entries start in `stats` (words), and the
    // first pixel of the band the wave covers (its `pixels` pixels in raster order).
    wave: vec4<u32>,
    // The light BVH in sel_buf: its nodes and trails (0xffffffff: none), its nodes'
    // count (gpu::light::tree_records).
    tree: vec4<u32>,
    // The BVH over the area lights' boxes in `nodes` and `items` (escape layout): its
    // first node, node count, first item.
    lbvh: vec4<u32>,
    // The media (gpu::direct::pack): the material of the first (a phase function: σ_t
    // in bsdf.k, the albedo as its colour), the camera's medium (NO_MEDIUM: vacuum),
    // whether rays walk through media, and the depth after whose vertices state::dims
    // puts the free flights' numbers (the options' max_depth, also for `direct`).
    media: vec4<u32>,
}

// One scene object: a single leaf (kind 0) or an intersection of plain-quadric leaves
// (kind 1), over `count` leaves (GpuObject) from `first`.
struct GpuShape { kind: u32, first: u32, count: u32, material: u32, lo: vec4<f32>, hi: vec4<f32> }

// A texture in place of a BSDF parameter (DirectScene's GpuTexture): a point-space
// checker (kind 1: a.xyz, b.xyz, scale in a.w), a solid pattern (2: noise.wgsl's pattern
// `code` with `size` octaves blending a.xyz at 0 to b.xyz at 1, scale in a.w) or an
// image by triplanar projection (3: RGB f32 pixels from sel_buf[code], size × b.x of
// them, scale in a.w, sharpness in b.y), clamped to [0, 1] where `clamp` is 1; 0: none.
struct GpuTexture { kind: u32, code: u32, size: u32, clamp: u32, a: vec4<f32>, b: vec4<f32> }

// A material: its BSDF with constant parameters, and textures in place of the colour
// (bsdf.rgb: diffuse reflectance, plastic's base, a conductor's η), a conductor's k
// (bsdf.k) and α (the first channel, clamped to [0, 1]); patterns and images are read
// at the point in the object's own space (dot(lx.xyz, p) + lx.w, …) with the normal
// there (normalize(dot(nx.xyz, n), …)). `emission`: the radiance its surface sends out
// on the outer side (0: none). `coats.x`: a plastic with a textured α, its coat tables
// at α = k/32 (COAT_WORDS words each: r_int, then the albedos); `coats.y`, `coats.z`:
// the media inside and around an object wearing it (NO_MEDIUM: vacuum).
struct GpuMaterial {
    bsdf: GpuBsdf, tex: array<GpuTexture, 3>,
    lx: vec4<f32>, ly: vec4<f32>, lz: vec4<f32>,
    nx: vec4<f32>, ny: vec4<f32>, nz: vec4<f32>, emission: vec4<f32>, coats: vec4<u32>,
}

// Perlin's permutation for noise.wgsl, at the start of sel_buf (DirectScene::new).
fn noise_perm(i: u32) -> u32 { return u32(sel_buf[i]); }

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> shapes: array<GpuShape>;
@group(0) @binding(2) var<storage, read> objects: array<GpuObject>;
@group(0) @binding(3) var<storage, read> quadrics: array<GpuQuadric>;
@group(0) @binding(4) var<storage, read> perturbations: array<GpuPerturbation>;
@group(0) @binding(5) var<storage, read> nodes: array<GpuBvhNode>;
@group(0) @binding(6) var<storage, read> items: array<GpuItemBox>;
@group(0) @binding(7) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(8) var<storage, read> lights: array<GpuAreaLight>;
@group(0) @binding(9) var<storage, read> sel_buf: array<f32>;
@group(0) @binding(10) var<storage, read_write> hits: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> draws: array<vec4<f32>>;
// stats[0..3]: the most loop iterations per invocation (camera and continuation trace,
// shadow trace, shade); then three queues (GPU.md §7.4), each a length and an indirect
// dispatch (x, y, z): the shadow rays at stats[4..8] (entry q, a draw index, at
// stats[16 + q]), the live slots at stats[8..12] (the slots whose continuation met a
// surface: the next depth's vertices; entries from frame.wave.x) and the continuations at stats[12..16] (the
// slots whose extending draw has a ray; entries from frame.wave.y).
@group(0) @binding(12) var<storage, read_write> stats: array<atomic<u32>>;
// CSG nodes of kind-2 shapes in post-order: (op, leaf or part count, 0, 0), op 0 leaf,
// 1 union, 2 intersection, 3 difference.
@group(0) @binding(13) var<storage, read> csg: array<vec4<u32>>;
// The scene's expression tapes (GpuObject kind 2, its first_op the tape's index), one
// after another, run by `trace_tape` and `tape_normal` after `use_tape`, which
// the kernel's source defines per scene (stubs without a tape).
@group(0) @binding(14) var<storage, read> tape: array<u32>;

// vec4s per slot in `hits`: [p, status], [n, material], [wo, media (inside | outside
// << 16, 0xffff: vacuum)], [outside-MIS rgb, ·],
// [β, ·], then the continuation the shade pass chose: [o, traced], [wi, survives],
// [β after it and roulette, ·]; then the camera ray's first hit for AOVs: [its outward
// normal, depth], [albedo, ·] (integrator/aov.rs).
// HIT_WORDS (those vec4s), DRAW_HEAD (the vec4s of a draw record before its pdfs,
// one per 4 techniques), MAX_TECH and draw_vec4s (vec4s per draw in `draws`) come from
// gpu::record, prepended by gpu::record::wave_consts_wgsl.
const FLAG_HIDE: u32 = 1u;
const FLAG_CENTER: u32 = 2u;
const FLAG_ORTHO: u32 = 4u;
const FLAG_PER_LIGHT: u32 = 8u;
const FLAG_AOVS: u32 = 16u;
// Objects emit: the light a draw receives is found by a nearest-hit ray (the object in
// the way may be the light; render::integrator::medium::transmitted).
const FLAG_EMITTERS: u32 = 32u;
// Slot status (hits[·].w of word 0) and draw status (draws[·].w of word 1).
const S_NONE: f32 = 0.0;      // escaped or met a light: outside sum only
const S_SURFACE: f32 = 1.0;   // a shading point
const S_OVERFLOW: f32 = 2.0;  // a ray past a fixed capacity: the CPU redoes the sample
const D_FAILED: f32 = 1.0;    // no direction
const D_ZERO: f32 = 2.0;      // a direction whose integrand is 0 without a shadow ray
const D_SHADOW: f32 = 3.0;    // a direction with a shadow ray to trace
const D_VISIBLE: f32 = 4.0;   // traced: unoccluded
const D_OCCLUDED: f32 = 5.0;  // traced: occluded
const D_CARRIED: f32 = 6.0;   // the draw that extends the path: traced as its next ray
const D_SKIP: f32 = 7.0;      // a technique that does not draw at a purely specular vertex
// Flags in draws[·].w of word 2: an outside-MIS draw (a delta lobe), and a purely
// specular vertex (no MIS there: Integrator::shade).
const F_OUTSIDE: f32 = 1.0;
const F_PURE: f32 = 2.0;

const QUEUE_LEN: u32 = 4u;
const QUEUE_ARGS: u32 = 5u;
const QUEUE_ITEMS: u32 = 16u;
const LIVE_LEN: u32 = 8u;
const LIVE_ARGS: u32 = 9u;
const CONT_LEN: u32 = 12u;
const CONT_ARGS: u32 = 13u;

// Appends `slot` to the queue whose length is at stats[len] and entries at stats[items].
fn push(len: u32, items: u32, slot: u32) {
    let q = atomicAdd(&stats[len], 1u);
    atomicStore(&stats[items + q], slot);
}

// Media (render::integrator::medium): no medium (vacuum); the BSDF kinds of a medium's
// phase function and of an index-matched boundary (gpu::bsdf::PHASE,
// gpu::direct::pack::INTERFACE); the most media stretches one walk keeps and the most
// boundaries it crosses before it is taken as blocked.
const NO_MEDIUM: u32 = 0xffffffffu;
const K_PHASE: u32 = 4u;
const K_INTERFACE: u32 = 5u;
const MAX_SEGMENTS: u32 = 16u;
const MAX_CROSSINGS: u32 = 64u;

const T_BSDF: u32 = 0u;
const T_POWER: u32 = 1u;
const T_UNIFORM: u32 = 2u;
const T_AREA: u32 = 3u;
const T_ONE: u32 = 4u;
const T_ENV: u32 = 5u;
const T_SPATIAL: u32 = 6u;
const T_TRAINED: u32 = 7u;
const T_COSINE: u32 = 8u;
const T_BVH: u32 = 9u;

fn bsdf_table(i: u32) -> f32 { return sel_buf[i]; }
