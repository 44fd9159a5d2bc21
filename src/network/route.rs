//! What a message is about: the route a partitioning assigns it (the partitioning
//! builds them), defined here, below the partitioning, so that channels
//! and TDMA frames name their routes without importing the layer that builds them.

use crate::scenario::model::DataKind;

/// A message route: a kind of data about one body (or link) from one node to another.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub struct Route {
    /// What is sent.
    pub kind: DataKind,
    /// Sending node (0-based).
    pub from: usize,
    /// Receiving node (0-based).
    pub to: usize,
    /// The body concerned (global index): the ghosted body for both kinds.
    pub body: usize,
    /// For [`DataKind::Force`], the border link (global index) whose force is sent.
    pub link: Option<usize>,
}
