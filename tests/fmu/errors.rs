//! What a user gets wrong about FMUs in a scenario, and what the run does when an FMU
//! fails: a clear error naming the field, the FMU and the variable (exit 2, nothing
//! written), or exit 3 naming the FMU, the function and the time.

use std::path::Path;
use std::process::Command;

use serde_json::{json, Value};

use crate::fmus::scratch;

use crate::fmu_build::{build_test_fmu, fmus_dir, write_zip};

/// A loop of msd (`plant`) and pd (`ctrl`) over one channel `c`.
fn base() -> Value {
    json!({
        "name": "errors", "seed": 1, "duration": 1.0, "dt": 0.001,
        "fmus": [
            {"name": "plant", "path": "msd.fmu", "node": 1},
            {"name": "ctrl", "path": "pd.fmu", "node": 2}
        ],
        "channels": [{"name": "c", "tau": 0.001, "latency": 0.0}],
        "connections": [
            {"from": "plant.x", "to": "ctrl.x", "channel": "c"},
            {"from": "ctrl.u", "to": "plant.F", "channel": "c"}
        ]
    })
}

/// The error of loading `v` from `dir` (where the FMUs are), as `path: message`.
fn error(dir: &Path, v: &Value) -> String {
    let path = dir.join("scenario.json");
    std::fs::write(&path, v.to_string()).unwrap();
    match dsmcosim::scenario::load(&path) {
        Ok(_) => panic!("accepted: {v}"),
        Err(e) => e.to_string(),
    }
}

/// `v` with the value at `pointer` set to `x` (an object's key is added if missing).
fn set(mut v: Value, pointer: &str, x: Value) -> Value {
    let (parent, key) = pointer.rsplit_once('/').expect("a pointer");
    let parent = v.pointer_mut(parent).unwrap_or_else(|| panic!("{pointer}"));
    match parent {
        Value::Array(items) => items[key.parse::<usize>().expect("an index")] = x,
        Value::Object(map) => {
            map.insert(key.to_string(), x);
        }
        _ => panic!("{pointer}"),
    }
    v
}

#[test]
fn each_mistake_is_named_by_its_field_its_fmu_and_its_variable() {
    let dir = scratch("fmu-errors", "validation");
    for id in ["msd", "pd", "faulty"] {
        build_test_fmu(id, &dir).unwrap();
    }
    let cases: Vec<(Value, &str, &str)> = vec![
        (
            set(base(), "/connections/0/from", json!("plant.xx")),
            "connections[0].from:",
            "FMU \"plant\" has no variable \"xx\"; did you mean \"x\"?",
        ),
        (
            set(base(), "/connections/0/from", json!("ctrl.x")),
            "connections[0].from:",
            "variable \"x\" has causality Input; a connection reads an Output",
        ),
        (
            set(base(), "/connections/1/to", json!("plant.x")),
            "connections[1].to:",
            "variable \"x\" has causality Output; a connection writes an Input",
        ),
        (
            set(base(), "/connections/0/from", json!("nobody.x")),
            "connections[0].from:",
            "unknown FMU \"nobody\" (fmus: ctrl, plant)",
        ),
        (
            set(base(), "/connections/0/from", json!("plant")),
            "connections[0].from:",
            "must read <fmu>.<variable>",
        ),
        (
            set(base(), "/connections/0/channel", json!("d")),
            "connections[0].channel:",
            "unknown channel \"d\" (channels: c)",
        ),
        (
            set(base(), "/connections/1/to", json!("ctrl.x")),
            "connections[1].to:",
            "\"ctrl.x\" is already fed by connections[0]",
        ),
        (
            set(base(), "/fmus/0/path", json!("missing.fmu")),
            "fmus[0].path:",
            "missing.fmu",
        ),
        (
            set(base(), "/fmus/0/step", json!(0.0015)),
            "fmus[0].step:",
            "must divide dt or be a whole multiple of it",
        ),
        (
            set(base(), "/fmus/0/node", json!(0)),
            "fmus[0].node:",
            "numbered from 1",
        ),
        (
            set(base(), "/fmus/1/name", json!("plant")),
            "fmus[1].name:",
            "duplicate name \"plant\"",
        ),
        (
            set(base(), "/fmus/0/name", json!("B2")),
            "fmus[0].name:",
            "reads as a body",
        ),
        (
            set(base(), "/fmus/0/start", json!({"x": 1.0})),
            "fmus[0].start.x:",
            "has causality Output; only parameters and inputs take start values",
        ),
        (
            set(
                set(base(), "/fmus/0/path", json!("faulty.fmu")),
                "/fmus/0/start",
                json!({"crash": 0.5}),
            ),
            "fmus[0].start.crash:",
            "\"crash\" is Integer: a whole number from -2147483648 to 2147483647 (got 0.5)",
        ),
        (
            set(
                set(base(), "/fmus/0/path", json!("faulty.fmu")),
                "/connections/0/from",
                json!("plant.crash"),
            ),
            "connections[0].from:",
            "variable \"crash\" has causality Parameter; a connection reads an Output",
        ),
        (
            set(base(), "/fmus/0/trace", json!(["F"])),
            "fmus[0].trace[0]:",
            "\"F\" is not an output (causality Input, type Real)",
        ),
        (
            set(base(), "/measurement", json!({"signals": ["plant.q"]})),
            "measurement.signals[0]:",
            "has no variable \"q\"",
        ),
        (
            set(base(), "/connections/0/from", json!("B1.px")),
            "connections[0].from:",
            "no body with id 1",
        ),
    ];
    for (v, path, message) in cases {
        let e = error(&dir, &v);
        assert!(
            e.starts_with(path) && e.contains(message),
            "want `{path} … {message}`, got `{e}`"
        );
    }
}

