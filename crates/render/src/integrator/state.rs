//! Per-pixel accumulation into a flat record, and ray counters.
//!
//! A pixel's record is `[N | outside-MIS Σ (R, G, B) | AOV Σ (7, if any) | one
//! [`mis::Kernel`] block per vertex depth]` ([`Record`]): plain `f64` words, so that the
//! records of a whole image are one array ([`crate::RenderState`]) that merges, serialises
//! and uploads as data.

use super::{Combine, Integrator};
use crate::color::Rgb;
use std::ops::AddAssign;

/// Rays traced, by kind: camera rays, secondary rays (nearest-hit queries that extend a
/// path) and shadow rays (any-hit visibility queries). Queries against the analytic area
/// lights alone are not counted. Also where the time went, for the stage breakdown of
/// `frepray bench` (the paper's Fig. 4–5): with `timing`, one query of each kind in
/// [`TIMED_EVERY`] (and the camera ray's generation with it) is timed, so that the timers
/// cost a few ns per ray, and each worker's busy time per tile.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Camera rays.
    pub camera: u64,
    /// Secondary (continuation) rays.
    pub secondary: u64,
    /// Shadow rays.
    pub shadow: u64,
    /// Nanoseconds of the timed queries: camera-ray generation, camera, secondary and
    /// shadow queries ([`RayKind`] order).
    pub timed_ns: [u64; 4],
    /// Nanoseconds the workers spent rendering tiles, all threads together.
    pub busy_ns: u64,
    /// Whether queries are timed ([`super::RenderOptions::stage_times`]).
    pub timing: bool,
}

/// One query of each kind in this many is timed.
pub const TIMED_EVERY: u64 = 16;

/// What a timed stretch of work is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// Generating a camera ray (its pixel position, lens and direction).
    Generate = 0,
    /// A camera ray's nearest-hit query.
    Camera = 1,
    /// A secondary ray's nearest-hit query.
    Secondary = 2,
    /// A shadow ray's any-hit query.
    Shadow = 3,
}

/// Estimated time per stage of a render, all worker threads together.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CpuStages {
    /// Camera-ray generation.
    pub generate: std::time::Duration,
    /// Camera-ray queries.
    pub camera: std::time::Duration,
    /// Secondary-ray queries.
    pub secondary: std::time::Duration,
    /// Shadow-ray queries.
    pub shadow: std::time::Duration,
    /// The rest of the workers' time: sampling, shading, light and BSDF pdfs, MIS
    /// weights and sums.
    pub shade: std::time::Duration,
}

impl RayCounts {
    /// No rays yet; `timing`: time the stages ([`super::RenderOptions::stage_times`]).
    pub fn new(timing: bool) -> Self {
        Self {
            timing,
            ..Self::default()
        }
    }

    /// All rays.
    pub fn total(&self) -> u64 {
        self.camera + self.secondary + self.shadow
    }

    /// Counts a query of `kind` (none for [`RayKind::Generate`]); returns its number
    /// among its kind (from 0).
    #[inline(always)]
    fn count(&mut self, kind: RayKind) -> u64 {
        let n = match kind {
            RayKind::Generate => return self.camera,
            RayKind::Camera => &mut self.camera,
            RayKind::Secondary => &mut self.secondary,
            RayKind::Shadow => &mut self.shadow,
        };
        *n += 1;
        *n - 1
    }

    /// The estimated time per stage: each kind's timed queries scaled by all its
    /// queries over the timed ones; the rest of the busy time is shading.
    pub fn stages(&self) -> CpuStages {
        let est = |kind: RayKind, count: u64| {
            let timed = count.div_ceil(TIMED_EVERY);
            let ns = self.timed_ns[kind as usize] as f64 * count as f64 / timed.max(1) as f64;
            std::time::Duration::from_nanos(ns as u64)
        };
        let generate = est(RayKind::Generate, self.camera);
        let camera = est(RayKind::Camera, self.camera);
        let secondary = est(RayKind::Secondary, self.secondary);
        let shadow = est(RayKind::Shadow, self.shadow);
        let busy = std::time::Duration::from_nanos(self.busy_ns);
        CpuStages {
            generate,
            camera,
            secondary,
            shadow,
            shade: busy.saturating_sub(generate + camera + secondary + shadow),
        }
    }
}

