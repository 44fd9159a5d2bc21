//! `dsmcosim check` of many scenarios at once, as CI runs it: each scenario against its
//! stored run `DIR/<name>/`, every outcome reported in argument order, the exit code by
//! precedence (4 mismatch > 1 missing > 2 bad scenario), and the JUnit and JSON
//! verdicts. Short variants (1 s) of shipped scenarios keep it fast.

use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::Value;

use super::{bin, said, scratch, shipped, write_json};

/// Short variants of two shipped scenarios (one monolithic, one partitioned on a fixed
/// delay), named `short_mono` and `short_space`.
fn short_scenarios(dir: &Path) -> Vec<PathBuf> {
    [
        ("grid16_monolithic", "short_mono"),
        ("grid16_space_fixed", "short_space"),
    ]
    .iter()
    .map(|(from, name)| {
        let mut v = shipped(from);
        v["name"] = Value::from(*name);
        v["duration"] = Value::from(1.0);
        v["output"]["decimation"] = Value::from(20);
        write_json(dir, &format!("{name}.json"), &v)
    })
    .collect()
}

/// Scratch directory `name` with the two short scenarios and their stored runs in
/// `stored/<scenario name>/`.
fn stored_pair(name: &str) -> (PathBuf, Vec<PathBuf>, PathBuf) {
    let dir = scratch(name);
    let files = short_scenarios(&dir);
    let stored = dir.join("stored");
    for (file, name) in files.iter().zip(["short_mono", "short_space"]) {
        let o = bin()
            .arg("run")
            .arg(file)
            .arg("--out")
            .arg(stored.join(name))
            .output()
            .expect("spawn dsmcosim");
        assert!(o.status.success(), "storing {name}: {}", said(&o));
    }
    (dir, files, stored)
}

/// `dsmcosim check FILES… --against DIR --json DIR/../verdict.json --junit
/// …/verdict.xml EXTRA…`.
fn check(dir: &Path, files: &[&Path], against: &Path, extra: &[&str]) -> Output {
    bin()
        .arg("check")
        .args(files)
        .arg("--against")
        .arg(against)
        .arg("--json")
        .arg(dir.join("verdict.json"))
        .arg("--junit")
        .arg(dir.join("verdict.xml"))
        .args(extra)
        .output()
        .expect("spawn dsmcosim")
}

fn verdict(dir: &Path) -> Value {
    let text = std::fs::read_to_string(dir.join("verdict.json")).expect("verdict.json");
    serde_json::from_str(&text).expect("verdict.json is JSON")
}

fn statuses(v: &Value) -> Vec<(String, String)> {
    v["scenarios"]
        .as_array()
        .expect("scenarios[]")
        .iter()
        .map(|s| {
            (
                s["name"].as_str().unwrap_or("?").to_string(),
                s["status"].as_str().unwrap_or("?").to_string(),
            )
        })
        .collect()
}

/// A JUnit test case as read back: name, and the tag, `type` and `message` of its
/// failure or error.
#[derive(Debug, PartialEq)]
struct Case {
    name: String,
    problem: Option<(String, String, String)>,
}

