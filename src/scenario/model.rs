//! The validated scenario: units applied, defaults filled in, ids resolved to indices.
//!
//! Built once from a [`ScenarioFile`](super::file::ScenarioFile) by
//! [`validate`](super::validate::validate); the simulation is built from this and never
//! looks at the raw file again.

use nalgebra::{UnitQuaternion, Vector3};

pub mod tdma;

use crate::error::Place;
use crate::kernel::SimTime;
pub use tdma::{Jitter, SlotEntry, SlotList, TdmaConfig};

/// Time integrator of the `(x, v, z)` state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Integrator {
    /// Explicit (forward) Euler over the whole state: every rate at the start of the step
    /// (the thesis's integrator).
    Euler,
    /// Symplectic (semi-implicit) Euler: velocities and multipliers first, then positions
    /// and orientations with the new velocities.
    SymplecticEuler,
    /// Classical fourth-order Runge–Kutta over the whole state.
    Rk4,
}

impl Integrator {
    /// The name used in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Euler => "euler",
            Integrator::SymplecticEuler => "symplectic_euler",
            Integrator::Rk4 => "rk4",
        }
    }
}

/// Constraint stabilization method (method §2).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Stabilizer {
    /// Sliding-mode control with multipliers `z` in the ODE state.
    Smc {
        /// Sliding-surface time constant μ [s].
        mu: f64,
        /// Robustness gain K [m/s].
        k: f64,
        /// Boundary-layer width ε [m].
        epsilon: f64,
    },
    /// Baumgarte stabilization with exact multipliers:
    /// `J M⁻¹ Jᵀ z = −J̇v − J M⁻¹ F − 2αẇ − β²w`.
    Baumgarte {
        /// Damping coefficient α [1/s].
        alpha: f64,
        /// Stiffness coefficient β [1/s].
        beta: f64,
    },
}

/// How the linear system in the multipliers is solved.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Solver {
    /// Exact Cholesky factorization: dense in place for small systems, else sparse in an
    /// approximate-minimum-degree order (faer), analysed once per run.
    Cholesky,
    /// The exact path's factor reused: `A` factorized every `refactor_every` solves (on
    /// systems above the dense path's size), the solves between them by CG
    /// preconditioned with the last factor to a relative residual `tolerance`, a solve
    /// that misses it in `max_iterations` factorizing afresh.
    CholeskyPcg {
        /// Solves per factorization (≥ 1; RK4 makes 4 solves per step, the Eulers 1).
        refactor_every: usize,
        /// Relative residual `‖b − A x‖ / ‖b‖` of a preconditioned solve.
        tolerance: f64,
        /// Preconditioned iterations before a solve factorizes instead.
        max_iterations: usize,
    },
    /// Jacobi-preconditioned conjugate gradient, warm-started from the previous solution.
    ConjugateGradient {
        /// Iteration budget per solve.
        max_iterations: usize,
        /// Stop when the residual norm falls below `tolerance · |rhs|`.
        tolerance: f64,
    },
}

/// Which body model the integrator uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum BodyModel {
    /// Point masses: no orientation or angular velocity in the state. Only valid when
    /// every link anchor is at a body centre and no body starts spinning.
    PointMass,
    /// Full rigid bodies: unit quaternions and Newton–Euler rotation.
    Rigid,
}

impl BodyModel {
    /// The name used in scenario files and summary.json.
    pub fn name(self) -> &'static str {
        match self {
            BodyModel::PointMass => "point_mass",
            BodyModel::Rigid => "rigid",
        }
    }
}

/// One body, with its initial state.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodySpec {
    /// The id used in the scenario file and in trace column names (`px_B<id>`).
    pub id: u32,
    /// Mass [kg].
    pub mass: f64,
    /// Edge of the cube the body is drawn as [m].
    pub size: f64,
    /// Principal moments of inertia in the body frame [kg·m²]
    /// (cube default `m s²/6` on each axis).
    pub inertia: Vector3<f64>,
    /// Initial position of the centre of mass [m].
    pub position: Vector3<f64>,
    /// Initial linear velocity [m/s].
    pub velocity: Vector3<f64>,
    /// Initial orientation (body frame → world frame).
    pub orientation: UnitQuaternion<f64>,
    /// Initial angular velocity in the world frame [rad/s].
    pub angular_velocity: Vector3<f64>,
}

