//! `dsmcosim check SCENARIO… --against DIR`: rerun scenarios beside their stored runs
//! and compare.
//!
//! This module compares one scenario with one stored run; [`batch`] checks many at once
//! (each mapped to `DIR/<scenario name>/`, in parallel) and [`junit`] and [`json`] write
//! the verdicts for CI.
//!
//! The new run goes to the sibling directory `DIR.new` (its previous outputs are
//! replaced), or to a work directory of the caller's choice, and stays there for
//! inspection. The verdict:
//!
//! 1. The digests in both `summary.json` files are compared (bit-for-bit over every
//!    step, TDMA cycle and epoch row, see [`crate::trace::digest`]).
//! 2. The CSV files are compared record by record ([`crate::trace::compare`]): exactly
//!    (equal text, i.e. equal bits) by default, or relatively with a tolerance. This
//!    also catches a stored CSV that was edited, or a change in how values are written,
//!    neither of which moves the digest.
//!
//! Without a tolerance the run matches when the digests and every CSV value are equal.
//! With a tolerance it passes when every value agrees within it, whatever the digests.
//! A diverged stored run (`"status": "diverged"`) is checked like any other: the rerun
//! diverges at the same step and writes the same files.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::error::{Error, Result};
use crate::scenario::Scenario;
use crate::trace::compare::{compare_dirs, DirComparison, Tolerance, REQUIRED_CSV};

pub mod batch;
pub mod json;
pub mod junit;
pub mod outcome;

/// What a run directory's `summary.json` says about the run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    /// The directory.
    pub dir: PathBuf,
    /// Scenario name (the `name` key of the scenario file).
    pub scenario: String,
    /// `ok` or `diverged`.
    pub status: String,
    /// The divergence message of a diverged run.
    pub error: Option<String>,
    /// Run digest (hex).
    pub digest: String,
    /// Wall-clock seconds the run took (absent in a hand-written summary) [s].
    pub wall_seconds: Option<f64>,
}

/// Reads `dir/summary.json`. A missing directory or file is an I/O error; a file that
/// is not a run summary (not JSON, no `digest` or `scenario` string) is a bad-input
/// error.
pub fn read_summary(dir: &Path) -> Result<RunSummary> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let bad = |message: String| Error::invalid(path.display().to_string(), message);
    let v: Value = serde_json::from_str(&text).map_err(|e| bad(format!("not JSON: {e}")))?;
    let text_of = |key: &str| v.get(key).and_then(Value::as_str).map(str::to_string);
    let required = |key: &str| {
        text_of(key).ok_or_else(|| bad(format!("no `{key}` string; not a run summary")))
    };
    Ok(RunSummary {
        dir: dir.to_path_buf(),
        scenario: required("scenario")?,
        digest: required("digest")?,
        status: text_of("status").unwrap_or_else(|| "ok".to_string()),
        error: text_of("error"),
        wall_seconds: v.get("wall_seconds").and_then(Value::as_f64),
    })
}

/// `path` made absolute with its existing part resolved (symlinks, `..`): the
/// canonical form of its longest existing ancestor, then the rest as given.
fn resolved(path: &Path) -> PathBuf {
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut head = abs.as_path();
    let mut tail = Vec::new();
    loop {
        if let Ok(c) = head.canonicalize() {
            return tail.iter().rev().fold(c, |p, t| p.join(t));
        }
        match (head.parent(), head.file_name()) {
            (Some(parent), Some(name)) => {
                tail.push(name.to_os_string());
                head = parent;
            }
            _ => return abs,
        }
    }
}

