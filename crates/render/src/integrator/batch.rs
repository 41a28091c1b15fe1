//! The batched engine ([`super::Engine::Batched`]): `direct` and `path` over a tile's
//! samples as a wavefront, the GPU back end's pipeline shape (DESIGN.md §4, "two CPU
//! engines, one pipeline shape"; docs/gpu.md).
//!
//! A [`Wave`] holds up to [`BATCH`] samples of distinct pixels and runs them stage by
//! stage over the whole wave:
//!
//! 1. **camera**: each sample's random stream (the first blocks of all of them evaluated
//!    together, [`crate::Sampler::streams_into`]), camera ray and nearest hit;
//!
//! then, vertex by vertex while some path goes on:
//!
//! 2. **delta lights**: point and spot lights at each vertex;
//! 3. **draws**: for each technique and draw, that draw for every sample, with the lights
//!    along its ray (one walk of the light BVH) and the BSDF's value (and pdf) there;
//! 4. **rays**: the continuation's nearest hit for the draw that extends a path, a
//!    shadow ray for the other draws whose BSDF value is not 0;
//! 5. **pdfs**: every technique's pdf at the draws the MIS combination takes;
//! 6. **records**: each sample's outcomes at the vertex into its pixel's record, in the
//!    per-ray order;
//! 7. **continuation**: throughput, Russian roulette and the next vertex.
//!
//! Every stage calls the per-ray integrator's own functions ([`Integrator::shade`]'s and
//! [`Integrator::path_sample`]'s parts) on each sample, a sample's additions reach its
//! record in the per-ray order, and a wave never holds two samples of one pixel (so the
//! vertices of different samples may interleave), so the state is the per-ray engine's
//! bit for bit (`batched_engine_equals_per_ray`). This is the frame the SIMD stages fill:
//! a stage that runs the same arithmetic over many samples at once replaces its loop,
//! and the test holds it to the same bits or to a documented rounding.
//!
//! **What runs per ray.** The renders the wave does not cover ([`Wave::covers`]: the AOV
//! integrators and AOV channels, scenes with media or emitting objects) run per ray
//! whole; a vertex with a delta lobe (mirror, smooth glass or coat) is shaded per ray in
//! stage 6.

use super::path::RR_MIN_Q;
use super::ray_log::RayLog;
use super::vertex::{
    emitted, incident_from, light_reached, spawn, trace_along, Continuation, Trace, Vertex,
};
use super::{Integrator, IntegratorKind, Pixel, RayKind};
use crate::color::Rgb;
use crate::light::Along;
use crate::sampler::SampleStream;
use crate::scene::Scene;
use crate::technique::{Sampling, ShadingPoint, Technique};
use frep::Ray;
use glam::DVec3;

/// Samples per wave: enough that each stage's loop runs long over uniform work, few
/// enough that a wave's draws (with their lights along) stay in the core's caches.
pub(crate) const BATCH: usize = 64;

/// How a sample's vertex is shaded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Item {
    /// No vertex: the path has ended.
    Done,
    /// By the wave's stages.
    Shade,
    /// Per ray in the record stage (a delta lobe at the vertex).
    PerRay,
}

/// Where a draw stands between the stages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// A failed draw for MIS (none drawn, refused, or an unlit BSDF draw that fails
    /// without its pdfs: [`Integrator::unlit_bsdf_draws_fail`]).
    Failed,
    /// A draw of value 0 that the combination skips.
    Skipped,
    /// Drawn; its value and pdfs still to come.
    Pending,
    /// Into the combination with its value and pdfs.
    Ready,
}