/// Parses `verdict.xml` (failing on anything that is not well-formed XML), checks the
/// suite's counts against its test cases, and returns them.
fn junit(dir: &Path) -> Vec<Case> {
    let text = std::fs::read_to_string(dir.join("verdict.xml")).expect("verdict.xml");
    let doc = roxmltree::Document::parse(&text)
        .unwrap_or_else(|e| panic!("verdict.xml is not XML: {e}\n{text}"));
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "testsuites", "{text}");
    let suites: Vec<_> = root.children().filter(|n| n.is_element()).collect();
    assert_eq!(suites.len(), 1, "{text}");
    let suite = suites[0];
    assert_eq!(suite.attribute("name"), Some("dsmcosim.check"));
    let mut cases = Vec::new();
    let mut times = Vec::new();
    for case in suite.children().filter(|n| n.has_tag_name("testcase")) {
        assert_eq!(
            case.attribute("classname"),
            Some("dsmcosim.check"),
            "{text}"
        );
        let time: f64 = case
            .attribute("time")
            .and_then(|t| t.parse().ok())
            .unwrap_or_else(|| panic!("a testcase without a time in seconds:\n{text}"));
        assert!(time >= 0.0);
        times.push(time);
        let problem = case
            .children()
            .find(|n| n.has_tag_name("failure") || n.has_tag_name("error"))
            .map(|p| {
                (
                    p.tag_name().name().to_string(),
                    p.attribute("type").unwrap_or("").to_string(),
                    p.attribute("message").unwrap_or("").to_string(),
                )
            });
        cases.push(Case {
            name: case.attribute("name").unwrap_or("").to_string(),
            problem,
        });
    }
    let count = |tag: &str| {
        cases
            .iter()
            .filter(|c| c.problem.as_ref().is_some_and(|p| p.0 == tag))
            .count()
            .to_string()
    };
    // The suite's time is the whole check's wall time: it contains every testcase's
    // interval, so it is at least the longest (the scenarios run in parallel, so it is
    // not their sum: src/check/junit.rs's unit test pins that rendering).
    let longest = times.iter().copied().fold(0.0, f64::max);
    for element in [root, suite] {
        let time: f64 = element
            .attribute("time")
            .and_then(|t| t.parse().ok())
            .unwrap_or_else(|| panic!("a suite without a time in seconds:\n{text}"));
        assert!(time >= longest, "suite time below a testcase's:\n{text}");
        assert_eq!(
            element.attribute("tests"),
            Some(cases.len().to_string().as_str())
        );
        assert_eq!(
            element.attribute("failures"),
            Some(count("failure").as_str())
        );
        assert_eq!(element.attribute("errors"), Some(count("error").as_str()));
    }
    cases
}

/// Changes one value of row `row` of `trace.csv` in `run` by one ULP; returns the
/// column name, the old and the new text.
fn nudge_one_ulp(run: &Path, row: usize) -> (String, String, String) {
    let path = run.join("trace.csv");
    let text = std::fs::read_to_string(&path).expect("trace.csv");
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let header: Vec<String> = lines[0].split(',').map(str::to_string).collect();
    let mut fields: Vec<String> = lines[row].split(',').map(str::to_string).collect();
    let (c, x) = fields
        .iter()
        .enumerate()
        .skip(1)
        .find_map(|(c, f)| {
            f.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && *x != 0.0)
                .map(|x| (c, x))
        })
        .expect("a nonzero number in the row");
    let nudged = f64::from_bits(x.to_bits() + 1);
    let old = std::mem::replace(&mut fields[c], format!("{nudged}"));
    assert_ne!(old, fields[c]);
    let new = fields[c].clone();
    lines[row] = fields.join(",");
    std::fs::write(&path, lines.join("\n") + "\n").expect("write trace.csv");
    (header[c].clone(), old, new)
}

#[test]
fn two_scenarios_that_match_exit_0() {
    let (dir, files, stored) = stored_pair("check-many-match");
    let o = check(&dir, &[&files[0], &files[1]], &stored, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let (mono, space) = (
        stdout
            .find("short_mono: matches")
            .expect("short_mono's line"),
        stdout
            .find("short_space: matches")
            .expect("short_space's line"),
    );
    assert!(mono < space, "argument order: {}", said(&o));
    assert!(stdout.contains("2 scenarios: 2 match"), "{}", said(&o));
    let v = verdict(&dir);
    assert_eq!(
        statuses(&v),
        [("short_mono", "match"), ("short_space", "match")].map(|(a, b)| (a.into(), b.into()))
    );
    assert_eq!(v["exit_code"], 0);
    assert_eq!(v["totals"]["match"], 2);
    // The JSON verdict's totals: the check's own wall time (the JUnit suite's) and the
    // scenarios' times added up.
    let summed: f64 = v["scenarios"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["wall_seconds"].as_f64().unwrap())
        .sum();
    let totals = &v["totals"];
    assert!(
        (totals["summed_seconds"].as_f64().unwrap() - summed).abs() < 1e-9,
        "{totals}"
    );
    assert!(totals["wall_seconds"].as_f64().is_some(), "{totals}");
    for s in v["scenarios"].as_array().unwrap() {
        assert_eq!(s["identical"], true);
        assert_eq!(s["digest"]["equal"], true);
        assert_eq!(s["first_difference"], Value::Null);
        assert!(s["wall_seconds"].as_f64().is_some_and(|t| t >= 0.0), "{s}");
    }
    let cases = junit(&dir);
    assert_eq!(cases.len(), 2);
    assert!(cases.iter().all(|c| c.problem.is_none()), "{cases:?}");
    // By default the reruns are kept beside the stored runs.
    assert!(stored.join("short_mono.new/summary.json").is_file());
    assert!(stored.join("short_space.new/summary.json").is_file());

    // One scenario against the directory of stored runs: mapped by name too.
    let o = bin()
        .arg("check")
        .arg(&files[1])
        .arg("--against")
        .arg(&stored)
        .output()
        .expect("spawn dsmcosim");
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("short_space: matches"),
        "{}",
        said(&o)
    );
}

