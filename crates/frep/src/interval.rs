//! Interval arithmetic: guaranteed bounds of an expression over a box.
//!
//! Every operation returns an interval that contains the exact result for every point of
//! its operands (Moore, "Interval Analysis", 1966), widened outward by one or two ulps so
//! that floating-point rounding can never make a bound too tight. An empty or undefined
//! result (√ of a wholly negative interval, 0·∞) is NaN, which callers read as "unknown".

use crate::scalar::{Scalar, Zero};
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::ops::{Add, Div, Mul, Neg, Sub};

/// A closed interval `[lo, hi]` of reals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Lower bound.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
}

/// The widening of a bound `v`: max(|v|, 2⁻⁹⁷⁰)·2⁻⁵², one ulp of v or more (two at most
/// from 2⁻⁹⁷⁰ up). Never subnormal: a zero bound widened by the least subnormal, as
/// before, made the next products and widenings multiply subnormals, which Intel CPUs
/// run through a microcode assist at about 15× a normal multiplication's time (grid
/// builds 1.1–2× faster without them: docs/notebook/2026-12-07-normal-widenings.md).
///
/// Computed on the bit pattern, with no multiplication at all: |v|·2⁻⁵² is |v| with 52
/// taken off its exponent, exact wherever the result is normal (|v| ≥ 2⁻⁹⁷⁰). Below, the
/// difference of bit patterns is a subnormal pattern or wraps to a negative number or a
/// NaN, and the comparison gives 2⁻¹⁰²² instead. An infinite v gives 2⁹⁷² (∞ ∓ 2⁹⁷² = ∞)
/// and NaN gives 2⁻¹⁰²² (v ∓ d is NaN). Three operations after |v| (an integer
/// subtraction, a `maxsd`, then v ∓ d), where max(|v|, 2⁻⁹⁷⁰)·2⁻⁵² capped at `f64::MAX`
/// took a max, a product and a min on the chain every tape node's bounds wait on: the
/// same values bit for bit (`widening_by_exponent_equals_the_product`).
#[inline]
fn relative_ulp(v: f64) -> f64 {
    let d = f64::from_bits(v.abs().to_bits().wrapping_sub(52 << 52));
    if d > f64::MIN_POSITIVE {
        d
    } else {
        f64::MIN_POSITIVE
    }
}

/// A value below `v` by at least one ulp (round to nearest: v − d with d ≥ ulp(v) is
/// below v even after rounding); infinities and NaN unchanged.
#[inline]
fn down(v: f64) -> f64 {
    v - relative_ulp(v)
}

/// A value above `v` by at least one ulp, as [`down`].
#[inline]
fn up(v: f64) -> f64 {
    v + relative_ulp(v)
}

impl Interval {
    /// The interval `[lo, hi]` (exact, not widened).
    #[inline]
    pub const fn new(lo: f64, hi: f64) -> Self {
        Self { lo, hi }
    }
    /// The degenerate interval `[v, v]`.
    #[inline]
    pub const fn point(v: f64) -> Self {
        Self { lo: v, hi: v }
    }
    /// The whole real line.
    pub const ENTIRE: Self = Self::new(f64::NEG_INFINITY, f64::INFINITY);
    /// The "unknown / empty" interval.
    pub const NAN: Self = Self::new(f64::NAN, f64::NAN);

    /// Bounds widened outward by one or two ulps each.
    #[inline]
    fn widened(lo: f64, hi: f64) -> Self {
        if lo.is_nan() || hi.is_nan() {
            Self::NAN
        } else {
            Self::new(down(lo), up(hi))
        }
    }
    /// Whether either bound is NaN.
    #[inline]
    pub fn is_nan(&self) -> bool {
        self.lo.is_nan() || self.hi.is_nan()
    }
    /// Whether `v` lies in the interval (false for NaN intervals).
    #[inline]
    pub fn contains(&self, v: f64) -> bool {
        self.lo <= v && v <= self.hi
    }
    /// hi − lo.
    #[inline]
    pub fn width(&self) -> f64 {
        self.hi - self.lo
    }
    /// The midpoint.
    #[inline]
    pub fn mid(&self) -> f64 {
        0.5 * (self.lo + self.hi)
    }
    /// Applies a non-decreasing function.
    #[inline]
    fn increasing(self, f: impl Fn(f64) -> f64) -> Self {
        Self::widened(f(self.lo), f(self.hi))
    }
}

impl Add for Interval {
    type Output = Self;
    #[inline]
    fn add(self, b: Self) -> Self {
        Self::widened(self.lo + b.lo, self.hi + b.hi)
    }
}

