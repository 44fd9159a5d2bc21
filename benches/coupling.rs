//! Cost per step of each coupling scheme on the thesis scene, as ratios measured in
//! one run.
//!
//! Run: `cargo bench --bench coupling`. Every case simulates 1 s of `grid16_space_fixed`
//! (4×4 grid on 4 quadrant nodes, both channels at τ = 5 ms, latency = τ; 1000
//! lock-steps) from a fresh copy of a world built outside the timed closure, under
//! `reset`, `predict` and `passive`. After criterion has measured them, the bench prints
//! each case's wall time per step and its ratio to `reset`, from the medians of this
//! run.
mod common;

use std::time::SystemTime;

use criterion::{criterion_group, BatchSize, Criterion, Throughput};
use dsmcosim::cosim::CoSim;
use dsmcosim::kernel::SimTime;
use dsmcosim::scenario::parse_str;
use serde_json::{json, Value};

const GROUP: &str = "coupling_1s";
const ONE_SECOND: SimTime = SimTime(1_000_000_000);
const CASES: [&str; 3] = ["reset", "predict", "passive"];

fn world(scheme: &str) -> CoSim {
    let p = format!(
        "{}/scenarios/grid16_space_fixed.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut v: Value =
        serde_json::from_str(&std::fs::read_to_string(p).expect("scenario")).expect("json");
    v["duration"] = json!(1.0);
    v["partition"]["coupling"] = json!(scheme);
    CoSim::new(&parse_str(&v.to_string(), scheme).expect("valid scenario"))
}

fn bench_coupling(c: &mut Criterion) {
    let mut group = c.benchmark_group(GROUP);
    group.throughput(Throughput::Elements(1000));
    group.sample_size(40);
    for case in CASES {
        let w = world(case);
        group.bench_function(case, |b| {
            b.iter_batched_ref(
                || w.clone(),
                |w| w.advance_to(ONE_SECOND, &mut ()).expect("bench run"),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

fn print_table(since: SystemTime) {
    println!("\n4-node thesis scene, 1 s simulated (criterion medians of this run):");
    println!(
        "  {:<8} {:>14} {:>10}",
        "scheme", "per step [µs]", "vs reset"
    );
    let reset = common::median(GROUP, "reset", since);
    for case in CASES {
        let Some(ns) = common::median(GROUP, case, since) else {
            println!("  {case:<8} (not measured in this run)");
            continue;
        };
        println!(
            "  {case:<8} {:>14.3} {:>10}",
            ns / 1000.0 / 1000.0,
            reset.map_or("—".into(), |r| format!("{:.3}×", ns / r)),
        );
    }
}

criterion_group!(benches, bench_coupling);

fn main() {
    let started = SystemTime::now();
    benches();
    Criterion::default().configure_from_args().final_summary();
    print_table(started);
}
