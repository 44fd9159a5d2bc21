//! The JSON verdict of a batch check (`dsmcosim check … --json FILE`).
//!
//! ```text
//! { "tool": "dsmcosim", "version": "0.1.0",
//!   "against": "results/", "layout": "by_name" | "single", "tolerance": null | X,
//!   "exit_code": 4,
//!   "totals": { "scenarios", "match", "mismatch", "missing", "error",
//!               "wall_seconds",                // the check's own, start to end
//!               "summed_seconds" },            // the scenarios' times added up
//!   "scenarios": [ {                       // in argument order
//!     "name", "scenario" (file), "stored" (dir), "new" (dir or null),
//!     "status": "match" | "mismatch" | "missing" | "error",
//!     "identical": true | false | null,    // false: a match only within the tolerance
//!     "digest": { "stored", "new", "equal" } | null,
//!     "first_difference": { "file", "kind", …, "text" } | null,
//!     "message",                           // what the command prints for it
//!     "wall_seconds" } ] }
//! ```
//!
//! `first_difference.kind` is `value` (with `row`, `time_column`, `time`, `column`,
//! `stored`, `new`, `abs`, `rel`), `header` (`column_index`, `stored`, `new`: column
//! names or null), `fields` (`row`, `time_column`, `time`, `stored`, `new`: field
//! counts) or `rows` (`stored`, `new`: row counts; `row`, `time_column`, `time` of the
//! first extra row). Wall seconds are the only wall-clock values.

use serde_json::{json, Value};

use super::batch::{Batch, Outcome};
use super::Verdict;
use crate::trace::compare::{Difference, DifferenceKind, Record, Tolerance};

/// The JSON verdict of `batch`, pretty-printed, with a final newline.
pub fn render(batch: &Batch) -> String {
    let mut text = serde_json::to_string_pretty(&value(batch)).unwrap_or_default();
    text.push('\n');
    text
}

/// The JSON verdict of `batch` as a value.
pub fn value(batch: &Batch) -> Value {
    let t = batch.totals();
    json!({
        "tool": "dsmcosim",
        "version": env!("CARGO_PKG_VERSION"),
        "against": batch.against.display().to_string(),
        "layout": batch.layout.name(),
        "tolerance": match batch.tolerance {
            Tolerance::Exact => Value::Null,
            Tolerance::Relative(x) => json!(x),
        },
        "exit_code": batch.exit_code(),
        "totals": {
            "scenarios": t.scenarios,
            "match": t.matched,
            "mismatch": t.mismatched,
            "missing": t.missing,
            "error": t.errors,
            "wall_seconds": batch.wall_seconds(),
            "summed_seconds": batch.summed_seconds(),
        },
        "scenarios": batch.outcomes.iter().map(outcome).collect::<Vec<_>>(),
    })
}

fn outcome(o: &Outcome) -> Value {
    let report = o.result.as_ref().ok();
    json!({
        "name": o.name,
        "scenario": o.scenario.display().to_string(),
        "stored": o.stored.display().to_string(),
        "new": o.new.as_ref().map(|d| d.display().to_string()),
        "status": o.status().name(),
        "identical": report.map(|r| r.verdict() == Verdict::Match),
        "digest": report.map(|r| json!({
            "stored": r.stored.digest,
            "new": r.new.digest,
            "equal": r.digests_equal(),
        })),
        "first_difference": o.first_difference().map(difference),
        "message": o.text(),
        "wall_seconds": o.wall_seconds,
    })
}

fn record(fields: &mut serde_json::Map<String, Value>, at: &Record) {
    fields.insert("row".into(), json!(at.row));
    fields.insert("time_column".into(), json!(at.time_column));
    fields.insert("time".into(), json!(at.time));
}

/// A first differing record as JSON (see the module docs).
pub fn difference(d: &Difference) -> Value {
    let mut f = serde_json::Map::new();
    f.insert("file".into(), json!(d.file));
    match &d.kind {
        DifferenceKind::Value {
            at,
            column,
            stored,
            new,
            abs,
            rel,
        } => {
            f.insert("kind".into(), json!("value"));
            record(&mut f, at);
            f.insert("column".into(), json!(column));
            f.insert("stored".into(), json!(stored));
            f.insert("new".into(), json!(new));
            f.insert("abs".into(), json!(abs));
            f.insert("rel".into(), json!(rel));
        }
        DifferenceKind::Header {
            column,
            stored,
            new,
        } => {
            f.insert("kind".into(), json!("header"));
            f.insert("column_index".into(), json!(column));
            f.insert("stored".into(), json!(stored));
            f.insert("new".into(), json!(new));
        }
        DifferenceKind::Fields { at, stored, new } => {
            f.insert("kind".into(), json!("fields"));
            record(&mut f, at);
            f.insert("stored".into(), json!(stored));
            f.insert("new".into(), json!(new));
        }
        DifferenceKind::Rows {
            stored,
            new,
            first_extra,
        } => {
            f.insert("kind".into(), json!("rows"));
            record(&mut f, first_extra);
            f.insert("stored".into(), json!(stored));
            f.insert("new".into(), json!(new));
        }
    }
    f.insert("text".into(), json!(d.to_string()));
    Value::Object(f)
}
