//! The `dsmcosim` binary as a user meets it: exit codes, what is (not) written, messages.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::{json, Value};

mod boundary_layer;
mod check;
mod contract;
mod conventions;
mod corpus;
#[path = "../support/fmu_build.rs"]
mod fmu_build;
mod front_page;
mod limits;
mod outputs;
mod overrides;
mod random_scenes;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh scratch directory under the target dir (removed first if present).
fn scratch(name: &str) -> PathBuf {
    let d = repo().join("target").join("test-scratch").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

fn write_json(dir: &Path, name: &str, v: &Value) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, serde_json::to_string_pretty(v).expect("json")).expect("write");
    p
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("spawn dsmcosim")
}

/// What a finished process said, for assertion messages: exit status, stdout, stderr.
fn said(o: &Output) -> String {
    format!(
        "{}\n--- stdout ---\n{}\n--- stderr ---\n{}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn short_grid() -> Value {
    json!({
        "name": "short_grid", "seed": 7, "duration": 2.0, "dt": 0.001,
        "model": {"grid": {"rows": 4, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0, "phase": 0.0, "from": 0.0, "until": 12.0}],
        "output": {"decimation": 20}
    })
}

/// A shipped scenario as JSON, for a test to edit.
fn shipped(name: &str) -> Value {
    let text = std::fs::read_to_string(repo().join("scenarios").join(format!("{name}.json")))
        .expect("shipped scenario");
    serde_json::from_str(&text).expect("json")
}

/// Runs scenario `v` (written into `dir`) into `dir/out`; the process and the output
/// directory.
fn run_in(dir: &Path, v: &Value) -> (Output, PathBuf) {
    let file = write_json(dir, "scenario.json", v);
    let out = dir.join("out");
    let o = run(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    (o, out)
}

fn summary(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).expect("summary"))
        .expect("summary is JSON")
}

/// Every shipped scenario validates (a scene with FMUs beside the test FMUs, which a
/// plain checkout does not hold).
#[test]
fn shipped_scenarios_validate() {
    let dir = scratch("shipped_validate");
    let mut checked = 0;
    for entry in std::fs::read_dir(repo().join("scenarios")).expect("scenarios/") {
        let p = entry.expect("entry").path();
        if p.extension().is_none_or(|e| e != "json") {
            continue;
        }
        let p = fmu_build::beside_test_fmus(&p, &dir).unwrap_or_else(|e| panic!("{e}"));
        let out = run(&["validate", p.to_str().expect("utf-8 path")]);
        assert!(out.status.success(), "{}: {}", p.display(), said(&out));
        checked += 1;
    }
    assert!(checked > 10, "only {checked} shipped scenarios found");
}

/// The studies read a scene's FMUs beside its scenario file, as `run` does, whatever
/// the working directory; `tradeoff`'s monolithic reference keeps the channels the
/// FMU's connections ride (it dropped them: "unknown channel").
#[test]
fn studies_of_an_fmu_scene_read_its_fmus_beside_the_scenario() {
    let dir = scratch("fmu_studies");
    let elsewhere = scratch("fmu_studies_cwd");
    let file = repo().join("scenarios").join("fmu_grid_pd.json");
    let scen = fmu_build::beside_test_fmus(&file, &dir).unwrap_or_else(|e| panic!("{e}"));
    for (command, written) in [
        ("stability-map", "stability_map.csv"),
        ("tradeoff", "tradeoff.csv"),
    ] {
        let out = elsewhere.join(command);
        let o = bin()
            .current_dir(&elsewhere)
            .args([command, scen.to_str().expect("utf-8 path"), "--out"])
            .arg(&out)
            .args(["--duration", "0.05", "-q"])
            .output()
            .expect("spawn dsmcosim");
        assert!(o.status.success(), "{command}: {}", said(&o));
        assert!(out.join(written).is_file(), "{command} wrote no {written}");
    }
}

