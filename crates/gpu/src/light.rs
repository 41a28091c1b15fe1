//! Area lights on the GPU (GPU.md §5.1 `GpuAreaLight`, §9 "light sample/pdf"): the POD
//! light, its WGSL mirror and functions ([`LIGHT_WGSL`]), and the CPU f32 twin written
//! operation for operation as the kernel, which it equals bit for bit on lavapipe
//! (GPU.md §3.5). The f64 originals are `render::light::AreaLight` (pbrt-v4 §6.2, §6.5,
//! §12.2): uniform area sampling with its solid-angle pdf, the sphere's cone sampling
//! (pbrt-v4 §6.2.4), crossings, light selection by power, uniformly or by area from a
//! CDF table (pbrt-v4 §A.5.1, `render::distribution`), and the spatial selection's
//! importance bound ([`importance`], pbrt-v4 §12.6.3, `render::light::importance`).
//!
//! Differences from the f64 code, each needed for f32:
//! - sin and cos are polynomials ([`sincos_small`]) written identically in WGSL and
//!   Rust, so the twin can be exact: WGSL's and libm's transcendentals differ;
//! - points sampled on a rim are found again by [`pdf_area`] and [`pdf_li`] with an
//!   f32-sized widening ([`EDGE`], [`RIM`]) where the f64 code widens by 1e-12;
//! - dot and cross products are written out in one order ([`dot`], [`cross`]).

use bytemuck::{Pod, Zeroable};

/// The WGSL of the light functions, mirroring this module; needs [`GPU_AREA_LIGHT_WGSL`]
/// and, for `light_select`, a storage array `sel_buf: array<f32>` holding the
/// [`table`]s.
pub const LIGHT_WGSL: &str = include_str!("shaders/light.wgsl");

/// `GpuAreaLight::shape` of a sphere (`p0` = centre, radius).
pub const SPHERE: u32 = 0;
/// `GpuAreaLight::shape` of a parallelogram (`p0` = corner, `e1`, `e2` = edges).
pub const RECT: u32 = 1;
/// `GpuAreaLight::shape` of a disk (`p0` = centre, radius; `e1` = unit normal).
pub const DISK: u32 = 2;

/// A uniform area light, 80 B (GPU.md §5.1). `radiance.w` holds the surface area (rounded
/// from f64), which every pdf divides by; power for selection lives in the CDF table.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuAreaLight {
    /// [`SPHERE`], [`RECT`] or [`DISK`].
    pub shape: u32,
    /// 1 when a planar light emits on both sides.
    pub two_sided: u32,
    /// `pad[0]` 1: an emitting object's bounding sphere (a proxy: sampled and counted
    /// in the pdfs as a sphere light, never met by a ray); else padding.
    pub pad: [u32; 2],
    /// Emitted radiance (rgb) and the area.
    pub radiance: [f32; 4],
    /// Centre or corner, and the radius.
    pub p0: [f32; 4],
    /// First edge, or the disk's normal.
    pub e1: [f32; 4],
    /// Second edge.
    pub e2: [f32; 4],
}

/// The WGSL mirror of [`GpuAreaLight`].
pub const GPU_AREA_LIGHT_WGSL: &str = "
struct GpuAreaLight { shape: u32, two_sided: u32, pad0: u32, pad1: u32, radiance: vec4<f32>, p0: vec4<f32>, e1: vec4<f32>, e2: vec4<f32> }
";

type V3 = [f32; 3];

