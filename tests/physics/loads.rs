//! Gravity, forces away from the centre and pure torques, against closed forms.

use nalgebra::{UnitQuaternion, Vector3};
use serde_json::json;

use super::{scenario, simulate};

/// A body thrown under gravity follows `p0 + v0 t + g t²/2`: RK4 integrates a quadratic
/// exactly, so the only error is round-off.
#[test]
fn a_body_thrown_under_gravity_follows_the_parabola() {
    let s = scenario(json!({
        "name": "throw", "seed": 1, "duration": 2.0, "dt": 0.01, "integrator": "rk4",
        "model": {
            "gravity": [0.0, 0.0, -9.81],
            "bodies": [{"id": 1, "mass": 3.0, "size": 0.1, "position": [1, 2, 3],
                        "velocity": [2, -1, 10]}]
        }
    }));
    let (p0, v0, g) = (
        Vector3::new(1.0, 2.0, 3.0),
        Vector3::new(2.0, -1.0, 10.0),
        Vector3::new(0.0, 0.0, -9.81),
    );
    let mut checked = 0;
    simulate(&s, |t, _, st| {
        let t = t.as_secs_f64();
        let expected = p0 + v0 * t + g * (0.5 * t * t);
        assert!(
            (st.p[0] - expected).norm() < 1e-11,
            "t = {t}: {:?} instead of {expected:?}",
            st.p[0]
        );
        assert!((st.v[0] - (v0 + g * t)).norm() < 1e-11, "t = {t}");
        checked += 1;
    });
    assert_eq!(checked, 201);
}

/// A constant force F = (0, 1, 0) N at the body point r = (0.5, 0, 0) m of a free body
/// at rest: its centre accelerates as F/m wherever the force acts, and it turns about z
/// with `I_zz θ̈ = |r| |F| cos θ` (the arm turns with the body), whose first integral is
/// `I_zz θ̇² / 2 = |r| |F| sin θ`.
#[test]
fn a_force_off_the_centre_turns_the_body_with_the_torque_r_cross_f() {
    let s = scenario(json!({
        "name": "lever", "seed": 1, "duration": 6.0, "dt": 0.001, "integrator": "rk4",
        "model": {"bodies": [{"id": 1, "mass": 2.0, "size": 0.1, "inertia": [1.0, 2.0, 3.0],
                              "position": [0, 0, 0]}]},
        "forces": [{"body": 1, "amplitude": [0, 1, 0], "phase": std::f64::consts::FRAC_PI_2,
                    "point": [0.5, 0, 0]}]
    }));
    assert_eq!(s.body_model, dsmcosim::scenario::model::BodyModel::Rigid);
    let mut turned: f64 = 0.0;
    simulate(&s, |t, _, st| {
        let t = t.as_secs_f64();
        assert!(
            (st.v[0] - Vector3::new(0.0, t / 2.0, 0.0)).norm() < 1e-12,
            "t = {t}"
        );
        let arm = UnitQuaternion::new_normalize(st.q[0]) * Vector3::x();
        let theta = arm.y.atan2(arm.x);
        let w = st.omega[0];
        assert!(
            w.x.abs() < 1e-12 && w.y.abs() < 1e-12,
            "t = {t}: ω {w:?} leaves z"
        );
        let first_integral = 3.0 * w.z * w.z / 2.0 - 0.5 * theta.sin();
        assert!(first_integral.abs() < 1e-9, "t = {t}: θ {theta}, ω {w:?}");
        turned = turned.max(theta);
    });
    // The lever turns well past a small angle, where cos θ matters.
    assert!(turned > 1.0, "turned only {turned} rad");
}

/// A constant pure torque τ about z on a body at rest: `ω = τ t / I_zz`, `θ = τ t² / (2 I_zz)`,
/// and the centre does not move.
#[test]
fn a_pure_torque_spins_the_body_up_without_moving_its_centre() {
    let s = scenario(json!({
        "name": "spin", "seed": 1, "duration": 1.0, "dt": 0.001, "integrator": "rk4",
        "model": {"bodies": [{"id": 1, "mass": 2.0, "size": 0.1, "inertia": [1.0, 2.0, 4.0],
                              "position": [1, 1, 1]}]},
        "torques": [{"body": 1, "amplitude": [0, 0, 2], "phase": std::f64::consts::FRAC_PI_2}]
    }));
    simulate(&s, |t, _, st| {
        let t = t.as_secs_f64();
        assert!((st.omega[0] - Vector3::new(0.0, 0.0, t / 2.0)).norm() < 1e-12);
        let theta = UnitQuaternion::new_normalize(st.q[0]).angle();
        assert!((theta - t * t / 4.0).abs() < 1e-9, "t = {t}: θ {theta}");
        assert_eq!(st.p[0], Vector3::new(1.0, 1.0, 1.0));
        assert_eq!(st.v[0], Vector3::zeros());
    });
}

#[test]
fn loads_that_turn_a_body_are_refused_on_point_masses() {
    let base = |extra: serde_json::Value| {
        let mut v = json!({
            "name": "x", "seed": 1, "duration": 1.0, "dt": 0.01, "body_model": "point_mass",
            "model": {"bodies": [{"id": 1, "mass": 1.0, "size": 0.1, "position": [0, 0, 0]}]}
        });
        for (k, x) in extra.as_object().unwrap() {
            v[k] = x.clone();
        }
        dsmcosim::scenario::parse_str(&v.to_string(), "<test>")
            .unwrap_err()
            .to_string()
    };
    let e = base(json!({"forces": [{"body": 1, "amplitude": [1, 0, 0], "point": [0, 1, 0]}]}));
    assert!(e.contains("forces[0].point") && e.contains("rigid"), "{e}");
    let e = base(json!({"torques": [{"body": 1, "amplitude": [1, 0, 0]}]}));
    assert!(
        e.contains("torques[0].amplitude") && e.contains("rigid"),
        "{e}"
    );
    let e = base(json!({"body_model": "rigid",
                        "torques": [{"body": 1, "amplitude": [1, 0, 0], "point": [0, 1, 0]}]}));
    assert!(
        e.starts_with("torques[0].point: a torque acts about the body's centre"),
        "{e}"
    );
}
