//! TDMA network model (method §4, "tdma"): the protocol core, independent of the
//! event kernel. The co-simulation drives it one cycle at a time
//! ([`engine::TdmaNetwork::run_cycle`]) and turns each frame into events: sample the
//! sender's data at the frame's `start`, deliver it at its `delivery` (lost frames
//! deliver nothing).
//!
//! | module | holds |
//! |---|---|
//! | [`config`] | [`TdmaConfig`] (units, zero-effect defaults), [`Jitter`], validation |
//! | [`layout`] | cycle geometry (sync, static, dynamic slots), [`layout::SlotList`] |
//! | [`frame`] | frame sizes (header + 8 B per float), transmission time, list fragments |
//! | [`schedule`] | requested τ → slot list, achieved τ of any list |
//! | [`clock`] | client clocks: drift, random walk, sync error, local ↔ global time |
//! | [`collision`] | frames on the wire and the collision rule |
//! | [`latency`] | transmission + propagation + seeded processing jitter |
//! | [`confirm`] | list broadcast, confirmation and switch at a cycle boundary |
//! | [`engine`] | one cycle after the other, all of the above together |
//! | [`random`] | one ChaCha8 stream per (source, node) from the scenario seed |
//!
//! Nodes: 0 is the server (sync frames, list decisions), client `i` is partition node
//! `i − 1` ([`tdma_node`]). Model only what the scene requires: with zero drift, random
//! walk, sync error and jitter no random number is drawn, and with an instantaneous
//! link and no propagation a list that realizes the requested periods delivers exactly
//! like an ideal channel sampling every τ from the (channel, sender) pair's first slot.

pub mod clock;
pub mod collision;
pub mod config;
pub mod confirm;
pub mod engine;
pub mod error;
pub mod frame;
pub mod latency;
pub mod layout;
pub mod random;
pub mod schedule;

pub use config::{Jitter, TdmaConfig};
pub use engine::{CycleReport, TdmaNetwork};
pub use error::TdmaError;
pub use layout::{CycleLayout, SlotEntry, SlotList};
pub use schedule::{schedule, ChannelRequest, Schedule};

/// The TDMA node of partition node `p` (0-based): node 0 is the server, so partition
/// node `p` is client `p + 1` (the number files and traces already use for it).
pub fn tdma_node(p: usize) -> usize {
    p + 1
}

#[cfg(test)]
mod tests;
