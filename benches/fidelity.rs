//! Fidelity levels: what each optional feature costs, as ratios on the same scene in one
//! benchmark run.
//!
//! Run: `cargo bench --bench fidelity`. Every case simulates 1 s (1000 explicit-Euler
//! steps) of the thesis 4×4 grid under the corner load, from a fresh copy of a world
//! built outside the timed closure. After criterion has measured them, the bench reads
//! the medians criterion just wrote and prints the ratios:
//!
//! - rotation: the rigid-body path against the point-mass path on a centre-anchored scene
//!   (what a scene without rotation saves by not paying for it);
//! - partitions: 4 quadrant nodes (ideal channels, τ = 5 ms) against one node;
//! - the co-simulation against bare integrator steps, split in two: the per-step outputs
//!   every run needs (gathered `w`, `f`, `p`, `v`, divergence check, cost sum), and the
//!   rest — event kernel and node structure, what a monolithic scene pays for the
//!   existence of partitions, networks and controllers;
//! - recording: digest only, trace.csv at decimation 100, and at decimation 1, against
//!   no observer;
//! - the TDMA network: the 4-node scene on TDMA (the `tdma` setting of `dsmcosim
//!   tradeoff`, [`tdma_network`]: slot 100 µs, cycle 5 ms = the channels' τ, guard 10 µs,
//!   100 Mbit/s, 26 B headers; nothing drawn) against ideal channels, and with clock
//!   drift, random walk, sync error and exponential jitter (`tdma_drift_jitter`) against
//!   plain TDMA;
//! - lookahead baselines: one controlled window (1 s, DSM with lookahead, CP) with a
//!   `grid` baseline against DSM alone, and DSM alone against the uncontrolled 4-node
//!   scene. The grid's forks run in parallel on all cores, so that ratio depends on the
//!   core count (2 on the machine docs/performance.md quotes).
mod common;

use std::path::PathBuf;
use std::time::{Instant, SystemTime};

use criterion::{criterion_group, BatchSize, Criterion, Throughput};
use dsmcosim::control::experiment::Controller;
use dsmcosim::cosim::CoSim;
use dsmcosim::kernel::SimTime;
use dsmcosim::multibody::{State, System};
use dsmcosim::output::AtomicFile;
use dsmcosim::scenario::{parse_str, Scenario};
use dsmcosim::trace::Recorder;
use dsmcosim::tradeoff::knobs::tdma_network;
use serde_json::{json, Value};

const GROUP: &str = "fidelity_1s";
const ONE_SECOND: SimTime = SimTime(1_000_000_000);

fn scene(edit: impl FnOnce(&mut Value)) -> Scenario {
    let mut v = json!({
        "name": "fidelity", "seed": 1, "duration": 1.0, "dt": 0.001, "integrator": "euler",
        "model": {"grid": {"rows": 4, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0}],
    });
    edit(&mut v);
    parse_str(&v.to_string(), "bench").expect("valid bench scenario")
}

/// 4 quadrant nodes, space distribution, τ = 5 ms (ideal channels unless edited).
fn quadrants(v: &mut Value) {
    v["partition"] = json!({"quadrants": true});
    v["channels"] = json!([
        {"name": "tau1", "tau": 0.005, "borders": [[1, 2], [1, 4]]},
        {"name": "tau2", "tau": 0.005, "borders": [[2, 3], [3, 4]]}
    ]);
}

/// The scene on 4 quadrant nodes, ideal channels, space distribution, τ = 5 ms.
fn four_nodes() -> Scenario {
    scene(quadrants)
}

/// The 4-node scene on the TDMA network of the tradeoff study's `tdma` setting (with
/// `drift_jitter`, its `tdma_drift_jitter` setting): the same periods, 5 ms.
fn four_nodes_tdma(drift_jitter: bool) -> Scenario {
    let network = tdma_network(&four_nodes(), drift_jitter);
    scene(|v| {
        quadrants(v);
        v["network"] = network;
    })
}

