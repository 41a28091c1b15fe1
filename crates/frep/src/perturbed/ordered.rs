//! The f64 scan in ray order: the support BVH hands out perturbations by the
//! parameter where the ray enters their box ([`EntryOrder`]), and each piece is scanned
//! as soon as every support that can start before its end is known, so that the walk
//! stops at the first crossing and never opens the boxes behind it.
//!
//! It visits the same pieces as [`super::scan::first_crossing`] (the breakpoints are the
//! same interval ends; a support whose box the ray enters after a piece's end cannot be
//! positive on it) and expands each the same way; only the order in which a piece sums
//! its perturbations differs (entry order, not the BVH's), so the answers agree to
//! rounding. Perturbations whose last interval ends before the current piece leave the
//! active set (once [`RETIRE`] have piled up, or when it is full), which so holds only
//! the supports near the scan front. Where the front still overlaps more than
//! [`MAX_ACTIVE`], the queue of pending boxes fills, or the range is unbounded, it defers
//! to [`super::scan::first_crossing`].
//!
//! **Pieces of certain sign.** Before a piece is expanded, a few flops per perturbation
//! bound it: F' lies between F's least value on the piece plus Σ f_i·q_i³ at each
//! term's least, and the same at the greatest (each quadratic's range over the piece,
//! from its expansion about the ray's origin; f·q³ is monotonic in q ≥ 0). Where that
//! range excludes 0 by a wide margin, the piece holds no crossing and its Bernstein form
//! need not be built. The margin (`MARGIN` times first-order bounds on the terms'
//! magnitudes) is some 10⁵ times the rounding bound the full expansion itself works
//! with, so a skipped piece is one whose full expansion would have certainly kept its
//! sign: skipping changes no answer.

use super::along::q_local_mag;
use super::scan::{Active, Actives, Coeffs, Fixed, Scan, MAX_ACTIVE};
use super::Perturbation;
use crate::bvh::{BvhRef, EntryOrder};
use crate::ray::Ray;

/// How far past a piece's end (relative to |t| + 1) a box entry still counts as before
/// it: a margin for the rounding of the slab test, so that a support is never missed.
const SLACK: f64 = 1e-9;

/// The relative margin of the certain-sign test, on the magnitudes of the terms summed:
/// some 10⁵ times the bound 32·ε the full expansion puts on its own rounding.
const MARGIN: f64 = 1e-9;

/// A support met by the ray, with what the certain-sign test reads: q along the ray
/// about its origin, and the sum of the magnitudes of that expansion's terms.
#[derive(Clone, Copy)]
struct Known {
    active: Active<f64>,
    along: Quadratic,
    mag: f64,
}

impl Actives<f64> for [Known] {
    #[inline]
    fn each(&self, mut visit: impl FnMut(&Active<f64>)) {
        self.iter().for_each(|k| visit(&k.active));
    }
}

/// a0 + a1·t + a2·t², by Horner's rule.
#[inline]
pub(super) fn quadratic_at([a0, a1, a2]: [f64; 3], t: f64) -> f64 {
    a0 + t * (a1 + t * a2)
}

/// A quadratic a0 + a1·t + a2·t² along the ray with its vertex found once: the
/// certain-sign test asks for its range over every piece it spans.
#[derive(Clone, Copy)]
pub(super) struct Quadratic {
    pub(super) a: [f64; 3],
    /// −a1 / (2·a2), NaN when a2 = 0 (so that no piece holds it).
    vertex: f64,
    /// The value there.
    peak: f64,
}

impl Quadratic {
    pub(super) fn new(a: [f64; 3]) -> Self {
        let mut q = Self {
            a,
            vertex: f64::NAN,
            peak: f64::NAN,
        };
        if a[2] != 0.0 {
            q.vertex = -a[1] / (2.0 * a[2]);
            q.peak = q.at(q.vertex);
        }
        q
    }