/// One constraint row: a rigid distance link (the thesis's), or one row of a joint.
///
/// A joint is several rows between the same two bodies (or a body and the world), each
/// a scalar `w` held at zero by the stabilizer like a link's: a ball joint is three
/// [`RowKind::Offset`] rows, a hinge adds two [`RowKind::Align`] rows, a weld three.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LinkSpec {
    /// Index (into [`Scenario::bodies`]) of body `a`.
    pub a: usize,
    /// Index of body `b`; equal to `a` when the row holds `a` to the world.
    pub b: usize,
    /// Link length L [m] (distance rows; 0 for joint rows).
    pub length: f64,
    /// Anchor on body `a`, in the body frame [m].
    pub anchor_a: Vector3<f64>,
    /// Anchor on body `b`, in the body frame [m]; on a world row, the fixed world point.
    pub anchor_b: Vector3<f64>,
    /// What the row holds.
    pub kind: RowKind,
    /// Whether side `b` is the world (fixed, immovable), not body `b`.
    pub world: bool,
    /// For a joint's row: the joint's index in `model.joints` and the row's index in
    /// the joint (trace columns `w_J<joint+1>_<row>`); `None` for a link.
    pub joint: Option<(u32, u32)>,
}

impl LinkSpec {
    /// The row's name in trace.csv's columns and the plots: `L<k>` for link k
    /// (`index` is the row's 0-based position), `J<j>_<r>` for row r (0-based) of joint
    /// j (1-based).
    pub fn name(&self, index: usize) -> String {
        row_name(index, self.joint)
    }
}

/// The name of constraint row `index` (0-based) that is row `joint.1` of joint
/// `joint.0` (0-based), or a link: see [`LinkSpec::name`].
pub fn row_name(index: usize, joint: Option<(u32, u32)>) -> String {
    match joint {
        Some((j, r)) => format!("J{}_{r}", j + 1),
        None => format!("L{}", index + 1),
    }
}

/// The scalar a constraint row holds at zero. With `d = P_a + R_a r_a − P_b − R_b r_b`
/// the anchors' separation:
///
/// 16 bytes: an alignment's two vectors sit behind a box, as every link of a
/// million-body grid carries a `RowKind`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub enum RowKind {
    /// `w = |d| − L` [m]: a distance link.
    #[default]
    Distance,
    /// `w = e_k · d` [m], `e_k` the k-th world axis (k = 0, 1, 2): one of a ball
    /// joint's three rows, which together make the anchors coincide.
    Offset(u8),
    /// `w = (R_a u) · (R_b v)` [1] for body-frame unit vectors `u` on `a` and `v` on `b`
    /// (on a world row `v` is a world vector): zero while they stay perpendicular. A
    /// hinge keeps its axis `u` perpendicular to two vectors normal to the axis on `b`.
    Align(Box<AlignAxes>),
    /// `w = (R_b n) · d` [m] for a unit vector `n` in `b`'s frame (on a world row a world
    /// vector): `a`'s anchor stays on the line through `b`'s anchor normal to `n`. A
    /// prismatic joint's two rows, `n` normal to its axis, keep `a` on the axis.
    Slide(Box<Vector3<f64>>),
}

/// The two body-frame vectors of a [`RowKind::Align`] row.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AlignAxes {
    /// Unit vector in `a`'s frame.
    pub u: Vector3<f64>,
    /// Unit vector in `b`'s frame (world frame on a world row).
    pub v: Vector3<f64>,
}

/// A joint type of `model.joints`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum JointType {
    /// Anchors coincide (3 rows); the bodies turn freely about the point.
    Ball,
    /// A ball joint whose bodies turn only about one common axis (5 rows).
    Hinge,
    /// A ball joint whose bodies keep their relative orientation (6 rows).
    Weld,
    /// Bodies that keep their relative orientation while `a` slides along an axis
    /// fixed in `b` (or the world): 5 rows.
    Prismatic,
}

impl JointType {
    /// Constraint rows the joint adds.
    pub fn rows(self) -> usize {
        match self {
            JointType::Ball => 3,
            JointType::Hinge => 5,
            JointType::Weld => 6,
            JointType::Prismatic => 5,
        }
    }
}

/// Where an external load acts on its body.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub enum LoadAt {
    /// A force at the centre of mass (no torque).
    #[default]
    Centre,
    /// A force at a point fixed in the body frame [m]: it adds the torque `(R r) × F`.
    Point(Vector3<f64>),
    /// A pure torque [N·m] in the world frame (the amplitude is a torque).
    Torque,
}

/// A sinusoidal external load on a body, `amplitude · sin(omega · t + phase)` for
/// `from ≤ t < until` (absolute time t): a force at the centre (the thesis's loads), a
/// force at a body-frame point, or a pure torque ([`LoadAt`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ForceSpec {
    /// Index of the driven body.
    pub body: usize,
    /// Amplitude vector [N] (a torque's [N·m]).
    pub amplitude: Vector3<f64>,
    /// Angular frequency ω [rad/s]; `0` gives the constant force `amplitude · sin(phase)`.
    pub omega: f64,
    /// Phase φ [rad].
    pub phase: f64,
    /// Switch-on time (inclusive).
    pub from: SimTime,
    /// Switch-off time (exclusive); `None` = never.
    pub until: Option<SimTime>,
    /// Optional linear amplitude envelope.
    pub ramp: Option<Ramp>,
    /// Where the load acts.
    pub applied: LoadAt,
}

