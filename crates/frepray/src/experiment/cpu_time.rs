//! The processor time of this process, all threads together: on a shared machine it
//! tells the work a render did better than wall time, which counts whatever else runs.

/// Seconds of processor time of the whole process so far (every thread, user and
/// system), from `clock_gettime(CLOCK_PROCESS_CPUTIME_ID)` at nanosecond resolution on
/// Unix; `None` elsewhere or if the clock fails.
pub fn process_cpu_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut t = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `t` is a valid, writable timespec for the call's duration.
        let ok = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) } == 0;
        ok.then_some(t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9)
    }
    #[cfg(not(unix))]
    {
        None
    }
}
