//! [`PerturbedSurface`]: a perturbed quadric prepared for ray intersection.
//!
//! A perturbation only acts inside its support q_i ≥ 0, so a BVH over the support boxes
//! hands each ray (and each point) only the perturbations it can touch; supports that
//! are not bounded ellipsoids are tested by every query. The crossing itself is the
//! exact piecewise-polynomial scan of [`super::scan`].

use super::along::{positive_set, q_local, q_local_f64, q_local_mag};
use super::ordered::{self, Quadratic};
use super::scan::{self, Coeffs};
use super::{Perturbation, PerturbedQuadric};
use crate::bvh::{Bvh, BvhRef};
use crate::quadric::Quadric;
use crate::ray::{slab_f32, Aabb, Ray};
use crate::surface::Surface;
use glam::{DVec3, Vec3};
use std::cmp::Ordering;

/// A bound on the magnitude of every term of q(o + t·d) for |t| ≤ `t`: Σ|c|·(1 +
/// |o|∞ + t·|d|∞)², each monomial of degree ≤ 2 in coordinates of at most that size.
/// The terms [`q_local`] sums are within a factor of a few of it: cruder than
/// [`q_local_mag`], at a fifth of its work, and 10⁻⁹ of it is still far above the
/// rounding of the sums (a few ε of them).
#[inline]
fn magnitude(c: &Coeffs<f64>, ray: &Ray, t: f64) -> f64 {
    let r = 1.0 + ray.o.abs().max_element() + t * ray.d.abs().max_element();
    c.iter().map(|v| v.abs()).sum::<f64>() * r * r
}

/// Whether the segment [lo, hi] of the ray may meet box `b` (a slab test with the
/// inverse direction `inv` given; true where the arithmetic is not conclusive).
#[inline]
fn may_meet(b: &Aabb, o: DVec3, inv: DVec3, lo: f64, hi: f64) -> bool {
    let (t1, t2) = ((b.lo - o) * inv, (b.hi - o) * inv);
    let near = t1.min(t2).max_element().max(lo);
    let far = t1.max(t2).min_element().min(hi);
    near.partial_cmp(&far) != Some(Ordering::Greater)
}

/// The most perturbations whose support boxes a shadow ray's certain miss
/// ([`PerturbedView::certainly_negative_within`]) tests one by one, not by the BVH.
const FEW_SUPPORTS: usize = 8;

/// An immutable perturbed quadric with a BVH over its perturbations' supports,
/// implementing [`Surface`] by exact root finding (RESEARCH.md §4).
#[derive(Clone, Debug)]
pub struct PerturbedSurface {
    base: Quadric,
    perturbations: Vec<Perturbation>,
    bvh: Bvh,
    bounds: Aabb,
}

impl PerturbedSurface {
    /// Prepares `pq`: builds the BVH over the support boxes
    /// ([`Quadric::support_bounds`]) of its perturbations.
    pub fn new(pq: &PerturbedQuadric) -> Self {
        let boxes: Vec<Aabb> = pq
            .perturbations()
            .iter()
            .map(|p| p.q.support_bounds())
            .collect();
        Self::with_boxes(pq, &boxes)
    }

    /// The same solid with no culling: every ray and point query tests every
    /// perturbation. For benchmarks and as a reference for what the BVH buys.
    pub fn unculled(pq: &PerturbedQuadric) -> Self {
        Self::with_boxes(pq, &vec![Aabb::EVERYTHING; pq.perturbations().len()])
    }

    fn with_boxes(pq: &PerturbedQuadric, boxes: &[Aabb]) -> Self {
        let mut bounds = pq.base().support_bounds();
        for p in pq.perturbations() {
            if p.f > 0.0 {
                bounds = bounds.union(&p.q.support_bounds());
            }
        }
        Self {
            base: *pq.base(),
            perturbations: pq.perturbations().to_vec(),
            bvh: Bvh::new(boxes),
            bounds,
        }
    }

    /// The base quadric F.
    pub fn base(&self) -> &Quadric {
        &self.base
    }

    /// The perturbations, indexed as the BVH's items.
    pub fn perturbations(&self) -> &[Perturbation] {
        &self.perturbations
    }

