//! Atomic file output: every file a run writes appears whole or not at all.
//!
//! Bytes go to a temporary file beside the target (`.<name>.tmp.<pid>.<random>`, made
//! by `tempfile` in the same directory so the final `rename` never crosses a file
//! system), are flushed and `sync_all`ed, and only then renamed over the target
//! ([`tempfile::NamedTempFile::persist`]). A crash or an error leaves at most a hidden
//! temporary file, never a half-written `summary.json` or `trace.csv`; on an error we
//! return, the temporary file is removed too (`tempfile` removes it on drop).
//!
//! I/O errors name the target path (not the temporary one), since that is the file the
//! user asked for.
//!
//! A rename replaces whatever has the target's name, so the target is checked first
//! ([`check_replaceable`]): absent, or a regular file. A symlink (which the rename would
//! replace, not write through), a FIFO (whose reader would wait forever), a device
//! node or a directory is refused naming the path, when the file is opened and again
//! just before the rename. Which regular files a command may replace is the callers'
//! rule ([`run_dir`] for a run's directory, [`check_report_target`] for a report
//! file); docs/reference.md ("What dsmcosim deletes or replaces") states it for users.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use tempfile::NamedTempFile;

use crate::error::{Error, Result};

pub mod run_dir;

/// Refuses (exit 2, naming the path) a `path` that exists and is not a regular file: a
/// symlink (not followed), a FIFO, a socket, a device node, a directory. `what` says
/// what the path was to be (`output`, `lock file`). An absent path is fine.
pub fn check_replaceable(path: &Path, what: &str) -> Result<()> {
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(Error::io(path, e)),
    };
    let t = meta.file_type();
    if t.is_file() {
        return Ok(());
    }
    let kind = if t.is_symlink() {
        "a symlink"
    } else if t.is_dir() {
        "a directory"
    } else {
        special_kind(&t)
    };
    Err(Error::invalid(
        path.display().to_string(),
        format!(
            "is {kind}, not a regular file: dsmcosim writes its {what} only as a new or \
             regular file (never through a symlink or onto a FIFO or device)"
        ),
    ))
}

/// The kind of a file that is neither regular, a directory nor a symlink.
fn special_kind(t: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device node";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    let _ = t;
    "a special file"
}

/// Checks a report file a command writes on request (`validate --json`, `check --json`,
/// `check --junit`) before anything runs: `flag` names the option. Refused, exit 2:
/// a path that is not a regular file ([`check_replaceable`]); one of the command's
/// `inputs` (the same file, however named); a file a run wrote in a directory that
/// holds a run ([`run_dir::is_run_file`]: a stored `summary.json`, `trace.csv`, …).
pub fn check_report_target(path: &Path, flag: &str, inputs: &[&Path]) -> Result<()> {
    let named = |m: String| Error::invalid(flag, format!("{}: {m}", path.display()));
    check_replaceable(path, "report").map_err(|e| match e {
        Error::Invalid { message, .. } => named(message),
        e => e,
    })?;
    if !path.exists() {
        return Ok(());
    }
    let same = |a: &Path, b: &Path| match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if let Some(input) = inputs.iter().find(|i| same(path, i)) {
        return Err(named(format!(
            "is an input of this command ({}); write the report elsewhere",
            input.display()
        )));
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    if run_dir::holds_run(dir) && run_dir::is_run_file(&name) {
        return Err(named(format!(
            "is the {name} of the run stored in {}; write the report elsewhere",
            dir.display()
        )));
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically: the file either keeps its old content (or stays
/// absent) or has exactly `bytes`, never a mix.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut file = AtomicFile::create(path)?;
    file.write_all(bytes).map_err(|e| Error::io(path, e))?;
    file.commit()
}

/// CSV text (RFC 4180, `\n` line ends) of `rows` of already formatted fields, written
/// with the `csv` crate: a field is quoted only if it holds a comma, a quote or a line
/// break (`QuoteStyle::Necessary`). Numbers are formatted by the caller (Rust's
/// shortest round-trip form, `format!("{x}")`), because the crate's own float
/// formatting differs (`1.0` for `1`, `1e21` for `1000000000000000000000`) and stored
/// files are compared byte for byte.
pub fn csv_text<R, F>(rows: impl IntoIterator<Item = R>) -> String
where
    R: IntoIterator<Item = F>,
    F: AsRef<[u8]>,
{
    let mut w = csv::WriterBuilder::new()
        .quote_style(csv::QuoteStyle::Necessary)
        .flexible(true)
        .from_writer(Vec::new());
    for row in rows {
        // Writing into a Vec cannot fail.
        let _ = w.write_record(row);
    }
    let bytes = w.into_inner().unwrap_or_default();
    // Every field was a str, so the bytes are UTF-8.
    String::from_utf8(bytes).unwrap_or_default()
}

/// One CSV field as [`csv_text`] writes it (quoted only where needed), for a header
/// written by hand.
pub fn csv_field(text: &str) -> String {
    let mut line = csv_text([[text]]);
    if line.ends_with('\n') {
        line.pop();
    }
    line
}

/// Creates `path` and its missing parents, like [`std::fs::create_dir_all`], with the
/// path in the error.
pub fn create_dir_all(path: &Path) -> Result<()> {
    std::fs::create_dir_all(path).map_err(|e| Error::io(path, e))
}

/// [`create_dir_all`] for a directory the user named (`--out`): a file where the
/// directory should be is a mistaken argument (`--out README.md`), not an I/O failure,
/// so it is refused saying so (exit 2) and left alone.
pub fn create_out_dir(path: &Path) -> Result<()> {
    if let Some(file) = path
        .ancestors()
        .find(|p| !p.as_os_str().is_empty() && p.exists() && !p.is_dir())
    {
        return Err(Error::invalid(
            path.display().to_string(),
            format!(
                "{} is a file, not a directory: outputs go into a directory (created if \
                 missing), e.g. `-o runs/NAME`",
                file.display()
            ),
        ));
    }
    create_dir_all(path)
}

/// Refuses a directory a study command would write into when it holds, under a name
/// the command writes, a file the command did not write there: the rule `run` keeps
/// (only what the tool wrote, only in a directory it claimed). The directory is the
/// command's when it is missing or holds the command's `manifest` (`sweep.json`,
/// `coupling.csv`, …, written first or together with the rest), and then its outputs
/// are replaced; otherwise the first existing entry named as `writes` says (in name
/// order) is the user's, refused with exit 2 before anything is computed.
pub fn refuse_foreign_outputs(
    dir: &Path,
    manifest: &str,
    writes: impl Fn(&str) -> bool,
) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(()); // missing (created later), or not a directory (refused later)
    };
    if dir.join(manifest).exists() {
        return Ok(());
    }
    let mut names: Vec<String> = entries
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| writes(n))
        .collect();
    names.sort();
    match names.first() {
        None => Ok(()),
        Some(name) => Err(Error::invalid(
            "--out",
            format!(
                "{} holds {name}, which dsmcosim did not write there (no {manifest} beside \
                 it) and would replace: choose another directory, or move the file",
                dir.display()
            ),
        )),
    }
}

