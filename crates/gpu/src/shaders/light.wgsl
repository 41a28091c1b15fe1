// Area lights: crossings, uniform area and sphere-cone sampling with their pdfs, and light
// selection. The twin of gpu::light (Rust, f32, the same operations in the same order);
// needs the GpuAreaLight struct (light::GPU_AREA_LIGHT_WGSL). Constants are bit patterns
// so that no literal is rounded twice.

const L_SPHERE: u32 = 0u;
const L_RECT: u32 = 1u;

fn l_two_pi() -> f32 { return bitcast<f32>(0x40c90fdbu); }
fn l_frac_pi_4() -> f32 { return bitcast<f32>(0x3f490fdbu); }
fn l_edge() -> f32 { return bitcast<f32>(0x3727c5acu); }   // 1e-5
fn l_rim() -> f32 { return bitcast<f32>(0x36800000u); }    // 2^-18
fn l_f32_max() -> f32 { return bitcast<f32>(0x7f7fffffu); }

fn l_dot(a: vec3<f32>, b: vec3<f32>) -> f32 { return a.x * b.x + a.y * b.y + a.z * b.z; }
fn l_cross(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
fn l_safe_sqrt(x: f32) -> f32 { return sqrt(max(x, 0.0)); }
fn l_neg_bit(x: f32) -> bool { return (bitcast<u32>(x) & 0x80000000u) != 0u; }

// (sin 2πu, cos 2πu): the nearest quarter turn out exactly, the rest to sincos_small.
fn sincos_2pi(u: f32) -> vec2<f32> {
    let k = floor(4.0 * u + 0.5);
    let sc = sincos_small(l_two_pi() * (u - 0.25 * k));
    switch (u32(k) & 3u) {
        case 0u: { return sc; }
        case 1u: { return vec2<f32>(sc.y, -sc.x); }
        case 2u: { return vec2<f32>(-sc.x, -sc.y); }
        default: { return vec2<f32>(-sc.y, sc.x); }
    }
}

// Shirley & Chiu's concentric map of [0,1)² onto the unit disk.
fn disk_concentric(u: vec2<f32>) -> vec2<f32> {
    let ox = 2.0 * u.x - 1.0;
    let oy = 2.0 * u.y - 1.0;
    if (ox == 0.0 && oy == 0.0) { return vec2<f32>(0.0, 0.0); }
    if (abs(ox) > abs(oy)) {
        let sc = sincos_small(l_frac_pi_4() * (oy / ox));
        return vec2<f32>(ox * sc.y, ox * sc.x);
    }
    let sc = sincos_small(l_frac_pi_4() * (ox / oy));
    return vec2<f32>(oy * sc.x, oy * sc.y);
}

struct LFrame { s: vec3<f32>, t: vec3<f32> }

// Duff et al. 2017 orthonormal basis around the unit n.
fn frame_from_z(n: vec3<f32>) -> LFrame {
    let sign = select(1.0, -1.0, l_neg_bit(n.z));
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return LFrame(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
                  vec3<f32>(b, sign + n.y * n.y * a, -n.y));
}

struct LCrossings { count: u32, t0: f32, t1: f32, n0: vec3<f32>, n1: vec3<f32> }

// Every crossing of o + t d with t > 0, nearest first (edges widened by l_edge()).
fn light_crossings(l: GpuAreaLight, o: vec3<f32>, d: vec3<f32>) -> LCrossings {
    var out = LCrossings(0u, 0.0, 0.0, vec3<f32>(0.0), vec3<f32>(0.0));
    let p0 = l.p0.xyz;
    if (l.shape == L_SPHERE) {
        let r = l.p0.w;
        let oc = o - p0;
        let b = l_dot(d, oc);
        let c = l_dot(oc, oc) - r * r;
        // r² − |f|², f the line's offset from the centre (Haines et al., RTG ch. 7).
        let f = oc - d * b;
        let disc = r * r - l_dot(f, f);
        if (disc < -(l_rim() * r * sqrt(l_dot(oc, oc)))) { return out; }
        let s = sqrt(max(disc, 0.0));
        let q = -(b + select(s, -s, l_neg_bit(b)));
        var t0 = q;
        var t1 = -b;
        if (q != 0.0) { t1 = c / q; }
        if (t0 > t1) { let x = t0; t0 = t1; t1 = x; }
        if (t0 > 0.0) {
            out.t0 = t0;
            out.n0 = (o + d * t0 - p0) * (1.0 / r);
            out.count = 1u;
        }
        if (t1 > 0.0) {
            let n1 = (o + d * t1 - p0) * (1.0 / r);
            if (out.count == 0u) { out.t0 = t1; out.n0 = n1; } else { out.t1 = t1; out.n1 = n1; }
            out.count += 1u;
        }
    } else if (l.shape == L_RECT) {
        let eu = l.e1.xyz;
        let ev = l.e2.xyz;
        let nn = l_cross(eu, ev);
        let denom = l_dot(d, nn);
        if (denom != 0.0) {
            let t = l_dot(p0 - o, nn) / denom;
            let q = o + d * t - p0;
            let l2 = l_dot(nn, nn);
            let a = l_dot(l_cross(q, ev), nn) / l2;
            let b = l_dot(l_cross(eu, q), nn) / l2;
            let e = l_edge();
            if (t > 0.0 && a >= -e && a <= 1.0 + e && b >= -e && b <= 1.0 + e) {
                out.count = 1u;
                out.t0 = t;
                out.n0 = nn * (1.0 / sqrt(l2));
            }
        }
    } else {
        let n = l.e1.xyz;
        let r = l.p0.w;
        let denom = l_dot(d, n);
        if (denom != 0.0) {
            let t = l_dot(p0 - o, n) / denom;
            let r2 = r * r * (1.0 + l_edge());
            let q = o + d * t - p0;
            if (t > 0.0 && l_dot(q, q) <= r2) {
                out.count = 1u;
                out.t0 = t;
                out.n0 = n;
            }
        }
    }
    return out;
}

// The nearest crossing with t in (t_min, t_max): (t, n), t = 0 when none.
fn light_intersect(l: GpuAreaLight, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> vec4<f32> {
    let c = light_crossings(l, o, d);
    if (c.count > 0u && c.t0 > t_min && c.t0 < t_max) { return vec4<f32>(c.t0, c.n0); }
    if (c.count > 1u && c.t1 > t_min && c.t1 < t_max) { return vec4<f32>(c.t1, c.n1); }
    return vec4<f32>(0.0);
}

fn light_emits(l: GpuAreaLight, n: vec3<f32>, w: vec3<f32>) -> bool {
    let c = l_dot(n, w);
    return c > 0.0 || (l.two_sided != 0u && c < 0.0 && l.shape != L_SPHERE);
}

// Σ over crossings of t² / (A |cos θ|).
fn light_pdf_area(l: GpuAreaLight, p: vec3<f32>, wi: vec3<f32>) -> f32 {
    let c = light_crossings(l, p, wi);
    let a = l.radiance.w;
    var sum = 0.0;
    if (c.count > 0u) {
        let cos0 = abs(l_dot(c.n0, wi));
        if (cos0 > 0.0) { sum += c.t0 * c.t0 / (a * cos0); }
    }
    if (c.count > 1u) {
        let cos1 = abs(l_dot(c.n1, wi));
        if (cos1 > 0.0) { sum += c.t1 * c.t1 / (a * cos1); }
    }
    return sum;
}

// ok = 0: no sample.
struct LSample { wi: vec3<f32>, dist: f32, pdf: f32, emits: u32, ok: u32 }

struct LPoint { q: vec3<f32>, n: vec3<f32> }

fn light_sample_point(l: GpuAreaLight, u: vec2<f32>) -> LPoint {
    let p0 = l.p0.xyz;
    if (l.shape == L_SPHERE) {
        let z = 1.0 - 2.0 * u.x;
        let r = l_safe_sqrt(1.0 - z * z);
        let sc = sincos_2pi(u.y);
        let n = vec3<f32>(r * sc.y, r * sc.x, z);
        return LPoint(p0 + n * l.p0.w, n);
    }
    if (l.shape == L_RECT) {
        let eu = l.e1.xyz;
        let ev = l.e2.xyz;
        let nn = l_cross(eu, ev);
        return LPoint(p0 + eu * u.x + ev * u.y, nn * (1.0 / sqrt(l_dot(nn, nn))));
    }
    let n = l.e1.xyz;
    let f = frame_from_z(n);
    let d = disk_concentric(u);
    let r = l.p0.w;
    return LPoint(p0 + f.s * (d.x * r) + f.t * (d.y * r), n);
}

// The sample toward q (normal n) from p; its pdf is light_pdf_area when area_pdf.
fn light_toward(l: GpuAreaLight, p: vec3<f32>, q: vec3<f32>, n: vec3<f32>, area_pdf: bool, pdf_in: f32) -> LSample {
    var out = LSample(vec3<f32>(0.0), 0.0, 0.0, 0u, 0u);
    let v = q - p;
    let dist = sqrt(l_dot(v, v));
    if (dist == 0.0) { return out; }
    let wi = v * (1.0 / dist);
    var pdf = pdf_in;
    if (area_pdf) { pdf = light_pdf_area(l, p, wi); }
    if (!(pdf > 0.0 && pdf <= l_f32_max())) { return out; }
    return LSample(wi, dist, pdf, u32(light_emits(l, n, wi * -1.0)), 1u);
}

fn light_sample_area(l: GpuAreaLight, p: vec3<f32>, u: vec2<f32>) -> LSample {
    let pt = light_sample_point(l, u);
    return light_toward(l, p, pt.q, pt.n, true, 0.0);
}

// (1 − cos θmax, sin² θmax, |c − p|²) of a sphere seen from p; x < 0 from inside.
fn light_cone(l: GpuAreaLight, p: vec3<f32>) -> vec3<f32> {
    let r = l.p0.w;
    let pc = l.p0.xyz - p;
    let dc2 = l_dot(pc, pc);
    if (dc2 <= r * r) { return vec3<f32>(-1.0, 0.0, 0.0); }
    let sin2_max = r * r / dc2;
    return vec3<f32>(sin2_max / (1.0 + l_safe_sqrt(1.0 - sin2_max)), sin2_max, dc2);
}

// The light's own sampling: a sphere's cone from outside (pbrt-v4 §6.2.4), else area.
// The area path and the cone share one toward() call site (llvmpipe inlines every call).
fn light_sample_li(l: GpuAreaLight, p: vec3<f32>, u: vec2<f32>) -> LSample {
    var q: vec3<f32>;
    var n: vec3<f32>;
    var area_pdf = true;
    var pdf = 0.0;
    var cone = vec3<f32>(-1.0, 0.0, 0.0);
    if (l.shape == L_SPHERE) { cone = light_cone(l, p); }
    if (cone.x < 0.0) {
        let pt = light_sample_point(l, u);
        q = pt.q;
        n = pt.n;
    } else {
        let omc = cone.x;
        let sin2_max = cone.y;
        let w = u.x * omc;
        let cos_t = 1.0 - w;
        let sin2_t = w * (2.0 - w);
        let cos_a = sin2_t / sqrt(sin2_max) + cos_t * l_safe_sqrt(1.0 - sin2_t / sin2_max);
        let sin_a = l_safe_sqrt(1.0 - cos_a * cos_a);
        let sp = sincos_2pi(u.y);
        let sa = clamp(sin_a, -1.0, 1.0);
        let ca = clamp(cos_a, -1.0, 1.0);
        let c = l.p0.xyz;
        let z = (c - p) * (1.0 / sqrt(cone.z));
        let f = frame_from_z(z);
        n = f.s * -(sa * sp.y) + f.t * -(sa * sp.x) + z * -ca;
        q = c + n * l.p0.w;
        area_pdf = false;
        pdf = 1.0 / (l_two_pi() * omc);
    }
    return light_toward(l, p, q, n, area_pdf, pdf);
}

// The solid-angle density of light_sample_li at the unit wi.
fn light_pdf_li(l: GpuAreaLight, p: vec3<f32>, wi: vec3<f32>) -> f32 {
    var cone = vec3<f32>(-1.0, 0.0, 0.0);
    if (l.shape == L_SPHERE) { cone = light_cone(l, p); }
    if (cone.x < 0.0) { return light_pdf_area(l, p, wi); }
    let r = l.p0.w;
    let pc = l.p0.xyz - p;
    let along = l_dot(pc, wi);
    let x = l_cross(pc, wi);
    if (along > 0.0 && l_dot(x, x) <= r * r + l_rim() * r * sqrt(cone.z)) {
        return 1.0 / (l_two_pi() * cone.x);
    }
    return 0.0;
}

// The light picked with uc and its probability (index bits, pmf): from the table at
// `off` of `sel_buf` (n, cdf[n + 1], pmf[n]) when table, else uniform over n. The
// including shader declares `sel_buf: array<f32>`.
fn light_select(off: u32, table: bool, n: u32, uc: f32) -> vec2<f32> {
    if (!table) {
        return vec2<f32>(bitcast<f32>(min(u32(uc * f32(n)), n - 1u)), 1.0 / f32(n));
    }
    let m = bitcast<u32>(sel_buf[off]);
    let i = cdf_find(off + 1u, m, uc);
    return vec2<f32>(bitcast<f32>(i), sel_buf[off + m + 2u + i]);
}

// The i with cdf[i] ≤ u < cdf[i + 1] among n cells, the CDF's n + 1 values at `cdf` in
// sel_buf (binary search as Rust's partition_point(c ≤ u), clamped to a cell).
fn cdf_find(cdf: u32, n: u32, u: f32) -> u32 {
    var lo = 0u;
    var hi = n + 1u;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (sel_buf[cdf + mid] <= u) { lo = mid + 1u; } else { hi = mid; }
    }
    return min(max(lo, 1u) - 1u, n - 1u);
}

// cos(max(0, θa − θb)) and sin(max(0, θa − θb)) (pbrt-v4 CosSubClamped, SinSubClamped).
fn l_cos_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if (cos_a > cos_b) { return 1.0; }
    return cos_a * cos_b + sin_a * sin_b;
}
fn l_sin_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if (cos_a > cos_b) { return 0.0; }
    return sin_a * cos_b - cos_a * sin_b;
}

