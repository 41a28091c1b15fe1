//! One scattering vertex: delta lights, the MIS draws of every technique, delta lobes and
//! the path's continuation (module docs of [`crate::integrator`]).

use super::medium::{transmitted, Flight, Walk};
use super::ray_log::RayLog;
use super::{Integrator, Pixel, RayKind, MAX_TECHNIQUES};
use crate::bsdf::{Bsdf, BsdfSample};
use crate::color::Rgb;
use crate::light::{Along, LightHit};
use crate::sampler::SampleStream;
use crate::scene::{Scene, SurfaceHit};
use crate::technique::Sampling;
use crate::technique::{ShadingPoint, Technique};
use ::state::Combine;
use frep::Ray;
use glam::DVec3;

/// Relative offset of secondary ray origins off the surface, along the normal toward the
/// ray's side, so that the surface just left is never found again.
const RAY_OFFSET: f64 = 1e-7;

/// Techniques up to which [`Integrator::add_unlit`] keeps its pdfs in a short array.
const UNLIT_SHORT: usize = 4;

/// What a ray met first.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Trace {
    /// An object's surface.
    Surface(SurfaceHit),
    /// An area light.
    Light(LightHit),
    /// Nothing: the ray escapes to the environment.
    Escape,
    /// A scattering point inside a medium (the free flight's stop, `integrator/medium.rs`).
    Medium {
        /// The point.
        p: DVec3,
        /// Index into [`Scene::media`].
        medium: usize,
    },
}

/// The nearest of objects and area lights along `ray` (a nearest-hit query), object
/// `skip` left out ([`Scene::left_behind`]).
pub(crate) fn trace(scene: &Scene, ray: &Ray, skip: Option<usize>) -> Trace {
    let hit = scene.intersect_skipping(ray, 0.0, f64::INFINITY, skip);
    let t_max = hit.map_or(f64::INFINITY, |h| h.t);
    if let Some(l) = scene.lights.intersect(ray, 0.0, t_max) {
        return Trace::Light(l);
    }
    hit.map_or(Trace::Escape, Trace::Surface)
}

/// [`trace`] with the lights along the ray already found ([`Lights::along`]).
pub(super) fn trace_along(scene: &Scene, ray: &Ray, along: &Along, skip: Option<usize>) -> Trace {
    let hit = scene.intersect_skipping(ray, 0.0, f64::INFINITY, skip);
    let t_max = hit.map_or(f64::INFINITY, |h| h.t);
    if let Some(l) = along.nearest.filter(|l| l.t < t_max) {
        return Trace::Light(l);
    }
    hit.map_or(Trace::Escape, Trace::Surface)
}

/// Emitted radiance arriving along a traced ray of direction `d`: the light's, the
/// environment's on escape, an emitting object's outside ([`Scene::surface_emission`]),
/// else 0.
pub(crate) fn emitted(scene: &Scene, t: &Trace, d: DVec3) -> Rgb {
    match t {
        Trace::Light(l) => l.radiance,
        Trace::Escape => scene.lights.environment_radiance(d),
        Trace::Surface(h) => scene.surface_emission(h, d),
        Trace::Medium { .. } => Rgb::ZERO,
    }
}

/// A ray leaving surface point `p` (normal `n`) in unit direction `wi`, its origin moved
/// off the surface to the side of `wi`.
pub(crate) fn spawn(p: DVec3, n: DVec3, wi: DVec3) -> Ray {
    let side = if wi.dot(n) >= 0.0 { n } else { -n };
    let scale = 1.0 + p.abs().max_element();
    Ray::new(p + side * (RAY_OFFSET * scale), wi)
}

/// `Li(ω)` by one shadow ray: the nearest area light along the ray (or the environment)
/// if no object lies before it (object `skip` left out: [`Scene::left_behind`]), times
/// the transmittance of the media on the way where the scene has them (the ray starts
/// in `medium`). No ray is traced when there is nothing to see.
pub(crate) fn incident(
    scene: &Scene,
    ray: &Ray,
    skip: Option<usize>,
    medium: Option<usize>,
    rays: &mut impl RayLog,
) -> Rgb {
    incident_from(
        scene,
        ray,
        scene.lights.intersect(ray, 0.0, f64::INFINITY),
        skip,
        medium,
        rays,
    )
}

