//! The reproducers of the hardening work (`tests/corpus/*.json`): each input that once
//! panicked, hung, aborted on allocation or gave a poor message, with the exit code and
//! a fragment of the one-line message `validate` must give now (`tests/corpus/expected.json`).
//! An input that became legal (exit 0) gets a fragment of its plan on stdout instead,
//! and nothing on stderr. An entry whose command is `run` runs the file into a scratch
//! directory: its fragment is looked for in everything the run printed (its summary
//! line, a warning, or the one-line error). A new reproducer is a new file and a new
//! entry.

use std::time::Duration;

use serde_json::Value;

use super::{repo, said};

#[test]
fn every_reproducer_gets_its_verdict() {
    let dir = repo().join("tests/corpus");
    let expected: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("expected.json")).unwrap()).unwrap();
    let entries = expected.as_object().unwrap();
    let files = std::fs::read_dir(&dir)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().file_name() != "expected.json")
        .count();
    assert_eq!(
        files,
        entries.len(),
        "every corpus file has an entry and back"
    );
    let scratch = super::scratch("corpus");
    for (name, want) in entries {
        let file = dir.join(format!("{name}.json"));
        let command = want["command"].as_str().unwrap();
        let out = scratch.join(name);
        let mut args = vec![command, file.to_str().unwrap()];
        if command == "run" {
            args.extend(["-o", out.to_str().unwrap()]);
        }
        let o = super::limits::bounded(&args, Duration::from_secs(300));
        let code = want["exit"].as_i64().unwrap() as i32;
        assert_eq!(o.status.code(), Some(code), "{name}: {}", said(&o));
        let err = String::from_utf8_lossy(&o.stderr);
        let fragment = want["fragment"].as_str().unwrap();
        if command == "run" {
            let all = String::from_utf8_lossy(&o.stdout).into_owned() + &err;
            let line = all.lines().find(|l| l.contains(fragment));
            assert!(
                line.is_some_and(|l| l.len() < 1000),
                "{name}: expected {fragment:?} on a short line: {}",
                said(&o)
            );
            continue;
        }
        if code == 0 {
            let out = String::from_utf8_lossy(&o.stdout);
            assert!(
                out.contains(fragment) && err.is_empty(),
                "{name}: expected {fragment:?} in the plan: {}",
                said(&o)
            );
            continue;
        }
        assert!(
            err.contains(fragment),
            "{name}: expected {fragment:?}: {}",
            said(&o)
        );
        assert_eq!(err.lines().count(), 1, "{name}: one line: {err}");
        assert!(
            err.len() < 1000,
            "{name}: a short message ({} bytes)",
            err.len()
        );
    }
}
