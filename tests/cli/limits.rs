//! Inputs legal field by field whose sizes or times together are not (issue
//! "Hardening"): each is refused at once by `validate` and by `run`, exit 2, the field
//! named, nothing written — within a bounded time, so a hang fails the test instead of
//! stalling CI.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::{json, Value};

use super::{bin, said, scratch, shipped, write_json};

#[path = "../support/memory_grid.rs"]
mod memory_grid;
use memory_grid::{joint_chain, memory_grid};

/// Runs `dsmcosim args…`, killing it after `limit` (then the test fails).
pub(super) fn bounded(args: &[&str], limit: Duration) -> Output {
    let mut child = bin()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn dsmcosim");
    let start = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("dsmcosim {args:?} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child.wait_with_output().expect("output")
}

/// Runs the sweep `sweep` (written into `dir`) into `dir/out`, bounded in time.
fn sweep_in(dir: &Path, sweep: &Value) -> (Output, std::path::PathBuf) {
    let file = write_json(dir, "sweep.json", sweep);
    let out = dir.join("out");
    let args = [
        "sweep",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    (bounded(&args, Duration::from_secs(300)), out)
}

/// `validate` and `run` both exit 2 naming `field` (and `what`), and `run` writes
/// nothing.
fn refused(dir: &Path, name: &str, v: &Value, field: &str, what: &str) {
    let file = write_json(dir, &format!("{name}.json"), v);
    let out = dir.join(format!("{name}_out"));
    let f = file.to_str().unwrap();
    for args in [
        vec!["validate", f],
        vec!["run", f, "--out", out.to_str().unwrap()],
    ] {
        let o = bounded(&args, Duration::from_secs(300));
        assert_eq!(o.status.code(), Some(2), "{name}: {args:?}: {}", said(&o));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(field) && err.contains(what),
            "{name}: {}",
            said(&o)
        );
        assert_eq!(err.lines().count(), 1, "{name}: one line: {err}");
    }
    assert!(!out.exists(), "{name}: run wrote {}", out.display());
}

#[test]
fn sizes_and_times_legal_one_by_one_but_not_together_are_refused_at_once() {
    let dir = scratch("limits");
    let mut v = shipped("grid16_monolithic");
    // A measurement period that rounds to 0 ns looped forever in `run`.
    for period in [1e-10, 5e-324] {
        v["measurement"] = json!({"period": period});
        refused(
            &dir,
            "period",
            &v,
            "measurement.period",
            "whole number of dt steps",
        );
    }
    // 1 ns slots in a 1 s cycle: 10⁹ slots per cycle.
    let mut t = shipped("tdma4_space_fixed");
    t["network"]["slot"] = json!(1e-9);
    t["network"]["cycle"] = json!(1.0);
    t["network"].as_object_mut().unwrap().remove("guard");
    refused(&dir, "slots", &t, "network.cycle", "at most 20000 slots");
    // m_r near i64::MAX reflections per DSM iteration.
    let mut c = shipped("grid16_space_cp");
    c["controller"]["dsm"]["reflections"] = json!(9_223_372_036_854_775_807_u64);
    refused(
        &dir,
        "reflections",
        &c,
        "controller.dsm.reflections",
        "from 1 to 1000",
    );
    // A simplex larger than the delay box: `validate` said ok, `run` refused.
    let mut c = shipped("grid16_space_cp");
    c["controller"]["dsm"]["size"] = json!(0.2);
    c["controller"]
        .as_object_mut()
        .unwrap()
        .remove("surface_window");
    c["controller"].as_object_mut().unwrap().remove("landscape");
    refused(
        &dir,
        "simplex",
        &c,
        "controller",
        "cannot start the simplex",
    );
    // A grid search of 10⁹ points per window.
    let mut c = shipped("grid16_space_cp");
    c["controller"]["tau_max"] = json!(1e6);
    refused(
        &dir,
        "grid",
        &c,
        "controller.grid_step",
        "at most 40000 points",
    );
}

/// A 1000 × 1000 grid on the exact solve: in link order its factor would have needed
/// about 130 GB, and the scene was refused; in AMD order it needs about 4.0 GB (3.4 GB
/// measured), so it plans within the default limit, and a lower `--max-memory` refuses
/// it at once naming the solver and the CG path's need (about 2.5 GB), nothing written.
/// An FMU stepping far faster than the bodies counts its steps against the step
/// limit: 200 s of 1-ns FMU steps (2·10¹¹ `doStep` calls beside 200 000 integration
/// steps) is refused naming the FMU's step; `validate` said "200000 steps" before.
#[test]
fn an_fmu_stepping_every_nanosecond_counts_its_steps_against_the_limit() {
    let dir = scratch("limits_fmu_steps");
    let file = super::repo().join("scenarios").join("fmu_grid_pd.json");
    let scen = super::fmu_build::beside_test_fmus(&file, &dir).unwrap_or_else(|e| panic!("{e}"));
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&scen).unwrap()).unwrap();
    v["duration"] = json!(200.0);
    v["fmus"][0]["step"] = json!(1e-9);
    refused(&dir, "fmu_ns", &v, "fmus[0].step", "200000000000 FMU steps");
    // At a 1-ms step the same FMU validates, and the plan counts its steps.
    v["fmus"][0]["step"] = json!(0.001);
    let f = write_json(&dir, "fmu_ms.json", &v);
    let o = bounded(&["validate", f.to_str().unwrap()], Duration::from_secs(300));
    assert!(o.status.success(), "{}", said(&o));
    let plan = String::from_utf8_lossy(&o.stdout);
    assert!(plan.contains("200000 steps and 200000 FMU steps"), "{plan}");
}

