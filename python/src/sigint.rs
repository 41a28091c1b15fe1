//! Ctrl-C for renders outside the main thread.
//!
//! Python runs its signal handlers only in the main thread, so a render in another
//! thread (a `ThreadPoolExecutor`, `asyncio`'s `run_in_executor`) never learnt of Ctrl-C
//! and kept the process alive after KeyboardInterrupt. Here a C-level SIGINT handler
//! is chained in front of Python's: it calls Python's handler (so the main thread still
//! raises KeyboardInterrupt) and then counts the signal; a render compares the count
//! with the one at its start.
//!
//! `signal.signal(SIGINT, …)` replaces the C handler (IPython does so before each
//! cell), so [`install`] runs at the start of every render and every ~50 ms while one
//! runs, always with the GIL held: Python changes handlers only under the GIL, so the
//! two never race. Where SIGINT is ignored or left to the default action (the process
//! dies) nothing is installed.

/// SIGINTs delivered since the hook was first installed.
pub fn count() -> u64 {
    imp::COUNT.load(std::sync::atomic::Ordering::Acquire)
}

/// Chains the hook in front of SIGINT's handler unless it is there already, or SIGINT
/// is ignored or has its default action. Call with the GIL held.
pub fn install() {
    imp::install();
}

#[cfg(unix)]
mod imp {
    use libc::{c_int, c_void, siginfo_t, SA_SIGINFO, SIGINT, SIG_DFL, SIG_IGN};
    use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};

    pub static COUNT: AtomicU64 = AtomicU64::new(0);
    /// The handler the hook replaced (a `sa_sigaction` value) and whether it takes
    /// `siginfo` (`SA_SIGINFO`).
    static PREV: AtomicUsize = AtomicUsize::new(SIG_DFL);
    static PREV_SIGINFO: AtomicBool = AtomicBool::new(false);

    type Plain = extern "C" fn(c_int);
    type WithInfo = extern "C" fn(c_int, *mut siginfo_t, *mut c_void);

    /// Calls the previous handler, then counts; async-signal-safe (atomics and a call).
    extern "C" fn on_sigint(sig: c_int, info: *mut siginfo_t, ctx: *mut c_void) {
        let prev = PREV.load(Ordering::Acquire);
        if prev != SIG_DFL && prev != SIG_IGN {
            // SAFETY: `prev` is the handler sigaction reported, of the kind its flags say.
            unsafe {
                if PREV_SIGINFO.load(Ordering::Acquire) {
                    std::mem::transmute::<usize, WithInfo>(prev)(sig, info, ctx);
                } else {
                    std::mem::transmute::<usize, Plain>(prev)(sig);
                }
            }
        }
        COUNT.fetch_add(1, Ordering::AcqRel);
    }

    pub fn install() {
        let ours = on_sigint as WithInfo as usize;
        // SAFETY: sigaction with a zeroed struct to read, then the read one changed only
        // in its handler and SA_SIGINFO; PREV is stored before the hook can run.
        unsafe {
            let mut cur: libc::sigaction = std::mem::zeroed();
            if libc::sigaction(SIGINT, std::ptr::null(), &mut cur) != 0 {
                return;
            }
            let h = cur.sa_sigaction;
            if h == ours || h == SIG_DFL || h == SIG_IGN {
                return;
            }
            PREV_SIGINFO.store(cur.sa_flags & SA_SIGINFO != 0, Ordering::Release);
            PREV.store(h, Ordering::Release);
            let mut hook = cur;
            hook.sa_sigaction = ours;
            hook.sa_flags |= SA_SIGINFO;
            libc::sigaction(SIGINT, &hook, std::ptr::null_mut());
        }
    }
}

#[cfg(not(unix))]
mod imp {
    //! Elsewhere renders outside the main thread stop by their cancel handle only.
    pub static COUNT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    pub fn install() {}
}