// The spatial selection's bound on a light's contribution at p with normal n (0 at a
// medium point) (render::light::importance, pbrt-v4 §12.6.3), from its 12-word record in
// sel_buf at `at` (light.rs importance_record: centre, radius, axis, cos θo, Φ, two-sided).
fn light_importance(at: u32, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let center = vec3<f32>(sel_buf[at], sel_buf[at + 1u], sel_buf[at + 2u]);
    let radius = sel_buf[at + 3u];
    let axis = vec3<f32>(sel_buf[at + 4u], sel_buf[at + 5u], sel_buf[at + 6u]);
    let cos_o = sel_buf[at + 7u];
    let phi = sel_buf[at + 8u];
    let two_sided = sel_buf[at + 9u] != 0.0;
    let v = p - center;
    let dist2 = l_dot(v, v);
    let r2 = radius * radius;
    let d2 = max(dist2, r2);
    var w = axis;
    if (dist2 > 0.0) { w = v * (1.0 / sqrt(dist2)); }
    var cos_w = l_dot(axis, w);
    if (two_sided) { cos_w = abs(cos_w); }
    let sin_w = l_safe_sqrt(1.0 - cos_w * cos_w);
    var cos_b = -1.0;
    if (!(dist2 <= r2)) { cos_b = l_safe_sqrt(1.0 - r2 / dist2); }
    let sin_b = l_safe_sqrt(1.0 - cos_b * cos_b);
    let sin_o = l_safe_sqrt(1.0 - cos_o * cos_o);
    let cos_x = l_cos_sub(sin_w, cos_w, sin_o, cos_o);
    let sin_x = l_sin_sub(sin_w, cos_w, sin_o, cos_o);
    let cos_p = l_cos_sub(sin_x, cos_x, sin_b, cos_b);
    if (cos_p <= 0.0) { return 0.0; }
    // No normal (a point inside a medium): no cosine to bound (pbrt-v4 likewise).
    var cos_ip = 1.0;
    if (n.x != 0.0 || n.y != 0.0 || n.z != 0.0) {
        let cos_i = abs(l_dot(n, w));
        let sin_i = l_safe_sqrt(1.0 - cos_i * cos_i);
        cos_ip = l_cos_sub(sin_i, cos_i, sin_b, cos_b);
    }
    let r = phi * cos_p * cos_ip / d2;
    if (r > 0.0) { return r; }
    return 0.0;
}

