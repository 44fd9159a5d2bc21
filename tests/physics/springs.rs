//! Spring-dampers (`model.springs`) against their closed forms and the conservation
//! laws: a mass on a spring oscillates at `√(k/m)` and keeps `KE + k x²/2`; damping
//! shrinks each swing by `exp(−c T/2m)`; a free pair on a spring between off-centre
//! anchors keeps momentum, angular momentum and energy.

use std::f64::consts::PI;

use dsmcosim::multibody::spring;
use dsmcosim::multibody::State;
use nalgebra::{UnitQuaternion, Vector3};
use serde_json::{json, Value};

use super::{scenario, simulate};

/// A 2 kg body on a spring of `k` N/m and `c` N·s/m to the world point 1 m along x,
/// its rest length 1 m, released 0.1 m out along x, no gravity.
fn oscillator(k: f64, c: f64, duration: f64) -> Value {
    json!({
        "name": "oscillator", "seed": 1, "duration": duration, "dt": 0.001, "integrator": "rk4",
        "model": {
            "bodies": [{"id": 1, "mass": 2.0, "size": 0.1, "position": [2.1, 0, 0]}],
            "springs": [{"a": 1, "anchor_b": [1, 0, 0], "stiffness": k, "damping": c,
                         "length": 1.0}]
        }
    })
}

/// Times of the maxima of x and their values, from a parabola through each local
/// maximum of the sampled x.
fn peaks(v: Value) -> Vec<(f64, f64)> {
    let s = scenario(v);
    let mut xs = Vec::new();
    simulate(&s, |t, _, st| xs.push((t.as_secs_f64(), st.p[0].x)));
    let mut out = Vec::new();
    for w in xs.windows(3) {
        let (a, b, c) = (w[0].1, w[1].1, w[2].1);
        if b > a && b >= c {
            let h = w[1].0 - w[0].0;
            let shift = 0.5 * (a - c) / (a - 2.0 * b + c);
            let top = b - 0.25 * (a - c) * shift;
            out.push((w[1].0 + shift * h, top));
        }
    }
    out
}

#[test]
fn a_mass_on_a_spring_oscillates_at_root_k_over_m_and_keeps_its_energy() {
    let (k, m) = (50.0, 2.0);
    let s = scenario(oscillator(k, 0.0, 10.0));
    let mut worst = 0.0f64;
    let mut e0 = None;
    simulate(&s, |_, _, st| {
        let e = 0.5 * m * st.v[0].norm_squared() + spring::energy(&s.springs[0], st, false);
        worst = worst.max((e - *e0.get_or_insert(e)).abs());
    });
    let p = peaks(oscillator(k, 0.0, 10.0));
    let period = (p[p.len() - 1].0 - p[0].0) / (p.len() - 1) as f64;
    let want = 2.0 * PI * (m / k).sqrt();
    eprintln!(
        "spring: period {period:.9} s (closed form {want:.9} s), energy within {worst:.3e} J"
    );
    assert!(
        ((period - want) / want).abs() < 1e-6,
        "period {period} vs {want}"
    );
    // 0.01 J of spring energy at the start: kept to RK4's truncation.
    assert!(worst < 1e-9, "energy moved by {worst} J");
}

#[test]
fn damping_shrinks_each_swing_by_its_closed_form_factor() {
    let (k, m, c) = (50.0, 2.0, 0.4);
    let p = peaks(oscillator(k, c, 10.0));
    let omega_d = (k / m - (c / (2.0 * m)).powi(2)).sqrt();
    let want = (-c / (2.0 * m) * 2.0 * PI / omega_d).exp();
    // x − 2 (the rest point) decays by the factor per period.
    let ratio = (p[3].1 - 2.0) / (p[2].1 - 2.0);
    eprintln!("damped spring: swing ratio {ratio:.9} (closed form {want:.9})");
    assert!((ratio - want).abs() < 1e-6, "ratio {ratio} vs {want}");
}

