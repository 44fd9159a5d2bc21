//! What the controller needs of the simulation it steers, as a trait the
//! co-simulation implements: the controller measures candidates on clones of the plant
//! and drives the live one, without knowing what a plant is made of (as rapier's
//! pipeline takes hooks, or a nexosim model a context). So `control/` depends on
//! nothing above it, and the co-simulation (`cosim/`) implements [`Plant`] for its
//! world.

use super::experiment::WindowReport;
use crate::error::Result;
use crate::kernel::SimTime;
use crate::scenario::Scenario;

/// Receives the controller's columns of each window the live plant ran.
pub trait WindowSink {
    /// Called when a controller has run a window on the live plant (after the plant
    /// closed the window). Forks report nothing.
    fn on_window(&mut self, report: &WindowReport);
}

/// A plant the controller can fork, steer and measure.
pub trait Plant: Clone + Sync {
    /// What watches the live plant as it advances (the trace recorder); it also takes
    /// the controller's window reports.
    type Observer: WindowSink + ?Sized;

    /// The scenario the plant runs.
    fn scenario(&self) -> &Scenario;

    /// Advances the plant to `t`, reporting to `obs`.
    fn advance_to(&mut self, t: SimTime, obs: &mut Self::Observer) -> Result<()>;

    /// Advances a fork to `t`, reporting nothing.
    fn advance_unobserved(&mut self, t: SimTime) -> Result<()>;

    /// Sets the channels' periods from `at` on: `requested` [s] as asked, `achieved`
    /// what an ideal channel runs at; returns the periods the decision achieves, or why
    /// the network cannot serve them.
    fn set_taus(
        &mut self,
        at: SimTime,
        requested: &[f64],
        achieved: &[SimTime],
    ) -> std::result::Result<Vec<SimTime>, String>;

    /// The last closed measurement window: its end and its cost [m].
    fn last_window(&self) -> Option<(SimTime, f64)>;

    /// Whether the plant has run to its end: the scenario's duration, or earlier where
    /// a part of it (an FMU) asked to stop. No window starts after it.
    fn finished(&self) -> bool;
}
