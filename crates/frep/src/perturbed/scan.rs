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
//!
//! **No allocation per ray.** The active perturbations (at most [`MAX_ACTIVE`]) and
//! their breakpoints (at most two each) live in fixed arrays on the stack; the
//! breakpoints are sorted in place.
//!
//! **Overflow rule.** When more than [`MAX_ACTIVE`] perturbations are positive somewhere
//! on the scanned range, none is dropped. The range is halved (a chunk end is one more
//! breakpoint: F' is the same polynomial on both sides of it, and the sign of F' at the
//! end of the left chunk carries into the right one) and each half re-queries its
//! [`Source`], left first, at most `MAX_SPLITS` = 6 times deep. A chunk that still
//! overflows streams: it re-reads the source for every piece, taking as next breakpoint
//! the least interval end above the current one (selection instead of sorting; GPU.md
//! §6.1's "select the next minimum") and summing the perturbations that hold at the
//! piece's middle, in the source's order. Streaming visits the very pieces and sums of
//! the array path, so it gives the same answer bit for bit, at O(pieces × candidates)
//! cost; chunks expand pieces about their own ends, so they agree to rounding. Either
//! way no sign change is missed.
//!
//! The f32 path is the GPU kernel's twin and uses the kernel's capacities,
//! [`GPU_ACTIVE`] = 32 and [`GPU_SPLITS`] = 4 halvings; where it streams, the kernel
//! reports the ray as overflowing instead (GPU.md §6.1).

pub(crate) use super::along::Coeffs;
use super::along::{positive_set, q_local, q_local_mag};
pub(super) use crate::fixed::Fixed;
use crate::poly::{Bernstein, Poly};
use num_traits::Float;
use std::cell::Cell;

/// The most perturbations one scan keeps in its fixed-capacity active set; past it, the
/// overflow rule of the module docs. GPU.md §6.1 proposes K = 32 for the WGSL kernel;
/// on the CPU 64 keeps the overflow path rare (with 4096 perturbations in the benchmark,
/// a quarter of the rays that enter its bounds meet more than 32 supports, 2 % more than
/// 64: docs/notebook/2026-11-21-perturbed-quadrics-scaling.md) for 9 KiB of stack per
/// scan.
pub const MAX_ACTIVE: usize = 64;

/// The GPU kernel's active-set capacity K (GPU.md §6.1), which the f32 path
/// ([`PerturbedView::first_crossing_f32_gpu`](super::PerturbedView::first_crossing_f32_gpu))
/// uses too, so that both overflow on the same rays.
pub const GPU_ACTIVE: usize = 32;

/// How many times the GPU kernel halves an overflowing range before it reports the ray
/// as overflowing (where the CPU streams); the f32 path uses it too.
pub const GPU_SPLITS: usize = 4;

/// Breakpoints a full active set can make: a quadratic has at most two real roots.
const MAX_BREAKS: usize = 2 * MAX_ACTIVE;

/// Where a scan reads the perturbations (f_i, q_i) that may act on its range, in a fixed
/// order: the order in which each piece sums them, so every pass must repeat it.
pub(crate) trait Source<T> {
    /// Calls `visit(f_i, q_i)` for every perturbation that may be positive on the ray
    /// over [lo, hi], a part of the range the source was made for.
    fn for_each(&self, lo: T, hi: T, visit: impl FnMut(T, &Coeffs<T>));
}

/// One perturbation that is positive somewhere on the scanned range.
#[derive(Clone, Copy)]
pub(super) struct Active<T> {
    pub(super) f: T,
    q: Coeffs<T>,
    set: [(T, T); 2],
    n: usize,
}

impl<T: Float> Active<T> {
    /// The perturbation (f, q) restricted to where it is positive on (lo, hi), if anywhere.
    #[inline]
    pub(super) fn on(f: T, q: &Coeffs<T>, o: [T; 3], d: [T; 3], lo: T, hi: T) -> Option<Self> {
        Self::on_along(f, q, o, d, lo, hi).map(|(a, _)| a)
    }

