//! The IFToMM multibody benchmark problems the format can express, each against a
//! reference computed here: A02, the N-four-bar, whose rows lose rank each time its
//! bars lie on one line, against its one-degree-of-freedom equation; A04, Bricard's
//! mechanism, a closed loop of six hinges with a row that depends on the others at every
//! position, against the conservation of its energy and the symmetry of its loop.
//! (A01, the simple pendulum, is in `mechanisms.rs`.)

use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};
use serde_json::{json, Value};

use super::{mechanical_energy, pendulum_angles, potential_energy, scenario, shipped, simulate};

const G: f64 = 9.81;

/// The benchmarks' high-precision threshold on a reference point's position [m].
const HIGH_PRECISION: f64 = 1e-3;

/// A02 with its 40 windows (41 rockers on world hinges, 40 couplers) for `duration`.
/// The rockers stand up; the top of the first, B0, moves at 1 m/s along +x.
fn n_four_bar(duration: f64) -> Value {
    let mut v = shipped("iftomm/a02_n_four_bar");
    v["duration"] = json!(duration);
    v
}

/// The couplers translate, so the N-four-bar is one pendulum in the rockers' angle θ
/// from the downward vertical: with `N + 1` rockers (`m L²/3` about their pivots, centres
/// at `L/2`) and `N` couplers (moving with the rockers' tips),
/// `((N+1)/3 + N) m L² θ̈ = −((N+1)/2 + N) m g L sin θ`; this is its `k` in `θ̈ = −k sin θ`.
fn n_four_bar_k(windows: f64) -> f64 {
    ((windows + 1.0) / 2.0 + windows) * G / ((windows + 1.0) / 3.0 + windows)
}

/// A02: 81 bars on 121 hinges (605 rows on 486 coordinates: the planar loops' rows in
/// space depend on each other), rank lost again at each horizontal passage, where the
/// degrees of freedom jump from 1 to 41. B0 must follow the one-degree-of-freedom
/// equation ([`n_four_bar_k`]), integrated here, within the benchmark's high-precision
/// threshold, through its singular positions; and the energy must hold.
#[test]
fn the_n_four_bar_a02_follows_its_equation_through_its_singular_positions() {
    let duration = 4.0;
    let s = scenario(n_four_bar(duration));
    let windows = ((s.bodies.len() - 1) / 2) as f64;
    // θ from the downward vertical, B0 = (sin θ, −cos θ): standing up, θ = π, and
    // ẋ(B0) = −θ̇ cos θ... = 1 m/s gives θ̇ = −1.
    let reference = pendulum_angles(n_four_bar_k(windows), (PI, -1.0), 1e-4, duration, 10);
    let (mut worst, mut singular, mut i) = (0.0f64, 0, 0);
    let mut last_y: Option<f64> = None;
    let (mut e0, mut worst_energy) = (None, 0.0f64);
    simulate(&s, |_, _, st| {
        let theta = reference[i];
        let b0 = st.p[0] + UnitQuaternion::new_normalize(st.q[0]) * Vector3::new(0.0, 0.5, 0.0);
        worst = worst.max((b0 - Vector3::new(theta.sin(), -theta.cos(), 0.0)).norm());
        // A singular position: B0 passes its pivot's height.
        if let Some(y0) = last_y {
            if (y0 < 0.0) != (b0.y < 0.0) {
                singular += 1;
            }
        }
        last_y = Some(b0.y);
        let e = mechanical_energy(&s, st, Vector3::new(0.0, -G, 0.0));
        worst_energy = worst_energy.max((e - *e0.get_or_insert(e)).abs());
        i += 1;
    });
    eprintln!(
        "A02 N-four-bar ({windows} windows) over {duration} s: {singular} singular positions \
         passed, B0 within {worst:.3e} m of its equation, energy within {worst_energy:.3e} J"
    );
    assert!(singular >= 3, "passed only {singular} singular positions");
    assert!(
        worst < HIGH_PRECISION,
        "{worst} m from the N-four-bar's equation"
    );
    assert!(worst_energy < 1e-6, "energy moved by {worst_energy} J");
}

