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

/// Rounding bound of the ray's quadratic, relative to the magnitude of its terms: each
/// term of a coefficient passes at most 6 roundings, and the quadric's coefficients were
/// rounded from f64 once (8 ε).
const ROUND: f32 = 8.0 * f32::EPSILON;

/// The ray's quadratic re-expanded about a centre, and what rounding leaves open.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Centred {
    /// `[q0, q1, q2]` about `o + tc·d`, as [`along`].
    pub k: [f32; 3],
    /// The centre's t.
    pub tc: f32,
    /// Whether the discriminant's sign (or a vanishing q2's) lies within rounding, with
    /// the parabola's vertex inside `(t_min, t_max)`: a grazing ray f32 cannot decide.
    pub open: bool,
}

/// q along the ray about the vertex of t ↦ q(o + t·d) (the ray's point nearest the
/// quadric's centre), where q's terms are small: evaluated at a far origin, a thin
/// cylinder's q(o) cancels to noise (measured: a needle of radius 1.25 mm 5 units away
/// lost a third of its crossings, and a double cone's apex region half) — the fix of
/// Haines et al. (Ray Tracing Gems, ch. 7) for spheres, for any quadric. The origin
/// stays where the vertex lies farther out than it (a ray near a cylinder's axis).
/// `open` bounds the rounding of the coefficients (`ROUND` × their terms' magnitudes),
/// the centre's own (the ray moved by up to ε·(|o| + |tc·d|)), and the discriminant's.
pub fn centred(c: &[f32; 10], o: [f32; 3], d: [f32; 3], t_min: f32, t_max: f32) -> Centred {
    let k0 = along(c, o, d);
    let big = |v: [f32; 3]| v[0].abs().max(v[1].abs()).max(v[2].abs());
    let mut tc = 0.0;
    if k0[2] != 0.0 {
        let tm = -k0[1] / (2.0 * k0[2]);
        let p = [o[0] + tm * d[0], o[1] + tm * d[1], o[2] + tm * d[2]];
        if big(p) <= big(o) {
            tc = tm;
        }
    }
    let p = [o[0] + tc * d[0], o[1] + tc * d[1], o[2] + tc * d[2]];
    let k = along(c, p, d);
    let ca = c.map(f32::abs);
    let m = along(&ca, p.map(f32::abs), d.map(f32::abs));
    let shift = f32::EPSILON * (big(o) + tc.abs() * big(d));
    let cmax = ca[..6].iter().fold(0f32, |x, &y| x.max(y));
    // |∇q(p)|₁ and its rounding: q0 moves by at most that times the shift.
    let [x, y, z] = p;
    let g = [
        2.0 * c[0] * x + c[3] * y + c[5] * z + c[6],
        2.0 * c[1] * y + c[3] * x + c[4] * z + c[7],
        2.0 * c[2] * z + c[4] * y + c[5] * x + c[8],
    ];
    let gmag = g[0].abs()
        + g[1].abs()
        + g[2].abs()
        + ROUND * (6.0 * cmax * big(p) + ca[6] + ca[7] + ca[8]);
    let e0 = ROUND * m[0] + gmag * shift;
    let e1 = ROUND * m[1] + 6.0 * cmax * shift * big(d);
    let e2 = ROUND * m[2];
    let [c0, b, a] = k;
    let open = if a == 0.0 {
        b != 0.0 && b.abs() <= e1
    } else if a.abs() <= e2 {
        true
    } else {
        let disc = b * b - 4.0 * a * c0;
        let edisc = 2.0 * b.abs() * e1
            + 4.0 * (a.abs() * e0 + c0.abs() * e2)
            + 4.0 * f32::EPSILON * (b * b + 4.0 * (a * c0).abs());
        let tv = tc - b / (2.0 * a);
        // Where the sign flips, the roots lie within √edisc/(2|a|) of the vertex.
        let margin = edisc.sqrt() / (2.0 * a.abs()) + 1e-3 * tv.abs().max(1.0);
        // NaN counts as open.
        let decided = disc.abs() > edisc;
        !decided && tv > t_min - margin && tv < t_max + margin
    };
    Centred { k, tc, open }
}

/// A plain quadric's answer for a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum QuadricHit {
    /// No crossing in (t_min, t_max).
    Miss,
    /// The first crossing.
    At(f32),
    /// A grazing ray whose outcome lies within f32 rounding ([`Centred::open`]): for
    /// the CPU.
    Undecided,
}

/// The first crossing in (t_min, t_max), operation for operation as the kernel.
pub fn first_crossing(
    q: &GpuQuadric,
    o: [f32; 3],
    d: [f32; 3],
    t_min: f32,
    t_max: f32,
) -> QuadricHit {
    let cq = centred(&q.c, o, d, t_min, t_max);
    if cq.open {
        return QuadricHit::Undecided;
    }
    let [c0, b, a] = cq.k;
    let tc = cq.tc;
    let inside = |t: f32| t > t_min && t < t_max;
    let hit = |t: f32| {
        if inside(t) {
            QuadricHit::At(t)
        } else {
            QuadricHit::Miss
        }
    };
    if a == 0.0 {
        if b == 0.0 {
            return QuadricHit::Miss;
        }
        return hit(tc + -c0 / b);
    }
    let disc = b * b - 4.0 * a * c0;
    if disc.is_nan() || disc <= 0.0 {
        return QuadricHit::Miss;
    }
    let s = disc.sqrt();
    let sgn = if b >= 0.0 { 1.0 } else { -1.0 };
    let h = -0.5 * (b + sgn * s);
    let r0 = tc + h / a;
    let r1 = if h != 0.0 { tc + c0 / h } else { r0 };
    let (lo, hi) = (r0.min(r1), r0.max(r1));
    if inside(lo) {
        QuadricHit::At(lo)
    } else if inside(hi) && hi != lo {
        QuadricHit::At(hi)
    } else {
        QuadricHit::Miss
    }
}
