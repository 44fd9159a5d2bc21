//! The events of a co-simulation.

use crate::network::Message;

/// What happens at a queued event. The lock-step itself (class `PartitionStep`) is not
/// queued: `CoSim` keeps the one pending step beside the queue and runs it exactly
/// where the kernel would pop it (see `CoSim::next_step`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Event {
    /// Channel `channel` samples its routes (class `Sample`).
    Sample {
        /// Channel index.
        channel: usize,
    },
    /// A message reaches its receiver (class `Delivery`).
    Deliver(Box<Message>),
    /// The measurement window ending at the event's time closes (class `Measurement`).
    WindowEnd,
    /// A TDMA cycle starts: the protocol computes it (class `ClockSync`).
    Cycle,
    /// A TDMA data frame starts: `sender` (TDMA node) samples its data of `channel`,
    /// delivered at `delivery`, or lost (`None`; such frames are scheduled only under
    /// `network.sample: "previous_slot"`, where the sender still takes its sample)
    /// (class `Slot`).
    Frame {
        /// Channel index.
        channel: usize,
        /// Sending TDMA node (partition node + 1).
        sender: usize,
        /// When every receiver has it (`None`: the frame collided).
        delivery: Option<crate::kernel::SimTime>,
    },
    /// A controller's decision reaches the TDMA server after its computing lag
    /// (class `Controller`): the list scheduled for these periods [s] is broadcast.
    Decide {
        /// Requested period per channel [s].
        requested: Vec<f64>,
    },
}