    /// [`on`](Self::on), and q along the ray about its origin (t = 0) as a quadratic
    /// in t, which [`on`](Self::on) computes anyway.
    #[inline]
    pub(super) fn on_along(
        f: T,
        q: &Coeffs<T>,
        o: [T; 3],
        d: [T; 3],
        lo: T,
        hi: T,
    ) -> Option<(Self, [T; 3])> {
        if f == T::zero() {
            return None;
        }
        let along = q_local(q, o, d);
        let (mut set, n) = positive_set(along);
        let mut k = 0;
        for j in 0..n {
            let (a, b) = set[j];
            if a < hi && b > lo {
                set[k] = (a, b);
                k += 1;
            }
        }
        (k > 0).then_some((
            Self {
                f,
                q: *q,
                set,
                n: k,
            },
            along,
        ))
    }

    /// The interval ends strictly inside (lo, hi): the piece breakpoints it makes.
    #[inline]
    pub(super) fn breaks(&self, lo: T, hi: T, mut visit: impl FnMut(T)) {
        for &(a, b) in &self.set[..self.n] {
            for e in [a, b] {
                if e > lo && e < hi {
                    visit(e);
                }
            }
        }
    }

    #[inline]
    pub(super) fn holds(&self, t: T) -> bool {
        self.set[..self.n].iter().any(|&(a, b)| a < t && t < b)
    }

    /// Whether it is positive somewhere after t (an interval of its set ends above t).
    #[inline]
    pub(super) fn reaches_past(&self, t: T) -> bool {
        self.set[..self.n].iter().any(|&(_, b)| b > t)
    }
}

/// The active perturbations of a scan, visited in the source's order.
pub(super) trait Actives<T> {
    fn each(&self, visit: impl FnMut(&Active<T>));
}

impl<T: Float> Actives<T> for [Active<T>] {
    #[inline]
    fn each(&self, visit: impl FnMut(&Active<T>)) {
        self.iter().for_each(visit);
    }
}

/// The overflow path: the active set recomputed from the source at every use.
struct Streamed<'a, T, S> {
    src: &'a S,
    o: [T; 3],
    d: [T; 3],
    lo: T,
    hi: T,
}

impl<T: Float, S: Source<T>> Actives<T> for Streamed<'_, T, S> {
    #[inline]
    fn each(&self, mut visit: impl FnMut(&Active<T>)) {
        let Self { o, d, lo, hi, .. } = *self;
        self.src.for_each(lo, hi, |f, q| {
            if let Some(a) = Active::on(f, q, o, d, lo, hi) {
                visit(&a);
            }
        });
    }
}

/// The first t in (t_min, t_max) where F' changes sign, scanning [lo, hi] ⊂ [t_min,
/// t_max]. `sign` is the sign of F' just after lo when the caller knows it (−1 when lo
/// is where the ray enters the bounds of {F' ≥ 0}), else 0 to read it from F'.
/// `perturbations` yields (f_i, q_i) for every perturbation the range may meet.
///
/// Allocation-free: up to [`MAX_ACTIVE`] active perturbations and their breakpoints live
/// in fixed arrays; past that, the overflow rule of the module docs.
#[allow(clippy::too_many_arguments)]
pub(crate) fn first_crossing<T: Float, S: Source<T>>(
    base: &Coeffs<T>,
    perturbations: &S,
    o: [T; 3],
    d: [T; 3],
    range: (T, T),
    t_min: T,
    t_max: T,
    sign: T,
) -> Option<T> {
    let ray = (o, d, t_min, t_max, sign);
    first_crossing_within(base, perturbations, ray, range, MAX_ACTIVE, MAX_SPLITS).0
}

/// [`first_crossing`] with the GPU kernel's capacities ([`GPU_ACTIVE`], [`GPU_SPLITS`]),
/// and whether the scan had to stream: the rays the kernel reports as overflowing.
#[allow(clippy::too_many_arguments)]
pub(crate) fn first_crossing_gpu<T: Float, S: Source<T>>(
    base: &Coeffs<T>,
    perturbations: &S,
    o: [T; 3],
    d: [T; 3],
    range: (T, T),
    t_min: T,
    t_max: T,
    sign: T,
) -> (Option<T>, bool) {
    let ray = (o, d, t_min, t_max, sign);
    first_crossing_within(base, perturbations, ray, range, GPU_ACTIVE, GPU_SPLITS)
}

