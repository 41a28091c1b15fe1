//! The expression tapes' remaining operations on the GPU — exp, ln, tan, asin, acos,
//! atan, floor, ceil, round, mod, compare, and, or, not — as point values and as sound
//! intervals with their derivative lanes, written operation for operation as the
//! kernel's `shaders/elementary.wgsl` (GPU.md §3.3: WGSL's builtins are not libm's, so
//! exp and ln are polynomials here, as sin and cos are in [`crate::tape::sin_cos`]).
//!
//! **Point values** (the tape's `eval_point`, used for normals and by the twins):
//! - exp: x = k·ln 2 + r with ln 2 in two parts (Cody & Waite 1980), |r| ≤ ½ ln 2, e^r by
//!   Taylor to r⁷ (truncation below 10⁻⁸), 2^k as two exact powers of two. 0 below
//!   [`EXP_LO`] (where e^x is near the subnormals a GPU may flush), +∞ above [`EXP_HI`].
//! - ln: x = m·2^e with m ∈ [√½, √2), ln m = 2 atanh s, s = (m − 1)/(m + 1), by its series
//!   to s¹¹; −∞ for 0 and subnormals (which a GPU may flush), NaN below 0.
//! - tan = sin/cos, asin x = atan2(x, √((1 − x)(1 + x))), acos x = atan2(√…, x),
//!   atan x = atan2(x, 1), on [`crate::env::atan2`]'s polynomial.
//! - round: half away from zero (Rust's `f32::round`; WGSL's `round` goes to even).
//! - mod: the Euclidean remainder a − |b|·⌊a/|b|⌋, brought into [0, |b|) (Rust's
//!   `rem_euclid`, but from a rounded quotient: within an ulp of a or so of it).
//!
//! **Intervals** (the tape's `eval_interval`, which decides every sign a ray trace reads):
//! each contains the exact function over its operand, as frep's [`frep::Interval`] does:
//! exp and ln widened by 8 ulps ([`EXP_LN_ULPS`]) beyond their measured error (≤ 3
//! ulps), the inverse trigonometric ones by [`crate::tape::TRIG_ERR`], tan as the
//! quotient of the sin and cos intervals. The derivative lane is the chain rule's, and
//! wherever the operand may cross a jump (a step of floor, ceil, round or compare, mod's
//! wrap, not/and/or where the operand may be 0) it is (−∞, ∞): the tracer then never
//! reads such a span as monotone, and a ray that meets the jump is bisected until its
//! budget runs out and left to the CPU — never answered from a derivative that does not
//! hold. frep's own dual numbers give such steps a zero derivative.

use crate::env::atan2;
use crate::tape::{any_nan, hull, I2, NAN2, TRIG_ERR};
use crate::tape::{down, i_add, i_div, i_mul, i_sin_cos, i_sqrt, i_square, i_sub, sin_cos, up};

/// Below this, [`exp`] is 0 (e^−87 = 1.6·10⁻³⁸, just above the least normal f32).
pub const EXP_LO: f32 = -87.0;
/// Above this, [`exp`] is +∞ (e^88.72 = 3.39·10³⁸, just below `f32::MAX`).
pub const EXP_HI: f32 = 88.72;
/// The widening of exp's and ln's intervals, in ulps: their measured error is ≤ 3 ulps
/// on lavapipe's round-to-nearest arithmetic, and the margin covers a real GPU's
/// looser `/` (2.5 ulps in WGSL).
pub const EXP_LN_ULPS: u32 = 8;

const LOG2E: f32 = f32::from_bits(0x3fb8_aa3b);
const LN2_HI: f32 = f32::from_bits(0x3f31_8000);
const LN2_LO: f32 = f32::from_bits(0xb95e_8083);
const SQRT2: f32 = f32::from_bits(0x3fb5_04f3);
const ENTIRE: I2 = [f32::NEG_INFINITY, f32::INFINITY];

/// 2ⁿ for −126 ≤ n ≤ 127, from its bits.
fn pow2(n: i32) -> f32 {
    f32::from_bits(((n + 127) as u32) << 23)
}