/// a + b.
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
/// a − b.
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
/// a·s.
pub fn scale(a: V3, s: f32) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
/// a · b, summed x, y, z.
pub fn dot(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// a × b.
pub fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn xyz(v: [f32; 4]) -> V3 {
    [v[0], v[1], v[2]]
}
fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// Half-width of the widening of a rect's edges (in edge units) and of a disk's radius²
/// (relative) in crossings, so that points sampled on an edge are found again in f32.
pub const EDGE: f32 = 1.0e-5;
/// The widening of a sphere's silhouette, for lines through points sampled on it: in
/// [`pdf_li`] and [`crossings`] the squared distance of the line from the centre may
/// exceed r² by `RIM · r · |p − c|`. 2⁻¹⁸ is 32 f32 ulp of 1, several times the few-ulp error of a
/// direction toward a sampled point.
pub const RIM: f32 = 1.0 / 262_144.0;
/// 2π as f32.
pub const TWO_PI: f32 = std::f32::consts::TAU;
/// π/4 as f32.
pub const FRAC_PI_4: f32 = std::f32::consts::FRAC_PI_4;

/// sin a and cos a for a ∈ [−π/4, π/4]: Taylor polynomials to a⁹ and a⁸ in Horner form
/// (truncation below 3e-8, a quarter of an f32 ulp at 1), the same operations as WGSL's
/// `sincos_small`, so both sides round alike (GPU.md §3.3: transcendentals differ).
pub fn sincos_small(a: f32) -> (f32, f32) {
    let x2 = a * a;
    let s = a
        * (1.0
            + x2 * (-f32::from_bits(0x3e2a_aaab)
                + x2 * (f32::from_bits(0x3c08_8889)
                    + x2 * (-f32::from_bits(0x3950_0d01) + x2 * f32::from_bits(0x3638_ef1d)))));
    let c = 1.0
        + x2 * (-0.5
            + x2 * (f32::from_bits(0x3d2a_aaab)
                + x2 * (-f32::from_bits(0x3ab6_0b61) + x2 * f32::from_bits(0x37d0_0d01))));
    (s, c)
}

/// (sin 2πu, cos 2πu) for u ∈ [0, 1]: the nearest quarter turn k = ⌊4u + ½⌋ is taken
/// out exactly, the rest (|a| ≤ π/4) goes to [`sincos_small`].
pub fn sincos_2pi(u: f32) -> (f32, f32) {
    let k = (4.0 * u + 0.5).floor();
    let a = TWO_PI * (u - 0.25 * k);
    let (s, c) = sincos_small(a);
    match (k as u32) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// A point of the unit disk, uniform in area (Shirley & Chiu 1997 concentric map, as
/// `render::warp::uniform_disk_concentric`).
pub fn disk_concentric(u: [f32; 2]) -> [f32; 2] {
    let o = [2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0];
    if o[0] == 0.0 && o[1] == 0.0 {
        return [0.0, 0.0];
    }
    if o[0].abs() > o[1].abs() {
        let (s, c) = sincos_small(FRAC_PI_4 * (o[1] / o[0]));
        [o[0] * c, o[0] * s]
    } else {
        // θ = π/2 − θ': cos θ = sin θ', sin θ = cos θ'.
        let (s, c) = sincos_small(FRAC_PI_4 * (o[0] / o[1]));
        [o[1] * s, o[1] * c]
    }
}

/// An orthonormal frame (s, t) around the unit vector n (Duff et al. 2017, JCGT 6(1), as
/// `render::frame::Frame::from_z`).
pub fn frame_from_z(n: V3) -> (V3, V3) {
    let sign = 1f32.copysign(n[2]);
    let a = -1.0 / (sign + n[2]);
    let b = n[0] * n[1] * a;
    let s = [1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]];
    let t = [b, sign + n[1] * n[1] * a, -n[1]];
    (s, t)
}

/// Up to two crossings of the line o + t d (t > 0), nearest first: `(t, outward normal)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Crossings {
    /// How many of `t`, `n` hold crossings.
    pub count: u32,
    /// Ray parameters.
    pub t: [f32; 2],
    /// Outward unit normals.
    pub n: [V3; 2],
}

