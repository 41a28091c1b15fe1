// BSDFs in the local shading frame (normal = +z), f32: diffuse, conductor, dielectric and
// plastic, rough (GGX) and smooth (delta lobes), after render::bsdf (pbrt-v4 ch. 9), and a
// medium's Henyey–Greenstein phase function (kind 4, g in `eta`; pbrt-v4 §11.3.1).
// Twin: gpu::bsdf, operation for operation. No WGSL builtins whose rounding may differ
// from Rust's (dot, normalize, length, cross, sin, cos): explicit +, −, ×, ÷, sqrt only,
// and a polynomial sincos used by both sides (GPU.md §3.5).
//
// Needs BSDF_STRUCT_WGSL (struct GpuBsdf) and a caller-defined
// `fn bsdf_table(i: u32) -> f32` returning entry i of the coat-albedo tables.
// Costly functions have one call site each (llvmpipe inlines every call).

const BSDF_PI: f32 = 3.14159265358979;
const BSDF_INV_PI: f32 = 0.31830987;
const BSDF_HALF_PI: f32 = 1.5707964;
const BSDF_F32_MAX: f32 = 3.4028235e38;
const BSDF_TABLE: f32 = 64.0;

// A run-time zero (GpuBsdf.zero, set by bsdf_eval and bsdf_sample_f): XOR with it keeps
// Mesa's algebraic rewrites of inexact float ops from reaching across a value (GPU.md §3.2).
// Measured on lavapipe: NIR reassociates (a·b)·const into (a·const)·b, and rewrote
// n1 + (x² + y²) in the conductor Fresnel term; so constants that end a product chain, and
// the two norms there, pass through it.
var<private> bsdf_zero: u32;

fn bsdf_opaque(x: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(x) ^ bsdf_zero);
}

struct BsdfSample {
    wi: vec3<f32>,
    pdf: f32,
    f: vec3<f32>,
    eta: f32,
    weight: vec3<f32>,
    // bit 0 valid, bit 1 specular, bit 2 transmission
    flags: u32,
}

fn bsdf_dot(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn bsdf_normalize(v: vec3<f32>) -> vec3<f32> {
    let l = sqrt(bsdf_dot(v, v));
    return vec3<f32>(v.x / l, v.y / l, v.z / l);
}

// sin and cos of (q + f)·π/2, |f| ≤ ½ (Taylor to degree 9 / 10; error < 2e-9 before rounding).
fn bsdf_sincos(q: u32, f: f32) -> vec2<f32> {
    let r = f * BSDF_HALF_PI;
    let r2 = r * r;
    let s = r * (1.0 + r2 * (-0.16666667 + r2 * (0.008333334 + r2 * (-0.0001984127 + r2 * 2.7557319e-6))));
    let c = 1.0 + r2 * (-0.5 + r2 * (0.041666668 + r2 * (-0.0013888889 + r2 * (2.4801588e-5 + r2 * -2.755732e-7))));
    let k = q & 3u;
    if (k == 0u) {
        return vec2<f32>(s, c);
    } else if (k == 1u) {
        return vec2<f32>(c, -s);
    } else if (k == 2u) {
        return vec2<f32>(-s, -c);
    }
    return vec2<f32>(-c, s);
}

// Henyey–Greenstein (pbrt-v4 §11.3.1; render::bsdf::HenyeyGreenstein): the density for
// cos θ = wo·wi. Cheap, so called from both bsdf_eval and bsdf_sample_f. The product with
// 4π passes through bsdf_opaque as in ggx_d, and so do the sums 1 + g and 1 + g² here and
// in bsdf_hg_sample: NIR's reassociation may move a constant term to the end of a chain
// (a rounding change; not seen on lavapipe, which matches the twin without them too).
fn bsdf_hg_p(g: f32, cos_theta: f32) -> f32 {
    let denom = bsdf_opaque(1.0 + g * g) + 2.0 * g * cos_theta;
    return (1.0 - g * g) / (bsdf_opaque(4.0 * BSDF_PI) * denom * sqrt(max(denom, 0.0)));
}

// The sign bit of x, as the CPU's copysign reads it (−0.0 is negative).
fn bsdf_neg_bit(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x80000000u) != 0u;
}

