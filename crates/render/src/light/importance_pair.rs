//! [`importance_of`] of two light-BVH nodes at once, in the two f64 lanes of SSE2 (part
//! of every x86-64): a descent of the light BVH weighs both children of every node it
//! passes, so the pair is its unit of work. Lane by lane the same operations in the same
//! order as the scalar function, with selects for its branches, so the values are the
//! same bit for bit (`pairs_equal_the_scalar_importance`; a zero may differ in sign,
//! which no probability or sum built from it shows). Elsewhere: the scalar function
//! twice.

#[cfg(any(test, not(target_arch = "x86_64")))]
use super::select::importance_of;
use super::select::ImportanceBounds;
use glam::DVec3;

/// `[importance_of(a, phi_a, p, n), importance_of(b, phi_b, p, n)]`.
#[inline]
pub(crate) fn importance_pair(
    (a, phi_a): (&ImportanceBounds, f64),
    (b, phi_b): (&ImportanceBounds, f64),
    p: DVec3,
    n: DVec3,
) -> [f64; 2] {
    #[cfg(target_arch = "x86_64")]
    {
        sse2((a, phi_a), (b, phi_b), p, n)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        [importance_of(a, phi_a, p, n), importance_of(b, phi_b, p, n)]
    }
}

#[cfg(target_arch = "x86_64")]
#[inline]
fn sse2(
    (a, phi_a): (&ImportanceBounds, f64),
    (b, phi_b): (&ImportanceBounds, f64),
    p: DVec3,
    n: DVec3,
) -> [f64; 2] {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of the x86-64 baseline; the one store writes two f64.
    unsafe {
        let pair = |x: f64, y: f64| _mm_set_pd(y, x);
        let splat = |x: f64| _mm_set1_pd(x);
        let zero = _mm_setzero_pd();
        let one = splat(1.0);
        // Lane-wise `if m { x } else { y }`.
        let select =
            |m: __m128d, x: __m128d, y: __m128d| _mm_or_pd(_mm_and_pd(m, x), _mm_andnot_pd(m, y));
        // `safe_sqrt`: max(x, 0) (NaN → 0, as `f64::max`), then √.
        let safe_sqrt = |x: __m128d| _mm_sqrt_pd(_mm_max_pd(x, zero));
        // cos(max(0, θa − θb)) and sin(max(0, θa − θb)) (`cos_sub_clamped`, `sin_sub_clamped`).
        let cos_sub = |sa: __m128d, ca: __m128d, sb: __m128d, cb: __m128d| {
            let v = _mm_add_pd(_mm_mul_pd(ca, cb), _mm_mul_pd(sa, sb));
            select(_mm_cmpgt_pd(ca, cb), one, v)
        };
        let sin_sub = |sa: __m128d, ca: __m128d, sb: __m128d, cb: __m128d| {
            let v = _mm_sub_pd(_mm_mul_pd(sa, cb), _mm_mul_pd(ca, sb));
            select(_mm_cmpgt_pd(ca, cb), zero, v)
        };
        let dot = |x: [__m128d; 3], y: [__m128d; 3]| {
            _mm_add_pd(
                _mm_add_pd(_mm_mul_pd(x[0], y[0]), _mm_mul_pd(x[1], y[1])),
                _mm_mul_pd(x[2], y[2]),
            )
        };
        let v = [0, 1, 2].map(|k| _mm_sub_pd(splat(p[k]), pair(a.center[k], b.center[k])));
        let axis = [0, 1, 2].map(|k| pair(a.axis[k], b.axis[k]));
        let radius = pair(a.radius, b.radius);
        let cos_o = pair(a.cos_o, b.cos_o);
        let dist2 = dot(v, v);
        let r2 = _mm_mul_pd(radius, radius);
        let d2 = _mm_max_pd(dist2, r2);
        let positive = _mm_cmpgt_pd(dist2, zero);
        let len = _mm_sqrt_pd(dist2);
        let w = [0, 1, 2].map(|k| select(positive, _mm_div_pd(v[k], len), axis[k]));
        let mut cos_w = dot(axis, w);
        let two_sided = _mm_castsi128_pd(_mm_set_epi64x(
            -i64::from(b.two_sided),
            -i64::from(a.two_sided),
        ));
        let abs = _mm_andnot_pd(splat(-0.0), cos_w);
        cos_w = select(two_sided, abs, cos_w);
        let sin_w = safe_sqrt(_mm_sub_pd(one, _mm_mul_pd(cos_w, cos_w)));
        let inside = _mm_cmple_pd(dist2, r2);
        let cone = safe_sqrt(_mm_sub_pd(one, _mm_div_pd(r2, dist2)));
        let cos_b = select(inside, splat(-1.0), cone);
        let sin_b = safe_sqrt(_mm_sub_pd(one, _mm_mul_pd(cos_b, cos_b)));
        let sin_o = safe_sqrt(_mm_sub_pd(one, _mm_mul_pd(cos_o, cos_o)));
        let cos_x = cos_sub(sin_w, cos_w, sin_o, cos_o);
        let sin_x = sin_sub(sin_w, cos_w, sin_o, cos_o);
        let cos_p = cos_sub(sin_x, cos_x, sin_b, cos_b);
        let cos_ip = if n == DVec3::ZERO {
            one
        } else {
            let nv = [0, 1, 2].map(|k| splat(n[k]));
            let cos_i = _mm_andnot_pd(splat(-0.0), dot(nv, w));
            let sin_i = safe_sqrt(_mm_sub_pd(one, _mm_mul_pd(cos_i, cos_i)));
            cos_sub(sin_i, cos_i, sin_b, cos_b)
        };
        let phi = pair(phi_a, phi_b);
        let value = _mm_div_pd(_mm_mul_pd(_mm_mul_pd(phi, cos_p), cos_ip), d2);
        let value = _mm_max_pd(value, zero);
        let value = select(_mm_cmple_pd(cos_p, zero), zero, value);
        let mut out = [0.0; 2];
        _mm_storeu_pd(out.as_mut_ptr(), value);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// splitmix64 (Steele et al. 2014) as numbers in [lo, hi).
    struct Rng(u64);

    impl Rng {
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            let u = ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64;
            lo + (hi - lo) * u
        }
        fn point(&mut self, r: f64) -> DVec3 {
            DVec3::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
        }
        fn unit(&mut self) -> DVec3 {
            self.point(1.0).normalize_or(DVec3::Z)
        }
    }

    /// The pair equals two scalar evaluations bit for bit (zeros up to sign) on random
    /// bounds and points, with the branches' edge cases: points inside the bounding
    /// sphere and at its centre, two-sided cones, cones of every spread (cos θo = ±1
    /// included), normals of zero and aligned with the axis.
    #[test]
    fn pairs_equal_the_scalar_importance() {
        let mut rng = Rng(9);
        let bounds = |rng: &mut Rng, k: usize| ImportanceBounds {
            center: rng.point(3.0),
            radius: if k.is_multiple_of(9) {
                0.0
            } else {
                rng.range(0.0, 2.0)
            },
            axis: rng.unit(),
            cos_o: match k % 5 {
                0 => -1.0,
                1 => 1.0,
                _ => rng.range(-1.0, 1.0),
            },
            two_sided: k.is_multiple_of(3),
        };
        let key = |v: f64| if v == 0.0 { 0 } else { v.to_bits() };
        let mut zeros = 0;
        for k in 0..200_000 {
            let (a, b) = (bounds(&mut rng, k), bounds(&mut rng, k / 2));
            let (phi_a, phi_b) = (rng.range(0.0, 10.0), rng.range(0.0, 10.0));
            let p = match k % 7 {
                0 => a.center,
                1 => b.center + 0.5 * b.radius * rng.unit(),
                _ => rng.point(4.0),
            };
            let n = match k % 4 {
                0 => DVec3::ZERO,
                1 => a.axis,
                _ => rng.unit(),
            };
            let got = importance_pair((&a, phi_a), (&b, phi_b), p, n);
            let want = [
                importance_of(&a, phi_a, p, n),
                importance_of(&b, phi_b, p, n),
            ];
            zeros += want.iter().filter(|&&v| v == 0.0).count();
            assert_eq!(
                got.map(key),
                want.map(key),
                "{a:?} {phi_a} {b:?} {phi_b} {p} {n}: {got:?} {want:?}"
            );
        }
        // Both kinds of lane occur: zero importance and positive.
        assert!(zeros > 10_000 && zeros < 300_000, "{zeros}");
    }
}
