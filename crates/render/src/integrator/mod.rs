//! Integrators: what one sample of a pixel computes (Veach 1997, ch. 9; Kondapaneni et al.
//! 2019; pbrt-v4 ch. 13).
//!
//! - [`IntegratorKind::Direct`]: the paper's direct-illumination estimator. Per iteration
//!   (one *sample*): one camera ray and `n_i` draws of each chosen [`Technique`] at the
//!   first hit, every technique's pdf evaluated for every draw, and `(f, pdfs)` handed to
//!   a per-pixel [`mis`] estimator; the pixel value is its estimate.
//! - [`IntegratorKind::Path`]: path tracing with the same per-vertex technique mix at every
//!   vertex, Russian roulette and a maximum depth; optimal MIS keeps one estimator per
//!   pixel and depth (the estimator and why it is consistent: `integrator/path.rs`).
//! - [`IntegratorKind::Depth`], [`IntegratorKind::Normals`], [`IntegratorKind::Albedo`]:
//!   first-hit arbitrary output variables as the image (also available as extra film
//!   channels beside any integrator, [`Aov`]).
//!
//! **Integrand.** At a shading point the direct-lighting integrand of a direction ω is
//! `f(ω) = β · f_s(ωo, ω) · |cos θ| · Li(ω)`, with `Li(ω)` the radiance arriving from ω:
//! the first thing along the ray among objects (which give 0: that light is indirect),
//! area lights (their emission) and, if nothing is met, the environment. It depends on
//! the direction only, as MIS needs (the light techniques' pdfs sum over every way a
//! direction can be drawn). β is the path throughput (1 for `direct`).
//!
//! **Outside MIS** (added to the pixel directly, as the paper does): emission and
//! environment seen by the camera ray; point and spot lights (a shadow ray to each, every
//! sample); and delta BSDF lobes. A delta lobe (mirror, smooth glass, a smooth coat) can be
//! reached by BSDF sampling only: a BSDF draw that lands on one is counted as a *failed*
//! draw in the MIS estimator (its continuous density is 0) and its `weight · Li / n` is
//! added outside. Purely specular surfaces skip MIS altogether (every continuous pdf is 0
//! there): their BSDF draws are all outside. Without a BSDF technique in the list, one
//! extra BSDF draw per vertex serves the delta lobes (and the path's continuation).
//!
//! **Per-light mode** ([`RenderOptions::per_light`]; Kondapaneni et al. 2019, §7: "the
//! illumination from individual light sources is evaluated separately … we add the
//! contributions together"). The directions at a vertex are split into one domain per
//! MIS light: those whose nearest light along the ray (objects ignored) is that light,
//! the environment's being those that meet no area light. Each light keeps its own
//! estimator per pixel and depth; a draw feeds the estimator of the light it reaches,
//! with the same `(f, pdfs)` as otherwise, and counts as a *failed* draw in every other
//! light's (it lies outside that domain: the `mis` crate's extended-domain model keeps
//! `A·n = 1` per light). The pixel is the sum over lights. A heuristic's weight depends
//! only on the pdfs at the draw, so the heuristics give the same image as without the
//! mode (to rounding); the optimal estimators solve one α per light, which can weight a
//! technique differently for each light. The state grows by the number of lights
//! (docs/render-state.md). With `path` and a heuristic there are no estimators, and the
//! mode changes nothing.
//!
//! **Surfaces missed.** An iteration whose camera ray reaches no surface (or, in `path`,
//! whose path ended before depth d) gives no sample to that depth's estimator and is not
//! counted in its iterations `N_d`; the pixel value is `Σ_d (N_d/N)·estimate_d` plus the
//! outside-MIS sum over N. This is the estimator of the depth-d integral conditioned on the
//! path reaching depth d, times the exact fraction that did: consistent for every method,
//! unbiased where the method is, and the optimal α is then the one for the paths that
//! exist (adding failures instead would shrink α towards 0).

