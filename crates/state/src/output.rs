//! Writing files whole or not at all: the bytes go to a temporary file in the same
//! directory, which is synced and then renamed over the destination (rename is atomic
//! within a file system on POSIX and Windows).
//!
//! A process killed mid-write leaves its temporary file (`.NAME.PID.N.tmp`); the next
//! write to the same path removes those of processes no longer running (on Linux, no
//! `/proc/PID`; elsewhere, older than a day).

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

fn temp_path(path: &Path) -> io::Result<PathBuf> {
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "path has no file name"))?;
    let unique = format!(
        ".{}.{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    );
    Ok(path.with_file_name(unique))
}

/// Whether the temporary file `name` of `target` was left by a write that cannot
/// finish any more (module docs).
fn is_stale(dir: &Path, name: &str, target: &str) -> bool {
    let Some(rest) = name
        .strip_prefix(&format!(".{target}."))
        .and_then(|r| r.strip_suffix(".tmp"))
    else {
        return false;
    };
    let Some(pid) = rest
        .split_once('.')
        .and_then(|(p, n)| n.parse::<u64>().ok().and(p.parse::<u32>().ok()))
    else {
        return false;
    };
    if pid == std::process::id() {
        return false;
    }
    if Path::new("/proc/self").exists() {
        return !Path::new(&format!("/proc/{pid}")).exists();
    }
    fs::metadata(dir.join(name))
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.elapsed().ok())
        .is_some_and(|age| age.as_secs() > 24 * 3600)
}

/// Removes the stale temporary files of earlier writes to `path` (module docs).
pub fn remove_stale_temporaries(path: &Path) {
    let (Some(dir), Some(target)) = (path.parent(), path.file_name()) else {
        return;
    };
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let target = target.to_string_lossy();
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if is_stale(dir, &name, &target) {
            let _ = fs::remove_file(e.path());
        }
    }
}

/// Runs `write` on a buffered temporary file next to `path` and renames it to `path`
/// on success; on any error the temporary file is removed and `path` is untouched.
/// Stale temporary files of killed writes to `path` are removed first.
pub fn write_atomically<F>(path: &Path, write: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    remove_stale_temporaries(path);
    let tmp = temp_path(path)?;
    let file = OpenOptions::new().write(true).create_new(true).open(&tmp)?;
    let result = (|| {
        let mut w = BufWriter::new(file);
        write(&mut w)?;
        w.flush()?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("render-output-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn failed_write_leaves_nothing() {
        let d = scratch("fail");
        let target = d.join("out.bin");
        fs::write(&target, b"old").unwrap();
        let err = write_atomically(&target, |w| {
            w.write_all(&[1u8; 100_000])?;
            Err(io::Error::other("disk on fire"))
        });
        assert!(err.is_err());
        assert_eq!(fs::read(&target).unwrap(), b"old");
        assert_eq!(
            fs::read_dir(&d).unwrap().count(),
            1,
            "temporary file left behind"
        );
        // A nonexistent directory: an error, and nothing created.
        let missing = d.join("no/such/dir/out.bin");
        assert!(write_atomically(&missing, |w| w.write_all(b"x")).is_err());
        assert!(!d.join("no").exists());
        write_atomically(&target, |w| w.write_all(b"new")).unwrap();
        assert_eq!(fs::read(&target).unwrap(), b"new");
        assert_eq!(fs::read_dir(&d).unwrap().count(), 1);
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn stale_temporaries_of_dead_writers_are_removed() {
        let d = scratch("stale");
        let target = d.join("out.exr");
        // A pid far above Linux's pid_max (2^22): no such process.
        let dead = d.join(".out.exr.999999999.0.tmp");
        let alive = d.join(format!(".out.exr.{}.7.tmp", std::process::id()));
        let other = d.join(".other.exr.999999999.0.tmp");
        for p in [&dead, &alive, &other] {
            fs::write(p, b"half").unwrap();
        }
        write_atomically(&target, |w| w.write_all(b"new")).unwrap();
        if Path::new("/proc/self").exists() {
            assert!(!dead.exists(), "a dead writer's temporary file is removed");
        }
        assert!(alive.exists(), "a running writer's temporary file is kept");
        assert!(other.exists(), "another file's temporary file is kept");
        fs::remove_dir_all(&d).unwrap();
    }
}
