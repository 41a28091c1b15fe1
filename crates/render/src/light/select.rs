//! Light selection: how a light technique picks one of the *MIS lights* (the area
//! lights, then the environment) before sampling it, and the mixture density that
//! results.
//!
//! Every strategy samples the chosen light the same way ([`AreaLight::sample_li`], or
//! the environment's own sampling), so a strategy is only its selection pmf `P(k | x)`,
//! and its density of a direction ω at the shading point x is the mixture
//! `p(ω) = Σ_k P(k | x) · p_k(ω)` over every light the direction meets (lights behind
//! lights included), as MIS needs (Veach 1997, §9.2). Per draw and per pmf, uniform
//! selection costs O(1), power selection O(log n) and O(1), the light BVH and the trained
//! table O(log n), the spatial selection O(n) (it sums every light's importance).

use super::importance_pair::importance_pair;
use super::{AreaLight, LightHit, LightSample, Lights, Shape, TrainedSelection};
use crate::color::luminance;
use crate::warp::safe_sqrt;
use frep::Ray;
use glam::{DVec2, DVec3};
use state::Technique;

/// A light-selection pmf.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Selection<'a> {
    /// ∝ luminance of power (the environment's from the scene radius, pbrt-v4 §12.5).
    Power,
    /// Uniform over the MIS lights.
    Uniform,
    /// ∝ [`importance`] at the shading point (pbrt-v4's BVH light sampler without the
    /// BVH): the environment, if any, with probability ½ (pbrt-v4's share for infinite
    /// lights), the area lights with the rest ∝ their importance.
    Spatial,
    /// ∝ the same importance, drawn from the light BVH ([`super::LightTree`]): O(log n)
    /// per draw and per pmf, where [`Selection::Spatial`] sums over every light. The
    /// environment as there.
    Bvh,
    /// MIS light k alone.
    One(usize),
    /// The trained table's pmf at the shading point ([`TrainedSelection`]); no light
    /// when the table covers another number of lights.
    Trained(&'a TrainedSelection),
}

/// `cos(max(0, θa − θb))` from the sines and cosines of θa and θb (pbrt-v4
/// `CosSubClamped`).
fn cos_sub_clamped(sin_a: f64, cos_a: f64, sin_b: f64, cos_b: f64) -> f64 {
    if cos_a > cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

/// `sin(max(0, θa − θb))` (pbrt-v4 `SinSubClamped`).
fn sin_sub_clamped(sin_a: f64, cos_a: f64, sin_b: f64, cos_b: f64) -> f64 {
    if cos_a > cos_b {
        0.0
    } else {
        sin_a * cos_b - cos_a * sin_b
    }
}

/// A bound on the unoccluded contribution of area light `l` at point `p` with normal
/// `n` (zero inside a medium; pbrt-v4 `LightBounds::Importance`, §12.6.3): `Φ · cos θ' · cos θi' / d²`, with
/// Φ the luminance of the light's power, d the distance to the centre of its bounding
/// sphere (at least the sphere's radius), θ' the smallest angle between the light's
/// normal cone and a direction from the light toward p, and θi' the smallest angle
/// between ±n and a direction from p into the bounding sphere. It is 0 only where the
/// light cannot shine on p (p behind a one-sided planar light). Unlike pbrt-v4 (a box
/// and `|diagonal|/2` as the least distance), the bound uses the light's bounding
/// sphere and its radius squared.
pub fn importance(l: &AreaLight, p: DVec3, n: DVec3) -> f64 {
    importance_of(&l.importance_bounds(), luminance(l.power()), p, n)
}

/// [`importance`] of anything bounded by `b` with power of luminance `phi`: a light, or
/// a node of the light BVH ([`super::LightTree`]).
#[inline]
pub fn importance_of(b: &ImportanceBounds, phi: f64, p: DVec3, n: DVec3) -> f64 {
    let ImportanceBounds {
        center,
        radius,
        axis,
        cos_o,
        two_sided,
    } = *b;
    let v = p - center;
    let dist2 = v.length_squared();
    let d2 = dist2.max(radius * radius);
    let w = if dist2 > 0.0 { v / dist2.sqrt() } else { axis };
    let mut cos_w = axis.dot(w);
    if two_sided {
        cos_w = cos_w.abs();
    }
    let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
    // The cone of directions from p into the bounding sphere: cos θb.
    let cos_b = if dist2 <= radius * radius {
        -1.0
    } else {
        safe_sqrt(1.0 - radius * radius / dist2)
    };
    let sin_b = safe_sqrt(1.0 - cos_b * cos_b);
    let sin_o = safe_sqrt(1.0 - cos_o * cos_o);
    let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, cos_o);
    let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, cos_o);
    let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if cos_p <= 0.0 {
        return 0.0;
    }
    // No normal (a point inside a medium): no cosine to bound (pbrt-v4 likewise).
    let cos_ip = if n == DVec3::ZERO {
        1.0
    } else {
        let cos_i = n.dot(w).abs();
        let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
        cos_sub_clamped(sin_i, cos_i, sin_b, cos_b)
    };
    (phi * cos_p * cos_ip / d2).max(0.0)
}

