//! Rays through participating media and index-matched boundaries (pbrt-v4 §14.1,
//! `VolPathIntegrator`; Mitsuba 3's `volpath`), for scenes where
//! [`Scene::participating`] holds.
//!
//! **Walk.** A ray is followed through `interface` surfaces (which light crosses
//! unchanged; the medium changes to the object's interior or exterior by the side it
//! enters) up to the first light, surface of another material, or escape. Each stretch
//! inside a medium is kept as a [`Segment`]; their product of `exp(−σ_t·len)` is the
//! walk's transmittance. Media are homogeneous, so the transmittance is exact: the
//! direct-lighting integrand of a direction, `f·|cos|·Tr·Le`, stays a deterministic
//! function of the direction, as MIS and the optimal estimators need.
//!
//! **Free flight.** The path's next vertex along a walk is drawn by the spectral-MIS
//! free-flight sampling of chromatic media, with channels chosen by the path's
//! throughput (Chiang et al. 2016, "Practical and Controllable Subsurface Scattering for
//! Production Path Tracing"; Miller et al. 2019): a channel c is picked with probability
//! `w_c = β_c / Σβ`, an optical depth τ = −ln(1 − u) is spent along the segments at σ_t
//! of channel c, and the event is weighted by the one-sample balance over the three
//! channels: a scattering point at t has density `p(t) = Σ_c w_c σ_t,c Tr_c(t)` and
//! weight `σ_s Tr(t) / p(t)`; passing every segment has probability `Σ_c w_c Tr_c` and
//! weight `Tr / Σ_c w_c Tr_c`. Choosing by throughput keeps the product of weights
//! bounded: in a non-absorbing medium Σ_c β_c is the same after every event, where a
//! uniform choice lets one channel's weight grow by up to 3 per event.
//! The light at the walk's end is not counted again: the vertex the walk leaves
//! already has it in its direct lighting (with the transmittance).

use super::ray_log::RayLog;
use super::vertex::{spawn, Trace};
use super::RayKind;
use crate::color::Rgb;
use crate::light::LightHit;
use crate::material::Material;
use crate::scene::{Scene, SurfaceHit};
use frep::Ray;
use glam::DVec3;

/// Most media stretches one walk keeps; a ray that would cross more is taken as
/// blocked (transmittance 0).
const MAX_SEGMENTS: usize = 16;
/// Most index-matched boundaries one walk crosses before it is taken as blocked.
const MAX_CROSSINGS: usize = 64;

/// A stretch of a ray inside medium `medium`: from `o` along unit `d` for `len`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Segment {
    medium: usize,
    o: DVec3,
    d: DVec3,
    len: f64,
}

/// A ray followed through index-matched boundaries (module docs).
#[derive(Clone, Debug)]
pub(crate) struct Walk {
    /// What ends it: a light, a surface that is not an interface, or the environment.
    pub end: Trace,
    /// Transmittance from the origin to the end.
    pub tr: Rgb,
    segments: [Segment; MAX_SEGMENTS],
    count: usize,
}

/// Where the free flight along a walk stops.
pub(crate) enum Flight {
    /// At a scattering point inside medium `medium`, with weight `σ_s Tr / p`.
    Scatter {
        /// The point.
        p: DVec3,
        /// Index into [`Scene::media`].
        medium: usize,
        /// σ_s·Tr(t)/p(t).
        weight: Rgb,
    },
    /// At the walk's end, with weight `Tr / P(pass)`.
    Through(Rgb),
}

/// Whether `hit` is on an index-matched boundary, which walks pass.
#[inline]
fn is_interface(scene: &Scene, hit: &SurfaceHit) -> bool {
    matches!(scene.materials[hit.material], Material::Interface)
}

/// The medium a ray along `d` enters at `hit`: the object's interior when it goes
/// inside (against the outward normal), else its exterior.
#[inline]
pub(crate) fn medium_entered(scene: &Scene, hit: &SurfaceHit, d: DVec3) -> Option<usize> {
    let o = &scene.objects[hit.object];
    if d.dot(hit.n) < 0.0 {
        o.interior
    } else {
        o.exterior
    }
}

impl Walk {
    fn blocked() -> Walk {
        Walk {
            end: Trace::Escape,
            tr: Rgb::ZERO,
            segments: [Segment::default(); MAX_SEGMENTS],
            count: 0,
        }
    }

