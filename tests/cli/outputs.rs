//! What `run`, `check`, `validate` and `sweep` may delete or replace (issue "Hardening,
//! third round"; the rule is in docs/reference.md): only files the tool wrote, in a
//! directory that holds a run of its own, never through a symlink or onto a
//! non-regular file. And every failure to write is an error with the right status.

use std::path::Path;
use std::process::{Command, Output};

use serde_json::json;

use super::{bin, repo, run, said, scratch, short_grid, summary, write_json};

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A short grid run of 0.2 s into `out`.
fn short(dir: &Path, name: &str) -> std::path::PathBuf {
    let mut v = short_grid();
    v["name"] = json!(name);
    v["duration"] = json!(0.2);
    v["measurement"] = json!({"period": 0.1});
    write_json(dir, &format!("{name}.json"), &v)
}

fn exit(o: &Output) -> Option<i32> {
    o.status.code()
}

#[test]
fn check_never_reruns_over_the_stored_run() {
    let dir = scratch("out-check-work");
    let s = short(&dir, "grid");
    let stored = dir.join("stored");
    let o = run(&["run", arg(&s), "--out", arg(&stored.join("grid"))]);
    assert!(o.status.success(), "{}", said(&o));
    // A hand-edited stored trace: caught without --work (exit 4) …
    let trace = stored.join("grid/trace.csv");
    let edited = std::fs::read_to_string(&trace)
        .unwrap()
        .replacen("\n0,", "\n0.0,", 1);
    std::fs::write(&trace, &edited).unwrap();
    let o = run(&["check", arg(&s), "--against", arg(&stored)]);
    assert_eq!(exit(&o), Some(4), "{}", said(&o));
    // … and with --work equal to --against (however spelled) refused before it reruns:
    // exit 2 naming --work, the edited trace still there.
    let dotted = dir.join("stored/grid/..");
    for work in [&stored, &dotted] {
        let o = run(&[
            "check",
            arg(&s),
            "--against",
            arg(&stored),
            "--work",
            arg(work),
        ]);
        assert_eq!(exit(&o), Some(2), "{}", said(&o));
        assert!(
            said(&o).contains("--work") && said(&o).contains("stored run"),
            "{}",
            said(&o)
        );
        assert_eq!(std::fs::read_to_string(&trace).unwrap(), edited);
    }
    // One scenario's stored run itself as --against, its parent as --work.
    let o = run(&[
        "check",
        arg(&s),
        "--against",
        arg(&stored.join("grid")),
        "--work",
        arg(&stored),
    ]);
    assert_eq!(exit(&o), Some(2), "{}", said(&o));
    assert_eq!(std::fs::read_to_string(&trace).unwrap(), edited);
    // --tolerance 1e308 would pass anything: refused, printed as 1e308.
    let o = run(&[
        "check",
        arg(&s),
        "--against",
        arg(&stored),
        "--tolerance",
        "1e308",
    ]);
    assert_eq!(exit(&o), Some(2), "{}", said(&o));
    assert!(
        said(&o).contains("--tolerance") && said(&o).contains("1e308"),
        "{}",
        said(&o)
    );
}

#[test]
fn reports_never_replace_inputs_stored_runs_or_special_files() {
    let dir = scratch("out-reports");
    let s = short(&dir, "grid");
    let before = std::fs::read(&s).unwrap();
    // validate S --json S: the scenario is kept.
    let o = run(&["validate", arg(&s), "--json", arg(&s)]);
    assert_eq!(exit(&o), Some(2), "{}", said(&o));
    assert!(
        said(&o).contains("--json") && said(&o).contains("input"),
        "{}",
        said(&o)
    );
    assert_eq!(std::fs::read(&s).unwrap(), before);
    // check --json onto a stored summary.json: refused before anything runs.
    let stored = dir.join("stored");
    let o = run(&["run", arg(&s), "--out", arg(&stored)]);
    assert!(o.status.success(), "{}", said(&o));
    let stored_summary = std::fs::read(stored.join("summary.json")).unwrap();
    let o = run(&[
        "check",
        arg(&s),
        "--against",
        arg(&stored),
        "--json",
        arg(&stored.join("summary.json")),
    ]);
    assert_eq!(exit(&o), Some(2), "{}", said(&o));
    assert_eq!(
        std::fs::read(stored.join("summary.json")).unwrap(),
        stored_summary
    );
    assert!(!dir.join("stored.new").exists(), "nothing ran");
    // A symlink, a FIFO, a device node: refused, none replaced or followed.
    let target = dir.join("target.txt");
    let link = dir.join("link.json");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let fifo = dir.join("fifo.json");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    for (path, kind) in [
        (link.as_path(), "a symlink"),
        (fifo.as_path(), "a FIFO"),
        (Path::new("/dev/full"), "a device node"),
    ] {
        for args in [
            vec!["validate", arg(&s), "--json", arg(path)],
            vec![
                "check",
                arg(&s),
                "--against",
                arg(&stored),
                "--junit",
                arg(path),
            ],
        ] {
            let o = run(&args);
            assert_eq!(exit(&o), Some(2), "{args:?}: {}", said(&o));
            assert!(said(&o).contains(kind), "{args:?}: {}", said(&o));
        }
    }
    assert!(!target.exists(), "the symlink was not followed");
    let fifo_type = std::fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(std::os::unix::fs::FileTypeExt::is_fifo(&fifo_type));
    let full_type = std::fs::symlink_metadata("/dev/full").unwrap().file_type();
    assert!(std::os::unix::fs::FileTypeExt::is_char_device(&full_type));
}

