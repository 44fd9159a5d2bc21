//! Mechanisms users build, each against a reference computed here: a heavy symmetric
//! top against Euler's equations about its fixed point, a conical pendulum against its
//! closed form, a free chain against the conservation laws. All run under the default
//! law of a scene with joints (no `stabilizer` section), which must be an ideal joint's:
//! no work, no couple.

use std::f64::consts::PI;

use dsmcosim::multibody::State;
use dsmcosim::scenario::model::Stabilizer;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde_json::{json, Value};

use super::{
    angular_momentum, elliptic_k, mechanical_energy, pendulum_angles, scenario, shipped, simulate,
};

const G: f64 = 9.81;

/// Kinetic plus potential energy of every body of `s` in `st` [J], gravity along −z.
fn energy(s: &dsmcosim::scenario::Scenario, st: &State, g: f64) -> f64 {
    mechanical_energy(s, st, Vector3::new(0.0, 0.0, -g))
}

// The heavy symmetric top: 1 kg, principal inertia 0.01 / 0.01 / 0.02 kg·m² about its
// centre, the centre 0.2 m up its symmetry axis from a ball joint to the world, the
// axis 30° from the vertical, spinning at 60 rad/s about it, released without
// precession.
const TOP_MASS: f64 = 1.0;
const TOP_INERTIA: [f64; 3] = [0.01, 0.01, 0.02];
const TOP_ARM: f64 = 0.2;
const TOP_TILT_DEG: f64 = 30.0;
const TOP_SPIN: f64 = 60.0;

fn top_orientation() -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), TOP_TILT_DEG.to_radians())
}

fn top_scene(duration: f64) -> Value {
    let q = top_orientation();
    let axis = q * Vector3::z();
    let centre = axis * TOP_ARM;
    let omega = axis * TOP_SPIN;
    json!({
        "name": "top", "seed": 1, "duration": duration, "dt": 0.001, "integrator": "rk4",
        "model": {
            "gravity": [0, 0, -G],
            "bodies": [{"id": 1, "mass": TOP_MASS, "size": 0.1, "inertia": TOP_INERTIA,
                        "position": [centre.x, centre.y, centre.z],
                        "orientation": [q.w, q.i, q.j, q.k],
                        "angular_velocity": [omega.x, omega.y, omega.z]}],
            "joints": [{"type": "ball", "a": 1, "at": [0, 0, 0]}]
        }
    })
}

/// The top's symmetry axis in the world from Euler's equations about the fixed point,
/// in the body frame (inertia about the pivot `I + m l² (1 − e_z e_zᵀ)`), integrated
/// here by RK4 at `h` and sampled every `every` steps.
fn top_reference(h: f64, steps: usize, every: usize) -> Vec<Vector3<f64>> {
    let ip = Vector3::new(
        TOP_INERTIA[0] + TOP_MASS * TOP_ARM * TOP_ARM,
        TOP_INERTIA[1] + TOP_MASS * TOP_ARM * TOP_ARM,
        TOP_INERTIA[2],
    );
    // State: quaternion (body → world) and body-frame ω.
    let rates = |q: Quaternion<f64>, w: Vector3<f64>| {
        let r = UnitQuaternion::new_normalize(q);
        // Gravity's torque about the pivot, in the body frame.
        let centre = r * Vector3::new(0.0, 0.0, TOP_ARM);
        let torque = r.inverse() * centre.cross(&Vector3::new(0.0, 0.0, -TOP_MASS * G));
        let iw = ip.component_mul(&w);
        let dw = (torque - w.cross(&iw)).component_div(&ip);
        let dq = q * Quaternion::from_imag(w) * 0.5;
        (dq, dw)
    };
    let mut q = *top_orientation().quaternion();
    let mut w = Vector3::new(0.0, 0.0, TOP_SPIN);
    let axis = |q: Quaternion<f64>| UnitQuaternion::new_normalize(q) * Vector3::z();
    let mut out = vec![axis(q)];
    for k in 1..=steps {
        let (q1, w1) = rates(q, w);
        let (q2, w2) = rates(q + q1 * (h / 2.0), w + w1 * (h / 2.0));
        let (q3, w3) = rates(q + q2 * (h / 2.0), w + w2 * (h / 2.0));
        let (q4, w4) = rates(q + q3 * h, w + w3 * h);
        q += (q1 + q2 * 2.0 + q3 * 2.0 + q4) * (h / 6.0);
        w += (w1 + w2 * 2.0 + w3 * 2.0 + w4) * (h / 6.0);
        q = q.normalize();
        if k % every == 0 {
            out.push(axis(q));
        }
    }
    out
}

