//! What a run records: the bit-exact digest ([`digest`]) and the decimated CSV trace
//! with the series kept for plots ([`recorder`]).

pub mod digest;
pub mod recorder;

pub use digest::Digest;
pub use recorder::Recorder;