// A direction drawn ∝ HG about wo, and its cos θ (xyz, w): cos θ by the exact inverse CDF
// (pbrt-v4 SampleHenyeyGreenstein), the azimuth u.y in turns (render::warp::
// spherical_direction), the frame about wo that render::frame::Frame::from_z builds
// (Duff et al. 2017, JCGT 6(1)). One call site.
fn bsdf_hg_sample(g: f32, wo: vec3<f32>, u: vec2<f32>) -> vec4<f32> {
    var c: f32;
    if (abs(g) < 1e-3) {
        c = 1.0 - 2.0 * u.x;
    } else {
        let s = (1.0 - g * g) / (bsdf_opaque(1.0 + g) - 2.0 * g * u.x);
        c = -(bsdf_opaque(1.0 + g * g) - s * s) / (2.0 * g);
    }
    c = clamp(c, -1.0, 1.0);
    let sin_t = sqrt(max(0.0, 1.0 - c * c));
    let v = 4.0 * u.y;
    let q = u32(v + 0.5);
    let sc = bsdf_sincos(q, v - f32(q));
    let x = sin_t * sc.y;
    let y = sin_t * sc.x;
    let n = wo;
    let sign = select(1.0, -1.0, bsdf_neg_bit(n.z));
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let fs = vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let ft = vec3<f32>(b, sign + n.y * n.y * a, -n.y);
    return vec4<f32>(
        fs.x * x + ft.x * y + n.x * c,
        fs.y * x + ft.y * y + n.y * c,
        fs.z * x + ft.z * y + n.z * c,
        c,
    );
}

fn bsdf_same_hemisphere(a: vec3<f32>, b: vec3<f32>) -> bool {
    return a.z * b.z > 0.0;
}

fn bsdf_reflect(wo: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let d = 2.0 * bsdf_dot(wo, n);
    return vec3<f32>(-wo.x + d * n.x, -wo.y + d * n.y, -wo.z + d * n.z);
}

// pbrt-v4 Refract; w = (direction, relative index n_t/n_i), w = 0 under total internal reflection.
fn bsdf_refract(wi: vec3<f32>, n_in: vec3<f32>, eta_in: f32) -> vec4<f32> {
    var cos_i = bsdf_dot(n_in, wi);
    var eta = eta_in;
    var n = n_in;
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = max(1.0 - cos_i * cos_i, 0.0);
    let sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.0) {
        return vec4<f32>(0.0);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let k = cos_i / eta - cos_t;
    return vec4<f32>(-wi.x / eta + k * n.x, -wi.y / eta + k * n.y, -wi.z / eta + k * n.z, eta);
}

// Fresnel reflectance of a dielectric (pbrt-v4 §9.3).
fn bsdf_fr_dielectric(cos_theta_i: f32, eta_in: f32) -> f32 {
    var c = clamp(cos_theta_i, -1.0, 1.0);
    var eta = eta_in;
    if (c < 0.0) {
        eta = 1.0 / eta;
        c = -c;
    }
    let sin2_t = (1.0 - c * c) / (eta * eta);
    if (sin2_t >= 1.0) {
        return 1.0;
    }
    let cos_t = sqrt(max(1.0 - sin2_t, 0.0));
    let r_parl = (eta * c - cos_t) / (eta * c + cos_t);
    let r_perp = (c - eta * cos_t) / (c + eta * cos_t);
    return (r_parl * r_parl + r_perp * r_perp) / 2.0;
}

