//! What a finished point leaves behind: its row of `sweep.csv` read from the run's
//! `summary.json` ([`Row::from_summary`]), and the marker `done.json` ([`Record`]) that
//! carries the row with the point's definition.
//!
//! `sweep.csv` is always written from `done.json` records read back from disk, by the
//! sweep and by `sweep-merge` alike, so both give the same bytes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{Error, Result};
use crate::output::write_atomic;

/// One channel's delays, averaged over the run's measurement windows [s].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelRow {
    /// Channel name.
    pub name: String,
    /// Mean requested delay [s].
    pub tau_requested: Option<f64>,
    /// Mean achieved delay [s].
    pub tau_achieved: Option<f64>,
}

/// A controlled run's live method against one baseline over the windows where both
/// were measured (summary.json → `paired.<baseline>`, method §5). `None` is a value
/// the run did not give (no window, or fewer than 2 for the interval).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairedRow {
    /// Windows where both were measured.
    pub n: Option<u64>,
    /// Windows where the live method was lower.
    pub wins: Option<u64>,
    /// Windows where the live method was higher.
    pub losses: Option<u64>,
    /// Ratio of the two means over those windows.
    pub ratio: Option<f64>,
    /// Mean paired difference (live − baseline).
    pub mean_difference: Option<f64>,
    /// 95 % confidence interval of the mean difference.
    pub ci95: Option<[f64; 2]>,
    /// Two-sided exact sign test of wins against losses.
    pub sign_test_p: Option<f64>,
    /// `better`, `worse` or `not_significant`.
    pub verdict: Option<String>,
}

impl PairedRow {
    /// Reads one comparison of summary.json's `paired` (missing keys stay `None`).
    fn from_summary(v: &Value) -> PairedRow {
        let f = |k: &str| v.get(k).and_then(Value::as_f64);
        let u = |k: &str| v.get(k).and_then(Value::as_u64);
        let ci95 = v.get("ci95").and_then(Value::as_array).and_then(|a| {
            match (
                a.first().and_then(Value::as_f64),
                a.get(1).and_then(Value::as_f64),
            ) {
                (Some(lo), Some(hi)) => Some([lo, hi]),
                _ => None,
            }
        });
        PairedRow {
            n: u("n"),
            wins: u("wins"),
            losses: u("losses"),
            ratio: f("ratio"),
            mean_difference: f("mean_difference"),
            ci95,
            sign_test_p: f("sign_test_p"),
            verdict: v.get("verdict").and_then(Value::as_str).map(str::to_string),
        }
    }
}

/// Where and when a diverged point failed (summary.json → `divergence`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DivergenceRow {
    /// Simulated time of the failing step [s].
    pub time: Option<f64>,
    /// Computing node, 1-based as printed (0 on a monolithic run).
    pub node: Option<u64>,
    /// The failing link (`L14`) or unlinked body (`B3`).
    pub place: Option<String>,
}

/// The measured part of one row of `sweep.csv`. `None` is a value the run did not
/// produce (an empty CSV field).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Row {
    /// `ok` or `diverged`.
    pub status: String,
    /// Where a diverged run failed (absent for a run that finished).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub divergence: Option<DivergenceRow>,
    /// Mean window cost [m].
    pub mean_cost: Option<f64>,
    /// `unpaired_mean_cost_<method>` of a controlled run, by method [m]: each method's
    /// mean over its own windows, not a comparison (that is `paired`).
    pub unpaired_mean_cost_by_method: BTreeMap<String, Option<f64>>,
    /// A controlled run's live method against each baseline over the windows where
    /// both were measured (`summary.json`'s `paired`), by baseline. Empty for a run
    /// without a controller.
    #[serde(default)]
    pub paired: BTreeMap<String, PairedRow>,
    /// The live method of a controlled run (`controller.method`).
    #[serde(default)]
    pub live_method: Option<String>,
    /// Frames lost on a TDMA network (0 on ideal channels).
    pub lost_frames: u64,
    /// Per channel, in the run's order.
    pub channels: Vec<ChannelRow>,
    /// Mean bandwidth used Σ k/τ [1/s].
    pub bandwidth: Option<f64>,
    /// Trace digest (hex).
    pub digest: String,
}