/// A linear amplitude envelope: scale `a0` until `t0`, `a1` from `t1`, linear between.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Ramp {
    /// Start of the ramp.
    pub t0: SimTime,
    /// End of the ramp.
    pub t1: SimTime,
    /// Scale before and at `t0` [1].
    pub a0: f64,
    /// Scale at and after `t1` [1].
    pub a1: f64,
}

impl Ramp {
    /// The scale at `t`.
    pub fn at(&self, t: SimTime) -> f64 {
        if t <= self.t0 {
            self.a0
        } else if t >= self.t1 {
            self.a1
        } else {
            let u = (t.0 - self.t0.0) as f64 / (self.t1.0 - self.t0.0) as f64;
            self.a0 + (self.a1 - self.a0) * u
        }
    }
}

impl Ramp {
    /// The scale's rate at `t` [1/s] (zero outside `(t0, t1)`).
    pub fn rate_at(&self, t: SimTime) -> f64 {
        if t < self.t0 || t >= self.t1 {
            0.0
        } else {
            (self.a1 - self.a0) / (self.t1.0 - self.t0.0) as f64 * 1e9
        }
    }
}

impl ForceSpec {
    /// The force [N] and torque [N·m] this load puts on its body at time `t`, the body
    /// turned by `rotation` (body → world; only a load at a point reads it).
    pub fn load(&self, t: SimTime, rotation: &UnitQuaternion<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let v = self.at(t);
        match self.applied {
            LoadAt::Centre => (v, Vector3::zeros()),
            LoadAt::Point(r) => (v, (rotation * r).cross(&v)),
            LoadAt::Torque => (Vector3::zeros(), v),
        }
    }

    /// The rates of [`load`](Self::load) [N/s, N·m/s], the body spinning at `omega`
    /// [rad/s]: a point's lever arm turns, `d((R r) × F)/dt = (ω × R r) × F + R r × Ḟ`.
    pub fn load_rate(
        &self,
        t: SimTime,
        rotation: &UnitQuaternion<f64>,
        omega: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let rate = self.rate_at(t);
        match self.applied {
            LoadAt::Centre => (rate, Vector3::zeros()),
            LoadAt::Point(r) => {
                let arm = rotation * r;
                (
                    rate,
                    omega.cross(&arm).cross(&self.at(t)) + arm.cross(&rate),
                )
            }
            LoadAt::Torque => (Vector3::zeros(), rate),
        }
    }

    /// The force's time derivative [N/s] at `t` (zero where the force is off).
    pub fn rate_at(&self, t: SimTime) -> Vector3<f64> {
        let on = t >= self.from && self.until.is_none_or(|u| t < u);
        if !on {
            return Vector3::zeros();
        }
        let arg = self.omega * t.as_secs_f64() + self.phase;
        let (scale, scale_rate) = self.ramp.map_or((1.0, 0.0), |r| (r.at(t), r.rate_at(t)));
        self.amplitude * (scale * self.omega * arg.cos() + scale_rate * arg.sin())
    }

    /// The force [N] at time `t`.
    pub fn at(&self, t: SimTime) -> Vector3<f64> {
        let on = t >= self.from && self.until.is_none_or(|u| t < u);
        if on {
            let scale = self.ramp.map_or(1.0, |r| r.at(t));
            self.amplitude * (scale * (self.omega * t.as_secs_f64() + self.phase).sin())
        } else {
            Vector3::zeros()
        }
    }
}

/// What a run writes besides summary.json.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OutputSpec {
    /// Keep every `decimation`-th step in trace.csv (the first and last steps are always
    /// kept). The digest covers every step regardless.
    pub decimation: u64,
    /// Indices of the bodies whose coordinates go into trace.csv.
    pub trace_bodies: Vec<usize>,
    /// Whether trace.csv also holds each traced body's orientation quaternion and
    /// angular velocity (identity and zero on the point-mass path).
    pub trace_rotation: bool,
    /// Indices of the bodies drawn in the body-coordinate plot.
    pub plot_bodies: Vec<usize>,
    /// TDMA: network.csv keeps every frame of every n-th cycle (plus every lost frame
    /// and every cycle in which a list goes into force).
    pub network_decimation: u64,
    /// TDMA: cycles drawn in the slot-timeline plot.
    pub timeline_cycles: u64,
}

/// How a partition treats the far-end bodies of the border links it owns (method §3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum GhostMode {
    /// The node integrates its ghosts like its own bodies, driven by its own links and
    /// the owner-side force carried in the state message; every arriving state
    /// overwrites the ghost's position and velocity (default, thesis).
    Integrate,
    /// The ghost stays at the last received state (zero-order hold, zero acceleration).
    Hold,
}