/// How many times an overflowing range is halved before the scan streams.
const MAX_SPLITS: usize = 6;

/// [`first_crossing`] with the overflow threshold `capacity` (≤ [`MAX_ACTIVE`]) and at
/// most `max_splits` halvings before streaming; tests force the overflow paths with a
/// small capacity. Also returns whether the scan streamed.
#[allow(clippy::type_complexity)]
fn first_crossing_within<T: Float, S: Source<T>>(
    base: &Coeffs<T>,
    perturbations: &S,
    (o, d, t_min, t_max, sign): ([T; 3], [T; 3], T, T, T),
    range: (T, T),
    capacity: usize,
    max_splits: usize,
) -> (Option<T>, bool) {
    let (lo, hi) = range;
    if lo.is_nan() || hi.is_nan() || lo >= hi {
        return (None, false);
    }
    let ray = Along {
        base,
        src: perturbations,
        o,
        d,
        t_min,
        t_max,
        capacity: capacity.min(MAX_ACTIVE),
        max_splits,
        streamed: Cell::new(false),
    };
    let t = match ray.chunk(lo, hi, sign, 0) {
        Ok(t) => t,
        // The range ends where the ray leaves the bounds of {F' ≥ 0} with F' ≥ 0 within
        // rounding there: the crossing is at that end (a perturbation's support ending
        // just past the crossing left its sign within rounding; f32 missed such exits).
        Err(s) if s > T::zero() && hi < t_max => Some(hi),
        // Its sign there unknown: the GPU kernel hands the ray to the CPU.
        Err(s) if s == T::zero() && hi < t_max => {
            ray.streamed.set(true);
            None
        }
        Err(_) => None,
    };
    (t, ray.streamed.get())
}

/// One ray against one source: what every chunk of the scan shares.
struct Along<'a, T, S> {
    base: &'a Coeffs<T>,
    src: &'a S,
    o: [T; 3],
    d: [T; 3],
    t_min: T,
    t_max: T,
    capacity: usize,
    max_splits: usize,
    /// Set when a chunk streamed (the GPU kernel's overflow report).
    streamed: Cell<bool>,
}

/// A point strictly inside (lo, hi) to split an overflowing range at, if there is one.
fn split_point<T: Float>(lo: T, hi: T) -> Option<T> {
    let one = T::one();
    let m = match (lo == -T::infinity(), hi == T::infinity()) {
        (true, true) => T::zero(),
        (true, false) => hi - hi.abs().max(one),
        (false, true) => lo + lo.abs().max(one),
        (false, false) => lo + (hi - lo) / (one + one),
    };
    (m > lo && m < hi).then_some(m)
}