/// One draw of one sample between the stages.
#[derive(Clone, Copy, Debug)]
struct Slot {
    state: State,
    /// The direction drawn.
    wi: DVec3,
    /// The technique's own pdf (NaN: taken from the pdfs, [`Sampling::draw`]).
    own_pdf: f64,
    /// The draw's ray, from the shading point.
    ray: Ray,
    /// The lights along the ray.
    along: Along,
    /// The BSDF's pdf at `wi` where a technique samples the BSDF.
    bsdf_pdf: Option<f64>,
    /// f·|cos|, then the draw's value β·f·|cos|·Li.
    value: Rgb,
    /// Whether the draw extends the path (the first BSDF draw where the path goes on).
    carries: bool,
    /// The BSDF sample's f·|cos|/pdf (the continuation's weight).
    weight: Rgb,
}

impl Default for Slot {
    fn default() -> Self {
        Self {
            state: State::Failed,
            wi: DVec3::ZERO,
            own_pdf: 0.0,
            ray: Ray::new(DVec3::ZERO, DVec3::Z),
            along: Along::default(),
            bsdf_pdf: None,
            value: Rgb::ZERO,
            carries: false,
            weight: Rgb::ZERO,
        }
    }
}

/// A batch of samples of one tile and their state between the stages (module docs).
pub(crate) struct Wave<'s> {
    /// Per sample: its pixel's index in the tile's records, its pixel and sample index.
    items: Vec<(usize, u32, u32, u32)>,
    /// Per sample: its pixel and sample index, as the sampler takes them.
    cells: Vec<(u32, u32, u32)>,
    rng: Vec<SampleStream>,
    /// What the path's last ray met (the next vertex where it is a surface).
    at: Vec<Trace>,
    /// The path throughput.
    beta: Vec<Rgb>,
    /// The direction toward the viewer at the next vertex.
    wo: Vec<DVec3>,
    /// The continuation drawn at the vertex being shaded.
    next: Vec<Option<Continuation>>,
    kind: Vec<Item>,
    vertex: Vec<Option<Vertex<'s>>>,
    /// Point and spot lights at the vertex.
    delta: Vec<Rgb>,
    /// Per sample, its draws at the vertex in the per-ray order (technique by technique).
    slots: Vec<Slot>,
    /// Every technique's pdf at each slot's direction.
    pdfs: Vec<f64>,
    /// Per slot of a sample: its technique's index and the draw's index for it.
    technique_of: Vec<(usize, u32)>,
}

impl<'s> Wave<'s> {
    /// Whether the wave renders `it` on `scene` (module docs).
    pub fn covers(it: &Integrator, scene: &Scene) -> bool {
        matches!(it.kind, IntegratorKind::Direct | IntegratorKind::Path)
            && !it.aovs
            && !scene.participating
            && !scene.has_emitting_objects()
    }

    /// An empty wave for `it`'s draws.
    pub fn new(it: &Integrator) -> Self {
        let technique_of: Vec<(usize, u32)> = it
            .counts
            .iter()
            .enumerate()
            .flat_map(|(k, &n)| (0..n).map(move |j| (k, j)))
            .collect();
        let slots = technique_of.len() * BATCH;
        Self {
            items: Vec::with_capacity(BATCH),
            cells: Vec::with_capacity(BATCH),
            rng: Vec::with_capacity(BATCH),
            at: Vec::with_capacity(BATCH),
            beta: Vec::with_capacity(BATCH),
            wo: Vec::with_capacity(BATCH),
            next: Vec::with_capacity(BATCH),
            kind: Vec::with_capacity(BATCH),
            vertex: Vec::with_capacity(BATCH),
            delta: Vec::with_capacity(BATCH),
            slots: vec![Slot::default(); slots],
            pdfs: vec![0.0; slots * it.techniques.len()],
            technique_of,
        }
    }

    /// Adds sample `index` of pixel (x, y), whose record is the tile's `pixel`-th; no
    /// other sample of the wave may be of that pixel.
    pub fn push(&mut self, pixel: usize, x: u32, y: u32, index: u32) {
        debug_assert!(self.items.iter().all(|&(p, ..)| p != pixel));
        self.items.push((pixel, x, y, index));
    }

