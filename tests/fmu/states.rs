//! Saved states of the mass-spring-damper FMU: restoring a state and stepping again gives
//! the same bits, in the same instance and, through serialization, in a fresh one. The
//! checks take the FMU's stem, so `fmi3.rs` runs them on msd3 as well.

use dsmcosim::fmu::{Fmu, Instance};

use crate::fmus::{load, real, start, vr};

const H: f64 = 1e-3;

/// Steps `inst` from step `from` to step `to` (t = i·H).
fn run(inst: &mut Instance, from: u32, to: u32) {
    for i in from..to {
        inst.do_step(f64::from(i) * H, H)
            .unwrap_or_else(|e| panic!("step {i}: {e}"));
    }
}

fn forced(fmu: &Fmu) -> Instance {
    let mut inst = start(fmu, "plant", &[("v0", 0.3)]);
    inst.set_real(&[vr(fmu, "F")], &[2.0]).expect("set F");
    inst
}

#[test]
fn restoring_a_state_repeats_the_run_bit_for_bit() {
    restoring_repeats("msd");
}

/// Steps `stem` to 1 s, saves, steps to 2 s, restores and steps to 2 s again: the same x.
pub fn restoring_repeats(stem: &str) {
    let fmu = load(stem, "plant");
    let x = vr(&fmu, "x");
    let mut inst = forced(&fmu);
    run(&mut inst, 0, 1000);
    let state = inst.get_state().expect("get_state at t = 1 s");
    let at_one = real(&inst, x);
    run(&mut inst, 1000, 2000);
    let first = real(&inst, x);
    assert_ne!(first, at_one, "the run from 1 s to 2 s must move x");
    inst.set_state(&state).expect("set_state");
    assert_eq!(
        real(&inst, x).to_bits(),
        at_one.to_bits(),
        "x right after set_state"
    );
    run(&mut inst, 1000, 2000);
    let second = real(&inst, x);
    assert_eq!(
        first.to_bits(),
        second.to_bits(),
        "x at t = 2 s: {first} then {second}"
    );
}

#[test]
fn a_serialized_state_resumes_in_a_fresh_instance_bit_for_bit() {
    serialized_resumes("msd");
}

/// Serializes `stem`'s state at 1 s and resumes it in a fresh instance: the same x at 2 s.
pub fn serialized_resumes(stem: &str) {
    let fmu = load(stem, "plant");
    let x = vr(&fmu, "x");
    let mut inst = forced(&fmu);
    run(&mut inst, 0, 1000);
    let state = inst.get_state().expect("get_state at t = 1 s");
    let bytes = inst.serialize_state(&state).expect("serialize");
    assert!(!bytes.is_empty(), "a serialized state has bytes");
    run(&mut inst, 1000, 2000);
    let want = real(&inst, x);

    // Default parameters and no force: everything that matters must come from the bytes.
    let mut fresh = start(&fmu, "fresh", &[]);
    let restored = fresh.deserialize_state(&bytes).expect("deserialize");
    fresh.set_state(&restored).expect("set_state");
    run(&mut fresh, 1000, 2000);
    let got = real(&fresh, x);
    assert_eq!(
        want.to_bits(),
        got.to_bits(),
        "x at t = 2 s: {want} then {got}"
    );

    // A state belongs to its instance.
    let err = inst.set_state(&restored).err().map(|e| e.to_string());
    assert!(err.is_some_and(|e| e.contains("another instance")));
}

#[test]
fn an_instance_and_its_states_outlive_the_fmu_handle_and_move_between_threads() {
    let fmu = load("msd", "plant");
    let dir = fmu.unpack_dir();
    let mut inst = start(&fmu, "plant", &[]);
    let state = inst.get_state().expect("get_state");
    drop(fmu);
    assert!(
        dir.exists(),
        "the unpack directory stays while an instance lives"
    );
    let moved = std::thread::spawn(move || {
        run(&mut inst, 0, 10);
        inst.set_state(&state).expect("set_state on another thread");
        drop(inst);
        state
    })
    .join()
    .expect("the stepping thread");
    drop(moved);
    assert!(
        !dir.exists(),
        "the unpack directory goes with the last instance and state"
    );
}
