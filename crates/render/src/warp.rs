//! Warps from [0,1)² to directions and points, with their densities
//! (pbrt-v4 §A.5, "Sampling Multidimensional Functions").

use glam::{DVec2, DVec3};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// √max(0, x).
#[inline]
pub fn safe_sqrt(x: f64) -> f64 {
    x.max(0.0).sqrt()
}

/// Taylor coefficients (−1)ᵏ/(2k+1)! and (−1)ᵏ/(2k)! of sin and cos, k = 1 … 8.
const SIN_TAYLOR: [f64; 8] = taylor(3);
const COS_TAYLOR: [f64; 8] = taylor(2);

/// `(−1)ᵏ / (first + 2k − 2)!` for k = 1 … 8, the factorials exact in f64 up to 18!.
const fn taylor(first: u32) -> [f64; 8] {
    let mut out = [0.0; 8];
    let mut k = 0;
    while k < 8 {
        let n = first + 2 * k as u32;
        let mut f = 1.0;
        let mut i = 2;
        while i <= n {
            f *= i as f64;
            i += 1;
        }
        out[k] = if k % 2 == 0 { -1.0 / f } else { 1.0 / f };
        k += 1;
    }
    out
}

/// (sin x, cos x) for |x| ≤ π/4 (a little beyond is fine): Taylor series to x¹⁷ and x¹⁸,
/// whose truncation is below 10⁻¹⁶ of the result there, in Horner form over x². Within
/// 2 ulps of `f64::sin_cos` (`sin_cos_kernel_is_within_two_ulps`), at about half the
/// instructions of glibc's `sincos` and no call: every sampled direction takes one
/// (the share of the diffuse scene's instructions that went to `sincos`:
/// docs/notebook/2026-12-02-cpu-speed-round-10.md).
#[inline]
pub fn sin_cos_kernel(x: f64) -> (f64, f64) {
    let z = x * x;
    let horner = |c: &[f64; 8]| c.iter().rev().fold(0.0, |acc, &k| acc * z + k);
    let s = x + x * z * horner(&SIN_TAYLOR);
    let c = 1.0 + z * horner(&COS_TAYLOR);
    (s, c)
}

/// (sin 2πu, cos 2πu) for u ≥ 0 (an azimuth in turns, as samplers draw it): u is
/// reduced to the nearest quarter turn exactly (4u − q, Sterbenz), the rest is
/// [`sin_cos_kernel`]'s.
#[inline]
pub fn sin_cos_turns(u: f64) -> (f64, f64) {
    let v = 4.0 * u;
    // The nearest quarter turn q (by truncation: v + ½ ≥ 0 for u ≥ 0).
    let q = (v + 0.5) as i64;
    let (s, c) = sin_cos_kernel((v - q as f64) * FRAC_PI_2);
    match q & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// A point of the unit disk, uniform in area (Shirley & Chiu 1997 concentric map).
/// The angle is π/4·(y/x) or π/2 − π/4·(x/y), |y/x|, |x/y| ≤ 1: sine and cosine
/// straight from [`sin_cos_kernel`], no reduction.
pub fn uniform_disk_concentric(u: DVec2) -> DVec2 {
    let o = 2.0 * u - DVec2::ONE;
    if o == DVec2::ZERO {
        return DVec2::ZERO;
    }
    if o.x.abs() > o.y.abs() {
        let (s, c) = sin_cos_kernel(FRAC_PI_4 * (o.y / o.x));
        o.x * DVec2::new(c, s)
    } else {
        // cos(π/2 − φ) = sin φ, sin(π/2 − φ) = cos φ.
        let (s, c) = sin_cos_kernel(FRAC_PI_4 * (o.x / o.y));
        o.y * DVec2::new(s, c)
    }
}

/// A point of the unit disk, uniform in area (polar map; pbrt-v4 SampleUniformDiskPolar).
pub fn uniform_disk_polar(u: DVec2) -> DVec2 {
    let r = u.x.sqrt();
    let (s, c) = sin_cos_turns(u.y);
    DVec2::new(r * c, r * s)
}

/// A direction of the upper hemisphere (z > 0) with density cos θ / π (Malley's method).
pub fn cosine_hemisphere(u: DVec2) -> DVec3 {
    let d = uniform_disk_concentric(u);
    DVec3::new(d.x, d.y, safe_sqrt(1.0 - d.length_squared()))
}

/// The density of [`cosine_hemisphere`]: max(cos θ, 0) / π.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f64) -> f64 {
    cos_theta.max(0.0) / PI
}

