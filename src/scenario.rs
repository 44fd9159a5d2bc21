//! Scenario files: the raw JSON form ([`file`](mod@file)), the validated form
//! ([`model`]) and the conversion between them ([`validate`]).

pub mod file;
pub mod grid;
pub mod model;
pub mod overrides;
pub mod validate;

pub use model::Scenario;
pub use overrides::{anchor_fmu_paths, load_with, relocated_fmu_paths};
pub use validate::{load, parse_at, parse_str};
