//! A failing fmi2DoStep is an error that names the FMU, the function and the time.

use dsmcosim::fmu::{FmuError, StepEnd};

use crate::fmus::{load, real, start, vr};

#[test]
fn a_step_past_fail_at_is_a_status_error_naming_fmu_function_and_time() {
    let fmu = load("faulty", "plant");
    let fail_at = 0.5;
    let mut inst = start(&fmu, "plant", &[("fail_at", fail_at)]);
    let mut crash = [-1];
    inst.get_integer(&[vr(&fmu, "crash")], &mut crash)
        .expect("get crash");
    assert_eq!(crash, [0], "crash defaults to 0");
    inst.set_real(&[vr(&fmu, "F")], &[1.0]).expect("set F");
    let h = 0.125; // binary-exact, so the step ending at fail_at is exactly at it
    let mut t = 0.0;
    let err = loop {
        match inst.do_step(t, h) {
            Ok(StepEnd::Completed) => {
                assert!(
                    t + h <= fail_at,
                    "a step ending at {} s past fail_at passed",
                    t + h
                );
                t += h;
            }
            Ok(other) => panic!("faulty asks for no stop: {other:?}"),
            Err(e) => break e,
        }
    };
    assert_eq!(t, fail_at, "the first failing step starts at fail_at");
    assert!(
        matches!(
            err,
            FmuError::Status {
                status: "fmi2Error",
                ..
            }
        ),
        "{err:?}"
    );
    assert_eq!(
        err.to_string(),
        format!("FMU 'plant': fmi2DoStep returned fmi2Error at t = {t} s")
    );
    // The steps before the failure happened: x = t²/2 for a unit force from rest.
    assert!((real(&inst, vr(&fmu, "x")) - t * t / 2.0).abs() <= 1e-15);
}
