//! `--set POINTER=VALUE`: changing values of a scenario file from the command line
//! (ns-3's `--param=value`, OMNeT++'s `--param=value` ini override).
//!
//! Each override is a JSON pointer (RFC 6901, `/channels/0/tau`) and a value: JSON
//! (`0.004`, `"rk4"`, `{"kind": "ideal"}`), or, where the text is not JSON, the text as
//! a string (`--set /integrator=rk4`). Overrides apply in the order given, to the file's
//! JSON before it is parsed and validated, so an overridden scenario is checked exactly
//! like a file. A pointer's parent must exist; its last key may be new on an object
//! (validation then names a key it does not know) and its last index must exist on an
//! array.

use std::path::Path;

use serde_json::Value;

use super::model::Scenario;
use crate::error::{Error, Result};
use crate::input::pointer::Pointer;

/// Most `--set` overrides on one command line.
pub const MAX_OVERRIDES: usize = 1000;

/// Makes the relative FMU paths of the scenario JSON `json`, read from the file at
/// `path`, relative to the working directory instead of the file's directory, so that
/// a variant the studies (`tradeoff`, `stability-map`, `coupling`) build from the JSON
/// and validate without a file reads the same FMUs as the file does. A path that is
/// absolute, or whose directory is not UTF-8, is left as it is.
pub fn anchor_fmu_paths(json: &mut Value, path: &Path) {
    let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) else {
        return;
    };
    map_relative_fmu_paths(json, |file| dir.join(file).to_str().map(str::to_string));
}

/// Replaces each relative `fmus[].path` of `json` by `new(path)` where that gives one;
/// whether any was replaced.
fn map_relative_fmu_paths(json: &mut Value, mut new: impl FnMut(&str) -> Option<String>) -> bool {
    let Some(fmus) = json.get_mut("fmus").and_then(Value::as_array_mut) else {
        return false;
    };
    let mut changed = false;
    for fmu in fmus {
        let Some(Value::String(file)) = fmu.get_mut("path") else {
            continue;
        };
        if Path::new(file.as_str()).is_relative() {
            if let Some(replaced) = new(file) {
                *file = replaced;
                changed = true;
            }
        }
    }
    changed
}

/// The scenario text `text`, read from the file at `path`, as a copy kept in the
/// directory `dir` must read to load the same FMUs: each relative `fmus[].path`
/// rewritten relative to `dir`. `None` where no path needs to change (no FMUs, only
/// absolute paths, or `dir` beside the file), or where the text is not JSON or a file
/// cannot be found (the copy is then kept as it is).
///
/// *Why*: a run directory keeps its scenario as `scenario.json`; with the file's
/// `fmu/pd.fmu` kept as it was, `dsmcosim run RUN/scenario.json` looked for
/// `RUN/fmu/pd.fmu` and could not rerun an FMU scene.
pub fn relocated_fmu_paths(text: &str, path: &Path, dir: &Path) -> Option<String> {
    let from = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let (from, to) = (
        std::fs::canonicalize(from).ok()?,
        std::fs::canonicalize(dir).ok()?,
    );
    if from == to {
        return None;
    }
    let mut json: Value = serde_json::from_str(text).ok()?;
    let mut missing = false;
    let changed = map_relative_fmu_paths(&mut json, |file| {
        let relative = std::fs::canonicalize(from.join(file))
            .ok()
            .and_then(|target| pathdiff::diff_paths(target, &to))
            .and_then(|r| r.to_str().map(str::to_string));
        missing |= relative.is_none();
        relative
    });
    if missing {
        return None;
    }
    changed.then(|| {
        let mut out = serde_json::to_string_pretty(&json).unwrap_or_else(|_| text.to_string());
        out.push('\n');
        out
    })
}

