//! CI regression: every stored run in `results/` reruns to the digest and the CSV files
//! it stored.
//!
//! A stored run is a directory `results/<dir>/` with a `summary.json` whose `scenario`
//! key names an existing `scenarios/<scenario>.json` (directories ending in `.new` are
//! `dsmcosim check` scratch output, not stored runs). Each is rerun in-process into a
//! scratch directory under `target/` and compared as `dsmcosim check` compares: the
//! digest, and every CSV file record by record, exactly. On a change the test prints the
//! first differing record (`dsmcosim::check`) and how to regenerate `results/` after a
//! deliberate change.
//!
//! Runs that would take too long for CI (stored `wall_seconds` above
//! [`MAX_WALL_SECONDS`]) are skipped and listed; today every stored run is below it (the
//! longest, `tdma16_space_cp`, about 20 s).

use std::path::{Path, PathBuf};
use std::time::Instant;

use dsmcosim::check::{read_summary, rerun, Report, RunSummary, Verdict};

#[path = "../support/fmu_build.rs"]
mod fmu_build;
use dsmcosim::trace::compare::Tolerance;

/// Stored runs whose recorded wall time exceeds this are not rerun in CI [s]. Above
/// every stored run's (the longest, `grid64_tight`, took 63 s; the next about 20 s),
/// so that all of them, the 16-node TDMA+DSM run included, are checked; a new stored
/// run longer than this should rather be shortened.
const MAX_WALL_SECONDS: f64 = 120.0;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A stored run and the scenario file that produced it.
struct Stored {
    summary: RunSummary,
    scenario_file: PathBuf,
}

/// The stored runs under `results/`, by directory name; directories with a summary but
/// no scenario file are returned in the second list with the reason.
fn stored_runs(results: &Path) -> (Vec<Stored>, Vec<String>) {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(results)
        .unwrap_or_else(|e| panic!("{}: {e}", results.display()))
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.is_dir() && p.join("summary.json").is_file())
        .filter(|p| !p.to_string_lossy().ends_with(".new"))
        .collect();
    dirs.sort();
    let (mut runs, mut without) = (Vec::new(), Vec::new());
    for dir in dirs {
        let summary = read_summary(&dir).unwrap_or_else(|e| panic!("stored run: {e}"));
        let scenario_file = repo()
            .join("scenarios")
            .join(format!("{}.json", summary.scenario));
        if scenario_file.is_file() {
            runs.push(Stored {
                summary,
                scenario_file,
            });
        } else {
            without.push(format!(
                "{} (no {})",
                dir.display(),
                scenario_file.display()
            ));
        }
    }
    (runs, without)
}

