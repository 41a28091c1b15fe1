//! Forward-mode automatic differentiation: a value with N partial derivatives.
//!
//! `Dual<f64, 3>` gives the gradient ∇F at a point (for normals); `Dual<Interval, 1>`
//! seeded with a ray direction bounds F and dF/dt over a ray segment, which the interval
//! intersector uses to prove a segment monotonic (one root at most).

use crate::scalar::{Scalar, Zero};
use std::ops::{Add, Div, Mul, Neg, Sub};

/// A value and its derivatives with respect to N variables.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<S, const N: usize> {
    /// The value.
    pub v: S,
    /// ∂value/∂variable_k.
    pub d: [S; N],
}

impl<S: Scalar, const N: usize> Dual<S, N> {
    /// A value whose derivatives are `d`.
    #[inline]
    pub fn new(v: S, d: [S; N]) -> Self {
        Self { v, d }
    }
    /// The k-th variable itself: derivative 1 along k, 0 elsewhere.
    #[inline]
    pub fn var(v: S, k: usize) -> Self {
        let mut d = [S::constant(0.0); N];
        d[k] = S::constant(1.0);
        Self { v, d }
    }
    /// Chain rule: a function with value `v` and derivative `dv` of self's value.
    #[inline]
    fn chain(self, v: S, dv: S) -> Self {
        Self {
            v,
            d: self.d.map(|d| d * dv),
        }
    }
    #[inline]
    fn zero_d() -> [S; N] {
        [S::constant(0.0); N]
    }
    /// Picks `a` or `b` as `choose` says, or the hull of both when undecided.
    #[inline]
    fn select(choose: Option<bool>, a: Self, b: Self, v: S) -> Self {
        match choose {
            Some(true) => a,
            Some(false) => b,
            None => {
                let mut d = a.d;
                for (x, y) in d.iter_mut().zip(b.d) {
                    *x = x.hull(y);
                }
                Self { v, d }
            }
        }
    }
}

impl<S: Scalar, const N: usize> Add for Dual<S, N> {
    type Output = Self;
    #[inline]
    fn add(self, b: Self) -> Self {
        let mut d = self.d;
        for (x, y) in d.iter_mut().zip(b.d) {
            *x = *x + y;
        }
        Self { v: self.v + b.v, d }
    }
}

impl<S: Scalar, const N: usize> Sub for Dual<S, N> {
    type Output = Self;
    #[inline]
    fn sub(self, b: Self) -> Self {
        let mut d = self.d;
        for (x, y) in d.iter_mut().zip(b.d) {
            *x = *x - y;
        }
        Self { v: self.v - b.v, d }
    }
}

impl<S: Scalar, const N: usize> Neg for Dual<S, N> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self {
            v: -self.v,
            d: self.d.map(|x| -x),
        }
    }
}

impl<S: Scalar, const N: usize> Mul for Dual<S, N> {
    type Output = Self;
    #[inline]
    fn mul(self, b: Self) -> Self {
        let mut d = self.d;
        for (x, y) in d.iter_mut().zip(b.d) {
            *x = *x * b.v + self.v * y;
        }
        Self { v: self.v * b.v, d }
    }
}

impl<S: Scalar, const N: usize> Div for Dual<S, N> {
    type Output = Self;
    #[inline]
    fn div(self, b: Self) -> Self {
        let v = self.v / b.v;
        let mut d = self.d;
        for (x, y) in d.iter_mut().zip(b.d) {
            *x = (*x - v * y) / b.v;
        }
        Self { v, d }
    }
}

impl<S: Scalar, const N: usize> Scalar for Dual<S, N> {
    const R_BOUND: bool = S::R_BOUND;

    /// The value narrowed as `S` narrows it; the derivatives as computed.
    fn r_bound(v: Self, a: Self, b: Self, union: bool) -> Self {
        Self {
            v: S::r_bound(v.v, a.v, b.v, union),
            d: v.d,
        }
    }

