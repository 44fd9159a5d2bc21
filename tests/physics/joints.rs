//! Joints against mechanics: pendulum periods (small-amplitude and the elliptic
//! integral), a double pendulum against its own Lagrangian equations integrated here,
//! energy, a hinge's axis, a hanging chain's static forces.

use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};
use serde_json::{json, Value};

use super::{elliptic_k, scenario, simulate};

const G: f64 = 9.81;

/// The stabilizer of the mechanics checks: Baumgarte's exact multipliers, so that what
/// is measured is the joints' Jacobians and `J̇ v`, not a control law's lag (the SMC
/// law solves for `ż` and leaves `w ≈ ε μ² d / K` for the part `d` of the constraint
/// jerk it does not model, which [`smc_error_shrinks_with_mu`] measures).
fn tight() -> Value {
    json!({"kind": "baumgarte", "alpha": 20.0, "beta": 20.0})
}

fn smc(mu: f64) -> Value {
    json!({"kind": "smc", "mu": mu, "k": 100.0, "epsilon": 0.1})
}

/// A bob of `size` (a cube of 1 kg) hanging from a world ball joint at the origin, `l`
/// below it, released at `theta0` from the vertical in the x-z plane.
fn pendulum(kind: &str, l: f64, theta0: f64, size: f64, duration: f64) -> Value {
    let mut joint = json!({"type": kind, "a": 1, "at": [0, 0, 0]});
    if kind == "hinge" {
        joint["axis"] = json!([0, 1, 0]);
    }
    json!({
        "name": "pendulum", "seed": 1, "duration": duration, "dt": 0.001, "integrator": "rk4",
        "stabilizer": tight(),
        "model": {
            "gravity": [0, 0, -G],
            "bodies": [{"id": 1, "mass": 1.0, "size": size,
                        "position": [l * theta0.sin(), 0, -l * theta0.cos()]}],
            "joints": [joint]
        }
    })
}

/// The times the bob's x crosses zero going up, linearly interpolated.
fn crossings(v: Value) -> Vec<f64> {
    let s = scenario(v);
    let mut last: Option<(f64, f64)> = None;
    let mut out = Vec::new();
    simulate(&s, |t, _, st| {
        let (t, x) = (t.as_secs_f64(), st.p[0].x);
        if let Some((t0, x0)) = last {
            if x0 < 0.0 && x >= 0.0 {
                out.push(t0 + (t - t0) * (-x0) / (x - x0));
            }
        }
        last = Some((t, x));
    });
    out
}

