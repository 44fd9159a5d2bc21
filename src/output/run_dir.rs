//! One run per output directory, and what a run may delete or replace in it.
//!
//! A run claims its directory before it writes anything:
//! 1. it takes an exclusive lock on `DIR/.dsmcosim.lock` (an advisory lock the
//!    operating system releases when the process ends, however it ends, so a killed run
//!    leaves no stale lock) and writes its process id into the file; a second run into
//!    the same directory fails at once, naming the holder. A lock path that is a
//!    symlink or not a regular file is refused, never followed;
//! 2. it refuses a directory whose `summary.json` is another scenario's run, unless
//!    forced (the user asked to replace it);
//! 3. it refuses a directory where a name it writes ([`OUTPUTS`], [`PLOTS`],
//!    `scenario.json`) is taken by anything but a regular file (a symlink, a FIFO, a
//!    device, a directory), and a directory that holds no run of its own (no
//!    `summary.json`, no lock file) where such a name is taken at all: those files are
//!    not a run's, so a run does not replace them.
//!
//! What a run deletes, it deletes only in a directory that holds a run, and only
//! regular files of the names above (and hidden temporary files of
//! [`super::AtomicFile`], `.<name>.tmp.<pid>.<n>`, that a killed run left behind):
//! - the previous run's outputs are kept until this run has written its own
//!   `summary.json`; then those this run did not write again (an earlier TDMA run's
//!   `network.csv`) are removed ([`RunDir::remove_stale`]). A run that fails before
//!   (a full disk) leaves the previous run's files it had not replaced yet;
//! - forced over another scenario's run, it also removes that run's checkpoints
//!   (`checkpoints/*.ckpt`), which would otherwise resume the other scenario.
//!
//! Nothing else is touched: the checkpoints of the same scenario's runs (a run may
//! resume from one of them into the same directory), a sweep point's `done.json`, the
//! user's own files. The lock file itself stays (deleting it would let a waiting run
//! lock a file that is no longer the directory's); it is hidden and ignored by git.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Name of the lock file inside a run directory.
pub const LOCK_FILE: &str = ".dsmcosim.lock";

/// Files a run writes at the top of its directory, besides its plots ([`PLOTS`]).
/// `scenario.json` is not among them: the caller that ran the scenario writes it (the
/// CLI after the run, a sweep before it), so it is never a leftover of another run.
pub const OUTPUTS: &[&str] = &[
    "summary.json",
    "trace.csv",
    "epochs.csv",
    "network.csv",
    "surface.csv",
    "landscape.csv",
];

/// The plots a run writes (which of them depends on the scenario).
pub const PLOTS: &[&str] = &[
    "constraints.svg",
    "bodies.svg",
    "angular_velocity.svg",
    "signals.svg",
    "cost.svg",
    "delays.svg",
    "bandwidth.svg",
    "timeline.svg",
    "list_lag.svg",
    "cost_methods.svg",
    "delays_optimum.svg",
    "surface.svg",
    "landscape.svg",
];

/// Whether `name` is a file a run writes at the top of its directory (`scenario.json`
/// included).
pub fn is_run_file(name: &str) -> bool {
    OUTPUTS.contains(&name) || PLOTS.contains(&name) || name == "scenario.json"
}

/// Whether `dir` holds a run of its own: a `summary.json` or a run's lock file.
pub fn holds_run(dir: &Path) -> bool {
    [dir.join("summary.json"), dir.join(LOCK_FILE)]
        .iter()
        .any(|p| std::fs::symlink_metadata(p).is_ok_and(|m| m.is_file()))
}

/// A claimed run directory; the lock is held until this is dropped.
#[derive(Debug)]
pub struct RunDir {
    path: PathBuf,
    _lock: File,
    /// The regular files of a previous run found at the claim, with their identity
    /// (device, inode): removed by [`RunDir::remove_stale`] unless replaced.
    previous: Vec<(PathBuf, Option<(u64, u64)>)>,
    /// The identity of `summary.json` at the claim (`None`: absent).
    summary: Option<(u64, u64)>,
}