/// What [`importance`] bounds a light by: its bounding sphere, and its normal cone
/// (axis and cos θo, the spread of its normals; cos θe = 0 for every shape), counted on
/// both sides for two-sided planar lights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImportanceBounds {
    /// Centre of the bounding sphere.
    pub center: DVec3,
    /// Its radius.
    pub radius: f64,
    /// Axis of the normal cone.
    pub axis: DVec3,
    /// cos θo.
    pub cos_o: f64,
    /// Whether the cone counts on both sides.
    pub two_sided: bool,
}

impl AreaLight {
    /// The bounds [`importance`] reads (module docs).
    pub fn importance_bounds(&self) -> ImportanceBounds {
        let (center, radius, axis, cos_o, two_sided) = match self.shape {
            Shape::Sphere { center, radius } => (center, radius, DVec3::Z, -1.0, false),
            Shape::Rect {
                corner,
                edge_u,
                edge_v,
            } => (
                corner + (edge_u + edge_v) / 2.0,
                (edge_u + edge_v).length().max((edge_u - edge_v).length()) / 2.0,
                edge_u.cross(edge_v).normalize(),
                1.0,
                self.two_sided,
            ),
            Shape::Disk {
                center,
                normal,
                radius,
            } => (center, radius, normal, 1.0, self.two_sided),
            Shape::Triangle { p0, e1, e2 } => {
                let c = p0 + (e1 + e2) / 3.0;
                let r = [p0, p0 + e1, p0 + e2]
                    .iter()
                    .map(|v| v.distance(c))
                    .fold(0.0, f64::max);
                (c, r, e1.cross(e2).normalize(), 1.0, self.two_sided)
            }
        };
        ImportanceBounds {
            center,
            radius,
            axis,
            cos_o,
            two_sided,
        }
    }
}

impl Lights {
    /// The number of MIS lights: area lights, then the environment.
    pub fn count(&self) -> usize {
        self.area.len() + usize::from(self.environment.is_some())
    }

    /// Σ over area lights of [`importance`] at (p, n).
    pub(super) fn importance_total(&self, p: DVec3, n: DVec3) -> f64 {
        // Two lights at a time, summed in order: the same sum bit for bit.
        let mut sum = 0.0;
        let mut pairs = self.importance.chunks_exact(2);
        for pair in &mut pairs {
            let [(a, phi_a), (b, phi_b)] = [pair[0], pair[1]];
            let [wa, wb] = importance_pair((&a, phi_a), (&b, phi_b), p, n);
            sum += wa;
            sum += wb;
        }
        for (b, phi) in pairs.remainder() {
            sum += importance_of(b, *phi, p, n);
        }
        sum
    }

    /// [`importance`] of area light `k`, from its bounds found once.
    #[inline]
    fn importance_of_light(&self, k: usize, p: DVec3, n: DVec3) -> f64 {
        let (b, phi) = &self.importance[k];
        importance_of(b, *phi, p, n)
    }

    /// The probability of the environment under [`Selection::Spatial`].
    fn spatial_env(&self) -> f64 {
        match (self.environment.is_some(), self.area.is_empty()) {
            (false, _) => 0.0,
            (true, true) => 1.0,
            (true, false) => 0.5,
        }
    }