    /// Whether the wave holds [`BATCH`] samples.
    pub fn is_full(&self) -> bool {
        self.items.len() == BATCH
    }

    /// Whether the wave holds no sample.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Runs the wave's samples into `records` (`stride` words per pixel) and empties it;
    /// returns the samples run.
    pub fn run(
        &mut self,
        it: &Integrator,
        scene: &'s Scene,
        records: &mut [f64],
        stride: usize,
        rays: &mut impl RayLog,
    ) -> u64 {
        self.camera(it, scene, records, stride, rays);
        let max_depth = match it.kind {
            IntegratorKind::Direct => 1,
            _ => it.max_depth as usize,
        };
        for depth in 0..max_depth {
            if !self.vertices(scene) {
                break;
            }
            let extend = depth + 1 < max_depth;
            self.delta_lights(it, scene, rays);
            self.draws(it, scene, depth, extend);
            self.rays(it, scene, rays);
            self.pdfs(it, scene);
            self.records(it, scene, records, stride, depth, extend, rays);
            self.continuation(it, depth);
        }
        for &(pixel, _, _, index) in &self.items {
            pixel_of(records, pixel, stride, index).end_sample();
        }
        let n = self.items.len() as u64;
        self.items.clear();
        self.kind.clear();
        self.vertex.clear();
        self.next.clear();
        n
    }

    /// Stage 1: random streams, camera rays, their nearest hits and what the camera
    /// sees directly (into the records).
    fn camera(
        &mut self,
        it: &Integrator,
        scene: &'s Scene,
        records: &mut [f64],
        stride: usize,
        rays: &mut impl RayLog,
    ) {
        self.cells.clear();
        self.cells
            .extend(self.items.iter().map(|&(_, x, y, index)| (x, y, index)));
        it.sampler.streams_into(&self.cells, &mut self.rng);
        self.at.clear();
        self.beta.clear();
        self.wo.clear();
        let camera_emitters = !it.hide_emitters && it.min_depth == 0;
        for (&(pixel, x, y, index), rng) in self.items.iter().zip(&self.rng) {
            let (ray, first) = it.camera_trace(scene, x, y, rng, rays);
            if camera_emitters {
                pixel_of(records, pixel, stride, index).add(emitted(scene, &first, ray.d));
            }
            self.at.push(first);
            self.beta.push(Rgb::ONE);
            self.wo.push(-ray.d);
        }
    }

    /// The vertex each path shades next (its last ray's surface); whether there is one.
    fn vertices(&mut self, scene: &'s Scene) -> bool {
        let n = self.at.len();
        self.kind.resize(n, Item::Done);
        self.next.resize_with(n, || None);
        self.vertex.resize_with(n, || None);
        let mut any = false;
        for (i, (at, &wo)) in self.at.iter().zip(&self.wo).enumerate() {
            // Written in place: a vertex is about 260 bytes, which a move copies.
            self.vertex[i] = match at {
                Trace::Surface(h) => Some(Vertex::new(scene, h, wo)),
                _ => None,
            };
            self.kind[i] = match &self.vertex[i] {
                None => Item::Done,
                Some(v) if v.bsdf.bxdf.has_specular() => Item::PerRay,
                Some(_) => Item::Shade,
            };
            self.next[i] = None;
            any |= self.kind[i] != Item::Done;
        }
        any
    }

    /// Stage 2: point and spot lights at the vertices.
    fn delta_lights(&mut self, it: &Integrator, scene: &Scene, rays: &mut impl RayLog) {
        self.delta.clear();
        for (v, kind) in self.vertex.iter().zip(&self.kind) {
            self.delta.push(match (v, kind) {
                (Some(v), Item::Shade) => it.delta_lights(scene, v, rays),
                _ => Rgb::ZERO,
            });
        }
    }