/// How a node uses border data that arrives late (`partition.coupling`).
///
/// Every sample a node receives is `age = t_arrival − t_sample` old. The schemes differ
/// in what they do with that age (see `partition::coupling` for the equations).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Coupling {
    /// Each arriving state overwrites the ghost; each border force is held until the
    /// next arrival (the thesis's reading; unstable once the age reaches a few ms).
    Reset,
    /// Delay-compensated ghosts and extrapolated border forces: a sample corrects the
    /// ghost by its error against the ghost's own past at the sample's time, carried to
    /// now; forces and owner-side loads are applied as `F + Ḟ·min(age, extrapolate)`.
    Predict {
        /// Longest time a force is carried forward by its rate [ns].
        extrapolate: SimTime,
    },
    /// `predict` over an energy account per border port: each node gives its bodies
    /// only the energy the other sides of its ports have taken in (as last reported)
    /// plus its [`Tank`]; a passivity controller dissipates the rest. The coupling can
    /// then create at most the tanks, whatever the delay, jitter or loss.
    Passive {
        /// How much energy the coupling may create.
        tank: Tank,
        /// Longest time a force is carried forward by its rate [ns].
        extrapolate: SimTime,
        /// Border links whose samples can grow older than this become transmission
        /// lines (see [`Lines`]); the others keep the predictor and the tank.
        lines: Lines,
    },
    /// Every border link is a transmission line (see [`Lines`]); the rest of the
    /// coupling (ghosts, owner-side loads) is `predict`'s.
    Tlm {
        /// Longest time a force is carried forward by its rate [ns].
        extrapolate: SimTime,
        /// The lines' impedance.
        lines: Lines,
    },
}

/// How much energy the `passive` coupling may create before its brake acts.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Tank {
    /// A fixed energy per border port [J], half on each side (`"tank": J`).
    Fixed(f64),
    /// Per node, this share of the largest kinetic energy the node's own bodies have
    /// held so far, measured against the centre of mass's velocity (`"tank_share"`;
    /// the default): the coupling can never create more than a share of the energy
    /// the mechanism itself has.
    Share(f64),
}

impl Tank {
    /// A fixed tank per port [J]; zero for a share.
    pub fn per_port(self) -> f64 {
        match self {
            Tank::Fixed(tank) => tank,
            Tank::Share(_) => 0.0,
        }
    }

    /// The share of the node's largest kinetic energy; `None` for a fixed tank.
    pub fn share(self) -> Option<f64> {
        match self {
            Tank::Fixed(_) => None,
            Tank::Share(share) => Some(share),
        }
    }
}

/// Which border links a scheme turns into transmission-line (TLM) links, and their
/// impedance.
///
/// A line replaces the border link's constraint by two local dampers of impedance `Z`
/// joined by waves that travel with the border's messages: it cannot create energy
/// whatever the delay, and it is a spring of stiffness `Z / T` with a parasitic mass
/// `Z · T` for a one-way delay `T` (see `partition::line`). With `Z` independent of the
/// delay, both errors vanish as `T → 0` and the line becomes the rigid link.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Lines {
    /// A border link becomes a line when the oldest sample it can use (the largest
    /// `τ + latency` of the channels carrying its data) is older than this [ns];
    /// `SimTime::ZERO` makes every border link a line.
    pub above: SimTime,
    /// The lines' impedance `Z` [N·s/m]; `None`: per link, its ends' reduced mass times
    /// the stabilizer's bandwidth (`2/μ` under SMC, `β` under Baumgarte), the choice that
    /// balances the line's compliance and mass errors up to that bandwidth.
    pub impedance: Option<f64>,
}

impl Coupling {
    /// The name used in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            Coupling::Reset => "reset",
            Coupling::Predict { .. } => "predict",
            Coupling::Passive { .. } => "passive",
            Coupling::Tlm { .. } => "tlm",
        }
    }

    /// Whether ghosts are corrected by prediction and forces extrapolated (and so
    /// whether messages carry the rates `Ḟ` of their forces).
    pub fn predicts(self) -> bool {
        !matches!(self, Coupling::Reset)
    }

    /// How far forward a predicting scheme carries a force by its rate.
    pub fn extrapolate(self) -> SimTime {
        match self {
            Coupling::Reset => SimTime::ZERO,
            Coupling::Predict { extrapolate }
            | Coupling::Passive { extrapolate, .. }
            | Coupling::Tlm { extrapolate, .. } => extrapolate,
        }
    }

    /// The tank of the `passive` scheme.
    pub fn tank(self) -> Option<Tank> {
        match self {
            Coupling::Passive { tank, .. } => Some(tank),
            _ => None,
        }
    }

    /// Which border links become transmission lines (`passive` and `tlm`).
    pub fn lines(self) -> Option<Lines> {
        match self {
            Coupling::Passive { lines, .. } | Coupling::Tlm { lines, .. } => Some(lines),
            _ => None,
        }
    }
}