/// Loads a shipped scenario (one with FMUs as a copy in `scratch` beside the test FMUs
/// built there, see [`fmu_build::beside_test_fmus`]).
fn load(file: &Path, scratch: &Path) -> dsmcosim::scenario::Scenario {
    let label = file.display().to_string();
    let path = fmu_build::beside_test_fmus(file, scratch).unwrap_or_else(|e| panic!("{e}"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{label}: {e}"));
    dsmcosim::scenario::parse_at(&text, &label, Some(&path))
        .unwrap_or_else(|e| panic!("{label}: {e}"))
}

#[test]
fn every_stored_run_reproduces_its_digest_and_csv_files() {
    let (runs, without) = stored_runs(&repo().join("results"));
    if !without.is_empty() {
        eprintln!("not rerun, no scenario file: {}", without.join(", "));
    }
    let (fast, slow): (Vec<&Stored>, Vec<&Stored>) = runs
        .iter()
        .partition(|r| r.summary.wall_seconds.unwrap_or(0.0) <= MAX_WALL_SECONDS);
    if !slow.is_empty() {
        let names: Vec<String> = slow
            .iter()
            .map(|r| {
                format!(
                    "{} ({:.0} s)",
                    r.summary.dir.display(),
                    r.summary.wall_seconds.unwrap_or(f64::NAN)
                )
            })
            .collect();
        eprintln!(
            "skipped, stored wall time above {MAX_WALL_SECONDS} s (check them with \
             `dsmcosim check`): {}",
            names.join(", ")
        );
    }
    assert!(
        !fast.is_empty(),
        "no stored run found under results/ (discovery broken?)"
    );

    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR")).join("regression");
    let mut failures = Vec::new();
    for run in fast {
        let stored = &run.summary;
        let name = stored
            .dir
            .file_name()
            .expect("a results/ subdirectory")
            .to_string_lossy()
            .into_owned();
        let scenario = load(&run.scenario_file, &scratch);
        let started = Instant::now();
        let new = rerun(&scenario, &scratch.join(&name))
            .unwrap_or_else(|e| panic!("rerunning {name}: {e}"));
        let digest_changed = new.digest != stored.digest;
        let report = Report::compare(stored.clone(), new, Tolerance::Exact)
            .unwrap_or_else(|e| panic!("comparing {name}: {e}"));
        let verdict = report.verdict();
        eprintln!(
            "{name}: {} in {:.2} s, digest {}, {} of {} CSV values differ{}",
            report.new.status,
            started.elapsed().as_secs_f64(),
            if digest_changed {
                "CHANGED"
            } else {
                "unchanged"
            },
            report.comparison.differing(),
            report.comparison.values(),
            if report.comparison.unpaired.is_empty() {
                String::new()
            } else {
                format!(
                    ", only in one run: {}",
                    report.comparison.unpaired.join(", ")
                )
            }
        );
        if verdict != Verdict::Match {
            failures.push(report.message());
        } else if !report.comparison.unpaired.is_empty() {
            // A CSV file only one of the runs wrote is a difference too.
            failures.push(format!(
                "{name}: CSV files written by only one of the runs: {}",
                report.comparison.unpaired.join(", ")
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} stored run(s) no longer reproduce:\n{}\n\nIf the change is deliberate, regenerate \
         with `results/regenerate.sh`, review the listed digest changes and the diff of \
         results/, and commit them together with the change.",
        failures.len(),
        failures.join("\n")
    );
}

/// `dsmcosim check` as a user meets it: its exit codes and the first-difference message.
#[test]
fn check_cli_exit_codes() {
    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR")).join("check-cli");
    let _ = std::fs::remove_dir_all(&scratch);
    let stored = scratch.join("stored");
    std::fs::create_dir_all(&stored).expect("scratch dir");
    for f in ["summary.json", "trace.csv", "epochs.csv"] {
        std::fs::copy(
            repo().join("results/grid16_space_fixed").join(f),
            stored.join(f),
        )
        .expect("copy a stored run");
    }
    let scenario = repo().join("scenarios/grid16_space_fixed.json");
    let check = |against: &Path, extra: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
            .arg("check")
            .arg(&scenario)
            .arg("--against")
            .arg(against)
            .args(extra)
            .output()
            .expect("spawn dsmcosim");
        let text = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        (out.status.code(), text)
    };
    // The stored run diverged at 23.991 s; the rerun diverges identically.
    let (code, text) = check(&stored, &[]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("matches"), "{text}");
    assert!(scratch.join("stored.new/trace.csv").is_file());

    // One changed digit in the last value of row 124 (t = 12.3): its KE, the last
    // column since the invariants follow the bodies.
    let trace = std::fs::read_to_string(stored.join("trace.csv")).expect("trace");
    let mut lines: Vec<String> = trace.lines().map(str::to_string).collect();
    let last = lines[124].pop().expect("a value");
    lines[124].push(if last == '1' { '2' } else { '1' });
    std::fs::write(stored.join("trace.csv"), lines.join("\n") + "\n").expect("write");
    let (code, text) = check(&stored, &[]);
    assert_eq!(code, Some(4), "{text}");
    assert!(
        text.contains("first difference: trace.csv, t = 12.3 (row 124), column KE: stored "),
        "{text}"
    );
    let (code, text) = check(&stored, &["--tolerance", "1e-6"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("within tolerance 1e-6"), "{text}");

    let (code, text) = check(&scratch.join("missing"), &[]);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("summary.json"), "{text}");
    let (code, text) = check(&stored, &["--tolerance", "-1"]);
    assert_eq!(code, Some(2), "{text}");
}
