//! Rigid bodies joined by distance links, with SMC (or Baumgarte) constraint
//! stabilization.
//!
//! - [`state`]: the ODE state `(x, v, z)` and its rates;
//! - [`system`]: the static model (masses, inertias, links, forces) and the workspace;
//! - [`dynamics`]: the rate function — link geometry, accelerations, the multiplier law;
//! - [`solver`]: the `J M⁻¹ Jᵀ` operator and its exact (Cholesky) or CG solve;
//! - [`integrator`]: explicit Euler, symplectic Euler and RK4 steps.

pub mod dynamics;
pub mod integrator;
pub mod invariants;
pub mod solver;
pub mod spring;
pub mod state;
pub mod system;

pub use state::State;
pub use system::{RowLoad, System};