/// Refuses a rerun directory `new` that is the stored run `stored`, lies inside it or
/// holds it (however the two are spelled: `--work D --against D`, symlinks, `..`): the
/// rerun would replace the stored files it is to be compared with (exit 2, naming
/// `--work`).
pub fn apart(stored: &Path, new: &Path) -> Result<()> {
    let (s, n) = (resolved(stored), resolved(new));
    if n.starts_with(&s) || s.starts_with(&n) {
        let how = if n == s {
            "is"
        } else if n.starts_with(&s) {
            "lies inside"
        } else {
            "holds"
        };
        return Err(Error::invalid(
            "--work",
            format!(
                "the rerun directory {} {how} the stored run {}: the rerun would replace \
                 what it is compared with (choose a --work outside the stored runs)",
                new.display(),
                stored.display()
            ),
        ));
    }
    Ok(())
}

/// The directory beside `dir` that a check writes its new run to: `DIR.new`.
pub fn sibling(dir: &Path) -> Result<PathBuf> {
    let dir = if dir.file_name().is_some() {
        dir.to_path_buf()
    } else {
        // `.` or `..`: name the directory itself.
        dir.canonicalize().map_err(|e| Error::io(dir, e))?
    };
    let mut name = dir
        .file_name()
        .ok_or_else(|| Error::invalid("--against", "the root directory has no sibling"))?
        .to_os_string();
    name.push(".new");
    Ok(dir.with_file_name(name))
}

/// Runs `scenario` into `out` (claimed as every run claims its directory: the previous
/// rerun's outputs there are replaced, [`crate::output::run_dir`]) and returns its
/// summary. A run that diverges or fails numerically is a result like any other; only
/// bad input and I/O failures are errors.
pub fn rerun(scenario: &Scenario, out: &Path) -> Result<RunSummary> {
    match crate::run::run(scenario, out) {
        Ok(_) | Err(Error::Diverged(_)) | Err(Error::Numerical { .. }) => read_summary(out),
        // `run`'s refusal of a directory holding another scenario's run names `run`'s
        // options; `check` has neither `--out` nor `--force`.
        Err(Error::Invalid { path, message }) if path == "--out" => Err(Error::invalid(
            out.display().to_string(),
            format!(
                "{} (the rerun's directory: an earlier check's? remove it, or give \
                 `--work DIR` to rerun elsewhere)",
                message
                    .split(" (choose another directory")
                    .next()
                    .unwrap_or(&message)
                    .trim_start_matches(&format!("{} ", out.display()))
            ),
        )),
        Err(e) => Err(e),
    }
}

/// How a check ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Equal digests and equal CSV text.
    Match,
    /// Every CSV value agrees within the tolerance, but the digests or some values
    /// differ.
    WithinTolerance,
    /// A CSV value differs (beyond the tolerance), or without a tolerance the digests
    /// differ.
    Mismatch,
}

/// A finished comparison of a stored and a new run.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// The stored run.
    pub stored: RunSummary,
    /// The new run (in [`sibling`] of the stored one).
    pub new: RunSummary,
    /// How values were compared.
    pub tolerance: Tolerance,
    /// The CSV comparison.
    pub comparison: DirComparison,
}

impl Report {
    /// Compares two finished run directories.
    pub fn compare(stored: RunSummary, new: RunSummary, tolerance: Tolerance) -> Result<Report> {
        let comparison = compare_dirs(&stored.dir, &new.dir, tolerance)?;
        Ok(Report {
            stored,
            new,
            tolerance,
            comparison,
        })
    }

    /// Whether the digests are equal.
    pub fn digests_equal(&self) -> bool {
        self.stored.digest == self.new.digest
    }

    /// The verdict.
    pub fn verdict(&self) -> Verdict {
        let csv_agree = self.comparison.first_difference().is_none();
        let identical = self.digests_equal() && self.comparison.differing() == 0;
        match (csv_agree, identical, self.tolerance) {
            (false, _, _) => Verdict::Mismatch,
            (true, true, _) => Verdict::Match,
            (true, false, Tolerance::Relative(_)) => Verdict::WithinTolerance,
            (true, false, Tolerance::Exact) => Verdict::Mismatch,
        }
    }

