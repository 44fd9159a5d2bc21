//! The scenario file as written: plain serde structs that mirror the JSON one to one.
//!
//! Nothing here checks values; [`validate`](super::validate::validate) does that once
//! and produces a [`Scenario`](super::model::Scenario). The structs only fix the shape:
//!
//! - every struct denies unknown keys, so a misspelt key is an error, never ignored;
//! - a key with a default may be left out, but a JSON `null` is never read as "use the
//!   default": `"until": null` is a type error like `"mass": null`;
//! - defaults that do not depend on other keys are filled in here (so a parsed file
//!   serializes back with them written out); defaults that do (a link's length, the
//!   measurement period, the traced bodies) stay `None` until validation.
//!
//! Units are SI throughout: seconds, metres, kilograms, newtons, radians.
//!
//! One serde quirk is left alone: a struct may also be written as an array of its values
//! in field order (`"grid": [4, 4, 1.8, 1.0, 0.2]`). Such a file is unambiguous and
//! validates like the object form; refusing it would need a hand-written deserializer.
//!
//! The `Serialize` impls write a file that parses back to an equal `ScenarioFile`.

use serde::{Deserialize, Deserializer, Serialize};

/// Default SMC sliding-surface time constant μ [s] (thesis).
pub const DEFAULT_SMC_MU: f64 = 0.05;
/// Default SMC robustness gain K [m/s] (thesis).
pub const DEFAULT_SMC_K: f64 = 10.0;
/// Default SMC boundary-layer width ε [m] (thesis).
pub const DEFAULT_SMC_EPSILON: f64 = 0.1;
/// Baumgarte's α and β [1/s] when a scene with joints gives no `stabilizer`, or gives
/// `"baumgarte"` without them: a constraint error decays critically damped with a
/// 50 ms time constant. Slow next to any step a mechanism runs at (RK4 holds the
/// error equation's double pole −β for `β dt < 2.78`, dt < 0.14 s), so the law stays
/// far from the integrator's limit and from a border's delays (a few ms), while the
/// exact multipliers keep the joints closed to the integrator's truncation error
/// (the drift they correct) rather than to a law's lag.
pub const DEFAULT_BAUMGARTE_RATE: f64 = 20.0;
/// Default CG iteration budget per solve (see [`SolverFile::max_iterations`]).
pub const DEFAULT_CG_MAX_ITERATIONS: usize = 50;
/// Default CG relative residual tolerance [1] (see [`SolverFile::tolerance`]).
pub const DEFAULT_CG_TOLERANCE: f64 = 1e-10;
/// Default solves per factorization of `"cholesky_pcg"` (see
/// [`SolverFile::refactor_every`]): five RK4 steps, twenty Euler steps.
pub const DEFAULT_PCG_REFACTOR_EVERY: usize = 20;
/// Default relative residual of a `"cholesky_pcg"` solve (see
/// [`SolverFile::tolerance`]).
pub const DEFAULT_PCG_TOLERANCE: f64 = 1e-8;
/// Default preconditioned iterations of `"cholesky_pcg"` before a solve factorizes.
pub const DEFAULT_PCG_MAX_ITERATIONS: usize = 10;
/// Default divergence bound [m] (see [`DivergenceFile::max_violation`]).
pub const DEFAULT_MAX_VIOLATION: f64 = 1.0;
/// Default measurement period [s] before rounding and capping
/// (see [`MeasurementFile::period`]).
pub const DEFAULT_MEASUREMENT_PERIOD: f64 = 1.0;
/// Default trace decimation [steps] (see [`OutputFile::decimation`]).
pub const DEFAULT_DECIMATION: u64 = 10;

/// Reads a present key into `Some`; used with `#[serde(default)]` so that an absent key
/// is `None` but an explicit `null` is a type error (serde's plain `Option` would read
/// `null` as `None`).
fn present<'de, D, T>(deserializer: D) -> Result<Option<T>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    T::deserialize(deserializer).map(Some)
}

/// Identity quaternion `[w, x, y, z]`.
fn identity_quaternion() -> [f64; 4] {
    [1.0, 0.0, 0.0, 0.0]
}

/// Longest `description` a scenario may carry [characters].
pub const MAX_DESCRIPTION_CHARS: usize = 4096;

