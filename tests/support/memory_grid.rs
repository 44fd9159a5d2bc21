//! A monolithic n×n grid run for 10 steps, shared by the memory tests of `tests/cli`
//! (the address-space refusal) and `tests/memory_peak.rs` (the estimate's bound).

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
