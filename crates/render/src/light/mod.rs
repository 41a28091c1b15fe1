//! Light sources (pbrt-v4 ch. 12) and the scene's collection of them.
//!
//! Area lights and the environment have pdfs in solid angle and take part in MIS;
//! point and spot lights ([`DeltaLight`]) are sampled on their own. Every sampling
//! routine here reports the density of the *direction* it produced, summed over every
//! way the routine could have produced it (e.g. a sphere seen through another light),
//! so that the pdfs integrate to 1 over the sphere of directions.

mod area;
mod delta;
mod environment;
mod importance_pair;
mod select;
mod tree;

pub use area::{AreaLight, Crossing, Shape};
pub use delta::DeltaLight;
pub use environment::{EnvMap, Environment};
pub use select::{importance, importance_of, Along, Crossed, ImportanceBounds, Selection};
pub use state::trained::{TrainedSelection, TRAIN_FLOOR, TRAIN_GRID};
pub use tree::LightTree;

use crate::color::{luminance, Rgb};
use crate::distribution::Distribution1D;
use frep::{Bvh, Ray};
use glam::{DVec2, DVec3};

/// A direction toward a light, drawn from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the shading point toward the light.
    pub wi: DVec3,
    /// Distance to the sampled point (infinite for the environment).
    pub dist: f64,
    /// Radiance leaving the sampled point toward the shading point (0 when it faces
    /// away); for delta lights, I/d².
    pub radiance: Rgb,
    /// Solid-angle density of the direction (1 for delta lights).
    pub pdf: f64,
    /// Whether the light is a delta light.
    pub delta: bool,
    /// Index of the sampled area light (None: environment or delta light).
    pub light: Option<usize>,
}

/// The nearest area light along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightHit {
    /// Index into [`Lights::area`].
    pub light: usize,
    /// Ray parameter.
    pub t: f64,
    /// Outward normal of the light there.
    pub n: DVec3,
    /// Radiance leaving the light toward the ray origin.
    pub radiance: Rgb,
}

/// The area lights' importance bounds and the luminance of their power, what
/// [`importance_of`] reads.
fn importance_inputs(area: &[AreaLight]) -> Vec<(ImportanceBounds, f64)> {
    area.iter()
        .map(|l| (l.importance_bounds(), luminance(l.power())))
        .collect()
}

/// The fewest wide nodes a light BVH has for [`Lights::intersect`] to walk it in AVX
/// lanes (where the CPU has AVX), from a function compiled for AVX: with 10 000 lights
/// the four f64 lanes take fewer instructions than SSE2's two pairs; a small tree walks
/// inlined. (The walk along a draw's ray, [`Lights::along`], stays inlined: behind the
/// same branch it cost the small scenes 0.3 % more instructions.)
const AVX_WIDE_NODES: usize = 16;

/// The BVH over the area lights' boxes, and whether [`Lights::intersect`] walks it in AVX
/// lanes ([`AVX_WIDE_NODES`]).
fn light_bvh(area: &[AreaLight]) -> (Bvh, bool) {
    let bvh = Bvh::new(&area.iter().map(AreaLight::bounds).collect::<Vec<_>>());
    let avx = bvh.wide().len() >= AVX_WIDE_NODES && bvh.as_ref().has_avx_walk();
    (bvh, avx)
}

/// [`Lights::intersect`]'s body over `walk`, a nearest-hit walk of the light BVH: written
/// once for the inlined walk and the AVX one, each with the closure written at its call.
macro_rules! nearest_light {
    ($lights:expr, $ray:expr, $t_min:expr, $t_max:expr, $($walk:tt)+) => {{
        let lights = $lights;
        let mut n = DVec3::ZERO;
        let (i, t) = $($walk)+($ray, $t_min, $t_max, |i: usize, lim: f64| {
            if lights.area[i].proxy {
                return None;
            }
            let c = lights.area[i].intersect($ray, $t_min, lim)?;
            n = c.n;
            Some(c.t)
        })?;
        // `n` is the last accepted crossing's, the nearest: `nearest` only accepts hits
        // below its shrinking t_max.
        Some(LightHit {
            light: i,
            t,
            n,
            radiance: lights.area[i].emitted(n, -$ray.d),
        })
    }};
}

