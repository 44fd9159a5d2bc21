//! The rate function of the `(x, v, z)` ODE (method §2).
//!
//! Stages, in this order because each needs the previous one's results:
//! 1. body frames: world inertia `R I Rᵀ` and its inverse (rigid path);
//! 2. body loads: external forces at `t`, springs, the held extra forces, gyroscopic
//!    torque `−ω × (I ω)`;
//! 3. link kinematics: `w = |P_a − P_b| − L`, `n`, `ẇ = J v`, `J̇ v`; under SMC the
//!    current multipliers' forces `Jᵀ z` are added to the loads;
//! 4. accelerations `M⁻¹ (loads)` and `ẅ = J a + J̇ v`;
//! 5. multiplier law: SMC solves `μ² J M⁻¹ Jᵀ ż = −(2μẅ + ẇ) − K sat(s/ε)` with
//!    `s = μ²ẅ + 2μẇ + w`; Baumgarte solves `J M⁻¹ Jᵀ z = −ẅ₀ − 2αẇ − β²w` (ẅ₀ without
//!    link forces) and adds `M⁻¹ Jᵀ z` to the accelerations.

use nalgebra::{Matrix3, Matrix6, Quaternion, UnitQuaternion, Vector3, Vector6};

use super::solver::SolveError;
use super::state::{Rates, State};
use super::system::{Link, System};
use crate::kernel::SimTime;
use crate::scenario::model::{LoadAt, RowKind, Stabilizer};

/// Why a rate evaluation failed.
#[derive(Debug, Clone, PartialEq)]
pub enum EvalError {
    /// A link's kinematics became non-finite (0-based link index).
    NonFinite {
        /// Link index.
        link: usize,
    },
    /// The multiplier solve failed.
    Solve(SolveError),
    /// A body's load or inertia overflowed `f64` (0-based body index, local to the
    /// system): the solve then fails on non-finite entries, not on the geometry.
    NonFiniteBody {
        /// Body index.
        body: usize,
        /// The quantity: `force`, `torque` or `inertia`.
        what: &'static str,
    },
}

/// `sat(y)`: `y` inside the boundary layer `|y| ≤ 1`, `sign(y)` outside.
pub fn sat(y: f64) -> f64 {
    y.clamp(-1.0, 1.0)
}

impl System {
    /// Evaluates the rates of `state` at time `t` into `out`.
    pub fn rates(&mut self, t: SimTime, state: &State, out: &mut Rates) -> Result<(), EvalError> {
        self.rates_to_rhs(t, state)?;
        self.solver
            .solve(&self.geo, &self.mass, &self.ws.rhs, &mut self.ws.sol)
            .map_err(|e| self.solve_failure(e))?;
        self.check_cg_budget().map_err(EvalError::Solve)?;
        self.rates_from_solution(state, out);
        Ok(())
    }

    /// Stages 1–4 and the right-hand side of the multiplier solve (stage 5 up to the
    /// solve, which reads `ws.rhs` and writes `ws.sol`).
    pub(crate) fn rates_to_rhs(&mut self, t: SimTime, state: &State) -> Result<(), EvalError> {
        self.body_frames(state);
        self.body_loads(t, state);
        let smc = matches!(self.stabilizer, Stabilizer::Smc { .. });
        self.link_kinematics(state, smc)?;
        self.accelerations();
        self.constraint_accelerations();
        match self.stabilizer {
            Stabilizer::Smc { mu, k, epsilon } => {
                let mu2 = mu * mu;
                for l in 0..self.links.len() {
                    let (w, wd, wdd) = (self.ws.w[l], self.ws.wd[l], self.ws.wdd[l]);
                    let s = mu2 * wdd + 2.0 * mu * wd + w;
                    let alpha_hat = 2.0 * mu * wdd + wd;
                    self.ws.rhs[l] = (-alpha_hat - k * sat(s / epsilon)) / mu2;
                }
                // Links with their own μ (border links of a delayed coupling): the same
                // law with that μ; every row of `μ² J M⁻¹ Jᵀ ż = …` is divided by its own
                // μ², so the matrix stays `J M⁻¹ Jᵀ`.
                for (l, &mu) in self.link_mu.iter().enumerate() {
                    let mu2 = mu * mu;
                    let (w, wd, wdd) = (self.ws.w[l], self.ws.wd[l], self.ws.wdd[l]);
                    let s = mu2 * wdd + 2.0 * mu * wd + w;
                    let alpha_hat = 2.0 * mu * wdd + wd;
                    self.ws.rhs[l] = (-alpha_hat - k * sat(s / epsilon)) / mu2;
                }
            }
            Stabilizer::Baumgarte { alpha, beta } => {
                for l in 0..self.links.len() {
                    let (w, wd, wdd) = (self.ws.w[l], self.ws.wd[l], self.ws.wdd[l]);
                    self.ws.rhs[l] = -wdd - 2.0 * alpha * wd - beta * beta * w;
                }
            }
        }
        Ok(())
    }

