//! Forks, checkpoints and the delay controller over a loop of FMUs: a fork carries each
//! FMU's state as bytes into an instance of its own and runs on bit for bit; a resumed
//! run ends with the uninterrupted run's digest; the controller's cost is the RMS of the
//! named FMU output.

use std::path::{Path, PathBuf};

use dsmcosim::cosim::CoSim;
use dsmcosim::kernel::SimTime;
use dsmcosim::run::{resume, run_with, RunOptions};
use serde_json::{json, Value};

use crate::fmus::scratch;

use crate::fmu_build::build_test_fmu;

/// The PD loop of `cosim.rs` with `extra` keys merged in, written into `dir` beside
/// msd.fmu and pd.fmu (or `plant` in their place), and loaded.
fn scene(dir: &Path, plant: &str, extra: Value) -> dsmcosim::scenario::Scenario {
    for id in ["msd", "pd", "faulty"] {
        build_test_fmu(id, dir).unwrap_or_else(|e| panic!("{id}.fmu: {e}"));
    }
    let mut v = json!({
        "name": "pd_loop",
        "seed": 1,
        "duration": 3.0,
        "dt": 0.001,
        "output": {"decimation": 1},
        "fmus": [
            {"name": "plant", "path": format!("{plant}.fmu"), "node": 1},
            {"name": "ctrl", "path": "pd.fmu", "node": 2}
        ],
        "channels": [
            {"name": "sense", "tau": 0.005, "latency": 0.005},
            {"name": "act", "tau": 0.005, "latency": 0.005}
        ],
        "connections": [
            {"from": "plant.x", "to": "ctrl.x", "channel": "sense"},
            {"from": "plant.v", "to": "ctrl.v", "channel": "sense"},
            {"from": "ctrl.u", "to": "plant.F", "channel": "act"}
        ]
    });
    for (k, x) in extra.as_object().unwrap() {
        v[k] = x.clone();
    }
    let path = dir.join("scenario.json");
    std::fs::write(&path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    dsmcosim::scenario::load(&path).unwrap_or_else(|e| panic!("scenario: {e}"))
}

fn bits(w: &CoSim) -> Vec<u64> {
    (0..2)
        .flat_map(|f| w.fmu_outputs(f))
        .map(|v| match v {
            dsmcosim::fmu::Value::Float(x) => x.to_bits(),
            other => panic!("the msd FMUs' outputs are Reals, got {other:?}"),
        })
        .collect()
}

#[test]
fn a_fork_runs_on_bit_for_bit_and_leaves_its_source_alone() {
    let dir = scratch("fmu-forks", "fork");
    let s = scene(&dir, "msd", json!({}));
    let at = |secs: f64| SimTime::from_secs_f64(secs).unwrap();
    let mut plain = CoSim::new(&s);
    plain.advance_to(at(2.0), &mut ()).unwrap();
    let mut live = CoSim::new(&s);
    live.advance_to(at(1.0), &mut ()).unwrap();
    let mut fork = live.clone();
    // A second fork steered elsewhere (other periods) must not touch the live run.
    let mut other = live.clone();
    other
        .set_taus(at(1.0), &[0.02, 0.02], &[at(0.02), at(0.02)])
        .unwrap();
    other.advance_to(at(2.0), &mut ()).unwrap();
    live.advance_to(at(2.0), &mut ()).unwrap();
    fork.advance_to(at(2.0), &mut ()).unwrap();
    assert_eq!(bits(&live), bits(&plain), "forking changed the live run");
    assert_eq!(
        bits(&fork),
        bits(&plain),
        "the fork left the live run's path"
    );
    assert_ne!(
        bits(&other),
        bits(&plain),
        "other periods must change the fork"
    );
}

#[test]
fn a_fork_of_an_fmu_that_cannot_save_its_state_fails_naming_it() {
    let dir = scratch("fmu-forks", "unforkable");
    // `faulty` has the plant's x, v and F, but no state saving.
    let s = scene(&dir, "faulty", json!({}));
    let at = |secs: f64| SimTime::from_secs_f64(secs).unwrap();
    let mut live = CoSim::new(&s);
    live.advance_to(at(0.1), &mut ()).unwrap();
    let mut fork = live.clone();
    let e = fork.advance_to(at(0.2), &mut ()).unwrap_err().to_string();
    assert!(
        e.contains("cannot be carried into a fork") && e.contains("'plant'"),
        "{e}"
    );
    assert!(e.contains("canGetAndSetFMUstate"), "{e}");
    // The live run is unaffected.
    live.advance_to(at(0.2), &mut ()).unwrap();
}

#[test]
fn a_run_resumed_from_any_checkpoint_ends_with_the_same_digest() {
    let dir = scratch("fmu-forks", "checkpoint");
    let s = scene(&dir, "msd", json!({}));
    let opts = RunOptions {
        checkpoint_every: SimTime::from_secs_f64(0.7),
        ..RunOptions::default()
    };
    let full = run_with(&s, &dir.join("full"), opts).expect("run");
    let plain = run_with(&s, &dir.join("plain"), RunOptions::default()).expect("run");
    assert_eq!(full.digest, plain.digest);
    let mut cps: Vec<PathBuf> = std::fs::read_dir(dir.join("full/checkpoints"))
        .expect("checkpoints")
        .map(|e| e.unwrap().path())
        .collect();
    cps.sort();
    assert_eq!(cps.len(), 4, "{cps:?}");
    for (i, cp) in cps.iter().enumerate() {
        let out = dir.join(format!("resumed{i}"));
        let r = resume(cp, &out, RunOptions::default()).expect("resume");
        assert_eq!(r.digest, full.digest, "resumed from {}", cp.display());
        assert_eq!(
            std::fs::read(out.join("trace.csv")).unwrap(),
            std::fs::read(dir.join("full/trace.csv")).unwrap()
        );
    }
}

#[test]
fn checkpoints_and_lookahead_are_refused_for_an_fmu_that_cannot_save_its_state() {
    let dir = scratch("fmu-forks", "refusals");
    let s = scene(&dir, "faulty", json!({}));
    let opts = RunOptions {
        checkpoint_every: SimTime::from_secs_f64(0.5),
        ..RunOptions::default()
    };
    let e = run_with(&s, &dir.join("out"), opts)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("--checkpoint-every") && e.contains("\"plant\""),
        "{e}"
    );
    assert!(e.contains("canGetAndSetFMUstate"), "{e}");
    assert!(!dir.join("out").exists(), "a refused run writes nothing");
    let controller = json!({
        "measurement": {"period": 0.5, "signals": ["plant.x"]},
        "controller": {"method": "dsm", "problem": "up", "penalty": 1e-4,
                        "tau_min": 0.001, "tau_max": 0.02, "dsm": {"size": 0.004}}
    });
    let path = dir.join("scenario.json");
    let mut v: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    for (k, x) in controller.as_object().unwrap() {
        v[k] = x.clone();
    }
    std::fs::write(&path, v.to_string()).unwrap();
    let e = dsmcosim::scenario::load(&path).unwrap_err().to_string();
    assert!(e.starts_with("controller.measure:"), "{e}");
    assert!(
        e.contains("\"plant\"") && e.contains("canGetAndSetFMUstate"),
        "{e}"
    );
}