/// Every crossing of `o + t d` with t > 0 (as `AreaLight::crossings`, edges widened by
/// [`EDGE`]).
pub fn crossings(l: &GpuAreaLight, o: V3, d: V3) -> Crossings {
    let mut out = Crossings::default();
    let p0 = xyz(l.p0);
    match l.shape {
        SPHERE => {
            let r = l.p0[3];
            let oc = sub(o, p0);
            let b = dot(d, oc);
            let c = dot(oc, oc) - r * r;
            // b² − c without cancelling |o − c|²: r² − |f|², f the offset of the line
            // from the centre (Haines et al., Ray Tracing Gems ch. 7; pbrt-v4 §6.8.2).
            let f = sub(oc, scale(d, b));
            let disc = r * r - dot(f, f);
            // A line within f32 rounding of tangent (a point sampled on the
            // silhouette) touches the sphere.
            if disc < -(RIM * r * dot(oc, oc).sqrt()) {
                return out;
            }
            let s = disc.max(0.0).sqrt();
            let q = -(b + s.copysign(b));
            let mut t0 = q;
            let mut t1 = if q != 0.0 { c / q } else { -b };
            if t0 > t1 {
                std::mem::swap(&mut t0, &mut t1);
            }
            for t in [t0, t1] {
                if t > 0.0 {
                    let k = out.count as usize;
                    out.t[k] = t;
                    out.n[k] = scale(sub(add(o, scale(d, t)), p0), 1.0 / r);
                    out.count += 1;
                }
            }
        }
        RECT => {
            let (eu, ev) = (xyz(l.e1), xyz(l.e2));
            let nn = cross(eu, ev);
            let denom = dot(d, nn);
            if denom != 0.0 {
                let t = dot(sub(p0, o), nn) / denom;
                let q = sub(add(o, scale(d, t)), p0);
                let l2 = dot(nn, nn);
                let a = dot(cross(q, ev), nn) / l2;
                let b = dot(cross(eu, q), nn) / l2;
                let inside = |x: f32| (-EDGE..=1.0 + EDGE).contains(&x);
                if t > 0.0 && inside(a) && inside(b) {
                    out.count = 1;
                    out.t[0] = t;
                    out.n[0] = scale(nn, 1.0 / l2.sqrt());
                }
            }
        }
        _ => {
            let n = xyz(l.e1);
            let r = l.p0[3];
            let denom = dot(d, n);
            if denom != 0.0 {
                let t = dot(sub(p0, o), n) / denom;
                let r2 = r * r * (1.0 + EDGE);
                let q = sub(add(o, scale(d, t)), p0);
                if t > 0.0 && dot(q, q) <= r2 {
                    out.count = 1;
                    out.t[0] = t;
                    out.n[0] = n;
                }
            }
        }
    }
    out
}

/// The nearest crossing with t in (t_min, t_max): `(t, normal)`.
pub fn intersect(l: &GpuAreaLight, o: V3, d: V3, t_min: f32, t_max: f32) -> Option<(f32, V3)> {
    let c = crossings(l, o, d);
    (0..c.count as usize)
        .find(|&k| c.t[k] > t_min && c.t[k] < t_max)
        .map(|k| (c.t[k], c.n[k]))
}

/// Whether the light emits from a point of normal `n` toward `w` (`AreaLight::emitted`).
pub fn emits(l: &GpuAreaLight, n: V3, w: V3) -> bool {
    let c = dot(n, w);
    c > 0.0 || (l.two_sided != 0 && c < 0.0 && l.shape != SPHERE)
}

/// A direction toward a light from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Unit direction.
    pub wi: V3,
    /// Distance to the sampled point.
    pub dist: f32,
    /// Solid-angle density.
    pub pdf: f32,
    /// Whether the sampled point emits toward the shading point (radiance, else 0).
    pub emits: bool,
}

/// A point uniform over the surface and its outward normal (`AreaLight::sample_point`).
pub fn sample_point(l: &GpuAreaLight, u: [f32; 2]) -> (V3, V3) {
    let p0 = xyz(l.p0);
    match l.shape {
        SPHERE => {
            let z = 1.0 - 2.0 * u[0];
            let r = safe_sqrt(1.0 - z * z);
            let (s, c) = sincos_2pi(u[1]);
            let n = [r * c, r * s, z];
            (add(p0, scale(n, l.p0[3])), n)
        }
        RECT => {
            let (eu, ev) = (xyz(l.e1), xyz(l.e2));
            let nn = cross(eu, ev);
            let q = add(add(p0, scale(eu, u[0])), scale(ev, u[1]));
            (q, scale(nn, 1.0 / dot(nn, nn).sqrt()))
        }
        _ => {
            let n = xyz(l.e1);
            let (s, t) = frame_from_z(n);
            let d = disk_concentric(u);
            let r = l.p0[3];
            let q = add(add(p0, scale(s, d[0] * r)), scale(t, d[1] * r));
            (q, n)
        }
    }
}