    /// What a failed multiplier solve of the last evaluation means: a body whose load or
    /// inertia overflowed (read from the evaluation's workspace, so the happy path pays
    /// nothing), else the solve's own error.
    pub(crate) fn solve_failure(&self, e: SolveError) -> EvalError {
        if matches!(e, SolveError::CgBudget { .. }) {
            return EvalError::Solve(e);
        }
        let finite = |x: &[f64]| x.iter().all(|v| v.is_finite());
        let nb = self.extra_force.len();
        for i in 0..nb {
            let what = if !finite(self.ws.force[i].as_slice()) {
                "force"
            } else if self.ws.torque.get(i).is_some_and(|t| !finite(t.as_slice())) {
                "torque"
            } else if self
                .mass
                .inv_inertia
                .get(i)
                .is_some_and(|m| !finite(m.as_slice()))
            {
                "inertia"
            } else {
                continue;
            };
            return EvalError::NonFiniteBody { body: i, what };
        }
        EvalError::Solve(e)
    }

    /// The rest of stage 5 once `ws.sol` holds the multipliers' solution, and the rates.
    pub(crate) fn rates_from_solution(&mut self, state: &State, out: &mut Rates) {
        match self.stabilizer {
            Stabilizer::Smc { .. } => out.z.copy_from_slice(&self.ws.sol),
            Stabilizer::Baumgarte { .. } => {
                self.ws.z_alg.copy_from_slice(&self.ws.sol);
                self.add_multiplier_accelerations();
                out.z.fill(0.0);
            }
        }
        let nb = state.p.len();
        out.p.copy_from_slice(&state.v);
        out.v.copy_from_slice(&self.ws.acc[..nb]);
        if self.rigid {
            out.omega.copy_from_slice(&self.ws.alpha[..nb]);
            for ((dq, q), w) in out.q.iter_mut().zip(&state.q).zip(&state.omega) {
                *dq = Quaternion::from_imag(*w) * q * 0.5;
            }
        }
    }

    /// Stage 1: world inertia and its inverse per body.
    fn body_frames(&mut self, state: &State) {
        if !self.rigid {
            return;
        }
        for i in 0..state.q.len() {
            let r = *UnitQuaternion::new_normalize(state.q[i])
                .to_rotation_matrix()
                .matrix();
            let d = self.inertia[i];
            let inv = if self.mass.inv_mass[i] == 0.0 {
                Vector3::zeros()
            } else {
                d.map(|x| 1.0 / x)
            };
            self.ws.inertia_world[i] = r * Matrix3::from_diagonal(&d) * r.transpose();
            self.mass.inv_inertia[i] = r * Matrix3::from_diagonal(&inv) * r.transpose();
        }
        // A ghost carrying its owner's reaction: `W = M⁻¹ − M⁻¹ K M⁻¹`, world frame.
        if self.reaction.iter().any(Option::is_some) {
            self.mass.compliance.resize(self.mass.inv_mass.len(), None);
            for (i, k) in self.reaction.iter().enumerate() {
                self.mass.compliance[i] = k.as_ref().map(|k| {
                    let rot = super::system::six_rotation(&state.q[i]);
                    let mut minv = Matrix6::zeros();
                    minv.fixed_view_mut::<3, 3>(0, 0)
                        .copy_from(&(Matrix3::identity() * self.mass.inv_mass[i]));
                    minv.fixed_view_mut::<3, 3>(3, 3)
                        .copy_from(&self.mass.inv_inertia[i]);
                    let k = rot * k * rot.transpose();
                    minv - minv * k * minv
                });
            }
        } else {
            self.mass.compliance.clear();
        }
    }

