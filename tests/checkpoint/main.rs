//! Checkpoint/resume: a run resumed from any of its checkpoints ends with the same
//! digest and the same output files as the uninterrupted run; a bad checkpoint is a
//! clear error.

use std::path::{Path, PathBuf};
use std::process::Command;

use dsmcosim::kernel::SimTime;
use dsmcosim::run::{resume, run_with, RunOptions};
use dsmcosim::scenario::parse_str;
use serde_json::{json, Value};

/// Where [`scratch`] puts `name` (without clearing it).
fn scratch_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("test-scratch")
        .join(name)
}

fn scratch(name: &str) -> PathBuf {
    let d = scratch_path(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch");
    d
}

fn shipped(name: &str) -> Value {
    let p = format!("{}/scenarios/{name}.json", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(p).expect("scenario")).expect("json")
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Runs `v` with checkpoints every `every` s, resumes from each checkpoint, and checks
/// digest, trace.csv and epochs.csv against the uninterrupted run.
fn check_resume(name: &str, v: &Value, every: f64, expected_checkpoints: usize) {
    let dir = scratch(name);
    let s = parse_str(&v.to_string(), name).expect("scenario");
    let opts = RunOptions {
        checkpoint_every: SimTime::from_secs_f64(every),
        ..RunOptions::default()
    };
    let full = run_with(&s, &dir.join("full"), opts);
    let plain = run_with(&s, &dir.join("plain"), RunOptions::default());
    // Checkpointing itself changes nothing.
    let digest = |r: &dsmcosim::Result<dsmcosim::run::Outcome>, d: &Path| match r {
        Ok(o) => o.digest.clone(),
        Err(_) => {
            let s: Value = serde_json::from_slice(&read(&d.join("summary.json"))).unwrap();
            s["digest"].as_str().unwrap().to_string()
        }
    };
    let want = digest(&full, &dir.join("full"));
    assert_eq!(
        want,
        digest(&plain, &dir.join("plain")),
        "{name}: checkpointing changed the run"
    );
    let mut cps: Vec<PathBuf> = std::fs::read_dir(dir.join("full/checkpoints"))
        .expect("checkpoints")
        .map(|e| e.unwrap().path())
        .collect();
    cps.sort();
    assert_eq!(cps.len(), expected_checkpoints, "{name}: {cps:?}");
    for (i, cp) in cps.iter().enumerate() {
        let out = dir.join(format!("resumed{i}"));
        let r = resume(cp, &out, RunOptions::default());
        assert_eq!(
            digest(&r, &out),
            want,
            "{name}: resumed from {}",
            cp.display()
        );
        for f in ["trace.csv", "epochs.csv", "network.csv", "summary.json"] {
            let stored = dir.join("full").join(f);
            if !stored.exists() {
                continue;
            }
            if f == "summary.json" {
                // Wall times differ; everything the network and controller report
                // must not.
                let strip = |p: &Path| {
                    let mut s: Value = serde_json::from_slice(&read(p)).unwrap();
                    for k in ["wall_seconds", "real_time_factor"] {
                        s.as_object_mut().unwrap().remove(k);
                    }
                    s
                };
                assert_eq!(strip(&out.join(f)), strip(&stored), "{name}: {f}");
                continue;
            }
            assert!(
                read(&out.join(f)) == read(&dir.join("full").join(f)),
                "{name}: {f} differs after resuming from {}",
                cp.display()
            );
        }
    }
}

#[test]
fn monolithic_run_resumes_bit_for_bit() {
    let mut v = shipped("grid16_monolithic");
    v["duration"] = json!(5.0);
    check_resume("mono", &v, 1.7, 2);
}

#[test]
fn sparse_solver_run_resumes_bit_for_bit() {
    // 8×8 grid: 112 links, above the dense limit, so the ordered sparse factorization
    // is analysed again after the restore (the same AMD order, so the same bits).
    let v = json!({
        "name": "grid64", "seed": 1, "duration": 1.0, "dt": 0.001,
        "model": {"grid": {"rows": 8, "cols": 8, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0}],
        "output": {"decimation": 50}
    });
    check_resume("sparse", &v, 0.4, 2);
}

#[test]
fn a_reused_factor_resumes_bit_for_bit() {
    // The same grid on `cholesky_pcg`: with RK4's 4 solves per step and a factorization
    // every 7 solves, both checkpoints (steps 400 and 800) fall between factorizations,
    // so the restored run must rebuild the factor it was iterating with.
    let v = json!({
        "name": "grid64", "seed": 1, "duration": 1.0, "dt": 0.001, "integrator": "rk4",
        "solver": {"kind": "cholesky_pcg", "refactor_every": 7},
        "model": {"grid": {"rows": 8, "cols": 8, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0}],
        "output": {"decimation": 50}
    });
    check_resume("pcg", &v, 0.4, 2);
}

#[test]
fn invariants_rotations_and_the_boundary_layer_resume_bit_for_bit() {
    // A rigid net (off-centre anchors) with its rotation traced, a load strong enough to
    // leave the boundary layer, switched off at 0.6 s: the undriven stretch 0.6–1.2 s
    // starts between the two checkpoints (0.5 s, 1.0 s) and ends after both, so its
    // start, the run's start and the layer's counts must all come from the checkpoint.
    let v = json!({
        "name": "rigid_invariants", "seed": 1, "duration": 1.2, "dt": 0.001,
        "integrator": "symplectic_euler",
        "model": {
            "bodies": [
                {"id": 1, "mass": 1.0, "size": 0.2, "position": [0, 0, 0],
                 "angular_velocity": [0, 0, 2.0]},
                {"id": 2, "mass": 2.0, "size": 0.3, "position": [2, 0, 0],
                 "velocity": [0, 0.4, 0]},
                {"id": 3, "mass": 1.5, "size": 0.25, "position": [1, 1.7, 0.3]}
            ],
            "links": [
                {"a": 1, "b": 2, "anchor_a": [0.1, 0, 0]},
                {"a": 2, "b": 3, "anchor_b": [0.1, -0.1, 0]},
                {"a": 3, "b": 1}
            ]
        },
        "forces": [{"body": 1, "amplitude": [0, 0, 300], "omega": 3.0, "until": 0.6}],
        "output": {"decimation": 7, "trace_rotation": true}
    });
    check_resume("invariants", &v, 0.5, 2);
    let s: Value =
        serde_json::from_slice(&read(&scratch_path("invariants").join("full/summary.json")))
            .unwrap();
    assert!(
        s["boundary_layer"]["steps_outside"].as_u64() > Some(0),
        "the scene leaves the layer: {}",
        s["boundary_layer"]
    );
    assert_eq!(s["invariants"]["undriven"][0]["from"], json!(0.6));
    assert_eq!(s["invariants"]["undriven"][0]["to"], json!(1.2));
}

#[test]
fn partitioned_fixed_delay_run_resumes_with_messages_in_flight() {
    let mut v = shipped("grid16_space_fixed");
    v["duration"] = json!(4.0);
    // 0.5035 s: mid-period for the 5 ms channels, messages in flight.
    check_resume("fixed", &v, 0.5035, 7);
}

#[test]
fn every_coupling_scheme_resumes_bit_for_bit() {
    // The scheme's state (ghost histories, extrapolated loads, port accounts) is part of
    // the checkpoint; the time distribution puts states and forces on two channels.
    for coupling in ["reset", "predict", "passive"] {
        let mut v = shipped("grid16_time_fixed");
        v["duration"] = json!(2.0);
        v["partition"]["coupling"] = json!(coupling);
        check_resume(&format!("coupling_{coupling}"), &v, 0.5035, 3);
    }
    // Transmission lines (waves in flight, held and filtered waves, open windows):
    // `tlm` at 5 ms, and the default at 50 ms, where its border links are lines.
    let mut v = shipped("grid16_time_fixed");
    v["duration"] = json!(2.0);
    v["partition"]["coupling"] = json!("tlm");
    check_resume("coupling_tlm", &v, 0.5035, 3);
    let mut v = shipped("grid16_time_fixed");
    v["duration"] = json!(2.0);
    for c in v["channels"].as_array_mut().expect("channels") {
        c["tau"] = json!(0.05);
    }
    check_resume("coupling_default_50ms", &v, 0.5335, 3);
}

#[test]
fn tdma_run_with_drift_and_jitter_resumes_bit_for_bit() {
    let mut v = shipped("tdma4_space_fixed");
    v["duration"] = json!(3.0);
    v["output"]["network_decimation"] = json!(7);
    // 0.5023 s: mid-cycle (5 ms cycles), frames and messages in flight.
    check_resume("tdma", &v, 0.5023, 5);
}

#[test]
fn joints_under_gravity_resume_bit_for_bit() {
    // The crane: a hinge to the world, a border ball joint on TDMA, a torque, gravity.
    let mut v = shipped("crane");
    v["duration"] = json!(3.0);
    check_resume("crane", &v, 0.5023, 5);
    // The hanging chain: ten ball joints, a border joint under `predict` and under the
    // default coupling.
    let mut v = shipped("hanging_chain");
    v["duration"] = json!(2.0);
    check_resume("hanging_chain", &v, 0.5035, 3);
    v["partition"]
        .as_object_mut()
        .expect("partition")
        .remove("coupling");
    check_resume("hanging_chain_default", &v, 0.5035, 3);
}

#[test]
fn controlled_tdma_run_resumes_with_its_pending_lists() {
    let mut v = shipped("tdma4_space_cp");
    v["duration"] = json!(4.0);
    v["controller"]["surface_window"] = json!(2.0);
    check_resume("tdma_cp", &v, 1.0, 3);
}

#[test]
fn controlled_dsm_run_resumes_with_its_simplex() {
    let mut v = shipped("grid16_space_cp_ds2");
    v["duration"] = json!(5.0);
    v["controller"]["surface_window"] = json!(2.0);
    // Checkpoints at the first window boundary at or after 1.5 s and 3 s: 2 s and 3 s.
    check_resume("dsm", &v, 1.5, 2);
}

#[test]
fn bad_checkpoints_are_clear_errors() {
    let dir = scratch("bad_checkpoint");
    let mut v = shipped("grid16_monolithic");
    v["duration"] = json!(1.0);
    let s = parse_str(&v.to_string(), "t").unwrap();
    run_with(
        &s,
        &dir.join("full"),
        RunOptions {
            checkpoint_every: SimTime::from_secs_f64(0.5),
            ..RunOptions::default()
        },
    )
    .unwrap();
    let cp = dir.join("full/checkpoints/t_000000.500000000.ckpt");
    let bytes = std::fs::read(&cp).unwrap();
    let mut foreign = bytes.clone();
    foreign[16..20].copy_from_slice(&99u32.to_le_bytes());
    let mut extended = bytes.clone();
    extended.push(0);
    let mut cases: Vec<(String, Vec<u8>, &str)> = vec![
        (
            "truncated".into(),
            bytes[..bytes.len() / 2].to_vec(),
            "corrupted or truncated",
        ),
        (
            "header_only".into(),
            bytes[..30].to_vec(),
            "corrupted or truncated",
        ),
        ("extended".into(), extended, "corrupted or truncated"),
        ("foreign".into(), foreign, "version 99"),
        (
            "other".into(),
            b"{\"hello\": 1}".to_vec(),
            "not a dsmcosim checkpoint",
        ),
        ("empty".into(), Vec::new(), "not a dsmcosim checkpoint"),
    ];
    // One flipped bit anywhere: the magic, the version, the body hash, the first body
    // byte, a quarter, the middle, three quarters in, and the last byte.
    let n = bytes.len();
    let flips = [
        (5, "not a dsmcosim checkpoint"),
        (17, "cannot be read by this binary"),
        (20, "corrupted or truncated"),
        (51, "corrupted or truncated"),
        (52, "corrupted or truncated"),
        (n / 4, "corrupted or truncated"),
        (n / 2, "corrupted or truncated"),
        (3 * n / 4, "corrupted or truncated"),
        (n - 1, "corrupted or truncated"),
    ];
    for (at, want) in flips {
        for bit in [0, 7] {
            let mut flipped = bytes.clone();
            flipped[at] ^= 1 << bit;
            cases.push((format!("flip_{at}_{bit}"), flipped, want));
        }
    }
    for (name, body, want) in cases {
        let p = dir.join(format!("{name}.ckpt"));
        std::fs::write(&p, body).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
            .args(["resume", p.to_str().unwrap(), "--out"])
            .arg(dir.join(format!("out_{name}")))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(want), "{name}: {err:?} must say {want:?}");
        assert_eq!(
            err.trim_end().lines().count(),
            1,
            "{name}: one line: {err:?}"
        );
        assert!(
            err.contains(p.to_str().unwrap()),
            "{name}: {err:?} must name the file"
        );
        assert!(
            !dir.join(format!("out_{name}")).exists(),
            "{name}: nothing written"
        );
    }
    // The untouched checkpoint still resumes.
    let o = Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .args(["resume", cp.to_str().unwrap(), "--out"])
        .arg(dir.join("out_good"))
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{}\n--- stdout ---\n{}\n--- stderr ---\n{}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A checkpoint whose carried trace lines were edited, and its hash recomputed, resumes
/// to the same run digest (which covers the bits of every step, not the text of the
/// rows) — but to a different `trace_digest`, which covers the bytes of trace.csv. So
/// a resumed run vouches for its trace text through `trace_digest`.
#[test]
fn edited_trace_lines_in_a_checkpoint_change_the_trace_digest() {
    let dir = scratch("tampered");
    let mut v = shipped("grid16_monolithic");
    v["duration"] = json!(2.0);
    let s = parse_str(&v.to_string(), "tampered").expect("scenario");
    let opts = RunOptions {
        checkpoint_every: SimTime::from_secs_f64(1.0),
        ..RunOptions::default()
    };
    let full = run_with(&s, &dir.join("full"), opts).expect("runs");
    let cp = dir
        .join("full/checkpoints")
        .join(dsmcosim::checkpoint::file_name(
            SimTime::from_secs_f64(1.0).unwrap(),
        ));
    let honest = resume(&cp, &dir.join("honest"), RunOptions::default()).expect("resumes");
    assert_eq!(honest.digest, full.digest);
    assert_eq!(honest.trace_digest, full.trace_digest);
    assert!(full.trace_digest.is_some());

    // Change one digit of the first data row the checkpoint carries, then re-hash.
    let mut bytes = read(&cp);
    let header = 16 + 4 + 32;
    let body_start = header;
    let row = b"\n0.1,";
    let at = bytes[body_start..]
        .windows(row.len())
        .position(|w| w == row)
        .map(|i| body_start + i + 1 + row.len())
        .expect("a carried trace row at t = 0.1 s");
    let digit = bytes[at..].iter().position(u8::is_ascii_digit).unwrap() + at;
    bytes[digit] = if bytes[digit] == b'1' { b'2' } else { b'1' };
    let hash = *blake3::hash(&bytes[header..]).as_bytes();
    bytes[16 + 4..header].copy_from_slice(&hash);
    let forged = dir.join("forged.ckpt");
    std::fs::write(&forged, &bytes).unwrap();
    let r = resume(&forged, &dir.join("forged"), RunOptions::default()).expect("resumes");
    assert_eq!(
        r.digest, full.digest,
        "the run digest does not see the text"
    );
    assert_ne!(r.trace_digest, full.trace_digest, "the trace digest does");
    assert!(read(&dir.join("forged/trace.csv")) != read(&dir.join("full/trace.csv")));
}