    /// The BVH over the perturbations' supports.
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// The solid as a borrowed view.
    pub fn view(&self) -> PerturbedView<'_> {
        PerturbedView {
            base: &self.base,
            perturbations: &self.perturbations,
            bvh: self.bvh.as_ref(),
            bounds: self.bounds,
        }
    }

    /// The first t in (t_min, t_max) where F' changes sign, in f32 (see
    /// [`PerturbedView::first_crossing_f32`]).
    pub fn first_crossing_f32(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        self.view().first_crossing_f32(o, d, t_min, t_max)
    }
}

/// A perturbed quadric over borrowed arrays: what [`PerturbedSurface`] and the flat
/// solids of [`crate::solid`] intersect. Perturbation k of the BVH is `perturbations[k]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerturbedView<'a> {
    /// The base quadric F.
    pub base: &'a Quadric,
    /// The perturbations.
    pub perturbations: &'a [Perturbation],
    /// The BVH over their supports.
    pub bvh: BvhRef<'a>,
    /// A box holding every point with F' ≥ 0 ([`PerturbedSurface::bounds`]).
    pub bounds: Aabb,
}

impl PerturbedView<'_> {
    /// The range [lo, hi] of [t_min, t_max] inside the bounds, and the sign of F' just
    /// after lo when known (−1 where the ray enters the bounds from outside, where F' < 0).
    fn clip(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, f64, f64)> {
        if t_min.is_nan() || t_max.is_nan() || t_min >= t_max || self.bounds.is_empty() {
            return None;
        }
        let (lo, hi) = self.bounds.clip(ray, t_min, t_max)?;
        Some((lo, hi, if lo > t_min { -1.0 } else { 0.0 }))
    }

    /// The first t in (t_min, t_max) where F' changes sign, computed in f32 throughout
    /// (RESEARCH.md §4 measures it): the CPU twin of the GPU kernel (GPU.md §6.1), which
    /// it equals bit for bit on lavapipe. See [`first_crossing_f32_gpu`](Self::first_crossing_f32_gpu).
    pub fn first_crossing_f32(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        self.first_crossing_f32_gpu(o, d, t_min, t_max).0
    }

    /// [`first_crossing_f32`](Self::first_crossing_f32), and whether the scan overflowed
    /// the kernel's capacities (more than [`GPU_ACTIVE`](super::GPU_ACTIVE) active perturbations after
    /// [`GPU_SPLITS`](super::GPU_SPLITS) halvings): there the CPU streams and still answers, while the
    /// kernel reports the ray as overflowing.
    ///
    /// Everything is the kernel's arithmetic: the clip to the bounds and the BVH walk use
    /// boxes rounded outward to f32 and the f32 slab test ([`crate::ray::slab_f32`]); each
    /// range is queried widened by an ulp at both ends; candidates come in pre-order
    /// ([`BvhRef::for_each_hit_f32`]), the order in which each piece sums them.
    pub fn first_crossing_f32_gpu(
        &self,
        o: Vec3,
        d: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> (Option<f32>, bool) {
        if t_min.is_nan() || t_max.is_nan() || t_min >= t_max || self.bounds.is_empty() {
            return (None, false);
        }
        let (o, d) = (o.to_array(), d.to_array());
        let inv = d.map(|v| 1.0 / v);
        let (blo, bhi) = self.bounds.outward_f32();
        let Some((lo, hi)) = slab_f32(blo, bhi, o, inv, t_min, t_max) else {
            return (None, false);
        };
        let sign = if lo > t_min { -1.0 } else { 0.0 };
        let src = F32 {
            perturbations: self.perturbations,
            bvh: self.bvh,
            o,
            inv,
        };
        scan::first_crossing_gpu::<f32, _>(
            &self.base.c.map(|v| v as f32),
            &src,
            o,
            d,
            (lo, hi),
            t_min,
            t_max,
            sign,
        )
    }

    /// F' at p, summing only the perturbations whose support box holds p.
    pub fn value(&self, p: DVec3) -> f64 {
        let mut v = self.base.eval(p);
        self.bvh.for_each_containing(p, |i| {
            let pt = &self.perturbations[i];
            let q = pt.q.eval(p);
            if q > 0.0 {
                v += pt.f * q * q * q;
            }
        });
        v
    }

    /// ∇F' = ∇F + Σ_{q_i>0} 3·f_i·q_i²·∇q_i (RESEARCH.md §4).
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        let mut g = self.base.gradient(p);
        self.bvh.for_each_containing(p, |i| {
            let pt = &self.perturbations[i];
            let q = pt.q.eval(p);
            if q > 0.0 {
                g += (3.0 * pt.f * q * q) * pt.q.gradient(p);
            }
        });
        g
    }

    /// The first t in (t_min, t_max) where F' changes sign (exact scan, no allocation).
    /// A plain quadric (no perturbations) takes the closed form instead.
    pub fn first_crossing(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        if self.perturbations.is_empty() {
            self.clip(ray, t_min, t_max)?;
            return quadric_first_crossing(&self.base.c, ray, t_min, t_max);
        }
        self.scan_first_crossing(ray, t_min, t_max, false)
    }

    /// Whether F' changes sign anywhere in (t_min, t_max) (shadow rays): the same as
    /// `first_crossing(..).is_some()`, without refining where the crossing is.
    pub fn crosses(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        if self.perturbations.is_empty() {
            return self.first_crossing(ray, t_min, t_max).is_some();
        }
        let Some((lo, hi, sign)) = self.clip(ray, t_min, t_max) else {
            return false;
        };
        // The base along the ray, which both checks read.
        let base = Quadratic::new(q_local(&self.base.c, ray.o.to_array(), ray.d.to_array()));
        if sign < 0.0 && self.certainly_positive_within(ray, &base, lo, hi) {
            return true;
        }
        if self.certainly_negative_within(ray, &base, lo, hi) {
            return false;
        }
        self.scan_first_crossing(ray, t_min, t_max, true).is_some()
    }

    /// Whether F' < 0 certainly all over [lo, hi], where it has no crossing: the base is
    /// below −10⁻⁹ of a bound on its terms' magnitudes there ([`magnitude`]: far above
    /// their rounding), and the ray meets the support box of no perturbation that adds
    /// material (the others only lower F'). Shadow rays that pass a solid's bounds by,
    /// or start in them away from its surface, are answered so without the scan.
    pub(super) fn certainly_negative_within(
        &self,
        ray: &Ray,
        base: &Quadratic,
        lo: f64,
        hi: f64,
    ) -> bool {
        let (_, top) = base.range(lo, hi);
        // (NaN and infinite ranges fail here.)
        let margin = 1e-9 * magnitude(&self.base.c, ray, lo.abs().max(hi.abs()));
        if top.partial_cmp(&-margin) != Some(Ordering::Less) {
            return false;
        }
        let adds = |i: u32| self.perturbations[i as usize].f > 0.0;
        let bvh = &self.bvh;
        if bvh.unbounded.iter().any(|&i| adds(i)) {
            return false;
        }
        // A few boxes are tested in turn; more take the BVH.
        if bvh.order.len() <= FEW_SUPPORTS {
            let inv = ray.d.recip();
            return !bvh
                .order
                .iter()
                .zip(bvh.item_bounds)
                .any(|(&i, b)| adds(i) && may_meet(b, ray.o, inv, lo, hi));
        }
        let mut met = false;
        bvh.for_each_hit(ray, lo, hi, |i| met |= adds(i as u32));
        !met
    }

    /// Whether F' is certainly positive somewhere in (lo, hi): at the middle of the
    /// first interval there where the base is positive. A ray entering the bounds at lo
    /// starts with F' < 0, so F' then has a root of odd order between (continuity), the
    /// crossing the exact scan would find: most shadow rays through a solid are answered
    /// without it. F' is summed along the ray, each quadric as its quadratic in t about
    /// the ray's origin ([`q_local`]), and counts as positive only above 10⁻⁹ of the
    /// magnitudes of its terms ([`q_local_mag`]), far above their rounding (a few ε of
    /// them) and above what a perturbation whose support box just misses the rounded
    /// point could add (its q there is within rounding of 0, and enters cubed).
    pub(super) fn certainly_positive_within(
        &self,
        ray: &Ray,
        base: &Quadratic,
        lo: f64,
        hi: f64,
    ) -> bool {
        let (o, d) = (ray.o.to_array(), ray.d.to_array());
        let at = ordered::quadratic_at;
        let (set, m) = positive_set(base.a);
        let Some(t) = set[..m]
            .iter()
            .map(|&(a, b)| (a.max(lo), b.min(hi)))
            .find(|&(a, b)| a < b)
            .map(|(a, b)| 0.5 * (a + b))
            .filter(|t| t.is_finite() && *t > lo && *t < hi)
        else {
            return false;
        };
        let mut value = base.at(t);
        let mut mag = at(q_local_mag(&self.base.c, o, d), t.abs());
        self.bvh.for_each_containing(ray.at(t), |i| {
            let p = &self.perturbations[i];
            let q = at(q_local(&p.q.c, o, d), t);
            let qm = at(q_local_mag(&p.q.c, o, d), t.abs());
            if q > 0.0 {
                value += p.f * q * q * q;
            }
            mag += p.f.abs() * qm * qm * qm;
        });
        value > 1e-9 * mag
    }

    /// [`Self::first_crossing`] by the scan, whatever the perturbations: in ray order
    /// ([`ordered`]), or where that defers, over the unordered BVH query. With `any`,
    /// a crossing's t is only somewhere past it ([`ordered::first_crossing`]).
    fn scan_first_crossing(&self, ray: &Ray, t_min: f64, t_max: f64, any: bool) -> Option<f64> {
        let (lo, hi, sign) = self.clip(ray, t_min, t_max)?;
        let base: &Coeffs<f64> = &self.base.c;
        let (perturbations, bvh) = (self.perturbations, self.bvh);
        let range = (lo, hi);
        ordered::first_crossing(
            base,
            perturbations,
            bvh,
            ray,
            range,
            t_min,
            t_max,
            sign,
            any,
        )
        .unwrap_or_else(|| self.unordered_first_crossing(ray, t_min, t_max))
    }

    /// The scan over every support the ray meets in [lo, hi], collected up front: the
    /// ray-order scan's fallback, and its reference in the tests.
    pub(super) fn unordered_first_crossing(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<f64> {
        let (lo, hi, sign) = self.clip(ray, t_min, t_max)?;
        let src = Supports {
            perturbations: self.perturbations,
            bvh: self.bvh,
            ray,
        };
        scan::first_crossing(
            &self.base.c,
            &src,
            ray.o.to_array(),
            ray.d.to_array(),
            (lo, hi),
            t_min,
            t_max,
            sign,
        )
    }
}

