//! FMI 2.0 and FMI 3.0 co-simulation FMUs (issue 31): the loader in `dsmcosim::fmu` against the
//! test FMUs of `tests/fmus/`, built from C by each test into its own temporary
//! directory.

#[path = "../support/fmu_build.rs"]
pub mod fmu_build;

mod archive;
mod capability;
mod closed_form;
mod cosim;
mod crash;
mod description;
mod errors;
mod fmi3;
mod fmus;
mod forks;
mod loading;
mod logging;
mod own_fmu;
mod quirks;
mod states;
mod status;
mod types;