    #[inline]
    pub(super) fn at(&self, t: f64) -> f64 {
        quadratic_at(self.a, t)
    }

    /// The least and greatest value on [ta, tb]: at the ends or at the vertex.
    #[inline]
    pub(super) fn range(&self, ta: f64, tb: f64) -> (f64, f64) {
        let (va, vb) = (self.at(ta), self.at(tb));
        let (mut lo, mut hi) = (va.min(vb), va.max(vb));
        if self.vertex > ta && self.vertex < tb {
            lo = lo.min(self.peak);
            hi = hi.max(self.peak);
        }
        (lo, hi)
    }
}

/// The base along the ray (about its origin) and the sum of its terms' magnitudes.
struct Base {
    along: Quadratic,
    mag: f64,
}

impl Base {
    /// ±1 when F' certainly has that sign all over [ta, tb] (see the module docs), else 0.
    fn certain_sign(&self, known: &[Known], ta: f64, tb: f64) -> f64 {
        // Terms expanded about a point |t| ≤ |ta| and scaled to a width h = tb − ta are
        // at most ((1 + |ta|)·(1 + h))² times their magnitudes at t = 0.
        let grow = ((1.0 + ta.abs()) * (1.0 + (tb - ta))).powi(2);
        // F' ∈ [lo, hi] on the piece, up to `slack`: F's range plus each term's, f·q³
        // being monotonic in q ≥ 0.
        let (mut lo, mut hi) = self.along.range(ta, tb);
        let mut slack = MARGIN * self.mag * grow;
        let mid = 0.5 * (ta + tb);
        for k in known {
            if k.active.holds(mid) {
                let pad = MARGIN * k.mag * grow;
                let (q0, q1) = k.along.range(ta, tb);
                let (q0, q1) = ((q0 - pad).max(0.0), q1 + pad);
                let f = k.active.f;
                let (c0, c1) = (f * q0 * q0 * q0, f * q1 * q1 * q1);
                lo += c0.min(c1);
                hi += c0.max(c1);
                // The rounding of q's local expansion (magnitudes ≤ mag·grow) through the
                // cube, and of the cube's coefficients (each ≤ 16·max q).
                slack += MARGIN * f.abs() * q1 * q1 * (k.mag * grow + 4096.0 * q1);
            }
        }
        if lo > slack {
            1.0
        } else if hi < -slack {
            -1.0
        } else {
            0.0
        }
    }
}

/// The first t in (t_min, t_max) where F' changes sign, scanning [lo, hi] ⊂ [t_min,
/// t_max] in ray order; `sign` as in [`super::scan::first_crossing`]. None when it must
/// defer (see the module docs), else the answer. With `any` (shadow rays), the answer
/// says only whether there is a crossing: Some(Some(t)) with t past it, at the end of
/// the first piece where F' certainly has the other sign ([`Scan::piece_or_any`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn first_crossing(
    base: &Coeffs<f64>,
    perturbations: &[Perturbation],
    bvh: BvhRef<'_>,
    ray: &Ray,
    (lo, hi): (f64, f64),
    t_min: f64,
    t_max: f64,
    sign: f64,
    any: bool,
) -> Option<Option<f64>> {
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return None;
    }
    let (o, d) = (ray.o.to_array(), ray.d.to_array());
    let sum = |m: [f64; 3]| m[0] + m[1] + m[2];
    let f = Base {
        along: Quadratic::new(super::along::q_local(base, o, d)),
        mag: sum(q_local_mag(base, o, d)),
    };
    let mut queue = EntryOrder::queue();
    let mut walk = EntryOrder::new(bvh, ray, lo, hi, &mut queue);
    let mut known = Fixed::<Known, MAX_ACTIVE>::new();
    let mut ends = Ends::new();
    let (mut ta, mut s) = (lo, sign);
    loop {
        // The piece's end: the least interval end above ta among the known supports,
        // lowered by any support whose box the ray enters before it.
        let mut tb = ends.least_above(ta).unwrap_or(hi);
        while let Some(i) = walk.next_before(tb + SLACK * (tb.abs() + 1.0)) {
            let p = &perturbations[i];
            if let Some((active, along)) = Active::on_along(p.f, &p.q.c, o, d, lo, hi) {
                let mag = sum(q_local_mag(&p.q.c, o, d));
                let along = Quadratic::new(along);
                let k = Known { active, along, mag };
                if !known.push(k) {
                    // Full: drop the supports left behind, then try again.
                    known.retain(|k| k.active.reaches_past(ta));
                    if !known.push(k) {
                        return None;
                    }
                }
                let mut room = true;
                active.breaks(ta, hi, |e| {
                    room &= ends.insert(e);
                    tb = tb.min(e);
                });
                if !room {
                    return None;
                }
            }
        }
        if walk.overflowed() {
            return None;
        }
        let certain = f.certain_sign(known.as_slice(), ta, tb);
        if certain != 0.0 && (s == 0.0 || s == certain) {
            s = certain;
        } else {
            let mut scan = Scan {
                base,
                active: known.as_slice(),
                o,
                d,
                s,
                t_min,
                t_max,
            };
            if let Some(found) = scan.piece_or_any(ta, tb, any) {
                return Some(found);
            }
            s = scan.s;
        }
        if tb >= hi {
            return Some(None);
        }
        ta = tb;
        if known.len() >= RETIRE {
            known.retain(|k| k.active.reaches_past(ta));
        }
    }
}

