// One sample's terms of its pixel's record (GPU.md §8): what state::Tally::add
// would add to the record's words for the slot's hits and draws, in
// f32, so that sums.wgsl can add them to the per-pixel f64 or double-float sums. One
// invocation per slot; its `stride` words of `terms` (cleared before the pass) start at
// (pixel · samples + sample) · stride, the layout sums.wgsl reads. The twin is
// gpu::record::slot_terms, operation for operation.
//
// A slot whose rays overflowed a fixed capacity adds nothing: it is appended to the
// overflow list (tally[8 + q]) for the CPU to render. tally[0] counts that list, tally[1..4]
// the camera, shadow and continuation rays the other slots traced.
//
// Record words (state::Record): [N | outside rgb | 7 AOVs, if kept | blocks],
// block (d, l) of depth d and light l at 4 + aov + (d · lights + l) · block; the blocks
// are mis::block's: heuristic [N | Σ rgb], optimal-direct [N | Â packed, b̂], uncorrelated
// [N_A, N_B | Â, b̂ of A | of B], progressive [N | Σ F (3) | α (3T) | Â, b̂], whose terms are
// α-free: G in the Σ F words and Q in the first T α words (progressive.wgsl applies α).
//
// Needs FLOAT_WGSL and gpu::record's constants before it.

struct RecordParams {
    slots: u32, pixels: u32, samples: u32, stride: u32,
    code: u32, heuristic: u32, aov: u32, depths: u32,
    lights: u32, block: u32, min_depth: u32, n_tech: u32,
    n_draws: u32, per_slot: u32, max_depth: u32, start: u32,
    aov_image: u32, param: f32, moments: u32, pad: u32,
    counts: array<vec4<f32>, 8>,
}

@group(0) @binding(0) var<uniform> rp: RecordParams;
@group(0) @binding(1) var<storage, read> hits: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> draws: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> terms: array<f32>;
@group(0) @binding(4) var<storage, read_write> tally: array<atomic<u32>>;

// HIT_WORDS, DRAW_HEAD, draw_vec4s (vec4s of a hit record, of a draw record's head, of
// a draw record), the record's words OUTSIDE
// and AOV, TALLY_LIST and how draws enter the record (C_AOV, C_OUTSIDE, C_WEIGHTED,
// C_DIRECT, C_UNCORRELATED, C_PROGRESSIVE) come from gpu::record's constants, prepended
// by gpu::record::record_consts_wgsl, and so do the heuristics' codes (H_BALANCE, H_POWER,
// H_MAXIMUM, H_CUTOFF).

var<private> base: u32;
var<private> half: u32;

fn add(w: u32, v: f32) { terms[base + w] = terms[base + w] + v; }
fn add3(w: u32, v: vec3<f32>) { add(w, v.x); add(w + 1u, v.y); add(w + 2u, v.z); }

fn draw_at(depth: u32, slot: u32, j: u32) -> u32 {
    return ((depth * rp.slots + slot) * rp.per_slot + j) * draw_vec4s(rp.n_tech);
}
fn n(k: u32) -> f32 { return rp.counts[k / 4u][k % 4u]; }
fn pdf(at: u32, k: u32) -> f32 { return draws[at + DRAW_HEAD + k / 4u][k % 4u]; }
fn q(at: u32, k: u32) -> f32 { return n(k) * pdf(at, k); }

// s = Σ n_k p_k, or -1 where the draw of technique k counts as failed (mis::Layout::is_valid).
fn mixture(at: u32, k: u32) -> f32 {
    var s = 0.0;
    for (var t = 0u; t < rp.n_tech; t++) { s = s + q(at, t); }
    if (pdf(at, k) > 0.0 && is_finite(s)) { return s; }
    return -1.0;
}

fn power(x: f32) -> f32 {
    if (rp.param == 2.0) { return x * x; }
    return pow(x, rp.param);
}

