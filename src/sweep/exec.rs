//! Running a sweep: checking every point, then running the selected ones in parallel,
//! each into its own directory, skipping those a previous run finished (`--resume`).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;
use serde_json::Value;

use super::file;
use super::points::{checked_points, expand, expand_points, plan, Plan, Point};
use super::record::{point_dir, Record, Row, DONE};
use crate::error::{Error, Result};
use crate::output::{create_dir_all, create_out_dir, write_atomic};
use crate::progress::Progress;

/// Which share of the points one invocation runs: `--shard i/n` runs the points whose
/// index `k` has `k mod n = i − 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based shard number `i`, `1 ≤ i ≤ n`.
    pub index: usize,
    /// Number of shards `n`, ≥ 1.
    pub count: usize,
}

impl Shard {
    /// Parses `i/n`; errors name `--shard`.
    pub fn parse(text: &str) -> Result<Shard> {
        let bad = || {
            Error::invalid(
                "--shard",
                format!("must be i/n with 1 ≤ i ≤ n, e.g. 2/8 (got {text:?})"),
            )
        };
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index < 1 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// Whether point `k` belongs to this shard.
    pub fn contains(&self, k: usize) -> bool {
        k % self.count == self.index - 1
    }
}

/// The lock file of a sweep's output directory (hidden; a run's own is
/// [`crate::output::run_dir::LOCK_FILE`], in each point's directory).
pub const SWEEP_LOCK: &str = ".dsmcosim-sweep.lock";

/// What each point keeps of its run (`--keep`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Keep {
    /// `scenario.json`, `summary.json`, `epochs.csv` and `done.json`: what `sweep.csv`
    /// and a rerun need.
    Summary,
    /// The summary files and every CSV the run wrote (`trace.csv`, `network.csv`, …).
    Trace,
    /// Everything the run wrote, plots included.
    #[default]
    All,
}

impl Keep {
    /// Whether a point keeps the run's file `name`.
    fn keeps(self, name: &str) -> bool {
        match self {
            Keep::All => true,
            Keep::Trace => name.ends_with(".csv") || name.ends_with(".json"),
            Keep::Summary => matches!(name, "scenario.json" | "summary.json" | "epochs.csv"),
        }
    }

    /// Removes from `dir` the run's files this setting does not keep (before `done.json`
    /// is written).
    fn prune(self, dir: &Path) -> Result<()> {
        if self == Keep::All {
            return Ok(());
        }
        let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(dir, e))?;
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if name == DONE || name.starts_with(".dsmcosim") || self.keeps(&name) {
                continue;
            }
            let kind = entry.file_type().map_err(|e| Error::io(&path, e))?;
            let removed = if kind.is_dir() {
                std::fs::remove_dir_all(&path)
            } else {
                std::fs::remove_file(&path)
            };
            removed.map_err(|e| Error::io(&path, e))?;
        }
        Ok(())
    }
}

/// Options of `dsmcosim sweep`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Options {
    /// What each point keeps of its run.
    pub keep: Keep,
    /// Continue a sweep in the output directory: skip points whose `done.json` records
    /// the same point definition.
    pub resume: bool,
    /// Run only this shard's points.
    pub shard: Option<Shard>,
    /// `--set POINTER=VALUE` overrides of the base scenario, applied in order before the
    /// sweep's own overrides and axes (as `run --set` applies them to a scenario file).
    pub sets: Vec<String>,
}

/// What a sweep did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Report {
    /// Sweep name.
    pub name: String,
    /// Points of the whole sweep.
    pub points: usize,
    /// Points of this invocation (this shard's, or all).
    pub selected: usize,
    /// Points run now.
    pub ran: usize,
    /// Points skipped because an earlier run finished them (`--resume`).
    pub skipped: usize,
    /// Selected points whose run diverged.
    pub diverged: usize,
}