    /// P(MIS light k | p, n) under `sel` (`total`: [`Self::importance_total`], for
    /// [`Selection::Spatial`]).
    #[inline]
    pub(super) fn pmf_with(
        &self,
        sel: Selection<'_>,
        p: DVec3,
        n: DVec3,
        k: usize,
        total: f64,
    ) -> f64 {
        let count = self.count();
        if k >= count {
            return 0.0;
        }
        match sel {
            Selection::Power => self.by_power.as_ref().map_or(0.0, |d| d.pmf(k)),
            Selection::Uniform => 1.0 / count as f64,
            Selection::One(j) => f64::from(u8::from(j == k)),
            Selection::Trained(t) if t.lights() == count => t.pmf(p, k),
            Selection::Trained(_) => 0.0,
            Selection::Spatial => {
                let pe = self.spatial_env();
                if k == self.area.len() {
                    pe
                } else if total > 0.0 {
                    (1.0 - pe) * self.importance_of_light(k, p, n) / total
                } else {
                    0.0
                }
            }
            Selection::Bvh => {
                let pe = self.spatial_env();
                match &self.tree {
                    _ if k == self.area.len() => pe,
                    Some(tree) => (1.0 - pe) * tree.pmf(p, n, k),
                    None => 0.0,
                }
            }
        }
    }

    /// P(MIS light k | p, n) under `sel`.
    pub fn selection_pmf(&self, sel: Selection<'_>, p: DVec3, n: DVec3, k: usize) -> f64 {
        let total = match sel {
            Selection::Spatial => self.importance_total(p, n),
            _ => 0.0,
        };
        self.pmf_with(sel, p, n, k, total)
    }

    /// Picks a MIS light with `uc` under `sel` at (p, n); None when no light has
    /// probability there.
    fn select(&self, sel: Selection<'_>, p: DVec3, n: DVec3, uc: f64) -> Option<usize> {
        let count = self.count();
        if count == 0 {
            return None;
        }
        match sel {
            Selection::Power => Some(self.by_power.as_ref()?.sample_discrete(uc).0),
            Selection::Uniform => Some(((uc * count as f64) as usize).min(count - 1)),
            Selection::One(k) => (k < count).then_some(k),
            Selection::Trained(t) => {
                if t.lights() != count {
                    return None;
                }
                Some(t.select(p, uc))
            }
            Selection::Bvh => {
                let pe = self.spatial_env();
                if uc < pe {
                    return Some(self.area.len());
                }
                let u = ((uc - pe) / (1.0 - pe)).min(crate::distribution::ONE_MINUS_EPSILON);
                self.tree.as_ref()?.sample(p, n, u).map(|(k, _)| k)
            }
            Selection::Spatial => {
                let pe = self.spatial_env();
                if uc < pe {
                    return Some(self.area.len());
                }
                let total = self.importance_total(p, n);
                if total.is_nan() || total <= 0.0 {
                    return None;
                }
                // Walk the lights again to the one `uc` falls in (no allocation).
                let target = (uc - pe) / (1.0 - pe) * total;
                let mut acc = 0.0;
                let mut last = None;
                for i in 0..self.area.len() {
                    let w = self.importance_of_light(i, p, n);
                    if w > 0.0 {
                        acc += w;
                        last = Some(i);
                        if target < acc {
                            return Some(i);
                        }
                    }
                }
                last
            }
        }
    }

    /// The density of MIS light `k`'s own sampling at direction `wi` from `p`.
    pub(crate) fn pdf_one(&self, p: DVec3, k: usize, wi: DVec3) -> f64 {
        if k == self.area.len() {
            self.environment.as_ref().map_or(0.0, |e| e.pdf(wi))
        } else {
            self.area[k].pdf_li(p, wi)
        }
    }

    /// Light sampling under `sel`: a MIS light chosen with `uc`, then its own sampling
    /// with `u`; the pdf is [`Self::pdf_selected`], the mixture over every light.
    pub fn sample_selected(
        &self,
        sel: Selection<'_>,
        p: DVec3,
        n: DVec3,
        uc: f64,
        u: DVec2,
    ) -> Option<LightSample> {
        let mut s = self.draw_selected(sel, p, n, uc, u)?;
        s.pdf = self.pdf_selected(sel, p, n, s.wi);
        (s.pdf > 0.0 && s.pdf.is_finite()).then_some(s)
    }

