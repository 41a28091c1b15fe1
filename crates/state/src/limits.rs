//! Resource limits checked before a render starts, so that a render too large for the
//! machine is an error with an estimate instead of an allocator abort, and a thread
//! count that would stall the machine is refused (docs/reliability.md).
//!
//! **Memory.** A render holds every pixel's record twice (the [`crate::RenderState`]
//! and the tiles' own copies, `width × height × stride × 8` bytes each, the stride from
//! [`crate::Record::stride`]: estimator, techniques, depth and AOVs), then the
//! resolved [`crate::Image`] (`width × height × (3 + AOV channels) × 8` bytes) and one
//! encoded copy of it while a file is written (at most as large again). The estimate
//! is compared with a limit: the caller's, else the memory the system reports available
//! (Linux: `MemAvailable` of `/proc/meminfo`); where the system reports none, with
//! [`FALLBACK_MEMORY`].

use crate::error::Error;
use crate::options::RenderOptions;
use crate::options_error::OptionsError;
use crate::tally::Tally;

/// The limit where the available memory cannot be read (not Linux, or no `/proc`):
/// 16 GiB; `--max-memory` sets another.
pub const FALLBACK_MEMORY: u64 = 16 << 30;

/// The most worker threads per core: more only adds scheduling overhead (and at
/// `--threads 100000` stalls the machine creating stacks).
pub const THREADS_PER_CORE: usize = 8;

/// Bytes a render of `width × height` pixels with `o` needs (module docs); errors when
/// the options are invalid. Saturates rather than overflows.
pub fn render_bytes(width: u32, height: u32, o: &RenderOptions) -> Result<u64, Error> {
    let it = Tally::new(o)?;
    let pixels = u64::from(width) * u64::from(height);
    let stride = it.record.stride() as u64;
    let channels = 3 + o
        .aovs
        .iter()
        .map(|a| a.channels().len() as u64)
        .sum::<u64>();
    let per_pixel = 2 * stride * 8 + 2 * channels * 8;
    Ok(pixels.saturating_mul(per_pixel))
}

/// `n` zeros, or an error naming `what` where the allocator cannot give them (a render
/// whose `--max-memory` was set above what the machine has: an error, not an abort).
pub fn zeroed(n: usize, what: &str) -> Result<Vec<f64>, Error> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        Error::Limit(format!(
            "{what} needs {} ({} words) and the system cannot give it; lower the \
             resolution, the AOVs or the depth, or --max-memory",
            bytes((n as u64).saturating_mul(8)),
            n
        ))
    })?;
    v.resize(n, 0.0);
    Ok(v)
}

/// A field of Linux's `/proc/meminfo` (`"MemAvailable:"`, …) in bytes; `None` where it
/// cannot be read.
fn meminfo(name: &str) -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kb: u64 = line[name.len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb.saturating_mul(1024))
}

/// The memory the system reports available now, in bytes (Linux `MemAvailable`);
/// `None` where it cannot be read.
pub fn available_memory() -> Option<u64> {
    meminfo("MemAvailable:")
}

/// The memory this machine has, RAM and swap, in bytes (Linux `MemTotal + SwapTotal`);
/// `None` where it cannot be read.
pub fn total_memory() -> Option<u64> {
    Some(meminfo("MemTotal:")?.saturating_add(meminfo("SwapTotal:").unwrap_or(0)))
}

/// The memory limit of a render: `max_memory` if non-zero (but never more than the
/// machine has, [`total_memory`]: beyond that the allocation cannot succeed), else the
/// available memory, else [`FALLBACK_MEMORY`]; with where it comes from, for messages.
pub fn memory_limit(max_memory: u64) -> (u64, &'static str) {
    if max_memory > 0 {
        return match total_memory() {
            Some(total) if total < max_memory => (
                total,
                "memory this machine has (RAM and swap; --max-memory asked for more)",
            ),
            _ => (max_memory, "--max-memory"),
        };
    }
    match available_memory() {
        Some(m) => (m, "available memory"),
        None => (FALLBACK_MEMORY, "the default limit"),
    }
}

