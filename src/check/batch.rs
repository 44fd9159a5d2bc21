//! Many scenarios checked at once: `dsmcosim check scenarios/*.json --against results/`.
//!
//! **Which stored run.** With one scenario and a `--against DIR` that holds a
//! `summary.json`, `DIR` is the stored run (the one-scenario form). Otherwise each
//! scenario's stored run is `DIR/<name>/`, where `<name>` is the scenario file's `name`
//! key; when `DIR/<name>/summary.json` does not exist but `DIR/<file stem>/summary.json`
//! does, that one is taken (a run stored under the file's name). Every shipped scenario's
//! name is its file stem, and `results/<name>/` its stored run.
//!
//! **Where the reruns go.** Beside the stored run, into `<stored>.new/`, or with
//! `--work W` into `W/<name>/`. Two scenarios that would rerun into the same directory
//! are refused (bad input for the later ones); the first is still checked.
//!
//! **In parallel, reported in order.** The scenarios are read and mapped first, in
//! argument order; the reruns then run on rayon's pool, and the outcomes come back in
//! argument order whatever order they finish in. A missing stored run or a bad scenario
//! is that scenario's outcome, not the end of the check: every other scenario is still
//! rerun and compared.
//!
//! **Exit code** ([`Batch::exit_code`]): 4 if any scenario mismatches; else 1 if any
//! stored run is missing or unreadable, or an I/O failure stopped a rerun; else 2 if any
//! scenario is bad (unparsable or invalid file, a `summary.json` that is not a run
//! summary, a name that cannot name a directory, a rerun directory two scenarios
//! share); else 0. A regression outranks everything else, since that is what the check
//! is for; an incomplete check outranks bad input, which a user fixes last.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;

pub use super::outcome::{Outcome, Status, Totals};
use super::{check_into, parse_tolerance, sibling};
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::scenario::Scenario;
use crate::trace::compare::Tolerance;

/// What a batch check is given besides the scenario files.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// `--against`: a stored run (one-scenario form) or the directory of stored runs.
    pub against: PathBuf,
    /// `--tolerance`: `None` for an exact comparison.
    pub tolerance: Option<f64>,
    /// `--work`: where the reruns go (`WORK/<name>/`) instead of `<stored>.new/`.
    pub work: Option<PathBuf>,
    /// `--set POINTER=VALUE` overrides applied to every scenario
    /// ([`crate::scenario::overrides`]).
    pub sets: Vec<String>,
}

/// How `--against` was read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// One scenario; `--against` is its stored run.
    Single,
    /// Each scenario's stored run is `--against/<name>/`.
    ByName,
}

impl Layout {
    /// `single` or `by_name`, as in the JSON verdict.
    pub fn name(self) -> &'static str {
        match self {
            Layout::Single => "single",
            Layout::ByName => "by_name",
        }
    }
}

/// The outcomes of a batch check, in argument order.
#[derive(Debug)]
pub struct Batch {
    /// How `--against` was read.
    pub layout: Layout,
    /// `--against` as given.
    pub against: PathBuf,
    /// How values were compared.
    pub tolerance: Tolerance,
    /// One per scenario, in argument order.
    pub outcomes: Vec<Outcome>,
    /// Wall-clock seconds of the whole check, from reading the first scenario to the
    /// last outcome [s]: less than the outcomes' sum when they ran in parallel.
    pub elapsed_seconds: f64,
}

/// Exit codes in order of precedence (see the module docs).
const PRECEDENCE: [u8; 4] = [4, 1, 2, 3];

impl Batch {
    /// Counts by status.
    pub fn totals(&self) -> Totals {
        let mut t = Totals {
            scenarios: self.outcomes.len(),
            ..Totals::default()
        };
        for o in &self.outcomes {
            match o.status() {
                Status::Match => t.matched += 1,
                Status::Mismatch => t.mismatched += 1,
                Status::Missing => t.missing += 1,
                Status::Error => t.errors += 1,
            }
        }
        t
    }

    /// The process exit code: the outcome codes' highest by precedence, 4 > 1 > 2
    /// (> 3, which no outcome asks for today), 0 when every scenario matches.
    pub fn exit_code(&self) -> u8 {
        let codes: Vec<u8> = self.outcomes.iter().map(Outcome::exit_code).collect();
        PRECEDENCE
            .iter()
            .copied()
            .find(|c| codes.contains(c))
            .or_else(|| codes.iter().copied().find(|&c| c != 0))
            .unwrap_or(0)
    }

    /// Wall-clock seconds the check took, as a CI job's clock sees it [s]; at least the
    /// longest scenario's and, with scenarios in parallel, less than their sum.
    pub fn wall_seconds(&self) -> f64 {
        self.elapsed_seconds
    }

    /// The scenarios' own wall seconds summed (CPU-ish work; more than
    /// [`Batch::wall_seconds`] when they ran in parallel) [s].
    pub fn summed_seconds(&self) -> f64 {
        self.outcomes.iter().map(|o| o.wall_seconds).sum()
    }