/// What a message carries (the `time` distribution routes by this).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub enum DataKind {
    /// A body's state `(x, ẋ)` (plus the owner-side force), owner → ghosting node.
    State,
    /// A border link's constraint force on a ghosted body, link owner → body owner.
    Force,
    /// An FMU output's value, for the FMU input it is connected to.
    Signal,
}

impl DataKind {
    /// The name used in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            DataKind::State => "state",
            DataKind::Force => "force",
            DataKind::Signal => "signal",
        }
    }
}

/// The split of the model over computing nodes. Node indices are 0-based here; files,
/// traces and messages name node `i` as `i + 1` (node 0 is the TDMA server).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PartitionSpec {
    /// Number of computing nodes.
    pub nodes: usize,
    /// Node of each body (by body index).
    pub node_of: Vec<usize>,
    /// Node owning each link (by link index): the node of both ends for an internal
    /// link; for a border link the scenario's override, the thesis ring rule for the
    /// 4-node quadrant layout, or else the node of the lower-numbered (file order) body.
    pub link_owner: Vec<usize>,
    /// Ghost treatment.
    pub ghosts: GhostMode,
    /// How late border data is used.
    pub coupling: Coupling,
}

/// A periodic communication channel (method §4).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChannelSpec {
    /// Name used in epochs.csv columns (`tau_<name>_requested`).
    pub name: String,
    /// Sampling period τ (the thesis's "time delay"); a whole number of `dt`.
    pub tau: SimTime,
    /// Delivery latency; `None` = equal to τ (the thesis's `x(t − τ)` reading), and
    /// follows τ when a controller changes it.
    pub latency: Option<SimTime>,
    /// Time of the first sample (ideal networks).
    pub phase: SimTime,
    /// Units per transfer k (bandwidth used is `Σ k/τ`) [1].
    pub k: f64,
    /// Borders carried (unordered node pairs, 0-based, smaller first); `None` = all.
    pub borders: Option<Vec<(usize, usize)>>,
    /// Kinds of data carried; `None` = both.
    pub kinds: Option<Vec<DataKind>>,
}

impl ChannelSpec {
    /// Whether a message of `kind` crossing the border between nodes `a` and `b` travels
    /// on this channel.
    pub fn carries(&self, kind: DataKind, a: usize, b: usize) -> bool {
        let border = (a.min(b), a.max(b));
        self.borders.as_ref().is_none_or(|bs| bs.contains(&border))
            && self.kinds.as_ref().is_none_or(|ks| ks.contains(&kind))
    }

    /// The latency in force for period `tau`.
    pub fn latency_for(&self, tau: SimTime) -> SimTime {
        self.latency.unwrap_or(tau)
    }
}

/// The network model carrying the channels.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum NetworkSpec {
    /// Ideal channels: sample every τ, deliver after the latency, nothing lost.
    Ideal,
    /// A TDMA network (method §4): the delays emerge from a slot list.
    Tdma(Box<TdmaSpec>),
}

/// A TDMA network of a scenario.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TdmaSpec {
    /// Slot geometry, link, clocks and jitter (`clients` = partition nodes).
    pub config: TdmaConfig,
    /// An explicit initial slot list; `None` = scheduled from the channels' `tau`.
    pub slot_list: Option<SlotList>,
    /// Time from a controller decision to the server's list broadcast (`T_s · m_r`).
    pub decision_lag: SimTime,
    /// Which sample a data frame carries (`network.sample`).
    pub sample: TdmaSample,
}

/// The delay-optimization problem (method §5).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Problem {
    /// CP: minimize C subject to `Σ k_i/τ_i ≤ budget`; the controller sets the first
    /// n − 1 channels and the last takes the remaining budget.
    Constrained {
        /// Bandwidth budget B [1/s].
        budget: f64,
    },
    /// UP: minimize `C + penalty · Σ k_i/τ_i` over all n delays.
    Unconstrained {
        /// Bandwidth price b [m·s].
        penalty: f64,
    },
}

impl Problem {
    /// The no-optimization delay of a constrained problem: every channel at the same
    /// delay, using the whole budget (`τ = Σ k_i / B`, before any bounds); `None` for UP,
    /// which has no budget to share.
    pub fn equal_share(&self, k: impl IntoIterator<Item = f64>) -> Option<f64> {
        match *self {
            Problem::Constrained { budget } => Some(k.into_iter().sum::<f64>() / budget),
            Problem::Unconstrained { .. } => None,
        }
    }
}

/// How the controller picks the delays the live plant runs at.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub enum Method {
    /// The Dynamic Simplex Method (method §5).
    Dsm,
    /// Every feasible grid point measured each window; the best is used ("true
    /// optimum").
    Grid,
    /// All delays equal, at the budget (CP) or at the initial value (UP).
    NoOptimization,
    /// The initial delays, never changed.
    Fixed,
    /// Static Nelder–Mead: treats the cost as fixed, converges, then stays.
    NelderMead,
}