/// Refuses a render of `width × height` with `o` whose estimate exceeds the limit
/// ([`memory_limit`] of `o.max_memory`); the estimate in bytes otherwise.
pub fn check_memory(width: u32, height: u32, o: &RenderOptions) -> Result<u64, Error> {
    let need = render_bytes(width, height, o)?;
    let (limit, what) = memory_limit(o.max_memory);
    if need > limit {
        return Err(Error::Limit(format!(
            "a {width}×{height} render with these settings needs about {} ({} bytes: \
             {} words of state per pixel, held twice, and the image), more than the {} \
             ({}); lower the resolution, the AOVs or the depth, or raise --max-memory",
            bytes(need),
            need,
            Tally::new(o)?.record.stride(),
            what,
            bytes(limit)
        )));
    }
    Ok(need)
}

/// The most worker threads allowed on this machine ([`THREADS_PER_CORE`] per core).
pub fn max_threads() -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    cores * THREADS_PER_CORE
}

/// Refuses a thread count above [`max_threads`] (0, one per core, is always allowed).
pub fn check_threads(n: usize) -> Result<(), Error> {
    let max = max_threads();
    if n > max {
        return Err(Error::Limit(format!(
            "--threads {n}: at most {max} ({THREADS_PER_CORE} per core on {} cores); 0 \
             uses one per core",
            max / THREADS_PER_CORE
        )));
    }
    Ok(())
}

/// A byte count for people: `1.5 GiB`, `12.0 MiB`, `512 B`.
pub fn bytes(n: u64) -> String {
    const UNITS: [&str; 6] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = n as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{n} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// Parses a byte size: a number with an optional unit `K`, `M`, `G`, `T` (powers of
/// 1024; `KiB`, `GB` and the like read the same), e.g. `512M`, `4G`, `1.5GiB`.
pub fn parse_bytes(s: &str) -> Result<u64, OptionsError> {
    let bad = || OptionsError::BadSize(s.to_string());
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let v: f64 = num.parse().map_err(|_| bad())?;
    let unit = unit.trim().to_ascii_uppercase();
    let unit = unit.trim_end_matches('B').trim_end_matches('I');
    let scale = match unit {
        "" => 1u64,
        "K" => 1 << 10,
        "M" => 1 << 20,
        "G" => 1 << 30,
        "T" => 1 << 40,
        _ => return Err(bad()),
    };
    let b = v * scale as f64;
    if !(b.is_finite() && b >= 1.0 && b < u64::MAX as f64) {
        return Err(bad());
    }
    Ok(b as u64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aov::Aov;

    #[test]
    fn estimate_grows_with_size_aovs_and_refuses_beyond_the_limit() {
        let o = RenderOptions::default();
        let small = render_bytes(10, 10, &o).unwrap();
        assert_eq!(render_bytes(20, 10, &o).unwrap(), 2 * small);
        let with_aovs = RenderOptions {
            aovs: vec![Aov::Depth, Aov::Normal],
            ..o.clone()
        };
        assert!(render_bytes(10, 10, &with_aovs).unwrap() > small);
        let limited = RenderOptions {
            max_memory: small,
            ..o.clone()
        };
        assert_eq!(check_memory(10, 10, &limited).unwrap(), small);
        let e = check_memory(11, 10, &limited).unwrap_err().to_string();
        assert!(
            e.contains("--max-memory") && e.contains("needs about"),
            "{e}"
        );
        // 100000 × 100000 is refused by the estimate, whatever the machine.
        let e = check_memory(100_000, 100_000, &o).unwrap_err().to_string();
        assert!(e.contains("100000×100000"), "{e}");
    }

    #[test]
    fn sizes_and_threads() {
        assert_eq!(parse_bytes("512M").unwrap(), 512 << 20);
        assert_eq!(parse_bytes("4GiB").unwrap(), 4 << 30);
        assert_eq!(parse_bytes("1.5g").unwrap(), 3 << 29);
        assert_eq!(parse_bytes("1000").unwrap(), 1000);
        assert!(parse_bytes("-1G").is_err() && parse_bytes("4X").is_err());
        assert_eq!(bytes(3 << 29), "1.5 GiB");
        assert!(check_threads(0).is_ok() && check_threads(max_threads()).is_ok());
        assert!(check_threads(100_000).is_err());
    }
}