/// The checked sweep: plan, points, base digest, definition text.
struct Loaded {
    plan: Plan,
    points: Vec<Point>,
    /// The base scenario's file: points read relative paths from its directory.
    base_path: PathBuf,
    base_digest: String,
    text: String,
}

/// A sweep file checked as a definition, with its base read but no point built.
struct Defined {
    plan: Plan,
    base: Value,
    base_label: String,
    /// The base scenario's file: points read relative paths from its directory.
    base_path: PathBuf,
    base_digest: String,
    text: String,
}

/// Reads the sweep file and its base, and checks every point.
fn load(sweep_path: &Path, sets: &[String]) -> Result<Loaded> {
    let d = define(sweep_path, sets)?;
    let points = expand(&d.plan, &d.base, (&d.base_label, &d.base_path), sets)?;
    Ok(Loaded {
        plan: d.plan,
        points,
        base_digest: d.base_digest,
        base_path: d.base_path,
        text: d.text,
    })
}

/// Reads the sweep file and its base (with `sets` applied) and checks the definition
/// (axes, counts, labels).
fn define(sweep_path: &Path, sets: &[String]) -> Result<Defined> {
    let (file, text) = file::load(sweep_path)?;
    let plan = plan(&file)?;
    let base_path: PathBuf = match sweep_path.parent() {
        Some(dir) => dir.join(&file.base),
        None => PathBuf::from(&file.base),
    };
    let bytes =
        crate::input::read(&base_path).map_err(|e| missing_base(e, &file.base, &base_path))?;
    let label = base_path.display().to_string();
    let mut base: Value = serde_json::from_slice(&bytes).map_err(|e| Error::Parse {
        file: label.clone(),
        message: e.to_string(),
        line: e.line(),
        column: e.column().max(1),
    })?;
    if sets.len() > crate::scenario::overrides::MAX_OVERRIDES {
        return Err(Error::invalid(
            "--set",
            format!(
                "{} overrides; at most {}",
                sets.len(),
                crate::scenario::overrides::MAX_OVERRIDES
            ),
        ));
    }
    // The base's digest (which `--resume` and `sweep-merge` compare) covers the
    // overrides: the same file under other `--set`s is another base.
    let mut digest = blake3::Hasher::new();
    digest.update(&bytes);
    for set in sets {
        crate::scenario::overrides::apply(&mut base, set)?;
        digest.update(b"\n--set ").update(set.as_bytes());
    }
    Ok(Defined {
        plan,
        base,
        base_label: if sets.is_empty() {
            label
        } else {
            format!("{label} with --set")
        },
        base_digest: digest.finalize().to_hex().to_string(),
        base_path,
        text,
    })
}

/// A base file that does not exist is an input error (exit 2) naming `base` and where
/// it was looked for; other read failures stay what they are.
fn missing_base(e: Error, base: &str, resolved: &Path) -> Error {
    match &e {
        Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            Error::invalid(
                "base",
                format!(
                    "no file {} (`base` {base:?} is resolved relative to the sweep file's \
                     directory); fix the path in the sweep file",
                    resolved.display()
                ),
            )
        }
        _ => e,
    }
}

/// What `dsmcosim validate` says about a sweep file: its definition holds and the
/// points [`checked_points`] picks validate, and which of those have a channel the
/// network never serves.
#[derive(Debug, Clone, PartialEq)]
pub struct Checked {
    /// Sweep name.
    pub name: String,
    /// Points.
    pub points: usize,
    /// Point scenarios built and validated ([`checked_points`]): at most
    /// `Σ min(values, 1 000) + Π extremes` over the axes, never `points` for a sweep of
    /// long ranges.
    pub checked: usize,
    /// One line per point whose plan has a channel with no achieved period (a TDMA
    /// slot list that leaves out one of its senders): such a run's delays grow without
    /// bound and it usually diverges.
    pub warnings: Vec<String>,
}