/// The identity (device, inode) of the regular file at `path`, not following a symlink.
fn identity(path: &Path) -> Option<(u64, u64)> {
    let m = std::fs::symlink_metadata(path).ok()?;
    if !m.is_file() {
        return None;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some((m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        // No inode: the length and modification time stand in for it.
        let t = m
            .modified()
            .ok()?
            .duration_since(std::time::UNIX_EPOCH)
            .ok()?;
        Some((m.len(), t.as_nanos() as u64))
    }
}

impl RunDir {
    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Removes the previous run's outputs this run did not write again, once this run
    /// has written its `summary.json` (before that, nothing: a run that stopped half-way
    /// leaves the previous run's files it had not replaced). Only regular files still
    /// the very files found at the claim are removed.
    pub fn remove_stale(&self) -> Result<()> {
        let summary = self.path.join("summary.json");
        let now = identity(&summary);
        if now.is_none() || now == self.summary {
            return Ok(());
        }
        for (path, id) in &self.previous {
            if id.is_some() && identity(path) == *id {
                std::fs::remove_file(path).map_err(|e| Error::io(path, e))?;
            }
        }
        Ok(())
    }
}

/// Whether `name` is a temporary file of an atomic write: `.<name>.tmp.<pid>.<n>`,
/// `<n>` digits (what earlier versions wrote) or letters and digits (`tempfile`'s
/// random part, what [`super::AtomicFile`] writes now).
fn is_temporary(name: &str) -> bool {
    let Some(rest) = name.strip_prefix('.') else {
        return false;
    };
    let Some((_, tail)) = rest.rsplit_once(".tmp.") else {
        return false;
    };
    let mut parts = tail.split('.');
    let numeric =
        |p: Option<&str>| p.is_some_and(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()));
    let alphanumeric = |p: Option<&str>| {
        p.is_some_and(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_alphanumeric()))
    };
    numeric(parts.next()) && alphanumeric(parts.next()) && parts.next().is_none()
}

/// The scenario name of the run stored in `dir`, if it holds a readable summary.
fn stored_scenario(dir: &Path) -> Option<String> {
    let path = dir.join("summary.json");
    let text = crate::input::read_text(&path).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v.get("scenario")?.as_str().map(str::to_string)
}

/// Opens (creating it if absent) and exclusively locks the lock file `dir/name`.
/// `what` names the holder in the error (`dsmcosim run`). A lock path that is a
/// symlink or not a regular file is refused, not followed (exit 2).
///
/// Errors: another process holds the lock (an I/O error, exit 1, naming its process
/// id, which the holder writes into the file).
pub fn lock(dir: &Path, name: &str, what: &str) -> Result<File> {
    let lock_path = dir.join(name);
    super::check_replaceable(&lock_path, "lock file")?;
    let mut options = OpenOptions::new();
    options.read(true).write(true).create(true).truncate(false);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // A symlink put there after the check above fails to open instead of being
        // followed.
        options.custom_flags(libc::O_NOFOLLOW);
    }
    let mut lock = options
        .open(&lock_path)
        .map_err(|e| Error::io(&lock_path, e))?;
    if let Err(e) = lock.try_lock() {
        let mut holder = String::new();
        let _ = (&mut lock).take(64).read_to_string(&mut holder);
        let holder = holder.trim();
        let who = if holder.is_empty() {
            "another process".to_string()
        } else {
            format!("process {holder}")
        };
        let message = format!("{} is in use by another {what} ({who}): {e}", dir.display());
        return Err(Error::io(
            dir,
            std::io::Error::new(std::io::ErrorKind::WouldBlock, message),
        ));
    }
    let _ = lock.set_len(0);
    let _ = lock.rewind();
    let _ = write!(lock, "{}", std::process::id());
    Ok(lock)
}

