//! Where the CPU integrator reports its ray queries ([`state::RayCounts`] counts them).

use state::{RayCounts, RayKind, TIMED_EVERY};

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
