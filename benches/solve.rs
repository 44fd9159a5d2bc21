//! The exact multiplier solve: where the dense path stops paying (crossover) and how
//! the per-step cost of the exact and CG paths grows with the grid (growth), as
//! ratios and fits from one run.
//!
//! Run: `cargo bench --bench solve` (or `-- crossover` / `-- growth` for one group).
//! With `GROWTH_OUT=DIR` set, the growth table is also written to `DIR/growth.csv` and
//! drawn log–log in `DIR/growth.svg` (`results/growth/` holds the stored one).
//!
//! - `crossover_{m}/dense` and `…/ordered`: one exact solve (assemble `J M⁻¹ Jᵀ`,
//!   factorize, solve) of an n×n grid's m = 2n(n−1) links with rigid bodies, on the
//!   dense in-place path and on the ordered sparse path (faer, AMD, supernodal), for
//!   n = 3…16 (12…480 links). The report names the smallest m where the sparse path
//!   wins, what [`DENSE_MAX_LINKS`] is set from.
//! - `growth_{n}/cg10`, `…/exact` and `…/pcg`: one explicit-Euler SMC step of a
//!   monolithic n×n grid of rigid bodies (warmed up 20 steps, then continuing its
//!   trajectory, restarted from the warm state every 1000 steps) with CG 10 (tolerance
//!   0), the exact solve, or the exact factor reused (`cholesky_pcg`, its defaults: a
//!   factorization every 20 solves, so every 20 Euler steps), n = 16…256. The report fits the exponent `p` of `time ∝ bodies^p` by least squares
//!   on the logs, for each path.
mod common;

use std::path::PathBuf;
use std::time::{Duration, Instant, SystemTime};

use criterion::{criterion_group, BenchmarkId, Criterion, Throughput};
use dsmcosim::multibody::solver::{ExactPath, Geometry, JsSolver, MassData, DENSE_MAX_LINKS};
use dsmcosim::report::{write_line_plot, LinePlot, Scale, Series};
use nalgebra::{Matrix3, Vector3};
use serde_json::json;

const GROUP: &str = "solve";
/// Grid sides of the crossover cases.
const CROSSOVER: [usize; 9] = [3, 4, 5, 6, 7, 8, 10, 12, 16];
/// Grid sides of the growth cases.
const GROWTH: [usize; 5] = [16, 32, 64, 128, 256];

/// The links of an n×n grid (row by row, each body's +x link before its +y link) with
/// rigid-body Jacobian data: directions tilted a little off the axes and anchors on the
/// bodies' faces, so every entry of `A` is non-zero where links share a body.
fn grid_system(n: usize) -> (Geometry, MassData) {
    let mut ends = Vec::new();
    for r in 0..n {
        for c in 0..n {
            let i = r * n + c;
            if c + 1 < n {
                ends.push((i, i + 1));
            }
            if r + 1 < n {
                ends.push((i, i + n));
            }
        }
    }
    let tilt = |k: usize| 0.1 * ((k as f64) * 0.37).sin();
    let n_vec: Vec<Vector3<f64>> = ends
        .iter()
        .enumerate()
        .map(|(k, &(a, b))| {
            let along = if b == a + 1 {
                Vector3::x()
            } else {
                Vector3::y()
            };
            (along + Vector3::new(tilt(k), tilt(k + 1), tilt(k + 2))).normalize()
        })
        .collect();
    let ca = n_vec
        .iter()
        .map(|d| (d * 0.1).cross(&Vector3::new(0.0, 0.0, 0.05)) + d * 0.01);
    let cb = n_vec
        .iter()
        .map(|d| (d * -0.1).cross(&Vector3::new(0.0, 0.05, 0.0)));
    let bodies = n * n;
    (
        Geometry {
            ca: ca.collect(),
            cb: cb.collect(),
            n: n_vec,
            ends,
        },
        MassData {
            inv_mass: vec![1.0; bodies],
            inv_inertia: vec![Matrix3::from_diagonal_element(150.0); bodies],
            compliance: Vec::new(),
        },
    )
}

fn crossover(c: &mut Criterion) {
    let mut g = c.benchmark_group(GROUP);
    g.sample_size(30);
    g.warm_up_time(Duration::from_millis(500));
    g.measurement_time(Duration::from_secs(2));
    for n in CROSSOVER {
        let (geo, mass) = grid_system(n);
        let m = geo.ends.len();
        let b: Vec<f64> = (0..m).map(|k| (k as f64 * 0.7).cos()).collect();
        for (name, path) in [("dense", ExactPath::Dense), ("ordered", ExactPath::Ordered)] {
            let mut solver = JsSolver::exact(path, n * n, &geo.ends);
            let mut x = vec![0.0; m];
            g.bench_function(BenchmarkId::new(format!("crossover_{m}"), name), |bench| {
                bench.iter(|| solver.solve(&geo, &mass, &b, &mut x).expect("solve"))
            });
        }
    }
    g.finish();
}

fn growth(c: &mut Criterion) {
    let mut g = c.benchmark_group(GROUP);
    g.sample_size(10);
    g.warm_up_time(Duration::from_secs(1));
    let cg10 = json!({"kind": "cg", "max_iterations": 10, "tolerance": 0.0});
    let exact = json!({"kind": "cholesky"});
    let reused = json!({"kind": "cholesky_pcg"});
    for n in GROWTH {
        g.throughput(Throughput::Elements((n * n) as u64));
        for (name, solver) in [("cg10", &cg10), ("exact", &exact), ("pcg", &reused)] {
            let mut setup = None;
            g.bench_function(BenchmarkId::new(format!("growth_{n}"), name), |bench| {
                // Built inside the closure: criterion calls it only when the filter
                // matches, and a 256×256 exact warm-up takes seconds.
                // Timed steps continue the warm trajectory, restarting from it every
                // 1000 steps (as `benches/step.rs`: a loose CG run driven for many
                // seconds would leave its bound). A clone shares the exact path's
                // analysis, so no restart pays for it.
                let (system, state, t) =
                    setup.get_or_insert_with(|| common::warm_grid(n, solver.clone(), "rigid", 20));
                bench.iter_custom(|iters| common::time_steps(system, state, *t, iters))
            });
        }
    }
    g.finish();
}

