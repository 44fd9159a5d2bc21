//! The static model (masses, inertias, links, forces) and the per-step workspace.

use nalgebra::{Matrix3, Matrix6, Vector3};

use super::solver::{Geometry, JsSolver, MassData, SolveError};
use super::state::Rates;
use crate::kernel::SimTime;
use crate::scenario::model::{
    BodyModel, ForceSpec, Integrator, RowKind, Scenario, SpringSpec, Stabilizer,
};

/// One constraint row (a distance link or a joint's row), with body indices resolved:
/// the scenario's own [`crate::scenario::model::LinkSpec`], shared with it.
pub type Link = crate::scenario::model::LinkSpec;

/// A multi-body system ready to integrate: model data, stabilizer, integrator and all
/// scratch memory (no allocation happens inside a step).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct System {
    pub(crate) rigid: bool,
    pub(crate) inertia: Vec<Vector3<f64>>,
    pub(crate) links: std::sync::Arc<[Link]>,
    pub(crate) forces: Vec<ForceSpec>,
    /// Spring-dampers (local body indices); empty: none, and no arithmetic.
    pub(crate) springs: Vec<SpringSpec>,
    /// Uniform gravity [m/s²] on every movable body (`None`: none).
    pub(crate) gravity: Option<Vector3<f64>>,
    pub(crate) stabilizer: Stabilizer,
    /// Per-link SMC surface parameter μ [s] where it differs from the stabilizer's
    /// (empty: every link uses the stabilizer's μ).
    pub(crate) link_mu: Vec<f64>,
    pub(crate) integrator: Integrator,
    pub(crate) dt: SimTime,
    /// Extra external force per body [N], held constant over a step (used for border
    /// forces received from other partitions; zero on a monolithic run).
    pub extra_force: Vec<Vector3<f64>>,
    /// Forces set by connections (`B<id>.fx` …) per body [N], held between deliveries;
    /// empty until the first (so a scene without them adds no arithmetic).
    pub input_force: Vec<Vector3<f64>>,
    /// Extra external torque per body [N·m] (rigid path only; empty on point masses).
    pub extra_torque: Vec<Vector3<f64>>,
    /// Rate of each body's extra force [N/s] and torque [N·m/s] (empty: held constant).
    /// A stage at time `t` of the step that began at [`System::extra_from`] applies
    /// `extra + rate·(t − extra_from)`: border values carried to each stage's time, so
    /// that a partition keeps a multi-stage integrator's order (held over RK4's stages,
    /// a border force makes the whole run first order in `dt`).
    pub extra_rate: ExtraRate,
    pub(crate) mass: MassData,
    pub(crate) geo: Geometry,
    pub(crate) ws: Workspace,
    pub(crate) solver: JsSolver,
    pub(crate) k: [Rates; 4],
    pub(crate) stage: super::state::State,
    /// `divergence.max_violation` [m]: with a stalled CG ([`System::check_cg_budget`]) a
    /// violation beyond it is reported as the CG budget's failure.
    pub(crate) max_violation: f64,
    /// Consecutive CG solves that stopped at their budget with a residual beyond what the
    /// stabilizer absorbs, and the largest such residual among them.
    pub(crate) cg_stalled: usize,
    pub(crate) cg_worst: f64,
    /// Whether the multipliers at each step start are kept for the rows' slopes:
    /// Baumgarte on a multi-stage integrator with rows (see
    /// [`System::multiplier_and_rate`]).
    pub(crate) keeps_slopes: bool,
    /// Those multipliers at the last step start; empty before the first step and when
    /// none are kept.
    pub(crate) z_step: Vec<f64>,
    /// Per body (a ghost), where its owner sent one: how the owner's rows answer a load
    /// put on it, `K = J_bᵀ A⁺ J_b` in the body's frame ([`System::set_reaction`]).
    /// Empty: none.
    pub(crate) reaction: Vec<Option<Matrix6<f64>>>,
    /// Per body with a whole inverse mass: the force of this system's rows on it at the
    /// last evaluation [N], and its impulse over the current step as the integrator
    /// weighs the stages [N·s] ([`System::row_impulse`]). Empty: none.
    pub(crate) row_force: Vec<Vector3<f64>>,
    pub(crate) row_impulse: Vec<Vector3<f64>>,
}