/// Claims `dir` for a run of scenario `scenario` (see the module documentation):
/// creates it, locks it, checks whose run it holds (`force` replaces another
/// scenario's) and that every name the run writes may be replaced, and removes the
/// temporary files of earlier runs (and, forced over another scenario, its
/// checkpoints). The previous run's outputs stay until [`RunDir::remove_stale`].
///
/// Errors: another process holds the lock (an I/O error, exit 1, naming its process
/// id); the directory holds another scenario's run and `force` is false, a name the
/// run writes is taken by something else than a regular file, or by a file in a
/// directory that holds no run (exit 2, naming `--out` or the path).
pub fn claim(dir: &Path, scenario: &str, force: bool) -> Result<RunDir> {
    super::create_out_dir(dir)?;
    let had_run = holds_run(dir);
    let lock = lock(dir, LOCK_FILE, "dsmcosim run")?;
    let other = stored_scenario(dir).filter(|s| s != scenario);
    if let (Some(other), false) = (&other, force) {
        return Err(Error::invalid(
            "--out",
            format!(
                "{} holds a run of scenario `{other}`, not `{scenario}` (choose another \
                 directory, or --force to replace it)",
                dir.display()
            ),
        ));
    }
    let names = OUTPUTS.iter().chain(PLOTS).chain(&["scenario.json"]);
    let mut previous = Vec::new();
    for name in names {
        let path = dir.join(name);
        super::check_replaceable(&path, "output")?;
        if !had_run && path.exists() {
            return Err(Error::invalid(
                path.display().to_string(),
                format!(
                    "exists in {}, which holds no dsmcosim run; a run replaces only its own \
                     files (choose another --out, or move the file)",
                    dir.display()
                ),
            ));
        }
        if *name != "scenario.json" {
            previous.push((path.clone(), identity(&path)));
        }
    }
    if had_run {
        let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(dir, e))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            let is_file = entry.file_type().is_ok_and(|t| t.is_file());
            if is_file && is_temporary(&name) {
                let path = entry.path();
                std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
            }
        }
    }
    if other.is_some() {
        remove_checkpoints(dir)?;
    }
    Ok(RunDir {
        path: dir.to_path_buf(),
        _lock: lock,
        summary: identity(&dir.join("summary.json")),
        previous,
    })
}

/// Removes the checkpoint files (`*.ckpt`, regular files) of `dir/checkpoints/`, and the
/// directory if that empties it; a `checkpoints` that is not a directory (or a symlink
/// to one) is left alone.
fn remove_checkpoints(dir: &Path) -> Result<()> {
    let cps = dir.join("checkpoints");
    if !std::fs::symlink_metadata(&cps).is_ok_and(|m| m.is_dir()) {
        return Ok(());
    }
    let entries = std::fs::read_dir(&cps).map_err(|e| Error::io(&cps, e))?;
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(&cps, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        if is_file && (name.ends_with(".ckpt") || is_temporary(&name)) {
            let path = entry.path();
            std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
        }
    }
    // Kept if the user put anything else there.
    let _ = std::fs::remove_dir(&cps);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporary_names_are_those_atomic_writes_use() {
        assert!(is_temporary(".trace.csv.tmp.4242.0"));
        assert!(is_temporary(".summary.json.tmp.1.17"));
        assert!(is_temporary(".trace.csv.tmp.4242.aB3xYz9q"));
        // The name an open atomic file really has.
        let dir = std::env::temp_dir().join(format!("dsmcosim-tmpname-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = super::super::AtomicFile::create(&dir.join("trace.csv")).unwrap();
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names.len(), 1);
        assert!(is_temporary(&names[0]), "{names:?}");
        drop(f);
        std::fs::remove_dir(&dir).unwrap();
        for name in [
            "trace.csv",
            ".trace.csv.tmp.x.0",
            ".a.tmp.1",
            "a.tmp.1.2",
            ".a.tmp.1.2.3",
            ".tmp.1.2x",
            ".trace.csv.tmp.1.a-b",
        ] {
            assert!(!is_temporary(name), "{name}");
        }
    }
}