/// How many known supports the scan lets pile up before it drops those left behind:
/// dropping moves the rest, keeping makes every piece test them.
const RETIRE: usize = 32;

/// The breakpoints still ahead of the scan, ascending, in `v[head..len]` (slots beyond
/// `len` never written, as in [`Fixed`]): supports come in entry order, so most of their
/// ends land at the back.
struct Ends {
    v: Fixed<f64, ENDS>,
    head: usize,
}

/// Room for the ends of a full active set (at most two finite ends each).
const ENDS: usize = 2 * MAX_ACTIVE;

impl Ends {
    fn new() -> Self {
        Self {
            v: Fixed::new(),
            head: 0,
        }
    }

    /// Inserts e in order; false when there is no room.
    fn insert(&mut self, e: f64) -> bool {
        if self.v.is_full() {
            self.v.drop_front(self.head);
            self.head = 0;
        }
        self.v.insert_from_back(e, self.head, |&p| p > e)
    }

    /// The least end above t, dropping those at or below it.
    fn least_above(&mut self, t: f64) -> Option<f64> {
        while self.head < self.v.len() && self.v.at(self.head) <= t {
            self.head += 1;
        }
        (self.head < self.v.len()).then(|| self.v.at(self.head))
    }
}

#[cfg(test)]
mod tests {
    use crate::perturbed::PerturbedQuadric;
    use crate::quadric::Quadric;
    use crate::ray::Ray;
    use glam::DVec3;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// The benchmark's solid (crates/frep/benches/perturbed.rs): n bumps and dents of
    /// support radius `r` on a Fibonacci lattice of an ellipsoid.
    fn bumpy(n: usize, r: f64) -> PerturbedQuadric {
        let radii = DVec3::new(1.0, 0.7, 0.5);
        let base = Quadric::ellipsoid(DVec3::ZERO, radii);
        let mut pq = PerturbedQuadric::new(base);
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        for k in 0..n {
            let z = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
            let phi = golden * k as f64;
            let c = radii
                * DVec3::new(
                    (1.0 - z * z).sqrt() * phi.cos(),
                    (1.0 - z * z).sqrt() * phi.sin(),
                    z,
                );
            let f = if k % 3 == 2 { -0.5 } else { 0.5 } * r * base.gradient(c).length();
            pq.push(f, Quadric::sphere(c, r));
        }
        pq
    }