/// e^x (the kernel's `t_exp`).
pub fn exp(x: f32) -> f32 {
    if x.is_nan() {
        return f32::NAN;
    }
    if x > EXP_HI {
        return f32::INFINITY;
    }
    if x < EXP_LO {
        return 0.0;
    }
    let k = (x * LOG2E + 0.5).floor();
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let p = 1.0
        + r * (1.0
            + r * (0.5
                + r * (f32::from_bits(0x3e2a_aaab)
                    + r * (f32::from_bits(0x3d2a_aaab)
                        + r * (f32::from_bits(0x3c08_8889)
                            + r * (f32::from_bits(0x3ab6_0b61)
                                + r * f32::from_bits(0x3950_0d01)))))));
    // k ∈ [−125, 128]: 2^k as two factors within f32's exponents.
    let k = k as i32;
    let h = k / 2;
    p * pow2(h) * pow2(k - h)
}

/// ln x (the kernel's `t_ln`).
pub fn ln(x: f32) -> f32 {
    if x.is_nan() || x < 0.0 {
        return f32::NAN;
    }
    if x < f32::MIN_POSITIVE {
        return f32::NEG_INFINITY;
    }
    if x == f32::INFINITY {
        return x;
    }
    let b = x.to_bits();
    let mut e = (b >> 23) as i32 - 127;
    let mut m = f32::from_bits((b & 0x007f_ffff) | 0x3f80_0000);
    if m > SQRT2 {
        m *= 0.5;
        e += 1;
    }
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let lnm = s
        * (2.0
            + s2 * (f32::from_bits(0x3f2a_aaab)
                + s2 * (f32::from_bits(0x3ecc_cccd)
                    + s2 * (f32::from_bits(0x3e92_4925)
                        + s2 * (f32::from_bits(0x3e63_8e39) + s2 * f32::from_bits(0x3e3a_2e8c))))));
    let e = e as f32;
    e * LN2_HI + (e * LN2_LO + lnm)
}

/// √((1 − x)(1 + x)), NaN outside [−1, 1]: the other side of asin's and acos's angle.
fn cosine_side(x: f32) -> f32 {
    // (NaN fails the test too.)
    let inside = x.abs() <= 1.0;
    if !inside {
        return f32::NAN;
    }
    ((1.0 - x) * (1.0 + x)).sqrt()
}

/// asin x, NaN outside [−1, 1] (the kernel's `t_asin`).
pub fn asin(x: f32) -> f32 {
    let c = cosine_side(x);
    if c.is_nan() {
        return c;
    }
    atan2(x, c)
}

/// acos x, NaN outside [−1, 1] (the kernel's `t_acos`).
pub fn acos(x: f32) -> f32 {
    let c = cosine_side(x);
    if c.is_nan() {
        return c;
    }
    atan2(c, x)
}

/// atan x (the kernel's `t_atan`).
pub fn atan(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    atan2(x, 1.0)
}

/// tan x = sin x / cos x, NaN past [`crate::tape::TRIG_MAX`].
pub fn tan(x: f32) -> f32 {
    sin_cos(x, false) / sin_cos(x, true)
}

/// x rounded half away from zero (the kernel's `t_round`).
pub fn round(x: f32) -> f32 {
    let t = x.trunc();
    if (x - t).abs() >= 0.5 {
        t + if x > 0.0 { 1.0 } else { -1.0 }
    } else {
        t
    }
}

/// The Euclidean remainder of a by b, in [0, |b|) (the kernel's `t_mod`).
pub fn modulo(a: f32, b: f32) -> f32 {
    let c = b.abs();
    let mut r = a - c * (a / c).floor();
    if r < 0.0 {
        r += c;
    }
    if r >= c {
        r -= c;
    }
    r
}

/// −1, 0 or 1 as a < b, a = b or a > b; NaN if either is.
pub fn compare(a: f32, b: f32) -> f32 {
    if a.is_nan() || b.is_nan() {
        f32::NAN
    } else if a < b {
        -1.0
    } else if a > b {
        1.0
    } else {
        0.0
    }
}

/// 1 if a is 0, else 0.
pub fn not(a: f32) -> f32 {
    if a == 0.0 {
        1.0
    } else {
        0.0
    }
}

/// a if a is 0, else b.
pub fn and(a: f32, b: f32) -> f32 {
    if a == 0.0 {
        a
    } else {
        b
    }
}

