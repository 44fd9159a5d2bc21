//! Parallel lock-step: the nodes of one world stepped on 1 and on 2 rayon threads, as
//! ratios measured in one run.
//!
//! Run: `cargo bench --bench parallel`. Each case runs a world built outside the timed
//! closure (a fresh copy per iteration, no recording) inside a rayon pool of one thread
//! (`…/1t`: the serial lock-step, as every run with `RAYON_NUM_THREADS=1`) or of two
//! threads with the parallel path forced on whatever the scene's size (`…/2t`,
//! `CoSim::set_parallel_min_links(0)`). The scenes, each an N×N grid (body 1 driven, one
//! ideal channel at τ = 5 ms, default coupling) split into square blocks of bodies, one
//! node each:
//!
//! - `grid64_16n_cg10`: 64×64 on 16 nodes of 16×16, CG 10 (tolerance 0), 100 lock-steps;
//! - `grid32_16n_cg10`: 32×32 on 16 nodes of 8×8, CG 10, 1000 lock-steps;
//! - `grid16_4n*` / `grid16_16n*`: 16×16 on 4 nodes of 8×8 / 16 nodes of 4×4, CG 10
//!   (`_cg10`) or the default exact solve, 1000 lock-steps;
//! - `grid12_4n_cg10` / `grid12_16n_cg10`: 12×12 on 4 nodes of 6×6 / 16 nodes of 3×3,
//!   CG 10, 1000 lock-steps;
//! - `grid8_16n`: 8×8 on 16 nodes of 2×2 (`tdma16`'s split, on ideal channels);
//! - `thesis`: the shipped `grid16_space_fixed` (4×4 on the 4 thesis nodes), 1000
//!   lock-steps.
//!
//! After criterion has measured them, the bench prints each scene's links per lock-step
//! (what `PARALLEL_MIN_LINKS` is compared with), the time per lock-step on 1 and 2
//! threads and the speed-up `1t ÷ 2t` from the medians of this run.
mod common;

use std::time::SystemTime;

use criterion::{criterion_group, BatchSize, BenchmarkId, Criterion, Throughput};
use dsmcosim::cosim::CoSim;
use dsmcosim::kernel::SimTime;
use dsmcosim::scenario::parse_str;
use rayon::{ThreadPool, ThreadPoolBuilder};
use serde_json::{json, Value};

const GROUP: &str = "parallel";

/// Scene name, lock-steps per iteration.
const SCENES: [(&str, u64); 10] = [
    ("grid64_16n_cg10", 100),
    ("grid32_16n_cg10", 1000),
    ("grid16_4n_cg10", 1000),
    ("grid16_16n_cg10", 1000),
    ("grid16_4n", 1000),
    ("grid16_16n", 1000),
    ("grid12_4n_cg10", 1000),
    ("grid12_16n_cg10", 1000),
    ("grid8_16n", 1000),
    ("thesis", 1000),
];

/// An `n`×`n` grid on `blocks`×`blocks` nodes of square blocks of bodies, one channel at
/// 5 ms, `solver` (`None`: the default exact solve).
fn blocks(n: usize, blocks: usize, solver: Option<Value>, steps: u64) -> CoSim {
    let side = n / blocks;
    let mut nodes = vec![Vec::new(); blocks * blocks];
    for r in 0..n {
        for c in 0..n {
            nodes[(r / side) * blocks + c / side].push(r * n + c + 1);
        }
    }
    let mut v = json!({
        "name": "parallel", "seed": 1, "duration": steps as f64 / 1000.0, "dt": 0.001,
        "model": {"grid": {"rows": n, "cols": n, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0}],
        "partition": {"nodes": nodes},
        "channels": [{"name": "all", "tau": 0.005}]
    });
    if let Some(s) = solver {
        v["solver"] = s;
    }
    CoSim::new(&parse_str(&v.to_string(), "parallel").expect("valid bench scenario"))
}

fn world(scene: &str, steps: u64) -> CoSim {
    let cg10 = || Some(json!({"kind": "cg", "max_iterations": 10, "tolerance": 0.0}));
    match scene {
        "grid64_16n_cg10" => blocks(64, 4, cg10(), steps),
        "grid32_16n_cg10" => blocks(32, 4, cg10(), steps),
        "grid16_4n_cg10" => blocks(16, 2, cg10(), steps),
        "grid16_16n_cg10" => blocks(16, 4, cg10(), steps),
        "grid16_16n" => blocks(16, 4, None, steps),
        "grid12_4n_cg10" => blocks(12, 2, cg10(), steps),
        "grid12_16n_cg10" => blocks(12, 4, cg10(), steps),
        "grid16_4n" => blocks(16, 2, None, steps),
        "grid8_16n" => blocks(8, 4, None, steps),
        _ => {
            let v = common::shipped_one_second("grid16_space_fixed");
            CoSim::new(&parse_str(&v.to_string(), "thesis").expect("valid scenario"))
        }
    }
}

fn pool(threads: usize) -> ThreadPool {
    ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("rayon pool")
}

fn bench_parallel(c: &mut Criterion) {
    let pools = [(1, pool(1)), (2, pool(2))];
    let mut g = c.benchmark_group(GROUP);
    for (scene, steps) in SCENES {
        g.throughput(Throughput::Elements(steps));
        g.sample_size(if steps < 1000 { 10 } else { 20 });
        let mut w = world(scene, steps);
        w.set_parallel_min_links(0);
        let end = SimTime(steps * 1_000_000);
        for (threads, pool) in &pools {
            g.bench_function(BenchmarkId::new(scene, format!("{threads}t")), |b| {
                b.iter_batched_ref(
                    || w.clone(),
                    |w| {
                        pool.install(|| w.advance_to(end, &mut ()))
                            .expect("bench run")
                    },
                    BatchSize::LargeInput,
                )
            });
        }
    }
    g.finish();
}

fn print_table(since: SystemTime) {
    println!("\nLock-step on 1 and 2 rayon threads (criterion medians of this run):");
    println!(
        "  {:<16} {:>6} {:>6} {:>14} {:>14} {:>9} {:>9}",
        "scene", "nodes", "links", "1t [µs/step]", "2t [µs/step]", "1t ÷ 2t", "auto"
    );
    for (scene, steps) in SCENES {
        let w = world(scene, steps);
        let links: usize = w.nodes().iter().map(|n| n.system.link_count()).sum();
        let auto = if links >= dsmcosim::cosim::world::PARALLEL_MIN_LINKS {
            "parallel"
        } else {
            "serial"
        };
        let one = common::median(GROUP, &format!("{scene}/1t"), since);
        let two = common::median(GROUP, &format!("{scene}/2t"), since);
        let (Some(one), Some(two)) = (one, two) else {
            println!("  {scene:<16} (not measured in this run)");
            continue;
        };
        let per_step = |ns: f64| ns / steps as f64 / 1000.0;
        println!(
            "  {scene:<16} {:>6} {:>6} {:>14.2} {:>14.2} {:>9} {:>9}",
            w.nodes().len(),
            links,
            per_step(one),
            per_step(two),
            common::times(one, Some(two)),
            auto
        );
    }
}

criterion_group!(benches, bench_parallel);

fn main() {
    common::run_then(benches, print_table);
}