/// The sample toward q (normal n) from p with density `pdf`, or None for a zero
/// distance or a density that is not positive and finite.
fn toward(l: &GpuAreaLight, p: V3, q: V3, n: V3, area_pdf: bool, pdf: f32) -> Option<Sample> {
    let v = sub(q, p);
    let dist = dot(v, v).sqrt();
    if dist == 0.0 {
        return None;
    }
    let wi = scale(v, 1.0 / dist);
    let pdf = if area_pdf { pdf_area(l, p, wi) } else { pdf };
    if !(pdf > 0.0 && pdf <= f32::MAX) {
        return None;
    }
    Some(Sample {
        wi,
        dist,
        pdf,
        emits: emits(l, n, scale(wi, -1.0)),
    })
}

/// Uniform area sampling seen from p; the pdf is [`pdf_area`] at the direction.
pub fn sample_area(l: &GpuAreaLight, p: V3, u: [f32; 2]) -> Option<Sample> {
    let (q, n) = sample_point(l, u);
    toward(l, p, q, n, true, 0.0)
}

/// Σ over crossings of t² / (A |cos θ|): the solid-angle density of [`sample_area`].
pub fn pdf_area(l: &GpuAreaLight, p: V3, wi: V3) -> f32 {
    let c = crossings(l, p, wi);
    let a = l.radiance[3];
    let mut sum = 0.0;
    for k in 0..c.count as usize {
        let cos = dot(c.n[k], wi).abs();
        if cos > 0.0 {
            sum += c.t[k] * c.t[k] / (a * cos);
        }
    }
    sum
}

/// The sphere's cone seen from p: `(1 − cos θmax, sin² θmax, |c − p|²)`, or None from
/// inside.
fn cone(l: &GpuAreaLight, p: V3) -> Option<(f32, f32, f32)> {
    let r = l.p0[3];
    let pc = sub(xyz(l.p0), p);
    let dc2 = dot(pc, pc);
    if dc2 <= r * r {
        return None;
    }
    let sin2_max = r * r / dc2;
    Some((sin2_max / (1.0 + safe_sqrt(1.0 - sin2_max)), sin2_max, dc2))
}

/// The light's own sampling (`AreaLight::sample_li`): for a sphere seen from outside,
/// uniform over its cone of directions (pbrt-v4 §6.2.4); uniform area otherwise.
pub fn sample_li(l: &GpuAreaLight, p: V3, u: [f32; 2]) -> Option<Sample> {
    if l.shape != SPHERE {
        return sample_area(l, p, u);
    }
    let Some((omc, sin2_max, dc2)) = cone(l, p) else {
        return sample_area(l, p, u);
    };
    let w = u[0] * omc;
    let cos_t = 1.0 - w;
    let sin2_t = w * (2.0 - w);
    let cos_a = sin2_t / sin2_max.sqrt() + cos_t * safe_sqrt(1.0 - sin2_t / sin2_max);
    let sin_a = safe_sqrt(1.0 - cos_a * cos_a);
    let (sp, cp) = sincos_2pi(u[1]);
    let (sa, ca) = (sin_a.clamp(-1.0, 1.0), cos_a.clamp(-1.0, 1.0));
    let c = xyz(l.p0);
    let z = scale(sub(c, p), 1.0 / dc2.sqrt());
    let (s, t) = frame_from_z(z);
    // n = frame.from_local(−w), w = (sa cp, sa sp, ca).
    let n = add(
        add(scale(s, -(sa * cp)), scale(t, -(sa * sp))),
        scale(z, -ca),
    );
    let q = add(c, scale(n, l.p0[3]));
    toward(l, p, q, n, false, 1.0 / (TWO_PI * omc))
}

