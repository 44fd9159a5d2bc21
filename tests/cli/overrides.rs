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
        for cmd in ["validate", "run"] {
            let mut args = vec![cmd, base.to_str().unwrap(), "--set", set];
            if cmd == "run" {
                args.extend(["--out", out.to_str().unwrap()]);
            }
            let o = run(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{set}: {}", said(&o));
            assert!(err.contains(want), "{set}: expected {want:?}: {}", said(&o));
        }
        assert!(!out.exists(), "{set}: wrote {}", out.display());
    }
}
