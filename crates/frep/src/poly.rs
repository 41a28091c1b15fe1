//! Polynomials of degree ≤ 6 in power and Bernstein form, and their first sign change.
//!
//! Along a ray a perturbed quadric F' = F + Σ f_i·q_i³ is, between the breakpoints
//! where some q_i changes sign, a polynomial of degree ≤ 6 in t (RESEARCH.md §4). This
//! module holds such pieces without allocation and finds the first place where one
//! changes sign: the piece is mapped to u ∈ [0, 1] and converted to Bernstein form, whose
//! coefficients bound the polynomial (convex hull property) and, by Descartes' rule of
//! signs in the Bernstein basis, bound its number of roots in (0, 1) by their number of
//! sign changes (Farouki & Rajan, "On the numerical condition of polynomials in Bernstein
//! form", CAGD 4, 1987; Lane & Riesenfeld, "Bounds on a polynomial", BIT 21, 1981).
//! No sign change: no root; one: exactly one, refined by safeguarded Newton; more: split
//! at ½ by de Casteljau and look left first. Everything is generic over
//! [`num_traits::Float`] so that the f32 path the GPU mirrors is the same code.

use crate::fixed::Fixed;
use num_traits::Float;

/// The highest degree held (a cubed quadratic).
pub const MAX_DEGREE: usize = 6;
const N1: usize = MAX_DEGREE + 1;
/// Subdivision depth after which an interval is treated as a single point.
pub const MAX_DEPTH: usize = 48;

/// `C(j,k) / C(n,k)`, the power-to-Bernstein weights: b_j = Σ_{k≤j} C(j,k)/C(n,k)·a_k
/// (Farouki & Rajan 1987, eq. 9).
const RATIO: [[[f64; N1]; N1]; N1] = ratio_table();

const fn binomial(n: usize, k: usize) -> f64 {
    let mut r = 1.0;
    let mut i = 0;
    while i < k {
        r = r * (n - i) as f64 / (i + 1) as f64;
        i += 1;
    }
    r
}

const fn ratio_table() -> [[[f64; N1]; N1]; N1] {
    let mut t = [[[0.0; N1]; N1]; N1];
    let mut n = 0;
    while n < N1 {
        let mut j = 0;
        while j <= n {
            let mut k = 0;
            while k <= j {
                t[n][j][k] = binomial(j, k) / binomial(n, k);
                k += 1;
            }
            j += 1;
        }
        n += 1;
    }
    t
}

#[inline(always)]
fn cst<T: Float>(v: f64) -> T {
    T::from(v).unwrap_or_else(T::nan)
}

/// A polynomial Σ c_k·x^k of nominal degree n ≤ 6 (coefficients above n are zero).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Poly<T> {
    c: [T; N1],
    n: usize,
}

impl<T: Float> Poly<T> {
    /// The zero polynomial.
    pub fn zero() -> Self {
        Self {
            c: [T::zero(); N1],
            n: 0,
        }
    }

    /// The polynomial with coefficients `c` (lowest power first; at most 7 of them).
    pub fn new(c: &[T]) -> Self {
        assert!(c.len() <= N1, "degree above {MAX_DEGREE}");
        let mut p = Self::zero();
        p.c[..c.len()].copy_from_slice(c);
        p.n = c.len().saturating_sub(1);
        p
    }

    /// a0 + a1·x + a2·x² (a quadric along a ray, see [`crate::quadric::Quadric::along`]).
    #[inline]
    pub fn quadratic(a: [T; 3]) -> Self {
        let mut p = Self::zero();
        p.c[0] = a[0];
        p.c[1] = a[1];
        p.c[2] = a[2];
        p.n = 2;
        p
    }

    /// The coefficients, lowest power first (length degree + 1).
    pub fn coeffs(&self) -> &[T] {
        &self.c[..=self.n]
    }

    /// The nominal degree (the leading coefficients may still be zero, see
    /// [`trimmed`](Self::trimmed)).
    pub fn degree(&self) -> usize {
        self.n
    }