impl Method {
    /// Name used in scenario files, summary keys (`unpaired_mean_cost_<name>`) and epochs.csv.
    pub fn name(self) -> &'static str {
        match self {
            Method::Dsm => "dsm",
            Method::Grid => "grid",
            Method::NoOptimization => "no_opt",
            Method::Fixed => "fixed",
            Method::NelderMead => "nelder_mead",
        }
    }
}

/// How a candidate's cost is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Measure {
    /// Fork the whole co-simulation at the window start and run the window under the
    /// candidate (the thesis's server-side simulation); the live plant then runs the
    /// window under the chosen delays.
    Lookahead,
    /// Run each candidate on the live plant for one window and measure it there.
    Online,
}

/// The controller (method §5). Its period T is the measurement period.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ControllerSpec {
    /// Method driving the live plant.
    pub method: Method,
    /// The problem.
    pub problem: Problem,
    /// How candidates are measured.
    pub measure: Measure,
    /// Lower bound of every delay [s].
    pub tau_min: f64,
    /// Upper bound of every delay [s].
    pub tau_max: f64,
    /// Initial controlled delays [s] (CP: the first n − 1 channels; UP: all n).
    pub initial: Vec<f64>,
    /// DSM simplex size D_s [s].
    pub dsm_size: f64,
    /// DSM reflections per iteration m_r.
    pub reflections: usize,
    /// Baselines evaluated every window from the live state (never the live method).
    pub baselines: Vec<Method>,
    /// Also evaluate DSM ± δ on each controlled delay (when the method is DSM).
    pub dsm_delta: Option<f64>,
    /// Grid-search step [s].
    pub grid_step: f64,
    /// Start of the window whose whole cost surface is plotted with the DSM path.
    pub surface_window: Option<SimTime>,
    /// Measure the landscape of the surface window (two-channel CP only).
    pub landscape: bool,
}

/// A linear spring-damper (`model.springs`): the force `−(k (d − L) + c ḋ) n` on `a`'s
/// anchor and its opposite on `b`'s (or on the world), `d` the anchors' distance and
/// `n` the unit vector from `b`'s anchor to `a`'s. A force element: no constraint row.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SpringSpec {
    /// Body `a` (index into the bodies).
    pub a: usize,
    /// Body `b`, or `None` for a fixed world point.
    pub b: Option<usize>,
    /// Anchor on `a`, body frame [m].
    pub anchor_a: Vector3<f64>,
    /// Anchor on `b`, body frame [m]; the world point [m] without `b`.
    pub anchor_b: Vector3<f64>,
    /// Stiffness k [N/m].
    pub stiffness: f64,
    /// Damping c [N·s/m].
    pub damping: f64,
    /// Rest length L [m].
    pub length: f64,
}

/// A validated scenario.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Scenario {
    /// Scenario name (copied into summary.json).
    pub name: String,
    /// Seed of every random stream of the run.
    pub seed: u64,
    /// Simulated duration.
    pub duration: SimTime,
    /// Integration step.
    pub dt: SimTime,
    /// Number of steps: `duration / dt` (exact).
    pub steps: u64,
    /// Time integrator.
    pub integrator: Integrator,
    /// Constraint stabilizer.
    pub stabilizer: Stabilizer,
    /// Multiplier solve.
    pub solver: Solver,
    /// Body model actually used (after resolving `auto`).
    pub body_model: BodyModel,
    /// Bodies, in file order (grid: row by row). Shared, not copied, by the world and
    /// the systems that use them whole (a monolithic run's node): the model is held once.
    pub bodies: std::sync::Arc<[BodySpec]>,
    /// Links, in file order (link k of the file is `links[k-1]`); shared as the bodies.
    pub links: std::sync::Arc<[LinkSpec]>,
    /// External forces and torques.
    pub forces: Vec<ForceSpec>,
    /// Uniform gravity [m/s²] acting on every movable body; `None` = none (the thesis
    /// scenes: no arithmetic is added, so their bits stay).
    pub gravity: Option<Vector3<f64>>,
    /// Spring-dampers between bodies, or a body and a world point; empty: none.
    pub springs: Vec<SpringSpec>,
    /// A run stops with a divergence error when any `|w|` exceeds this [m].
    pub max_violation: f64,
    /// Length T of a cost measurement window.
    pub measurement_period: SimTime,
    /// Output options.
    pub output: OutputSpec,
    /// The partitioning; `None` = one node holding the whole model (monolithic).
    pub partition: Option<PartitionSpec>,
    /// Network model.
    pub network: NetworkSpec,
    /// Channels (empty on a monolithic run).
    pub channels: Vec<ChannelSpec>,
    /// Delay controller; `None` = channels keep their scenario periods.
    pub controller: Option<ControllerSpec>,
    /// `schedule`: the periods the channels change to, at window boundaries, in time
    /// order; empty = none.
    pub schedule: Vec<ScheduledPeriods>,
    /// FMUs run as parts of the scene (docs/fmi.md).
    pub fmus: Vec<FmuSpec>,
    /// FMU output → FMU input connections, each on a channel.
    pub connections: Vec<ConnectionSpec>,
    /// `measurement.signals`: the FMU outputs (FMU, index into its `outputs`) whose
    /// summed RMS is a window's cost; empty = the links' `Σ RMS w`.
    pub cost_signals: Vec<(usize, usize)>,
}