/// The first simple root of the quadric along the ray in (t_min, t_max): the least end of
/// its positive set there ([`positive_set`]: stable quadratic formula; a double root is a
/// touch, not a crossing). Planes, boxes and plain quadrics need no Bernstein scan. The
/// quadratic is expanded about the ray's origin whatever t_min is, so that a walk from
/// one root to the next (t_min = the last root) never finds the same root again.
fn quadric_first_crossing(c: &Coeffs<f64>, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
    let (set, n) = positive_set(q_local_f64(c, ray.o.to_array(), ray.d.to_array()));
    set[..n]
        .iter()
        .flat_map(|&(a, b)| [a, b])
        .filter(|&t| t > t_min && t < t_max && t.is_finite())
        .min_by(f64::total_cmp)
}

/// The perturbations whose support box the ray meets on a part of [lo, hi], nearer BVH
/// subtrees first, read straight from the BVH walk (nothing is collected).
struct Supports<'a> {
    perturbations: &'a [Perturbation],
    bvh: BvhRef<'a>,
    ray: &'a Ray,
}

impl scan::Source<f64> for Supports<'_> {
    #[inline]
    fn for_each(&self, lo: f64, hi: f64, mut visit: impl FnMut(f64, &Coeffs<f64>)) {
        self.bvh.for_each_hit(self.ray, lo, hi, |i| {
            let p = &self.perturbations[i];
            visit(p.f, &p.q.c)
        });
    }
}