/// A whole scenario file (method §7 plus our own optional sections).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// The JSON Schema this file follows (`"$schema": "../docs/schema/scenario.schema.json"`),
    /// for editors' completion and checks; optional, ignored by the tool.
    #[serde(rename = "$schema", default, skip_serializing_if = "Option::is_none")]
    pub schema: Option<String>,
    /// Scenario name, copied into summary.json; required, non-empty.
    pub name: String,
    /// What the scenario is for, in words (what its τ and latency mean, where it comes
    /// from); optional, at most [`MAX_DESCRIPTION_CHARS`] characters, read by people
    /// only: nothing of it reaches a run.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub description: Option<String>,
    /// Seed of every random stream of the run; required (no hidden default seed).
    pub seed: u64,
    /// Simulated duration [s]; required, a whole number of `dt` steps.
    pub duration: f64,
    /// Integration step [s]; required, at least 1 ns and a whole number of nanoseconds.
    pub dt: f64,
    /// Time integrator; default `"euler"` (the thesis's integrator).
    #[serde(default)]
    pub integrator: IntegratorFile,
    /// Constraint stabilizer; default by the model: the thesis's SMC on a scene of
    /// distance links only, Baumgarte's exact multipliers (α = β =
    /// [`DEFAULT_BAUMGARTE_RATE`]) on a scene with joints, where the SMC law does work
    /// (docs/method.md §2.1).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub stabilizer: Option<StabilizerFile>,
    /// Multiplier solve; default exact Cholesky.
    #[serde(default)]
    pub solver: SolverFile,
    /// Body model; default `"auto"` (point masses when nothing can rotate).
    #[serde(default)]
    pub body_model: BodyModelFile,
    /// The bodies and links: a generated grid or an explicit list; required, except in
    /// a scene of `fmus` only.
    #[serde(default)]
    pub model: ModelFile,
    /// External forces; default none.
    #[serde(default)]
    pub forces: Vec<ForceFile>,
    /// External torques: entries of the same form as `forces`, the amplitude a torque
    /// [N·m] in the world frame about the body's centre (`point` is refused); default
    /// none. Needs rigid bodies.
    #[serde(default)]
    pub torques: Vec<ForceFile>,
    /// Divergence bound; default `max_violation` 1 m.
    #[serde(default)]
    pub divergence: DivergenceFile,
    /// Cost measurement window; default period 1 s.
    #[serde(default)]
    pub measurement: MeasurementFile,
    /// What goes into trace.csv and the plots; defaults in [`OutputFile`].
    #[serde(default)]
    pub output: OutputFile,
    /// The split of the model over computing nodes; default none (a monolithic run, one
    /// node holding the whole model).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub partition: Option<PartitionFile>,
    /// The network model carrying the channels; default `{"kind": "ideal"}`.
    #[serde(default)]
    pub network: NetworkFile,
    /// The communication channels between nodes; default none. Needs `partition`; with
    /// a partition that has border links, every message must travel on exactly one
    /// channel (an empty list counts as none).
    #[serde(default)]
    pub channels: Vec<ChannelFile>,
    /// The delay controller; default none (channels keep their periods).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub controller: Option<ControllerFile>,
    /// A fixed schedule of channel periods, changed at window boundaries (what a
    /// controller would decide, written down: a Python-steered run's decisions replay
    /// here); default none. Not with a `controller`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub schedule: Vec<ScheduleEntryFile>,
    /// FMI 2.0 co-simulation FMUs run as parts of the scene, each on a node; default none.
    #[serde(default)]
    pub fmus: Vec<FmuFile>,
    /// Connections from an FMU's output to an FMU's input, each carried by a channel;
    /// default none.
    #[serde(default)]
    pub connections: Vec<ConnectionFile>,
    /// The directory relative FMU paths are read from: the scenario file's directory
    /// when it was loaded from a file, else the working directory. Not part of the file.
    #[serde(skip)]
    #[schemars(skip)]
    pub base_dir: Option<std::path::PathBuf>,
}

/// `fmus[i]`: an FMI 2.0 co-simulation FMU (docs/fmi.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FmuFile {
    /// Name, unique, of letters, digits and `_`: connections say `<name>.<variable>`
    /// and trace.csv's columns `<name>.<variable>`; required.
    pub name: String,
    /// The `.fmu` file, relative to the scenario file's directory; required.
    pub path: String,
    /// Node the FMU runs on (1-based); default 1. Nodes beyond the partition's (or
    /// beyond node 1 without a partition) hold FMUs only.
    #[serde(default = "default_fmu_node")]
    pub node: usize,
    /// Communication step [s]: a whole number of nanoseconds that divides `dt` or is a
    /// whole multiple of it, and divides the duration; default `dt`.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub step: Option<f64>,
    /// Start values of parameters and inputs, by variable name, of any type: a number
    /// for Real/Float64, Float32 and the integer types (an Int64 or a UInt64 as a whole
    /// JSON number, read without loss), `true`/`false` or 0/1 for a Boolean, a string for
    /// a String, a string of hex digits for a Binary; default none (the FMU's own
    /// starts).
    #[serde(default)]
    pub start: std::collections::BTreeMap<String, StartValue>,
    /// Outputs of any type recorded in trace.csv (and the digest), an array by its name
    /// (columns `<variable>[1]` …); default every output.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub trace: Option<Vec<String>>,
    /// Print every log message of the FMU on stderr; off, those of status warning and worse
    /// are still printed (and kept in summary.json); default `false`.
    #[serde(default)]
    pub logging: bool,
}

/// A value of `fmus[i].start`: a JSON number (kept as written, so a 64-bit integer is
/// exact), a Boolean or a string.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum StartValue {
    /// `true` or `false`.
    Bool(bool),
    /// A number.
    Number(serde_json::Number),
    /// A string (a String's text, a Binary's hex bytes).
    Text(String),
}

fn default_fmu_node() -> usize {
    1
}

