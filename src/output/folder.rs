//! An output folder owned by one run.
//!
//! A run *claims* its folder before it writes anything: it takes an exclusive lock on
//! `.thermocontact.lock` (held until the run ends, released by the OS if the process dies, so a
//! killed run never leaves a stale lock), then looks for the files of another run. A folder with
//! results is refused unless the caller asks to replace them (`--overwrite`: that run's files
//! are removed first; the CLI's default folder: only a *completed* run's, [`Existing::ReplaceCompleted`])
//! or to continue them (`--restart`: the frames after the checkpoint are
//! removed; so is a stopped run's frame of its last state). So `summary.json`, `solution.pvd` and the frames always belong to one run.
//!
//! Only the run's own file names are touched: a user's notes or scripts in the folder stay.
//!
//! The lock file is removed when the run ends (the [`RunFolder`] dropped, still holding the
//! lock), so a finished folder holds only results. Removing a locked file races with a run that
//! opened it just before: that run would lock a file no longer in the folder, while a third
//! creates a new one. So a claim checks, once locked, that the file it locked is still the one
//! named `.thermocontact.lock`, and starts again where it is not. A killed run's lock file
//! stays, unlocked: the next claim locks and reuses it, as before.
//!
//! *Rejected*: a lock file created with `create_new` and removed at the end. A killed run leaves
//! it behind, and the next run must then guess whether its owner is still alive.

use std::fs::{self, File, OpenOptions, TryLockError};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The lock file's name.
pub const LOCK_FILE: &str = ".thermocontact.lock";

/// The checkpoint's file name in an output folder.
pub const CHECKPOINT_FILE: &str = "checkpoint.bin";

/// What a run may do with the results of another run it finds in its folder.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Existing {
    /// Refuse the folder.
    Refuse,
    /// Remove that run's files first.
    Overwrite,
    /// Continue that run from its checkpoint: keep the frames of these time levels (the output
    /// times it reached), remove the others (those after the checkpoint, and a stopped run's
    /// frame of its last state).
    Continue { frames: Vec<usize> },
    /// Remove that run's files first if it completed (its `summary.json` says so); refuse the
    /// folder otherwise (a running, interrupted or failed run may still be continued or
    /// inspected). The CLI's default folder, so that running the same command twice works.
    ReplaceCompleted,
}

/// Whether `dir` holds the results of a run that completed: its `summary.json` says
/// `"status": "completed"`.
pub fn holds_completed_run(dir: &Path) -> bool {
    let Ok(bytes) = fs::read(dir.join("summary.json")) else {
        return false;
    };
    serde_json::from_slice::<serde_json::Value>(&bytes)
        .is_ok_and(|summary| summary.get("status").and_then(|s| s.as_str()) == Some("completed"))
}

/// Why a folder cannot be claimed.
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    #[error("cannot use {} as the output folder: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error(
        "another run is writing into {} ({holder}); wait for it, or choose another --out",
        dir.display()
    )]
    Locked { dir: PathBuf, holder: String },
    #[error(
        "{} holds the results of another run ({found}); pass --overwrite to replace them{}, or choose another --out",
        dir.display(), restart_phrase(dir, *restartable)
    )]
    HoldsResults {
        dir: PathBuf,
        found: String,
        /// The folder has a checkpoint, so `--restart` could continue that run.
        restartable: bool,
    },
}

/// A claimed output folder; the lock is held until it is dropped.
#[derive(Debug)]
pub struct RunFolder {
    dir: PathBuf,
    /// Held until the run ends; taken by `drop`.
    lock: Option<File>,
}

impl RunFolder {
    /// Creates `dir` if needed, locks it, and deals with another run's results as `existing`
    /// says.
    pub fn claim(dir: &Path, existing: &Existing) -> Result<Self, FolderError> {
        let io = |source| FolderError::Io {
            path: dir.to_path_buf(),
            source,
        };
        fs::create_dir_all(dir).map_err(io)?;
        let lock_path = dir.join(LOCK_FILE);
        let mut lock = loop {
            let lock = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&lock_path)
                .map_err(io)?;
            match lock.try_lock() {
                // The run before removed the file after this one opened it: lock the new one.
                Ok(()) if !same_file(&lock, &lock_path) => continue,
                Ok(()) => break lock,
                Err(error) => return Err(locked(dir, &lock_path, error)),
            }
        };
        lock.set_len(0).map_err(io)?;
        write!(lock, "process {}", std::process::id()).map_err(io)?;
        // From here on the lock file goes with `folder`, a refusal's included.
        let folder = RunFolder {
            dir: dir.to_path_buf(),
            lock: Some(lock),
        };