/// The scenario of the file at `path` with `sets` applied, and its JSON text (what the
/// run directory keeps as `scenario.json`). Without overrides the text is the file's
/// own bytes.
pub fn load_with(path: &Path, sets: &[String]) -> Result<(Scenario, String)> {
    if sets.is_empty() {
        // Read once: a second read of a pipe would find nothing.
        let bytes = crate::input::read(path)?;
        let Ok(text) = String::from_utf8(bytes) else {
            // Not UTF-8: the plain loader says where.
            return super::load(path).map(|s| (s, String::new()));
        };
        let label = path.display().to_string();
        let scenario = super::validate::parse_at(&text, &label, Some(path))?;
        return Ok((scenario, text));
    }
    let Ok(text) = crate::input::read_text(path) else {
        // Not readable or not UTF-8: the plain loader says which, and where.
        return super::load(path).map(|s| (s, String::new()));
    };
    let label = path.display().to_string();
    text_with(&text, &label, Some(path), sets)
}

/// The scenario of the JSON `text` with `sets` applied, and its text (the given text
/// without overrides), as [`load_with`] does for a file; `label` names the source in
/// errors and `path` (if any) is where relative FMU paths are read from (the library's
/// callers that hold a scenario in memory, such as the Python package, use it).
pub fn text_with(
    text: &str,
    label: &str,
    path: Option<&Path>,
    sets: &[String],
) -> Result<(Scenario, String)> {
    if sets.is_empty() {
        let scenario = super::validate::parse_at(text, label, path)?;
        return Ok((scenario, text.to_string()));
    }
    if sets.len() > MAX_OVERRIDES {
        return Err(Error::invalid(
            "--set",
            format!("{} overrides; at most {MAX_OVERRIDES}", sets.len()),
        ));
    }
    let body = text.strip_prefix('\u{feff}').unwrap_or(text);
    let Ok(mut doc) = serde_json::from_str::<Value>(body) else {
        // A syntax error: the plain parser names its line and column.
        return super::validate::parse_at(text, label, path).map(|s| (s, text.to_string()));
    };
    for set in sets {
        apply(&mut doc, set)?;
    }
    let mut text =
        serde_json::to_string_pretty(&doc).map_err(|e| Error::invalid("--set", e.to_string()))?;
    text.push('\n');
    let label = format!("{label} with --set");
    let scenario = super::validate::parse_at(&text, &label, path).map_err(|e| locate(e, sets))?;
    Ok((scenario, text))
}

/// An error in the overridden scenario, told against what the user wrote: a line and
/// column would point into the rewritten JSON, which the user never saw, so they give
/// way to the override that set the field (or, for a field no override set, to a note
/// that the overrides were applied).
fn locate(e: Error, sets: &[String]) -> Error {
    let Error::Invalid { path, message } = e else {
        return e;
    };
    let message = without_position(message);
    let message = match set_for(&path, sets) {
        Some(set) => format!("{message} (set by `--set {set}`)"),
        None => format!("{message} (in the file with the --set overrides applied)"),
    };
    Error::Invalid { path, message }
}

/// `message` without a trailing `(line L, column C)`, which would point into JSON that
/// the overrides rewrote.
fn without_position(message: String) -> String {
    match message.rfind(" (line ") {
        Some(at) if message.ends_with(')') => message[..at].to_string(),
        _ => message,
    }
}

/// The last of `sets` whose pointer names the field `path` (`channels[0].tau`).
fn set_for<'a>(path: &str, sets: &'a [String]) -> Option<&'a String> {
    sets.iter().rev().find(|set| {
        set.split_once('=')
            .is_some_and(|(pointer, _)| pointer_as_path(pointer) == path)
    })
}

/// A validation error of a scenario built from a file with `sets` applied and then
/// changed further (a sweep's points): when an override set the field the error names,
/// the error names that override instead of a position in the rewritten JSON;
/// otherwise it is returned as it was. `later` lists the pointers set after the
/// overrides (the sweep's own overrides and axes), which then own the field.
pub(crate) fn name_override(e: Error, sets: &[String], later: &[String]) -> Error {
    let Error::Invalid { path, message } = e else {
        return e;
    };
    let owned_later = later.iter().any(|p| pointer_as_path(p) == path);
    match set_for(&path, sets) {
        Some(set) if !owned_later => Error::Invalid {
            message: format!("{} (set by `--set {set}`)", without_position(message)),
            path,
        },
        _ => Error::Invalid { path, message },
    }
}