#[test]
fn a_million_body_exact_solve_is_planned_from_its_ordered_factor() {
    let dir = scratch("limits_exact");
    let big = json!({
        "name": "big", "seed": 1, "duration": 0.01, "dt": 0.001,
        "model": {"grid": {"rows": 1000, "cols": 1000, "spacing": 1.0, "mass": 1.0, "size": 0.1}},
        "output": {"decimation": 1000}
    });
    let file = write_json(&dir, "big.json", &big);
    let f = file.to_str().unwrap();
    let o = bounded(&["validate", f], Duration::from_secs(300));
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("needs about 3964 MB"),
        "{}",
        said(&o)
    );
    let out = dir.join("big_out");
    let o = bounded(
        &[
            "run",
            f,
            "--out",
            out.to_str().unwrap(),
            "--max-memory",
            "3000000000",
        ],
        Duration::from_secs(300),
    );
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("solver") && err.contains("{\"kind\": \"cg\"}` needs about 2510 MB"),
        "{err}"
    );
    assert!(!out.exists(), "run wrote {}", out.display());
}

#[test]
fn a_sweep_axis_of_a_billion_steps_is_refused_before_anything_is_allocated() {
    let dir = scratch("limits-sweep");
    write_json(&dir, "base.json", &shipped("grid16_monolithic"));
    let sweep = json!({
        "name": "huge", "base": "base.json",
        "axes": [{"name": "k", "pointer": "/stabilizer/k",
                  "range": {"from": 1.0, "to": 10.0, "steps": 1_000_000_000}}]
    });
    let (o, out) = sweep_in(&dir, &sweep);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(said(&o).contains("range.steps"), "{}", said(&o));
    assert!(!out.exists(), "nothing written");
}

#[test]
fn runs_beyond_the_step_output_and_checkpoint_limits_are_refused_unless_lifted() {
    let dir = scratch("limits-budget");
    let mut v = shipped("grid16_monolithic");
    // 10¹¹ steps.
    v["duration"] = json!(1e8);
    v["forces"] = json!([]);
    refused(&dir, "steps", &v, "duration", "--max-steps");
    let file = write_json(&dir, "steps.json", &v);
    let o = bounded(
        &[
            "validate",
            file.to_str().unwrap(),
            "--max-steps",
            "200000000000",
            "--max-output",
            "1000000000000000000",
        ],
        Duration::from_secs(300),
    );
    assert!(o.status.success(), "lifted: {}", said(&o));
    assert!(said(&o).contains("1000000001 trace rows"), "{}", said(&o));
    // 10⁹ steps at decimation 1: terabytes of trace.
    v["duration"] = json!(1e6);
    v["output"]["decimation"] = json!(1);
    refused(&dir, "output", &v, "output.decimation", "--max-output");
    // A checkpoint every step of a 30 s run.
    let file = write_json(&dir, "mono.json", &shipped("grid16_monolithic"));
    let out = dir.join("ckpt_out");
    let o = bounded(
        &[
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--checkpoint-every",
            "0.001",
        ],
        Duration::from_secs(300),
    );
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(
        said(&o).contains("--checkpoint-every") && said(&o).contains("30000 checkpoints"),
        "{}",
        said(&o)
    );
    assert!(!out.exists(), "nothing written");
}

#[test]
fn a_sweep_point_that_run_would_refuse_is_refused_before_any_point_runs() {
    // D_s 2 ms fits the delay box, 200 ms does not: `run` refuses the second point, so
    // the sweep refuses before running the first.
    let dir = scratch("limits-sweep-point");
    let mut base = shipped("grid16_space_cp");
    base["duration"] = json!(2.0);
    let c = base["controller"].as_object_mut().unwrap();
    c.remove("surface_window");
    c.remove("landscape");
    write_json(&dir, "base.json", &base);
    let sweep = json!({
        "name": "ds", "base": "base.json",
        "axes": [{"name": "D_s", "pointer": "/controller/dsm/size", "values": [0.002, 0.2]}]
    });
    let (o, out) = sweep_in(&dir, &sweep);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(
        said(&o).contains("point p1") && said(&o).contains("cannot start the simplex"),
        "{}",
        said(&o)
    );
    assert!(!out.exists(), "nothing written");
}