/// A row's load on one of its bodies with its rates, for a border message
/// ([`System::link_load_and_rate_on`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RowLoad {
    /// Force [N].
    pub force: Vector3<f64>,
    /// Torque [N·m].
    pub torque: Vector3<f64>,
    /// Force rate [N/s], carried as far as the coupling extrapolates.
    pub force_rate: Vector3<f64>,
    /// Torque rate [N·m/s], likewise.
    pub torque_rate: Vector3<f64>,
    /// The force's rate measured over the last step alone [N/s] (a Baumgarte
    /// multiplier's slope on a row that is not an alignment row), carried one step.
    pub step_force_rate: Vector3<f64>,
    /// The torque's, likewise [N·m/s].
    pub step_torque_rate: Vector3<f64>,
}

/// A row's multiplier with its rates ([`System::multiplier_and_rate`]).
struct RowRates {
    z: f64,
    rate: f64,
    step_rate: f64,
}

/// The rates of a system's extra loads over a step (see [`System::extra_rate`]).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExtraRate {
    /// Time the extra loads hold their value at (the step's start).
    pub from: SimTime,
    /// Force rate per body [N/s] (empty: none).
    pub force: Vec<Vector3<f64>>,
    /// Torque rate per body [N·m/s] (rigid path; empty: none).
    pub torque: Vec<Vector3<f64>>,
}

/// Consecutive stalled CG solves ([`System::check_cg_budget`]) after which a violation
/// beyond `divergence.max_violation` is blamed on the CG budget: one RK4 step's solves,
/// four Euler steps.
pub const CG_STALL_SOLVES: usize = 4;

/// A CG solve at its budget is stalled when its residual alone holds a link off by more
/// than this fraction of `divergence.max_violation` ([`System::check_cg_budget`]).
pub const CG_STALL_FRACTION: f64 = 0.1;

/// Per-evaluation scratch: body accumulators and per-link kinematics.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct Workspace {
    /// Net force per body [N].
    pub force: Vec<Vector3<f64>>,
    /// Net torque per body [N·m] (rigid path only).
    pub torque: Vec<Vector3<f64>>,
    /// Linear acceleration per body [m/s²].
    pub acc: Vec<Vector3<f64>>,
    /// Angular acceleration per body [rad/s²] (rigid path only).
    pub alpha: Vec<Vector3<f64>>,
    /// World inertia per body [kg·m²] (rigid path only).
    pub inertia_world: Vec<Matrix3<f64>>,
    /// Constraint value w = |P_a − P_b| − L per link [m].
    pub w: Vec<f64>,
    /// ẇ = J v [m/s].
    pub wd: Vec<f64>,
    /// ẅ = J a + J̇ v [m/s²].
    pub wdd: Vec<f64>,
    /// J̇ v [m/s²].
    pub jdv: Vec<f64>,
    /// Right-hand side of the multiplier solve.
    pub rhs: Vec<f64>,
    /// Solution of the multiplier solve (warm start for CG).
    pub sol: Vec<f64>,
    /// Baumgarte's algebraic multipliers z at the last evaluation [N].
    pub z_alg: Vec<f64>,
}