    /// Stage 2: external, held and gyroscopic loads.
    fn body_loads(&mut self, t: SimTime, state: &State) {
        let nb = self.extra_force.len();
        self.ws.force[..nb].copy_from_slice(&self.extra_force);
        // The world's slot (rows held to the world), if any: nothing acts on it.
        self.ws.force[nb..].fill(Vector3::zeros());
        self.ws.torque[state.omega.len()..].fill(Vector3::zeros());
        if self.rigid {
            for i in 0..state.omega.len() {
                let w = state.omega[i];
                self.ws.torque[i] = self.extra_torque[i] - w.cross(&(self.ws.inertia_world[i] * w));
            }
        }
        for f in &self.forces {
            match f.applied {
                LoadAt::Centre => self.ws.force[f.body] += f.at(t),
                // A torque on point masses: validation admits only a zero one.
                LoadAt::Torque if !self.rigid => {}
                // Off the centre and torques: validation chose rigid bodies.
                _ => {
                    let rotation = UnitQuaternion::new_normalize(state.q[f.body]);
                    let (force, torque) = f.load(t, &rotation);
                    self.ws.force[f.body] += force;
                    self.ws.torque[f.body] += torque;
                }
            }
        }
        for s in &self.springs {
            let [fa, ta, fb, tb] = super::spring::loads(s, state, self.rigid);
            self.ws.force[s.a] += fa;
            if self.rigid {
                self.ws.torque[s.a] += ta;
            }
            if let Some(b) = s.b {
                self.ws.force[b] += fb;
                if self.rigid {
                    self.ws.torque[b] += tb;
                }
            }
        }
        for (f, input) in self.ws.force.iter_mut().zip(&self.input_force) {
            *f += input;
        }
        // Later stages of a step carry the extra loads by their rates (the first stage,
        // at their own time, adds nothing, so single-stage schemes keep their bits).
        let rate = &self.extra_rate;
        if t != rate.from && !rate.force.is_empty() {
            let s = SimTime(t.0.saturating_sub(rate.from.0)).as_secs_f64();
            for (f, r) in self.ws.force.iter_mut().zip(&rate.force) {
                *f += r * s;
            }
            for (tq, r) in self.ws.torque.iter_mut().zip(&rate.torque) {
                *tq += r * s;
            }
        }
    }

    /// Stage 3: per-row kinematics (and, under SMC, the current multipliers' forces).
    fn link_kinematics(&mut self, state: &State, smc: bool) -> Result<(), EvalError> {
        for l in 0..self.links.len() {
            let (a, b) = self.geo.ends[l];
            let row = row_kinematics(&self.links[l], state, self.rigid);
            if !row.finite() {
                return Err(EvalError::NonFinite { link: l });
            }
            if self.rigid {
                self.geo.ca[l] = row.ca;
                self.geo.cb[l] = row.cb;
            }
            self.geo.n[l] = row.n;
            self.ws.w[l] = row.w;
            self.ws.wd[l] = row.wd;
            self.ws.jdv[l] = row.jdv;
            if smc {
                let z = state.z[l];
                self.ws.force[a] += row.n * z;
                self.ws.force[b] -= row.n * z;
                if self.rigid {
                    self.ws.torque[a] += row.ca * z;
                    self.ws.torque[b] -= row.cb * z;
                }
            }
        }
        Ok(())
    }

    /// Stage 4a: `a = M⁻¹ F` (plus gravity on every movable body), `α = I⁻¹ τ`.
    fn accelerations(&mut self) {
        for i in 0..self.ws.acc.len() {
            self.ws.acc[i] = self.ws.force[i] * self.mass.inv_mass[i];
        }
        // Gravity as an acceleration, not as a force `m g`: a body held immovable
        // (`1/m = 0`) stays put, and every copy of a body (its owner's, a ghost
        // integrated on another node) falls alike without gravity crossing the network.
        if let Some(g) = self.gravity {
            for (a, &inv) in self.ws.acc.iter_mut().zip(&self.mass.inv_mass) {
                if inv != 0.0 {
                    *a += g;
                }
            }
        }
        for i in 0..self.ws.alpha.len() {
            self.ws.alpha[i] = self.mass.inv_inertia[i] * self.ws.torque[i];
        }
    }