/// Accepted values that once hung (issue "Hardening, third round"): one step of a dt
/// near the end of simulated time runs, `tradeoff` and `stability-map` refuse a horizon
/// of 10⁹ s naming `--duration`, and an endless input is refused after the size cap —
/// as a scenario, a sweep's base, and a checkpoint. Each bounded only against a hang.
#[test]
fn accepted_values_end_and_endless_inputs_are_refused() {
    let dir = scratch("limits-hangs");
    let generous = Duration::from_secs(300);
    // dt = duration near 1.8e10 s: dt × 1024 wrapped and the one-step run spun.
    for d in [1.8e10, 1.7e10, 18_014_398.509_481_984] {
        let mut v = shipped("grid16_monolithic");
        v["dt"] = json!(d);
        v["duration"] = json!(d);
        v["measurement"] = json!({"period": d});
        v["forces"] = json!([]);
        let file = write_json(&dir, "one_step.json", &v);
        let out = dir.join("one_step_out");
        let o = bounded(
            &[
                "run",
                file.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
            generous,
        );
        assert!(o.status.success(), "dt {d}: {}", said(&o));
        assert_eq!(super::summary(&out)["steps"], json!(1), "dt {d}");
    }
    let mono = write_json(&dir, "mono.json", &shipped("grid16_monolithic"));
    for command in ["tradeoff", "stability-map"] {
        let out = dir.join(format!("{command}_out"));
        let args = [
            command,
            mono.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--duration",
            "1e9",
        ];
        let o = bounded(&args, generous);
        assert_eq!(o.status.code(), Some(2), "{command}: {}", said(&o));
        assert!(
            said(&o).contains("--duration") && said(&o).contains("steps"),
            "{}",
            said(&o)
        );
        assert!(!out.exists(), "{command} wrote {}", out.display());
    }
    // /dev/zero as a scenario, a sweep's base and a checkpoint.
    let o = bounded(&["validate", "/dev/zero"], generous);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(
        said(&o).contains("/dev/zero: holds more than"),
        "{}",
        said(&o)
    );
    let sweep = json!({"name": "z", "base": "/dev/zero",
        "axes": [{"name": "s", "pointer": "/seed", "values": [1, 2]}]});
    let (o, out) = sweep_in(&dir, &sweep);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(
        said(&o).contains("/dev/zero: holds more than"),
        "{}",
        said(&o)
    );
    assert!(!out.exists());
    let out = dir.join("resume_out");
    let o = bounded(
        &["resume", "/dev/zero", "--out", out.to_str().unwrap()],
        generous,
    );
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(
        said(&o).contains("not a dsmcosim checkpoint"),
        "{}",
        said(&o)
    );
    assert!(!out.exists());
}

proptest::proptest! {
    // A hang is caught by proptest's per-case timeout (each case in its own process);
    // what is asserted is the verdict.
    #![proptest_config(proptest::prelude::ProptestConfig {
        timeout: 300_000, ..proptest::prelude::ProptestConfig::with_cases(12)
    })]

    /// Step counts of every command that takes a horizon: `tradeoff` and
    /// `stability-map` over horizons of 10⁸ to 10¹² s (10¹¹ steps and more) are refused
    /// naming `--duration`, nothing written.
    #[test]
    fn study_horizons_past_the_step_limit_are_refused(exp in 8i32..13, study in 0usize..2) {
        let dir = scratch(&format!("limits-study-{exp}-{study}"));
        let mono = write_json(&dir, "mono.json", &shipped("grid16_monolithic"));
        let command = ["tradeoff", "stability-map"][study];
        let out = dir.join("out");
        let horizon = format!("1e{exp}");
        let args = [command, mono.to_str().unwrap(), "--out", out.to_str().unwrap(), "--duration", &horizon];
        let o = bounded(&args, Duration::from_secs(300));
        proptest::prop_assert_eq!(o.status.code(), Some(2), "{}", said(&o));
        proptest::prop_assert!(said(&o).contains("--duration:"), "{}", said(&o));
        proptest::prop_assert!(!out.exists());
    }

    /// Time slices: one to three steps of a dt from 10⁶ s to the end of simulated time
    /// end, run through or diverged (a slice of 1024 steps wrapped `u64` and spun).
    #[test]
    fn steps_near_the_end_of_time_run_to_their_end(dt_exp in 6.0f64..10.25, steps in 1u64..4) {
        let dt = (10f64.powf(dt_exp) * 1e3).round() / 1e3;
        let dir = scratch(&format!("limits-slice-{}", dt.to_bits() % 100_000));
        let mut v = shipped("grid16_monolithic");
        v["dt"] = json!(dt);
        v["duration"] = json!(dt * steps as f64);
        v["measurement"] = json!({"period": dt});
        v["forces"] = json!([]);
        let file = write_json(&dir, "s.json", &v);
        let out = dir.join("out");
        let o = bounded(&["run", file.to_str().unwrap(), "--out", out.to_str().unwrap()], Duration::from_secs(300));
        match o.status.code() {
            // The duration beyond the range of time, or not whole steps after rounding.
            Some(2) => proptest::prop_assert!(said(&o).contains("duration") || said(&o).contains("dt"), "{}", said(&o)),
            // Run to the end, or diverged on the way (a step of 10⁶ s and more is far past
            // any stability limit): a verdict either way.
            Some(3) => proptest::prop_assert!(said(&o).contains("diverged at t = "), "{}", said(&o)),
            code => {
                proptest::prop_assert_eq!(code, Some(0), "{}", said(&o));
                proptest::prop_assert_eq!(&super::summary(&out)["steps"], &json!(steps));
            }
        }
    }
}