impl Row {
    /// Reads a row from a run's `summary.json` (as JSON). `what` names the file in
    /// errors.
    ///
    /// `lost_frames` absent counts as 0; a channel without `tau_requested` /
    /// `tau_achieved` (or with `null`, a run without windows) uses its `tau` for both;
    /// without `bandwidth_mean` the bandwidth is Σ k/τ over the channels (k default 1).
    pub fn from_summary(summary: &Value, what: &Path) -> Result<Row> {
        let bad = |m: &str| Error::invalid(what.display().to_string(), m.to_string());
        let obj = summary
            .as_object()
            .ok_or_else(|| bad("not a run summary (not a JSON object)"))?;
        let text = |key: &str| {
            obj.get(key)
                .and_then(Value::as_str)
                .map(str::to_string)
                .ok_or_else(|| bad(&format!("not a run summary (no `{key}`)")))
        };
        let unpaired_mean_cost_by_method = obj
            .iter()
            .filter_map(|(k, v)| {
                Some((
                    k.strip_prefix("unpaired_mean_cost_")?.to_string(),
                    v.as_f64(),
                ))
            })
            .collect();
        let paired = obj
            .get("paired")
            .and_then(Value::as_object)
            .map(|m| {
                m.iter()
                    .map(|(k, v)| (k.clone(), PairedRow::from_summary(v)))
                    .collect()
            })
            .unwrap_or_default();
        let live_method = obj
            .get("controller")
            .and_then(|c| c.get("method"))
            .and_then(Value::as_str)
            .map(str::to_string);
        let mut channels = Vec::new();
        let mut bandwidth_sum = Some(0.0);
        for (i, c) in obj
            .get("channels")
            .and_then(Value::as_array)
            .map(Vec::as_slice)
            .unwrap_or_default()
            .iter()
            .enumerate()
        {
            let name = c
                .get("name")
                .and_then(Value::as_str)
                .ok_or_else(|| bad(&format!("channels[{i}] has no name")))?;
            let tau = c.get("tau").and_then(Value::as_f64);
            let get = |k: &str| c.get(k).and_then(Value::as_f64).or(tau);
            let k = c.get("k").and_then(Value::as_f64).unwrap_or(1.0);
            bandwidth_sum = match (bandwidth_sum, tau) {
                (Some(s), Some(t)) if t > 0.0 => Some(s + k / t),
                _ => None,
            };
            channels.push(ChannelRow {
                name: name.to_string(),
                tau_requested: get("tau_requested"),
                tau_achieved: get("tau_achieved"),
            });
        }
        let bandwidth = obj
            .get("bandwidth_mean")
            .and_then(Value::as_f64)
            .or(bandwidth_sum);
        let divergence = obj
            .get("divergence")
            .filter(|d| d.is_object())
            .map(|d| DivergenceRow {
                time: d.get("time").and_then(Value::as_f64),
                node: d.get("node").and_then(Value::as_u64),
                place: ["link", "body"]
                    .iter()
                    .find_map(|k| d.get(*k).and_then(Value::as_str))
                    .map(str::to_string),
            });
        Ok(Row {
            status: text("status")?,
            divergence,
            mean_cost: obj.get("mean_cost").and_then(Value::as_f64),
            unpaired_mean_cost_by_method,
            paired,
            live_method,
            lost_frames: obj.get("lost_frames").and_then(Value::as_u64).unwrap_or(0),
            channels,
            bandwidth,
            digest: text("digest")?,
        })
    }
}

/// The content of `points/<key>/done.json`: the point's definition and its row.
/// Written last, atomically, once every file of the point's run is in place.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Record {
    /// Index of the point.
    pub index: usize,
    /// Its axis values, in axis order.
    pub values: Vec<Value>,
    /// Its scenario's seed.
    pub seed: u64,
    /// BLAKE3 (hex) of its scenario text (`points/<key>/scenario.json`).
    pub scenario_digest: String,
    /// BLAKE3 (hex) of the base scenario file's bytes.
    pub base_digest: String,
    /// What the run measured.
    pub row: Row,
    /// Wall-clock time of the run [s]; goes to `timing.csv` only.
    pub wall_seconds: f64,
}

