//! docs/fmi.md's worked example ("Your own FMU"), built and run as the page writes it:
//! its C source, model description and scenario taken from the page, its shell block of
//! build commands run in a scratch checkout (with the FMI layer it copies from
//! `tests/fmus/`), and the run's trace checked against the lag's closed form.

use std::path::Path;
use std::process::Command;

/// The first fenced block of `lang` after the heading `## Your own FMU`.
fn block(page: &str, lang: &str) -> String {
    let section = &page[page.find("## Your own FMU").expect("the section")..];
    let start = section
        .find(&format!("```{lang}\n"))
        .unwrap_or_else(|| panic!("a {lang} block"))
        + lang.len()
        + 4;
    let len = section[start..].find("```").expect("closed");
    section[start..start + len].to_string()
}

#[test]
fn the_own_fmu_example_builds_runs_and_follows_its_closed_form() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let page = std::fs::read_to_string(repo.join("docs/fmi.md")).expect("docs/fmi.md");
    let root = tempfile::tempdir().expect("scratch");
    let root = root.path();
    // A checkout's part the page's commands read, and the page's three files.
    std::fs::create_dir_all(root.join("tests/fmus")).expect("mkdir");
    for header in ["fmi2_cs_functions.h", "fmi2_abi.h"] {
        std::fs::copy(
            repo.join("tests/fmus").join(header),
            root.join("tests/fmus").join(header),
        )
        .expect("copy a header");
    }
    let lag = root.join("lag");
    std::fs::create_dir_all(&lag).expect("mkdir");
    std::fs::write(lag.join("lag.c"), block(&page, "c")).expect("write");
    std::fs::write(lag.join("modelDescription.xml"), block(&page, "xml")).expect("write");
    std::fs::write(lag.join("lag.json"), block(&page, "json")).expect("write");
    // The build, as written (the first sh block: it builds, the second runs).
    let build = block(&page, "sh");
    assert!(build.contains("zip"), "{build}");
    if Command::new("zip").arg("-v").output().is_ok() {
        for line in build.lines().filter(|l| !l.trim().is_empty()) {
            let o = Command::new("sh")
                .args(["-c", line])
                .current_dir(root)
                .output()
                .expect("sh");
            assert!(
                o.status.success(),
                "`{line}`: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
    } else {
        // No zip here: the same layout, zipped by the test FMUs' builder.
        crate::fmu_build::build_fmu(
            &lag.join("lag.c"),
            &lag.join("modelDescription.xml"),
            "lag",
            &lag.join("lag.fmu"),
        )
        .map(|_| ())
        .unwrap_or_else(|e| panic!("{e}"));
    }
    let out = root.join("runs/lag");
    let o = Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .args(["run", "lag/lag.json", "--out", "runs/lag"])
        .current_dir(root)
        .output()
        .expect("dsmcosim");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // A scene of an FMU alone reports what it has: no |w|, no cost of links.
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        said.starts_with("lag: 2000 steps in ") && !said.contains("|w|") && !said.contains("cost"),
        "{said}"
    );
    // Its plan likewise: no body model, integrator, law or solve.
    let plan = Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .args(["validate", "lag/lag.json"])
        .current_dir(root)
        .output()
        .expect("dsmcosim");
    let plan = String::from_utf8_lossy(&plan.stdout);
    assert!(
        plan.contains("ok — no bodies; 2000 steps of 0.001 s"),
        "{plan}"
    );
    assert!(
        !plan.contains("stabilizer") && !plan.contains("integrator"),
        "{plan}"
    );
    let trace = std::fs::read_to_string(out.join("trace.csv")).expect("trace.csv");
    let mut lines = trace.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let (t_col, y_col) = (
        header.iter().position(|h| *h == "t").expect("t"),
        header.iter().position(|h| *h == "lag.y").expect("lag.y"),
    );
    let (mut worst, mut rows, mut last) = (0.0f64, 0, 0.0);
    for line in lines {
        let cells: Vec<f64> = line
            .split(',')
            .map(|c| c.parse().expect("number"))
            .collect();
        let (t, y) = (cells[t_col], cells[y_col]);
        worst = worst.max((y - (1.0 - (-t / 0.5).exp())).abs());
        rows += 1;
        last = y;
    }
    eprintln!("the docs' lag FMU: {rows} rows, within {worst:.1e} of 1 − e^(−t/T)");
    assert!(rows > 10 && last > 0.95, "{rows} rows, y ends at {last}");
    assert!(worst < 1e-12, "{worst} from the closed form");
}