#[test]
fn an_fmu_without_a_binary_for_this_platform_lists_the_ones_it_has() {
    let dir = scratch("fmu-errors", "platform");
    build_test_fmu("pd", &dir).unwrap();
    let dll = dir.join("msd.dll");
    std::fs::write(&dll, b"MZ").unwrap();
    write_zip(
        &dir.join("msd.fmu"),
        &[
            ("modelDescription.xml".into(), fmus_dir().join("msd.xml")),
            ("binaries/win64/msd.dll".into(), dll),
        ],
    )
    .unwrap();
    let e = error(&dir, &base());
    assert!(
        e.starts_with("fmus[0].path:") && e.contains("win64") && e.contains("linux64"),
        "{e}"
    );
}

fn dsmcosim(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .args(args)
        .output()
        .expect("run dsmcosim")
}

#[test]
fn on_the_command_line_a_bad_fmu_scene_exits_2_and_writes_nothing() {
    let dir = scratch("fmu-errors", "cli-invalid");
    for id in ["msd", "pd"] {
        build_test_fmu(id, &dir).unwrap();
    }
    let path = dir.join("scenario.json");
    let v = set(base(), "/connections/0/from", json!("plant.xx"));
    std::fs::write(&path, v.to_string()).unwrap();
    let out = dir.join("out");
    let o = dsmcosim(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("connections[0].from") && stderr.contains("\"xx\""),
        "{stderr}"
    );
    assert!(!out.exists(), "a refused scene writes nothing");
}

#[test]
fn an_fmu_that_returns_an_error_stops_the_run_with_exit_3_naming_it() {
    let dir = scratch("fmu-errors", "cli-status");
    for id in ["faulty", "pd"] {
        build_test_fmu(id, &dir).unwrap();
    }
    let v = set(
        set(base(), "/fmus/0/path", json!("faulty.fmu")),
        "/fmus/0/start",
        json!({"fail_at": 0.25}),
    );
    let path = dir.join("scenario.json");
    std::fs::write(&path, v.to_string()).unwrap();
    let out = dir.join("out");
    let o = dsmcosim(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("FMU 'plant': fmi2DoStep returned fmi2Error at t = 0.25 s"),
        "{stderr}"
    );
    let summary: Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "fmu_error");
    assert!(summary["error"].as_str().unwrap().contains("fmi2DoStep"));
}