/// The solid-angle density of [`sample_li`] at the unit direction wi.
pub fn pdf_li(l: &GpuAreaLight, p: V3, wi: V3) -> f32 {
    if l.shape != SPHERE {
        return pdf_area(l, p, wi);
    }
    let Some((omc, _, dc2)) = cone(l, p) else {
        return pdf_area(l, p, wi);
    };
    let r = l.p0[3];
    let pc = sub(xyz(l.p0), p);
    let along = dot(pc, wi);
    let x = cross(pc, wi);
    if along > 0.0 && dot(x, x) <= r * r + RIM * r * dc2.sqrt() {
        1.0 / (TWO_PI * omc)
    } else {
        0.0
    }
}

/// f32 words of one light's [`importance_record`].
pub const IMPORTANCE_WORDS: usize = 12;

/// What the spatial selection's importance reads of an area light, in the f32 buffer:
/// its bounding sphere's centre and radius, its normal cone's axis and cos θo, the
/// luminance of its power and whether it is two-sided (1 or 0), then two words of padding
/// ([`state::LightBounds`], rounded from f64).
pub fn importance_record(b: &state::LightBounds) -> [f32; IMPORTANCE_WORDS] {
    let phi = b.power;
    let c = b.center.as_vec3();
    let a = b.axis.as_vec3();
    [
        c.x,
        c.y,
        c.z,
        b.radius as f32,
        a.x,
        a.y,
        a.z,
        b.cos_o as f32,
        phi as f32,
        f32::from(u8::from(b.two_sided)),
        0.0,
        0.0,
    ]
}

/// cos(max(0, θa − θb)) (pbrt-v4 `CosSubClamped`).
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

/// sin(max(0, θa − θb)) (pbrt-v4 `SinSubClamped`).
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        0.0
    } else {
        sin_a * cos_b - cos_a * sin_b
    }
}

/// The spatial selection's bound on a light's contribution at p with normal n, n = 0 at
/// a medium point (`render::light::importance`, pbrt-v4 §12.6.3) from its [`importance_record`] at
/// `buf[at..]` (the kernel's `light_importance`).
pub fn importance(buf: &[f32], at: usize, p: V3, n: V3) -> f32 {
    let r = &buf[at..at + IMPORTANCE_WORDS];
    let (center, radius) = ([r[0], r[1], r[2]], r[3]);
    let (axis, cos_o) = ([r[4], r[5], r[6]], r[7]);
    let (phi, two_sided) = (r[8], r[9] != 0.0);
    let v = sub(p, center);
    let dist2 = dot(v, v);
    let r2 = radius * radius;
    let d2 = dist2.max(r2);
    let w = if dist2 > 0.0 {
        scale(v, 1.0 / dist2.sqrt())
    } else {
        axis
    };
    let mut cos_w = dot(axis, w);
    if two_sided {
        cos_w = cos_w.abs();
    }
    let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
    let cos_b = if dist2 <= r2 {
        -1.0
    } else {
        safe_sqrt(1.0 - r2 / dist2)
    };
    let sin_b = safe_sqrt(1.0 - cos_b * cos_b);
    let sin_o = safe_sqrt(1.0 - cos_o * cos_o);
    let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, cos_o);
    let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, cos_o);
    let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if cos_p <= 0.0 {
        return 0.0;
    }
    // No normal (a point inside a medium): no cosine to bound (pbrt-v4 likewise).
    let cos_ip = if n == [0.0; 3] {
        1.0
    } else {
        let cos_i = dot(n, w).abs();
        let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
        cos_sub_clamped(sin_i, cos_i, sin_b, cos_b)
    };
    let v = phi * cos_p * cos_ip / d2;
    if v > 0.0 {
        v
    } else {
        0.0
    }
}