#[test]
fn the_controller_optimizes_the_periods_on_the_rms_of_an_fmu_output() {
    let dir = scratch("fmu-forks", "controller");
    let s = scene(
        &dir,
        "msd",
        json!({
            "measurement": {"period": 0.5, "signals": ["plant.x"]},
            "controller": {"method": "dsm", "problem": "up", "penalty": 1e-4,
                           "tau_min": 0.001, "tau_max": 0.02, "initial": [0.005, 0.005],
                           "dsm": {"size": 0.004}, "baselines": ["no_opt", "grid"],
                           "grid_step": 0.006}
        }),
    );
    let out = dir.join("out");
    let a = run_with(&s, &out, RunOptions::default()).expect("run");
    // The grid's forks run on rayon's threads, each with FMU instances of its own: on
    // one thread the same digest.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let b = one
        .install(|| run_with(&s, &dir.join("again"), RunOptions::default()))
        .expect("run");
    assert_eq!(
        a.digest, b.digest,
        "forks and decisions must be deterministic"
    );
    // Each window's cost is sqrt((1/T) Σ x_k² dt) over the steps that start in it.
    let mut trace = csv::Reader::from_path(out.join("trace.csv")).unwrap();
    let col = trace
        .headers()
        .unwrap()
        .iter()
        .position(|h| h == "plant.x")
        .unwrap();
    let x: Vec<f64> = trace
        .records()
        .map(|r| r.unwrap()[col].parse().unwrap())
        .collect();
    let mut epochs = csv::Reader::from_path(out.join("epochs.csv")).unwrap();
    let head = epochs.headers().unwrap().clone();
    let cost_col = head.iter().position(|h| h == "cost").unwrap();
    let mut moved = false;
    for (w, r) in epochs.records().enumerate() {
        let r = r.unwrap();
        let cost: f64 = r[cost_col].parse().unwrap();
        let steps = &x[w * 500..(w + 1) * 500];
        let want = (steps.iter().map(|x| x * x).sum::<f64>() * 0.001 / 0.5).sqrt();
        assert!(
            (cost - want).abs() <= 1e-12 * want.max(1e-300),
            "window {w}: cost {cost}, RMS of plant.x {want}"
        );
        moved |= r[2].parse::<f64>().unwrap() != 0.005;
    }
    assert!(moved, "the DSM never left its initial periods");
}

