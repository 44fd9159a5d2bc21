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
/// Default CG iteration budget per solve (see [`SolverFile::max_iterations`]).
pub const DEFAULT_CG_MAX_ITERATIONS: usize = 50;
/// Default CG relative residual tolerance [1] (see [`SolverFile::tolerance`]).
pub const DEFAULT_CG_TOLERANCE: f64 = 1e-10;
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

/// A whole scenario file (SPEC section 7 plus our own optional sections).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// Scenario name, copied into summary.json; required, non-empty.
    pub name: String,
    /// Seed of every random stream of the run; required (no hidden default seed).
    pub seed: u64,
    /// Simulated duration [s]; required, a whole number of `dt` steps.
    pub duration: f64,
    /// Integration step [s]; required, at least 1 ns and a whole number of nanoseconds.
    pub dt: f64,
    /// Time integrator; default `"euler"` (the thesis's integrator).
    #[serde(default)]
    pub integrator: IntegratorFile,
    /// Constraint stabilizer; default SMC with the thesis parameters.
    #[serde(default)]
    pub stabilizer: StabilizerFile,
    /// Multiplier solve; default exact Cholesky.
    #[serde(default)]
    pub solver: SolverFile,
    /// Body model; default `"auto"` (point masses when nothing can rotate).
    #[serde(default)]
    pub body_model: BodyModelFile,
    /// The bodies and links: a generated grid or an explicit list; required.
    pub model: ModelFile,
    /// External forces; default none.
    #[serde(default)]
    pub forces: Vec<ForceFile>,
    /// Divergence bound; default `max_violation` 1 m.
    #[serde(default)]
    pub divergence: DivergenceFile,
    /// Cost measurement window; default period 1 s.
    #[serde(default)]
    pub measurement: MeasurementFile,
    /// What goes into trace.csv and the plots; defaults in [`OutputFile`].
    #[serde(default)]
    pub output: OutputFile,
}

/// `integrator`: the time integrator of the `(x, v, z)` state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
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
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
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
    /// Baumgarte damping α [1/s], ≥ 0; required for `"baumgarte"` (no value is canonical).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub alpha: Option<f64>,
    /// Baumgarte stiffness β [1/s], ≥ 0; required for `"baumgarte"`.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub beta: Option<f64>,
}

/// `solver.kind`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolverKind {
    /// `"cholesky"`: exact sparse Cholesky (the default: no solver error to account for).
    #[default]
    Cholesky,
    /// `"cg"`: Jacobi-preconditioned conjugate gradient with a fixed budget.
    Cg,
}

/// `solver`: `{"kind": "cholesky"}` or `{"kind": "cg", "max_iterations", "tolerance"}`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverFile {
    /// Which solver; required inside the section.
    pub kind: SolverKind,
    /// CG iteration budget per solve, ≥ 1; default 50 (about twice the 24 unknowns of
    /// the thesis scene, on which exact-arithmetic CG would finish in 24 iterations).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub max_iterations: Option<usize>,
    /// CG relative residual tolerance [1], ≥ 0; default 1e-10 (near round-off, so the
    /// budget, not the tolerance, is what limits accuracy).
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub tolerance: Option<f64>,
}

/// `body_model`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BodyModelFile {
    /// `"auto"` (default): point masses when every link anchor is at a body centre and
    /// no body starts spinning (rotation cannot be excited, SPEC section 2), else rigid.
    #[default]
    Auto,
    /// `"rigid"`: always full rigid bodies.
    Rigid,
    /// `"point_mass"`: point masses; an error if an anchor is off-centre or a body spins.
    PointMass,
}

/// `model`: exactly one of `grid`, or `bodies` (+ `links`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// A generated `rows × cols` grid (SPEC section 3).
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
}

/// `model.grid`: bodies on the z = 0 plane, linked to their 4-neighbours.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceFile {
    /// Id of the driven body.
    pub body: u32,
    /// Amplitude vector [N]; required.
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
}

fn default_max_violation() -> f64 {
    DEFAULT_MAX_VIOLATION
}

/// `divergence`: when a run is declared diverged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
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
}

fn default_decimation() -> u64 {
    DEFAULT_DECIMATION
}

/// `output`: what goes into trace.csv and the plots.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    /// Ids of the bodies drawn in the body-coordinate plot; default the first and the
    /// last body in file order (the driven opposite corners of the thesis grid), or the
    /// only body.
    #[serde(
        default,
        deserialize_with = "present",
        skip_serializing_if = "Option::is_none"
    )]
    pub plot_bodies: Option<Vec<u32>>,
}

impl Default for OutputFile {
    fn default() -> Self {
        OutputFile {
            decimation: default_decimation(),
            trace_bodies: None,
            plot_bodies: None,
        }
    }
}