/// f32 words of one light-BVH node in [`tree_records`].
pub const TREE_NODE_WORDS: usize = IMPORTANCE_WORDS;
/// f32 words of one light's trail in [`tree_records`].
pub const TREE_TRAIL_WORDS: usize = 3;

/// A light BVH (`render::light::LightTree`) as the kernels read it: per node its
/// [`importance_record`] (the node's bounds and power) with the second child's or the
/// light's index (bits) in word 10 and 1 in word 11 for a leaf; then per light its trail
/// (low and high 32 bits, as bits) and the trail's length. Returns the words and where
/// the trails start in them.
pub fn tree_records(t: &state::LightTreeTable) -> (Vec<f32>, usize) {
    let mut out =
        Vec::with_capacity(TREE_NODE_WORDS * t.nodes.len() + TREE_TRAIL_WORDS * t.trails.len());
    for node in &t.nodes {
        let mut r = importance_record(&node.bounds);
        r[10] = f32::from_bits(node.index);
        r[11] = f32::from(u8::from(node.leaf));
        out.extend(r);
    }
    let trails = out.len();
    for &(trail, depth) in &t.trails {
        out.extend([
            f32::from_bits(trail as u32),
            f32::from_bits((trail >> 32) as u32),
            f32::from_bits(u32::from(depth)),
        ]);
    }
    (out, trails)
}

/// The largest f32 below 1.
const ONE_MINUS_EPSILON: f32 = f32::from_bits(0x3f7f_ffff);

/// The branch probabilities at inner node `i` of the tree at `buf[nodes..]`, None where
/// neither child shines on p (`LightTree::split`; the kernel's `tree_split`).
fn tree_split(buf: &[f32], nodes: usize, i: usize, p: V3, n: V3) -> Option<[f32; 2]> {
    let at = nodes + TREE_NODE_WORDS * i;
    let wa = importance(buf, at + TREE_NODE_WORDS, p, n);
    let b = buf[at + 10].to_bits() as usize;
    let wb = importance(buf, nodes + TREE_NODE_WORDS * b, p, n);
    let total = wa + wb;
    (total > 0.0 && total.is_finite()).then(|| [wa / total, wb / total])
}

/// The light the tree at `buf[nodes..]` ([`tree_records`]) draws with `u` ∈ [0, 1) at
/// (p, n), and its probability; None where no light can shine on p (`LightTree::sample`;
/// the kernel's `tree_sample`, at most 65 steps).
pub fn tree_sample(buf: &[f32], nodes: usize, p: V3, n: V3, u: f32) -> Option<(u32, f32)> {
    let (mut i, mut u, mut pmf) = (0, u, 1.0f32);
    for _ in 0..65 {
        let at = nodes + TREE_NODE_WORDS * i;
        let index = buf[at + 10].to_bits();
        if buf[at + 11] != 0.0 {
            return (importance(buf, at, p, n) > 0.0).then_some((index, pmf));
        }
        let [pa, pb] = tree_split(buf, nodes, i, p, n)?;
        if u < pa {
            (u, pmf, i) = ((u / pa).min(ONE_MINUS_EPSILON), pmf * pa, i + 1);
        } else {
            let next = index as usize;
            (u, pmf, i) = (((u - pa) / pb).min(ONE_MINUS_EPSILON), pmf * pb, next);
        }
    }
    None
}

/// The probability that [`tree_sample`] draws light `k` at (p, n): the product of the
/// same branch probabilities along its trail at `buf[trails..]` (`LightTree::pmf`; the
/// kernel's `tree_pmf`).
pub fn tree_pmf(buf: &[f32], nodes: usize, trails: usize, p: V3, n: V3, k: usize) -> f32 {
    let t = trails + TREE_TRAIL_WORDS * k;
    let trail = u64::from(buf[t].to_bits()) | u64::from(buf[t + 1].to_bits()) << 32;
    let depth = buf[t + 2].to_bits().min(64);
    let (mut i, mut pmf) = (0, 1.0f32);
    for d in 0..depth {
        let Some([pa, pb]) = tree_split(buf, nodes, i, p, n) else {
            return 0.0;
        };
        if trail >> d & 1 == 0 {
            (pmf, i) = (pmf * pa, i + 1);
        } else {
            let next = buf[nodes + TREE_NODE_WORDS * i + 10].to_bits() as usize;
            (pmf, i) = (pmf * pb, next);
        }
    }
    if importance(buf, nodes + TREE_NODE_WORDS * i, p, n) > 0.0 {
        pmf
    } else {
        0.0
    }
}

