//! What in-process fuzzing cannot catch with `catch_unwind`: an input that allocates
//! without bound, runs for ever, or kills the process (stack overflow, abort). The
//! input being executed is kept in a static buffer so that the allocator, a watchdog
//! thread and a signal handler can save it to a file before the process dies.

use std::alloc::{GlobalAlloc, Layout, System};
use std::fs::File;
use std::io::Write;
use std::os::fd::AsRawFd;
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicU64, AtomicUsize, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// The longest input executed (longer mutants are cut).
pub const MAX_INPUT: usize = 256 << 10;
/// Live heap one execution may reach before it counts as unbounded memory.
pub const MEMORY_LIMIT: usize = 1 << 30;
/// An execution this long in wall time is killed (saved as a hang first); one over a
/// second of CPU time is only recorded, after it ends.
pub const KILL_AFTER: Duration = Duration::from_secs(30);

struct Current(std::cell::UnsafeCell<[u8; MAX_INPUT]>);
// SAFETY: written only by the fuzzing thread while no execution runs; read by the
// guards only while one runs (or on that same thread).
unsafe impl Sync for Current {}
static CURRENT: Current = Current(std::cell::UnsafeCell::new([0; MAX_INPUT]));
static CURRENT_LEN: AtomicUsize = AtomicUsize::new(0);
/// Milliseconds since `EPOCH` when the running execution began; 0 between executions.
static STARTED: AtomicU64 = AtomicU64::new(0);
static EPOCH: OnceLock<Instant> = OnceLock::new();
/// Pre-opened files for the input that killed the process (no allocation when dying).
static DEATH: OnceLock<(File, File)> = OnceLock::new();
static DEATH_FD: AtomicI32 = AtomicI32::new(-1);
static DYING: AtomicBool = AtomicBool::new(false);

/// Counts live heap bytes and the peak; refuses to go past [`MEMORY_LIMIT`] during an
/// execution.
pub struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
/// The live heap when the running execution began.
static BASE: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        grow(l.size());
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        grow(l.size());
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        LIVE.fetch_sub(l.size(), Ordering::Relaxed);
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        if new > l.size() {
            grow(new - l.size());
        } else {
            LIVE.fetch_sub(l.size() - new, Ordering::Relaxed);
        }
        unsafe { System.realloc(p, l, new) }
    }
}

fn grow(n: usize) {
    let live = LIVE.fetch_add(n, Ordering::Relaxed) + n;
    PEAK.fetch_max(live, Ordering::Relaxed);
    if STARTED.load(Ordering::Relaxed) != 0
        && live.saturating_sub(BASE.load(Ordering::Relaxed)) > MEMORY_LIMIT
    {
        die("memory: an execution went past the 1 GiB heap limit");
    }
}

/// Peak live heap of the whole run, in bytes.
pub fn peak_heap() -> usize {
    PEAK.load(Ordering::Relaxed)
}

/// Peak resident set of the process (VmHWM), in bytes, where Linux reports it.
pub fn peak_rss() -> Option<usize> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: usize = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Prepares the guards: `oom` and `dead` are where an input that exhausts memory or
/// kills the process is written; a watchdog thread kills executions past
/// [`KILL_AFTER`], writing them to `hang` first.
pub fn install(oom: &std::path::Path, dead: &std::path::Path, hang: std::path::PathBuf) {
    EPOCH.get_or_init(Instant::now);
    let files = (File::create(oom).unwrap(), File::create(dead).unwrap());
    DEATH_FD.store(files.1.as_raw_fd(), Ordering::SeqCst);
    let _ = DEATH.set(files);
    // SAFETY: the handler only calls async-signal-safe functions (write, signal, raise).
    unsafe {
        for sig in [libc::SIGSEGV, libc::SIGBUS, libc::SIGABRT, libc::SIGILL] {
            let mut a: libc::sigaction = std::mem::zeroed();
            a.sa_sigaction = on_signal as *const () as usize;
            a.sa_flags = libc::SA_ONSTACK | libc::SA_NODEFER | libc::SA_RESETHAND;
            libc::sigaction(sig, &a, std::ptr::null_mut());
        }
    }
    // SAFETY: the handler only stores to an atomic.
    unsafe {
        for sig in [libc::SIGTERM, libc::SIGINT] {
            libc::signal(sig, on_stop as *const () as libc::sighandler_t);
        }
    }
    std::thread::spawn(move || loop {
        std::thread::sleep(Duration::from_millis(250));
        let t0 = STARTED.load(Ordering::SeqCst);
        if t0 != 0 && now_ms().saturating_sub(t0) > KILL_AFTER.as_millis() as u64 {
            let _ = std::fs::write(&hang, current());
            eprintln!(
                "hang: an execution ran past {KILL_AFTER:?}; saved to {}",
                hang.display()
            );
            std::process::exit(3);
        }
    });
}

