// The progressive optimal estimators' per-pixel sums (GPU.md §8): a sequential pass per
// pixel over a wave's terms (record.wgsl, code 5), in sample order, that applies each
// block's α as the CPU would (state::LinearMis::Progressive): Σ F_c +=
// G_c − Σ_i α_ci Q_i, every other word of the record += its term, and the α words left
// alone. Where a block's N reaches a point of the schedule (mis::Schedule::solves_at)
// the pixel stops after that sample, so that the CPU re-solves α before the next
// (gpu::progressive); the pass is run again from where each pixel stopped.
//
// Needs before it `alias Sum` (f64, or vec2<f32> for double-float), `sum_add(Sum, f32)`
// and `sum_count(Sum) -> u32` (gpu::progressive's preludes).
//
// Bindings: params = [zero, pixels, samples, stride, first block word, blocks, words
// per block, T, schedule kind (0 doubling, 1 every, 2 once, 3 fixed), its W];
// terms[(pixel · samples + sample) · stride + k]; alpha[(pixel · blocks + b) · 3T +
// c · T + i]; state: stride sums per pixel, added to in place; cursor[pixel] the next
// sample, cursor[pixels + pixel] 1 where the pixel stopped at a solve.

@group(0) @binding(0) var<storage, read> params: array<u32>;
@group(0) @binding(1) var<storage, read> terms: array<f32>;
@group(0) @binding(2) var<storage, read> alpha: array<f32>;
@group(0) @binding(3) var<storage, read_write> state: array<Sum>;
@group(0) @binding(4) var<storage, read_write> cursor: array<u32>;

fn add(w: u32, v: f32) { state[w] = sum_add(state[w], v); }

// mis::Schedule::solves_at.
fn solves_at(n: u32) -> bool {
    let w = max(params[9], 1u);
    switch params[8] {
        case 0u: { return n >= w && n % w == 0u && countOneBits(n / w) == 1u; }
        case 1u: { return n >= w; }
        case 2u: { return n == w; }
        default: { return false; }
    }
}

@compute @workgroup_size(64)
fn progressive(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // Dispatches of more than 65 535 workgroups are split over y.
    let pixel = id.x + id.y * groups.x * 64u;
    let pixels = params[1];
    if (pixel >= pixels) { return; }
    let samples = params[2];
    let stride = params[3];
    let first = params[4];
    let blocks = params[5];
    let words = params[6];
    let t = params[7];
    let rec = pixel * stride;
    var j = cursor[pixel];
    var stop = false;
    while (j < samples && !stop) {
        let base = (pixel * samples + j) * stride;
        for (var k = 0u; k < first; k++) { add(rec + k, terms[base + k]); }
        for (var b = 0u; b < blocks; b++) {
            let w = first + b * words;
            let a = (pixel * blocks + b) * 3u * t;
            let dn = terms[base + w];
            add(rec + w, dn);
            for (var c = 0u; c < 3u; c++) {
                var v = terms[base + w + 1u + c];
                for (var i = 0u; i < t; i++) {
                    v = v - alpha[a + c * t + i] * terms[base + w + 4u + i];
                }
                add(rec + w + 1u + c, v);
            }
            for (var k = w + 4u + 3u * t; k < w + words; k++) { add(rec + k, terms[base + k]); }
            if (dn != 0.0 && solves_at(sum_count(state[rec + w]))) { stop = true; }
        }
        j++;
    }
    cursor[pixel] = j;
    cursor[pixels + pixel] = select(0u, 1u, stop);
}
