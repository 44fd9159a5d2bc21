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
