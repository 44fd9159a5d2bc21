//! Real-time factor of partitioned co-simulations with ideal channels.
//!
//! Run: `cargo bench --bench cosim`. Each iteration simulates 1 s (1000 lock-steps of
//! every node with their messages) from a fresh world; throughput is in lock-steps, so
//! criterion's `elem/s` divided by 1000 is the real-time factor.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use dsmcosim::cosim::CoSim;
use dsmcosim::kernel::SimTime;
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

fn bench_cosim(c: &mut Criterion) {
    let space = json!([
        {"name": "tau1", "tau": 0.005, "borders": [[1, 2], [1, 4]]},
        {"name": "tau2", "tau": 0.005, "borders": [[2, 3], [3, 4]]}
    ]);
    let one = json!([{"name": "all", "tau": 0.005}]);
    let cases = [
        ("grid4_monolithic", grid(4, json!([]), None)),
        (
            "grid4_4nodes_space_5ms",
            grid(4, space, Some(json!({"quadrants": true}))),
        ),
        ("grid8_monolithic", grid(8, json!([]), None)),
        (
            "grid8_16nodes_5ms",
            grid(8, one, Some(json!({"quadrants": true}))),
        ),
    ];
    let mut group = c.benchmark_group("cosim_1s");
    group.throughput(Throughput::Elements(1000));
    group.sample_size(20);
    for (name, world) in cases {
        group.bench_function(name, |b| {
            b.iter_batched_ref(
                || world.clone(),
                |w| {
                    w.advance_to(SimTime(1_000_000_000), &mut ())
                        .expect("bench run")
                },
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, bench_cosim);
criterion_main!(benches);
