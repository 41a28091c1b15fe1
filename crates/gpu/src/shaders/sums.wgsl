// Per-pixel MIS sums in double-float (GPU.md §3.2, §8): each sum is an unevaluated pair
// (hi, lo) of f32 with hi = fl(hi + lo), grown by TwoSum (Knuth, TAOCP vol. 2 §4.2.2;
// Møller 1965) and renormalised by a second TwoSum. WGSL lets the compiler reassociate,
// which erases the compensation on lavapipe, so each intermediate is laundered through
// an XOR with a zero read at run time (`params[0]`, df.wgsl). The twin is gpu::sums::df_add.
//
// Bindings: params = [zero, pixels, samples, sums per pixel S]; terms[(pixel · samples
// + sample) · S + k]; prev and state: S pairs per pixel. state = prev + Σ_samples terms,
// each sum adding its terms in sample order, as the CPU adds them.

@group(0) @binding(0) var<storage, read> params: array<u32>;
@group(0) @binding(1) var<storage, read> terms: array<f32>;
@group(0) @binding(2) var<storage, read> prev: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> state: array<vec2<f32>>;

@compute @workgroup_size(64)
fn accumulate_df(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // Dispatches of more than 65 535 workgroups are split over y.
    let pixel = id.x + id.y * groups.x * 64u;
    let samples = params[2];
    let s = params[3];
    if (pixel >= params[1]) { return; }
    for (var k = 0u; k < s; k++) {
        var acc = prev[pixel * s + k];
        for (var j = 0u; j < samples; j++) {
            acc = df_add(acc, terms[(pixel * samples + j) * s + k]);
        }
        state[pixel * s + k] = acc;
    }
}
