//! A run whose `|w|` leaves the SMC boundary layer `ε` says so on stderr and in
//! summary.json's `boundary_layer`, whose counts this file recounts from a trace of every
//! step; a run inside it reports zero steps outside and prints nothing.

use serde_json::{json, Value};

use super::{run_in, said, scratch, short_grid, summary};

/// Per trace row: `t` and the largest `|w_L<k>|` over the links.
fn max_w_per_row(trace: &str) -> Vec<(f64, f64)> {
    let mut lines = trace.lines();
    let head: Vec<&str> = lines.next().expect("header").split(',').collect();
    let links: Vec<usize> = (0..head.len())
        .filter(|&c| head[c].starts_with("w_L"))
        .collect();
    lines
        .map(|l| {
            let cells: Vec<f64> = l.split(',').map(|x| x.parse().expect("number")).collect();
            let max = links.iter().fold(0.0f64, |m, &c| m.max(cells[c].abs()));
            (cells[0], max)
        })
        .collect()
}

#[test]
fn a_run_that_leaves_the_boundary_layer_says_so() {
    let dir = scratch("boundary_layer_out");
    let mut v = short_grid();
    v["duration"] = json!(1.0);
    // Fifteen times the thesis load on one corner: the links stretch past ε = 0.1 m
    // (and stay below the 1 m divergence bound).
    v["forces"][0]["amplitude"] = json!([0, 0, 300]);
    v["output"]["decimation"] = json!(1);
    let (o, out) = run_in(&dir, &v);
    assert!(o.status.success(), "{}", said(&o));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("warning: max |w| left the SMC boundary layer ε = 0.1 m on "),
        "{}",
        said(&o)
    );
    let s = summary(&out);
    let b = &s["boundary_layer"];
    // Recounted from the trace, which keeps every step here.
    let rows = max_w_per_row(&std::fs::read_to_string(out.join("trace.csv")).unwrap());
    assert_eq!(rows.len(), 1001);
    let outside = rows.iter().filter(|r| r.1 > 0.1).count() as u64;
    assert!(outside > 0, "the scene must leave the layer");
    assert_eq!(b["steps_outside"].as_u64(), Some(outside), "{b}");
    assert_eq!(b["share_outside"].as_f64(), Some(outside as f64 / 1001.0));
    assert_eq!(b["epsilon"].as_f64(), Some(0.1));
    let worst = rows.iter().fold(0.0f64, |m, r| m.max(r.1));
    let at = rows.iter().find(|r| r.1 == worst).unwrap().0;
    assert_eq!(b["worst"].as_f64(), Some(worst));
    assert_eq!(b["worst_time"].as_f64(), Some(at));
    assert!(
        stderr.contains(&format!("on {outside} of 1001 steps")),
        "{stderr}"
    );
}

#[test]
fn a_run_inside_the_boundary_layer_reports_no_step_outside() {
    let dir = scratch("boundary_layer_in");
    let (o, out) = run_in(&dir, &short_grid());
    assert!(o.status.success(), "{}", said(&o));
    assert!(o.stderr.is_empty(), "{}", said(&o));
    let s = summary(&out);
    let b = &s["boundary_layer"];
    assert_eq!(b["steps_outside"].as_u64(), Some(0), "{b}");
    assert_eq!(b["share_outside"].as_f64(), Some(0.0));
    let worst = b["worst"].as_f64().unwrap();
    assert!(worst > 0.0 && worst <= 0.1, "{b}");
    assert_eq!(b["worst"], s["max_constraint_violation"]);
    // Baumgarte has no boundary layer: no account of one.
    let dir = scratch("boundary_layer_baumgarte");
    let mut v = short_grid();
    v["stabilizer"] = json!({"kind": "baumgarte", "alpha": 10.0, "beta": 10.0});
    let (o, out) = run_in(&dir, &v);
    assert!(o.status.success(), "{}", said(&o));
    assert_eq!(summary(&out).get("boundary_layer"), None::<&Value>);
}

/// A bob on its steady cone, 1 m below a world ball joint, for 0.3 s, under `law`
/// (null: the default of a scene with joints).
fn cone(law: Value) -> Value {
    let (g, l, theta) = (9.81f64, 1.0f64, 30f64.to_radians());
    let omega = (g / (l * theta.cos())).sqrt();
    let mut v = json!({
        "name": "cone", "seed": 1, "duration": 0.3, "dt": 0.001, "integrator": "rk4",
        "model": {"gravity": [0, 0, -g],
                  "bodies": [{"id": 1, "mass": 1.0, "size": 0.1,
                              "position": [l * theta.sin(), 0, -l * theta.cos()],
                              "velocity": [0, omega * l * theta.sin(), 0],
                              "angular_velocity": [0, 0, omega]}],
                  "joints": [{"type": "ball", "a": 1, "at": [0, 0, 0]}]}
    });
    if !law.is_null() {
        v["stabilizer"] = law;
    }
    v
}

/// The work a law does on a joint is measured, reported in summary.json's
/// `joint_work`, and named on stderr when it is a visible share of the mechanism's
/// energy: the SMC law by name does some on a conical pendulum; the default does none.
#[test]
fn a_law_that_does_work_on_a_joint_says_so() {
    let dir = scratch("joint_work_out");
    let (o, out) = run_in(&dir, &cone(json!({"kind": "smc"})));
    assert!(o.status.success(), "{}", said(&o));
    let work = &summary(&out)["joint_work"];
    let share = work["share_of_kinetic_energy"].as_f64().expect("share");
    assert!(share > 0.01, "{work}");
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("warning: the joints' forces did "),
        "{}",
        said(&o)
    );
    let dir = scratch("joint_work_default_out");
    let (o, out) = run_in(&dir, &cone(Value::Null));
    assert!(o.status.success(), "{}", said(&o));
    let work = &summary(&out)["joint_work"];
    // Round-off: the joint stays closed to the integrator's truncation.
    assert!(work["net"].as_f64().expect("net").abs() < 1e-6, "{work}");
    assert!(
        !String::from_utf8_lossy(&o.stderr).contains("the joints' forces did"),
        "{}",
        said(&o)
    );
}