    /// [`Self::sample_selected`]'s direction without its mixture pdf (NaN), for a
    /// caller that evaluates every technique's pdf at the direction anyway: the walk
    /// over the lights it crosses is then done once, not twice.
    pub fn draw_selected(
        &self,
        sel: Selection<'_>,
        p: DVec3,
        n: DVec3,
        uc: f64,
        u: DVec2,
    ) -> Option<LightSample> {
        let i = self.select(sel, p, n, uc)?;
        let s = if i == self.area.len() {
            self.env_sample(u)?
        } else {
            LightSample {
                light: Some(i),
                ..self.area[i].sample_li(p, u)?
            }
        };
        Some(LightSample { pdf: f64::NAN, ..s })
    }

    /// Σ_k P(k | p, n) · p_k(wi) over the MIS lights: the density of
    /// [`Self::sample_selected`].
    pub fn pdf_selected(&self, sel: Selection<'_>, p: DVec3, n: DVec3, wi: DVec3) -> f64 {
        self.pdf_selected_over(sel, p, n, wi, None)
    }

    /// [`Self::pdf_selected`] over the lights `crossed` lists (None: found by the BVH
    /// here). The same terms in the same order: the same value bit for bit.
    pub fn pdf_selected_over(
        &self,
        sel: Selection<'_>,
        p: DVec3,
        n: DVec3,
        wi: DVec3,
        crossed: Option<&Crossed>,
    ) -> f64 {
        if let Selection::One(k) = sel {
            return match crossed {
                // An area light's density is 0 off the lights the draw's ray crosses
                // (the list the mixtures' pdfs sum over: padded boxes hold every
                // direction of positive density); evaluated only where the list holds it.
                Some(c) if k < self.area.len() && !c.lights().contains(&(k as u32)) => 0.0,
                _ if k < self.count() => self.pdf_one(p, k, wi),
                _ => 0.0,
            };
        }
        // The selections whose probabilities do not depend on (p, n) without the general
        // dispatch per light (most pdfs of `light` and `light-uniform`): the same terms.
        match sel {
            Selection::Power => {
                let d = self.by_power.as_ref();
                self.pdf_mixture_over(p, wi, crossed, |k| d.map_or(0.0, |d| d.pmf(k)))
            }
            Selection::Uniform => {
                let pm = 1.0 / self.count() as f64;
                self.pdf_mixture_over(p, wi, crossed, |_| pm)
            }
            _ => {
                let total = match sel {
                    Selection::Spatial => self.importance_total(p, n),
                    _ => 0.0,
                };
                self.pdf_mixture_over(p, wi, crossed, |k| self.pmf_with(sel, p, n, k, total))
            }
        }
    }

    /// The pdf at `wi` of `light-power` or `light-area` from the lights `crossed` lists,
    /// in a scene without an environment (None otherwise): [`Self::pdf_selected_over`]'s
    /// and [`Self::pdf_by_area_over`]'s terms in the same order, bit for bit, without the
    /// general dispatch. The optimal estimators take these pdfs for every draw, the
    /// zero-valued ones too (docs/results.md, Overhead).
    #[inline(always)]
    pub(crate) fn pdf_listed(&self, t: Technique, c: &Crossed) -> Option<f64> {
        if self.environment.is_some() {
            return None;
        }
        let mut sum = 0.0;
        match t {
            Technique::LightPower => {
                for (&k, &pdf) in c.lights().iter().zip(c.pdf_li()) {
                    self.add_power_term(&mut sum, k, pdf);
                }
            }
            Technique::LightArea => {
                let d = self.by_area.as_ref()?;
                for (&i, &pdf) in c.lights().iter().zip(c.pdf_area()) {
                    sum += d.pmf(i as usize) * pdf;
                }
            }
            _ => return None,
        }
        Some(sum)
    }