/// `connections[i]`: an FMU output carried to an FMU input by a channel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConnectionFile {
    /// Source, `<fmu>.<variable>`: a scalar output that is a number or a Boolean (or a
    /// body's `B<id>.px` … `B<id>.vz`); required.
    pub from: String,
    /// Target, `<fmu>.<variable>`: an input of the source's type fed by no other
    /// connection (or a body's `B<id>.fx` … `B<id>.fz`); required.
    pub to: String,
    /// Name of the channel that samples the source every τ and delivers each sample
    /// after its latency; required.
    pub channel: String,
}

/// `integrator`: the time integrator of the `(x, v, z)` state.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum IntegratorFile {
    /// `"euler"`: explicit Euler; the default because the thesis uses it.
    #[default]
    Euler,
    /// `"symplectic_euler"`: semi-implicit Euler.
    SymplecticEuler,
    /// `"rk4"`: classical fourth-order Runge–Kutta.
    Rk4,
}

/// `stabilizer.kind`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum StabilizerKind {
    /// `"smc"`: sliding-mode control (the thesis's method; the default).
    #[default]
    Smc,
    /// `"baumgarte"`: Baumgarte stabilization with exact multipliers (the comparison).
    Baumgarte,
}

/// `stabilizer`: `{"kind": "smc", "mu", "k", "epsilon"}` or
/// `{"kind": "baumgarte", "alpha", "beta"}`.
///
/// Kept flat (rather than a serde-tagged enum) so that a bad value is reported with its
/// full path (`stabilizer.mu`); validation rejects keys that belong to the other kind.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StabilizerFile {
    /// Which stabilizer; required inside the section.
    pub kind: StabilizerKind,
    /// SMC sliding-surface time constant μ [s]; default 0.05 s (thesis).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub mu: Option<f64>,
    /// SMC robustness gain K [m/s]; default 10 (thesis).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub k: Option<f64>,
    /// SMC boundary-layer width ε [m]; default 0.1 m (thesis).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub epsilon: Option<f64>,
    /// Baumgarte damping α [1/s], ≥ 0; default [`DEFAULT_BAUMGARTE_RATE`].
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub alpha: Option<f64>,
    /// Baumgarte stiffness β [1/s], ≥ 0; default [`DEFAULT_BAUMGARTE_RATE`].
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub beta: Option<f64>,
}

/// `solver.kind`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum SolverKind {
    /// `"cholesky"`: exact Cholesky (the default: no solver error to account for),
    /// sparse in an approximate-minimum-degree order above a few dozen links.
    #[default]
    Cholesky,
    /// `"cholesky_amd"`: the same as `"cholesky"`, which now always orders for fill; kept
    /// so that files written when the ordering was opt-in still read.
    CholeskyAmd,
    /// `"cholesky_pcg"`: the exact path's factor reused for `refactor_every` solves,
    /// the solves between factorizations by CG preconditioned with it, to `tolerance`.
    CholeskyPcg,
    /// `"cg"`: Jacobi-preconditioned conjugate gradient with a fixed budget.
    Cg,
}

/// `solver`: `{"kind": "cholesky"}`, `{"kind": "cholesky_pcg", "refactor_every",
/// "max_iterations", "tolerance"}` or `{"kind": "cg", "max_iterations", "tolerance"}`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolverFile {
    /// Which solver; required inside the section.
    pub kind: SolverKind,
    /// Solves per factorization of `"cholesky_pcg"`, ≥ 1 (1: every solve factorizes, as
    /// `"cholesky"`); default 20 (five RK4 steps).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub refactor_every: Option<usize>,
    /// CG iteration budget per solve, ≥ 1; default 50 (about twice the 24 unknowns of
    /// the thesis scene, on which exact-arithmetic CG would finish in 24 iterations).
    /// For `"cholesky_pcg"`, the preconditioned iterations before a solve factorizes
    /// instead; default 10.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub max_iterations: Option<usize>,
    /// CG relative residual tolerance [1], ≥ 0; default 1e-10 (near round-off, so the
    /// budget, not the tolerance, is what limits accuracy). For `"cholesky_pcg"`, in
    /// (0, 1); default 1e-8.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub tolerance: Option<f64>,
}

/// `body_model`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum BodyModelFile {
    /// `"auto"` (default): point masses when every link anchor is at a body centre and
    /// no body starts spinning (rotation cannot be excited, method §2), else rigid.
    #[default]
    Auto,
    /// `"rigid"`: always full rigid bodies.
    Rigid,
    /// `"point_mass"`: point masses; an error if an anchor is off-centre or a body spins.
    PointMass,
}