    /// Stage 4b: `ẅ = J a + J̇ v` per link.
    fn constraint_accelerations(&mut self) {
        for (l, &(a, b)) in self.geo.ends.iter().enumerate() {
            let mut wdd = self.geo.n[l].dot(&(self.ws.acc[a] - self.ws.acc[b])) + self.ws.jdv[l];
            if self.rigid {
                wdd +=
                    self.geo.ca[l].dot(&self.ws.alpha[a]) - self.geo.cb[l].dot(&self.ws.alpha[b]);
            }
            self.ws.wdd[l] = wdd;
        }
    }

    /// Baumgarte: adds `M⁻¹ Jᵀ z` to the accelerations.
    fn add_multiplier_accelerations(&mut self) {
        let whole = !self.mass.compliance.is_empty();
        self.row_force.clear();
        if whole {
            self.row_force
                .resize(self.mass.inv_mass.len(), Vector3::zeros());
        }
        for (l, &(a, b)) in self.geo.ends.iter().enumerate() {
            let z = self.ws.z_alg[l];
            let f = self.geo.n[l] * z;
            if whole && self.rigid {
                let (ca, cb) = (self.geo.ca[l] * z, self.geo.cb[l] * z);
                for (body, f, c) in [(a, f, ca), (b, -f, -cb)] {
                    if let Some(w) = self.mass.compliance(body) {
                        self.row_force[body] += f;
                        let r = w * Vector6::new(f.x, f.y, f.z, c.x, c.y, c.z);
                        self.ws.acc[body] += Vector3::new(r[0], r[1], r[2]);
                        self.ws.alpha[body] += Vector3::new(r[3], r[4], r[5]);
                    } else {
                        self.ws.acc[body] += f * self.mass.inv_mass[body];
                        self.ws.alpha[body] += self.mass.inv_inertia[body] * c;
                    }
                }
                continue;
            }
            self.ws.acc[a] += f * self.mass.inv_mass[a];
            self.ws.acc[b] -= f * self.mass.inv_mass[b];
            if self.rigid {
                let (ca, cb) = (self.geo.ca[l] * z, self.geo.cb[l] * z);
                self.ws.alpha[a] += self.mass.inv_inertia[a] * ca;
                self.ws.alpha[b] -= self.mass.inv_inertia[b] * cb;
            }
        }
    }
}

/// One constraint row's value and Jacobian at a state: `J = [nᵀ, c_aᵀ]` on body `a`,
/// `[−nᵀ, −c_bᵀ]` on body `b` (or the world), `w`, `ẇ = J v` and `J̇ v`.
pub(crate) struct RowKinematics {
    pub w: f64,
    pub wd: f64,
    pub jdv: f64,
    pub n: Vector3<f64>,
    /// `c_a`, `c_b` (zero on point masses, which carry no angular Jacobian).
    pub ca: Vector3<f64>,
    pub cb: Vector3<f64>,
    /// World-frame anchor offsets `R r_a`, `R r_b` of a distance or offset row (zero on
    /// point masses, for the world's side and for an alignment row).
    pub ra: Vector3<f64>,
    pub rb: Vector3<f64>,
    /// An alignment row's `ċ` with the bodies' ω held (zero for the other rows).
    pub c_dot: Vector3<f64>,
    /// A slide row's `ṅ` (its normal turns with `b`) and `ċ_b` (zero for the other
    /// rows).
    pub n_dot: Vector3<f64>,
    pub cb_dot: Vector3<f64>,
    /// For a distance row: the anchors' distance `d` (1 for the other rows).
    pub d: f64,
}

impl RowKinematics {
    fn finite(&self) -> bool {
        self.d > 0.0 && self.jdv.is_finite() && self.wd.is_finite()
    }
}