    /// A one-line report of a match, or the lines explaining a mismatch.
    pub fn message(&self) -> String {
        let (s, n) = (&self.stored, &self.new);
        let (name, dir, new_dir) = (&n.scenario, s.dir.display(), n.dir.display());
        match self.verdict() {
            Verdict::Match => format!(
                "{name}: matches {dir} (digest {}); new run in {new_dir}",
                s.digest
            ),
            Verdict::WithinTolerance => format!(
                "{name}: within tolerance {:e} of {dir} ({} of {} values differ, largest \
                 relative difference {:.3e}); {}; new run in {new_dir}",
                match self.tolerance {
                    Tolerance::Relative(x) => x,
                    Tolerance::Exact => 0.0,
                },
                self.comparison.differing(),
                self.comparison.values(),
                self.comparison.max_rel(),
                if self.digests_equal() {
                    format!("digests equal ({})", s.digest)
                } else {
                    format!("digests differ (stored {}, new {})", s.digest, n.digest)
                }
            ),
            Verdict::Mismatch => {
                let mut m = format!("{name}: differs from {dir}\n");
                if self.digests_equal() {
                    m.push_str(&format!("  digest: equal ({})\n", s.digest));
                } else {
                    m.push_str(&format!(
                        "  digest: stored {}, new {}\n",
                        s.digest, n.digest
                    ));
                }
                match self.comparison.first_difference() {
                    Some(d) => {
                        m.push_str(&format!("  first difference: {d}\n"));
                        if self.digests_equal() {
                            m.push_str(
                                "  (the digests are equal, so the stored CSV was edited or \
                                 written by a different formatter)\n",
                            );
                        }
                    }
                    None => m.push_str(
                        "  every CSV value is equal: the runs differ in steps the trace does \
                         not keep (set output.decimation to 1 to see them)\n",
                    ),
                }
                if s.scenario != n.scenario {
                    m.push_str(&format!(
                        "  the stored run is of scenario `{}`, not `{}`\n",
                        s.scenario, n.scenario
                    ));
                }
                if s.status != n.status || s.error != n.error {
                    let status = |r: &RunSummary| match &r.error {
                        Some(e) => format!("{} ({e})", r.status),
                        None => r.status.clone(),
                    };
                    m.push_str(&format!(
                        "  stored run: {}; new run: {}\n",
                        status(s),
                        status(n)
                    ));
                }
                if !self.comparison.unpaired.is_empty() {
                    m.push_str(&format!(
                        "  not compared (only in one run): {}\n",
                        self.comparison.unpaired.join(", ")
                    ));
                }
                m.push_str(&format!("  new run kept in {new_dir}"));
                m
            }
        }
    }
}

/// The comparison rule for `--tolerance`: `None` for an exact comparison, else a
/// relative tolerance, which must be in [0, 1) (bad input otherwise).
pub fn parse_tolerance(tolerance: Option<f64>) -> Result<Tolerance> {
    match tolerance {
        None => Ok(Tolerance::Exact),
        Some(x) if (0.0..1.0).contains(&x) => Ok(Tolerance::Relative(x)),
        // A relative difference is 1 between any value and 0, and up to 2 between values
        // of opposite signs: from 1 on, nearly anything would pass.
        Some(x) => Err(Error::invalid(
            "--tolerance",
            format!(
                "must be a relative difference ≥ 0 and below 1 (got {}; at 1 any value \
                 agrees with 0)",
                crate::error::num(x)
            ),
        )),
    }
}

/// Reads the stored run in `against`: its summary and the presence of every required
/// CSV file. A missing directory or file is an I/O error, a summary that is not a run
/// summary bad input.
pub fn read_stored(against: &Path) -> Result<RunSummary> {
    let stored = read_summary(against)?;
    for name in REQUIRED_CSV {
        let path = against.join(name);
        std::fs::metadata(&path).map_err(|e| Error::io(&path, e))?;
    }
    Ok(stored)
}

