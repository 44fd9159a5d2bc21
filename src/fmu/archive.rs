//! Safe unpacking of a `.fmu` (a zip archive) into a private temporary directory.
//!
//! The archive is first copied into the private directory while its blake3 hash is
//! computed, so the hash names exactly the bytes that are unpacked (the user's file may
//! change meanwhile without the two disagreeing) and memory stays bounded. Each entry is
//! then refused if its path is absolute, contains `..` or otherwise leaves the directory,
//! or if it is a symbolic link; no entry is ever written through a link because none is
//! created. Sizes are counted on the bytes actually written, never taken from the zip
//! headers, which an archive may understate (a "zip bomb").

use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Write};
use std::path::{Component, Path, PathBuf};

use tempfile::TempDir;

use super::FmuError;

/// Largest `.fmu` file read [bytes]: 512 MiB. FMUs are compiled models with small
/// resources (kilobytes to tens of megabytes); a bigger file is more likely a mistake
/// than a model, and it is copied to disk before unpacking.
pub const MAX_ARCHIVE_BYTES: u64 = 512 << 20;
/// Most entries in one archive: 10 000. An FMU has a description, a few binaries and
/// its resources; each entry costs a file creation, so the count is capped too.
pub const MAX_ENTRIES: u64 = 10_000;
/// Most bytes written in total by one unpack [bytes]: 1 GiB, counted as written, so a
/// small archive that inflates to fill the disk stops here.
pub const MAX_TOTAL_BYTES: u64 = 1 << 30;
/// Most bytes written for one entry [bytes]: 512 MiB, counted as written; no single
/// binary or resource of a sane FMU is near it.
pub const MAX_ENTRY_BYTES: u64 = 512 << 20;

/// The caps one unpack applies; [`Limits::default`] is the `MAX_*` constants. Tests and
/// callers with special needs pass others to [`unpack_with_limits`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest archive file [bytes].
    pub archive_bytes: u64,
    /// Most entries.
    pub entries: u64,
    /// Most bytes written in total [bytes].
    pub total_bytes: u64,
    /// Most bytes written for one entry [bytes].
    pub entry_bytes: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            archive_bytes: MAX_ARCHIVE_BYTES,
            entries: MAX_ENTRIES,
            total_bytes: MAX_TOTAL_BYTES,
            entry_bytes: MAX_ENTRY_BYTES,
        }
    }
}

/// An unpacked FMU: its private directory (mode 0700, removed on drop) and the blake3
/// hash of the archive it came from.
#[derive(Debug)]
pub struct Unpacked {
    dir: TempDir,
    hash: String,
}

impl Unpacked {
    /// The unpacked tree: `modelDescription.xml`, `binaries/`, `resources/`.
    pub fn root(&self) -> PathBuf {
        self.dir.path().join(CONTENT)
    }

    /// The blake3 hash of the `.fmu` file, lower-case hex.
    pub fn hash(&self) -> &str {
        &self.hash
    }
}

/// Subdirectory of the private directory that receives the entries; the archive's copy
/// sits beside it while unpacking, so no entry name can collide with it.
const CONTENT: &str = "fmu";
/// Name of the archive's copy inside the private directory.
const COPY: &str = "archive.fmu";

/// Start of every unpack directory's name, followed by the unpacking process's id and a
/// random suffix: `dsmcosim-fmu-<pid>-XXXXXX`.
const PREFIX: &str = "dsmcosim-fmu-";

/// Removes from `tmp` the unpack directories of processes that no longer run: an FMU
/// that crashed or called `exit` takes the process down before its directory is
/// removed. Only directories (never a symlink) named `dsmcosim-fmu-<pid>-…`, owned by
/// this user, whose process is gone are removed; a live (or reused) pid keeps its
/// directory, and nothing here stops a run.
fn remove_stale(tmp: &Path) {
    let Ok(entries) = fs::read_dir(tmp) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix(PREFIX))
            .and_then(|rest| rest.split_once('-'))
            .and_then(|(pid, _)| pid.parse::<u32>().ok())
        else {
            continue;
        };
        let Ok(meta) = fs::symlink_metadata(entry.path()) else {
            continue;
        };
        if !meta.is_dir() || !owned_by_us(&meta) || process_runs(pid) {
            continue;
        }
        let _ = fs::remove_dir_all(entry.path());
    }
}