/// The kinematics of `link` in `state` (see [`RowKind`]). Only what the row's kind and
/// the body model need is computed: this runs for every row at every rate evaluation.
pub(crate) fn row_kinematics(link: &Link, state: &State, rigid: bool) -> RowKinematics {
    let (a, b) = (link.a, link.b);
    let zero = Vector3::zeros();
    let rotation = |i: usize| UnitQuaternion::new_normalize(state.q[i]);
    if let RowKind::Align(axes) = &link.kind {
        // Joints run on rigid bodies only (validation chooses them).
        let uw = rotation(a) * axes.u;
        let (vw, wb) = if link.world {
            (axes.v, zero)
        } else {
            (rotation(b) * axes.v, state.omega[b])
        };
        let wa = state.omega[a];
        let c = uw.cross(&vw);
        let rel = wa - wb;
        // d/dt of c with the bodies' ω held: what J̇ v adds.
        let c_dot = wa.cross(&uw).cross(&vw) + uw.cross(&wb.cross(&vw));
        return RowKinematics {
            w: uw.dot(&vw),
            wd: rel.dot(&c),
            jdv: rel.dot(&c_dot),
            n: zero,
            ca: c,
            cb: c,
            ra: zero,
            rb: zero,
            c_dot,
            n_dot: zero,
            cb_dot: zero,
            d: 1.0,
        };
    }
    // Side b: a body, or the world's fixed point.
    let (pb, vb) = if link.world {
        (link.anchor_b, zero)
    } else {
        (state.p[b], state.v[b])
    };
    // In this order of operations (centres, then the anchors' offsets): a distance
    // link's bits as they were before joints existed.
    let (mut delta, mut u) = (state.p[a] - pb, state.v[a] - vb);
    let (mut ra, mut rb, mut spin) = (zero, zero, zero);
    if rigid {
        let wa = state.omega[a];
        ra = rotation(a) * link.anchor_a;
        let wb = if link.world {
            zero
        } else {
            rb = rotation(b) * link.anchor_b;
            state.omega[b]
        };
        delta += ra - rb;
        u += wa.cross(&ra) - wb.cross(&rb);
        // The anchors' centripetal accelerations' difference.
        spin = wa.cross(&wa.cross(&ra)) - wb.cross(&wb.cross(&rb));
    }
    // A slide row's normal turns with `b` (a world row's stays): `ṅ = ω_b × n`, and
    // `w = n · d` adds `ṅ · d` to `ẇ` and `n̈ · d + 2 ṅ · ḋ` to `J̇ v`.
    let (mut slide_cb, mut n_dot, mut cb_dot) = (None, zero, zero);
    let (w, wd, mut jdv, n, d) = match &link.kind {
        RowKind::Offset(k) => {
            let k = usize::from(*k);
            let mut n = zero;
            n[k] = 1.0;
            (delta[k], u[k], spin[k], n, 1.0)
        }
        RowKind::Slide(normal) => {
            let (n, wb) = if link.world {
                (**normal, zero)
            } else {
                (rotation(b) * **normal, state.omega[b])
            };
            n_dot = wb.cross(&n);
            // `b`'s angular Jacobian: the force acts at `a`'s anchor, `R_b r_b + d` from
            // `b`'s centre.
            slide_cb = Some((rb + delta).cross(&n));
            cb_dot = (wb.cross(&rb) + u).cross(&n) + (rb + delta).cross(&n_dot);
            (
                n.dot(&delta),
                n_dot.dot(&delta) + n.dot(&u),
                wb.cross(&n_dot).dot(&delta) + 2.0 * n_dot.dot(&u) + n.dot(&spin),
                n,
                1.0,
            )
        }
        _ => {
            let d = delta.norm();
            let n = delta / d;
            let wd = n.dot(&u);
            (d - link.length, wd, (u.norm_squared() - wd * wd) / d, n, d)
        }
    };
    let (mut ca, mut cb) = (zero, zero);
    if rigid {
        if matches!(link.kind, RowKind::Distance) {
            jdv += n.dot(&spin);
        }
        ca = ra.cross(&n);
        cb = slide_cb.unwrap_or_else(|| rb.cross(&n));
    }
    RowKinematics {
        w,
        wd,
        jdv,
        n,
        ca,
        cb,
        ra,
        rb,
        c_dot: zero,
        n_dot,
        cb_dot,
        d,
    }
}