/// The 4-node scene under DSM with lookahead (CP, budget 400/s, τ in [1, 50] ms, one
/// 1 s window), evaluating `baselines` on forks too.
fn controlled(baselines: &[&str]) -> Scenario {
    scene(|v| {
        quadrants(v);
        v["measurement"] = json!({"period": 1.0});
        v["controller"] = json!({
            "method": "dsm", "problem": "cp", "budget": 400.0,
            "tau_min": 0.001, "tau_max": 0.05, "baselines": baselines,
        });
    })
}

/// One controlled window: the world and the controller before it (cloned per run).
fn control_case(s: &Scenario) -> (CoSim, Controller) {
    let controller = Controller::new(s)
        .expect("controller")
        .expect("scene has a controller");
    (CoSim::new(s), controller)
}

/// A recorder of `s` writing trace.csv (to a temporary file that is dropped, never
/// committed) at `decimation`, or only digesting if `decimation` is `None`.
fn recorder(s: &Scenario, decimation: Option<u64>, dir: &std::path::Path) -> Recorder {
    let ids: Vec<u32> = s.bodies.iter().map(|b| b.id).collect();
    let file =
        decimation.map(|_| AtomicFile::create(&dir.join("trace.csv")).expect("scratch trace"));
    Recorder::new(
        file,
        decimation.unwrap_or(u64::MAX),
        s.links.len(),
        &ids,
        &s.output.trace_bodies,
        &s.output.plot_bodies,
    )
    .expect("recorder")
}

/// 1000 integrator steps that also produce what every co-simulation step produces for
/// any scene: the gathered `w`, `f`, `p`, `v`, the divergence check and the cost sum.
/// The co-simulation's extra cost over this is its event kernel and node structure —
/// what a monolithic scene pays for partitions, networks and controllers existing.
fn steps_with_outputs(sys: &mut System, st: &mut State) -> f64 {
    let (nl, nb) = (sys.violations().len(), st.p.len());
    let (mut w, mut f) = (vec![0.0; nl], vec![0.0; nl]);
    let (mut p, mut v) = (st.p.clone(), st.v.clone());
    let mut cost = 0.0;
    for k in 0..1000u64 {
        let t = SimTime(k * 1_000_000);
        sys.begin_step(t, st).expect("rates");
        w.copy_from_slice(sys.violations());
        for (l, f) in f.iter_mut().enumerate() {
            *f = sys.tension(st, l);
        }
        p[..nb].copy_from_slice(&st.p);
        v[..nb].copy_from_slice(&st.v);
        let sane = w
            .iter()
            .zip(&f)
            .all(|(w, f)| w.abs() <= 1.0 && f.is_finite())
            && p.iter().chain(&v).all(|x| x.iter().all(|c| c.is_finite()));
        assert!(sane, "bench scene diverged");
        cost += w.iter().map(|w| w * w).sum::<f64>();
        sys.finish_step(t, st).expect("step");
    }
    std::hint::black_box((&p, &v));
    cost
}