    /// The same polynomial with exactly-zero leading coefficients dropped.
    pub fn trimmed(&self) -> Self {
        let mut p = *self;
        while p.n > 0 && p.c[p.n] == T::zero() {
            p.n -= 1;
        }
        p
    }

    /// p(x) by Horner's rule.
    #[inline]
    pub fn eval(&self, x: T) -> T {
        let mut v = self.c[self.n];
        for k in (0..self.n).rev() {
            v = v * x + self.c[k];
        }
        v
    }

    /// p'.
    pub fn derivative(&self) -> Self {
        let mut p = Self::zero();
        for k in 1..=self.n {
            p.c[k - 1] = self.c[k] * cst(k as f64);
        }
        p.n = self.n.saturating_sub(1);
        p
    }

    /// p + q.
    pub fn add(&self, q: &Self) -> Self {
        let mut p = *self;
        for k in 0..N1 {
            p.c[k] = p.c[k] + q.c[k];
        }
        p.n = self.n.max(q.n);
        p
    }

    /// k·p.
    pub fn scale(&self, k: T) -> Self {
        let mut p = *self;
        for v in &mut p.c {
            *v = *v * k;
        }
        p
    }

    /// p·q; panics when the degrees add up to more than 6.
    pub fn mul(&self, q: &Self) -> Self {
        assert!(self.n + q.n <= MAX_DEGREE, "degree above {MAX_DEGREE}");
        let mut p = Self::zero();
        for i in 0..=self.n {
            for j in 0..=q.n {
                p.c[i + j] = p.c[i + j] + self.c[i] * q.c[j];
            }
        }
        p.n = self.n + q.n;
        p
    }

    /// Adds f·(a0 + a1·x + a2·x²)³ (one active perturbation, expanded by the multinomial
    /// theorem); the degree becomes 6.
    #[inline]
    pub fn add_scaled_cube(&mut self, f: T, q: [T; 3]) {
        let [a, b, c] = q;
        let three = cst::<T>(3.0);
        let (a2, b2, c2) = (a * a, b * b, c * c);
        let cube = [
            a2 * a,
            three * a2 * b,
            three * a * (a * c + b2),
            b2 * b + cst::<T>(6.0) * a * b * c,
            three * c * (b2 + a * c),
            three * b * c2,
            c2 * c,
        ];
        for (k, v) in cube.into_iter().enumerate() {
            self.c[k] = self.c[k] + f * v;
        }
        self.n = MAX_DEGREE;
    }

    /// Adds a first-order bound on the error of f·q³ as formed by
    /// [`add_scaled_cube`](Self::add_scaled_cube), in units of ε, when each coefficient
    /// of q = [a0, a1, a2] may be off by ε times the matching entry of `m` and |q| ≤
    /// `q_max` on the interval of interest: |f|·(3·q_max²·m + |q|³), the derivative of the
    /// cube times the input error plus the rounding of the products (|q|³ taken
    /// coefficient-wise, since the power-form coefficients can cancel).
    pub fn add_cube_error(&mut self, f: T, q: [T; 3], m: [T; 3], q_max: T) {
        let a = q.map(T::abs);
        let three = cst::<T>(3.0);
        let f = f.abs();
        let mut cube = Self::zero();
        cube.add_scaled_cube(f, a);
        let k = f * three * q_max * q_max;
        for (j, &mj) in m.iter().enumerate() {
            cube.c[j] = cube.c[j] + k * mj;
        }
        *self = self.add(&cube);
    }

    /// p(h·x): the coefficient of x^k is multiplied by h^k. A zero coefficient stays
    /// zero even where h^k overflows (in f32 from h ≈ 2.6e6 at degree 6), instead of
    /// becoming 0·∞ = NaN: a cubed linear q_i has zero coefficients above degree 3.
    pub fn scaled(&self, h: T) -> Self {
        let mut p = *self;
        let mut hk = T::one();
        for k in 1..=p.n {
            hk = hk * h;
            if p.c[k] != T::zero() {
                p.c[k] = p.c[k] * hk;
            }
        }
        p
    }