/// How a light technique picks a light (pbrt-v4 §12.5; `render::light::Selection`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Select {
    /// From a CDF table ∝ power (or ∝ area): the table's offset in the f32 buffer.
    Table(u32),
    /// Uniform over the lights.
    Uniform,
}

/// A selection table in the f32 buffer: n, then the CDF (n + 1 values from 0 to 1),
/// then the pmf (n values), from `scene::Distribution1D` rounded to f32.
pub fn table(d: &scene::Distribution1D) -> Vec<f32> {
    let n = d.func.len();
    let mut t = vec![f32::from_bits(n as u32)];
    t.extend(d.cdf.iter().map(|&c| c as f32));
    let norm = d.integral * n as f64;
    t.extend(d.func.iter().map(|&f| (f / norm) as f32));
    t
}

/// The light picked with uc ∈ [0, 1) and its probability: for a table the i with
/// `cdf[i] ≤ uc < cdf[i + 1]` by binary search (as `partition_point(c ≤ u)`); for uniform
/// ⌊uc n⌋ (at most n − 1) with 1/n. `n` is the number of lights.
pub fn select(buf: &[f32], how: Select, n: u32, uc: f32) -> (u32, f32) {
    match how {
        Select::Uniform => (((uc * n as f32) as u32).min(n - 1), 1.0 / n as f32),
        Select::Table(off) => {
            let off = off as usize;
            let n = buf[off].to_bits();
            let i = cdf_find(buf, off + 1, n, uc);
            (i, buf[off + n as usize + 2 + i as usize])
        }
    }
}