/// Checks the sweep in `sweep_path`: the definition as `sweep` does (axes, labels, the
/// count of points), then the bounded set of points [`checked_points`] picks, each
/// built, validated and preflighted as `sweep` does before it runs anything, and
/// planned ([`crate::run::plan::plan`]) to find channels that are never served. A
/// point outside the set that a rule refuses (a value inside a range of more than
/// 1 000 steps, a combination that is not an extreme one) is refused by `sweep`, which
/// checks every point before it runs any.
pub fn check(sweep_path: &Path) -> Result<Checked> {
    check_with(sweep_path, &[])
}

/// [`check`] of the sweep with `--set` overrides `sets` applied to its base.
pub fn check_with(sweep_path: &Path, sets: &[String]) -> Result<Checked> {
    let d = define(sweep_path, sets)?;
    let indices = checked_points(&d.plan);
    let points = expand_points(
        &d.plan,
        &d.base,
        (&d.base_label, &d.base_path),
        &indices,
        sets,
    )?;
    let mut warnings = Vec::new();
    for p in &points {
        let scenario = crate::scenario::parse_at(&p.text, &p.key, Some(&d.base_path))?;
        let plan = crate::run::plan::plan(&scenario)?;
        let never: Vec<&str> = plan
            .channels
            .iter()
            .filter(|c| c.tau_achieved.is_none())
            .map(|c| c.name.as_str())
            .collect();
        if !never.is_empty() {
            warnings.push(format!(
                "point p{} ({}): the slot list never serves channel {} (achieved τ infinite)",
                p.index,
                d.plan.describe(p.index),
                never.join(", ")
            ));
        }
    }
    Ok(Checked {
        name: d.plan.name.clone(),
        points: d.plan.points.len(),
        checked: points.len(),
        warnings,
    })
}

/// Points' traces above which a sweep that keeps them says how much it will keep
/// [bytes]: 100 MB.
pub const KEEP_WARNING_BYTES: u64 = 100_000_000;

/// What keeping every point's files will cost, when it is much: the traces alone of the
/// points to run (each point's estimate is its run's bound on `trace.csv`, taken from
/// the first point: a sweep's points share their output settings unless an axis moves
/// them), above [`KEEP_WARNING_BYTES`], with `--keep summary`'s way out.
fn keep_warning(loaded: &Loaded, to_run: &[&Point], keep: Keep) -> Result<Option<String>> {
    let Some(first) = to_run.first().filter(|_| keep != Keep::Summary) else {
        return Ok(None);
    };
    let scenario = crate::scenario::parse_at(&first.text, &first.key, Some(&loaded.base_path))?;
    let each = crate::run::budget::Estimate::of(&scenario, None).trace_bytes;
    Ok(keep_message(to_run.len(), each, keep))
}

/// [`keep_warning`]'s line for `points` points of `each` trace bytes kept as `keep`
/// says, if they come to more than [`KEEP_WARNING_BYTES`].
fn keep_message(points: usize, each: u64, keep: Keep) -> Option<String> {
    let total = each.saturating_mul(points as u64);
    (keep != Keep::Summary && total > KEEP_WARNING_BYTES).then(|| {
        format!(
            "{points} points will keep every file they write (--keep {}): their traces alone \
             come to about {} MB; `--keep summary` keeps what sweep.csv and a rerun need",
            if keep == Keep::All { "all" } else { "trace" },
            total / 1_000_000
        )
    })
}