#[cfg(unix)]
fn owned_by_us(meta: &fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    // SAFETY: geteuid has no preconditions and cannot fail.
    meta.uid() == unsafe { libc::geteuid() }
}

#[cfg(not(unix))]
fn owned_by_us(_: &fs::Metadata) -> bool {
    false
}

/// Whether process `pid` exists (signal 0 probes without sending; a process of another
/// user answers EPERM and exists too).
#[cfg(unix)]
fn process_runs(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return true;
    };
    // SAFETY: kill with signal 0 only checks that the process exists.
    let probed = unsafe { libc::kill(pid, 0) };
    probed == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

#[cfg(not(unix))]
fn process_runs(_: u32) -> bool {
    true
}

/// Unpacks `path` with the default caps ([`Limits::default`]).
pub fn unpack(path: &Path) -> Result<Unpacked, FmuError> {
    unpack_with_limits(path, &Limits::default())
}

/// Unpacks `path` into a new private temporary directory, refusing unsafe entries and
/// stopping at the first cap exceeded.
pub fn unpack_with_limits(path: &Path, limits: &Limits) -> Result<Unpacked, FmuError> {
    let io_err = |p: &Path| {
        let p = p.to_path_buf();
        move |source| FmuError::Io { path: p, source }
    };
    static SWEPT: std::sync::Once = std::sync::Once::new();
    SWEPT.call_once(|| remove_stale(&std::env::temp_dir()));
    let dir = tempfile::Builder::new()
        .prefix(&format!("{PREFIX}{}-", std::process::id()))
        .tempdir()
        .map_err(io_err(&std::env::temp_dir()))?;
    // tempfile creates it 0700 already; set it anyway, the privacy is the point.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        fs::set_permissions(dir.path(), fs::Permissions::from_mode(0o700))
            .map_err(io_err(dir.path()))?;
    }
    let copy = dir.path().join(COPY);
    let hash = copy_hashed(path, &copy, limits.archive_bytes)?;
    let root = dir.path().join(CONTENT);
    make_dir(&root)?;
    let file = File::open(&copy).map_err(io_err(&copy))?;
    let mut zip = zip::ZipArchive::new(file).map_err(|e| FmuError::NotZip {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let count = zip.len() as u64;
    if count > limits.entries {
        return Err(FmuError::CapExceeded {
            what: "MAX_ENTRIES (entries in the archive)".into(),
            value: count,
            limit: limits.entries,
        });
    }
    let mut total = 0u64;
    for i in 0..zip.len() {
        let mut entry = zip.by_index(i).map_err(|e| FmuError::NotZip {
            path: path.to_path_buf(),
            message: format!("entry {i}: {e}"),
        })?;
        let name = entry
            .name()
            .map(|n| n.into_owned())
            .unwrap_or_else(|_| format!("#{i} (name not readable)"));
        let rel = safe_relative(&name, entry.enclosed_name(), entry.is_symlink())?;
        let dest = root.join(&rel);
        if entry.is_dir() {
            make_dir(&dest)?;
            continue;
        }
        if let Some(parent) = dest.parent() {
            make_dir(parent)?;
        }
        let exec = entry.unix_mode().is_some_and(|m| m & 0o100 != 0);
        let mut out = new_private_file(exec)
            .open(&dest)
            .map_err(|source| FmuError::Entry {
                entry: name.clone(),
                source,
            })?;
        let allowance = limits.entry_bytes.min(limits.total_bytes - total);
        let written =
            io::copy(&mut (&mut entry).take(allowance + 1), &mut out).map_err(|source| {
                FmuError::Entry {
                    entry: name.clone(),
                    source,
                }
            })?;
        if written > limits.entry_bytes {
            return Err(FmuError::CapExceeded {
                what: format!("MAX_ENTRY_BYTES (bytes of entry '{name}')"),
                value: written,
                limit: limits.entry_bytes,
            });
        }
        total += written;
        if total > limits.total_bytes {
            return Err(FmuError::CapExceeded {
                what: "MAX_TOTAL_BYTES (bytes unpacked)".into(),
                value: total,
                limit: limits.total_bytes,
            });
        }
    }
    drop(zip);
    fs::remove_file(&copy).map_err(io_err(&copy))?;
    Ok(Unpacked { dir, hash })
}

/// The entry's path relative to the unpack root, or why it is refused. `enclosed` is the
/// zip reader's own check (`None`: absolute, or leaves the directory); the raw name is
/// checked too, so `a/../b`, which the reader would accept, is refused as well.
fn safe_relative(
    name: &str,
    enclosed: Option<PathBuf>,
    symlink: bool,
) -> Result<PathBuf, FmuError> {
    let refuse = |reason| FmuError::UnsafeEntry {
        entry: name.to_string(),
        reason,
    };
    if symlink {
        return Err(refuse("it is a symbolic link"));
    }
    if name.split(['/', '\\']).any(|part| part == "..") {
        return Err(refuse("its path contains '..'"));
    }
    // `C:…` is a Windows drive path.
    if name.starts_with(['/', '\\']) || name.as_bytes().get(1) == Some(&b':') {
        return Err(refuse("its path is absolute"));
    }
    let rel = enclosed.ok_or_else(|| refuse("its path leaves the unpack directory"))?;
    if !rel
        .components()
        .all(|c| matches!(c, Component::Normal(_) | Component::CurDir))
        || rel.as_os_str().is_empty()
    {
        return Err(refuse("its path leaves the unpack directory"));
    }
    Ok(rel)
}

/// Options that create a new file (never open an existing one), 0600, or 0700 when
/// `exec` (an entry stored executable: some FMUs ship helper programs).
fn new_private_file(exec: bool) -> OpenOptions {
    let mut o = OpenOptions::new();
    o.write(true).create_new(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.mode(if exec { 0o700 } else { 0o600 });
    }
    #[cfg(not(unix))]
    let _ = exec;
    o
}

/// Creates `dir` and its parents, each 0700.
fn make_dir(dir: &Path) -> Result<(), FmuError> {
    let mut b = fs::DirBuilder::new();
    b.recursive(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::DirBuilderExt;
        b.mode(0o700);
    }
    b.create(dir).map_err(|source| FmuError::Io {
        path: dir.to_path_buf(),
        source,
    })
}

/// Copies `from` to `to` (created 0600), hashing the bytes as they pass; refuses a file
/// over `cap` bytes, both by its size and by the bytes actually read.
fn copy_hashed(from: &Path, to: &Path, cap: u64) -> Result<String, FmuError> {
    let io_err = |p: &Path| {
        let p = p.to_path_buf();
        move |source| FmuError::Io { path: p, source }
    };
    let mut src = File::open(from).map_err(io_err(from))?;
    let len = src.metadata().map_err(io_err(from))?.len();
    let too_big = |value| FmuError::CapExceeded {
        what: format!("MAX_ARCHIVE_BYTES (size of {})", from.display()),
        value,
        limit: cap,
    };
    if len > cap {
        return Err(too_big(len));
    }
    let mut dst = new_private_file(false).open(to).map_err(io_err(to))?;
    let mut hasher = blake3::Hasher::new();
    let mut buf = vec![0u8; 64 << 10];
    let mut seen = 0u64;
    loop {
        let n = match src.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(io_err(from)(e)),
        };
        seen += n as u64;
        if seen > cap {
            return Err(too_big(seen));
        }
        hasher.update(&buf[..n]);
        dst.write_all(&buf[..n]).map_err(io_err(to))?;
    }
    dst.flush().map_err(io_err(to))?;
    Ok(hasher.finalize().to_hex().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raw_names_that_leave_or_link_are_refused() {
        let ok = |n: &str| safe_relative(n, Some(PathBuf::from(n)), false);
        assert!(ok("binaries/linux64/m.so").is_ok());
        assert!(ok("./modelDescription.xml").is_ok());
        for bad in [
            "../evil",
            "a/../b",
            "a\\..\\b",
            "/etc/passwd",
            "C:/x",
            "\\x",
        ] {
            let err = ok(bad).err().map(|e| e.to_string()).unwrap_or_default();
            assert!(err.contains(bad), "{bad}: {err}");
        }
        let link = safe_relative("l", Some(PathBuf::from("l")), true);
        assert!(matches!(link, Err(FmuError::UnsafeEntry { .. })));
        let outside = safe_relative("x", None, false);
        assert!(matches!(outside, Err(FmuError::UnsafeEntry { .. })));
    }
}
