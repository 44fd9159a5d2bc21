//! The front page works on a fresh clone: every shell command block of README.md and
//! the run steps of docs/guide.md's GitHub Actions job, run as written in a copy of the
//! checkout's files. Python blocks run in `python/tests/test_front_page.py`.
//!
//! Commands are run by `sh` with the binary under test first on `PATH`, in the order
//! written. Three cargo commands cannot run inside `cargo test` (the build directory is
//! locked while it runs): `cargo run --release -- ARGS` is the binary with ARGS, `cargo
//! run --release --example build_fmus -- DIR` builds the same test FMUs into DIR through
//! the code the example runs, and `cargo test --release` / `cargo build --release` are
//! what this test is running. Any other command is an error here, so a new kind of
//! command on the front page comes with its way of being tested.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::{fmu_build, repo, said, scratch};

/// The command lines of every fenced block in `text` whose info string is `lang`.
fn blocks(text: &str, lang: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut current: Option<Vec<String>> = None;
    for line in text.lines() {
        let fence = line.trim_start().strip_prefix("```");
        match (&mut current, fence) {
            (None, Some(info)) if info.trim() == lang => current = Some(Vec::new()),
            (Some(_), Some(_)) => out.push(current.take().expect("open block")),
            (Some(lines), None) if !line.trim().is_empty() => lines.push(line.to_string()),
            _ => {}
        }
    }
    out
}

/// The `run:` commands of a GitHub Actions job in YAML (a `run: >` folded block joined
/// into one line).
fn actions_runs(yaml: &str) -> Vec<String> {
    let mut runs = Vec::new();
    let mut lines = yaml.lines().peekable();
    while let Some(line) = lines.next() {
        let trimmed = line.trim_start().trim_start_matches("- ");
        let Some(value) = trimmed.strip_prefix("run:") else {
            continue;
        };
        let value = value.trim();
        if value == ">" || value == "|" {
            let indent = line.len() - line.trim_start().len();
            let mut parts = Vec::new();
            while let Some(next) = lines.peek() {
                if next.len() - next.trim_start().len() <= indent || next.trim().is_empty() {
                    break;
                }
                parts.push(next.trim().to_string());
                lines.next();
            }
            runs.push(parts.join(" "));
        } else {
            runs.push(value.to_string());
        }
    }
    runs
}

/// A copy of what the front page's commands read (the scenarios, the stored runs, the
/// docs), in a fresh directory: a clone's files, without build products or FMUs.
fn fresh_clone(name: &str) -> PathBuf {
    let dir = scratch(name);
    for part in ["scenarios", "results", "docs"] {
        copy_tree(&repo().join(part), &dir.join(part));
    }
    for file in ["README.md", "Cargo.toml", "Cargo.lock"] {
        std::fs::copy(repo().join(file), dir.join(file)).expect("copy");
    }
    // What a clone has not: FMUs built by a user, scratch runs of `check`.
    let _ = std::fs::remove_dir_all(dir.join("scenarios/fmu"));
    dir
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read_dir") {
        let p = entry.expect("entry").path();
        let name = p.file_name().expect("name").to_string_lossy().into_owned();
        if name.ends_with(".new") || name == "fmu" && p.is_dir() {
            continue;
        }
        if p.is_dir() {
            copy_tree(&p, &to.join(&name));
        } else {
            std::fs::copy(&p, to.join(&name)).expect("copy");
        }
    }
}

/// Runs one front-page command in `clone`; `Err` with what it said when it fails.
fn run_command(clone: &Path, line: &str) -> Result<(), String> {
    let line = line.trim();
    let words: Vec<&str> = line.split_whitespace().collect();
    if matches!(
        words.as_slice(),
        ["cargo", "test", "--release", ..] | ["cargo", "build", "--release", ..]
    ) {
        return Ok(()); // what this test is running
    }
    if let Some(i) = words.iter().position(|w| *w == "build_fmus") {
        assert_eq!(words[..2], ["cargo", "run"], "{line}");
        let out = clone.join(words.get(i + 2).ok_or_else(|| format!("{line}: no DIR"))?);
        std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;
        for stem in fmu_build::TEST_FMUS {
            fmu_build::build_test_fmu(stem, &out)?;
        }
        return Ok(());
    }
    let command = if let Some(rest) = line.strip_prefix("cargo run --release -- ") {
        format!("dsmcosim {rest}")
    } else if let Some(rest) = line.strip_prefix("target/release/dsmcosim ") {
        format!("dsmcosim {rest}")
    } else if line.starts_with("dsmcosim ") {
        line.to_string()
    } else {
        panic!("the front page has a command this test cannot run: {line}");
    };
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .parent()
        .expect("bin dir")
        .to_path_buf();
    let path = std::env::join_paths(std::iter::once(bin_dir).chain(std::env::split_paths(
        &std::env::var_os("PATH").unwrap_or_default(),
    )))
    .expect("PATH");
    let o = Command::new("sh")
        .arg("-c")
        .arg(&command)
        .current_dir(clone)
        .env("PATH", path)
        .output()
        .expect("spawn sh");
    if o.status.success() {
        Ok(())
    } else {
        Err(format!("`{command}` failed: {}", said(&o)))
    }
}

#[test]
fn every_readme_command_block_runs_on_a_fresh_clone() {
    let readme = std::fs::read_to_string(repo().join("README.md")).expect("README.md");
    let sh = blocks(&readme, "sh");
    assert!(sh.len() >= 5, "only {} sh blocks in README.md", sh.len());
    let clone = fresh_clone("front-page-readme");
    let mut ran = 0;
    for line in sh.iter().flatten() {
        run_command(&clone, line).unwrap_or_else(|e| {
            panic!(
                "README.md: {e}\n\nIf a stored run in results/ no longer reproduces after a \
                 deliberate change, regenerate with `results/regenerate.sh`, review the \
                 digest changes it lists and the diff of results/, and commit them with the \
                 change."
            )
        });
        ran += 1;
    }
    // What the quick start and the four jobs promise is there.
    for out in [
        "runs/grid16_monolithic/summary.json",
        "runs/slot_layouts/sweep.csv",
        "runs/fmu_pd_tdma_cp/summary.json",
        "refs/tdma4_space_fixed/summary.json",
        "check.xml",
    ] {
        assert!(
            clone.join(out).is_file(),
            "README.md's commands wrote no {out}"
        );
    }
    eprintln!("README.md: {ran} commands ran on a fresh copy");
}

#[test]
fn the_guides_ci_job_runs_on_a_fresh_clone() {
    let guide = std::fs::read_to_string(repo().join("docs/guide.md")).expect("guide");
    let jobs = blocks(&guide, "yaml");
    let job = jobs
        .iter()
        .find(|b| b.iter().any(|l| l.contains("dsmcosim check")))
        .expect("docs/guide.md has a CI job running dsmcosim check");
    let runs = actions_runs(&job.join("\n"));
    assert!(runs.len() >= 2, "{runs:?}");
    let clone = fresh_clone("front-page-ci");
    for line in &runs {
        run_command(&clone, line).unwrap_or_else(|e| panic!("docs/guide.md CI job: {e}"));
    }
    assert!(clone.join("check.xml").is_file() && clone.join("check.json").is_file());
}