    /// Follows `ray` (which starts in `medium`, object `skip` left out) to the first
    /// thing that is not an index-matched boundary. `first_light`: the nearest light
    /// along the ray where the caller found it ([`crate::light::Lights::along_into`]).
    pub fn new(
        scene: &Scene,
        ray: &Ray,
        skip: Option<usize>,
        medium: Option<usize>,
        first_light: Option<Option<LightHit>>,
    ) -> Walk {
        let mut w = Walk::blocked();
        w.tr = Rgb::ONE;
        let (mut ray, mut skip, mut medium) = (*ray, skip, medium);
        for crossing in 0..MAX_CROSSINGS {
            let hit = scene.intersect_skipping(&ray, 0.0, f64::INFINITY, skip);
            let t_max = hit.map_or(f64::INFINITY, |h| h.t);
            let light = match first_light {
                Some(l) if crossing == 0 => l.filter(|l| l.t < t_max),
                _ => scene.lights.intersect(&ray, 0.0, t_max),
            };
            let (len, end) = match (light, hit) {
                (Some(l), _) => (l.t, Trace::Light(l)),
                (None, Some(h)) => (h.t, Trace::Surface(h)),
                (None, None) => (f64::INFINITY, Trace::Escape),
            };
            if let Some(m) = medium {
                if w.count == MAX_SEGMENTS {
                    return Walk::blocked();
                }
                w.segments[w.count] = Segment {
                    medium: m,
                    o: ray.o,
                    d: ray.d,
                    len,
                };
                w.count += 1;
                w.tr *= scene.media[m].transmittance(len);
            }
            match end {
                Trace::Surface(h) if is_interface(scene, &h) => {
                    medium = medium_entered(scene, &h, ray.d);
                    skip = scene.left_behind(h.object, h.n, ray.d);
                    ray = spawn(h.p, h.n, ray.d);
                }
                _ => {
                    w.end = end;
                    return w;
                }
            }
        }
        Walk::blocked()
    }

    /// The free flight along the walk (module docs) for a path of throughput `beta`
    /// (non-negative, not all 0), from the channel number `uc` and the distance number
    /// `u`, both in [0, 1).
    pub fn fly(&self, scene: &Scene, beta: Rgb, uc: f64, u: f64) -> Flight {
        if self.count == 0 {
            return Flight::Through(Rgb::ONE);
        }
        let total = beta.x + beta.y + beta.z;
        let w = if total > 0.0 && total.is_finite() {
            beta / total
        } else {
            Rgb::splat(1.0 / 3.0)
        };
        let c = if uc < w.x {
            0
        } else if uc < w.x + w.y || w.z == 0.0 {
            1
        } else {
            2
        };
        let mut tau = -(1.0 - u).ln();
        let mut tr = Rgb::ONE;
        for s in &self.segments[..self.count] {
            let m = &scene.media[s.medium];
            let sigma = m.sigma_t[c];
            if sigma > 0.0 {
                let depth = sigma * s.len;
                if depth > tau {
                    let t = tau / sigma;
                    let tr_t = tr * m.transmittance(t);
                    let pdf = w.dot(m.sigma_t * tr_t);
                    let p = s.o + s.d * t;
                    let weight = if pdf > 0.0 {
                        m.sigma_s(p) * tr_t / pdf
                    } else {
                        Rgb::ZERO
                    };
                    return Flight::Scatter {
                        p,
                        medium: s.medium,
                        weight,
                    };
                }
                tau -= depth;
            }
            tr *= m.transmittance(s.len);
        }
        let pass = w.dot(tr);
        Flight::Through(if pass > 0.0 { tr / pass } else { Rgb::ZERO })
    }
}

/// Light `le` from `t_max` along `ray` (a light's point, or ∞ for the environment)
/// times the transmittance to it, through index-matched boundaries and media; where
/// another surface is in the way, its emission (0 unless it is an emitting object's
/// outside) times the transmittance to it, or 0 without `emitters` (a point or spot
/// light's shadow ray, whose blocker's emission its own draws count). The ray starts in
/// `medium`, object `skip` left out. Out of line and cold: scenes without media or
/// emitting objects never call it, and their shadow-ray path stays inlined.
#[cold]
#[inline(never)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn transmitted(
    scene: &Scene,
    ray: &Ray,
    t_max: f64,
    le: Rgb,
    emitters: bool,
    skip: Option<usize>,
    medium: Option<usize>,
    rays: &mut impl RayLog,
) -> Rgb {
    let target = t_max.is_finite().then(|| ray.at(t_max));
    let (mut ray, mut skip, mut medium, mut t_max) = (*ray, skip, medium, t_max);
    let mut tr = Rgb::ONE;
    for _ in 0..MAX_CROSSINGS {
        rays.begin(RayKind::Shadow);
        let hit = scene.intersect_skipping(&ray, 0.0, t_max, skip);
        rays.end(RayKind::Shadow);
        let len = hit.map_or(t_max, |h| h.t);
        if let Some(m) = medium {
            tr *= scene.media[m].transmittance(len);
        }
        match hit {
            None => return tr * le,
            Some(h) if is_interface(scene, &h) => {
                medium = medium_entered(scene, &h, ray.d);
                skip = scene.left_behind(h.object, h.n, ray.d);
                ray = spawn(h.p, h.n, ray.d);
                if let Some(target) = target {
                    t_max = (target - ray.o).dot(ray.d);
                    if t_max <= 0.0 {
                        return tr * le;
                    }
                }
            }
            Some(h) if emitters => return tr * scene.surface_emission(&h, ray.d),
            Some(_) => return Rgb::ZERO,
        }
        if tr == Rgb::ZERO {
            return Rgb::ZERO;
        }
    }
    Rgb::ZERO
}
