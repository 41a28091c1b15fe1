//! The processor clock of `experiment` counts every thread of the process. Alone in its
//! test binary: the harness runs the tests of one binary on parallel threads, whose work
//! the process clock would count too.

use frepray::experiment::process_cpu_seconds;

/// A fixed amount of work (not a wall-clock span, so that load does not matter).
fn work() {
    let mut x = 0u64;
    for _ in 0..30_000_000u64 {
        x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
    }
}

/// The same work on two threads costs twice the processor time of one: the clock
/// counts every thread, whatever else the machine runs. Each is the least of three
/// measurements: a busy sibling of a virtual CPU slows a thread's work, which then
/// costs more processor time, and that noise only adds.
#[test]
fn the_clock_counts_every_thread() {
    if process_cpu_seconds().is_none() {
        return;
    }
    let least = |f: &dyn Fn()| {
        (0..3)
            .map(|_| {
                let t0 = process_cpu_seconds().unwrap();
                f();
                process_cpu_seconds().unwrap() - t0
            })
            .fold(f64::INFINITY, f64::min)
    };
    let one = least(&work);
    let two = least(&|| {
        std::thread::scope(|s| {
            s.spawn(work);
            s.spawn(work);
        })
    });
    assert!(one > 0.0, "{one}");
    assert!(
        (1.5..2.6).contains(&(two / one)),
        "one thread {one} s, two {two} s"
    );
}