impl Scenario {
    /// Whether the rows' exact multipliers are kept at each step start for their slope
    /// over the step: Baumgarte on a multi-stage integrator with rows. A predicting
    /// coupling then sends a border load's step rate (`network::StepRate`) beside its
    /// rate.
    pub fn slopes_multipliers(&self) -> bool {
        matches!(self.stabilizer, Stabilizer::Baumgarte { .. })
            && self.integrator == Integrator::Rk4
            && !self.links.is_empty()
    }

    /// Whether a ghost carries its owner's reaction stiffness (`System::set_reaction`):
    /// exact multipliers on rigid bodies, an exact solve, and a predicting coupling whose
    /// ghosts integrate. Then a body's owner sends, with its state, how its own rows
    /// answer a load on it, and the border load without the part that answers the
    /// receiver's own force (`partition::node`).
    pub fn ghosts_carry_reactions(&self) -> bool {
        matches!(self.stabilizer, Stabilizer::Baumgarte { .. })
            && self.body_model == BodyModel::Rigid
            && !matches!(self.solver, Solver::ConjugateGradient { .. })
            && self
                .partition
                .as_ref()
                .is_some_and(|p| p.coupling.predicts() && p.ghosts == GhostMode::Integrate)
    }

    /// The traced FMU outputs' names, `unit.variable` (an array's elements
    /// `unit.variable[i]`), FMU by FMU in scenario order: the trace's signal columns and
    /// every value list that follows them.
    pub fn signal_names(&self) -> Vec<String> {
        self.fmus
            .iter()
            .flat_map(|f| {
                f.outputs.iter().filter(|v| v.traced).flat_map(move |v| {
                    let names = v.element_names().into_iter();
                    names.map(move |n| format!("{}.{n}", f.name))
                })
            })
            .collect()
    }

    /// Where constraint row `l` is (0-based, in the scenario's order: links, then
    /// joints' rows), as an error names it.
    pub fn place_of_row(&self, l: usize) -> Place {
        match self.links[l].joint {
            Some((j, r)) => Place::JointRow {
                joint: j as usize + 1,
                row: r as usize,
            },
            None => Place::Link(l + 1),
        }
    }

    /// Computing nodes: the partition's (1 without one), or more where an FMU runs on
    /// a node of its own.
    pub fn node_count(&self) -> usize {
        let model = self.partition.as_ref().map_or(1, |p| p.nodes);
        self.fmus.iter().map(|f| f.node + 1).fold(model, usize::max)
    }

    /// The node (0-based) holding body `b`: its partition node, or node 0.
    pub fn node_of_body(&self, b: usize) -> usize {
        self.partition.as_ref().map_or(0, |p| p.node_of[b])
    }
}

/// `network.sample` (TDMA): which sample a data frame carries.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum TdmaSample {
    /// The sender's state at the frame's start (data as old as the transmission).
    #[default]
    Slot,
    /// The sample taken at the sender's previous frame of the channel (data one period
    /// old on arrival, plus the transmission).
    PreviousSlot,
}

/// One validated `schedule` entry: from `at` on, the channels are asked for `tau` [s].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ScheduledPeriods {
    /// A window boundary before the scenario's end.
    pub at: SimTime,
    /// The requested period per channel [s].
    pub tau: Vec<f64>,
}

/// The highest node number an FMU may run on (1-based): each node is a place in the
/// network's tables and, on TDMA, a sender in the slot list.
pub const MAX_FMU_NODE: usize = 1024;

