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
//                   technique at the vertex (dimensions of render::integrator::dims),
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
// by the CPU (render::integrator::Accumulator).
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
    tech: array<vec4<u32>, 2>,
    count: array<vec4<u32>, 2>,
    env: GpuEnv,
    // The trained selection's table in sel_buf (0xffffffff: none; lo.xyz, scale.xyz,
    // then res³ pmfs over `z` lights), its cells per axis, the lights it covers.
    trained: vec4<u32>,
    // Where the live and continuation queues' entries start in `stats` (words), and the
    // first pixel of the band the wave covers (its `pixels` pixels in raster order).
    wave: vec4<u32>,
}

// One scene object: a single leaf (kind 0) or an intersection of plain-quadric leaves
// (kind 1), over `count` leaves (GpuObject) from `first`.
struct GpuShape { kind: u32, first: u32, count: u32, material: u32, lo: vec4<f32>, hi: vec4<f32> }

// A material: its BSDF with constant colours, and a point-space checker replacing
// bsdf.rgb where tex_kind is 1 (a.xyz, b.xyz, scale in a.w).
struct GpuMaterial { bsdf: GpuBsdf, tex_kind: u32, pad0: u32, pad1: u32, pad2: u32, a: vec4<f32>, b: vec4<f32> }

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
// The scene's expression tapes (GpuObject kind 2, its first_op the tape's index), each
// padded to the longest, run by `trace_tape` and `tape_normal` after `use_tape`, which
// the kernel's source defines per scene (stubs without a tape).
@group(0) @binding(14) var<storage, read> tape: array<u32>;

// vec4s per slot in `hits`: [p, status], [n, material], [wo, ·], [outside-MIS rgb, ·],
// [β, ·], then the continuation the shade pass chose: [o, traced], [wi, survives],
// [β after it and roulette, ·]; then the camera ray's first hit for AOVs: [its outward
// normal, depth], [albedo, ·] (integrator/aov.rs).
const HIT_WORDS: u32 = 10u;
const DRAW_WORDS: u32 = 5u;   // vec4s per draw in `draws`
const FLAG_HIDE: u32 = 1u;
const FLAG_CENTER: u32 = 2u;
const FLAG_ORTHO: u32 = 4u;
const FLAG_PER_LIGHT: u32 = 8u;
const FLAG_AOVS: u32 = 16u;
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

const T_BSDF: u32 = 0u;
const T_POWER: u32 = 1u;
const T_UNIFORM: u32 = 2u;
const T_AREA: u32 = 3u;
const T_ONE: u32 = 4u;
const T_ENV: u32 = 5u;
const T_SPATIAL: u32 = 6u;
const T_TRAINED: u32 = 7u;

fn bsdf_table(i: u32) -> f32 { return sel_buf[i]; }

// --- random numbers: render::sampler, truncated to 24 bits ---------------------------

fn rnd(px: u32, py: u32, index: u32, dim: u32) -> f32 {
    let b = philox4x32_10(vec4<u32>(px, py, index, dim / 4u), vec2<u32>(frame.seed_lo, frame.seed_hi));
    return philox_unit(b[dim % 4u]);
}

// --- frames (render::frame::Frame::from_z, Duff et al. 2017) -------------------------

struct Basis { s: vec3<f32>, t: vec3<f32>, n: vec3<f32> }

fn basis(n: vec3<f32>) -> Basis {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let s = vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let t = vec3<f32>(b, sign + n.y * n.y * a, -n.y);
    return Basis(s, t, n);
}

fn to_local(f: Basis, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, f.s), dot(v, f.t), dot(v, f.n));
}

fn from_local(f: Basis, v: vec3<f32>) -> vec3<f32> {
    return f.s * v.x + f.t * v.y + f.n * v.z;
}

// --- objects ---------------------------------------------------------------------------

// (t_near, t_far) of the box along the ray, clipped to (t0, t1); x > y when missed.
fn clip_box(lo: vec3<f32>, hi: vec3<f32>, o: vec3<f32>, inv: vec3<f32>, t0: f32, t1: f32) -> vec2<f32> {
    let a = (lo - o) * inv;
    let b = (hi - o) * inv;
    let near = min(a, b);
    let far = max(a, b);
    // NaN (0·∞ on an axis the ray runs along inside a face) keeps the other axes' bounds.
    var tn = t0;
    var tf = t1;
    for (var k = 0u; k < 3u; k++) {
        if (!is_nan(near[k])) { tn = max(tn, near[k]); }
        if (!is_nan(far[k])) { tf = min(tf, far[k]); }
    }
    return vec2<f32>(tn, tf);
}