#[test]
fn a_run_replaces_only_its_own_files() {
    let dir = scratch("out-own-files");
    let s = short(&dir, "grid");
    // A directory with the user's figures, one of them named like a run's plot: the
    // run is refused, nothing deleted.
    let figures = dir.join("figures");
    std::fs::create_dir_all(&figures).unwrap();
    std::fs::write(figures.join("mine.svg"), "<svg/>").unwrap();
    std::fs::write(figures.join("bodies.svg"), "<svg>the user's</svg>").unwrap();
    let o = run(&["run", arg(&s), "--out", arg(&figures)]);
    assert_eq!(exit(&o), Some(2), "{}", said(&o));
    assert!(said(&o).contains("bodies.svg") && said(&o).contains("holds no dsmcosim run"));
    assert_eq!(
        std::fs::read_to_string(figures.join("bodies.svg")).unwrap(),
        "<svg>the user's</svg>"
    );
    // Without the clash it runs, and keeps the user's other figures, also on a rerun.
    std::fs::remove_file(figures.join("bodies.svg")).unwrap();
    for _ in 0..2 {
        let o = run(&["run", arg(&s), "--out", arg(&figures)]);
        assert!(o.status.success(), "{}", said(&o));
        assert!(
            figures.join("mine.svg").is_file(),
            "the user's figure is kept"
        );
    }
    // A symlink at the lock file's name is refused, not followed.
    let locked = dir.join("locked");
    std::fs::create_dir_all(&locked).unwrap();
    let victim = dir.join("victim.txt");
    std::fs::write(&victim, "keep me").unwrap();
    std::os::unix::fs::symlink(&victim, locked.join(".dsmcosim.lock")).unwrap();
    let o = run(&["run", arg(&s), "--out", arg(&locked)]);
    assert_eq!(exit(&o), Some(2), "{}", said(&o));
    assert!(said(&o).contains(".dsmcosim.lock") && said(&o).contains("symlink"));
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep me");
    // An output name taken by a symlink in a run's own directory: refused, not replaced.
    std::fs::remove_file(figures.join("epochs.csv")).unwrap();
    std::os::unix::fs::symlink(&victim, figures.join("epochs.csv")).unwrap();
    let o = run(&["run", arg(&s), "--out", arg(&figures)]);
    assert_eq!(exit(&o), Some(2), "{}", said(&o));
    assert!(std::fs::symlink_metadata(figures.join("epochs.csv"))
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep me");
}

#[test]
fn force_over_another_scenario_removes_its_checkpoints() {
    let dir = scratch("out-force-checkpoints");
    let (a, b) = (short(&dir, "first"), short(&dir, "second"));
    let out = dir.join("out");
    let o = run(&[
        "run",
        arg(&a),
        "--out",
        arg(&out),
        "--checkpoint-every",
        "0.1",
    ]);
    assert!(o.status.success(), "{}", said(&o));
    let cps = out.join("checkpoints");
    assert_eq!(std::fs::read_dir(&cps).unwrap().count(), 1);
    // The same scenario again keeps them (a run may resume from one).
    let o = run(&["run", arg(&a), "--out", arg(&out)]);
    assert!(o.status.success(), "{}", said(&o));
    assert!(cps.is_dir());
    // Another scenario, forced: the first one's checkpoints go with its run.
    let o = run(&["run", arg(&b), "--out", arg(&out), "--force"]);
    assert!(o.status.success(), "{}", said(&o));
    assert!(
        !cps.exists(),
        "checkpoints of `first` left under a run of `second`"
    );
    assert_eq!(summary(&out)["scenario"], json!("second"));
}

#[test]
fn a_rerun_that_cannot_write_keeps_the_previous_outputs() {
    let dir = scratch("out-full-disk");
    let s = short(&dir, "grid");
    let out = dir.join("out");
    let o = run(&["run", arg(&s), "--out", arg(&out)]);
    assert!(o.status.success(), "{}", said(&o));
    let names = [
        "summary.json",
        "trace.csv",
        "epochs.csv",
        "bodies.svg",
        "constraints.svg",
    ];
    let before: Vec<Vec<u8>> = names
        .iter()
        .map(|n| std::fs::read(out.join(n)).unwrap())
        .collect();
    // A longer rerun whose trace cannot be written: file size limited to 8 kB (the
    // signal ignored, so that the write fails with EFBIG as on a full disk).
    let mut longer = short_grid();
    longer["name"] = json!("grid");
    longer["duration"] = json!(2.0);
    longer["output"]["decimation"] = json!(1);
    std::fs::write(&s, serde_json::to_string(&longer).unwrap()).unwrap();
    let o = Command::new("sh")
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 16; exec \"$0\" run \"$1\" --out \"$2\"")
        .arg(env!("CARGO_BIN_EXE_dsmcosim"))
        .arg(&s)
        .arg(&out)
        .output()
        .expect("sh");
    assert_eq!(exit(&o), Some(1), "{}", said(&o));
    for (n, b) in names.iter().zip(&before) {
        assert_eq!(
            &std::fs::read(out.join(n)).unwrap(),
            b,
            "{n} of the previous run"
        );
    }
    for e in std::fs::read_dir(&out).unwrap() {
        let name = e.unwrap().file_name().into_string().unwrap();
        assert!(!name.contains(".tmp."), "leftover {name}");
    }
}