impl System {
    /// Builds the system of a validated scenario.
    pub fn new(scenario: &Scenario) -> System {
        let rigid = scenario.body_model == BodyModel::Rigid;
        // The scenario's rows themselves, not a copy: the model is held once.
        let links = std::sync::Arc::clone(&scenario.links);
        let mut inv_mass: Vec<f64> = scenario.bodies.iter().map(|b| 1.0 / b.mass).collect();
        let inertia = scenario.bodies.iter().map(|b| b.inertia).collect();
        let nb = inv_mass.len();
        // Rows held to the world end on one more body, immovable and stateless: the
        // solver and the per-body accumulators see it (its `1/m` and `I⁻¹` are zero, so
        // nothing moves it), the state does not.
        let world = links.iter().any(|l| l.world);
        let solver_bodies = nb + usize::from(world);
        if world {
            inv_mass.push(0.0);
        }
        let nl = links.len();
        let nr = if rigid { solver_bodies } else { 0 };
        let nlr = if rigid { nl } else { 0 };
        let v3 = Vector3::zeros;
        let geo = Geometry {
            ends: links
                .iter()
                .map(|l| (l.a, if l.world { nb } else { l.b }))
                .collect(),
            n: vec![v3(); nl],
            ca: vec![v3(); nlr],
            cb: vec![v3(); nlr],
        };
        let mass = MassData {
            inv_mass,
            inv_inertia: vec![Matrix3::zeros(); nr],
            compliance: Vec::new(),
        };
        let solver = JsSolver::new(scenario.solver, solver_bodies, &geo.ends);
        let shape = super::state::State {
            p: vec![v3(); nb],
            v: vec![v3(); nb],
            q: vec![nalgebra::Quaternion::identity(); if rigid { nb } else { 0 }],
            omega: vec![v3(); if rigid { nb } else { 0 }],
            z: vec![0.0; nl],
        };
        // Only RK4 uses the stages k2..k4 and the stage state; the Eulers' are left
        // empty (a quarter of a point-mass body's memory: 4 × 64 bytes per body with
        // its two links).
        let rk4 = scenario.integrator == Integrator::Rk4;
        let k = std::array::from_fn(|i| {
            if i == 0 || rk4 {
                Rates::zeros_like(&shape)
            } else {
                Rates::zeros_like(&super::state::State::empty())
            }
        });
        let stage = if rk4 {
            shape
        } else {
            super::state::State::empty()
        };
        System {
            rigid,
            inertia,
            links,
            forces: scenario.forces.clone(),
            springs: scenario.springs.clone(),
            gravity: scenario.gravity,
            stabilizer: scenario.stabilizer,
            link_mu: Vec::new(),
            integrator: scenario.integrator,
            dt: scenario.dt,
            extra_force: vec![v3(); nb],
            input_force: Vec::new(),
            extra_torque: vec![v3(); if rigid { nb } else { 0 }],
            extra_rate: ExtraRate::default(),
            mass,
            geo,
            ws: Workspace {
                force: vec![v3(); solver_bodies],
                torque: vec![v3(); nr],
                acc: vec![v3(); solver_bodies],
                alpha: vec![v3(); nr],
                inertia_world: vec![Matrix3::zeros(); nr],
                w: vec![0.0; nl],
                wd: vec![0.0; nl],
                wdd: vec![0.0; nl],
                jdv: vec![0.0; nl],
                rhs: vec![0.0; nl],
                sol: vec![0.0; nl],
                z_alg: vec![0.0; nl],
            },
            solver,
            k,
            stage,
            max_violation: scenario.max_violation,
            cg_stalled: 0,
            cg_worst: 0.0,
            keeps_slopes: scenario.slopes_multipliers(),
            z_step: Vec::new(),
            reaction: Vec::new(),
            row_force: Vec::new(),
            row_impulse: Vec::new(),
        }
    }

