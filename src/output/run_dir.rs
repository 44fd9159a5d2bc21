//! One run per output directory.
//!
//! A run claims its directory before it writes anything:
//! 1. it takes an exclusive lock on `DIR/.dsmcosim.lock` (an advisory lock the
//!    operating system releases when the process ends, however it ends, so a killed run
//!    leaves no stale lock) and writes its process id into the file; a second run into
//!    the same directory fails at once, naming the holder;
//! 2. it refuses a directory whose `summary.json` is another scenario's run, unless
//!    forced (the user asked to replace it);
//! 3. it removes what earlier runs left that this run might not overwrite: the files a
//!    run writes at the top of its directory ([`OUTPUTS`], every `.svg`) and hidden
//!    temporary files of [`super::AtomicFile`] (`.<name>.tmp.<pid>.<n>`) that a killed
//!    run left behind. Nothing else is touched: `checkpoints/` (a run may resume from
//!    one of them into the same directory), a sweep point's `done.json`, the user's own
//!    files.
//!
//! The lock file itself stays (deleting it would let a waiting run lock a file that is
//! no longer the directory's); it is hidden and ignored by git.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Name of the lock file inside a run directory.
pub const LOCK_FILE: &str = ".dsmcosim.lock";

/// Files a run writes at the top of its directory, besides its `.svg` plots.
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

/// A claimed run directory; the lock is held until this is dropped.
#[derive(Debug)]
pub struct RunDir {
    path: PathBuf,
    _lock: File,
}

impl RunDir {
    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
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
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v.get("scenario")?.as_str().map(str::to_string)
}

/// Claims `dir` for a run of scenario `scenario` (see the module documentation):
/// creates it, locks it, checks whose run it holds (`force` replaces another
/// scenario's), and clears the outputs and temporary files of earlier runs.
///
/// Errors: another process holds the lock (an I/O error, exit 1, naming its process
/// id); the directory holds another scenario's run and `force` is false (exit 2,
/// naming `--out`).
pub fn claim(dir: &Path, scenario: &str, force: bool) -> Result<RunDir> {
    super::create_dir_all(dir)?;
    let lock_path = dir.join(LOCK_FILE);
    let mut lock = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&lock_path)
        .map_err(|e| Error::io(&lock_path, e))?;
    if let Err(e) = lock.try_lock() {
        let mut holder = String::new();
        let _ = lock.read_to_string(&mut holder);
        let holder = holder.trim();
        let who = if holder.is_empty() {
            "another process".to_string()
        } else {
            format!("process {holder}")
        };
        let message = format!(
            "{} is in use by another dsmcosim run ({who}): {e}",
            dir.display()
        );
        return Err(Error::io(
            dir,
            std::io::Error::new(std::io::ErrorKind::WouldBlock, message),
        ));
    }
    let _ = lock.set_len(0);
    let _ = lock.rewind();
    let _ = write!(lock, "{}", std::process::id());
    if !force {
        if let Some(other) = stored_scenario(dir).filter(|s| s != scenario) {
            return Err(Error::invalid(
                "--out",
                format!(
                    "{} holds a run of scenario `{other}`, not `{scenario}` (choose another \
                     directory, or --force to replace it)",
                    dir.display()
                ),
            ));
        }
    }
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        let ours =
            OUTPUTS.contains(&name.as_str()) || name.ends_with(".svg") || is_temporary(&name);
        if is_file && ours {
            let path = entry.path();
            std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
        }
    }
    Ok(RunDir {
        path: dir.to_path_buf(),
        _lock: lock,
    })
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