/// A run of an FMU scene keeps a scenario.json that reruns it: its relative FMU paths
/// point from the run directory to the same files, and the rerun has the same digest.
#[test]
fn a_runs_own_scenario_copy_reruns_an_fmu_scene() {
    let dir = scratch("fmu_rerun");
    let file = repo().join("scenarios").join("fmu_grid_pd.json");
    let scen = fmu_build::beside_test_fmus(&file, &dir).unwrap_or_else(|e| panic!("{e}"));
    let (first, again) = (dir.join("runs").join("first"), dir.join("again"));
    let o = run(&[
        "run",
        scen.to_str().unwrap(),
        "--out",
        first.to_str().unwrap(),
        "--set",
        "/duration=1",
    ]);
    assert!(o.status.success(), "{}", said(&o));
    let copy = first.join("scenario.json");
    let kept: Value = serde_json::from_str(&std::fs::read_to_string(&copy).unwrap()).unwrap();
    assert_eq!(kept["fmus"][0]["path"], json!("../../fmu/pd.fmu"), "{kept}");
    let o = run(&[
        "run",
        copy.to_str().unwrap(),
        "--out",
        again.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", said(&o));
    assert_eq!(summary(&first)["digest"], summary(&again)["digest"]);
}

#[test]
fn run_writes_the_output_contract_and_is_deterministic() {
    let dir = scratch("contract");
    let scen = write_json(&dir, "s.json", &short_grid());
    let (a, b) = (dir.join("a"), dir.join("b"));
    for out in [&a, &b] {
        let o = run(&[
            "run",
            scen.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", said(&o));
        assert!(o.stderr.is_empty(), "a short run is quiet on stderr");
    }
    let (sa, sb) = (summary(&a), summary(&b));
    // Provenance: the tool, the compiler, the scenario as run; and the file itself.
    assert_eq!(sa["provenance"]["tool"], json!("dsmcosim"));
    assert_eq!(
        sa["provenance"]["version"],
        json!(env!("CARGO_PKG_VERSION"))
    );
    assert_eq!(
        sa["provenance"]["scenario_blake3"], sb["provenance"]["scenario_blake3"],
        "the same scenario hashes alike"
    );
    assert_eq!(
        sa["provenance"]["scenario_blake3"].as_str(),
        Some(
            blake3::hash(&std::fs::read(&scen).unwrap())
                .to_hex()
                .as_str()
        ),
        "scenario_blake3 is the hash of the file's bytes as read, whatever the binary's \
         model holds"
    );
    assert_eq!(
        std::fs::read(a.join("scenario.json")).unwrap(),
        std::fs::read(&scen).unwrap(),
        "the run directory keeps the file it ran"
    );
    assert_eq!(
        sa["digest"], sb["digest"],
        "same scenario and seed, same digest"
    );
    assert_eq!(sa["steps"], json!(2000));
    assert_eq!(sa["body_model"], json!("point_mass"));
    assert_eq!(
        std::fs::read(a.join("trace.csv")).unwrap(),
        std::fs::read(b.join("trace.csv")).unwrap()
    );
    let breaches = contract::problems(&a);
    assert!(breaches.is_empty(), "output contract: {breaches:#?}");
    // The check itself catches breaches: a summary without its digest, a trace with a
    // non-number, a plot that is not XML.
    let broken = dir.join("broken");
    std::fs::create_dir_all(&broken).unwrap();
    for e in std::fs::read_dir(&a).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, broken.join(p.file_name().unwrap())).unwrap();
    }
    let mut s = summary(&a);
    s.as_object_mut().unwrap().remove("digest");
    write_json(&broken, "summary.json", &s);
    let trace = std::fs::read_to_string(a.join("trace.csv")).unwrap();
    std::fs::write(
        broken.join("trace.csv"),
        trace.replacen("\n0,", "\nNaN,", 1),
    )
    .unwrap();
    std::fs::write(broken.join("bodies.svg"), "<svg><text>t [s]</svg>").unwrap();
    let breaches = contract::problems(&broken).join("\n");
    for want in ["'digest'", "trace.csv row 2, column t", "bodies.svg"] {
        assert!(
            breaches.contains(want),
            "{want} is reported in:\n{breaches}"
        );
    }
    // Trace columns: t, w_L1..w_L24, f_L1..f_L24, 6 per body, the 7 invariants.
    let trace = std::fs::read_to_string(a.join("trace.csv")).unwrap();
    let head: Vec<&str> = trace.lines().next().unwrap().split(',').collect();
    assert_eq!(head.len(), 1 + 24 + 24 + 16 * 6 + 7);
    assert_eq!(&head[145..], &["Px", "Py", "Pz", "Lx", "Ly", "Lz", "KE"]);
    assert_eq!(head[1], "w_L1");
    assert_eq!(head[25], "f_L1");
    assert_eq!(
        &head[49..55],
        &["px_B1", "py_B1", "pz_B1", "vx_B1", "vy_B1", "vz_B1"]
    );
    // 2000 steps, every 20th plus the last: rows at 0, 0.02, …, 2.0.
    assert_eq!(trace.lines().count(), 1 + 101);
    // The plots of a monolithic run: titled, both axes labelled with units, a legend.
    for (file, x_label, y_label) in [
        ("constraints.svg", "t [s]", "[m]"),
        ("bodies.svg", "t [s]", "[m]"),
    ] {
        let svg = std::fs::read_to_string(a.join(file))
            .unwrap_or_else(|e| panic!("{file} is written: {e}"));
        assert!(
            svg.starts_with("<svg") || svg.starts_with("<?xml"),
            "{file}"
        );
        assert!(svg.contains(x_label), "{file} labels its time axis");
        assert!(svg.contains(y_label), "{file} gives the unit of its values");
    }
    // No temporary files are left behind (the hidden lock file stays, by design).
    for e in std::fs::read_dir(&a).unwrap() {
        let name = e.unwrap().file_name().into_string().unwrap();
        assert!(
            !name.starts_with('.') || name == ".dsmcosim.lock",
            "leftover {name}"
        );
    }
}

#[test]
fn decimation_and_traced_bodies_do_not_change_the_digest() {
    let dir = scratch("decimation");
    let mut v = short_grid();
    let a = write_json(&dir, "a.json", &v);
    v["output"] = json!({"decimation": 7, "trace_bodies": [1, 16]});
    let b = write_json(&dir, "b.json", &v);
    for (s, o) in [(&a, "ra"), (&b, "rb")] {
        let out = run(&[
            "run",
            s.to_str().unwrap(),
            "--out",
            dir.join(o).to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", said(&out));
    }
    assert_eq!(
        summary(&dir.join("ra"))["digest"],
        summary(&dir.join("rb"))["digest"]
    );
}

#[test]
fn bad_input_exits_2_names_the_field_and_writes_nothing() {
    let dir = scratch("bad");
    let cases: Vec<(Value, &str)> = vec![
        (
            {
                let mut v = short_grid();
                v["dt"] = json!(-0.001);
                v
            },
            "dt",
        ),
        (
            {
                let mut v = short_grid();
                v["forces"][0]["until"] = json!(-1.0);
                v
            },
            "forces[0]",
        ),
        (
            {
                let mut v = short_grid();
                v["forces"][0]["body"] = json!(99);
                v
            },
            "forces[0].body",
        ),
        (
            {
                let mut v = short_grid();
                v["colour"] = json!("red");
                v
            },
            "colour",
        ),
        (
            {
                let mut v = short_grid();
                v["stabilizer"] = json!({"kind": "smc", "mu": 0.0});
                v
            },
            "stabilizer.mu",
        ),
    ];
    for (i, (v, field)) in cases.iter().enumerate() {
        let scen = write_json(&dir, &format!("bad{i}.json"), v);
        let out_dir = dir.join(format!("out{i}"));
        let o = run(&[
            "run",
            scen.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "case {i}: {err}");
        assert!(
            err.contains(field),
            "case {i}: message {err:?} must name {field}"
        );
        assert_eq!(
            err.trim_end().lines().count(),
            1,
            "case {i}: one line: {err:?}"
        );
        assert!(!out_dir.exists(), "case {i}: nothing may be written");
    }
    // Malformed JSON: line and column.
    let p = dir.join("broken.json");
    std::fs::write(&p, "{\n  \"name\": \"x\",\n  \"seed\": 1,,\n}").unwrap();
    let o = run(&["validate", p.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2));
    assert!(err.contains("line 3"), "{err}");
    assert!(err.contains("column"), "{err}");
    // A missing file is an I/O error, not a panic.
    let o = run(&["validate", dir.join("nope.json").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn divergence_exits_3_names_time_node_and_link_and_keeps_the_trace() {
    let dir = scratch("diverge");
    // Explicit Euler with SMC at dt = 40 ms is far past its stability limit
    // (the boundary-layer rate K/ε = 100 /s needs dt < 20 ms).
    let mut v = short_grid();
    v["dt"] = json!(0.04);
    v["duration"] = json!(20.0);
    let (o, out) = run_in(&dir, &v);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(err.contains("diverged at t = "), "{err}");
    assert!(err.contains("on node 1"), "{err}");
    assert!(err.contains("link L"), "{err}");
    let s = summary(&out);
    assert_eq!(s["status"], json!("diverged"));
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    assert!(
        trace.lines().count() > 2,
        "the trace up to the divergence is kept"
    );
    assert!(
        !trace.contains("NaN") && !trace.contains("inf"),
        "no non-finite value in the trace"
    );
}

#[test]
fn every_subcommand_has_help() {
    let top = run(&["--help"]);
    assert!(top.status.success(), "{}", said(&top));
    let listing = String::from_utf8_lossy(&top.stdout).into_owned();
    // One line per subcommand, as cargo's and rg's (the details are in its own --help).
    let commands = listing
        .split("Commands:")
        .nth(1)
        .and_then(|rest| rest.split("\n\n").next())
        .expect("a Commands section");
    for line in commands.lines().filter(|l| !l.trim().is_empty()) {
        assert!(line.chars().count() <= 80, "a long summary line: {line:?}");
    }
    assert!(listing
        .lines()
        .next()
        .is_some_and(|l| l.chars().count() <= 100));
    let subcommands = [
        "validate",
        "run",
        "resume",
        "check",
        "tradeoff",
        "stability-map",
        "sweep",
        "sweep-merge",
        "coupling",
        "distance",
    ];
    for sub in subcommands {
        assert!(listing.contains(sub), "`--help` lists `{sub}`");
        let o = run(&[sub, "--help"]);
        assert!(o.status.success(), "{sub} --help: {}", said(&o));
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            text.contains("Usage") && text.contains(sub),
            "{sub} --help prints its usage"
        );
    }
}

#[test]
fn a_tdma_run_writes_the_network_outputs() {
    let dir = scratch("tdma_outputs");
    let mut v = shipped("tdma4_space_fixed");
    v["duration"] = json!(1.0);
    v["output"]["network_decimation"] = json!(50);
    let (o, out) = run_in(&dir, &v);
    assert!(o.status.success(), "{}", said(&o));
    let breaches = contract::problems(&out);
    assert!(breaches.is_empty(), "output contract: {breaches:#?}");
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["network"]["kind"], json!("tdma"));
    assert_eq!(s["lost_frames"], json!(0));
    assert_eq!(s["network"]["cycles"], json!(200), "1 s of 5 ms cycles");
    assert!(s["network"]["random_words_drawn"].as_u64().unwrap() > 0);
    // network.csv: the header, and every frame of cycles 0, 50, 100, 150: sync, 5
    // static frames and the 6 list entries.
    let net = std::fs::read_to_string(out.join("network.csv")).unwrap();
    let mut lines = net.lines();
    assert_eq!(
        lines.next().unwrap(),
        "cycle,slot,sender,kind,channel,bytes,nominal,send_time,delivery_time,lost,latency,info"
    );
    assert_eq!(lines.count(), 4 * 12);
    let epochs = std::fs::read_to_string(out.join("epochs.csv")).unwrap();
    assert!(epochs.starts_with(
        "t_start,t_end,tau_tau1_requested,tau_tau1_achieved,tau_tau2_requested,tau_tau2_achieved"
    ));
    let timeline = std::fs::read_to_string(out.join("timeline.svg")).unwrap();
    assert!(timeline.contains("TDMA slot timeline") && timeline.contains("time t [ms]"));
}

/// A request a TDMA slot list cannot serve (50 ms on a 5-ms cycle) runs at what the
/// list achieves, is said on the terminal and in summary.json, and the coupling's lines
/// are chosen by the achieved period (5 ms + latency: no line), not the requested one
/// (which made 8 border links lines).
#[test]
fn a_delay_the_tdma_list_cannot_serve_is_reported_and_lines_follow_the_achieved_one() {
    let dir = scratch("tdma_unserved");
    let mut v = shipped("tdma4_space_fixed");
    v["duration"] = json!(1.0);
    v["channels"][0]["tau"] = json!(0.05);
    v["channels"][1]["tau"] = json!(0.05);
    let (o, out) = run_in(&dir, &v);
    assert!(o.status.success(), "{}", said(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("warning: channel tau1 asked for τ = 0.05 s and ran at 0.0051"),
        "{}",
        said(&o)
    );
    let s = summary(&out);
    let missed = s["delays_not_realized"].as_array().expect("a list");
    assert_eq!(missed.len(), 2, "{missed:?}");
    assert_eq!(missed[0]["channel"], json!("tau1"));
    assert_eq!(missed[0]["requested"], json!(0.05));
    assert!(missed[0]["achieved"].as_f64().unwrap() < 0.006);
    // Every border link kept its predictor and port account (a line has neither), and
    // the plan lists no line.
    assert!(
        s["coupling"]["ports_given_j"].as_f64().unwrap() > 0.0,
        "no line at an achieved 5 ms: {}",
        s["coupling"]
    );
    let file = write_json(&dir, "fifty.json", &v);
    let plan = run(&["validate", file.to_str().unwrap()]);
    assert!(plan.status.success(), "{}", said(&plan));
    assert!(
        !String::from_utf8_lossy(&plan.stdout).contains("transmission lines"),
        "{}",
        said(&plan)
    );
    // As shipped (5 ms requested, 5 ms served): nothing to report.
    let (o, out) = run_in(&scratch("tdma_served"), &{
        let mut v = shipped("tdma4_space_fixed");
        v["duration"] = json!(1.0);
        v
    });
    assert!(o.status.success(), "{}", said(&o));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("asked for"));
    assert_eq!(summary(&out)["delays_not_realized"], json!([]));
}

#[test]
fn a_controlled_run_writes_the_output_contract() {
    let dir = scratch("controlled_outputs");
    let mut v = shipped("grid16_space_cp");
    v["duration"] = json!(2.0);
    v["controller"]["baselines"] = json!(["grid", "no_opt"]);
    v["controller"]["grid_step"] = json!(0.004);
    v["controller"]["surface_window"] = json!(1.0);
    let (o, out) = run_in(&dir, &v);
    assert!(
        matches!(o.status.code(), Some(0) | Some(3)),
        "a finished or diverged run still writes its outputs: {}",
        said(&o)
    );
    let breaches = contract::problems(&out);
    assert!(breaches.is_empty(), "output contract: {breaches:#?}");
    let s = summary(&out);
    for key in [
        "unpaired_mean_cost_dsm",
        "unpaired_mean_cost_grid",
        "unpaired_mean_cost_no_opt",
    ] {
        assert!(s.get(key).is_some(), "summary.json has {key}");
    }
    assert!(
        out.join("surface.svg").exists(),
        "the surface of window 1 s"
    );
}

#[test]
fn distance_measures_how_far_runs_drift_from_a_reference() {
    let dir = scratch("distance");
    let runs = |name: &str, v: Value| {
        let sub = dir.join(name);
        std::fs::create_dir_all(&sub).unwrap();
        let (o, out) = run_in(&sub, &v);
        assert!(o.status.success(), "{}", said(&o));
        out
    };
    let reference = runs("mono", short_grid());
    let same = runs("same", short_grid());
    let mut pushed = short_grid();
    pushed["forces"][0]["amplitude"] = json!([0, 0, 21]);
    let other = runs("other", pushed);
    let out = dir.join("cmp");
    let args = |bodies: &str, list: &[&Path]| {
        let mut a = vec!["distance".to_string(), reference.display().to_string()];
        a.extend(list.iter().map(|p| p.display().to_string()));
        a.extend(["--bodies".into(), bodies.into(), "--out".into()]);
        a.push(out.display().to_string());
        a
    };
    let call = |a: Vec<String>| bin().args(a).output().expect("spawn");
    let o = call(args("1,16", &[&same, &other]));
    assert!(o.status.success(), "{}", said(&o));
    let csv = std::fs::read_to_string(out.join("distance.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let name = |p: &Path, b: &str| format!("{}_B{b}", p.display());
    assert_eq!(
        header,
        [
            "t".to_string(),
            name(&same, "1"),
            name(&same, "16"),
            name(&other, "1"),
            name(&other, "16")
        ]
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 101, "2 s at every 20th step, and t = 0");
    // The same scenario is at distance 0; a 5 % stronger push on body 1 moves body 1
    // off at once, and reaches the far corner, body 16, only through the net: at 0.4 s
    // body 16 is still 100 times closer than body 1, by 2 s both have drifted.
    assert!(rows.iter().all(|r| r[1] == 0.0 && r[2] == 0.0));
    assert_eq!((rows[0][3], rows[0][4]), (0.0, 0.0), "same start");
    assert!(rows[20][3] > 1e-3, "body 1 at 0.4 s: {}", rows[20][3]);
    assert!(
        rows[20][4] < rows[20][3] / 100.0,
        "body 16 at 0.4 s: {}",
        rows[20][4]
    );
    assert!(
        rows[100][3] > 1e-3 && rows[100][4] > 1e-3,
        "both drift by 2 s"
    );
    let svg = std::fs::read_to_string(out.join("distance.svg")).unwrap();
    assert!(svg.contains("|p − p_ref| [m]") && svg.contains("time t [s]"));
    // A body the traces do not hold, too many curves, a trace of other times: exit 2.
    let o = call(args("99", &[&same]));
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(said(&o).contains("--bodies 99"), "{}", said(&o));
    let o = call(args("1,2,3,4,5,6,7", &[&same, &other]));
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    // A run that ended earlier (as a diverged run does) is compared up to its end, its
    // cells empty after it; one traced longer than the reference is refused.
    let mut shorter = short_grid();
    shorter["duration"] = json!(1.0);
    let short = runs("short", shorter);
    let o = call(args("1", &[&same, &short]));
    assert!(o.status.success(), "{}", said(&o));
    let csv = std::fs::read_to_string(out.join("distance.csv")).unwrap();
    let cells: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(cells.len(), 101, "the reference's times");
    assert_eq!(cells[50][2], "0", "the short run up to its end at 1 s");
    assert_eq!(cells[51][2], "", "nothing after its end");
    assert_eq!(cells[51][1], "0", "the full run goes on");
    let mut longer = short_grid();
    longer["duration"] = json!(3.0);
    let long = runs("long", longer);
    let o = call(args("1", &[&long]));
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(said(&o).contains("not traced at the times"), "{}", said(&o));
}

#[test]
fn an_output_directory_belongs_to_one_run() {
    let dir = scratch("run-dir");
    let out = dir.join("out");
    let o_str = out.to_str().unwrap().to_string();
    // A TDMA run leaves network.csv; a stale temporary file of a killed run is there too.
    let mut tdma = shipped("tdma4_space_fixed");
    tdma["duration"] = json!(0.2);
    tdma["measurement"] = json!({"period": 0.1});
    let first = write_json(&dir, "tdma.json", &tdma);
    let o = run(&["run", first.to_str().unwrap(), "--out", &o_str]);
    assert!(o.status.success(), "{}", said(&o));
    assert!(out.join("network.csv").is_file());
    std::fs::write(out.join(".trace.csv.tmp.99999.3"), "half a trace").unwrap();
    std::fs::write(out.join("notes.txt"), "the user's own file").unwrap();
    // Another scenario into that directory: refused, nothing touched.
    let other = write_json(&dir, "grid.json", &short_grid());
    let o = run(&["run", other.to_str().unwrap(), "--out", &o_str]);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(said(&o).contains("--force"), "{}", said(&o));
    assert!(out.join("network.csv").is_file() && out.join(".trace.csv.tmp.99999.3").is_file());
    // With --force it replaces that run: no network.csv of the old one, no stale
    // temporary file; the user's file stays.
    let o = run(&["run", other.to_str().unwrap(), "--out", &o_str, "--force"]);
    assert!(o.status.success(), "{}", said(&o));
    assert!(
        !out.join("network.csv").exists(),
        "the old run's network.csv is gone"
    );
    assert!(
        !out.join(".trace.csv.tmp.99999.3").exists(),
        "stale temporary file removed"
    );
    assert!(
        out.join("notes.txt").is_file(),
        "files a run does not write are kept"
    );
    assert_eq!(summary(&out)["scenario"], json!("short_grid"));
    // The same scenario again needs no --force.
    let o = run(&["run", other.to_str().unwrap(), "--out", &o_str]);
    assert!(o.status.success(), "{}", said(&o));
    // While another process holds the directory's lock, a run exits 1 naming it.
    let lock = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(out.join(".dsmcosim.lock"))
        .expect("the run left its lock file");
    lock.try_lock().expect("no run holds it now");
    let o = run(&["run", other.to_str().unwrap(), "--out", &o_str]);
    assert_eq!(o.status.code(), Some(1), "{}", said(&o));
    assert!(
        said(&o).contains("in use by another dsmcosim run"),
        "{}",
        said(&o)
    );
    drop(lock);
    let o = run(&["run", other.to_str().unwrap(), "--out", &o_str]);
    assert!(o.status.success(), "released: {}", said(&o));
}