    /// One line counting the outcomes: `3 scenarios: 2 match, 1 mismatch`.
    pub fn summary_line(&self) -> String {
        let t = self.totals();
        let mut parts = vec![format!("{} match", t.matched)];
        for (n, what) in [
            (t.mismatched, "mismatch"),
            (t.missing, "missing"),
            (t.errors, "error"),
        ] {
            if n > 0 {
                parts.push(format!("{n} {what}"));
            }
        }
        let s = if t.scenarios == 1 { "" } else { "s" };
        format!("{} scenario{s}: {}", t.scenarios, parts.join(", "))
    }

    /// Ends the command: the lines to print on stdout, and `Ok` or the error that sets
    /// the exit code.
    ///
    /// With one scenario this is the one-scenario form's behaviour: the match line, or
    /// the scenario's own error ([`Error::Mismatch`] with the explanation, or what
    /// stopped the check). With several, every scenario's text in argument order and
    /// the count line, then [`Error::Checks`] unless all match.
    pub fn conclude(mut self) -> (Vec<String>, Result<()>) {
        if self.outcomes.len() == 1 {
            let o = self.outcomes.remove(0);
            let status = o.status();
            // A missing stored run: the error, then the command that stores one.
            let hint = (status == Status::Missing).then(|| {
                format!(
                    "store one with `dsmcosim run {} -o {}`",
                    o.scenario.display(),
                    o.stored.display()
                )
            });
            return match (o.result, status) {
                (Ok(r), Status::Mismatch) => (vec![], Err(Error::Mismatch(r.message()))),
                (Ok(r), _) => (vec![r.message()], Ok(())),
                (Err(e), _) => (hint.into_iter().collect(), Err(e)),
            };
        }
        let mut lines: Vec<String> = self.outcomes.iter().map(Outcome::text).collect();
        let summary = self.summary_line();
        let code = self.exit_code();
        if code == 0 {
            lines.push(summary);
            return (lines, Ok(()));
        }
        (
            lines,
            Err(Error::Checks {
                message: summary,
                code,
            }),
        )
    }
}

/// A scenario read and mapped to its stored run, ready to rerun.
struct Job {
    name: String,
    scenario_file: PathBuf,
    stored: PathBuf,
    new: PathBuf,
    scenario: Scenario,
}

/// A scenario file's stem, for naming a scenario whose `name` could not be read.
fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

/// Whether `name` is one plain path component (no separator, not `.` or `..`).
fn is_plain_component(name: &str) -> bool {
    let mut parts = Path::new(name).components();
    matches!(
        (parts.next(), parts.next()),
        (Some(std::path::Component::Normal(c)), None) if c == std::ffi::OsStr::new(name)
    )
}

/// The stored run of a scenario named `name` read from `file`, in the by-name layout.
fn stored_dir(against: &Path, name: &str, file: &Path) -> PathBuf {
    let by_name = against.join(name);
    let by_stem = against.join(stem(file));
    if !by_name.join("summary.json").exists() && by_stem.join("summary.json").exists() {
        by_stem
    } else {
        by_name
    }
}

/// Checks every scenario file against its stored run (see the module docs). Errors
/// only for a bad `--tolerance` (before anything runs); everything about one scenario
/// is in its [`Outcome`].
pub fn run(scenarios: &[PathBuf], options: &Options) -> Result<Batch> {
    let started = Instant::now();
    let tolerance = parse_tolerance(options.tolerance)?;
    let against = &options.against;
    let layout = if scenarios.len() == 1 && against.join("summary.json").exists() {
        Layout::Single
    } else {
        Layout::ByName
    };

    // Read and map in argument order; a scenario that cannot be is its outcome.
    let mut planned: Vec<std::result::Result<Job, Outcome>> = Vec::new();
    let mut rerun_dirs: BTreeMap<PathBuf, String> = BTreeMap::new();
    for file in scenarios {
        let failed = |name: String, stored: PathBuf, new: Option<PathBuf>, e: Error| Outcome {
            name,
            scenario: file.clone(),
            stored,
            new,
            wall_seconds: 0.0,
            result: Err(e),
            stored_failed: false,
        };
        let guess = match layout {
            Layout::Single => against.clone(),
            Layout::ByName => against.join(stem(file)),
        };
        let scenario = match crate::scenario::load_with(file, &options.sets) {
            Ok((s, _)) => s,
            Err(e) => {
                planned.push(Err(failed(stem(file), guess, None, e)));
                continue;
            }
        };
        let name = scenario.name.clone();
        if !is_plain_component(&name) {
            let e = Error::invalid(
                "name",
                format!("`{name}` cannot name a run directory (one path component, not . or ..)"),
            );
            planned.push(Err(failed(name, guess, None, e)));
            continue;
        }
        let stored = match layout {
            Layout::Single => against.clone(),
            Layout::ByName => stored_dir(against, &name, file),
        };
        let new = match &options.work {
            Some(work) => work.join(&name),
            None => match sibling(&stored) {
                Ok(dir) => dir,
                Err(e) => {
                    planned.push(Err(failed(name, stored, None, e)));
                    continue;
                }
            },
        };
        if let Err(e) = super::apart(&stored, &new) {
            planned.push(Err(failed(name, stored, None, e)));
            continue;
        }
        if let Some(first) = rerun_dirs.get(&new) {
            let e = Error::invalid(
                "name",
                format!(
                    "reruns into {}, as the scenario `{first}` given before it does; give \
                     each scenario once (scenario names must differ)",
                    new.display()
                ),
            );
            planned.push(Err(failed(name, stored, None, e)));
            continue;
        }
        rerun_dirs.insert(new.clone(), name.clone());
        planned.push(Ok(Job {
            name,
            scenario_file: file.clone(),
            stored,
            new,
            scenario,
        }));
    }

    // One bar over the scenarios (on a terminal, after a while), none per rerun,
    // as a sweep does; a single scenario keeps its run's own bar.
    let several = planned.len() > 1;
    let progress = Mutex::new(Progress::with_unit(planned.len() as u64, "scenarios"));
    let finished = AtomicU64::new(0);
    let outcomes = planned
        .into_par_iter()
        .map(|p| {
            let outcome = match p {
                Ok(job) if several => crate::progress::quietly(|| check_job(job, tolerance)),
                Ok(job) => check_job(job, tolerance),
                Err(outcome) => outcome,
            };
            let n = finished.fetch_add(1, Ordering::Relaxed) + 1;
            if let Ok(mut bar) = progress.lock() {
                bar.tick(n);
            }
            outcome
        })
        .collect();
    if let Ok(bar) = progress.lock() {
        bar.finish();
    }
    Ok(Batch {
        layout,
        against: against.clone(),
        tolerance,
        outcomes,
        elapsed_seconds: started.elapsed().as_secs_f64(),
    })
}

