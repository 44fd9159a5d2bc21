//! What a real FMU does besides computing, with `quirks.fmu` (`tests/fmus/quirks.c`)
//! doing each at a set time: the messages it logs are printed and kept in summary.json
//! (bounded), and a request to stop ends the run normally.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::{json, Value};

use crate::fmu_build::build_test_fmu;
use crate::fmus::scratch;

/// `quirks.fmu` as `q` alone for `duration` [s] at dt = 1 ms, its parameters `start`.
fn alone(duration: f64, start: Value) -> Value {
    json!({
        "name": "quirks", "seed": 1, "duration": duration, "dt": 0.001,
        "fmus": [{"name": "q", "path": "quirks.fmu", "start": start, "trace": ["x", "v"]}]
    })
}

/// Runs `scenario` from `dir` (where quirks.fmu is built) with `dsmcosim run`; its output
/// directory, the process's output and summary.json (null when none was written).
fn run(dir: &Path, scenario: &Value) -> (PathBuf, Output, Value) {
    if !dir.join("quirks.fmu").exists() {
        build_test_fmu("quirks", dir).expect("build quirks.fmu");
    }
    let path = dir.join("scenario.json");
    std::fs::write(&path, scenario.to_string()).unwrap();
    let out = dir.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .args([
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .expect("run dsmcosim");
    let summary = std::fs::read(out.join("summary.json"))
        .map(|b| serde_json::from_slice(&b).expect("summary.json is JSON"))
        .unwrap_or(Value::Null);
    (out, o, summary)
}

/// The lines of `stderr` that print a message the FMU logged.
fn logged_lines(stderr: &str) -> Vec<&str> {
    stderr
        .lines()
        .filter(|l| l.starts_with("warning: FMU 'q' logged fmi2"))
        .collect()
}

#[test]
fn an_fmus_error_message_is_printed_and_kept_though_its_logging_is_off() {
    let dir = scratch("fmu-quirks", "error-message");
    let (_, o, summary) = run(
        &dir,
        &alone(0.2, json!({"warn_from": 0.1, "fail_at": 0.15})),
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{stderr}");
    let why = "Failed to open resource file table.csv: no data past fail_at";
    assert!(
        stderr.contains(&format!(
            "warning: FMU 'q' logged fmi2Error (logStatusError): {why}"
        )),
        "{stderr}"
    );
    // The FMU's reason comes before the run's own error, which names the call.
    let reason = stderr.find(why).unwrap();
    let error = stderr
        .find("fmi2DoStep returned fmi2Error")
        .expect("the run's error");
    assert!(reason < error, "{stderr}");
    let messages = summary["fmus"][0]["messages"].as_array().expect("messages");
    let error_entry = messages
        .iter()
        .find(|m| m["status"] == "fmi2Error")
        .expect("the error is kept");
    assert_eq!(error_entry["message"], why);
    assert_eq!(error_entry["category"], "logStatusError");
    assert_eq!(error_entry["instance"], "q");
    assert_eq!(error_entry["count"], 1);
    // Every warning (one per step from warn_from to fail_at, each naming its step's end)
    // is printed once and kept once.
    let warnings: Vec<&Value> = messages
        .iter()
        .filter(|m| m["status"] == "fmi2Warning")
        .collect();
    assert!((50..=51).contains(&warnings.len()), "{}", warnings.len());
    let lines = logged_lines(&stderr);
    assert_eq!(lines.len(), warnings.len() + 1, "{stderr}");
    for w in &warnings {
        let text = w["message"].as_str().unwrap();
        assert!(text.starts_with("step to t = 0.1"), "{text}");
        assert_eq!(
            lines.iter().filter(|l| l.ends_with(text)).count(),
            1,
            "{text}"
        );
    }
    assert_eq!(summary["fmus"][0]["messages_not_kept"], 0);
}

#[test]
fn an_fmu_logging_at_every_step_is_kept_to_its_bound() {
    let dir = scratch("fmu-quirks", "message-bound");
    let (_, o, summary) = run(&dir, &alone(0.2, json!({"warn_from": 0.0})));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    let bound = dsmcosim::fmu::log::MAX_KEPT_MESSAGES;
    // 200 steps, each warning with its own text: the first `bound` printed and kept,
    // the rest counted, and the cap said once.
    assert_eq!(logged_lines(&stderr).len(), bound, "{stderr}");
    assert_eq!(
        stderr
            .matches("logged more than 64 distinct messages")
            .count(),
        1,
        "{stderr}"
    );
    let fmu = &summary["fmus"][0];
    assert_eq!(fmu["messages"].as_array().unwrap().len(), bound);
    assert_eq!(fmu["messages_not_kept"], 200 - bound as u64);
}

#[test]
fn a_quiet_fmu_keeps_no_message() {
    let dir = scratch("fmu-quirks", "quiet");
    let (_, o, summary) = run(&dir, &alone(0.05, json!({})));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert!(logged_lines(&stderr).is_empty(), "{stderr}");
    assert_eq!(summary["fmus"][0]["messages"], json!([]));
}

/// The rows of trace.csv: (t, x).
fn rows(out: &Path) -> Vec<(f64, f64)> {
    let trace = std::fs::read_to_string(out.join("trace.csv")).expect("trace.csv");
    let mut lines = trace.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let x = header
        .iter()
        .position(|c| *c == "q.x")
        .expect("a q.x column");
    lines
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            (f[0], f[x])
        })
        .collect()
}

#[test]
fn a_stop_request_ends_the_run_normally_at_the_completed_step_with_its_row() {
    let dir = scratch("fmu-quirks", "stop");
    // x'' = 1 from rest: x = t²/2 exactly at every communication point (to round-off).
    let (out, o, summary) = run(&dir, &alone(0.2, json!({"stop_at": 0.1, "F": 1.0})));
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(o.status.code(), Some(0), "{stdout}{stderr}");
    let message = "stopped by FMU 'q' at t = 0.1 s \
                   (fmi2DoStep returned fmi2Discard and fmi2Terminated is true)";
    assert!(stdout.contains(message), "{stdout}");
    assert_eq!(summary["status"], "stopped");
    assert_eq!(summary["error"], Value::Null);
    assert_eq!(summary["stopped"]["fmu"], "q");
    assert_eq!(summary["stopped"]["time"], 0.1);
    assert_eq!(summary["stopped"]["message"], message);
    assert_eq!(summary["steps"], 100);
    let rows = rows(&out);
    let &(t, x) = rows.last().unwrap();
    assert_eq!(t, 0.1, "the stop's row is the last");
    assert!((x - 0.005).abs() < 1e-15, "x(0.1 s) = {x}");
    assert_eq!(rows.len(), 11, "rows 0, 0.01, … 0.1 s (decimation 10)");
}

#[test]
fn a_stop_request_of_an_fmu_stepping_slower_than_the_lock_step_ends_at_its_point() {
    let dir = scratch("fmu-quirks", "stop-slow");
    // Communication steps of 10 ms over lock-steps of 1 ms: the step from 40 to 50 ms
    // asks to stop, so the run ends at 50 ms, where the FMU's outputs are published.
    let mut scenario = alone(0.2, json!({"stop_at": 0.05, "F": 1.0}));
    scenario["fmus"][0]["step"] = json!(0.01);
    let (out, o, summary) = run(&dir, &scenario);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert_eq!(summary["stopped"]["time"], 0.05);
    assert_eq!(summary["steps"], 50);
    let &(t, x) = rows(&out).last().unwrap();
    assert_eq!((t, x), (0.05, 0.00125), "x = t²/2 at 50 ms");
}

#[test]
fn a_nan_output_is_a_divergence_naming_time_node_fmu_and_variable() {
    let dir = scratch("fmu-quirks", "nan");
    // x turns NaN after the step ending past 50 ms: the outputs of t = 51 ms.
    let (out, o, summary) = run(&dir, &alone(0.2, json!({"nan_at": 0.05, "F": 1.0})));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{stderr}");
    let message = "diverged at t = 0.051000000 s on node 1, FMU 'q' output x: \
                   non-finite output x = NaN";
    assert!(stderr.contains(message), "{stderr}");
    assert_eq!(summary["status"], "diverged");
    assert_eq!(summary["error"], message);
    let d = &summary["divergence"];
    assert_eq!(
        (&d["time"], &d["node"], &d["fmu_output"]),
        (&json!(0.051), &json!(1), &json!("q.x"))
    );
    // The trace holds the sane steps, up to 50 ms, and no NaN.
    let rows = rows(&out);
    assert_eq!(rows.last().unwrap().0, 0.05);
    assert!(rows.iter().all(|(_, x)| x.is_finite()));
}

/// quirks.fmu as the plant `q` of the PD controller FMU over two channels, the DSM
/// measuring every candidate on a fork (lookahead) with the no-optimization and grid
/// baselines, its parameters `start`.
fn controlled(start: Value) -> Value {
    json!({
        "name": "quirks_dsm", "seed": 1, "duration": 2.0, "dt": 0.001,
        "fmus": [
            {"name": "q", "path": "quirks.fmu", "node": 1, "start": start, "trace": ["x"]},
            {"name": "ctrl", "path": "pd.fmu", "node": 2, "start": {"r": 1.0}}
        ],
        "channels": [
            {"name": "sense", "tau": 0.005, "latency": 0.005},
            {"name": "act", "tau": 0.005, "latency": 0.005}
        ],
        "connections": [
            {"from": "q.x", "to": "ctrl.x", "channel": "sense"},
            {"from": "q.v", "to": "ctrl.v", "channel": "sense"},
            {"from": "ctrl.u", "to": "q.F", "channel": "act"}
        ],
        "measurement": {"period": 0.5, "signals": ["q.x"]},
        "controller": {"method": "dsm", "problem": "up", "penalty": 1e-4,
                       "tau_min": 0.001, "tau_max": 0.02, "initial": [0.005, 0.005],
                       "dsm": {"size": 0.004}, "baselines": ["no_opt", "grid"],
                       "grid_step": 0.006}
    })
}

#[test]
fn an_fmu_whose_state_saving_fails_stops_a_controlled_run_naming_it_and_the_call() {
    let dir = scratch("fmu-quirks", "fork-failure");
    build_test_fmu("pd", &dir).expect("build pd.fmu");
    // The same scene with state saving working: the controller measures finite costs.
    let (_, o, summary) = run(&dir, &controlled(json!({})));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    let cost = summary["mean_cost"].as_f64().unwrap();
    assert!(cost.is_finite() && cost > 0.0, "{cost}");
    // fmi2GetFMUstate fails: no fork can be made once the FMU has started (the first
    // window's forks start fresh instances from the start values, as the run did), and
    // the run says so instead of deciding on infinite costs.
    let (out, o, summary) = run(&dir, &controlled(json!({"fail_get_state": 1})));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{stderr}");
    let error = "error: FMU 'q': fmi2GetFMUstate returned fmi2Error at t = 0.5 s: the \
                 FMU's state cannot be carried into a fork (measuring a candidate on a fork \
                 of the run for the window from t = 0.5 s)";
    assert!(stderr.contains(error), "{stderr}");
    assert!(
        stderr.contains("logged fmi2Error (logStatusError): the model refuses to save its state"),
        "the FMU's own reason is printed: {stderr}"
    );
    assert_eq!(summary["status"], "fmu_error");
    assert_eq!(
        std::fs::read_to_string(out.join("epochs.csv"))
            .unwrap()
            .lines()
            .count(),
        2,
        "a header and the first window: none was decided on unmeasured costs"
    );
}
