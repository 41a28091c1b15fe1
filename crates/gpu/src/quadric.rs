//! Rays against plain quadrics on the GPU (GPU.md §6, the degree-2 case) and the CPU f32
//! twin the kernel is tested against: the first t in (t_min, t_max) where q changes sign,
//! from the ray's quadratic `q0 + q1 t + q2 t²` (frep's `q_local` about the origin) and the
//! cancellation-free roots `h = −(q1 + sign(q1)·√D)/2`, `h/q2` and `q0/h` (Press et al.,
//! Numerical Recipes §5.6). A tangent ray (D ≤ 0) has no sign change.

use crate::layout::GpuQuadric;

/// The WGSL of `quadric_along` and `quadric_first_crossing` (needs `layout::LAYOUT_WGSL`).
pub const QUADRIC_WGSL: &str = include_str!("shaders/quadric.wgsl");

/// q along the ray about its origin: `[q(o), ∇q(o)·d, dᵀAd]`, in the kernel's order.
pub fn along(c: &[f32; 10], p: [f32; 3], d: [f32; 3]) -> [f32; 3] {
    let [x, y, z] = p;
    let gx = 2.0 * c[0] * x + c[3] * y + c[5] * z + c[6];
    let gy = 2.0 * c[1] * y + c[3] * x + c[4] * z + c[7];
    let gz = 2.0 * c[2] * z + c[4] * y + c[5] * x + c[8];
    let [u, v, w] = d;
    let curv =
        c[0] * u * u + c[1] * v * v + c[2] * w * w + c[3] * u * v + c[4] * v * w + c[5] * u * w;
    let q0 = x * (c[0] * x + c[3] * y + c[5] * z + c[6])
        + y * (c[1] * y + c[4] * z + c[7])
        + z * (c[2] * z + c[8])
        + c[9];
    [q0, gx * u + gy * v + gz * w, curv]
}

/// The first crossing in (t_min, t_max), operation for operation as the kernel.
pub fn first_crossing(
    q: &GpuQuadric,
    o: [f32; 3],
    d: [f32; 3],
    t_min: f32,
    t_max: f32,
) -> Option<f32> {
    let [c0, b, a] = along(&q.c, o, d);
    let inside = |t: f32| t > t_min && t < t_max;
    if a == 0.0 {
        if b == 0.0 {
            return None;
        }
        let t = -c0 / b;
        return inside(t).then_some(t);
    }
    let disc = b * b - 4.0 * a * c0;
    if disc.is_nan() || disc <= 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let sgn = if b >= 0.0 { 1.0 } else { -1.0 };
    let h = -0.5 * (b + sgn * s);
    let r0 = h / a;
    let r1 = if h != 0.0 { c0 / h } else { r0 };
    let (lo, hi) = (r0.min(r1), r0.max(r1));
    if inside(lo) {
        Some(lo)
    } else if inside(hi) && hi != lo {
        Some(hi)
    } else {
        None
    }
}