    /// Stage 3: every draw of every technique, with the lights along its ray and the
    /// BSDF's value there (and its pdf, where a technique samples the BSDF).
    fn draws(&mut self, it: &Integrator, scene: &Scene, depth: usize, extend: bool) {
        let per = self.technique_of.len();
        for (slot, &(k, j)) in self.technique_of.iter().enumerate() {
            let tech = it.techniques[k];
            let carries = extend && j == 0 && tech == Technique::Bsdf;
            for (i, v) in self.vertex.iter().enumerate() {
                let (Some(v), Item::Shade) = (v, self.kind[i]) else {
                    continue;
                };
                let s = &mut self.slots[i * per + slot];
                let ctx = shading_point(it, scene, v);
                let d = it.dims.technique(&self.rng[i], depth, k, j);
                let drawn = tech.draw(&ctx, d.uc, d.u);
                let Some(ts) = drawn.as_ref() else {
                    s.state = State::Failed;
                    continue;
                };
                debug_assert!(!ts.specular, "delta lobes are shaded per ray");
                s.state = State::Pending;
                s.carries = carries;
                s.weight = ts.bsdf.as_ref().map_or(Rgb::ZERO, |b| b.weight);
                s.wi = ts.wi;
                s.own_pdf = ts.pdf;
                s.ray = spawn(v.p, v.n, ts.wi);
                scene.lights.along_into(&s.ray, it.area_pdfs, &mut s.along);
                let (f, bsdf_pdf) = if it.bsdf_index.is_some() {
                    let (f, p) = v.bsdf.f_pdf(v.wo, ts.wi);
                    (f, Some(p))
                } else {
                    (v.bsdf.f(v.wo, ts.wi), None)
                };
                s.bsdf_pdf = bsdf_pdf;
                s.value = f * v.cos(ts.wi);
            }
        }
    }

    /// Stage 4: the continuation's nearest hit for the draw that extends a path (its
    /// `Li` is what the hit emits), `Li` by a shadow ray for the other draws whose BSDF
    /// value is not 0; the draws of value 0 are skipped, or failed without their pdfs,
    /// as per ray.
    fn rays(&mut self, it: &Integrator, scene: &Scene, rays: &mut impl RayLog) {
        let per = self.technique_of.len();
        for (i, v) in self.vertex.iter().enumerate() {
            let (Some(v), Item::Shade) = (v, self.kind[i]) else {
                continue;
            };
            let beta = self.beta[i];
            for (slot, &(k, _)) in self.technique_of.iter().enumerate() {
                let s = &mut self.slots[i * per + slot];
                if s.state != State::Pending {
                    continue;
                }
                let fc = s.value;
                let skip = v.left_behind(scene, s.wi);
                let li = if s.carries {
                    rays.begin(RayKind::Secondary);
                    let t = trace_along(scene, &s.ray, &s.along, skip);
                    rays.end(RayKind::Secondary);
                    self.next[i] = Some(Continuation {
                        weight: s.weight,
                        trace: t,
                        wi: s.wi,
                    });
                    emitted(scene, &t, s.wi)
                } else if fc != Rgb::ZERO {
                    incident_from(
                        scene,
                        &s.ray,
                        s.along.nearest,
                        skip,
                        v.medium_toward(s.wi),
                        rays,
                    )
                } else {
                    Rgb::ZERO
                };
                s.value = beta * fc * li;
                if s.value != Rgb::ZERO {
                    continue;
                }
                if !it.zero_draws_count {
                    s.state = State::Skipped;
                } else if it.unlit_bsdf_draws_fail
                    && it.techniques[k] == Technique::Bsdf
                    && s.along.crossed().is_some_and(|c| c.lights().is_empty())
                    && scene.lights.environment().is_none()
                {
                    s.state = State::Failed;
                }
            }
        }
    }

