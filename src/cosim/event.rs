//! The events of a co-simulation.

use crate::network::Message;

/// What happens at an event.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Event {
    /// All nodes step from the event's time (class `PartitionStep`).
    Step,
    /// Channel `channel` samples its routes (class `Sample`).
    Sample {
        /// Channel index.
        channel: usize,
    },
    /// A message reaches its receiver (class `Delivery`).
    Deliver(Box<Message>),
    /// The measurement window ending at the event's time closes (class `Measurement`).
    WindowEnd,
}