/// Signed angle [rad] of the relative turn `q_a⁻¹ q_b` about `axis` (in `a`'s frame).
fn turn(qa: &UnitQuaternion<f64>, qb: &UnitQuaternion<f64>, axis: &Vector3<f64>) -> f64 {
    let rel = qa.inverse() * qb;
    2.0 * rel.imag().dot(axis).atan2(rel.w)
}

/// A04: five rods along the edges of a unit cube, closed to the world by six hinges,
/// each axis normal to both bars it joins (the orthogonal Bricard linkage). 30 rows on
/// 30 coordinates, one of them dependent on the others at every position, and still
/// one degree of freedom: the solve must drop the dependent row and let the loop fold
/// under gravity. Its energy must hold while tens of joules move between potential and
/// kinetic, the loop must stay closed, and the linkage's kinematics must show through:
/// the hexagon is unchanged by a third of a turn about the cube's diagonal, which moves
/// each joint two places on, so along its one-dimensional configuration curve the odd
/// joints turn alike and the even joints turn alike (equal cosines; the signs follow
/// the axes' directions). No row enforces that: the closure does.
#[test]
fn bricards_mechanism_a04_drops_its_dependent_row_and_moves_with_one_degree_of_freedom() {
    let s = scenario(shipped("iftomm/a04_bricard"));
    let gravity = Vector3::new(0.0, -G, 0.0);
    // Every body starts unturned, so each hinge's world axis is its axis in both frames.
    let axes: Vec<Vector3<f64>> = [
        (0, 1, 0),
        (0, 0, 1),
        (1, 0, 0),
        (0, 1, 0),
        (0, 0, 1),
        (1, 0, 0),
    ]
    .iter()
    .map(|&(x, y, z)| Vector3::new(x as f64, y as f64, z as f64))
    .collect();
    let (mut e0, mut worst_energy, mut moved) = (None, 0.0f64, 0.0f64);
    let (mut worst_pair, mut widest, mut worst_w) = (0.0f64, 0.0f64, 0.0f64);
    simulate(&s, |_, system, st| {
        let q: Vec<UnitQuaternion<f64>> =
            st.q.iter()
                .map(|&q| UnitQuaternion::new_normalize(q))
                .collect();
        let world = UnitQuaternion::identity();
        // Joint k joins bar k (0-based; the world before bar 0 and after bar 4).
        let angles: Vec<f64> = (0..6)
            .map(|k| {
                let a = if k == 0 { &world } else { &q[k - 1] };
                let b = if k == 5 { &world } else { &q[k] };
                turn(a, b, &axes[k])
            })
            .collect();
        for k in 0..4 {
            worst_pair = worst_pair.max((angles[k].cos() - angles[k + 2].cos()).abs());
        }
        widest = widest.max(angles[0].abs());
        let e = mechanical_energy(&s, st, gravity);
        let e0 = *e0.get_or_insert(e);
        worst_energy = worst_energy.max((e - e0).abs());
        moved = moved.max(e0 - potential_energy(&s, st, gravity));
        worst_w = system
            .violations()
            .iter()
            .fold(worst_w, |m, w| m.max(w.abs()));
    });
    eprintln!(
        "A04 Bricard over {} s: energy within {worst_energy:.3e} J while {moved:.2} J moved \
         between potential and kinetic; joint 1 turned up to {:.1}°; joints two apart turned alike to \
         {worst_pair:.3e} in cosine; rows within {worst_w:.3e} m",
        s.duration.as_secs_f64(),
        widest.to_degrees()
    );
    assert!(moved > 10.0, "the loop hardly moved ({moved} J)");
    assert!(worst_energy < 1e-6, "energy moved by {worst_energy} J");
    assert!(
        worst_pair < 1e-6,
        "joints two apart differ by {worst_pair} in cosine"
    );
    assert!(worst_w < 1e-8, "a row is {worst_w} m open");
}
