//! The FMU's log messages reach stderr, prefixed with the instance name, only when the
//! instance's logging is on. Run in a child process (this test binary again) so its
//! stderr can be read.

use crate::fmus::{load, rerun_self};

const CHILD: &str = "DSMCOSIM_FMU_LOG_CHILD";
const TEST: &str = "logging::log_messages_are_printed_only_when_logging_is_on";

#[test]
fn log_messages_are_printed_only_when_logging_is_on() {
    if let Some(on) = std::env::var_os(CHILD) {
        let fmu = load("faulty", "plant");
        let mut inst = fmu.instantiate("plant", on == "1").expect("instantiate");
        inst.setup_experiment(0.0, None).expect("setup");
        inst.enter_initialization_mode().expect("enter");
        inst.exit_initialization_mode().expect("exit");
        // fail_at defaults to 0.5 s: this step fails, and the FMU logs why.
        let failed = inst.do_step(0.0, 1.0).is_err();
        eprintln!("child: step failed = {failed}");
        return;
    }
    for on in ["0", "1"] {
        let out = rerun_self(TEST, CHILD, on);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success(),
            "child ({on}): {:?}\n{stderr}",
            out.status
        );
        assert!(stderr.contains("child: step failed = true"), "{stderr}");
        let logged = "[plant] fmi2Error logStatusError: the step would end past fail_at";
        assert_eq!(
            stderr.contains(logged),
            on == "1",
            "logging {on}, stderr:\n{stderr}"
        );
    }
}