    /// After a successful multiplier solve: whether a CG budget too small for the scene
    /// is what is breaking the constraints.
    ///
    /// A CG solve that stops at its iteration budget leaves a residual `r = b − A ż`, and
    /// the multipliers then obey `μ² A ż = −α̂ − K sat(s/ε) − μ² r`: the residual enters
    /// the sliding dynamics as a disturbance `μ² r`. Inside the boundary layer the law
    /// answers a steady disturbance `d` with `s = −ε d / K`, and `w` follows `s`
    /// (`s = μ²ẅ + 2μẇ + w`), so the residual alone holds each link off by about
    /// `w_r = ε μ_l² |r_l| / K` metres; beyond `w_r = ε` the disturbance outweighs the
    /// whole gain `K` and `s` leaves the layer. Under Baumgarte (`ẅ = −2αẇ − β²w − r`)
    /// the same reading gives `w_r = |r_l| / β²`. A solve is *stalled* when it stopped at
    /// its budget above its tolerance with `max_l w_r` above
    /// [`CG_STALL_FRACTION`] of `divergence.max_violation`: its residual accounts for a
    /// visible part of the violation the run allows.
    ///
    /// The residual alone does not predict divergence: the thesis scene with CG 1 runs
    /// its 30 s with up to 175 consecutive solves at `μ²‖r‖∞ > K` and stays below 1 m
    /// (docs/accuracy.md, "A CG budget that cannot hold the asked accuracy"). So a
    /// stalled run is an error only once it also breaks the asked accuracy: after at least [`CG_STALL_SOLVES`] consecutive stalled solves, a
    /// link of this system violates `divergence.max_violation`. The error comes where
    /// the run would otherwise stop with a plain divergence (the same violation at the
    /// same step, or at an RK4 stage inside it), and names the budget, the residual and
    /// the way out. A run whose violation stays within the bound never sees it, however
    /// inexact its solves: loose CG runs are the fast end of the trade by design.
    ///
    /// Why an error and not a fallback to the exact solve: a fallback would switch the
    /// method in the middle of a run (its digest would depend on where), and would
    /// silently cost the exact path's time to a user who chose CG for its speed; the
    /// error says which of the two to change.
    pub(crate) fn check_cg_budget(&mut self) -> Result<(), SolveError> {
        let Some((r, iterations)) = self.solver.cg_residual_at_budget() else {
            self.cg_stalled = 0;
            self.cg_worst = 0.0;
            return Ok(());
        };
        let largest = |r: &[f64]| r.iter().fold(0.0f64, |a, &x| a.max(x.abs()));
        let held_off = match self.stabilizer {
            // One μ for every link (no border links with their own): one scaling.
            Stabilizer::Smc { mu, k, epsilon } if self.link_mu.is_empty() => {
                epsilon * mu * mu * largest(r) / k
            }
            Stabilizer::Smc { k, epsilon, .. } => r
                .iter()
                .zip(&self.link_mu)
                .map(|(&x, &mu)| epsilon * mu * mu * x.abs() / k)
                .fold(0.0, f64::max),
            Stabilizer::Baumgarte { beta, .. } => largest(r) / (beta * beta),
        };
        // NaN (0/0: no gain and no residual) is no stall.
        if held_off.is_nan() || held_off <= CG_STALL_FRACTION * self.max_violation {
            self.cg_stalled = 0;
            self.cg_worst = 0.0;
            return Ok(());
        }
        self.cg_stalled += 1;
        self.cg_worst = self.cg_worst.max(held_off);
        if self.cg_stalled < CG_STALL_SOLVES {
            return Ok(());
        }
        let worst_link = self
            .ws
            .w
            .iter()
            .enumerate()
            .fold((0, 0.0f64), |best, (l, &w)| {
                // A non-finite w is beyond any bound.
                let w = if w.is_finite() {
                    w.abs()
                } else {
                    f64::INFINITY
                };
                if w > best.1 {
                    (l, w)
                } else {
                    best
                }
            });
        if worst_link.1 > self.max_violation {
            return Err(SolveError::CgBudget {
                iterations,
                residual: held_off,
                worst: self.cg_worst,
                solves: self.cg_stalled,
                link: worst_link.0,
                violation: worst_link.1,
                bound: self.max_violation,
            });
        }
        Ok(())
    }

    /// Number of bodies.
    pub fn body_count(&self) -> usize {
        self.extra_force.len()
    }

    /// Sets component `axis` of the connection-set force on body `b` [N].
    pub fn set_input_force(&mut self, b: usize, axis: usize, value: f64) {
        if self.input_force.is_empty() {
            self.input_force = vec![Vector3::zeros(); self.extra_force.len()];
        }
        self.input_force[b][axis] = value;
    }

    /// Number of links.
    pub fn link_count(&self) -> usize {
        self.links.len()
    }