/// Least-squares slope of `ln y` against `ln x`.
fn exponent(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> = points.iter().map(|&(x, y)| (x.ln(), y.ln())).collect();
    let len = logs.len() as f64;
    let (mx, my) = logs
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x / len, b + y / len));
    let sxy: f64 = logs.iter().map(|&(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = logs.iter().map(|&(x, _)| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

fn report(since: SystemTime) {
    let median = |case: String| common::median(GROUP, &case, since);
    println!("\nCrossover (one exact solve: assemble, factorize, solve):");
    println!("| links | dense | ordered (faer AMD) | dense ÷ ordered |");
    println!("|---|---|---|---|");
    let mut first_win = None;
    for n in CROSSOVER {
        let m = 2 * n * (n - 1);
        let dense = median(format!("crossover_{m}/dense"));
        let ordered = median(format!("crossover_{m}/ordered"));
        if let (Some(d), Some(o)) = (dense, ordered) {
            println!(
                "| {m} | {:.2} µs | {:.2} µs | {} |",
                d / 1e3,
                o / 1e3,
                common::times(d, Some(o))
            );
            if d > o && first_win.is_none() {
                first_win = Some(m);
            }
        }
    }
    if let Some(m) = first_win {
        println!("ordered first faster at {m} links (DENSE_MAX_LINKS = {DENSE_MAX_LINKS})");
    }

    println!("\nGrowth (one step, rigid bodies, explicit Euler, SMC):");
    println!("| grid | bodies | CG 10 | exact | exact ÷ CG 10 | reused factor | reused ÷ CG 10 |");
    println!("|---|---|---|---|---|---|---|");
    let mut points: [Vec<(f64, f64)>; 3] = Default::default();
    let mut csv = String::from(
        "grid,bodies,cg10_seconds_per_step,exact_seconds_per_step,pcg_seconds_per_step\n",
    );
    for n in GROWTH {
        let bodies = (n * n) as f64;
        let [c, e, r] = SERIES.map(|(case, _)| median(format!("growth_{n}/{case}")));
        let cell = |v: Option<f64>| v.map_or("—".into(), |v| format!("{:.3} ms", v / 1e6));
        let ratio = |v: Option<f64>| v.map_or("—".into(), |v| common::times(v, c));
        println!(
            "| {n}×{n} | {} | {} | {} | {} | {} | {} |",
            n * n,
            cell(c),
            cell(e),
            ratio(e),
            cell(r),
            ratio(r)
        );
        let secs = |v: Option<f64>| v.map_or(String::new(), |v| format!("{:e}", v / 1e9));
        csv.push_str(&format!(
            "{n},{},{},{},{}\n",
            n * n,
            secs(c),
            secs(e),
            secs(r)
        ));
        for (p, v) in points.iter_mut().zip([c, e, r]) {
            p.extend(v.map(|v| (bodies, v / 1e9)));
        }
    }
    let fits = points
        .each_ref()
        .map(|p| (p.len() >= 2).then(|| exponent(p)));
    for ((_, label), fit) in SERIES.iter().zip(&fits) {
        if let Some(p) = fit {
            println!("{label}: time ∝ bodies^{p:.3}");
        }
    }
    if let (Some(dir), [Some(a), Some(b), Some(c)]) =
        (std::env::var_os("GROWTH_OUT").map(PathBuf::from), fits)
    {
        write_growth(&dir, &csv, &points, [a, b, c]);
    }
}

/// The growth bench's solvers: (case name, label).
const SERIES: [(&str, &str); 3] = [
    ("cg10", "CG 10"),
    ("exact", "exact, AMD-ordered Cholesky"),
    ("pcg", "exact factor reused (cholesky_pcg)"),
];

fn write_growth(dir: &std::path::Path, csv: &str, points: &[Vec<(f64, f64)>; 3], fits: [f64; 3]) {
    std::fs::create_dir_all(dir).expect("GROWTH_OUT directory");
    dsmcosim::output::write_atomic(&dir.join("growth.csv"), csv.as_bytes()).expect("growth.csv");
    let series: Vec<Series> = SERIES
        .iter()
        .zip(points)
        .zip(fits)
        .map(|(((_, label), p), fit)| {
            Series::new(format!("{label} (fit: bodies^{fit:.2})"), p.clone())
        })
        .collect();
    let mut plot = LinePlot::new(
        "Cost of one step against grid size (monolithic grids, rigid bodies, Euler + SMC)",
        "bodies",
        "wall time per step [s]",
        &series,
    );
    plot.x_scale = Scale::Log;
    plot.y_scale = Scale::Log;
    plot.markers = true;
    write_line_plot(&dir.join("growth.svg"), &plot).expect("growth.svg");
    println!("wrote {}/growth.csv and growth.svg", dir.display());
}

criterion_group!(benches, crossover, growth);

fn main() {
    let started = Instant::now();
    common::run_then(benches, report);
    eprintln!("solve bench: {:.0} s", started.elapsed().as_secs_f64());
}
