//! Criterion benchmarks of one integration step (explicit Euler, SMC) on grids of
//! increasing size, exact vs CG multiplier solve, point-mass vs rigid-body path.
//!
//! Run: `cargo bench --bench step` (add a filter, e.g. `-- grid64`, for one group).
//! Each system is first driven for 200 steps by a corner force so the multipliers are
//! busy (a grid at rest has a zero right-hand side and would make CG look free).

use criterion::{criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion, Throughput};
use dsmcosim::kernel::SimTime;
use dsmcosim::multibody::{State, System};
use dsmcosim::scenario::parse_str;
use serde_json::json;

fn grid(n: usize, solver: serde_json::Value, body_model: &str) -> (System, State, SimTime) {
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
    for _ in 0..200 {
        system.step(t, &mut state).expect("warm-up step");
        t = SimTime(t.0 + s.dt.0);
    }
    (system, state, t)
}

fn bench_steps(c: &mut Criterion) {
    let cg = |iters: usize| json!({"kind": "cg", "max_iterations": iters, "tolerance": 1e-10});
    let cases: Vec<(usize, &str, serde_json::Value, &str)> = vec![
        (4, "exact", json!({"kind": "cholesky"}), "point_mass"),
        (4, "cg10", cg(10), "point_mass"),
        (4, "exact", json!({"kind": "cholesky"}), "rigid"),
        (64, "exact", json!({"kind": "cholesky"}), "point_mass"),
        (64, "cg10", cg(10), "point_mass"),
        (64, "cg10", cg(10), "rigid"),
        (64, "cg40", cg(40), "point_mass"),
        (256, "cg10", cg(10), "point_mass"),
    ];
    let mut group = c.benchmark_group("step");
    for (n, solver_name, solver, model) in cases {
        let (mut system, state, t) = grid(n, solver, model);
        let bodies = (n * n) as u64;
        group.throughput(Throughput::Elements(bodies));
        if n >= 64 {
            group.sample_size(10);
        } else {
            group.sample_size(50);
        }
        let id = BenchmarkId::new(format!("grid{n}/{solver_name}"), model);
        group.bench_function(id, |b| {
            b.iter_batched_ref(
                || state.clone(),
                |s| system.step(t, s).expect("bench step"),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, bench_steps);
criterion_main!(benches);
