//! What the command line prints for a person: one line at a time on stdout.

/// Prints a line to stdout, ignoring a closed pipe (`dsmcosim run … | head` must not
/// panic): the work is done and its files are written either way.
pub fn say(line: std::fmt::Arguments) {
    use std::io::Write as _;
    let _ = writeln!(std::io::stdout(), "{line}");
}
