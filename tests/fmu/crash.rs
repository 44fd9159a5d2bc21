//! A crash inside an FMU is not a Rust panic: it ends the process by its signal. Run in
//! a child process (this test binary again, told by an environment variable to crash),
//! since it would end this one.

use std::os::unix::process::ExitStatusExt;

use crate::fmus::{load, rerun_self, vr};

const CHILD: &str = "DSMCOSIM_FMU_CRASH_CHILD";

#[test]
fn a_crash_inside_an_fmu_kills_the_process_by_its_signal() {
    if std::env::var_os(CHILD).is_some() {
        let fmu = load("faulty", "plant");
        let mut inst = fmu.instantiate("plant", false).expect("instantiate");
        inst.set_integer(&[vr(&fmu, "crash")], &[1])
            .expect("set crash");
        inst.setup_experiment(0.0, None).expect("setup");
        inst.enter_initialization_mode().expect("enter");
        inst.exit_initialization_mode().expect("exit");
        let result = inst.do_step(0.0, 0.1);
        // Reached only if the FMU did not crash: the parent then sees exit code 0.
        eprintln!("child: fmi2DoStep returned {result:?}");
        return;
    }
    let out = rerun_self(
        "crash::a_crash_inside_an_fmu_kills_the_process_by_its_signal",
        CHILD,
        "1",
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.signal(),
        Some(libc::SIGSEGV),
        "the child should die of SIGSEGV; status {:?}, stderr:\n{stderr}",
        out.status
    );
    assert!(
        !stderr.contains("panicked"),
        "a crash is not a panic:\n{stderr}"
    );
}

/// The crashed process's unpack directory stays behind in TMPDIR (nothing of it runs
/// after the signal); the next dsmcosim that unpacks an FMU removes it, since its
/// process is gone, and keeps the directory of a process that still runs.
#[test]
fn a_crashed_runs_unpack_directory_is_removed_by_the_next_run() {
    if std::env::var_os(CHILD).is_some() {
        return; // the crash itself is the test above's child
    }
    let tmp = crate::fmus::scratch("crash", "tmpdir");
    let exe = std::env::current_exe().expect("this test binary");
    let crashed = std::process::Command::new(exe)
        .args([
            "--exact",
            "crash::a_crash_inside_an_fmu_kills_the_process_by_its_signal",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD, "1")
        .env("TMPDIR", &tmp)
        .output()
        .expect("run the child");
    assert_eq!(crashed.status.signal(), Some(libc::SIGSEGV));
    let left = |dir: &std::path::Path| -> Vec<String> {
        std::fs::read_dir(dir)
            .expect("tmpdir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with("dsmcosim-fmu-"))
            .collect()
    };
    let stale = left(&tmp);
    assert_eq!(stale.len(), 1, "the crash left its directory: {stale:?}");
    // A live process's directory (this test's own pid) must stay.
    let live = format!("dsmcosim-fmu-{}-live", std::process::id());
    std::fs::create_dir(tmp.join(&live)).expect("mkdir");
    // The next dsmcosim that unpacks an FMU: validate a scene with the msd FMU.
    let fmus = tmp.join("fmus");
    std::fs::create_dir_all(&fmus).expect("mkdir");
    crate::fmu_build::build_test_fmu("msd", &fmus).expect("build msd");
    let scenario = fmus.join("s.json");
    std::fs::write(
        &scenario,
        r#"{"name": "s", "seed": 1, "duration": 0.01, "dt": 0.001,
            "fmus": [{"name": "plant", "path": "msd.fmu"}]}"#,
    )
    .expect("write");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .arg("validate")
        .arg(&scenario)
        .env("TMPDIR", &tmp)
        .output()
        .expect("dsmcosim");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        left(&tmp),
        vec![live],
        "the stale directory is gone, the live one kept"
    );
}
