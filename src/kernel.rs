//! The event kernel: integer simulated time (and, as it grows, the event queue).

pub mod time;

pub use time::SimTime;