/// Reruns and compares one mapped scenario.
fn check_job(job: Job, tolerance: Tolerance) -> Outcome {
    let started = Instant::now();
    let stored_failed = super::read_stored(&job.stored).err();
    let (result, stored_failed) = match stored_failed {
        Some(e) => (Err(e), true),
        None => (
            check_into(&job.scenario, &job.stored, &job.new, tolerance),
            false,
        ),
    };
    Outcome {
        name: job.name,
        scenario: job.scenario_file,
        stored: job.stored,
        new: (!stored_failed).then_some(job.new),
        wall_seconds: started.elapsed().as_secs_f64(),
        result,
        stored_failed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::Report;

    fn outcome(result: Result<Report>, stored_failed: bool) -> Outcome {
        Outcome {
            name: "s".into(),
            scenario: "s.json".into(),
            stored: "r/s".into(),
            new: None,
            wall_seconds: 0.0,
            result,
            stored_failed,
        }
    }

    fn io() -> Error {
        Error::io("r/s/summary.json", std::io::ErrorKind::NotFound.into())
    }

    #[test]
    fn plain_components_only_name_a_directory() {
        assert!(is_plain_component("grid16_monolithic"));
        assert!(is_plain_component("a b.c"));
        for bad in ["", ".", "..", "a/b", "/a", "a/", "../x"] {
            assert!(!is_plain_component(bad), "{bad:?}");
        }
    }

    #[test]
    fn missing_is_an_io_error_on_the_stored_run_only() {
        assert_eq!(outcome(Err(io()), true).status(), Status::Missing);
        assert_eq!(outcome(Err(io()), false).status(), Status::Error);
        let bad = Error::invalid("r/s/summary.json", "not a run summary");
        assert_eq!(outcome(Err(bad), true).status(), Status::Error);
    }

    #[test]
    fn exit_code_precedence_is_mismatch_then_missing_then_bad_input() {
        let batch = |results: Vec<(Result<Report>, bool)>| Batch {
            layout: Layout::ByName,
            against: "r".into(),
            tolerance: Tolerance::Exact,
            outcomes: results.into_iter().map(|(r, f)| outcome(r, f)).collect(),
            elapsed_seconds: 0.0,
        };
        let bad = || Error::invalid("name", "must not be empty");
        let mismatch = || Err(Error::Mismatch("x".into()));
        assert_eq!(batch(vec![]).exit_code(), 0);
        assert_eq!(
            batch(vec![(Err(bad()), false), (Err(io()), true)]).exit_code(),
            1
        );
        assert_eq!(batch(vec![(Err(bad()), false)]).exit_code(), 2);
        // An Error::Mismatch result stands in for a mismatching report here.
        assert_eq!(
            batch(vec![
                (Err(bad()), false),
                (mismatch(), false),
                (Err(io()), true)
            ])
            .exit_code(),
            4
        );
        let t = batch(vec![(Err(bad()), false), (Err(io()), true)]).totals();
        assert_eq!((t.scenarios, t.missing, t.errors), (2, 1, 1));
        let line = batch(vec![(Err(bad()), false), (Err(io()), true)]).summary_line();
        assert_eq!(line, "2 scenarios: 0 match, 1 missing, 1 error");
    }
}