/// Peak-to-peak tilt of an axis from the vertical over a run [rad]: the nutation.
fn nutation(axes: &[Vector3<f64>]) -> f64 {
    let tilts = axes.iter().map(|a| a.z.clamp(-1.0, 1.0).acos());
    let (lo, hi) = tilts.fold((f64::MAX, f64::MIN), |(lo, hi), t| (lo.min(t), hi.max(t)));
    hi - lo
}

#[test]
fn the_default_law_of_a_jointed_scene_is_exact_multipliers() {
    // A scene of links only keeps the thesis's SMC law (and every stored digest).
    let s = scenario(top_scene(1.0));
    assert!(
        matches!(s.stabilizer, Stabilizer::Baumgarte { .. }),
        "{:?}",
        s.stabilizer
    );
    let links = scenario(json!({
        "name": "links", "seed": 1, "duration": 1.0, "dt": 0.001,
        "model": {"grid": {"rows": 1, "cols": 2, "spacing": 1.0, "mass": 1.0, "size": 0.2}}
    }));
    assert!(matches!(links.stabilizer, Stabilizer::Smc { .. }));
}

/// The top follows Euler's equations: its axis stays on the reference's, so its
/// nutation keeps the reference's amplitude, and its energy stays.
#[test]
fn a_heavy_top_nutates_as_eulers_equations_say_and_keeps_its_energy() {
    let duration = 5.0;
    // The reference at a tenth of the run's step, sampled at the run's steps.
    let reference = top_reference(1e-4, 50_000, 10);
    let s = scenario(top_scene(duration));
    let (mut axes, mut worst_axis, mut worst_energy) = (Vec::new(), 0.0f64, 0.0f64);
    let mut e0 = None;
    let mut k = 0;
    // Angular momentum about the pivot (the origin): gravity's torque there is
    // horizontal, so its vertical part is kept and its horizontal part precesses.
    let l0 = angular_momentum(&s, &State::initial(&s));
    let (mut worst_lz, mut turned_l) = (0.0f64, 0.0f64);
    simulate(&s, |_, _, st| {
        let axis = UnitQuaternion::new_normalize(st.q[0]) * Vector3::z();
        worst_axis = worst_axis.max(axis.angle(&reference[k]));
        let e = energy(&s, st, G);
        worst_energy = worst_energy.max((e - *e0.get_or_insert(e)).abs());
        let l = angular_momentum(&s, st);
        worst_lz = worst_lz.max((l.z - l0.z).abs() / l0.norm());
        turned_l = turned_l.max((l.xy() - l0.xy()).norm() / l0.norm());
        axes.push(axis);
        k += 1;
    });
    assert_eq!(k, reference.len());
    let (got, want) = (nutation(&axes), nutation(&reference));
    eprintln!(
        "heavy top over {duration} s: nutation {:.4}° (Euler's equations {:.4}°), axis within \
         {worst_axis:.3e} rad of the reference, energy within {worst_energy:.3e} J",
        got.to_degrees(),
        want.to_degrees()
    );
    // The reference nutates visibly: a test of a top that did not would prove nothing.
    assert!(want.to_degrees() > 1.0, "reference nutation {want} rad");
    assert!(
        ((got - want) / want).abs() < 0.10,
        "nutation {got} rad vs {want} rad"
    );
    assert!(worst_energy < 0.05, "energy moved by {worst_energy} J");
    eprintln!(
        "heavy top: vertical angular momentum about the pivot within {worst_lz:.3e} of |L|, \
         its horizontal part turned by up to {turned_l:.2} of |L|"
    );
    assert!(turned_l > 0.5, "the top did not precess ({turned_l})");
    assert!(worst_lz < 1e-6, "L_z moved by {worst_lz} of |L|");
    // Both ways: the axis is the reference's, not merely a top of the same amplitude.
    assert!(worst_axis < 1e-3, "axis {worst_axis} rad off the reference");
}

