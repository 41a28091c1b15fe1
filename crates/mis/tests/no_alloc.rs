//! No allocation in the per-pixel work: a counting global allocator (this test binary
//! only) watches every method's kernel add samples, fail samples, close iterations (the
//! progressive re-solves), merge and estimate (the direct and uncorrelated solves,
//! including the pseudo-inverse fallback of a singular `Â`) on blocks the caller owns.

use mis::{Kernel, Layout, Method, Params};
use std::alloc::{GlobalAlloc, Layout as AllocLayout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Counts allocations made by threads that have switched counting on.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static COUNT_HERE: Cell<bool> = const { Cell::new(false) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: AllocLayout) -> *mut u8 {
        if COUNT_HERE.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: AllocLayout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: AllocLayout, new_size: usize) -> *mut u8 {
        if COUNT_HERE.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by this thread while running `f`.
fn allocations(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    COUNT_HERE.with(|c| c.set(true));
    f();
    COUNT_HERE.with(|c| c.set(false));
    ALLOCATIONS.load(Ordering::Relaxed) - before
}

#[test]
fn kernels_do_not_allocate() {
    // T = 3 and T = 16 (the largest stack scratch); three channels. Techniques 1 and 2
    // have proportional pdfs, so `Â` is singular at ridge 0: the pseudo-inverse path runs.
    for t in [3usize, 16] {
        let layout = Layout::new(&vec![1; t], 3);
        for m in Method::ALL {
            for ridge in [None, Some(0.0)] {
                let k = Kernel::new(
                    m,
                    &layout,
                    &Params {
                        ridge,
                        ..Params::default()
                    },
                )
                .unwrap();
                let (mut a, mut b) = (vec![0.0; k.block_len()], vec![0.0; k.block_len()]);
                let (mut pdfs, mut out) = (vec![0.0; t], [0.0; 3]);
                let n = allocations(|| {
                    for i in 0..64u64 {
                        for tech in 0..t {
                            let x = ((i * 7 + tech as u64 * 3) % 11) as f64 / 11.0 + 0.05;
                            for (j, p) in pdfs.iter_mut().enumerate() {
                                *p = if j == 2 { 2.0 * x } else { 0.5 + x * j as f64 };
                            }
                            let f = [x, 1.0 - x, x * x];
                            let block = if i % 2 == 0 { &mut a } else { &mut b };
                            if (i + tech as u64) % 9 == 4 {
                                k.add_failed(block, i, tech);
                            } else {
                                k.add_sample(block, i, tech, &f, &pdfs);
                            }
                        }
                        let block = if i % 2 == 0 { &mut a } else { &mut b };
                        k.end_iteration(block, i);
                    }
                    k.merge(&mut a, &b);
                    k.estimate(&a, &mut out);
                });
                assert_eq!(n, 0, "{m}, T = {t}, ridge {ridge:?}: {n} allocations");
                assert!(out.iter().all(|v| v.is_finite()), "{m}: {out:?}");
            }
        }
    }
}