    /// Stage 5: every technique's pdf at the draws the combination takes; a draw whose
    /// own pdf is not positive there is refused, as [`Sampling::sample`] refuses it.
    fn pdfs(&mut self, it: &Integrator, scene: &Scene) {
        let per = self.technique_of.len();
        let t_count = it.techniques.len();
        for (i, v) in self.vertex.iter().enumerate() {
            let (Some(v), Item::Shade) = (v, self.kind[i]) else {
                continue;
            };
            let ctx = shading_point(it, scene, v);
            for (slot, &(k, _)) in self.technique_of.iter().enumerate() {
                let at = i * per + slot;
                let s = &mut self.slots[at];
                if s.state != State::Pending {
                    continue;
                }
                let pdfs = &mut self.pdfs[at * t_count..(at + 1) * t_count];
                crate::technique::pdfs_known(
                    it.one_light(),
                    &it.techniques,
                    &ctx,
                    s.wi,
                    s.along.crossed(),
                    s.bsdf_pdf,
                    pdfs,
                );
                s.state = if s.own_pdf.is_nan() && !(pdfs[k] > 0.0 && pdfs[k].is_finite()) {
                    State::Failed
                } else {
                    State::Ready
                };
            }
        }
    }

    /// Stage 6: each sample's outcomes at vertex `depth` into its pixel's record, in the
    /// per-ray order ([`Integrator::shade`]): point lights, the draws, the vertex's end,
    /// then the extra BSDF draw that extends a path without a BSDF technique. Vertices
    /// with a delta lobe are shaded here per ray.
    #[allow(clippy::too_many_arguments)]
    fn records(
        &mut self,
        it: &Integrator,
        scene: &Scene,
        records: &mut [f64],
        stride: usize,
        depth: usize,
        extend: bool,
        rays: &mut impl RayLog,
    ) {
        let per = self.technique_of.len();
        let t_count = it.techniques.len();
        let mute = depth + 1 < it.min_depth as usize;
        for (i, &(pixel, _, _, index)) in self.items.iter().enumerate() {
            let Some(v) = &self.vertex[i] else {
                continue;
            };
            let (beta, rng) = (self.beta[i], &self.rng[i]);
            let mut px = pixel_of(records, pixel, stride, index);
            px.mute = mute;
            match self.kind[i] {
                Item::PerRay => {
                    self.next[i] = it.shade(scene, v, beta, depth, extend, rng, &mut px, rays);
                }
                Item::Shade => {
                    px.add(beta * self.delta[i]);
                    for (slot, &(k, _)) in self.technique_of.iter().enumerate() {
                        let at = i * per + slot;
                        let s = &self.slots[at];
                        match s.state {
                            State::Failed => px.add_failed(it, depth, k),
                            State::Skipped => {}
                            State::Ready => {
                                let light = if it.record.lights > 1 {
                                    light_reached(scene, s.along.nearest)
                                } else {
                                    None
                                };
                                let pdfs = &self.pdfs[at * t_count..(at + 1) * t_count];
                                px.add_draw(it, depth, k, s.value, pdfs, light);
                            }
                            State::Pending => unreachable!("stage 5 settles every draw"),
                        }
                    }
                    px.end_vertex(it, depth);
                    if it.bsdf_index.is_none() && extend {
                        // No BSDF technique: one extra draw extends the path (its
                        // continuous outcomes are already covered by the techniques).
                        let d = it.dims.extra(rng, depth);
                        if let Some(s) = v.bsdf.sample_f(v.wo, d.uc, d.u) {
                            debug_assert!(!s.specular, "delta lobes are shaded per ray");
                            it.li_of_bsdf_draw(
                                scene,
                                v,
                                beta,
                                &s,
                                true,
                                false,
                                None,
                                depth,
                                rng,
                                &mut self.next[i],
                                rays,
                            );
                        }
                    }
                }
                Item::Done => {}
            }
            px.mute = false;
        }
    }

