//! The batched engine ([`super::Engine::Batched`]): `direct` over a tile's samples as a
//! wavefront, the GPU back end's pipeline shape (DESIGN.md §4, "two CPU engines, one
//! pipeline shape"; docs/gpu.md).
//!
//! A [`Wave`] holds up to [`BATCH`] samples (pixel, sample index) and runs them stage by
//! stage over the whole batch:
//!
//! 1. **camera**: each sample's random stream, camera ray and nearest hit;
//! 2. **delta lights**: point and spot lights at each first hit;
//! 3. **draws**: for each technique and draw, that draw for every sample, with the lights
//!    along its ray (one walk of the light BVH) and the BSDF's value (and pdf) there;
//! 4. **shadow rays**: `Li` of the draws whose BSDF value is not 0;
//! 5. **pdfs**: every technique's pdf at the draws the MIS combination takes;
//! 6. **records**: each sample's outcomes into its pixel's record, in the per-ray order,
//!    the samples in the batch's order (each pixel's in index order).
//!
//! Every stage calls the per-ray integrator's own functions ([`Integrator::shade`]'s parts)
//! on each sample, and a sample's additions reach its record in the per-ray order, so the
//! state is the per-ray engine's bit for bit (`batched_engine_equals_per_ray`). This is the
//! frame the SIMD stages fill: a stage that runs the same arithmetic over many samples at
//! once replaces its loop, and the test holds it to the same bits or to a documented
//! rounding.
//!
//! **What runs per ray.** The renders the wave does not cover ([`Wave::covers`]: `path`,
//! the AOV integrators and AOV channels, scenes with media or emitting objects) run per
//! ray whole; a sample whose first hit has a delta lobe (mirror, smooth glass or coat) is
//! shaded per ray in stage 6.

use super::ray_log::RayLog;
use super::vertex::{emitted, incident_from, light_reached, spawn, trace, Trace, Vertex};
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

/// What a sample does after its camera ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Item {
    /// Nothing more: its ray met a light or nothing.
    Done,
    /// Shaded by the wave's stages.
    Shade,
    /// Shaded per ray in the record stage (a delta lobe at the hit).
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
    /// f·|cos|, then the draw's value f·|cos|·Li.
    value: Rgb,
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
    kind: Vec<Item>,
    /// The radiance the camera ray sees directly.
    seen: Vec<Rgb>,
    vertex: Vec<Option<Vertex<'s>>>,
    /// Point and spot lights at the hit.
    delta: Vec<Rgb>,
    /// Per sample, its draws in the per-ray order (technique by technique).
    slots: Vec<Slot>,
    /// Every technique's pdf at each slot's direction.
    pdfs: Vec<f64>,
    /// Per slot of a sample: its technique's index.
    technique_of: Vec<usize>,
}

impl<'s> Wave<'s> {
    /// Whether the wave renders `it` on `scene` (module docs).
    pub fn covers(it: &Integrator, scene: &Scene) -> bool {
        it.kind == IntegratorKind::Direct
            && !it.aovs
            && !scene.participating
            && !scene.has_emitting_objects()
    }

    /// An empty wave for `it`'s draws.
    pub fn new(it: &Integrator) -> Self {
        let technique_of: Vec<usize> = it
            .counts
            .iter()
            .enumerate()
            .flat_map(|(k, &n)| std::iter::repeat_n(k, n as usize))
            .collect();
        let slots = technique_of.len() * BATCH;
        Self {
            items: Vec::with_capacity(BATCH),
            cells: Vec::with_capacity(BATCH),
            rng: Vec::with_capacity(BATCH),
            kind: Vec::with_capacity(BATCH),
            seen: Vec::with_capacity(BATCH),
            vertex: Vec::with_capacity(BATCH),
            delta: Vec::with_capacity(BATCH),
            slots: vec![Slot::default(); slots],
            pdfs: vec![0.0; slots * it.techniques.len()],
            technique_of,
        }
    }

    /// Adds sample `index` of pixel (x, y), whose record is the tile's `pixel`-th.
    pub fn push(&mut self, pixel: usize, x: u32, y: u32, index: u32) {
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
        self.camera(it, scene, rays);
        self.delta_lights(it, scene, rays);
        self.draws(it, scene);
        self.shadows(it, scene, rays);
        self.pdfs(it, scene);
        self.records(it, scene, records, stride, rays);
        let n = self.items.len() as u64;
        self.items.clear();
        self.rng.clear();
        self.kind.clear();
        self.seen.clear();
        self.vertex.clear();
        self.delta.clear();
        n
    }

    /// Stage 1: random streams (the first blocks of every sample's evaluated together,
    /// [`crate::Sampler::streams_into`]), camera rays and their nearest hits.
    fn camera(&mut self, it: &Integrator, scene: &'s Scene, rays: &mut impl RayLog) {
        self.cells.clear();
        self.cells
            .extend(self.items.iter().map(|&(_, x, y, index)| (x, y, index)));
        it.sampler.streams_into(&self.cells, &mut self.rng);
        for (&(_, x, y, _), rng) in self.items.iter().zip(&self.rng) {
            rays.begin(RayKind::Generate);
            let ray = it.camera_ray(scene, x, y, rng);
            rays.end(RayKind::Generate);
            rays.begin(RayKind::Camera);
            let first = trace(scene, &ray, None);
            rays.end(RayKind::Camera);
            self.seen.push(emitted(scene, &first, ray.d));
            let v = match first {
                Trace::Surface(ref h) => Some(Vertex::new(scene, h, -ray.d)),
                _ => None,
            };
            self.kind.push(match &v {
                None => Item::Done,
                Some(v) if v.bsdf.bxdf.has_specular() => Item::PerRay,
                Some(_) => Item::Shade,
            });
            self.vertex.push(v);
        }
    }

