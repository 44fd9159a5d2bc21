//! Cost per step of each coupling scheme on the thesis scene, as ratios measured in
//! one run.
//!
//! Run: `cargo bench --bench coupling`. Every case simulates 1 s of `grid16_space_fixed`
//! (4×4 grid on 4 quadrant nodes, both channels at τ = 5 ms, latency = τ; 1000
//! lock-steps) from a fresh copy of a world built outside the timed closure, under
//! `reset`, `predict`, `passive` and `tlm` (every border link a transmission line);
//! and 1 s of a 16×16 grid (256 bodies, body 1 driven)
//! on 4 nodes of 8×8 bodies, one channel at 5 ms, latency 5 ms, under `reset` and
//! `passive` (`big_*`): the coupling's work grows with the border, a node's step with
//! its bodies. After criterion has measured them, the bench prints each case's wall
//! time per step and its ratio to `reset` of the same scene, from the medians of this
//! run.
mod common;

use std::time::SystemTime;

use criterion::{criterion_group, Criterion};
use dsmcosim::cosim::CoSim;
use dsmcosim::scenario::parse_str;
use serde_json::json;

const GROUP: &str = "coupling_1s";
const CASES: [&str; 6] = [
    "reset",
    "predict",
    "passive",
    "tlm",
    "big_reset",
    "big_passive",
];

fn world(case: &str) -> CoSim {
    if let Some(scheme) = case.strip_prefix("big_") {
        return big(scheme);
    }
    let scheme = case;
    let mut v = common::shipped_one_second("grid16_space_fixed");
    v["partition"]["coupling"] = json!(scheme);
    CoSim::new(&parse_str(&v.to_string(), scheme).expect("valid scenario"))
}

/// 16×16 grid on 4 nodes of 8×8 bodies.
fn big(scheme: &str) -> CoSim {
    let n = 16;
    let mut nodes = vec![Vec::new(); 4];
    for r in 0..n {
        for c in 0..n {
            nodes[(r / 8) * 2 + c / 8].push(r * n + c + 1);
        }
    }
    let v = json!({
        "name": "big", "seed": 1, "duration": 1.0, "dt": 0.001,
        "model": {"grid": {"rows": n, "cols": n, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0}],
        "partition": {"nodes": nodes, "coupling": scheme},
        "channels": [{"name": "all", "tau": 0.005}]
    });
    CoSim::new(&parse_str(&v.to_string(), scheme).expect("valid scenario"))
}

fn bench_coupling(c: &mut Criterion) {
    common::bench_one_second(c, GROUP, &CASES, 40, world);
}

fn print_table(since: SystemTime) {
    println!("\n1 s simulated, 1000 lock-steps (criterion medians of this run):");
    println!(
        "  {:<12} {:>14} {:>10}",
        "case", "per step [µs]", "vs reset"
    );
    for case in CASES {
        let base = if case.starts_with("big_") {
            "big_reset"
        } else {
            "reset"
        };
        let reset = common::median(GROUP, base, since);
        let Some(ns) = common::median(GROUP, case, since) else {
            println!("  {case:<12} (not measured in this run)");
            continue;
        };
        println!(
            "  {case:<12} {:>14.3} {:>10}",
            ns / 1000.0 / 1000.0,
            common::times(ns, reset),
        );
    }
}

criterion_group!(benches, bench_coupling);

fn main() {
    common::run_then(benches, print_table);
}
