//! Prismatic joints: a block sliding down a tilted rail fixed in the world against the
//! closed form of uniform acceleration, and a bead sliding out along a spinning rod
//! against its two-degree-of-freedom equations, integrated here.

use nalgebra::{UnitQuaternion, Vector3};
use serde_json::json;

use super::{angular_momentum, kinetic_energy, scenario, simulate};

const G: f64 = 9.81;

/// A 1 kg block on a world rail tilted 30° up from +x, its joint point 0.1 m off its
/// centre (so the rail's rows act through levers), released moving up the rail at
/// 2 m/s under gravity along −z: it must move along the rail as `s = v₀ t − ½ g sin 30° t²`
/// and neither leave the rail nor turn.
#[test]
fn a_block_on_a_tilted_rail_accelerates_as_gravity_along_the_rail_says() {
    let tilt = 30f64.to_radians();
    let axis = Vector3::new(tilt.cos(), 0.0, tilt.sin());
    let (v0, duration) = (2.0, 1.0);
    let s = scenario(json!({
        "name": "rail", "seed": 1, "duration": duration, "dt": 0.001, "integrator": "rk4",
        "model": {
            "gravity": [0, 0, -G],
            "bodies": [{"id": 1, "mass": 1.0, "size": 0.1, "position": [0, 0, 0],
                        "velocity": [v0 * axis.x, 0, v0 * axis.z]}],
            "joints": [{"type": "prismatic", "a": 1, "at": [0.1, 0.05, 0.0],
                        "axis": [axis.x, axis.y, axis.z]}]
        }
    }));
    let (mut worst, mut turned, mut travelled) = (0.0f64, 0.0f64, 0.0f64);
    simulate(&s, |t, _, st| {
        let t = t.as_secs_f64();
        let along = v0 * t - 0.5 * G * tilt.sin() * t * t;
        worst = worst.max((st.p[0] - axis * along).norm());
        turned = turned.max(UnitQuaternion::new_normalize(st.q[0]).angle());
        travelled = travelled.max(along.abs());
    });
    eprintln!(
        "block on a 30° rail over {duration} s: within {worst:.3e} m of uniform acceleration \
         along the rail (up to {travelled:.2} m from the start), turned {turned:.3e} rad"
    );
    assert!(travelled > 0.3, "the block hardly moved");
    assert!(worst < 1e-9, "{worst} m off the closed form");
    assert!(turned < 1e-9, "the block turned by {turned} rad");
}

// The bead on a rod: a 2 kg rod on a world hinge about z at its centre, spinning at
// 3 rad/s, and a 0.5 kg bead 0.2 m out along it on a prismatic joint along the rod,
// moving outwards at 0.1 m/s. No gravity.
const ROD_MASS: f64 = 2.0;
const ROD_LENGTH: f64 = 1.0;
const BEAD_MASS: f64 = 0.5;
const BEAD_SIZE: f64 = 0.05;
const SPIN: f64 = 3.0;
const R0: f64 = 0.2;
const RDOT0: f64 = 0.1;

/// `(r, φ)` of the bead every `every` steps of RK4 at `h`: with `I(r)` the pair's inertia
/// about the hinge (the rod's, the bead's own, and `m r²`), the angular momentum
/// `L = I(r) φ̇` is conserved and `r̈ = r φ̇²`.
fn bead_reference(h: f64, duration: f64, every: usize) -> Vec<(f64, f64)> {
    let own = ROD_MASS * ROD_LENGTH * ROD_LENGTH / 12.0 + BEAD_MASS * BEAD_SIZE * BEAD_SIZE / 6.0;
    let inertia = |r: f64| own + BEAD_MASS * r * r;
    let l = inertia(R0) * SPIN;
    // y = (r, ṙ, φ)
    let rate = |y: [f64; 3]| {
        let w = l / inertia(y[0]);
        [y[1], y[0] * w * w, w]
    };
    let add =
        |y: [f64; 3], d: [f64; 3], s: f64| [y[0] + s * d[0], y[1] + s * d[1], y[2] + s * d[2]];
    let mut y = [R0, RDOT0, 0.0];
    let mut out = vec![(y[0], y[2])];
    for step in 1..=(duration / h).round() as usize {
        let k1 = rate(y);
        let k2 = rate(add(y, k1, h / 2.0));
        let k3 = rate(add(y, k2, h / 2.0));
        let k4 = rate(add(y, k3, h));
        for i in 0..3 {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        if step % every == 0 {
            out.push((y[0], y[2]));
        }
    }
    out
}

/// The bead slides out as the rod turns slower: its path must follow the equations
/// ([`bead_reference`]) and the pair keep its angular momentum about the hinge and its
/// kinetic energy (the prismatic joint does no work, the hinge none either).
#[test]
fn a_bead_on_a_spinning_rod_slides_out_as_its_equations_say() {
    let duration = 2.0;
    let m = BEAD_MASS;
    let inertia_rod = ROD_MASS * ROD_LENGTH * ROD_LENGTH / 12.0;
    let s = scenario(json!({
        "name": "bead", "seed": 1, "duration": duration, "dt": 0.001, "integrator": "rk4",
        "model": {
            "bodies": [
                {"id": 1, "mass": ROD_MASS, "size": 0.05,
                 "inertia": [1e-3, inertia_rod, inertia_rod],
                 "position": [0, 0, 0], "angular_velocity": [0, 0, SPIN]},
                {"id": 2, "mass": m, "size": BEAD_SIZE, "position": [R0, 0, 0],
                 "velocity": [RDOT0, SPIN * R0, 0], "angular_velocity": [0, 0, SPIN]}
            ],
            "joints": [
                {"type": "hinge", "a": 1, "at": [0, 0, 0], "axis": [0, 0, 1]},
                {"type": "prismatic", "a": 2, "b": 1, "at": [R0, 0, 0], "axis": [1, 0, 0]}
            ]
        }
    }));
    let reference = bead_reference(1e-4, duration, 10);
    let spin_z = |st: &dsmcosim::multibody::State| angular_momentum(&s, st).z;
    let initial = dsmcosim::multibody::State::initial(&s);
    let (l0, e0) = (spin_z(&initial), kinetic_energy(&s, &initial));
    let (mut worst, mut dl, mut de, mut out, mut k) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0);
    simulate(&s, |_, _, st| {
        let (r, phi) = reference[k];
        let want = Vector3::new(r * phi.cos(), r * phi.sin(), 0.0);
        worst = worst.max((st.p[1] - want).norm());
        dl = dl.max(((spin_z(st) - l0) / l0).abs());
        de = de.max(((kinetic_energy(&s, st) - e0) / e0).abs());
        out = out.max(r);
        k += 1;
    });
    eprintln!(
        "bead on a spinning rod over {duration} s: out to {out:.3} m, within {worst:.3e} m of \
         its equations; angular momentum within {dl:.1e}, kinetic energy within {de:.1e} \
         (relative)"
    );
    assert!(out > 2.0 * R0, "the bead hardly moved out ({out} m)");
    assert!(worst < 1e-6, "{worst} m off the bead's equations");
    assert!(dl < 1e-8 && de < 1e-8, "ΔL {dl}, ΔKE {de}");
}