    /// Stage 7: each path's throughput after the continuation drawn at vertex `depth`,
    /// Russian roulette, and what the continuation met ([`Integrator::path_sample`]).
    fn continuation(&mut self, it: &Integrator, depth: usize) {
        for i in 0..self.items.len() {
            let Some(next) = self.next[i].take() else {
                self.at[i] = Trace::Escape;
                continue;
            };
            let beta = &mut self.beta[i];
            *beta *= next.weight;
            let ends = matches!(next.trace, Trace::Light(_) | Trace::Escape)
                || *beta == Rgb::ZERO
                || !beta.is_finite();
            if ends {
                self.at[i] = Trace::Escape;
                continue;
            }
            if depth + 1 >= it.rr_depth as usize {
                let q = (1.0 - beta.max_element()).max(RR_MIN_Q);
                if it.dims.roulette(&self.rng[i], depth) < q {
                    self.at[i] = Trace::Escape;
                    continue;
                }
                *beta /= 1.0 - q;
            }
            self.at[i] = next.trace;
            self.wo[i] = -next.wi;
        }
    }
}

/// The record of the tile's `pixel`-th pixel, for sample `index`.
#[inline]
fn pixel_of(records: &mut [f64], pixel: usize, stride: usize, index: u32) -> Pixel<'_> {
    Pixel {
        rec: &mut records[pixel * stride..(pixel + 1) * stride],
        key: u64::from(index),
        mute: false,
    }
}

