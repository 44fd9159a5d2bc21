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
