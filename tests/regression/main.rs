//! `dsmcosim check`, the CI regression check, as a user meets it: its exit codes and its
//! first-difference message on a stored run made to differ.
//!
//! The rerun of every stored run in `results/` against its digest and CSV files is the
//! README's own command, `dsmcosim check scenarios/*.json --against results/`, run on a
//! fresh copy of the checkout by `tests/cli/front_page.rs`.

use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `dsmcosim check` as a user meets it: its exit codes and the first-difference message.
#[test]
fn check_cli_exit_codes() {
    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR")).join("check-cli");
    let _ = std::fs::remove_dir_all(&scratch);
    let stored = scratch.join("stored");
    std::fs::create_dir_all(&stored).expect("scratch dir");
    for f in ["summary.json", "trace.csv", "epochs.csv"] {
        std::fs::copy(
            repo().join("results/grid16_space_fixed").join(f),
            stored.join(f),
        )
        .expect("copy a stored run");
    }
    let scenario = repo().join("scenarios/grid16_space_fixed.json");
    let check = |against: &Path, extra: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
            .arg("check")
            .arg(&scenario)
            .arg("--against")
            .arg(against)
            .args(extra)
            .output()
            .expect("spawn dsmcosim");
        let text = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        (out.status.code(), text)
    };
    // The stored run diverged at 23.991 s; the rerun diverges identically.
    let (code, text) = check(&stored, &[]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("matches"), "{text}");
    assert!(scratch.join("stored.new/trace.csv").is_file());

    // One changed digit in the last value of row 124 (t = 12.3): its KE, the last
    // column since the invariants follow the bodies.
    let trace = std::fs::read_to_string(stored.join("trace.csv")).expect("trace");
    let mut lines: Vec<String> = trace.lines().map(str::to_string).collect();
    let last = lines[124].pop().expect("a value");
    lines[124].push(if last == '1' { '2' } else { '1' });
    std::fs::write(stored.join("trace.csv"), lines.join("\n") + "\n").expect("write");
    let (code, text) = check(&stored, &[]);
    assert_eq!(code, Some(4), "{text}");
    assert!(
        text.contains("first difference: trace.csv, t = 12.3 (row 124), column KE: stored "),
        "{text}"
    );
    let (code, text) = check(&stored, &["--tolerance", "1e-6"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("within tolerance 1e-6"), "{text}");

    let (code, text) = check(&scratch.join("missing"), &[]);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("summary.json"), "{text}");
    let (code, text) = check(&stored, &["--tolerance", "-1"]);
    assert_eq!(code, Some(2), "{text}");
}
