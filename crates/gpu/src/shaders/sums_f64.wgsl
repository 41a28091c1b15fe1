// Per-pixel MIS sums in f64 where the adapter has SHADER_F64 (GPU.md §3.3, §8): only
// f32 → f64 conversion and f64 `+`, both exact on lavapipe. Bindings as sums.wgsl, with
// prev and state one f64 per sum.

@group(0) @binding(0) var<storage, read> params: array<u32>;
@group(0) @binding(1) var<storage, read> terms: array<f32>;
@group(0) @binding(2) var<storage, read> prev: array<f64>;
@group(0) @binding(3) var<storage, read_write> state: array<f64>;

@compute @workgroup_size(64)
fn accumulate_f64(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // Dispatches of more than 65 535 workgroups are split over y.
    let pixel = id.x + id.y * groups.x * 64u;
    let samples = params[2];
    let s = params[3];
    if (pixel >= params[1]) { return; }
    for (var k = 0u; k < s; k++) {
        var acc = prev[pixel * s + k];
        for (var j = 0u; j < samples; j++) {
            acc = acc + f64(terms[(pixel * samples + j) * s + k]);
        }
        state[pixel * s + k] = acc;
    }
}