fn bench_fidelity(c: &mut Criterion) {
    let point = scene(|_| {});
    let rigid = scene(|v| v["body_model"] = json!("rigid"));
    let nodes = four_nodes();
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("bench-scratch");
    std::fs::create_dir_all(&dir).expect("scratch dir");

    let mut group = c.benchmark_group(GROUP);
    group.throughput(Throughput::Elements(1000));
    group.sample_size(40);

    // Bare integrator steps: what the co-simulation wraps.
    let system = System::new(&point);
    let state = State::initial(&point);
    group.bench_function("bare_system_steps", |b| {
        b.iter_batched_ref(
            || (system.clone(), state.clone()),
            |(sys, st)| {
                for k in 0..1000u64 {
                    sys.step(SimTime(k * 1_000_000), st).expect("step");
                }
            },
            BatchSize::LargeInput,
        )
    });
    group.bench_function("bare_steps_with_outputs", |b| {
        b.iter_batched_ref(
            || (system.clone(), state.clone()),
            |(sys, st)| steps_with_outputs(sys, st),
            BatchSize::LargeInput,
        )
    });
    let (tdma, drift) = (four_nodes_tdma(false), four_nodes_tdma(true));
    for (name, s) in [
        ("monolithic_point_mass", &point),
        ("monolithic_rigid", &rigid),
        ("four_nodes_tau_5ms", &nodes),
        ("four_nodes_tdma", &tdma),
        ("four_nodes_tdma_drift_jitter", &drift),
    ] {
        let world = CoSim::new(s);
        group.bench_function(name, |b| {
            b.iter_batched_ref(
                || world.clone(),
                |w| w.advance_to(ONE_SECOND, &mut ()).expect("bench run"),
                BatchSize::LargeInput,
            )
        });
    }
    for (name, baselines) in [("dsm_window", &[][..]), ("dsm_grid_window", &["grid"][..])] {
        let (world, controller) = control_case(&controlled(baselines));
        group.bench_function(name, |b| {
            b.iter_batched_ref(
                || (world.clone(), controller.clone()),
                |(w, c)| c.run_until(w, &mut (), ONE_SECOND).expect("bench run"),
                BatchSize::LargeInput,
            )
        });
    }
    let world = CoSim::new(&point);
    for (name, decimation) in [
        ("record_digest_only", None),
        ("record_trace_decimation_100", Some(100)),
        ("record_trace_decimation_1", Some(1)),
    ] {
        group.bench_function(name, |b| {
            b.iter_batched_ref(
                || (world.clone(), recorder(&point, decimation, &dir)),
                |(w, r)| w.advance_to(ONE_SECOND, r).expect("bench run"),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

/// The ratios printed: (label, numerator case, denominator case).
const RATIOS: &[(&str, &str, &str)] = &[
    (
        "rotation: rigid ÷ point-mass path",
        "monolithic_rigid",
        "monolithic_point_mass",
    ),
    (
        "partitions: 4 nodes (τ = 5 ms) ÷ 1 node",
        "four_nodes_tau_5ms",
        "monolithic_point_mass",
    ),
    (
        "co-simulation: monolithic CoSim ÷ bare steps",
        "monolithic_point_mass",
        "bare_system_steps",
    ),
    (
        "outputs: bare steps with outputs ÷ bare steps",
        "bare_steps_with_outputs",
        "bare_system_steps",
    ),
    (
        "kernel and nodes: monolithic CoSim ÷ steps with outputs",
        "monolithic_point_mass",
        "bare_steps_with_outputs",
    ),
    (
        "digest only ÷ no observer",
        "record_digest_only",
        "monolithic_point_mass",
    ),
    (
        "trace.csv every 100th step ÷ no observer",
        "record_trace_decimation_100",
        "monolithic_point_mass",
    ),
    (
        "trace.csv every step ÷ no observer",
        "record_trace_decimation_1",
        "monolithic_point_mass",
    ),
    (
        "TDMA vs ideal: 4 nodes on TDMA ÷ ideal channels",
        "four_nodes_tdma",
        "four_nodes_tau_5ms",
    ),
    (
        "drift+jitter vs plain TDMA",
        "four_nodes_tdma_drift_jitter",
        "four_nodes_tdma",
    ),
    (
        "lookahead: DSM window ÷ uncontrolled 4 nodes",
        "dsm_window",
        "four_nodes_tau_5ms",
    ),
    (
        "lookahead baselines: DSM + grid ÷ DSM alone",
        "dsm_grid_window",
        "dsm_window",
    ),
];

/// Median time [ns] criterion recorded for `case` of this bench's group since `since`.
fn median(case: &str, since: SystemTime) -> Option<f64> {
    common::median(GROUP, case, since)
}

fn print_ratios(since: SystemTime) {
    println!("\nfidelity ratios (criterion medians of this run, 1 s of the 4×4 grid):");
    for &(label, num, den) in RATIOS {
        match (median(num, since), median(den, since)) {
            (Some(a), Some(b)) => println!(
                "  {label:<58} {:>6.3}  ({:.3} ms / {:.3} ms)",
                a / b,
                a / 1e6,
                b / 1e6
            ),
            _ => println!("  {label:<58} not measured in this run"),
        }
    }
}

/// One timed run of a case [s]; setup (world copy, recorder) is outside the timing.
type Case = Box<dyn FnMut() -> f64>;

/// A statistic of a case's sorted run times [s].
type Summary = fn(&[f64]) -> f64;

/// The same comparisons as minima and as medians of interleaved runs: every round runs
/// each case once, so a change of machine load hits all of them alike; the minimum
/// discards the runs that load slowed down (on a shared machine the steadier ratio), the
/// median is the typical run.
fn interleaved(rounds: usize) {
    let point = scene(|_| {});
    let rigid = scene(|v| v["body_model"] = json!("rigid"));
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("bench-scratch");
    let cosim = |s: &Scenario| -> Case {
        let world = CoSim::new(s);
        Box::new(move || {
            let mut w = world.clone();
            let t = Instant::now();
            w.advance_to(ONE_SECOND, &mut ()).expect("bench run");
            t.elapsed().as_secs_f64()
        })
    };
    let recorded = |s: &Scenario, decimation: Option<u64>| -> Case {
        let (world, s, dir) = (CoSim::new(s), s.clone(), dir.clone());
        Box::new(move || {
            let (mut w, mut r) = (world.clone(), recorder(&s, decimation, &dir));
            let t = Instant::now();
            w.advance_to(ONE_SECOND, &mut r).expect("bench run");
            t.elapsed().as_secs_f64()
        })
    };
    let window = |s: &Scenario| -> Case {
        let (world, controller) = control_case(s);
        Box::new(move || {
            let (mut w, mut c) = (world.clone(), controller.clone());
            let t = Instant::now();
            c.run_until(&mut w, &mut (), ONE_SECOND).expect("bench run");
            t.elapsed().as_secs_f64()
        })
    };
    let nodes = four_nodes();
    let bare = |outputs: bool| -> Case {
        let (system, state) = (System::new(&point), State::initial(&point));
        Box::new(move || {
            let (mut sys, mut st) = (system.clone(), state.clone());
            let t = Instant::now();
            if outputs {
                std::hint::black_box(steps_with_outputs(&mut sys, &mut st));
            } else {
                for k in 0..1000u64 {
                    sys.step(SimTime(k * 1_000_000), &mut st).expect("step");
                }
            }
            t.elapsed().as_secs_f64()
        })
    };
    let mut cases: Vec<(&str, Case)> = vec![
        ("bare_system_steps", bare(false)),
        ("bare_steps_with_outputs", bare(true)),
        ("monolithic_point_mass", cosim(&point)),
        ("monolithic_rigid", cosim(&rigid)),
        ("four_nodes_tau_5ms", cosim(&nodes)),
        ("four_nodes_tdma", cosim(&four_nodes_tdma(false))),
        (
            "four_nodes_tdma_drift_jitter",
            cosim(&four_nodes_tdma(true)),
        ),
        ("dsm_window", window(&controlled(&[]))),
        ("dsm_grid_window", window(&controlled(&["grid"]))),
        ("record_digest_only", recorded(&point, None)),
        ("record_trace_decimation_100", recorded(&point, Some(100))),
        ("record_trace_decimation_1", recorded(&point, Some(1))),
    ];
    let mut times = vec![Vec::with_capacity(rounds); cases.len()];
    for _ in 0..rounds {
        for (t, (_, case)) in times.iter_mut().zip(cases.iter_mut()) {
            t.push(case());
        }
    }
    for t in &mut times {
        t.sort_by(f64::total_cmp);
    }
    let summaries: [(&str, Summary); 2] = [
        ("minimum", |t| t[0]),
        ("median", |t| {
            let n = t.len();
            (t[(n - 1) / 2] + t[n / 2]) / 2.0
        }),
    ];
    for (what, summary) in summaries {
        let get = |name: &str| {
            cases
                .iter()
                .position(|(n, _)| *n == name)
                .map(|i| summary(&times[i]))
                .unwrap_or(f64::NAN)
        };
        println!("\nthe same, {what} of {rounds} interleaved runs per case:");
        for &(label, num, den) in RATIOS {
            let (a, b) = (get(num), get(den));
            println!(
                "  {label:<58} {:>6.3}  ({:.3} ms / {:.3} ms)",
                a / b,
                a * 1e3,
                b * 1e3
            );
        }
    }
}

criterion_group!(benches, bench_fidelity);

fn main() {
    common::run_then(benches, print_ratios);
    // `cargo test --benches` and `--list` only check that the bench runs.
    let args: Vec<String> = std::env::args().collect();
    if !args.iter().any(|a| a == "--test" || a == "--list") {
        interleaved(100);
    }
}
