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

fn quadric_big(v: vec3<f32>) -> f32 { return max(max(abs(v.x), abs(v.y)), abs(v.z)); }

// gpu::quadric::centred: the ray's quadratic about the vertex of t ↦ q(o + t·d) (where
// q's terms are small; the origin stays where the vertex lies farther out), its centre's
// t, and whether rounding leaves the outcome open (1.0) near a vertex in (t_min, t_max).
struct Centred { k: vec3<f32>, tc: f32, open: bool }

fn quadric_centred(c: array<f32, 10>, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> Centred {
    let k0 = quadric_along(c, o, d);
    var tc = 0.0;
    if (k0.z != 0.0) {
        let tm = -k0.y / (2.0 * k0.z);
        let pm = vec3<f32>(o.x + tm * d.x, o.y + tm * d.y, o.z + tm * d.z);
        if (quadric_big(pm) <= quadric_big(o)) { tc = tm; }
    }
    let p = vec3<f32>(o.x + tc * d.x, o.y + tc * d.y, o.z + tc * d.z);
    let k = quadric_along(c, p, d);
    let ca = array<f32, 10>(abs(c[0]), abs(c[1]), abs(c[2]), abs(c[3]), abs(c[4]), abs(c[5]), abs(c[6]), abs(c[7]), abs(c[8]), abs(c[9]));
    let m = quadric_along(ca, abs(p), abs(d));
    let eps = 0x1p-23f;
    let round = 8.0 * eps;
    let shift = eps * (quadric_big(o) + abs(tc) * quadric_big(d));
    let cmax = max(max(max(max(max(max(0.0, ca[0]), ca[1]), ca[2]), ca[3]), ca[4]), ca[5]);
    let gx = 2.0 * c[0] * p.x + c[3] * p.y + c[5] * p.z + c[6];
    let gy = 2.0 * c[1] * p.y + c[3] * p.x + c[4] * p.z + c[7];
    let gz = 2.0 * c[2] * p.z + c[4] * p.y + c[5] * p.x + c[8];
    let gmag = abs(gx) + abs(gy) + abs(gz) + round * (6.0 * cmax * quadric_big(p) + ca[6] + ca[7] + ca[8]);
    let e0 = round * m.x + gmag * shift;
    let e1 = round * m.y + 6.0 * cmax * shift * quadric_big(d);
    let e2 = round * m.z;
    let c0 = k.x;
    let b = k.y;
    let a = k.z;
    var open = false;
    if (a == 0.0) {
        open = b != 0.0 && abs(b) <= e1;
    } else if (abs(a) <= e2) {
        open = true;
    } else {
        let disc = b * b - 4.0 * a * c0;
        let edisc = 2.0 * abs(b) * e1 + 4.0 * (abs(a) * e0 + abs(c0) * e2) + 4.0 * eps * (b * b + 4.0 * abs(a * c0));
        let tv = tc - b / (2.0 * a);
        let margin = sqrt(edisc) / (2.0 * abs(a)) + 1e-3 * max(abs(tv), 1.0);
        open = !(abs(disc) > edisc) && tv > t_min - margin && tv < t_max + margin;
    }
    return Centred(k, tc, open);
}

// (t, 1) for the first crossing in (t_min, t_max), (0, 0) for none, (0, 2) where rounding
// leaves it open (Centred.open: for the CPU).
fn quadric_first_crossing(q: GpuQuadric, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> vec2<f32> {
    let cq = quadric_centred(q.c, o, d, t_min, t_max);
    if (cq.open) { return vec2<f32>(0.0, 2.0); }
    let c0 = cq.k.x;
    let b = cq.k.y;
    let a = cq.k.z;
    let tc = cq.tc;
    if (a == 0.0) {
        if (b == 0.0) { return vec2<f32>(0.0, 0.0); }
        let t = tc + -c0 / b;
        if (t > t_min && t < t_max) { return vec2<f32>(t, 1.0); }
        return vec2<f32>(0.0, 0.0);
    }
    let disc = b * b - 4.0 * a * c0;
    if (!(disc > 0.0)) { return vec2<f32>(0.0, 0.0); }
    let s = sqrt(disc);
    let sgn = select(-1.0, 1.0, b >= 0.0);
    let h = -0.5 * (b + sgn * s);
    let r0 = tc + h / a;
    var r1 = r0;
    if (h != 0.0) { r1 = tc + c0 / h; }
    let lo = min(r0, r1);
    let hi = max(r0, r1);
    if (lo > t_min && lo < t_max) { return vec2<f32>(lo, 1.0); }
    if (hi > t_min && hi < t_max && hi != lo) { return vec2<f32>(hi, 1.0); }
    return vec2<f32>(0.0, 0.0);
}