    /// p(x0 + x), the Taylor shift, by repeated synthetic division (O(n²)).
    pub fn shifted(&self, x0: T) -> Self {
        let mut p = *self;
        for i in 0..p.n {
            for k in (i..p.n).rev() {
                p.c[k] = p.c[k] + x0 * p.c[k + 1];
            }
        }
        p
    }

    /// The piece on [t0, t1] as a polynomial in u ∈ [0, 1]: p(t0 + (t1 − t0)·u).
    pub fn on_interval(&self, t0: T, t1: T) -> Self {
        self.shifted(t0).scaled(t1 - t0)
    }

    /// Cauchy's bound: every complex root z has |z| < 1 + max_{k<n} |c_k / c_n|
    /// (Cauchy 1829). None for a constant (after trimming zero leading coefficients).
    pub fn cauchy_bound(&self) -> Option<T> {
        let p = self.trimmed();
        if p.n == 0 {
            return None;
        }
        let lead = p.c[p.n].abs();
        let mut m = T::zero();
        for k in 0..p.n {
            m = m.max(p.c[k].abs() / lead);
        }
        Some(T::one() + m)
    }

    /// The Bernstein form on [0, 1] of the same degree.
    pub fn to_bernstein(&self) -> Bernstein<T> {
        let n = self.n;
        let mut b = [T::zero(); N1];
        for (j, bj) in b.iter_mut().enumerate().take(n + 1) {
            let mut s = T::zero();
            for (r, &a) in RATIO[n][j].iter().zip(&self.c).take(j + 1) {
                s = s + cst::<T>(*r) * a;
            }
            *bj = s;
        }
        Bernstein { b, n }
    }
}

/// A polynomial on [0, 1] in Bernstein form: Σ b_j·C(n,j)·u^j·(1−u)^{n−j}.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bernstein<T> {
    b: [T; N1],
    n: usize,
}

/// One pending sub-interval of the left-first search.
#[derive(Clone, Copy)]
struct Frame<T> {
    b: [T; N1],
    e: [T; N1],
    u0: T,
    u1: T,
    depth: usize,
}

impl<T: Float> Bernstein<T> {
    /// The polynomial with Bernstein coefficients `b` (at most 7).
    pub fn new(b: &[T]) -> Self {
        assert!(!b.is_empty() && b.len() <= N1, "degree above {MAX_DEGREE}");
        let mut c = [T::zero(); N1];
        c[..b.len()].copy_from_slice(b);
        Self {
            b: c,
            n: b.len() - 1,
        }
    }

    /// The coefficients b_0 … b_n.
    pub fn coeffs(&self) -> &[T] {
        &self.b[..=self.n]
    }

    /// The degree n.
    pub fn degree(&self) -> usize {
        self.n
    }

    /// k·p.
    pub fn scale(&self, k: T) -> Self {
        let mut p = *self;
        for v in &mut p.b {
            *v = *v * k;
        }
        p
    }

    /// p(u) by de Casteljau's algorithm (numerically stable on [0, 1]).
    pub fn eval(&self, u: T) -> T {
        eval_d(&self.b, self.n, u).0
    }

    /// The number of sign changes in the coefficient sequence (zeros skipped): an upper
    /// bound on the number of roots in (0, 1), with the same parity.
    pub fn sign_changes(&self) -> usize {
        sign_changes(&self.b[..=self.n])
    }

    /// The halves on [0, ½] and [½, 1], each reparametrised to [0, 1] (de Casteljau).
    pub fn split_half(&self) -> (Self, Self) {
        let (l, r) = split_half(&self.b, self.n);
        (Self { b: l, n: self.n }, Self { b: r, n: self.n })
    }

    /// The default rounding bound of each coefficient: 32·ε·max_j |b_j| (ε the machine
    /// epsilon of T), for a polynomial known only by its coefficients.
    pub fn uniform_error(&self) -> Self {
        let big = self.b[..=self.n]
            .iter()
            .fold(T::zero(), |m, v| m.max(v.abs()));
        let mut e = *self;
        e.b = [T::epsilon() * cst(32.0) * big; N1];
        e
    }