        let files = run_files(dir).map_err(io)?;
        let refuse = || FolderError::HoldsResults {
            dir: dir.to_path_buf(),
            found: describe(&files),
            restartable: files.iter().any(|f| f == CHECKPOINT_FILE),
        };
        match existing {
            Existing::Refuse if !files.is_empty() => return Err(refuse()),
            Existing::ReplaceCompleted if !files.is_empty() && !holds_completed_run(dir) => return Err(refuse()),
            Existing::Refuse => {}
            Existing::Overwrite | Existing::ReplaceCompleted => {
                for file in &files {
                    remove(&dir.join(file)).map_err(io)?;
                }
            }
            Existing::Continue { frames } => {
                let stale = |f: &&String| frame_step(f).is_some_and(|n| !frames.contains(&n)) || is_temporary(f);
                for file in files.iter().filter(stale) {
                    remove(&dir.join(file)).map_err(io)?;
                }
            }
        }
        Ok(folder)
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

impl Drop for RunFolder {
    /// The run ended (completed, failed or stopped): its lock file goes, removed while still
    /// locked and only if it is still this run's (see the module's header).
    fn drop(&mut self) {
        let path = self.dir.join(LOCK_FILE);
        if let Some(lock) = self.lock.take() {
            if same_file(&lock, &path) {
                let _ = fs::remove_file(&path);
            }
            drop(lock);
        }
    }
}

/// Whether the open file `file` is the one at `path` now.
fn same_file(file: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (file.metadata(), fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (file, path);
        true
    }
}

/// The error of a lock that could not be taken.
fn locked(dir: &Path, lock_path: &Path, error: TryLockError) -> FolderError {
    match error {
        TryLockError::WouldBlock => {
            let holder = fs::read_to_string(lock_path).unwrap_or_default();
            let holder = match holder.trim() {
                "" => "a process that has not written its id yet".to_string(),
                text => text.to_string(),
            };
            FolderError::Locked {
                dir: dir.to_path_buf(),
                holder,
            }
        }
        TryLockError::Error(source) => FolderError::Io {
            path: dir.to_path_buf(),
            source,
        },
    }
}

/// The `--restart` choice, offered only where there is a checkpoint to continue from (a
/// completed run has none).
fn restart_phrase(dir: &Path, restartable: bool) -> String {
    if restartable {
        format!(
            ", `--restart {}` to continue that run from its checkpoint",
            dir.display()
        )
    } else {
        String::new()
    }
}

fn remove(path: &Path) -> std::io::Result<()> {
    match fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

/// The names of the files a run writes that are in `dir`, sorted.
pub fn run_files(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut files = Vec::new();
    for entry in fs::read_dir(dir)? {
        let name = entry?.file_name().to_string_lossy().into_owned();
        if is_run_file(&name) {
            files.push(name);
        }
    }
    files.sort();
    Ok(files)
}

/// A file name of a run's output: the fixed names, the frames, and temporary files that an
/// atomic write of one of them left (`.{name}.tmp-{pid}-{n}`).
fn is_run_file(name: &str) -> bool {
    const FIXED: [&str; 5] = [
        "summary.json",
        "solution.pvd",
        "scenario.toml",
        "steps.csv",
        CHECKPOINT_FILE,
    ];
    FIXED.contains(&name) || frame_step(name).is_some() || is_temporary(name)
}

fn is_temporary(name: &str) -> bool {
    name.strip_prefix('.')
        .and_then(|rest| rest.split_once(".tmp-"))
        .is_some_and(|(target, _)| is_run_file(target))
}

/// The time level of a frame file (`solution_0016.vtu`, `contact_0016.csv`; a distributed
/// run's `solution_0016.pvtu` and its pieces `solution_0016_p1.vtu`).
pub fn frame_step(name: &str) -> Option<usize> {
    fn number(s: &str) -> Option<&str> {
        (!s.is_empty() && s.bytes().all(|b| b.is_ascii_digit())).then_some(s)
    }
    let digits = if let Some(rest) = name.strip_prefix("solution_") {
        match rest.strip_suffix(".vtu") {
            Some(stem) => match stem.split_once("_p") {
                Some((digits, rank)) => number(rank).and(Some(digits)),
                None => Some(stem),
            },
            None => rest.strip_suffix(".pvtu"),
        }
    } else {
        name.strip_prefix("contact_").and_then(|rest| rest.strip_suffix(".csv"))
    };
    number(digits?)?.parse().ok()
}

/// "summary.json, solution.pvd, 8 frame files" for a message.
fn describe(files: &[String]) -> String {
    let frames = files.iter().filter(|f| frame_step(f).is_some()).count();
    let mut parts: Vec<String> = files
        .iter()
        .filter(|f| frame_step(f).is_none() && !f.starts_with('.'))
        .cloned()
        .collect();
    if frames > 0 {
        parts.push(format!("{frames} frame files"));
    }
    if parts.is_empty() {
        parts.push("temporary files of an interrupted write".into());
    }
    parts.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("tc-folder-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn names_of_a_run() {
        assert_eq!(frame_step("solution_0016.vtu"), Some(16));
        assert_eq!(frame_step("contact_12345.csv"), Some(12345));
        assert_eq!(frame_step("solution_.vtu"), None);
        assert_eq!(frame_step("solution_12a.vtu"), None);
        assert_eq!(frame_step("solution_0016.pvtu"), Some(16));
        assert_eq!(frame_step("solution_0016_p12.vtu"), Some(16));
        assert_eq!(frame_step("solution_0016_p.vtu"), None);
        assert_eq!(frame_step("solution_0016_q1.vtu"), None);
        assert!(is_run_file(".solution_0001_p1.vtu.tmp-77-3"));
        assert!(is_run_file(".solution_0001.vtu.tmp-77-3"));
        assert!(is_run_file("summary.json"));
        assert!(!is_run_file("notes.txt"));
        assert!(!is_run_file(".notes.txt.tmp-1-2"));
    }

    #[test]
    fn a_folder_with_results_is_refused_overwritten_or_continued() {
        let dir = folder("claim");
        for f in [
            "summary.json",
            "solution_0016.vtu",
            "solution_0032.vtu",
            "contact_0032.csv",
            "notes.txt",
        ] {
            fs::write(dir.join(f), "x").unwrap();
        }
        let e = RunFolder::claim(&dir, &Existing::Refuse).unwrap_err().to_string();
        assert!(
            e.contains("--overwrite") && e.contains("summary.json") && e.contains("3 frame files"),
            "{e}"
        );
        // No checkpoint (a completed run): nothing to continue, so no `--restart`.
        assert!(!e.contains("--restart"), "{e}");
        fs::write(dir.join("checkpoint.bin"), "x").unwrap();
        let e = RunFolder::claim(&dir, &Existing::Refuse).unwrap_err().to_string();
        assert!(e.contains(&format!("`--restart {}`", dir.display())), "{e}");
        drop(RunFolder::claim(&dir, &Existing::Continue { frames: vec![16] }).unwrap());
        assert!(dir.join("solution_0016.vtu").exists() && !dir.join("solution_0032.vtu").exists());
        assert!(!dir.join("contact_0032.csv").exists() && dir.join("summary.json").exists());
        drop(RunFolder::claim(&dir, &Existing::Overwrite).unwrap());
        assert_eq!(run_files(&dir).unwrap(), Vec::<String>::new());
        assert!(dir.join("notes.txt").exists(), "a user's file stays");
        RunFolder::claim(&dir, &Existing::Refuse).unwrap();
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_locked_folder_is_refused() {
        let dir = folder("lock");
        let first = RunFolder::claim(&dir, &Existing::Refuse).unwrap();
        let e = RunFolder::claim(&dir, &Existing::Overwrite).unwrap_err();
        assert!(matches!(e, FolderError::Locked { .. }), "{e}");
        assert!(
            e.to_string().contains(&format!("process {}", std::process::id())),
            "{e}"
        );
        drop(first);
        RunFolder::claim(&dir, &Existing::Refuse).unwrap();
        fs::remove_dir_all(&dir).unwrap();
    }
}
