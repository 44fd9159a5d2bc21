//! `dsmcosim sweep` and `dsmcosim sweep-merge`: output independent of the thread count,
//! shards merged equal to the unsharded run, resume, bad sweep files, derived seeds.
//!
//! The base scenario is the thesis grid on 4 quadrant nodes (`grid16_space_fixed`) cut
//! to 0.2 s, so every point runs in milliseconds.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::{json, Value};

/// A fresh empty directory under the system temp dir, unique per test and process.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dsmcosim-sweep-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes the short base scenario into `dir/base.json`.
fn write_base(dir: &Path) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/grid16_space_fixed.json");
    let mut base: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    base["duration"] = json!(0.2);
    base["measurement"]["period"] = json!(0.05);
    base["output"]["decimation"] = json!(20);
    std::fs::write(
        dir.join("base.json"),
        serde_json::to_string_pretty(&base).unwrap(),
    )
    .unwrap();
}

/// Writes `sweep` into `dir/<file>` beside a base scenario and returns its path.
fn write_sweep(dir: &Path, file: &str, sweep: &Value) -> PathBuf {
    write_base(dir);
    let path = dir.join(file);
    std::fs::write(&path, serde_json::to_string_pretty(sweep).unwrap()).unwrap();
    path
}

/// Six points: two channel delays, factorial.
fn two_taus() -> Value {
    json!({
        "name": "taus",
        "base": "base.json",
        "combine": "factorial",
        "axes": [
            {"name": "tau1", "pointer": "/channels/0/tau", "values": [0.001, 0.005, 0.01]},
            {"name": "tau2", "pointer": "/channels/1/tau", "range": {"from": 0.002, "to": 0.004, "steps": 2}}
        ]
    })
}

fn dsmcosim(args: &[&Path]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs the CLI with string-ish arguments and asserts success.
fn ok(args: &[&dyn AsRef<std::ffi::OsStr>]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .args(args.iter().map(|a| a.as_ref()))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "dsmcosim {:?} failed: {}\n--- stdout ---\n{}\n--- stderr ---\n{}",
        args.iter().map(|a| a.as_ref()).collect::<Vec<_>>(),
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The column `name` of a CSV text.
fn column(csv: &str, name: &str) -> Vec<String> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = header.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| l.split(',').nth(k).unwrap().to_string())
        .collect()
}

/// Directory of point `i` of the sweep in `out`: `points/<key>`, the key read from the
/// `point` column of `csv` (a `sweep.csv`).
fn point_in(out: &Path, csv: &str, i: usize) -> PathBuf {
    let index = column(csv, "index");
    let row = index.iter().position(|x| *x == i.to_string()).unwrap();
    out.join("points").join(&column(csv, "point")[row])
}