/// Where the integrator reports its ray queries: [`RayCounts`] counts them, [`Timed`]
/// also times one in [`TIMED_EVERY`]. The integrator is generic over it, so that a
/// render without timers has no timer code in its loop at all (a branch on a flag there
/// cost 2–4 %: docs/notebook/2026-11-30-cpu-and-gpu-on-lavapipe.md).
pub(crate) trait RayLog {
    /// Before a query of `kind` (or a camera ray's generation).
    fn begin(&mut self, kind: RayKind);
    /// After it.
    fn end(&mut self, kind: RayKind);
}

impl RayLog for RayCounts {
    #[inline(always)]
    fn begin(&mut self, kind: RayKind) {
        self.count(kind);
    }
    #[inline(always)]
    fn end(&mut self, _: RayKind) {}
}

/// [`RayCounts`] that also times one query of each kind in [`TIMED_EVERY`]: the counts,
/// and when the query being timed started.
pub(crate) struct Timed<'a>(pub &'a mut RayCounts, pub Option<std::time::Instant>);

impl RayLog for Timed<'_> {
    #[inline(always)]
    fn begin(&mut self, kind: RayKind) {
        let n = self.0.count(kind);
        self.1 = n.is_multiple_of(TIMED_EVERY).then(std::time::Instant::now);
    }
    #[inline(always)]
    fn end(&mut self, kind: RayKind) {
        if let Some(t) = self.1.take() {
            self.0.timed_ns[kind as usize] += t.elapsed().as_nanos() as u64;
        }
    }
}

impl AddAssign for RayCounts {
    fn add_assign(&mut self, o: RayCounts) {
        self.camera += o.camera;
        self.secondary += o.secondary;
        self.shadow += o.shadow;
        for (a, b) in self.timed_ns.iter_mut().zip(o.timed_ns) {
            *a += b;
        }
        self.busy_ns += o.busy_ns;
        self.timing |= o.timing;
    }
}

/// Where each sum lives in a pixel's record (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Record {
    /// AOV words (7: depth, normal, albedo; or 0).
    pub aov: usize,
    /// Vertex depths with MIS blocks.
    pub depths: usize,
    /// MIS blocks per depth: 1, or in per-light mode one per MIS light.
    pub lights: usize,
    /// Words of one MIS block.
    pub block: usize,
}

impl Record {
    /// Offset of the outside-MIS sums.
    pub const OUTSIDE: usize = 1;
    /// Offset of the AOV sums.
    pub const AOV: usize = 4;
    /// Words of one record.
    pub fn stride(&self) -> usize {
        Self::AOV + self.aov + self.blocks() * self.block
    }
    /// MIS blocks per record: depths × lights.
    pub fn blocks(&self) -> usize {
        self.depths * self.lights
    }
    /// [`Record::blocks`], `None` where it overflows.
    pub fn blocks_checked(&self) -> Option<usize> {
        self.depths.checked_mul(self.lights)
    }
    /// The range of block `i` (depth `i / lights`, light `i % lights`).
    pub fn block_range(&self, i: usize) -> std::ops::Range<usize> {
        let at = Self::AOV + self.aov + i * self.block;
        at..at + self.block
    }
    /// The range of the block of depth `d` and light `l` (0 when not per light).
    pub fn depth_light(&self, d: usize, l: usize) -> std::ops::Range<usize> {
        self.block_range(d * self.lights + l)
    }
}

