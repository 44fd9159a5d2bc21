//! Reading the files a user gives: scenario and sweep files (and a sweep's base),
//! with a size cap.
//!
//! Each is read whole before it is parsed, so an unbounded input (`/dev/zero`, a pipe
//! that never closes) would be read until memory ran out. [`read`] stops after
//! [`MAX_INPUT_BYTES`] and refuses the file naming it (bad input, exit 2); a file that
//! cannot be read at all is an I/O error (exit 1) as before.

pub mod pointer;

use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result};

/// Most bytes of a scenario or sweep file [bytes]: 64 MiB. The shipped files are a few
/// kB; a scene of a million bodies fits as a `model.grid` of a few lines (an explicit
/// body list of that size would take about 200 MB and is refused).
pub const MAX_INPUT_BYTES: u64 = 64 << 20;

/// Default bound on a run's estimated peak memory [bytes]: 16 GB (`--max-memory` lifts
/// it; `run::budget` lowers it where the process may have less). A checkpoint, a run's
/// state, is read up to it.
pub const DEFAULT_MAX_MEMORY_BYTES: u64 = 16_000_000_000;

/// The bytes of the file at `path`, at most `cap` of them: a longer file (or an endless
/// stream) is refused after `cap + 1` bytes, naming the path and the cap.
pub fn read_capped(path: &Path, cap: u64) -> Result<Vec<u8>> {
    if path.is_dir() {
        let hint = if path.join("scenario.json").is_file() {
            format!(
                " (a run's folder keeps its scenario as {})",
                path.join("scenario.json").display()
            )
        } else {
            String::new()
        };
        return Err(Error::invalid(
            path.display().to_string(),
            format!("is a directory, not a file{hint}"),
        ));
    }
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut bytes = Vec::new();
    file.take(cap.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > cap {
        return Err(Error::invalid(
            path.display().to_string(),
            format!(
                "holds more than {cap} bytes ({} MiB), the most an input file may hold \
                 (is it a stream such as /dev/zero?)",
                cap >> 20
            ),
        ));
    }
    Ok(bytes)
}

/// The bytes of the scenario or sweep file at `path`, at most [`MAX_INPUT_BYTES`].
pub fn read(path: &Path) -> Result<Vec<u8>> {
    read_capped(path, MAX_INPUT_BYTES)
}

/// The text of the file at `path`, at most [`MAX_INPUT_BYTES`]; text that is not UTF-8
/// is an I/O error of kind `InvalidData`, as [`std::fs::read_to_string`] gives.
pub fn read_text(path: &Path) -> Result<String> {
    String::from_utf8(read(path)?).map_err(|e| {
        Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_endless_stream_is_refused_after_the_cap() {
        let e = read_capped(Path::new("/dev/zero"), 1000).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let m = e.to_string();
        assert!(
            m.starts_with("/dev/zero: holds more than 1000 bytes"),
            "{m}"
        );
        let e = read_capped(Path::new("/no/such/file"), 1000).unwrap_err();
        assert_eq!(e.exit_code(), 1);
    }

    #[test]
    fn a_file_up_to_the_cap_is_read_whole() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.json");
        std::fs::write(&p, [b'x'; 1000]).unwrap();
        assert_eq!(read_capped(&p, 1000).unwrap().len(), 1000);
        assert!(read_capped(&p, 999).is_err());
        std::fs::write(&p, [0xff, 0xfe]).unwrap();
        assert_eq!(read_text(&p).unwrap_err().exit_code(), 1);
    }
}
