//! Bad scenario files: every one is rejected with a one-line error naming the field, and
//! never panics. Plus a property test: any valid explicit scenario survives a JSON round
//! trip and validates to the same `Scenario`.
//!
//! Each bad file is the valid `base()` with one change, so a case is one line (the case
//! tables are exempt from rustfmt to keep it that way).

use dsmcosim::scenario::file::{
    BodyFile, BodyModelFile, ChannelFile, DataKindFile, DivergenceFile, ForceFile, GhostsFile,
    GridFile, IntegratorFile, LinkFile, LinkOwnerFile, MeasurementFile, ModelFile, NetworkFile,
    OutputFile, PartitionFile, ScenarioFile, SolverFile, SolverKind, StabilizerFile,
    StabilizerKind,
};
use dsmcosim::scenario::model::{Solver, Stabilizer};
use dsmcosim::scenario::validate::{parse_file, validate};
use dsmcosim::scenario::{load, parse_str};
use dsmcosim::Error;
use proptest::prelude::*;
use serde_json::{json, Value};

#[path = "../support/fmu_build.rs"]
mod fmu_build;

/// A valid explicit scenario that sets every section.
fn base() -> Value {
    json!({
        "name": "base",
        "seed": 42,
        "duration": 2.0,
        "dt": 0.001,
        "integrator": "rk4",
        "stabilizer": {"kind": "smc", "mu": 0.05, "k": 10, "epsilon": 0.1},
        "solver": {"kind": "cg", "max_iterations": 20, "tolerance": 1e-8},
        "body_model": "auto",
        "model": {
            "bodies": [
                {"id": 1, "mass": 1, "size": 0.2, "position": [0, 0, 0]},
                {"id": 2, "mass": 1, "size": 0.2, "position": [1.8, 0, 0],
                 "velocity": [0, 0, 0], "orientation": [1, 0, 0, 0],
                 "angular_velocity": [0, 0, 0], "inertia": [0.1, 0.1, 0.1]},
                {"id": 3, "mass": 1, "size": 0.2, "position": [1.8, 1.8, 0]}
            ],
            "links": [
                {"a": 1, "b": 2, "length": 1.8},
                {"a": 2, "b": 3, "anchor_a": [0, 0, 0], "anchor_b": [0, 0, 0]}
            ]
        },
        "forces": [
            {"body": 1, "amplitude": [0, 0, 20], "omega": 2, "phase": 0, "from": 0, "until": 1},
            {"body": 3, "amplitude": [0, 0, 20], "omega": 2, "from": 1}
        ],
        "divergence": {"max_violation": 0.5},
        "measurement": {"period": 0.5},
        "output": {"decimation": 5, "trace_bodies": [1, 3], "plot_bodies": [3]}
    })
}

/// The thesis grid, minimal.
fn grid_base() -> Value {
    json!({
        "name": "grid", "seed": 7, "duration": 1.0, "dt": 0.001,
        "model": {"grid": {"rows": 4, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}}
    })
}

/// The thesis grid in quadrants (ring 1–2–3–4–1), states on `tau1`, forces on `tau2`.
fn part_base() -> Value {
    let mut doc = grid_base();
    doc["partition"] = json!({"quadrants": true, "ghosts": "integrate"});
    doc["network"] = json!({"kind": "ideal"});
    doc["channels"] = json!([
        {"name": "tau1", "tau": 0.005, "latency": 0.005, "k": 1.0, "kinds": ["state"]},
        {"name": "tau2", "tau": 0.01, "kinds": ["force"]}
    ]);
    doc
}

/// The thesis layout as explicit node lists (same nodes as the quadrants).
fn thesis_nodes() -> Value {
    json!([
        [1, 2, 5, 6],
        [3, 4, 7, 8],
        [11, 12, 15, 16],
        [9, 10, 13, 14]
    ])
}

/// Sets (or adds) the value at a JSON pointer such as `/model/bodies/0/mass`.
fn put(mut doc: Value, pointer: &str, value: Value) -> Value {
    let (parent, key) = pointer.rsplit_once('/').expect("pointer starts with /");
    let target = doc.pointer_mut(parent).expect("parent exists in the base");
    match target {
        Value::Object(map) => {
            map.insert(key.to_string(), value);
        }
        Value::Array(items) => items[key.parse::<usize>().expect("array index")] = value,
        _ => panic!("{parent} is not a container"),
    }
    doc
}

/// `base()` with one value set.
fn set(pointer: &str, value: Value) -> String {
    put(base(), pointer, value).to_string()
}

/// `grid_base()` with one value set.
fn set_grid(pointer: &str, value: Value) -> String {
    put(grid_base(), pointer, value).to_string()
}

/// `part_base()` with one value set.
fn set_part(pointer: &str, value: Value) -> String {
    put(part_base(), pointer, value).to_string()
}

/// `base()` with one key removed.
fn remove(pointer: &str) -> String {
    remove_from(base(), pointer)
}

/// `part_base()` with one key removed.
fn remove_part(pointer: &str) -> String {
    remove_from(part_base(), pointer)
}

/// `doc` with one key removed.
fn remove_from(mut doc: Value, pointer: &str) -> String {
    let (parent, key) = pointer.rsplit_once('/').expect("pointer starts with /");
    let removed = match doc.pointer_mut(parent).expect("parent exists") {
        Value::Object(map) => map.remove(key),
        _ => None,
    };
    assert!(removed.is_some(), "{pointer} is not in the base");
    doc.to_string()
}

/// Rejected as `Invalid` at a path containing `path`, with a message containing
/// `what`, on one line.
#[track_caller]
fn invalid(text: String, path: &str, what: &str) {
    match parse_str(&text, "case.json") {
        Err(e @ Error::Invalid { .. }) => check(&e, path, what),
        Err(e) => panic!("expected an Invalid error at {path}, got {e:?}"),
        Ok(_) => panic!("expected an Invalid error at {path}, but the file validated"),
    }
}

/// Rejected as `Parse` (with a line and column) naming `path` (may be empty).
#[track_caller]
fn parse_error(text: &str, path: &str, what: &str) {
    match parse_str(text, "case.json") {
        Err(e @ Error::Parse { line, column, .. }) => {
            assert!(line >= 1 && column >= 1, "{e}");
            check(&e, path, what);
        }
        Err(e) => panic!("expected a Parse error, got {e:?}"),
        Ok(_) => panic!("expected a Parse error, but the file validated"),
    }
}

/// `validate` (without JSON, so values JSON cannot hold) rejects at `path`.
#[track_caller]
fn invalid_file(file: ScenarioFile, path: &str, what: &str) {
    match validate(file) {
        Err(e @ Error::Invalid { .. }) => check(&e, path, what),
        Err(e) => panic!("expected an Invalid error at {path}, got {e:?}"),
        Ok(_) => panic!("expected an Invalid error at {path}, but the file validated"),
    }
}

#[track_caller]
fn check(e: &Error, path: &str, what: &str) {
    let shown = e.to_string();
    assert!(!shown.contains('\n'), "not one line: {shown:?}");
    assert_eq!(e.exit_code(), 2, "{shown}");
    if let Error::Invalid { path: p, .. } = e {
        assert!(
            p.contains(path),
            "path {p:?} does not name {path:?}: {shown}"
        );
    }
    assert!(shown.contains(path), "{shown:?} does not name {path:?}");
    assert!(shown.contains(what), "{shown:?} does not say {what:?}");
}

#[test]
fn the_bases_are_valid() {
    let s = parse_str(&base().to_string(), "base.json").unwrap();
    assert_eq!((s.bodies.len(), s.links.len(), s.forces.len()), (3, 2, 2));
    assert_eq!(s.steps, 2000);
    let g = parse_str(&grid_base().to_string(), "grid.json").unwrap();
    assert_eq!((g.bodies.len(), g.links.len()), (16, 24));
}

#[test]
fn shipped_scenarios_load() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let scratch = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("shipped_load");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            // A scene with FMUs reads them beside it: from the test FMUs built here.
            let path =
                fmu_build::beside_test_fmus(&path, &scratch).unwrap_or_else(|e| panic!("{e}"));
            if let Err(e) = load(&path) {
                panic!("{}: {e}", path.display());
            }
            count += 1;
        }
    }
    assert!(count > 0, "no scenario files in {}", dir.display());
}

