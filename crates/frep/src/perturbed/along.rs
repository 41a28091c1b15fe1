//! A quadric along a ray: q(o + t·d) as a quadratic in t, the magnitudes that bound its
//! rounding, and the set where it is inside (≥ 0). Generic over the float type, like the
//! scan ([`super::scan`]) that builds on it.

use num_traits::Float;

/// A quadric's coefficients `[xx, yy, zz, xy, yz, xz, x, y, z, 1]` in T.
pub(crate) type Coeffs<T> = [T; 10];

/// q(p).
#[inline]
pub(crate) fn q_eval<T: Float>(c: &Coeffs<T>, p: [T; 3]) -> T {
    let [x, y, z] = p;
    x * (c[0] * x + c[3] * y + c[5] * z + c[6])
        + y * (c[1] * y + c[4] * z + c[7])
        + z * (c[2] * z + c[8])
        + c[9]
}

/// q along the ray about the point p = o + t₀·d, as a quadratic in s = t − t₀:
/// `[q(p), ∇q(p)·d, dᵀAd]`.
#[inline]
pub(crate) fn q_local<T: Float>(c: &Coeffs<T>, p: [T; 3], d: [T; 3]) -> [T; 3] {
    let [x, y, z] = p;
    let two = T::one() + T::one();
    let gx = two * c[0] * x + c[3] * y + c[5] * z + c[6];
    let gy = two * c[1] * y + c[3] * x + c[4] * z + c[7];
    let gz = two * c[2] * z + c[4] * y + c[5] * x + c[8];
    let [u, v, w] = d;
    let curv =
        c[0] * u * u + c[1] * v * v + c[2] * w * w + c[3] * u * v + c[4] * v * w + c[5] * u * w;
    [q_eval(c, p), gx * u + gy * v + gz * w, curv]
}

/// [`q_local`] in f64 with a shortcut for planes (no quadratic terms): the same sums in
/// the same order without the zero terms, so the same values (up to the sign of a zero),
/// at a third of the work (closed-form paths for boxes and half-spaces).
#[inline]
pub(crate) fn q_local_f64(c: &Coeffs<f64>, p: [f64; 3], d: [f64; 3]) -> [f64; 3] {
    if c[..6].iter().all(|&v| v == 0.0) && p.iter().chain(&d).all(|v| v.is_finite()) {
        let [x, y, z] = p;
        let [u, v, w] = d;
        return [
            x * c[6] + y * c[7] + z * c[8] + c[9],
            c[6] * u + c[7] * v + c[8] * w,
            0.0,
        ];
    }
    q_local(c, p, d)
}

/// Bounds on the magnitude of the terms summed by [`q_local`], for each of its three
/// outputs: the same sums with every term made positive. Rounding errors of q_local
/// are a few ε times these.
#[inline]
pub(crate) fn q_local_mag<T: Float>(c: &Coeffs<T>, p: [T; 3], d: [T; 3]) -> [T; 3] {
    let c = c.map(T::abs);
    let [x, y, z] = p.map(T::abs);
    let [u, v, w] = d.map(T::abs);
    let two = T::one() + T::one();
    let gx = two * c[0] * x + c[3] * y + c[5] * z + c[6];
    let gy = two * c[1] * y + c[3] * x + c[4] * z + c[7];
    let gz = two * c[2] * z + c[4] * y + c[5] * x + c[8];
    let curv =
        c[0] * u * u + c[1] * v * v + c[2] * w * w + c[3] * u * v + c[4] * v * w + c[5] * u * w;
    [q_eval(&c, [x, y, z]), gx * u + gy * v + gz * w, curv]
}

/// The set {t : a0 + a1·t + a2·t² ≥ 0} (inside, by the FRep convention F ≥ 0) as at
/// most two intervals, with the real roots as their finite ends (stable quadratic
/// formula: Press et al., Numerical Recipes §5.6). Only its ends matter to a ray, so
/// isolated points are dropped: a double root is a touch, not an interval end. A
/// constant 0 (a ray lying in a plane or along a cylinder's surface) is inside.
pub(crate) fn positive_set<T: Float>(a: [T; 3]) -> ([(T, T); 2], usize) {
    let (inf, none) = (T::infinity(), [(T::zero(), T::zero()); 2]);
    let [a0, a1, a2] = a;
    if a2 == T::zero() {
        if a1 == T::zero() {
            return if a0 >= T::zero() {
                ([(-inf, inf), (T::zero(), T::zero())], 1)
            } else {
                (none, 0)
            };
        }
        let r = -a0 / a1;
        return if a1 > T::zero() {
            ([(r, inf), none[0]], 1)
        } else {
            ([(-inf, r), none[0]], 1)
        };
    }
    let four = T::from(4.0).unwrap_or_else(T::nan);
    let disc = a1 * a1 - four * a2 * a0;
    if disc.is_nan() || disc <= T::zero() {
        return if a2 > T::zero() {
            ([(-inf, inf), none[0]], 1)
        } else {
            (none, 0)
        };
    }
    let half = T::from(0.5).unwrap_or_else(T::nan);
    let q = -half * (a1 + a1.signum() * disc.sqrt());
    let (r1, r2) = if q == T::zero() {
        // a1 = 0 and a0 = 0 would give disc = 0: here a1 = 0, roots ±√(−a0/a2).
        let r = (-a0 / a2).sqrt();
        (-r, r)
    } else {
        let (x, y) = (q / a2, a0 / q);
        (x.min(y), x.max(y))
    };
    if a2 < T::zero() {
        ([(r1, r2), none[0]], 1)
    } else {
        ([(-inf, r1), (r2, inf)], 2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The plane shortcut gives q_local's values on random planes, points and directions.
    #[test]
    fn plane_shortcut_equals_q_local() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
        for _ in 0..10_000 {
            let mut c = [0.0; 10];
            for v in &mut c[6..] {
                *v = rng.gen_range(-10.0..10.0);
            }
            let p = [0; 3].map(|_| rng.gen_range(-1e3..1e3));
            let d = [0; 3].map(|_| rng.gen_range(-1.0..1.0));
            assert_eq!(
                q_local_f64(&c, p, d),
                q_local(&c, p, d),
                "{c:?} {p:?} {d:?}"
            );
        }
    }
}
