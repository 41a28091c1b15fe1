//! Rays through expression solids that are polynomials of low degree.
//!
//! Where a tape uses only constants, coordinates, +, −, ×, squares, non-negative integer
//! powers and division by a constant, and no node's degree exceeds
//! [`poly::MAX_DEGREE`](crate::poly::MAX_DEGREE), F along a ray segment [t0, t1] is a
//! polynomial in u ∈ [0, 1] (t = t0 + (t1 − t0)·u). The tape is then evaluated once per
//! ray over polynomials instead of numbers, with x = x(t0) + (t1 − t0)·d_x·u, and the
//! result converted to Bernstein form. The search is [`crate::interval_trace`]'s, with
//! the Bernstein coefficients in place of intervals: their hull bounds F on a segment and
//! their differences bound dF/du (the convex hull property; Farouki & Rajan, "On the
//! numerical condition of polynomials in Bernstein form", CAGD 4, 1987), and de
//! Casteljau's split gives both halves' coefficients without evaluating the tape again.
//! The hull is tight where intervals are not: x⁴ − 5x² is bounded as one polynomial,
//! where interval arithmetic bounds x⁴ and 5x² apart and subtracts. Tanglecube-like
//! models (quartics, sextics, tori written out as polynomials) take this path.
//!
//! The decisions are the interval search's: a segment whose bound excludes 0 holds no
//! crossing; one on which F is monotonic, or shorter than the resolution, is decided by
//! the signs at its ends, and a crossing found is refined by the same safeguarded
//! Newton, on the polynomial (Horner's rule, not the tape), to the same tolerance. The
//! signs at the ends of the range and at the split points are the polynomial's (its
//! constant term is the tape's value at the start, by the same operations; the split
//! points' values are free from de Casteljau). The polynomial is F up to the
//! rounding of its coefficients, of the order of the tape's own rounding, so the
//! crossings agree with the interval search's far within its tolerance
//! (crates/frep/tests/poly_trace.rs).

use crate::expr::Node;
use crate::interval_trace::{newton_in, MAX_SEGMENTS};
use crate::poly::{Bernstein, Poly, MAX_DEGREE};
use crate::ray::Ray;
use crate::tree::{BinaryOp, UnaryOp, Var};
use glam::DVec3;
use std::cell::RefCell;

/// Deepest subdivision: far below any resolution a ray asks for (2⁻⁶⁰ of the range).
const MAX_DEPTH: u32 = 60;

thread_local! {
    /// Each node's polynomial along the ray, reused by every trace of a thread.
    static SCRATCH: RefCell<Vec<Coeffs>> = const { RefCell::new(Vec::new()) };
}

/// The degree of the tape (root last) as a polynomial of x, y, z when it is one whose
/// every node has degree ≤ [`MAX_DEGREE`]; None otherwise (any other operation, a
/// negative power, division by a non-constant, or a degree above the limit).
pub fn degree(tape: &[Node]) -> Option<usize> {
    let mut deg: Vec<usize> = Vec::with_capacity(tape.len());
    for &n in tape {
        let d = |i: u32| deg[i as usize];
        let k = match n {
            Node::Const(_) => 0,
            Node::Var(_) => 1,
            Node::Unary(UnaryOp::Neg, a) => d(a),
            Node::Unary(UnaryOp::Square, a) => 2 * d(a),
            Node::Binary(BinaryOp::Add | BinaryOp::Sub, a, b) => d(a).max(d(b)),
            Node::Binary(BinaryOp::Mul, a, b) => d(a) + d(b),
            Node::Binary(BinaryOp::Div, a, b) if d(b) == 0 => d(a),
            Node::PowI(a, k) if k >= 0 => d(a).checked_mul(k as usize)?,
            _ => return None,
        };
        if k > MAX_DEGREE {
            return None;
        }
        deg.push(k);
    }
    deg.last().copied()
}

/// Coefficients of a polynomial in u, lowest power first, and its nominal degree (the
/// coefficients above it are zero).
type Coeffs = ([f64; MAX_DEGREE + 1], usize);

/// p·q into `out`; the degrees add up to at most [`MAX_DEGREE`] in the tapes [`degree`]
/// accepts. Accumulated in place: a product built on the stack and copied out was
/// reloaded in 16-byte halves of its 8-byte stores (a store-forwarding stall).
#[inline(always)]
fn mul_into(out: &mut Coeffs, (p, m): &Coeffs, (q, n): &Coeffs) {
    out.0 = [0.0; MAX_DEGREE + 1];
    for (i, a) in p.iter().enumerate().take(m + 1) {
        for (j, b) in q.iter().enumerate().take(n + 1) {
            out.0[i + j] += a * b;
        }
    }
    out.1 = m + n;
}

