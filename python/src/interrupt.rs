//! Long calls without the GIL that Ctrl-C stops.
//!
//! The work runs on a scoped thread with the GIL released; the calling thread wakes
//! every few milliseconds, and every ~50 ms takes the GIL to run Python's signal
//! handlers (`Python::check_signals`). On KeyboardInterrupt it sets the stop flag, which
//! the render loop reads between tiles, waits for the work to end with what it has, and
//! hands the exception back with the result.

use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Runs `work(stop)` with the GIL released. Returns its result and the exception that
/// interrupted it (a KeyboardInterrupt), if any; `work` must end soon after `stop` is
/// set.
pub fn run<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(&AtomicBool) -> T + Send,
) -> (T, Option<PyErr>) {
    let stop = AtomicBool::new(false);
    let done = AtomicBool::new(false);
    let mut interrupted = None;
    let out = std::thread::scope(|s| {
        let handle = s.spawn(|| {
            let r = work(&stop);
            done.store(true, Ordering::Release);
            r
        });
        loop {
            let finished = py.detach(|| {
                let t = Instant::now();
                while t.elapsed() < Duration::from_millis(50) {
                    if done.load(Ordering::Acquire) {
                        return true;
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
                done.load(Ordering::Acquire)
            });
            if finished {
                break;
            }
            if interrupted.is_none() {
                if let Err(e) = py.check_signals() {
                    stop.store(true, Ordering::Release);
                    interrupted = Some(e);
                }
            }
        }
        handle.join()
    });
    match out {
        Ok(v) => (v, interrupted),
        Err(panic) => std::panic::resume_unwind(panic),
    }
}