/// Runs the sweep defined in `sweep_path` into `out`; see the module docs of
/// [`crate::sweep`].
///
/// Every point is built and validated first; a bad sweep or point is an
/// [`Error::Invalid`] and nothing is written. A point whose run diverges is a row with
/// status `diverged`. Points run in parallel on rayon's pool; the first failure (in
/// index order) of a point that could not run is the error, after every other point
/// has finished and written its `done.json`.
pub fn run(sweep_path: &Path, out: &Path, options: &Options) -> Result<Report> {
    let loaded = load(sweep_path, &options.sets)?;
    // One sweep at a time in a directory: a second `sweep --resume` (a requeued cluster
    // task) is refused at once, naming the holder, instead of both rerunning the same
    // points and neither writing sweep.csv. Held until the sweep returns.
    let (selected, to_run, _lock) = prepare(&loaded, out, options)?;
    let to_run: Vec<&Point> = to_run.iter().map(|&k| &loaded.points[k]).collect();
    if let Some(w) = keep_warning(&loaded, &to_run, options.keep)? {
        eprintln!("warning: {w}");
    }
    let progress = Mutex::new(Progress::with_unit(to_run.len() as u64, "points"));
    let finished = AtomicU64::new(0);
    let results: Vec<Result<()>> = to_run
        .par_iter()
        .map(|p| {
            // After Ctrl-C (the handler `dsmcosim sweep` installs) no point starts; the
            // running ones stop at their slice, marked interrupted, without done.json.
            if crate::interrupt::requested() {
                return Ok(());
            }
            let r = run_point(out, &loaded, p, options.keep);
            let n = finished.fetch_add(1, Ordering::Relaxed) + 1;
            if let Ok(mut bar) = progress.lock() {
                bar.tick(n);
            }
            r
        })
        .collect();
    if let Ok(bar) = progress.lock() {
        bar.finish();
    }
    if crate::interrupt::requested() {
        let done = to_run
            .iter()
            .filter(|p| point_dir(out, &p.key).join(DONE).is_file())
            .count();
        return Err(Error::Checks {
            message: format!(
                "interrupted: {done} of the {} points to run finished (each with its \
                 done.json); `dsmcosim sweep {} --out {} --resume` runs the rest",
                to_run.len(),
                sweep_path.display(),
                out.display()
            ),
            code: 130,
        });
    }
    results.into_iter().collect::<Result<Vec<()>>>()?;
    complete(out, &loaded, &selected, to_run.len())
}

/// Sets `out` up for the sweep as [`run`] does before its first point: refuses a
/// directory it did not write (or, without `resume`, one that holds a sweep), writes
/// `sweep.json`, and removes the stale `done.json` of every point to rerun. Returns the
/// indices of the selected points and of those to run (without the ones `resume`
/// finds finished), and the directory's sweep lock.
fn prepare(
    loaded: &Loaded,
    out: &Path,
    options: &Options,
) -> Result<(Vec<usize>, Vec<usize>, std::fs::File)> {
    crate::output::refuse_foreign_outputs(out, "sweep.json", super::writes)?;
    if !options.resume && out.join("sweep.json").exists() {
        return Err(Error::invalid(
            "--out",
            format!(
                "{} already holds a sweep; pass --resume to continue it (finished points are kept), or choose another directory",
                out.display()
            ),
        ));
    }
    create_out_dir(out)?;
    let lock = crate::output::run_dir::lock(out, SWEEP_LOCK, "dsmcosim sweep")?;
    // sweep.json first: it claims the directory, so a sweep stopped at any point after
    // it resumes.
    write_atomic(&out.join("sweep.json"), loaded.text.as_bytes())?;
    create_dir_all(&out.join("points"))?;
    let selected = selected(loaded, options.shard);
    let mut to_run = Vec::new();
    for &k in &selected {
        let p = &loaded.points[k];
        let dir = point_dir(out, &p.key);
        if options.resume {
            if let Ok(Some(done)) = Record::read(&dir) {
                if done.same_point(&expected(p, &loaded.base_digest)) {
                    if done.index != p.index {
                        // An axis gained a value: the point moved in the order, its run
                        // did not change.
                        Record {
                            index: p.index,
                            ..done
                        }
                        .write(&dir)?;
                    }
                    continue;
                }
            }
        }
        // A stale marker must not survive a rerun that fails half-way.
        match std::fs::remove_file(dir.join(DONE)) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(Error::io(dir.join(DONE), e))
            }
            _ => {}
        }
        to_run.push(k);
    }
    Ok((selected, to_run, lock))
}