/// Two free bodies on a prismatic joint, tumbling about an oblique axis with no load:
/// the slide's normal turns with `b` in three dimensions, so every term of its rows'
/// Jacobian and `J̇ v` is exercised. Momentum, angular momentum and kinetic energy are
/// conserved, and the joint keeps `a` on the axis and the pair turning as one.
#[test]
fn a_tumbling_pair_on_a_prismatic_joint_keeps_its_momenta_and_energy() {
    let omega = Vector3::new(0.4, -0.7, 1.1);
    let (pa, pb) = (Vector3::new(0.6, 0.1, 0.0), Vector3::new(-0.3, 0.0, 0.0));
    let (vb, slide) = (Vector3::new(0.05, 0.1, -0.2), 0.3);
    // a moves with b's frame plus its slide along x.
    let va = vb + omega.cross(&(pa - pb)) + Vector3::x() * slide;
    let vec = |v: Vector3<f64>| json!([v.x, v.y, v.z]);
    let s = scenario(json!({
        "name": "pair", "seed": 1, "duration": 3.0, "dt": 0.001, "integrator": "rk4",
        "model": {
            "bodies": [
                {"id": 1, "mass": 0.7, "size": 0.1, "inertia": [0.002, 0.003, 0.004],
                 "position": vec(pa), "velocity": vec(va), "angular_velocity": vec(omega)},
                {"id": 2, "mass": 1.5, "size": 0.2, "inertia": [0.02, 0.05, 0.04],
                 "position": vec(pb), "velocity": vec(vb), "angular_velocity": vec(omega)}
            ],
            "joints": [{"type": "prismatic", "a": 1, "b": 2, "at": [0.5, 0.1, 0.0],
                        "axis": [1, 0, 0]}]
        }
    }));
    let momentum =
        |st: &dsmcosim::multibody::State| st.v[0] * s.bodies[0].mass + st.v[1] * s.bodies[1].mass;
    let initial = dsmcosim::multibody::State::initial(&s);
    let (p0, l0, e0) = (
        momentum(&initial),
        angular_momentum(&s, &initial),
        kinetic_energy(&s, &initial),
    );
    let (mut dp, mut dl, mut de, mut apart, mut w) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    simulate(&s, |_, system, st| {
        dp = dp.max((momentum(st) - p0).norm());
        dl = dl.max((angular_momentum(&s, st) - l0).norm() / l0.norm());
        de = de.max(((kinetic_energy(&s, st) - e0) / e0).abs());
        let (qa, qb) = (
            UnitQuaternion::new_normalize(st.q[0]),
            UnitQuaternion::new_normalize(st.q[1]),
        );
        apart = apart.max(qa.angle_to(&qb));
        w = system.violations().iter().fold(w, |m, x| m.max(x.abs()));
    });
    eprintln!(
        "tumbling prismatic pair over 3 s: ΔP {dp:.1e} kg·m/s, ΔL {dl:.1e}, ΔKE {de:.1e} \
         (relative), relative turn {apart:.1e} rad, rows within {w:.1e} m"
    );
    assert!(dp < 1e-12, "momentum moved by {dp}");
    assert!(dl < 1e-8 && de < 1e-8, "ΔL {dl}, ΔKE {de}");
    assert!(
        apart < 1e-8 && w < 1e-8,
        "turned apart {apart} rad, rows {w} m"
    );
}
