//! The GPU's plain-quadric intersection (its CPU f32 twin) against the f64 quadratic of
//! the same rays: 100 000 rays from 5 units away toward a needle's axis (a cylinder of
//! radius 1.25 mm) and toward points within 0.1 of a double cone's apex; counts of
//! wrong hits and misses, t off by over 10⁻⁴·max(1, t), and rays left to the CPU.
//!
//! `cargo run --release -p gpu --example quadric_check`
use frep::Quadric;
use glam::DVec3;
use gpu::layout::GpuQuadric;
use gpu::quadric::{first_crossing, QuadricHit};

fn f64_first(q: &Quadric, o: DVec3, d: DVec3) -> Option<f64> {
    let [c, b, a] = q.along(o, d);
    let disc = b * b - 4.0 * a * c;
    if a == 0.0 {
        return (b != 0.0).then(|| -c / b).filter(|t| *t > 0.0);
    }
    if disc <= 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let h = -0.5 * (b + b.signum() * s);
    let (r0, r1) = (h / a, c / h);
    let (lo, hi) = (r0.min(r1), r0.max(r1));
    if lo > 0.0 {
        Some(lo)
    } else if hi > 0.0 {
        Some(hi)
    } else {
        None
    }
}

fn main() {
    let mut seed = 1u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64) / (1u64 << 53) as f64
    };
    let cases = [
        (
            "needle",
            Quadric::cylinder(DVec3::new(0.3, 0.2, 0.0), DVec3::Z, 0.00125),
            DVec3::new(0.3, 0.2, 0.0),
            0.0,
        ),
        (
            "cone",
            Quadric::cone(DVec3::new(0.1, 0.2, 0.3), DVec3::Z, 30f64.to_radians()),
            DVec3::new(0.1, 0.2, 0.3),
            1e-1,
        ),
    ];
    for (name, q, p0, spread) in cases {
        let g = GpuQuadric::from(&q);
        let (mut wrong_hit, mut wrong_miss, mut toff, mut n, mut und) = (0, 0, 0, 0, 0);
        for _ in 0..100000 {
            let u = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
            let target = if name == "needle" {
                p0 + DVec3::new(0.0, 0.0, rnd() - 0.5)
            } else {
                p0 + spread * DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5)
            };
            let o = target - 5.0 * u;
            let (o32, d32) = (o.as_vec3(), (target - o).normalize().as_vec3());
            let got = first_crossing(&g, o32.to_array(), d32.to_array(), 0.0, 100.0);
            let want = f64_first(&q, o32.as_dvec3(), d32.as_dvec3());
            n += 1;
            let got = match got {
                QuadricHit::Undecided => {
                    und += 1;
                    continue;
                }
                QuadricHit::At(t) => Some(t),
                QuadricHit::Miss => None,
            };
            match (got, want) {
                (Some(t), Some(w)) => {
                    if (t as f64 - w).abs() > 1e-4 * w.max(1.0) {
                        toff += 1
                    }
                }
                (None, None) => {}
                (Some(_), None) => wrong_hit += 1,
                (None, Some(_)) => wrong_miss += 1,
            }
        }
        println!("{name}: {n} rays: false hits {wrong_hit}, misses {wrong_miss}, t off {toff}, undecided {und}");
    }
}