#[test]
fn write_failures_are_errors_with_their_own_status() {
    let dir = scratch("out-failures");
    let s = short(&dir, "grid");
    // stdout on a full device: the command's files are written, the exit is 1.
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let o = bin()
        .args(["validate", arg(&s)])
        .stdout(full)
        .output()
        .unwrap();
    assert_eq!(exit(&o), Some(1), "{}", said(&o));
    assert!(said(&o).contains("standard output"), "{}", said(&o));
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let out = dir.join("out");
    let o = bin()
        .args(["run", arg(&s), "--out", arg(&out)])
        .stdout(full)
        .output()
        .unwrap();
    assert_eq!(exit(&o), Some(1), "{}", said(&o));
    assert_eq!(
        summary(&out)["status"],
        json!("ok"),
        "the run itself is fine"
    );
    // A checkpoint that cannot be written (a file named `checkpoints`): exit 1 and the
    // summary says `failed`, not `diverged`.
    let out = dir.join("ckpt");
    std::fs::create_dir_all(&out).unwrap();
    let o = run(&["run", arg(&s), "--out", arg(&out)]);
    assert!(o.status.success(), "{}", said(&o));
    std::fs::write(out.join("checkpoints"), "in the way").unwrap();
    let o = run(&[
        "run",
        arg(&s),
        "--out",
        arg(&out),
        "--checkpoint-every",
        "0.1",
    ]);
    assert_eq!(exit(&o), Some(1), "{}", said(&o));
    assert_eq!(summary(&out)["status"], json!("failed"));
    // Not a divergence: `error` says what stopped it, and no divergence object claims
    // a time and place for it.
    assert_eq!(summary(&out)["divergence"], json!(null));
    assert!(summary(&out)["error"]
        .as_str()
        .is_some_and(|e| !e.is_empty()));
    // --checkpoint-every 1e308 says what is wrong, in a short number.
    let o = run(&[
        "run",
        arg(&s),
        "--out",
        arg(&out),
        "--checkpoint-every",
        "1e308",
    ]);
    assert_eq!(exit(&o), Some(2), "{}", said(&o));
    assert!(
        said(&o).contains("beyond the range of simulated time (got 1e308 s"),
        "{}",
        said(&o)
    );
}