/// The indices of the points `shard` runs (all of them without one).
fn selected(loaded: &Loaded, shard: Option<Shard>) -> Vec<usize> {
    (0..loaded.points.len())
        .filter(|&k| shard.is_none_or(|s| s.contains(loaded.points[k].index)))
        .collect()
}

/// Writes the sweep's tables and figures from the `done.json` of the `selected` points
/// (every one must be done), as [`run`] ends; `ran` counts the points run now.
fn complete(out: &Path, loaded: &Loaded, selected: &[usize], ran: usize) -> Result<Report> {
    let records = selected
        .iter()
        .map(|&k| {
            let dir = point_dir(out, &loaded.points[k].key);
            Record::read(&dir)?.ok_or_else(|| {
                Error::io(
                    dir.join(DONE),
                    std::io::Error::new(std::io::ErrorKind::NotFound, "point did not finish"),
                )
            })
        })
        .collect::<Result<Vec<_>>>()?;
    super::write_outputs(out, &loaded.plan, &records)?;
    Ok(Report {
        name: loaded.plan.name.clone(),
        points: loaded.points.len(),
        selected: selected.len(),
        ran,
        skipped: selected.len() - ran,
        diverged: records.iter().filter(|r| r.row.status != "ok").count(),
    })
}

/// A sweep run by an embedding's own executor (the Python package's
/// `sweep(..., executor=...)`), in three calls: [`pending`] sets `out` up as [`run`]
/// does and names the points to run; [`run_one`] runs one of them, in any process that
/// sees `out` (each point writes only its own `points/<key>/`); [`finish`] writes the
/// tables once every point is done. The result is [`run`]'s, byte for byte: the same
/// points, the same records, the same writer.
///
/// The keys of the points of the sweep at `sweep_path` left to run in `out`, in index
/// order: all of them, or with `options.resume` those without a matching `done.json`.
pub fn pending(sweep_path: &Path, out: &Path, options: &Options) -> Result<Vec<String>> {
    let loaded = load(sweep_path, &options.sets)?;
    let (_, to_run, _lock) = prepare(&loaded, out, options)?;
    Ok(to_run
        .into_iter()
        .map(|k| loaded.points[k].key.clone())
        .collect())
}

/// Runs the point `key` of the sweep at `sweep_path` (with the overrides `sets`) into
/// `out/points/<key>/`, as [`run`] runs each point, unless its `done.json` already
/// records this very point; see [`pending`].
pub fn run_one(
    sweep_path: &Path,
    out: &Path,
    sets: &[String],
    keep: Keep,
    key: &str,
) -> Result<()> {
    let loaded = load(sweep_path, sets)?;
    let p = loaded
        .points
        .iter()
        .find(|p| p.key == key)
        .ok_or_else(|| Error::invalid("point", format!("the sweep has no point {key:?}")))?;
    // Done already (a retried task, a rerun): its record stands, as under `--resume`.
    if let Ok(Some(done)) = Record::read(&point_dir(out, key)) {
        if done.same_point(&expected(p, &loaded.base_digest)) {
            return Ok(());
        }
    }
    run_point(out, &loaded, p, keep)
}

/// Writes `out`'s `sweep.csv`, `timing.csv` and figures once every point [`pending`]
/// named is done; `ran` counts the points run since. See [`pending`].
pub fn finish(sweep_path: &Path, out: &Path, options: &Options, ran: usize) -> Result<Report> {
    let loaded = load(sweep_path, &options.sets)?;
    let _lock = crate::output::run_dir::lock(out, SWEEP_LOCK, "dsmcosim sweep")?;
    let selected = selected(&loaded, options.shard);
    complete(out, &loaded, &selected, ran)
}