// Complex numbers as vec2 (re, im), for the conductor Fresnel term (pbrt-v4 FrComplex).
fn cx_mul(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}
fn cx_div(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    let d = b.x * b.x + b.y * b.y;
    return vec2<f32>((a.x * b.x + a.y * b.y) / d, (a.y * b.x - a.x * b.y) / d);
}
fn cx_norm(a: vec2<f32>) -> f32 { return a.x * a.x + a.y * a.y; }
fn cx_sqrt(a: vec2<f32>) -> vec2<f32> {
    let n = sqrt(cx_norm(a));
    if (n == 0.0) {
        return vec2<f32>(0.0);
    }
    let t1 = sqrt(0.5 * (n + abs(a.x)));
    let t2 = 0.5 * a.y / t1;
    if (a.x >= 0.0) {
        return vec2<f32>(t1, t2);
    }
    let t1s = bitcast<f32>((bitcast<u32>(t1) & 0x7fffffffu) | (bitcast<u32>(a.y) & 0x80000000u));
    return vec2<f32>(abs(t2), t1s);
}

// One channel of the conductor reflectance; one call site (in the loop below).
fn bsdf_fr_complex(c: f32, eta: f32, k: f32) -> f32 {
    let ci = vec2<f32>(c, 0.0);
    let e = vec2<f32>(eta, k);
    let sin2_t = cx_div(vec2<f32>(1.0 - c * c, 0.0), cx_mul(e, e));
    let cos_t = cx_sqrt(vec2<f32>(1.0, 0.0) - sin2_t);
    let eci = cx_mul(e, ci);
    let r_parl = cx_div(eci - cos_t, eci + cos_t);
    let ect = cx_mul(e, cos_t);
    let r_perp = cx_div(ci - ect, ci + ect);
    return (bsdf_opaque(cx_norm(r_parl)) + bsdf_opaque(cx_norm(r_perp))) / 2.0;
}

fn bsdf_fr_conductor(cos_theta_i: f32, eta: vec3<f32>, k: vec3<f32>) -> vec3<f32> {
    let c = clamp(cos_theta_i, 0.0, 1.0);
    var r = vec3<f32>(0.0);
    for (var ch = 0u; ch < 3u; ch++) {
        r[ch] = bsdf_fr_complex(c, eta[ch], k[ch]);
    }
    return r;
}

// GGX (Trowbridge–Reitz) with height-correlated Smith masking (pbrt-v4 §9.6).
fn ggx_tan2(w: vec3<f32>) -> f32 {
    return max(1.0 - w.z * w.z, 0.0) / (w.z * w.z);
}

fn ggx_cos2_sin2_phi(w: vec3<f32>) -> vec2<f32> {
    let s2 = w.x * w.x + w.y * w.y;
    if (s2 == 0.0) {
        return vec2<f32>(1.0, 0.0);
    }
    return vec2<f32>(w.x * w.x / s2, w.y * w.y / s2);
}

fn ggx_d(m: GpuBsdf, wm: vec3<f32>) -> f32 {
    let t2 = ggx_tan2(wm);
    if (t2 > BSDF_F32_MAX) {
        return 0.0;
    }
    let z2 = wm.z * wm.z;
    let cos4 = z2 * z2;
    if (cos4 < 1e-16) {
        return 0.0;
    }
    let cs = ggx_cos2_sin2_phi(wm);
    let e = t2 * (cs.x / (m.alpha_x * m.alpha_x) + cs.y / (m.alpha_y * m.alpha_y));
    return 1.0 / (bsdf_opaque(BSDF_PI) * m.alpha_x * m.alpha_y * cos4 * (1.0 + e) * (1.0 + e));
}

fn ggx_lambda(m: GpuBsdf, w: vec3<f32>) -> f32 {
    let t2 = ggx_tan2(w);
    if (t2 > BSDF_F32_MAX) {
        return 0.0;
    }
    let cs = ggx_cos2_sin2_phi(w);
    let a2 = cs.x * m.alpha_x * m.alpha_x + cs.y * m.alpha_y * m.alpha_y;
    return (sqrt(1.0 + a2 * t2) - 1.0) / 2.0;
}

