//! Ctrl-C (SIGINT): the first sets a stop flag, so that the render in flight ends
//! within a sample and its partial result is written; the second quits at once. Either
//! way the process exits with status 130 (128 + SIGINT, what shells report), so that a
//! `for …; do frepray render …; done` loop stops too.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

/// The exit status of an interrupted command: 128 + SIGINT.
pub const EXIT_INTERRUPTED: u8 = 130;

/// The process's stop flag (one handler per process).
static STOP: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// The flag that Ctrl-C sets, the handler installed on first use. A second Ctrl-C
/// exits with [`EXIT_INTERRUPTED`] without waiting.
pub fn stop_flag() -> Arc<AtomicBool> {
    STOP.get_or_init(|| {
        let stop = Arc::new(AtomicBool::new(false));
        let s = stop.clone();
        let installed = ctrlc::set_handler(move || {
            if s.swap(true, Ordering::SeqCst) {
                note!("\ninterrupted twice: quitting without writing");
                std::process::exit(i32::from(EXIT_INTERRUPTED));
            }
            note!("\ninterrupted: finishing the samples in flight (Ctrl-C again to quit)");
        });
        if let Err(e) = installed {
            note!("warning: Ctrl-C will not stop renders cleanly: {e}");
        }
        stop
    })
    .clone()
}

/// Whether Ctrl-C was pressed.
pub fn interrupted() -> bool {
    STOP.get().is_some_and(|s| s.load(Ordering::SeqCst))
}