/// `model`: exactly one of `grid`, or `bodies` (+ `links`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// A generated `rows × cols` grid (method §3).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub grid: Option<GridFile>,
    /// Explicit bodies, in file order.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub bodies: Option<Vec<BodyFile>>,
    /// Explicit links, in file order (link k is the k-th entry, 1-based); only with
    /// `bodies`; default none.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub links: Option<Vec<LinkFile>>,
    /// Uniform gravity `[gx, gy, gz]` [m/s²] on every body (e.g. `[0, 0, -9.81]`);
    /// default none.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub gravity: Option<[f64; 3]>,
    /// Joints between two bodies or a body and the world (a pivot), in file order
    /// (joint j is the j-th entry, 1-based); their rows follow the links'. Default none.
    /// Joints turn their bodies: they need rigid bodies (`auto` chooses them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub joints: Vec<JointFile>,
    /// Linear spring-dampers between two anchors, or an anchor and a world point, in
    /// file order; default none. A force element, not a constraint: it adds no row.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub springs: Vec<SpringFile>,
}

/// One entry of `model.springs`: the force `−(k (d − L) + c ḋ) n` on `a`'s anchor and
/// its opposite on `b`'s, `d` the anchors' distance, `n` the unit vector from `b`'s
/// anchor to `a`'s.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SpringFile {
    /// Id of body `a`.
    pub a: u32,
    /// Id of body `b`; without it the spring holds `a` to the world point `anchor_b`.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub b: Option<u32>,
    /// Anchor on body `a`, body frame [m]; default the body centre.
    #[serde(default)]
    pub anchor_a: [f64; 3],
    /// Anchor on body `b`, body frame [m] (default its centre); without `b`, the fixed
    /// world point [m] (default the origin).
    #[serde(default)]
    pub anchor_b: [f64; 3],
    /// Stiffness k [N/m], ≥ 0; required.
    pub stiffness: f64,
    /// Damping c [N·s/m], ≥ 0; default 0.
    #[serde(default)]
    pub damping: f64,
    /// Rest length L [m], ≥ 0; default the anchors' distance at t = 0 (the spring
    /// starts unloaded).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub length: Option<f64>,
}

/// A joint type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum JointTypeFile {
    /// The bodies share the point `at` and turn freely about it (3 constraint rows).
    Ball,
    /// A ball joint that lets the bodies turn only about `axis` (5 rows).
    Hinge,
    /// The bodies move as one (6 rows).
    Weld,
    /// Body `a` slides along `axis`, fixed in body `b` (or the world), neither body
    /// turning against the other (5 rows).
    Prismatic,
}

/// One entry of `model.joints`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct JointFile {
    /// `"ball"`, `"hinge"`, `"weld"` or `"prismatic"`.
    #[serde(rename = "type")]
    pub kind: JointTypeFile,
    /// Id of body `a`.
    pub a: u32,
    /// Id of body `b` (not `a`); default none: `a` is joined to the world at `at`, a
    /// fixed pivot.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub b: Option<u32>,
    /// The joint's point in world coordinates at t = 0 [m]; required. Each body's
    /// anchor is this point in its own frame, so the scene starts on the joint.
    pub at: [f64; 3],
    /// `hinge`: the axis the bodies turn about; `prismatic`: the axis `a` slides along
    /// (fixed in `b`, or in the world). A world direction at t = 0 (any length but
    /// zero); required for a hinge or a prismatic joint, refused otherwise.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub axis: Option<[f64; 3]>,
}

/// `model.grid`: bodies on the z = 0 plane, linked to their 4-neighbours.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GridFile {
    /// Number of rows (along y), ≥ 1.
    pub rows: u32,
    /// Number of columns (along x), ≥ 1.
    pub cols: u32,
    /// Distance between neighbours, and the length of every link [m].
    pub spacing: f64,
    /// Mass of every body [kg].
    pub mass: f64,
    /// Cube edge of every body [m].
    pub size: f64,
}

/// One entry of `model.bodies`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BodyFile {
    /// Body id, unique; used by links, forces and output, and in trace column names.
    pub id: u32,
    /// Mass [kg], > 0.
    pub mass: f64,
    /// Cube edge [m], > 0.
    pub size: f64,
    /// Principal moments of inertia `[Ixx, Iyy, Izz]` in the body frame [kg·m²], each
    /// > 0; default the solid cube's `m s²/6` on each axis.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub inertia: Option<[f64; 3]>,
    /// Initial position of the centre of mass [m]; required.
    pub position: [f64; 3],
    /// Initial linear velocity [m/s]; default at rest.
    #[serde(default)]
    pub velocity: [f64; 3],
    /// Initial orientation, quaternion `[w, x, y, z]` (body → world); default identity;
    /// normalized on validation, must not be zero.
    #[serde(default = "identity_quaternion")]
    pub orientation: [f64; 4],
    /// Initial angular velocity in the world frame [rad/s]; default not spinning.
    #[serde(default)]
    pub angular_velocity: [f64; 3],
}

/// One entry of `model.links`: a rigid distance link between two anchors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LinkFile {
    /// Id of body `a`.
    pub a: u32,
    /// Id of body `b` (not `a`).
    pub b: u32,
    /// Link length [m], > 0; default the initial distance between the two anchors in
    /// world coordinates (so the scene starts on the constraint manifold).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub length: Option<f64>,
    /// Anchor on body `a`, body frame [m]; default the body centre.
    #[serde(default)]
    pub anchor_a: [f64; 3],
    /// Anchor on body `b`, body frame [m]; default the body centre.
    #[serde(default)]
    pub anchor_b: [f64; 3],
}