// frep's Solid::plain_intersection in f32: the inside set along the ray is the
// intersection of the parts' positive sets; its first end in (t_min, t_max), with the
// leaf that makes it. (t, leaf bits, 1) or (0, 0, 0).
fn plain_intersection(sh: GpuShape, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> vec3<f32> {
    var a: array<f32, 10>;
    var b: array<f32, 10>;
    var ka: array<u32, 10>;
    var kb: array<u32, 10>;
    a[0] = -inf();
    b[0] = inf();
    ka[0] = sh.first;
    kb[0] = sh.first;
    var n = 1u;
    for (var k = 0u; k < sh.count; k++) {
        loops++;
        let leaf = sh.first + k;
        let ps = positive_set(q_local(quadrics[objects[leaf].first_op].c, o, d));
        var na: array<f32, 10>;
        var nb: array<f32, 10>;
        var nka: array<u32, 10>;
        var nkb: array<u32, 10>;
        var m = 0u;
        for (var j = 0u; j < n; j++) {
            for (var w = 0u; w < ps.n; w++) {
                loops++;
                let c = ps.s[2u * w];
                let e = ps.s[2u * w + 1u];
                var lo = a[j];
                var klo = ka[j];
                if (c > lo) { lo = c; klo = leaf; }
                var hi = b[j];
                var khi = kb[j];
                if (e < hi) { hi = e; khi = leaf; }
                if (lo < hi && m < 10u) {
                    na[m] = lo; nb[m] = hi; nka[m] = klo; nkb[m] = khi;
                    m++;
                }
            }
        }
        if (m == 0u) { return vec3<f32>(0.0); }
        a = na; b = nb; ka = nka; kb = nkb;
        n = m;
    }
    var best = inf();
    var which = 0u;
    for (var j = 0u; j < n; j++) {
        loops++;
        if (a[j] > t_min && a[j] < t_max && is_finite(a[j]) && a[j] < best) { best = a[j]; which = ka[j]; }
        if (b[j] > t_min && b[j] < t_max && is_finite(b[j]) && b[j] < best) { best = b[j]; which = kb[j]; }
    }
    if (best == inf()) { return vec3<f32>(0.0); }
    return vec3<f32>(best, bitcast<f32>(which), 1.0);
}

// --- CSG by inside spans ------------------------------------------------------------------
//
// Each leaf's inside set along the ray is a sorted list of ends; a node's is the boolean
// combination of its parts' (a sweep over their sorted ends), so the post-order node list
// runs on a stack of span lists in a fixed pool. An end keeps the leaf whose root it is,
// and a flip bit (bit 31) where a difference turns that leaf's outside in (its normal
// then points the other way, as frep's combine). The crossing is the first end in
// (t_min, t_max). A pool or stack overflow is reported (status 2), never a miss.
//
// A plain quadric's ends are its positive set on the whole line (≤ 2 intervals, closed
// form). A perturbed or expression part has no closed form: its ends are its crossings
// found one by one, as frep's combine finds them, from a nudge before its box (where it
// is outside) to the window's end (the shape's box grown, on (t_min, t_max)), each search
// starting a nudge past the last end. Those searches are the scene's costly crossing
// functions, which llvmpipe inlines at every call site (GPU.md, compile time), so the
// walk is resumable: `csg_run` stops at a general part and asks `scene_trace`, whose one
// call site runs every search, then `csg_feed` takes each answer.

const SPAN_POOL: u32 = 64u;
const SPAN_LISTS: u32 = 16u;
// Past this many loop iterations a CSG walk reports overflow (the CPU renders the
// sample), so that its repeated searches keep the invocation's budget (GPU.md §3.1).
const CSG_BUDGET: u32 = 28000u;
var<private> sp_t: array<f32, SPAN_POOL>;
var<private> sp_k: array<u32, SPAN_POOL>;
var<private> tmp_t: array<f32, SPAN_POOL>;
var<private> tmp_k: array<u32, SPAN_POOL>;
var<private> ls_at: array<u32, SPAN_LISTS>;

// The walk of one CSG shape: its nodes, the next one, the pool and stack in use, the
// segment and window, and the general part being searched (from cs_ta to cs_tb).
var<private> cs_first: u32;
var<private> cs_count: u32;
var<private> cs_i: u32;
var<private> cs_top: u32;
var<private> cs_nl: u32;
var<private> cs_tmin: f32;
var<private> cs_tmax: f32;
var<private> cs_w: vec2<f32>;
var<private> cs_general: bool;
var<private> cs_pending: bool;
var<private> cs_leaf: u32;
var<private> cs_ta: f32;
var<private> cs_tb: f32;
var<private> cs_nudge: f32;

fn csg_inside(op: u32, first: bool, inside: u32, count: u32) -> bool {
    if (op == 1u) { return inside > 0u; }
    if (op == 2u) { return inside == count; }
    // Difference: inside the first part, outside every other.
    return first && inside == 1u;
}

fn csg_start(sh: GpuShape, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) {
    cs_first = sh.first;
    cs_count = sh.count;
    cs_i = 0u;
    cs_top = 0u;
    cs_nl = 0u;
    cs_tmin = t_min;
    cs_tmax = t_max;
    let grow = vec3<f32>(1e-5 * length(sh.hi.xyz - sh.lo.xyz));
    let inv = vec3<f32>(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
    cs_w = clip_box(sh.lo.xyz - grow, sh.hi.xyz + grow, o, inv, t_min, t_max);
    cs_general = false;
    cs_pending = false;
}

// Takes a general part's search answer (status 0 none, 1 at t, 2 overflow): 0 when that
// part has more to search, 1 when it is done, 2 on overflow.
fn csg_feed(status: u32, t: f32) -> u32 {
    if (status == 2u || loops > CSG_BUDGET) { return 2u; }
    if (status == 1u) {
        if (cs_top == SPAN_POOL) { return 2u; }
        sp_t[cs_top] = t;
        sp_k[cs_top] = cs_leaf;
        cs_top++;
        cs_ta = t + cs_nudge + 1e-6 * abs(t);
        if (cs_ta < cs_tb) { return 0u; }
    }
    cs_pending = false;
    return 1u;
}

// Runs the walk on from node cs_i: (t, leaf | flip << 31 bits, status) with status 0
// miss, 1 hit, 2 overflow, 3 a general part's search wanted (cs_leaf, cs_ta, cs_tb).
fn csg_run(o: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    var top = cs_top;
    var nl = cs_nl;
    for (var i = cs_i; i < cs_count; i++) {
        loops++;
        let node = csg[cs_first + i];
        if (node.x == 0u && objects[node.y].kind != 0u) {
            if (nl == SPAN_LISTS) { return vec3<f32>(0.0, 0.0, 2.0); }
            if (!(cs_w.x <= cs_w.y)) { return vec3<f32>(0.0); }
            ls_at[nl] = top;
            nl++;
            cs_general = true;
            let ob = objects[node.y];
            let lo = vec3<f32>(ob.lo_x, ob.lo_y, ob.lo_z);
            let hi = vec3<f32>(ob.hi_x, ob.hi_y, ob.hi_z);
            let inv = vec3<f32>(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
            let c = clip_box(lo, hi, o, inv, -inf(), cs_w.y);
            if (!(c.x <= c.y)) { continue; }
            cs_nudge = 8e-6 * length(hi - lo) / length(d);
            cs_leaf = node.y;
            cs_ta = c.x - cs_nudge - 1e-6 * abs(c.x);
            cs_tb = c.y;
            cs_pending = true;
            cs_i = i + 1u;
            cs_top = top;
            cs_nl = nl;
            return vec3<f32>(0.0, 0.0, 3.0);
        }
        if (node.x == 0u) {
            if (nl == SPAN_LISTS || top + 4u > SPAN_POOL) { return vec3<f32>(0.0, 0.0, 2.0); }
            let ps = positive_set(q_local(quadrics[objects[node.y].first_op].c, o, d));
            ls_at[nl] = top;
            nl++;
            for (var w = 0u; w < 2u * ps.n; w++) {
                loops++;
                sp_t[top] = ps.s[w];
                sp_k[top] = node.y;
                top++;
            }
            continue;
        }
        // Combine the last `node.y` lists: repeated selection of the least head.
        let k = node.y;
        let base = ls_at[nl - k];
        var head: array<u32, 8>;
        var end: array<u32, 8>;
        var inside_j: array<bool, 8>;
        for (var j = 0u; j < k; j++) {
            loops++;
            head[j] = ls_at[nl - k + j];
            end[j] = top;
            if (j + 1u < k) { end[j] = ls_at[nl - k + j + 1u]; }
            inside_j[j] = false;
        }
        var inside = 0u;
        var state = false;
        var n = 0u;
        loop {
            loops += 1u + k;
            var best = 8u;
            var bt = 0.0;
            for (var j = 0u; j < k; j++) {
                if (head[j] < end[j] && (best == 8u || sp_t[head[j]] < bt)) {
                    best = j;
                    bt = sp_t[head[j]];
                }
            }
            if (best == 8u) { break; }
            let e = head[best];
            head[best]++;
            inside_j[best] = !inside_j[best];
            if (inside_j[best]) { inside++; } else { inside--; }
            let now = csg_inside(node.x, inside_j[0], inside, k);
            if (now != state) {
                state = now;
                if (n == SPAN_POOL) { return vec3<f32>(0.0, 0.0, 2.0); }
                var key = sp_k[e];
                if (node.x == 3u && best > 0u) { key = key ^ 0x80000000u; }
                tmp_t[n] = sp_t[e];
                tmp_k[n] = key;
                n++;
            }
        }
        if (base + n > SPAN_POOL) { return vec3<f32>(0.0, 0.0, 2.0); }
        for (var j = 0u; j < n; j++) {
            loops++;
            sp_t[base + j] = tmp_t[j];
            sp_k[base + j] = tmp_k[j];
        }
        top = base + n;
        nl = nl - k + 1u;
    }
    // A general part's ends are known only up to the window's end; before the window
    // the shape is empty.
    for (var j = 0u; j < top; j++) {
        loops++;
        let t = sp_t[j];
        let in_window = !cs_general || (t > cs_w.x && t <= cs_w.y);
        if (t > cs_tmin && t < cs_tmax && is_finite(t) && in_window) {
            return vec3<f32>(t, bitcast<f32>(sp_k[j]), 1.0);
        }
    }
    return vec3<f32>(0.0);
}

// Nearest (or, with `any`, some) object crossing in (0, t_max): (status, t, leaf) with
// status 0 none, 1 hit, 2 overflow. One loop over the shapes and the CSG walks' searches,
// so that each costly search has one call site.
struct SceneHit { status: u32, t: f32, leaf: u32 }

fn scene_trace(o: vec3<f32>, d: vec3<f32>, t_max: f32, any_hit: bool) -> SceneHit {
    let inv = vec3<f32>(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
    var res = SceneHit(0u, t_max, 0u);
    var s = 0u;
    var in_csg = false;
    loop {
        loops++;
        var search = false;
        var leaf = 0u;
        var ta = 0.0;
        var tb = res.t;
        if (in_csg) {
            search = cs_pending;
            leaf = cs_leaf;
            ta = cs_ta;
            tb = cs_tb;
        } else {
            if (s >= frame.n_shapes) { break; }
            let sh = shapes[s];
            s++;
            let c = clip_box(sh.lo.xyz, sh.hi.xyz, o, inv, 0.0, res.t);
            if (!(c.x <= c.y)) { continue; }
            leaf = sh.first;
            var found = false;
            var t = 0.0;
            if (sh.kind == 1u) {
                let r = plain_intersection(sh, o, d, 0.0, res.t);
                found = r.z == 1.0;
                t = r.x;
                leaf = bitcast<u32>(r.y);
            } else if (sh.kind == 2u) {
                csg_start(sh, o, d, 0.0, res.t);
                in_csg = true;
            } else if (objects[leaf].kind == 0u) {
                let r = quadric_first_crossing(quadrics[objects[leaf].first_op], o, d, 0.0, res.t);
                found = r.y == 1.0;
                t = r.x;
            } else {
                search = true;
            }
            if (found && t < res.t) {
                res = SceneHit(1u, t, leaf);
                if (any_hit) { return res; }
            }
            if (!search && !in_csg) { continue; }
        }
        var status = 0u;
        var t = 0.0;
        if (search) {
            if (objects[leaf].kind == 2u) {
                use_tape(objects[leaf].first_op);
                let r = trace_tape(o, d, ta, tb);
                status = r.status & 3u;
                t = r.t;
            } else {
                let r = perturbed_first_crossing(leaf, o, d, ta, tb);
                status = r.status;
                t = r.t;
            }
        }
        if (!in_csg) {
            if (status == 2u) { return SceneHit(2u, 0.0, 0u); }
            if (status == 1u && t < res.t) {
                res = SceneHit(1u, t, leaf);
                if (any_hit) { return res; }
            }
            continue;
        }
        if (search) {
            let f = csg_feed(status, t);
            if (f == 2u) { return SceneHit(2u, 0.0, 0u); }
            if (f == 0u) { continue; }
        }
        let r = csg_run(o, d);
        if (r.z == 3.0) { continue; }
        in_csg = false;
        if (r.z == 2.0) { return SceneHit(2u, 0.0, 0u); }
        if (r.z == 1.0 && r.x < res.t) {
            res = SceneHit(1u, r.x, bitcast<u32>(r.y));
            if (any_hit) { return res; }
        }
    }
    return res;
}

fn q_grad(c: array<f32, 10>, p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        2.0 * c[0] * p.x + c[3] * p.y + c[5] * p.z + c[6],
        2.0 * c[1] * p.y + c[3] * p.x + c[4] * p.z + c[7],
        2.0 * c[2] * p.z + c[4] * p.y + c[5] * p.x + c[8]);
}

// The outward unit normal of leaf `leaf` at p: −∇F'/|∇F'| (frep::outward), with
// ∇F' = ∇q + Σ 3 f_i q_i² ∇q_i over the perturbations positive at p.
fn leaf_normal(key: u32, p: vec3<f32>) -> vec3<f32> {
    let leaf = key & 0x7fffffffu;
    let sign = select(-1.0, 1.0, (key & 0x80000000u) != 0u);
    let ob = objects[leaf];
    if (ob.kind == 2u) {
        use_tape(ob.first_op);
        return -sign * tape_normal(p);
    }
    var g = q_grad(quadrics[ob.first_op].c, p);
    if (ob.kind == 1u) {
        let n = ob.item_count + ob.unbounded;
        for (var k = 0u; k < n; k++) {
            loops++;
            let pert = perturbations[ob.op_count + items[ob.first_item + k].item];
            let q = q_eval(pert.q, p);
            if (q > 0.0) { g += (3.0 * pert.f * q * q) * q_grad(pert.q, p); }
        }
    }
    let l = length(g);
    if (l > 0.0 && is_finite(l)) { return sign * g / l; }
    return vec3<f32>(0.0, 0.0, 1.0);
}

// --- lights ------------------------------------------------------------------------

// The nearest area light along the ray: (t, index bits) with the radiance it sends back
// along −d (0 from a non-emitting side); t = ∞ when none.
struct LightHit { t: f32, index: u32, le: vec3<f32>, n: vec3<f32> }

fn nearest_light(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> LightHit {
    var h = LightHit(inf(), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
    var best = t_max;
    for (var i = 0u; i < frame.n_lights; i++) {
        loops++;
        let l = lights[i];
        let c = light_intersect(l, o, d, 0.0, best);
        if (c.x > 0.0) {
            best = c.x;
            var le = vec3<f32>(0.0);
            if (light_emits(l, c.yzw, -d)) { le = l.radiance.xyz; }
            h = LightHit(c.x, i, le, c.yzw);
        }
    }
    return h;
}

// The MIS lights: the area lights, then the environment (render::light::Lights::count).
fn n_mis() -> u32 {
    return frame.n_lights + select(0u, 1u, frame.env.kind != ENV_NONE);
}

// Radiance arriving along d from the nearest light `lh` found, or from the environment
// where the ray escapes (render::light::Lights::radiance_along over (0, ∞)).
fn incoming(lh: LightHit, d: vec3<f32>) -> vec3<f32> {
    if (lh.t < inf()) { return lh.le; }
    return env_radiance(frame.env, d);
}

// The spatial selection (render::light::Selection::Spatial): the environment with
// probability ½ (1 without area lights), the area lights with the rest ∝ their
// importance at (p, n).
fn spatial_env() -> f32 {
    if (frame.env.kind == ENV_NONE) { return 0.0; }
    if (frame.n_lights == 0u) { return 1.0; }
    return 0.5;
}

fn importance_of(i: u32, p: vec3<f32>, n: vec3<f32>) -> f32 {
    return light_importance(frame.spatial_off + 12u * i, p, n);
}

fn importance_total(p: vec3<f32>, n: vec3<f32>) -> f32 {
    var total = 0.0;
    for (var i = 0u; i < frame.n_lights; i++) {
        loops++;
        total += importance_of(i, p, n);
    }
    return total;
}

// The MIS light the spatial selection picks with uc, as bits (n_lights: the
// environment), or 0xffffffff when none has probability (Lights::select).
fn spatial_select(p: vec3<f32>, n: vec3<f32>, uc: f32) -> u32 {
    let pe = spatial_env();
    if (uc < pe) { return frame.n_lights; }
    let total = importance_total(p, n);
    if (!(total > 0.0)) { return 0xffffffffu; }
    let aim = (uc - pe) / (1.0 - pe) * total;
    var acc = 0.0;
    var last = 0xffffffffu;
    for (var i = 0u; i < frame.n_lights; i++) {
        loops++;
        let w = importance_of(i, p, n);
        if (w > 0.0) {
            acc += w;
            last = i;
            if (aim < acc) { return i; }
        }
    }
    return last;
}

// The trained selection (render::light::TrainedSelection): whether its table covers the
// MIS lights, and the offset of the pmf row of p's cell (points outside the grid go to
// the nearest cell).
fn trained_usable() -> bool {
    return frame.trained.x != 0xffffffffu && frame.trained.z == n_mis();
}

fn trained_row(p: vec3<f32>) -> u32 {
    let off = frame.trained.x;
    let res = frame.trained.y;
    let lo = vec3<f32>(sel_buf[off], sel_buf[off + 1u], sel_buf[off + 2u]);
    let sc = vec3<f32>(sel_buf[off + 3u], sel_buf[off + 4u], sel_buf[off + 5u]);
    let q = floor((p - lo) * sc);
    let m = f32(res - 1u);
    var c = vec3<u32>(0u);
    for (var k = 0u; k < 3u; k++) {
        if (q[k] == q[k]) { c[k] = u32(clamp(q[k], 0.0, m)); }
    }
    return off + 6u + ((c.z * res + c.y) * res + c.x) * frame.trained.z;
}

// The MIS light the trained pmf at p picks with uc (0xffffffff: none).
fn trained_select(p: vec3<f32>, uc: f32) -> u32 {
    if (!trained_usable()) { return 0xffffffffu; }
    let row = trained_row(p);
    let n = frame.trained.z;
    var acc = 0.0;
    for (var i = 0u; i < n; i++) {
        loops++;
        acc += sel_buf[row + i];
        if (uc < acc) { return i; }
    }
    for (var i = n; i > 0u; i--) {
        loops++;
        if (sel_buf[row + i - 1u] > 0.0) { return i - 1u; }
    }
    return 0xffffffffu;
}

fn pmf_at(off: u32, i: u32) -> f32 {
    let n = bitcast<u32>(sel_buf[off]);
    return sel_buf[off + 1u + (n + 1u) + i];
}

// The solid-angle pdf of technique `code` (light index `one` for T_ONE) at wi, the
// BSDF's being `bsdf_pdf` (render::technique::Technique::pdf).
fn tech_pdf(code: u32, one: u32, p: vec3<f32>, n: vec3<f32>, wi: vec3<f32>, bsdf_pdf: f32) -> f32 {
    if (code == T_BSDF) { return bsdf_pdf; }
    if (code == T_ENV) { return env_pdf(frame.env, wi); }
    if (code == T_TRAINED) {
        if (!trained_usable()) { return 0.0; }
        let row = trained_row(p);
        var sum = 0.0;
        for (var i = 0u; i < frame.n_lights; i++) {
            loops++;
            let pm = sel_buf[row + i];
            if (pm > 0.0) { sum += pm * light_pdf_li(lights[i], p, wi); }
        }
        if (frame.env.kind != ENV_NONE) {
            let pm = sel_buf[row + frame.n_lights];
            if (pm > 0.0) { sum += pm * env_pdf(frame.env, wi); }
        }
        return sum;
    }
    if (code == T_SPATIAL) {
        // Σ P(k | p, n) p_k(wi): (1 − P(env)) · importance_k / total over the area
        // lights, then the environment (Lights::pdf_selected_over).
        let pe = spatial_env();
        var sum = 0.0;
        let total = importance_total(p, n);
        if (total > 0.0) {
            for (var i = 0u; i < frame.n_lights; i++) {
                loops++;
                let pm = (1.0 - pe) * importance_of(i, p, n) / total;
                if (pm > 0.0) { sum += pm * light_pdf_li(lights[i], p, wi); }
            }
        }
        if (pe > 0.0) { sum += pe * env_pdf(frame.env, wi); }
        return sum;
    }
    if (code == T_ONE) {
        if (one == frame.n_lights) { return env_pdf(frame.env, wi); }
        return light_pdf_li(lights[one], p, wi);
    }
    var sum = 0.0;
    for (var i = 0u; i < frame.n_lights; i++) {
        loops++;
        if (code == T_AREA) {
            let pm = pmf_at(frame.area_off, i);
            if (pm > 0.0) { sum += pm * light_pdf_area(lights[i], p, wi); }
        } else {
            var pm = 1.0 / f32(n_mis());
            if (code == T_POWER) { pm = pmf_at(frame.power_off, i); }
            if (pm > 0.0) { sum += pm * light_pdf_li(lights[i], p, wi); }
        }
    }
    // The environment last, as Lights::pdf_selected_over (not a by-area light).
    if (code != T_AREA && frame.env.kind != ENV_NONE) {
        var pm = 1.0 / f32(n_mis());
        if (code == T_POWER) { pm = pmf_at(frame.power_off, frame.n_lights); }
        if (pm > 0.0) { sum += pm * env_pdf(frame.env, wi); }
    }
    return sum;
}

fn tech_code(k: u32) -> u32 { return frame.tech[k / 4u][k % 4u] & 0xffu; }
fn tech_light(k: u32) -> u32 { return frame.tech[k / 4u][k % 4u] >> 8u; }

// --- kernels -------------------------------------------------------------------------

fn slot_pixel(slot: u32) -> vec3<u32> {
    let pix = frame.wave.z + slot % frame.pixels;
    return vec3<u32>(pix % frame.width, pix / frame.width, frame.sample + slot / frame.pixels);
}

fn camera_ray(px: vec3<u32>) -> array<vec3<f32>, 2> {
    var ox = rnd(px.x, px.y, px.z, 0u);
    var oy = rnd(px.x, px.y, px.z, 1u);
    if ((frame.flags & FLAG_CENTER) != 0u) { ox = 0.5; oy = 0.5; }
    let scale = frame.eye.w;
    let aspect = frame.right.w;
    let sx = (2.0 * (f32(px.x) + ox) / f32(frame.width) - 1.0) * scale * aspect;
    let sy = (1.0 - 2.0 * (f32(px.y) + oy) / f32(frame.height)) * scale;
    if ((frame.flags & FLAG_ORTHO) != 0u) {
        return array<vec3<f32>, 2>(frame.eye.xyz + sx * frame.right.xyz + sy * frame.up.xyz, frame.forward.xyz);
    }
    return array<vec3<f32>, 2>(frame.eye.xyz, normalize(frame.forward.xyz + sx * frame.right.xyz + sy * frame.up.xyz));
}

// Draw records per slot and depth: the techniques' Σ n_k, the extra BSDF draw, then one
// per point or spot light (frame.per_slot in all).
fn draw_at(slot: u32, j: u32) -> u32 {
    return ((frame.depth * frame.slots + slot) * frame.per_slot + j) * DRAW_WORDS;
}

fn write_vertex(at: u32, p: vec3<f32>, leaf: u32, wo: vec3<f32>, beta: vec3<f32>) {
    hits[at] = vec4<f32>(p, S_SURFACE);
    hits[at + 1u] = vec4<f32>(leaf_normal(leaf, p), bitcast<f32>(objects[leaf & 0x7fffffffu].material));
    hits[at + 2u] = vec4<f32>(wo, 0.0);
    hits[at + 4u] = vec4<f32>(beta, 0.0);
}

fn trace_camera(slot: u32) {
    let px = slot_pixel(slot);
    let ray = camera_ray(px);
    let o = ray[0];
    let d = ray[1];
    let h = scene_trace(o, d, inf(), false);
    let at = slot * HIT_WORDS;
    hits[at + 3u] = vec4<f32>(0.0);
    // The first hit's AOVs: nothing where the ray escapes (integrator/aov.rs).
    hits[at + 8u] = vec4<f32>(0.0);
    hits[at + 9u] = vec4<f32>(0.0);
    if (h.status == 2u) {
        hits[at] = vec4<f32>(0.0, 0.0, 0.0, S_OVERFLOW);
        return;
    }
    let lh = nearest_light(o, d, h.t);
    if (lh.t < inf()) {
        // A light: its depth and normal, albedo 0.
        hits[at + 8u] = vec4<f32>(lh.n, lh.t);
        var le = lh.le;
        if ((frame.flags & FLAG_HIDE) != 0u) { le = vec3<f32>(0.0); }
        hits[at] = vec4<f32>(0.0, 0.0, 0.0, S_NONE);
        hits[at + 3u] = vec4<f32>(le, 0.0);
        return;
    }
    if (h.status == 0u) {
        // Escaped: the environment seen directly, outside MIS.
        var le = env_radiance(frame.env, d);
        if ((frame.flags & FLAG_HIDE) != 0u) { le = vec3<f32>(0.0); }
        hits[at] = vec4<f32>(0.0, 0.0, 0.0, S_NONE);
        hits[at + 3u] = vec4<f32>(le, 0.0);
        return;
    }
    write_vertex(at, o + h.t * d, h.leaf, -d, vec3<f32>(1.0));
    hits[at + 8u] = vec4<f32>(hits[at + 1u].xyz, h.t);
}

// The continuation of a slot's path from vertex `depth`: its nearest hit is the extending
// draw's Li (a light) and the next vertex (an object), if roulette kept the path.
fn trace_continuation(slot: u32) {
    let at = slot * HIT_WORDS;
    let c = hits[at + 5u];
    if (hits[at].w != S_SURFACE) { return; }
    if (c.w != 1.0) {
        hits[at].w = S_NONE;
        return;
    }
    let o = c.xyz;
    let cd = hits[at + 6u];
    let d = cd.xyz;
    let h = scene_trace(o, d, inf(), false);
    if (h.status == 2u) {
        hits[at].w = S_OVERFLOW;
        return;
    }
    let lh = nearest_light(o, d, h.t);
    let r = draw_at(slot, frame.carry);
    let w2 = draws[r + 2u];
    var g = vec3<f32>(0.0);
    if (lh.t < inf() || h.status == 0u) { g = w2.xyz * incoming(lh, d); }
    draws[r + 2u] = vec4<f32>(g, w2.w);
    if (lh.t < inf() || h.status == 0u || cd.w != 1.0) {
        hits[at].w = S_NONE;
        return;
    }
    write_vertex(at, o + h.t * d, h.leaf, -d, hits[at + 7u].xyz);
    push(LIVE_LEN, frame.wave.x, slot);
}

fn trace_shadow(q: u32) {
    if (q >= atomicLoad(&stats[QUEUE_LEN])) { return; }
    let i = atomicLoad(&stats[QUEUE_ITEMS + q]);
    let at = (frame.depth * frame.slots * frame.per_slot + i) * DRAW_WORDS;
    let h = scene_trace(draws[at].xyz, draws[at + 1u].xyz, draws[at].w, true);
    if (h.status == 2u) {
        draws[at + 1u].w = S_OVERFLOW + 10.0;
    } else if (h.status == 1u) {
        draws[at + 1u].w = D_OCCLUDED;
    } else {
        draws[at + 1u].w = D_VISIBLE;
    }
}

// A ray batch for tests (mode 3): ray i from draws[5i] (origin) and draws[5i + 1]
// (direction); the nearest object hit into hits[8i] = (t, leaf key, status, loops) and
// hits[8i + 1] = its normal.
fn probe(i: u32) {
    let o = draws[i * DRAW_WORDS].xyz;
    let d = draws[i * DRAW_WORDS + 1u].xyz;
    let h = scene_trace(o, d, inf(), false);
    var n = vec3<f32>(0.0);
    if (h.status == 1u) { n = leaf_normal(h.leaf, o + h.t * d); }
    hits[i * HIT_WORDS] = vec4<f32>(h.t, bitcast<f32>(h.leaf), f32(h.status), f32(loops));
    hits[i * HIT_WORDS + 1u] = vec4<f32>(n, 0.0);
}

@compute @workgroup_size(64)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let i = gid.x + gid.y * nw.x * 64u;
    loops = 0u;
    if (frame.mode == 1u) {
        trace_shadow(i);
    } else {
        if (i >= frame.slots) { return; }
        if (frame.mode == 0u) {
            trace_camera(i);
        } else if (frame.mode == 2u) {
            // The slots the shade pass queued, and no other.
            if (i < atomicLoad(&stats[CONT_LEN])) {
                trace_continuation(atomicLoad(&stats[frame.wave.y + i]));
            }
        } else {
            probe(i);
        }
    }
    atomicMax(&stats[select(0u, 1u, frame.mode == 1u)], loops);
}

// Draw j of the vertex of slot q / nd at depth 0 (every slot, in slot order: coherent
// rays), else of the live slot queued at q / nd: technique k's (j < Σ n_k), or the
// extra BSDF draw that only extends the path (j = Σ n_k). The draws of slots not
// queued keep the zeros the wave began with (status 0: no vertex).
@compute @workgroup_size(64)
fn shade(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let q = gid.x + gid.y * nw.x * 64u;
    let nd = frame.per_slot;
    var slot = q / nd;
    if (frame.depth == 0u) {
        if (q >= frame.slots * nd) { return; }
    } else {
        if (q >= atomicLoad(&stats[LIVE_LEN]) * nd) { return; }
        slot = atomicLoad(&stats[frame.wave.x + q / nd]);
    }
    loops = 0u;
    let j = q % nd;
    let i = slot * nd + j;
    let at = draw_at(slot, j);
    let ha = slot * HIT_WORDS;
    let hp = hits[ha];
    if (hp.w != S_SURFACE) {
        draws[at + 1u] = vec4<f32>(0.0, 0.0, 0.0, 0.0);
        return;
    }
    let extend = frame.depth + 1u < frame.max_depth;
    let carries = extend && j == frame.carry;
    let hn = hits[ha + 1u];
    let mat = materials[bitcast<u32>(hn.w)];
    // Delta lobes (render::bsdf::Bxdf::has_specular) and nothing else but them.
    let spec_mat = mat.bsdf.delta != 0u;
    let pure = spec_mat && (mat.bsdf.kind == 1u || mat.bsdf.kind == 2u);
    let vflags = select(0.0, F_PURE, pure);
    // The extra BSDF draw serves the continuation and, without a BSDF technique, the
    // delta lobes (Integrator::shade).
    let extra_used = carries || (frame.carry == frame.n_draws && spec_mat);
    let px = slot_pixel(slot);
    let p = hp.xyz;
    let n = hn.xyz;
    let wo = hits[ha + 2u].xyz;
    let beta = hits[ha + 4u].xyz;
    var m = mat.bsdf;
    m.zero = frame.zero;
    if (mat.tex_kind == 1u) {
        // render::texture: cells of p·scale − n·10⁻³, a where their index sum is even.
        let q = floor(p * mat.a.w - n * 1e-3);
        let cells = q.x + q.y + q.z;
        let r = cells - 2.0 * floor(cells * 0.5);
        m.rgb = select(mat.b, mat.a, r < 0.5);
        m.rgb.w = 0.0;
    }
    let f = basis(n);
    let wo_l = to_local(f, wo);
    if (frame.depth == 0u && j == 0u && (frame.flags & FLAG_AOVS) != 0u) {
        // The albedo AOV: one BSDF draw's weight, from its own dimensions
        // (integrator/aov.rs, dims::ALBEDO).
        let s = bsdf_sample_f(m, wo_l, rnd(px.x, px.y, px.z, 2u),
            vec2<f32>(rnd(px.x, px.y, px.z, 3u), rnd(px.x, px.y, px.z, 4u)));
        var albedo = vec3<f32>(0.0);
        if ((s.flags & 1u) != 0u) { albedo = s.weight; }
        hits[ha + 9u] = vec4<f32>(albedo, 0.0);
    }
    if (j == frame.n_draws && !extra_used) {
        draws[at + 1u] = vec4<f32>(0.0, 0.0, 0.0, 0.0);
        return;
    }
    if (j > frame.n_draws) {
        shade_delta(i, at, j - frame.n_draws - 1u, p, n, f, wo_l, m, beta);
        atomicMax(&stats[2], loops);
        return;
    }
    // Technique k of draw j (the extra draw samples the BSDF).
    var k = 0u;
    var first = 0u;
    var code = T_BSDF;
    if (j < frame.n_draws) {
        for (var t = 0u; t < frame.n_tech; t++) {
            loops++;
            let c = frame.count[t / 4u][t % 4u];
            if (j < first + c) { k = t; break; }
            first += c;
        }
        code = tech_code(k);
    }
    if (pure && code != T_BSDF) {
        draws[at + 1u] = vec4<f32>(0.0, 0.0, 0.0, D_SKIP);
        draws[at + 2u] = vec4<f32>(0.0, 0.0, 0.0, vflags);
        return;
    }
    let base = 8u + frame.depth * frame.stride;
    let dim = base + 3u * j;
    let uc = rnd(px.x, px.y, px.z, dim);
    let u = vec2<f32>(rnd(px.x, px.y, px.z, dim + 1u), rnd(px.x, px.y, px.z, dim + 2u));
    var wi = vec3<f32>(0.0);
    var ok = false;
    var weight = vec3<f32>(0.0);
    var spec = false;
    if (code == T_BSDF) {
        let s = bsdf_sample_f(m, wo_l, uc, u);
        ok = (s.flags & 1u) != 0u;
        spec = ok && (s.flags & 2u) != 0u;
        wi = from_local(f, s.wi);
        weight = s.weight;
    } else if (code == T_ENV) {
        let es = env_sample(frame.env, u);
        ok = es.ok != 0u;
        wi = es.wi;
    } else if (code == T_AREA) {
        if (frame.n_lights > 0u) {
            let sel = light_select(frame.area_off, true, frame.n_lights, uc);
            let ls = light_sample_area(lights[bitcast<u32>(sel.x)], p, u);
            ok = ls.ok != 0u;
            wi = ls.wi;
        }
    } else if (n_mis() > 0u) {
        var li = tech_light(k);
        if (code == T_SPATIAL) {
            li = spatial_select(p, n, uc);
        } else if (code == T_TRAINED) {
            li = trained_select(p, uc);
        } else if (code != T_ONE) {
            let sel = light_select(frame.power_off, code == T_POWER, n_mis(), uc);
            li = bitcast<u32>(sel.x);
        }
        if (li == 0xffffffffu) {
            ok = false;
        } else if (li == frame.n_lights) {
            // The environment, the last MIS light.
            let es = env_sample(frame.env, u);
            ok = es.ok != 0u;
            wi = es.wi;
        } else {
            let ls = light_sample_li(lights[li], p, u);
            ok = ls.ok != 0u;
            wi = ls.wi;
        }
    }
    let o = spawn(p, n, wi);
    if (carries) {
        // The path's next ray, β after it, and roulette (render::integrator::path).
        var next = beta * weight;
        var survives = ok && all(next == next) && any(next != vec3<f32>(0.0)) && is_finite(max(next.x, max(next.y, next.z)));
        if (survives && frame.depth + 1u >= frame.rr_depth) {
            let q = max(0.05, 1.0 - max(next.x, max(next.y, next.z)));
            if (rnd(px.x, px.y, px.z, base + 3u * (frame.n_draws + 1u)) < q) {
                survives = false;
            } else {
                next = next / (1.0 - q);
            }
        }
        hits[ha + 5u] = vec4<f32>(o, select(0.0, 1.0, ok));
        hits[ha + 6u] = vec4<f32>(wi, select(0.0, 1.0, survives));
        hits[ha + 7u] = vec4<f32>(next, 0.0);
        // Traced for the draw's Li even where roulette ends the path there.
        if (ok) { push(CONT_LEN, frame.wave.y, slot); }
    }
    if (spec) {
        // A delta lobe: outside MIS, weight·Li/n (n the BSDF technique's draws, 1 for the
        // extra draw), Li from the continuation's trace or a shadow ray.
        var nk = 1u;
        if (j < frame.n_draws) { nk = frame.count[k / 4u][k % 4u]; }
        let gw = beta * weight / f32(nk);
        if (carries) {
            write_carried(at, o, wi, gw, F_OUTSIDE + vflags);
        } else {
            let lh = nearest_light(o, wi, inf());
            let le = incoming(lh, wi);
            let traced = any(le != vec3<f32>(0.0));
            write_shadow(i, at, o, wi, lh.t, gw * le, F_OUTSIDE + vflags, traced);
        }
        atomicMax(&stats[2], loops);
        return;
    }
    if (carries) {
        if (j == frame.n_draws) {
            draws[at + 1u] = vec4<f32>(wi, select(0.0, D_CARRIED, ok));
            draws[at + 2u] = vec4<f32>(0.0, 0.0, 0.0, vflags);
            atomicMax(&stats[2], loops);
            return;
        }
    }
    var pdfs: array<f32, 8>;
    var fc = vec3<f32>(0.0);
    if (ok) {
        let wi_l = to_local(f, wi);
        let ev = bsdf_eval(m, wo_l, wi_l);
        fc = ev.xyz * abs(dot(wi, n));
        for (var t = 0u; t < frame.n_tech; t++) {
            loops++;
            pdfs[t] = tech_pdf(tech_code(t), tech_light(t), p, n, wi, ev.w);
        }
        // A light draw's own density is the mixture's, and it fails where that is not
        // positive (Lights::sample_selected, sample_by_area).
        let own = pdfs[k];
        if (code != T_BSDF) { ok = own > 0.0 && is_finite(own); }
    }
    if (!ok || j == frame.n_draws) {
        // (The extra draw, when it neither extends the path nor hit a delta lobe, adds
        // nothing.)
        draws[at + 1u] = vec4<f32>(0.0, 0.0, 0.0, select(D_FAILED, 0.0, j == frame.n_draws));
        draws[at + 2u] = vec4<f32>(0.0, 0.0, 0.0, vflags);
        atomicMax(&stats[2], loops);
        return;
    }
    draws[at + 3u] = vec4<f32>(pdfs[0], pdfs[1], pdfs[2], pdfs[3]);
    draws[at + 4u] = vec4<f32>(pdfs[4], pdfs[5], pdfs[6], pdfs[7]);
    // Per-light mode: the MIS light the draw's ray reaches, objects ignored (the nearest
    // area light, else the environment; render::integrator::vertex::light_reached),
    // as 4 × (1 + index) in the flags (0: none).
    let per_light = (frame.flags & FLAG_PER_LIGHT) != 0u;
    var lh = LightHit(inf(), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
    if (!carries || per_light) { lh = nearest_light(o, wi, inf()); }
    var reached = vflags;
    if (per_light) {
        if (lh.t < inf()) {
            reached += 4.0 * f32(lh.index + 1u);
        } else if (frame.env.kind != ENV_NONE) {
            reached += 4.0 * f32(frame.n_lights + 1u);
        }
    }
    if (carries) {
        write_carried(at, o, wi, beta * fc, reached);
    } else {
        // render::integrator::vertex::incident.
        let le = incoming(lh, wi);
        let traced = any(fc != vec3<f32>(0.0)) && any(le != vec3<f32>(0.0));
        write_shadow(i, at, o, wi, lh.t, beta * fc * le, reached, traced);
    }
    atomicMax(&stats[2], loops);
}

// A draw whose light arrives along a shadow ray from o along wi up to t_max: its record,
// with g the integrand before visibility, and, where `traced`, the ray queued for the
// shadow pass (which runs over the queue alone: compaction, GPU.md §7.4).
fn write_shadow(i: u32, at: u32, o: vec3<f32>, wi: vec3<f32>, t_max: f32, g: vec3<f32>, flags: f32, traced: bool) {
    draws[at] = vec4<f32>(o, t_max);
    draws[at + 1u] = vec4<f32>(wi, select(D_ZERO, D_SHADOW, traced));
    draws[at + 2u] = vec4<f32>(g, flags);
    if (traced) { push(QUEUE_LEN, QUEUE_ITEMS, i); }
}

// The draw that extends the path: Li comes from the continuation's trace (mode 2),
// which multiplies it into g.
fn write_carried(at: u32, o: vec3<f32>, wi: vec3<f32>, g: vec3<f32>, flags: f32) {
    draws[at] = vec4<f32>(o, 0.0);
    draws[at + 1u] = vec4<f32>(wi, D_CARRIED);
    draws[at + 2u] = vec4<f32>(g, flags);
}

// render::integrator::vertex::spawn, with an offset for f32: the CPU's 10⁻⁷ (for f64)
// left 2.7 % of a test image's pixels darker by over 30 % (shadow rays finding the
// surface they leave); 10⁻⁵ left none (docs/gpu.md).
fn spawn(p: vec3<f32>, n: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    var side = n;
    if (dot(wi, n) < 0.0) { side = -n; }
    return p + side * (1e-5 * (1.0 + max(abs(p.x), max(abs(p.y), abs(p.z)))));
}

// Point or spot light l (after the area lights in `lights`: shape 3 point, 4 spot;
// radiance = intensity, p0 = position, e1 = axis and cos of the falloff's start,
// e2.x = cos of the cone) at the vertex, outside MIS (Integrator::delta_lights): its
// shadow ray is queued with β·f·|cos|·I/d², unless nothing could arrive.
fn shade_delta(i: u32, at: u32, l: u32, p: vec3<f32>, n: vec3<f32>, f: Basis, wo_l: vec3<f32>, m: GpuBsdf, beta: vec3<f32>) {
    draws[at + 1u] = vec4<f32>(0.0, 0.0, 0.0, 0.0);
    let dl = lights[frame.n_lights + l];
    let v = dl.p0.xyz - p;
    let d2 = dot(v, v);
    if (d2 == 0.0) { return; }
    let wi = v / sqrt(d2);
    var intensity = dl.radiance.xyz;
    if (dl.shape == 4u) {
        // smoothstep(axis·(−wi), cos_end, cos_start), as render::light::delta.
        let a = dl.e2.x;
        let b = dl.e1.w;
        let x = dot(dl.e1.xyz, -wi);
        var s = 0.0;
        if (a == b) {
            s = select(1.0, 0.0, x < a);
        } else {
            let t = clamp((x - a) / (b - a), 0.0, 1.0);
            s = t * t * (3.0 - 2.0 * t);
        }
        intensity = intensity * s;
    }
    let radiance = intensity / d2;
    let fc = bsdf_eval(m, wo_l, to_local(f, wi)).xyz * abs(dot(wi, n));
    if (all(fc == vec3<f32>(0.0)) || all(radiance == vec3<f32>(0.0))) { return; }
    let o = spawn(p, n, wi);
    let dist = length(dl.p0.xyz - o);
    if (nearest_light(o, wi, dist).t < inf()) { return; }
    write_shadow(i, at, o, wi, dist, beta * fc * radiance, 0.0, true);
}

// An indirect dispatch of n invocations at stats[at..at + 3], split over y where x
// would pass 65 535 workgroups.
fn dispatch_args(at: u32, n: u32) {
    let groups = max((n + 63u) / 64u, 1u);
    let x = min(groups, 65535u);
    atomicStore(&stats[at], x);
    atomicStore(&stats[at + 1u], (groups + x - 1u) / x);
    atomicStore(&stats[at + 2u], 1u);
}

// The queued passes' indirect dispatches from their queues' lengths (one invocation):
// the shadow rays, the live slots' draws, the continuations.
@compute @workgroup_size(1)
fn prepare() {
    dispatch_args(QUEUE_ARGS, atomicLoad(&stats[QUEUE_LEN]));
    dispatch_args(LIVE_ARGS, atomicLoad(&stats[LIVE_LEN]) * frame.per_slot);
    dispatch_args(CONT_ARGS, atomicLoad(&stats[CONT_LEN]));
}
