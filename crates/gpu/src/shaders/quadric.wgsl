// Rays against plain quadrics: the first t in (t_min, t_max) where q changes sign.
// The twin of gpu::quadric::first_crossing (Rust, f32, the same operations in the same
// order). Needs the GpuQuadric struct of layout.rs.

// q along the ray about its origin, as s ↦ q0 + q1 s + q2 s² (frep's q_local, f32).
fn quadric_along(c: array<f32, 10>, p: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let x = p.x;
    let y = p.y;
    let z = p.z;
    let gx = 2.0 * c[0] * x + c[3] * y + c[5] * z + c[6];
    let gy = 2.0 * c[1] * y + c[3] * x + c[4] * z + c[7];
    let gz = 2.0 * c[2] * z + c[4] * y + c[5] * x + c[8];
    let u = d.x;
    let v = d.y;
    let w = d.z;
    let curv = c[0] * u * u + c[1] * v * v + c[2] * w * w + c[3] * u * v + c[4] * v * w + c[5] * u * w;
    let q0 = x * (c[0] * x + c[3] * y + c[5] * z + c[6]) + y * (c[1] * y + c[4] * z + c[7]) + z * (c[2] * z + c[8]) + c[9];
    return vec3<f32>(q0, gx * u + gy * v + gz * w, curv);
}

// (t, 1) for the first crossing in (t_min, t_max), else (0, 0).
fn quadric_first_crossing(q: GpuQuadric, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> vec2<f32> {
    let k = quadric_along(q.c, o, d);
    let c0 = k.x;
    let b = k.y;
    let a = k.z;
    if (a == 0.0) {
        if (b == 0.0) { return vec2<f32>(0.0, 0.0); }
        let t = -c0 / b;
        if (t > t_min && t < t_max) { return vec2<f32>(t, 1.0); }
        return vec2<f32>(0.0, 0.0);
    }
    let disc = b * b - 4.0 * a * c0;
    if (!(disc > 0.0)) { return vec2<f32>(0.0, 0.0); }
    let s = sqrt(disc);
    let sgn = select(-1.0, 1.0, b >= 0.0);
    let h = -0.5 * (b + sgn * s);
    var r0 = h / a;
    var r1 = r0;
    if (h != 0.0) { r1 = c0 / h; }
    let lo = min(r0, r1);
    let hi = max(r0, r1);
    if (lo > t_min && lo < t_max) { return vec2<f32>(lo, 1.0); }
    if (hi > t_min && hi < t_max && hi != lo) { return vec2<f32>(hi, 1.0); }
    return vec2<f32>(0.0, 0.0);
}