impl Sub for Interval {
    type Output = Self;
    #[inline]
    fn sub(self, b: Self) -> Self {
        Self::widened(self.lo - b.hi, self.hi - b.lo)
    }
}

impl Neg for Interval {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self::new(-self.hi, -self.lo)
    }
}

impl Mul for Interval {
    type Output = Self;
    #[inline]
    fn mul(self, b: Self) -> Self {
        let p = [
            self.lo * b.lo,
            self.lo * b.hi,
            self.hi * b.lo,
            self.hi * b.hi,
        ];
        if p.iter().any(|v| v.is_nan()) {
            // 0·∞: the product is unbounded unless an operand is exactly zero.
            if (self.lo == 0.0 && self.hi == 0.0) || (b.lo == 0.0 && b.hi == 0.0) {
                return Self::point(0.0);
            }
            if self.is_nan() || b.is_nan() {
                return Self::NAN;
            }
            return Self::ENTIRE;
        }
        // Pairwise, not folded: two levels of min/max wait on the products, not four
        // (no product is NaN here, and a zero bound's sign is lost in the widening).
        let min = |a: f64, b: f64| if a < b { a } else { b };
        let max = |a: f64, b: f64| if a > b { a } else { b };
        let lo = min(min(p[0], p[1]), min(p[2], p[3]));
        let hi = max(max(p[0], p[1]), max(p[2], p[3]));
        Self::widened(lo, hi)
    }
}

impl Div for Interval {
    type Output = Self;
    #[inline]
    fn div(self, b: Self) -> Self {
        if b.is_nan() || self.is_nan() {
            return Self::NAN;
        }
        if b.lo <= 0.0 && b.hi >= 0.0 {
            if b.lo == 0.0 && b.hi == 0.0 {
                return Self::NAN;
            }
            return Self::ENTIRE;
        }
        self * Self::widened(1.0 / b.hi, 1.0 / b.lo)
    }
}

impl Scalar for Interval {
    const R_BOUND: bool = true;

    fn r_bound(v: Self, a: Self, b: Self, union: bool) -> Self {
        let ends = [a.lo, a.hi, b.lo, b.hi];
        if !ends.iter().all(|e| e.is_finite()) || v.is_nan() {
            return v;
        }
        // The R-function at a corner, in outward-rounded interval arithmetic.
        let at = |x: f64, y: f64| {
            let (x, y) = (Self::point(x), Self::point(y));
            let root = (x.square() + y.square()).sqrt();
            if union {
                x + y + root
            } else {
                x + y - root
            }
        };
        let lo = v.lo.max(at(a.lo, b.lo).lo);
        let hi = v.hi.min(at(a.hi, b.hi).hi);
        if lo <= hi {
            Self::new(lo, hi)
        } else {
            v
        }
    }

