//! Errors of the TDMA model: a bad configuration, a slot list that does not fit the
//! cycle, or a request the scheduler cannot serve.
//!
//! Every message starts with the field it is about (`slot`, `drift_ppm`,
//! `slot_list[3].sender`, `tau[1]`) so the scenario layer can prefix its own path
//! (`network.tdma.`) and report it as is.

use crate::kernel::SimTime;

/// What is wrong with a TDMA configuration, slot list or schedule request.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TdmaError {
    /// A configuration field has a bad value (`field` is its name in [`super::TdmaConfig`]).
    #[error("{field}: {message}")]
    Config {
        /// The field.
        field: &'static str,
        /// What is wrong, with the offending value.
        message: String,
    },
    /// The slot list has more entries than the cycle has dynamic slots.
    #[error(
        "slot_list: {len} entries do not fit the cycle, whose dynamic part holds {capacity} \
         slots (cycle {cycle}, slot {slot}, sync + {statics} static slots)"
    )]
    CycleTooShort {
        /// Entries in the list.
        len: usize,
        /// Dynamic slots per cycle.
        capacity: usize,
        /// Cycle length.
        cycle: SimTime,
        /// Slot length.
        slot: SimTime,
        /// Static slots (server + clients).
        statics: usize,
    },
    /// A slot-list entry names a node that does not exist.
    #[error("slot_list[{index}].sender: unknown node {node} (nodes are 0 (server) to {max})")]
    UnknownNode {
        /// Entry index.
        index: usize,
        /// The node named.
        node: usize,
        /// Largest node number.
        max: usize,
    },
    /// A slot-list entry names a channel that does not exist.
    #[error("slot_list[{index}].channel: unknown channel {channel} (the scene has {channels})")]
    UnknownChannel {
        /// Entry index.
        index: usize,
        /// The channel named.
        channel: usize,
        /// Number of channels.
        channels: usize,
    },
    /// A frame does not fit the usable part of a slot (slot minus guard).
    #[error(
        "slot: {slot} minus the guard {guard} is shorter than the largest frame ({what}: \
         {bytes} bytes take {needed} at the link rate)"
    )]
    FrameTooLong {
        /// Which frame (`sync`, `list broadcast`, `node 2 on channel 1`).
        what: String,
        /// Its size [B].
        bytes: u64,
        /// Its transmission time.
        needed: SimTime,
        /// Slot length.
        slot: SimTime,
        /// Guard time.
        guard: SimTime,
    },
    /// A requested period is zero.
    #[error("tau[{channel}]: the requested period must be > 0")]
    ZeroPeriod {
        /// Channel index.
        channel: usize,
    },
    /// A requested period is shorter than the gap the sync and static part force on
    /// every channel (from the last dynamic slot of one cycle to the first of the next).
    #[error(
        "tau[{channel}]: requested {requested} is below {minimum}, the shortest period the \
         cycle allows (the sync and static part lie between the dynamic parts of two cycles)"
    )]
    PeriodTooShort {
        /// Channel index.
        channel: usize,
        /// Requested period.
        requested: SimTime,
        /// Shortest achievable worst gap.
        minimum: SimTime,
    },
    /// The requested periods need more slots than the dynamic part holds.
    #[error(
        "tau: the requested periods need {needed} dynamic slots per cycle, the cycle has \
         {available}"
    )]
    Infeasible {
        /// Slots needed (at least).
        needed: usize,
        /// Dynamic slots per cycle.
        available: usize,
    },
    /// The slots left free by the other channels cannot give this sender the requested
    /// period, although the total count fits.
    #[error(
        "tau[{channel}]: no placement of node {sender}'s slots in the {free} free dynamic \
         slots keeps every gap within {bound} (requested {requested})"
    )]
    Unschedulable {
        /// Channel index.
        channel: usize,
        /// Sending node.
        sender: usize,
        /// Requested period.
        requested: SimTime,
        /// The largest gap allowed (requested rounded up to whole slots).
        bound: SimTime,
        /// Free dynamic slots when the sender was placed.
        free: usize,
    },
}

impl TdmaError {
    /// A [`TdmaError::Config`] error.
    pub(crate) fn config(field: &'static str, message: impl Into<String>) -> TdmaError {
        TdmaError::Config {
            field,
            message: message.into(),
        }
    }
}
