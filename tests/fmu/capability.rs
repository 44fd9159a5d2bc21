//! The faulty FMU declares no state saving: the loader refuses state calls from the
//! description's flags, before the FMU is called (the FMU itself would answer
//! fmi2Error, which would be a `Status` error instead).

use dsmcosim::fmu::FmuError;

use crate::fmus::{load, real, start, vr};

#[test]
fn state_calls_on_an_fmu_without_the_capability_are_refused_before_the_call() {
    let fmu = load("faulty", "controller");
    let cs = fmu
        .description()
        .co_simulation
        .clone()
        .expect("co-simulation");
    assert!(!cs.can_get_and_set_fmu_state && !cs.can_serialize_fmu_state);
    let mut inst = start(&fmu, "controller", &[]);
    match inst.get_state() {
        Err(e @ FmuError::CapabilityMissing { .. }) => {
            let text = e.to_string();
            assert!(text.contains("canGetAndSetFMUstate"), "{text}");
            assert!(text.contains("'controller'"), "{text}");
            assert!(text.contains("fmi2GetFMUstate"), "{text}");
        }
        other => panic!("get_state: expected the capability refusal, got {other:?}"),
    }
    match inst.deserialize_state(&[0; 8]) {
        Err(FmuError::CapabilityMissing { capability, .. }) => {
            assert_eq!(capability, "canGetAndSetFMUstate");
        }
        other => panic!("deserialize_state: expected the capability refusal, got {other:?}"),
    }
    // The instance is unharmed: it steps (before its `fail_at`, 0.5 s) from rest under a
    // push, so x leaves 0 in the push's direction.
    inst.set_real(&[vr(&fmu, "F")], &[2.0]).expect("set F");
    inst.do_step(0.0, 0.01).expect("step");
    let x = real(&inst, vr(&fmu, "x"));
    assert!(x > 0.0 && x < 1e-3, "x = {x}");
}

#[test]
fn the_pd_controller_computes_its_law_from_the_inputs_it_holds() {
    let fmu = load("pd", "controller");
    let mut inst = start(&fmu, "controller", &[]);
    inst.set_real(&[vr(&fmu, "x"), vr(&fmu, "v")], &[0.3, -0.2])
        .expect("set inputs");
    inst.do_step(0.0, 0.01).expect("step");
    let u = real(&inst, vr(&fmu, "u"));
    let want = -10.0 * (0.3 - 0.0) - 2.0 * -0.2;
    assert!((u - want).abs() <= 1e-15, "u = {u}, want {want}");
}