    /// The links, in file order.
    pub fn links(&self) -> &[Link] {
        &self.links
    }

    /// Whether the rigid-body (rotational) path is in use.
    pub fn is_rigid(&self) -> bool {
        self.rigid
    }

    /// Whether the integrator evaluates rates after the step's start (RK4's stages).
    pub fn is_multistage(&self) -> bool {
        self.integrator == Integrator::Rk4
    }

    /// Step length.
    pub fn dt(&self) -> SimTime {
        self.dt
    }

    /// Constraint values w [m] of the last [`begin_step`](Self::begin_step).
    pub fn violations(&self) -> &[f64] {
        &self.ws.w
    }

    /// Constraint rates ẇ [m/s] of the last [`begin_step`](Self::begin_step).
    pub fn violation_rates(&self) -> &[f64] {
        &self.ws.wd
    }

    /// Link tensions f [N] at the last [`begin_step`](Self::begin_step) for `state`:
    /// positive when the link pulls its bodies together (`f = −z`).
    pub fn tension(&self, state: &super::State, link: usize) -> f64 {
        match self.stabilizer {
            Stabilizer::Smc { .. } => -state.z[link],
            Stabilizer::Baumgarte { .. } => -self.ws.z_alg[link],
        }
    }

    /// Row `l`'s multiplier [N] in `state` as the last evaluation left it (SMC: the
    /// state's `z`; Baumgarte: the last evaluation's algebraic one).
    pub fn multiplier(&self, state: &super::State, l: usize) -> f64 {
        match self.stabilizer {
            Stabilizer::Smc { .. } => state.z[l],
            Stabilizer::Baumgarte { .. } => self.ws.z_alg[l],
        }
    }

    /// Under Baumgarte, sets the multipliers the next samples read before an
    /// evaluation of this system's own (one per row); under SMC they are state and this
    /// does nothing.
    pub fn set_multipliers(&mut self, z: &[f64]) {
        if matches!(self.stabilizer, Stabilizer::Baumgarte { .. }) {
            self.ws.z_alg.copy_from_slice(z);
        }
    }

    /// Sets link `l`'s SMC surface parameter μ [s] (the others keep the stabilizer's).
    pub fn set_link_mu(&mut self, l: usize, mu: f64) {
        if let Stabilizer::Smc { mu: base, .. } = self.stabilizer {
            if self.link_mu.is_empty() {
                self.link_mu = vec![base; self.links.len()];
            }
            self.link_mu[l] = mu;
        }
    }

    /// Makes body `i` immovable (infinite mass and inertia): its acceleration is zero
    /// and link forces do not move it (used for held ghosts).
    pub fn set_immovable(&mut self, i: usize) {
        self.mass.inv_mass[i] = 0.0;
    }

    /// Force [N] and torque [N·m] that link `l` exerts on its body `body` (which must be
    /// one of its ends) in `state`, from the geometry of `state` and the multiplier
    /// (SMC: the state's `z`; Baumgarte: the last evaluation's).
    pub fn link_load_on(
        &self,
        state: &super::State,
        l: usize,
        body: usize,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let link = &self.links[l];
        if link.joint.is_some() {
            let load = self.joint_row_load_on(state, l, body);
            return (load.force, load.torque);
        }
        let anchor = |i: usize, r: &Vector3<f64>| {
            if self.rigid {
                nalgebra::UnitQuaternion::new_normalize(state.q[i]) * r
            } else {
                Vector3::zeros()
            }
        };
        let (ra, rb) = (
            anchor(link.a, &link.anchor_a),
            anchor(link.b, &link.anchor_b),
        );
        let n = (state.p[link.a] + ra - state.p[link.b] - rb).normalize();
        let z = match self.stabilizer {
            Stabilizer::Smc { .. } => state.z[l],
            Stabilizer::Baumgarte { .. } => self.ws.z_alg[l],
        };
        if body == link.a {
            (n * z, ra.cross(&n) * z)
        } else {
            (-n * z, -rb.cross(&n) * z)
        }
    }

