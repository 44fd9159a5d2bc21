//! The static model (masses, inertias, links, forces) and the per-step workspace.

use nalgebra::{Matrix3, Vector3};

use super::solver::{Geometry, JsSolver, MassData};
use super::state::Rates;
use crate::kernel::SimTime;
use crate::scenario::model::{BodyModel, ForceSpec, Integrator, Scenario, Stabilizer};

/// One distance link, with body indices resolved.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Link {
    /// Index of body `a`.
    pub a: usize,
    /// Index of body `b`.
    pub b: usize,
    /// Length L [m].
    pub length: f64,
    /// Anchor on `a` in the body frame [m].
    pub anchor_a: Vector3<f64>,
    /// Anchor on `b` in the body frame [m].
    pub anchor_b: Vector3<f64>,
}

/// A multi-body system ready to integrate: model data, stabilizer, integrator and all
/// scratch memory (no allocation happens inside a step).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct System {
    pub(crate) rigid: bool,
    pub(crate) inertia: Vec<Vector3<f64>>,
    pub(crate) links: Vec<Link>,
    pub(crate) forces: Vec<ForceSpec>,
    pub(crate) stabilizer: Stabilizer,
    /// Per-link SMC surface parameter μ [s] where it differs from the stabilizer's
    /// (empty: every link uses the stabilizer's μ).
    pub(crate) link_mu: Vec<f64>,
    pub(crate) integrator: Integrator,
    pub(crate) dt: SimTime,
    /// Extra external force per body [N], held constant over a step (used for border
    /// forces received from other partitions; zero on a monolithic run).
    pub extra_force: Vec<Vector3<f64>>,
    /// Extra external torque per body [N·m] (rigid path only; empty on point masses).
    pub extra_torque: Vec<Vector3<f64>>,
    pub(crate) mass: MassData,
    pub(crate) geo: Geometry,
    pub(crate) ws: Workspace,
    pub(crate) solver: JsSolver,
    pub(crate) k: [Rates; 4],
    pub(crate) stage: super::state::State,
}

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
    /// World-frame anchor offsets `R r_a`, `R r_b` per link [m] (rigid path only).
    pub ra: Vec<Vector3<f64>>,
    /// See `ra`.
    pub rb: Vec<Vector3<f64>>,
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
        let links: Vec<Link> = scenario
            .links
            .iter()
            .map(|l| Link {
                a: l.a,
                b: l.b,
                length: l.length,
                anchor_a: l.anchor_a,
                anchor_b: l.anchor_b,
            })
            .collect();
        let inv_mass: Vec<f64> = scenario.bodies.iter().map(|b| 1.0 / b.mass).collect();
        let inertia = scenario.bodies.iter().map(|b| b.inertia).collect();
        let nb = inv_mass.len();
        let nl = links.len();
        let nr = if rigid { nb } else { 0 };
        let nlr = if rigid { nl } else { 0 };
        let v3 = Vector3::zeros;
        let geo = Geometry {
            ends: links.iter().map(|l| (l.a, l.b)).collect(),
            n: vec![v3(); nl],
            ca: vec![v3(); nlr],
            cb: vec![v3(); nlr],
        };
        let mass = MassData {
            inv_mass,
            inv_inertia: vec![Matrix3::zeros(); nr],
        };
        let solver = JsSolver::new(scenario.solver, nb, &geo.ends);
        let shape = super::state::State {
            p: vec![v3(); nb],
            v: vec![v3(); nb],
            q: vec![nalgebra::Quaternion::identity(); nr],
            omega: vec![v3(); nr],
            z: vec![0.0; nl],
        };
        let k = std::array::from_fn(|_| Rates::zeros_like(&shape));
        System {
            rigid,
            inertia,
            links,
            forces: scenario.forces.clone(),
            stabilizer: scenario.stabilizer,
            link_mu: Vec::new(),
            integrator: scenario.integrator,
            dt: scenario.dt,
            extra_force: vec![v3(); nb],
            extra_torque: vec![v3(); nr],
            mass,
            geo,
            ws: Workspace {
                force: vec![v3(); nb],
                torque: vec![v3(); nr],
                acc: vec![v3(); nb],
                alpha: vec![v3(); nr],
                inertia_world: vec![Matrix3::zeros(); nr],
                ra: vec![v3(); nlr],
                rb: vec![v3(); nlr],
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
            stage: shape,
        }
    }

    /// Number of bodies.
    pub fn body_count(&self) -> usize {
        self.mass.inv_mass.len()
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

    /// The integration step.
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
    /// the step that ended at `state`). Under Baumgarte `z` is algebraic and has no rate
    /// of its own: only the `ṅ z` part is returned. One pass for both, as a message
    /// needs both.
    pub fn link_load_and_rate_on(
        &self,
        state: &super::State,
        l: usize,
        body: usize,
    ) -> [Vector3<f64>; 4] {
        let link = &self.links[l];
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
        let (z, z_dot) = match self.stabilizer {
            Stabilizer::Smc { .. } => (state.z[l], self.k[0].z.get(l).copied().unwrap_or(0.0)),
            Stabilizer::Baumgarte { .. } => (self.ws.z_alg[l], 0.0),
        };
        let f_dot = n_dot * z + n * z_dot;
        let f = n * z;
        if body == link.a {
            [
                f,
                ra.cross(&n) * z,
                f_dot,
                wa.cross(&ra).cross(&f) + ra.cross(&f_dot),
            ]
        } else {
            [
                -n * z,
                -rb.cross(&n) * z,
                -f_dot,
                -(wb.cross(&rb).cross(&f) + rb.cross(&f_dot)),
            ]
        }
    }

    /// Iterations used by the last multiplier solve (0 for Cholesky).
    pub fn last_solver_iterations(&self) -> usize {
        self.solver.last_iterations()
    }
}
