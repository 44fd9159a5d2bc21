//! # dsmcosim
//!
//! A deterministic discrete-event co-simulator of distributed multi-body simulations:
//! rigid bodies joined by rigid distance links, stabilized by sliding-mode control (SMC),
//! integrated in lock-step and (as the project grows) split over computing nodes that
//! exchange border data over a network whose delays a Dynamic Simplex controller tunes.
//!
//! ```text
//!   scenario.json ──parse──▶ ScenarioFile ──validate──▶ Scenario ──build──▶ System
//!                                                                            │
//!        ┌───────────────────────── one step k → k+1 (dt) ───────────────────┘
//!        │  1. external forces F(t_k)
//!        │  2. link geometry: w, ẇ, J̇v per link          (multibody::dynamics)
//!        │  3. accelerations under the current z
//!        │  4. SMC: solve μ² J M⁻¹ Jᵀ ż = −α̂ − K sat(s/ε)  (multibody::solver)
//!        │  5. integrator combines rates into the new (x, v, z) (multibody::integrator)
//!        │  6. divergence check, trace record, digest       (trace)
//!        └──▶ summary.json, trace.csv, *.svg written atomically (run, report, output)
//! ```
//!
//! Simulated time is an integer count of nanoseconds ([`kernel::SimTime`]); nothing that
//! reaches a trace depends on hash-map order or the wall clock.

#![warn(missing_docs)]
// Physical fields carry their unit in brackets (`[s]`, `[m]`); rustdoc would read those
// as links.
#![allow(rustdoc::broken_intra_doc_links)]

pub mod check;
pub mod checkpoint;
pub mod cli;
pub mod control;
pub mod cosim;
pub mod error;
pub mod kernel;
pub mod multibody;
pub mod network;
pub mod output;
pub mod partition;
pub mod progress;
pub mod report;
pub mod run;
pub mod scenario;
pub mod sweep;
pub mod trace;
pub mod tradeoff;

pub use error::{Error, Result};
