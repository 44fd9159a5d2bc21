//! `dsmcosim sweep-merge --out OUT SHARD_DIR...`: the `done.json` records of every shard's
//! output directory, checked and written out as one sweep, with the same bytes of
//! `sweep.csv` as an unsharded run.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::Value;

use super::file;
use super::points::plan;
use super::record::{Record, Row, DONE};
use crate::error::{Error, Result};
use crate::output::{create_out_dir, write_atomic};

/// What a merge found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MergeReport {
    /// Sweep name.
    pub name: String,
    /// Points merged (all of the sweep's).
    pub points: usize,
    /// Points whose run diverged.
    pub diverged: usize,
}

/// The `done.json` records under `dir/points/` of the points of `keys` (directory name →
/// index), by index, with the directory each came from. Sub-directories not named by a
/// point's key, or without a `done.json`, are skipped.
fn records(dir: &Path, keys: &BTreeMap<String, usize>) -> Result<Vec<(usize, Record, PathBuf)>> {
    let points = dir.join("points");
    let entries = match std::fs::read_dir(&points) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(Error::io(&points, e)),
    };
    let mut found = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(&points, e))?;
        let name = entry.file_name();
        let Some(&index) = name.to_str().and_then(|n| keys.get(n)) else {
            continue;
        };
        let path = entry.path();
        if let Some(record) = Record::read(&path)? {
            found.push((index, record, path));
        }
    }
    found.sort_by_key(|(i, _, _)| *i);
    Ok(found)
}

/// Merges the sweep output directories `shards` into `out`: checks that they hold the
/// same sweep definition (`sweep.json`), that every point `0..N` is done in exactly one
/// of them with the definition's axis values, all on the same base scenario, then
/// writes `sweep.json`, `sweep.csv`, `timing.csv` and the plots into `out`.
pub fn merge(out: &Path, shards: &[PathBuf]) -> Result<MergeReport> {
    let first = shards
        .first()
        .ok_or_else(|| Error::invalid("sweep-merge", "needs at least one shard directory"))?;
    crate::output::refuse_foreign_outputs(out, "sweep.json", super::writes)?;
    let mut definition: Option<(Value, String)> = None;
    for dir in shards {
        let path = dir.join("sweep.json");
        let text = std::fs::read_to_string(&path).map_err(|e| {
            Error::invalid(
                dir.display().to_string(),
                format!("not a sweep output directory (cannot read sweep.json: {e})"),
            )
        })?;
        let value: Value = serde_json::from_str(&text)
            .map_err(|e| Error::invalid(path.display().to_string(), e.to_string()))?;
        match &definition {
            None => definition = Some((value, text)),
            Some((v, _)) if *v == value => {}
            Some(_) => {
                return Err(Error::invalid(
                    path.display().to_string(),
                    format!(
                        "differs from {}: shards of different sweeps cannot be merged",
                        first.join("sweep.json").display()
                    ),
                ))
            }
        }
    }
    let Some((_, text)) = definition else {
        return Err(Error::invalid(
            "sweep-merge",
            "needs at least one shard directory",
        ));
    };
    let plan = plan(&file::parse(
        &text,
        &first.join("sweep.json").display().to_string(),
    )?)?;
    let n = plan.points.len();
    let keys: BTreeMap<String, usize> = (0..n).map(|i| (plan.key(i), i)).collect();
    let mut by_index: BTreeMap<usize, (Record, PathBuf)> = BTreeMap::new();
    for dir in shards {
        for (index, record, path) in records(dir, &keys)? {
            let at = path.join(DONE).display().to_string();
            if record.index != index || index >= n {
                return Err(Error::invalid(
                    at,
                    format!(
                        "records point p{} in directory p{index}, but the sweep has points p0 … p{}",
                        record.index,
                        n - 1
                    ),
                ));
            }
            if record.values != plan.values(index) {
                return Err(Error::invalid(
                    at,
                    format!(
                        "its axis values differ from the sweep definition's point p{index} ({})",
                        plan.describe(index)
                    ),
                ));
            }
            // done.json is a copy of its run's summary.json row: they must agree, so an
            // edited or stale done.json is not merged as a result.
            let summary_path = path.join("summary.json");
            let summary: Value = std::fs::read_to_string(&summary_path)
                .map_err(|e| e.to_string())
                .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()))
                .map_err(|e| {
                    Error::invalid(&at, format!("its run's summary.json cannot be read: {e}"))
                })?;
            let row = Row::from_summary(&summary, &summary_path)?;
            if row != record.row {
                return Err(Error::invalid(
                    at,
                    format!(
                        "does not match its run's summary.json (digest {} vs {}, mean cost \
                         {:?} vs {:?}): rerun the point with --resume after removing done.json",
                        record.row.digest, row.digest, record.row.mean_cost, row.mean_cost
                    ),
                ));
            }
            if let Some((_, other)) = by_index.get(&index) {
                return Err(Error::invalid(
                    format!("point p{index}"),
                    format!(
                        "done in two shard directories: {} and {}",
                        other.display(),
                        path.display()
                    ),
                ));
            }
            by_index.insert(index, (record, path));
        }
    }
    let missing: Vec<String> = (0..n)
        .filter(|i| !by_index.contains_key(i))
        .map(|i| format!("p{i}"))
        .collect();
    if !missing.is_empty() {
        let shown = missing
            .iter()
            .take(10)
            .cloned()
            .collect::<Vec<_>>()
            .join(", ");
        let more = if missing.len() > 10 { ", …" } else { "" };
        return Err(Error::invalid(
            "sweep-merge",
            format!(
                "{} of {n} points are not done in the given directories: {shown}{more} (run their shards, or --resume them)",
                missing.len()
            ),
        ));
    }
    let records: Vec<Record> = by_index.into_values().map(|(r, _)| r).collect();
    if let Some(r) = records
        .iter()
        .find(|r| r.base_digest != records[0].base_digest)
    {
        return Err(Error::invalid(
            format!("point p{}", r.index),
            format!(
                "ran on another base scenario than point p0 (base digest {} vs {})",
                r.base_digest, records[0].base_digest
            ),
        ));
    }
    create_out_dir(out)?;
    write_atomic(&out.join("sweep.json"), text.as_bytes())?;
    super::write_outputs(out, &plan, &records)?;
    Ok(MergeReport {
        name: plan.name,
        points: n,
        diverged: records.iter().filter(|r| r.row.status != "ok").count(),
    })
}
