//! Several values of one scalar type carried through one pass over a tape: the node's
//! operation is decoded once and performed lane by lane. Each lane performs exactly the
//! operations a single evaluation would, so every lane's result equals the one-value
//! evaluation bit for bit; what the lanes share is the interpreter around the arithmetic
//! (the node's `match`, its operand indices, the R-function pattern test), which is most
//! of a short interval operation's cost (docs/notebook/2026-12-06-three-simd-and-tile-experiments.md).
//!
//! The occupancy grid's octree evaluates a box's children this way, all with the tape
//! their parent left ([`crate::occupancy`]).

use crate::scalar::{Scalar, Zero};
use std::ops::{Add, Div, Mul, Neg, Sub};

/// `L` values evaluated together.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lanes<S, const L: usize>(pub [S; L]);

impl<S: Copy, const L: usize> Lanes<S, L> {
    /// The lanes `v`.
    #[inline(always)]
    pub fn new(v: [S; L]) -> Self {
        Lanes(v)
    }

    /// Lane `i`.
    #[inline(always)]
    pub fn lane(&self, i: usize) -> S {
        self.0[i]
    }
}

/// Lane-wise binary operators.
macro_rules! lane_op {
    ($tr:ident, $f:ident) => {
        impl<S: Scalar, const L: usize> $tr for Lanes<S, L> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, b: Self) -> Self {
                Lanes(std::array::from_fn(|i| $tr::$f(self.0[i], b.0[i])))
            }
        }
    };
}
lane_op!(Add, add);
lane_op!(Sub, sub);
lane_op!(Mul, mul);
lane_op!(Div, div);

impl<S: Scalar, const L: usize> Neg for Lanes<S, L> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Lanes(self.0.map(|a| -a))
    }
}

/// Lane-wise methods of [`Scalar`], one argument or two.
macro_rules! lane_methods {
    ($($f:ident),*; $($g:ident),*) => {
        $(
            #[inline(always)]
            fn $f(self) -> Self {
                Lanes(self.0.map(S::$f))
            }
        )*
        $(
            #[inline(always)]
            fn $g(self, b: Self) -> Self {
                Lanes(std::array::from_fn(|i| S::$g(self.0[i], b.0[i])))
            }
        )*
    };
}

impl<S: Scalar, const L: usize> Scalar for Lanes<S, L> {
    const R_BOUND: bool = S::R_BOUND;

    #[inline(always)]
    fn constant(v: f64) -> Self {
        Lanes([S::constant(v); L])
    }

    lane_methods!(
        abs, sqrt, square, exp, ln, sin, cos, tan, asin, acos, atan, floor, ceil, round, not;
        atan2, min, max, modulo, compare, hull, and, or
    );

    #[inline(always)]
    fn powi(self, n: i32) -> Self {
        Lanes(self.0.map(|a| a.powi(n)))
    }

    /// What every lane says, where they all say the same; else [`Zero::Maybe`].
    fn zero(self) -> Zero {
        let first = self.0[0].zero();
        match self.0.iter().all(|a| a.zero() == first) {
            true => first,
            false => Zero::Maybe,
        }
    }

    /// What every lane says, where they all say the same; else undecided.
    fn less(self, b: Self) -> Option<bool> {
        let first = self.0[0].less(b.0[0]);
        (0..L)
            .all(|i| self.0[i].less(b.0[i]) == first)
            .then_some(first)?
    }

    #[inline(always)]
    fn r_bound(v: Self, a: Self, b: Self, union: bool) -> Self {
        Lanes(std::array::from_fn(|i| {
            S::r_bound(v.0[i], a.0[i], b.0[i], union)
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::{eval_nodes, Expr};
    use crate::interval::Interval;
    use rand::{Rng, SeedableRng};

    /// Every lane of a lane evaluation equals the one-value evaluation bit for bit, over
    /// boxes and points of the repository's expression models (min/max, R-functions,
    /// transcendentals) and over degenerate, infinite and NaN boxes; and the lanes'
    /// `zero` and `less` say what every lane says, where they all agree.
    #[test]
    fn each_lane_is_the_single_evaluation() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(31);
        let bits = |v: Interval| (v.lo.to_bits(), v.hi.to_bits());
        let (mut one, mut eight) = (Vec::new(), Vec::new());
        for (m, tree) in crate::test_models::expression_models() {
            let expr = Expr::new(&tree);
            let tape = expr.nodes();
            // Points and boxes of every width up to 3, some of them degenerate.
            let mut boxes: Vec<[Interval; 3]> = (0..400)
                .map(|_| {
                    std::array::from_fn(|_| {
                        let a = rng.gen_range(-1.5..1.5);
                        let w = 3.0 * rng.gen_range(0.0..1.0f64).powi(4);
                        Interval::new(a, a + w)
                    })
                })
                .collect();
            boxes.push([Interval::point(0.0); 3]);
            boxes.push([Interval::new(f64::NEG_INFINITY, f64::INFINITY); 3]);
            boxes.push([Interval::new(f64::NAN, 1.0); 3]);
            for chunk in boxes.chunks(8) {
                let lane = |k: usize| {
                    Lanes::<Interval, 8>(std::array::from_fn(|i| chunk[i % chunk.len()][k]))
                };
                let got = eval_nodes(tape, lane(0), lane(1), lane(2), &mut eight);
                for i in 0..8 {
                    let bx = chunk[i % chunk.len()];
                    let want = eval_nodes(tape, bx[0], bx[1], bx[2], &mut one);
                    assert_eq!(bits(got.lane(i)), bits(want), "{m}, box {bx:?}");
                }
            }
        }
        let l = |a: f64, b: f64| Lanes::<Interval, 2>([Interval::point(a), Interval::point(b)]);
        assert_eq!(l(1.0, 2.0).less(l(3.0, 4.0)), Some(true));
        assert_eq!(l(1.0, 5.0).less(l(3.0, 4.0)), None);
        assert_eq!(l(0.0, 0.0).zero(), Zero::Yes);
        assert_eq!(l(0.0, 1.0).zero(), Zero::Maybe);
    }
}
