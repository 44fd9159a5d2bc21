//! The ODE state `(x, v, z)` and its time derivative.
//!
//! Struct-of-arrays, indexed by body index (file order) and link index. On the
//! point-mass path the orientation and angular-velocity arrays are empty, so a scene
//! without rotation neither stores nor integrates it.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::scenario::model::{BodyModel, Scenario};

/// Positions, orientations, velocities of every body and the link multipliers.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct State {
    /// Centre-of-mass positions [m].
    pub p: Vec<Vector3<f64>>,
    /// Linear velocities [m/s].
    pub v: Vec<Vector3<f64>>,
    /// Orientations (body → world), unit quaternions; empty on the point-mass path.
    pub q: Vec<Quaternion<f64>>,
    /// Angular velocities in the world frame [rad/s]; empty on the point-mass path.
    pub omega: Vec<Vector3<f64>>,
    /// Link multipliers z [N]; the force on body `a` is `n z` with `n` pointing from
    /// `b`'s anchor to `a`'s, so a negative `z` pulls the bodies together.
    pub z: Vec<f64>,
}

/// Time derivative of a [`State`] (same layout).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Rates {
    /// ṗ = v [m/s].
    pub p: Vec<Vector3<f64>>,
    /// v̇ = a [m/s²].
    pub v: Vec<Vector3<f64>>,
    /// q̇ = ½ (0, ω) ⊗ q [1/s].
    pub q: Vec<Quaternion<f64>>,
    /// ω̇ [rad/s²].
    pub omega: Vec<Vector3<f64>>,
    /// ż [N/s] (zero under Baumgarte, whose z is algebraic).
    pub z: Vec<f64>,
}

impl State {
    /// The initial state of a scenario: bodies as given, `z = 0` (method §3).
    pub fn initial(scenario: &Scenario) -> State {
        let rigid = scenario.body_model == BodyModel::Rigid;
        let bodies = &scenario.bodies;
        State {
            p: bodies.iter().map(|b| b.position).collect(),
            v: bodies.iter().map(|b| b.velocity).collect(),
            q: if rigid {
                bodies.iter().map(|b| *b.orientation.quaternion()).collect()
            } else {
                Vec::new()
            },
            omega: if rigid {
                bodies.iter().map(|b| b.angular_velocity).collect()
            } else {
                Vec::new()
            },
            z: vec![0.0; scenario.links.len()],
        }
    }

    /// A state with no bodies and no links (a placeholder for moved-out scratch).
    pub fn empty() -> State {
        State {
            p: Vec::new(),
            v: Vec::new(),
            q: Vec::new(),
            omega: Vec::new(),
            z: Vec::new(),
        }
    }

    /// `self += h · rates`, in place.
    pub fn add_scaled(&mut self, rates: &Rates, h: f64) {
        for (x, r) in self.p.iter_mut().zip(&rates.p) {
            *x += r * h;
        }
        for (x, r) in self.v.iter_mut().zip(&rates.v) {
            *x += r * h;
        }
        for (x, r) in self.omega.iter_mut().zip(&rates.omega) {
            *x += r * h;
        }
        for (x, r) in self.q.iter_mut().zip(&rates.q) {
            *x += r * h;
        }
        for (x, r) in self.z.iter_mut().zip(&rates.z) {
            *x += r * h;
        }
    }

    /// Number of bodies.
    pub fn bodies(&self) -> usize {
        self.p.len()
    }

    /// Whether orientations are part of the state (rigid-body path).
    pub fn is_rigid(&self) -> bool {
        !self.q.is_empty()
    }

    /// `self + h · rates` into `out` (which must have the same shape).
    pub fn add_scaled_into(&self, rates: &Rates, h: f64, out: &mut State) {
        axpy_v3(&self.p, &rates.p, h, &mut out.p);
        axpy_v3(&self.v, &rates.v, h, &mut out.v);
        axpy_v3(&self.omega, &rates.omega, h, &mut out.omega);
        for ((o, x), r) in out.q.iter_mut().zip(&self.q).zip(&rates.q) {
            *o = x + r * h;
        }
        for ((o, x), r) in out.z.iter_mut().zip(&self.z).zip(&rates.z) {
            *o = x + h * r;
        }
    }

    /// Re-normalizes every orientation quaternion (after an integration step).
    pub fn normalize_orientations(&mut self) {
        for q in &mut self.q {
            *q = *UnitQuaternion::new_normalize(*q).quaternion();
        }
    }

    /// Whether every value of the state is finite.
    pub fn is_finite(&self) -> bool {
        self.p
            .iter()
            .chain(&self.v)
            .chain(&self.omega)
            .all(|x| x.iter().all(|c| c.is_finite()))
            && self
                .q
                .iter()
                .all(|q| q.coords.iter().all(|c| c.is_finite()))
            && self.z.iter().all(|z| z.is_finite())
    }
}

impl Rates {
    /// Zero rates shaped like `state`.
    pub fn zeros_like(state: &State) -> Rates {
        Rates {
            p: vec![Vector3::zeros(); state.p.len()],
            v: vec![Vector3::zeros(); state.v.len()],
            q: vec![Quaternion::new(0.0, 0.0, 0.0, 0.0); state.q.len()],
            omega: vec![Vector3::zeros(); state.omega.len()],
            z: vec![0.0; state.z.len()],
        }
    }

    /// `self = a · self + b · other` (used to accumulate the RK4 combination).
    pub fn combine(&mut self, a: f64, other: &Rates, b: f64) {
        for (x, y) in self.p.iter_mut().zip(&other.p) {
            *x = *x * a + y * b;
        }
        for (x, y) in self.v.iter_mut().zip(&other.v) {
            *x = *x * a + y * b;
        }
        for (x, y) in self.omega.iter_mut().zip(&other.omega) {
            *x = *x * a + y * b;
        }
        for (x, y) in self.q.iter_mut().zip(&other.q) {
            *x = *x * a + y * b;
        }
        for (x, y) in self.z.iter_mut().zip(&other.z) {
            *x = *x * a + y * b;
        }
    }
}

fn axpy_v3(x: &[Vector3<f64>], r: &[Vector3<f64>], h: f64, out: &mut [Vector3<f64>]) {
    for ((o, x), r) in out.iter_mut().zip(x).zip(r) {
        *o = x + r * h;
    }
}