    #[inline]
    fn constant(v: f64) -> Self {
        Self::point(v)
    }
    fn abs(self) -> Self {
        if self.lo >= 0.0 {
            self
        } else if self.hi <= 0.0 {
            -self
        } else {
            Self::new(0.0, self.hi.max(-self.lo))
        }
    }
    fn sqrt(self) -> Self {
        if self.hi < 0.0 || self.is_nan() {
            return Self::NAN;
        }
        Self::widened(self.lo.max(0.0).sqrt(), self.hi.sqrt()).clamp_lo(0.0)
    }
    fn square(self) -> Self {
        let a = Scalar::abs(self);
        Self::widened(a.lo * a.lo, a.hi * a.hi).clamp_lo(0.0)
    }
    fn powi(self, n: i32) -> Self {
        match n {
            0 => Self::point(1.0),
            1 => self,
            n if n < 0 => Self::point(1.0) / self.powi(-n),
            n if n % 2 == 0 => {
                let a = Scalar::abs(self);
                Self::widened(a.lo.powi(n), a.hi.powi(n)).clamp_lo(0.0)
            }
            n => self.increasing(|v| v.powi(n)),
        }
    }
    fn exp(self) -> Self {
        self.increasing(f64::exp).clamp_lo(0.0)
    }
    fn ln(self) -> Self {
        if self.hi < 0.0 || self.is_nan() {
            return Self::NAN;
        }
        let lo = if self.lo <= 0.0 {
            f64::NEG_INFINITY
        } else {
            self.lo.ln()
        };
        Self::widened(lo, self.hi.ln())
    }
    fn sin(self) -> Self {
        (self - Self::point(FRAC_PI_2)).cos()
    }
    fn cos(self) -> Self {
        if self.is_nan() {
            return Self::NAN;
        }
        if self.width() >= TAU {
            return Self::new(-1.0, 1.0);
        }
        // Shift so that lo ∈ [0, 2π); cos has its maximum at 2πk, minimum at π + 2πk.
        // The shift is only used to locate the extrema, with slack for its rounding;
        // the endpoint values come from the unshifted arguments.
        let k = (self.lo / TAU).floor();
        let lo = self.lo - k * TAU;
        let hi = self.hi - k * TAU;
        let slack = 1e-12 * (1.0 + self.lo.abs().max(self.hi.abs()));
        let (cl, ch) = (self.lo.cos(), self.hi.cos());
        let mut min = cl.min(ch);
        let mut max = cl.max(ch);
        let has = |c: f64| lo <= c + slack && hi >= c - slack;
        if has(PI) || has(3.0 * PI) {
            min = -1.0;
        }
        if has(TAU) || has(0.0) {
            max = 1.0;
        }
        Self::widened(min, max).clamp(-1.0, 1.0)
    }
    fn tan(self) -> Self {
        if self.is_nan() || self.width() >= PI {
            return Self::ENTIRE;
        }
        // A pole at π/2 + kπ inside the interval makes it unbounded.
        let k = ((self.lo - FRAC_PI_2) / PI).floor();
        let pole = FRAC_PI_2 + (k + 1.0) * PI;
        if self.hi >= pole {
            return Self::ENTIRE;
        }
        self.increasing(f64::tan)
    }
    fn asin(self) -> Self {
        if self.hi < -1.0 || self.lo > 1.0 || self.is_nan() {
            return Self::NAN;
        }
        Self::widened(self.lo.max(-1.0).asin(), self.hi.min(1.0).asin())
    }
    fn acos(self) -> Self {
        if self.hi < -1.0 || self.lo > 1.0 || self.is_nan() {
            return Self::NAN;
        }
        Self::widened(self.hi.min(1.0).acos(), self.lo.max(-1.0).acos())
    }
    fn atan(self) -> Self {
        self.increasing(f64::atan)
    }
    fn atan2(self, x: Self) -> Self {
        let y = self;
        if y.is_nan() || x.is_nan() {
            return Self::NAN;
        }
        // Over a box that neither contains the origin nor meets the branch cut
        // (x ≤ 0, y = 0), atan2 is continuous and its extremes lie at the corners.
        let meets_cut = x.lo <= 0.0 && y.lo <= 0.0 && y.hi >= 0.0;
        if meets_cut {
            return Self::new(-PI, PI);
        }
        let c = [
            y.lo.atan2(x.lo),
            y.lo.atan2(x.hi),
            y.hi.atan2(x.lo),
            y.hi.atan2(x.hi),
        ];
        let lo = c.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = c.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Self::widened(lo, hi).clamp(-PI, PI)
    }
    fn min(self, b: Self) -> Self {
        Self::new(self.lo.min(b.lo), self.hi.min(b.hi))
    }
    fn max(self, b: Self) -> Self {
        Self::new(self.lo.max(b.lo), self.hi.max(b.hi))
    }
    fn floor(self) -> Self {
        Self::new(self.lo.floor(), self.hi.floor())
    }
    fn ceil(self) -> Self {
        Self::new(self.lo.ceil(), self.hi.ceil())
    }
    fn round(self) -> Self {
        Self::new(self.lo.round(), self.hi.round())
    }
    fn modulo(self, b: Self) -> Self {
        if self.is_nan() || b.is_nan() {
            return Self::NAN;
        }
        if b.lo == b.hi && b.lo != 0.0 && b.lo.is_finite() {
            let c = b.lo.abs();
            let k0 = (self.lo / c).floor();
            let k1 = (self.hi / c).floor();
            if k0 == k1 && self.lo.is_finite() {
                return Self::widened(self.lo - k0 * c, self.hi - k0 * c).clamp(0.0, c);
            }
            return Self::new(0.0, c);
        }
        if b.lo > 0.0 || b.hi < 0.0 {
            return Self::new(0.0, b.lo.abs().max(b.hi.abs()));
        }
        Self::ENTIRE
    }
    fn compare(self, b: Self) -> Self {
        if self.is_nan() || b.is_nan() {
            Self::NAN
        } else if self.hi < b.lo {
            Self::point(-1.0)
        } else if self.lo > b.hi {
            Self::point(1.0)
        } else if self.lo == self.hi && b.lo == b.hi {
            Self::point(0.0)
        } else {
            Self::new(-1.0, 1.0)
        }
    }
    fn zero(self) -> Zero {
        if self.lo == 0.0 && self.hi == 0.0 {
            Zero::Yes
        } else if self.lo > 0.0 || self.hi < 0.0 {
            Zero::No
        } else {
            Zero::Maybe
        }
    }
    fn hull(self, b: Self) -> Self {
        Self::new(self.lo.min(b.lo), self.hi.max(b.hi))
    }
    fn less(self, b: Self) -> Option<bool> {
        if self.hi < b.lo {
            Some(true)
        } else if self.lo >= b.hi {
            Some(false)
        } else {
            None
        }
    }
}

