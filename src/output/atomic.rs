//! Atomic file replacement: write to a temporary sibling, sync, then rename.
//!
//! `rename` within one directory is atomic on POSIX and replaces the target
//! on Windows too, so readers (ParaView polling a time series, a user
//! inspecting results of a run that was killed) only ever see a complete file.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Distinguishes temp files of concurrent writes from the same process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes `bytes` to `path` atomically (whole or not at all).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Streams the content produced by `f` to `path` atomically.
///
/// The data go to `.{filename}.tmp-{pid}-{n}` in the target's directory (the
/// same file system, so the final rename cannot degrade into a copy). If `f`
/// or any later step fails, or `f` panics, the temporary file is removed and
/// an existing target is left untouched.
pub fn write_atomic_with(path: &Path, f: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<()> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("not a file path: {}", path.display()),
        )
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp-{}-{n}", std::process::id()));
    let tmp = TempFile(dir.join(tmp_name));

    // create_new: never clobber a file we do not own.
    let file = OpenOptions::new().write(true).create_new(true).open(&tmp.0)?;
    let mut w = BufWriter::new(file);
    f(&mut w)?;
    let file = w.into_inner().map_err(io::IntoInnerError::into_error)?;
    // Data must be on disk before the rename publishes them, otherwise a
    // power loss can leave a complete-looking but empty target.
    file.sync_all()?;
    drop(file);
    fs::rename(&tmp.0, path)?;
    tmp.disarm();
    sync_dir(dir);
    Ok(())
}

/// Makes the rename itself durable. Best effort: the write already succeeded
/// and is atomic either way, and not every platform can open a directory.
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

/// Removes the temporary file on drop unless disarmed (covers `?` and panics).
struct TempFile(PathBuf);

impl TempFile {
    fn disarm(self) {
        std::mem::forget(self);
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = fs::remove_file(&self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch_dir(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!(
            "thermocontact-atomic-{tag}-{}-{}",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn content_round_trips_and_replaces() {
        let dir = scratch_dir("rt");
        let path = dir.join("a.txt");
        write_atomic(&path, b"first").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"first");
        write_atomic_with(&path, |w| {
            w.write_all(b"sec")?;
            w.write_all(b"ond")
        })
        .unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"second");
        assert_eq!(entries(&dir), ["a.txt"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failing_writer_leaves_nothing() {
        let dir = scratch_dir("fail");
        let path = dir.join("b.txt");
        let err = write_atomic_with(&path, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        })
        .unwrap_err();
        assert_eq!(err.to_string(), "boom");
        assert!(entries(&dir).is_empty(), "left {:?}", entries(&dir));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failing_writer_keeps_old_target() {
        let dir = scratch_dir("keep");
        let path = dir.join("c.txt");
        write_atomic(&path, b"old").unwrap();
        assert!(write_atomic_with(&path, |_| Err(io::Error::other("boom"))).is_err());
        assert_eq!(fs::read(&path).unwrap(), b"old");
        assert_eq!(entries(&dir), ["c.txt"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn panicking_writer_leaves_no_temp() {
        let dir = scratch_dir("panic");
        let path = dir.join("d.txt");
        let r = std::panic::catch_unwind(|| {
            let _ = write_atomic_with(&path, |_| panic!("writer panicked"));
        });
        assert!(r.is_err());
        assert!(entries(&dir).is_empty(), "left {:?}", entries(&dir));
        fs::remove_dir_all(&dir).unwrap();
    }
}