/// The perturbations rounded to f32 whose f32 support box the ray meets, walked as the
/// GPU kernel walks them (the source of [`PerturbedView::first_crossing_f32_gpu`]).
struct F32<'a> {
    perturbations: &'a [Perturbation],
    bvh: BvhRef<'a>,
    o: [f32; 3],
    inv: [f32; 3],
}

impl scan::Source<f32> for F32<'_> {
    #[inline]
    fn for_each(&self, lo: f32, hi: f32, mut visit: impl FnMut(f32, &Coeffs<f32>)) {
        // Widened by an ulp each way, so that a box the rounded range ends touch is kept.
        let (lo, hi) = (lo.next_down(), hi.next_up());
        self.bvh.for_each_hit_f32(self.o, self.inv, lo, hi, |i| {
            let p = &self.perturbations[i];
            visit(p.f as f32, &p.q.c.map(|v| v as f32))
        });
    }
}

impl Surface for PerturbedSurface {
    /// F' at p, summing only the perturbations whose support box holds p.
    fn value(&self, p: DVec3) -> f64 {
        self.view().value(p)
    }

    /// ∇F' = ∇F + Σ_{q_i>0} 3·f_i·q_i²·∇q_i (RESEARCH.md §4).
    fn gradient(&self, p: DVec3) -> DVec3 {
        self.view().gradient(p)
    }

