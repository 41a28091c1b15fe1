// Double-float addition (GPU.md §3.2), shared by sums.wgsl and progressive.wgsl: each
// kernel binds `params: array<u32>` with params[0] == 0, through which every
// intermediate is laundered so that the compiler cannot fold the compensation away.
// The twin is gpu::sums::df_add.

// x, through a bit pattern the compiler cannot see (params[0] == 0).
fn opaque(x: f32) -> f32 { return bitcast<f32>(bitcast<u32>(x) ^ params[0]); }

// s + e = a + b exactly, s = fl(a + b) (TwoSum, 6 flops, no branch).
fn two_sum(a: f32, b: f32) -> vec2<f32> {
    let s = opaque(a + b);
    let bb = opaque(s - a);
    return vec2<f32>(s, (a - opaque(s - bb)) + (b - bb));
}

// (hi, lo) + v, renormalised.
fn df_add(acc: vec2<f32>, v: f32) -> vec2<f32> {
    let p = two_sum(acc.x, v);
    return two_sum(p.x, opaque(p.y + acc.y));
}