/// a if a is not 0 (or NaN), else b.
pub fn or(a: f32, b: f32) -> f32 {
    if a.is_nan() || a != 0.0 {
        a
    } else {
        b
    }
}

fn up8(x: f32) -> f32 {
    (0..EXP_LN_ULPS).fold(x, |x, _| up(x))
}

fn down8(x: f32) -> f32 {
    (0..EXP_LN_ULPS).fold(x, |x, _| down(x))
}

/// e^a: exp at the ends (held within [`EXP_LO`], [`EXP_HI`], where it is finite and
/// normal), widened by [`EXP_LN_ULPS`]; 0 below and +∞ above.
pub(crate) fn i_exp(a: I2) -> I2 {
    if any_nan(a) {
        return NAN2;
    }
    let lo = if a[0] < EXP_LO {
        0.0
    } else {
        down8(exp(a[0].min(EXP_HI))).max(0.0)
    };
    let hi = if a[1] > EXP_HI {
        f32::INFINITY
    } else {
        up8(exp(a[1].max(EXP_LO)))
    };
    [lo, hi]
}

/// ln a: NaN wholly below 0, −∞ from an end below the least normal, the ends' values
/// widened by [`EXP_LN_ULPS`] (an upper end below the least normal reads as it).
pub(crate) fn i_ln(a: I2) -> I2 {
    if any_nan(a) || a[1] < 0.0 {
        return NAN2;
    }
    let lo = if a[0] < f32::MIN_POSITIVE {
        f32::NEG_INFINITY
    } else {
        down8(ln(a[0]))
    };
    [lo, up8(ln(a[1].max(f32::MIN_POSITIVE)))]
}

/// tan a as the quotient of a's sin and cos intervals: (−∞, ∞) where cos may vanish.
pub(crate) fn i_tan(a: I2) -> I2 {
    i_div(i_sin_cos(a, false), i_sin_cos(a, true))
}

/// asin (`cos` false) or acos over a ∩ [−1, 1], widened by [`TRIG_ERR`]; NaN outside.
pub(crate) fn i_asin_acos(a: I2, cos: bool) -> I2 {
    if any_nan(a) || a[1] < -1.0 || a[0] > 1.0 {
        return NAN2;
    }
    let (lo, hi) = (a[0].max(-1.0), a[1].min(1.0));
    if cos {
        [acos(hi) - TRIG_ERR, acos(lo) + TRIG_ERR]
    } else {
        [asin(lo) - TRIG_ERR, asin(hi) + TRIG_ERR]
    }
}

/// atan a, widened by [`TRIG_ERR`].
pub(crate) fn i_atan(a: I2) -> I2 {
    if any_nan(a) {
        return NAN2;
    }
    [atan(a[0]) - TRIG_ERR, atan(a[1]) + TRIG_ERR]
}

/// floor (0), ceil (1) or round (2) at both ends (exact, monotone), with the derivative
/// 0 where both ends give the same step, else (−∞, ∞).
pub(crate) fn i_step(a: I2, which: u32) -> (I2, I2) {
    let f = |x: f32| match which {
        0 => x.floor(),
        1 => x.ceil(),
        _ => round(x),
    };
    let v = [f(a[0]), f(a[1])];
    (v, flat_or_jump(v[0] == v[1]))
}

/// The derivative of a piecewise-constant operation: 0 where it holds one value, else
/// (−∞, ∞) (it may jump).
fn flat_or_jump(flat: bool) -> I2 {
    if flat {
        [0.0, 0.0]
    } else {
        ENTIRE
    }
}

