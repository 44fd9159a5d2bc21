//! Sweep throughput: points per minute of the shipped slot-layout study on 1 and 2
//! threads, and their ratio, measured in one run.
//!
//! Run: `cargo bench --bench sweep`. Each iteration is `dsmcosim::sweep::run` (the
//! library entry point of `dsmcosim sweep`: checks every point, runs the selected ones
//! in parallel, writes every point's outputs and the tables and plots) of
//! `scenarios/sweeps/tdma4_slot_layouts.json` into a fresh temporary directory, inside
//! a rayon pool of 1 or 2 threads built outside the timed closure. The directory is
//! created before and removed after the timed part.
//!
//! By default an iteration runs shard 1/10 of the study (`--shard 1/10`: points 0, 10,
//! 20, …, i.e. every layout at every drift level with the first seed, 60 of the 600
//! points, ≈ 70 ms each), so criterion's ten samples take about a minute per thread
//! count; `DSMCOSIM_BENCH_SHARDS=1` runs the whole study in every iteration (about ten
//! times as long).
//!
//! After criterion has measured both, the bench prints points per minute for each
//! thread count and the 2-vs-1-thread ratio, from the medians of this run.
mod common;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::SystemTime;

use criterion::{criterion_group, BatchSize, Criterion, Throughput};
use dsmcosim::sweep::{self, Options, Shard};

const GROUP: &str = "sweep_tdma4_slot_layouts";
const THREADS: [usize; 2] = [1, 2];

fn study() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/sweeps/tdma4_slot_layouts.json")
}

/// The share of the study one iteration runs (`DSMCOSIM_BENCH_SHARDS`, default 10).
fn shard() -> Option<Shard> {
    let count = std::env::var("DSMCOSIM_BENCH_SHARDS")
        .ok()
        .and_then(|s| s.trim().parse::<usize>().ok())
        .filter(|&n| n >= 1)
        .unwrap_or(10);
    (count > 1).then_some(Shard { index: 1, count })
}

/// Points one iteration runs: the study's points in the shard.
fn points() -> usize {
    let (file, _) = sweep::file::load(&study()).expect("shipped sweep file");
    let plan = sweep::points::plan(&file).expect("shipped sweep plan");
    let all = plan.points.len();
    shard().map_or(all, |s| (0..all).filter(|&k| s.contains(k)).count())
}

/// An output directory that is removed when dropped (outside the timed part).
struct Scratch(PathBuf);

impl Scratch {
    fn new(threads: usize) -> Scratch {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let dir = std::env::temp_dir().join(format!(
            "dsmcosim-bench-sweep-{}-{threads}t-{}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = std::fs::remove_dir_all(&dir);
        Scratch(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn bench_sweep(c: &mut Criterion) {
    let study = study();
    let options = Options {
        keep: Default::default(),
        resume: false,
        shard: shard(),
        sets: Vec::new(),
    };
    let n = points();
    let mut group = c.benchmark_group(GROUP);
    group.throughput(Throughput::Elements(n as u64));
    group.sample_size(10);
    for threads in THREADS {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("rayon pool");
        group.bench_function(format!("threads_{threads}"), |b| {
            b.iter_batched(
                || Scratch::new(threads),
                |out| {
                    let report = pool
                        .install(|| sweep::run(&study, &out.0, &options))
                        .expect("bench sweep");
                    assert_eq!(report.ran, n, "every selected point ran");
                    out
                },
                BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

/// Median time [ns] criterion recorded for `case` of this bench's group since `since`.
fn median(case: &str, since: SystemTime) -> Option<f64> {
    common::median(GROUP, case, since)
}

fn print_table(since: SystemTime) {
    let n = points();
    let what = match shard() {
        Some(s) => format!("shard {}/{} of tdma4_slot_layouts", s.index, s.count),
        None => "all of tdma4_slot_layouts".to_string(),
    };
    println!("\n{what}: {n} points per iteration (criterion medians of this run):");
    println!(
        "  {:<10} {:>14} {:>12} {:>14}",
        "threads", "sweep [s]", "points/min", "vs 1 thread"
    );
    let one = median("threads_1", since);
    for threads in THREADS {
        let case = format!("threads_{threads}");
        let Some(ns) = median(&case, since) else {
            println!("  {threads:<10} (not measured in this run)");
            continue;
        };
        let secs = ns / 1e9;
        println!(
            "  {threads:<10} {secs:>14.2} {:>12.0} {:>14}",
            n as f64 / secs * 60.0,
            one.map_or("—".into(), |o| format!("{:.2}×", o / ns)),
        );
    }
}

criterion_group!(benches, bench_sweep);

fn main() {
    common::run_then(benches, print_table);
}