/// [`incident`] with the nearest area light along the ray already found.
#[inline(always)]
pub(super) fn incident_from(
    scene: &Scene,
    ray: &Ray,
    light: Option<LightHit>,
    skip: Option<usize>,
    medium: Option<usize>,
    rays: &mut impl RayLog,
) -> Rgb {
    let (t_max, le) = match light {
        Some(h) => (h.t, h.radiance),
        None => (f64::INFINITY, scene.lights.environment_radiance(ray.d)),
    };
    // Through media and index-matched boundaries, or by a nearest-hit ray where an
    // object in the way may be the light (out of line: other scenes keep this inlined).
    if scene.participating || scene.has_emitting_objects() {
        return transmitted(scene, ray, t_max, le, true, skip, medium, rays);
    }
    if le == Rgb::ZERO {
        return Rgb::ZERO;
    }
    rays.begin(RayKind::Shadow);
    let occluded = scene.occluded_skipping(ray, 0.0, t_max, skip);
    rays.end(RayKind::Shadow);
    if occluded {
        Rgb::ZERO
    } else {
        le
    }
}

/// The MIS light a ray reaches if nothing but lights were in the scene: the nearest
/// area light along it (`nearest`), else the environment (index `area().len()`), else
/// None. It decides which per-light estimator a draw feeds; an object in front of the
/// light makes the draw's integrand 0, not its light another.
pub(super) fn light_reached(scene: &Scene, nearest: Option<LightHit>) -> Option<usize> {
    match nearest {
        Some(h) => Some(h.light),
        None => scene
            .lights
            .environment()
            .map(|_| scene.lights.area().len()),
    }
}

/// A shading point: a surface hit with its BSDF, or a point inside a medium with its
/// phase function; and the direction toward the viewer.
pub(crate) struct Vertex<'s> {
    pub p: DVec3,
    /// The outward normal at a surface; zero inside a medium.
    pub n: DVec3,
    pub wo: DVec3,
    pub bsdf: Bsdf<'s>,
    /// The object hit (None inside a medium).
    pub object: Option<usize>,
    /// The media on the two sides: against the normal (inside the object) and along it;
    /// both the medium itself at a medium point.
    inside: Option<usize>,
    outside: Option<usize>,
}

impl<'s> Vertex<'s> {
    #[inline]
    pub fn new(scene: &'s Scene, hit: &SurfaceHit, wo: DVec3) -> Self {
        let bsdf = scene.bsdf(hit);
        let o = &scene.objects[hit.object];
        Self {
            p: hit.p,
            n: hit.n,
            wo,
            bsdf,
            object: Some(hit.object),
            inside: o.interior,
            outside: o.exterior,
        }
    }

    /// The vertex at point `p` inside medium `medium`.
    pub fn in_medium(scene: &'s Scene, p: DVec3, medium: usize, wo: DVec3) -> Self {
        Self {
            p,
            n: DVec3::ZERO,
            wo,
            bsdf: Bsdf::phase(scene.media[medium].g, wo),
            object: None,
            inside: Some(medium),
            outside: Some(medium),
        }
    }

    /// The object a ray leaving here along `wi` need not test ([`Scene::left_behind`]).
    pub fn left_behind(&self, scene: &Scene, wi: DVec3) -> Option<usize> {
        self.object.and_then(|o| scene.left_behind(o, self.n, wi))
    }

    /// The medium a ray leaving here along `wi` starts in.
    #[inline]
    pub fn medium_toward(&self, wi: DVec3) -> Option<usize> {
        if wi.dot(self.n) < 0.0 {
            self.inside
        } else {
            self.outside
        }
    }

    /// The integrand's projection factor for `wi`: |cos θi| at a surface, 1 in a medium.
    #[inline]
    pub fn cos(&self, wi: DVec3) -> f64 {
        self.bsdf.cos(self.n, wi)
    }
}

/// The BSDF draw that extends a path, with what its ray met.
pub(crate) struct Continuation {
    /// f·|cos|/pdf of the draw.
    pub weight: Rgb,
    /// What the continuation ray met first.
    pub trace: Trace,
    /// Its direction.
    pub wi: DVec3,
}