/// Same bytes of the files that must not depend on how the sweep was run.
fn assert_same_outputs(a: &Path, b: &Path, what: &str) {
    for file in [
        "sweep.csv",
        "cost_vs_tau1.svg",
        "cost_heatmap.svg",
        "sweep.json",
    ] {
        assert_eq!(
            read(&a.join(file)),
            read(&b.join(file)),
            "{what}: {file} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

#[test]
fn two_threads_write_the_same_bytes_as_one() {
    let dir = scratch("threads");
    let sweep = write_sweep(&dir, "sweep.json", &two_taus());
    let mut outs = Vec::new();
    for threads in [1, 2] {
        let out = dir.join(format!("out{threads}"));
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let report = pool
            .install(|| dsmcosim::sweep::run(&sweep, &out, &dsmcosim::sweep::Options::default()))
            .unwrap();
        assert_eq!((report.points, report.ran, report.skipped), (6, 6, 0));
        outs.push(out);
    }
    assert_same_outputs(&outs[0], &outs[1], "1 vs 2 threads");
    let csv = read(&outs[0].join("sweep.csv"));
    assert_eq!(
        csv.lines().next().unwrap(),
        "index,point,tau1,tau2,seed,status,diverged_at,diverged_node,diverged_where,mean_cost,\
         lost_frames,tau_tau1_requested,tau_tau1_achieved,\
         tau_tau2_requested,tau_tau2_achieved,bandwidth,digest"
    );
    assert_eq!(
        column(&csv, "tau1"),
        ["0.001", "0.001", "0.005", "0.005", "0.01", "0.01"]
    );
    assert_eq!(
        column(&csv, "tau2"),
        ["0.002", "0.004", "0.002", "0.004", "0.002", "0.004"]
    );
    assert_eq!(column(&csv, "tau_tau1_achieved")[2], "0.005");
    assert_eq!(column(&csv, "status"), vec!["ok"; 6]);
    // Different delays give different runs.
    let digests: std::collections::BTreeSet<String> = column(&csv, "digest").into_iter().collect();
    assert_eq!(digests.len(), 6);
    // timing.csv has the wall time, sweep.csv does not.
    let timing = read(&outs[0].join("timing.csv"));
    assert!(timing.starts_with("index,wall_seconds\n0,"), "{timing}");
    assert_eq!(timing.lines().count(), 7);
    let p5 = point_in(&outs[0], &csv, 5);
    assert!(p5.join("done.json").is_file());
    assert!(p5.join("scenario.json").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sharded_and_merged_equals_unsharded() {
    let dir = scratch("shards");
    let sweep = write_sweep(&dir, "sweep.json", &two_taus());
    let (full, s1, s2, merged) = (
        dir.join("full"),
        dir.join("s1"),
        dir.join("s2"),
        dir.join("merged"),
    );
    ok(&[&"sweep", &sweep, &"--out", &full]);
    let said = ok(&[&"sweep", &sweep, &"--out", &s1, &"--shard", &"1/2"]);
    assert!(
        said.contains("3 of 6 points (3 run, 0 already done)"),
        "{said}"
    );
    let shard1 = read(&s1.join("sweep.csv"));
    assert_eq!(column(&shard1, "index"), ["0", "2", "4"]);

    // One shard alone is not the whole sweep.
    let out = dsmcosim(&[Path::new("sweep-merge"), Path::new("--out"), &merged, &s1]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("3 of 6 points are not done") && err.contains("p1, p3, p5"),
        "{err}"
    );

    ok(&[&"sweep", &sweep, &"--out", &s2, &"--shard", &"2/2"]);
    let said = ok(&[&"sweep-merge", &"--out", &merged, &s1, &s2]);
    assert!(
        said.contains("merged 6 points from 2 directories"),
        "{said}"
    );
    assert_same_outputs(&full, &merged, "unsharded vs shards 1/2 + 2/2 merged");
    assert_eq!(read(&merged.join("timing.csv")).lines().count(), 7);

    // A done.json edited after its run (here its mean cost) no longer matches the run's
    // summary.json: refused, naming the file.
    let done = point_in(&s2, &read(&s2.join("sweep.csv")), 1).join("done.json");
    let text = read(&done);
    let mut v: Value = serde_json::from_str(&text).unwrap();
    let cost = v["row"]["mean_cost"].as_f64().expect("a mean cost");
    v["row"]["mean_cost"] = json!(cost * 0.5);
    std::fs::write(&done, serde_json::to_string(&v).unwrap()).unwrap();
    let out = dsmcosim(&[
        Path::new("sweep-merge"),
        Path::new("-o"),
        &dir.join("m1"),
        &s1,
        &s2,
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&done.display().to_string()) && err.contains("does not match"),
        "{err}"
    );
    std::fs::write(&done, text).unwrap();

    // The same shard twice, and shards of another sweep, are refused.
    let out = dsmcosim(&[
        Path::new("sweep-merge"),
        Path::new("-o"),
        &dir.join("m2"),
        &s1,
        &s2,
        &full,
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("done in two shard directories"), "{err}");
    let mut other = two_taus();
    other["axes"][0]["values"] = json!([0.001, 0.005, 0.02]);
    let other_sweep = write_sweep(&dir, "other.json", &other);
    let s2b = dir.join("s2b");
    ok(&[&"sweep", &other_sweep, &"--out", &s2b, &"--shard", &"2/2"]);
    let out = dsmcosim(&[
        Path::new("sweep-merge"),
        Path::new("-o"),
        &dir.join("m3"),
        &s1,
        &s2b,
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("shards of different sweeps"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn resume_reruns_only_unfinished_points() {
    let dir = scratch("resume");
    let sweep = write_sweep(&dir, "sweep.json", &two_taus());
    let out = dir.join("out");
    ok(&[&"sweep", &sweep, &"--out", &out]);
    let csv = read(&out.join("sweep.csv"));
    let summary = |i: usize| point_in(&out, &csv, i).join("summary.json");
    let mtime = |i: usize| std::fs::metadata(summary(i)).unwrap().modified().unwrap();
    let before: Vec<_> = (0..6).map(mtime).collect();

    // An interrupted sweep: two points never finished, the tables never written.
    std::fs::remove_file(point_in(&out, &csv, 1).join("done.json")).unwrap();
    std::fs::remove_file(point_in(&out, &csv, 4).join("done.json")).unwrap();
    std::fs::remove_file(out.join("sweep.csv")).unwrap();

    // Without --resume the directory is refused, untouched.
    let o = dsmcosim(&[Path::new("sweep"), &sweep, Path::new("--out"), &out]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--resume"), "{err}");
    assert!(!out.join("sweep.csv").exists());

    std::thread::sleep(std::time::Duration::from_millis(20));
    let said = ok(&[&"sweep", &sweep, &"--out", &out, &"--resume"]);
    assert!(
        said.contains("6 of 6 points (2 run, 4 already done)"),
        "{said}"
    );
    assert_eq!(
        read(&out.join("sweep.csv")),
        csv,
        "resumed sweep.csv differs"
    );
    for i in [0, 2, 3, 5] {
        assert_eq!(mtime(i), before[i], "finished point p{i} was rerun");
    }
    for i in [1, 4] {
        assert!(point_in(&out, &csv, i).join("done.json").is_file());
    }

    // A changed definition reruns exactly the points it changes (tau1 = 0.01 → 0.02:
    // p4 and p5).
    let mut changed = two_taus();
    changed["axes"][0]["values"] = json!([0.001, 0.005, 0.02]);
    let sweep2 = write_sweep(&dir, "sweep.json", &changed);
    let said = ok(&[&"sweep", &sweep2, &"--out", &out, &"--resume"]);
    assert!(said.contains("(2 run, 4 already done)"), "{said}");
    let csv2 = read(&out.join("sweep.csv"));
    assert_eq!(column(&csv2, "tau1")[5], "0.02");
    assert_eq!(
        csv2.lines().take(5).collect::<Vec<_>>(),
        csv.lines().take(5).collect::<Vec<_>>()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_sweeps_exit_2_naming_the_axis_and_write_nothing() {
    let dir = scratch("bad");
    let axis = |name: &str, pointer: &str, values: Value| json!({"name": name, "pointer": pointer, "values": values});
    let sweep = |axes: Value| json!({"name": "bad", "base": "base.json", "axes": axes});
    let cases: Vec<(&str, Value, Vec<&str>)> = vec![
        (
            "unknown pointer",
            sweep(json!([
                axis("tau1", "/channels/0/tau", json!([0.001])),
                axis("foo", "/network/foo/bar", json!([1]))
            ])),
            vec!["axes[1].pointer: /network/foo/bar: no key `foo` in /network"],
        ),
        (
            "unknown top-level parent",
            sweep(json!([axis("x", "/nosuch/x", json!([1]))])),
            vec!["axes[0].pointer: /nosuch/x:"],
        ),
        (
            "new key the scenario rejects",
            sweep(json!([axis("foo", "/network/foo", json!([1]))])),
            vec![
                "point p0 (foo = 1)",
                "unknown field `foo`",
                "axes[0].pointer /network/foo",
            ],
        ),
        (
            "empty axis",
            sweep(json!([axis("tau1", "/channels/0/tau", json!([]))])),
            vec!["axes[0].values: axis `tau1` is empty"],
        ),
        (
            "string for /dt",
            sweep(json!([axis("step", "/dt", json!([0.001, "fast"]))])),
            vec!["point p1 (step = fast): dt:", "string"],
        ),
        (
            "zero points",
            sweep(json!([])),
            vec!["axes: the sweep has zero points"],
        ),
        (
            "zip with unequal lengths",
            json!({"name": "bad", "base": "base.json", "combine": "zip", "axes": [
                axis("tau1", "/channels/0/tau", json!([0.001, 0.002])),
                axis("tau2", "/channels/1/tau", json!([0.001]))]}),
            vec!["axes[1]: zip needs axes of equal length", "tau1", "tau2"],
        ),
        (
            "range with zero steps",
            sweep(
                json!([{"name": "tau1", "pointer": "/channels/0/tau", "range": {"from": 0.001, "to": 0.002, "steps": 0}}]),
            ),
            vec!["axes[0].range.steps: axis `tau1` needs steps ≥ 1"],
        ),
        (
            "unknown key",
            json!({"name": "bad", "base": "base.json", "axes": [axis("a", "/dt", json!([0.001]))], "axis": []}),
            vec!["unknown field `axis`"],
        ),
        (
            "a point that fails validation",
            sweep(json!([axis(
                "tau1",
                "/channels/0/tau",
                json!([0.001, 0.0005])
            )])),
            vec!["point p1 (tau1 = 0.0005): channels[0].tau"],
        ),
    ];
    for (what, definition, wants) in cases {
        let path = write_sweep(&dir, "sweep.json", &definition);
        let out = dir.join("out");
        let o = dsmcosim(&[Path::new("sweep"), &path, Path::new("--out"), &out]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{what}: {err}");
        assert_eq!(err.lines().count(), 1, "{what}: one line expected: {err}");
        for want in wants {
            assert!(err.contains(want), "{what}: expected {want:?} in: {err}");
        }
        assert!(!out.exists(), "{what}: wrote {}", out.display());
    }
    let path = write_sweep(&dir, "sweep.json", &two_taus());
    let o = dsmcosim(&[
        Path::new("sweep"),
        &path,
        Path::new("--out"),
        &dir.join("out"),
        Path::new("--shard"),
        Path::new("3/2"),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--shard"));
    assert!(!dir.join("out").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn seeds_are_derived_per_point_and_reproducible() {
    let dir = scratch("seeds");
    let sweep = write_sweep(&dir, "sweep.json", &two_taus());
    let (a, b) = (dir.join("a"), dir.join("b"));
    ok(&[&"sweep", &sweep, &"--out", &a]);
    ok(&[&"sweep", &sweep, &"--out", &b]);
    let csv = read(&a.join("sweep.csv"));
    assert_eq!(csv, read(&b.join("sweep.csv")), "a second sweep differs");
    let seeds: Vec<u64> = column(&csv, "seed")
        .iter()
        .map(|s| s.parse().unwrap())
        .collect();
    let distinct: std::collections::BTreeSet<u64> = seeds.iter().copied().collect();
    assert_eq!(distinct.len(), 6);
    let p3 = point_in(&a, &csv, 3);
    let scenario: Value = serde_json::from_str(&read(&p3.join("scenario.json"))).unwrap();
    assert_eq!(scenario["seed"], json!(seeds[3]));
    let key = p3.file_name().unwrap().to_string_lossy().into_owned();
    assert_eq!(key.len(), 16, "a 16-hex-digit key: {key}");
    assert_eq!(scenario["name"], json!(format!("taus_{key}")));
    assert_eq!(scenario["channels"][0]["tau"], json!(0.005));

    // An axis on /seed wins over the derived seed; string values are quoted JSON and
    // drawn at their index.
    let own = json!({
        "name": "own", "base": "base.json", "combine": "zip",
        "axes": [
            {"name": "s", "pointer": "/seed", "values": [1, 2]},
            {"name": "ghosts", "pointer": "/partition/ghosts", "values": ["integrate", "hold"]}
        ]
    });
    let path = write_sweep(&dir, "own.json", &own);
    let c = dir.join("c");
    ok(&[&"sweep", &path, &"--out", &c]);
    let csv = read(&c.join("sweep.csv"));
    assert_eq!(column(&csv, "seed"), ["1", "2"]);
    assert_eq!(column(&csv, "ghosts"), ["integrate", "hold"]);
    let heatmap = read(&c.join("cost_heatmap.svg"));
    // One cell per value, named by the value.
    assert!(
        heatmap.contains("integrate") && heatmap.contains("hold"),
        "categorical tick labels"
    );
    assert!(c.join("cost_vs_s.svg").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A point's seed and its `--resume` entry follow its configuration, not its index:
/// a sweep that gains an axis value reruns only the new points, and the points it
/// shares with the old sweep keep their seeds and digests.
#[test]
fn adding_an_axis_value_keeps_every_other_points_seed_and_resume_entry() {
    let dir = scratch("grow");
    let small = json!({
        "name": "grow", "base": "base.json", "repeat": 2,
        "axes": [{"name": "tau1", "pointer": "/channels/0/tau", "values": [0.001, 0.01]}]
    });
    let mut grown = small.clone();
    grown["axes"][0]["values"] = json!([0.001, 0.005, 0.01]);
    let out = dir.join("out");
    ok(&[
        &"sweep",
        &write_sweep(&dir, "small.json", &small),
        &"--out",
        &out,
    ]);
    let before = read(&out.join("sweep.csv"));
    // The same directory, the grown definition: only the two new points run.
    let path = write_sweep(&dir, "grown.json", &grown);
    let report = dsmcosim::sweep::run(
        &path,
        &out,
        &dsmcosim::sweep::Options {
            resume: true,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((report.points, report.ran, report.skipped), (6, 2, 4));
    let after = read(&out.join("sweep.csv"));
    let key = |csv: &str| -> Vec<(String, String, String, String)> {
        let (t, r, s, d) = (
            column(csv, "tau1"),
            column(csv, "rep"),
            column(csv, "seed"),
            column(csv, "digest"),
        );
        (0..t.len())
            .map(|i| (t[i].clone(), r[i].clone(), s[i].clone(), d[i].clone()))
            .collect()
    };
    let (old, new) = (key(&before), key(&after));
    assert_eq!(old.len(), 4);
    assert_eq!(new.len(), 6);
    for row in &old {
        assert!(
            new.contains(row),
            "{row:?} changed when an axis value was added"
        );
    }
    assert_ne!(old[0].2, old[1].2, "repetitions draw different seeds");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A point that diverges is a row that says where, a cross in the plots, and no part of
/// any mean; `--keep summary` leaves only the small files.
#[test]
fn diverged_points_are_flagged_and_kept_out_of_the_means() {
    let dir = scratch("diverged");
    // A tiny divergence bound makes the stiff points fail at once.
    let sweep = json!({
        "name": "div", "base": "base.json", "repeat": 2,
        "overrides": {"/divergence": {"max_violation": 1.0}},
        "axes": [{"name": "bound", "pointer": "/divergence/max_violation", "values": [1e-9, 10.0]}]
    });
    let path = write_sweep(&dir, "div.json", &sweep);
    let out = dir.join("out");
    ok(&[&"sweep", &path, &"--out", &out, &"--keep", &"summary"]);
    let csv = read(&out.join("sweep.csv"));
    assert_eq!(column(&csv, "status"), ["diverged", "diverged", "ok", "ok"]);
    let at = column(&csv, "diverged_at");
    assert!(at[0].parse::<f64>().unwrap() >= 0.0, "time {at:?}");
    assert!(at[2].is_empty());
    assert!(column(&csv, "diverged_node")[0].parse::<u64>().unwrap() >= 1);
    assert!(column(&csv, "diverged_where")[0].starts_with('L'));
    let svg = svg_text(&read(&out.join("cost_vs_bound.svg")));
    assert!(
        svg.contains("diverged: 2 of 4 points"),
        "legend counts them"
    );
    assert!(svg.contains("mean over rep"), "repetitions are averaged");
    let mut kept: Vec<String> = std::fs::read_dir(point_in(&out, &csv, 0))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with('.'))
        .collect();
    kept.sort();
    assert_eq!(
        kept,
        ["done.json", "epochs.csv", "scenario.json", "summary.json"]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_controlled_sweep_plots_the_dsm_over_its_baselines_and_an_uncontrolled_one_does_not() {
    let dir = scratch("ratios");
    let sweep = json!({
        "name": "ds", "base": "base.json",
        "overrides": {
            "/controller": {"method": "dsm", "problem": "cp", "budget": 400.0,
                            "tau_min": 0.001, "tau_max": 0.02, "initial": [0.005],
                            "dsm": {"size": 0.002, "reflections": 2},
                            "baselines": ["grid", "no_opt"], "grid_step": 0.001}
        },
        "axes": [{"name": "D_s", "pointer": "/controller/dsm/size", "values": [0.002, 0.004]}]
    });
    let path = write_sweep(&dir, "ds.json", &sweep);
    let out = dir.join("out");
    ok(&[&"sweep", &path, &"--out", &out]);
    let csv = read(&out.join("sweep.csv"));
    let ratio = |a: &str, b: &str| -> Vec<f64> {
        let (a, b) = (column(&csv, a), column(&csv, b));
        a.iter()
            .zip(&b)
            .map(|(x, y)| x.parse::<f64>().unwrap() / y.parse::<f64>().unwrap())
            .collect()
    };
    for (file, baseline) in [
        ("dsm_over_grid", "unpaired_mean_cost_grid"),
        ("dsm_over_no_opt", "unpaired_mean_cost_no_opt"),
    ] {
        let svg = read(&out.join(format!("{file}_vs_D_s.svg")));
        assert!(svg.contains("D_s [s]"), "{file}: x label");
        assert!(svg.contains(" [1]"), "{file}: a ratio's unit");
        for r in ratio("unpaired_mean_cost_dsm", baseline) {
            assert!(r.is_finite() && r > 0.0, "{file}: ratio {r}");
        }
    }
    // Every DSM vertex (5 ms ± whole D_s) is a 1 ms grid point, so the grid optimum
    // bounds the DSM from below in every window: the ratio is ≥ 1.
    assert!(ratio("unpaired_mean_cost_dsm", "unpaired_mean_cost_grid")
        .iter()
        .all(|&r| r >= 1.0 - 1e-12));
    let plain = dir.join("plain");
    ok(&[
        &"sweep",
        &write_sweep(&dir, "taus.json", &two_taus()),
        &"--out",
        &plain,
    ]);
    assert!(!plain.join("dsm_over_grid_vs_tau1.svg").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_diverged_point_is_a_row() {
    let dir = scratch("diverged");
    let sweep = json!({
        "name": "gain", "base": "base.json",
        "axes": [{"name": "K", "pointer": "/stabilizer/k", "values": [10.0, 10000.0]}]
    });
    let path = write_sweep(&dir, "sweep.json", &sweep);
    let out = dir.join("out");
    let said = ok(&[&"sweep", &path, &"--out", &out]);
    assert!(said.contains("1 diverged"), "{said}");
    let csv = read(&out.join("sweep.csv"));
    assert_eq!(column(&csv, "status"), ["ok", "diverged"]);
    let svg = read(&out.join("cost_vs_K.svg"));
    assert!(svg.contains("K [m/s]") && svg.contains("mean cost C [m]"));
    assert!(
        !out.join("cost_heatmap.svg").exists(),
        "one axis has no heatmap"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_line_plot_averages_over_seed_axes_and_names_values_by_their_labels() {
    let dir = scratch("labels");
    let sweep = json!({
        "name": "lab", "base": "base.json",
        "axes": [
            {"name": "ghosts", "pointer": "/partition/ghosts", "values": ["integrate", "hold"],
             "labels": ["integrated ghosts", "held ghosts"]},
            {"name": "tau1", "pointer": "/channels/0/tau", "values": [0.001, 0.005]},
            {"name": "draw", "pointer": "/seed", "values": [1, 2, 3]}
        ]
    });
    let path = write_sweep(&dir, "lab.json", &sweep);
    let out = dir.join("out");
    ok(&[&"sweep", &path, &"--out", &out]);
    let svg = svg_text(&read(&out.join("cost_vs_tau1.svg")));
    assert!(
        svg.contains("mean over draw"),
        "the title names the averaged axis"
    );
    for label in ["ghosts = integrated ghosts", "ghosts = held ghosts"] {
        assert!(svg.contains(label), "legend entry {label:?}");
    }
    assert!(
        !svg.contains("draw = "),
        "one line per ghosts value, not per draw"
    );

    // A label list of the wrong length is refused, naming the axis.
    let mut bad = sweep.clone();
    bad["axes"][0]["labels"] = json!(["only one"]);
    let path = write_sweep(&dir, "bad.json", &bad);
    let res = dsmcosim(&[
        Path::new("sweep"),
        &path,
        Path::new("--out"),
        &dir.join("bad"),
    ]);
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert_eq!(res.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("axes[0].labels"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `validate` on a sweep file checks every point and warns where a point's slot list
/// never serves a channel (the run would diverge); the sweep itself still validates.
#[test]
fn validate_warns_about_a_slot_list_that_never_serves_a_channel() {
    let dir = scratch("validate");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/tdma4_space_fixed.json");
    let mut base: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    base["duration"] = json!(0.2);
    base["measurement"]["period"] = json!(0.05);
    std::fs::write(dir.join("tdma.json"), base.to_string()).unwrap();
    let full = json!([{"node": 1, "channel": "tau1"}, {"node": 2, "channel": "tau2"},
                      {"node": 2, "channel": "tau1"}, {"node": 3, "channel": "tau2"},
                      {"node": 4, "channel": "tau1"}, {"node": 4, "channel": "tau2"}]);
    let mut short = full.clone();
    short.as_array_mut().unwrap().pop(); // node 4 never sends on tau2
    let sweep = json!({
        "name": "lists", "base": "tdma.json",
        "axes": [{"name": "list", "pointer": "/network/slot_list", "values": [full, short],
                  "labels": ["full", "no node 4 on tau2"]}]
    });
    let path = write_sweep(&dir, "lists.json", &sweep);
    let o = dsmcosim(&[Path::new("validate"), &path]);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{out}{err}");
    assert!(out.contains("sweep lists of 2 points"), "{out}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("point p1 (list = no node 4 on tau2)")
            && err.contains("never serves channel tau2"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `validate` on a sweep checks the definition, each axis's values and the extreme
/// combinations, not every point (issue "Hardening"): what is asserted is the number of
/// point scenarios it builds and validates, not a time.
#[test]
fn validate_checks_each_value_and_the_extremes_not_every_point() {
    let dir = scratch("validate-bounded");
    let omega = |steps: u64| {
        json!({"name": "omega", "pointer": "/forces/0/omega",
               "range": {"from": 1.0, "to": 3.0, "steps": steps}})
    };
    // A 100 000-step range alone: 1 000 of its values, both ends among them.
    let path = write_sweep(
        &dir,
        "long.json",
        &json!({"name": "long", "base": "base.json", "axes": [omega(100_000)]}),
    );
    let c = dsmcosim::sweep::check(&path).unwrap();
    assert_eq!(c.points, 100_000);
    assert_eq!(c.checked, dsmcosim::sweep::points::CHECKED_VALUES_PER_AXIS);
    let plan =
        dsmcosim::sweep::points::plan(&dsmcosim::sweep::file::load(&path).unwrap().0).unwrap();
    let picked = dsmcosim::sweep::points::checked_points(&plan);
    assert_eq!(
        (picked[0], *picked.last().unwrap()),
        (0, 99_999),
        "both ends"
    );

    // × two step sizes and 3 repetitions: each value of each axis once with the other
    // at its first, and the four corners; repetitions are not checked again.
    let grid = json!({"name": "grid", "base": "base.json", "repeat": 3, "axes": [
        omega(10_000),
        {"name": "step", "pointer": "/dt", "values": [0.001, 0.0005]}]});
    let path = write_sweep(&dir, "grid.json", &grid);
    let c = dsmcosim::sweep::check(&path).unwrap();
    assert_eq!(c.points, 60_000);
    assert!(c.checked <= 1_000 + 2 + 4, "{} points checked", c.checked);

    // A bad value on a short axis is still named with its axis and value, by `validate`
    // as by `sweep`, in a sweep too big to check whole.
    let mut bad = grid.clone();
    bad["axes"][1]["values"] = json!([0.001, "fast"]);
    let path = write_sweep(&dir, "bad.json", &bad);
    let e = dsmcosim::sweep::check(&path).unwrap_err().to_string();
    assert!(
        e.starts_with("point p3 (omega = 1.0, step = fast, rep = 0): dt:"),
        "{e}"
    );
    // Every value of an axis of up to 1 000 is checked: the middle of a 3-step range
    // that is no valid window (0.0015 s, not a whole number of 1-ms steps) is found
    // though both ends are valid.
    let path = write_sweep(
        &dir,
        "mid.json",
        &json!({"name": "mid", "base": "base.json", "axes": [
            {"name": "period", "pointer": "/measurement/period",
             "range": {"from": 0.001, "to": 0.002, "steps": 3}}]}),
    );
    let e = dsmcosim::sweep::check(&path).unwrap_err().to_string();
    assert!(
        e.starts_with("point p1 (period = 0.0015): measurement.period"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

mod hostile {
    //! Sweep files legal or not, field by field and together (issue "Hardening"): every
    //! one gets a verdict at once — the points, or an error naming a field — never a
    //! panic, a hang or a huge allocation.

    use proptest::prelude::*;
    use serde_json::{json, Value};

    fn value() -> impl Strategy<Value = Value> {
        prop_oneof![
            (-1e3f64..1e3).prop_map(|x| json!(x)),
            Just(json!(0.005)),
            Just(json!(1e-300)),
            Just(json!(1e300)),
            Just(json!("integrate")),
            Just(json!("x")),
            Just(json!([1, 2])),
            Just(json!({"kind": "ideal"})),
            Just(json!(null)),
        ]
    }

    fn axis() -> impl Strategy<Value = Value> {
        let pointer = prop_oneof![
            Just("/channels/0/tau"),
            Just("/seed"),
            Just("/duration"),
            Just("/partition/ghosts"),
            Just("/network"),
            Just("/nope/x"),
            Just("channels"),
            Just("/name"),
            Just("/channels/7/tau"),
        ];
        let steps = prop_oneof![-2i64..4, Just(100_000), Just(100_001), Just(i64::MAX)];
        (
            pointer,
            prop::collection::vec(value(), 0..4),
            steps,
            any::<bool>(),
            prop::option::of(prop::collection::vec("[a-z ]{0,6}", 0..4)),
        )
            .prop_map(|(pointer, values, steps, range, labels)| {
                let mut a = json!({"name": "a", "pointer": pointer});
                if range {
                    a["range"] = json!({"from": 0.001, "to": 0.01, "steps": steps});
                } else {
                    a["values"] = json!(values);
                }
                if let Some(l) = labels {
                    a["labels"] = json!(l);
                }
                a
            })
    }

    proptest! {
        // A hang is caught by proptest's per-case timeout (each case in its own
        // process, failed after 300 s); what is asserted is the verdict, not the time
        // (users run the suite on busy machines, where a 5-s bound failed at 7.6 s).
        #![proptest_config(ProptestConfig { timeout: 300_000, ..ProptestConfig::with_cases(128) })]

        #[test]
        fn every_sweep_file_gets_a_verdict_at_once(
            axes in prop::collection::vec(axis(), 0..4),
            repeat in prop_oneof![Just(json!(1)), Just(json!(0)), Just(json!(3)), Just(json!(1_000_000)), Just(json!("2"))],
            zip in any::<bool>(),
        ) {
            // Distinct axis names, so that the name rule is not all that is tested.
            let axes: Vec<Value> = axes
                .into_iter()
                .enumerate()
                .map(|(i, mut a)| {
                    a["name"] = json!(format!("a{i}"));
                    a
                })
                .collect();
            let sweep = json!({
                "name": "hostile", "base": "base.json", "repeat": repeat,
                "combine": if zip { "zip" } else { "factorial" }, "axes": axes,
            });
            let dir = super::scratch(&format!("hostile-{}", std::thread::current().name().unwrap_or("t").len()));
            let path = super::write_sweep(&dir, "s.json", &sweep);
            match dsmcosim::sweep::check(&path) {
                // Bounded work: never every point of a long range, at most
                // 1 000 values per axis (≤ 3 axes) and the ≤ 4·4·4 extreme combinations.
                Ok(c) => prop_assert!(
                    c.points >= 1 && c.points <= 100_000 && c.checked <= c.points.min(3 * 1_000 + 64),
                    "{} points, {} checked", c.points, c.checked
                ),
                Err(e) => {
                    let m = e.to_string();
                    prop_assert_eq!(e.exit_code(), 2, "{}", m);
                    prop_assert!(m.lines().count() == 1 && m.contains(": "), "{}", m);
                }
            }        }
    }
}

/// The text of an SVG plot, its rows joined by spaces: a legend entry that wraps onto a
/// second row reads as one.
fn svg_text(svg: &str) -> String {
    svg.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('<'))
        .collect::<Vec<_>>()
        .join(" ")
}
