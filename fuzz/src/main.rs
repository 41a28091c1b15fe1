//! `frepray-fuzz TARGET EXECS [SEED]`: coverage-guided mutational fuzzing of one reader
//! in process, on the stable toolchain. Inputs that reach new coverage join the corpus
//! (`fuzz/corpus/TARGET`, reused by later runs); an input that panics is saved under
//! `fuzz/crashes/TARGET`, one that runs over a second under `fuzz/hangs/TARGET`. The
//! last line is a summary `run.sh` collects.

mod cov;
mod guard;
mod mutate;
mod targets;

use mutate::{mutate, tokens, Rng};
use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::Mutex;
use std::time::{Duration, Instant};
use targets::Target;

#[global_allocator]
static ALLOC: guard::Counting = guard::Counting;

/// An execution taking more CPU time than this is a hang.
const HANG: Duration = Duration::from_secs(1);
/// Inputs kept per distinct panic location.
const KEEP_PER_CRASH: usize = 5;

/// The last panic's message and location, set by the hook.
static PANIC: Mutex<Option<String>> = Mutex::new(None);

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: frepray-fuzz TARGET EXECS [SEED] | TARGET replay FILE...  (TARGET: frep, hf, vm, toml, json, toml-resolve, json-resolve, state)";
    if let (Some(t), Some("replay")) = (
        args.get(1).and_then(|s| Target::from_name(s)),
        args.get(2).map(|s| s.as_str()),
    ) {
        std::process::exit(replay(t, &args[3..]));
    }
    let (Some(t), Some(execs)) = (
        args.get(1).and_then(|s| Target::from_name(s)),
        args.get(2)
            .and_then(|s| s.replace('_', "").parse::<u64>().ok()),
    ) else {
        eprintln!("{usage}");
        std::process::exit(2);
    };
    let seed = args.get(3).and_then(|s| s.parse().ok()).unwrap_or_else(|| {
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(1, |d| d.as_nanos() as u64)
    });
    std::process::exit(fuzz(t, execs, seed));
}

/// Runs saved inputs once each (a crash or hang found earlier), saying how each ended
/// and how long it took; status 1 when one panicked.
fn replay(t: Target, files: &[String]) -> i32 {
    let sandbox = targets::Sandbox::new();
    let mut status = 0;
    for f in files {
        let input = std::fs::read(f).unwrap_or_else(|e| panic!("{f}: {e}"));
        let t0 = Instant::now();
        let r = catch_unwind(AssertUnwindSafe(|| targets::run(t, &input, &sandbox.dir)));
        let took = t0.elapsed();
        if r.is_err() {
            status = 1;
        }
        let how = if r.is_ok() { "ok" } else { "PANIC" };
        println!("{f}: {how} in {took:?}, {} bytes", input.len());
    }
    status
}

/// The output folders of a target.
struct Dirs {
    corpus: PathBuf,
    crashes: PathBuf,
    hangs: PathBuf,
}

impl Dirs {
    fn new(t: Target) -> Dirs {
        let base = Path::new(env!("CARGO_MANIFEST_DIR"));
        let d = Dirs {
            corpus: base.join("corpus").join(t.name()),
            crashes: base.join("crashes").join(t.name()),
            hangs: base.join("hangs").join(t.name()),
        };
        for p in [&d.corpus, &d.crashes, &d.hangs] {
            std::fs::create_dir_all(p).unwrap();
        }
        d
    }
}

fn save(dir: &Path, data: &[u8]) -> PathBuf {
    let p = dir.join(format!("{:016x}", fnv(data)));
    std::fs::write(&p, data).unwrap();
    p
}

fn fnv(data: &[u8]) -> u64 {
    data.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}

/// What a run found.
#[derive(Default)]
struct Tally {
    execs: u64,
    crashes: u64,
    hangs: u64,
    slowest: Duration,
    /// Panic location → inputs hitting it.
    by_site: BTreeMap<String, u64>,
}

