//! The co-simulation world: partitions stepping in lock-step, channels carrying their
//! messages, measurement windows — all ordered by the event kernel.
//!
//! ```text
//!  time t:  Measurement(t)   close the window ending at t (cost, τ, bandwidth)
//!           Sample(c)        channel c samples its routes' values at t and schedules
//!                            Delivery(t + latency); the receiver of a state keeps
//!                            its ghost's state of t; next Sample(c) at t + τ_c
//!           Delivery(msg)    the receiver uses the sample as its coupling says
//!                            (reset: overwrite the ghost / hold the force; predict,
//!                            passive: correct the ghost, extrapolate the force)
//!           PartitionStep    every node: this step's border loads (and, passive, its
//!                            port accounts) → rates at t → check → record → step
//! ```
//!
//! On a `tdma` network ([`tdma`]) the channels do not sample on their own: a
//! `ClockSync` event at every cycle start computes the cycle, and each data frame
//! becomes a `Slot` event at its actual start that samples what the sender has then
//! and schedules the `Delivery` of its messages (nothing for a lost frame).
//!
//! Within a [`crate::kernel::EventClass`] at equal time events leave FIFO, so channels sample in
//! channel order and messages arrive in the order they were sent. Nodes step in node
//! order inside one `PartitionStep` event; they share nothing during a step, so the
//! order cannot change a bit of the result, and from [`world::PARALLEL_MIN_LINKS`] links
//! per lock-step they step in parallel on rayon's threads, every reduction (the first
//! error, max |w|) done in node order after the parallel part.

pub mod event;
pub mod fit;
pub mod fmus;
mod partitions;
pub mod tdma;
pub mod unit;
pub mod world;

pub use event::Event;
pub use tdma::TdmaLink;
pub use unit::Unit;
pub use world::{CoSim, EpochRecord, Observation, Observer, StepValues};