    /// Stage 2: point and spot lights at the hits.
    fn delta_lights(&mut self, it: &Integrator, scene: &Scene, rays: &mut impl RayLog) {
        for (v, kind) in self.vertex.iter().zip(&self.kind) {
            self.delta.push(match (v, kind) {
                (Some(v), Item::Shade) => it.delta_lights(scene, v, rays),
                _ => Rgb::ZERO,
            });
        }
    }

    /// Stage 3: every draw of every technique, with the lights along its ray and the
    /// BSDF's value there (and its pdf, where a technique samples the BSDF).
    fn draws(&mut self, it: &Integrator, scene: &Scene) {
        let per = self.technique_of.len();
        for (slot, &k) in self.technique_of.iter().enumerate() {
            let tech = it.techniques[k];
            let j = (slot - self.technique_of.iter().position(|&t| t == k).unwrap_or(0)) as u32;
            for (i, v) in self.vertex.iter().enumerate() {
                let (Some(v), Item::Shade) = (v, self.kind[i]) else {
                    continue;
                };
                let s = &mut self.slots[i * per + slot];
                let ctx = shading_point(it, scene, v);
                let d = it.dims.technique(&self.rng[i], 0, k, j);
                let drawn = tech.draw(&ctx, d.uc, d.u);
                let Some(ts) = drawn.as_ref() else {
                    s.state = State::Failed;
                    continue;
                };
                debug_assert!(!ts.specular, "delta lobes are shaded per ray");
                s.state = State::Pending;
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

    /// Stage 4: `Li` by a shadow ray for the draws whose BSDF value is not 0; the
    /// draws of value 0 are skipped, or failed without their pdfs, as per ray.
    fn shadows(&mut self, it: &Integrator, scene: &Scene, rays: &mut impl RayLog) {
        let per = self.technique_of.len();
        for (i, v) in self.vertex.iter().enumerate() {
            let (Some(v), Item::Shade) = (v, self.kind[i]) else {
                continue;
            };
            for (slot, &k) in self.technique_of.iter().enumerate() {
                let s = &mut self.slots[i * per + slot];
                if s.state != State::Pending {
                    continue;
                }
                let fc = s.value;
                let li = if fc != Rgb::ZERO {
                    incident_from(
                        scene,
                        &s.ray,
                        s.along.nearest,
                        v.left_behind(scene, s.wi),
                        v.medium_toward(s.wi),
                        rays,
                    )
                } else {
                    Rgb::ZERO
                };
                // The path throughput of the first vertex is 1, as per ray.
                s.value = Rgb::ONE * fc * li;
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
            for (slot, &k) in self.technique_of.iter().enumerate() {
                let at = i * per + slot;
                let s = &mut self.slots[at];
                if s.state != State::Pending {
                    continue;
                }
                let pdfs = &mut self.pdfs[at * t_count..(at + 1) * t_count];
                crate::technique::pdfs(
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

    /// Stage 6: each sample into its pixel's record, in the per-ray order.
    fn records(
        &mut self,
        it: &Integrator,
        scene: &Scene,
        records: &mut [f64],
        stride: usize,
        rays: &mut impl RayLog,
    ) {
        let per = self.technique_of.len();
        let t_count = it.techniques.len();
        let camera_emitters = !it.hide_emitters && it.min_depth == 0;
        let mute = 1 < it.min_depth;
        for (i, &(pixel, _, _, index)) in self.items.iter().enumerate() {
            let mut px = Pixel {
                rec: &mut records[pixel * stride..(pixel + 1) * stride],
                key: u64::from(index),
                mute: false,
            };
            if camera_emitters {
                px.add(self.seen[i]);
            }
            if let Some(v) = &self.vertex[i] {
                px.mute = mute;
                match self.kind[i] {
                    Item::PerRay => {
                        it.shade(scene, v, Rgb::ONE, 0, false, &self.rng[i], &mut px, rays);
                    }
                    Item::Shade => {
                        px.add(Rgb::ONE * self.delta[i]);
                        for (slot, &k) in self.technique_of.iter().enumerate() {
                            let at = i * per + slot;
                            let s = &self.slots[at];
                            match s.state {
                                State::Failed => px.add_failed(it, 0, k),
                                State::Skipped => {}
                                State::Ready => {
                                    let light = if it.record.lights > 1 {
                                        light_reached(scene, s.along.nearest)
                                    } else {
                                        None
                                    };
                                    let pdfs = &self.pdfs[at * t_count..(at + 1) * t_count];
                                    px.add_draw(it, 0, k, s.value, pdfs, light);
                                }
                                State::Pending => unreachable!("stage 5 settles every draw"),
                            }
                        }
                        px.end_vertex(it, 0);
                    }
                    Item::Done => {}
                }
                px.mute = false;
            }
            px.end_sample();
        }
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
    /// wave), perturbed and expression solids; every estimator family, per-light mode,
    /// the trained selection, a minimum depth, emitters hidden; threads 1 and 2 and
    /// tiles that end mid-wave. Renders the wave does not cover (`path`, AOVs) run per
    /// ray and agree trivially; one of each is checked to take that route.
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
        // `path` and AOV channels run per ray.
        let scene = scene("cornell.toml", 8, 6);
        for o in [
            RenderOptions {
                integrator: IntegratorKind::Path,
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