/// A buffered file that appears at its path only when [`AtomicFile::commit`] succeeds.
///
/// For large streamed outputs such as `trace.csv`. Dropping it without a commit (an
/// error path, a panic unwinding) removes the temporary file and leaves the target
/// untouched.
#[derive(Debug)]
pub struct AtomicFile {
    /// The file the caller wants.
    path: PathBuf,
    /// The temporary file the bytes go to until the commit; `None` only while
    /// committing or dropping. Dropped unpersisted, `tempfile` removes it.
    writer: Option<BufWriter<NamedTempFile>>,
}

impl AtomicFile {
    /// Opens a temporary file beside `path` (the directory must exist):
    /// `.<name>.tmp.<pid>.<random>`, which [`run_dir`] recognizes as a leftover.
    pub fn create(path: &Path) -> Result<AtomicFile> {
        let name = path.file_name().ok_or_else(|| {
            Error::io(
                path,
                io::Error::new(io::ErrorKind::InvalidInput, "not a file name"),
            )
        })?;
        let mut prefix = std::ffi::OsString::from(".");
        prefix.push(name);
        prefix.push(format!(".tmp.{}.", std::process::id()));
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        check_replaceable(path, "output")?;
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).rand_bytes(8);
        // The mode a plain `File::create` gives (0o666 less the umask), not tempfile's
        // owner-only default: outputs are meant to be read by others as before.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let file = builder.tempfile_in(dir).map_err(|e| Error::io(path, e))?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            writer: Some(BufWriter::with_capacity(1 << 16, file)),
        })
    }

    /// The path the file will have once committed.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes, syncs and renames the temporary file over the target. On an error the
    /// temporary file is removed and the target keeps its old content.
    pub fn commit(mut self) -> Result<()> {
        let path = self.path.clone();
        let writer = self
            .writer
            .take()
            .ok_or_else(|| Error::io(&path, io::Error::other("atomic file already committed")))?;
        // `into_inner` flushes the buffer; on failure the temporary file drops (removed).
        let file = writer
            .into_inner()
            .map_err(|e| Error::io(&path, e.into_error()))?;
        file.as_file().sync_all().map_err(|e| Error::io(&path, e))?;
        // Again at the rename: the target may have changed while the file was written.
        check_replaceable(&path, "output")?;
        // On failure the error carries the temporary file, which drops (removed).
        file.persist(&path).map_err(|e| Error::io(&path, e.error))?;
        sync_parent_dir(&path);
        Ok(())
    }
}