#[test]
fn a_divergence_counts_its_own_step_in_the_largest_violation() {
    let dir = scratch("out-divergence-max");
    let mut v = short_grid();
    v["dt"] = json!(0.04);
    v["duration"] = json!(20.0);
    let file = write_json(&dir, "s.json", &v);
    let out = dir.join("out");
    let o = run(&["run", arg(&file), "--out", arg(&out)]);
    assert_eq!(exit(&o), Some(3), "{}", said(&o));
    let s = summary(&out);
    let what = s["divergence"]["what"].as_str().unwrap().to_string();
    // `|w| = 1.028e0 m > bound 1 m` or a non-finite value.
    let reported: Option<f64> = what
        .split("|w| = ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|x| x.parse().ok());
    let max = s["max_constraint_violation"].as_f64().unwrap();
    match reported {
        Some(w) => assert!(max >= w, "max {max} below the diverging |w| {w}: {what}"),
        None => assert!(max > 0.0, "{what}"),
    }
}

#[test]
fn a_second_sweep_into_a_running_sweep_is_refused() {
    let dir = scratch("out-sweep-lock");
    let mut base = short_grid();
    base["duration"] = json!(0.2);
    base["measurement"] = json!({"period": 0.1});
    write_json(&dir, "base.json", &base);
    let sweep = json!({"name": "s", "base": "base.json",
        "axes": [{"name": "s", "pointer": "/seed", "values": [1, 2]}]});
    let file = write_json(&dir, "sweep.json", &sweep);
    let out = dir.join("out");
    let o = run(&["sweep", arg(&file), "--out", arg(&out)]);
    assert!(o.status.success(), "{}", said(&o));
    // Another process holds the sweep's lock: `--resume` exits 1 naming it.
    let lock = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(out.join(".dsmcosim-sweep.lock"))
        .expect("the sweep left its lock file");
    lock.try_lock().expect("no sweep holds it now");
    let o = run(&["sweep", arg(&file), "--out", arg(&out), "--resume"]);
    assert_eq!(exit(&o), Some(1), "{}", said(&o));
    assert!(
        said(&o).contains("in use by another dsmcosim sweep"),
        "{}",
        said(&o)
    );
    drop(lock);
    let o = run(&["sweep", arg(&file), "--out", arg(&out), "--resume"]);
    assert!(o.status.success(), "released: {}", said(&o));
}

#[test]
fn distance_quotes_a_run_path_with_a_comma() {
    let dir = scratch("out-distance-comma");
    let s = short(&dir, "grid");
    let (a, b) = (dir.join("ref"), dir.join("run, with comma"));
    for out in [&a, &b] {
        let o = run(&["run", arg(&s), "--out", arg(out)]);
        assert!(o.status.success(), "{}", said(&o));
    }
    let out = dir.join("cmp");
    let o = run(&[
        "distance",
        arg(&a),
        arg(&b),
        "--bodies",
        "1",
        "--out",
        arg(&out),
    ]);
    assert!(o.status.success(), "{}", said(&o));
    let csv = std::fs::read_to_string(out.join("distance.csv")).unwrap();
    let mut r = csv::Reader::from_reader(csv.as_bytes());
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header, ["t".to_string(), format!("{}_B1", b.display())]);
}

/// Every study command keeps `run`'s rule: a file of one of its output names in a
/// directory it has not claimed (no manifest: sweep.json, coupling.csv, …) is the
/// user's. The command refuses it with exit 2 before computing anything, and the file
/// is left as it was.
#[test]
fn no_command_replaces_a_users_file_in_a_directory_it_has_not_claimed() {
    let dir = scratch("out-foreign-files");
    let repo = repo();
    let path = |p: &str| repo.join(p).display().to_string();
    let cases: Vec<(Vec<String>, &str, &str)> = vec![
        (
            vec![
                "sweep".into(),
                path("scenarios/sweeps/tdma4_slot_layouts.json"),
            ],
            "timing.csv",
            "sweep.json",
        ),
        (vec!["sweep-merge".into()], "sweep.csv", "sweep.json"),
        (
            vec!["coupling".into(), path("scenarios/mechanisms/ring12.json")],
            "coupling.md",
            "coupling.csv",
        ),
        (
            vec!["tradeoff".into(), path("scenarios/grid16_monolithic.json")],
            "pareto.svg",
            "tradeoff.csv",
        ),
        (
            vec![
                "stability-map".into(),
                path("scenarios/grid16_monolithic.json"),
            ],
            "stability_map.svg",
            "stability_map.csv",
        ),
        (
            vec![
                "distance".into(),
                path("results/grid16_monolithic"),
                path("results/grid16_space_fixed"),
                "--bodies".into(),
                "1".into(),
            ],
            "distance.svg",
            "distance.csv",
        ),
    ];
    for (i, (mut args, theirs, manifest)) in cases.into_iter().enumerate() {
        let out = dir.join(format!("case{i}"));
        std::fs::create_dir_all(&out).expect("mkdir");
        std::fs::write(out.join(theirs), "the user's own\n").expect("write");
        args.extend(["--out".into(), out.display().to_string()]);
        if args[0] == "sweep-merge" {
            // A shard, never read: the refusal comes first.
            args.push(dir.join("no-shard").display().to_string());
        }
        let argv: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = run(&argv);
        assert_eq!(exit(&o), Some(2), "{args:?}: {}", said(&o));
        assert!(
            said(&o).contains(&format!(
                "holds {theirs}, which dsmcosim did not write there (no {manifest} beside it)"
            )),
            "{args:?}: {}",
            said(&o)
        );
        assert_eq!(
            std::fs::read_to_string(out.join(theirs)).expect("still there"),
            "the user's own\n"
        );
        assert!(!out.join(manifest).exists(), "{args:?} wrote {manifest}");
    }
}