    fn first_crossing(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        self.view().first_crossing(ray, t_min, t_max)
    }

    fn any_crossing(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        self.view().crosses(ray, t_min, t_max)
    }

    /// The base's support box united with the support boxes of every perturbation that
    /// adds material (f_i > 0): outside them F < 0 and every term f_i·r_i ≤ 0.
    fn bounds(&self) -> Aabb {
        self.bounds
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transform::Affine;

    fn ball() -> Quadric {
        Quadric::sphere(DVec3::ZERO, 1.0)
    }

    /// The roots of the quadratic a0 + a1·t + a2·t² in (t_min, t_max), ascending.
    fn quadratic_roots(a: [f64; 3], t_min: f64, t_max: f64) -> Vec<f64> {
        let [c, b, a] = a;
        let disc = b * b - 4.0 * a * c;
        let mut r = if a == 0.0 {
            vec![-c / b]
        } else if disc > 0.0 {
            vec![
                (-b - disc.sqrt()) / (2.0 * a),
                (-b + disc.sqrt()) / (2.0 * a),
            ]
        } else {
            vec![]
        };
        r.sort_by(f64::total_cmp);
        r.retain(|&t| t > t_min && t < t_max);
        r
    }

    #[test]
    fn unperturbed_quadrics_give_their_closed_form_roots() {
        let axis = DVec3::new(0.3, 1.0, -0.2);
        let quadrics = [
            ball(),
            Quadric::ellipsoid(DVec3::new(0.1, 0.2, -0.3), DVec3::new(0.5, 1.2, 0.8)),
            Quadric::cylinder(DVec3::new(0.0, 0.1, 0.0), axis, 0.7),
            Quadric::cone(DVec3::ZERO, axis, 0.5),
            Quadric::paraboloid(DVec3::new(0.0, -1.0, 0.0), axis, 1.5),
            Quadric::plane(DVec3::new(0.2, 0.9, 0.1), 0.3),
        ];
        let mut checked = 0;
        for q in quadrics {
            let s = PerturbedQuadric::new(q).surface();
            for k in 0..400 {
                let a = k as f64 * 0.7;
                let o = DVec3::new(3.0 * a.cos(), 1.5 * (0.3 * a).sin(), 3.0 * a.sin());
                let d =
                    (DVec3::new(0.2 * (1.3 * a).cos(), 0.3 * (0.9 * a).sin(), 0.1) - o).normalize();
                let ray = Ray::new(o, d);
                for (t_min, t_max) in [(0.0, f64::INFINITY), (-5.0, 4.0), (3.1, 3.5)] {
                    let a = q.along(o, d);
                    let want = quadratic_roots(a, t_min, t_max).first().copied();
                    // The closed form `first_crossing` takes, and the general scan.
                    let got = s.first_crossing(&ray, t_min, t_max);
                    let scanned = s.view().scan_first_crossing(&ray, t_min, t_max, false);
                    for (how, got) in [("closed form", got), ("scan", scanned)] {
                        match (got, want) {
                            (Some(g), Some(w)) => {
                                // Rounding of the quadratic's terms over its slope.
                                let terms =
                                    1.0 + a[0].abs() + (a[1] * w).abs() + (a[2] * w * w).abs();
                                let tol = 1e-14 * terms / (a[1] + 2.0 * a[2] * w).abs();
                                assert!((g - w).abs() < tol, "{how} {q:?}: {g} vs {w}, tol {tol}")
                            }
                            (None, None) => {}
                            _ => panic!(
                                "{how} {q:?} {ray:?} [{t_min}, {t_max}]: {got:?} vs {want:?}"
                            ),
                        }
                    }
                    checked += got.is_some() as usize;
                }
            }
        }
        assert!(checked > 1000, "{checked}");
    }

    /// A shadow ray is answered without the scan only as the scan answers it: crossed
    /// where it enters the bounds and F' is certainly positive inside, missed where F'
    /// is certainly negative all along; and most rays are answered so. The solids put
    /// F' < 0 or F' ≈ 0 where the base's chord has its middle: a ball hollowed by a dent
    /// at its centre, a ball whose dent cancels the base exactly at its centre (F' = 0
    /// there, > 0 around it), a ball with a bite taken out (rays through the bite meet
    /// the base only where the dent removes it), and a ball with bumps and dents on its
    /// surface.
    #[test]
    fn shadow_rays_through_a_solid_are_certain_only_where_the_scan_crosses() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(12);
        let hollow = {
            let mut pq = PerturbedQuadric::new(ball());
            pq.push(-8.0, Quadric::sphere(DVec3::ZERO, 0.7));
            pq
        };
        // F' = 1 − r² − ((0.49 − r²)/0.49)³ within r < 0.7: 0 at r = 0.
        let cancelling = {
            let mut pq = PerturbedQuadric::new(ball());
            pq.push(-1.0 / 0.7f64.powi(6), Quadric::sphere(DVec3::ZERO, 0.7));
            pq
        };
        let bitten = {
            let mut pq = PerturbedQuadric::new(ball());
            pq.push(-40.0, Quadric::sphere(DVec3::new(0.9, 0.0, 0.0), 0.8));
            pq
        };
        let bumpy = {
            let mut pq = PerturbedQuadric::new(ball());
            for k in 0..12 {
                let a = k as f64 * 0.52;
                let c = DVec3::new(a.cos(), a.sin(), (k as f64 * 0.3).sin()).normalize();
                pq.push(
                    if k % 2 == 0 { 0.6 } else { -0.6 },
                    Quadric::sphere(c, 0.35),
                );
            }
            pq
        };
        let solids = [
            ("bitten", bitten, DVec3::new(0.9, 0.0, 0.0)),
            ("hollow", hollow, DVec3::ZERO),
            ("cancelling", cancelling, DVec3::ZERO),
            ("bumpy", bumpy, DVec3::ZERO),
        ];
        for (name, pq, aim) in solids {
            let s = PerturbedSurface::new(&pq);
            let view = s.view();
            let (mut crossed, mut certain, mut missed, mut rays) = (0, 0, 0, 0);
            for k in 0..4000 {
                let dir = |rng: &mut rand_pcg::Pcg64| {
                    DVec3::new(
                        rng.gen_range(-1.0..1.0),
                        rng.gen_range(-1.0..1.0),
                        rng.gen_range(-1.0..1.0),
                    )
                };
                let o = 3.0 * dir(&mut rng).normalize();
                // Through the neighbourhood of `aim`, or anywhere at the ball.
                let at = match k % 2 == 0 {
                    true => aim + 0.3 * dir(&mut rng),
                    false => 1.2 * dir(&mut rng),
                };
                // Every fifth ray starts inside the bounds (outside or inside the solid).
                let o = match k % 5 == 4 {
                    true => 1.1 * dir(&mut rng),
                    false => o,
                };
                let ray = Ray::new(o, (at - o).normalize());
                let t_max = if k % 3 == 0 {
                    rng.gen_range(1.0..4.0)
                } else {
                    f64::INFINITY
                };
                let Some((lo, hi, sign)) = view.clip(&ray, 0.0, t_max) else {
                    continue;
                };
                let scan = view.first_crossing(&ray, 0.0, t_max).is_some();
                crossed += scan as usize;
                rays += 1;
                let (o, d) = (ray.o.to_array(), ray.d.to_array());
                let base = Quadratic::new(q_local(&view.base.c, o, d));
                if sign < 0.0 && view.certainly_positive_within(&ray, &base, lo, hi) {
                    assert!(
                        scan,
                        "{name} ray {k}: {ray:?} to {t_max} certain, scan none"
                    );
                    certain += 1;
                }
                if view.certainly_negative_within(&ray, &base, lo, hi) {
                    assert!(
                        !scan,
                        "{name} ray {k}: {ray:?} to {t_max} certain miss, scan hit"
                    );
                    missed += 1;
                }
                assert_eq!(view.crosses(&ray, 0.0, t_max), scan, "{name} ray {k}");
            }
            // The hollow and cancelling balls' chords through the centre have their
            // middle where F' ≤ 0: only the others are certain.
            assert!(crossed > 1500, "{name}: {crossed} crossed");
            assert!(
                certain > crossed / 4 && certain < crossed,
                "{name}: {certain} certain of {crossed} crossed"
            );
            assert!(
                missed > (rays - crossed) / 4 && missed < rays - crossed,
                "{name}: {missed} certain misses of {} missed",
                rays - crossed
            );
        }
    }