/// F(p + u·dp) as a polynomial in u, for a tape that [`degree`] accepts. Each node's
/// coefficients are computed in their own slot (sized beforehand), not on the stack and
/// copied: see [`mul_into`].
fn along(tape: &[Node], p: DVec3, dp: DVec3, scratch: &mut Vec<Coeffs>) -> Coeffs {
    if scratch.len() < tape.len() {
        scratch.resize(tape.len(), ([0.0; MAX_DEGREE + 1], 0));
    }
    for (i, &n) in tape.iter().enumerate() {
        let (done, rest) = scratch.split_at_mut(i);
        let (s, out) = (|i: u32| &done[i as usize], &mut rest[0]);
        match n {
            Node::Const(b) => {
                out.0 = [0.0; MAX_DEGREE + 1];
                out.0[0] = f64::from_bits(b);
                out.1 = 0;
            }
            Node::Var(x) => {
                let k = match x {
                    Var::X => 0,
                    Var::Y => 1,
                    Var::Z => 2,
                };
                out.0 = [0.0; MAX_DEGREE + 1];
                (out.0[0], out.0[1]) = (p[k], dp[k]);
                out.1 = 1;
            }
            Node::Unary(UnaryOp::Neg, a) => {
                let (a, m) = s(a);
                *out = (a.map(|c| -c), *m);
            }
            Node::Unary(UnaryOp::Square, a) => mul_into(out, s(a), s(a)),
            Node::Binary(op @ (BinaryOp::Add | BinaryOp::Sub), a, b) => {
                let ((a, m), (b, n)) = (s(a), s(b));
                out.0 = match op {
                    BinaryOp::Add => std::array::from_fn(|k| a[k] + b[k]),
                    _ => std::array::from_fn(|k| a[k] - b[k]),
                };
                out.1 = *m.max(n);
            }
            Node::Binary(BinaryOp::Mul, a, b) => mul_into(out, s(a), s(b)),
            Node::Binary(BinaryOp::Div, a, b) => {
                let ((a, m), d) = (s(a), s(b).0[0]);
                *out = (a.map(|c| c / d), *m);
            }
            Node::PowI(a, k) => {
                let mut r = [0.0; MAX_DEGREE + 1];
                r[0] = 1.0;
                *out = (r, 0);
                for _ in 0..k {
                    let prev = *out;
                    mul_into(out, &prev, s(a));
                }
            }
            _ => unreachable!("a tape `degree` accepted"),
        }
    }
    scratch[tape.len() - 1]
}

/// One ray's search of [t0, t1] over a polynomial tape: F(t0 + h·u) = `p`(u).
struct Search {
    p: Poly<f64>,
    dp: Poly<f64>,
    eps_u: f64,
    tol_u: f64,
    visits: u32,
}

impl Search {
    /// The first crossing in [u0, u1], where `p` has Bernstein coefficients `b` and the
    /// ends are inside as (ia, ib).
    fn run(
        &mut self,
        b: &Bernstein<f64>,
        (u0, u1): (f64, f64),
        (ia, ib): (bool, bool),
        depth: u32,
    ) -> Option<f64> {
        self.visits += 1;
        let c = b.coeffs();
        if c.iter().all(|&v| v > 0.0) || c.iter().all(|&v| v < 0.0) {
            return None;
        }
        let rising = c.windows(2).all(|w| w[1] > w[0]);
        let falling = c.windows(2).all(|w| w[1] < w[0]);
        if rising
            || falling
            || u1 - u0 <= self.eps_u
            || depth >= MAX_DEPTH
            || self.visits > MAX_SEGMENTS
        {
            return (ia != ib).then(|| self.refine(u0, u1, ia));
        }
        let (l, r) = b.split_half();
        let um = 0.5 * (u0 + u1);
        let im = r.coeffs()[0] >= 0.0;
        self.run(&l, (u0, um), (ia, im), depth + 1)
            .or_else(|| self.run(&r, (um, u1), (im, ib), depth + 1))
    }

    /// The crossing in [a, b], where the inside predicate differs at the ends: the
    /// safeguarded Newton of the interval search, on the polynomial.
    fn refine(&self, a: f64, b: f64, inside_a: bool) -> f64 {
        newton_in(a, b, inside_a, self.tol_u, |x| {
            (self.p.eval(x), self.dp.eval(x))
        })
    }
}

/// F along one ray's segment [t0, t1] of a polynomial tape: F(t0 + h·u) = `p`(u).
pub(crate) struct Along {
    p: Poly<f64>,
    t0: f64,
    h: f64,
}