/// The i with `cdf[i] ≤ u < cdf[i + 1]` among n cells, the CDF's n + 1 values at
/// `buf[cdf..]`: a binary search as `partition_point(c ≤ u)`, clamped to a cell (the
/// kernel's `cdf_find`).
pub fn cdf_find(buf: &[f32], cdf: usize, n: u32, u: f32) -> u32 {
    let (mut lo, mut hi) = (0u32, n + 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if buf[cdf + mid as usize] <= u {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    (lo.max(1) - 1).min(n - 1)
}

impl GpuAreaLight {
    /// A sphere light.
    pub fn sphere(center: V3, radius: f32, radiance: V3, area: f32) -> Self {
        Self::new(
            SPHERE, false, radiance, area, center, radius, [0.0; 3], [0.0; 3],
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn new(
        shape: u32,
        two_sided: bool,
        rad: V3,
        area: f32,
        p0: V3,
        r: f32,
        e1: V3,
        e2: V3,
    ) -> Self {
        Self {
            shape,
            two_sided: u32::from(two_sided),
            pad: [0; 2],
            radiance: [rad[0], rad[1], rad[2], area],
            p0: [p0[0], p0[1], p0[2], r],
            e1: [e1[0], e1[1], e1[2], 0.0],
            e2: [e2[0], e2[1], e2[2], 0.0],
        }
    }

    /// A parallelogram light `corner + a·edge_u + b·edge_v`.
    pub fn rect(
        corner: V3,
        edge_u: V3,
        edge_v: V3,
        two_sided: bool,
        radiance: V3,
        area: f32,
    ) -> Self {
        Self::new(RECT, two_sided, radiance, area, corner, 0.0, edge_u, edge_v)
    }

    /// A disk light of unit normal `normal`.
    pub fn disk(
        center: V3,
        normal: V3,
        radius: f32,
        two_sided: bool,
        radiance: V3,
        area: f32,
    ) -> Self {
        Self::new(
            DISK, two_sided, radiance, area, center, radius, normal, [0.0; 3],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// At n = 0 (a point inside a medium has no normal) the importance bounds no
    /// receiver cosine: bit for bit what a normal along the direction to the light's
    /// bounding sphere gives (θi = 0 ≤ θb, so cos θ'i = 1 exactly), for a sphere, one- and
    /// two-sided planar lights and a cone, from points outside and inside the bounding
    /// sphere and at its centre, with zeros of either sign; and never less than any other
    /// normal gives.
    #[test]
    fn importance_at_a_zero_normal_has_no_receiver_cosine() {
        use glam::DVec3;
        let bounds = |axis: DVec3, cos_o: f64, two_sided: bool| state::LightBounds {
            center: DVec3::new(0.5, -1.0, 2.0),
            radius: 0.75,
            axis: axis.normalize(),
            cos_o,
            two_sided,
            power: 3.5,
        };
        let lights = [
            bounds(DVec3::Z, -1.0, false),
            bounds(DVec3::new(0.3, -0.2, 1.0), 1.0, false),
            bounds(DVec3::new(-1.0, 0.4, 0.1), 1.0, true),
            bounds(DVec3::new(0.0, 1.0, 1.0), 0.5, false),
        ];
        let (mut lit, mut below) = (0, 0);
        for b in &lights {
            let r = importance_record(b);
            for k in 0..=1000 {
                // A spiral through the bounding sphere's centre out to 4 radii.
                let t = k as f32 / 1000.0;
                let a = 40.0 * t;
                let p = add(
                    [r[0], r[1], r[2]],
                    scale([a.cos(), a.sin(), 2.0 * t - 1.0], 3.0 * t),
                );
                let v = sub(p, [r[0], r[1], r[2]]);
                let toward = if dot(v, v) > 0.0 {
                    normalize3(v)
                } else {
                    [r[4], r[5], r[6]]
                };
                let want = importance(&r, 0, p, toward);
                for n in [[0.0; 3], [-0.0, 0.0, -0.0], [-0.0; 3]] {
                    let got = importance(&r, 0, p, n);
                    assert_eq!(got.to_bits(), want.to_bits(), "{b:?} at {p:?}, n {n:?}");
                }
                lit += usize::from(want > 0.0);
                // Another normal bounds the cosine: never more than n = 0 gives (up to an
                // ulp of cos θ'i's rounding above 1).
                let n = normalize3([t - 0.5, 1.0 - t, 0.25]);
                let with_n = importance(&r, 0, p, n);
                assert!(
                    with_n <= want * (1.0 + 2.0 * f32::EPSILON),
                    "{with_n} > {want}"
                );
                below += usize::from(with_n < want);
            }
        }
        assert!(lit > 2000 && below > 1000, "lit {lit}, below {below}");
    }

    fn normalize3(v: V3) -> V3 {
        scale(v, 1.0 / dot(v, v).sqrt())
    }

    /// Every f32 constant appears in the WGSL as the same bit pattern, and the
    /// polynomial's coefficients are 1/k! rounded once.
    #[test]
    fn wgsl_constants_are_the_rust_ones() {
        let bits = |x: f32| format!("0x{:08x}u", x.to_bits());
        for x in [TWO_PI, FRAC_PI_4, EDGE, RIM, f32::MAX] {
            assert!(LIGHT_WGSL.contains(&bits(x)), "{x} = {}", bits(x));
        }
        let fact = |k: u32| (1..=k).map(f64::from).product::<f64>();
        for (k, b) in [
            (3, 0x3e2a_aaab),
            (5, 0x3c08_8889),
            (7, 0x3950_0d01),
            (9, 0x3638_ef1d),
            (4, 0x3d2a_aaab),
            (6, 0x3ab6_0b61),
            (8, 0x37d0_0d01),
        ] {
            assert_eq!((1.0 / fact(k)) as f32, f32::from_bits(b), "1/{k}!");
            assert!(crate::TRIG_WGSL.contains(&format!("0x{b:08x}u")), "1/{k}!");
        }
    }
}