impl Integrator {
    /// A zero-valued draw of technique `k` ([`Self::unlit_listed`]) into the MIS
    /// combination, every pdf from the lights `c` lists and the BSDF's `bsdf_pdf`
    /// ([`crate::technique::pdfs_listed`]): what [`crate::technique::pdfs`], the own-pdf
    /// check and [`Pixel::add_draw`] do for it, the same sums bit for bit, without their
    /// general dispatch. False (nothing added) where a pdf needs more than the list (an
    /// environment). The pdfs are written into the caller's `pdfs` (one per technique),
    /// which every call overwrites: an array of 32 zeroed here cost a tenth of the call.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn add_unlit<const ONE: bool>(
        &self,
        lights: &crate::light::Lights,
        c: &crate::light::Crossed,
        p: DVec3,
        wi: DVec3,
        bsdf_pdf: Option<f64>,
        depth: usize,
        k: usize,
        f: Rgb,
        pdfs: &mut [f64],
        px: &mut Pixel,
    ) -> bool {
        // At most three techniques qualify (the BSDF and the two mixtures, each once).
        if !ONE {
            match self.unlit_sized {
                Some(2) => return self.add_unlit_sized::<2>(lights, c, bsdf_pdf, depth, k, px),
                Some(3) => return self.add_unlit_sized::<3>(lights, c, bsdf_pdf, depth, k, px),
                _ => {}
            }
        }
        let (t, map) = (&self.techniques, self.one_light_map.as_ref());
        if !crate::technique::pdfs_listed::<ONE>(t, lights, c, p, wi, bsdf_pdf, map, pdfs) {
            return false;
        }
        // A light draw without density of its own is refused as failed, which is what
        // the sums do with a sample whose own pdf is 0 (`mis`, `Moments::add`).
        px.add_zero_valued(self, depth, k, f, pdfs);
        true
    }

    /// [`Self::add_unlit`] where [`Self::unlit_sized`] is `T`: the pdfs in an array of
    /// their own and optimal-direct's sums without the estimator's dispatch
    /// ([`Pixel::add_zero_valued_sized`]); the same sums bit for bit.
    #[inline(always)]
    fn add_unlit_sized<const T: usize>(
        &self,
        lights: &crate::light::Lights,
        c: &crate::light::Crossed,
        bsdf_pdf: Option<f64>,
        depth: usize,
        k: usize,
        px: &mut Pixel,
    ) -> bool {
        let Combine::Estimator(kernel) = &self.combine else {
            return false;
        };
        let mut pdfs = [0.0; T];
        let t = &self.techniques[..T];
        if !crate::technique::pdfs_mixtures(t, lights, c, bsdf_pdf, &mut pdfs) {
            return false;
        }
        px.add_zero_valued_sized(self, kernel, depth, k, &pdfs);
        true
    }

    /// The continuation of a BSDF draw along `ray` in a scene with media: the walk's
    /// `Li` (with its transmittance) and the free flight's stop (`integrator/medium.rs`).
    /// Out of line and cold, so that scenes without media keep the short path inlined.
    #[cold]
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn continue_through_media(
        &self,
        scene: &Scene,
        ray: &Ray,
        skip: Option<usize>,
        medium: Option<usize>,
        nearest: Option<Option<LightHit>>,
        beta: Rgb,
        s: &BsdfSample,
        depth: usize,
        rng: &SampleStream,
        rays: &mut impl RayLog,
    ) -> (Rgb, Continuation) {
        rays.begin(RayKind::Secondary);
        let walk = Walk::new(scene, ray, skip, medium, nearest);
        rays.end(RayKind::Secondary);
        let li = walk.tr * emitted(scene, &walk.end, s.wi);
        let (uc, u) = self.dims.flight(rng, depth + 1);
        let (flight, trace) = match walk.fly(scene, beta * s.weight, uc, u) {
            Flight::Scatter { p, medium, weight } => (weight, Trace::Medium { p, medium }),
            Flight::Through(weight) => (weight, walk.end),
        };
        let c = Continuation {
            weight: s.weight * flight,
            trace,
            wi: s.wi,
        };
        (li, c)
    }

    /// Point and spot lights at `v`: Σ f·|cos|·I/d² over the visible ones (outside MIS).
    pub(super) fn delta_lights(&self, scene: &Scene, v: &Vertex, rays: &mut impl RayLog) -> Rgb {
        let mut sum = Rgb::ZERO;
        for l in scene.lights.delta() {
            let Some(ls) = l.sample_li(v.p) else { continue };
            let fc = v.bsdf.f(v.wo, ls.wi) * v.cos(ls.wi);
            if fc == Rgb::ZERO || ls.radiance == Rgb::ZERO {
                continue;
            }
            let ray = spawn(v.p, v.n, ls.wi);
            let dist = (l.position() - ray.o).length();
            if scene.lights.intersect(&ray, 0.0, dist).is_some() {
                continue;
            }
            let skip = v.left_behind(scene, ls.wi);
            if scene.participating {
                let medium = v.medium_toward(ls.wi);
                sum += fc * transmitted(scene, &ray, dist, ls.radiance, false, skip, medium, rays);
                continue;
            }
            rays.begin(RayKind::Shadow);
            let occluded = scene.occluded_skipping(&ray, 0.0, dist, skip);
            rays.end(RayKind::Shadow);
            if !occluded {
                sum += fc * ls.radiance;
            }
        }
        sum
    }

    /// Traces a BSDF draw's ray (nearest hit) when it extends the path, else evaluates
    /// `Li` by a shadow ray; returns `Li` and records the continuation. `along`: the
    /// lights along the draw's ray ([`spawn`]), where the caller found them. Through
    /// media the continuation is the free flight's stop (`integrator/medium.rs`), drawn
    /// with the numbers of vertex `depth + 1` and the path's throughput `beta` at `v`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn li_of_bsdf_draw(
        &self,
        scene: &Scene,
        v: &Vertex,
        beta: Rgb,
        s: &BsdfSample,
        extends: bool,
        needed: bool,
        along: Option<&Along>,
        depth: usize,
        rng: &SampleStream,
        next: &mut Option<Continuation>,
        rays: &mut impl RayLog,
    ) -> Rgb {
        let ray = spawn(v.p, v.n, s.wi);
        let skip = v.left_behind(scene, s.wi);
        let medium = v.medium_toward(s.wi);
        if extends && scene.participating {
            let (li, c) = self.continue_through_media(
                scene,
                &ray,
                skip,
                medium,
                along.map(|a| a.nearest),
                beta,
                s,
                depth,
                rng,
                rays,
            );
            *next = Some(c);
            li
        } else if extends {
            rays.begin(RayKind::Secondary);
            let t = match along {
                Some(a) => trace_along(scene, &ray, a, skip),
                None => trace(scene, &ray, skip),
            };
            rays.end(RayKind::Secondary);
            let li = emitted(scene, &t, s.wi);
            *next = Some(Continuation {
                weight: s.weight,
                trace: t,
                wi: s.wi,
            });
            li
        } else if needed {
            match along {
                Some(a) => incident_from(scene, &ray, a.nearest, skip, medium, rays),
                None => incident(scene, &ray, skip, medium, rays),
            }
        } else {
            Rgb::ZERO
        }
    }

    /// Shades vertex `depth` (0: the camera ray's hit) with throughput `beta`: delta
    /// lights and delta lobes into `px.sum`, the techniques' draws into the depth's MIS
    /// combination. With `extend`, returns the BSDF draw that continues the path (the
    /// first draw of [`Technique::Bsdf`], or an extra BSDF draw without one).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn shade(
        &self,
        scene: &Scene,
        v: &Vertex,
        beta: Rgb,
        depth: usize,
        extend: bool,
        rng: &SampleStream,
        px: &mut Pixel,
        rays: &mut impl RayLog,
    ) -> Option<Continuation> {
        px.add(beta * self.delta_lights(scene, v, rays));
        let mut next = None;
        if v.bsdf.bxdf.is_pure_specular() {
            // No continuous density anywhere: every BSDF draw is outside MIS.
            let nb = self.bsdf_index.map_or(1, |k| self.counts[k]);
            for j in 0..nb {
                let d = match self.bsdf_index {
                    Some(k) => self.dims.technique(rng, depth, k, j),
                    None => self.dims.extra(rng, depth),
                };
                if let Some(s) = v.bsdf.sample_f(v.wo, d.uc, d.u) {
                    let li = self.li_of_bsdf_draw(
                        scene,
                        v,
                        beta,
                        &s,
                        extend && j == 0,
                        true,
                        None,
                        depth,
                        rng,
                        &mut next,
                        rays,
                    );
                    px.add(beta * s.weight * li / f64::from(nb));
                }
            }
            return next;
        }
        let ctx = ShadingPoint {
            p: v.p,
            n: v.n,
            wo: v.wo,
            bsdf: &v.bsdf,
            lights: &scene.lights,
            trained: self.trained.as_deref(),
        };
        let t_count = self.techniques.len();
        let mut pdfs = [0.0; MAX_TECHNIQUES];
        let mut along = Along::default();
        for (k, (&tech, &n_k)) in self.techniques.iter().zip(&self.counts).enumerate() {
            for j in 0..n_k {
                let d = self.dims.technique(rng, depth, k, j);
                // A light technique's draw leaves its pdf to `pdfs` below (NaN here).
                // Read in place: moving the sample out of the Option copied its few
                // hundred bytes on every light draw.
                let drawn = tech.draw(&ctx, d.uc, d.u);
                let Some(s) = drawn.as_ref() else {
                    px.add_failed(self, depth, k);
                    continue;
                };
                let carries = extend && j == 0 && tech == Technique::Bsdf;
                if s.specular {
                    // A delta lobe: a failed draw for MIS, its own estimate outside.
                    px.add_failed(self, depth, k);
                    let bs = s.bsdf.as_ref().expect("specular draws come from the BSDF");
                    let li = self.li_of_bsdf_draw(
                        scene, v, beta, bs, carries, true, None, depth, rng, &mut next, rays,
                    );
                    px.add(beta * bs.weight * li / f64::from(n_k));
                    continue;
                }
                // One walk of the light BVH along the draw's ray gives the light its Li
                // needs and every light's pdf there (taken from the ray's origin).
                let ray = spawn(v.p, v.n, s.wi);
                scene.lights.along_into(&ray, self.area_pdfs, &mut along);
                // f and, where a technique samples the BSDF, its pdf in one evaluation.
                let (f, bsdf_pdf) = if self.bsdf_index.is_some() {
                    let (f, p) = v.bsdf.f_pdf(v.wo, s.wi);
                    (f, Some(p))
                } else {
                    (v.bsdf.f(v.wo, s.wi), None)
                };
                let fc = f * v.cos(s.wi);
                // Li along the draw: the continuation's trace for the draw that carries
                // the path, else a shadow ray toward the light it meets. Before the pdfs,
                // so that a draw whose value is 0 skips its pdfs and MIS term where such
                // draws add nothing (heuristic weights; most BSDF draws of `direct` meet
                // no light). A draw that carries the path is a BSDF draw, whose own pdf
                // is its sample's: never refused below, where a draw whose own pdf comes
                // from `pdfs` can be (a refused light draw has traced one shadow ray for
                // nothing).
                debug_assert!(!(carries && s.pdf.is_nan()));
                let li = match &s.bsdf {
                    Some(bs) if carries => self.li_of_bsdf_draw(
                        scene,
                        v,
                        beta,
                        bs,
                        true,
                        true,
                        Some(&along),
                        depth,
                        rng,
                        &mut next,
                        rays,
                    ),
                    _ if fc != Rgb::ZERO => incident_from(
                        scene,
                        &ray,
                        along.nearest,
                        v.left_behind(scene, s.wi),
                        v.medium_toward(s.wi),
                        rays,
                    ),
                    _ => Rgb::ZERO,
                };
                if beta * fc * li == Rgb::ZERO {
                    if !self.zero_draws_count {
                        continue;
                    }
                    // A BSDF draw that meets no light: every other pdf is 0 there, and
                    // its one term is a failed draw's (`Integrator::unlit_bsdf_draws_fail`).
                    if self.unlit_bsdf_draws_fail
                        && tech == Technique::Bsdf
                        && along.crossed().is_some_and(|c| c.lights().is_empty())
                        && scene.lights.environment().is_none()
                    {
                        px.add_failed(self, depth, k);
                        continue;
                    }
                    if self.unlit_listed {
                        if let Some(c) = along.crossed() {
                            let (f, l) = (beta * fc * li, &scene.lights);
                            // Short sets of mixtures (the paper's) apart from sets
                            // with one technique per light (`light#*`).
                            let out = &mut pdfs[..t_count];
                            let added = if t_count <= UNLIT_SHORT && !self.unlit_one {
                                self.add_unlit::<false>(
                                    l, c, v.p, s.wi, bsdf_pdf, depth, k, f, out, px,
                                )
                            } else {
                                self.add_unlit::<true>(
                                    l, c, v.p, s.wi, bsdf_pdf, depth, k, f, out, px,
                                )
                            };
                            if added {
                                continue;
                            }
                        }
                    }
                }
                crate::technique::pdfs_known(
                    self.one_light(),
                    &self.techniques,
                    &ctx,
                    s.wi,
                    along.crossed(),
                    bsdf_pdf,
                    &mut pdfs[..t_count],
                );
                if s.pdf.is_nan() && !(pdfs[k] > 0.0 && pdfs[k].is_finite()) {
                    // What `Technique::sample` refuses: no density of its own there.
                    px.add_failed(self, depth, k);
                    continue;
                }
                let light = if self.record.lights > 1 {
                    light_reached(scene, along.nearest)
                } else {
                    None
                };
                px.add_draw(self, depth, k, beta * fc * li, &pdfs[..t_count], light);
            }
        }
        px.end_vertex(self, depth);
        if self.bsdf_index.is_none() && (extend || v.bsdf.bxdf.has_specular()) {
            // No BSDF technique: one extra draw for the delta lobes and the continuation;
            // its continuous outcomes are already covered by the techniques.
            let d = self.dims.extra(rng, depth);
            if let Some(s) = v.bsdf.sample_f(v.wo, d.uc, d.u) {
                let li = self.li_of_bsdf_draw(
                    scene, v, beta, &s, extend, s.specular, None, depth, rng, &mut next, rays,
                );
                if s.specular {
                    px.add(beta * s.weight * li);
                }
            }
        }
        next
    }
}