/// Under an address-space limit (`ulimit -v`) below a run's estimate, the default
/// `--max-memory` is that limit: the run is refused before it starts, exit 2, the
/// message naming the estimate, the limit and the flag, nothing written — instead of an
/// allocation failure half-way.
#[test]
fn an_address_space_limit_below_the_estimate_refuses_the_run_up_front() {
    let dir = scratch("limits-rlimit");
    let cg = json!({"kind": "cg", "max_iterations": 10, "tolerance": 1e-9});
    // 700 × 700 bodies: about 1.2 GB estimated, above a 1 GiB address space.
    let file = write_json(&dir, "big.json", &memory_grid(700, Some(cg)));
    let out = dir.join("out");
    let exe = env!("CARGO_BIN_EXE_dsmcosim");
    for args in [
        format!("validate '{}'", file.display()),
        format!("run '{}' --out '{}'", file.display(), out.display()),
    ] {
        let o = Command::new("sh")
            .arg("-c")
            .arg(format!("ulimit -v 1048576 && exec '{exe}' {args}"))
            .output()
            .expect("sh");
        assert_eq!(o.status.code(), Some(2), "{args}: {}", said(&o));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("model: a run needs about 1235 MB of memory")
                && err.contains("address-space limit (RLIMIT_AS, `ulimit -v`) of 1073 MB")
                && err.contains("--max-memory"),
            "{args}: {err}"
        );
        assert!(!out.exists(), "{args}: wrote {}", out.display());
    }
    // The flag still decides when given.
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 1048576 && exec '{exe}' validate '{}' --max-memory 2000000000",
            file.display()
        ))
        .output()
        .expect("sh");
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An allocation the exact solve cannot make (faer's analysis, buffers or factor under
/// a tight `ulimit -v`, the estimate overridden by `--max-memory`) is an out-of-memory
/// error, exit 1 naming memory: never a divergence or a "not positive definite"
/// matrix. Over a range of limits around the 5000-weld chain's need, every run either
/// succeeds, stops with that error, or is aborted by an allocation outside the solve
/// (what `--max-memory` takes responsibility for); at least one limit lands in the
/// solve.
#[test]
fn a_failed_allocation_of_the_solve_is_out_of_memory_not_a_divergence() {
    let dir = scratch("limits-oom");
    let file = write_json(&dir, "welds.json", &joint_chain(5000, "weld"));
    let exe = env!("CARGO_BIN_EXE_dsmcosim");
    let mut in_the_solve = 0;
    for kb in (66_000..=82_000).step_by(2_000) {
        let out = dir.join(format!("out{kb}"));
        let o = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "ulimit -v {kb} && exec '{exe}' -j 1 run '{}' --out '{}' --max-memory 1000000000",
                file.display(),
                out.display()
            ))
            .output()
            .expect("sh");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !err.contains("not positive definite") && !err.contains("diverged"),
            "ulimit -v {kb}: {err}"
        );
        match o.status.code() {
            Some(0) => {}
            Some(1) if err.contains("out of memory: the exact solve's factorization") => {
                in_the_solve += 1
            }
            // An allocation outside the solve aborted the process (SIGABRT).
            None => {}
            other => panic!("ulimit -v {kb}: exit {other:?}: {err}"),
        }
    }
    assert!(
        in_the_solve > 0,
        "no limit landed in the solve's allocations"
    );
}
