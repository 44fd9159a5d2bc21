//! Building, loading and starting the test FMUs.

use dsmcosim::fmu::{Fmu, Instance};

use crate::fmu_build;

/// Builds the test FMU `stem` in a fresh temporary directory and loads it as `name`.
/// The build directory goes away at once: the loader works from its own copy.
pub fn load(stem: &str, name: &str) -> Fmu {
    let dir = tempfile::tempdir().expect("temporary directory");
    let path = fmu_build::build_test_fmu(stem, dir.path())
        .unwrap_or_else(|e| panic!("building {stem}.fmu: {e}"));
    Fmu::load(name, &path).unwrap_or_else(|e| panic!("loading {stem}.fmu: {e}"))
}

/// The value reference of the variable `var`.
pub fn vr(fmu: &Fmu, var: &str) -> u32 {
    fmu.description()
        .variable(var)
        .unwrap_or_else(|| panic!("{} has no variable {var}", fmu.name()))
        .value_reference
}

/// An instance with `params` (name, value) set, set up from t = 0 and initialized.
pub fn start(fmu: &Fmu, instance: &str, params: &[(&str, f64)]) -> Instance {
    let mut inst = fmu.instantiate(instance, false).expect("instantiate");
    let refs: Vec<u32> = params.iter().map(|(n, _)| vr(fmu, n)).collect();
    let values: Vec<f64> = params.iter().map(|&(_, v)| v).collect();
    inst.set_real(&refs, &values).expect("set parameters");
    inst.setup_experiment(0.0, None).expect("setup");
    inst.enter_initialization_mode()
        .expect("enter initialization");
    inst.exit_initialization_mode()
        .expect("exit initialization");
    inst
}

/// One Real output.
pub fn real(inst: &Instance, vr: u32) -> f64 {
    let mut v = [f64::NAN];
    inst.get_real(&[vr], &mut v).expect("get_real");
    v[0]
}

/// Runs this test binary again for the single test `test` with `var=value` set: for
/// tests whose subject must happen in another process (a crash, stderr output).
pub fn rerun_self(test: &str, var: &str, value: &str) -> std::process::Output {
    let exe = std::env::current_exe().expect("this test binary");
    std::process::Command::new(exe)
        .args(["--exact", test, "--nocapture", "--test-threads=1"])
        .env(var, value)
        .output()
        .expect("run the child")
}

/// A fresh directory `target/test-scratch/<group>/<name>` for a test's files (kept after
/// the test, for a look at what a failing run wrote).
pub fn scratch(group: &str, name: &str) -> std::path::PathBuf {
    let d = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("test-scratch")
        .join(group)
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch");
    d
}
