//! Ray counters and stage timers: what a render of either back end reports
//! ([`crate::RenderStats`]).

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
    pub fn count(&mut self, kind: RayKind) -> u64 {
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