fn fuzz(t: Target, execs: u64, seed: u64) -> i32 {
    let dirs = Dirs::new(t);
    // Named by process, so that a later run does not overwrite what killed this one.
    guard::tidy_stale(&dirs.crashes);
    guard::tidy_stale(&dirs.hangs);
    let pid = std::process::id();
    let oom = dirs.crashes.join(format!("memory-{pid}"));
    let dead = dirs.crashes.join(format!("signal-{pid}"));
    guard::install(&oom, &dead, dirs.hangs.join(format!("killed-{pid}")));
    std::panic::set_hook(Box::new(|info| {
        let at = info
            .location()
            .map_or(String::new(), |l| format!("{}:{}", l.file(), l.line()));
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        *PANIC.lock().unwrap_or_else(|e| e.into_inner()) = Some(format!("{at}: {msg}"));
    }));
    let sandbox = targets::Sandbox::new();
    let mut cov = cov::Coverage::new();
    if cov.size() == 0 {
        eprintln!("not instrumented: build with fuzz/run.sh (SanitizerCoverage flags)");
        return 2;
    }
    let seeds = targets::seeds(t);
    let dict = tokens(seeds.iter().map(|s| s.as_slice()));
    // Saved finds are reused up to the mutants' size limit.
    let mut saved: Vec<PathBuf> = std::fs::read_dir(&dirs.corpus)
        .map(|r| r.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    saved.retain(|p| std::fs::metadata(p).is_ok_and(|m| m.len() <= mutate::MAX_GROWTH as u64));
    saved.sort();
    let mut rng = Rng::new(seed);
    let mut tally = Tally::default();
    let start = Instant::now();
    let mut corpus: Vec<Vec<u8>> = Vec::new();
    let one = |input: &[u8], cov: &mut cov::Coverage, tally: &mut Tally| -> bool {
        cov.reset();
        let mut panicked = false;
        let took = guard::execute(input, || {
            panicked =
                catch_unwind(AssertUnwindSafe(|| targets::run(t, input, &sandbox.dir))).is_err();
        });
        tally.execs += 1;
        let new = cov.update();
        tally.slowest = tally.slowest.max(took);
        if panicked {
            tally.crashes += 1;
            let site = PANIC
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .take()
                .unwrap_or_default();
            let n = tally.by_site.entry(site.clone()).or_default();
            *n += 1;
            if *n <= KEEP_PER_CRASH as u64 {
                let p = save(&dirs.crashes, input);
                eprintln!("crash: {site} (input {})", p.display());
            }
        }
        if took > HANG {
            tally.hangs += 1;
            let p = save(&dirs.hangs, input);
            eprintln!("hang: {took:?} (input {})", p.display());
        }
        new
    };
    // Seeds and the saved corpus first: every one is kept (they are the starting points).
    let seeds_n = seeds.len();
    for s in seeds
        .into_iter()
        .chain(saved.iter().filter_map(|p| std::fs::read(p).ok()))
    {
        if tally.execs >= execs {
            break;
        }
        one(&s, &mut cov, &mut tally);
        corpus.push(s);
    }
    let mut next_report = Instant::now() + Duration::from_secs(30);
    let mut found = 0;
    // `FUZZ_MAX_SECONDS` (or SIGTERM, SIGINT) stops a run early, with its summary, to fit
    // a time budget.
    let budget = std::env::var("FUZZ_MAX_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .map_or(Duration::MAX, Duration::from_secs);
    let go = |tally: &Tally| {
        tally.execs < execs && start.elapsed() < budget && !guard::STOP.load(Ordering::Relaxed)
    };
    while go(&tally) && !corpus.is_empty() {
        // Favour the newest finds (the frontier of coverage) and short inputs (fast to
        // run: the shorter of two picks).
        let i = if rng.below(2) == 0 {
            corpus.len() - 1 - rng.below(corpus.len().min(32))
        } else {
            let (a, b) = (rng.below(corpus.len()), rng.below(corpus.len()));
            if corpus[a].len() <= corpus[b].len() {
                a
            } else {
                b
            }
        };
        let mut input = corpus[i].clone();
        let other = &corpus[rng.below(corpus.len())];
        mutate(&mut input, &mut rng, &dict, other);
        if one(&input, &mut cov, &mut tally) {
            save(&dirs.corpus, &input);
            corpus.push(input);
            found += 1;
        }
        if Instant::now() > next_report {
            next_report += Duration::from_secs(30);
            eprintln!(
                "{}: {} execs, {:.0}/s, corpus {}, edges {}, crashes {}, hangs {}, heap {:.1} MiB",
                t.name(),
                tally.execs,
                tally.execs as f64 / start.elapsed().as_secs_f64(),
                corpus.len(),
                cov.edges,
                tally.crashes,
                tally.hangs,
                guard::peak_heap() as f64 / (1 << 20) as f64
            );
        }
    }
    guard::tidy(&[&oom, &dead]);
    let secs = start.elapsed().as_secs_f64();
    for (site, n) in &tally.by_site {
        eprintln!("panic site ({n} inputs): {site}");
    }
    println!(
        "RESULT target={} execs={} seconds={:.0} execs_per_s={:.0} seeds={} corpus={} new={} \
         edges={} counters={} crashes={} crash_sites={} hangs={} slowest_ms={} \
         peak_heap_mib={:.1} peak_rss_mib={:.1} seed={}",
        t.name(),
        tally.execs,
        secs,
        tally.execs as f64 / secs,
        seeds_n,
        corpus.len(),
        found,
        cov.edges,
        cov.size(),
        tally.crashes,
        tally.by_site.len(),
        tally.hangs,
        tally.slowest.as_millis(),
        guard::peak_heap() as f64 / (1 << 20) as f64,
        guard::peak_rss().unwrap_or(0) as f64 / (1 << 20) as f64,
        seed
    );
    i32::from(tally.crashes > 0 || tally.hangs > 0)
}