    /// The sign of p just after u = 0, reading coefficients within ±err_j as zero: that
    /// of the first significant coefficient (the basis function of lowest index
    /// dominates near 0), else of the first non-zero one; 0 when p ≡ 0.
    pub fn sign_after_zero_bounded(&self, err: &Self) -> T {
        let b = &self.b[..=self.n];
        b.iter()
            .zip(&err.b)
            .find(|(v, e)| v.abs() > **e)
            .map(|(v, _)| v)
            .or_else(|| b.iter().find(|v| **v != T::zero()))
            .map_or(T::zero(), |v| v.signum())
    }

    /// [`sign_after_zero_bounded`](Self::sign_after_zero_bounded) with the
    /// [`uniform_error`](Self::uniform_error).
    pub fn sign_after_zero(&self) -> T {
        self.sign_after_zero_bounded(&self.uniform_error())
    }

    /// The first u ∈ [0, 1] where p turns negative: inf{u : p(u) < 0}, or None when
    /// p ≥ 0 on [0, 1], with [`uniform_error`](Self::uniform_error) bounds (see
    /// [`first_negative_bounded`](Self::first_negative_bounded)).
    pub fn first_negative(&self) -> Option<T> {
        self.first_negative_bounded(&self.uniform_error())
    }

    /// The first u ∈ [0, 1] where p turns negative, given a bound err_j ≥ 0 on the
    /// rounding error of each coefficient b_j (a polynomial of the same degree).
    ///
    /// Only certain signs count: p(u0) = b_0 < −err_0 is a crossing at u0, all b_j ≥
    /// −err_j means nothing on the interval, and one significant sign change from b_0 ≥
    /// 0 to b_n < −err_n is refined; anything else is split in half, left first, with the
    /// bounds split alongside (de Casteljau is a positive combination). So a tangent
    /// touch of zero (an even-multiplicity root) is not a crossing, nor is a dip below
    /// zero that rounding could have produced; a true crossing is located to within
    /// the width where p stays inside its error bound. Subdivision stops at depth
    /// [`MAX_DEPTH`] or a width of 8ε, where a remaining certainly negative end or
    /// middle counts as a crossing.
    pub fn first_negative_bounded(&self, err: &Self) -> Option<T> {
        let n = self.n;
        let tol = T::epsilon() * cst(8.0);
        let half = cst::<T>(0.5);
        // Pending right halves. Left uninitialised: zero-filling 49 frames (6.6 KiB in f64)
        // on every call cost more than most searches (perf, many-lights scene).
        let mut stack = Fixed::<Frame<T>, { MAX_DEPTH + 1 }>::new();
        let mut cur = Frame {
            b: self.b,
            e: err.b,
            u0: T::zero(),
            u1: T::one(),
            depth: 0,
        };
        loop {
            let (b, e) = (&cur.b[..=n], &cur.e[..=n]);
            if b[0] < -e[0] {
                // p(u0) < 0 for certain; everything before u0 was ≥ −err: the crossing is
                // where the computed p last leaves ≥ 0 before u0.
                return Some(self.polish(cur.u0, cur.u1 - cur.u0));
            }
            if b.iter().zip(e).any(|(v, e)| *v < -*e) {
                let w = cur.u1 - cur.u0;
                let at = |v: T| cur.u0 + w * v;
                let last_negative = b[n] < -e[n];
                if b[0] >= T::zero() && last_negative && significant_sign_changes(b, e) == 1 {
                    // One sign change, to certainly negative: refine the computed root
                    // (when p(u0) is within its error bound this is still the best
                    // estimate of where p leaves zero).
                    return Some(at(refine(&cur.b, n, T::zero(), T::one())));
                }
                if cur.depth >= MAX_DEPTH || w <= tol {
                    if b[0] < T::zero() {
                        return Some(self.polish(cur.u0, w));
                    }
                    if last_negative {
                        return Some(at(refine(&cur.b, n, T::zero(), T::one())));
                    }
                    let big_e = e.iter().fold(T::zero(), |m, v| m.max(*v));
                    if eval_d(&cur.b, n, half).0 < -big_e {
                        return Some(at(refine(&cur.b, n, T::zero(), half)));
                    }
                } else {
                    let (l, r) = split_half(&cur.b, n);
                    let (el, er) = split_half(&cur.e, n);
                    let mid = cur.u0 + w * half;
                    stack.push_within(Frame {
                        b: r,
                        e: er,
                        u0: mid,
                        u1: cur.u1,
                        depth: cur.depth + 1,
                    });
                    cur = Frame {
                        b: l,
                        e: el,
                        u0: cur.u0,
                        u1: mid,
                        depth: cur.depth + 1,
                    };
                    continue;
                }
            }
            match stack.pop() {
                Some(f) => cur = f,
                None => return None,
            }
        }
    }

