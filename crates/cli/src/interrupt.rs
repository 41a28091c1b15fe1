//! Ctrl-C (SIGINT), SIGTERM and SIGHUP: the first sets a stop flag, so that the render in
//! flight ends within a sample and its partial result is written; the second quits at
//! once. Either way the process exits with status 128 + the first signal's number (130,
//! 143 or 129, what shells report), so that a `for …; do frepray render …; done` loop, a
//! scheduler or `timeout` sees the interruption. Schedulers, `timeout`, container stops
//! and SLURM send SIGTERM (then SIGKILL after a grace period); a closed terminal sends
//! SIGHUP.

use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::{Arc, OnceLock};

/// The process's stop flag (one handler per process).
static STOP: OnceLock<Arc<AtomicBool>> = OnceLock::new();
/// The first signal received (0: none).
static FIRST: AtomicI32 = AtomicI32::new(0);

/// A signal's name and how it usually comes.
fn describe(signal: i32) -> &'static str {
    match signal {
        SIGINT => "interrupted (Ctrl-C)",
        SIGTERM => "terminated (SIGTERM)",
        SIGHUP => "hung up (SIGHUP)",
        _ => "signalled",
    }
}

/// The flag that the signals set, the handler installed on first use. A second signal
/// exits with 128 + its number without waiting.
pub fn stop_flag() -> Arc<AtomicBool> {
    STOP.get_or_init(|| {
        let stop = Arc::new(AtomicBool::new(false));
        let s = stop.clone();
        // The handler only wakes this thread (signal-hook's self-pipe), which does the
        // printing and exiting outside the signal context.
        match signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
            Ok(mut signals) => {
                std::thread::spawn(move || {
                    for signal in signals.forever() {
                        if s.swap(true, Ordering::SeqCst) {
                            note!("\n{} again: quitting without writing", describe(signal));
                            std::process::exit(128 + signal);
                        }
                        FIRST.store(signal, Ordering::SeqCst);
                        note!(
                            "\n{}: finishing the samples in flight (Ctrl-C again to quit)",
                            describe(signal)
                        );
                    }
                });
            }
            Err(e) => note!("warning: Ctrl-C and SIGTERM will not stop renders cleanly: {e}"),
        }
        stop
    })
    .clone()
}

/// The exit status of a command that a signal interrupted: 128 + the signal's number
/// (`None` when no signal came).
pub fn exit_status() -> Option<u8> {
    match FIRST.load(Ordering::SeqCst) {
        0 => None,
        s => u8::try_from(128 + s).ok(),
    }
}
