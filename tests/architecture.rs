//! Imports run one way, down the stages (docs/architecture.md, "Stages"): every
//! `crate::…` path in the library's non-test code names a module of its own stage or of
//! a lower one. A path that names a higher stage fails here with the file and line, so
//! a cycle between stages cannot come back unnoticed.

use std::path::{Path, PathBuf};

/// The stages, lowest first. A module of the crate (a top-level module, or for
/// `scenario` its submodule) is in exactly one.
const STAGES: &[(&str, &[&str])] = &[
    (
        "foundation",
        &[
            "kernel",
            "error",
            "input",
            "output",
            "progress",
            "interrupt",
            "console",
            "fmu",
        ],
    ),
    (
        "the scene's data",
        &["scenario::model", "scenario::file", "scenario::grid"],
    ),
    ("network", &["network"]),
    ("dynamics and partitions", &["multibody", "partition"]),
    ("delay control", &["control"]),
    ("the world", &["cosim"]),
    ("recording", &["trace", "report"]),
    (
        "reading a scenario",
        &["scenario", "scenario::validate", "scenario::overrides"],
    ),
    ("checkpoints", &["checkpoint"]),
    ("a run", &["run"]),
    (
        "studies and tools",
        &[
            "sweep",
            "tradeoff",
            "coupling_study",
            "check",
            "distance",
            "schema",
        ],
    ),
    ("the command line", &["cli", "main", "lib"]),
];

fn stage_of(module: &str) -> Option<usize> {
    STAGES
        .iter()
        .position(|(_, modules)| modules.contains(&module))
}

/// The module a source file belongs to: `src/cosim/world.rs` → `cosim`,
/// `src/scenario/validate/network.rs` → `scenario::validate`.
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).expect("under src");
    let parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    match parts.as_slice() {
        [top, sub, ..] if top == "scenario" => format!("scenario::{sub}"),
        [top, ..] => top.clone(),
        [] => unreachable!("a file has a name"),
    }
}

/// The module a `crate::` path names: its first segment, or for `scenario` the
/// submodule (the scenario module's own items: `Scenario` is the model's, the rest —
/// `parse_str`, `load`, … — the reading stage's).
fn target_of(path: &str) -> String {
    let mut segments = path.split("::");
    let top = segments.next().unwrap_or_default().to_string();
    if matches!(top.as_str(), "Error" | "Result") {
        // The crate root's re-exports of the error module.
        return "error".into();
    }
    if top != "scenario" {
        return top;
    }
    match segments.next() {
        Some(sub @ ("model" | "file" | "grid" | "validate" | "overrides")) => {
            format!("scenario::{sub}")
        }
        Some("Scenario") => "scenario::model".into(),
        _ => "scenario".into(),
    }
}

/// Every `crate::a::b…` path on a line of code (comments removed), with a `{…}` group
/// expanded into its items (`crate::scenario::{parse_str, Scenario}` → two paths).
fn paths_in(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        rest = &rest[i + "crate::".len()..];
        let end = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
            .unwrap_or(rest.len());
        let path = rest[..end].trim_end_matches(':');
        if rest[end..].starts_with('{') && path.ends_with("scenario") {
            let group = &rest[end + 1..rest[end..].find('}').map_or(rest.len(), |j| end + j)];
            for item in group.split(',') {
                out.push(format!("{path}::{}", item.trim()));
            }
        } else {
            out.push(path.to_string());
        }
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable src") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn imports_run_down_the_stages() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut checked = 0;
    let mut upward = Vec::new();
    for file in &files {
        if file.file_name().is_some_and(|n| n == "tests.rs") {
            continue;
        }
        let module = module_of(&src, file);
        let from = stage_of(&module)
            .unwrap_or_else(|| panic!("{}: module `{module}` is in no stage", file.display()));
        let text = std::fs::read_to_string(file).expect("readable source");
        // The unit tests at a file's end may use any stage.
        let code = text.split("#[cfg(test)]").next().unwrap_or_default();
        for (n, line) in code.lines().enumerate() {
            let code = line.split("//").next().unwrap_or_default();
            for path in paths_in(code) {
                let target = target_of(&path);
                if target == module || module.starts_with(&format!("{target}::")) {
                    continue;
                }
                let to = stage_of(&target).unwrap_or_else(|| {
                    panic!(
                        "{}:{}: `crate::{path}` is in no stage",
                        file.display(),
                        n + 1
                    )
                });
                checked += 1;
                if to > from {
                    upward.push(format!(
                        "{}:{}: `{module}` ({}) imports `crate::{path}` ({})",
                        file.display(),
                        n + 1,
                        STAGES[from].0,
                        STAGES[to].0
                    ));
                }
            }
        }
    }
    assert!(
        checked > 300,
        "only {checked} paths found: is the scan reading src?"
    );
    assert!(
        upward.is_empty(),
        "imports up the stages:\n{}",
        upward.join("\n")
    );
}

#[test]
fn the_scan_sees_groups_and_the_scenario_modules_stages() {
    assert_eq!(
        paths_in("use crate::scenario::{parse_str, Scenario}; // crate::run"),
        vec!["scenario::parse_str", "scenario::Scenario", "run"]
    );
    assert_eq!(target_of("scenario::Scenario"), "scenario::model");
    assert_eq!(target_of("scenario::parse_str"), "scenario");
    assert_eq!(target_of("scenario::model::ChannelSpec"), "scenario::model");
    assert_eq!(target_of("cosim::world::CoSim"), "cosim");
    // An upward path is seen as one: the world importing a run.
    let (from, to) = (stage_of("cosim"), stage_of(&target_of("run::run")));
    assert!(from < to);
}