    /// [`link_load_on`](Self::link_load_on) (the same bits) with its time derivative:
    /// `d(n z)/dt = ṅ z + n ż` [N/s] and `d(r × n z)/dt` [N·m/s], with
    /// `ṅ = (u − n (n·u)) / d` from the anchors' relative velocity `u` in `state`, and
    /// `ż` the SMC law's rate at the last evaluation (the slope the integrator used over
    /// the step that ended at `state`). Under Baumgarte `z` is algebraic and `ż` its
    /// slope over the last step ([`System::multiplier_and_rate`]), a step rate on a row
    /// whose direction does not turn it. One pass for all, as a message needs all.
    pub fn link_load_and_rate_on(&self, state: &super::State, l: usize, body: usize) -> RowLoad {
        let link = &self.links[l];
        if link.joint.is_some() {
            return self.joint_row_load_on(state, l, body);
        }
        let (mut ra, mut rb) = (Vector3::zeros(), Vector3::zeros());
        let (mut wa, mut wb) = (Vector3::zeros(), Vector3::zeros());
        if self.rigid {
            ra = nalgebra::UnitQuaternion::new_normalize(state.q[link.a]) * link.anchor_a;
            rb = nalgebra::UnitQuaternion::new_normalize(state.q[link.b]) * link.anchor_b;
            wa = state.omega[link.a];
            wb = state.omega[link.b];
        }
        let n = (state.p[link.a] + ra - state.p[link.b] - rb).normalize();
        let d = (state.p[link.a] + ra - state.p[link.b] - rb).norm();
        let u = state.v[link.a] + wa.cross(&ra) - state.v[link.b] - wb.cross(&rb);
        let n_dot = (u - n * n.dot(&u)) / d;
        let rates = self.multiplier_and_rate(state, l);
        let (z, z_dot) = (rates.z, rates.rate);
        let f_dot = n_dot * z + n * z_dot;
        let f = n * z;
        let (r, w, sign) = if body == link.a {
            (ra, wa, 1.0)
        } else {
            (rb, wb, -1.0)
        };
        let mut load = RowLoad {
            force: f * sign,
            torque: r.cross(&n) * z * sign,
            force_rate: f_dot * sign,
            torque_rate: (w.cross(&r).cross(&f) + r.cross(&f_dot)) * sign,
            ..RowLoad::default()
        };
        if rates.step_rate != 0.0 {
            load.step_force_rate = n * rates.step_rate * sign;
            load.step_torque_rate = r.cross(&n) * rates.step_rate * sign;
        }
        load
    }

    /// [`link_load_and_rate_on`](Self::link_load_and_rate_on) for a joint's row (rigid
    /// bodies, as every joint's): force `n z`, torque `c z` on `a` (`−n z`, `−c_b z` on `b`)
    /// and their rates. An offset row's `n` is a fixed axis, so its force turns only
    /// with `ż`; its lever `R r` turns with the body (`ċ = (ω × R r) × n`). An
    /// alignment row has no force, and its `c = u × v` turns with both bodies.
    fn joint_row_load_on(&self, state: &super::State, l: usize, body: usize) -> RowLoad {
        let link = &self.links[l];
        let row = super::dynamics::row_kinematics(link, state, self.rigid);
        let rates = self.multiplier_and_rate(state, l);
        let (z, z_dot) = (rates.z, rates.rate);
        // `ċ_a`, `ċ_b`: an alignment row's from its kinematics; an offset row's levers
        // turn with their bodies (the world's side does not turn).
        let (ca_dot, cb_dot) = match &link.kind {
            RowKind::Align(_) => (row.c_dot, row.c_dot),
            // A slide row's normal turns with `b`, and with it both levers.
            RowKind::Slide(_) => (
                state.omega[link.a].cross(&row.ra).cross(&row.n) + row.ra.cross(&row.n_dot),
                row.cb_dot,
            ),
            _ => {
                let wb = if link.world {
                    Vector3::zeros()
                } else {
                    state.omega[link.b]
                };
                (
                    state.omega[link.a].cross(&row.ra).cross(&row.n),
                    wb.cross(&row.rb).cross(&row.n),
                )
            }
        };
        // Only a slide row's normal turns (the others' `ṅ` is zero: not added, so a
        // zero's sign stays as it was).
        let f_dot = match &link.kind {
            RowKind::Slide(_) => row.n_dot * z + row.n * z_dot,
            _ => row.n * z_dot,
        };
        let mut load = if body == link.a {
            RowLoad {
                force: row.n * z,
                torque: row.ca * z,
                force_rate: f_dot,
                torque_rate: ca_dot * z + row.ca * z_dot,
                ..RowLoad::default()
            }
        } else {
            RowLoad {
                force: -row.n * z,
                torque: -row.cb * z,
                force_rate: -f_dot,
                torque_rate: -(cb_dot * z + row.cb * z_dot),
                ..RowLoad::default()
            }
        };
        if rates.step_rate != 0.0 {
            let (sign, c) = if body == link.a {
                (1.0, row.ca)
            } else {
                (-1.0, row.cb)
            };
            load.step_force_rate = row.n * rates.step_rate * sign;
            load.step_torque_rate = c * rates.step_rate * sign;
        }
        load
    }