/// Mean period from up-crossings.
fn period(v: Value) -> f64 {
    let c = crossings(v);
    assert!(c.len() >= 3, "only {} crossings", c.len());
    (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64
}

#[test]
fn a_small_swing_has_the_period_two_pi_root_l_over_g() {
    let (l, theta0) = (1.0, 0.01);
    // A 1 mm bob: its own inertia shifts the period by 1e-7.
    let t = period(pendulum("ball", l, theta0, 0.001, 12.0));
    eprintln!("small swing: period {t} s");
    // 2π√(L/g), with the amplitude's first correction θ0²/16 (6e-6 here).
    let want = 2.0 * PI * (l / G).sqrt() * (1.0 + theta0 * theta0 / 16.0);
    assert!(((t - want) / want).abs() < 1e-4, "period {t} s vs {want} s");
}

#[test]
fn a_swing_from_120_degrees_has_the_elliptic_integrals_period() {
    let (l, theta0) = (1.0, 120f64.to_radians());
    let t = period(pendulum("ball", l, theta0, 0.001, 12.0));
    let want = 4.0 * (l / G).sqrt() * elliptic_k((theta0 / 2.0).sin());
    eprintln!("120° swing: period {t} s, elliptic integral {want} s");
    assert!(((t - want) / want).abs() < 1e-4, "period {t} s vs {want} s");
    // The large swing is far from the small one (2π√(L/g) = 2.006 s).
    assert!(t > 1.3 * 2.0 * PI * (l / G).sqrt());
}

/// A hinge about y lets the bob swing in the x-z plane and holds its axis: given a
/// spin about x and z besides, the bob still swings with the pendulum's period, and
/// its body y axis stays on the world's within the boundary layer.
#[test]
fn a_hinge_holds_its_axis_and_swings_like_the_pendulum() {
    let (l, theta0) = (1.0, 0.01);
    let t = period(pendulum("hinge", l, theta0, 0.001, 12.0));
    let want = 2.0 * PI * (l / G).sqrt() * (1.0 + theta0 * theta0 / 16.0);
    assert!(((t - want) / want).abs() < 1e-4, "period {t} s vs {want} s");

    // The axis under the SMC law with the thesis's parameters: held within ε.
    let mut v = pendulum("hinge", l, 0.5, 0.2, 5.0);
    v["stabilizer"] = json!({"kind": "smc"});
    v["model"]["bodies"][0]["angular_velocity"] = json!([0.3, 1.0, -0.2]);
    let s = scenario(v);
    let epsilon = match s.stabilizer {
        dsmcosim::scenario::model::Stabilizer::Smc { epsilon, .. } => epsilon,
        _ => unreachable!(),
    };
    let (mut worst, mut swung) = (0.0f64, 0.0f64);
    simulate(&s, |_, sys, st| {
        let axis = UnitQuaternion::new_normalize(st.q[0]) * Vector3::y();
        worst = worst.max(axis.cross(&Vector3::y()).norm());
        // The hinge's two alignment rows are rows 3 and 4.
        for w in &sys.violations()[3..5] {
            assert!(w.abs() <= epsilon, "alignment row off by {w}");
        }
        swung = swung.max(st.p[0].x.abs());
    });
    assert!(worst <= epsilon, "axis off by {worst} rad");
    assert!(
        swung > 0.4,
        "the hinge did not let the bob swing ({swung} m)"
    );
}

/// Two uniform rods (1 kg, 1 m) on ball joints, the first pinned at the origin,
/// released horizontal along x under gravity along −z: a compound double pendulum in
/// the x-z plane.
fn double_pendulum(duration: f64, dt: f64) -> Value {
    let rod = |id: u32, x: f64| {
        json!({"id": id, "mass": 1.0, "size": 0.05, "inertia": [1e-3, 1.0 / 12.0, 1.0 / 12.0],
               "position": [x, 0, 0]})
    };
    json!({
        "name": "double", "seed": 1, "duration": duration, "dt": dt, "integrator": "rk4",
        "stabilizer": tight(),
        "model": {
            "gravity": [0, 0, -G],
            "bodies": [rod(1, 0.5), rod(2, 1.5)],
            "joints": [{"type": "ball", "a": 1, "at": [0, 0, 0]},
                       {"type": "ball", "a": 1, "b": 2, "at": [1, 0, 0]}]
        }
    })
}

/// The double pendulum's Lagrangian equations in the angles θ1, θ2 from the downward
/// vertical (rods of mass m, length L, inertia I = mL²/12 about their centre):
/// `M11 θ̈1 + h cos Δ θ̈2 + h sin Δ θ̇2² = −3/2 m g L sin θ1`,
/// `h cos Δ θ̈1 + M22 θ̈2 − h sin Δ θ̇1² = −1/2 m g L sin θ2`,
/// with `Δ = θ1 − θ2`, `h = mL²/2`, `M11 = 5/4 mL² + I`, `M22 = 1/4 mL² + I`.
fn lagrangian_rates(y: [f64; 4]) -> [f64; 4] {
    let (m, l) = (1.0, 1.0);
    let i = m * l * l / 12.0;
    let [t1, t2, w1, w2] = y;
    let d = t1 - t2;
    let h = m * l * l / 2.0;
    let (m11, m22, m12) = (1.25 * m * l * l + i, 0.25 * m * l * l + i, h * d.cos());
    let r1 = -1.5 * m * G * l * t1.sin() - h * d.sin() * w2 * w2;
    let r2 = -0.5 * m * G * l * t2.sin() + h * d.sin() * w1 * w1;
    let det = m11 * m22 - m12 * m12;
    [
        w1,
        w2,
        (r1 * m22 - m12 * r2) / det,
        (m11 * r2 - m12 * r1) / det,
    ]
}

/// RK4 of [`lagrangian_rates`] from rest at θ1 = θ2 = π/2, sampled every `every` steps
/// of `h`: the centres of both rods.
fn lagrangian_centres(h: f64, steps: usize, every: usize) -> Vec<[Vector3<f64>; 2]> {
    let add = |y: [f64; 4], k: [f64; 4], s: f64| std::array::from_fn(|i| y[i] + s * k[i]);
    let mut y = [PI / 2.0, PI / 2.0, 0.0, 0.0];
    let centres = |y: [f64; 4]| {
        let dir = |t: f64| Vector3::new(t.sin(), 0.0, -t.cos());
        [dir(y[0]) * 0.5, dir(y[0]) + dir(y[1]) * 0.5]
    };
    let mut out = vec![centres(y)];
    for k in 1..=steps {
        let k1 = lagrangian_rates(y);
        let k2 = lagrangian_rates(add(y, k1, h / 2.0));
        let k3 = lagrangian_rates(add(y, k2, h / 2.0));
        let k4 = lagrangian_rates(add(y, k3, h));
        y = std::array::from_fn(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        if k % every == 0 {
            out.push(centres(y));
        }
    }
    out
}

#[test]
fn a_double_pendulum_follows_its_lagrangian_equations() {
    let worst = lagrangian_error(tight());
    eprintln!("double pendulum (Baumgarte): {worst:.3e} m from the Lagrangian solution over 2 s");
    assert!(worst < 1e-6, "{worst} m from the Lagrangian solution");
}

/// The largest distance of either rod's centre from the Lagrangian solution over the
/// first 2 s, with `stabilizer`.
fn lagrangian_error(stabilizer: Value) -> f64 {
    // The reference at a tenth of the step, sampled at the run's steps.
    let reference = lagrangian_centres(1e-4, 20_000, 10);
    let mut v = double_pendulum(2.0, 0.001);
    v["stabilizer"] = stabilizer;
    let s = scenario(v);
    let mut worst = 0.0f64;
    let mut k = 0;
    simulate(&s, |_, _, st| {
        let r = reference[k];
        worst = worst.max((st.p[0] - r[0]).norm().max((st.p[1] - r[1]).norm()));
        k += 1;
    });
    assert_eq!(k, reference.len());
    worst
}

/// Under SMC the joints are held by a law on `ż` that does not model the turning of
/// the Jacobian (`d/dt(J M⁻¹ Jᵀ) z`): the double pendulum then departs from its
/// Lagrangian solution by an amount that shrinks with μ at least as μ² (the boundary
/// layer's `ε μ² d / K`), and every row stays inside the layer.
#[test]
fn smc_error_shrinks_with_mu() {
    let coarse = lagrangian_error(smc(0.01));
    let fine = lagrangian_error(smc(0.005));
    eprintln!("double pendulum under SMC (K 100, ε 0.1): {coarse:.3e} m at μ 0.01, {fine:.3e} m at μ 0.005");
    assert!(coarse < 1e-2, "μ 0.01: {coarse} m");
    // Halving μ divides the error by 3.9 here (order 2); 3 leaves room for round-off.
    assert!(fine < coarse / 3.0, "μ 0.005: {fine} m, μ 0.01: {coarse} m");
}

#[test]
fn a_double_pendulum_keeps_its_energy() {
    let s = scenario(double_pendulum(10.0, 0.001));
    let energy = |st: &dsmcosim::multibody::State| -> f64 {
        (0..2)
            .map(|i| {
                let inertia = super::world_inertia(&s, st, i);
                0.5 * st.v[i].norm_squared()
                    + 0.5 * st.omega[i].dot(&(inertia * st.omega[i]))
                    + G * st.p[i].z
            })
            .sum()
    };
    let (mut worst, mut kinetic_max) = (0.0f64, 0.0f64);
    let mut e0 = None;
    simulate(&s, |_, _, st| {
        let e = energy(st);
        let e0 = *e0.get_or_insert(e);
        worst = worst.max((e - e0).abs());
        kinetic_max = kinetic_max.max(e0 - G * (st.p[0].z + st.p[1].z));
    });
    // Relative to the largest kinetic energy the swing reaches (it starts at rest).
    let relative = worst / kinetic_max;
    eprintln!(
        "double pendulum (Baumgarte): energy within {relative:.3e} of the largest KE over 10 s"
    );
    assert!(
        relative < 1e-6,
        "energy drifted {relative:.3e} of {kinetic_max} J"
    );
}

/// Ten 1 kg bodies hanging in a chain of ball joints from a world pivot, released at
/// rest on the joints: under the SMC law (the thesis's parameters) the multipliers
/// grow from zero to the static forces, and under the default law (exact multipliers)
/// they are the static forces from the first step; each joint carries the weight of
/// every body below it.
#[test]
fn a_hanging_chain_settles_with_its_joints_carrying_the_weight_below() {
    for law in [json!({"kind": "smc"}), Value::Null] {
        hanging_chain_settles(law);
    }
}

/// [`a_hanging_chain_settles_with_its_joints_carrying_the_weight_below`] under `law`
/// (null: the default).
fn hanging_chain_settles(law: Value) {
    let n = 10;
    let bodies: Vec<Value> = (0..n)
        .map(
            |i| json!({"id": i + 1, "mass": 1.0, "size": 0.1, "position": [0, 0, -0.5 - i as f64]}),
        )
        .collect();
    let mut joints = vec![json!({"type": "ball", "a": 1, "at": [0, 0, 0]})];
    for i in 1..n {
        joints.push(json!({"type": "ball", "a": i, "b": i + 1, "at": [0, 0, -(i as f64)]}));
    }
    let mut v = json!({
        "name": "chain", "seed": 1, "duration": 10.0, "dt": 0.001, "integrator": "rk4",
        "model": {"gravity": [0, 0, -G], "bodies": bodies, "joints": joints}
    });
    if !law.is_null() {
        v["stabilizer"] = law.clone();
    }
    let s = scenario(v);
    // The rows' forces at the last step (a row's tension is −z).
    let mut tension = vec![0.0; 3 * n];
    let end = simulate(&s, |_, sys, st| {
        for (row, f) in tension.iter_mut().enumerate() {
            *f = sys.tension(st, row);
        }
    });
    for j in 0..n {
        // Joint j's vertical row is row 2 of its three; it pulls its upper body up.
        let z = tension[3 * j + 2];
        let below = (n - j) as f64 * G;
        assert!(
            ((z.abs() - below) / below).abs() < 1e-6,
            "{law}: joint {}: {z} N, the weight below is {below} N",
            j + 1
        );
    }
    for i in 0..n {
        assert!(
            end.v[i].norm() < 1e-6,
            "{law}: body {} still moves at {:?}",
            i + 1,
            end.v[i]
        );
    }
}

/// Two cubes welded at their common face, spinning together about z at 1 rad/s with
/// no force: they turn as one body (relative orientation and distance kept) and keep
/// the pair's angular momentum.
#[test]
fn a_weld_makes_two_bodies_turn_as_one() {
    let cube = |id: u32, x: f64| {
        json!({"id": id, "mass": 1.0, "size": 1.0, "position": [x, 0, 0],
               "velocity": [0, x, 0], "angular_velocity": [0, 0, 1]})
    };
    let s = scenario(json!({
        "name": "weld", "seed": 1, "duration": 5.0, "dt": 0.001, "integrator": "rk4",
        "stabilizer": tight(),
        "model": {"bodies": [cube(1, -0.5), cube(2, 0.5)],
                  "joints": [{"type": "weld", "a": 1, "b": 2, "at": [0, 0, 0]}]}
    }));
    let inertia = s.bodies[0].inertia;
    let momentum = |st: &dsmcosim::multibody::State| -> Vector3<f64> {
        (0..2)
            .map(|i| {
                let r = UnitQuaternion::new_normalize(st.q[i]).to_rotation_matrix();
                let world = r.matrix()
                    * nalgebra::Matrix3::from_diagonal(&inertia)
                    * r.matrix().transpose();
                st.p[i].cross(&st.v[i]) + world * st.omega[i]
            })
            .sum()
    };
    let l0 = momentum(&dsmcosim::multibody::State::initial(&s));
    let mut turned = 0.0f64;
    simulate(&s, |t, _, st| {
        let (qa, qb) = (
            UnitQuaternion::new_normalize(st.q[0]),
            UnitQuaternion::new_normalize(st.q[1]),
        );
        assert!(
            qa.angle_to(&qb) < 1e-6,
            "t = {t}: the halves turned apart by {}",
            qa.angle_to(&qb)
        );
        assert!(((st.p[0] - st.p[1]).norm() - 1.0).abs() < 1e-6, "t = {t}");
        assert!(
            (momentum(st) - l0).norm() < 1e-6 * l0.norm(),
            "t = {t}: L {:?}",
            momentum(st)
        );
        turned = turned.max(qa.angle());
    });
    assert!(turned > 3.0, "the pair turned only {turned} rad");
}

/// Bad joints are refused naming the field and what is wrong.
#[test]
fn bad_joints_are_refused_naming_the_field() {
    let refusal = |joint: Value, extra: Option<(&str, Value)>| -> String {
        let mut v = json!({
            "name": "x", "seed": 1, "duration": 1.0, "dt": 0.01,
            "model": {"bodies": [{"id": 1, "mass": 1.0, "size": 0.1, "position": [1, 0, 0]},
                                 {"id": 2, "mass": 1.0, "size": 0.1, "position": [2, 0, 0]}],
                      "joints": [joint]}
        });
        if let Some((k, x)) = extra {
            v[k] = x;
        }
        dsmcosim::scenario::parse_str(&v.to_string(), "<test>")
            .unwrap_err()
            .to_string()
    };
    let cases = [
        (
            json!({"type": "ball", "a": 7, "at": [0, 0, 0]}),
            None,
            "model.joints[0].a: no body with id 7",
        ),
        (
            json!({"type": "ball", "a": 1, "b": 1, "at": [0, 0, 0]}),
            None,
            "model.joints[0].b: a joint cannot join body 1 to itself",
        ),
        (
            json!({"type": "hinge", "a": 1, "at": [0, 0, 0]}),
            None,
            "model.joints[0].axis: a hinge needs",
        ),
        (
            json!({"type": "hinge", "a": 1, "at": [0, 0, 0], "axis": [0, 0, 0]}),
            None,
            "model.joints[0].axis: must not be zero",
        ),
        (
            json!({"type": "ball", "a": 1, "at": [0, 0, 0], "axis": [0, 0, 1]}),
            None,
            "model.joints[0].axis: only a hinge",
        ),
        (
            json!({"type": "prismatic", "a": 1, "at": [0, 0, 0]}),
            None,
            "model.joints[0].axis: a prismatic joint needs",
        ),
        (
            json!({"type": "slider", "a": 1, "at": [0, 0, 0]}),
            None,
            "model.joints[0].type",
        ),
        (
            json!({"type": "ball", "a": 1, "at": [0, 0, 0]}),
            Some(("body_model", json!("point_mass"))),
            "model.joints: joints turn their bodies",
        ),
    ];
    for (joint, extra, want) in cases {
        let e = refusal(joint.clone(), extra);
        assert!(e.starts_with(want), "{joint}: {e}");
    }
}

/// Joint rows go through every multiplier solve: the double pendulum under CG with a
/// generous budget and under the reused factor follows the exact solve's run.
#[test]
fn joints_solve_alike_exactly_and_iteratively() {
    let with = |solver: Value| {
        let mut v = double_pendulum(1.0, 0.001);
        v["solver"] = solver;
        let s = scenario(v);
        let mut ends = Vec::new();
        simulate(&s, |_, _, st| ends.push([st.p[0], st.p[1]]));
        ends
    };
    let exact = with(json!({"kind": "cholesky"}));
    for solver in [
        json!({"kind": "cg", "max_iterations": 200, "tolerance": 1e-14}),
        json!({"kind": "cholesky_pcg"}),
    ] {
        let other = with(solver.clone());
        let worst = exact
            .iter()
            .zip(&other)
            .map(|(a, b)| (a[0] - b[0]).norm().max((a[1] - b[1]).norm()))
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "{solver}: {worst} m from the exact solve");
    }
}