#[test]
fn a_one_ulp_edit_in_one_of_two_exits_4_and_names_scenario_and_record() {
    let (dir, files, stored) = stored_pair("check-many-ulp");
    let (column, old, nudged) = nudge_one_ulp(&stored.join("short_space"), 3);
    let o = check(&dir, &[&files[0], &files[1]], &stored, &[]);
    assert_eq!(o.status.code(), Some(4), "{}", said(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("short_mono: matches"), "{}", said(&o));
    assert!(stdout.contains("short_space: differs from"), "{}", said(&o));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("2 scenarios: 1 match, 1 mismatch"),
        "{}",
        said(&o)
    );

    let v = verdict(&dir);
    assert_eq!(
        statuses(&v),
        [("short_mono", "match"), ("short_space", "mismatch")].map(|(a, b)| (a.into(), b.into()))
    );
    assert_eq!(v["exit_code"], 4);
    let d = &v["scenarios"][1]["first_difference"];
    assert_eq!(d["file"], "trace.csv", "{d}");
    assert_eq!(d["kind"], "value", "{d}");
    assert_eq!(d["row"], 3, "{d}");
    assert_eq!(d["time_column"], "t", "{d}");
    assert_eq!(d["column"], column.as_str(), "{d}");
    assert_eq!(d["stored"], nudged.as_str(), "{d}");
    assert_eq!(d["new"], old.as_str(), "{d}");
    assert!(
        d["rel"].as_f64().is_some_and(|r| r > 0.0 && r < 3e-16),
        "one ULP: {d}"
    );
    // The digests agree: only the stored CSV changed.
    assert_eq!(v["scenarios"][1]["digest"]["equal"], true);

    let cases = junit(&dir);
    assert_eq!(cases.len(), 2);
    assert_eq!(cases[0].name, "short_mono");
    assert_eq!(cases[0].problem, None);
    assert_eq!(cases[1].name, "short_space");
    let (tag, kind, message) = cases[1].problem.clone().expect("a failure");
    assert_eq!((tag.as_str(), kind.as_str()), ("failure", "mismatch"));
    let time = d["time"].as_str().expect("time");
    let expected =
        format!("trace.csv, t = {time} (row 3), column {column}: stored {nudged}, new {old}");
    assert!(
        message.starts_with(&expected),
        "{message}\nexpected {expected}"
    );
}