impl Interval {
    #[inline]
    fn clamp_lo(self, lo: f64) -> Self {
        if self.is_nan() {
            self
        } else {
            Self::new(self.lo.max(lo), self.hi.max(lo))
        }
    }
    #[inline]
    fn clamp(self, lo: f64, hi: f64) -> Self {
        if self.is_nan() {
            self
        } else {
            Self::new(self.lo.clamp(lo, hi), self.hi.clamp(lo, hi))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// 2⁻⁹⁷⁰: below it in magnitude a bound is widened by 2⁻⁹⁷⁰·2⁻⁵² = 2⁻¹⁰²², the least
    /// normal, instead of |v|·2⁻⁵² ([`relative_ulp`]).
    const FLOOR: f64 = f64::from_bits(53 << 52);

    /// Outward rounding moves every finite bound from 2⁻⁹⁷⁰ up by one or two ulps, and
    /// every smaller one (zero and the subnormals included) by at least one ulp and at
    /// most 2⁻¹⁰²¹; it keeps infinities and NaN.
    #[test]
    fn widening_is_one_or_two_ulps() {
        let tiny = f64::from_bits(1);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let mut values = vec![
            0.0,
            tiny,
            3.0 * tiny,
            f64::MIN_POSITIVE / 3.0,
            f64::MIN_POSITIVE,
            2f64.powi(-971),
            FLOOR,
            1e-300,
            1.0,
            1.5,
            0.1,
            3e7,
            2f64.powi(52),
            1.0 - f64::EPSILON / 2.0,
            f64::MAX / 4.0,
        ];
        for _ in 0..100_000 {
            let e = rng.gen_range(-1022..1023);
            values.push(rng.gen_range(1.0..2.0) * 2f64.powi(e));
        }
        for _ in 0..10_000 {
            values.push(f64::from_bits(rng.gen_range(1..1u64 << 52)));
        }
        for v in values.clone() {
            values.push(-v);
        }
        for v in values {
            let (d, u) = (down(v), up(v));
            assert!(
                d <= v.next_down() && u >= v.next_up(),
                "{v:e}: [{d:e}, {u:e}]"
            );
            if v.abs() >= FLOOR {
                assert!(d >= v.next_down().next_down(), "down {v:e}: {d:e}");
                assert!(u <= v.next_up().next_up(), "up {v:e}: {u:e}");
            } else {
                let most = 2.0 * f64::MIN_POSITIVE;
                assert!(v - d <= most && u - v <= most, "{v:e}: [{d:e}, {u:e}]");
            }
        }
        assert_eq!(up(f64::MAX), f64::INFINITY);
        assert_eq!(down(-f64::MAX), f64::NEG_INFINITY);
        for inf in [f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!((down(inf), up(inf)), (inf, inf));
        }
        assert!(down(f64::NAN).is_nan() && up(f64::NAN).is_nan());
    }

    /// The widening taken from the exponent equals max(|v|, 2⁻⁹⁷⁰)·2⁻⁵² capped at
    /// `f64::MAX` bit for bit, over every exponent, the subnormals, zero, the ends of the
    /// range and the exponents where the bit patterns' difference wraps; and both give
    /// the same bounds at infinity.
    #[test]
    fn widening_by_exponent_equals_the_product() {
        let product = |v: f64| (v.abs().max(FLOOR) * f64::EPSILON).min(f64::MAX);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(12);
        let mut values = vec![
            0.0,
            f64::from_bits(1),
            f64::MIN_POSITIVE,
            f64::from_bits(52 << 52),
            f64::from_bits((52 << 52) - 1),
            f64::from_bits((52 << 52) + 1),
            FLOOR,
            f64::from_bits((53 << 52) - 1),
            f64::from_bits((53 << 52) + 1),
            1.0,
            f64::MAX,
        ];
        for _ in 0..200_000 {
            values.push(f64::from_bits(rng.gen_range(0..0x7ff0_0000_0000_0000u64)));
        }
        for v in values {
            for v in [v, -v] {
                assert_eq!(relative_ulp(v).to_bits(), product(v).to_bits(), "{v:e}");
            }
        }
        for inf in [f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(inf - relative_ulp(inf), inf - product(inf));
            assert_eq!(inf + relative_ulp(inf), inf + product(inf));
        }
    }

    /// A zero bound widens to the least normal, not to a subnormal, so that the
    /// operations on intervals that touch zero (products of [0, a], sums, odd powers)
    /// give normal bounds or zero (squares and even powers, clamped: never negative);
    /// with the least subnormal as the widening of zero, every one of the others was
    /// subnormal.
    #[test]
    fn zero_bounds_widen_to_normals() {
        assert_eq!(
            (down(0.0), up(0.0)),
            (-f64::MIN_POSITIVE, f64::MIN_POSITIVE)
        );
        assert_eq!(
            (down(-0.0), up(-0.0)),
            (-f64::MIN_POSITIVE, f64::MIN_POSITIVE)
        );
        let (p, n) = (Interval::new(0.0, 2.0), Interval::new(-3.0, 0.0));
        let results = [
            p * p,
            n * n,
            p * n,
            p + p,
            n - p,
            p.square(),
            n.square(),
            p.powi(3),
        ];
        for r in results {
            let zero_end = if r.lo.abs() < r.hi.abs() { r.lo } else { r.hi };
            assert!(zero_end == 0.0 || zero_end.is_normal(), "{r:?}");
            assert!(zero_end.abs() <= 2.0 * f64::MIN_POSITIVE, "{r:?}");
        }
    }

    /// Every unary operation's interval contains the point results of random points in it.
    #[test]
    fn unary_ops_enclose_samples() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        type Op = (&'static str, fn(Interval) -> Interval, fn(f64) -> f64);
        let ops: [Op; 12] = [
            ("sin", Scalar::sin, f64::sin),
            ("cos", Scalar::cos, f64::cos),
            ("tan", Scalar::tan, f64::tan),
            ("exp", Scalar::exp, f64::exp),
            ("ln", Scalar::ln, f64::ln),
            ("sqrt", Scalar::sqrt, f64::sqrt),
            ("square", Scalar::square, |v| v * v),
            ("cube", |v| v.powi(3), |v| v.powi(3)),
            ("pow4", |v| v.powi(4), |v| v.powi(4)),
            ("asin", Scalar::asin, f64::asin),
            ("acos", Scalar::acos, f64::acos),
            ("atan", Scalar::atan, f64::atan),
        ];
        for _ in 0..2000 {
            let a: f64 = rng.gen_range(-8.0..8.0);
            let b: f64 = a + rng.gen_range(0.0..6.0f64).powi(2) * 0.3;
            let i = Interval::new(a, b);
            for (name, fi, fp) in ops.iter() {
                let r = fi(i);
                for k in 0..=16 {
                    let v = (a + (b - a) * k as f64 / 16.0).min(b);
                    let p = fp(v);
                    if p.is_nan() || r.is_nan() {
                        continue;
                    }
                    assert!(
                        r.lo <= p && p <= r.hi || (r.lo == f64::NEG_INFINITY && p.is_infinite()),
                        "{name}([{a}, {b}]) = {r:?} misses {name}({v}) = {p}"
                    );
                }
            }
        }
    }

    #[test]
    fn binary_ops_enclose_samples() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(8);
        for _ in 0..3000 {
            let (a0, b0): (f64, f64) = (rng.gen_range(-4.0..4.0), rng.gen_range(-4.0..4.0));
            let a = Interval::new(a0, a0 + rng.gen_range(0.0..3.0));
            let b = Interval::new(b0, b0 + rng.gen_range(0.0..3.0));
            for i in 0..=6 {
                for j in 0..=6 {
                    let x = (a.lo + a.width() * i as f64 / 6.0).min(a.hi);
                    let y = (b.lo + b.width() * j as f64 / 6.0).min(b.hi);
                    let checks = [
                        ((a + b), x + y),
                        ((a - b), x - y),
                        ((a * b), x * y),
                        ((a / b), x / y),
                        (a.atan2(b), x.atan2(y)),
                        (Scalar::min(a, b), x.min(y)),
                        (Scalar::max(a, b), x.max(y)),
                        (a.modulo(Interval::point(1.5)), x.rem_euclid(1.5)),
                    ];
                    for (k, (r, p)) in checks.iter().enumerate() {
                        if p.is_nan() || p.is_infinite() {
                            continue;
                        }
                        assert!(r.contains(*p), "op {k}: {a:?} {b:?} -> {r:?} misses {p}");
                    }
                }
            }
        }
    }
}