#[test]
fn a_free_pair_on_a_spring_keeps_momentum_angular_momentum_and_energy() {
    let s = scenario(json!({
        "name": "pair", "seed": 1, "duration": 5.0, "dt": 0.001, "integrator": "rk4",
        "model": {
            "bodies": [
                {"id": 1, "mass": 1.0, "size": 0.2, "position": [0, 0, 0],
                 "velocity": [0, 0.5, 0.1], "angular_velocity": [0.2, 0, 1]},
                {"id": 2, "mass": 3.0, "size": 0.3, "inertia": [0.02, 0.03, 0.04],
                 "position": [1.5, 0, 0], "velocity": [0, -0.2, 0]}
            ],
            "springs": [{"a": 1, "b": 2, "anchor_a": [0.1, 0, 0], "anchor_b": [-0.15, 0.05, 0],
                         "stiffness": 20.0, "length": 1.0}]
        }
    }));
    let inertia = |i: usize, st: &State| super::world_inertia(&s, st, i);
    let invariants = |st: &State| {
        let (mut p, mut l, mut e) = (Vector3::zeros(), Vector3::zeros(), 0.0);
        for (i, b) in s.bodies.iter().enumerate() {
            p += st.v[i] * b.mass;
            l += st.p[i].cross(&st.v[i]) * b.mass + inertia(i, st) * st.omega[i];
            e += 0.5 * b.mass * st.v[i].norm_squared()
                + 0.5 * st.omega[i].dot(&(inertia(i, st) * st.omega[i]));
        }
        (p, l, e + spring::energy(&s.springs[0], st, true))
    };
    let first = invariants(&State::initial(&s));
    let (mut dp, mut dl, mut de, mut turned) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    simulate(&s, |_, _, st| {
        let (p, l, e) = invariants(st);
        dp = dp.max((p - first.0).norm());
        dl = dl.max((l - first.1).norm());
        de = de.max((e - first.2).abs());
        turned = turned.max(UnitQuaternion::new_normalize(st.q[1]).angle());
    });
    eprintln!(
        "spring pair: |ΔP| {dp:.3e}, |ΔL| {dl:.3e}, |ΔE| {de:.3e} J; body 2 turned {turned:.2} rad"
    );
    // The off-centre anchors turn the bodies: the spring's torques are at work.
    assert!(turned > 0.1, "body 2 turned only {turned} rad");
    assert!(dp < 1e-12 && dl < 1e-9 && de < 1e-7, "{dp} {dl} {de}");
}

#[test]
fn bad_springs_are_refused_naming_the_field() {
    let refusal = |spring: Value, extra: Option<(&str, Value)>| -> String {
        let mut v = json!({
            "name": "x", "seed": 1, "duration": 1.0, "dt": 0.01,
            "model": {"bodies": [{"id": 1, "mass": 1.0, "size": 0.1, "position": [1, 0, 0]},
                                 {"id": 2, "mass": 1.0, "size": 0.1, "position": [2, 0, 0]}],
                      "links": [],
                      "springs": [spring]}
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
            json!({"a": 7, "stiffness": 1}),
            None,
            "model.springs[0].a: no body with id 7",
        ),
        (
            json!({"a": 1, "b": 1, "stiffness": 1}),
            None,
            "model.springs[0].b: a spring cannot join body 1",
        ),
        (
            json!({"a": 1, "b": 2, "stiffness": -1}),
            None,
            "model.springs[0].stiffness: must be ≥ 0",
        ),
        (
            json!({"a": 1, "b": 2, "stiffness": 1, "damping": -2}),
            None,
            "model.springs[0].damping: must be ≥ 0",
        ),
        (json!({"a": 1, "b": 2}), None, "model.springs[0]"),
        (
            json!({"a": 1, "anchor_b": [1, 0, 0], "stiffness": 1, "length": 0}),
            None,
            "model.springs[0].length: a spring of rest length 0 must start stretched",
        ),
        (
            json!({"a": 1, "b": 2, "anchor_a": [0.05, 0, 0], "stiffness": 1}),
            Some(("body_model", json!("point_mass"))),
            "model.springs[0]: an anchor off a body's centre",
        ),
        (
            json!({"a": 1, "b": 2, "stiffness": 1}),
            Some(("partition", json!({"nodes": [[1], [2]]}))),
            "model.springs[0]: joins body 1 on node 1 to body 2 on node 2",
        ),
    ];
    for (spring, extra, want) in cases {
        let e = refusal(spring.clone(), extra);
        assert!(e.starts_with(want), "{spring}: {e}");
    }
}