/// One entry of `forces`: `amplitude · sin(omega · t + phase)` at the body centre for
/// `from ≤ t < until`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ForceFile {
    /// Id of the driven body.
    pub body: u32,
    /// Amplitude vector [N] (in `torques`, [N·m]); required.
    pub amplitude: [f64; 3],
    /// Angular frequency ω [rad/s]; default 0 (with `phase` = π/2, a constant push).
    #[serde(default)]
    pub omega: f64,
    /// Phase φ [rad]; default 0.
    #[serde(default)]
    pub phase: f64,
    /// Switch-on time [s], ≥ 0, inclusive; default 0 (on from the start).
    #[serde(default)]
    pub from: f64,
    /// Switch-off time [s], ≥ `from`, exclusive; default never.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub until: Option<f64>,
    /// Linear amplitude envelope; default none (scale 1).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub ramp: Option<RampFile>,
    /// Point of application in the body frame [m]; default the centre of mass. Off the
    /// centre the force also turns the body (torque `(R r) × F`): needs rigid bodies.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub point: Option<[f64; 3]>,
}

/// `forces[].ramp`: the amplitude is scaled by `a0` until `t0`, by `a1` from `t1`, and
/// linearly in between (used to move a load smoothly from one body to another).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RampFile {
    /// Ramp start [s], ≥ 0.
    pub t0: f64,
    /// Ramp end [s], > `t0`.
    pub t1: f64,
    /// Scale at and before `t0` [1].
    pub a0: f64,
    /// Scale at and after `t1` [1].
    pub a1: f64,
}

fn default_max_violation() -> f64 {
    DEFAULT_MAX_VIOLATION
}

/// `divergence`: when a run is declared diverged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DivergenceFile {
    /// Stop when any link's `|w|` exceeds this [m], > 0; default 1 m: ten times the SMC
    /// boundary layer ε = 0.1 m that a stable run stays within, yet below the thesis's
    /// link length 1.8 m, so a blown-up run is caught before it is meaningless.
    #[serde(default = "default_max_violation")]
    pub max_violation: f64,
}

impl Default for DivergenceFile {
    fn default() -> Self {
        DivergenceFile {
            max_violation: default_max_violation(),
        }
    }
}

/// `measurement`: the cost measurement window.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MeasurementFile {
    /// Window length T [s], > 0, a whole number of `dt` steps, ≤ `duration`; default
    /// 1 s (30 windows over the thesis's 30 s run: fine enough for the controller to
    /// follow the load switching at 12 s and 24 s), rounded down to a whole number of
    /// steps and capped at `duration` so that short test runs still validate.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub period: Option<f64>,
    /// FMU outputs whose RMS over a window, summed, is the window's cost instead of the
    /// links' `Σ RMS w` (`<fmu>.<variable>`, scalar outputs that are numbers or
    /// Booleans); default none (the links).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub signals: Option<Vec<String>>,
}

fn default_decimation() -> u64 {
    DEFAULT_DECIMATION
}

/// `output`: what goes into trace.csv and the plots.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputFile {
    /// Keep every n-th step in trace.csv, ≥ 1; default 10 (1 kHz thesis steps become a
    /// 100 Hz trace, plenty for the 2 rad/s load, a tenth of the file size).
    #[serde(default = "default_decimation")]
    pub decimation: u64,
    /// Ids of the bodies whose coordinates go into trace.csv, in column order; default
    /// every body in file order.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub trace_bodies: Option<Vec<u32>>,
    /// `true`: trace.csv also holds each traced body's orientation quaternion (body →
    /// world) `qw_B<id>,qx_B<id>,qy_B<id>,qz_B<id>` and world angular velocity
    /// `wx_B<id>,wy_B<id>,wz_B<id>` [rad/s], seven columns per traced body after the
    /// invariants (identity and zero on the point-mass path, which has no rotation
    /// state). Default `false`: most scenes are point masses, and a rigid one's
    /// rotation is needed only to study it; the trace stays 7 columns per body smaller.
    #[serde(default)]
    pub trace_rotation: bool,
    /// Ids of the bodies drawn in the body-coordinate plot; default the first and the
    /// last body in file order (the driven opposite corners of the thesis grid), or the
    /// only body.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub plot_bodies: Option<Vec<u32>>,
    /// TDMA: network.csv keeps every frame of every n-th cycle (and every lost frame
    /// and every cycle in which a list goes into force), ≥ 1; default 1.
    #[serde(default = "default_network_decimation")]
    pub network_decimation: u64,
    /// TDMA: cycles drawn in the slot-timeline plot, ≥ 1; default 3.
    #[serde(default = "default_timeline_cycles")]
    pub timeline_cycles: u64,
}

fn default_network_decimation() -> u64 {
    1
}

fn default_timeline_cycles() -> u64 {
    3
}

impl Default for OutputFile {
    fn default() -> Self {
        OutputFile {
            decimation: default_decimation(),
            trace_bodies: None,
            trace_rotation: false,
            plot_bodies: None,
            network_decimation: default_network_decimation(),
            timeline_cycles: default_timeline_cycles(),
        }
    }
}

