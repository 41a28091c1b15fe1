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
/// counts every thread, whatever else the machine runs.
#[test]
fn the_clock_counts_every_thread() {
    let Some(t0) = process_cpu_seconds() else {
        return;
    };
    work();
    let t1 = process_cpu_seconds().unwrap();
    std::thread::scope(|s| {
        s.spawn(work);
        s.spawn(work);
    });
    let t2 = process_cpu_seconds().unwrap();
    let (one, two) = (t1 - t0, t2 - t1);
    assert!(one > 0.0, "{one}");
    assert!(
        (1.5..2.6).contains(&(two / one)),
        "one thread {one} s, two {two} s"
    );
}