impl<T: Float, S: Source<T>> Along<'_, T, S> {
    /// Scans [lo, hi] from the sign `sign` just after lo: Ok(answer) when decided, else
    /// Err(the sign of F' at hi, 0 when unknown), to carry into the next chunk.
    fn chunk(&self, lo: T, hi: T, sign: T, depth: usize) -> Result<Option<T>, T> {
        let Self { o, d, .. } = *self;
        let mut active = Fixed::<Active<T>, MAX_ACTIVE>::new();
        let mut breaks = Fixed::<T, MAX_BREAKS>::new();
        let mut overflow = false;
        self.src.for_each(lo, hi, |f, q| {
            if overflow {
                return;
            }
            if let Some(a) = Active::on(f, q, o, d, lo, hi) {
                if active.len() == self.capacity || !active.push(a) {
                    overflow = true;
                    return;
                }
                // At most two ends each: the breaks never outgrow 2·MAX_ACTIVE.
                a.breaks(lo, hi, |e| {
                    breaks.push(e);
                });
            }
        });
        if overflow {
            // A chunk boundary is one more breakpoint: F' is the same polynomial on both
            // sides, and the sign carries over.
            if let Some(m) = split_point(lo, hi).filter(|_| depth < self.max_splits) {
                return match self.chunk(lo, m, sign, depth + 1) {
                    Err(s) => self.chunk(m, hi, s, depth + 1),
                    decided => decided,
                };
            }
            return self.streamed(lo, hi, sign);
        }
        let any = !breaks.is_empty();
        let breaks = breaks.as_mut_slice();
        breaks.sort_unstable_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
        let mut k = 0;
        let next = |ta: T| {
            // The sorted breaks in turn, skipping repeats (ends are never NaN).
            while k < breaks.len() && breaks[k] <= ta {
                k += 1;
            }
            if k < breaks.len() {
                breaks[k]
            } else {
                hi
            }
        };
        self.scan(active.as_mut_slice(), sign)
            .run(lo, hi, any, next)
    }

    /// The last resort: the active set re-read from the source for every piece.
    fn streamed(&self, lo: T, hi: T, sign: T) -> Result<Option<T>, T> {
        self.streamed.set(true);
        let streamed = Streamed {
            src: self.src,
            o: self.o,
            d: self.d,
            lo,
            hi,
        };
        let next = |ta: T| {
            let mut best = hi;
            streamed.each(|a| {
                a.breaks(lo, hi, |e| {
                    if e > ta && e < best {
                        best = e;
                    }
                })
            });
            best
        };
        self.scan(&streamed, sign).run(lo, hi, next(lo) < hi, next)
    }

    fn scan<'b, A: Actives<T> + ?Sized>(&'b self, active: &'b A, sign: T) -> Scan<'b, T, A> {
        Scan {
            base: self.base,
            active,
            o: self.o,
            d: self.d,
            s: sign,
            t_min: self.t_min,
            t_max: self.t_max,
        }
    }
}

/// The state of one scan: the sign of F' before the current piece (0 while unknown).
pub(super) struct Scan<'a, T, A: ?Sized> {
    pub(super) base: &'a Coeffs<T>,
    pub(super) active: &'a A,
    pub(super) o: [T; 3],
    pub(super) d: [T; 3],
    pub(super) s: T,
    pub(super) t_min: T,
    pub(super) t_max: T,
}

/// How far past a finite anchor an unbounded piece's first sub-piece reaches, and the
/// growth factor of the following ones (a power of two, so that dividing by it undoes
/// multiplying exactly).
const GROWTH: f64 = 8.0;