/// `partition`: which computing node holds each body, and who owns the border links
/// (method §3). Exactly one of `nodes` or `"quadrants": true`.
///
/// Nodes are numbered from 1 in the file (node 0 is the TDMA server): the i-th list of
/// `nodes` is node i + 1.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PartitionFile {
    /// Body ids per node: every body in exactly one node, no node empty.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub nodes: Option<Vec<Vec<u32>>>,
    /// `true`: split a `grid` model with even rows and cols into 2×2 blocks of bodies,
    /// one node each. A 4×4 grid gives the thesis ring (node 1 = bodies 1, 2, 5, 6,
    /// node 2 = 3, 4, 7, 8, node 3 = 11, 12, 15, 16, node 4 = 9, 10, 13, 14; each node
    /// owns its border links toward the next node of the ring 1–2–3–4–1); any other grid
    /// numbers the blocks row by row from the origin corner. Default `false`.
    #[serde(default)]
    pub quadrants: bool,
    /// What a node does with the ghosts (far-end bodies of its border links); default
    /// `"integrate"` (the thesis's ghost equations).
    #[serde(default)]
    pub ghosts: GhostsFile,
    /// How a node uses border data that arrives `age` late: `"reset"` (overwrite the
    /// ghost, hold the force), `"predict"` (correct the ghost by its prediction error
    /// at the sample's time, apply `F + Ḟ·age`), `"passive"` (predict over an energy
    /// tank per border port, transmission lines where the data can be older than
    /// `lines_above`) or `"tlm"` (every border link a transmission line), or an object
    /// `{"scheme": …, "tank": J, "tank_share": r, "extrapolate": s, "impedance": N·s/m,
    /// "lines_above": s}`; default `"passive"` with each node's tank a tenth of the
    /// largest kinetic energy its bodies have held, 0.01 s of extrapolation and lines
    /// above 0.04 s (bounded on the thesis scene and the 16-node scene up to τ = 50 ms
    /// and the most accurate scheme there; see docs/guide.md "Coupling across
    /// partitions").
    #[serde(default)]
    pub coupling: CouplingFile,
    /// Owners of chosen border links, overriding the default rule (the thesis ring for
    /// the 4-node quadrants, else the node of the body with more other constraints per
    /// kilogram, else the node of the lower-numbered body); default none.
    #[serde(default)]
    pub link_owners: Vec<LinkOwnerFile>,
}

/// `partition.ghosts`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum GhostsFile {
    /// `"integrate"` (default): ghosts are integrated like own bodies between arrivals,
    /// as in the thesis.
    #[default]
    Integrate,
    /// `"hold"`: a ghost stays at the last received state (zero-order hold).
    Hold,
}

/// `partition.coupling`: a scheme's name, or an object when it takes parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum CouplingFile {
    /// `"reset"`, `"predict"` or `"passive"` (with its default tank).
    Name(CouplingName),
    /// `{"scheme": …, "tank": J, …}`.
    Spec(CouplingSpecFile),
}

impl Default for CouplingFile {
    fn default() -> CouplingFile {
        CouplingFile::Name(CouplingName::Passive)
    }
}

/// The coupling schemes by name.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum CouplingName {
    /// `"reset"`: every arriving state overwrites its ghost, every border force is held
    /// until the next arrival (the thesis's ghost equations).
    #[default]
    Reset,
    /// `"predict"`: delay-compensated ghosts and extrapolated border forces.
    Predict,
    /// `"passive"` (the default of `partition.coupling`): `predict` gated by an energy
    /// tank per border port, and transmission lines on the border links whose samples
    /// grow older than `lines_above`.
    Passive,
    /// `"tlm"`: every border link is a transmission line.
    Tlm,
}

/// `partition.coupling` as an object.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CouplingSpecFile {
    /// The scheme.
    pub scheme: CouplingName,
    /// `passive`: a fixed tank, the energy [J] each border port may create, ≥ 0, in
    /// place of the default `tank_share`.
    #[serde(default)]
    pub tank: Option<f64>,
    /// `passive`: each node's tank as a share of the largest kinetic energy its own
    /// bodies have held so far (against the centre of mass's velocity), in [0, 10];
    /// default 0.1. Not with `tank`.
    #[serde(default)]
    pub tank_share: Option<f64>,
    /// `predict` and `passive`: the longest time a border force or owner-side load is
    /// carried forward by its rate [s], ≥ 0 (older samples are held at that value);
    /// default 0.01 s.
    #[serde(default)]
    pub extrapolate: Option<f64>,
    /// `passive` and `tlm`: the transmission lines' impedance `Z` [N·s/m], > 0 (a line
    /// of one-way delay `T` is a spring of stiffness `Z / T` with a parasitic mass
    /// `Z · T`); default per link: its ends' reduced mass times the stabilizer's
    /// bandwidth (`2/μ` under SMC, `β` under Baumgarte).
    #[serde(default)]
    pub impedance: Option<f64>,
    /// `passive`: a border link becomes a transmission line when the oldest sample it
    /// can use (`τ + latency` of the channels carrying its data, as in the file) is
    /// older than this [s], in [0, 1000]; default 0.04 s.
    #[serde(default)]
    pub lines_above: Option<f64>,
}