#[test]
fn online_measurement_needs_no_fork_and_runs_an_fmu_that_cannot_save_its_state() {
    let dir = scratch("fmu-forks", "online");
    let s = scene(
        &dir,
        "faulty",
        json!({
            "fmus": [
                {"name": "plant", "path": "faulty.fmu", "node": 1, "start": {"fail_at": 100.0}},
                {"name": "ctrl", "path": "pd.fmu", "node": 2}
            ],
            "measurement": {"period": 0.25, "signals": ["plant.x"]},
            "controller": {"method": "dsm", "problem": "up", "penalty": 1e-4,
                           "measure": "online", "tau_min": 0.001, "tau_max": 0.02,
                           "initial": [0.005, 0.005], "dsm": {"size": 0.004}}
        }),
    );
    let a = run_with(&s, &dir.join("a"), RunOptions::default()).expect("online run");
    let b = run_with(&s, &dir.join("b"), RunOptions::default()).expect("online run");
    assert_eq!(a.digest, b.digest);
    let epochs = std::fs::read_to_string(dir.join("a/epochs.csv")).unwrap();
    assert_eq!(epochs.lines().count(), 1 + 12, "{epochs}");
}

#[test]
fn a_sweep_over_an_fmu_scene_reads_the_fmus_beside_its_base() {
    let dir = scratch("fmu-forks", "sweep");
    scene(&dir, "msd", json!({}));
    let sweep = json!({
        "name": "latency",
        "base": "scenario.json",
        "overrides": {"/duration": 0.5},
        "axes": [{"name": "latency", "pointer": "/channels/0/latency",
                  "values": [0.0, 0.01, 0.02]}]
    });
    std::fs::write(dir.join("sweep.json"), sweep.to_string()).unwrap();
    // Run from elsewhere: the FMU paths are relative to the base, not the working
    // directory.
    let out = dir.join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .current_dir(std::env::temp_dir())
        .args(["sweep", dir.join("sweep.json").to_str().unwrap(), "--out"])
        .arg(&out)
        .output()
        .expect("dsmcosim");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert_eq!(table.lines().count(), 4, "{table}");
}