/// A JSON pointer written as the dotted path errors name fields by: `/channels/0/tau`
/// is `channels[0].tau`.
fn pointer_as_path(pointer: &str) -> String {
    let mut path = String::new();
    for part in pointer.split('/').skip(1) {
        let part = part.replace("~1", "/").replace("~0", "~");
        if part.parse::<usize>().is_ok() {
            path.push_str(&format!("[{part}]"));
        } else {
            if !path.is_empty() {
                path.push('.');
            }
            path.push_str(&part);
        }
    }
    path
}

/// Applies one `POINTER=VALUE` to `doc`; errors name `--set` and the override.
pub fn apply(doc: &mut Value, set: &str) -> Result<()> {
    let bad = |m: String| Error::invalid(format!("--set {set}"), m);
    let (pointer, value) = set
        .split_once('=')
        .ok_or_else(|| bad("must be POINTER=VALUE, e.g. /channels/0/tau=0.004".into()))?;
    let pointer = Pointer::parse(pointer).map_err(bad)?;
    let value: Value =
        serde_json::from_str(value).unwrap_or_else(|_| Value::String(value.to_string()));
    pointer.set(doc, value).map(|_| ()).map_err(bad)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_scenario_in_memory_takes_overrides_as_a_file_does() {
        let text = r#"{"name": "m", "seed": 1, "duration": 1.0, "dt": 0.001,
            "model": {"grid": {"rows": 2, "cols": 2, "spacing": 1.0, "mass": 1.0,
            "size": 0.1}}}"#;
        let (plain, same) = text_with(text, "mem", None, &[]).unwrap();
        assert_eq!(same, text, "without overrides the text is kept as given");
        let (s, rewritten) = text_with(text, "mem", None, &["/duration=2.0".into()]).unwrap();
        assert_eq!(s.steps, 2 * plain.steps);
        assert!(rewritten.contains("\"duration\": 2.0"));
        let e = text_with(text, "mem", None, &["/dt=-1".into()]).unwrap_err();
        assert!(
            e.to_string().contains("dt") && e.to_string().contains("--set /dt=-1"),
            "{e}"
        );
    }

    #[test]
    fn a_pointer_reads_as_the_path_errors_name() {
        assert_eq!(pointer_as_path("/channels/0/tau"), "channels[0].tau");
        assert_eq!(pointer_as_path("/integrator"), "integrator");
        assert_eq!(
            pointer_as_path("/model/bodies/3/mass"),
            "model.bodies[3].mass"
        );
    }

    #[test]
    fn values_are_json_or_else_text() {
        let mut doc = json!({"a": {"b": 1}, "list": [1, 2], "x~/y": 0});
        apply(&mut doc, "/a/b=2.5").unwrap();
        apply(&mut doc, "/a/c=rk4").unwrap();
        apply(&mut doc, r#"/a/d={"kind": "ideal"}"#).unwrap();
        apply(&mut doc, "/list/1=\"s\"").unwrap();
        apply(&mut doc, "/x~0~1y=3").unwrap();
        assert_eq!(
            doc,
            json!({"a": {"b": 2.5, "c": "rk4", "d": {"kind": "ideal"}}, "list": [1, "s"], "x~/y": 3})
        );
    }

    #[test]
    fn bad_overrides_are_named() {
        let mut doc = json!({"a": {"b": 1}, "list": [1]});
        for (set, want) in [
            ("/a/b", "must be POINTER=VALUE"),
            ("a/b=1", "must start with `/`"),
            (
                "/nope/b=1",
                "no key `nope` in the top level, so the parent /nope does not exist",
            ),
            ("/list/3=1", "an array of 1"),
            ("/list/+0=1", "no element `+0`"),
            ("/a/b/c=1", "/a/b is a number, not an object or array"),
            ("/a~2=1", "bad escape `~2`"),
        ] {
            let e = apply(&mut doc, set).unwrap_err().to_string();
            assert!(e.starts_with(&format!("--set {set}: ")), "{e}");
            assert!(e.contains(want), "{set}: {e}");
        }
    }
}
