//! Whether a scenario's TDMA network can carry it, asked by validation once the
//! scenario is complete. A frame's size follows from the messages of its routes (the
//! partition's borders, its coupling, its transmission lines and the FMU connections),
//! which the world assembles ([`super::world::channels_of`], [`TdmaLink::new`]): the
//! check lives here, above the partition and the network, and validation names the
//! scenario's fields for what it finds.

use super::world::channels_of;
use super::TdmaLink;
use crate::network::tdma::TdmaError;
use crate::partition::Layout;
use crate::scenario::model::{ControllerSpec, NetworkSpec, Problem, Scenario};

/// What of a scenario a TDMA network cannot carry.
#[derive(Debug, Clone, PartialEq)]
pub enum Misfit {
    /// The network does not build: a frame longer than its slot, an initial list that
    /// does not fit the cycle, a bad configuration. `predicts`: the partition's coupling
    /// sends force rates (and, passive, energy reports and line waves) with every
    /// message, so its frames are longer than under `reset`.
    Network {
        /// What the network reports.
        error: TdmaError,
        /// Whether the coupling predicts.
        predicts: bool,
    },
    /// `schedule[entry]`'s periods cannot be scheduled.
    Schedule {
        /// The entry's index.
        entry: usize,
        /// What the scheduler reports.
        error: TdmaError,
    },
    /// The controller may choose `taus` [s] within its bounds, and they cannot be
    /// scheduled.
    Controller {
        /// The request that fails.
        taus: Vec<f64>,
        /// What the scheduler reports.
        error: TdmaError,
    },
}

/// Checks a complete scenario's `tdma` network (nothing on an ideal one): it builds
/// with the scenario's routes, every `schedule` entry can be scheduled, and so can the
/// requests of a controller that need the most slots (so no decision within its bounds
/// is refused).
pub fn check_tdma(s: &Scenario) -> Result<(), Misfit> {
    let NetworkSpec::Tdma(_) = &s.network else {
        return Ok(());
    };
    let layout = Layout::new(s);
    let channels = channels_of(s, &layout);
    let link = TdmaLink::new(s, &channels).map_err(|error| Misfit::Network {
        error,
        predicts: s.partition.as_ref().is_some_and(|p| p.coupling.predicts()),
    })?;
    for (entry, e) in s.schedule.iter().enumerate() {
        link.schedule_secs(&e.tau)
            .map_err(|error| Misfit::Schedule { entry, error })?;
    }
    let Some(c) = &s.controller else {
        return Ok(());
    };
    for taus in extreme_requests(s, c) {
        if let Err(error) = link.schedule_secs(&taus) {
            return Err(Misfit::Controller { taus, error });
        }
    }
    Ok(())
}

/// The requests that need the most slots among a controller's choices: every channel
/// at `tau_min` for UP; for CP each channel at the smallest delay the budget leaves it
/// when the others sit at `tau_max` (the slot demand `Σ senders/τ` is largest at such
/// a vertex of the budget set).
fn extreme_requests(s: &Scenario, c: &ControllerSpec) -> Vec<Vec<f64>> {
    let n = s.channels.len();
    match c.problem {
        Problem::Unconstrained { .. } => vec![vec![c.tau_min; n]],
        Problem::Constrained { budget } => (0..n)
            .map(|i| {
                let others: f64 = (0..n)
                    .filter(|&j| j != i)
                    .map(|j| s.channels[j].k / c.tau_max)
                    .sum();
                let left = budget - others;
                let tau_i = if left > 0.0 {
                    (s.channels[i].k / left).max(c.tau_min)
                } else {
                    c.tau_max
                };
                let mut taus = vec![c.tau_max; n];
                taus[i] = tau_i.min(c.tau_max);
                taus
            })
            .collect(),
    }
}
