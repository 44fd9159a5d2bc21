//! Errors of the library and the exit codes the CLI maps them to.

use std::path::PathBuf;

use crate::kernel::SimTime;

/// Everything that can stop a command.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The scenario file is not valid JSON (or does not match the schema's types).
    #[error("{file}: {message} at line {line}, column {column}")]
    Parse {
        /// File being read.
        file: String,
        /// What serde_json reported.
        message: String,
        /// 1-based line of the problem.
        line: usize,
        /// 1-based column of the problem.
        column: usize,
    },
    /// A field of the scenario has a bad value; `path` names it (`forces[2].until`).
    #[error("{path}: {message}")]
    Invalid {
        /// Field path inside the scenario file.
        path: String,
        /// What is wrong, with the offending value.
        message: String,
    },
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The operating-system error.
        #[source]
        source: std::io::Error,
    },
    /// The simulation state diverged (non-finite values or a violation beyond the bound).
    #[error("{0}")]
    Diverged(Divergence),
    /// A numerical method failed without the state diverging (e.g. a singular `J_s`).
    #[error("numerical failure at t = {time}: {message}")]
    Numerical {
        /// Simulated time of the failure.
        time: SimTime,
        /// What failed.
        message: String,
    },
    /// An FMU failed: a call returned an error status, it could not be loaded at run
    /// time, or it cannot do what the run asks (fork, checkpoint); the message names
    /// the FMU, the function and the simulated time.
    #[error("{0}")]
    Fmu(String),
    /// An allocation the run needed failed (the process's memory limit, `ulimit -v`):
    /// `what` names what was being allocated and when. Not a divergence: nothing about
    /// the simulation is wrong.
    #[error("out of memory: {what}")]
    OutOfMemory {
        /// What could not be allocated, with the time and node.
        what: String,
    },
    /// `dsmcosim check`: the rerun differs from the stored run; the message names the
    /// first differing record.
    #[error("{0}")]
    Mismatch(String),
    /// The run was stopped by Ctrl-C or SIGTERM at `at` (its outputs up to there are
    /// written, marked interrupted).
    #[error(
        "interrupted at t = {} s of {} s: the outputs up to there are written and marked \
         \"status\": \"interrupted\" in summary.json; {hint}",
        at.as_secs_f64(),
        end.as_secs_f64()
    )]
    Interrupted {
        /// Simulated time reached.
        at: crate::kernel::SimTime,
        /// The run's end.
        end: crate::kernel::SimTime,
        /// How to continue instead of starting over.
        hint: String,
    },
    /// `dsmcosim check` of several scenarios: not all match. `message` counts the
    /// outcomes; `code` is the exit code their precedence gives
    /// ([`crate::check::batch::Batch::exit_code`]).
    #[error("{message}")]
    Checks {
        /// The count line (`3 scenarios: 2 match, 1 mismatch`).
        message: String,
        /// Exit code: 4, 1, 2 (or 3).
        code: u8,
    },
}

/// Where and how a run diverged.
#[derive(Debug, Clone, PartialEq)]
pub struct Divergence {
    /// Simulated time of the first step whose state failed the check.
    pub time: SimTime,
    /// Computing node (0 for a monolithic run).
    pub node: usize,
    /// The link (or, for an unlinked body, the body) whose values failed.
    pub place: Place,
    /// What was seen: `|w| = 1.3 m > bound 1 m`, or `non-finite z`.
    pub what: String,
}

impl std::fmt::Display for Divergence {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "diverged at t = {} on node {}, {}: {}",
            self.time, self.node, self.place, self.what
        )
    }
}

/// A named element of the model, for error messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Place {
    /// Link number k (1-based, file order), printed `link L<k>`.
    Link(usize),
    /// Row `row` (0-based) of joint `joint` (1-based, file order), printed
    /// `joint J<joint> row <row>`.
    JointRow {
        /// Joint number, 1-based.
        joint: usize,
        /// Row within the joint, 0-based.
        row: usize,
    },
    /// Body id, printed `body B<id>`.
    Body(u32),
    /// An output of an FMU, printed `FMU 'plant' output x`.
    FmuOutput {
        /// The FMU's name in the scenario.
        fmu: String,
        /// The output variable's name.
        variable: String,
    },
}

impl std::fmt::Display for Place {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Place::Link(k) => write!(f, "link L{k}"),
            Place::JointRow { joint, row } => write!(f, "joint J{joint} row {row}"),
            Place::Body(id) => write!(f, "body B{id}"),
            Place::FmuOutput { fmu, variable } => write!(f, "FMU '{fmu}' output {variable}"),
        }
    }
}

impl Error {
    /// Shorthand for an [`Error::Invalid`].
    pub fn invalid(path: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Invalid {
            path: path.into(),
            message: message.into(),
        }
    }

    /// Shorthand for an [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Error {
        Error::Io {
            path: path.into(),
            source,
        }
    }

    /// Process exit code: 2 for bad input, 3 for a diverged or numerically failed run or a
    /// failed FMU,
    /// 1 for I/O failures and a failed allocation, 4 for a `check` that found a difference; for a `check` of
    /// several scenarios, the code their outcomes give.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Parse { .. } | Error::Invalid { .. } => 2,
            Error::Diverged(_) | Error::Numerical { .. } | Error::Fmu(_) => 3,
            Error::Io { .. } | Error::OutOfMemory { .. } => 1,
            Error::Mismatch(_) => 4,
            Error::Checks { code, .. } => *code,
            Error::Interrupted { .. } => 130,
        }
    }
}

/// Formats a number for a message: plain for ordinary magnitudes (`-1`, `0.05`),
/// exponent form for tiny or huge ones (`1e-300`, `1e308`, never 309 digits), `NaN` and
/// `inf` as Rust spells them. Every value a user gave that an error repeats goes
/// through it.
pub fn num(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() || (1e-4..1e16).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Result with the crate's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;
