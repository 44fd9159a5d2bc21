//! What the command line prints for a person: one line at a time on stdout.
//!
//! A line that cannot be written (`dsmcosim validate s.json > /dev/full`, a closed pipe)
//! does not stop the command, whose files are written either way, but it is not
//! ignored: the first such error is kept, and [`crate::cli::main`] reports it and exits
//! 1 once the command is done (unless the command failed itself).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// The first error writing standard output, if any.
static FAILED: Mutex<Option<String>> = Mutex::new(None);

/// `--quiet`: lines for a person are not printed (errors and warnings still are, on
/// stderr).
static QUIET: AtomicBool = AtomicBool::new(false);

/// Stops [`say`] from printing (`dsmcosim -q`).
pub fn hush() {
    QUIET.store(true, Ordering::Relaxed);
}

/// Prints a line to stdout (nothing under `--quiet`); a write error is remembered for
/// [`take_failure`], never a panic.
pub fn say(line: std::fmt::Arguments) {
    use std::io::Write as _;
    if QUIET.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    // stdout is line-buffered: the newline flushes, so a full disk shows here; the
    // explicit flush covers a line without one reaching the device.
    let written = writeln!(out, "{line}").and_then(|()| out.flush());
    if let Err(e) = written {
        if let Ok(mut first) = FAILED.lock() {
            first.get_or_insert_with(|| e.to_string());
        }
    }
}

/// The first error writing standard output since the last call, if any.
pub fn take_failure() -> Option<String> {
    FAILED.lock().ok().and_then(|mut f| f.take())
}
