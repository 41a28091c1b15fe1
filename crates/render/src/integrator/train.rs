//! The training pass of `light-trained` ([`crate::light::TrainedSelection`]): before the
//! render, [`RenderOptions::training`](super::RenderOptions::training)`.spp` camera rays
//! per pixel (default [`TRAIN_SPP`]) find first-hit shading points; at each,
//! one MIS light chosen uniformly is sampled once and its contribution
//! `L · lum(f_s · |cos θ| · Li) / p` is measured with a shadow ray (visibility included,
//! L the number of MIS lights: the uniform choice's 1/L undone). The sums per cell of a
//! `grid`³ grid over the bounding box of those points (default [`TRAIN_GRID`]) are the
//! weights of [`TrainedSelection::from_draws`], with the options' `floor` (a sparse
//! table: only the lights measured in a cell are kept there).
//!
//! The pass draws from its own random streams (the render's seed with a salt), so it is
//! the same for every sample range of a render (split renders merge) and for any thread
//! count (it runs on one thread, in pixel order); its samples are not part of the
//! image, and its rays are not counted in the render's statistics. It trains on first
//! hits only: `path` uses the same table at deeper vertices (points outside the box go
//! to the nearest cell).

use super::vertex::{incident, spawn, Vertex};
use super::{Integrator, RayCounts};
use crate::color::luminance;
#[cfg(doc)]
use crate::light::TRAIN_GRID;
use crate::light::{Selection, TrainedSelection};
use crate::sampler::Sampler;
use crate::scene::Scene;
use crate::technique::Technique;
use glam::{DVec2, DVec3};

/// Training samples per pixel, by default (`scene::Training::spp`).
pub const TRAIN_SPP: u32 = 4;

/// Mixed into the seed for the training streams ("light-tr").
const TRAIN_SALT: u64 = 0x6c69_6768_742d_7472;

impl Integrator {
    /// The trained selection for `scene`, when a technique needs one (module docs).
    pub(crate) fn train(&self, scene: &Scene) -> Option<TrainedSelection> {
        if !self.techniques.contains(&Technique::LightTrained) {
            return None;
        }
        let lights = scene.lights.count();
        if lights == 0 {
            return None;
        }
        let sampler = Sampler::new(self.seed ^ TRAIN_SALT);
        let mut rays = RayCounts::default();
        // (point, light, measured contribution) of every training draw.
        let mut draws: Vec<(DVec3, usize, f64)> = Vec::new();
        let (w, h) = (scene.camera.width, scene.camera.height);
        for y in 0..h {
            for x in 0..w {
                for i in 0..self.training.spp {
                    let rng = sampler.stream(x, y, i);
                    let ray = scene.camera.ray_through_lens(
                        x,
                        y,
                        rng.get_2d(state::dims::PIXEL),
                        rng.get_2d(state::dims::LENS),
                    );
                    let Some(hit) = scene.intersect(&ray, 0.0, f64::INFINITY) else {
                        continue;
                    };
                    if scene.lights.intersect(&ray, 0.0, hit.t).is_some() {
                        continue;
                    }
                    let v = Vertex::new(scene, &hit, -ray.d);
                    if v.bsdf.bxdf.is_pure_specular() {
                        continue;
                    }
                    let k = ((rng.get(2) * lights as f64) as usize).min(lights - 1);
                    let u = DVec2::new(rng.get(3), rng.get(4));
                    let value = scene
                        .lights
                        .sample_selected(Selection::One(k), v.p, v.n, 0.0, u)
                        .map_or(0.0, |s| {
                            let fc = v.bsdf.f(v.wo, s.wi) * v.cos(s.wi);
                            if luminance(fc) <= 0.0 {
                                return 0.0;
                            }
                            let li = incident(
                                scene,
                                &spawn(v.p, v.n, s.wi),
                                v.left_behind(scene, s.wi),
                                v.medium_toward(s.wi),
                                &mut rays,
                            );
                            lights as f64 * luminance(fc * li) / s.pdf
                        });
                    draws.push((v.p, k, value));
                }
            }
        }
        let (lo, hi) = draws.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), d| (lo.min(d.0), hi.max(d.0)),
        );
        let (lo, hi) = if lo.x <= hi.x {
            // A hair of margin so that the far faces fall inside the last cells.
            let pad = (hi - lo).max_element().max(1e-9) * 1e-6;
            (lo - pad, hi + pad)
        } else {
            (DVec3::ZERO, DVec3::ONE)
        };
        let (grid, floor) = (self.training.grid as usize, self.training.floor);
        let cells = draws
            .into_iter()
            .map(|(p, k, value)| (TrainedSelection::cell_of(lo, hi, grid, p), k, value));
        Some(TrainedSelection::from_draws(
            lo, hi, grid, lights, floor, cells,
        ))
    }
}