// The heuristic's w_k / (n_k p_k) (mis::Heuristic::weight; balance: 1/s).
fn scale(at: u32, k: u32, s: f32) -> f32 {
    if (rp.heuristic == H_BALANCE) { return 1.0 / s; }
    let qt = q(at, k);
    var w = 0.0;
    if (is_nan(qt) || qt <= 0.0) {
        w = 0.0;
    } else if (rp.heuristic == H_MAXIMUM) {
        w = 1.0;
        for (var t = 0u; t < rp.n_tech; t++) {
            let below = select(q(at, t) <= qt, q(at, t) < qt, t < k);
            if (!below) { w = 0.0; }
        }
    } else {
        var m = 0.0;
        for (var t = 0u; t < rp.n_tech; t++) { m = rmax(m, q(at, t)); }
        if (rp.heuristic == H_POWER) {
            var sum = 0.0;
            for (var t = 0u; t < rp.n_tech; t++) { sum = sum + power(q(at, t) / m); }
            w = power(qt / m) / sum;
        } else {
            let floor = rp.param * m;
            if (!(qt < floor)) {
                var sum = 0.0;
                for (var t = 0u; t < rp.n_tech; t++) {
                    if (q(at, t) >= floor) { sum = sum + q(at, t); }
                }
                w = qt / sum;
            }
        }
    }
    return w / (n(k) * pdf(at, k));
}

// Â_kk += 1/n_k² in the moments at word m (mis::Moments::add_failed).
fn moments_failed(m: u32, k: u32) {
    add(m + k * (k + 1u) / 2u + k, 1.0 / (n(k) * n(k)));
}

// One sample into the moments at word m: Â_ij += r_i r_j, b̂_ci += (f_c / s) r_i with
// r_i = p_i / s (mis::Moments::add, each term p_i p_j / s² in a form that cannot overflow
// f32: r_i ≤ 1/n_i).
fn moments_add(m: u32, k: u32, f: vec3<f32>, at: u32) {
    let s = mixture(at, k);
    if (s < 0.0) { moments_failed(m, k); return; }
    var idx = m;
    for (var i = 0u; i < rp.n_tech; i++) {
        let ri = pdf(at, i) / s;
        for (var j = 0u; j <= i; j++) {
            add(idx, ri * (pdf(at, j) / s));
            idx++;
        }
    }
    for (var c = 0u; c < 3u; c++) {
        if (f[c] != 0.0) {
            let fs = f[c] / s;
            for (var i = 0u; i < rp.n_tech; i++) {
                add(idx + c * rp.n_tech + i, fs * (pdf(at, i) / s));
            }
        }
    }
}

fn block_at(depth: u32, light: u32) -> u32 {
    return AOV + rp.aov + (depth * rp.lights + light) * rp.block;
}

// mis::Kernel::add_sample, add_failed, end_iteration on the block at word b.
fn block_sample(b: u32, k: u32, f: vec3<f32>, at: u32) {
    if (rp.code == C_WEIGHTED) {
        let s = mixture(at, k);
        if (s < 0.0) { return; }
        let w = scale(at, k, s);
        if (w != 0.0) { add3(b + 1u, f * w); }
    } else if (rp.code == C_DIRECT) {
        moments_add(b + 1u, k, f, at);
    } else if (rp.code == C_PROGRESSIVE) {
        // The α-free terms (state::LinearMis::Progressive): G_c = f_c / s in
        // the Σ F words, Q_i = p_i / s in the first T α words; a failed draw 1/n_k in Q_k.
        moments_add(b + 4u + 3u * rp.n_tech, k, f, at);
        let s = mixture(at, k);
        if (s < 0.0) {
            add(b + 4u + k, 1.0 / n(k));
            return;
        }
        for (var c = 0u; c < 3u; c++) { add(b + 1u + c, f[c] / s); }
        for (var i = 0u; i < rp.n_tech; i++) { add(b + 4u + i, pdf(at, i) / s); }
    } else {
        moments_add(b + 2u + half * rp.moments, k, f, at);
    }
}
fn block_failed(b: u32, k: u32) {
    if (rp.code == C_DIRECT) {
        moments_failed(b + 1u, k);
    } else if (rp.code == C_UNCORRELATED) {
        moments_failed(b + 2u + half * rp.moments, k);
    } else if (rp.code == C_PROGRESSIVE) {
        moments_failed(b + 4u + 3u * rp.n_tech, k);
        add(b + 4u + k, 1.0 / n(k));
    }
}
fn block_end(b: u32) {
    if (rp.code == C_UNCORRELATED) { add(b + half, 1.0); } else { add(b, 1.0); }
    if (rp.code == C_PROGRESSIVE) {
        // Q_i − 1: the iteration's Σ_i α_ci.
        for (var i = 0u; i < rp.n_tech; i++) { add(b + 4u + i, -1.0); }
    }
}

