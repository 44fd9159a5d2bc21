//! Ideal periodic channels (method §4): a channel samples its routes every τ and
//! delivers each sample after its latency; the receiver holds a value until the next
//! arrival.

use crate::kernel::SimTime;
use crate::partition::layout::Route;
use crate::scenario::model::ChannelSpec;

/// A channel's configuration and the routes it carries.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Channel {
    /// The scenario's description.
    pub spec: ChannelSpec,
    /// The period in force (achieved: a whole number of `dt`).
    pub tau: SimTime,
    /// The period last requested [s] (a controller may ask for any real value; the
    /// channel runs at the next whole number of steps, `tau`).
    pub requested: f64,
    /// Routes carried, in layout order.
    pub routes: Vec<Route>,
}

impl Channel {
    /// A channel at its scenario period, carrying the routes it matches.
    pub fn new(spec: &ChannelSpec, all_routes: &[Route]) -> Channel {
        Channel {
            tau: spec.tau,
            requested: spec.tau.as_secs_f64(),
            routes: all_routes
                .iter()
                .filter(|r| spec.carries(r.kind, r.from, r.to))
                .copied()
                .collect(),
            spec: spec.clone(),
        }
    }

    /// Latency in force.
    pub fn latency(&self) -> SimTime {
        self.spec.latency_for(self.tau)
    }

    /// Bandwidth used [units/s]: `k / τ`.
    pub fn bandwidth(&self) -> f64 {
        self.spec.k / self.tau.as_secs_f64()
    }
}
