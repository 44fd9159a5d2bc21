//! What an FMU logs at warning and above: printed on stderr as it arrives and kept,
//! bounded, for summary.json.
//!
//! An FMU reports why it fails through its log callback ("Failed to open resource file
//! …") and then returns a bare status, so the message is the only place the reason is
//! given. Every message of status warning or worse is therefore printed (as the command
//! line prints its own warnings, `warning: …`) whether or not the scenario turned the
//! FMU's logging on, and kept in the FMU's [`FmuLog`], which all its instances share (a
//! run's and its forks'): a message repeated by a fork or at every step is kept once,
//! with a count. Bounded so an FMU that logs at every step cannot fill memory or the
//! terminal: at most [`MAX_KEPT_MESSAGES`] distinct messages of at most
//! [`MAX_MESSAGE_CHARS`] characters each; later distinct ones are only counted.

use std::io::Write;
use std::sync::{Arc, Mutex};

/// Distinct messages kept (and printed) per FMU: 64, enough for every distinct reason a
/// run stops or warns, few enough that summary.json stays small.
pub const MAX_KEPT_MESSAGES: usize = 64;

/// Characters kept of one message: 1000; a longer one is cut and ends in `…`.
pub const MAX_MESSAGE_CHARS: usize = 1000;

/// One message an FMU logged at warning or above.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct LogEntry {
    /// The instance that logged it first (as the FMU named it).
    pub instance: String,
    /// The status it was logged with (`fmi2Warning`, `fmi2Error`, `fmi3Fatal`, …).
    pub status: &'static str,
    /// The FMU's log category (`logStatusError`), as given.
    pub category: String,
    /// The text, at most [`MAX_MESSAGE_CHARS`] characters. FMI 2.0: the format string as
    /// written (its printf arguments are not filled in: see [`super::fmi2::Logger`]).
    pub message: String,
    /// How often the FMU logged this status, category and text.
    pub count: u64,
}

/// The messages of one FMU, shared by all its instances.
#[derive(Debug, Default)]
pub struct FmuLog {
    entries: Vec<LogEntry>,
    not_kept: u64,
}

impl FmuLog {
    /// The messages kept, in the order they first came.
    pub fn entries(&self) -> &[LogEntry] {
        &self.entries
    }

    /// Messages not kept because [`MAX_KEPT_MESSAGES`] distinct ones were (each
    /// occurrence counted).
    pub fn not_kept(&self) -> u64 {
        self.not_kept
    }
}

/// A shared [`FmuLog`].
pub type SharedLog = Arc<Mutex<FmuLog>>;

/// Keeps a message of `fmu` logged by `instance` with a status of warning or worse, and
/// prints it on stderr the first time it comes (unless `printed`: the FMU's logging is
/// on and the logger has printed it already). Never panics (a poisoned lock is used as
/// it is, a write error ignored).
pub(crate) fn keep(
    log: &SharedLog,
    fmu: &str,
    entry: (String, &'static str, String, String),
    printed: bool,
) {
    let (instance, status, category, message) = entry;
    let message = bounded(message);
    let mut log = log.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    if let Some(e) = log
        .entries
        .iter_mut()
        .find(|e| e.status == status && e.category == category && e.message == message)
    {
        e.count = e.count.saturating_add(1);
        return;
    }
    if log.entries.len() >= MAX_KEPT_MESSAGES {
        if log.not_kept == 0 {
            let _ = writeln!(
                std::io::stderr(),
                "warning: FMU '{fmu}' logged more than {MAX_KEPT_MESSAGES} distinct messages; \
                 further ones are counted in summary.json, not printed or kept"
            );
        }
        log.not_kept = log.not_kept.saturating_add(1);
        return;
    }
    if !printed {
        let _ = writeln!(
            std::io::stderr(),
            "warning: FMU '{fmu}' logged {status} ({category}): {message}"
        );
    }
    log.entries.push(LogEntry {
        instance,
        status,
        category,
        message,
        count: 1,
    });
}

/// `message` cut to [`MAX_MESSAGE_CHARS`] characters (the last one `…`).
fn bounded(message: String) -> String {
    match message.char_indices().nth(MAX_MESSAGE_CHARS - 1) {
        Some((at, _)) if message[at..].chars().nth(1).is_some() => {
            let mut cut = message[..at].to_string();
            cut.push('…');
            cut
        }
        _ => message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_message_is_cut_to_its_bound_and_a_short_one_kept_whole() {
        let long = "é".repeat(MAX_MESSAGE_CHARS + 5);
        let cut = bounded(long);
        assert_eq!(cut.chars().count(), MAX_MESSAGE_CHARS);
        assert!(cut.ends_with('…'));
        let exact = "a".repeat(MAX_MESSAGE_CHARS);
        assert_eq!(bounded(exact.clone()), exact);
    }

    #[test]
    fn repeats_are_counted_and_distinct_messages_beyond_the_bound_only_counted() {
        let log = SharedLog::default();
        let entry = |m: String| ("i".to_string(), "fmi2Warning", "c".to_string(), m);
        for _ in 0..3 {
            keep(&log, "f", entry("same".into()), true);
        }
        for k in 0..MAX_KEPT_MESSAGES + 10 {
            keep(&log, "f", entry(format!("m{k}")), true);
        }
        let log = log.lock().unwrap();
        assert_eq!(log.entries()[0].count, 3);
        assert_eq!(log.entries().len(), MAX_KEPT_MESSAGES);
        assert_eq!(log.not_kept(), 11);
    }
}