/// The record point `p` will get, without its measurements (for matching).
fn expected(p: &Point, base_digest: &str) -> Record {
    Record {
        index: p.index,
        values: p.values.clone(),
        seed: p.seed,
        scenario_digest: p.digest.clone(),
        base_digest: base_digest.to_string(),
        row: Row {
            status: String::new(),
            divergence: None,
            mean_cost: None,
            unpaired_mean_cost_by_method: Default::default(),
            paired: Default::default(),
            live_method: None,
            lost_frames: 0,
            channels: Vec::new(),
            bandwidth: None,
            digest: String::new(),
        },
        wall_seconds: 0.0,
    }
}

/// Runs point `p` into `out/points/<key>/`: the run's outputs, `scenario.json`, then
/// `done.json`.
fn run_point(out: &Path, loaded: &Loaded, p: &Point, keep: Keep) -> Result<()> {
    let dir = point_dir(out, &p.key);
    create_dir_all(&dir)?;
    let label = format!("{}_{}", loaded.plan.name, p.key);
    let scenario = crate::scenario::parse_at(&p.text, &label, Some(&loaded.base_path))?;
    let started = Instant::now();
    // `--keep summary` drops the trace files: they are never written, not written and
    // removed.
    let options = crate::run::RunOptions {
        skip_trace_files: keep == Keep::Summary,
        scenario_blake3: Some(*blake3::hash(p.text.as_bytes()).as_bytes()),
        ..Default::default()
    };
    let scenario = std::sync::Arc::new(scenario);
    match crate::progress::quietly(|| crate::run::run_shared(scenario, &dir, options)) {
        Ok(_) | Err(Error::Diverged(_) | Error::Numerical { .. }) => {}
        Err(Error::Invalid { path, message }) => {
            return Err(Error::invalid(
                format!(
                    "point p{} ({}): {path}",
                    p.index,
                    loaded.plan.describe(p.index)
                ),
                message,
            ))
        }
        Err(e) => return Err(e),
    }
    // After the run, as `dsmcosim run` writes it: before, the point's directory would
    // hold a file of a run's name and no run (which a run refuses to replace).
    write_atomic(&dir.join("scenario.json"), p.text.as_bytes())?;
    let wall_seconds = started.elapsed().as_secs_f64();
    let summary_path = dir.join("summary.json");
    let text = std::fs::read_to_string(&summary_path).map_err(|e| Error::io(&summary_path, e))?;
    let summary: Value = serde_json::from_str(&text).map_err(|e| {
        Error::invalid(
            summary_path.display().to_string(),
            format!("not a run summary: {e}"),
        )
    })?;
    let record = Record {
        row: Row::from_summary(&summary, &summary_path)?,
        wall_seconds,
        ..expected(p, &loaded.base_digest)
    };
    keep.prune(&dir)?;
    record.write(&dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sweep_that_keeps_much_says_how_much_and_one_that_keeps_summaries_does_not() {
        // 600 points of 387 kB each: the slot-layout study's size.
        let m = keep_message(600, 387_000, Keep::All).expect("a warning");
        assert_eq!(
            m,
            "600 points will keep every file they write (--keep all): their traces alone \
             come to about 232 MB; `--keep summary` keeps what sweep.csv and a rerun need"
        );
        assert!(keep_message(600, 387_000, Keep::Trace).is_some_and(|m| m.contains("--keep trace")));
        assert_eq!(keep_message(600, 387_000, Keep::Summary), None);
        assert_eq!(keep_message(60, 387_000, Keep::All), None);
        assert_eq!(keep_message(usize::MAX, u64::MAX, Keep::Summary), None);
    }

    #[test]
    fn shards_split_by_index() {
        let s = Shard::parse("2/3").unwrap();
        let mine: Vec<usize> = (0..8).filter(|&k| s.contains(k)).collect();
        assert_eq!(mine, vec![1, 4, 7]);
        for bad in ["0/2", "3/2", "1", "a/2", "1/0", "-1/2"] {
            let e = Shard::parse(bad).unwrap_err();
            assert!(e.to_string().starts_with("--shard:"), "{bad}: {e}");
            assert_eq!(e.exit_code(), 2);
        }
    }
}
