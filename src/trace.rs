//! What a run records: the bit-exact digest ([`digest`]) and the decimated CSV trace
//! with the series kept for plots ([`recorder`]), with the net's momenta and energy
//! ([`invariants`]) beside the state; and the record-by-record comparison
//! of two runs' CSV files ([`compare`], used by `dsmcosim check`).

pub mod compare;
pub mod digest;
pub mod drift;
pub mod joint_work;
pub mod network_log;
pub mod plot_samples;
pub mod recorder;

/// The net's invariants, computed by the dynamics' layer ([`crate::multibody::invariants`]).
pub use crate::multibody::invariants::{self, Invariants};
pub use digest::Digest;
pub use network_log::NetworkLog;
pub use recorder::Recorder;