/// A cube bob 1 m below a world ball joint, set on its steady cone at 30° (velocity
/// `Ω ẑ × r` and the body turning with the cone at `Ω ẑ`): for a bob with isotropic
/// inertia about its centre, the steady cone turns at `Ω² = g / (L cos θ)` (the
/// gyroscopic terms cancel), so the period is `2π √(L cos θ / g)` whatever its size.
#[test]
fn a_conical_pendulum_keeps_its_cone_and_its_closed_form_period() {
    let (l, theta, size, duration) = (1.0, 30f64.to_radians(), 0.1, 6.0);
    let omega = (G / (l * theta.cos())).sqrt();
    let r = Vector3::new(l * theta.sin(), 0.0, -l * theta.cos());
    let v = Vector3::z().cross(&r) * omega;
    let s = scenario(json!({
        "name": "cone", "seed": 1, "duration": duration, "dt": 0.001, "integrator": "rk4",
        "model": {
            "gravity": [0, 0, -G],
            "bodies": [{"id": 1, "mass": 1.0, "size": size, "position": [r.x, r.y, r.z],
                        "velocity": [v.x, v.y, v.z], "angular_velocity": [0, 0, omega]}],
            "joints": [{"type": "ball", "a": 1, "at": [0, 0, 0]}]
        }
    }));
    let (mut up, mut last, mut worst_angle) = (Vec::new(), None::<(f64, f64)>, 0.0f64);
    simulate(&s, |t, _, st| {
        let (t, x) = (t.as_secs_f64(), st.p[0].x);
        if let Some((t0, x0)) = last {
            if x0 < 0.0 && x >= 0.0 {
                up.push(t0 + (t - t0) * (-x0) / (x - x0));
            }
        }
        last = Some((t, x));
        let cone = (-st.p[0].z / st.p[0].norm()).acos();
        worst_angle = worst_angle.max((cone - theta).abs());
    });
    assert!(up.len() >= 3, "{} turns", up.len());
    let period = (up[up.len() - 1] - up[0]) / (up.len() - 1) as f64;
    let want = 2.0 * PI / omega;
    eprintln!(
        "conical pendulum over {duration} s: period {period:.9} s (closed form {want:.9} s), \
         cone angle within {worst_angle:.3e} rad"
    );
    assert!(
        ((period - want) / want).abs() < 0.01,
        "period {period} s vs {want} s"
    );
    assert!(worst_angle < 1e-3, "the cone opened by {worst_angle} rad");
}

/// Five uniform rods (1 kg, 1 m) on four ball joints, tumbling with no gravity: each
/// rod spins at its own rate about its own axis and the centres move so every joint's
/// two anchors move alike (the scene starts on its velocity constraints). No external
/// force or torque: momentum, angular momentum and kinetic energy are conserved.
#[test]
fn a_free_chain_on_ball_joints_keeps_momentum_angular_momentum_and_energy() {
    // The shipped chain (its velocities built so every joint's two anchors move alike),
    // on one node, for 5 s.
    let mut v = shipped("mechanisms/free_chain5");
    v["duration"] = json!(5.0);
    let s = scenario(v);
    let n = s.bodies.len();
    let initial = State::initial(&s);
    let momentum = |st: &State| st.v.iter().sum::<Vector3<f64>>();
    let (p0, l0, e0) = (
        momentum(&initial),
        angular_momentum(&s, &initial),
        energy(&s, &initial, 0.0),
    );
    let (mut dp, mut dl, mut de, mut bent) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let first_axis = |st: &State| UnitQuaternion::new_normalize(st.q[0]) * Vector3::x();
    let last_axis = |st: &State| UnitQuaternion::new_normalize(st.q[n - 1]) * Vector3::x();
    simulate(&s, |_, _, st| {
        dp = dp.max((momentum(st) - p0).norm());
        dl = dl.max((angular_momentum(&s, st) - l0).norm() / l0.norm());
        de = de.max((energy(&s, st, 0.0) - e0).abs() / e0);
        bent = bent.max(first_axis(st).angle(&last_axis(st)));
    });
    eprintln!(
        "free chain of {n} rods over 5 s: |ΔP| {dp:.3e} kg·m/s, |ΔL|/|L| {dl:.3e}, \
         |ΔKE|/KE {de:.3e} (KE {e0:.3} J), end rods up to {bent:.2} rad apart"
    );
    // The chain flexes (it is not a rigid body turning): the joints carry forces.
    assert!(bent > 0.5, "the chain stayed straight ({bent} rad)");
    assert!(dp < 1e-9, "momentum moved by {dp} kg·m/s");
    assert!(dl < 0.01, "angular momentum moved by {dl} of |L|");
    assert!(de < 0.05, "kinetic energy moved by {de} of KE");
    // An ideal joint does no work and leaves no couple: both to the integrator's
    // truncation, far inside the targets above.
    assert!(dl < 1e-6 && de < 1e-6, "ΔL {dl}, ΔKE {de}");
}