    #[test]
    fn rays_from_inside_leave_and_repeated_calls_walk_every_crossing() {
        // A ball hollowed by a strong negative perturbation at its centre: the ray along
        // x meets the surface four times.
        let solid = PerturbedQuadric::new(ball()).with(-200.0, Quadric::sphere(DVec3::ZERO, 0.5));
        let s = solid.surface();
        let ray = Ray::new(DVec3::new(-3.0, 0.0, 0.0), DVec3::X);
        let mut t = 0.0;
        let mut hits = Vec::new();
        while let Some(h) = s.first_crossing(&ray, t, f64::INFINITY) {
            assert!(h > t);
            hits.push(h);
            t = h;
        }
        assert_eq!(hits.len(), 4, "{hits:?}");
        // The crossings alternate in, out, in, out, and the solid's value agrees.
        for (k, &h) in hits.iter().enumerate() {
            assert!(solid.eval(ray.at(h)).abs() < 1e-9);
            let inside_after = solid.eval(ray.at(h + 1e-6)) > 0.0;
            assert_eq!(inside_after, k % 2 == 0);
        }
        // Starting inside the shell (between the first two crossings).
        let mid = 0.5 * (hits[0] + hits[1]);
        let from_inside = Ray::new(ray.at(mid), DVec3::X);
        let exit = s.first_crossing(&from_inside, 0.0, f64::INFINITY).unwrap();
        assert!((exit - (hits[1] - mid)).abs() < 1e-9);
    }