/// One pixel's record while a sample runs: the view the integrators add into. `key` is
/// the sample's global index, which keys the uncorrelated estimator's sets. While
/// `mute` is set (a vertex below [`super::RenderOptions::min_depth`]) nothing but AOVs
/// is added.
pub(crate) struct Pixel<'a> {
    pub rec: &'a mut [f64],
    pub key: u64,
    pub mute: bool,
}

impl Pixel<'_> {
    /// Adds `c` outside MIS.
    #[inline]
    pub fn add(&mut self, c: Rgb) {
        if self.mute {
            return;
        }
        let s = &mut self.rec[Record::OUTSIDE..Record::OUTSIDE + 3];
        s[0] += c.x;
        s[1] += c.y;
        s[2] += c.z;
    }

    /// Adds one sample's AOV values (depth, normal, albedo) if the record keeps them.
    #[inline]
    pub fn add_aovs(&mut self, v: &[f64; 7]) {
        if let Some(s) = self.rec.get_mut(Record::AOV..Record::AOV + 7) {
            for (s, v) in s.iter_mut().zip(v) {
                *s += v;
            }
        }
    }

    /// Counts the finished sample.
    #[inline]
    pub fn end_sample(&mut self) {
        self.rec[0] += 1.0;
    }

    /// A draw of technique `k` at vertex `depth` with integrand `f` (throughput included)
    /// and every technique's pdf. `light` is the MIS light the draw's ray reaches
    /// (nearest along it, objects ignored): in per-light mode its block gets the draw
    /// and every other light's block a failed draw (the draw lies outside that light's
    /// domain); None (no light) fails in every block. Ignored otherwise.
    #[inline]
    pub fn add_draw(
        &mut self,
        it: &Integrator,
        depth: usize,
        k: usize,
        f: Rgb,
        pdfs: &[f64],
        light: Option<usize>,
    ) {
        if self.mute {
            return;
        }
        match &it.combine {
            Combine::Heuristic(h) => {
                // w_k f / (n_k p_k) (Veach 1997, eq. 9.4); a draw with own pdf 0 adds 0.
                let Some(s) = it.layout.is_valid(k, pdfs) else {
                    return;
                };
                let scale = match h {
                    mis::Heuristic::Balance => 1.0 / s,
                    h => h.scale(k, it.layout.counts(), pdfs),
                };
                if scale != 0.0 {
                    self.add(f * scale);
                }
            }
            Combine::Estimator(kernel) => {
                if it.record.lights == 1 {
                    let r = it.record.depth_light(depth, 0);
                    kernel.add_sample(&mut self.rec[r], self.key, k, &f.to_array(), pdfs);
                    return;
                }
                for l in 0..it.record.lights {
                    let r = it.record.depth_light(depth, l);
                    if Some(l) == light {
                        kernel.add_sample(&mut self.rec[r], self.key, k, &f.to_array(), pdfs);
                    } else {
                        kernel.add_failed(&mut self.rec[r], self.key, k);
                    }
                }
            }
        }
    }

    /// Technique `k` produced no draw (or a delta-lobe draw) at vertex `depth`.
    #[inline]
    pub fn add_failed(&mut self, it: &Integrator, depth: usize, k: usize) {
        if self.mute {
            return;
        }
        if let Combine::Estimator(kernel) = &it.combine {
            for l in 0..it.record.lights {
                let r = it.record.depth_light(depth, l);
                kernel.add_failed(&mut self.rec[r], self.key, k);
            }
        }
    }

    /// Closes the iteration of vertex `depth`'s estimator.
    #[inline]
    pub fn end_vertex(&mut self, it: &Integrator, depth: usize) {
        if self.mute {
            return;
        }
        if let Combine::Estimator(kernel) = &it.combine {
            for l in 0..it.record.lights {
                let r = it.record.depth_light(depth, l);
                kernel.end_iteration(&mut self.rec[r], self.key);
            }
        }
    }
}