/// A direction uniform over the sphere (density 1/4π).
pub fn uniform_sphere(u: DVec2) -> DVec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = safe_sqrt(1.0 - z * z);
    let (s, c) = sin_cos_turns(u.y);
    DVec3::new(r * c, r * s, z)
}

/// The density of [`uniform_sphere`].
pub const UNIFORM_SPHERE_PDF: f64 = 1.0 / (4.0 * PI);

/// The direction with polar angle (sin θ, cos θ) and azimuth 2π·`turns` about +z.
#[inline]
pub fn spherical_direction(sin_theta: f64, cos_theta: f64, turns: f64) -> DVec3 {
    let s = sin_theta.clamp(-1.0, 1.0);
    let (sp, cp) = sin_cos_turns(turns);
    DVec3::new(s * cp, s * sp, cos_theta.clamp(-1.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{sphere_chi2, SphereBins};

    /// Units in the last place of `v`'s magnitude (its spacing at |v|).
    fn ulp(v: f64) -> f64 {
        let a = v.abs();
        f64::from_bits(a.to_bits() + 1) - a
    }

    /// The kernel is within 2 ulps of libm's `sin_cos` over [−π/4, π/4] (a little beyond
    /// too), on a dense grid and at its ends.
    #[test]
    fn sin_cos_kernel_is_within_two_ulps() {
        let n = 200_000;
        for i in 0..=n {
            let x = (2.0 * f64::from(i) / f64::from(n) - 1.0) * (FRAC_PI_4 * 1.001);
            let (s, c) = sin_cos_kernel(x);
            let (rs, rc) = x.sin_cos();
            assert!(
                (s - rs).abs() <= 2.0 * ulp(rs),
                "sin {x}: {s:e} against {rs:e}"
            );
            assert!(
                (c - rc).abs() <= 2.0 * ulp(rc),
                "cos {x}: {c:e} against {rc:e}"
            );
        }
        assert_eq!(sin_cos_kernel(0.0), (0.0, 1.0));
    }

    /// In turns: exact at the quarter turns, and within rounding of 2πu elsewhere (the
    /// reference's own product 2π·u is off by up to an ulp of 2π).
    #[test]
    fn sin_cos_turns_is_sin_cos_of_two_pi_u() {
        assert_eq!(sin_cos_turns(0.0), (0.0, 1.0));
        // Compared with ==, for which −0 and 0 are equal.
        for (u, ws, wc) in [(0.25, 1.0, 0.0), (0.5, 0.0, -1.0), (0.75, -1.0, 0.0)] {
            let (s, c) = sin_cos_turns(u);
            assert!(s == ws && c == wc, "u = {u}: ({s}, {c})");
        }
        let n = 400_000;
        for i in 0..n {
            let u = f64::from(i) / f64::from(n) + 0.3 / f64::from(n);
            let (s, c) = sin_cos_turns(u);
            let (rs, rc) = (2.0 * PI * u).sin_cos();
            assert!((s - rs).abs() < 2e-15 && (c - rc).abs() < 2e-15, "u = {u}");
        }
    }

    #[test]
    fn concentric_disk_stays_inside_and_is_uniform() {
        let mut inner = 0usize;
        let n = 100_000;
        for i in 0..n {
            let u = DVec2::new(
                (i as f64 + 0.5) / n as f64,
                ((i * 7919) % n) as f64 / n as f64,
            );
            let p = uniform_disk_concentric(u);
            assert!(p.length() <= 1.0 + 1e-12);
            inner += (p.length() < 0.5) as usize;
        }
        // Area fraction of radius ½ is ¼; a stratified set comes within 1 %.
        assert!((inner as f64 / n as f64 - 0.25).abs() < 0.01);
    }

    /// Cosine and uniform-sphere warps against their densities: chi-square over
    /// 16 × 32 cells, 200 000 samples, significance 1e-3.
    #[test]
    fn warps_match_densities() {
        let bins = SphereBins::new(16, 32);
        let p = sphere_chi2(
            &bins,
            200_000,
            11,
            |u| Some(cosine_hemisphere(DVec2::new(u[1], u[2]))),
            |w| cosine_hemisphere_pdf(w.z),
        );
        assert!(p.p_value > 1e-3 && (p.mass - 1.0).abs() < 1e-3, "{p:?}");
        let p = sphere_chi2(
            &bins,
            200_000,
            12,
            |u| Some(uniform_sphere(DVec2::new(u[1], u[2]))),
            |_| UNIFORM_SPHERE_PDF,
        );
        assert!(p.p_value > 1e-3 && (p.mass - 1.0).abs() < 1e-3, "{p:?}");
    }
}