impl Along {
    /// F along [t0, t1] for a tape whose [`degree`] is `deg`. None where a coefficient
    /// is not finite (`x/0`, overflow): the polynomial says nothing there, and the
    /// interval search, which evaluates the tape itself, takes the ray.
    pub(crate) fn new(tape: &[Node], deg: usize, ray: &Ray, t0: f64, t1: f64) -> Option<Self> {
        let h = t1 - t0;
        let (c, _) = SCRATCH.with_borrow_mut(|s| along(tape, ray.at(t0), ray.d * h, s));
        c.iter().all(|v| v.is_finite()).then(|| Self {
            p: Poly::new(&c[..=deg]),
            t0,
            h,
        })
    }

    /// Whether F ≥ 0 at t0 and at t1: the constant term is F(t0) by the tape's own
    /// operations (integer powers aside, which it multiplies out), p(1) is F(t1) to
    /// rounding.
    pub(crate) fn end_signs(&self) -> (bool, bool) {
        (self.p.coeffs()[0] >= 0.0, self.p.eval(1.0) >= 0.0)
    }

    /// The first crossing in [t0, t1], whose ends are inside as (ia, ib); `eps_t` the
    /// resolution and `tol` the tolerance along the ray, as in [`crate::interval_trace`].
    pub(crate) fn first_crossing(
        &self,
        (ia, ib): (bool, bool),
        eps_t: f64,
        tol: f64,
    ) -> Option<f64> {
        let mut search = Search {
            p: self.p,
            dp: self.p.derivative(),
            eps_u: eps_t / self.h,
            tol_u: tol / self.h,
            visits: 0,
        };
        let u = search.run(&self.p.to_bernstein(), (0.0, 1.0), (ia, ib), 0)?;
        Some(self.t0 + self.h * u)
    }
}

/// Grows this thread's scratch to a tape of `n` nodes (nothing allocates once warm).
pub(crate) fn reserve(n: usize) {
    SCRATCH.with_borrow_mut(|s| {
        if s.capacity() < n {
            s.reserve(n - s.len());
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::Expr;
    use crate::tree::Tree;

    fn tape(t: &Tree) -> Vec<Node> {
        Expr::new(t).nodes().to_vec()
    }

    /// Degrees of polynomial tapes, and None for everything else.
    #[test]
    fn degrees_of_polynomial_tapes() {
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let tangle = x.clone().powi(4) - 5.0 * x.clone().square() + y.clone().powi(4)
            - 5.0 * y.clone().square()
            + z.clone().powi(4)
            - 5.0 * z.clone().square()
            + 11.8;
        assert_eq!(degree(&tape(&tangle)), Some(4));
        assert_eq!(degree(&tape(&(x.clone() * y.clone() / 3.0))), Some(2));
        assert_eq!(degree(&tape(&(x.clone().powi(6) - 1.0))), Some(6));
        assert_eq!(degree(&tape(&(x.clone().powi(7) - 1.0))), None);
        assert_eq!(degree(&tape(&(x.clone().powi(-1)))), None);
        assert_eq!(degree(&tape(&(x.clone() / y.clone()))), None);
        assert_eq!(degree(&tape(&(x.clone().square() + 1.0).sqrt())), None);
        assert_eq!(degree(&tape(&x.min(&y))), None);
        // x⁴·x³ is degree 7 even though every operand is below the limit.
        assert_eq!(
            degree(&tape(&(x.clone().powi(4) * z.clone().powi(3)))),
            None
        );
    }

    /// The polynomial along a ray equals the tape evaluated at points of the ray.
    #[test]
    fn polynomial_along_a_ray_equals_the_tape() {
        let (x, y, z) = (Tree::x(), Tree::y(), Tree::z());
        let t = (x.clone().square() + y.clone().square() + z.clone().square() + 0.3).square()
            - 4.0 * (x.clone().square() + y.clone().square()) / 2.0
            + x.clone() * y.clone() * z.clone()
            - (-z.clone()).powi(3);
        let nodes = tape(&t);
        assert_eq!(degree(&nodes), Some(4));
        let (p, dp) = (DVec3::new(0.3, -1.2, 0.7), DVec3::new(-0.4, 2.1, 0.9));
        let (c, n) = along(&nodes, p, dp, &mut Vec::new());
        assert_eq!(n, 4);
        let poly = Poly::new(&c[..=n]);
        for k in 0..=10 {
            let u = k as f64 / 10.0;
            let q = p + u * dp;
            let want = Expr::new(&t).eval(q.to_array());
            let got = poly.eval(u);
            assert!(
                (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                "{got} {want}"
            );
        }
    }
}
