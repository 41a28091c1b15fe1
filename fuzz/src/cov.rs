//! Edge coverage from LLVM's SanitizerCoverage inline 8-bit counters: each instrumented
//! module registers its counter array at start-up, the target bumps the counters, and
//! after each execution the hit counts are bucketed (AFL's classes) and compared with
//! everything seen so far. Only stable codegen flags are needed (see run.sh).

use std::sync::atomic::{AtomicUsize, Ordering};

/// Enough for every codegen unit of the product and its dependencies.
const MAX_REGIONS: usize = 1 << 16;

static mut REGIONS: [(usize, usize); MAX_REGIONS] = [(0, 0); MAX_REGIONS];
static N_REGIONS: AtomicUsize = AtomicUsize::new(0);

/// Called by each instrumented module's constructor, before `main`: records where its
/// counters are.
///
/// # Safety
/// Called by the instrumentation with a valid `[start, stop)` counter range.
#[no_mangle]
pub unsafe extern "C" fn __sanitizer_cov_8bit_counters_init(start: *mut u8, stop: *mut u8) {
    let i = N_REGIONS.fetch_add(1, Ordering::SeqCst);
    if i < MAX_REGIONS && start < stop {
        // SAFETY: constructors run one at a time before main; each writes its own slot.
        unsafe {
            std::ptr::addr_of_mut!(REGIONS)
                .cast::<(usize, usize)>()
                .add(i)
                .write((start as usize, stop as usize))
        };
    }
}

fn regions() -> &'static [(usize, usize)] {
    let n = N_REGIONS.load(Ordering::SeqCst).min(MAX_REGIONS);
    // SAFETY: written only before main, read-only afterwards.
    unsafe { std::slice::from_raw_parts(std::ptr::addr_of!(REGIONS).cast::<(usize, usize)>(), n) }
}

/// AFL's hit-count classes as one bit each: 1, 2, 3, 4–7, 8–15, 16–31, 32–127, 128+.
fn bucket(n: u8) -> u8 {
    match n {
        0 => 0,
        1 => 1,
        2 => 2,
        3 => 4,
        4..=7 => 8,
        8..=15 => 16,
        16..=31 => 32,
        32..=127 => 64,
        _ => 128,
    }
}

/// The counters of every module, and the buckets seen so far per counter.
pub struct Coverage {
    counters: Vec<&'static mut [u8]>,
    seen: Vec<Vec<u8>>,
    /// Counters hit at least once so far.
    pub edges: usize,
}

impl Coverage {
    /// Takes over the registered counters (call once, in `main`).
    pub fn new() -> Coverage {
        let counters: Vec<&'static mut [u8]> = regions()
            .iter()
            // SAFETY: each range is a counter array that lives for the whole program.
            .map(|&(a, b)| unsafe { std::slice::from_raw_parts_mut(a as *mut u8, b - a) })
            .collect();
        let seen = counters.iter().map(|c| vec![0; c.len()]).collect();
        Coverage {
            counters,
            seen,
            edges: 0,
        }
    }

    /// Counters in all (0 means the build was not instrumented).
    pub fn size(&self) -> usize {
        self.counters.iter().map(|c| c.len()).sum()
    }

    /// Zeroes the counters before an execution.
    pub fn reset(&mut self) {
        for c in &mut self.counters {
            c.fill(0);
        }
    }

    /// Folds the counters of the last execution into what was seen; true when some
    /// counter reached a new bucket (the input is worth keeping).
    pub fn update(&mut self) -> bool {
        let mut new = false;
        for (c, seen) in self.counters.iter().zip(&mut self.seen) {
            // Most counters are zero: skip them eight at a time.
            let words = c.len() / 8;
            for w in 0..words {
                let chunk = &c[w * 8..w * 8 + 8];
                if u64::from_ne_bytes(chunk.try_into().unwrap()) == 0 {
                    continue;
                }
                for k in w * 8..w * 8 + 8 {
                    new |= fold(c[k], &mut seen[k], &mut self.edges);
                }
            }
            for k in words * 8..c.len() {
                new |= fold(c[k], &mut seen[k], &mut self.edges);
            }
        }
        new
    }
}

fn fold(hits: u8, seen: &mut u8, edges: &mut usize) -> bool {
    let b = bucket(hits);
    if b & !*seen == 0 {
        return false;
    }
    if *seen == 0 {
        *edges += 1;
    }
    *seen |= b;
    true
}
