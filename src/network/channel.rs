//! Ideal periodic channels (method §4): a channel samples its routes every τ (at the
//! first step at or after each multiple of τ, so any τ ≥ dt runs at its exact average
//! rate) and delivers each sample after its latency; the receiver holds a value until
//! the next arrival.

use super::route::Route;
use crate::kernel::SimTime;
use crate::scenario::model::ChannelSpec;

/// A channel's configuration and the routes it carries.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Channel {
    /// The scenario's description.
    pub spec: ChannelSpec,
    /// The period in force, to the nanosecond: on ideal channels the requested one
    /// (on TDMA what the slot list achieves).
    pub tau: SimTime,
    /// The period last requested [s] (a controller may ask for any real value; an ideal
    /// channel runs it to the nanosecond).
    pub requested: f64,
    /// Routes carried, in layout order.
    pub routes: Vec<Route>,
    /// When the period in force began (the channel's phase at the start; a period
    /// change's time after one).
    pub since: SimTime,
    /// Samples taken since `since`.
    pub taken: u64,
}

/// The period an ideal channel runs a requested delay `tau` [s] at: the request to the
/// nanosecond, at least one step `dt`. The channel samples at the first step at or
/// after each multiple of it, so its average rate is the requested one.
pub fn achieved_period(tau: f64, dt: SimTime) -> SimTime {
    SimTime(((tau * 1e9).round() as u64).max(dt.as_nanos()))
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
            since: spec.phase,
            taken: 0,
        }
    }

    /// When an ideal channel samples next: at the first step at or after
    /// `since + k·τ`, `k = taken`, so that however `τ` falls between steps the
    /// channel samples `1/τ` times per second on average (a period of whole steps
    /// samples exactly every `τ`).
    pub fn next_sample(&self, dt: SimTime) -> SimTime {
        // Samples 0 … taken − 1 are behind: the next is sample `taken`.
        let offset = self.tau.0.saturating_mul(self.taken);
        SimTime(
            self.since
                .0
                .saturating_add(offset.div_ceil(dt.0).saturating_mul(dt.0)),
        )
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
