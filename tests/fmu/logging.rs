//! The FMU's log messages reach stderr, prefixed with the instance name, only when the
//! instance's logging is on, in both FMI versions (FMI 3.0's callback is not variadic:
//! its messages arrive whole). Run in a child process (this test binary again) so its
//! stderr can be read.

use crate::fmus::{load, rerun_self};

/// In the child (`child` set in its environment): `stem` instantiated with logging as
/// the variable says, initialized, and stepped by `h` [s], which must fail. In the
/// parent: the child ran so, and its stderr holds `logged` exactly when logging is on.
fn logs_only_when_on(test: &str, child: &str, stem: &str, h: f64, logged: &str) {
    if let Some(on) = std::env::var_os(child) {
        let fmu = load(stem, "plant");
        let mut inst = fmu.instantiate("plant", on == "1").expect("instantiate");
        inst.setup_experiment(0.0, None).expect("setup");
        inst.enter_initialization_mode().expect("enter");
        inst.exit_initialization_mode().expect("exit");
        let failed = inst.do_step(0.0, h).is_err();
        eprintln!("child: step failed = {failed}");
        return;
    }
    for on in ["0", "1"] {
        let out = rerun_self(test, child, on);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success(),
            "child ({on}): {:?}\n{stderr}",
            out.status
        );
        assert!(stderr.contains("child: step failed = true"), "{stderr}");
        assert_eq!(
            stderr.contains(logged),
            on == "1",
            "logging {on}, stderr:\n{stderr}"
        );
    }
}

#[test]
fn log_messages_are_printed_only_when_logging_is_on() {
    // fail_at defaults to 0.5 s: a 1-s step fails, and the FMU logs why.
    logs_only_when_on(
        "logging::log_messages_are_printed_only_when_logging_is_on",
        "DSMCOSIM_FMU_LOG_CHILD",
        "faulty",
        1.0,
        "[plant] fmi2Error logStatusError: the step would end past fail_at",
    );
}

#[test]
fn fmi3_log_messages_arrive_whole_and_only_when_logging_is_on() {
    // A step of size 0 is refused, and msd3 logs why.
    logs_only_when_on(
        "logging::fmi3_log_messages_arrive_whole_and_only_when_logging_is_on",
        "DSMCOSIM_FMU3_LOG_CHILD",
        "msd3",
        0.0,
        "[plant] fmi3Error logStatusError: fmi3DoStep with a step size <= 0",
    );
}
