//! Criterion benchmarks of one integration step (explicit Euler, SMC) on grids of
//! increasing size, exact vs CG multiplier solve, point-mass vs rigid-body path.
//!
//! Run: `cargo bench --bench step` (add a filter, e.g. `-- grid64`, for one group).
//! Each system is first driven for 200 steps by a corner force so the multipliers are
//! busy; timed steps then continue the trajectory (so CG's warm start is as good as in
//! a real run, no better), restarting from that state every 1000 steps.

mod common;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use dsmcosim::kernel::SimTime;
use dsmcosim::multibody::{State, System};
use serde_json::{json, Value};

fn grid(n: usize, solver: Value, body_model: &str) -> (System, State, SimTime) {
    common::warm_grid(n, solver, body_model, 200)
}

/// Mean CG iterations per step over `steps` steps from the given point.
fn mean_iterations(system: &System, state: &State, t: SimTime, steps: u64) -> f64 {
    let (mut sys, mut st, mut tt) = (system.clone(), state.clone(), t);
    let mut total = 0;
    for _ in 0..steps {
        sys.step(tt, &mut st).expect("step");
        total += sys.last_solver_iterations();
        tt = SimTime(tt.0 + 1_000_000);
    }
    total as f64 / steps as f64
}

fn bench_steps(c: &mut Criterion) {
    // Tolerance 0: every solve runs exactly its budget, so sizes compare at equal work
    // per link; `cg_tol` stops at a relative residual of 1e-8 (budget 50).
    let cg = |iters: usize| json!({"kind": "cg", "max_iterations": iters, "tolerance": 0.0});
    let cg_tol = json!({"kind": "cg", "max_iterations": 50, "tolerance": 1e-8});
    let exact = json!({"kind": "cholesky"});
    let cases: Vec<(usize, &str, Value, &str)> = vec![
        (4, "exact", exact.clone(), "point_mass"),
        (4, "cg10", cg(10), "point_mass"),
        (4, "exact", exact.clone(), "rigid"),
        (64, "exact", exact, "point_mass"),
        (64, "cg10", cg(10), "point_mass"),
        (64, "cg10", cg(10), "rigid"),
        (64, "cg_tol", cg_tol.clone(), "point_mass"),
        (256, "cg10", cg(10), "point_mass"),
        (256, "cg_tol", cg_tol, "point_mass"),
    ];
    let mut group = c.benchmark_group("step");
    for (n, solver_name, solver, model) in cases {
        group.throughput(Throughput::Elements((n * n) as u64));
        group.sample_size(if n >= 64 { 10 } else { 50 });
        let id = BenchmarkId::new(format!("grid{n}/{solver_name}"), model);
        let mut setup: Option<(System, State, SimTime)> = None;
        // Setup inside the closure: criterion only calls it when the filter matches.
        group.bench_function(id, |b| {
            let (system, state, t) = setup.get_or_insert_with(|| {
                let (sys, st, t) = grid(n, solver.clone(), model);
                eprintln!(
                    "grid{n}/{solver_name}/{model}: {:.1} CG iterations per step (0 = exact)",
                    mean_iterations(&sys, &st, t, 100)
                );
                (sys, st, t)
            });
            b.iter_custom(|iters| common::time_steps(system, state, *t, iters))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_steps);
criterion_main!(benches);