mod accumulate;
mod aov;
mod batch;
mod medium;
mod path;
mod ray_log;
mod train;
mod vertex;

pub use ::state::OptionsError;
use ::state::{dims, Combine, Pixel, Tally};
pub use ::state::{
    uses_mis, CpuStages, Engine, LinearMis, LinearRecord, RayCounts, RayKind, Record,
    RenderOptions, ShadedDraw, ShadedVertex, MAX_TECHNIQUES, TIMED_EVERY,
};
pub use accumulate::{Accumulator, CpuHost};
pub use aov::Aov;
pub(crate) use batch::Wave;
use ray_log::RayLog;
pub use train::TRAIN_SPP;

use crate::light::TrainedSelection;
use crate::sampler::Sampler;
pub use crate::scene::IntegratorKind;
use crate::scene::Scene;
use crate::technique::Technique;
#[cfg(doc)]
use mis::Kernel;
use std::sync::Arc;

/// The trained light selection a render of `scene` with `o` would use (None when no
/// technique needs one): the training pass of `integrator/train.rs`, for inspection.
pub fn trained_selection(
    scene: &Scene,
    o: &RenderOptions,
) -> Result<Option<TrainedSelection>, OptionsError> {
    let mut it = Integrator::new(o)?;
    it.prepare(scene)?;
    Ok(it.trained.map(|t| (*t).clone()))
}

