//! Measuring and controlling: the constraint-violation cost, the Dynamic Simplex Method
//! that tunes the delays online, and the static Nelder–Mead baseline.

pub mod cost;
pub mod dsm;
pub mod experiment;
pub mod nelder_mead;
pub mod paired;
pub mod plant;
pub mod problem;

pub use cost::{CostMeter, Epoch};
pub use dsm::{d_s_min, Dsm, DsmConfig, DsmError, DsmPhase, Feasible, SimplexError};
pub use nelder_mead::{NelderMead, NelderMeadConfig, NelderMeadPhase};
pub use paired::{Paired, Verdict};
pub use plant::{Plant, WindowSink};
