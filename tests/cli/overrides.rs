//! `--set POINTER=VALUE` on `run` and `validate`: the overridden scenario is validated
//! like a file, runs as the edited file would (same digest), and is the `scenario.json`
//! the run directory keeps; a bad override exits 2 naming it, writing nothing.

use serde_json::{json, Value};

use super::{run, said, scratch, short_grid, summary, write_json};

#[test]
fn an_override_runs_like_the_edited_file_and_is_kept() {
    let dir = scratch("overrides");
    let base = write_json(&dir, "base.json", &short_grid());
    let mut edited = short_grid();
    edited["duration"] = json!(0.5);
    edited["integrator"] = json!("rk4");
    let edited = write_json(&dir, "edited.json", &edited);
    let (a, b) = (dir.join("a"), dir.join("b"));
    let o = run(&[
        "run",
        base.to_str().unwrap(),
        "--set",
        "/duration=0.5",
        "--set",
        "/integrator=rk4",
        "--out",
        a.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", said(&o));
    let o = run(&[
        "run",
        edited.to_str().unwrap(),
        "--out",
        b.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", said(&o));
    assert_eq!(summary(&a)["digest"], summary(&b)["digest"]);
    let kept: Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("scenario.json")).unwrap()).unwrap();
    assert_eq!(kept["duration"], json!(0.5));
    assert_eq!(kept["integrator"], json!("rk4"));

    let o = run(&["validate", base.to_str().unwrap(), "--set", "/duration=0.5"]);
    assert!(o.status.success(), "{}", said(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("500 steps"),
        "{}",
        said(&o)
    );
}

#[test]
fn a_bad_override_exits_2_naming_it_and_writes_nothing() {
    let dir = scratch("overrides_bad");
    let base = write_json(&dir, "base.json", &short_grid());
    // A sweep on that base: `sweep --set` changes the base as `run --set` changes a
    // scenario, with the same refusals.
    let sweep = write_json(
        &dir,
        "sweep.json",
        &json!({"name": "s", "base": "base.json",
                "axes": [{"name": "mass", "pointer": "/model/grid/mass", "values": [1.0, 2.0]}]}),
    );
    for (set, want) in [
        (
            "/integrator=rk5",
            "integrator: unknown variant `rk5`; did you mean `rk4`? (set by `--set /integrator=rk5`)",
        ),
        ("/dt=-1", "dt"),
        (
            "/nope/x=1",
            "--set /nope/x=1: /nope/x: no key `nope` in the top level, so the parent /nope \
             does not exist",
        ),
        (
            "duration=1",
            "--set duration=1: duration: must start with `/`",
        ),
    ] {
        let out = dir.join("out");
        for (cmd, file) in [
            ("validate", &base),
            ("run", &base),
            ("sweep", &sweep),
            ("validate", &sweep),
        ] {
            let mut args = vec![cmd, file.to_str().unwrap(), "--set", set];
            if cmd != "validate" {
                args.extend(["--out", out.to_str().unwrap()]);
            }
            let o = run(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{cmd} {set}: {}", said(&o));
            assert!(
                err.contains(want),
                "{cmd} {set}: expected {want:?}: {}",
                said(&o)
            );
            // Never a position in the JSON the overrides rewrote, which the user never
            // saw.
            assert!(!err.contains("(line "), "{cmd} {set}: {}", said(&o));
        }
        assert!(!out.exists(), "{set}: wrote {}", out.display());
    }
}

#[test]
fn a_sweep_override_changes_its_base_as_editing_the_file_does() {
    let dir = scratch("overrides_sweep");
    write_json(&dir, "base.json", &short_grid());
    let mut edited = short_grid();
    edited["duration"] = json!(0.5);
    edited["integrator"] = json!("rk4");
    write_json(&dir, "edited.json", &edited);
    let axes = json!([{"name": "mass", "pointer": "/model/grid/mass", "values": [1.0, 2.0]}]);
    let sweep = write_json(
        &dir,
        "sweep.json",
        &json!({"name": "s", "base": "base.json", "axes": axes}),
    );
    let sweep_edited = write_json(
        &dir,
        "sweep_edited.json",
        &json!({"name": "s", "base": "edited.json", "axes": axes}),
    );
    let (a, b) = (dir.join("a"), dir.join("b"));
    let o = run(&[
        "sweep",
        sweep.to_str().unwrap(),
        "--set",
        "/duration=0.5",
        "--set",
        "/integrator=rk4",
        "--keep",
        "summary",
        "-o",
        a.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", said(&o));
    let o = run(&[
        "sweep",
        sweep_edited.to_str().unwrap(),
        "--keep",
        "summary",
        "-o",
        b.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", said(&o));
    let csv = |d: &std::path::Path| std::fs::read_to_string(d.join("sweep.csv")).unwrap();
    assert_eq!(csv(&a), csv(&b), "same points, same runs");
    for point in std::fs::read_dir(a.join("points")).unwrap() {
        let kept: Value = serde_json::from_str(
            &std::fs::read_to_string(point.unwrap().path().join("scenario.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(kept["duration"], json!(0.5));
        assert_eq!(kept["integrator"], json!("rk4"));
    }
    // `--resume` under other overrides reruns every point: the base is another one.
    let o = run(&[
        "sweep",
        sweep.to_str().unwrap(),
        "--set",
        "/duration=0.4",
        "--keep",
        "summary",
        "--resume",
        "-o",
        a.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", said(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("(2 run, 0 already done)"),
        "{}",
        said(&o)
    );
}