    #[test]
    fn unbounded_base_with_infinite_range_finds_far_crossings() {
        // The plane y = 0 (solid below) with a bump: a nearly parallel ray from above
        // crosses the plane a million units away; with t_min = −∞ it also has a crossing
        // behind its origin.
        let bumps = PerturbedQuadric::new(Quadric::plane(DVec3::Y, 0.0))
            .with(10.0, Quadric::sphere(DVec3::new(1.0, 0.0, 0.0), 0.5));
        let s = bumps.surface();
        assert_eq!(s.bounds(), Aabb::EVERYTHING);
        let ray = Ray::new(DVec3::new(-2.0, 1.0, 0.3), DVec3::new(1.0, -1e-6, 0.0));
        let t = s.first_crossing(&ray, 0.0, f64::INFINITY).unwrap();
        assert!((t - 1e6).abs() < 1e-6, "{t}");
        let up = Ray::new(DVec3::new(5.0, 1.0, 0.0), DVec3::new(0.0, 1.0, 0.0));
        assert_eq!(s.first_crossing(&up, 0.0, f64::INFINITY), None);
        let t = s
            .first_crossing(&up, f64::NEG_INFINITY, f64::INFINITY)
            .unwrap();
        assert!((t + 1.0).abs() < 1e-12, "{t}");
        // Straight down through the bump: F' = −y + 10·(1 − 4y²)³ on the axis (the
        // sphere helper is 1 − |x − c|²/r²).
        let down = Ray::new(DVec3::new(1.0, 2.0, 0.0), -DVec3::Y);
        let t = s
            .first_crossing(&down, f64::NEG_INFINITY, f64::INFINITY)
            .unwrap();
        let y = 2.0 - t;
        assert!(
            (-y + 10.0 * (1.0 - 4.0 * y * y).powi(3)).abs() < 1e-12,
            "y = {y}"
        );
        assert!(y > 0.0);
    }

