//! What travels between nodes: messages ([`message`]) on periodic channels
//! ([`channel`]).

pub mod channel;
pub mod message;
pub mod route;
pub mod tdma;

pub use channel::Channel;
pub use message::{LineSample, Message, Payload, StepRate};
pub use route::Route;