    /// Row `l`'s multiplier [N] and its rates [N/s] for a border message, taken between
    /// steps: SMC's state `z` and the law's `ż`; Baumgarte's algebraic `z` as the last
    /// evaluation left it and, on a multi-stage integrator, its slope over the last
    /// step, from the step's first stage to its last (`(z(t) − z(t − h)) / h`, both
    /// evaluated inside one step, so no ghost correction between them makes a jump of
    /// it). An alignment row's slope is its rate (its couple's direction turns with a
    /// spinning body while its multiplier turns it back, so the two travel together);
    /// every other row's is a step rate, carried one step ([`RowLoad`]). A single-stage
    /// step evaluates once: no slope.
    fn multiplier_and_rate(&self, state: &super::State, l: usize) -> RowRates {
        match self.stabilizer {
            Stabilizer::Smc { .. } => RowRates {
                z: state.z[l],
                rate: self.k[0].z.get(l).copied().unwrap_or(0.0),
                step_rate: 0.0,
            },
            Stabilizer::Baumgarte { .. } => {
                let z = self.ws.z_alg[l];
                let slope = self
                    .z_step
                    .get(l)
                    .map(|&start| (z - start) / self.dt.as_secs_f64());
                match (slope, &self.links[l].kind) {
                    (Some(rate), RowKind::Align(_)) => RowRates {
                        z,
                        rate,
                        step_rate: 0.0,
                    },
                    (Some(step_rate), _) => RowRates {
                        z,
                        rate: 0.0,
                        step_rate,
                    },
                    (None, _) => RowRates {
                        z,
                        rate: 0.0,
                        step_rate: 0.0,
                    },
                }
            }
        }
    }

    /// After the evaluation that begins a step: keeps the multipliers, the start of the
    /// slope [`System::multiplier_and_rate`] sends (when [`System::keeps_slopes`]).
    ///
    /// Why: a border force travels with its rate, `d(c z)/dt = ċ z + c ż` per row. A
    /// hinge's alignment rows turn with the body they are fixed in (a rotor's at its
    /// spin), and their multipliers change to keep the joint's summed couple steady:
    /// without `ż` only the turning was extrapolated, and a spinning rotor on a border
    /// hinge was driven by a couple turning at its spin rate (its angular momentum off
    /// by 30 % at 20 ms with no latency, where holding the couple kept it to 1.5 %).
    /// Every other row's force held over RK4's stages made a partitioned run first
    /// order; its slope is carried one step.
    pub(crate) fn note_step_multipliers(&mut self) {
        if self.keeps_slopes {
            self.z_step.clone_from(&self.ws.z_alg);
        }
    }