    /// [`Self::pdf_listed`] of `light-power` and of `light-area` from one pass over `c`'s
    /// list: each sum's terms in the same order, so both the same bit for bit, at the
    /// cost of one loop (a zero-valued draw of the optimal estimators takes both; one
    /// call per technique was a third of its pdfs' instructions). The area sum only
    /// where `c` holds by-area pdfs and there is a by-area selection, else None; None
    /// altogether in a scene with an environment.
    #[inline(always)]
    pub(crate) fn pdf_listed_mixtures(&self, c: &Crossed) -> Option<(f64, Option<f64>)> {
        if self.environment.is_some() {
            return None;
        }
        let mut power = 0.0;
        let Some(d) = self.by_area.as_ref().filter(|_| c.by_area) else {
            for (&k, &pdf) in c.lights().iter().zip(c.pdf_li()) {
                self.add_power_term(&mut power, k, pdf);
            }
            return Some((power, None));
        };
        let mut area = 0.0;
        for ((&k, &pdf), &pa) in c.lights().iter().zip(c.pdf_li()).zip(c.pdf_area()) {
            self.add_power_term(&mut power, k, pdf);
            area += d.pmf(k as usize) * pa;
        }
        Some((power, Some(area)))
    }

    /// Light k's term of `light-power`'s pdf, its own pdf `pdf` times its pmf, added to
    /// `sum` where both are nonzero ([`Self::pdf_listed`], [`Self::pdf_listed_mixtures`]).
    #[inline(always)]
    fn add_power_term(&self, sum: &mut f64, k: u32, pdf: f64) {
        if pdf != 0.0 {
            let pm = self.by_power.as_ref().map_or(0.0, |d| d.pmf(k as usize));
            *sum += if pm > 0.0 { pm * pdf } else { 0.0 };
        }
    }

    /// Σ_k pmf(k) · p_k(wi) over the area lights `crossed` lists (None: found by the
    /// BVH here), then the environment; p_k evaluated only where pmf(k) > 0. `pmf` is
    /// [`Self::pmf_with`]'s for MIS lights (every index here is one).
    #[inline(always)]
    fn pdf_mixture_over(
        &self,
        p: DVec3,
        wi: DVec3,
        crossed: Option<&Crossed>,
        pmf: impl Fn(usize) -> f64,
    ) -> f64 {
        // P(k)·p_k, p_k evaluated only where P(k) > 0.
        #[inline(always)]
        fn term(pm: f64, pdf: impl FnOnce() -> f64) -> f64 {
            if pm > 0.0 {
                pm * pdf()
            } else {
                0.0
            }
        }
        // Only the area lights the ray from p along wi crosses have density there. A
        // light whose box the ray enters but which it misses (p_k = 0) adds +0.0 to a
        // sum that holds +0.0 or more whatever P(k) is, so P(k) — a walk down the light
        // BVH for `light-bvh` — is not asked for it: the same sum, bit for bit.
        let mut sum = 0.0;
        match crossed {
            Some(c) => {
                for (&k, &pdf) in c.lights().iter().zip(c.pdf_li()) {
                    if pdf != 0.0 {
                        sum += term(pmf(k as usize), || pdf);
                    }
                }
            }
            None => self
                .bvh
                .for_each_hit(&Ray::new(p, wi), 0.0, f64::INFINITY, |k| {
                    let pdf = self.pdf_one(p, k, wi);
                    if pdf != 0.0 {
                        sum += term(pmf(k), || pdf);
                    }
                }),
        }
        if self.environment.is_some() {
            let k = self.area.len();
            sum += term(pmf(k), || self.pdf_one(p, k, wi));
        }
        sum
    }

    /// The area lights the ray from `p` along `wi` crosses, in the BVH's order, with
    /// each one's own solid-angle pdf (and, with `area`, its by-area pdf): what every
    /// light technique's density at `wi` needs, found once for them all. None past
    /// [`Crossed::CAPACITY`] lights.
    pub fn crossed(&self, p: DVec3, wi: DVec3, area: bool) -> Option<Crossed> {
        let mut out = Along::default();
        self.walk_crossed(&Ray::new(p, wi), area, false, &mut out);
        out.crossed().copied()
    }