/// Makes the rename durable by syncing the directory entry (Unix only).
///
/// Best effort: the rename has already happened, so the file is complete whatever this
/// returns, and some file systems refuse to sync a directory; failing the run for that
/// would be worse than the small durability window it closes.
fn sync_parent_dir(path: &Path) {
    #[cfg(unix)]
    {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
    #[cfg(not(unix))]
    let _ = path;
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match &mut self.writer {
            Some(w) => w.write(buf),
            None => Err(io::Error::other("atomic file already committed")),
        }
    }

    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        match &mut self.writer {
            Some(w) => w.write_all(buf),
            None => Err(io::Error::other("atomic file already committed")),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match &mut self.writer {
            Some(w) => w.flush(),
            None => Ok(()),
        }
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(w) = self.writer.take() {
            // Discard the buffer without writing it: the file is going away (dropping
            // the `NamedTempFile` removes it).
            let (file, _unwritten) = w.into_parts();
            drop(file);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh empty directory under the system temp dir, unique per test and process.
    fn scratch_dir(test: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("dsmcosim-output-{}-{}", test, std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn csv_text_quotes_only_where_needed() {
        let rows = [
            vec!["t", "label", "x"],
            vec!["0.00001", "one, two", ""],
            vec!["1e300", "say \"hi\"", "1"],
        ];
        assert_eq!(
            csv_text(rows),
            "t,label,x\n0.00001,\"one, two\",\n1e300,\"say \"\"hi\"\"\",1\n"
        );
    }

    #[test]
    fn write_then_read_back() {
        let dir = scratch_dir("roundtrip");
        let path = dir.join("summary.json");
        write_atomic(&path, b"{\"steps\": 3}\n").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"{\"steps\": 3}\n");
        assert_eq!(entries(&dir), vec!["summary.json".to_string()]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn streamed_file_commits() {
        let dir = scratch_dir("stream");
        let path = dir.join("trace.csv");
        let mut f = AtomicFile::create(&path).unwrap();
        assert_eq!(f.path(), path.as_path());
        writeln!(f, "t,w_L1").unwrap();
        for k in 0..10_000 {
            writeln!(f, "{k},0.0").unwrap();
        }
        assert!(!path.exists(), "target must not appear before the commit");
        f.commit().unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 10_001);
        assert_eq!(entries(&dir), vec!["trace.csv".to_string()]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn dropped_file_leaves_nothing() {
        let dir = scratch_dir("drop");
        let path = dir.join("trace.csv");
        {
            let mut f = AtomicFile::create(&path).unwrap();
            f.write_all(&[b'x'; 100_000]).unwrap();
            assert_eq!(
                entries(&dir).len(),
                1,
                "the temporary file exists while open"
            );
        }
        assert!(!path.exists());
        assert!(entries(&dir).is_empty(), "left: {:?}", entries(&dir));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn dropped_file_keeps_old_content() {
        let dir = scratch_dir("drop-old");
        let path = dir.join("a.txt");
        write_atomic(&path, b"old").unwrap();
        {
            let mut f = AtomicFile::create(&path).unwrap();
            f.write_all(b"new new new").unwrap();
        }
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(entries(&dir), vec!["a.txt".to_string()]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn overwrite_replaces_completely() {
        let dir = scratch_dir("overwrite");
        let path = dir.join("a.txt");
        write_atomic(&path, &[b'a'; 4096]).unwrap();
        write_atomic(&path, b"short").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"short");
        assert_eq!(entries(&dir), vec!["a.txt".to_string()]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_directory_names_the_path() {
        let dir = scratch_dir("missing");
        let path = dir.join("no-such-dir").join("summary.json");
        match write_atomic(&path, b"x") {
            Err(Error::Io { path: p, source }) => {
                assert_eq!(p, path);
                assert_eq!(source.kind(), io::ErrorKind::NotFound);
            }
            other => panic!("expected an Io error, got {other:?}"),
        }
        let msg = write_atomic(&path, b"x").unwrap_err().to_string();
        assert!(msg.contains("no-such-dir"), "message: {msg}");
        assert!(entries(&dir).is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn path_without_file_name_is_an_error() {
        assert!(matches!(
            write_atomic(Path::new("/"), b"x"),
            Err(Error::Io { .. })
        ));
    }

    #[test]
    fn create_dir_all_nests_and_names_the_path() {
        let dir = scratch_dir("mkdir");
        let nested = dir.join("a").join("b");
        create_dir_all(&nested).unwrap();
        assert!(nested.is_dir());
        // A regular file in the way.
        let file = dir.join("f");
        write_atomic(&file, b"x").unwrap();
        let bad = file.join("sub");
        match create_dir_all(&bad) {
            Err(Error::Io { path, .. }) => assert_eq!(path, bad),
            other => panic!("expected an Io error, got {other:?}"),
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