/// a mod b (Euclidean) and its derivative (a's and b's as `ad`, `bd`): with b a nonzero
/// constant c, and k = ⌊a/|c|⌋ the same at both ends of a, a − k|c| with da − k·db where
/// that interval proves itself within [0, |c|) (then every x in a has ⌊x/|c|⌋ = k, so
/// no quotient's rounding can misplace a wrap); else [0, max |b|] (b excluding 0) or
/// (−∞, ∞), with the derivative (−∞, ∞): a wrap is a jump.
pub(crate) fn i_mod(a: I2, ad: I2, b: I2, bd: I2) -> (I2, I2) {
    if any_nan(a) || any_nan(b) {
        return (NAN2, NAN2);
    }
    if b[0] == b[1] && b[0] != 0.0 && b[0].is_finite() {
        let c = b[0].abs();
        if a[0].is_finite() && a[1].is_finite() {
            let k = (a[0] / c).floor();
            if k == (a[1] / c).floor() {
                let v = i_sub(a, i_mul([k, k], [c, c]));
                if v[0] >= 0.0 && v[1] < c {
                    return (v, i_sub(ad, i_mul(bd, [k, k])));
                }
            }
        }
        return ([0.0, c], ENTIRE);
    }
    if b[0] > 0.0 || b[1] < 0.0 {
        return ([0.0, b[0].abs().max(b[1].abs())], ENTIRE);
    }
    (ENTIRE, ENTIRE)
}

/// Where a mod b's first wrap lies within a, as a fraction of a's span in the direction
/// a grows along the ray (the derivative lane `ad` of one sign), for b one nonzero
/// constant c: (w − lo)/(hi − lo) for the first multiple w of |c| above lo where a
/// increases, (hi − w)/(hi − lo) for the last below hi where it decreases; 2 where a
/// holds no wrap or is not monotone. A tracer splitting a segment there isolates the
/// jump in a step or two, where halving would take log₂(length/ε) of them.
pub fn wrap_fraction(a: I2, ad: I2, b: I2) -> f32 {
    let none = 2.0;
    if !(b[0] == b[1] && b[0] != 0.0 && b[0].is_finite() && a[0].is_finite() && a[1].is_finite()) {
        return none;
    }
    let c = b[0].abs();
    let (k0, k1) = ((a[0] / c).floor(), (a[1] / c).floor());
    if !(k1 > k0 && a[1] > a[0]) {
        return none;
    }
    let f = if ad[0] > 0.0 {
        ((k0 + 1.0) * c - a[0]) / (a[1] - a[0])
    } else if ad[1] < 0.0 {
        (a[1] - k1 * c) / (a[1] - a[0])
    } else {
        return none;
    };
    if f > 0.0 && f < 1.0 {
        f
    } else {
        none
    }
}

/// compare(a, b) as frep's interval: −1 or 1 where a and b are apart, 0 where both are
/// one equal point, else [−1, 1] with the derivative (−∞, ∞).
pub(crate) fn i_compare(a: I2, b: I2) -> (I2, I2) {
    if any_nan(a) || any_nan(b) {
        return (NAN2, NAN2);
    }
    let v = if a[1] < b[0] {
        -1.0
    } else if a[0] > b[1] {
        1.0
    } else if a[0] == a[1] && b[0] == b[1] {
        0.0
    } else {
        return ([-1.0, 1.0], ENTIRE);
    };
    ([v, v], [0.0, 0.0])
}

/// Whether an interval is the point 0 (`Some(true)`), excludes 0 (`Some(false)`), or
/// may hold it (`None`, NaN too): frep's `Zero`.
fn zero(a: I2) -> Option<bool> {
    if a[0] == 0.0 && a[1] == 0.0 {
        Some(true)
    } else if a[0] > 0.0 || a[1] < 0.0 {
        Some(false)
    } else {
        None
    }
}

/// not a: 1 or 0 where a is or excludes 0, else [0, 1] with the derivative (−∞, ∞).
pub(crate) fn i_not(a: I2) -> (I2, I2) {
    match zero(a) {
        Some(true) => ([1.0, 1.0], [0.0, 0.0]),
        Some(false) => ([0.0, 0.0], [0.0, 0.0]),
        None => ([0.0, 1.0], ENTIRE),
    }
}

/// and (`or` false) or or over a, b with their derivatives: one operand where a decides,
/// else the hull (with 0 for and) and the derivative (−∞, ∞).
pub(crate) fn i_and_or(a: I2, ad: I2, b: I2, bd: I2, or: bool) -> (I2, I2) {
    match (zero(a), or) {
        (Some(true), false) | (Some(false), true) => (a, ad),
        (Some(false), false) | (Some(true), true) => (b, bd),
        (None, false) => (hull([0.0, 0.0], b), ENTIRE),
        (None, true) => (hull(a, b), ENTIRE),
    }
}

