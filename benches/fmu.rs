//! Cost of FMU nodes: one FMU step, and one exchange of FMU signals over a channel.
//!
//! Run: `cargo bench --bench fmu` (needs a C compiler: it builds the test FMUs msd and
//! pd from `tests/fmus/` first, into `target/bench-fmus/`). Each iteration simulates
//! 1 s, 1000 lock-steps of dt = 1 ms, from a fresh copy of a world:
//!
//! - `msd_alone`, `pd_alone`: one FMU, nothing connected (its `doStep` and the kernel's
//!   lock-step around it);
//! - `loop_ideal_every_step`: plant and controller over two ideal channels sampled every
//!   step, so every lock-step adds two FMU steps, three values sampled and delivered in
//!   two messages (x and v on `sense`, u on `act`);
//! - `loop_tdma`: the same loop on a 5-ms TDMA network (drift, jitter), both channels at
//!   5 ms.
//!
//! After criterion's summary it prints per-lock-step times and, from the same run, the
//! cost of one exchange: (loop − msd alone − pd alone) / 2 messages.

mod common;

#[path = "../tests/support/fmu_build.rs"]
mod fmu_build;

use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::SystemTime;

use criterion::{criterion_group, Criterion};
use dsmcosim::cosim::CoSim;
use dsmcosim::scenario::parse_str;
use serde_json::{json, Value};

const GROUP: &str = "fmu_1s";
const CASES: [&str; 4] = [
    "msd_alone",
    "pd_alone",
    "loop_ideal_every_step",
    "loop_tdma",
];

/// The test FMUs, built once per bench run.
fn fmus() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/bench-fmus");
        std::fs::create_dir_all(&dir).expect("bench FMU directory");
        for stem in ["msd", "pd"] {
            fmu_build::build_test_fmu(stem, &dir).expect("build a test FMU (needs cc)");
        }
        dir
    })
}

fn world(case: &str) -> CoSim {
    let path = |stem: &str| fmus().join(format!("{stem}.fmu")).display().to_string();
    let plant = json!({"name": "plant", "path": path("msd"), "node": 1,
                       "start": {"m": 1.0, "k": 4.0, "c": 0.4, "x0": 1.0}});
    let ctrl = json!({"name": "ctrl", "path": path("pd"), "node": 2,
                      "start": {"kp": 10.0, "kd": 2.0, "r": 0.0}});
    let mut v: Value = json!({"name": case, "seed": 1, "duration": 1.0, "dt": 0.001});
    match case {
        "msd_alone" => v["fmus"] = json!([plant]),
        "pd_alone" => v["fmus"] = json!([ctrl]),
        _ => {
            let tau = if case == "loop_tdma" { 0.005 } else { 0.001 };
            v["fmus"] = json!([plant, ctrl]);
            v["channels"] = json!([
                {"name": "sense", "tau": tau, "latency": 0.0},
                {"name": "act", "tau": tau, "latency": 0.0}
            ]);
            v["connections"] = json!([
                {"from": "plant.x", "to": "ctrl.x", "channel": "sense"},
                {"from": "plant.v", "to": "ctrl.v", "channel": "sense"},
                {"from": "ctrl.u", "to": "plant.F", "channel": "act"}
            ]);
            if case == "loop_tdma" {
                for c in v["channels"].as_array_mut().expect("channels") {
                    c.as_object_mut().expect("channel").remove("latency");
                }
                v["network"] = json!({
                    "kind": "tdma", "slot": 0.0001, "cycle": 0.005, "guard": 1e-05,
                    "link_rate": 1e8, "propagation": 5e-07, "header_bytes": 26,
                    "drift_ppm": 50.0, "random_walk_ppm": 0.5, "sync_error": 2e-07,
                    "jitter": {"kind": "exponential", "mean": 2e-05}
                });
            }
        }
    }
    CoSim::new(&parse_str(&v.to_string(), case).expect("valid bench scenario"))
}

fn bench_fmu(c: &mut Criterion) {
    common::bench_one_second(c, GROUP, &CASES, 20, world);
}

fn print_table(since: SystemTime) {
    let median = |case: &str| common::median(GROUP, case, since);
    println!("\n1 s simulated, 1000 lock-steps (criterion medians of this run):");
    println!("  {:<24} {:>14}", "case", "per lock-step");
    for case in CASES {
        match median(case) {
            Some(ns) => println!("  {case:<24} {:>11.2} µs", ns / 1000.0 / 1e3),
            None => println!("  {case:<24} (not measured in this run)"),
        }
    }
    if let (Some(lp), Some(m), Some(p)) = (
        median("loop_ideal_every_step"),
        median("msd_alone"),
        median("pd_alone"),
    ) {
        println!(
            "  one exchange (a sampled message delivered and applied): {:.2} µs",
            (lp - m - p) / 1000.0 / 2.0 / 1e3
        );
    }
}

criterion_group!(benches, bench_fmu);

fn main() {
    common::run_then(benches, print_table);
}
