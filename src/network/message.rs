//! Messages between nodes.

use nalgebra::{Quaternion, Vector3};

use crate::kernel::SimTime;
use crate::scenario::model::{Coupling, DataKind};

/// The data a message carries.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Payload {
    /// A body's state for the nodes that ghost it, with the owner-side load on it (the
    /// external force and every link force the receiver does not compute itself).
    State {
        /// Global body index.
        body: usize,
        /// Position [m].
        p: Vector3<f64>,
        /// Velocity [m/s].
        v: Vector3<f64>,
        /// Orientation (identity on the point-mass path).
        q: Quaternion<f64>,
        /// Angular velocity [rad/s] (zero on the point-mass path).
        omega: Vector3<f64>,
        /// Owner-side force [N].
        force: Vector3<f64>,
        /// Owner-side torque [N·m].
        torque: Vector3<f64>,
        /// Rate of the owner-side force [N/s] (zero under the `reset` coupling, which
        /// does not send it).
        force_rate: Vector3<f64>,
        /// Rate of the owner-side torque [N·m/s] (zero where not sent).
        torque_rate: Vector3<f64>,
        /// The part of the load's rate measured over the sender's last step alone.
        #[serde(default)]
        step_rate: StepRate,
        /// How the sender's rows answer a load on the body, `K = J_bᵀ A⁺ J_b` in the
        /// body's frame, where they hold it and the scene sends it
        /// (`Scenario::ghosts_carry_reactions`); `force` and `torque` then leave out
        /// their answer to the receiver's own border force.
        #[serde(default)]
        reaction: Option<Box<nalgebra::Matrix6<f64>>>,
        /// `passive`: the energy the body has put into its port with the receiver so far
        /// [J] (zero under the other schemes, which do not send it).
        energy: f64,
        /// The waves of the transmission lines from this body to the receiver's bodies
        /// (empty without lines).
        lines: Vec<LineSample>,
    },
    /// A transmission line's wave from the link owner's end (sent on the link's force
    /// route instead of a force).
    Line(LineSample),
    /// An FMU output's value for the input it is connected to.
    Signal {
        /// Connection index (`Scenario::connections`).
        connection: usize,
        /// The output's value at the sample time, as [`crate::fmu::Value::to_carrier`]
        /// makes it: a number as itself, an Int64 or UInt64 as its 64 bits
        /// reinterpreted (never computed with on the way).
        value: f64,
    },
    /// A border link's load on a ghosted body, for the body's owner.
    Force {
        /// Global link index.
        link: usize,
        /// Global body index.
        body: usize,
        /// Force [N].
        force: Vector3<f64>,
        /// Torque [N·m].
        torque: Vector3<f64>,
        /// Rate of the force [N/s] (zero under the `reset` coupling, which does not
        /// send it).
        force_rate: Vector3<f64>,
        /// Rate of the torque [N·m/s] (zero where not sent).
        torque_rate: Vector3<f64>,
        /// The part of the load's rate measured over the sender's last step alone.
        #[serde(default)]
        step_rate: StepRate,
        /// `passive`: the energy the sender's bodies have put into the port of this
        /// body so far [J] (zero where not sent).
        energy: f64,
        /// A predicting coupling: the impulse the sender's links have put on its ghost
        /// of the body so far [N·s] (zero where not sent).
        #[serde(default)]
        impulse: Vector3<f64>,
    },
}

/// The part of a load's rate that its sender measured over its last step alone: the
/// slope of an exact (Baumgarte) multiplier from the step's first stage to its last, on
/// a row whose direction does not turn it (a joint's offset and slide rows, a distance
/// link). The receiver carries the load by it for one step at most, then holds it.
///
/// Why apart from the rate: over the step after the sample it is what keeps a
/// partitioned RK4 run second order (held over the stages, the force made it first
/// order). Carried over a whole sample period it is a one-step slope extrapolated
/// across many steps, and it closes the loop a border joint has with the load behind
/// its ghost (docs/method.md §2.1): a chain at rest split at a joint diverged at 4 ms.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepRate {
    /// Force rate [N/s].
    pub force: Vector3<f64>,
    /// Torque rate [N·m/s].
    pub torque: Vector3<f64>,
}

impl Payload {
    /// The kind of data.
    pub fn kind(&self) -> DataKind {
        match self {
            Payload::State { .. } => DataKind::State,
            Payload::Force { .. } | Payload::Line(_) => DataKind::Force,
            Payload::Signal { .. } => DataKind::Signal,
        }
    }

    /// Number of `f64` values on the wire (rotation only where the scene has it, the
    /// force rates only where the coupling sends them).
    pub fn floats(
        &self,
        rigid: bool,
        coupling: Coupling,
        extras: crate::network::tdma::frame::WireExtras,
    ) -> usize {
        let lines = match self {
            Payload::State { lines, .. } => lines.len(),
            Payload::Force { .. } | Payload::Signal { .. } => 0,
            Payload::Line(_) => 1,
        };
        crate::network::tdma::frame::floats_per_route(self.kind(), rigid, coupling, extras, lines)
    }
}

/// One end's sample of a transmission line (see `partition::line`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LineSample {
    /// Global link index.
    pub link: usize,
    /// Mean outgoing wave over the window [N].
    pub wave: f64,
    /// Window length (the receiver holds the wave this long).
    pub span: SimTime,
    /// The sending end's anchor position [m].
    pub p: Vector3<f64>,
    /// The sending end's anchor velocity [m/s].
    pub v: Vector3<f64>,
    /// The owner end's: the impulse the line has applied to its body so far [N·s]
    /// (`partition::momentum`; zero from the other end).
    #[serde(default)]
    pub impulse: Vector3<f64>,
}

/// A message in flight.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Message {
    /// Sending node (0-based).
    pub from: usize,
    /// Receiving node (0-based).
    pub to: usize,
    /// Channel index.
    pub channel: usize,
    /// Sample time (the values are those at this time).
    pub sent: SimTime,
    /// The data.
    pub payload: Payload,
    /// A predicting coupling: the momentum the sender's coupling has made [N·s]
    /// (`partition::momentum`).
    #[serde(default)]
    pub momentum: Option<Vector3<f64>>,
}

impl Message {
    /// The message of `route` on `channel`, sampled at `sent`.
    #[inline]
    pub fn on(
        route: &crate::network::route::Route,
        channel: usize,
        sent: SimTime,
        payload: Payload,
        momentum: Option<Vector3<f64>>,
    ) -> Message {
        Message {
            from: route.from,
            to: route.to,
            channel,
            sent,
            payload,
            momentum,
        }
    }
}
