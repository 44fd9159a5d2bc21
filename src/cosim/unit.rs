//! The one interface the world steps its units through: a multibody partition (one per
//! node, [`crate::partition::Node`]) and an FMU ([`super::fmus::FmuUnit`]) both implement
//! [`Unit`], the way [`crate::control::Plant`] is all the controller knows of the world.
//!
//! A unit samples what it sends on a route, takes what is delivered to it, and steps
//! in two halves around the observers' look at each step. The kernel, the channels and
//! the TDMA network see only routes and messages, never what a unit computes; the world
//! finds a route's source and a message's receiver and hands them over. A unit's state
//! is saved and restored as the world's is: `Clone` is a fork, serde a checkpoint (an
//! FMU carries its instance's serialized FMU state in both).

use crate::error::Result;
use crate::kernel::SimTime;
use crate::network::route::Route;
use crate::network::Message;
use crate::scenario::model::Scenario;

/// A unit of the co-simulation world.
pub trait Unit: Send + Sync {
    /// The message this unit, the source of `route`, sends on it over `channel`,
    /// sampled at `t` ([`Message::on`]); `None` when it has nothing to send on it then.
    /// Built by the unit whole, where it is returned: a state message is a few hundred
    /// bytes, and every copy of it on the way to the event queue costs (callgrind).
    fn sample(
        &mut self,
        t: SimTime,
        channel: usize,
        route: &Route,
        scenario: &Scenario,
    ) -> Option<Message>;

    /// `msg`, for this unit, was just sampled: the unit keeps what it will compare the
    /// sample with when it arrives (a partition: its ghost's or port's state of the
    /// sample time). Nothing by default.
    fn sampled(&mut self, _msg: &Message) {}

    /// `msg` reaches this unit; `state_time` is the time of the state the units hold
    /// (the next step's).
    fn deliver(&mut self, msg: &Message, state_time: SimTime, scenario: &Scenario);

    /// The first half of the lock-step at `t` for every unit of this kind, in order,
    /// the first error stopping them: what they evaluate at `t` before the observers
    /// see step `t`. Nothing by default (an FMU computes from one communication point
    /// to the next, in the second half). A kind may do it together (a partition: its
    /// dense solves batched, on rayon's threads when `parallel`) if the bits and the
    /// first error are those of a serial loop in unit order.
    fn begin_steps(
        _units: &mut [Self],
        _t: SimTime,
        _scenario: &Scenario,
        _parallel: bool,
    ) -> Result<()>
    where
        Self: Sized,
    {
        Ok(())
    }

    /// The second half, from `t` to `t + dt`, for every unit of this kind, under the
    /// same rule.
    fn finish_steps(
        units: &mut [Self],
        t: SimTime,
        dt: SimTime,
        scenario: &Scenario,
        parallel: bool,
    ) -> Result<()>
    where
        Self: Sized;
}