impl Record {
    /// Whether this record is of the same point definition: axis values, seed and
    /// scenario text (not the index, which moves when an axis gains a value).
    pub fn same_point(&self, other: &Record) -> bool {
        self.values == other.values
            && self.seed == other.seed
            && self.scenario_digest == other.scenario_digest
    }

    /// Writes the record into `dir/done.json`, atomically.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let path = dir.join(DONE);
        let mut text = serde_json::to_string_pretty(self)
            .map_err(|e| Error::io(&path, std::io::Error::other(e)))?;
        text.push('\n');
        write_atomic(&path, text.as_bytes())
    }

    /// Reads `dir/done.json`: `Ok(None)` if absent, an error naming the file if it is
    /// not a record.
    pub fn read(dir: &Path) -> Result<Option<Record>> {
        let path = dir.join(DONE);
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(Error::io(&path, e)),
        };
        serde_json::from_str(&text).map(Some).map_err(|e| {
            Error::invalid(
                path.display().to_string(),
                format!("not a sweep point record: {e}"),
            )
        })
    }
}

/// File name of the marker of a finished point.
pub const DONE: &str = "done.json";

/// Directory of the point with key `key` ([`super::points::Plan::key`]) under a sweep's
/// output directory: `points/<key>`.
pub fn point_dir(out: &Path, key: &str) -> PathBuf {
    out.join("points").join(key)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn row_of_an_ideal_run() {
        let s = json!({
            "status": "ok", "digest": "ab", "mean_cost": 0.25, "lost_frames": 0,
            "channels": [{"name": "tau1", "tau": 0.005, "k": 1.0}, {"name": "tau2", "tau": 0.01, "k": 2.0}],
        });
        let r = Row::from_summary(&s, Path::new("summary.json")).unwrap();
        assert_eq!(r.channels[0].tau_requested, Some(0.005));
        assert_eq!(r.channels[1].tau_achieved, Some(0.01));
        assert_eq!(r.bandwidth, Some(1.0 / 0.005 + 2.0 / 0.01));
        assert!(r.unpaired_mean_cost_by_method.is_empty());
    }

    #[test]
    fn row_of_a_controlled_tdma_run() {
        let s = json!({
            "status": "diverged", "digest": "cd", "mean_cost": 1.5, "lost_frames": 3,
            "unpaired_mean_cost_dsm": 1.5, "unpaired_mean_cost_grid": null, "bandwidth_mean": 400.0,
            "channels": [{"name": "c", "tau": 0.005, "tau_requested": 0.004, "tau_achieved": 0.0045}],
        });
        let r = Row::from_summary(&s, Path::new("summary.json")).unwrap();
        assert_eq!(r.divergence, None, "no `divergence` object: none");
        assert_eq!(r.lost_frames, 3);
        assert_eq!(r.bandwidth, Some(400.0));
        assert_eq!(r.channels[0].tau_requested, Some(0.004));
        assert_eq!(
            r.unpaired_mean_cost_by_method,
            BTreeMap::from([("dsm".to_string(), Some(1.5)), ("grid".to_string(), None)])
        );
    }

    #[test]
    fn a_diverged_run_says_where() {
        let s = json!({
            "status": "diverged", "digest": "cd", "channels": [],
            "divergence": {"time": 3.12, "node": 2, "link": "L14", "body": null, "what": "|w| = 1.1 m"},
        });
        let r = Row::from_summary(&s, Path::new("summary.json")).unwrap();
        assert_eq!(
            r.divergence,
            Some(DivergenceRow {
                time: Some(3.12),
                node: Some(2),
                place: Some("L14".into())
            })
        );
    }

    #[test]
    fn not_a_summary_is_an_error() {
        let e = Row::from_summary(&json!([1]), Path::new("x/summary.json")).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("x/summary.json: not a run summary"),
            "{e}"
        );
    }
}
