//! The JSON Schemas in `docs/schema/` are what `dsmcosim schema` generates from the
//! types that read the files, every shipped scenario and sweep file validates against
//! them, and a file that names its schema in `"$schema"` still loads.

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn json_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    files
}

#[test]
fn the_committed_schemas_are_current() {
    for (name, generated) in [
        (dsmcosim::schema::SCENARIO, dsmcosim::schema::scenario()),
        (dsmcosim::schema::SWEEP, dsmcosim::schema::sweep()),
    ] {
        let path = repo().join("docs/schema").join(name);
        let committed = std::fs::read_to_string(&path).unwrap();
        assert!(
            committed == dsmcosim::schema::text(&generated),
            "{} is stale: run `cargo run --release -- schema --out docs/schema`",
            path.display()
        );
    }
    let fields = repo().join("docs/schema").join(dsmcosim::schema::FIELDS);
    assert!(
        std::fs::read_to_string(&fields).unwrap() == dsmcosim::schema::reference(),
        "{} is stale: run `cargo run --release -- schema --out docs/schema`",
        fields.display()
    );
}

#[test]
fn every_shipped_file_validates_against_its_schema() {
    let scenario = jsonschema::validator_for(&dsmcosim::schema::scenario()).unwrap();
    let sweep = jsonschema::validator_for(&dsmcosim::schema::sweep()).unwrap();
    let scenarios = json_files(&repo().join("scenarios"));
    let sweeps = json_files(&repo().join("scenarios/sweeps"));
    assert!(scenarios.len() >= 20 && !sweeps.is_empty());
    for path in scenarios.iter().chain(&sweeps) {
        let doc = read_json(path);
        // scenarios/sweeps/ also holds the sweeps' base scenarios.
        let v = if doc.get("axes").is_some() {
            &sweep
        } else {
            &scenario
        };
        let errors: Vec<String> = v.iter_errors(&doc).map(|e| e.to_string()).collect();
        assert!(errors.is_empty(), "{}: {errors:?}", path.display());
    }
    // The schema rejects what the tool rejects: an unknown key, a wrong type.
    let mut bad = read_json(&scenarios[0]);
    bad["colour"] = json!("red");
    assert!(!scenario.is_valid(&bad), "an unknown key passes the schema");
    let mut bad = read_json(&scenarios[0]);
    bad["dt"] = json!("fast");
    assert!(!scenario.is_valid(&bad), "a string dt passes the schema");
}

#[test]
fn a_file_may_name_its_schema() {
    let mut doc = read_json(&repo().join("scenarios/grid16_monolithic.json"));
    doc["$schema"] = json!("../docs/schema/scenario.schema.json");
    let text = doc.to_string();
    let s = dsmcosim::scenario::parse_str(&text, "with_schema.json").expect("loads");
    assert_eq!(s.name, "grid16_monolithic");
}