/// The shading point of vertex `v` for the techniques.
#[inline]
fn shading_point<'a>(it: &'a Integrator, scene: &'a Scene, v: &'a Vertex) -> ShadingPoint<'a> {
    ShadingPoint {
        p: v.p,
        n: v.n,
        wo: v.wo,
        bsdf: &v.bsdf,
        lights: &scene.lights,
        trained: it.trained.as_deref(),
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Aov, Engine, RenderOptions};
    use crate::scene::{IntegratorKind, Scene};
    use crate::Technique;
    use mis::Method;
    use std::path::Path;
    use std::sync::atomic::AtomicBool;

    /// A shipped scene at `w` × `h` pixels.
    fn scene(name: &str, w: u32, h: u32) -> Scene {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenes")
            .join(name);
        let o = ::scene::Overrides {
            width: Some(w),
            height: Some(h),
            ..Default::default()
        };
        let (data, _) = ::scene::load_with(&path, &o).unwrap();
        Scene::from_data(&data)
    }

    /// The render's state, word for word.
    fn state(scene: &Scene, o: &RenderOptions) -> Vec<u64> {
        let (s, _) =
            crate::render_loop::render(scene, o, &AtomicBool::new(false), &|_, _| {}).unwrap();
        s.data().iter().map(|v| v.to_bits()).collect()
    }

    /// The batched engine gives the per-ray state bit for bit: shipped scenes with area
    /// and point lights, an environment map, glass and mirrors (shaded per ray in the
    /// wave), perturbed and expression solids; `direct` and `path` (roulette, minimum
    /// depths, a path extended by the extra BSDF draw); every estimator family,
    /// per-light mode, the trained selection, emitters hidden; threads 1 and 2 and
    /// tiles smaller than a wave. Renders the wave does not cover (AOVs) run per ray and
    /// agree trivially; two are checked to take that route.
    #[test]
    fn batched_engine_equals_per_ray() {
        let base = RenderOptions {
            integrator: IntegratorKind::Direct,
            spp: 3,
            seed: 11,
            tile_size: 7,
            ..RenderOptions::default()
        };
        let t = |list: &[(Technique, u32)]| list.to_vec();
        let bsdf_light = t(&[(Technique::Bsdf, 1), (Technique::LightPower, 2)]);
        let cases: Vec<(&str, RenderOptions)> = vec![
            ("cornell.toml", base.clone()),
            (
                "cornell.toml",
                RenderOptions {
                    method: Method::OptimalDirect,
                    techniques: t(&[
                        (Technique::Bsdf, 2),
                        (Technique::LightUniform, 1),
                        (Technique::LightArea, 1),
                        (Technique::CosineHemisphere, 1),
                    ]),
                    threads: 2,
                    ..base.clone()
                },
            ),
            (
                "many-lights.toml",
                RenderOptions {
                    method: Method::Power,
                    techniques: t(&[(Technique::LightBvh, 1), (Technique::LightSpatial, 1)]),
                    hide_emitters: true,
                    ..base.clone()
                },
            ),
            (
                "two-lights.toml",
                RenderOptions {
                    method: Method::OptimalProgressive,
                    techniques: bsdf_light.clone(),
                    per_light: 2,
                    ..base.clone()
                },
            ),
            (
                "rooms.toml",
                RenderOptions {
                    method: Method::OptimalDirect,
                    techniques: t(&[(Technique::Bsdf, 1), (Technique::LightTrained, 1)]),
                    min_depth: 1,
                    ..base.clone()
                },
            ),
            (
                "point-lights.toml",
                RenderOptions {
                    method: Method::OptimalUncorrelated,
                    techniques: bsdf_light.clone(),
                    ..base.clone()
                },
            ),
            (
                "environment.toml",
                RenderOptions {
                    method: Method::Balance,
                    techniques: t(&[(Technique::Bsdf, 1), (Technique::Environment, 1)]),
                    threads: 2,
                    ..base.clone()
                },
            ),
            ("table.toml", base.clone()),
            // `path`: glass and mirrors on the way, roulette from the first vertex.
            (
                "cornell.toml",
                RenderOptions {
                    integrator: IntegratorKind::Path,
                    max_depth: 5,
                    rr_depth: 1,
                    ..base.clone()
                },
            ),
            (
                "cornell.toml",
                RenderOptions {
                    integrator: IntegratorKind::Path,
                    method: Method::OptimalDirect,
                    techniques: t(&[(Technique::Bsdf, 1), (Technique::LightArea, 2)]),
                    max_depth: 4,
                    min_depth: 2,
                    threads: 2,
                    ..base.clone()
                },
            ),
            // No BSDF technique: the extra draw extends the path.
            (
                "environment.toml",
                RenderOptions {
                    integrator: IntegratorKind::Path,
                    method: Method::Power,
                    techniques: t(&[(Technique::Environment, 1), (Technique::LightPower, 1)]),
                    max_depth: 3,
                    ..base.clone()
                },
            ),
            (
                "table.toml",
                RenderOptions {
                    integrator: IntegratorKind::Path,
                    method: Method::OptimalProgressive,
                    techniques: bsdf_light.clone(),
                    max_depth: 3,
                    ..base.clone()
                },
            ),
            (
                "point-lights.toml",
                RenderOptions {
                    integrator: IntegratorKind::Path,
                    max_depth: 3,
                    rr_depth: 2,
                    ..base.clone()
                },
            ),
        ];
        for (name, o) in &cases {
            let scene = scene(name, 23, 17);
            let per_ray = state(&scene, o);
            let batched = RenderOptions {
                engine: Engine::Batched,
                ..o.clone()
            };
            let it = super::Integrator::new(&batched).unwrap();
            assert!(it.batched(&scene), "{name}: not batched");
            assert_eq!(state(&scene, &batched), per_ray, "{name} {:?}", o.method);
        }
        // AOV channels and integrators run per ray.
        let scene = scene("cornell.toml", 8, 6);
        for o in [
            RenderOptions {
                integrator: IntegratorKind::Normals,
                ..base.clone()
            },
            RenderOptions {
                aovs: vec![Aov::Depth],
                ..base.clone()
            },
        ] {
            let o = RenderOptions {
                engine: Engine::Batched,
                ..o
            };
            assert!(!super::Integrator::new(&o).unwrap().batched(&scene));
        }
    }
}