/// One of these unary operations over a with derivative lane ad: (value, derivative)
/// intervals (the kernel's `elementary_interval`). None for the tape's other operations.
pub(crate) fn unary(op: frep::UnaryOp, a: I2, ad: I2) -> Option<(I2, I2)> {
    use frep::UnaryOp as U;
    let v = match op {
        U::Floor => return Some(i_step(a, 0)),
        U::Ceil => return Some(i_step(a, 1)),
        U::Round => return Some(i_step(a, 2)),
        U::Not => return Some(i_not(a)),
        U::Asin | U::Acos => i_asin_acos(a, op == U::Acos),
        U::Exp => i_exp(a),
        U::Ln => i_ln(a),
        U::Tan => i_tan(a),
        U::Atan => i_atan(a),
        U::Neg | U::Abs | U::Sqrt | U::Square | U::Sin | U::Cos => return None,
    };
    Some((v, chain(op, a, ad, v)))
}

/// d(asin) = da/√(1 − a²), d(acos) its negative, d(atan) = da/(1 + a²),
/// d(tan) = (1 + tan²)·da, d(exp) = e^a·da, d(ln) = da/a: the chain rule in intervals.
fn chain(op: frep::UnaryOp, a: I2, ad: I2, v: I2) -> I2 {
    use frep::UnaryOp as U;
    let one = [1.0, 1.0];
    match op {
        U::Exp => i_mul(v, ad),
        U::Ln => i_div(ad, a),
        U::Tan => i_mul(i_add(one, i_square(v)), ad),
        U::Asin => i_div(ad, i_sqrt(i_sub(one, i_square(a)))),
        U::Acos => {
            let d = i_div(ad, i_sqrt(i_sub(one, i_square(a))));
            [-d[1], -d[0]]
        }
        U::Atan => i_div(ad, i_add(one, i_square(a))),
        _ => NAN2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tape::tests::lcg;

    /// |got − want| in ulps of want as an f32.
    fn ulps(got: f32, want: f64) -> f64 {
        let w = want as f32;
        let ulp = f64::from(w.abs().next_up()) - f64::from(w.abs());
        (f64::from(got) - want).abs() / ulp
    }

    #[test]
    fn exp_and_ln_are_within_three_ulps() {
        let mut seed = 11;
        let (mut worst_exp, mut worst_ln) = (0f64, 0f64);
        for k in 0..400_000 {
            let x = ((lcg(&mut seed) * 2.0 - 1.0) * [0.5, 5.0, 40.0, 87.0][k % 4]) as f32;
            let e = ulps(exp(x), f64::from(x).exp());
            worst_exp = worst_exp.max(e);
            assert!(
                e <= 3.0,
                "exp({x}): {} against {}: {e} ulps",
                exp(x),
                f64::from(x).exp()
            );
            // ln over every binade of normal f32, and near 1.
            let y = match k % 3 {
                0 => (lcg(&mut seed) * 250.0 - 125.0).exp2() as f32,
                1 => (1.0 + (lcg(&mut seed) * 2.0 - 1.0) * 1e-3) as f32,
                _ => (lcg(&mut seed) * 4.0) as f32,
            };
            if y < f32::MIN_POSITIVE {
                continue;
            }
            let e = ulps(ln(y), f64::from(y).ln());
            worst_ln = worst_ln.max(e);
            assert!(
                e <= 3.0,
                "ln({y}): {} against {}: {e} ulps",
                ln(y),
                f64::from(y).ln()
            );
        }
        eprintln!("exp: {worst_exp:.2} ulps, ln: {worst_ln:.2} ulps at most");
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(exp(89.0), f32::INFINITY);
        assert_eq!(exp(-88.0), 0.0);
        assert_eq!(ln(0.0), f32::NEG_INFINITY);
        assert_eq!(ln(f32::INFINITY), f32::INFINITY);
        assert!(ln(-1.0).is_nan() && exp(f32::NAN).is_nan() && ln(f32::NAN).is_nan());
    }

    #[test]
    fn inverse_trigonometric_functions_are_within_half_their_widening() {
        let mut seed = 12;
        let mut worst = 0f64;
        for k in 0..200_000 {
            let x = (lcg(&mut seed) * 2.0 - 1.0) as f32;
            let t = ((lcg(&mut seed) * 2.0 - 1.0) * [1.0, 10.0, 1e4][k % 3]) as f32;
            let xd = f64::from(x);
            for (got, want) in [
                (asin(x), xd.asin()),
                (acos(x), xd.acos()),
                (atan(t), f64::from(t).atan()),
            ] {
                let e = (f64::from(got) - want).abs();
                worst = worst.max(e);
                assert!(
                    e <= f64::from(TRIG_ERR) / 2.0,
                    "{x} {t}: {got} against {want}"
                );
            }
            let tan_want = f64::from(t).tan();
            if t.abs() < 1e3 && tan_want.abs() < 1e3 {
                let e = (f64::from(tan(t)) - tan_want).abs() / (1.0 + tan_want * tan_want);
                assert!(e <= 1e-6, "tan({t}): {} against {tan_want}", tan(t));
            }
        }
        for x in [1.0f32, -1.0, 0.0] {
            assert_eq!(asin(x), atan2(x, 0.0_f32.max((1.0 - x) * (1.0 + x)).sqrt()));
        }
        assert!(asin(1.0001).is_nan() && acos(-1.0001).is_nan() && atan(f32::NAN).is_nan());
        eprintln!("asin, acos, atan: largest error {worst:e}");
    }

    #[test]
    fn rounding_mod_and_logic_are_rusts() {
        let mut seed = 13;
        let mut v: Vec<f32> = vec![0.5, -0.5, 1.5, -2.5, 0.0, -0.0, 8_388_609.0, 0.499_999_97];
        v.extend((0..20_000).map(|_| ((lcg(&mut seed) * 2.0 - 1.0) * 50.0) as f32));
        v.extend((0..1_000).map(|_| (lcg(&mut seed) * 40.0 - 20.0).round() as f32 * 0.5));
        for &x in &v {
            assert_eq!(round(x).to_bits(), x.round().to_bits(), "round({x})");
            for b in [0.5f32, -0.5, 3.0, 0.1, 7.25] {
                let (got, want) = (modulo(x, b), x.rem_euclid(b));
                let near = (got - want).abs() <= 4.0 * f32::EPSILON * x.abs().max(1.0);
                // A remainder next to |b| and one next to 0 are the same point.
                let wrapped = (got - want).abs() >= b.abs() - 4.0 * f32::EPSILON * x.abs();
                assert!(near || wrapped, "{x} mod {b}: {got} against {want}");
                assert!((0.0..b.abs()).contains(&got), "{x} mod {b}: {got}");
                use frep::Scalar;
                assert_eq!(compare(x, b), Scalar::compare(x, b));
                assert_eq!(and(x, b), Scalar::and(x, b));
                assert_eq!(or(x, b), Scalar::or(x, b));
                assert_eq!(not(x), Scalar::not(x));
            }
        }
        assert!(modulo(1.0, 0.0).is_nan() && compare(f32::NAN, 1.0).is_nan());
    }

    fn inside(x: f64, i: I2) -> bool {
        f64::from(i[0]) <= x && x <= f64::from(i[1])
    }

    /// Over random intervals (narrow to wide, across 0, ±1, the poles, integers), every
    /// f64 value of the function at 17 points lies in the value interval, and every
    /// derivative f′(x)·da (da at the ends of its interval) in the derivative interval,
    /// where the function is smooth over the whole operand.
    #[test]
    fn intervals_hold_the_function_and_its_derivative() {
        use frep::UnaryOp as U;
        let mut seed = 14;
        let ops = [
            U::Exp,
            U::Ln,
            U::Tan,
            U::Asin,
            U::Acos,
            U::Atan,
            U::Floor,
            U::Ceil,
            U::Round,
            U::Not,
        ];
        let mut checked = 0u64;
        for k in 0..40_000 {
            let centre = (lcg(&mut seed) * 2.0 - 1.0) * [1.2, 3.0, 30.0, 100.0][k % 4];
            let width = [0.0, 1e-6, 1e-2, 0.5, 5.0][k % 5] * lcg(&mut seed);
            let a = [centre as f32, (centre + width) as f32];
            let ad = [
                (lcg(&mut seed) * 2.0 - 1.0) as f32,
                (lcg(&mut seed) * 2.0 + 1.0) as f32,
            ];
            for op in ops {
                let (v, d) = unary(op, a, ad).expect("one of this module's operations");
                if v[0].is_nan() {
                    continue;
                }
                for j in 0..=16 {
                    let x = f64::from(a[0]) + (f64::from(a[1]) - f64::from(a[0])) * j as f64 / 16.0;
                    let (f, df) = match op {
                        U::Exp => (x.exp(), x.exp()),
                        U::Ln => (x.ln(), 1.0 / x),
                        U::Tan => (x.tan(), 1.0 + x.tan().powi(2)),
                        U::Asin => (x.asin(), 1.0 / (1.0 - x * x).sqrt()),
                        U::Acos => (x.acos(), -1.0 / (1.0 - x * x).sqrt()),
                        U::Atan => (x.atan(), 1.0 / (1.0 + x * x)),
                        U::Floor => (x.floor(), 0.0),
                        U::Ceil => (x.ceil(), 0.0),
                        U::Round => (x.round(), 0.0),
                        _ => (if x == 0.0 { 1.0 } else { 0.0 }, 0.0),
                    };
                    if f.is_nan() {
                        continue;
                    }
                    assert!(inside(f, v), "{op:?} over {a:?}: {v:?} misses {f} at {x}");
                    for da in ad {
                        let g = df * f64::from(da);
                        if g.is_finite() && !d[0].is_nan() {
                            assert!(
                                inside(g, d),
                                "{op:?}' over {a:?}, {ad:?}: {d:?} misses {g} at {x}"
                            );
                        }
                    }
                    checked += 1;
                }
            }
        }
        eprintln!("{checked} points inside their intervals");
    }

    /// mod, compare, and, or over random intervals and constants: the f64 function at
    /// a grid of points lies in the value interval, and mod's derivative (da where it
    /// does not wrap) in its derivative interval.
    #[test]
    fn binary_intervals_hold_the_function() {
        let mut seed = 15;
        for k in 0..40_000 {
            let c = (lcg(&mut seed) * 2.0 - 1.0) * [1.0, 10.0, 1000.0][k % 3];
            let w = [0.0, 1e-5, 0.1, 3.0][k % 4] * lcg(&mut seed);
            let a = [c as f32, (c + w) as f32];
            let b = if k % 2 == 0 {
                let m = [0.5f32, -0.25, 3.0, 0.1][k % 4];
                [m, m]
            } else {
                let m = (lcg(&mut seed) * 4.0 - 2.0) as f32;
                [m, m + lcg(&mut seed) as f32]
            };
            let (ad, bd) = ([0.5f32, 2.0], [0.0f32, 0.0]);
            let (mv, md) = i_mod(a, ad, b, bd);
            let (cv, _) = i_compare(a, b);
            let (andv, _) = i_and_or(a, ad, b, bd, false);
            let (orv, _) = i_and_or(a, ad, b, bd, true);
            for i in 0..=8 {
                for j in 0..=4 {
                    let x = f64::from(a[0]) + (f64::from(a[1]) - f64::from(a[0])) * i as f64 / 8.0;
                    let y = f64::from(b[0]) + (f64::from(b[1]) - f64::from(b[0])) * j as f64 / 4.0;
                    use frep::Scalar;
                    let m = x.rem_euclid(y);
                    if m.is_finite() {
                        assert!(inside(m, mv), "{a:?} mod {b:?}: {mv:?} misses {m}");
                    }
                    let checks = [
                        (Scalar::compare(x, y), cv),
                        (Scalar::and(x, y), andv),
                        (Scalar::or(x, y), orv),
                    ];
                    for (f, iv) in checks {
                        assert!(inside(f, iv), "{a:?}, {b:?}: {iv:?} misses {f}");
                    }
                }
            }
            if md[0] > f32::NEG_INFINITY {
                assert!(
                    inside(0.5, md) && inside(2.0, md),
                    "{a:?} mod {b:?}: d {md:?}"
                );
            }
        }
    }
}