/// One entry of `partition.link_owners`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LinkOwnerFile {
    /// Link number (1-based, file order; a grid numbers its links row by row, each
    /// body's +x link before its +y link); must be a border link.
    pub link: usize,
    /// Owning node (1-based): one of the two nodes holding the link's bodies.
    pub node: usize,
}

/// `network.kind`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum NetworkKind {
    /// `"ideal"` (default): each channel samples every τ and delivers after its
    /// latency, nothing lost (the thesis's chapter-3 reading).
    #[default]
    Ideal,
    /// `"tdma"`: the delays emerge from a TDMA schedule (method §4): sync slot,
    /// one static slot per node, a dynamic part that follows the slot list.
    Tdma,
}

/// `network`: `{"kind": "ideal"}` or `{"kind": "tdma", "slot": …, "cycle": …, …}`.
///
/// Kept flat like [`StabilizerFile`] (a `kind` plus the keys of each kind, checked by
/// validation), so that further network models add a variant and their keys here.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NetworkFile {
    /// Which network model; required inside the section.
    pub kind: NetworkKind,
    /// TDMA: length of every slot [s]; required for `tdma`.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub slot: Option<f64>,
    /// TDMA: cycle length [s], a whole number of slots; required for `tdma`.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub cycle: Option<f64>,
    /// TDMA: guard time at the end of every slot [s]; default 0.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub guard: Option<f64>,
    /// TDMA: link rate [bit/s]; default: an instantaneous link (frames take no time).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub link_rate: Option<f64>,
    /// TDMA: propagation delay [s]; default 0.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub propagation: Option<f64>,
    /// TDMA: header bytes of every frame [B]; default 0.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub header_bytes: Option<u64>,
    /// TDMA: bound of each client's clock-rate offset [ppm], drawn once per run; default 0.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub drift_ppm: Option<f64>,
    /// TDMA: random walk of the rate offset [ppm/√s]; default 0.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub random_walk_ppm: Option<f64>,
    /// TDMA: bound of the residual clock offset after a sync [s]; default 0.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub sync_error: Option<f64>,
    /// TDMA: processing jitter added to every frame's latency; default none.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub jitter: Option<JitterFile>,
    /// TDMA: an explicit slot list (what-if studies); default: scheduled from the
    /// channels' `tau` (and re-scheduled from every controller decision).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub slot_list: Option<Vec<SlotEntryFile>>,
    /// TDMA: time the server needs to compute a decision before broadcasting its list [s]
    /// (the thesis's `T_s · m_r`); default 0.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub decision_lag: Option<f64>,
    /// TDMA: which sample a data frame carries: `"slot"` (default: the sender's state at
    /// the frame's start, so the data's age on arrival is the transmission latency) or
    /// `"previous_slot"` (the sample the sender took at its previous frame of the same
    /// channel: the data is one period old, the thesis's `x(t − τ)` reading on a slot
    /// list).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub sample: Option<TdmaSample>,
}

/// `network.sample` (TDMA): defined with the model, which holds it as read.
pub use super::model::TdmaSample;

/// `network.jitter`: `{"kind": "uniform", "max": s}` or `{"kind": "exponential", "mean": s}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct JitterFile {
    /// Distribution.
    pub kind: JitterKind,
    /// Uniform: largest jitter [s].
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub max: Option<f64>,
    /// Exponential: mean jitter [s].
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub mean: Option<f64>,
}

/// `network.jitter.kind`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum JitterKind {
    /// Uniform on `[0, max]`.
    Uniform,
    /// Exponential with mean `mean`.
    Exponential,
}

/// `network.slot_list[]`: `{"node": n, "channel": "name"}` (node 0 is the server,
/// node n ≥ 1 the partition node n) or `{"idle": true}` for a slot nobody uses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SlotEntryFile {
    /// Sending node.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub node: Option<usize>,
    /// Channel name.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub channel: Option<String>,
    /// `true` for an idle slot.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub idle: Option<bool>,
}

/// `channels[].kinds` entries: what kind of data a channel carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DataKindFile {
    /// `"state"`: body states `(x, ẋ)`, from a body's owner to the nodes ghosting it.
    State,
    /// `"force"`: border-link constraint forces, from the link's owner to the owner of
    /// the ghosted body.
    Force,
    /// `"signal"`: FMU connections' values (only those naming the channel).
    Signal,
}

/// Default units per transfer k [1] (see [`ChannelFile::k`]).
pub const DEFAULT_CHANNEL_K: f64 = 1.0;

fn default_channel_k() -> f64 {
    DEFAULT_CHANNEL_K
}

/// One entry of `schedule`: from `at` on, the channels run at `tau`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ScheduleEntryFile {
    /// When the periods change [s]: a measurement window boundary (a whole multiple of
    /// `measurement.period`, 0 included) before `duration`, later than the entry
    /// before; required.
    pub at: f64,
    /// The period asked of each channel [s], one per entry of `channels` in their order,
    /// each > 0; required. An ideal channel runs it to the nanosecond (at least one
    /// step); a TDMA network what the slot list it schedules from them serves.
    pub tau: Vec<f64>,
}

