//! Helpers shared by the benches that print ratios from one criterion run.

use std::path::PathBuf;
use std::time::SystemTime;

use serde_json::Value;

/// Median time [ns] criterion recorded for `group/case` since `since`, if it ran in
/// this run (an older estimate on disk is ignored).
pub fn median(group: &str, case: &str, since: SystemTime) -> Option<f64> {
    let home = std::env::var_os("CRITERION_HOME")
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("CARGO_TARGET_DIR").map(|d| PathBuf::from(d).join("criterion"))
        })
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/criterion"));
    let path = home.join(group).join(case).join("new/estimates.json");
    if std::fs::metadata(&path).ok()?.modified().ok()? < since {
        return None;
    }
    let v: Value = serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()?;
    v["median"]["point_estimate"].as_f64()
}