// A visible normal (Heitz 2018, JCGT 7(4)); u.y drives the polar angle 2π u.y.
fn ggx_sample_wm(m: GpuBsdf, w: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    var wh = bsdf_normalize(vec3<f32>(m.alpha_x * w.x, m.alpha_y * w.y, w.z));
    if (wh.z < 0.0) {
        wh = -wh;
    }
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if (wh.z < 0.99999) {
        t1 = bsdf_normalize(vec3<f32>(-wh.y, wh.x, 0.0));
    }
    let t2 = vec3<f32>(
        wh.y * t1.z - wh.z * t1.y,
        wh.z * t1.x - wh.x * t1.z,
        wh.x * t1.y - wh.y * t1.x,
    );
    let r = sqrt(u.x);
    let v = 4.0 * u.y;
    let q = floor(v + 0.5);
    let sc = bsdf_sincos(u32(q), v - q);
    let px = r * sc.y;
    var py = r * sc.x;
    let h = sqrt(max(1.0 - px * px, 0.0));
    let s = (1.0 + wh.z) / 2.0;
    py = (1.0 - s) * h + s * py;
    let pz = sqrt(max(1.0 - (px * px + py * py), 0.0));
    let nh = vec3<f32>(
        px * t1.x + py * t2.x + pz * wh.x,
        px * t1.y + py * t2.y + pz * wh.y,
        px * t1.z + py * t2.z + pz * wh.z,
    );
    return bsdf_normalize(vec3<f32>(m.alpha_x * nh.x, m.alpha_y * nh.y, max(nh.z, 1e-6)));
}

// Malley's method on Shirley–Chiu's concentric disk (pbrt-v4 §A.5).
fn bsdf_cosine_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let ox = 2.0 * u.x - 1.0;
    let oy = 2.0 * u.y - 1.0;
    var d = vec2<f32>(0.0);
    if (ox != 0.0 || oy != 0.0) {
        var r: f32;
        var sc: vec2<f32>;
        if (abs(ox) > abs(oy)) {
            r = ox;
            sc = bsdf_sincos(0u, oy / ox / 2.0);
        } else {
            r = oy;
            sc = bsdf_sincos(1u, -(ox / oy) / 2.0);
        }
        d = vec2<f32>(r * sc.y, r * sc.x);
    }
    return vec3<f32>(d.x, d.y, sqrt(max(1.0 - (d.x * d.x + d.y * d.y), 0.0)));
}

// The coat's directional albedo E(μ): Fresnel when smooth, else the 65-entry table over √μ.
fn bsdf_coat_albedo(m: GpuBsdf, mu_in: f32) -> f32 {
    let mu = min(abs(mu_in), 1.0);
    if (m.delta != 0u) {
        return bsdf_fr_dielectric(mu, m.eta);
    }
    let x = sqrt(mu) * BSDF_TABLE;
    let j = min(u32(x), 63u);
    let f = x - f32(j);
    return bsdf_table(m.table + j) * (1.0 - f) + bsdf_table(m.table + j + 1u) * f;
}

// Plastic: probability of choosing the coat, E / (E + (1 − E)·mean(ρ)).
fn bsdf_p_coat(m: GpuBsdf, mu_o: f32) -> f32 {
    let e = bsdf_coat_albedo(m, mu_o);
    let d = (1.0 - e) * ((m.rgb.x + m.rgb.y + m.rgb.z) / 3.0);
    if (e + d > 0.0) {
        return e / (e + d);
    }
    return 1.0;
}

