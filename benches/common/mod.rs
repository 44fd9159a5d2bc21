//! Helpers shared by the benches that print ratios from one criterion run.

use std::path::PathBuf;
use std::time::SystemTime;

use criterion::{BatchSize, Criterion, Throughput};
use dsmcosim::cosim::CoSim;
use dsmcosim::kernel::SimTime;
use serde_json::Value;

/// Median time [ns] criterion recorded for `group/case` since `since`, if it ran in
/// this run (an older estimate on disk is ignored).
#[allow(dead_code)] // not every bench that shares this module prints ratios
pub fn median(group: &str, case: &str, since: SystemTime) -> Option<f64> {
    let home = std::env::var_os("CRITERION_HOME")
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("CARGO_TARGET_DIR").map(|d| PathBuf::from(d).join("criterion"))
        })
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/criterion"));
    let path = home.join(group).join(case).join("new/estimates.json");
    if std::fs::metadata(&path).ok()?.modified().ok()? < since {
        return None;
    }
    let v: Value = serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()?;
    v["median"]["point_estimate"].as_f64()
}

/// Benchmarks 1 s (1000 lock-steps) of each case's world in criterion group `group`,
/// from a fresh copy of a world built outside the timed closure, `samples` samples.
#[allow(dead_code)] // not every bench that shares this module times worlds
pub fn bench_one_second(
    c: &mut Criterion,
    group: &str,
    cases: &[&str],
    samples: usize,
    world: impl Fn(&str) -> CoSim,
) {
    let mut g = c.benchmark_group(group);
    g.throughput(Throughput::Elements(1000));
    g.sample_size(samples);
    for &case in cases {
        let w = world(case);
        g.bench_function(case, |b| {
            b.iter_batched_ref(
                || w.clone(),
                |w| {
                    w.advance_to(SimTime(1_000_000_000), &mut ())
                        .expect("bench run")
                },
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

/// A bench binary's `main`: runs the criterion `benches`, prints criterion's summary, then
/// `report(started)` with the time the run started (so the report reads only this run's
/// medians, see [`median`]).
#[allow(dead_code)] // not every bench that shares this module reports after the run
pub fn run_then(benches: fn(), report: impl FnOnce(SystemTime)) {
    let started = SystemTime::now();
    benches();
    criterion::Criterion::default()
        .configure_from_args()
        .final_summary();
    report(started);
}

/// `a / b` as `1.234×`, or `—` when `b` was not measured in this run.
#[allow(dead_code)] // not every bench that shares this module prints ratios
pub fn times(a: f64, b: Option<f64>) -> String {
    b.map_or("—".into(), |b| format!("{:.3}×", a / b))
}

/// A shipped scenario (`scenarios/NAME.json`) cut to 1 s, as JSON for a bench to edit.
#[allow(dead_code)] // not every bench that shares this module reads shipped scenarios
pub fn shipped_one_second(name: &str) -> Value {
    let p = format!("{}/scenarios/{name}.json", env!("CARGO_MANIFEST_DIR"));
    let mut v: Value =
        serde_json::from_str(&std::fs::read_to_string(p).expect("scenario")).expect("json");
    v["duration"] = serde_json::json!(1.0);
    v
}