/// A validated FMU of `fmus[]`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FmuSpec {
    /// Name (unique in the scenario).
    pub name: String,
    /// The `.fmu` file as resolved (relative to the scenario file's directory).
    pub path: std::path::PathBuf,
    /// BLAKE3 of the `.fmu` file (hex): a run refuses a file that changed since
    /// validation, and summary.json records it.
    pub hash: String,
    /// Node (0-based).
    pub node: usize,
    /// Communication step: divides `dt` or is a whole multiple of it.
    pub step: SimTime,
    /// FMI version of the model description (`"2.0"`).
    pub fmi_version: String,
    /// The co-simulation model identifier (the binary's name).
    pub model_identifier: String,
    /// The description's `guid`.
    pub guid: String,
    /// The tool that generated the FMU, if the description says.
    pub generation_tool: Option<String>,
    /// `canGetAndSetFMUstate`: forks and lookahead measurement need it.
    pub can_get_set_state: bool,
    /// `canSerializeFMUstate`: forks and checkpoints need it.
    pub can_serialize_state: bool,
    /// `canBeInstantiatedOnlyOncePerProcess`: no fork can run beside the live run.
    pub only_once_per_process: bool,
    /// Start values set before initialization.
    pub start: Vec<FmuStart>,
    /// Outputs read after every communication step: the traced ones and the connected
    /// ones, in description order.
    pub outputs: Vec<FmuVar>,
    /// Inputs fed by connections, in description order.
    pub inputs: Vec<FmuVar>,
    /// Print the FMU's log messages.
    pub logging: bool,
}

/// A variable an FMU reads or writes through the co-simulation.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FmuVar {
    /// Variable name.
    pub name: String,
    /// Value reference.
    pub vr: u32,
    /// Its FMI type.
    pub kind: crate::fmu::VarKind,
    /// Output recorded in trace.csv (outputs only).
    pub traced: bool,
    /// Value before the first delivery (inputs: the start value; outputs: unused).
    pub start: crate::fmu::Value,
    /// An FMI 3.0 array's size per dimension (outermost first); empty for a scalar.
    #[serde(default)]
    pub shape: Vec<usize>,
}

impl FmuVar {
    /// How many values it has: 1 for a scalar, an array's element count.
    pub fn len(&self) -> usize {
        if self.shape.is_empty() {
            1
        } else {
            self.shape.iter().product()
        }
    }

    /// Whether it is an array of no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The names of its values: `name` for a scalar; for an array, row-major,
    /// `name[1]` … `name[n]` (one dimension) or `name[1,1]`, `name[1,2]` … (several),
    /// 1-based as FMI 3.0 numbers elements in its descriptions.
    pub fn element_names(&self) -> Vec<String> {
        if self.shape.is_empty() {
            return vec![self.name.clone()];
        }
        let mut index = vec![0usize; self.shape.len()];
        (0..self.len())
            .map(|_| {
                let parts: Vec<String> = index.iter().map(|i| (i + 1).to_string()).collect();
                let name = format!("{}[{}]", self.name, parts.join(","));
                for (d, i) in index.iter_mut().enumerate().rev() {
                    *i += 1;
                    if *i < self.shape[d] {
                        break;
                    }
                    *i = 0;
                }
                name
            })
            .collect()
    }
}

/// A start value of `fmus[i].start`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FmuStart {
    /// Variable name.
    pub name: String,
    /// Value reference.
    pub vr: u32,
    /// Type at the FMI interface.
    pub kind: crate::fmu::VarKind,
    /// Value, in the type's form.
    pub value: crate::fmu::Value,
}

/// A validated connection: a source's value carried by a channel to a sink.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ConnectionSpec {
    /// What is sampled.
    pub from: SignalSource,
    /// What the delivered value sets.
    pub to: SignalSink,
    /// Channel carrying it.
    pub channel: usize,
}

/// The sampled end of a connection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum SignalSource {
    /// Output `output` (index into the FMU's `outputs`) of FMU `fmu`.
    Fmu {
        /// FMU index.
        fmu: usize,
        /// Index into its `outputs`.
        output: usize,
    },
    /// A coordinate of a body's state, `B<id>.px` … `B<id>.vz`: position [m] for
    /// `quantity` 0–2 (x, y, z), velocity [m/s] for 3–5.
    Body {
        /// Body index.
        body: usize,
        /// 0–2: position x, y, z; 3–5: velocity x, y, z.
        quantity: usize,
    },
}

/// The set end of a connection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum SignalSink {
    /// Input `input` (index into the FMU's `inputs`) of FMU `fmu`.
    Fmu {
        /// FMU index.
        fmu: usize,
        /// Index into its `inputs`.
        input: usize,
    },
    /// A component of a force [N] on a body's centre, `B<id>.fx` … `B<id>.fz`, held
    /// from each delivery until the next.
    BodyForce {
        /// Body index.
        body: usize,
        /// 0, 1, 2: x, y, z.
        axis: usize,
    },
}

impl ConnectionSpec {
    /// Node (0-based) whose values the source samples.
    pub fn from_node(&self, s: &Scenario) -> usize {
        match self.from {
            SignalSource::Fmu { fmu, .. } => s.fmus[fmu].node,
            SignalSource::Body { body, .. } => s.node_of_body(body),
        }
    }

    /// Node (0-based) that receives the value.
    pub fn to_node(&self, s: &Scenario) -> usize {
        match self.to {
            SignalSink::Fmu { fmu, .. } => s.fmus[fmu].node,
            SignalSink::BodyForce { body, .. } => s.node_of_body(body),
        }
    }
}
