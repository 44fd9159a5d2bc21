//! # dsmcosim
//!
//! A deterministic discrete-event co-simulator of distributed multi-body simulations:
//! rigid bodies joined by rigid distance links, stabilized by sliding-mode control (SMC),
//! integrated in lock-step on partitions ("nodes") that exchange border data over a
//! network (ideal periodic channels or a TDMA schedule), with the communication delays
//! re-chosen every measurement window by a Dynamic Simplex controller or a baseline.
//! The method, with every choice and its reason, is `docs/method.md` in the repository;
//! the module docs cite its sections as "method §N".
//!
//! ```text
//!   scenario.json ─parse─▶ ScenarioFile ─validate─▶ Scenario ─build─▶ CoSim (kernel + nodes + network)
//!
//!   event kernel (kernel::Kernel): pops (time, class, seq) in order; at equal time
//!   Measurement < Controller < ClockSync < Slot < Sample < Delivery < PartitionStep
//!
//!   at a window boundary t = jT:
//!     Measurement ── close window [t−T, t): cost C = Σ_links sqrt(1/T ∫ w²)  (control::cost)
//!     Controller  ── control::experiment: fork the world per candidate (lookahead),
//!                    DSM / baselines choose τ for [t, t+T); through TDMA a `Decide`
//!                    event broadcasts the slot list, clients confirm, switch at a cycle
//!   every cycle / period:
//!     ClockSync, Slot ── network::tdma: clocks, frames, collisions, latency
//!     Sample     ── ideal channels sample the owners' state / border forces at t
//!     Delivery   ── a message reaches its node: ghost state overwritten, force held
//!   every dt:
//!     PartitionStep ── every node, in node order (they share nothing within a step):
//!        1. external forces F(t_k) + held border forces
//!        2. link geometry: w, ẇ, J̇v per link            (multibody::dynamics)
//!        3. accelerations under the current z
//!        4. SMC: solve μ² J M⁻¹ Jᵀ ż = −α̂ − K sat(s/ε)    (multibody::solver)
//!        5. integrator: new (x, v, z) of bodies and ghosts (multibody::integrator)
//!        6. divergence check, trace record, digest chain   (trace)
//!
//!   end ─▶ summary.json, trace.csv, epochs.csv, network.csv, *.svg, written atomically
//! ```
//!
//! Simulated time is an integer count of nanoseconds ([`kernel::SimTime`]); the class
//! order above and the FIFO rule among equal keys are a documented guarantee (see
//! [`kernel::queue`] for why each class sits where it does). On ideal networks the
//! controller is not itself a queued event: the driver (`control::experiment`) advances
//! the kernel with `CoSim::advance_to(t)`, which stops right after the `Measurement`
//! events at `t`, decides, and lets the kernel go on — exactly the `Controller` slot of
//! the order. Likewise the one pending lock-step waits beside the queue rather than in
//! it (`PartitionStep` is the last class and no other event has it, so it runs exactly
//! where the queue would pop it). Nothing that reaches a trace depends on hash-map order, the thread count
//! or the wall clock; every random source is its own seeded ChaCha stream.

#![warn(missing_docs)]
// Physical fields carry their unit in brackets (`[s]`, `[m]`); rustdoc would read those
// as links. Every unresolved "link" is such a unit: with this line removed, `cargo doc`
// lists 237, all of them `[s]`, `[m]`, `[ns]`, `[N]`, … and no item name.
#![allow(rustdoc::broken_intra_doc_links)]

pub mod check;
pub mod checkpoint;
pub mod cli;
pub mod console;
pub mod control;
pub mod cosim;
pub mod coupling_study;
pub mod distance;
pub mod error;
pub mod fmu;
pub mod input;
pub mod interrupt;
pub mod kernel;
pub mod multibody;
pub mod network;
pub mod output;
pub mod partition;
pub mod progress;
pub mod report;
pub mod run;
pub mod scenario;
pub mod schema;
pub mod sweep;
pub mod trace;
pub mod tradeoff;

pub use error::{Error, Result};
