//! Same digest whatever may vary between two runs of the same scenario with the same
//! binary: a second run, the rayon thread count, a fork of the world mid-run, and (while
//! no randomness is configured) the seed. Issue 6, item 4; resume from a checkpoint is
//! in `tests/checkpoint`.
//!
//! The scenarios: the shipped monolithic, fixed-delay and TDMA (drift and jitter) runs
//! to their end (30 s monolithic; the partitioned thesis runs diverge at 23.991 s, which
//! is their stored result), and the shipped ideal-channel DSM run cut to 4 s, with its
//! grid search (forks on rayon), no-optimization, Nelder–Mead and DSM ± δ baselines.
//! Every test compares the digest of every step, TDMA cycle and epoch row, through the
//! same [`Recorder`] and the same controller loop `dsmcosim run` uses.

use std::path::{Path, PathBuf};
use std::process::Command;

use dsmcosim::control::experiment::Controller;
use dsmcosim::cosim::CoSim;
use dsmcosim::kernel::SimTime;
use dsmcosim::scenario::Scenario;
use dsmcosim::trace::Recorder;
use serde_json::{json, Value};

/// A scenario under test: a shipped scenario file, possibly cut short.
#[derive(Clone, Copy)]
struct Case {
    /// Name in messages and scratch directories.
    name: &'static str,
    /// The shipped `scenarios/<file>.json`.
    file: &'static str,
    /// Cut the run to this duration (and its surface window into it) [s].
    duration: Option<f64>,
    /// Where the fork test forks the world [ns]; a controlled run forks at the first
    /// window boundary at or after each.
    forks: [u64; 3],
}

/// 1 ms: right after the first step; 5.0005 s: mid-window, mid-τ; 12 s: a window
/// boundary where body 16's load starts.
const LONG_FORKS: [u64; 3] = [1_000_000, 5_000_500_000, 12_000_000_000];

/// One monolithic, one partitioned (4 nodes, space distribution, τ = 5 ms), one TDMA
/// scenario (the same on a TDMA network with clock drift, random walk, sync error and
/// jitter) and one DSM-controlled scenario on ideal channels.
const SCENARIOS: [Case; 4] = [
    Case {
        name: "grid16_monolithic",
        file: "grid16_monolithic",
        duration: None,
        forks: LONG_FORKS,
    },
    Case {
        name: "grid16_space_fixed",
        file: "grid16_space_fixed",
        duration: None,
        forks: LONG_FORKS,
    },
    Case {
        name: "tdma4_space_fixed",
        file: "tdma4_space_fixed",
        duration: None,
        forks: LONG_FORKS,
    },
    Case {
        name: "grid16_space_cp_ds2_4s",
        file: "grid16_space_cp_ds2",
        duration: Some(4.0),
        // Forks at 1 s (after the first window), 2 s and 3 s.
        forks: [1_000_000, 1_500_500_000, 3_000_000_000],
    },
];

/// The scenarios that configure no random source: the monolithic, fixed-delay and DSM
/// cases above, and the time-distributed fixed-delay run.
const NOT_RANDOM: [Case; 4] = [
    SCENARIOS[0],
    SCENARIOS[1],
    SCENARIOS[3],
    Case {
        name: "grid16_time_fixed",
        file: "grid16_time_fixed",
        duration: None,
        forks: LONG_FORKS,
    },
];

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scenario_file(name: &str) -> PathBuf {
    repo().join("scenarios").join(format!("{name}.json"))
}

impl Case {
    /// The scenario file's JSON, cut short when the case says so.
    fn json(&self) -> Value {
        let text = std::fs::read_to_string(scenario_file(self.file))
            .unwrap_or_else(|e| panic!("{}: {e}", self.file));
        let mut v: Value = serde_json::from_str(&text).expect("json");
        if let Some(d) = self.duration {
            v["duration"] = json!(d);
            if v["controller"].get("surface_window").is_some() {
                v["controller"]["surface_window"] = json!(d / 2.0);
            }
        }
        v
    }

    fn load(&self) -> Scenario {
        dsmcosim::scenario::parse_str(&self.json().to_string(), self.name)
            .unwrap_or_else(|e| panic!("{}: {e}", self.name))
    }

    /// A scenario file for the binary: the shipped one, or the cut one written into
    /// `dir`.
    fn path(&self, dir: &Path) -> PathBuf {
        if self.duration.is_none() {
            return scenario_file(self.file);
        }
        std::fs::create_dir_all(dir).expect("scratch dir");
        let p = dir.join(format!("{}.json", self.name));
        std::fs::write(&p, self.json().to_string()).expect("write scenario");
        p
    }
}

/// A recorder that only digests (no trace file), configured as `run` configures it.
fn recorder(s: &Scenario) -> Recorder {
    Recorder::for_scenario(None, s).expect("no file, no I/O")
}

