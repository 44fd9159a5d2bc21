//! Spring-damper loads (`model.springs`): force elements, evaluated from the state at
//! every rate evaluation like an external force.

use nalgebra::{UnitQuaternion, Vector3};

use super::state::State;
use crate::scenario::model::SpringSpec;

/// Force and torque on `a`, then on `b` (zero for a world point), of spring `s` in
/// `state`: `F_a = −(k (d − L) + c ḋ) n` at `a`'s anchor, `F_b = −F_a` at `b`'s, with
/// `d` the anchors' distance, `ḋ` its rate and `n` the unit vector from `b`'s anchor to
/// `a`'s. Anchors off the centre exist only on the rigid path (validation).
pub(crate) fn loads(s: &SpringSpec, state: &State, rigid: bool) -> [Vector3<f64>; 4] {
    let (pa, va, ra) = anchor(state, s.a, &s.anchor_a, rigid);
    let (pb, vb, rb) = match s.b {
        Some(b) => anchor(state, b, &s.anchor_b, rigid),
        None => (s.anchor_b, Vector3::zeros(), Vector3::zeros()),
    };
    let delta = pa - pb;
    let d = delta.norm();
    // Anchors on one point: no direction, no force (a zero-length spring passing
    // through its rest point).
    if d == 0.0 {
        return [Vector3::zeros(); 4];
    }
    let n = delta / d;
    let rate = n.dot(&(va - vb));
    let f = -n * (s.stiffness * (d - s.length) + s.damping * rate);
    [f, ra.cross(&f), -f, rb.cross(&-f)]
}

/// The spring's potential energy `k (d − L)² / 2` [J] in `state`.
pub fn energy(s: &SpringSpec, state: &State, rigid: bool) -> f64 {
    let pa = anchor(state, s.a, &s.anchor_a, rigid).0;
    let pb =
        s.b.map_or(s.anchor_b, |b| anchor(state, b, &s.anchor_b, rigid).0);
    let stretch = (pa - pb).norm() - s.length;
    0.5 * s.stiffness * stretch * stretch
}

/// Body `i`'s anchor `r` (body frame) in `state`: its world point, velocity and offset
/// from the centre (point masses: the centre's, no offset).
fn anchor(
    state: &State,
    i: usize,
    r: &Vector3<f64>,
    rigid: bool,
) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    if rigid {
        let rr = UnitQuaternion::new_normalize(state.q[i]) * r;
        (state.p[i] + rr, state.v[i] + state.omega[i].cross(&rr), rr)
    } else {
        (state.p[i], state.v[i], Vector3::zeros())
    }
}
