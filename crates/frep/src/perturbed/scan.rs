//! The piecewise-polynomial scan along one ray (RESEARCH.md §4), generic over the float
//! type so that the f32 path the GPU mirrors is this very code.
//!
//! Along x = o + t·d the base F and every q_i are quadratics in t. The real roots of
//! the q_i cut the ray into pieces on which the set of positive q_i is fixed, so that
//! F' = F + Σ_{q_i>0} f_i·q_i³ is one polynomial of degree ≤ 6 per piece. Pieces are
//! scanned left to right, each expanded about its left end (evaluating the quadrics
//! there, not shifting a global polynomial, so that far pieces lose no precision),
//! mapped to u ∈ [0, 1] and searched with [`Bernstein::first_negative`]. An unbounded
//! piece is cut at Cauchy's root bound, past which its polynomial has no root.

use crate::poly::{Bernstein, Poly};
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

/// The open set {t : a0 + a1·t + a2·t² > 0} as at most two open intervals, with the
/// real roots as their finite ends (stable quadratic formula: Press et al., Numerical
/// Recipes §5.6). A double root is a touch, not an interval end.
pub(crate) fn positive_set<T: Float>(a: [T; 3]) -> ([(T, T); 2], usize) {
    let (inf, none) = (T::infinity(), [(T::zero(), T::zero()); 2]);
    let [a0, a1, a2] = a;
    if a2 == T::zero() {
        if a1 == T::zero() {
            return if a0 > T::zero() {
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

/// One perturbation that is positive somewhere on the scanned range.
#[derive(Clone, Copy)]
struct Active<T> {
    f: T,
    q: Coeffs<T>,
    set: [(T, T); 2],
    n: usize,
}

impl<T: Float> Active<T> {
    #[inline]
    fn holds(&self, t: T) -> bool {
        self.set[..self.n].iter().any(|&(a, b)| a < t && t < b)
    }
}

/// The first t in (t_min, t_max) where F' changes sign, scanning [lo, hi] ⊂ [t_min,
/// t_max]. `sign` is the sign of F' just after lo when the caller knows it (−1 when lo
/// is where the ray enters the bounds of {F' ≥ 0}), else 0 to read it from F'.
/// `perturbations` yields (f_i, q_i) for every perturbation the range may meet.
#[allow(clippy::too_many_arguments)]
pub(crate) fn first_crossing<T: Float>(
    base: &Coeffs<T>,
    perturbations: impl Iterator<Item = (T, Coeffs<T>)>,
    o: [T; 3],
    d: [T; 3],
    range: (T, T),
    t_min: T,
    t_max: T,
    sign: T,
) -> Option<T> {
    let (lo, hi) = range;
    if lo.is_nan() || hi.is_nan() || lo >= hi {
        return None;
    }
    let mut active: Vec<Active<T>> = Vec::new();
    let mut breaks: Vec<T> = Vec::new();
    for (f, q) in perturbations {
        if f == T::zero() {
            continue;
        }
        let (mut set, n) = positive_set(q_local(&q, o, d));
        let mut k = 0;
        for j in 0..n {
            let (a, b) = set[j];
            if a < hi && b > lo {
                set[k] = (a, b);
                k += 1;
                for e in [a, b] {
                    if e > lo && e < hi {
                        breaks.push(e);
                    }
                }
            }
        }
        if k > 0 {
            active.push(Active { f, q, set, n: k });
        }
    }
    breaks.sort_unstable_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    // An unbounded range needs a finite point to expand about.
    if lo == -T::infinity() && hi == T::infinity() && breaks.is_empty() {
        breaks.push(T::zero());
    }
    let mut scan = Scan {
        base,
        active: &active,
        o,
        d,
        s: sign,
        t_min,
        t_max,
    };
    let mut ta = lo;
    for k in 0..=breaks.len() {
        let tb = if k < breaks.len() { breaks[k] } else { hi };
        if tb.is_nan() || tb <= ta {
            continue;
        }
        let found = if ta == -T::infinity() {
            scan.left_unbounded(tb)
        } else if tb == T::infinity() {
            scan.right_unbounded(ta)
        } else {
            scan.piece(ta, tb)
        };
        if let Some(result) = found {
            return result;
        }
        ta = tb;
    }
    None
}

/// The state of one scan: the sign of F' before the current piece (0 while unknown).
struct Scan<'a, T> {
    base: &'a Coeffs<T>,
    active: &'a [Active<T>],
    o: [T; 3],
    d: [T; 3],
    s: T,
    t_min: T,
    t_max: T,
}

/// How far past a finite anchor an unbounded piece's first sub-piece reaches, and the
/// growth factor of the following ones.
const GROWTH: f64 = 8.0;

impl<T: Float> Scan<'_, T> {
    /// Scans the finite piece [ta, tb]: Some(answer) when the scan is decided.
    fn piece(&mut self, ta: T, tb: T) -> Option<Option<T>> {
        let (b, e) = Piece::new(self.base, self.active, self.o, self.d, ta, tb, None).bernstein();
        if !b.coeffs().iter().all(|v| v.is_finite()) {
            // Beyond the range of T (only far along an unbounded piece): give up there.
            return Some(None);
        }
        if self.s == T::zero() {
            self.s = b.sign_after_zero_bounded(&e);
            if self.s == T::zero() {
                return None;
            }
        }
        let u = b.scale(self.s).first_negative_bounded(&e)?;
        let t = (ta + (tb - ta) * u).max(ta).min(tb);
        if t >= self.t_max {
            return Some(None);
        }
        let above = self.t_min + (self.t_min.abs() * T::epsilon()).max(T::min_positive_value());
        Some(Some(t.max(above)))
    }

    /// The polynomial of an unbounded piece expanded about its finite end `at`, read
    /// at `inside`, and Cauchy's bound on its roots in s = t − at.
    fn root_bound(&self, at: T, inside: T) -> Option<T> {
        let p = Piece::new(self.base, self.active, self.o, self.d, at, at, Some(inside));
        p.poly.cauchy_bound()
    }

    /// [ta, ∞): past ta + R no root is left; before it, sub-pieces growing by GROWTH.
    fn right_unbounded(&mut self, ta: T) -> Option<Option<T>> {
        let one = T::one();
        let width = ta.abs().max(one);
        let Some(r) = self.root_bound(ta, ta + width) else {
            return self.piece(ta, ta + width);
        };
        let growth = T::from(GROWTH).unwrap_or_else(T::nan);
        let end = ta + r;
        let (mut a, mut w) = (ta, width.min(r));
        while a < end {
            let b = (a + w).min(end);
            if let Some(found) = self.piece(a, b) {
                return Some(found);
            }
            a = b;
            w = w * growth;
        }
        None
    }

    /// (−∞, tb]: nothing changes before tb − R; from there, sub-pieces shrinking by
    /// GROWTH towards tb.
    fn left_unbounded(&mut self, tb: T) -> Option<Option<T>> {
        let one = T::one();
        let width = tb.abs().max(one);
        let Some(r) = self.root_bound(tb, tb - width) else {
            return self.piece(tb - width, tb);
        };
        let growth = T::from(GROWTH).unwrap_or_else(T::nan);
        let mut cuts = vec![tb];
        let mut w = width.min(r);
        while w < r {
            cuts.push(tb - w);
            w = w * growth;
        }
        cuts.push(tb - r);
        for k in (1..cuts.len()).rev() {
            if let Some(found) = self.piece(cuts[k], cuts[k - 1]) {
                return Some(found);
            }
        }
        None
    }
}

/// F' on one piece as a polynomial in s = t − ta (degree ≤ 6), with a first-order bound
/// on the rounding error of each coefficient in units of ε: the summed magnitudes of
/// the base's terms, and for each perturbation the error of q propagated through the
/// cube ([`Poly::add_cube_error`]).
struct Piece<T> {
    poly: Poly<T>,
    mag: Poly<T>,
    h: T,
}

/// The safety factor on the first-order rounding bound of a piece's coefficients.
const ROUNDING: f64 = 32.0;

impl<T: Float> Piece<T> {
    /// The piece [ta, tb], its active perturbations read at `inside` (default: the
    /// middle).
    fn new(
        base: &Coeffs<T>,
        active: &[Active<T>],
        o: [T; 3],
        d: [T; 3],
        ta: T,
        tb: T,
        inside: Option<T>,
    ) -> Self {
        let half = T::from(0.5).unwrap_or_else(T::nan);
        let inside = inside.unwrap_or((ta + tb) * half);
        let h = tb - ta;
        let p = [o[0] + ta * d[0], o[1] + ta * d[1], o[2] + ta * d[2]];
        let mut poly = Poly::quadratic(q_local(base, p, d));
        let mut mag = Poly::quadratic(q_local_mag(base, p, d));
        for a in active {
            if a.holds(inside) {
                let q = q_local(&a.q, p, d);
                poly.add_scaled_cube(a.f, q);
                // |q| on [ta, tb]: the largest Bernstein coefficient of the quadratic.
                let [q0, q1, q2] = q;
                let mid = q0 + q1 * h * half;
                let end = q0 + (q1 + q2 * h) * h;
                let q_max = q0.abs().max(mid.abs()).max(end.abs());
                mag.add_cube_error(a.f, q, q_local_mag(&a.q, p, d), q_max);
            }
        }
        Self {
            poly,
            mag,
            h: tb - ta,
        }
    }

    /// The piece over u ∈ [0, 1] (t = ta + h·u) in Bernstein form, with a bound on the
    /// rounding error of each coefficient.
    fn bernstein(&self) -> (Bernstein<T>, Bernstein<T>) {
        let b = self.poly.scaled(self.h).to_bernstein();
        let k = T::epsilon() * T::from(ROUNDING).unwrap_or_else(T::nan);
        let e = self.mag.scaled(self.h).to_bernstein().scale(k);
        (b, e)
    }
}