/// One entry of `channels`: a periodic channel (method §4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ChannelFile {
    /// Channel name, unique, of letters, digits and `_` (it becomes part of CSV column
    /// names such as `tau_<name>_requested`); required.
    pub name: String,
    /// Sampling period τ [s], at least `dt`; required. Between steps, each sample is
    /// taken at the first step at or after its multiple of τ.
    pub tau: f64,
    /// Delivery latency [s], ≥ 0, a whole number of nanoseconds; default τ (the thesis's
    /// `x(t − τ)` reading), following τ when a controller changes it.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub latency: Option<f64>,
    /// Time of the first sample [s], ≥ 0, a whole number of nanoseconds, below τ
    /// (`ideal` networks only); default 0. A TDMA pair whose slot sits at this offset
    /// delivers at the same times (see docs/guide.md "TDMA network").
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub phase: Option<f64>,
    /// Units per transfer k [1], > 0 (bandwidth used is `Σ k/τ`); default 1 (thesis).
    #[serde(default = "default_channel_k")]
    pub k: f64,
    /// Borders carried, as pairs of node numbers `[a, b]` (1-based, either order), each
    /// a pair of nodes joined by at least one border link; default every border.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub borders: Option<Vec<[usize; 2]>>,
    /// Kinds of data carried, `"state"` and/or `"force"`, non-empty, no repeats; default
    /// both.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub kinds: Option<Vec<DataKindFile>>,
}

/// A controller method name.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum MethodFile {
    /// `"dsm"`: Dynamic Simplex Method (default).
    #[default]
    Dsm,
    /// `"grid"`: grid search every window.
    Grid,
    /// `"no_opt"`: equal delays at the budget.
    NoOpt,
    /// `"fixed"`: the initial delays.
    Fixed,
    /// `"nelder_mead"`: static Nelder–Mead.
    NelderMead,
}

/// `controller.problem`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ProblemKind {
    /// `"cp"`: constrained by the bandwidth budget.
    Cp,
    /// `"up"`: unconstrained with a bandwidth penalty.
    Up,
}

/// `controller.measure`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum MeasureFile {
    /// `"lookahead"`: fork the world per candidate (default).
    #[default]
    Lookahead,
    /// `"online"`: one candidate per window on the live plant.
    Online,
}

fn default_dsm_size() -> f64 {
    0.012
}

fn default_reflections() -> usize {
    5
}

fn default_grid_step() -> f64 {
    0.001
}

/// `controller.dsm`: the simplex (thesis values by default).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DsmFile {
    /// Simplex size D_s [s]; default 0.012 (thesis: 2 D_smin).
    #[serde(default = "default_dsm_size")]
    pub size: f64,
    /// Reflections per iteration m_r; default 5 (thesis).
    #[serde(default = "default_reflections")]
    pub reflections: usize,
}

impl Default for DsmFile {
    fn default() -> Self {
        DsmFile {
            size: default_dsm_size(),
            reflections: default_reflections(),
        }
    }
}

/// `controller`: delay optimization (method §5). Its period is `measurement.period`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ControllerFile {
    /// Method driving the live plant; default `"dsm"`.
    #[serde(default)]
    pub method: MethodFile,
    /// `"cp"` or `"up"`; required.
    pub problem: ProblemKind,
    /// Bandwidth budget B [1/s]; required for `cp`.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub budget: Option<f64>,
    /// Bandwidth price b [m·s]; required for `up`.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub penalty: Option<f64>,
    /// How candidates are measured; default `"lookahead"`.
    #[serde(default)]
    pub measure: MeasureFile,
    /// Lower bound of every delay [s]; default `dt`.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub tau_min: Option<f64>,
    /// Upper bound of every delay [s]; required.
    pub tau_max: f64,
    /// Initial controlled delays [s], the centre of the DSM's first simplex; default:
    /// CP, the no-optimization point (every controlled delay at `Σ k / budget`); UP,
    /// the channels' `tau`.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub initial: Option<Vec<f64>>,
    /// DSM simplex; default thesis values.
    #[serde(default)]
    pub dsm: DsmFile,
    /// Baselines evaluated every window; default none.
    #[serde(default)]
    pub baselines: Vec<MethodFile>,
    /// Also evaluate DSM ± δ [s] on each controlled delay; default none.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub dsm_delta: Option<f64>,
    /// Grid-search step [s]; default 0.001 (thesis).
    #[serde(default = "default_grid_step")]
    pub grid_step: f64,
    /// Window start [s] whose cost surface is plotted with the DSM path; default none.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub surface_window: Option<f64>,
    /// Two-channel constrained problem: also measure the surface window's cost over
    /// every grid pair of both delays, the budget ignored (landscape.csv/.svg); default
    /// false. Needs `surface_window`; costs one fork per grid pair.
    #[serde(default)]
    pub landscape: bool,
}