/// All lights of a scene, with the distributions used to choose among them.
#[derive(Clone, Debug)]
pub struct Lights {
    area: Vec<AreaLight>,
    delta: Vec<DeltaLight>,
    environment: Option<Environment>,
    /// Area lights then (last) the environment, ∝ luminance of power.
    by_power: Option<Distribution1D>,
    /// Area lights ∝ area.
    by_area: Option<Distribution1D>,
    /// A BVH over the area lights' boxes: a ray meets, and a direction has density
    /// under, only the lights whose box it crosses, so queries cost O(log n).
    bvh: Bvh,
    /// Whether [`Self::intersect`] walks [`Self::bvh`] in AVX lanes ([`AVX_WIDE_NODES`]).
    avx_walk: bool,
    /// The light BVH of [`Selection::Bvh`] (None without an area light).
    tree: Option<LightTree>,
    /// Per area light, [`importance_inputs`]: found once, read by every
    /// [`Selection::Spatial`] query (which sums over every light).
    importance: Vec<(ImportanceBounds, f64)>,
}

impl Lights {
    /// The lights of a scene whose geometry fits in a ball of radius `scene_radius`
    /// (which sets the environment's power for selection).
    pub fn new(
        area: Vec<AreaLight>,
        delta: Vec<DeltaLight>,
        environment: Option<Environment>,
        scene_radius: f64,
    ) -> Self {
        let mut power: Vec<f64> = area.iter().map(|l| luminance(l.power())).collect();
        if let Some(e) = &environment {
            power.push(luminance(e.power(scene_radius)));
        }
        let by_power = (!power.is_empty()).then(|| Distribution1D::new(&power));
        let areas: Vec<f64> = area.iter().map(|l| l.area()).collect();
        let by_area = (!areas.is_empty()).then(|| Distribution1D::new(&areas));
        let importance = importance_inputs(&area);
        let (bvh, avx_walk) = light_bvh(&area);
        Self {
            avx_walk,
            bvh,
            tree: LightTree::new(&importance),
            importance,
            area,
            delta,
            environment,
            by_power,
            by_area,
        }
    }
    /// The lights with selection distributions computed elsewhere (a resolved scene's):
    /// `by_power` over the area lights then the environment, `by_area` over the area
    /// lights.
    pub fn from_parts(
        area: Vec<AreaLight>,
        delta: Vec<DeltaLight>,
        environment: Option<Environment>,
        by_power: Option<Distribution1D>,
        by_area: Option<Distribution1D>,
    ) -> Self {
        let n = area.len() + usize::from(environment.is_some());
        assert_eq!(by_power.as_ref().map_or(0, |d| d.len()), n, "by_power");
        assert_eq!(
            by_area.as_ref().map_or(0, |d| d.len()),
            area.len(),
            "by_area"
        );
        let importance = importance_inputs(&area);
        let (bvh, avx_walk) = light_bvh(&area);
        Self {
            avx_walk,
            bvh,
            tree: LightTree::new(&importance),
            importance,
            area,
            delta,
            environment,
            by_power,
            by_area,
        }
    }
    /// The area lights.
    pub fn area(&self) -> &[AreaLight] {
        &self.area
    }
    /// The point and spot lights.
    pub fn delta(&self) -> &[DeltaLight] {
        &self.delta
    }
    /// The environment, if any.
    pub fn environment(&self) -> Option<&Environment> {
        self.environment.as_ref()
    }
    /// The light BVH of [`Selection::Bvh`] (None without an area light).
    pub fn tree(&self) -> Option<&LightTree> {
        self.tree.as_ref()
    }
    /// The nearest area light along `ray` (unit direction) with t in (t_min, t_max).
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<LightHit> {
        #[cfg(target_arch = "x86_64")]
        if self.avx_walk {
            // SAFETY: `avx_walk` holds only where the CPU has AVX.
            return unsafe { self.intersect_avx(ray, t_min, t_max) };
        }
        nearest_light!(self, ray, t_min, t_max, self.bvh.nearest)
    }