// The four-bars: two 1 kg, 1 m cranks on world hinges `span` apart carrying a 2 kg
// coupler on two more hinges, every axis along y, under gravity.
const CRANK: f64 = 1.0;
const COUPLER: f64 = 2.0;
const ARM: f64 = 1.0;

/// The four-bar with its cranks hanging down and turning at `spin` [rad/s] (along −x
/// at the bottom), for `duration`.
fn four_bar(span: f64, spin: f64, duration: f64) -> Value {
    let (m, big_m, l) = (CRANK, COUPLER, ARM);
    let crank = |id: u32, x: f64| {
        json!({"id": id, "mass": m, "size": 0.05,
               "inertia": [m * l * l / 12.0, m * l * l / 12.0, 1e-4],
               "position": [x, 0, -l / 2.0], "velocity": [-spin * l / 2.0, 0, 0],
               "angular_velocity": [0, spin, 0]})
    };
    json!({
        "name": "four-bar", "seed": 1, "duration": duration, "dt": 0.001, "integrator": "rk4",
        "model": {
            "gravity": [0, 0, -G],
            "bodies": [
                crank(1, 0.0), crank(2, span),
                {"id": 3, "mass": big_m, "size": 0.05,
                 "inertia": [1e-4, big_m * span * span / 12.0, big_m * span * span / 12.0],
                 "position": [span / 2.0, 0, -l], "velocity": [-spin * l, 0, 0]}
            ],
            "joints": [
                {"type": "hinge", "a": 1, "at": [0, 0, 0], "axis": [0, 1, 0]},
                {"type": "hinge", "a": 2, "at": [span, 0, 0], "axis": [0, 1, 0]},
                {"type": "hinge", "a": 1, "b": 3, "at": [0, 0, -l], "axis": [0, 1, 0]},
                {"type": "hinge", "a": 2, "b": 3, "at": [span, 0, -l], "axis": [0, 1, 0]}
            ]
        }
    })
}

/// The coupler translates, so a four-bar is one pendulum in its cranks' angle θ:
/// `(2 m L²/3 + M L²) θ̈ = −(m + M) g L sin θ`; this is its `k` in `θ̈ = −k sin θ`.
fn four_bar_k() -> f64 {
    let inertia = 2.0 * CRANK * ARM * ARM / 3.0 + COUPLER * ARM * ARM;
    (CRANK + COUPLER) * G * ARM / inertia
}

/// A planar parallelogram four-bar built of hinges only, its world hinges 1.5 m apart.
/// Four hinges give 20 rows on 18 coordinates for one degree of freedom: three rows
/// depend on the others (a planar loop in space), and the solve must drop them rather
/// than stop. Its period at amplitude θ₀ is `4 K(sin(θ₀/2)) / ω₀`, `ω₀² = k`
/// ([`four_bar_k`]).
#[test]
fn a_four_bar_of_hinges_drops_its_redundant_rows_and_swings_with_its_closed_form_period() {
    let (span, spin) = (1.5, 2.0);
    let s = scenario(four_bar(span, spin, 8.0));
    let omega0 = four_bar_k().sqrt();
    // The amplitude from the energy: ½ θ̇² = k (1 − cos θ₀).
    let amplitude = (1.0 - 0.5 * spin * spin / four_bar_k()).acos();
    let want = 4.0 * elliptic_k((amplitude / 2.0).sin()) / omega0;
    let (mut up, mut last, mut turned, mut worst_energy) =
        (Vec::new(), None::<(f64, f64)>, 0.0f64, 0.0f64);
    let mut e0 = None;
    simulate(&s, |t, _, st| {
        let (t, x) = (t.as_secs_f64(), st.p[2].x - span / 2.0);
        if let Some((t0, x0)) = last {
            if x0 < 0.0 && x >= 0.0 {
                up.push(t0 + (t - t0) * (-x0) / (x - x0));
            }
        }
        last = Some((t, x));
        turned = turned.max(UnitQuaternion::new_normalize(st.q[2]).angle());
        let e = energy(&s, st, G);
        worst_energy = worst_energy.max((e - *e0.get_or_insert(e)).abs());
    });
    assert!(up.len() >= 3, "{} swings", up.len());
    let period = (up[up.len() - 1] - up[0]) / (up.len() - 1) as f64;
    eprintln!(
        "hinge four-bar over 8 s: period {period:.9} s (closed form {want:.9} s at amplitude \
         {:.2}°), coupler turned at most {turned:.3e} rad, energy within {worst_energy:.3e} J",
        amplitude.to_degrees()
    );
    assert!(
        ((period - want) / want).abs() < 1e-4,
        "period {period} s vs {want} s"
    );
    assert!(turned < 1e-6, "the coupler turned by {turned} rad");
    assert!(worst_energy < 1e-6, "energy moved by {worst_energy} J");
}