// state::Pixel::add_draw: `light` is the per-light block the draw feeds
// (lights + 1: none).
fn add_draw(depth: u32, k: u32, f: vec3<f32>, at: u32, light: u32) {
    if (rp.code == C_OUTSIDE) {
        let s = mixture(at, k);
        if (s < 0.0) { return; }
        let w = scale(at, k, s);
        if (w != 0.0) { add3(OUTSIDE, f * w); }
        return;
    }
    if (rp.lights == 1u) {
        block_sample(block_at(depth, 0u), k, f, at);
        return;
    }
    for (var l = 0u; l < rp.lights; l++) {
        if (l == light) {
            block_sample(block_at(depth, l), k, f, at);
        } else {
            block_failed(block_at(depth, l), k);
        }
    }
}

@compute @workgroup_size(64)
fn record_terms(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = id.x + id.y * groups.x * 64u;
    if (slot >= rp.slots) { return; }
    let sample = slot / rp.pixels;
    base = ((slot % rp.pixels) * rp.samples + sample) * rp.stride;
    half = (rp.start + sample) & 1u;
    let h = slot * HIT_WORDS;
    var overflow = hits[h].w == 2.0;
    for (var d = 0u; d < rp.max_depth; d++) {
        for (var j = 0u; j < rp.per_slot; j++) {
            if (draws[draw_at(d, slot, j) + 1u].w == 12.0) { overflow = true; }
        }
    }
    if (overflow) {
        let q = atomicAdd(&tally[0], 1u);
        atomicStore(&tally[TALLY_LIST + q], slot);
        return;
    }
    atomicAdd(&tally[1], 1u);
    let nd = hits[h + 8u];
    let albedo = hits[h + 9u];
    if (rp.code == C_AOV) {
        if (rp.aov_image == 0u) {
            add3(OUTSIDE, vec3<f32>(nd.w));
        } else if (rp.aov_image == 1u) {
            add3(OUTSIDE, nd.xyz);
        } else {
            add3(OUTSIDE, albedo.xyz);
        }
    }
    if (rp.aov != 0u) {
        add(AOV, nd.w);
        add3(AOV + 1u, nd.xyz);
        add3(AOV + 4u, albedo.xyz);
    }
    if (rp.code == C_AOV) {
        add(0u, 1.0);
        return;
    }
    if (rp.min_depth == 0u) { add3(OUTSIDE, hits[h + 3u].xyz); }
    var shaded = 0u;
    while (shaded < rp.max_depth && rp.n_draws > 0u && draws[draw_at(shaded, slot, 0u) + 1u].w != 0.0) {
        shaded++;
    }
    var shadow = 0u;
    var secondary = 0u;
    for (var d = 0u; d < shaded; d++) {
        let mute = d + 1u < rp.min_depth;
        var outside = vec3<f32>(0.0);
        for (var j = 0u; j < rp.per_slot; j++) {
            let at = draw_at(d, slot, j);
            let status = draws[at + 1u].w;
            if (status == 4.0 || status == 5.0) { shadow++; }
            if (status == 6.0) { secondary++; }
            let flags = u32(draws[at + 2u].w);
            if ((j > rp.n_draws || (flags & 1u) != 0u) && (status == 4.0 || status == 6.0)) {
                outside = outside + draws[at + 2u].xyz;
            }
        }
        if (mute) { continue; }
        add3(OUTSIDE, outside);
        if ((u32(draws[draw_at(d, slot, 0u) + 2u].w) & 2u) != 0u) { continue; }
        var j = 0u;
        for (var k = 0u; k < rp.n_tech; k++) {
            for (var r = 0u; r < u32(n(k)); r++) {
                let at = draw_at(d, slot, j);
                let status = draws[at + 1u].w;
                let flags = u32(draws[at + 2u].w);
                if (status == 1.0 || (flags & 1u) != 0u) {
                    if (rp.code != C_OUTSIDE) {
                        for (var l = 0u; l < rp.lights; l++) { block_failed(block_at(d, l), k); }
                    }
                } else {
                    var f = vec3<f32>(0.0);
                    if (status == 4.0 || status == 6.0) { f = draws[at + 2u].xyz; }
                    // flags >> 2 is 1 + the light the ray reaches, 0 none: none → lights.
                    add_draw(d, k, f, at, ((flags >> 2u) + rp.lights) % (rp.lights + 1u));
                }
                j++;
            }
        }
        if (rp.code != C_OUTSIDE) {
            for (var l = 0u; l < rp.lights; l++) { block_end(block_at(d, l)); }
        }
    }
    atomicAdd(&tally[2], shadow);
    atomicAdd(&tally[3], secondary);
    add(0u, 1.0);
}