    /// [`Self::intersect`] compiled for AVX, its BVH walk in AVX lanes.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn intersect_avx(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<LightHit> {
        // SAFETY (the walk): compiled for AVX, called where the CPU has it.
        nearest_light!(self, ray, t_min, t_max, self.bvh.as_ref().nearest_avx)
    }
    /// Radiance arriving at `ray.o` from direction `ray.d` when nothing but lights
    /// lies in (t_min, t_max): the nearest area light, or the environment if the ray
    /// escapes (t_max infinite).
    pub fn radiance_along(&self, ray: &Ray, t_min: f64, t_max: f64) -> Rgb {
        match self.intersect(ray, t_min, t_max) {
            Some(h) => h.radiance,
            None if t_max == f64::INFINITY => self.environment_radiance(ray.d),
            None => Rgb::ZERO,
        }
    }
    /// Radiance of the environment from direction `dir` (0 without one).
    pub fn environment_radiance(&self, dir: DVec3) -> Rgb {
        self.environment
            .as_ref()
            .map_or(Rgb::ZERO, |e| e.radiance(dir))
    }
    fn env_sample(&self, u: DVec2) -> Option<LightSample> {
        let e = self.environment.as_ref()?;
        let (wi, pdf) = e.sample(u)?;
        Some(LightSample {
            wi,
            dist: f64::INFINITY,
            radiance: e.radiance(wi),
            pdf,
            delta: false,
            light: None,
        })
    }
    /// Light sampling: a light (or the environment) chosen ∝ power with `uc`, then
    /// its preferred sampling ([`AreaLight::sample_li`]); pdf = [`Self::pdf_by_power`].
    /// [`Self::sample_selected`] with [`Selection::Power`].
    pub fn sample_by_power(&self, p: DVec3, uc: f64, u: DVec2) -> Option<LightSample> {
        self.sample_selected(Selection::Power, p, DVec3::ZERO, uc, u)
    }
    /// Σ_lights P(light) · pdf_light(wi), over every light the direction meets.
    pub fn pdf_by_power(&self, p: DVec3, wi: DVec3) -> f64 {
        self.pdf_selected(Selection::Power, p, DVec3::ZERO, wi)
    }
    /// Uniform light-area sampling: an area light chosen ∝ area, then a point uniform
    /// on it, i.e. a point uniform over the total emitting area; pdf =
    /// [`Self::pdf_by_area`].
    pub fn sample_by_area(&self, p: DVec3, uc: f64, u: DVec2) -> Option<LightSample> {
        let s = self.draw_by_area(p, uc, u)?;
        let pdf = self.pdf_by_area(p, s.wi);
        (pdf > 0.0).then_some(LightSample { pdf, ..s })
    }
    /// [`Self::sample_by_area`]'s direction without its pdf (NaN), for a caller that
    /// evaluates every technique's pdf at the direction anyway.
    pub fn draw_by_area(&self, p: DVec3, uc: f64, u: DVec2) -> Option<LightSample> {
        let (i, _, _) = self.by_area.as_ref()?.sample_discrete(uc);
        let s = self.area[i].sample_area(p, u)?;
        Some(LightSample {
            pdf: f64::NAN,
            light: Some(i),
            ..s
        })
    }
    /// Σ_lights P(light) · pdf_area,light(wi).
    pub fn pdf_by_area(&self, p: DVec3, wi: DVec3) -> f64 {
        self.pdf_by_area_over(p, wi, None)
    }
    /// [`Self::pdf_by_area`] over the lights `crossed` lists (with their by-area pdfs;
    /// None: found by the BVH here), bit for bit the same.
    pub fn pdf_by_area_over(&self, p: DVec3, wi: DVec3, crossed: Option<&Crossed>) -> f64 {
        let Some(d) = &self.by_area else {
            return 0.0;
        };
        // Only the lights the ray from p along wi crosses have density there.
        let mut sum = 0.0;
        match crossed {
            Some(c) => {
                for (&i, &pdf) in c.lights().iter().zip(c.pdf_area()) {
                    sum += d.pmf(i as usize) * pdf;
                }
            }
            None => self
                .bvh
                .for_each_hit(&Ray::new(p, wi), 0.0, f64::INFINITY, |i| {
                    sum += d.pmf(i) * self.area[i].pdf_area(p, wi)
                }),
        }
        sum
    }
    /// Environment sampling (None without an environment).
    pub fn sample_environment(&self, u: DVec2) -> Option<LightSample> {
        self.env_sample(u)
    }
    /// The density of [`Self::sample_environment`].
    pub fn pdf_environment(&self, wi: DVec3) -> f64 {
        self.environment.as_ref().map_or(0.0, |e| e.pdf(wi))
    }
}

#[cfg(test)]
mod tests;