/// How a run ended: its digests and, for a diverged run, the error.
#[derive(Debug, PartialEq)]
struct End {
    digest: String,
    dynamics_digest: String,
    steps: u64,
    error: Option<String>,
}

/// A run in progress: the world and, on a controlled scenario, its controller.
#[derive(Clone)]
struct Live {
    world: CoSim,
    controller: Option<Controller>,
}

impl Live {
    fn new(s: &Scenario) -> Live {
        Live {
            world: CoSim::new(s),
            controller: Controller::new(s).expect("controller settings"),
        }
    }

    /// Runs to `t` (controlled: every window that starts before `t`), as `run` drives.
    fn advance(&mut self, t: SimTime, obs: &mut (dyn dsmcosim::cosim::Observer + 'static)) {
        let r = match &mut self.controller {
            Some(c) => c.run_until(&mut self.world, obs, t),
            None => self.world.advance_to(t, obs),
        };
        r.unwrap_or_else(|e| panic!("{e}"));
    }

    /// Runs to the end, as `run` drives.
    fn run_to_end(
        &mut self,
        obs: &mut (dyn dsmcosim::cosim::Observer + 'static),
    ) -> dsmcosim::Result<()> {
        let end = self.world.scenario().duration;
        if let Some(c) = &mut self.controller {
            c.run_until(&mut self.world, obs, end)?;
        }
        self.world.run_to_end(obs)
    }
}

fn finish(live: &mut Live, rec: &mut Recorder) -> End {
    let error = live.run_to_end(rec).err().map(|e| e.to_string());
    End {
        digest: rec.digest(),
        dynamics_digest: rec.dynamics_digest(),
        steps: live.world.steps_done(),
        error,
    }
}

/// The scenario run from start to end in-process.
fn digest(s: &Scenario) -> End {
    let mut rec = recorder(s);
    finish(&mut Live::new(s), &mut rec)
}

#[test]
fn two_runs_give_the_same_digest() {
    for case in &SCENARIOS {
        let (name, s) = (case.name, case.load());
        let (a, b) = (digest(&s), digest(&s));
        assert_eq!(a, b, "{name}: two runs differ");
        assert!(a.steps > 1000, "{name}: ran only {} steps", a.steps);
    }
}

/// The forked world (a `Clone` after `advance_to`, with its controller) continues
/// exactly as the unforked run would have, while the original is driven on
/// independently.
#[test]
fn a_forked_world_finishes_with_the_unforked_digest() {
    for case in &SCENARIOS {
        let (name, s) = (case.name, case.load());
        let whole = digest(&s);
        for fork_at in case.forks {
            let mut live = Live::new(&s);
            let mut rec = recorder(&s);
            live.advance(SimTime(fork_at), &mut rec);
            let mut fork = live.clone();
            // The original runs on first; the fork must not see any of it.
            let _ = live.run_to_end(&mut ());
            let forked = finish(&mut fork, &mut rec);
            assert_eq!(
                forked,
                whole,
                "{name}: fork at t = {} differs from the unforked run",
                SimTime(fork_at)
            );
        }
    }
}

/// Without a random source the seed must not reach the trace.
#[test]
fn a_changed_seed_changes_nothing_without_randomness() {
    for case in &NOT_RANDOM {
        let (name, s) = (case.name, case.load());
        let base = digest(&s);
        for seed in [s.seed.wrapping_add(1), 0, u64::MAX] {
            let mut t = s.clone();
            t.seed = seed;
            assert_eq!(digest(&t), base, "{name}: seed {seed} changed the digest");
        }
    }
}

/// `dsmcosim run` with `RAYON_NUM_THREADS=threads` into `out`; the stored digest.
fn run_binary(scenario: &Path, out: &Path, threads: &str) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .arg("run")
        .arg(scenario)
        .arg("--out")
        .arg(out)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .expect("spawn dsmcosim");
    // 0 ok, 3 diverged (the partitioned thesis runs): both are results.
    let code = output.status.code();
    assert!(
        matches!(code, Some(0) | Some(3)),
        "{}: exit {code:?}: {}",
        scenario.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    dsmcosim::check::read_summary(out)
        .unwrap_or_else(|e| panic!("{e}"))
        .digest
}

/// Parallel work (the controller's grid search and baselines on forks) must merge in a
/// fixed order (method §6), so the thread count cannot matter; the uncontrolled
/// runs here are below the parallel lock-step's threshold (they use no rayon), and must
/// not start to depend on it. The parallel lock-step itself is compared with the serial
/// one below.
#[test]
fn rayon_thread_count_does_not_change_the_digest() {
    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR")).join("determinism");
    for case in &SCENARIOS {
        let name = case.name;
        let file = case.path(&scratch);
        let one = run_binary(&file, &scratch.join(format!("{name}-1")), "1");
        let two = run_binary(&file, &scratch.join(format!("{name}-2")), "2");
        assert_eq!(one, two, "{name}: RAYON_NUM_THREADS=1 and 2 differ");
        assert_eq!(
            one,
            digest(&case.load()).digest,
            "{name}: binary vs library"
        );
    }
}

/// On a TDMA scene with drift and jitter the seed reaches the trace; with every random
/// source of the same scene set to zero it does not, and nothing is drawn.
#[test]
fn a_changed_seed_changes_the_run_only_where_randomness_is_configured() {
    let s = SCENARIOS[2].load();
    let base = digest(&s);
    let mut other = s.clone();
    other.seed = s.seed + 1;
    assert_ne!(digest(&other), base, "drift and jitter follow the seed");

    let mut quiet = s.clone();
    if let dsmcosim::scenario::model::NetworkSpec::Tdma(t) = &mut quiet.network {
        t.config.drift_ppm = 0.0;
        t.config.random_walk_ppm = 0.0;
        t.config.sync_error = SimTime::ZERO;
        t.config.jitter = dsmcosim::network::tdma::Jitter::None;
    }
    let quiet_digest = digest(&quiet);
    let mut quiet_other = quiet.clone();
    quiet_other.seed = 0;
    assert_eq!(digest(&quiet_other), quiet_digest);
    let mut world = CoSim::new(&quiet);
    world.run_to_end(&mut ()).expect("runs");
    let net = world.tdma().expect("tdma").network();
    assert_eq!(net.words_drawn(), 0, "no random source, nothing drawn");
}

/// A DSM-controlled TDMA run (forks, grid search on rayon, list decisions through the
/// confirmation protocol) gives the same digest on 1 and 2 threads.
#[test]
fn a_controlled_tdma_run_is_the_same_on_one_and_two_threads() {
    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR")).join("determinism_tdma_cp");
    std::fs::create_dir_all(&scratch).expect("scratch dir");
    let text = std::fs::read_to_string(scenario_file("tdma4_space_cp")).expect("scenario");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    v["duration"] = serde_json::json!(4.0);
    v["controller"]["surface_window"] = serde_json::json!(2.0);
    let file = scratch.join("tdma4_space_cp_short.json");
    std::fs::write(&file, v.to_string()).expect("write scenario");
    let one = run_binary(&file, &scratch.join("1"), "1");
    let two = run_binary(&file, &scratch.join("2"), "2");
    assert_eq!(one, two, "RAYON_NUM_THREADS=1 and 2 differ");
}

/// `pool` with `threads` rayon threads.
fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("rayon pool")
}

/// `s` run to its end inside `pool`, its nodes stepped in parallel from `min_links`
/// links per lock-step on; with whether the parallel path was taken.
fn digest_in(pool: &rayon::ThreadPool, s: &Scenario, min_links: usize) -> (End, bool) {
    pool.install(|| {
        let mut rec = recorder(s);
        let mut live = Live::new(s);
        live.world.set_parallel_min_links(min_links);
        let parallel = live.world.steps_in_parallel();
        (finish(&mut live, &mut rec), parallel)
    })
}

/// The parallel lock-step (issue 17, item 4) forced on the cases above and on the
/// 16-node TDMA scene, however small they are: the nodes stepped on two threads give the
/// digests, the step count and the error of the serial lock-step on one thread (the
/// partitioned thesis runs diverge at 23.991 s: the same error, found in the same
/// node), and a run to its end gives the digest stored in `results/`. The DSM run also
/// forks its world on rayon, inside the same pool.
#[test]
fn the_parallel_lock_step_gives_the_serial_digest() {
    let (one, two) = (pool(1), pool(2));
    let tdma16 = Case {
        name: "tdma16_space_fixed",
        file: "tdma16_space_fixed",
        duration: None,
        forks: LONG_FORKS,
    };
    for case in SCENARIOS.iter().chain([&tdma16]) {
        let (name, s) = (case.name, case.load());
        let (serial, took_serial) = digest_in(&one, &s, 0);
        let (parallel, took_parallel) = digest_in(&two, &s, 0);
        assert!(!took_serial, "{name}: one thread steps serially");
        assert_eq!(
            took_parallel,
            s.partition.is_some(),
            "{name}: two threads and two nodes or more step in parallel"
        );
        assert_eq!(serial, parallel, "{name}: 1 and 2 threads differ");
        assert_eq!(serial, digest(&s), "{name}: forced vs default threshold");
        if case.duration.is_none() {
            let stored = dsmcosim::check::read_summary(&repo().join("results").join(case.file))
                .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(parallel.digest, stored.digest, "{name}: stored digest");
        }
    }
}

/// A 64×64 grid on 16 nodes of 16×16 (CG 10), above the default threshold: 1 and 2
/// threads give the same digest, and the 2-thread run takes the parallel path.
#[test]
fn a_64_by_64_grid_on_16_nodes_is_the_same_on_one_and_two_threads() {
    let v = grid64_16_nodes();
    let s = dsmcosim::scenario::parse_str(&v.to_string(), "grid64_16n").expect("scenario");
    let default = dsmcosim::cosim::world::PARALLEL_MIN_LINKS;
    let (serial, took_serial) = digest_in(&pool(1), &s, default);
    let (parallel, took_parallel) = digest_in(&pool(2), &s, default);
    assert!(!took_serial && took_parallel, "1 thread serial, 2 parallel");
    assert_eq!(serial.error, None, "runs its 50 steps");
    assert_eq!(serial.steps, 51);
    assert_eq!(serial, parallel, "1 and 2 threads differ");
}

/// A 64×64 grid on 16 nodes of 16×16 bodies (CG 10, 50 steps): 8064 links per
/// lock-step, above the parallel lock-step's threshold.
fn grid64_16_nodes() -> serde_json::Value {
    let n = 64;
    let mut nodes = vec![Vec::new(); 16];
    for r in 0..n {
        for c in 0..n {
            nodes[(r / 16) * 4 + c / 16].push(r * n + c + 1);
        }
    }
    json!({
        "name": "grid64_16n", "seed": 1, "duration": 0.05, "dt": 0.001,
        "model": {"grid": {"rows": n, "cols": n, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0}],
        "solver": {"kind": "cg", "max_iterations": 10, "tolerance": 0.0},
        "partition": {"nodes": nodes},
        "channels": [{"name": "all", "tau": 0.005}]
    })
}

/// The same grid through `dsmcosim run`, which drives the world from a thread of
/// rayon's pool: 1 and 2 threads give the library's digest.
#[test]
fn the_binary_steps_a_parallel_lock_step_to_the_same_digest_on_one_and_two_threads() {
    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR")).join("determinism_grid64_16n");
    std::fs::create_dir_all(&scratch).expect("scratch dir");
    let v = grid64_16_nodes();
    let file = scratch.join("grid64_16n.json");
    std::fs::write(&file, v.to_string()).expect("write scenario");
    let one = run_binary(&file, &scratch.join("1"), "1");
    let two = run_binary(&file, &scratch.join("2"), "2");
    assert_eq!(one, two, "RAYON_NUM_THREADS=1 and 2 differ");
    let s = dsmcosim::scenario::parse_str(&v.to_string(), "grid64_16n").expect("scenario");
    assert_eq!(one, digest(&s).digest, "binary vs library");
}

/// `cholesky_pcg` on nodes above the dense size (a 16×16 grid on 4 nodes of 8×8: 112
/// links each, and their border links), RK4 and a factorization every 7 solves, so the
/// nodes' factors are reused across steps: 1 and 2 threads (forced parallel) give the
/// same digest, and so does a fork of the world taken between two factorizations.
#[test]
fn a_reused_factor_is_the_same_on_one_and_two_threads_and_in_a_fork() {
    let n = 16;
    let mut nodes = vec![Vec::new(); 4];
    for r in 0..n {
        for c in 0..n {
            nodes[(r / 8) * 2 + c / 8].push(r * n + c + 1);
        }
    }
    let v = json!({
        "name": "grid16_4n_pcg", "seed": 1, "duration": 0.1, "dt": 0.001, "integrator": "rk4",
        "model": {"grid": {"rows": n, "cols": n, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0}],
        "solver": {"kind": "cholesky_pcg", "refactor_every": 7},
        "partition": {"nodes": nodes},
        "channels": [{"name": "all", "tau": 0.005}]
    });
    let s = dsmcosim::scenario::parse_str(&v.to_string(), "grid16_4n_pcg").expect("scenario");
    let (serial, took_serial) = digest_in(&pool(1), &s, usize::MAX);
    let (parallel, took_parallel) = digest_in(&pool(2), &s, 0);
    assert!(!took_serial && took_parallel, "1 thread serial, 2 parallel");
    assert_eq!(serial.error, None, "runs its 100 steps");
    assert_eq!(serial, parallel, "1 and 2 threads differ");
    // Forked after 13 steps (52 solves per node: 3 past a factorization).
    let mut rec = recorder(&s);
    let mut live = Live::new(&s);
    live.advance(SimTime(13_000_000), &mut rec);
    let mut fork = live.clone();
    // The original runs on first; the fork must not see any of it.
    let _ = live.run_to_end(&mut ());
    assert_eq!(finish(&mut fork, &mut rec), serial, "the fork");
}
