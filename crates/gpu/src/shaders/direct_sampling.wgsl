// --- random numbers: state::sampler, truncated to 24 bits ---------------------------

fn rnd(px: u32, py: u32, index: u32, dim: u32) -> f32 {
    let b = philox4x32_10(vec4<u32>(px, py, index, dim / 4u), vec2<u32>(frame.seed_lo, frame.seed_hi));
    return philox_unit(b[dim % 4u]);
}

// --- frames (render::frame::Frame::from_z, Duff et al. 2017) -------------------------

struct Basis { s: vec3<f32>, t: vec3<f32>, n: vec3<f32> }

fn basis(n: vec3<f32>) -> Basis {
    // The sign bit, as the CPU's copysign: a normal with z = −0.0 takes the −z branch on
    // both back ends (the same frame, so the same directions from the same seed).
    let sign = select(1.0, -1.0, l_neg_bit(n.z));
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
