//! The TDMA network's configuration as a scenario holds it: slot geometry, link,
//! clocks, jitter and a slot list. Plain data, defined with the model so that the model
//! needs nothing of the network; the protocol ([`crate::network::tdma`]) implements
//! their methods (construction, checks, scheduling) and re-exports them.

use crate::kernel::SimTime;

/// Processing jitter added to every frame's latency (drawn per frame from the
/// sender's jitter stream).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Jitter {
    /// No jitter: nothing is drawn.
    None,
    /// Uniform on the whole nanoseconds `0..=max`; `max = 0` draws nothing.
    Uniform {
        /// Largest jitter [ns].
        max: SimTime,
    },
    /// Exponential with the given mean, rounded to the nanosecond; `mean = 0` draws
    /// nothing.
    Exponential {
        /// Mean jitter [ns].
        mean: SimTime,
    },
}

/// A TDMA network: node 0 is the server, nodes `1..=clients` the clients (client `i`
/// is partition node `i − 1`, see [`crate::network::tdma::tdma_node`]).
///
/// A cycle is `cycle` long and made of slots of length `slot`, in this order: the
/// sync slot (server), one static slot per node (server first, then clients 1..=n),
/// then `capacity = cycle / slot − (n + 2)` dynamic slots that follow the slot list.
///
/// `TdmaConfig::new` (in [`crate::network::tdma::config`]) gives the zero-effect values (no guard, instantaneous link, no
/// propagation, no header, perfect clocks, no jitter) for every field but the
/// geometry; a scene sets what it needs.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TdmaConfig {
    /// Length of every slot (sync, static and dynamic) [ns]; > 0.
    pub slot: SimTime,
    /// Guard time [ns]: the last `guard` of every slot is left silent, so a frame must
    /// fit in `slot − guard`; it absorbs clock offsets (see the crate docs on
    /// collisions). `< slot`.
    pub guard: SimTime,
    /// Cycle length [ns]: a whole number of slots, at least the sync and static part,
    /// `(clients + 2) · slot`.
    pub cycle: SimTime,
    /// Link rate [bit/s]; > 0, `f64::INFINITY` for an instantaneous link (frames take
    /// no time on the wire, as on an ideal channel).
    pub link_rate: f64,
    /// Propagation delay from any node to any node [ns].
    pub propagation: SimTime,
    /// Header bytes of every frame [B]; a sync frame is a bare header.
    pub header_bytes: u64,
    /// Number of client nodes `n` (≥ 1); the network has nodes `0..=n`.
    pub clients: usize,
    /// Bound of the clients' clock drift [ppm]: each client's rate offset is drawn once,
    /// uniformly in `[−drift_ppm, +drift_ppm]`; 0 = perfect oscillators, nothing drawn.
    pub drift_ppm: f64,
    /// Random walk of the rate offset [ppm/√s]: at every cycle boundary each client's
    /// rate moves by a normal step of standard deviation `random_walk_ppm · √cycle`
    /// (not bounded by `drift_ppm`); 0 = off, nothing drawn.
    pub random_walk_ppm: f64,
    /// Bound of the residual clock error after a sync [ns]: at every received sync
    /// frame a client's offset is set to a whole number of ns drawn uniformly in
    /// `[−sync_error, +sync_error]`; 0 = exact sync, nothing drawn.
    pub sync_error: SimTime,
    /// Processing jitter added to every frame's latency.
    pub jitter: Jitter,
}

/// One dynamic slot's use: `sender` transmits its data of `channel`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
pub struct SlotEntry {
    /// Sending TDMA node (0 = server).
    pub sender: usize,
    /// Channel index.
    pub channel: usize,
}

/// The dynamic part of a cycle: entry `j` is dynamic slot `j` (`None` = idle); slots
/// past the end of the list are idle. The same list repeats every cycle until a new
/// one goes into force.
#[derive(Debug, Clone, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct SlotList {
    /// Entries in dynamic-slot order.
    pub entries: Vec<Option<SlotEntry>>,
}