    /// Body `b`'s reaction stiffness as this system's rows give it now (world frame
    /// turned into `b`'s frame, `state`'s orientation), for a node that ghosts `b`:
    /// `None` where no row holds `b` (see [`JsSolver::reaction_stiffness`]).
    pub fn reaction_of(&self, state: &super::State, b: usize) -> Option<Matrix6<f64>> {
        let k = self.solver.reaction_stiffness(&self.geo, &self.mass, b)?;
        let r = six_rotation(&state.q[b]);
        Some(r.transpose() * k * r)
    }

    /// `K M_b⁻¹ F` for the load `(f, τ)` on body `b` (`k` in `b`'s frame, as
    /// [`System::reaction_of`] gives it): minus what this system's rows add to `b`'s load
    /// in answer to it.
    pub fn reaction_answer(
        &self,
        state: &super::State,
        b: usize,
        k: &Matrix6<f64>,
        (f, torque): (Vector3<f64>, Vector3<f64>),
    ) -> (Vector3<f64>, Vector3<f64>) {
        let r = six_rotation(&state.q[b]);
        let k = r * k * r.transpose();
        let a = f * self.mass.inv_mass[b];
        let alpha = self.mass.inv_inertia[b] * torque;
        let x = k * nalgebra::Vector6::new(a.x, a.y, a.z, alpha.x, alpha.y, alpha.z);
        (
            Vector3::new(x[0], x[1], x[2]),
            Vector3::new(x[3], x[4], x[5]),
        )
    }

    /// The impulse of this system's rows on body `b` over the last step [N·s], where `b`
    /// answers them with a whole inverse mass (a ghost carrying its owner's reaction),
    /// whose momentum change then does not measure it.
    pub fn row_impulse(&self, b: usize) -> Option<Vector3<f64>> {
        self.mass.compliance(b)?;
        self.row_impulse.get(b).copied()
    }

    /// Adds the last evaluation's row forces, weighted by `weight` [s], to the step's
    /// row impulses; `start` begins a step's sum.
    pub(crate) fn book_row_forces(&mut self, weight: f64, start: bool) {
        if self.row_force.is_empty() {
            self.row_impulse.clear();
            return;
        }
        self.row_impulse
            .resize(self.row_force.len(), Vector3::zeros());
        for (i, f) in self.row_impulse.iter_mut().zip(&self.row_force) {
            if start {
                *i = Vector3::zeros();
            }
            *i += f * weight;
        }
    }

    /// Sets ghost `b`'s reaction stiffness (body frame; `None`: its owner's rows do not
    /// hold it). From then on the ghost answers the loads of this system's rows as its
    /// owner's subsystem does, `W = M⁻¹ − M⁻¹ K M⁻¹` in place of its own `M⁻¹`.
    pub fn set_reaction(&mut self, b: usize, k: Option<Matrix6<f64>>) {
        if self.reaction.len() <= b {
            if k.is_none() {
                return;
            }
            self.reaction.resize(self.mass.inv_mass.len(), None);
        }
        self.reaction[b] = k;
    }

    /// The force [N] and torque [N·m] the springs put on body `body` in `state`.
    pub fn spring_load_on(
        &self,
        state: &super::State,
        body: usize,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let mut load = (Vector3::zeros(), Vector3::zeros());
        for s in &self.springs {
            if s.a == body || s.b == Some(body) {
                let [fa, ta, fb, tb] = super::spring::loads(s, state, self.rigid);
                if s.a == body {
                    load.0 += fa;
                    load.1 += ta;
                } else {
                    load.0 += fb;
                    load.1 += tb;
                }
            }
        }
        load
    }

    /// Iterations used by the last multiplier solve (0 for Cholesky).
    pub fn last_solver_iterations(&self) -> usize {
        self.solver.last_iterations()
    }
}

/// The 6 × 6 rotation `diag(R, R)` of a body frame (force and torque, or acceleration
/// and angular acceleration, turned alike).
pub(crate) fn six_rotation(q: &nalgebra::Quaternion<f64>) -> Matrix6<f64> {
    let r = *nalgebra::UnitQuaternion::new_normalize(*q)
        .to_rotation_matrix()
        .matrix();
    let mut six = Matrix6::zeros();
    six.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    six.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    six
}