/// A simple pendulum as the IFToMM multibody benchmark A01 gives it: a 1 kg point mass
/// 1 m from a world pivot, released from the horizontal under gravity (a bob of 1 mm,
/// inertia 1.7e-7 kg·m², where the format needs a size). Against `θ̈ = −(g/L) sin θ`
/// integrated here by RK4 at a tenth of the step, over 10 s.
#[test]
fn a_point_mass_pendulum_released_horizontal_follows_its_equation() {
    let (l, duration, dt): (f64, f64, f64) = (1.0, 10.0, 0.001);
    let s = scenario(json!({
        "name": "A01", "seed": 1, "duration": duration, "dt": dt, "integrator": "rk4",
        "model": {
            "gravity": [0, 0, -G],
            "bodies": [{"id": 1, "mass": 1.0, "size": 0.001, "position": [l, 0, 0]}],
            "joints": [{"type": "ball", "a": 1, "at": [0, 0, 0]}]
        }
    }));
    // θ from the downward vertical; the bob starts at θ = π/2 (along +x).
    let reference = pendulum_angles(G / l, (PI / 2.0, 0.0), dt / 10.0, duration, 10);
    let (mut worst, mut k) = (0.0f64, 0);
    simulate(&s, |_, _, st| {
        let theta = reference[k];
        let want = Vector3::new(l * theta.sin(), 0.0, -l * theta.cos());
        worst = worst.max((st.p[0] - want).norm());
        k += 1;
    });
    eprintln!("A01 simple pendulum over {duration} s: {worst:.3e} m from its equation");
    assert!(worst < 1e-4, "{worst} m from the pendulum's equation");
}

/// The hinge four-bar with a span equal to its cranks' length, spun fast enough to
/// turn over: each time its cranks pass the horizontal, all four bars lie on one line
/// and its constraint rows lose rank (the singular position of the IFToMM benchmark
/// A02, the N-four-bar), where a solve that cannot drop dependent rows stopped. It must
/// pass them and follow its one-degree-of-freedom equation ([`four_bar_k`]), integrated
/// here, over 4 s (nearly four turns, eight singular passages).
#[test]
fn a_four_bar_turning_over_passes_its_singular_positions() {
    let (span, spin, duration) = (ARM, 8.0, 4.0);
    let s = scenario(four_bar(span, spin, duration));
    // θ from the downward vertical (x = L sin θ); the cranks start down moving along
    // −x: θ̇ = −spin.
    let reference = pendulum_angles(four_bar_k(), (0.0, -spin), 1e-4, duration, 10);
    let (mut worst, mut singular, mut i) = (0.0f64, 0, 0);
    let mut last_z: Option<f64> = None;
    simulate(&s, |_, _, st| {
        let theta = reference[i];
        let want = Vector3::new(span / 2.0 + ARM * theta.sin(), 0.0, -ARM * theta.cos());
        worst = worst.max((st.p[2] - want).norm());
        // A singular position: the coupler passes the pivots' height (z = 0).
        let z = st.p[2].z;
        if let Some(z0) = last_z {
            if (z0 < 0.0) != (z < 0.0) {
                singular += 1;
            }
        }
        last_z = Some(z);
        i += 1;
    });
    let turns = (reference[reference.len() - 1] / (2.0 * PI)).abs();
    eprintln!(
        "four-bar turning over: {singular} singular positions passed in {turns:.1} turns, \
         coupler within {worst:.3e} m of its equation over {duration} s"
    );
    assert!(singular >= 6, "passed only {singular} singular positions");
    assert!(worst < 1e-4, "{worst} m from the four-bar's equation");
}