    /// What a ray from a shading point (unit direction) meets among the area lights,
    /// from one walk of the light BVH: the nearest light (what `Li` along it needs,
    /// as [`Self::intersect`] over (0, ∞) finds it) and every light crossed with its pdfs
    /// from the ray's origin (as [`Self::crossed`] finds them), each light's crossings
    /// computed once for both.
    pub fn along(&self, ray: &Ray, area: bool) -> Along {
        let mut out = Along::default();
        self.along_into(ray, area, &mut out);
        out
    }

    /// [`Self::along`] written over `out`: a caller that keeps one [`Along`] for all
    /// its draws copies nothing (returned by value, the list of a few hundred bytes was
    /// built on the callee's stack and copied out on every draw; its share of the
    /// diffuse scene's instructions: docs/notebook/2026-12-01-cpu-speed-round-4.md).
    pub fn along_into(&self, ray: &Ray, area: bool, out: &mut Along) {
        self.walk_crossed(ray, area, true, out)
    }

    /// [`Self::along_into`]; without `nearest`, only the lights crossed and their pdfs.
    #[inline]
    fn walk_crossed(&self, ray: &Ray, area: bool, nearest: bool, out: &mut Along) {
        let (p, wi) = (ray.o, ray.d);
        // Only the count is reset: entries past it are never read.
        out.all.n = 0;
        out.all.by_area = area;
        out.over = false;
        let (c, over) = (&mut out.all, &mut out.over);
        let mut best: Option<(usize, super::Crossing)> = None;
        self.bvh.for_each_hit(ray, 0.0, f64::INFINITY, |k| {
            let l = &self.area[k];
            let (li, pa) = if nearest || area {
                let (cr, m) = l.crossings(p, wi);
                // Crossings come nearest first, all at t > 0; the first light found wins
                // a tie, as in the nearest-hit walk.
                // A proxy (an emitting object's bounding sphere) has density but no
                // surface: it is never the light a ray meets.
                if let Some(first) = cr[0].filter(|_| nearest && m > 0 && !l.proxy) {
                    if best.is_none_or(|(_, b)| first.t < b.t) {
                        best = Some((k, first));
                    }
                }
                let pa = if area {
                    l.pdf_area_over(wi, &cr[..m])
                } else {
                    0.0
                };
                (l.pdf_li_over(p, wi, &cr[..m]), pa)
            } else {
                (l.pdf_li(p, wi), 0.0)
            };
            if c.n == Crossed::CAPACITY {
                *over = true;
                return;
            }
            c.lights[c.n] = k as u32;
            c.li[c.n] = li;
            c.area[c.n] = pa;
            c.n += 1;
        });
        out.nearest = best.map(|(light, h)| LightHit {
            light,
            t: h.t,
            n: h.n,
            radiance: self.area[light].emitted(h.n, -wi),
        });
    }
}

/// The area lights along one ray ([`Lights::along`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Along {
    /// The nearest light crossed (t > 0).
    pub nearest: Option<LightHit>,
    all: Crossed,
    over: bool,
}

impl Along {
    /// Every light crossed, with its pdfs; None past [`Crossed::CAPACITY`] lights.
    pub fn crossed(&self) -> Option<&Crossed> {
        (!self.over).then_some(&self.all)
    }
}

/// The area lights one direction crosses, with their pdfs ([`Lights::crossed`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Crossed {
    n: usize,
    lights: [u32; Crossed::CAPACITY],
    li: [f64; Crossed::CAPACITY],
    area: [f64; Crossed::CAPACITY],
    /// Whether the by-area pdfs were found (a technique samples by area).
    by_area: bool,
}

impl Crossed {
    /// The most lights one list holds.
    pub const CAPACITY: usize = 8;

    /// The lights crossed, nearest subtrees first.
    pub fn lights(&self) -> &[u32] {
        &self.lights[..self.n]
    }

    /// Each light's own solid-angle pdf ([`crate::light::AreaLight::pdf_li`]).
    pub fn pdf_li(&self) -> &[f64] {
        &self.li[..self.n]
    }

    /// Each light's by-area pdf ([`crate::light::AreaLight::pdf_area`]; 0 unless asked
    /// for).
    pub fn pdf_area(&self) -> &[f64] {
        &self.area[..self.n]
    }
}
