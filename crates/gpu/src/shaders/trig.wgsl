// Trigonometric polynomials shared by the kernels (TRIG_WGSL), written operation for
// operation as their Rust twins (light::sincos_small, tape::sin_cos, env::atan01,
// env::atan2): WGSL's builtins differ from libm (GPU.md §3.3).

// sin a, cos a for |a| ≤ π/4: Taylor to a⁹ / a⁸, Horner (light.rs sincos_small).
fn sincos_small(a: f32) -> vec2<f32> {
    let x2 = a * a;
    let s = a * (1.0 + x2 * (-bitcast<f32>(0x3e2aaaabu) + x2 * (bitcast<f32>(0x3c088889u)
        + x2 * (-bitcast<f32>(0x39500d01u) + x2 * bitcast<f32>(0x3638ef1du)))));
    let c = 1.0 + x2 * (-0.5 + x2 * (bitcast<f32>(0x3d2aaaabu)
        + x2 * (-bitcast<f32>(0x3ab60b61u) + x2 * bitcast<f32>(0x37d00d01u))));
    return vec2<f32>(s, c);
}

// atan a for a ∈ [0, 1]: above tan(π/8) as π/4 + atan((a − 1)/(a + 1)); Taylor to x¹⁵
// on |x| ≤ tan(π/8) (truncation below 2e-8).
fn env_atan01(a: f32) -> f32 {
    var x = a;
    var base = 0.0;
    if (a > bitcast<f32>(0x3ed413cdu)) {
        x = (a - 1.0) / (a + 1.0);
        base = bitcast<f32>(0x3f490fdbu);
    }
    let x2 = x * x;
    let p = 1.0 + x2 * (-bitcast<f32>(0x3eaaaaabu) + x2 * (bitcast<f32>(0x3e4ccccdu)
        + x2 * (-bitcast<f32>(0x3e124925u) + x2 * (bitcast<f32>(0x3de38e39u)
        + x2 * (-bitcast<f32>(0x3dba2e8cu) + x2 * (bitcast<f32>(0x3d9d89d9u)
        - x2 * bitcast<f32>(0x3d888889u)))))));
    return base + x * p;
}

// atan2(y, x) in [−π, π], 0 at the origin.
fn env_atan2(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    let hi = max(ax, ay);
    if (hi == 0.0) { return 0.0; }
    var r = env_atan01(min(ax, ay) / hi);
    if (ay > ax) { r = bitcast<f32>(0x3fc90fdbu) - r; }
    if (x < 0.0) { r = bitcast<f32>(0x40490fdbu) - r; }
    if (y < 0.0) { r = -r; }
    return r;
}

// gpu::tape::sin_cos: sin x (or cos x) for |x| < 10⁴, else NaN; the quarter turn out in
// two parts (Cody & Waite), the rest to sincos_small.
fn t_sin_cos(x: f32, cosine: bool) -> f32 {
    if (!(abs(x) < 1.0e4)) { return bitcast<f32>(0x7fc00000u); }
    let k = floor(x * bitcast<f32>(0x3f22f983u) + 0.5);
    let r = (x - k * bitcast<f32>(0x3fc90000u)) - k * bitcast<f32>(0x39fdaa22u);
    let sc = sincos_small(r);
    let q = (i32(k) + select(0, 1, cosine)) & 3;
    if (q == 0) { return sc.x; }
    if (q == 1) { return sc.y; }
    if (q == 2) { return -sc.x; }
    return -sc.y;
}
