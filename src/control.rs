//! Measuring and (as the project grows) controlling: the constraint-violation cost.

pub mod cost;

pub use cost::{CostMeter, Epoch};
