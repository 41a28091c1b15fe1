//! Long calls without the GIL that can be stopped: by Ctrl-C, by a `frepray.Cancel`
//! handle, and by the interpreter's exit.
//!
//! The work runs on a scoped thread with the GIL released; the calling thread wakes
//! every millisecond to look at the cancel handle, and every ~50 ms takes the GIL to
//! look for Ctrl-C: in the main thread by running Python's signal handlers
//! (`Python::check_signals`), elsewhere, where those do nothing, by the SIGINT count of
//! module `sigint`. Either sets the stop flag, which the render loop reads between
//! samples; the work ends with what it has and the exception comes back with it.
//!
//! At exit Python kills a thread that takes the GIL once finalisation has begun
//! (`pthread_exit`), which unwinds through Rust frames and aborts the process ("FATAL:
//! exception not rethrown"). So an `atexit` hook ([`at_exit`]) marks the exit, and a
//! render outside the main thread that sees the mark while it holds no GIL stops its
//! work and parks for good, never taking the GIL again; the hook waits (without the GIL)
//! until every such render has.

use crate::errors::Cancelled;
use crate::sigint;
use pyo3::exceptions::PyKeyboardInterrupt;
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Set by the `atexit` hook: the interpreter is exiting.
static EXITING: AtomicBool = AtomicBool::new(false);
/// Renders outside the main thread that may still take the GIL.
static ACTIVE: AtomicUsize = AtomicUsize::new(0);

/// A handle that stops renders from any thread: pass it as `cancel=` to `render`,
/// `experiment` or `Model.preview`, then call `cancel()`. Each render given it stops
/// within a sample and raises `frepray.Cancelled` whose `state` holds what it rendered;
/// a render started with a cancelled handle stops at once.
#[pyclass(module = "frepray", frozen)]
pub struct Cancel {
    flag: AtomicBool,
}

#[pymethods]
impl Cancel {
    #[new]
    fn new() -> Self {
        Cancel {
            flag: AtomicBool::new(false),
        }
    }
    /// Stops every render given this handle (now and later).
    fn cancel(&self) {
        self.flag.store(true, Ordering::Release);
    }
    /// Whether `cancel()` was called.
    #[getter]
    fn cancelled(&self) -> bool {
        self.flag.load(Ordering::Acquire)
    }
    fn __repr__(&self) -> String {
        format!("<frepray.Cancel cancelled={}>", self.cancelled())
    }
}

impl Cancel {
    /// The flag `run` watches.
    pub fn flag(&self) -> &AtomicBool {
        &self.flag
    }
}

/// Marks the interpreter's exit (registered with `atexit` when the module loads) and
/// waits, without the GIL and at most 5 s, until no render outside the main thread can
/// take the GIL any more (they stop and park).
#[pyfunction]
pub fn _at_exit(py: Python<'_>) {
    EXITING.store(true, Ordering::Release);
    py.detach(|| {
        let t = Instant::now();
        while ACTIVE.load(Ordering::Acquire) > 0 && t.elapsed() < Duration::from_secs(5) {
            std::thread::sleep(Duration::from_millis(1));
        }
    });
}

/// Counts a render outside the main thread in [`ACTIVE`] while it lives.
struct Active;

impl Active {
    fn enter() -> Active {
        ACTIVE.fetch_add(1, Ordering::AcqRel);
        Active
    }
}