// f (xyz) and pdf (w) of the non-delta part at (wo, wi).
fn bsdf_eval(m: GpuBsdf, wo: vec3<f32>, wi: vec3<f32>) -> vec4<f32> {
    bsdf_zero = m.zero;
    if (m.kind == 4u) {
        // The whole sphere, no hemisphere test: f = pdf = p.
        return vec4<f32>(bsdf_hg_p(m.eta, bsdf_dot(wo, wi)));
    }
    let same = bsdf_same_hemisphere(wo, wi);
    if (m.kind == 0u) {
        if (!same) {
            return vec4<f32>(0.0);
        }
        return vec4<f32>(m.rgb.xyz * BSDF_INV_PI, abs(wi.z) * BSDF_INV_PI);
    }
    // Plastic's base lobe and coat probability.
    var base = vec3<f32>(0.0);
    var pc = 0.0;
    if (m.kind == 3u) {
        if (!same) {
            return vec4<f32>(0.0);
        }
        let tr_o = 1.0 - bsdf_coat_albedo(m, abs(wo.z));
        let tr_i = 1.0 - bsdf_coat_albedo(m, abs(wi.z));
        let kk = tr_o * tr_i * bsdf_opaque(BSDF_INV_PI) / (m.eta * m.eta);
        base = kk * m.rgb.xyz / (vec3<f32>(1.0) - m.rgb.xyz * m.r_int);
        pc = bsdf_p_coat(m, abs(wo.z));
        if (m.delta != 0u) {
            return vec4<f32>(base, (1.0 - pc) * abs(wi.z) * bsdf_opaque(BSDF_INV_PI));
        }
    }
    if (m.delta != 0u) {
        return vec4<f32>(0.0);
    }
    // The microfacet normal: the half vector (Walter et al. 2007, eq. 16 for transmission).
    let co = wo.z;
    let ci = wi.z;
    var etap = 1.0;
    if (m.kind == 2u && !same) {
        etap = select(1.0 / m.eta, m.eta, co > 0.0);
    } else if (!same) {
        return vec4<f32>(0.0);
    }
    var wm = vec3<f32>(wi.x * etap + wo.x, wi.y * etap + wo.y, wi.z * etap + wo.z);
    let l2 = bsdf_dot(wm, wm);
    if (ci == 0.0 || co == 0.0 || l2 == 0.0) {
        return vec4<f32>(0.0); // dielectric only: reflection has wo.z·wi.z > 0
    }
    wm = bsdf_normalize(wm);
    if (wm.z < 0.0) {
        wm = -wm;
    }
    let wo_m = bsdf_dot(wo, wm);
    let wi_m = bsdf_dot(wi, wm);
    if (m.kind == 2u && (wi_m * ci < 0.0 || wo_m * co < 0.0)) {
        return vec4<f32>(0.0);
    }
    let d = ggx_d(m, wm);
    let lo = ggx_lambda(m, wo);
    let li = ggx_lambda(m, wi);
    let g = 1.0 / (1.0 + lo + li);
    let g1 = 1.0 / (1.0 + lo);
    let aco = abs(co);
    let aci = abs(ci);
    var sgn = wo_m;
    if (co <= 0.0) {
        sgn = -wo_m;
    }
    let pdf_wm = g1 / aco * d * max(sgn, 0.0);
    if (m.kind == 1u) {
        let fr = bsdf_fr_conductor(abs(wo_m), m.rgb.xyz, m.k.xyz);
        return vec4<f32>(fr * (d * g / (4.0 * aco * aci)), pdf_wm / (4.0 * abs(wo_m)));
    }
    let fr = bsdf_fr_dielectric(select(wo_m, abs(wo_m), m.kind == 3u), m.eta);
    if (m.kind == 3u) {
        let fc = d * g * fr / (4.0 * aco * aci);
        let pdf = pc * (pdf_wm / (4.0 * abs(wo_m))) + (1.0 - pc) * aci * bsdf_opaque(BSDF_INV_PI);
        return vec4<f32>(base + vec3<f32>(fc), pdf);
    }
    // Dielectric.
    let dg = d * g;
    let t = 1.0 - fr;
    if (same) {
        let f = dg * fr / abs(4.0 * ci * co);
        return vec4<f32>(vec3<f32>(f), pdf_wm / (4.0 * abs(wo_m)) * fr / (fr + t));
    }
    let x = wi_m + wo_m / etap;
    let x2 = x * x;
    let f = dg * t * abs(wi_m * wo_m / (x2 * ci * co)) / (etap * etap);
    return vec4<f32>(vec3<f32>(f), pdf_wm * abs(wi_m) / x2 * t / (fr + t));
}