impl<T: Float, A: Actives<T> + ?Sized> Scan<'_, T, A> {
    /// Scans the pieces of [lo, hi] left to right; `next(ta)` is the first breakpoint
    /// above ta (hi when none is left), `any` whether there is one at all.
    /// Ok(answer) when decided, else Err(the sign of F' at hi).
    fn run(
        mut self,
        lo: T,
        hi: T,
        any: bool,
        mut next: impl FnMut(T) -> T,
    ) -> Result<Option<T>, T> {
        // An unbounded range needs a finite point to expand about.
        let split_at_zero = lo == -T::infinity() && hi == T::infinity() && !any;
        let mut ta = lo;
        loop {
            let tb = if split_at_zero && ta == lo {
                T::zero()
            } else {
                next(ta)
            };
            if tb.is_nan() || tb <= ta {
                return Err(self.s);
            }
            let found = if ta == -T::infinity() {
                self.left_unbounded(tb)
            } else if tb == T::infinity() {
                self.right_unbounded(ta)
            } else {
                self.piece(ta, tb)
            };
            if let Some(result) = found {
                return Ok(result);
            }
            if tb >= hi {
                return Err(self.s);
            }
            ta = tb;
        }
    }

    /// Scans the finite piece [ta, tb]: Some(answer) when the scan is decided.
    pub(super) fn piece(&mut self, ta: T, tb: T) -> Option<Option<T>> {
        self.piece_or_any(ta, tb, false)
    }

    /// [`piece`](Self::piece), or with `any` (a shadow ray, which asks only whether there
    /// is a crossing) Some(Some(tb)) as soon as F' certainly has the other sign at tb
    /// (before t_max): there is a crossing in the piece, and where is not asked.
    pub(super) fn piece_or_any(&mut self, ta: T, tb: T, any: bool) -> Option<Option<T>> {
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
        let n = b.degree();
        if any && tb < self.t_max && self.s * b.coeffs()[n] < -e.coeffs()[n] {
            return Some(Some(tb));
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
    /// GROWTH towards tb: cuts at tb − w for w = w₀·GROWTHᵏ < R, visited from the
    /// largest down (dividing back by GROWTH, exact for a power of two).
    fn left_unbounded(&mut self, tb: T) -> Option<Option<T>> {
        let one = T::one();
        let width = tb.abs().max(one);
        let Some(r) = self.root_bound(tb, tb - width) else {
            return self.piece(tb - width, tb);
        };
        let growth = T::from(GROWTH).unwrap_or_else(T::nan);
        let (mut w, mut largest, mut count) = (width.min(r), T::zero(), 0usize);
        while w < r {
            largest = w;
            count += 1;
            w = w * growth;
        }
        let mut left = tb - r;
        for _ in 0..count {
            let cut = tb - largest;
            if let Some(found) = self.piece(left, cut) {
                return Some(found);
            }
            left = cut;
            largest = largest / growth;
        }
        self.piece(left, tb)
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
    fn new<A: Actives<T> + ?Sized>(
        base: &Coeffs<T>,
        active: &A,
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
        active.each(|a| {
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
        });
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadric::Quadric;
    use glam::DVec3;

    struct List(Vec<(f64, Coeffs<f64>)>);

    impl Source<f64> for List {
        fn for_each(&self, _: f64, _: f64, mut visit: impl FnMut(f64, &Coeffs<f64>)) {
            self.0.iter().for_each(|(f, q)| visit(*f, q));
        }
    }

    /// The overflow paths find the same crossings as the array path: pure streaming bit
    /// for bit, chunks (capacity 0, 1, 3, then streaming) to rounding.
    #[test]
    fn streaming_matches_the_fixed_arrays_bit_for_bit() {
        let base = Quadric::ellipsoid(DVec3::ZERO, DVec3::new(1.0, 0.7, 0.5)).c;
        let perts = List(
            (0..24)
                .map(|k| {
                    let a = k as f64 * 2.4;
                    let c = DVec3::new(a.cos(), 0.7 * a.sin(), 0.5 * (0.4 * a).sin());
                    let f = if k % 3 == 0 { -30.0 } else { 50.0 };
                    (f, Quadric::sphere(c, 0.3).c)
                })
                .collect(),
        );
        let mut hits = 0;
        for k in 0..500 {
            let u = k as f64 * 0.37;
            let o = [2.0 * u.cos(), 1.5 * (0.7 * u).sin(), 2.0 * u.sin()];
            let d = [-o[0] + 0.2 * u.sin(), -o[1], -o[2] + 0.1];
            let ray = (o, d, 0.0, f64::INFINITY, 0.0);
            let (want, _) =
                first_crossing_within(&base, &perts, ray, (0.0, 4.0), MAX_ACTIVE, MAX_SPLITS);
            let along = Along {
                base: &base,
                src: &perts,
                o,
                d,
                t_min: 0.0,
                t_max: f64::INFINITY,
                capacity: 0,
                max_splits: MAX_SPLITS,
                streamed: Cell::new(false),
            };
            let streamed = along.streamed(0.0, 4.0, 0.0).ok().flatten();
            assert_eq!(
                streamed.map(f64::to_bits),
                want.map(f64::to_bits),
                "ray {k}"
            );
            for cap in [0, 1, 3] {
                let (got, _) =
                    first_crossing_within(&base, &perts, ray, (0.0, 4.0), cap, MAX_SPLITS);
                // Chunk ends expand the pieces about other points: rounding only.
                match (got, want) {
                    (Some(g), Some(w)) => assert!((g - w).abs() < 1e-12, "ray {k}: {g} vs {w}"),
                    (g, w) => assert_eq!(g, w, "ray {k}"),
                }
            }
            hits += want.is_some() as usize;
        }
        assert!(hits > 100, "{hits}");
    }
}