/// Set by SIGTERM or SIGINT: the run stops after the current execution and reports.
pub static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_stop(_: libc::c_int) {
    STOP.store(true, Ordering::SeqCst);
}

extern "C" fn on_signal(sig: libc::c_int) {
    // Std's own handler (stack overflow message) is replaced; say what happened.
    let fd = DEATH_FD.load(Ordering::SeqCst);
    if fd >= 0 && !DYING.swap(true, Ordering::SeqCst) {
        let b = current();
        // SAFETY: write(2) on an open descriptor and a valid buffer.
        unsafe {
            libc::write(fd, b.as_ptr().cast(), b.len());
            let m = b"fatal signal during an execution: input saved (stack overflow or abort)\n";
            libc::write(2, m.as_ptr().cast(), m.len());
        }
    }
    // SAFETY: SA_RESETHAND restored the default action; re-raise to die by the signal.
    unsafe {
        libc::raise(sig);
    }
}

fn die(why: &str) -> ! {
    if !DYING.swap(true, Ordering::SeqCst) {
        if let Some((oom, _)) = DEATH.get() {
            let mut f: &File = oom;
            let _ = f.write_all(current());
        }
        // Unbuffered stderr: no allocation.
        let _ = std::io::stderr().write_all(why.as_bytes());
        let _ = std::io::stderr().write_all(b"; input saved\n");
    }
    std::process::abort()
}

fn now_ms() -> u64 {
    EPOCH.get_or_init(Instant::now).elapsed().as_millis() as u64 + 1
}

fn current() -> &'static [u8] {
    let n = CURRENT_LEN.load(Ordering::SeqCst);
    // SAFETY: see `Current`.
    unsafe { std::slice::from_raw_parts(CURRENT.0.get().cast::<u8>(), n) }
}

/// CPU time of the calling thread: on a shared machine at `nice 19` wall time says more
/// about the neighbours than about the input.
pub fn thread_cpu() -> Duration {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: a valid timespec to write to.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
}

/// Runs `f` as one guarded execution of `input`; returns the CPU time it took.
pub fn execute(input: &[u8], f: impl FnOnce()) -> Duration {
    let n = input.len().min(MAX_INPUT);
    // SAFETY: no execution runs now; the guards read only while STARTED != 0.
    unsafe { std::ptr::copy_nonoverlapping(input.as_ptr(), CURRENT.0.get().cast::<u8>(), n) };
    CURRENT_LEN.store(n, Ordering::SeqCst);
    BASE.store(LIVE.load(Ordering::Relaxed), Ordering::Relaxed);
    let t = thread_cpu();
    STARTED.store(now_ms(), Ordering::SeqCst);
    f();
    STARTED.store(0, Ordering::SeqCst);
    thread_cpu().saturating_sub(t)
}

/// Removes empty death files (`NAME-PID`) of processes no longer running: a running
/// fuzzer's file is open and may yet receive the input that kills it.
pub fn tidy_stale(dir: &std::path::Path) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let pid = name
            .rsplit_once('-')
            .and_then(|(_, p)| p.parse::<u32>().ok());
        let empty = e.metadata().is_ok_and(|m| m.len() == 0);
        if let (Some(pid), true) = (pid, empty) {
            if !std::path::Path::new(&format!("/proc/{pid}")).exists() {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

/// Removes the death files when nothing was written to them.
pub fn tidy(paths: &[&std::path::Path]) {
    for p in paths {
        if std::fs::metadata(p).map(|m| m.len() == 0).unwrap_or(false) {
            let _ = std::fs::remove_file(p);
        }
    }
}
