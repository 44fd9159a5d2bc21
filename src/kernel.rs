//! The event kernel: integer simulated time and the event queue.
//!
//! Events leave the queue in `(time, class, seq)` order; the class order at equal time
//! is a documented guarantee (see [`queue`]).

pub mod queue;
pub mod time;

pub use queue::{EventClass, EventKey, Kernel, KernelError, SlotHasher};
pub use time::SimTime;