#[test]
fn a_scenario_without_a_stored_run_exits_1_and_the_others_are_checked() {
    let (dir, files, stored) = stored_pair("check-many-missing");
    let mut v = shipped("grid16_monolithic");
    v["name"] = Value::from("short_unstored");
    v["duration"] = Value::from(1.0);
    let unstored = write_json(&dir, "short_unstored.json", &v);
    let o = check(&dir, &[&files[0], &unstored, &files[1]], &stored, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", said(&o));
    let v = verdict(&dir);
    assert_eq!(
        statuses(&v),
        [
            ("short_mono", "match"),
            ("short_unstored", "missing"),
            ("short_space", "match")
        ]
        .map(|(a, b)| (a.into(), b.into()))
    );
    assert_eq!(v["totals"]["missing"], 1);
    assert!(!stored.join("short_unstored.new").exists(), "nothing rerun");
    let cases = junit(&dir);
    assert_eq!(cases.len(), 3);
    let (tag, kind, message) = cases[1].problem.clone().expect("an error");
    assert_eq!((tag.as_str(), kind.as_str()), ("error", "missing"));
    assert!(message.contains("short_unstored/summary.json"), "{message}");

    // A bad scenario file is exit 2 when nothing else fails ...
    let bad = dir.join("bad.json");
    std::fs::write(&bad, "{\"name\": \"bad\", \"dt\": -1}").expect("write");
    let o = check(&dir, &[&files[0], &bad], &stored, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    assert_eq!(
        statuses(&verdict(&dir)),
        [("short_mono", "match"), ("bad", "error")].map(|(a, b)| (a.into(), b.into()))
    );
    // ... and a mismatch outranks a missing run and a bad scenario.
    nudge_one_ulp(&stored.join("short_mono"), 2);
    let o = check(&dir, &[&bad, &unstored, &files[0], &files[1]], &stored, &[]);
    assert_eq!(o.status.code(), Some(4), "{}", said(&o));
    let cases = junit(&dir);
    let kinds: Vec<Option<String>> = cases
        .iter()
        .map(|c| c.problem.as_ref().map(|p| p.1.clone()))
        .collect();
    assert_eq!(
        kinds,
        [Some("error"), Some("missing"), Some("mismatch"), None].map(|k| k.map(String::from))
    );
}

#[test]
fn work_puts_the_reruns_elsewhere_and_leaves_nothing_beside_the_stored_runs() {
    let (dir, files, stored) = stored_pair("check-many-work");
    let listing = |d: &Path| {
        let mut names: Vec<String> = std::fs::read_dir(d)
            .expect("read_dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    };
    let runs = ["short_mono", "short_space"];
    let before = listing(&stored);
    let before_runs: Vec<Vec<String>> = runs.iter().map(|r| listing(&stored.join(r))).collect();
    let work = dir.join("work");
    let o = check(
        &dir,
        &[&files[0], &files[1]],
        &stored,
        &["--work", work.to_str().expect("utf-8")],
    );
    assert_eq!(o.status.code(), Some(0), "{}", said(&o));
    assert_eq!(
        listing(&stored),
        before,
        "nothing new beside the stored runs"
    );
    for (name, files) in runs.iter().zip(&before_runs) {
        assert!(work.join(name).join("summary.json").is_file(), "{name}");
        assert_eq!(
            &listing(&stored.join(name)),
            files,
            "{name}: stored run untouched"
        );
    }
    let v = verdict(&dir);
    assert_eq!(
        v["scenarios"][0]["new"],
        work.join("short_mono").display().to_string()
    );
}

#[test]
fn a_run_stored_under_the_file_stem_is_found_and_a_scenario_given_twice_is_refused() {
    let (dir, files, stored) = stored_pair("check-many-stem");
    // short_mono.json renamed inside, its run stored under the file stem.
    let mut v: Value =
        serde_json::from_str(&std::fs::read_to_string(&files[0]).expect("read")).expect("json");
    v["name"] = Value::from("renamed_mono");
    write_json(&dir, "short_mono.json", &v);
    let o = check(&dir, &[&files[0], &files[1], &files[1]], &stored, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", said(&o));
    let v = verdict(&dir);
    assert_eq!(
        statuses(&v),
        [
            ("renamed_mono", "match"),
            ("short_space", "match"),
            ("short_space", "error")
        ]
        .map(|(a, b)| (a.into(), b.into()))
    );
    assert_eq!(
        v["scenarios"][0]["stored"],
        stored.join("short_mono").display().to_string()
    );
    let message = v["scenarios"][2]["message"].as_str().unwrap_or("");
    assert!(message.contains("give each scenario once"), "{message}");
}
