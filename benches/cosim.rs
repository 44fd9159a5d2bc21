//! Real-time factor of partitioned co-simulations with ideal channels.
//!
//! Run: `cargo bench --bench cosim`. Each iteration simulates 1 s (1000 lock-steps of
//! every node with their messages) from a fresh world; throughput is in lock-steps, so
//! criterion's `elem/s` divided by 1000 is the real-time factor.

mod common;

use criterion::{criterion_group, criterion_main, Criterion};
use dsmcosim::cosim::CoSim;
use dsmcosim::scenario::parse_str;
use serde_json::{json, Value};

fn grid(n: usize, channels: Value, partition: Option<Value>) -> CoSim {
    let mut v = json!({
        "name": "bench", "seed": 1, "duration": 1.0, "dt": 0.001,
        "model": {"grid": {"rows": n, "cols": n, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0}],
    });
    if let Some(p) = partition {
        v["partition"] = p;
        v["channels"] = channels;
    }
    CoSim::new(&parse_str(&v.to_string(), "bench").expect("valid bench scenario"))
}

const CASES: [&str; 4] = [
    "grid4_monolithic",
    "grid4_4nodes_space_5ms",
    "grid8_monolithic",
    "grid8_16nodes_5ms",
];

fn world(case: &str) -> CoSim {
    let space = json!([
        {"name": "tau1", "tau": 0.005, "borders": [[1, 2], [1, 4]]},
        {"name": "tau2", "tau": 0.005, "borders": [[2, 3], [3, 4]]}
    ]);
    let one = json!([{"name": "all", "tau": 0.005}]);
    let quadrants = Some(json!({"quadrants": true}));
    match case {
        "grid4_monolithic" => grid(4, json!([]), None),
        "grid4_4nodes_space_5ms" => grid(4, space, quadrants),
        "grid8_monolithic" => grid(8, json!([]), None),
        _ => grid(8, one, quadrants),
    }
}

fn bench_cosim(c: &mut Criterion) {
    common::bench_one_second(c, "cosim_1s", &CASES, 20, world);
}

criterion_group!(benches, bench_cosim);
criterion_main!(benches);