#[test]
fn unreadable_files_are_reported() {
    let missing = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("no_such_file.json");
    assert!(matches!(load(&missing), Err(Error::Io { .. })));
    let latin1 = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("latin1.json");
    std::fs::write(&latin1, b"{\n  \"name\": \"caf\xe9\"}").unwrap();
    match load(&latin1) {
        Err(
            e @ Error::Parse {
                line: 2,
                column: 15,
                ..
            },
        ) => {
            assert!(e.to_string().contains("invalid UTF-8"), "{e}")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn malformed_json_reports_line_and_column() {
    let text = "{\n  \"name\": \"x\",\n  \"seed\": 1\n  \"dt\": 0.1\n}";
    match parse_str(text, "bad.json") {
        Err(e @ Error::Parse { .. }) => {
            assert_eq!(
                e.to_string(),
                "bad.json: expected `,` or `}` at line 4, column 3"
            );
        }
        other => panic!("{other:?}"),
    }
    parse_error("", "", "EOF");
    parse_error("{\"name\": \"x\",", "", "EOF");
    parse_error(&(base().to_string() + " {}"), "", "trailing characters");
    parse_error("{\"name\": \"x\" \"seed\": 1}", "", "expected");
    parse_error("{'name': 'x'}", "", "key must be a string");
}

#[test]
fn non_finite_numbers_are_rejected() {
    let text = |v: &str| {
        base()
            .to_string()
            .replace("\"mass\":1,", &format!("\"mass\":{v},"))
    };
    // The message quotes the bad value as written.
    parse_error(
        &text("1e999"),
        "model.bodies[0].mass",
        "number out of range: got `1e999`",
    );
    parse_error(
        &text("-1e999"),
        "model.bodies[0].mass",
        "number out of range: got `-1e999`",
    );
    parse_error(
        &text("NaN"),
        "model.bodies[0].mass",
        "got `NaN`, and JSON numbers must be finite",
    );
    parse_error(
        &text("Infinity"),
        "model.bodies[0].mass",
        "got `Infinity`, and JSON numbers must be finite",
    );
    let text = base()
        .to_string()
        .replace("\"duration\":2.0", "\"duration\":1e400");
    parse_error(&text, "duration", "number out of range");
}

#[test]
fn non_finite_values_built_in_code_are_rejected() {
    let file = || parse_file(&base().to_string(), "base.json").unwrap();
    let mut f = file();
    f.model.bodies.as_mut().unwrap()[0].mass = f64::NAN;
    invalid_file(f, "model.bodies[0].mass", "finite number (got NaN)");
    let mut f = file();
    f.model.bodies.as_mut().unwrap()[2].position[1] = f64::INFINITY;
    invalid_file(f, "model.bodies[2].position[1]", "got inf");
    let mut f = file();
    f.model.bodies.as_mut().unwrap()[1].angular_velocity[0] = f64::NEG_INFINITY;
    invalid_file(f, "model.bodies[1].angular_velocity[0]", "got -inf");
    let mut f = file();
    f.model.bodies.as_mut().unwrap()[1].orientation[3] = f64::NAN;
    invalid_file(f, "model.bodies[1].orientation[3]", "NaN");
    let mut f = file();
    f.forces[0].amplitude[2] = f64::NAN;
    invalid_file(f, "forces[0].amplitude[2]", "NaN");
    let mut f = file();
    f.forces[1].omega = f64::INFINITY;
    invalid_file(f, "forces[1].omega", "inf");
    let mut f = file();
    f.forces[0].until = Some(f64::NAN);
    invalid_file(f, "forces[0].until", "NaN");
    let mut f = file();
    f.dt = f64::NAN;
    invalid_file(f, "dt", "NaN");
    let mut f = file();
    f.model.links.as_mut().unwrap()[1].anchor_b[0] = f64::NAN;
    invalid_file(f, "model.links[1].anchor_b[0]", "NaN");
    let mut f = file();
    f.stabilizer = Some(StabilizerFile {
        epsilon: Some(f64::INFINITY),
        ..StabilizerFile::default()
    });
    invalid_file(f, "stabilizer.epsilon", "inf");
}

/// `part_base()` in 0.25-s windows with `schedule` set to `entries`.
fn scheduled(entries: Value) -> String {
    let mut doc = part_base();
    doc["measurement"] = json!({"period": 0.25});
    doc["schedule"] = entries;
    doc.to_string()
}

#[test]
#[rustfmt::skip]
fn a_schedule_sits_on_window_boundaries_with_a_period_per_channel() {
    let ok = |e: Value| parse_str(&scheduled(e), "case.json").unwrap_or_else(|e| panic!("{e}"));
    let s = ok(json!([{"at": 0, "tau": [0.004, 0.02]}, {"at": 0.5, "tau": [0.006, 0.01]}]));
    assert_eq!(s.schedule.len(), 2);
    assert_eq!(s.schedule[1].at.as_nanos(), 500_000_000);
    assert_eq!(s.schedule[1].tau, vec![0.006, 0.01]);
    invalid(scheduled(json!([{"at": 0.3, "tau": [0.004, 0.02]}])), "schedule[0].at", "window boundary");
    invalid(scheduled(json!([{"at": 1.0, "tau": [0.004, 0.02]}])), "schedule[0].at", "before duration");
    invalid(scheduled(json!([{"at": -0.25, "tau": [0.004, 0.02]}])), "schedule[0].at", "≥ 0");
    invalid(scheduled(json!([{"at": 0.5, "tau": [0.004, 0.02]}, {"at": 0.25, "tau": [0.004, 0.02]}])), "schedule[1].at", "later than schedule[0].at");
    invalid(scheduled(json!([{"at": 0.25, "tau": [0.004]}])), "schedule[0].tau", "one period per channel, 2 (got 1)");
    invalid(scheduled(json!([{"at": 0.25, "tau": [0.004, 0]}])), "schedule[0].tau[1]", "> 0");
    invalid(scheduled(json!([{"at": 0.25, "tau": [0.004, 0.01], "why": 1}])), "schedule[0].why", "unknown field");
    let mut doc: Value = serde_json::from_str(&scheduled(json!([{"at": 0.25, "tau": [0.004, 0.01]}]))).unwrap();
    doc["controller"] = json!({"problem": "cp", "budget": 400, "tau_max": 0.05});
    invalid(doc.to_string(), "schedule", "beside a `controller`");
    invalid(set("/schedule", json!([{"at": 0, "tau": [0.004]}])), "schedule", "needs `channels`");
}

#[test]
#[rustfmt::skip]
fn unknown_keys_are_rejected() {
    invalid(set_part("/partition/colour", json!(1)), "partition.colour", "unknown field `colour`");
    invalid(set_part("/partition/link_owners", json!([{"link": 3, "node": 2, "why": 1}])), "partition.link_owners[0].why", "unknown field");
    invalid(set_part("/network/slots", json!([])), "network.slots", "unknown field `slots`");
    invalid(set_part("/channels/1/period", json!(0.01)), "channels[1].period", "unknown field");
    invalid(set("/controller", json!({"problem": "cp", "tau_max": 0.05, "gain": 1})), "controller.gain", "unknown field");
    invalid(set("/model/bodies/1/colour", json!(1)), "model.bodies[1].colour", "unknown field");
    invalid(set("/model/links/0/stiffness", json!(1)), "model.links[0].stiffness", "unknown");
    invalid(set("/forces/1/to", json!(2)), "forces[1].to", "unknown field `to`");
    invalid(set("/stabilizer/gamma", json!(1)), "stabilizer.gamma", "unknown field");
    invalid(set("/solver/restart", json!(1)), "solver.restart", "unknown field");
    invalid(set("/output/format", json!("csv")), "output.format", "unknown field");
    invalid(set("/divergence/max_w", json!(1)), "divergence.max_w", "unknown field");
    invalid(set("/measurement/T", json!(1)), "measurement.T", "unknown field");
    invalid(set("/model/dampers", json!([])), "model.dampers", "unknown field");
    invalid(set_grid("/model/grid/depth", json!(1)), "model.grid.depth", "unknown field");
    // A key holding an escaped newline stays on one line.
    invalid(set("/se\ned", json!(1)), "se\\ned", "unknown field");
}

#[test]
#[rustfmt::skip]
fn wrong_types_are_rejected() {
    invalid(set("/model/bodies/2/mass", json!("1 kg")), "model.bodies[2].mass", "string");
    invalid(set("/seed", json!(-1)), "seed", "expected u64");
    invalid(set("/seed", json!(1.5)), "seed", "expected u64");
    invalid(set("/name", json!(7)), "name", "invalid type");
    invalid(set("/description", json!(["a"])), "description", "invalid type");
    invalid(set("/description", json!("x".repeat(4097))), "description", "4097 characters; at most 4096");
    invalid(set_part("/network/sample", json!("now")), "network.sample", "unknown variant");
    invalid(set_part("/network/sample", json!("previous_slot")), "network.sample", "not a key of kind \"ideal\"");
    invalid(set("/dt", json!("1ms")), "dt", "invalid type");
    invalid(set("/model/bodies/0/position", json!([0, 0])), "model.bodies[0].position", "length 2");
    invalid(set("/model/bodies/0/position", json!([0, 0, "z"])), "model.bodies[0].position[2]", "string");
    invalid(set("/model/bodies/0/id", json!(1.0)), "model.bodies[0].id", "expected u32");
    invalid(set("/model/links/0/a", json!("1")), "model.links[0].a", "invalid type");
    invalid(set("/integrator", json!("rk5")), "integrator", "unknown variant `rk5`");
    invalid(set("/body_model", json!("soft")), "body_model", "unknown variant");
    invalid(set("/stabilizer/kind", json!("pid")), "stabilizer.kind", "unknown variant");
    invalid(set("/solver/kind", json!("lu")), "solver.kind", "unknown variant");
    invalid(set("/forces", json!({})), "forces", "invalid type");
    invalid(set("/output/trace_bodies", json!([1, -3])), "output.trace_bodies[1]", "expected u32");
    invalid(set("/output/decimation", json!(-1)), "output.decimation", "expected u64");
    invalid(set_grid("/model/grid/rows", json!(-4)), "model.grid.rows", "expected u32");
    invalid(set_grid("/model/grid/cols", json!(2.5)), "model.grid.cols", "expected u32");
    invalid(remove("/model/bodies/1/mass"), "model.bodies[1]", "missing field `mass`");
    invalid(remove("/forces/0/amplitude"), "forces[0]", "missing field `amplitude`");
    invalid(remove("/stabilizer/kind"), "stabilizer", "missing field `kind`");
    invalid(remove("/seed"), "top level", "missing field `seed`");
    invalid(set_part("/partition/ghosts", json!("freeze")), "partition.ghosts", "unknown variant `freeze`");
    invalid(set_part("/partition/quadrants", json!("yes")), "partition.quadrants", "invalid type");
    invalid(set_part("/partition/nodes", json!([[1, -2]])), "partition.nodes[0][1]", "expected u32");
    invalid(set_part("/partition/nodes", json!([1, 2])), "partition.nodes[0]", "invalid type");
    invalid(set_part("/partition/link_owners", json!([{"link": 3}])), "partition.link_owners[0]", "missing field `node`");
    invalid(set_part("/network/kind", json!("carrier_pigeon")), "network.kind", "unknown variant");
    invalid(set_part("/network", json!({})), "network", "missing field `kind`");
    invalid(set_part("/channels/0/kinds", json!(["state", "torque"])), "channels[0].kinds[1]", "unknown variant `torque`");
    invalid(set_part("/channels/0/borders", json!([[1]])), "channels[0].borders[0]", "length 1");
    // serde_json reports a too-long fixed array as trailing characters, at the field.
    parse_error(&set_part("/channels/0/borders", json!([[1, 2, 3]])), "channels[0].borders[0]", "trailing characters");
    invalid(set_part("/channels/0/borders", json!([[1, -2]])), "channels[0].borders[0][1]", "expected usize");
    invalid(set_part("/channels/0/name", json!(1)), "channels[0].name", "invalid type");
    invalid(set_part("/channels", json!({"name": "tau1"})), "channels", "invalid type");
    invalid(remove_part("/channels/1/tau"), "channels[1]", "missing field `tau`");
    invalid(remove_part("/channels/0/name"), "channels[0]", "missing field `name`");
}

#[test]
#[rustfmt::skip]
fn null_is_never_a_default() {
    invalid(set("/model/bodies/0/mass", Value::Null), "model.bodies[0].mass", "null");
    invalid(set("/forces/0/until", Value::Null), "forces[0].until", "null");
    invalid(set("/forces/0/omega", Value::Null), "forces[0].omega", "null");
    invalid(set("/model/links/1/length", Value::Null), "model.links[1].length", "null");
    invalid(set("/model/bodies/1/inertia", Value::Null), "model.bodies[1].inertia", "null");
    invalid(set("/model/bodies/1/velocity", Value::Null), "model.bodies[1].velocity", "null");
    invalid(set("/stabilizer/mu", Value::Null), "stabilizer.mu", "null");
    invalid(set("/stabilizer", Value::Null), "stabilizer", "null");
    invalid(set("/forces", Value::Null), "forces", "null");
    invalid(set("/measurement/period", Value::Null), "measurement.period", "null");
    invalid(set("/output/plot_bodies", Value::Null), "output.plot_bodies", "null");
    invalid(set("/model/grid", Value::Null), "model.grid", "null");
    invalid(set_part("/partition", Value::Null), "partition", "null");
    invalid(set_part("/partition/nodes", Value::Null), "partition.nodes", "null");
    invalid(set_part("/partition/quadrants", Value::Null), "partition.quadrants", "null");
    // serde_json reads a unit variant from `null` as a syntax error, still at the field.
    parse_error(&set_part("/partition/ghosts", Value::Null), "partition.ghosts", "expected value");
    parse_error(&set_part("/network/kind", Value::Null), "network.kind", "expected value");
    invalid(set_part("/partition/link_owners", Value::Null), "partition.link_owners", "null");
    invalid(set_part("/network", Value::Null), "network", "null");
    invalid(set_part("/channels", Value::Null), "channels", "null");
    invalid(set_part("/channels/0/latency", Value::Null), "channels[0].latency", "null");
    invalid(set_part("/channels/0/k", Value::Null), "channels[0].k", "null");
    invalid(set_part("/channels/0/borders", Value::Null), "channels[0].borders", "null");
    invalid(set_part("/channels/1/kinds", Value::Null), "channels[1].kinds", "null");
}

#[test]
#[rustfmt::skip]
fn non_positive_physical_values_are_rejected() {
    invalid(set("/model/bodies/0/mass", json!(-1)), "model.bodies[0].mass", "must be > 0 (got -1)");
    invalid(set("/model/bodies/2/mass", json!(0)), "model.bodies[2].mass", "must be > 0 (got 0)");
    invalid(set("/model/bodies/1/size", json!(0)), "model.bodies[1].size", "must be > 0 (got 0)");
    invalid(set("/model/bodies/1/size", json!(-0.2)), "model.bodies[1].size", "got -0.2");
    invalid(set("/dt", json!(0)), "dt", "must be > 0 (got 0)");
    invalid(set("/dt", json!(-0.001)), "dt", "must be > 0 (got -0.001)");
    invalid(set("/duration", json!(0)), "duration", "must be > 0 (got 0)");
    invalid(set("/duration", json!(-30)), "duration", "must be > 0 (got -30)");
    invalid(set("/model/links/0/length", json!(0)), "model.links[0].length", "must be > 0");
    invalid(set("/model/links/0/length", json!(-1.8)), "model.links[0].length", "got -1.8");
    invalid(set("/stabilizer/epsilon", json!(0)), "stabilizer.epsilon", "must be > 0 (got 0)");
    invalid(set("/stabilizer/mu", json!(-0.05)), "stabilizer.mu", "must be > 0 (got -0.05)");
    invalid(set("/stabilizer/k", json!(0)), "stabilizer.k", "must be > 0 (got 0)");
    invalid(set("/model/bodies/1/inertia", json!([0.1, 0, 0.1])), "model.bodies[1].inertia[1]", "must be > 0 (got 0)");
    invalid(set("/model/bodies/1/inertia", json!([0.1, 0.1, -1])), "model.bodies[1].inertia[2]", "got -1");
    invalid(set("/divergence/max_violation", json!(0)), "divergence.max_violation", "must be > 0");
    invalid(set("/measurement/period", json!(0)), "measurement.period", "must be > 0 (got 0)");
    let tiny = put(base(), "/model/bodies/0/mass", json!(1e-90));
    let tiny = put(tiny, "/model/bodies/0/size", json!(1e-20)).to_string();
    invalid(tiny, "model.bodies[0].inertia", "the cube default m s²/6 is 1.6666666666666665e-131");
    // Masses and moments beyond 1e100 either way: their products leave f64.
    invalid(set("/model/bodies/0/mass", json!(1e-300)), "model.bodies[0].mass", "magnitude from 1e-100 to 1e100");
    invalid(set("/model/bodies/1/inertia", json!([0.1, 1e-310, 0.1])), "model.bodies[1].inertia[1]", "got 1e-310");
}

#[test]
#[rustfmt::skip]
fn time_step_and_duration_must_fit() {
    invalid(set("/dt", json!(3)), "dt", "must not exceed duration (got dt 3 s > duration 2 s)");
    invalid(set("/duration", json!(2.0005)), "duration", "whole number of dt steps");
    invalid(set("/dt", json!(0.0003)), "duration", "whole number of dt steps");
    invalid(set("/dt", json!(1e-10)), "dt", "at least 1 ns");
    invalid(set("/dt", json!(1.5e-9)), "dt", "whole number of nanoseconds");
    invalid(set("/duration", json!(1e12)), "duration", "range of simulated time");
    invalid(set("/measurement/period", json!(0.0015)), "measurement.period", "whole number of dt steps");
    invalid(set("/measurement/period", json!(3)), "measurement.period", "must not exceed duration");
}

#[test]
#[rustfmt::skip]
fn force_windows_are_checked() {
    invalid(set("/forces/0/until", json!(-1)), "forces[0].until", "must not be before from");
    invalid(set("/forces/1/until", json!(0.5)), "forces[1].until", "got until 0.5 s < from 1 s");
    invalid(set("/forces/1/from", json!(-1)), "forces[1].from", "must be ≥ 0 (got -1)");
    invalid(set("/forces/0/from", json!(-0.5)), "forces[0].from", "got -0.5");
}

#[test]
#[rustfmt::skip]
fn ids_must_resolve() {
    invalid(set("/forces/1/body", json!(9)), "forces[1].body", "no body with id 9");
    invalid(set("/model/links/0/a", json!(4)), "model.links[0].a", "no body with id 4");
    invalid(set("/model/links/1/b", json!(0)), "model.links[1].b", "no body with id 0");
    invalid(set("/model/links/1/b", json!(2)), "model.links[1].b", "cannot join body 2 to itself");
    invalid(set("/model/bodies/2/id", json!(1)), "model.bodies[2].id", "duplicate id 1");
    invalid(set("/output/trace_bodies", json!([1, 5])), "output.trace_bodies[1]", "no body with id 5");
    invalid(set("/output/plot_bodies", json!([7])), "output.plot_bodies[0]", "no body with id 7");
    invalid(set("/output/trace_bodies", json!([3, 1, 3])), "output.trace_bodies[2]", "listed twice");
    invalid(set_grid("/forces", json!([{"body": 17, "amplitude": [0, 0, 1]}])), "forces[0].body", "no body with id 17");
    invalid(set_grid("/output", json!({"plot_bodies": [1, 17]})), "output.plot_bodies[1]", "no body with id 17");
}

#[test]
#[rustfmt::skip]
fn orientations_and_anchors_are_checked() {
    invalid(set("/model/bodies/1/orientation", json!([0, 0, 0, 0])), "model.bodies[1].orientation", "zero quaternion");
    invalid(set("/model/bodies/1/orientation", json!([1, 0, 0])), "model.bodies[1].orientation", "length 3");
    let coincident = put(base(), "/model/bodies/2/position", json!([1.8, 0, 0])).to_string();
    invalid(coincident, "model.links[1].length", "coincide");
    // Off-centre anchors that meet in the world are coincident too.
    let meet = put(base(), "/model/links/1/anchor_a", json!([0, 0.9, 0]));
    let meet = put(meet, "/model/links/1/anchor_b", json!([0, -0.9, 0])).to_string();
    invalid(meet, "model.links[1].length", "coincide");
}

#[test]
fn explicit_point_mass_must_not_need_rotation() {
    let pm = put(base(), "/body_model", json!("point_mass"));
    let anchor = put(pm.clone(), "/model/links/1/anchor_a", json!([0, 0.1, 0])).to_string();
    invalid(anchor, "model.links[1].anchor_a", "point_mass");
    let spin = put(
        pm.clone(),
        "/model/bodies/2/angular_velocity",
        json!([0, 0, 1]),
    )
    .to_string();
    invalid(spin, "model.bodies[2].angular_velocity", "got [0, 0, 1]");
    assert!(parse_str(&pm.to_string(), "pm.json").is_ok());
}

#[test]
#[rustfmt::skip]
fn model_needs_exactly_one_form() {
    let grid = json!({"rows": 2, "cols": 2, "spacing": 1, "mass": 1, "size": 0.1});
    invalid(set("/model/grid", grid.clone()), "model", "not both");
    invalid(set("/model", json!({})), "model", "needs either `grid` or `bodies`");
    invalid(set("/model", json!({"links": []})), "model.links", "needs `bodies`");
    invalid(set("/model", json!({"grid": grid, "links": []})), "model", "not both");
    invalid(set("/model/bodies", json!([])), "model.bodies", "at least one body");
    invalid(remove("/model"), "model", "or leave `model` out in a scene of `fmus` only");
}

#[test]
#[rustfmt::skip]
fn grid_values_are_checked() {
    invalid(set_grid("/model/grid/rows", json!(0)), "model.grid.rows", "must be ≥ 1 (got 0)");
    invalid(set_grid("/model/grid/cols", json!(0)), "model.grid.cols", "must be ≥ 1 (got 0)");
    invalid(set_grid("/model/grid/spacing", json!(0)), "model.grid.spacing", "must be > 0 (got 0)");
    invalid(set_grid("/model/grid/spacing", json!(-1.8)), "model.grid.spacing", "got -1.8");
    invalid(set_grid("/model/grid/mass", json!(0)), "model.grid.mass", "must be > 0");
    invalid(set_grid("/model/grid/size", json!(-0.2)), "model.grid.size", "must be > 0");
    invalid(set_grid("/model/grid/rows", json!(1_000_000)), "model.grid.rows", "more than the limit");
}

#[test]
#[rustfmt::skip]
fn stabilizer_and_solver_sections_are_checked() {
    let baumgarte = |a: Value, b: Value| set("/stabilizer", json!({"kind": "baumgarte", "alpha": a, "beta": b}));
    assert!(parse_str(&baumgarte(json!(0), json!(0)), "b.json").is_ok());
    invalid(baumgarte(json!(-1), json!(5)), "stabilizer.alpha", "must be ≥ 0 (got -1)");
    invalid(baumgarte(json!(5), json!(-2)), "stabilizer.beta", "must be ≥ 0 (got -2)");
    // An omitted α or β takes the default of a jointed scene's law, 20 /s.
    let one = parse_str(&set("/stabilizer", json!({"kind": "baumgarte", "beta": 1})), "b.json").unwrap();
    assert_eq!(one.stabilizer, Stabilizer::Baumgarte { alpha: 20.0, beta: 1.0 });
    invalid(set("/stabilizer", json!({"kind": "baumgarte", "alpha": 1, "beta": 1, "mu": 0.1})), "stabilizer.mu", "not a key of kind \"baumgarte\"");
    invalid(set("/stabilizer/alpha", json!(1)), "stabilizer.alpha", "not a key of kind \"smc\"");
    invalid(set("/solver/max_iterations", json!(0)), "solver.max_iterations", "must be ≥ 1 (got 0)");
    invalid(set("/solver/tolerance", json!(-1e-9)), "solver.tolerance", "must be ≥ 0 (got -1e-9)");
    invalid(set("/solver", json!({"kind": "cholesky", "tolerance": 1e-6})), "solver.tolerance", "not a key of kind \"cholesky\"");
    let pcg = |v: Value| set("/solver", v);
    let s = parse_str(&pcg(json!({"kind": "cholesky_pcg"})), "p.json").unwrap();
    assert_eq!(s.solver, Solver::CholeskyPcg { refactor_every: 20, tolerance: 1e-8, max_iterations: 10 });
    invalid(pcg(json!({"kind": "cholesky_pcg", "refactor_every": 0})), "solver.refactor_every", "must be ≥ 1 (got 0)");
    invalid(pcg(json!({"kind": "cholesky_pcg", "max_iterations": 0})), "solver.max_iterations", "must be ≥ 1 (got 0)");
    invalid(pcg(json!({"kind": "cholesky_pcg", "tolerance": 0})), "solver.tolerance", "must be in (0, 1) for cholesky_pcg (got 0)");
    invalid(pcg(json!({"kind": "cholesky_pcg", "tolerance": 1})), "solver.tolerance", "must be in (0, 1) for cholesky_pcg (got 1)");
    invalid(pcg(json!({"kind": "cholesky_pcg", "refactor_every": -3})), "solver.refactor_every", "invalid value");
    invalid(pcg(json!({"kind": "cholesky", "refactor_every": 5})), "solver.refactor_every", "not a key of kind \"cholesky\"");
    invalid(pcg(json!({"kind": "cg", "refactor_every": 5})), "solver.refactor_every", "not a key of kind \"cg\"");
}

#[test]
fn partitioned_bases_are_valid() {
    let s = parse_str(&part_base().to_string(), "part.json").unwrap();
    let p = s.partition.as_ref().unwrap();
    assert_eq!((p.nodes, s.channels.len()), (4, 2));
    // The thesis layout written out, with the ring's owners for the four border links
    // the general rule gives to the other node (links 9, 11, 17, 23).
    let owners = json!([{"link": 9, "node": 4}, {"link": 11, "node": 4},
                        {"link": 17, "node": 3}, {"link": 23, "node": 3}]);
    let explicit = set_part(
        "/partition",
        json!({"nodes": thesis_nodes(), "link_owners": owners}),
    );
    assert_eq!(parse_str(&explicit, "e.json").unwrap(), s);
    // One node: no border links, no channels needed.
    let one = put(base(), "/partition", json!({"nodes": [[3, 1, 2]]})).to_string();
    let one = parse_str(&one, "one.json").unwrap();
    assert_eq!(one.partition.unwrap().node_of, vec![0, 0, 0]);
    // The thesis space distribution.
    let space = set_part(
        "/channels",
        json!([{"name": "tau1", "tau": 0.005, "borders": [[1, 2], [1, 4]]},
               {"name": "tau2", "tau": 0.005, "borders": [[3, 2], [3, 4]], "k": 2}]),
    );
    let space = parse_str(&space, "space.json").unwrap();
    assert_eq!(space.channels[1].borders, Some(vec![(1, 2), (2, 3)]));
    assert_eq!(space.channels[1].k, 2.0);
}

#[test]
#[rustfmt::skip]
fn partitions_are_checked() {
    invalid(set_part("/partition/nodes", thesis_nodes()), "partition", "not both");
    invalid(set_part("/partition", json!({"ghosts": "hold"})), "partition", "needs either `nodes` or");
    invalid(set_part("/partition", json!({"nodes": thesis_nodes(), "quadrants": false, "colour": 1})), "partition.colour", "unknown field");
    invalid(set("/partition", json!({"quadrants": true})), "partition.quadrants", "needs a `grid` model (got explicit `bodies`)");
    invalid(put(part_base(), "/model/grid/rows", json!(3)).to_string(), "partition.quadrants", "got a 3×4 grid");
    invalid(put(part_base(), "/model/grid/cols", json!(5)).to_string(), "partition.quadrants", "even number of rows and cols (got a 4×5 grid)");
    invalid(set("/partition", json!({"nodes": []})), "partition.nodes", "at least one node");
    invalid(set("/partition", json!({"nodes": [[1, 2], [], [3]]})), "partition.nodes[1]", "node 2 is empty");
    invalid(set("/partition", json!({"nodes": [[1, 2], [3, 99]]})), "partition.nodes[1][1]", "no body with id 99");
    invalid(set("/partition", json!({"nodes": [[1, 2], [2, 3]]})), "partition.nodes[1][0]", "body 2 is already in node 1");
    invalid(set("/partition", json!({"nodes": [[1], [3]]})), "partition.nodes", "body 2 is in no node");
    invalid(set_part("/partition", json!({"nodes": [[1, 2, 5, 6, 7], [3, 4, 8], [11, 7, 12, 15, 16], [9, 10, 13, 14]]})), "partition.nodes[2][1]", "body 7 is already in node 1");
    invalid(set_part("/partition", json!({"nodes": [[1, 2, 5, 6], [3, 4, 7, 8], [11, 12, 15, 16], [9, 10, 14]]})), "partition.nodes", "body 13 is in no node");
    invalid(set_part("/partition", json!({"nodes": [[1, 2, 5, 6], [3, 4, 7, 8]]})), "partition.nodes", "body 9 is in no node (nor are 7 more bodies)");
}

#[test]
#[rustfmt::skip]
fn couplings_are_checked() {
    let coupling = |c: Value| set_part("/partition/coupling", c);
    invalid(coupling(json!({"scheme": "predict", "tank": 1})), "partition.coupling.tank", "only the \"passive\" scheme has a tank");
    invalid(coupling(json!({"scheme": "tlm", "tank_share": 0.1})), "partition.coupling.tank_share", "only the \"passive\" scheme has a tank");
    invalid(coupling(json!({"scheme": "passive", "tank": 1, "tank_share": 0.1})), "partition.coupling.tank_share", "not both");
    invalid(coupling(json!({"scheme": "passive", "tank": -1})), "partition.coupling.tank", "finite energy ≥ 0 J, got -1");
    invalid(coupling(json!({"scheme": "passive", "tank_share": 11})), "partition.coupling.tank_share", "between 0 and 10, got 11");
    invalid(coupling(json!({"scheme": "passive", "tank_share": -0.5})), "partition.coupling.tank_share", "got -0.5");
    invalid(coupling(json!({"scheme": "passive", "tank_share": "a tenth"})), "partition.coupling", "");
    invalid(coupling(json!({"scheme": "passive", "extrapolate": 11})), "partition.coupling.extrapolate", "between 0 and 10 s");
}

#[test]
#[rustfmt::skip]
fn link_owners_are_checked() {
    let owners = |o: Value| set_part("/partition/link_owners", o);
    invalid(owners(json!([{"link": 0, "node": 1}])), "partition.link_owners[0].link", "no link 0 (links are numbered 1 to 24)");
    invalid(owners(json!([{"link": 25, "node": 1}])), "partition.link_owners[0].link", "no link 25");
    invalid(owners(json!([{"link": 1, "node": 1}])), "partition.link_owners[0].link", "link 1 (bodies 1–2) lies inside node 1");
    invalid(owners(json!([{"link": 11, "node": 3}])), "partition.link_owners[0].node", "must be node 1 or node 4, the nodes of link 11 (bodies 6–10) (got 3)");
    invalid(owners(json!([{"link": 11, "node": 0}])), "partition.link_owners[0].node", "(got 0)");
    invalid(owners(json!([{"link": 11, "node": 4}, {"link": 3, "node": 2}, {"link": 11, "node": 1}])), "partition.link_owners[2].link", "link 11 is given an owner twice (also partition.link_owners[0])");
    let no_links = put(base(), "/model/links", json!([]));
    let no_links = put(no_links, "/partition", json!({"nodes": [[1], [2, 3]], "link_owners": [{"link": 1, "node": 1}]}));
    invalid(no_links.to_string(), "partition.link_owners[0].link", "no link 1 (the model has no links)");
}

#[test]
#[rustfmt::skip]
fn channel_values_are_checked() {
    invalid(set("/channels", json!([{"name": "a", "tau": 0.01}])), "channels", "needs a `partition` section or `connections` (got 1 channel(s)");
    invalid(remove_part("/channels"), "channels", "a partition with border links needs channels (got none; 8 border links join 4 pairs of nodes)");
    invalid(set_part("/channels", json!([])), "channels", "needs channels");
    invalid(set_part("/channels/0/name", json!("")), "channels[0].name", "must not be empty");
    invalid(set_part("/channels/1/name", json!("tau 2")), "channels[1].name", "letters, digits and _ (got \"tau 2\")");
    invalid(set_part("/channels/1/name", json!("τ2")), "channels[1].name", "letters, digits and _");
    invalid(set_part("/channels/1/name", json!("tau1")), "channels[1].name", "duplicate name \"tau1\" (also channels[0].name)");
    invalid(set_part("/channels/0/tau", json!(0)), "channels[0].tau", "must be > 0 (got 0)");
    invalid(set_part("/channels/0/tau", json!(-0.005)), "channels[0].tau", "must be > 0 (got -0.005)");
    // A period between steps is valid (the channel samples at the first step at or after
    // each multiple of it); below one step it is not.
    assert!(parse_str(&set_part("/channels/0/tau", json!(0.0015)), "t.json").is_ok());
    invalid(set_part("/channels/0/tau", json!(0.0001)), "channels[0].tau", "must be at least one step, dt = 0.001 s (got 0.0001 s)");
    invalid(set_part("/channels/1/tau", json!(1e-12)), "channels[1].tau", "at least one step");
    invalid(set_part("/channels/0/latency", json!(-0.001)), "channels[0].latency", "must be ≥ 0 (got -0.001)");
    invalid(set_part("/channels/0/latency", json!(1.5e-9)), "channels[0].latency", "whole number of nanoseconds");
    invalid(set_part("/channels/1/k", json!(0)), "channels[1].k", "must be > 0 (got 0)");
    invalid(set_part("/channels/1/k", json!(-1)), "channels[1].k", "got -1");
    invalid(set_part("/channels/0/kinds", json!([])), "channels[0].kinds", "at least one kind");
    invalid(set_part("/channels/0/kinds", json!(["state", "state"])), "channels[0].kinds[1]", "\"state\" is listed twice");
}

#[test]
#[rustfmt::skip]
fn channel_borders_are_checked() {
    let borders = |b: Value| set_part("/channels/0/borders", b);
    invalid(borders(json!([])), "channels[0].borders", "at least one border");
    invalid(borders(json!([[1, 3]])), "channels[0].borders[0]", "nodes 1 and 3 share no border link");
    invalid(borders(json!([[1, 2], [4, 2]])), "channels[0].borders[1]", "nodes 4 and 2 share no border link");
    invalid(borders(json!([[1, 5]])), "channels[0].borders[0]", "no node 5 (the partition has nodes 1 to 4)");
    invalid(borders(json!([[0, 1]])), "channels[0].borders[0]", "no node 0");
    invalid(borders(json!([[2, 2]])), "channels[0].borders[0]", "two different nodes (got [2, 2])");
    invalid(borders(json!([[1, 2], [2, 3], [2, 1]])), "channels[0].borders[2]", "border 1–2 is listed twice (also channels[0].borders[0])");
}

#[test]
#[rustfmt::skip]
fn every_message_travels_on_exactly_one_channel() {
    // Forces have no channel once tau2 is gone.
    let mut doc = part_base();
    doc["channels"].as_array_mut().unwrap().pop();
    invalid(doc.to_string(), "channels", "no channel carries force messages across border 1–2");
    // tau2 carries both kinds: states would travel on tau1 and tau2.
    invalid(remove_part("/channels/1/kinds"), "channels", "state messages across border 1–2 would travel on both channels[0] \"tau1\" and channels[1] \"tau2\"");
    // Space distribution with border 3–4 left out.
    let space = json!([{"name": "tau1", "tau": 0.005, "borders": [[1, 2], [1, 4]]},
                       {"name": "tau2", "tau": 0.01, "borders": [[2, 3]]}]);
    invalid(set_part("/channels", space), "channels", "no channel carries state messages across border 3–4");
    let split = json!([{"name": "a", "tau": 0.005, "borders": [[1, 2], [1, 4]], "kinds": ["state"]},
                       {"name": "b", "tau": 0.005, "kinds": ["force"]},
                       {"name": "c", "tau": 0.005, "borders": [[2, 3], [3, 4]], "kinds": ["state"]}]);
    assert!(parse_str(&set_part("/channels", split), "split.json").is_ok());
    // A channel on a partition without border links carries nothing.
    let one = put(base(), "/partition", json!({"nodes": [[1, 2, 3]]}));
    let one = put(one, "/channels", json!([{"name": "idle", "tau": 0.01}])).to_string();
    invalid(one, "channels[0]", "channel \"idle\" carries no message (no border link or connection uses it)");
}

#[test]
#[rustfmt::skip]
fn other_sections_are_checked() {
    invalid(set("/name", json!("")), "name", "must not be empty");
    invalid(set("/name", json!("  ")), "name", "must not be empty");
    invalid(set("/output/decimation", json!(0)), "output.decimation", "must be ≥ 1 (got 0)");
    invalid(set("/divergence/max_violation", json!(-1)), "divergence.max_violation", "got -1");
}

// ---------------------------------------------------------------------------------------
// Property test: JSON round trip of random valid explicit scenarios.

/// `k / scale` for k in `lo..hi`: a short decimal, so that JSON printing and parsing
/// are exact without serde_json's `float_roundtrip` feature.
fn decimal(lo: i64, hi: i64, scale: f64) -> impl Strategy<Value = f64> {
    (lo..hi).prop_map(move |k| k as f64 / scale)
}

fn vec3(lo: i64, hi: i64, scale: f64) -> impl Strategy<Value = [f64; 3]> {
    [
        decimal(lo, hi, scale),
        decimal(lo, hi, scale),
        decimal(lo, hi, scale),
    ]
}

/// A body at index `i`: x in [10 i, 10 i + 5), so positions are distinct and far apart.
fn body(i: usize, id: u32) -> impl Strategy<Value = BodyFile> {
    (
        decimal(1, 1000, 100.0),
        decimal(1, 100, 100.0),
        prop::option::of(vec3(1, 100, 1000.0)),
        (
            decimal(0, 50, 10.0),
            decimal(-50, 50, 10.0),
            decimal(-50, 50, 10.0),
        ),
        vec3(-10, 10, 10.0),
        // Non-zero: w in 1..4.
        (1i64..4, -3i64..4, -3i64..4, -3i64..4),
        prop_oneof![Just([0.0; 3]), vec3(-10, 10, 10.0)],
    )
        .prop_map(
            move |(mass, size, inertia, (x, y, z), velocity, q, angular_velocity)| BodyFile {
                id,
                mass,
                size,
                inertia,
                position: [10.0 * i as f64 + x, y, z],
                velocity,
                orientation: [q.0 as f64, q.1 as f64, q.2 as f64, q.3 as f64],
                angular_velocity,
            },
        )
}

fn link(ids: Vec<u32>) -> impl Strategy<Value = LinkFile> {
    let n = ids.len();
    (
        0..n,
        1..n,
        prop::option::of(decimal(1, 1000, 100.0)),
        prop_oneof![Just([0.0; 3]), vec3(-3, 4, 10.0)],
        prop_oneof![Just([0.0; 3]), vec3(-3, 4, 10.0)],
    )
        .prop_map(move |(a, offset, length, anchor_a, anchor_b)| LinkFile {
            a: ids[a],
            b: ids[(a + offset) % n],
            length,
            anchor_a,
            anchor_b,
        })
}

/// `links` without those that join the same two bodies at the same anchors as an
/// earlier one (in either direction), which validation refuses as given twice.
fn distinct_links(links: Vec<LinkFile>) -> Vec<LinkFile> {
    let end = |id: u32, anchor: [f64; 3]| (id, anchor.map(f64::to_bits));
    let mut seen = std::collections::BTreeSet::new();
    links
        .into_iter()
        .filter(|l| {
            let (x, y) = (end(l.a, l.anchor_a), end(l.b, l.anchor_b));
            seen.insert(if x.0 <= y.0 { (x, y) } else { (y, x) })
        })
        .collect()
}

fn force(ids: Vec<u32>) -> impl Strategy<Value = ForceFile> {
    (
        prop::sample::select(ids),
        vec3(-200, 200, 10.0),
        decimal(-100, 100, 10.0),
        decimal(-31, 32, 10.0),
        0i64..100,
        prop::option::of(0i64..100),
    )
        // Times in tenths of a second, summed as integers so that `until` is a short
        // decimal too.
        .prop_map(|(body, amplitude, omega, phase, from, length)| ForceFile {
            body,
            amplitude,
            omega,
            phase,
            from: from as f64 / 10.0,
            until: length.map(|l| (from + l) as f64 / 10.0),
            ramp: None,
            point: None,
        })
}

fn stabilizer() -> impl Strategy<Value = StabilizerFile> {
    let opt = |lo, hi, scale| prop::option::of(decimal(lo, hi, scale));
    prop_oneof![
        (opt(1, 100, 1000.0), opt(1, 100, 1.0), opt(1, 100, 100.0)).prop_map(|(mu, k, epsilon)| {
            StabilizerFile {
                kind: StabilizerKind::Smc,
                mu,
                k,
                epsilon,
                alpha: None,
                beta: None,
            }
        }),
        (decimal(0, 100, 1.0), decimal(0, 100, 1.0)).prop_map(|(alpha, beta)| StabilizerFile {
            kind: StabilizerKind::Baumgarte,
            alpha: Some(alpha),
            beta: Some(beta),
            ..StabilizerFile::default()
        }),
    ]
}

fn solver() -> impl Strategy<Value = SolverFile> {
    prop_oneof![
        Just(SolverFile::default()),
        (
            prop::option::of(1usize..500),
            prop::option::of(decimal(0, 100, 1e12))
        )
            .prop_map(|(max_iterations, tolerance)| SolverFile {
                kind: SolverKind::Cg,
                max_iterations,
                tolerance,
                refactor_every: None,
            }),
        (
            prop::option::of(1usize..500),
            prop::option::of(1usize..100),
            prop::option::of(decimal(1, 100, 1e12))
        )
            .prop_map(|(refactor_every, max_iterations, tolerance)| SolverFile {
                kind: SolverKind::CholeskyPcg,
                refactor_every,
                max_iterations,
                tolerance,
            }),
    ]
}

/// Picks an optional sub-list of the ids, in random order.
fn id_list(ids: Vec<u32>) -> impl Strategy<Value = Option<Vec<u32>>> {
    let n = ids.len();
    prop::option::of(prop::sample::subsequence(ids, 0..=n).prop_shuffle())
}

/// A drawn partition: a node (0..3) per body, ghosts held, channels split by kind, τ in
/// steps, latency in µs, and whether the first border link gets an override owner.
type PartitionDraw = (Vec<usize>, bool, bool, u64, Option<u64>, bool);

fn partition_draw(bodies: usize) -> impl Strategy<Value = Option<PartitionDraw>> {
    prop::option::of((
        prop::collection::vec(0usize..3, bodies),
        any::<bool>(),
        any::<bool>(),
        1u64..20,
        prop::option::of(0u64..50_000),
        any::<bool>(),
    ))
}

/// The `partition` and `channels` sections of a drawn partition: empty nodes dropped,
/// one channel for everything (or one per kind) when there are border links.
fn partition_sections(
    draw: Option<PartitionDraw>,
    bodies: &[BodyFile],
    links: &[LinkFile],
    dt_ns: u64,
) -> (Option<PartitionFile>, Vec<ChannelFile>) {
    let Some((drawn, hold, by_kind, tau_steps, latency_us, override_first)) = draw else {
        return (None, Vec::new());
    };
    let mut nodes: Vec<Vec<u32>> = vec![Vec::new(); 3];
    for (b, &n) in bodies.iter().zip(&drawn) {
        nodes[n].push(b.id);
    }
    nodes.retain(|n| !n.is_empty());
    // File position and node (0-based, after dropping empty nodes) of a body id.
    let index = |id: u32| bodies.iter().position(|b| b.id == id).unwrap();
    let node = |id: u32| nodes.iter().position(|n| n.contains(&id)).unwrap();
    let border: Vec<usize> = (0..links.len())
        .filter(|&k| node(links[k].a) != node(links[k].b))
        .collect();
    let link_owners = match border.first() {
        Some(&k) if override_first => {
            let l = &links[k];
            // The general rule gives the link to the node of its first body in file
            // order; hand it to the other one.
            let other = if index(l.a) < index(l.b) { l.b } else { l.a };
            vec![LinkOwnerFile {
                link: k + 1,
                node: node(other) + 1,
            }]
        }
        _ => Vec::new(),
    };
    let channel = |name: &str, kinds: Option<Vec<DataKindFile>>| ChannelFile {
        name: name.to_string(),
        tau: (dt_ns * tau_steps) as f64 / 1e9,
        latency: latency_us.map(|us| us as f64 / 1e6),
        phase: None,
        k: 1.0,
        borders: None,
        kinds,
    };
    let channels = match (border.is_empty(), by_kind) {
        (true, _) => Vec::new(),
        (false, false) => vec![channel("all", None)],
        (false, true) => vec![
            channel("states", Some(vec![DataKindFile::State])),
            channel("forces", Some(vec![DataKindFile::Force])),
        ],
    };
    let partition = PartitionFile {
        nodes: Some(nodes),
        quadrants: false,
        ghosts: if hold {
            GhostsFile::Hold
        } else {
            GhostsFile::Integrate
        },
        coupling: Default::default(),
        link_owners,
    };
    (Some(partition), channels)
}

/// A random valid explicit scenario.
fn scenario() -> impl Strategy<Value = ScenarioFile> {
    // Distinct ids in random order.
    let ids = prop::collection::btree_set(0u32..1000, 1..=6)
        .prop_flat_map(|set| Just(set.into_iter().collect::<Vec<_>>()).prop_shuffle());
    ids.prop_flat_map(|ids| {
        let bodies: Vec<_> = ids.iter().enumerate().map(|(i, &id)| body(i, id)).collect();
        let links = if ids.len() > 1 {
            prop::collection::vec(link(ids.clone()), 0..8)
                .prop_map(distinct_links)
                .boxed()
        } else {
            Just(Vec::new()).boxed()
        };
        let dt_ns = prop::sample::select(vec![500_000u64, 1_000_000, 2_000_000, 10_000_000]);
        (
            (
                bodies,
                links,
                prop::collection::vec(force(ids.clone()), 0..4),
            ),
            (any::<u64>(), dt_ns, 1u64..3000, 1u64..100),
            (
                prop::sample::select(vec![
                    IntegratorFile::Euler,
                    IntegratorFile::SymplecticEuler,
                    IntegratorFile::Rk4,
                ]),
                stabilizer(),
                solver(),
                prop::sample::select(vec![BodyModelFile::Auto, BodyModelFile::Rigid]),
            ),
            (
                decimal(1, 1000, 100.0),
                prop::bool::ANY,
                1u64..100,
                id_list(ids.clone()),
                id_list(ids.clone()),
            ),
            partition_draw(ids.len()),
        )
    })
    .prop_map(
        |(
            (bodies, links, forces),
            (seed, dt_ns, steps, period_steps),
            (integrator, stabilizer, solver, body_model),
            (max_violation, explicit_period, decimation, trace_bodies, plot_bodies),
            partition_draw,
        )| {
            let secs = |ns: u64| ns as f64 / 1e9;
            let (partition, channels) = partition_sections(partition_draw, &bodies, &links, dt_ns);
            ScenarioFile {
                schema: None,
                name: format!("random {seed}"),
                description: None,
                seed,
                duration: secs(dt_ns * steps),
                dt: secs(dt_ns),
                integrator,
                stabilizer: Some(stabilizer),
                solver,
                body_model,
                model: ModelFile {
                    grid: None,
                    bodies: Some(bodies),
                    links: Some(links),
                    ..ModelFile::default()
                },
                forces,
                torques: Vec::new(),
                divergence: DivergenceFile { max_violation },
                measurement: MeasurementFile {
                    period: explicit_period.then(|| secs(dt_ns * period_steps.min(steps))),
                    signals: None,
                },
                output: OutputFile {
                    decimation,
                    trace_bodies,
                    plot_bodies,
                    ..OutputFile::default()
                },
                partition,
                controller: None,
                network: NetworkFile::default(),
                channels,
                fmus: Vec::new(),
                connections: Vec::new(),
                schedule: Vec::new(),
                base_dir: None,
            }
        },
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn valid_scenarios_survive_a_json_round_trip(file in scenario()) {
        let direct = validate(file.clone());
        prop_assert!(direct.is_ok(), "generated scenario is invalid: {:?}", direct.err());
        let text = serde_json::to_string_pretty(&file).unwrap();
        prop_assert_eq!(&parse_file(&text, "random.json").unwrap(), &file);
        prop_assert_eq!(parse_str(&text, "random.json").unwrap(), direct.unwrap());
    }
}

#[test]
fn grid_files_survive_a_json_round_trip() {
    let file = ScenarioFile {
        model: ModelFile {
            grid: Some(GridFile {
                rows: 3,
                cols: 5,
                spacing: 0.7,
                mass: 2.0,
                size: 0.1,
            }),
            bodies: None,
            links: None,
            ..ModelFile::default()
        },
        ..parse_file(&grid_base().to_string(), "grid.json").unwrap()
    };
    let text = serde_json::to_string(&file).unwrap();
    assert_eq!(parse_file(&text, "grid.json").unwrap(), file);
    let s = parse_str(&text, "grid.json").unwrap();
    assert_eq!((s.bodies.len(), s.links.len()), (15, 22));
    assert_eq!(s, validate(file).unwrap());
}

/// `part_base()` on a TDMA network (channels without latency).
fn tdma_base() -> Value {
    let mut doc = remove_from_value(part_base(), "/channels/0/latency");
    doc["network"] = json!({
        "kind": "tdma", "slot": 0.0001, "cycle": 0.005, "guard": 0.00001,
        "link_rate": 100e6, "header_bytes": 26, "drift_ppm": 50
    });
    doc
}

fn remove_from_value(mut doc: Value, pointer: &str) -> Value {
    let (parent, key) = pointer.rsplit_once('/').expect("pointer starts with /");
    if let Some(Value::Object(map)) = doc.pointer_mut(parent) {
        map.remove(key);
    }
    doc
}

fn set_tdma(pointer: &str, value: Value) -> String {
    put(tdma_base(), pointer, value).to_string()
}

#[test]
fn tdma_base_is_valid() {
    parse_str(&tdma_base().to_string(), "tdma.json").expect("tdma base validates");
}

#[test]
#[rustfmt::skip]
fn tdma_configurations_are_checked() {
    let list = |l: Value| set_tdma("/network/slot_list", l);
    invalid(set_tdma("/network/drift_ppm", json!(-5)), "network.drift_ppm", "must be ≥ 0 (got -5)");
    invalid(set_tdma("/network/random_walk_ppm", json!(-0.1)), "network.random_walk_ppm", "got -0.1");
    invalid(set_tdma("/network/drift_ppm", json!(2e6)), "network.drift_ppm", "below 10⁶ ppm");
    invalid(set_tdma("/network/slot", json!(0)), "network.slot", "must be > 0");
    invalid(set_tdma("/network/guard", json!(0.0001)), "network.guard", "shorter than the slot");
    invalid(set_tdma("/network/cycle", json!(0.0005)), "network.cycle", "shorter than the sync and static part (6 slots");
    invalid(set_tdma("/network/cycle", json!(0.00505)), "network.cycle", "whole number of slots");
    invalid(set_tdma("/network/link_rate", json!(0)), "network.link_rate", "must be > 0");
    invalid(set_tdma("/network/jitter", json!({"kind": "uniform"})), "network.jitter.max", "required for kind \"uniform\"");
    invalid(set_tdma("/network/jitter", json!({"kind": "uniform", "mean": 1e-5})), "network.jitter.mean", "not a key of kind \"uniform\"");
    invalid(set_tdma("/network/colour", json!(1)), "network.colour", "unknown field");
    invalid(set_part("/network/slot", json!(0.0001)), "network.slot", "not a key of kind \"ideal\"");
    invalid(remove_from(tdma_base(), "/network/cycle"), "network.cycle", "required for kind \"tdma\"");
    // A slot shorter than a frame: node 1's state frame (4 states × 9 floats + header)
    // takes 31 µs at 10 Mbit/s… 310 µs, more than the 90 µs usable.
    invalid(set_tdma("/network/link_rate", json!(10e6)), "network.slot", "is shorter than the largest frame");
    // Cycle too short for the list: 44 dynamic slots, 45 entries.
    let entry = json!({"node": 1, "channel": "tau1"});
    invalid(list(json!(vec![entry.clone(); 45])), "network.slot_list", "45 entries do not fit the cycle, whose dynamic part holds 44");
    invalid(list(json!([{"node": 9, "channel": "tau1"}])), "network.slot_list[0].node", "unknown node 9 (nodes are 0 (server) to 4)");
    invalid(list(json!([{"node": 1, "channel": "tau9"}])), "network.slot_list[0].channel", "unknown channel \"tau9\"");
    invalid(list(json!([{"node": 1}])), "network.slot_list[0].channel", "required");
    invalid(list(json!([{"idle": true, "node": 1}])), "network.slot_list[0]", "an idle slot names no");
    // A period the cycle cannot serve: τ below the sync + static gap.
    invalid(set_tdma("/channels/0/tau", json!(0.0)), "channels[0].tau", "must be > 0");
    invalid(put(put(tdma_base(), "/dt", json!(0.0001)), "/channels/0/tau", json!(0.0003)).to_string(), "channels[0].tau", "shortest period the cycle allows");
    invalid(set_tdma("/channels/0/latency", json!(0.001)), "channels[0].latency", "not used by a \"tdma\" network");
    invalid(set_tdma("/channels/0/phase", json!(0.001)), "channels[0].phase", "not used by a \"tdma\" network");
    invalid(set_part("/channels/0/phase", json!(0.005)), "channels[0].phase", "must be below the period");
    let mono = put(tdma_base(), "/partition", Value::Null);
    let mono = remove_from_value(remove_from_value(mono, "/partition"), "/channels");
    invalid(mono.to_string(), "network.kind", "needs a `partition` section");
}

/// The thesis grid on 4 quadrant nodes over a TDMA network with `slot` and `cycle` [s].
fn tdma_with(slot: f64, cycle: f64) -> Value {
    let mut v = part_base();
    v["network"] = json!({"kind": "tdma", "slot": slot, "cycle": cycle});
    v["channels"][0].as_object_mut().unwrap().remove("latency");
    v
}

proptest! {
    // A hang is caught by proptest's per-case timeout (each case in its own process,
    // failed after 300 s); what is asserted is each verdict, not the time.
    #![proptest_config(ProptestConfig { timeout: 300_000, ..ProptestConfig::with_cases(256) })]

    /// Times near and below the nanosecond grid, and products of legal values: every case
    /// ends in well under a second with a clean verdict, never a panic, a hang or a huge
    /// allocation (issue "Hardening").
    #[test]
    fn sizes_and_times_near_the_limits_give_a_verdict_at_once(
        period_exp in -330i32..1,
        slot_ns in 1u64..200_000,
        slots in prop_oneof![1u64..200, 19_000u64..21_000, 1_000_000u64..1_000_000_000],
        steps_exp in 0u32..8,
        dsm_refl in prop_oneof![0u64..5, 999u64..1002, Just(u64::MAX / 2)],
    ) {
        // A measurement period of 10^e s: accepted only as a whole number of dt steps.
        let mut v = serde_json::from_str::<Value>(&set("/measurement", json!({"period": 10f64.powi(period_exp)}))).unwrap();
        v["duration"] = json!(1.0);
        match parse_str(&v.to_string(), "p") {
            Ok(s) => prop_assert!(s.measurement_period.as_nanos() >= s.dt.as_nanos()),
            Err(e) => prop_assert!(e.to_string().contains("measurement.period"), "{e}"),
        }
        // A TDMA cycle of `slots` slots of `slot_ns`.
        let slot = slot_ns as f64 * 1e-9;
        let t = tdma_with(slot, slot * slots as f64);
        match parse_str(&t.to_string(), "t") {
            Ok(_) => prop_assert!(slots <= 20_000, "{slots} slots per cycle accepted"),
            // The slot grid, or the channels that cannot be scheduled on it.
            Err(e) => prop_assert!(
                e.to_string().contains("network.") || e.to_string().contains("channels"),
                "{e}"
            ),
        }
        // 10^k seconds of 1 ms steps.
        let mut d: Value = serde_json::from_str(&set("/duration", json!(10f64.powi(steps_exp as i32)))).unwrap();
        d["measurement"] = json!({"period": 1.0});
        let _ = parse_str(&d.to_string(), "d");
        // m_r reflections.
        let mut c = part_base();
        c["controller"] = json!({"problem": "cp", "budget": 400, "tau_max": 0.05,
                                 "dsm": {"size": 0.002, "reflections": dsm_refl}});
        let in_range = (1..=1000).contains(&dsm_refl);
        match parse_str(&c.to_string(), "c") {
            Ok(s) => prop_assert!(in_range && s.controller.unwrap().reflections as u64 == dsm_refl),
            Err(e) => prop_assert!(!in_range && e.to_string().contains("controller.dsm.reflections"), "{e}"),
        }    }
}

/// `m·10^e` for `e` over the whole exponent range of `f64`, subnormals and the
/// largest finite value included.
fn any_magnitude() -> impl Strategy<Value = f64> {
    prop_oneof![
        (1.0f64..10.0, -330i32..309).prop_map(|(m, e)| m * 10f64.powi(e)),
        Just(f64::MAX),
        Just(f64::MIN_POSITIVE / 2.0),
        Just(5e-324),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { timeout: 300_000, ..ProptestConfig::with_cases(256) })]

    /// Bandwidth and objectives over every magnitude of `k` and `penalty` (issue
    /// "Hardening, third round": k = 1e308 gave an infinite bandwidth, penalty = 1e308
    /// infinite objectives): refused naming the field, or every bandwidth `k/τ` at the
    /// shortest delay and the penalty on it finite.
    #[test]
    fn bandwidths_and_objectives_are_finite_or_refused(k in any_magnitude(), penalty in any_magnitude()) {
        let mut v = part_base();
        v["channels"][0]["k"] = json!(k);
        v["controller"] = json!({"problem": "up", "penalty": penalty, "tau_min": 0.001,
                                 "tau_max": 0.05, "dsm": {"size": 0.002}});
        match parse_str(&v.to_string(), "k") {
            Ok(s) => {
                let c = s.controller.as_ref().unwrap();
                let bandwidth: f64 = s.channels.iter().map(|ch| ch.k / c.tau_min).sum();
                prop_assert!(bandwidth.is_finite(), "k {k}: bandwidth {bandwidth}");
                let dsmcosim::scenario::model::Problem::Unconstrained { penalty } = c.problem else {
                    panic!("up")
                };
                prop_assert!((penalty * bandwidth).is_finite(), "penalty {penalty}");
            }
            Err(e) => {
                let m = e.to_string();
                prop_assert!(
                    m.starts_with("channels[0].k:") || m.starts_with("controller.penalty:"),
                    "{m}"
                );
            }
        }
    }

    /// Masses, moments of inertia, force amplitudes, ramp scales and the SMC μ over
    /// every magnitude: refused naming the field, or a run whose first steps are
    /// finite or stop with a divergence naming a link (never a singular J M⁻¹ Jᵀ, the
    /// wrong cause that μ = 1e155 or a subnormal inertia gave).
    #[test]
    fn magnitudes_give_a_finite_step_or_a_refusal(
        x in any_magnitude(),
        (field, name) in prop::sample::select(vec![
            ("/model/bodies/0/mass", "model.bodies[0].mass"),
            ("/model/bodies/1/inertia/0", "model.bodies[1].inertia[0]"),
            ("/forces/0/amplitude/2", "forces[0].amplitude[2]"),
            ("/forces/0/ramp/a1", "forces[0].ramp.a1"),
            ("/stabilizer/mu", "stabilizer.mu"),
            ("/stabilizer/k", "stabilizer.k"),
        ]),
    ) {
        let mut v = base();
        v["model"]["bodies"][1]["inertia"] = json!([0.1, 0.1, 0.1]);
        v["forces"][0]["ramp"] = json!({"t0": 0.0, "t1": 0.5, "a0": 1.0, "a1": 2.0});
        v["duration"] = json!(0.01);
        v["measurement"] = json!({"period": 0.01});
        let v = put(v, field, json!(x));
        match parse_str(&v.to_string(), "m") {
            Ok(s) => {
                let dir = tempfile::tempdir().unwrap();
                match dsmcosim::run::run(&s, dir.path()) {
                    Ok(_) | Err(Error::Diverged(_)) => {}
                    // A CG budget may run out on an extreme but legal scene; a singular
                    // J M⁻¹ Jᵀ is not what a single magnitude can cause.
                    Err(Error::Numerical { message, .. }) => prop_assert!(
                        !message.contains("not positive definite"),
                        "{field} = {x}: {message}"
                    ),
                    Err(e) => prop_assert!(false, "{field} = {x}: {e}"),
                }
            }
            Err(e) => {
                let m = e.to_string();
                // A tiny mass can pass its own bound and still give a cube-default
                // inertia below the inertia's: that refusal names the defaulted field.
                let defaulted = name == "model.bodies[0].mass"
                    && m.starts_with("model.bodies[0].inertia: the cube default");
                prop_assert!(m.starts_with(&format!("{name}:")) || defaulted, "{field} = {x}: {m}");
            }
        }
    }
}