    /// The computed crossing just left of `u` (where p < 0): steps left by w, 2w, 4w, …
    /// until p ≥ 0, then refines between the two; `u` itself when p stays negative as far
    /// as 0 (the crossing is at the start) or for 40 doublings.
    fn polish(&self, u: T, w: T) -> T {
        let mut step = w;
        for _ in 0..40 {
            let lo = (u - step).max(T::zero());
            if eval_d(&self.b, self.n, lo).0 >= T::zero() {
                return refine(&self.b, self.n, lo, u);
            }
            if lo == T::zero() {
                break;
            }
            step = step + step;
        }
        u
    }

    /// The first u ∈ (0, 1) where p changes sign: with s the sign of p just after 0,
    /// the first point after which p has sign −s (a root at u = 1 is not a change within
    /// [0, 1]). None when p keeps its sign (touching zero tangentially is not a change)
    /// or p ≡ 0. Uses the [`uniform_error`](Self::uniform_error) bounds.
    pub fn first_sign_change(&self) -> Option<T> {
        let s = self.sign_after_zero();
        if s == T::zero() {
            return None;
        }
        self.scale(s).first_negative()
    }
}

fn sign_changes<T: Float>(b: &[T]) -> usize {
    let mut count = 0;
    let mut prev = T::zero();
    for &v in b {
        if v != T::zero() {
            if prev != T::zero() && (v < T::zero()) != (prev < T::zero()) {
                count += 1;
            }
            prev = v;
        }
    }
    count
}

/// Sign changes among the coefficients larger than their error bound in magnitude.
fn significant_sign_changes<T: Float>(b: &[T], e: &[T]) -> usize {
    let mut count = 0;
    let mut prev = T::zero();
    for (&v, &err) in b.iter().zip(e) {
        if v.abs() > err {
            if prev != T::zero() && (v < T::zero()) != (prev < T::zero()) {
                count += 1;
            }
            prev = v;
        }
    }
    count
}

/// The halves [0, ½] and [½, 1] by de Casteljau. Each degree takes a copy with the
/// degree fixed at compile time, whose loops unroll into registers: the same operations
/// in the same order, so the same values bit for bit, without the round trips through
/// the stack that made the search's next reads of the halves stall.
#[inline]
fn split_half<T: Float>(b: &[T; N1], n: usize) -> ([T; N1], [T; N1]) {
    debug_assert!(n <= MAX_DEGREE);
    match n {
        0 => split_half_fixed::<T, 0>(b),
        1 => split_half_fixed::<T, 1>(b),
        2 => split_half_fixed::<T, 2>(b),
        3 => split_half_fixed::<T, 3>(b),
        4 => split_half_fixed::<T, 4>(b),
        5 => split_half_fixed::<T, 5>(b),
        _ => split_half_fixed::<T, MAX_DEGREE>(b),
    }
}

/// [`split_half`] for the degree N.
#[inline(always)]
fn split_half_fixed<T: Float, const N: usize>(b: &[T; N1]) -> ([T; N1], [T; N1]) {
    let half = cst::<T>(0.5);
    let mut w = *b;
    let mut l = [T::zero(); N1];
    let mut r = [T::zero(); N1];
    l[0] = w[0];
    r[N] = w[N];
    for k in 1..=N {
        for j in 0..=N - k {
            w[j] = (w[j] + w[j + 1]) * half;
        }
        l[k] = w[0];
        r[N - k] = w[N - k];
    }
    (l, r)
}