    /// The f32 scan over a left-unbounded range: the plane y = 0 with a half-space
    /// perturbation growing as (−3 − x)³ meets a slanted ray 1 633 units behind its
    /// origin; Cauchy's bound there makes sub-pieces millions of units long, whose h⁶
    /// overflows f32 (the scan used to give up there and answer a miss).
    #[test]
    fn f32_scan_finds_far_crossings_of_unbounded_ranges() {
        let pq = PerturbedQuadric::new(Quadric::plane(DVec3::Y, 0.0))
            .with(-1e-3, Quadric::plane(DVec3::X, -3.0));
        let s = pq.surface();
        let (o, d) = (
            Vec3::new(0.964_901_57, -0.191_183_48, -2.828_187_5),
            Vec3::new(0.034_240_786, 0.085_781_8, 0.995_725_4),
        );
        let ray = Ray::new(o.as_dvec3(), d.as_dvec3());
        let t64 = s.first_crossing(&ray, f64::NEG_INFINITY, 8.0).unwrap();
        let t32 = s.first_crossing_f32(o, d, f32::NEG_INFINITY, 8.0).unwrap();
        assert!((t64 + 1633.353).abs() < 1e-2, "{t64}");
        assert!(
            (f64::from(t32) - t64).abs() < 1e-4 * t64.abs(),
            "{t32} vs {t64}"
        );
    }

    #[test]
    fn value_gradient_and_bounds_agree_with_the_definition() {
        let mut pq =
            PerturbedQuadric::new(Quadric::ellipsoid(DVec3::ZERO, DVec3::new(1.0, 0.7, 0.5)));
        for k in 0..40 {
            let a = k as f64 * 2.4;
            let c = DVec3::new(
                a.cos() * (0.4 * a).cos(),
                0.7 * a.sin(),
                0.5 * (0.4 * a).sin(),
            );
            let f = if k % 3 == 0 { -30.0 } else { 50.0 };
            pq.push(f, Quadric::sphere(c, 0.2 + 0.01 * k as f64));
        }
        let s = pq.surface();
        let b = s.bounds();
        for i in 0..4000 {
            let u = i as f64;
            let p = 1.4 * DVec3::new((0.37 * u).sin(), (0.71 * u).cos(), (1.13 * u).sin());
            assert!((s.value(p) - pq.eval(p)).abs() < 1e-12 * (1.0 + pq.eval(p).abs()));
            let h = 1e-6;
            let fd = DVec3::new(
                pq.eval(p + DVec3::X * h) - pq.eval(p - DVec3::X * h),
                pq.eval(p + DVec3::Y * h) - pq.eval(p - DVec3::Y * h),
                pq.eval(p + DVec3::Z * h) - pq.eval(p - DVec3::Z * h),
            ) / (2.0 * h);
            let g = s.gradient(p);
            assert!((g - fd).length() < 1e-6 * (1.0 + g.length()), "{g} vs {fd}");
            if pq.eval(p) >= 0.0 {
                assert!(b.contains(p));
            }
        }
    }

    #[test]
    fn transformed_solid_meets_the_transformed_ray_at_the_same_t() {
        let pq = PerturbedQuadric::new(ball())
            .with(40.0, Quadric::sphere(DVec3::new(0.0, 1.0, 0.0), 0.4))
            .with(-40.0, Quadric::sphere(DVec3::new(1.0, 0.0, 0.0), 0.3));
        let a = Affine::scale(DVec3::new(2.0, 1.0, 0.5))
            .then(&Affine::rotate(DVec3::new(1.0, 1.0, 0.0), 0.7))
            .then(&Affine::translate(DVec3::new(0.5, -1.0, 3.0)));
        let moved = pq.transformed(&a).unwrap().surface();
        let s = pq.surface();
        for k in 0..200 {
            let u = k as f64 * 0.31;
            let o = DVec3::new(3.0 * u.cos(), 2.0 * u.sin(), 0.5);
            let d = -o + 0.3 * DVec3::new(u.sin(), 0.0, u.cos());
            let ray = Ray::new(o, d);
            let moved_ray = Ray::new(a.point(o), a.m * d);
            let (t0, t1) = (
                s.first_crossing(&ray, 0.0, f64::INFINITY),
                moved.first_crossing(&moved_ray, 0.0, f64::INFINITY),
            );
            assert_eq!(t0.is_some(), t1.is_some());
            if let (Some(t0), Some(t1)) = (t0, t1) {
                assert!((t0 - t1).abs() < 1e-9, "{t0} vs {t1}");
            }
        }
        assert!(pq.transformed(&Affine::scale(DVec3::ZERO)).is_none());
    }
}