    #[inline]
    fn constant(v: f64) -> Self {
        Self {
            v: S::constant(v),
            d: Self::zero_d(),
        }
    }
    fn abs(self) -> Self {
        let neg = self.v.less(S::constant(0.0));
        Self::select(neg, -self, self, self.v.abs())
    }
    #[inline]
    fn sqrt(self) -> Self {
        let r = self.v.sqrt();
        self.chain(r, S::constant(0.5) / r)
    }
    #[inline]
    fn square(self) -> Self {
        // 2v as v + v: the same value (doubling is exact), an addition instead of a
        // product (four, for an interval).
        self.chain(self.v.square(), self.v + self.v)
    }
    fn powi(self, n: i32) -> Self {
        match n {
            0 => Self::constant(1.0),
            1 => self,
            _ => self.chain(self.v.powi(n), S::constant(n as f64) * self.v.powi(n - 1)),
        }
    }
    fn exp(self) -> Self {
        let e = self.v.exp();
        self.chain(e, e)
    }
    fn ln(self) -> Self {
        self.chain(self.v.ln(), S::constant(1.0) / self.v)
    }
    fn sin(self) -> Self {
        self.chain(self.v.sin(), self.v.cos())
    }
    fn cos(self) -> Self {
        self.chain(self.v.cos(), -self.v.sin())
    }
    fn tan(self) -> Self {
        let t = self.v.tan();
        self.chain(t, S::constant(1.0) + t.square())
    }
    fn asin(self) -> Self {
        let dv = S::constant(1.0) / (S::constant(1.0) - self.v.square()).sqrt();
        self.chain(self.v.asin(), dv)
    }
    fn acos(self) -> Self {
        let dv = -(S::constant(1.0) / (S::constant(1.0) - self.v.square()).sqrt());
        self.chain(self.v.acos(), dv)
    }
    fn atan(self) -> Self {
        self.chain(
            self.v.atan(),
            S::constant(1.0) / (S::constant(1.0) + self.v.square()),
        )
    }
    fn atan2(self, x: Self) -> Self {
        // d atan2(y, x) = (x dy − y dx) / (x² + y²)
        let r2 = x.v.square() + self.v.square();
        let mut d = self.d;
        for (dy, dx) in d.iter_mut().zip(x.d) {
            *dy = (x.v * *dy - self.v * dx) / r2;
        }
        Self {
            v: self.v.atan2(x.v),
            d,
        }
    }
    fn min(self, b: Self) -> Self {
        Self::select(self.v.less(b.v), self, b, self.v.min(b.v))
    }
    fn max(self, b: Self) -> Self {
        Self::select(self.v.less(b.v), b, self, self.v.max(b.v))
    }
    fn floor(self) -> Self {
        Self::new(self.v.floor(), Self::zero_d())
    }
    fn ceil(self) -> Self {
        Self::new(self.v.ceil(), Self::zero_d())
    }
    fn round(self) -> Self {
        Self::new(self.v.round(), Self::zero_d())
    }
    fn modulo(self, b: Self) -> Self {
        // a mod b = a − b·⌊a/b⌋, with ⌊a/b⌋ locally constant.
        let k = (self.v / b.v).floor();
        let mut d = self.d;
        for (da, db) in d.iter_mut().zip(b.d) {
            *da = *da - db * k;
        }
        Self {
            v: self.v.modulo(b.v),
            d,
        }
    }
    fn compare(self, b: Self) -> Self {
        Self::new(self.v.compare(b.v), Self::zero_d())
    }
    fn zero(self) -> Zero {
        self.v.zero()
    }
    fn hull(self, b: Self) -> Self {
        let mut d = self.d;
        for (x, y) in d.iter_mut().zip(b.d) {
            *x = x.hull(y);
        }
        Self {
            v: self.v.hull(b.v),
            d,
        }
    }
    fn less(self, b: Self) -> Option<bool> {
        self.v.less(b.v)
    }
}
