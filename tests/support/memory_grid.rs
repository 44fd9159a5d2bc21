//! The scenes of the memory tests, shared by `tests/cli` (the address-space refusal,
//! the out-of-memory failure) and `tests/memory_peak.rs` (the estimate's bound): a
//! monolithic n×n grid and a chain of joints, each run for 10 steps.

use serde_json::{json, Value};

/// A monolithic point-mass grid of `n × n` bodies, 10 steps, one traced body, on
/// `solver` (`None`: the default exact solve): the scenes of the memory table in
/// docs/reference.md.
pub fn memory_grid(n: u32, solver: Option<Value>) -> Value {
    let mut v = json!({
        "name": format!("grid{n}"), "seed": 7, "duration": 0.01, "dt": 0.001,
        "integrator": "euler",
        "stabilizer": {"kind": "smc", "mu": 0.05, "k": 10.0, "epsilon": 0.1},
        "model": {"grid": {"rows": n, "cols": n, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0, "phase": 0.0,
                    "from": 0.0, "until": 0.01}],
        "measurement": {"period": 0.005},
        "output": {"decimation": 10, "trace_bodies": [1], "plot_bodies": [1]}
    });
    if let Some(s) = solver {
        v["solver"] = s;
    }
    v
}

/// A chain of `n` bodies on `kind` joints (weld: 6 rows each, ball: 3), 10 steps, the
/// exact solve: three to six rows per body where a grid has two.
#[allow(dead_code)] // not every includer builds chains
pub fn joint_chain(n: usize, kind: &str) -> Value {
    let bodies: Vec<_> = (0..n)
        .map(|i| {
            json!({"id": i + 1, "mass": 1.0, "size": 0.1, "position": [i as f64, 0, 0],
                        "angular_velocity": [0, 0, 0.001]})
        })
        .collect();
    let joints: Vec<_> = (0..n - 1)
        .map(|i| json!({"type": kind, "a": i + 1, "b": i + 2, "at": [i as f64 + 0.5, 0, 0]}))
        .collect();
    json!({"name": format!("{kind}_chain"), "seed": 1, "duration": 0.01, "dt": 0.001,
           "model": {"bodies": bodies, "joints": joints}, "output": {"decimation": 10}})
}