// Draws wi given wo (uc chooses the lobe), as render::bsdf::Bsdf::sample_f in the local frame;
// non-delta samples take f and pdf from bsdf_eval of the drawn direction (the phase
// function's from its drawn cos θ, as the CPU's).
fn bsdf_sample_f(m: GpuBsdf, wo: vec3<f32>, uc: f32, u: vec2<f32>) -> BsdfSample {
    bsdf_zero = m.zero;
    var s = BsdfSample(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 1.0, vec3<f32>(0.0), 0u);
    if (wo.z == 0.0) {
        return s;
    }
    let mirror = vec3<f32>(-wo.x, -wo.y, wo.z);
    // Delta lobes.
    var spec = false;
    var pc = 0.0;
    var r = 0.0;
    var t = 0.0;
    if (m.kind == 3u) {
        pc = bsdf_p_coat(m, abs(wo.z));
        spec = m.delta != 0u && uc < pc;
    } else if (m.delta != 0u && (m.kind == 1u || m.kind == 2u)) {
        spec = true;
    }
    if (spec) {
        var f = vec3<f32>(0.0);
        if (m.kind == 1u) {
            s.wi = mirror;
            s.pdf = 1.0;
            let c = abs(mirror.z);
            f = bsdf_fr_conductor(c, m.rgb.xyz, m.k.xyz) / c;
        } else if (m.kind == 3u) {
            s.wi = mirror;
            s.pdf = pc;
            f = vec3<f32>(bsdf_fr_dielectric(abs(wo.z), m.eta) / abs(mirror.z));
        } else {
            r = bsdf_fr_dielectric(wo.z, m.eta);
            t = 1.0 - r;
            if (uc < r / (r + t)) {
                s.wi = mirror;
                s.pdf = r / (r + t);
                f = vec3<f32>(r / abs(mirror.z));
            } else {
                let w = bsdf_refract(wo, vec3<f32>(0.0, 0.0, 1.0), m.eta);
                if (w.w == 0.0) {
                    return s;
                }
                s.wi = w.xyz;
                s.eta = w.w;
                s.pdf = t / (r + t);
                f = vec3<f32>(t / abs(w.z) / (w.w * w.w));
            }
        }
        s.f = f;
        s.flags = 2u;
    } else if (m.kind == 4u) {
        // f = pdf = p at the drawn cos θ, as render's HenyeyGreenstein::sample_f.
        let h = bsdf_hg_sample(m.eta, wo, u);
        let p = bsdf_hg_p(m.eta, h.w);
        s.wi = h.xyz;
        s.f = vec3<f32>(p);
        s.pdf = p;
    } else {
        var wi: vec3<f32>;
        if (m.kind == 0u || (m.kind == 3u && uc >= pc)) {
            wi = bsdf_cosine_hemisphere(u);
            if (wo.z < 0.0) {
                wi.z = -wi.z;
            }
        } else {
            let wm = ggx_sample_wm(m, wo, u);
            var refl = true;
            if (m.kind == 2u) {
                r = bsdf_fr_dielectric(bsdf_dot(wo, wm), m.eta);
                t = 1.0 - r;
                refl = uc < r / (r + t);
            }
            if (refl) {
                wi = bsdf_reflect(wo, wm);
                if (!bsdf_same_hemisphere(wo, wi)) {
                    return s;
                }
            } else {
                let w = bsdf_refract(wo, wm, m.eta);
                if (w.w == 0.0) {
                    return s;
                }
                wi = w.xyz;
                if (bsdf_same_hemisphere(wo, wi) || wi.z == 0.0) {
                    return s;
                }
                s.eta = w.w;
            }
        }
        let e = bsdf_eval(m, wo, wi);
        s.wi = wi;
        s.f = e.xyz;
        s.pdf = e.w;
    }
    if (!(s.pdf > 0.0 && s.pdf <= BSDF_F32_MAX) || s.wi.z == 0.0) {
        return BsdfSample(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 1.0, vec3<f32>(0.0), 0u);
    }
    // A phase function's weight is p/p = 1 exactly (no cosine factor).
    s.weight = vec3<f32>(1.0);
    if (m.kind != 4u) {
        s.weight = s.f * (abs(s.wi.z) / s.pdf);
    }
    s.flags = s.flags | 1u;
    if (s.wi.z * wo.z < 0.0) {
        s.flags = s.flags | 4u;
    }
    return s;
}
