//! The number types an expression can be evaluated over.
//!
//! One generic evaluator ([`crate::Expr::eval_with`]) serves plain `f64` and `f32` point
//! evaluation, [`crate::Interval`] bounds and [`crate::Dual`] derivatives: each type says
//! here how it performs every operation of the expression language.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// What a value tells about whether it is zero (used by the logical opcodes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Zero {
    /// Certainly zero.
    Yes,
    /// Certainly not zero.
    No,
    /// May or may not be zero (intervals that straddle 0, NaN).
    Maybe,
}

/// A number type the expression evaluator works over.
///
/// Semantics follow Fidget's opcodes where the two overlap: `compare` gives −1, 0 or 1,
/// `modulo` is the Euclidean remainder, `and`/`or` select an operand.
pub trait Scalar:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// A constant.
    fn constant(v: f64) -> Self;
    /// |a|.
    fn abs(self) -> Self;
    /// √a.
    fn sqrt(self) -> Self;
    /// a².
    fn square(self) -> Self;
    /// aⁿ for an integer n.
    fn powi(self, n: i32) -> Self;
    /// eᵃ.
    fn exp(self) -> Self;
    /// ln a.
    fn ln(self) -> Self;
    /// sin a.
    fn sin(self) -> Self;
    /// cos a.
    fn cos(self) -> Self;
    /// tan a.
    fn tan(self) -> Self;
    /// asin a.
    fn asin(self) -> Self;
    /// acos a.
    fn acos(self) -> Self;
    /// atan a.
    fn atan(self) -> Self;
    /// atan2(a, b) (a is the ordinate, as in `f64::atan2`).
    fn atan2(self, b: Self) -> Self;
    /// min(a, b).
    fn min(self, b: Self) -> Self;
    /// max(a, b).
    fn max(self, b: Self) -> Self;
    /// ⌊a⌋.
    fn floor(self) -> Self;
    /// ⌈a⌉.
    fn ceil(self) -> Self;
    /// a rounded half away from zero.
    fn round(self) -> Self;
    /// Euclidean remainder of a by b.
    fn modulo(self, b: Self) -> Self;
    /// −1, 0 or 1 as a <, =, > b (NaN when unordered).
    fn compare(self, b: Self) -> Self;
    /// Whether the value is zero.
    fn zero(self) -> Zero;
    /// The smallest value of this type containing both (intervals); `self` for points.
    fn hull(self, b: Self) -> Self;
    /// Whether `self < b` certainly holds (`Some(true)`), certainly fails (`Some(false)`),
    /// or is undecided.
    fn less(self, b: Self) -> Option<bool>;

    /// Whether [`Scalar::r_bound`] narrows anything: true for intervals, so that point
    /// evaluators skip the R-function pattern test at compile time.
    const R_BOUND: bool = false;

    /// `v`, the value of the R-function a + b ± √(a² + b²) (Rvachev; α = 0, as HyperFun's
    /// `|` and `&`) evaluated op by op, narrowed by its monotonicity: both forms are
    /// non-decreasing in a and in b (∂/∂a = 1 ± a/√(a² + b²) ≥ 0), so over intervals they
    /// lie between their values at the operands' lower ends and at their upper ends.
    /// Interval arithmetic alone loses this (a and b each appear twice) and bounds an
    /// R-function CSG model so loosely that ray tracing subdivides to its resolution.
    fn r_bound(v: Self, _a: Self, _b: Self, _union: bool) -> Self {
        v
    }

    /// 1 if a is zero, else 0.
    fn not(self) -> Self {
        match self.zero() {
            Zero::Yes => Self::constant(1.0),
            Zero::No => Self::constant(0.0),
            Zero::Maybe => Self::constant(0.0).hull(Self::constant(1.0)),
        }
    }
    /// a if a is zero, else b.
    fn and(self, b: Self) -> Self {
        match self.zero() {
            Zero::Yes => self,
            Zero::No => b,
            Zero::Maybe => Self::constant(0.0).hull(b),
        }
    }
    /// a if a is not zero, else b.
    fn or(self, b: Self) -> Self {
        match self.zero() {
            Zero::Yes => b,
            Zero::No => self,
            Zero::Maybe => self.hull(b),
        }
    }
}

macro_rules! float_scalar {
    ($t:ty) => {
        impl Scalar for $t {
            #[inline]
            fn constant(v: f64) -> Self {
                v as $t
            }
            #[inline]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline]
            fn square(self) -> Self {
                self * self
            }
            #[inline]
            fn powi(self, n: i32) -> Self {
                <$t>::powi(self, n)
            }
            #[inline]
            fn exp(self) -> Self {
                <$t>::exp(self)
            }
            #[inline]
            fn ln(self) -> Self {
                <$t>::ln(self)
            }
            #[inline]
            fn sin(self) -> Self {
                <$t>::sin(self)
            }
            #[inline]
            fn cos(self) -> Self {
                <$t>::cos(self)
            }
            #[inline]
            fn tan(self) -> Self {
                <$t>::tan(self)
            }
            #[inline]
            fn asin(self) -> Self {
                <$t>::asin(self)
            }
            #[inline]
            fn acos(self) -> Self {
                <$t>::acos(self)
            }
            #[inline]
            fn atan(self) -> Self {
                <$t>::atan(self)
            }
            #[inline]
            fn atan2(self, b: Self) -> Self {
                <$t>::atan2(self, b)
            }
            #[inline]
            fn min(self, b: Self) -> Self {
                <$t>::min(self, b)
            }
            #[inline]
            fn max(self, b: Self) -> Self {
                <$t>::max(self, b)
            }
            #[inline]
            fn floor(self) -> Self {
                <$t>::floor(self)
            }
            #[inline]
            fn ceil(self) -> Self {
                <$t>::ceil(self)
            }
            #[inline]
            fn round(self) -> Self {
                <$t>::round(self)
            }
            #[inline]
            fn modulo(self, b: Self) -> Self {
                <$t>::rem_euclid(self, b)
            }
            #[inline]
            fn compare(self, b: Self) -> Self {
                match self.partial_cmp(&b) {
                    Some(o) => o as i8 as $t,
                    None => <$t>::NAN,
                }
            }
            #[inline]
            fn zero(self) -> Zero {
                if self == 0.0 {
                    Zero::Yes
                } else if self.is_nan() {
                    Zero::Maybe
                } else {
                    Zero::No
                }
            }
            #[inline]
            fn hull(self, _b: Self) -> Self {
                self
            }
            #[inline]
            fn less(self, b: Self) -> Option<bool> {
                Some(self < b)
            }
            #[inline]
            fn and(self, b: Self) -> Self {
                if self == 0.0 {
                    self
                } else {
                    b
                }
            }
            #[inline]
            fn or(self, b: Self) -> Self {
                if self != 0.0 {
                    self
                } else {
                    b
                }
            }
            #[inline]
            fn not(self) -> Self {
                if self == 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
        }
    };
}

float_scalar!(f64);
float_scalar!(f32);