#[test]
fn a_crash_inside_an_fmu_kills_the_run_by_its_signal_and_is_no_panic() {
    let dir = scratch("fmu-errors", "cli-crash");
    for id in ["faulty", "pd"] {
        build_test_fmu(id, &dir).unwrap();
    }
    let v = set(
        set(base(), "/fmus/0/path", json!("faulty.fmu")),
        "/fmus/0/start",
        json!({"crash": 1}),
    );
    let path = dir.join("scenario.json");
    std::fs::write(&path, v.to_string()).unwrap();
    let out = dir.join("out");
    let o = dsmcosim(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(o.status.signal(), Some(11), "{:?} {stderr}", o.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
    // The outputs are written atomically at the end: none is there.
    for f in ["summary.json", "trace.csv", "epochs.csv"] {
        assert!(!out.join(f).exists(), "{f} after a crash");
    }
}

/// pd.fmu built into `dir` from pd.xml with `from` replaced by `to` (a variant of its
/// description; the binary is pd's).
fn pd_variant(dir: &Path, from: &str, to: &str) {
    let xml = std::fs::read_to_string(fmus_dir().join("pd.xml")).unwrap();
    assert!(xml.contains(from), "pd.xml has {from}");
    let variant = dir.join("pd_variant.xml");
    std::fs::write(&variant, xml.replace(from, to)).unwrap();
    crate::fmu_build::build_fmu(
        &fmus_dir().join("pd.c"),
        &variant,
        "pd",
        &dir.join("pd.fmu"),
    )
    .expect("build the pd variant");
}

#[test]
fn two_variables_of_one_name_are_refused_at_load_naming_both() {
    let dir = scratch("fmu-errors", "duplicate-names");
    build_test_fmu("msd", &dir).unwrap();
    // pd's input v renamed x: two variables called x (the 4th and the 5th).
    pd_variant(&dir, "name=\"v\"", "name=\"x\"");
    let e = error(&dir, &base());
    assert!(
        e.starts_with("fmus[1].path:")
            && e.contains(
                "ModelVariables: variables 4 and 5 (1-based, in document order) are both \
                 named \"x\""
            ),
        "{e}"
    );
}

#[test]
fn two_connections_to_inputs_sharing_a_value_reference_are_refused_naming_both() {
    let dir = scratch("fmu-errors", "shared-reference");
    build_test_fmu("msd", &dir).unwrap();
    // pd's input v given x's value reference (3): an alias of x in the FMU.
    pd_variant(
        &dir,
        "name=\"v\" valueReference=\"4\"",
        "name=\"v\" valueReference=\"3\"",
    );
    let mut v = base();
    v["connections"]
        .as_array_mut()
        .unwrap()
        .push(json!({"from": "plant.v", "to": "ctrl.v", "channel": "c"}));
    let e = error(&dir, &v);
    assert_eq!(
        e,
        "connections[2].to: input \"v\" of FMU \"ctrl\" has value reference 3, as input \
         \"x\" fed by connections[0] does: the FMU holds one value for both, so one of the \
         two connections would be lost"
    );
    // Alone, each of the two inputs can be fed.
    let alone = set(base(), "/connections/0/to", json!("ctrl.v"));
    std::fs::write(dir.join("scenario.json"), alone.to_string()).unwrap();
    dsmcosim::scenario::load(&dir.join("scenario.json")).expect("one connection to v");
}

#[test]
fn a_misspelt_channel_is_named_as_unknown_with_the_nearest_name() {
    let dir = scratch("fmu-errors", "misspelt-channel");
    for id in ["msd", "pd"] {
        build_test_fmu(id, &dir).unwrap();
    }
    // Both connections misspell the one channel: it is unused, yet the error is the
    // connection's, not "channel "sense" carries no message".
    let mut v = set(base(), "/channels/0/name", json!("sense"));
    for k in 0..2 {
        v = set(v, &format!("/connections/{k}/channel"), json!("sens"));
    }
    assert_eq!(
        error(&dir, &v),
        "connections[0].channel: unknown channel \"sens\" (channels: sense); did you mean \
         \"sense\"?"
    );
    // Nothing close: the channels listed, no guess.
    let v = set(v, "/connections/0/channel", json!("actuator"));
    assert_eq!(
        error(&dir, &v),
        "connections[0].channel: unknown channel \"actuator\" (channels: sense)"
    );
}

#[test]
fn a_missing_test_fmu_says_how_to_build_it_into_its_folder() {
    let dir = scratch("fmu-errors", "missing-test-fmu");
    build_test_fmu("pd", &dir).unwrap();
    // As on a fresh clone: a shipped scene reads fmu/<stem>.fmu beside it, not built yet.
    for stem in crate::fmu_build::TEST_FMUS {
        let v = set(base(), "/fmus/0/path", json!(format!("fmu/{stem}.fmu")));
        let e = error(&dir, &v);
        let build = format!(
            "build them into that folder with `cargo run --release --example build_fmus -- {}` \
             (needs a C compiler)",
            dir.join("fmu").display()
        );
        assert!(e.starts_with("fmus[0].path:") && e.contains(&build), "{e}");
    }
    // A missing FMU of the user's own: no such hint.
    let e = error(&dir, &set(base(), "/fmus/0/path", json!("fmu/mine.fmu")));
    assert!(
        e.starts_with("fmus[0].path:") && !e.contains("build_fmus"),
        "{e}"
    );
}