/// Reruns `scenario` beside the stored run in `against` and compares (see the module
/// docs). `tolerance`: `None` for an exact comparison, else the relative tolerance
/// (finite, ≥ 0). The stored run is read before the rerun, so a missing one fails fast.
pub fn check(scenario: &Scenario, against: &Path, tolerance: Option<f64>) -> Result<Report> {
    let tolerance = parse_tolerance(tolerance)?;
    let new_dir = sibling(against)?;
    check_into(scenario, against, &new_dir, tolerance)
}

/// Like [`check`], with the new run written into `new_dir` instead of beside the
/// stored run.
pub fn check_into(
    scenario: &Scenario,
    against: &Path,
    new_dir: &Path,
    tolerance: Tolerance,
) -> Result<Report> {
    apart(against, new_dir)?;
    let stored = read_stored(against)?;
    let new = rerun(scenario, new_dir)?;
    Report::compare(stored, new, tolerance)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sibling_is_beside_the_stored_run() {
        let s = |p: &str| sibling(Path::new(p)).unwrap();
        assert_eq!(s("results/grid16"), PathBuf::from("results/grid16.new"));
        assert_eq!(s("results/grid16/"), PathBuf::from("results/grid16.new"));
        assert_eq!(s("grid16"), PathBuf::from("grid16.new"));
        let here = std::env::current_dir().unwrap();
        assert_eq!(
            s("."),
            here.with_file_name(format!(
                "{}.new",
                here.file_name().unwrap().to_string_lossy()
            ))
        );
    }

    fn summary(dir: &str, digest: &str) -> RunSummary {
        RunSummary {
            dir: PathBuf::from(dir),
            scenario: "s".into(),
            status: "ok".into(),
            error: None,
            digest: digest.into(),
            wall_seconds: None,
        }
    }

    fn report(stored: &str, new: &str, tol: Tolerance, csv_equal: bool) -> Report {
        let t = "t,x\n0,1\n";
        let u = if csv_equal { t } else { "t,x\n0,2\n" };
        Report {
            stored: summary("a", stored),
            new: summary("a.new", new),
            tolerance: tol,
            comparison: DirComparison {
                files: vec![crate::trace::compare::compare_csv("trace.csv", t, u, tol)],
                unpaired: vec![],
            },
        }
    }

    #[test]
    fn verdicts() {
        use Tolerance::{Exact, Relative};
        assert_eq!(report("d", "d", Exact, true).verdict(), Verdict::Match);
        assert_eq!(report("d", "e", Exact, true).verdict(), Verdict::Mismatch);
        assert_eq!(report("d", "d", Exact, false).verdict(), Verdict::Mismatch);
        assert_eq!(
            report("d", "e", Relative(1e-3), true).verdict(),
            Verdict::WithinTolerance
        );
        assert_eq!(
            report("d", "e", Relative(1e-3), false).verdict(),
            Verdict::Mismatch
        );
        // Equal digests but an edited value within the tolerance: not an identical match.
        assert_eq!(
            report("d", "d", Relative(1.0), false).verdict(),
            Verdict::WithinTolerance
        );
        let m = report("d", "e", Exact, true).message();
        assert!(m.contains("steps the trace does not keep"), "{m}");
        let m = report("d", "d", Exact, false).message();
        assert!(m.contains("stored CSV was edited"), "{m}");
        assert!(m.contains("first difference: trace.csv, t = 0 (row 1), column x"));
    }

    #[test]
    fn missing_stored_run_is_an_io_error_and_a_bad_summary_bad_input() {
        let e = read_summary(Path::new("/nonexistent/run")).unwrap_err();
        assert_eq!(e.exit_code(), 1);
        assert!(
            e.to_string().starts_with("/nonexistent/run/summary.json: "),
            "{e}"
        );
        let dir = std::env::temp_dir().join(format!("dsmcosim-check-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("summary.json"), "{\"scenario\": \"s\"}").unwrap();
        let e = read_summary(&dir).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(
            e.to_string()
                .ends_with("no `digest` string; not a run summary"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
