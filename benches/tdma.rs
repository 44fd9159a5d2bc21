//! TDMA against ideal channels on the 16-node scene, as ratios measured in one run.
//!
//! Run: `cargo bench --bench tdma`. Every case simulates 1 s of `tdma16_space_fixed`
//! (8×8 grid on 16 quadrant nodes, two delay classes at 5 ms; 1000 lock-steps) from a
//! fresh copy of a world built outside the timed closure:
//!
//! - `ideal`: the same channels on ideal channels with zero latency (sample and hold,
//!   what TDMA's microsecond latencies approximate);
//! - `tdma_plain`: the TDMA network without drift, random walk, sync error or jitter
//!   (nothing is drawn);
//! - `tdma_full`: the shipped scenario, drift 50 ppm + random walk + sync error +
//!   exponential jitter.
//!
//! After criterion has measured them, the bench prints each case's kernel events per
//! wall second and real-time factor, and the ratios against `ideal`, all from the
//! medians of this run.
mod common;

use std::time::SystemTime;

use criterion::{criterion_group, Criterion};
use dsmcosim::cosim::CoSim;
use dsmcosim::kernel::SimTime;
use dsmcosim::scenario::parse_str;
use serde_json::{json, Value};

const GROUP: &str = "tdma16_1s";
const ONE_SECOND: SimTime = SimTime(1_000_000_000);
const CASES: [&str; 3] = ["ideal", "tdma_plain", "tdma_full"];

fn shipped() -> Value {
    common::shipped_one_second("tdma16_space_fixed")
}

fn world(case: &str) -> CoSim {
    let mut v = shipped();
    match case {
        "ideal" => {
            v["network"] = json!({"kind": "ideal"});
            for c in v["channels"].as_array_mut().expect("channels") {
                c["latency"] = json!(0.0);
            }
        }
        "tdma_plain" => {
            let n = v["network"].as_object_mut().expect("network");
            for key in ["drift_ppm", "random_walk_ppm", "sync_error", "jitter"] {
                n.remove(key);
            }
        }
        _ => {}
    }
    CoSim::new(&parse_str(&v.to_string(), case).expect("valid bench scenario"))
}

fn bench_tdma(c: &mut Criterion) {
    common::bench_one_second(c, GROUP, &CASES, 20, world);
}

/// Median time [ns] criterion recorded for `case` of this bench's group since `since`.
fn median(case: &str, since: SystemTime) -> Option<f64> {
    common::median(GROUP, case, since)
}

fn print_table(since: SystemTime) {
    println!("\n16-node scene, 1 s simulated (criterion medians of this run):");
    println!(
        "  {:<11} {:>10} {:>12} {:>14} {:>8} {:>11}",
        "case", "wall [ms]", "events", "events/s", "RTF", "vs ideal"
    );
    let ideal = median("ideal", since);
    for case in CASES {
        let Some(ns) = median(case, since) else {
            println!("  {case:<11} (not measured in this run)");
            continue;
        };
        let mut w = world(case);
        w.advance_to(ONE_SECOND, &mut ()).expect("run");
        let events = w.events();
        let secs = ns / 1e9;
        println!(
            "  {case:<11} {:>10.2} {:>12} {:>14.3e} {:>8.1} {:>11}",
            ns / 1e6,
            events,
            events as f64 / secs,
            1.0 / secs,
            common::times(ns, ideal),
        );
    }
}

criterion_group!(benches, bench_tdma);

fn main() {
    common::run_then(benches, print_table);
}
