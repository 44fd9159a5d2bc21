//! The split of a model over computing nodes (method §3).
//!
//! - [`layout`]: who owns which body and link, which bodies each node ghosts, and the
//!   message routes between nodes;
//! - [`node`]: one node's own [`System`](crate::multibody::System) over its bodies, its
//!   ghosts and its links, and how it builds and applies messages;
//! - [`coupling`]: what a node does with border data that arrives late (`reset`,
//!   `predict`, `passive`): ghost histories and corrections, extrapolated forces, the
//!   energy accounts of the border ports;
//! - [`momentum`]: the momentum a predicting coupling makes or its brake takes,
//!   measured and given back to the net as a whole.
//!
//! A monolithic run is the one-node layout: the node's system is the whole model, it
//! has no ghosts and sends nothing.

pub mod com;
pub mod coupling;
pub mod layout;
pub mod line;
pub mod momentum;
pub mod node;

pub use layout::Layout;
pub use node::Node;