#[cfg(test)]
thread_local! {
    /// Tests: integrators made on this thread combine every draw, also those whose value
    /// is 0 under heuristic weights (the reference for skipping them).
    static COUNT_ZERO_DRAWS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

#[cfg(test)]
fn forced_zero_draws() -> bool {
    COUNT_ZERO_DRAWS.with(std::cell::Cell::get)
}

#[cfg(test)]
thread_local! {
    /// Tests: integrators made on this thread take every unlit BSDF draw through its
    /// pdfs (the reference for [`Integrator::unlit_bsdf_draws_fail`]).
    static NO_UNLIT_SHORTCUT: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

#[cfg(test)]
fn unlit_shortcut_allowed() -> bool {
    !NO_UNLIT_SHORTCUT.with(std::cell::Cell::get)
}

#[cfg(not(test))]
fn unlit_shortcut_allowed() -> bool {
    true
}

#[cfg(test)]
thread_local! {
    /// Tests: integrators made on this thread take every zero-valued draw through the
    /// general pdfs (the reference for [`Integrator::unlit_listed`]).
    static NO_UNLIT_LISTED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

#[cfg(test)]
fn unlit_listed_allowed() -> bool {
    !NO_UNLIT_LISTED.with(std::cell::Cell::get)
}

#[cfg(not(test))]
fn unlit_listed_allowed() -> bool {
    true
}

#[cfg(not(test))]
fn forced_zero_draws() -> bool {
    false
}

/// An integrator ready to run: the options digested once per render, the records'
/// bookkeeping ([`Tally`], through `Deref`) and what only the CPU integrator needs.
#[derive(Clone, Debug)]
pub(crate) struct Integrator {
    pub tally: Tally,
    pub sampler: Sampler,
    /// Index of [`Technique::Bsdf`] in the list.
    pub bsdf_index: Option<usize>,
    /// Whether a technique needs the lights' by-area pdfs ([`Technique::LightArea`]).
    pub area_pdfs: bool,
    /// Whether a draw whose value is 0 still enters the MIS combination (the optimal
    /// estimators); else it is skipped before its pdfs are found ([`Kernel::counts_zero_samples`]).
    pub zero_draws_count: bool,
    /// Whether a zero-valued BSDF draw that meets no light (in a scene without an
    /// environment) may be counted as a failed draw without its pdfs: the other
    /// techniques all sample lights, so their pdfs there are 0, and the draw's only term
    /// is `p_k²/(n_k p_k)² = 1/n_k²` on `Â_kk`, a failed draw's (`mis` crate,
    /// `Moments::add_failed`): the same sums and residuals to rounding, at a fraction of
    /// the cost (the heuristics skip such draws altogether).
    pub unlit_bsdf_draws_fail: bool,
    /// Whether a zero-valued draw that still enters the combination may take its pdfs
    /// from the lights its ray crosses in one short call ([`Self::add_unlit`]): every
    /// technique is the BSDF, one light or a light mixture whose pdf is a sum over that
    /// list ([`crate::light::Lights::pdf_listed`]), and one block per vertex. The same sums bit
    /// for bit as through [`crate::technique::pdfs`], at a fraction of the cost (the
    /// heuristics skip such draws; docs/results.md, Overhead).
    pub unlit_listed: bool,
    /// Whether a technique is one light's (`light#k`).
    pub unlit_one: bool,
    /// The technique count where [`Self::unlit_listed`]'s draws take the short form of
    /// optimal-direct's sums ([`mis::Kernel::zero_valued_size`]) and no technique is one
    /// light's; None elsewhere.
    pub unlit_sized: Option<usize>,
    /// Each light's technique where techniques are one light's
    /// ([`crate::technique::one_light_map`]).
    pub one_light_map: Option<crate::technique::OneLightMap>,
    pub max_depth: u32,
    pub rr_depth: u32,
    /// Whether emitters seen by the camera are left out.
    pub hide_emitters: bool,
    /// Whether camera rays go through pixel centres ([`RenderOptions::pixel_center`]).
    pub pixel_center: bool,
    /// Per-light mode: the number of MIS lights (0: off).
    pub per_light: usize,
    /// The render's seed (the training pass derives its streams from it).
    pub seed: u64,
    /// How the training pass runs ([`RenderOptions::training`]).
    pub training: scene::Training,
    /// The trained light selection, once [`Self::prepare`] has trained it.
    pub trained: Option<Arc<TrainedSelection>>,
    /// How the samples run ([`RenderOptions::engine`]).
    pub engine: Engine,
}

impl std::ops::Deref for Integrator {
    type Target = Tally;
    fn deref(&self) -> &Tally {
        &self.tally
    }
}

impl Integrator {
    /// Digests validated options.
    pub fn new(o: &RenderOptions) -> Result<Self, OptionsError> {
        let tally = Tally::new(o)?;
        let zero_draws_count = forced_zero_draws()
            || match &tally.combine {
                Combine::Estimator(k) => k.counts_zero_samples(),
                Combine::Heuristic(_) => false,
            };
        let bsdf_count = tally
            .techniques
            .iter()
            .filter(|&&t| t == Technique::Bsdf)
            .count();
        let unlit_bsdf_draws_fail = zero_draws_count
            && unlit_shortcut_allowed()
            && bsdf_count == 1
            && tally
                .techniques
                .iter()
                .all(|&t| t == Technique::Bsdf || crate::technique::samples_lights(t));
        let unlit_listed = zero_draws_count
            && unlit_listed_allowed()
            && tally.record.lights == 1
            && tally.techniques.iter().all(|&t| {
                matches!(
                    t,
                    Technique::Bsdf
                        | Technique::LightPower
                        | Technique::LightArea
                        | Technique::Light(_)
                )
            });
        let unlit_one = tally
            .techniques
            .iter()
            .any(|t| matches!(t, Technique::Light(_)));
        let one_light_map = crate::technique::one_light_map(&tally.techniques);
        Ok(Self {
            unlit_bsdf_draws_fail,
            unlit_listed: unlit_listed && (!unlit_one || one_light_map.is_some()),
            unlit_sized: match &tally.combine {
                Combine::Estimator(k) if unlit_listed && !unlit_one => k.zero_valued_size(),
                _ => None,
            },
            unlit_one,
            one_light_map,
            sampler: Sampler::new(o.seed),
            bsdf_index: tally.techniques.iter().position(|&t| t == Technique::Bsdf),
            area_pdfs: tally.techniques.contains(&Technique::LightArea),
            zero_draws_count,
            tally,
            max_depth: o.max_depth,
            rr_depth: o.rr_depth,
            hide_emitters: o.hide_emitters,
            pixel_center: o.pixel_center,
            per_light: o.per_light as usize,
            seed: o.seed,
            training: o.training,
            trained: None,
            engine: o.engine,
        })
    }

    /// Checks the options against the scene's lights: `light#k` needs k below the
    /// number of MIS lights (area lights, then the environment), per-light mode their
    /// number.
    pub fn check_scene(&self, scene: &Scene) -> Result<(), OptionsError> {
        let count = scene.lights.count();
        if self.per_light > 0 && scene.lights.area().iter().any(|l| l.proxy) {
            return Err(OptionsError::PerLightEmittingObjects);
        }
        if self.per_light > 0 && self.per_light != count {
            return Err(OptionsError::PerLightMismatch {
                per_light: self.per_light,
                lights: count,
            });
        }
        for t in &self.techniques {
            if let Technique::Light(k) = *t {
                if k >= count {
                    return Err(OptionsError::NoSuchLight {
                        technique: t.name().into_owned(),
                        lights: count,
                    });
                }
            }
        }
        Ok(())
    }

    /// Checks the options against `scene` ([`Self::check_scene`]) and runs the training
    /// pass of `light-trained` if it is listed (`integrator/train.rs`).
    pub fn prepare(&mut self, scene: &Scene) -> Result<(), OptionsError> {
        self.check_scene(scene)?;
        self.trained = self.train(scene).map(Arc::new);
        Ok(())
    }

    /// The camera ray's position in pixel (x, y) of sample stream `rng`: uniform in the
    /// pixel, or its centre. The random dimensions are drawn either way, so the rest of
    /// the sample is the same; a thin lens takes its point from dimensions of its own
    /// ([`dims::LENS`]).
    pub fn camera_ray(
        &self,
        scene: &Scene,
        x: u32,
        y: u32,
        rng: &crate::sampler::SampleStream,
    ) -> frep::Ray {
        let u = rng.get_2d(dims::PIXEL);
        let u = if self.pixel_center {
            glam::DVec2::splat(0.5)
        } else {
            u
        };
        match scene.camera.lens() {
            Some(_) => scene
                .camera
                .ray_through_lens(x, y, u, rng.get_2d(dims::LENS)),
            None => scene.camera.ray(x, y, u),
        }
    }

    /// Where the one-light techniques are, for [`crate::technique::pdfs_known`].
    pub fn one_light(&self) -> crate::technique::OneLight<'_> {
        use crate::technique::OneLight;
        match (&self.one_light_map, self.unlit_one) {
            (_, false) => OneLight::None,
            (Some(m), true) => OneLight::Map(m),
            (None, true) => OneLight::Search,
        }
    }

    /// Whether the samples of this render of `scene` run in [`Wave`]s.
    pub fn batched(&self, scene: &Scene) -> bool {
        self.engine == Engine::Batched && Wave::covers(self, scene)
    }

    /// Runs `wave`'s samples into `records` (`stride` words per pixel): [`Wave::run`],
    /// timed as [`Self::sample`] is.
    pub fn run_wave<'s>(
        &self,
        scene: &'s Scene,
        wave: &mut Wave<'s>,
        records: &mut [f64],
        stride: usize,
        rays: &mut RayCounts,
    ) -> u64 {
        if rays.timing {
            wave.run(
                self,
                scene,
                records,
                stride,
                &mut ray_log::Timed(rays, None),
            )
        } else {
            wave.run(self, scene, records, stride, rays)
        }
    }

    /// The camera ray of pixel (x, y) in stream `rng` and what it meets first among
    /// objects and lights (no media), both queries reported to `rays`.
    fn camera_trace(
        &self,
        scene: &Scene,
        x: u32,
        y: u32,
        rng: &crate::sampler::SampleStream,
        rays: &mut impl RayLog,
    ) -> (frep::Ray, vertex::Trace) {
        rays.begin(RayKind::Generate);
        let ray = self.camera_ray(scene, x, y, rng);
        rays.end(RayKind::Generate);
        rays.begin(RayKind::Camera);
        let first = vertex::trace(scene, &ray, None);
        rays.end(RayKind::Camera);
        (ray, first)
    }

    /// Runs sample `index` of pixel (x, y) into the pixel's record `rec`.
    pub fn sample(
        &self,
        scene: &Scene,
        x: u32,
        y: u32,
        index: u32,
        rec: &mut [f64],
        rays: &mut RayCounts,
    ) {
        if rays.timing {
            self.sample_with(scene, x, y, index, rec, &mut ray_log::Timed(rays, None));
        } else {
            self.sample_with(scene, x, y, index, rec, rays);
        }
    }

    /// [`Self::sample`], reporting queries to `rays`.
    fn sample_with(
        &self,
        scene: &Scene,
        x: u32,
        y: u32,
        index: u32,
        rec: &mut [f64],
        rays: &mut impl RayLog,
    ) {
        let rng = self.sampler.stream(x, y, index);
        let mut px = Pixel {
            rec,
            key: u64::from(index),
            mute: false,
        };
        match self.kind {
            IntegratorKind::Direct | IntegratorKind::Path => {
                self.path_sample(scene, x, y, &rng, &mut px, rays)
            }
            IntegratorKind::Depth | IntegratorKind::Normals | IntegratorKind::Albedo => {
                self.aov_sample(scene, x, y, &rng, &mut px, rays)
            }
        }
        px.end_sample();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::RenderSettings;
    use mis::Method;

    #[test]
    fn options_validate_and_map_from_settings() {
        let ok = RenderOptions::default();
        assert!(ok.validate().is_ok());
        let twice = RenderOptions {
            techniques: vec![(Technique::Bsdf, 1), (Technique::Bsdf, 2)],
            ..ok.clone()
        };
        assert!(matches!(
            twice.validate().unwrap_err(),
            OptionsError::TechniqueTwice(name) if name == "bsdf"
        ));
        let zero = RenderOptions {
            techniques: vec![(Technique::Bsdf, 0)],
            ..ok.clone()
        };
        assert!(zero.validate().is_err());
        let none = RenderOptions {
            techniques: vec![],
            ..ok.clone()
        };
        assert!(none.validate().is_err());
        let aov = RenderOptions {
            integrator: IntegratorKind::Depth,
            techniques: vec![],
            ..ok.clone()
        };
        assert!(aov.validate().is_ok());
        assert!(RenderOptions {
            spp: 0,
            ..ok.clone()
        }
        .validate()
        .is_err());
        let mut settings = RenderSettings {
            aovs: vec!["albedo".into(), "depth".into()],
            ..RenderSettings::default()
        };
        let o = RenderOptions::from_settings(&settings).unwrap();
        assert_eq!(o.aovs, vec![Aov::Albedo, Aov::Depth]);
        assert_eq!((o.integrator, o.spp), (settings.integrator, settings.spp));
        settings.aovs = vec!["position".into()];
        assert!(RenderOptions::from_settings(&settings).is_err());
    }

    /// Skipping the draws whose value is 0 under heuristic weights changes no bit of the
    /// image: a floor, a ball shadowing it, a sphere light and a one-sided rectangle
    /// light without red (most BSDF draws meet no light, many light draws are shadowed;
    /// draws of the rectangle are 0 in red only and must be kept), `direct` and `path`,
    /// balance and power, against the same renders combining every draw.
    #[test]
    fn skipping_zero_draws_changes_no_bit() {
        use crate::camera::Camera;
        use crate::color::Rgb;
        use crate::light::{AreaLight, Lights, Shape as LightShape};
        use crate::scene::{Object, Scene};
        use crate::{Material, Texture};
        use frep::{PerturbedQuadric, Quadric, Shape, Solid};
        use glam::DVec3;
        use std::sync::atomic::AtomicBool;
        let object = |q: Quadric| Object {
            name: "test".into(),
            geometry: Solid::build(&Shape::Perturbed(PerturbedQuadric::new(q)))
                .unwrap()
                .into(),
            material: 0,
            to_local: None,
            interior: None,
            exterior: None,
        };
        let sphere = LightShape::Sphere {
            center: DVec3::new(0.8, 0.1, 1.5),
            radius: 0.3,
        };
        // Facing −z (edge_u × edge_v), one-sided: the ball's top half sees its back.
        let rect = LightShape::Rect {
            corner: DVec3::new(-1.2, -0.4, 1.2),
            edge_u: DVec3::new(0.0, 0.8, 0.0),
            edge_v: DVec3::new(0.6, 0.0, 0.0),
        };
        let scene = Scene::new(
            Camera::look_at(
                DVec3::new(0.0, -2.0, 2.0),
                DVec3::ZERO,
                DVec3::Z,
                50.0,
                20,
                20,
            ),
            vec![Material::Diffuse {
                reflectance: Texture::Constant(Rgb::new(0.8, 0.6, 0.4)),
            }],
            vec![
                object(Quadric::plane(DVec3::Z, 0.0)),
                object(Quadric::sphere(DVec3::new(0.3, 0.0, 0.5), 0.4)),
            ],
            Lights::new(
                vec![
                    AreaLight::new(sphere, Rgb::new(6.0, 4.0, 2.0)),
                    // No red: a draw whose value is 0 in one channel only is kept.
                    AreaLight::new(rect, Rgb::new(0.0, 2.0, 3.0)),
                ],
                vec![],
                None,
                3.0,
            ),
        );
        let render = |o: &RenderOptions, every: bool| {
            COUNT_ZERO_DRAWS.with(|c| c.set(every));
            let r = crate::render_loop::render(&scene, o, &AtomicBool::new(false), &|_, _| {});
            COUNT_ZERO_DRAWS.with(|c| c.set(false));
            r.unwrap().0.image()
        };
        // BSDF, light-power and light-area draws to depth 3.
        let options = |integrator, method, spp, seed| RenderOptions {
            integrator,
            method,
            techniques: vec![
                (Technique::Bsdf, 1),
                (Technique::LightPower, 1),
                (Technique::LightArea, 1),
            ],
            spp,
            seed,
            max_depth: 3,
            ..RenderOptions::default()
        };
        for integrator in [IntegratorKind::Direct, IntegratorKind::Path] {
            for method in [Method::Balance, Method::Power] {
                let o = options(integrator, method, 4, 5);
                assert!(!Integrator::new(&o).unwrap().zero_draws_count);
                let (fast, every) = (render(&o, false), render(&o, true));
                let bits =
                    |i: &crate::Image| i.data().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert!(
                    fast.data().iter().any(|&v| v > 0.0),
                    "{integrator:?} {method}: black"
                );
                assert_eq!(bits(&fast), bits(&every), "{integrator:?} {method}");
            }
        }
        let optimal = RenderOptions {
            method: Method::OptimalDirect,
            ..RenderOptions::default()
        };
        assert!(Integrator::new(&optimal).unwrap().zero_draws_count);
        // The optimal estimators count an unlit BSDF draw as a failed draw without its
        // pdfs: the same image as through its pdfs, bit for bit where the sums are the
        // same numbers (n_bsdf = 1: p²/(1·p)² = 1), the progressive residual −α·p/p
        // against −α to rounding.
        let shortcut = |o: &RenderOptions, on: bool| {
            NO_UNLIT_SHORTCUT.with(|c| c.set(!on));
            assert_eq!(Integrator::new(o).unwrap().unlit_bsdf_draws_fail, on);
            let r = crate::render_loop::render(&scene, o, &AtomicBool::new(false), &|_, _| {});
            NO_UNLIT_SHORTCUT.with(|c| c.set(false));
            r.unwrap().0.image()
        };
        for integrator in [IntegratorKind::Direct, IntegratorKind::Path] {
            for method in [
                Method::OptimalDirect,
                Method::OptimalUncorrelated,
                Method::OptimalProgressive,
            ] {
                let o = options(integrator, method, 8, 6);
                let (fast, slow) = (shortcut(&o, true), shortcut(&o, false));
                assert!(fast.data().iter().any(|&v| v > 0.0));
                for (a, b) in fast.data().iter().zip(slow.data()) {
                    assert!(
                        (a - b).abs() <= 1e-12 * b.abs().max(1e-3),
                        "{integrator:?} {method}: {a} {b}"
                    );
                }
            }
        }
        // Their other zero-valued draws take their pdfs from the lights their rays
        // cross in one short call: the same states, bit for bit.
        let listed = |o: &RenderOptions, on: bool| {
            NO_UNLIT_LISTED.with(|c| c.set(!on));
            assert_eq!(Integrator::new(o).unwrap().unlit_listed, on);
            let r = crate::render_loop::render(&scene, o, &AtomicBool::new(false), &|_, _| {});
            NO_UNLIT_LISTED.with(|c| c.set(false));
            r.unwrap().0.to_bytes()
        };
        for integrator in [IntegratorKind::Direct, IntegratorKind::Path] {
            for method in [
                Method::OptimalDirect,
                Method::OptimalUncorrelated,
                Method::OptimalProgressive,
            ] {
                let mut o = options(integrator, method, 8, 7);
                let one = [(Technique::Light(0), 1), (Technique::Light(1), 2)];
                let mixtures = [(Technique::LightPower, 1), (Technique::LightArea, 1)];
                for techniques in [
                    o.techniques.clone(),
                    vec![(Technique::LightPower, 2), (Technique::LightArea, 1)],
                    vec![(Technique::LightPower, 1), (Technique::Bsdf, 2)],
                    // One technique per light, alone and beside the mixtures.
                    [&one[..], &[(Technique::Bsdf, 1)]].concat(),
                    [&one[..], &mixtures[..], &[(Technique::Bsdf, 1)]].concat(),
                ] {
                    o.techniques = techniques;
                    // Optimal-direct's short form of the sums where no technique is
                    // one light's (`Integrator::unlit_sized`).
                    let t = o.techniques.len();
                    let one_light = o
                        .techniques
                        .iter()
                        .any(|t| matches!(t.0, Technique::Light(_)));
                    let sized = (method == Method::OptimalDirect && !one_light).then_some(t);
                    assert_eq!(Integrator::new(&o).unwrap().unlit_sized, sized);
                    let (on, off) = (listed(&o, true), listed(&o, false));
                    assert!(on == off, "{integrator:?} {method} {:?}", o.techniques);
                }
            }
        }
    }

    /// Up to [`MAX_TECHNIQUES`] techniques; the per-pixel state of optimal-direct is
    /// `4 + (1 + T(T+1)/2 + 3T)·depths·lights` words (docs/render-state.md).
    #[test]
    fn technique_limit_and_state_size() {
        let many = |t: usize, method, per_light| RenderOptions {
            method,
            per_light,
            techniques: (0..t).map(|k| (Technique::Light(k), 1)).collect(),
            ..RenderOptions::default()
        };
        assert!(many(MAX_TECHNIQUES, Method::Balance, 0).validate().is_ok());
        let e = many(MAX_TECHNIQUES + 1, Method::Balance, 0)
            .validate()
            .unwrap_err();
        assert_eq!(e, OptionsError::TooManyTechniques(33));
        assert!(e.to_string().contains("at most 32"), "{e}");
        let stride = |t, m, l| Integrator::new(&many(t, m, l)).unwrap().record.stride();
        assert_eq!(stride(32, Method::OptimalDirect, 0), 4 + 1 + 528 + 96);
        assert_eq!(stride(3, Method::OptimalDirect, 0), 4 + 1 + 6 + 9);
        assert_eq!(stride(3, Method::OptimalDirect, 10), 4 + 10 * 16);
        assert_eq!(stride(3, Method::Balance, 10), 4 + 10 * 4);
    }
}