/// (p(u), p'(u)) by de Casteljau: after n − 1 rounds two values remain, whose
/// difference times n is the derivative.
///
/// Degree 6 (every piece with a perturbation) takes a copy with the degree fixed at
/// compile time, whose loops unroll: the same operations in the same order, so the same
/// values bit for bit, at a third of the instructions (root refinement was a tenth of
/// the perturbed benchmark).
#[inline]
fn eval_d<T: Float>(b: &[T; N1], n: usize, u: T) -> (T, T) {
    // Unrolled for the two degrees that occur most: perturbed pieces (6) and quadrics'
    // pieces where no perturbation acts (2). The same operations in the same order.
    match n {
        MAX_DEGREE => eval_d_fixed::<T, MAX_DEGREE>(b, u),
        2 => eval_d_fixed::<T, 2>(b, u),
        _ => eval_d_any(b, n, u),
    }
}

/// [`eval_d`] for the degree N.
#[inline(always)]
fn eval_d_fixed<T: Float, const N: usize>(b: &[T; N1], u: T) -> (T, T) {
    let v = T::one() - u;
    let mut w = *b;
    for k in 1..N {
        for j in 0..=N - k {
            w[j] = v * w[j] + u * w[j + 1];
        }
    }
    (v * w[0] + u * w[1], cst::<T>(N as f64) * (w[1] - w[0]))
}

/// [`eval_d`] for any degree n ≤ [`MAX_DEGREE`].
#[inline]
fn eval_d_any<T: Float>(b: &[T; N1], n: usize, u: T) -> (T, T) {
    if n == 0 {
        return (b[0], T::zero());
    }
    let v = T::one() - u;
    let mut w = *b;
    for k in 1..n {
        for j in 0..=n - k {
            w[j] = v * w[j] + u * w[j + 1];
        }
    }
    (v * w[0] + u * w[1], cst::<T>(n as f64) * (w[1] - w[0]))
}

/// The root in [lo, hi] where p goes from ≥ 0 at lo to < 0 at hi, by Newton's method
/// safeguarded by bisection (Press et al., Numerical Recipes, `rtsafe`).
fn refine<T: Float>(b: &[T; N1], n: usize, lo: T, hi: T) -> T {
    refine_counted(b, n, lo, hi).0
}

/// [`refine`] and the number of Newton or bisection steps it took.
#[inline]
fn refine_counted<T: Float>(b: &[T; N1], n: usize, mut lo: T, mut hi: T) -> (T, usize) {
    let tol = T::epsilon() * cst(2.0);
    let half = cst::<T>(0.5);
    let (glo, ghi) = (eval_d(b, n, lo).0, eval_d(b, n, hi).0);
    // Start from the secant point (regula falsi) of the bracket.
    let mut x = lo + (hi - lo) * (glo / (glo - ghi));
    if !(x > lo && x < hi) {
        x = (lo + hi) * half;
    }
    let mut step_old = hi - lo;
    for steps in 1..=100 {
        let (g, dg) = eval_d(b, n, x);
        if g == T::zero() {
            return (x, steps);
        }
        if g > T::zero() {
            lo = x;
        } else {
            hi = x;
        }
        let newton = x - g / dg;
        let close = tol * x.abs().max(T::one());
        let next = if newton > lo && newton < hi && (g + g).abs() <= (step_old * dg).abs() {
            newton
        } else if dg < T::zero() && (newton - x).abs() <= close {
            // Converged: p falls through the bracketed root and Newton's step is under
            // an ulp, so it lands on the bracket's end just moved to x. Bisecting from
            // there would walk ~50 halvings back to x (rtsafe tests the step before the
            // bracket). Answer on the far side of the root as that walk would: x where p
            // is already negative, else one tolerance past x, so that a search restarted
            // there does not meet this root again. (Where p rises at x, Newton heads
            // for another root outside the bracket: bisect.)
            return (
                if g < T::zero() {
                    x
                } else {
                    (x + close).min(hi)
                },
                steps,
            );
        } else {
            (lo + hi) * half
        };
        step_old = (next - x).abs();
        x = next;
        if step_old <= tol * x.abs().max(T::one()) || hi - lo <= tol {
            return (x, steps);
        }
    }
    (x, 100)
}

#[cfg(test)]
mod tests;