// A light BVH in sel_buf (light.rs tree_records; render::light::LightTree): 12 words per
// node from `nodes` (its importance record, with the second child's or the light's index
// in word 10 and 1 in word 11 for a leaf), 3 per light from `trails` (the path to its
// leaf, low and high 32 bits, and the path's length).
fn l_one_minus_eps() -> f32 { return bitcast<f32>(0x3f7fffffu); }

// The branch probabilities at inner node i, or (−1, −1) where neither child shines on p
// (LightTree::split).
fn tree_split(nodes: u32, i: u32, p: vec3<f32>, n: vec3<f32>) -> vec2<f32> {
    let at = nodes + 12u * i;
    let wa = light_importance(at + 12u, p, n);
    let wb = light_importance(nodes + 12u * bitcast<u32>(sel_buf[at + 10u]), p, n);
    let total = wa + wb;
    if (!(total > 0.0) || (bitcast<u32>(total) & 0x7f800000u) == 0x7f800000u) {
        return vec2<f32>(-1.0);
    }
    return vec2<f32>(wa / total, wb / total);
}

// The light the tree draws with u ∈ [0, 1) at (p, n) and its probability (index bits,
// pmf); index 0xffffffff where none can shine on p (LightTree::sample). A descent goes
// to higher node indices and a tree of n lights is ⌈log₂ n⌉ deep: 65 steps bound it.
fn tree_sample(nodes: u32, p: vec3<f32>, n: vec3<f32>, u_in: f32) -> vec2<f32> {
    var i = 0u;
    var u = u_in;
    var pmf = 1.0;
    for (var d = 0u; d < 65u; d++) {
        let at = nodes + 12u * i;
        let index = bitcast<u32>(sel_buf[at + 10u]);
        if (sel_buf[at + 11u] != 0.0) {
            if (light_importance(at, p, n) > 0.0) { return vec2<f32>(bitcast<f32>(index), pmf); }
            break;
        }
        let s = tree_split(nodes, i, p, n);
        if (s.x < 0.0) { break; }
        if (u < s.x) {
            u = min(u / s.x, l_one_minus_eps());
            pmf = pmf * s.x;
            i = i + 1u;
        } else {
            u = min((u - s.x) / s.y, l_one_minus_eps());
            pmf = pmf * s.y;
            i = index;
        }
    }
    return vec2<f32>(bitcast<f32>(0xffffffffu), 0.0);
}

// The probability that tree_sample draws light k at (p, n): the product of the same
// branch probabilities along its trail (LightTree::pmf).
fn tree_pmf(nodes: u32, trails: u32, p: vec3<f32>, n: vec3<f32>, k: u32) -> f32 {
    let t = trails + 3u * k;
    let lo = bitcast<u32>(sel_buf[t]);
    let hi = bitcast<u32>(sel_buf[t + 1u]);
    let depth = min(bitcast<u32>(sel_buf[t + 2u]), 64u);
    var i = 0u;
    var pmf = 1.0;
    for (var d = 0u; d < depth; d++) {
        let s = tree_split(nodes, i, p, n);
        if (s.x < 0.0) { return 0.0; }
        var bit = (lo >> d) & 1u;
        if (d >= 32u) { bit = (hi >> (d - 32u)) & 1u; }
        if (bit == 0u) {
            pmf = pmf * s.x;
            i = i + 1u;
        } else {
            pmf = pmf * s.y;
            i = bitcast<u32>(sel_buf[nodes + 12u * i + 10u]);
        }
    }
    if (light_importance(nodes + 12u * i, p, n) > 0.0) { return pmf; }
    return 0.0;
}