impl Drop for Active {
    fn drop(&mut self) {
        ACTIVE.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Stops the work and parks this thread for good, without the GIL: the process is
/// exiting, and taking the GIL now would abort it.
fn park_for_exit(stop: &AtomicBool, active: Active) -> ! {
    stop.store(true, Ordering::Release);
    drop(active);
    loop {
        std::thread::park();
    }
}

/// Whether this is the interpreter's main thread (the one that runs signal handlers
/// and finalises).
fn is_main_thread(py: Python<'_>) -> bool {
    let main = || -> PyResult<bool> {
        let t = py.import("threading")?;
        let ident = t.call_method0("get_ident")?;
        t.call_method0("main_thread")?.getattr("ident")?.eq(ident)
    };
    main().unwrap_or(true)
}

/// While a render runs in the main thread, SIGTERM and SIGHUP (schedulers, `timeout`,
/// container stops, a closed terminal) stop it as Ctrl-C does, instead of killing the
/// process with the render lost: where their handler is the default, a temporary one
/// raises `SystemExit(128 + signal)` — uncaught, the interpreter exits with the status a
/// shell expects (143, 129) after running `finally` blocks; caught, the exception's
/// `state` holds the partial render. Returns the handlers to put back.
fn terminate_handlers(py: Python<'_>) -> Vec<(i32, Py<PyAny>)> {
    let install = || -> PyResult<Vec<(i32, Py<PyAny>)>> {
        let signal = py.import("signal")?;
        let default = signal.getattr("SIG_DFL")?;
        let mut old = Vec::new();
        for name in ["SIGTERM", "SIGHUP"] {
            let Ok(num) = signal.getattr(name) else {
                continue;
            };
            if !signal.call_method1("getsignal", (&num,))?.eq(&default)? {
                continue;
            }
            let raise = pyo3::types::PyCFunction::new_closure(
                py,
                None,
                None,
                |args: &Bound<'_, pyo3::types::PyTuple>,
                 _: Option<&Bound<'_, pyo3::types::PyDict>>|
                 -> PyResult<()> {
                    let signum: i32 = args.get_item(0)?.extract()?;
                    Err(pyo3::exceptions::PySystemExit::new_err(128 + signum))
                },
            )?;
            signal.call_method1("signal", (&num, raise))?;
            old.push((num.extract()?, default.clone().unbind()));
        }
        Ok(old)
    };
    install().unwrap_or_default()
}

/// Puts back the handlers [`terminate_handlers`] replaced.
fn restore_handlers(py: Python<'_>, old: Vec<(i32, Py<PyAny>)>) {
    if let Ok(signal) = py.import("signal") {
        for (num, handler) in old {
            let _ = signal.call_method1("signal", (num, handler));
        }
    }
}

/// Why the waiting thread woke.
enum Woke {
    Done,
    Cancelled,
    Tick,
}

/// Runs `work(stop)` with the GIL released. Returns its result and the exception that
/// stopped it, if any: KeyboardInterrupt for Ctrl-C, `frepray.Cancelled` for `cancel`,
/// SystemExit for SIGTERM and SIGHUP in the main thread ([`terminate_handlers`]).
/// `work` must end soon after `stop` is set.
pub fn run<T: Send>(
    py: Python<'_>,
    cancel: Option<&Cancel>,
    work: impl FnOnce(&AtomicBool) -> T + Send,
) -> (T, Option<PyErr>) {
    let main = is_main_thread(py);
    let cancel = cancel.map(Cancel::flag);
    let stop = AtomicBool::new(cancel.is_some_and(|c| c.load(Ordering::Acquire)));
    let mut active = (!main).then(Active::enter);
    if active.is_some() && EXITING.load(Ordering::Acquire) {
        let a = active.take().expect("outside the main thread");
        py.detach(move || park_for_exit(&AtomicBool::new(false), a));
    }
    sigint::install();
    let sigints = sigint::count();
    let replaced = if main {
        terminate_handlers(py)
    } else {
        Vec::new()
    };
    let done = AtomicBool::new(false);
    let mut interrupted = cancel
        .is_some_and(|c| c.load(Ordering::Acquire))
        .then(|| Cancelled::new_err("cancelled before it started"));
    let out = std::thread::scope(|s| {
        let handle = s.spawn(|| {
            let r = work(&stop);
            done.store(true, Ordering::Release);
            r
        });
        loop {
            let woke = py.detach(|| {
                let t = Instant::now();
                loop {
                    if active.is_some() && EXITING.load(Ordering::Acquire) {
                        park_for_exit(&stop, active.take().expect("outside the main thread"));
                    }
                    if done.load(Ordering::Acquire) {
                        return Woke::Done;
                    }
                    let cancelled = cancel.is_some_and(|c| c.load(Ordering::Acquire));
                    if cancelled && !stop.load(Ordering::Acquire) {
                        return Woke::Cancelled;
                    }
                    if t.elapsed() >= Duration::from_millis(50) {
                        return Woke::Tick;
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
            });
            match woke {
                Woke::Done => break,
                Woke::Cancelled => {
                    stop.store(true, Ordering::Release);
                    interrupted.get_or_insert_with(|| Cancelled::new_err("cancelled"));
                }
                Woke::Tick => {}
            }
            if interrupted.is_none() {
                let signalled = if main {
                    py.check_signals().err()
                } else {
                    (sigint::count() != sigints).then(|| {
                        PyKeyboardInterrupt::new_err("SIGINT stopped the render in this thread")
                    })
                };
                if let Some(e) = signalled {
                    stop.store(true, Ordering::Release);
                    interrupted = Some(e);
                }
            }
            sigint::install();
        }
        handle.join()
    });
    restore_handlers(py, replaced);
    drop(active);
    match out {
        Ok(v) => (v, interrupted),
        Err(panic) => std::panic::resume_unwind(panic),
    }
}