    /// A ray at the benchmark's solid: from a point inside its bounds, or from the sphere
    /// of radius 3 around it, towards a point of its bounds (so that some graze it).
    fn random_ray(rng: &mut Pcg64, inside: bool) -> Ray {
        let o = if inside {
            DVec3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-0.7..0.7),
                rng.gen_range(-0.5..0.5),
            )
        } else {
            let a = rng.gen_range(0.0..std::f64::consts::TAU);
            let z = rng.gen_range(-1.0..1.0f64);
            3.0 * DVec3::new(
                (1.0 - z * z).sqrt() * a.cos(),
                (1.0 - z * z).sqrt() * a.sin(),
                z,
            )
        };
        let at = DVec3::new(
            rng.gen_range(-1.1..1.1),
            rng.gen_range(-0.8..0.8),
            rng.gen_range(-0.6..0.6),
        );
        Ray::new(o, at - o)
    }

    /// The ray-order scan (with its certain-sign skips) finds what the unordered scan
    /// finds, crossing after crossing along each ray: rays from outside at the solid and
    /// grazing it, and rays starting inside its bounds, at 16, 256 and 4096
    /// perturbations. Same hit or miss; |Δt| ≤ 1e-12 (the scans differ only in the order
    /// each piece sums its perturbations).
    #[test]
    fn ray_order_scan_agrees_with_the_unordered_scan() {
        let mut rng = Pcg64::seed_from_u64(10);
        for (n, r) in [(16, 0.3), (256, 0.08), (4096, 0.08)] {
            let s = bumpy(n, r).surface();
            let view = s.view();
            let (mut hits, mut rays) = (0, 0);
            for k in 0..1500 {
                let ray = random_ray(&mut rng, k % 4 == 0);
                let mut t = 0.0;
                for step in 0..8 {
                    let got = view.first_crossing(&ray, t, f64::INFINITY);
                    let want = view.unordered_first_crossing(&ray, t, f64::INFINITY);
                    rays += 1;
                    match (got, want) {
                        (Some(g), Some(w)) => {
                            assert!(
                                (g - w).abs() <= 1e-12,
                                "n {n} ray {k} step {step}: {g} vs {w}"
                            );
                            hits += 1;
                            t = w;
                        }
                        (None, None) => break,
                        _ => panic!("n {n} ray {k} step {step} from {t}: {got:?} vs {want:?}"),
                    }
                }
            }
            assert!(hits > 1000, "n {n}: {hits} crossings of {rays} queries");
        }
    }

    /// A shadow ray's answer (`crosses`, which stops at the first piece whose far end
    /// certainly has the other sign) is whether the full scan finds a crossing: rays at
    /// the solid and from inside its bounds, over their whole length and over stretches
    /// that start and end anywhere, at 16, 256 and 4096 perturbations.
    #[test]
    fn shadow_rays_see_what_the_scan_finds() {
        let mut rng = Pcg64::seed_from_u64(11);
        for (n, r) in [(16, 0.3), (256, 0.08), (4096, 0.08)] {
            let s = bumpy(n, r).surface();
            let view = s.view();
            let (mut hits, mut misses) = (0, 0);
            for k in 0..2000 {
                let ray = random_ray(&mut rng, k % 4 == 0);
                let t0 = if k % 3 == 0 {
                    0.0
                } else {
                    rng.gen_range(0.0..1.5)
                };
                let t1 = if k % 5 == 0 {
                    f64::INFINITY
                } else {
                    t0 + rng.gen_range(0.01..1.5)
                };
                let want = view.first_crossing(&ray, t0, t1).is_some();
                assert_eq!(
                    view.crosses(&ray, t0, t1),
                    want,
                    "n {n} ray {k}: {ray:?} in ({t0}, {t1})"
                );
                if want {
                    hits += 1;
                } else {
                    misses += 1;
                }
            }
            assert!(
                hits > 400 && misses > 400,
                "n {n}: {hits} hits, {misses} misses"
            );
        }
    }
}
