//! The conventions users of cargo, ripgrep, OMNeT++ or ns-3 expect: `--version` with the
//! commit and compiler, `-o` for `--out`, `-j` for threads (the same bits at any
//! count), `-q` and `-v`, shell completions and man pages generated from the command
//! line's definition, and `--set` on every command that reads a scenario.

use serde_json::json;

use super::{bin, repo, run, said, scratch, shipped, summary, write_json};

#[test]
fn version_names_the_commit_and_the_compiler() {
    let o = run(&["--version"]);
    assert!(o.status.success(), "{}", said(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.starts_with("dsmcosim "), "{text}");
    assert!(
        text.contains("(commit ") && text.contains("rustc"),
        "{text}"
    );
}

#[test]
fn short_flags_quiet_verbose_and_jobs() {
    let dir = scratch("conventions_flags");
    let mut v = shipped("grid16_space_fixed");
    v["duration"] = json!(1.0);
    let file = write_json(&dir, "s.json", &v);
    let f = file.to_str().unwrap();
    let out = |name: &str| dir.join(name).to_str().unwrap().to_string();
    // -o, -q: the run writes its files and prints nothing.
    let q = run(&["-q", "run", f, "-o", &out("quiet")]);
    assert!(q.status.success(), "{}", said(&q));
    assert!(q.stdout.is_empty(), "{}", said(&q));
    // -v: the plan first (what validate prints), then the usual lines.
    let verbose = run(&["run", f, "-o", &out("verbose"), "-v"]);
    assert!(verbose.status.success(), "{}", said(&verbose));
    let text = String::from_utf8_lossy(&verbose.stdout);
    assert!(text.contains("node 1") && text.contains("digest"), "{text}");
    // -j: one thread and two give the same digest as the default.
    let one = run(&["run", f, "-o", &out("j1"), "-j", "1"]);
    let two = run(&["-j", "2", "run", f, "-o", &out("j2")]);
    assert!(
        one.status.success() && two.status.success(),
        "{}",
        said(&one)
    );
    let digest = |d: &str| summary(&dir.join(d))["digest"].clone();
    assert_eq!(digest("j1"), digest("quiet"));
    assert_eq!(digest("j2"), digest("quiet"));
    assert_eq!(digest("verbose"), digest("quiet"));
    // -q and -v together are refused as clap refuses conflicting flags.
    let both = run(&["-q", "-v", "run", f, "-o", &out("both")]);
    assert_eq!(both.status.code(), Some(2), "{}", said(&both));
    let zero = run(&["-j", "0", "run", f, "-o", &out("j0")]);
    assert_eq!(zero.status.code(), Some(2), "{}", said(&zero));
}

#[test]
fn completions_and_man_pages_come_from_the_definition() {
    for (shell, marker) in [
        ("bash", "_dsmcosim()"),
        ("zsh", "#compdef dsmcosim"),
        ("fish", "complete -c dsmcosim"),
    ] {
        let o = run(&["completions", shell]);
        assert!(o.status.success(), "{shell}: {}", said(&o));
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains(marker), "{shell}: no `{marker}`");
        for sub in ["validate", "run", "coupling", "sweep"] {
            assert!(text.contains(sub), "{shell}: completes `{sub}`");
        }
    }
    let dir = scratch("conventions_man");
    let o = run(&["man", "-o", dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", said(&o));
    for page in [
        "dsmcosim.1",
        "dsmcosim-run.1",
        "dsmcosim-coupling.1",
        "dsmcosim-man.1",
    ] {
        let text =
            std::fs::read_to_string(dir.join(page)).unwrap_or_else(|e| panic!("{page}: {e}"));
        assert!(text.contains(".TH"), "{page} is a man page");
    }
    let run_page = std::fs::read_to_string(dir.join("dsmcosim-run.1")).unwrap();
    assert!(
        run_page.contains("checkpoint"),
        "the run page carries its options"
    );
    // Its synopsis is the command a user types, with the global options it takes.
    let synopsis = run_page
        .split(".SH SYNOPSIS")
        .nth(1)
        .and_then(|s| s.split(".SH").next())
        .expect("a synopsis");
    assert!(synopsis.contains("dsmcosim run"), "{synopsis}");
    assert!(!synopsis.contains("dsmcosim\\-run"), "{synopsis}");
    for global in ["jobs", "quiet", "verbose"] {
        assert!(synopsis.contains(global), "{global} in {synopsis}");
    }
    // One page on standard output, the same bytes as the file.
    let o = run(&["man", "run"]);
    assert!(o.status.success(), "{}", said(&o));
    assert_eq!(String::from_utf8_lossy(&o.stdout), run_page);
    let o = run(&["man", "nosuch"]);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(
        said(&o).contains("COMMAND: no subcommand `nosuch`"),
        "{}",
        said(&o)
    );
}

#[test]
fn every_command_that_reads_a_scenario_takes_set() {
    // The override is applied before the study checks the scenario: dropping the
    // partition makes the coupling study refuse it, naming `partition`; a bad pointer
    // is refused naming the override, on each study command; nothing is written.
    let dir = scratch("conventions_set");
    let ring = repo().join("scenarios/mechanisms/ring12.json");
    let ring = ring.to_str().unwrap();
    let out = dir.join("out");
    // (command, override, what the refusal names)
    let cases = [
        ("coupling", "/partition=null", "partition"),
        ("coupling", "/nowhere/deep=1", "--set /nowhere/deep=1"),
        ("tradeoff", "/nowhere/deep=1", "--set /nowhere/deep=1"),
        ("stability-map", "/nowhere/deep=1", "--set /nowhere/deep=1"),
    ];
    for (command, set, named) in cases {
        let o = run(&[command, ring, "--set", set, "-o", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{command} {set}: {}", said(&o));
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains(named), "{command} {set}: {}", said(&o));
    }
    assert!(!out.exists(), "nothing written");
    // And a good override changes what runs: the study of a 1.2-s ring.
    let o = run(&[
        "coupling",
        ring,
        "--set",
        "/duration=1.2",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", said(&o));
    let md = std::fs::read_to_string(out.join("coupling.md")).unwrap();
    assert!(md.contains("ring12"), "{md}");
}

#[test]
fn a_file_of_the_other_kind_or_a_mistyped_key_gets_a_pointer_to_the_fix() {
    let dir = scratch("conventions_messages");
    let sweep = repo().join("scenarios/sweeps/tdma4_slot_layouts.json");
    let scenario = repo().join("scenarios/grid16_space_fixed.json");
    let out = dir.join("out");
    let o = run(&["run", sweep.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("dsmcosim sweep"),
        "{}",
        said(&o)
    );
    let o = run(&[
        "sweep",
        scenario.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("dsmcosim run"),
        "{}",
        said(&o)
    );
    assert!(!out.exists(), "nothing written");
    let mut v = shipped("grid16_space_fixed");
    let dt = v["dt"].take();
    v.as_object_mut().unwrap().remove("dt");
    v["dtt"] = dt;
    let file = write_json(&dir, "typo.json", &v);
    let o = run(&["validate", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("`dtt`; did you mean `dt`?"), "{e}");
    // An output "directory" that is a file: exit 2, saying so, the file untouched.
    let notes = dir.join("notes.md");
    std::fs::write(&notes, "mine").unwrap();
    // The same for every command that writes into an --out directory.
    let ring = repo().join("scenarios/mechanisms/ring12.json");
    for (command, input) in [("run", &scenario), ("coupling", &ring)] {
        let o = run(&[
            command,
            input.to_str().unwrap(),
            "-o",
            notes.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{command}: {}", said(&o));
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("is a file, not a directory"),
            "{command}: {}",
            said(&o)
        );
        assert_eq!(std::fs::read_to_string(&notes).unwrap(), "mine");
    }
    // A missing stored run: the command that stores it.
    let refs = dir.join("refs");
    std::fs::create_dir_all(&refs).unwrap();
    let o = run(&[
        "check",
        scenario.to_str().unwrap(),
        "--against",
        refs.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", said(&o));
    let both = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(both.contains("store one with `dsmcosim run"), "{both}");
}

/// A run of 3000 s of simulated time of a net at rest (about a minute of wall time),
/// with `extra` arguments, sent SIGINT once it has claimed its directory and run 0.3 s
/// more: what it said, and its directory. Guarded against a hang only (300 s).
fn interrupted_run(name: &str, extra: &[&str]) -> (std::process::Output, std::path::PathBuf) {
    let dir = scratch(name);
    let out = dir.join("out");
    let scenario = repo().join("scenarios/grid16_monolithic.json");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .args([
            "run",
            scenario.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--set",
            "/duration=3000",
            "--set",
            "/output/decimation=10000",
            // At rest, so that nothing can diverge before the signal lands.
            "--set",
            "/forces=[]",
        ])
        .args(extra)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    // A hang guard, not a time assertion: at most 15 000 polls 20 ms apart.
    let mut polls = 0;
    while !out.join("trace.csv").exists() && !has_temporary(&out) {
        polls += 1;
        assert!(polls < 15_000, "the run never started");
        if let Some(status) = child.try_wait().expect("try_wait") {
            panic!("the run ended ({status}) before it was interrupted");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    // SAFETY: kill(2) on the child's pid, which has not been waited for.
    let rc = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    assert_eq!(rc, 0);
    (child.wait_with_output().expect("wait"), out)
}

#[test]
fn ctrl_c_stops_a_run_cleanly_and_says_how_to_continue() {
    // It stops at the end of its slice, writes what it has (summary.json
    // "interrupted", no temporary file left), exits 130 and names the option that
    // makes a run resumable.
    let (o, out) = interrupted_run("conventions_ctrl_c", &[]);
    assert_eq!(o.status.code(), Some(130), "{}", said(&o));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("interrupted at t = ") && e.contains("--checkpoint-every"),
        "{e}"
    );
    assert_eq!(summary(&out)["status"], json!("interrupted"));
    // The scenario as run stays beside the outputs, as after a finished run.
    assert!(out.join("scenario.json").is_file(), "no scenario.json");
    assert!(
        !has_temporary(&out),
        "a temporary file was left in {}",
        out.display()
    );
}

/// With checkpoints, the hint names the last one written, a file that exists, and the
/// command it gives continues the run; before the first is due, it says there is none.
#[test]
fn ctrl_c_names_the_checkpoint_a_run_continues_from() {
    let (o, out) = interrupted_run("conventions_ctrl_c_cp", &["--checkpoint-every", "5"]);
    assert_eq!(o.status.code(), Some(130), "{}", said(&o));
    let e = String::from_utf8_lossy(&o.stderr);
    let command = e
        .split('`')
        .find(|part| part.starts_with("dsmcosim resume "))
        .unwrap_or_else(|| panic!("no resume command in: {e}"));
    let checkpoint = command
        .split_whitespace()
        .nth(2)
        .expect("a checkpoint path");
    assert!(
        std::path::Path::new(checkpoint).is_file(),
        "the hint names {checkpoint}, which does not exist: {e}"
    );
    assert!(
        std::path::Path::new(checkpoint).starts_with(out.join("checkpoints")),
        "{e}"
    );

    let (o, _) = interrupted_run("conventions_ctrl_c_nocp", &["--checkpoint-every", "1000"]);
    assert_eq!(o.status.code(), Some(130), "{}", said(&o));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("no checkpoint was written yet (the first was due at t = 1000.000000000 s)"),
        "{e}"
    );
}

/// Whether `dir` holds a temporary file of an atomic write (`.NAME.tmp…`).
fn has_temporary(dir: &std::path::Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|entries| {
        entries
            .filter_map(|e| e.ok())
            .any(|e| e.file_name().to_string_lossy().contains(".tmp"))
    })
}

#[test]
fn a_coupling_study_past_the_step_limit_is_refused_before_it_runs() {
    // 10⁹ s of the thesis scene at 1 ms: 10¹² steps per run, 292 runs. Refused at once
    // naming the horizon, nothing written (it used to start computing).
    let dir = scratch("conventions_coupling_limit");
    let scenario = repo().join("scenarios/grid16_space_fixed.json");
    let out = dir.join("out");
    let o = run(&[
        "coupling",
        scenario.to_str().unwrap(),
        "--set",
        "/duration=1e9",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(
        said(&o).contains("--duration: the study would integrate"),
        "{}",
        said(&o)
    );
    assert!(!out.exists());
}

#[test]
fn a_sweep_without_its_base_names_base_and_where_it_looked() {
    let dir = scratch("conventions_missing_base");
    let sub = dir.join("sweeps");
    std::fs::create_dir_all(&sub).unwrap();
    let sweep = write_json(
        &sub,
        "study.json",
        &json!({"name": "s", "base": "../scenarios/nowhere.json",
                "axes": [{"name": "draw", "pointer": "/seed", "values": [1, 2]}]}),
    );
    let out = dir.join("out");
    for args in [
        vec![
            "sweep",
            sweep.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        vec!["validate", sweep.to_str().unwrap()],
    ] {
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", said(&o));
        let e = String::from_utf8_lossy(&o.stderr);
        let resolved = sub.join("../scenarios/nowhere.json");
        for want in [
            "base: ",
            "resolved relative to the sweep file",
            resolved.to_str().unwrap(),
        ] {
            assert!(e.contains(want), "{args:?}: no {want:?}: {}", said(&o));
        }
    }
    assert!(!out.exists(), "nothing written");
}

#[test]
fn max_memory_takes_sizes_with_units() {
    let scenario = repo().join("scenarios/grid16_space_fixed.json");
    let scenario = scenario.to_str().unwrap();
    for ok in ["16G", "16GiB", "1.5GiB", "512M", "2000000000", "16GB"] {
        let o = run(&["validate", scenario, "--max-memory", ok]);
        assert!(o.status.success(), "{ok}: {}", said(&o));
    }
    // Too small a size is the budget's refusal, naming the flag.
    let o = run(&["validate", scenario, "--max-memory", "1K"]);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("--max-memory"),
        "{}",
        said(&o)
    );
    // Bad input: exit 2 naming the flag and showing what it takes.
    for (bad, want) in [("16X", "unknown unit"), ("G", "must be a number of bytes")] {
        let o = run(&["validate", scenario, "--max-memory", bad]);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", said(&o));
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(
            e.contains("--max-memory") && e.contains(want) && e.contains("16G"),
            "{bad}: {}",
            said(&o)
        );
    }
}

/// A file of another kind given where a scenario belongs is named for what it is, with
/// what to do instead; a check whose rerun directory holds another scenario's run says
/// so in `check`'s own terms (it has no `--out` or `--force`). Each exits 2 and writes
/// nothing.
#[test]
fn a_file_of_another_kind_is_named_for_what_it_is() {
    let dir = scratch("conventions_other_kinds");
    let stored = repo().join("results/grid16_space_cp");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "check".into(),
                "scenarios/sweeps/tdma4_slot_layouts.json".into(),
                "--against".into(),
                dir.join("none").display().to_string(),
            ],
            "is a sweep file (it has `base` and `axes`), not a scenario: run its points with \
             `dsmcosim sweep FILE -o DIR`",
        ),
        (
            vec![
                "run".into(),
                stored.join("summary.json").display().to_string(),
                "-o".into(),
                dir.join("a").display().to_string(),
            ],
            "is a run's summary.json, not a scenario: the run's scenario is the scenario.json \
             beside it",
        ),
        (
            vec![
                "run".into(),
                stored.display().to_string(),
                "-o".into(),
                dir.join("b").display().to_string(),
            ],
            "is a directory, not a file (a run's folder keeps its scenario as",
        ),
    ];
    for (args, want) in cases {
        let o = bin()
            .current_dir(repo())
            .args(&args)
            .output()
            .expect("spawn");
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", said(&o));
        assert!(e.contains(want), "{args:?}: {e}");
    }
    for made in ["a", "b"] {
        assert!(!dir.join(made).exists(), "{made} was written");
    }
    // A check whose `<stored>.new` holds another scenario's run.
    let other = dir.join("other");
    for d in [&other, &dir.join("other.new")] {
        std::fs::create_dir_all(d).expect("mkdir");
        for f in ["summary.json", "trace.csv", "epochs.csv"] {
            std::fs::copy(repo().join("results/grid16_space_fixed").join(f), d.join(f))
                .expect("copy");
        }
    }
    let o = run(&[
        "check",
        repo()
            .join("scenarios/grid16_space_cp.json")
            .to_str()
            .unwrap(),
        "--against",
        other.to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains(
            "holds a run of scenario `grid16_space_fixed`, not `grid16_space_cp` (the \
                    rerun's directory: an earlier check's? remove it, or give `--work DIR`"
        ),
        "{e}"
    );
    assert!(!e.contains("--force"), "{e}");
}

/// A resumed run keeps the scenario it runs beside its outputs: the scenario.json of the
/// run its checkpoint came from.
#[test]
fn a_resumed_run_keeps_its_scenario() {
    let dir = scratch("conventions_resume_scenario");
    let (first, second) = (dir.join("first"), dir.join("second"));
    let scenario = repo().join("scenarios/grid16_monolithic.json");
    let o = run(&[
        "run",
        scenario.to_str().unwrap(),
        "-o",
        first.to_str().unwrap(),
        "--set",
        "/duration=1",
        "--checkpoint-every",
        "0.5",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    let checkpoint = first.join("checkpoints/t_000000.500000000.ckpt");
    let o = run(&[
        "resume",
        checkpoint.to_str().unwrap(),
        "-o",
        second.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    assert_eq!(
        std::fs::read_to_string(second.join("scenario.json")).expect("scenario.json"),
        std::fs::read_to_string(first.join("scenario.json")).expect("the first's")
    );
}

/// Ctrl-C on a sweep: no point starts after it, the running ones stop unmarked as done,
/// and the sweep exits 130 counting what finished and giving the `--resume` command,
/// which then runs the rest to the full table.
#[test]
fn ctrl_c_on_a_sweep_says_how_to_resume_it() {
    let dir = scratch("conventions_ctrl_c_sweep");
    let out = dir.join("out");
    let sweep = repo().join("scenarios/sweeps/tdma4_slot_layouts.json");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .args([
            "sweep",
            sweep.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--keep", "summary", "-j", "1"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    let done = |out: &std::path::Path| {
        std::fs::read_dir(out.join("points")).map_or(0, |entries| {
            entries
                .filter_map(|e| e.ok())
                .filter(|e| e.path().join("done.json").is_file())
                .count()
        })
    };
    // A hang guard, not a time assertion: at most 15 000 polls 20 ms apart.
    let mut polls = 0;
    while done(&out) < 3 {
        polls += 1;
        assert!(polls < 15_000, "no point finished");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // SAFETY: kill(2) on the child's pid, which has not been waited for.
    let rc = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    assert_eq!(rc, 0);
    let o = child.wait_with_output().expect("wait");
    assert_eq!(o.status.code(), Some(130), "{}", said(&o));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("interrupted: ")
            && e.contains("points to run finished")
            && e.contains("--resume"),
        "{e}"
    );
    assert!(
        !out.join("sweep.csv").exists(),
        "an interrupted sweep wrote its table"
    );
    let o = run(&[
        "sweep",
        sweep.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--keep",
        "summary",
        "--resume",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    let table = std::fs::read_to_string(out.join("sweep.csv")).expect("sweep.csv");
    assert_eq!(table.lines().count(), 601, "the header and every point");
}
