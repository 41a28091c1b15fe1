// The environment light: a constant dome, or a lat-long map importance-sampled by its
// piecewise-constant distribution ∝ L·sin θ (render::light::environment, pbrt-v4 §12.5;
// render::distribution, pbrt-v4 §A.5). The twin of gpu::env (Rust, f32, the same
// operations in the same order). Tables and pixels live in `sel_buf: array<f32>`,
// which the including shader declares; needs LIGHT_WGSL (sincos_2pi, cdf_find). Constants are
// bit patterns so that no literal is rounded twice.

struct GpuEnv {
    kind: u32, width: u32, height: u32, pixels: u32,
    marginal: u32, rows: u32, row_words: u32, pad: u32,
    radiance: vec4<f32>,
    x: vec4<f32>, y: vec4<f32>, z: vec4<f32>,
}

const ENV_NONE: u32 = 0u;
const ENV_CONSTANT: u32 = 1u;
const ENV_MAP: u32 = 2u;

fn e_pi() -> f32 { return bitcast<f32>(0x40490fdbu); }
fn e_two_pi() -> f32 { return bitcast<f32>(0x40c90fdbu); }
fn e_two_pi2() -> f32 { return bitcast<f32>(0x419de9e6u); }   // 2π²
fn e_inv_4pi() -> f32 { return bitcast<f32>(0x3da2f983u); }
fn e_below_one() -> f32 { return bitcast<f32>(0x3f7fffffu); } // 1 − 2⁻²⁴

// A direction's map coordinates (u = φ/2π, v = θ/π, θ from the map's +z) and sin θ.
struct EnvUv { u: f32, v: f32, sin_t: f32 }

fn env_uv(e: GpuEnv, d: vec3<f32>) -> EnvUv {
    // Into the map's frame: to_worldᵀ·d, to_world's columns being x, y, z.
    let mx = e.x.x * d.x + e.x.y * d.y + e.x.z * d.z;
    let my = e.y.x * d.x + e.y.y * d.y + e.y.z * d.z;
    let mz = e.z.x * d.x + e.z.y * d.y + e.z.z * d.z;
    let l = sqrt(mx * mx + my * my + mz * mz);
    let qx = mx / l;
    let qy = my / l;
    let qz = mz / l;
    var phi = env_atan2(qy, qx);
    if (phi < 0.0) { phi = phi + e_two_pi(); }
    let sin_t = sqrt(qx * qx + qy * qy);
    let theta = env_atan2(sin_t, qz);
    return EnvUv(phi / e_two_pi(), theta / e_pi(), sin_t);
}

// Radiance arriving from direction d (nearest pixel of a map).
fn env_radiance(e: GpuEnv, d: vec3<f32>) -> vec3<f32> {
    if (e.kind == ENV_CONSTANT) { return e.radiance.xyz; }
    if (e.kind != ENV_MAP) { return vec3<f32>(0.0); }
    let uv = env_uv(e, d);
    let x = min(u32(uv.u * f32(e.width)), e.width - 1u);
    let y = min(u32(uv.v * f32(e.height)), e.height - 1u);
    let at = e.pixels + 3u * (y * e.width + x);
    return vec3<f32>(sel_buf[at], sel_buf[at + 1u], sel_buf[at + 2u]);
}

// A 1-D table at `off` (n, cdf[n + 1], density[n]): the continuous sample for u — the
// i with cdf[i] ≤ u < cdf[i + 1] (as partition_point), x = (i + du)/n below 1 — with
// the density there and i.
struct EnvPick { x: f32, pdf: f32, i: u32 }

fn env_continuous(off: u32, u: f32) -> EnvPick {
    let n = bitcast<u32>(sel_buf[off]);
    let cdf = off + 1u;
    let i = cdf_find(cdf, n, u);
    var du = u - sel_buf[cdf + i];
    let width = sel_buf[cdf + i + 1u] - sel_buf[cdf + i];
    if (width > 0.0) { du = du / width; }
    let x = min((f32(i) + du) / f32(n), e_below_one());
    return EnvPick(x, sel_buf[cdf + n + 1u + i], i);
}

// The density of the table at `off` at x (0 outside [0, 1)).
fn env_density(off: u32, x: f32) -> f32 {
    if (!(x >= 0.0 && x < 1.0)) { return 0.0; }
    let n = bitcast<u32>(sel_buf[off]);
    let i = min(u32(x * f32(n)), n - 1u);
    return sel_buf[off + n + 2u + i];
}

struct EnvSample { wi: vec3<f32>, pdf: f32, ok: u32 }

// A direction and its solid-angle pdf: uniform on the sphere for the dome; for a map,
// (u, v) from the 2-D table and p(u, v) / (2π² sin θ).
fn env_sample(e: GpuEnv, u: vec2<f32>) -> EnvSample {
    let none = EnvSample(vec3<f32>(0.0), 0.0, 0u);
    if (e.kind == ENV_CONSTANT) {
        let z = 1.0 - 2.0 * u.x;
        let r = sqrt(max(1.0 - z * z, 0.0));
        let sc = sincos_2pi(u.y);
        return EnvSample(vec3<f32>(r * sc.y, r * sc.x, z), e_inv_4pi(), 1u);
    }
    if (e.kind != ENV_MAP) { return none; }
    let pv = env_continuous(e.marginal, u.y);
    let pu = env_continuous(e.rows + pv.i * e.row_words, u.x);
    let pdf_uv = pu.pdf * pv.pdf;
    // θ = π v, φ = 2π u.
    let st = sincos_2pi(0.5 * pv.x);
    let sin_t = st.x;
    if (!(sin_t > 0.0) || !(pdf_uv > 0.0)) { return none; }
    let sp = sincos_2pi(pu.x);
    let mx = sin_t * sp.y;
    let my = sin_t * sp.x;
    let mz = st.y;
    let wi = vec3<f32>(
        e.x.x * mx + e.y.x * my + e.z.x * mz,
        e.x.y * mx + e.y.y * my + e.z.y * mz,
        e.x.z * mx + e.y.z * my + e.z.z * mz);
    return EnvSample(wi, pdf_uv / (e_two_pi2() * sin_t), 1u);
}

// The solid-angle density of env_sample at the unit direction wi.
fn env_pdf(e: GpuEnv, wi: vec3<f32>) -> f32 {
    if (e.kind == ENV_CONSTANT) { return e_inv_4pi(); }
    if (e.kind != ENV_MAP) { return 0.0; }
    let uv = env_uv(e, wi);
    if (!(uv.sin_t > 0.0)) { return 0.0; }
    let pv = env_density(e.marginal, uv.v);
    if (pv == 0.0) { return 0.0; }
    let row = min(u32(uv.v * f32(e.height)), e.height - 1u);
    let pu = env_density(e.rows + row * e.row_words, uv.u);
    return pv * pu / (e_two_pi2() * uv.sin_t);
}
