//! The sweep file as written: plain serde structs that mirror the JSON, every one denying
//! unknown keys. Nothing here checks values; [`super::points::plan`] does that once.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{Error, Result};

/// A whole sweep file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// The JSON Schema this file follows (`"$schema": "../../docs/schema/sweep.schema.json"`),
    /// for editors' completion and checks; optional, ignored by the tool.
    #[serde(rename = "$schema", default, skip_serializing_if = "Option::is_none")]
    pub schema: Option<String>,
    /// Name of the sweep; point `i` is named `<name>_p<i>`. Required, not empty.
    pub name: String,
    /// The base scenario file, relative to the sweep file's directory (or absolute).
    pub base: String,
    /// How the axes combine into points; default `factorial`.
    #[serde(default)]
    pub combine: Combine,
    /// The swept fields, at least one.
    pub axes: Vec<AxisFile>,
    /// Runs of each configuration, on seeds derived from the configuration and the
    /// repetition (a `rep` column in `sweep.csv`); default 1. Not with an axis on
    /// `/seed`.
    #[serde(default = "one")]
    pub repeat: i64,
    /// Fixed values set on every point before the axes, keyed by JSON pointer (applied
    /// in the pointers' sorted order, so a parent before its children); default none.
    #[serde(default)]
    pub overrides: BTreeMap<String, Value>,
}

fn one() -> i64 {
    1
}

/// How axes combine.
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Combine {
    /// Every combination of values; the last axis varies fastest.
    #[default]
    Factorial,
    /// The i-th values of all axes together; all axes need the same length.
    Zip,
}

/// One swept field: exactly one of `values` and `range`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AxisFile {
    /// Column name in `sweep.csv`: `[A-Za-z0-9_.-]`, unique.
    pub name: String,
    /// RFC 6901 JSON pointer into the scenario (`/channels/0/tau`).
    pub pointer: String,
    /// The values, any JSON (numbers, strings, arrays, objects).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub values: Option<Vec<Value>>,
    /// Evenly spaced numbers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<RangeFile>,
    /// Optional short names of the values, one per value, used in plot legends instead
    /// of the values themselves (useful when the values are long lists or objects).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub labels: Option<Vec<String>>,
}

/// `steps` evenly spaced numbers from `from` to `to`, both included.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RangeFile {
    /// First value.
    pub from: f64,
    /// Last value.
    pub to: f64,
    /// Number of values, ≥ 1 (1 gives `from` alone).
    pub steps: i64,
}

/// Parses sweep JSON; `label` names the file in syntax errors.
///
/// Syntax errors are [`Error::Parse`] with line and column; a wrong type, a missing key
/// or an unknown key is an [`Error::Invalid`] naming the field (`axes[1].range.steps`).
pub fn parse(text: &str, label: &str) -> Result<SweepFile> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut de = serde_json::Deserializer::from_str(text);
    let file: SweepFile = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let path = e.path().to_string();
        serde_error(e.inner(), &path, label)
    })?;
    de.end().map_err(|e| serde_error(&e, ".", label))?;
    Ok(file)
}

/// Reads and parses the sweep file at `path`, returning it with its bytes.
pub fn load(path: &Path) -> Result<(SweepFile, String)> {
    let text = crate::input::read_text(path)?;
    let file = parse(&text, &path.display().to_string())?;
    Ok((file, text))
}

/// Maps a serde_json error at `path` to a one-line [`Error`].
fn serde_error(err: &serde_json::Error, path: &str, label: &str) -> Error {
    use serde_json::error::Category;
    let (line, column) = (err.line(), err.column().max(1));
    let full = err.to_string();
    let message = full
        .strip_suffix(&format!(" at line {} column {}", err.line(), err.column()))
        .unwrap_or(&full)
        .replace(['\n', '\r'], " ");
    let path = (path != "." && path != "?").then(|| path.to_string());
    match err.classify() {
        Category::Data => Error::Invalid {
            path: path.unwrap_or_else(|| "top level".to_string()),
            message: format!("{message} (line {line}, column {column})"),
        },
        Category::Syntax | Category::Eof | Category::Io => Error::Parse {
            file: label.to_string(),
            message,
            line,
            column,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        parse(text, "s.json").unwrap_err().to_string()
    }

    #[test]
    fn minimal_file_parses_with_defaults() {
        let f = parse(
            r#"{"name": "s", "base": "b.json", "axes": [{"name": "a", "pointer": "/dt", "values": [1]}]}"#,
            "s.json",
        )
        .unwrap();
        assert_eq!(f.combine, Combine::Factorial);
        assert!(f.overrides.is_empty());
        assert_eq!(f.axes[0].values.as_deref(), Some(&[Value::from(1)][..]));
    }

    #[test]
    fn unknown_keys_are_named() {
        let m = err(r#"{"name": "s", "base": "b", "axes": [], "colour": 1}"#);
        assert!(m.contains("colour"), "{m}");
        let m = err(
            r#"{"name": "s", "base": "b", "axes": [{"name": "a", "pointer": "/x", "valeus": [1]}]}"#,
        );
        assert!(m.contains("axes[0]") && m.contains("valeus"), "{m}");
    }

    #[test]
    fn wrong_types_name_the_field() {
        let m = err(
            r#"{"name": "s", "base": "b", "axes": [{"name": "a", "pointer": "/x", "range": {"from": 0, "to": 1, "steps": 2.5}}]}"#,
        );
        assert!(m.starts_with("axes[0].range.steps:"), "{m}");
        let m = err(r#"{"name": "s", "base": "b", "combine": "cartesian", "axes": []}"#);
        assert!(m.starts_with("combine:"), "{m}");
    }

    #[test]
    fn syntax_errors_name_the_file() {
        let e = parse("{\"name\": ", "s.json").unwrap_err();
        assert!(matches!(e, Error::Parse { .. }), "{e}");
        assert!(e.to_string().starts_with("s.json:"), "{e}");
    }
}
