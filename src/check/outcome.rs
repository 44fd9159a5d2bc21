//! The outcome of checking one scenario in a batch ([`super::batch`]): its status in one
//! word, the exit code it asks for, and the texts the command and the reports print.

use std::path::PathBuf;

use super::{Report, Verdict};
use crate::error::{Error, Result};
use crate::trace::compare::Difference;

/// A scenario's verdict in one word.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// Matches the stored run (exactly, or within the tolerance).
    Match,
    /// Differs from the stored run.
    Mismatch,
    /// The stored run is missing or unreadable (an I/O error reading it).
    Missing,
    /// Anything else that kept the scenario from being compared: a bad scenario file, a
    /// `summary.json` that is not a run summary, a rerun that could not be written.
    Error,
}

impl Status {
    /// `match`, `mismatch`, `missing` or `error`.
    pub fn name(self) -> &'static str {
        match self {
            Status::Match => "match",
            Status::Mismatch => "mismatch",
            Status::Missing => "missing",
            Status::Error => "error",
        }
    }
}

/// The check of one scenario.
#[derive(Debug)]
pub struct Outcome {
    /// Scenario name (its `name` key; the file stem when the file could not be read).
    pub name: String,
    /// The scenario file as given.
    pub scenario: PathBuf,
    /// The stored run it was compared with (or would have been).
    pub stored: PathBuf,
    /// The directory of the rerun (`None` when the scenario never got that far).
    pub new: Option<PathBuf>,
    /// Wall-clock seconds of reading the stored run, the rerun and the comparison [s].
    pub wall_seconds: f64,
    /// The comparison, or what stopped it.
    pub result: Result<Report>,
    /// Whether an error arose reading the stored run (so it is [`Status::Missing`] when
    /// it is an I/O error).
    pub(crate) stored_failed: bool,
}

impl Outcome {
    /// The verdict in one word.
    pub fn status(&self) -> Status {
        match &self.result {
            Ok(r) if r.verdict() == Verdict::Mismatch => Status::Mismatch,
            Ok(_) => Status::Match,
            Err(Error::Io { .. }) if self.stored_failed => Status::Missing,
            Err(_) => Status::Error,
        }
    }

    /// The exit code this outcome alone asks for (0 for a match).
    pub fn exit_code(&self) -> u8 {
        match &self.result {
            Ok(r) if r.verdict() == Verdict::Mismatch => 4,
            Ok(_) => 0,
            Err(e) => e.exit_code(),
        }
    }

    /// The first differing record of a mismatch, if the CSV files differ.
    pub fn first_difference(&self) -> Option<&Difference> {
        match &self.result {
            Ok(r) if r.verdict() == Verdict::Mismatch => r.comparison.first_difference(),
            _ => None,
        }
    }

    /// One line saying why a mismatch, a missing run or an error failed (`None` for a
    /// match): the first differing record when there is one.
    pub fn headline(&self) -> Option<String> {
        match &self.result {
            Ok(r) if r.verdict() == Verdict::Mismatch => Some(match self.first_difference() {
                Some(d) => d.to_string(),
                None if !r.digests_equal() => format!(
                    "digest differs (stored {}, new {}); every CSV value is equal",
                    r.stored.digest, r.new.digest
                ),
                None => "the runs differ".to_string(),
            }),
            Ok(_) => None,
            Err(e) => Some(e.to_string()),
        }
    }

    /// What the command prints for this scenario: the line of a match, the lines
    /// explaining a mismatch, or the error.
    pub fn text(&self) -> String {
        match (&self.result, self.status()) {
            (Ok(r), _) => r.message(),
            (Err(e), Status::Missing) => format!(
                "{}: no stored run: {e} (store one with `dsmcosim run {} -o {}`)",
                self.name,
                self.scenario.display(),
                self.stored.display()
            ),
            (Err(e), _) => format!("{} ({}): {e}", self.name, self.scenario.display()),
        }
    }
}

/// Counts of outcomes by status.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Totals {
    /// Scenarios checked.
    pub scenarios: usize,
    /// Matching.
    pub matched: usize,
    /// Differing.
    pub mismatched: usize,
    /// Stored run missing or unreadable.
    pub missing: usize,
    /// Not compared for another reason.
    pub errors: usize,
}
