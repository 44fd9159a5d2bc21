//! Helpers shared by the benches that print ratios from one criterion run.

use std::path::PathBuf;
use std::time::SystemTime;

use criterion::{BatchSize, Criterion, Throughput};
use dsmcosim::cosim::CoSim;
use dsmcosim::kernel::SimTime;
use dsmcosim::multibody::{State, System};
use dsmcosim::scenario::parse_str;
use serde_json::{json, Value};

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

/// A monolithic `n`×`n` grid (spacing 1.8 m, 1 kg bodies of 0.2 m, body 1 driven by a
/// 20 N sinusoid, dt 1 ms) with `solver` and `body_model`, stepped `warm` steps so the
/// multipliers are busy and CG's warm start is as good as in a real run: the system,
/// its state and the time reached.
#[allow(dead_code)] // not every bench that shares this module steps grids
pub fn warm_grid(n: usize, solver: Value, body_model: &str, warm: u64) -> (System, State, SimTime) {
    let s = parse_str(
        &json!({
            "name": "bench", "seed": 1, "duration": 1.0, "dt": 0.001,
            "model": {"grid": {"rows": n, "cols": n, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
            "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0, "phase": 1.0}],
            "solver": solver,
            "body_model": body_model
        })
        .to_string(),
        "bench",
    )
    .expect("valid bench scenario");
    let mut system = System::new(&s);
    let mut state = State::initial(&s);
    let mut t = SimTime::ZERO;
    for _ in 0..warm {
        system.step(t, &mut state).expect("warm-up step");
        t = SimTime(t.0 + s.dt.0);
    }
    (system, state, t)
}

/// Wall time of `iters` steps (dt 1 ms) continuing from `(system, state, t)`, restarting
/// from that point every 1000 steps so a long measurement never drives the scene far
/// from where it was warmed up; copies are made outside the timing.
#[allow(dead_code)] // not every bench that shares this module steps grids
pub fn time_steps(system: &System, state: &State, t: SimTime, iters: u64) -> std::time::Duration {
    let mut elapsed = std::time::Duration::ZERO;
    let mut done = 0;
    while done < iters {
        let (mut sys, mut st, mut now) = (system.clone(), state.clone(), t);
        let chunk = (iters - done).min(1000);
        let start = std::time::Instant::now();
        for _ in 0..chunk {
            sys.step(now, &mut st).expect("bench step");
            now = SimTime(now.0 + 1_000_000);
        }
        elapsed += start.elapsed();
        done += chunk;
    }
    elapsed
}
