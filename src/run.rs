//! One run of a scenario: the [`CoSim`] world driven to the end, recorded, measured
//! and written to an output directory (method §8). A monolithic scenario is the
//! one-node world.
//!
//! Written files: `trace.csv` (streamed, decimated), `epochs.csv`, `summary.json` and
//! the plots. A diverged run still writes everything up to the last sane step, then
//! returns the divergence error.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use serde_json::{json, Value};

use crate::control::experiment::{Controller, Experiment};
use crate::cosim::CoSim;
use crate::error::{Error, Result};
use crate::kernel::SimTime;
use crate::output::run_dir::claim;
use crate::output::{write_atomic, AtomicFile};
use crate::report::{envelope, write_line_plot, LinePlot, Scale, Series};
use crate::scenario::model::{Scenario, Solver, Stabilizer, Tank};
use crate::trace::{NetworkLog, Recorder};

pub mod budget;
mod controlled;
mod landscape;
mod network;
pub mod plan;
pub mod unserved;

/// What a finished (or diverged) run measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Run digest (hex): every step, TDMA cycle and epoch row ([`crate::trace::digest`]).
    pub digest: String,
    /// Dynamics digest (hex): the step and TDMA cycle records only.
    pub dynamics_digest: String,
    /// Steps integrated (recorded steps: `steps + 1` rows including t = 0 on success).
    pub steps: u64,
    /// Largest `|w|` over the run [m].
    pub max_constraint_violation: f64,
    /// Mean window cost: [m] for the links' `Σ RMS w`, the signals' own unit for
    /// `measurement.signals`.
    pub mean_cost: f64,
    /// Constraint rows of the scene (links and joints' rows): none, and there is no
    /// `|w|` to report.
    pub rows: usize,
    /// Whether the cost is `measurement.signals`' (in the signals' units), not the
    /// links' [m].
    pub signal_cost: bool,
    /// Wall-clock seconds the simulation took (not part of anything digested).
    pub wall_seconds: f64,
    /// Messages delivered between nodes.
    pub messages: u64,
    /// Kernel events processed.
    pub events: u64,
    /// BLAKE3 (hex) of the bytes of trace.csv, hashed as they are written. The run digest covers the
    /// bits of every step, not the text of the decimated rows; this one covers the text,
    /// so a resumed run whose checkpoint carried edited trace lines shows a different
    /// `trace_digest` from the uninterrupted run's even where `digest` agrees.
    pub trace_digest: Option<String>,
    /// The SMC boundary layer's account (`None` under Baumgarte): how many steps some
    /// link's `|w|` spent beyond `ε`, and the worst.
    pub boundary_layer: Option<crate::trace::drift::LayerWatch>,
    /// The work the law did on the joints' rows (`None` without joints): an ideal
    /// joint does none.
    pub joint_work: Option<crate::trace::joint_work::JointWork>,
    /// Channels whose requested delays the network did not realize ([`unserved`]).
    pub unserved: Vec<unserved::Unserved>,
    /// An FMU asked to end the run before its duration: who, when and how
    /// (`stopped by FMU 'stair' at t = 9 s (…)`); the run ended normally there.
    pub stopped: Option<String>,
}

impl Outcome {
    /// What the command line prints as `warning:` lines after a run: the law left the
    /// SMC boundary layer, did work on the joints, or a channel's delays were not
    /// realized.
    pub fn warnings(&self) -> Vec<String> {
        let layer = self.boundary_layer.as_ref().and_then(|l| l.warning());
        let joints = self.joint_work.as_ref().and_then(|j| j.warning());
        layer
            .into_iter()
            .chain(joints)
            .chain(self.unserved.iter().map(|u| u.warning()))
            .collect()
    }
}

/// Options of a run beyond its scenario.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RunOptions {
    /// Write a checkpoint into `OUT/checkpoints/` every this much simulated time (at the
    /// first window boundary at or after each multiple, for controlled runs).
    pub checkpoint_every: Option<SimTime>,
    /// Replace another scenario's run in the output directory
    /// ([`crate::output::run_dir::claim`]).
    pub force: bool,
    /// Bounds on steps, output and checkpoints ([`budget`]).
    pub limits: budget::Limits,
    /// Write no trace.csv and network.csv (a sweep point with `--keep summary`): the
    /// digests are the same, `trace_digest` is absent.
    pub skip_trace_files: bool,
    /// BLAKE3 of the scenario's text as the run keeps it (`scenario.json`: the file's
    /// bytes as read, or with `--set` the overridden text), which summary.json records
    /// as `provenance.scenario_blake3`: byte-identical files give the same hash. `None`
    /// (a scenario built in memory, a resumed checkpoint): the hash of the validated
    /// model as JSON instead.
    pub scenario_blake3: Option<[u8; 32]>,
}

/// Runs `scenario` and writes its outputs into `out`.
pub fn run(scenario: &Scenario, out: &Path) -> Result<Outcome> {
    run_with(scenario, out, RunOptions::default())
}

/// Everything a run checks and builds that can still refuse a validated scenario, before
/// it writes anything: the cost estimate against the limits, and the controller (its
/// simplex must fit the delay bounds). `validate` and a sweep's point check call it too,
/// so they refuse exactly what `run` would.
pub fn preflight(scenario: &Scenario, options: &RunOptions) -> Result<Option<Controller>> {
    budget::Estimate::of(scenario, options.checkpoint_every).check(&options.limits)?;
    if options.checkpoint_every.is_some() {
        // A checkpoint holds each FMU's state as bytes.
        if let Some(f) = scenario
            .fmus
            .iter()
            .find(|f| !(f.can_get_set_state && f.can_serialize_state))
        {
            return Err(Error::invalid(
                "--checkpoint-every",
                format!(
                    "a checkpoint stores every FMU's state, and FMU {:?} cannot save it \
                     (it lacks {})",
                    f.name,
                    if f.can_get_set_state {
                        "canSerializeFMUstate"
                    } else {
                        "canGetAndSetFMUstate"
                    }
                ),
            ));
        }
    }
    Controller::new(scenario)
}

/// Runs `scenario` with `options` and writes its outputs into `out`.
pub fn run_with(scenario: &Scenario, out: &Path, options: RunOptions) -> Result<Outcome> {
    run_shared(Arc::new(scenario.clone()), out, options)
}

/// [`run_with`] on a scenario the caller hands over: the run's world holds it without
/// a copy.
pub fn run_shared(shared: Arc<Scenario>, out: &Path, options: RunOptions) -> Result<Outcome> {
    let scenario = &*shared;
    let controller = preflight(scenario, &options)?;
    let dir = claim(out, &scenario.name, options.force)?;
    let trace_path = out.join("trace.csv");
    let file = if options.skip_trace_files {
        None
    } else {
        Some(AtomicFile::create(&trace_path)?)
    };
    let mut recorder =
        Recorder::for_scenario(file, scenario).map_err(|e| Error::io(&trace_path, e))?;
    let world = CoSim::shared(Arc::clone(&shared));
    if world.tdma().is_some() {
        let path = out.join("network.csv");
        let names = scenario.channels.iter().map(|c| c.name.clone()).collect();
        let file = if options.skip_trace_files {
            None
        } else {
            Some(AtomicFile::create(&path)?)
        };
        let log = NetworkLog::new(
            file,
            scenario.output.network_decimation,
            scenario.output.timeline_cycles,
            names,
        )
        .map_err(|e| Error::io(&path, e))?;
        recorder.attach_network(log);
    }
    if options.checkpoint_every.is_some() {
        recorder.keep_lines();
    }
    let result = finish(out, world, recorder, controller, options);
    stale_removed(&dir, result)
}

/// Runs `scenario` as [`run_with`] does and keeps `text`, the scenario as run (overrides
/// applied), as `out/scenario.json`: beside the outputs of every run that wrote them
/// (finished, diverged, failed numerically or in an FMU, interrupted: each is a result,
/// and an interrupted one is continued from its checkpoint with its scenario in view).
/// `dsmcosim run` and the Python package call it.
pub fn run_keeping_scenario(
    scenario: Scenario,
    text: &str,
    out: &Path,
    options: RunOptions,
) -> Result<Outcome> {
    run_keeping_scenario_of(scenario, text, None, out, options)
}

/// [`run_keeping_scenario`] of the scenario file `source`: the copy's relative FMU paths
/// point from `out` to the FMUs the file names
/// ([`crate::scenario::relocated_fmu_paths`]), so that `dsmcosim run OUT/scenario.json`
/// reruns the scene. `provenance.scenario_blake3` stays the hash of `text`, the file
/// as read.
pub fn run_keeping_scenario_of(
    scenario: Scenario,
    text: &str,
    source: Option<&Path>,
    out: &Path,
    options: RunOptions,
) -> Result<Outcome> {
    let options = RunOptions {
        scenario_blake3: options
            .scenario_blake3
            .or_else(|| Some(*blake3::hash(text.as_bytes()).as_bytes())),
        ..options
    };
    let result = run_shared(Arc::new(scenario), out, options);
    if result.is_ok()
        || matches!(
            result,
            Err(Error::Diverged(_)
                | Error::Numerical { .. }
                | Error::Fmu(_)
                | Error::Interrupted { .. })
        )
    {
        let relocated = source.and_then(|f| crate::scenario::relocated_fmu_paths(text, f, out));
        let kept = relocated.as_deref().unwrap_or(text);
        write_atomic(&out.join("scenario.json"), kept.as_bytes())?;
    }
    result
}

/// `result`, after removing the previous run's outputs this run did not replace (only
/// once this run's summary.json is written, [`crate::output::run_dir::RunDir::remove_stale`]).
fn stale_removed(dir: &crate::output::run_dir::RunDir, result: Result<Outcome>) -> Result<Outcome> {
    let removed = dir.remove_stale();
    let outcome = result?;
    removed.map(|()| outcome)
}

/// Finishes the run saved in the checkpoint at `path`, writing every output into `out`
/// (the trace from t = 0: the checkpoint carries the lines written before it).
pub fn resume(path: &Path, out: &Path, options: RunOptions) -> Result<Outcome> {
    let cp = crate::checkpoint::read(path)?;
    budget::Estimate::of(cp.world.scenario(), options.checkpoint_every).check(&options.limits)?;
    let dir = claim(out, &cp.world.scenario().name, options.force)?;
    let trace_path = out.join("trace.csv");
    let mut recorder = cp.recorder;
    recorder
        .reattach(AtomicFile::create(&trace_path)?)
        .map_err(|e| Error::io(&trace_path, e))?;
    if recorder.network().is_some() {
        let path = out.join("network.csv");
        recorder
            .reattach_network(AtomicFile::create(&path)?)
            .map_err(|e| Error::io(&path, e))?;
    }
    let name = cp.world.scenario().name.clone();
    let result = finish(out, cp.world, recorder, cp.controller, options);
    keep_scenario_of_checkpoint(path, out, &name)?;
    stale_removed(&dir, result)
}

/// A resumed run keeps the scenario it runs as `out/scenario.json`: the one of the run
/// the checkpoint came from (`RUN/checkpoints/t_….ckpt` beside `RUN/scenario.json`), if
/// it is there and names the same scenario. A checkpoint moved away from its run leaves
/// none (the checkpoint holds the model, not the file's text).
fn keep_scenario_of_checkpoint(checkpoint: &Path, out: &Path, name: &str) -> Result<()> {
    let Some(source) = checkpoint
        .parent()
        .and_then(Path::parent)
        .map(|run| run.join("scenario.json"))
    else {
        return Ok(());
    };
    let target = out.join("scenario.json");
    let same_file = std::fs::canonicalize(&source).ok() == std::fs::canonicalize(&target).ok();
    if same_file {
        return Ok(()); // resumed into its own run directory: it is there already
    }
    let Ok(text) = crate::input::read_text(&source) else {
        return Ok(());
    };
    let names_it = serde_json::from_str::<serde_json::Value>(&text)
        .ok()
        .and_then(|v| v.get("name").and_then(|n| n.as_str()).map(|n| n == name))
        .unwrap_or(false);
    if names_it {
        let relocated = crate::scenario::relocated_fmu_paths(&text, &source, out);
        write_atomic(&target, relocated.as_deref().unwrap_or(&text).as_bytes())?;
    }
    Ok(())
}

/// Runs the world from where it is to its end, then writes every output.
fn finish(
    out: &Path,
    mut world: CoSim,
    mut recorder: Recorder,
    mut controller: Option<Controller>,
    options: RunOptions,
) -> Result<Outcome> {
    let started = Instant::now();
    // Driven on a thread of rayon's pool, so that a parallel lock-step forks from a
    // worker (which then takes a share of the nodes itself) instead of handing each of
    // its three parallel regions per step to the pool and sleeping until they are done:
    // a 64×64 grid on 16 nodes runs 15 % faster on 2 threads (docs/performance.md).
    // The caller's progress listener goes with the driver onto the pool's thread.
    let listener = crate::progress::listener();
    let result = rayon::scope(|_| {
        crate::progress::reporting_to(listener, || {
            drive(out, &mut world, &mut recorder, controller.as_mut(), options)
        })
    });
    let wall_seconds = started.elapsed().as_secs_f64();
    let trace_digest = recorder.trace_digest();
    recorder.commit()?;
    let experiment = controller.map(|c| c.experiment).unwrap_or_default();
    let outcome = Outcome {
        trace_digest,
        digest: recorder.digest(),
        dynamics_digest: recorder.dynamics_digest(),
        steps: world.steps_done().saturating_sub(1),
        max_constraint_violation: world.max_violation(),
        mean_cost: world.mean_cost(),
        rows: world.scenario().links.len(),
        signal_cost: !world.scenario().cost_signals.is_empty(),
        wall_seconds,
        messages: world.messages(),
        events: world.events(),
        boundary_layer: recorder.boundary_layer().cloned(),
        joint_work: recorder.joint_work().cloned(),
        unserved: unserved::unserved(&world),
        stopped: world.stopped().map(ToString::to_string),
    };
    write_epochs(out, &world, &experiment)?;
    let run = Ran {
        world: &world,
        recorder: &recorder,
        outcome: &outcome,
        failure: result.as_ref().err(),
        experiment: &experiment,
        scenario_blake3: options.scenario_blake3,
    };
    write_summary(out, &run)?;
    write_plots(out, &world, &recorder)?;
    network::write_plots(out, &world, &recorder)?;
    if world.scenario().controller.is_some() {
        controlled::write_plots(out, &world, &experiment)?;
        landscape::write(out, &world, &experiment)?;
    }
    result.map(|()| outcome)
}

/// The steps of one slice of an uncontrolled run: 1024, fewer on a large model (about
/// 2^18 body-steps a slice, at least 16 steps), so that a slice takes a fraction of a
/// second and Ctrl-C, checked between slices, is answered within it. Slicing changes
/// nothing a run writes: events are processed in the same order.
pub fn slice_steps(scenario: &Scenario) -> u64 {
    let bodies = scenario.bodies.len().max(1) as u64;
    ((1 << 18) / bodies).clamp(16, 1024)
}

/// Drives the world to its end — window by window under a controller, else in slices
/// of [`slice_steps`] with progress on a terminal — writing checkpoints on the way.
fn drive(
    out: &Path,
    world: &mut CoSim,
    recorder: &mut Recorder,
    mut controller: Option<&mut Controller>,
    options: RunOptions,
) -> Result<()> {
    let s = world.scenario();
    let (steps, dt, end) = (s.steps, s.dt, s.duration);
    let mut progress = crate::progress::Progress::new(steps);
    // Saturating: a dt near the end of simulated time (about 1.8e10 s) times 1024 wrapped
    // to a slice that never reached the end.
    let slice = SimTime(dt.0.saturating_mul(slice_steps(s)));
    let mut t = match &controller {
        Some(c) => c.next_window(),
        None => world.now(),
    };
    let every = options.checkpoint_every.filter(|e| e.0 > 0);
    let next_multiple = |t: SimTime, e: SimTime| SimTime((t.0 / e.0 + 1).saturating_mul(e.0));
    let mut next_cp = every.map(|e| next_multiple(t, e));
    let mut last_cp: Option<std::path::PathBuf> = None;
    while t < end {
        let target = next_cp.unwrap_or(end).min(end);
        match controller.as_deref_mut() {
            Some(c) => {
                c.run_until(world, recorder, target)?;
                t = c.next_window();
            }
            None => {
                while t < target && !world.finished() {
                    t = SimTime(t.0.saturating_add(slice.0)).min(target);
                    world.advance_to(t, recorder)?;
                    progress.tick(world.steps_done());
                    interrupted(out, t, end, (last_cp.as_deref(), next_cp))?;
                }
            }
        }
        if world.finished() {
            break; // an FMU asked to stop: the run ends where it did
        }
        interrupted(out, t, end, (last_cp.as_deref(), next_cp))?;
        if let (Some(e), Some(cp)) = (every, next_cp) {
            if t < end {
                last_cp = Some(crate::checkpoint::write(
                    out,
                    t,
                    world,
                    recorder,
                    controller.as_deref(),
                )?);
            }
            next_cp = Some(next_multiple(t, e).max(SimTime(cp.0.saturating_add(e.0))));
        }
    }
    world.run_to_end(recorder)?;
    progress.finish();
    Ok(())
}

/// The error of a run stopped by Ctrl-C or SIGTERM at `t` (see [`crate::interrupt`]),
/// with the way to continue: the last checkpoint written (`checkpoints.0`), else when the
/// first is due (`checkpoints.1`, on a run that writes them), else the option that makes
/// a run write them.
fn interrupted(
    out: &Path,
    t: SimTime,
    end: SimTime,
    checkpoints: (Option<&Path>, Option<SimTime>),
) -> Result<()> {
    if !crate::interrupt::requested() || t >= end {
        return Ok(());
    }
    let hint = match checkpoints {
        (Some(last), _) => format!(
            "continue from the last checkpoint with `dsmcosim resume {} -o {}`",
            last.display(),
            out.display()
        ),
        (None, Some(first)) => format!(
            "no checkpoint was written yet (the first was due at t = {first}), so a rerun \
             starts from t = 0"
        ),
        (None, None) => "a rerun starts from t = 0; `--checkpoint-every S` writes checkpoints \
                         that `dsmcosim resume` continues from"
            .to_string(),
    };
    Err(Error::Interrupted { at: t, end, hint })
}

fn write_epochs(out: &Path, world: &CoSim, exp: &Experiment) -> Result<()> {
    let mut s = String::from("t_start,t_end");
    for c in world.channels() {
        s.push_str(&format!(",tau_{0}_requested,tau_{0}_achieved", c.spec.name));
    }
    s.push_str(",bandwidth,cost");
    s.push_str(&controlled::epoch_header(world, exp));
    s.push('\n');
    for (i, e) in world.epochs().iter().enumerate() {
        s.push_str(&format!(
            "{},{}",
            e.t_start.as_secs_f64(),
            e.t_end.as_secs_f64()
        ));
        for (req, ach) in &e.taus {
            s.push_str(&format!(",{req},{ach}"));
        }
        s.push_str(&format!(",{},{}", e.bandwidth, e.cost));
        s.push_str(&controlled::epoch_row(world, exp, i));
        s.push('\n');
    }
    write_atomic(&out.join("epochs.csv"), s.as_bytes())
}

/// `digest_algorithm` in summary.json: the records of the chain, in order.
const DIGEST_ALGORITHM: &str = "BLAKE3(dynamics || epochs) of two BLAKE3 chains \
d_(k+1) = BLAKE3(d_k, record_k) from 32 zero bytes, each in kernel event order. dynamics: \
every step (t [ns], the bits of w, f, p, v) and every TDMA cycle (start, then per frame \
slot, sender, start, delivery [ns]); epochs: every epochs.csv row when its window closes \
(t_start, t_end [ns], the bits of each channel's requested and achieved tau, bandwidth, \
cost; then, on a controlled run, the bits of each objective, the grid optimum's count and \
bits, the measurement count). dynamics_digest: the dynamics chain alone. See \
dsmcosim::trace::digest";

/// The stabilizer as summary.json and the plan give it.
pub(crate) fn stabilizer_json(scenario: &Scenario) -> Value {
    match scenario.stabilizer {
        Stabilizer::Smc { mu, k, epsilon } => {
            json!({"kind": "smc", "mu": mu, "k": k, "epsilon": epsilon})
        }
        Stabilizer::Baumgarte { alpha, beta } => {
            json!({"kind": "baumgarte", "alpha": alpha, "beta": beta})
        }
    }
}

/// The multiplier solve as summary.json and the plan give it.
pub(crate) fn solver_json(scenario: &Scenario) -> Value {
    match scenario.solver {
        Solver::Cholesky => json!({"kind": "cholesky"}),
        Solver::CholeskyPcg {
            refactor_every,
            tolerance,
            max_iterations,
        } => json!({
            "kind": "cholesky_pcg",
            "refactor_every": refactor_every,
            "max_iterations": max_iterations,
            "tolerance": tolerance,
        }),
        Solver::ConjugateGradient {
            max_iterations,
            tolerance,
        } => json!({"kind": "cg", "max_iterations": max_iterations, "tolerance": tolerance}),
    }
}

/// `divergence` in summary.json: where and when a run diverged or failed numerically,
/// as fields (the same as the `error` text); null for a failure that is not one (an
/// unwritable checkpoint, an FMU's error, an interruption: `error` says what).
fn divergence(e: &Error) -> Value {
    match e {
        Error::Diverged(d) => {
            use crate::error::Place;
            let (link, body, fmu_output) = match &d.place {
                Place::Link(k) => (Some(format!("L{k}")), None, None),
                Place::JointRow { joint, row } => (Some(format!("J{joint}_{row}")), None, None),
                Place::Body(id) => (None, Some(format!("B{id}")), None),
                // As trace.csv names its column.
                Place::FmuOutput { fmu, variable } => {
                    (None, None, Some(format!("{fmu}.{variable}")))
                }
            };
            let mut v = json!({"time": d.time.as_secs_f64(), "node": d.node, "link": link, "body": body, "what": d.what});
            if let Some(column) = fmu_output {
                v["fmu_output"] = json!(column);
            }
            v
        }
        Error::Numerical { time, message } => {
            json!({"time": time.as_secs_f64(), "node": null, "link": null, "body": null, "what": message})
        }
        _ => Value::Null,
    }
}

/// What a finished (or diverged) run leaves for its summary.
struct Ran<'a> {
    world: &'a CoSim,
    recorder: &'a Recorder,
    outcome: &'a Outcome,
    failure: Option<&'a Error>,
    experiment: &'a Experiment,
    /// [`RunOptions::scenario_blake3`].
    scenario_blake3: Option<[u8; 32]>,
}

fn write_summary(out: &Path, run: &Ran) -> Result<()> {
    let Ran {
        world,
        recorder,
        outcome,
        failure,
        experiment: exp,
        scenario_blake3,
    } = *run;
    let scenario = world.scenario();
    let error = failure.map(ToString::to_string);
    let stabilizer = stabilizer_json(scenario);
    let solver = solver_json(scenario);
    let sim_seconds = SimTime(outcome.steps * scenario.dt.0).as_secs_f64();
    let epochs = world.epochs();
    // Mean over the windows; a value that every window shares is reported as it is
    // (a sum of n copies divided by n need not give the same f64 back).
    let mean = |f: &dyn Fn(&crate::cosim::EpochRecord) -> f64| {
        let first = f(epochs.first()?);
        if epochs.iter().all(|e| f(e) == first) {
            return Some(first);
        }
        Some(epochs.iter().map(f).sum::<f64>() / epochs.len() as f64)
    };
    let tdma = world.tdma().is_some();
    let channels: Vec<_> = world
        .channels()
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let mut entry = json!({
                "name": c.spec.name,
                "tau": c.tau.as_secs_f64(),
                "tau_requested": mean(&|e| e.taus[i].0),
                "tau_achieved": mean(&|e| e.taus[i].1),
                "tau_achieved_max": epochs.iter().map(|e| e.taus[i].1).fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.max(x)))),
                "k": c.spec.k,
                "routes": c.routes.len(),
            });
            if !tdma {
                entry["latency"] = json!(c.latency().as_secs_f64());
            }
            entry
        })
        .collect();
    let summary = json!({
        "scenario": scenario.name,
        "provenance": provenance(scenario, scenario_blake3),
        "seed": scenario.seed,
        // `diverged` for what the simulation did (a divergence, a numerical failure);
        // `failed` for what stopped it from outside (an unwritable checkpoint).
        "status": match failure {
            None if world.stopped().is_some() => "stopped",
            None => "ok",
            Some(Error::Diverged(_) | Error::Numerical { .. }) => "diverged",
            Some(Error::Fmu(_)) => "fmu_error",
            Some(Error::Interrupted { .. }) => "interrupted",
            Some(_) => "failed",
        },
        "error": error,
        // Who ended the run before its duration, when and how ("status": "stopped").
        "stopped": world.stopped().map(|s| json!({
            "fmu": s.fmu,
            "time": s.time.as_secs_f64(),
            "reason": s.reason,
            "message": s.to_string(),
        })),
        "divergence": failure.map_or(Value::Null, divergence),
        "digest": outcome.digest,
        "digest_algorithm": DIGEST_ALGORITHM,
        "dynamics_digest": outcome.dynamics_digest,
        "trace_digest": outcome.trace_digest,
        "steps": outcome.steps,
        "sim_seconds": sim_seconds,
        "wall_seconds": outcome.wall_seconds,
        "real_time_factor": sim_seconds / outcome.wall_seconds.max(1e-12),
        "max_constraint_violation": outcome.max_constraint_violation,
        "mean_cost": outcome.mean_cost,
        "bodies": scenario.bodies.len(),
        "links": scenario.links.len(),
        "nodes": scenario.node_count(),
        "messages": outcome.messages,
        "events": outcome.events,
        "channels": channels,
        "bandwidth_mean": mean(&|e| e.bandwidth),
        "lost_frames": world.tdma().map_or(0, |l| l.network().lost()),
        "body_model": scenario.body_model.name(),
        "integrator": scenario.integrator.name(),
        "dt": scenario.dt.as_secs_f64(),
        "stabilizer": stabilizer,
        "solver": solver,
    });
    let mut summary = summary;
    if let Some(invariants) = recorder.invariants_summary() {
        summary["invariants"] = invariants;
    }
    if let Some(layer) = recorder.boundary_layer() {
        summary["boundary_layer"] = layer.summary();
    }
    if let Some(work) = recorder.joint_work() {
        summary["joint_work"] = work.summary();
    }
    // Always present on a partitioned run, empty when every request ran as asked.
    if scenario.partition.is_some() || !scenario.channels.is_empty() {
        summary["delays_not_realized"] = json!(outcome.unserved);
    }
    if let Some(p) = &scenario.partition {
        let mut ports = crate::partition::coupling::PortAccount::default();
        let (mut port_count, mut peaks) = (0, 0.0);
        for node in world.nodes() {
            let e = node.port_energy();
            ports.taken += e.taken;
            ports.given += e.given;
            ports.dissipated += e.dissipated;
            port_count += node.bodies.len() - node.owned;
            peaks += node.energy_scale();
        }
        let mut coupling = json!({"scheme": p.coupling.name()});
        if let Some(tank) = p.coupling.tank() {
            // What the coupling could create over the run, all nodes together.
            let tanks = match tank {
                Tank::Fixed(per_port) => {
                    coupling["tank_j"] = json!(per_port);
                    per_port * port_count as f64
                }
                Tank::Share(share) => {
                    coupling["tank_share"] = json!(share);
                    share * peaks
                }
            };
            coupling["tanks_j"] = json!(tanks);
            coupling["ports_taken_j"] = json!(ports.taken);
            coupling["ports_given_j"] = json!(ports.given);
            coupling["dissipated_j"] = json!(ports.dissipated);
        }
        summary["coupling"] = coupling;
    }
    if !scenario.fmus.is_empty() {
        summary["fmus"] = scenario
            .fmus
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let (messages, not_kept) = world.fmu_messages(i);
                json!({
                    "name": f.name,
                    "path": f.path.display().to_string(),
                    "blake3": f.hash,
                    "fmi_version": f.fmi_version,
                    "model_identifier": f.model_identifier,
                    "guid": f.guid,
                    "generation_tool": f.generation_tool,
                    "node": f.node + 1,
                    "step": f.step.as_secs_f64(),
                    // trace.csv's columns of this FMU and the FMI type of each (FMI 3.0's
                    // names: Float64, Int32, …), for a reader that types them.
                    "trace_columns": f
                        .outputs
                        .iter()
                        .filter(|v| v.traced)
                        .flat_map(|v| {
                            let names = v.element_names().into_iter();
                            names.map(move |n| json!({
                                "column": format!("{}.{n}", f.name),
                                "type": v.kind.fmi3_name(),
                            }))
                        })
                        .collect::<Vec<_>>(),
                    "messages": messages,
                    "messages_not_kept": not_kept,
                })
            })
            .collect();
        summary["connections"] = json!(scenario.connections.len());
    }
    network::summarize(world, &mut summary);
    controlled::summarize(world, exp, &mut summary);
    landscape::summarize(world, exp, &mut summary);
    let mut text = serde_json::to_string_pretty(&summary).unwrap_or_default();
    text.push('\n');
    write_atomic(&out.join("summary.json"), text.as_bytes())
}

/// Who computed the run and from what: the tool's version, the git commit it was built
/// from (null outside a checkout; `-dirty` when tracked files differed), the compiler,
/// and BLAKE3 of the scenario: of its text as the run keeps it (`text_blake3`, the
/// file's bytes as read, [`RunOptions::scenario_blake3`]), so that byte-identical files
/// give the same hash; without a text (a scenario built in memory, a resumed
/// checkpoint), of the validated model with every default applied, serialized as JSON.
fn provenance(scenario: &Scenario, text_blake3: Option<[u8; 32]>) -> serde_json::Value {
    let non_empty = |s: &'static str| (!s.is_empty()).then_some(s);
    let hash = match text_blake3 {
        Some(bytes) => blake3::Hash::from(bytes),
        None => model_blake3(scenario),
    };
    json!({
        "tool": "dsmcosim",
        "version": env!("CARGO_PKG_VERSION"),
        "git_commit": non_empty(env!("DSMCOSIM_GIT_COMMIT")),
        "rustc": non_empty(env!("DSMCOSIM_RUSTC")),
        "scenario_blake3": hash.to_hex().to_string(),
    })
}

/// BLAKE3 of the validated model serialized as JSON.
fn model_blake3(scenario: &Scenario) -> blake3::Hash {
    // Streamed into the hash: the JSON text of a million-body model is about 0.8 GB,
    // which a `to_vec` held on top of the whole world at the run's end (its peak).
    let mut hasher = blake3::Hasher::new();
    let streamed = {
        let mut w = std::io::BufWriter::with_capacity(1 << 16, &mut hasher);
        serde_json::to_writer(&mut w, scenario).is_ok() && std::io::Write::flush(&mut w).is_ok()
    };
    if !streamed {
        // As `to_vec(..).unwrap_or_default()` did: the hash of nothing.
        hasher.reset();
    }
    hasher.finalize()
}

fn plot(
    out: &Path,
    file: &str,
    title: &str,
    x: &str,
    y: &str,
    series: &[Series],
    step: bool,
) -> Result<()> {
    write_line_plot(
        &out.join(file),
        &LinePlot {
            title,
            x_label: x,
            y_label: y,
            series,
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            step,
            markers: step,
        },
    )
}

/// FMU outputs drawn in `signals.svg`, one panel each.
const SIGNAL_PANELS: usize = 12;

/// Links of largest `max |w|` drawn one line each in the constraint plot of a scene
/// with more than [`envelope::FEW`] links.
const WORST_LINKS: usize = 4;

fn write_plots(out: &Path, world: &CoSim, rec: &Recorder) -> Result<()> {
    let title = |what: &str| crate::report::capitalized(what);
    let time = "time t [s]";
    // Up to 6 links one line each; more as their envelope plus the worst few.
    let links = rec.constraint_series();
    // A scene with joints has rows (a joint's are in m or, for its alignments, in
    // units of the cosine they hold at zero), not only links.
    let joints = world.scenario().links.iter().any(|l| l.joint.is_some());
    let noun = if joints { "constraint rows" } else { "links" };
    let what = if links.len() > envelope::FEW {
        format!("constraint values of {} {noun}", links.len())
    } else {
        "constraint values".to_string()
    };
    let axis = if joints {
        "constraint value w [m; alignment rows: 1]"
    } else {
        "constraint value w [m]"
    };
    // A scene of FMUs only has no links and no bodies to draw.
    if !links.is_empty() {
        plot(
            out,
            "constraints.svg",
            &title(&what),
            time,
            axis,
            &envelope::summarize(&links, noun, WORST_LINKS),
            false,
        )?;
    }
    let bodies = rec.body_series();
    if !bodies.is_empty() {
        plot(
            out,
            "bodies.svg",
            &title("body coordinates"),
            time,
            "position [m]",
            &bodies,
            false,
        )?;
    }
    // Each FMU output on its own axes: an FMU's variables have units of their own
    // (a position, a force), which one axis would mix. At most the first
    // [`SIGNAL_PANELS`]; trace.csv holds them all.
    let signals = rec.signal_series();
    let titles: Vec<String> = signals
        .iter()
        .take(SIGNAL_PANELS)
        .map(|s| format!("FMU output {}", s.label))
        .collect();
    let labels: Vec<String> = signals
        .iter()
        .take(SIGNAL_PANELS)
        .map(|s| format!("{} [the FMU's unit]", s.label))
        .collect();
    let panels: Vec<LinePlot> = signals
        .iter()
        .zip(titles.iter().zip(&labels))
        .map(|(s, (title, label))| LinePlot::new(title, time, label, std::slice::from_ref(s)))
        .collect();
    if !panels.is_empty() {
        crate::report::write_panels(&out.join("signals.svg"), &panels)?;
    }
    let spins = rec.angular_velocity_series();
    if !spins.is_empty() {
        plot(
            out,
            "angular_velocity.svg",
            &title("angular velocity of the plotted bodies (world frame)"),
            time,
            "angular velocity [rad/s]",
            &spins,
            false,
        )?;
    }
    let epochs = world.epochs();
    // Step plots: each window's value from its start, and the last one held to its end.
    let per_epoch = |label: String, f: &dyn Fn(&crate::cosim::EpochRecord) -> f64| {
        let mut points: Vec<(f64, f64)> = epochs
            .iter()
            .map(|e| (e.t_start.as_secs_f64(), f(e)))
            .collect();
        if let Some(e) = epochs.last() {
            points.push((e.t_end.as_secs_f64(), f(e)));
        }
        Series::new(label, points)
    };
    // The cost is Σ RMS w over the rows [m], or the measured signals' (in their own
    // units); a scene with neither measures nothing and gets no cost plot.
    let scenario = world.scenario();
    let measured = !scenario.cost_signals.is_empty();
    if measured || !scenario.links.is_empty() {
        let period = scenario.measurement_period.as_secs_f64();
        plot(
            out,
            "cost.svg",
            &title(&format!("cost per window (T = {period} s)")),
            "time t [s]",
            if measured {
                "cost C [the measured signals' units]"
            } else {
                "cost C [m]"
            },
            &[per_epoch("cost C".into(), &|e| e.cost)],
            true,
        )?;
    }
    if world.channels().is_empty() {
        return Ok(());
    }
    let mut delays = Vec::new();
    for (c, ch) in world.channels().iter().enumerate() {
        delays.push(per_epoch(format!("{} requested", ch.spec.name), &|e| {
            e.taus[c].0 * 1e3
        }));
        delays.push(per_epoch(format!("{} achieved", ch.spec.name), &|e| {
            e.taus[c].1 * 1e3
        }));
    }
    plot(
        out,
        "delays.svg",
        &title("delays per channel"),
        "time t [s]",
        "delay τ [ms]",
        &delays,
        true,
    )?;
    plot(
        out,
        "bandwidth.svg",
        &title("bandwidth used"),
        "time t [s]",
        "bandwidth Σ k/τ [1/s]",
        &[per_epoch("bandwidth used".into(), &|e| e.bandwidth)],
        true,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::tests_support::texts;

    /// Runs a `rows` × `cols` grid (body 1 driven) for 0.5 s into a fresh directory and
    /// returns its `constraints.svg`, `bodies.svg` and `trace.csv`.
    fn grid_run(rows: u32, cols: u32) -> (String, String, String) {
        let name = format!("plots_grid{rows}x{cols}");
        let json = serde_json::json!({
            "name": name, "seed": 7, "duration": 0.5, "dt": 0.001, "integrator": "euler",
            "stabilizer": {"kind": "smc", "mu": 0.05, "k": 10.0, "epsilon": 0.1},
            "model": {"grid": {"rows": rows, "cols": cols, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
            "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0, "phase": 0.0}],
            "output": {"decimation": 10}
        });
        let scenario = crate::scenario::parse_str(&json.to_string(), &name).unwrap();
        let dir = std::env::temp_dir().join(format!("dsmcosim-{name}-{}", std::process::id()));
        run(&scenario, &dir).unwrap();
        let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
        let out = (
            read("constraints.svg"),
            read("bodies.svg"),
            read("trace.csv"),
        );
        std::fs::remove_dir_all(&dir).unwrap();
        out
    }

    /// Largest x of the points of every `<polyline>` with more than 2 points (the data
    /// lines; legend swatches have 2).
    fn rightmost_data_x(svg: &str) -> i32 {
        svg.split("<polyline")
            .skip(1)
            .filter_map(|rest| {
                let at = rest.find(" points=\"")? + 9;
                let len = rest[at..].find('"')?;
                let xs: Vec<i32> = rest[at..at + len]
                    .split_whitespace()
                    .filter_map(|p| p.split(',').next()?.parse().ok())
                    .collect();
                (xs.len() > 2).then(|| xs.into_iter().max())?
            })
            .max()
            .unwrap_or(0)
    }

    /// Link names `L<k>` among the texts of `svg`, with their x (a legend row of a line
    /// drawn dashed on another reads `L2 (dashed, lies on L1)`).
    fn link_names(svg: &str) -> Vec<(i32, String)> {
        texts(svg)
            .into_iter()
            // An entry's first row starts with its name (`L2 (dashed, lies on L1)` may
            // wrap after it).
            .map(|t| {
                (
                    t.0,
                    t.1,
                    t.2.split(' ').next().unwrap_or_default().to_string(),
                )
            })
            .filter(|t| t.2.len() > 1 && t.2.starts_with('L'))
            .filter(|t| t.2[1..].chars().all(|c| c.is_ascii_digit()))
            .map(|t| (t.0, t.2))
            .collect()
    }

    #[test]
    fn many_links_plot_their_envelope_and_the_four_worst_beside_the_data() {
        let (svg, bodies, trace) = grid_run(4, 4);
        let texts = texts(&svg);
        let has = |s: &str| texts.iter().any(|t| t.2 == s);
        assert!(has("Constraint values of 24 links"));
        // The legend entry wraps after "band" in its panel.
        assert!(has("RMS of 24 links, band") && has("min–max"));
        assert!(has("time t [s]") && has("constraint value w [m]"));
        assert!(!texts.iter().any(|t| t.2.contains("more")), "nothing cut");
        // The 4 links of largest max |w| in the trace, largest first.
        let mut peak = [0.0f64; 24];
        for row in trace.lines().skip(1) {
            for (k, w) in row.split(',').skip(1).take(24).enumerate() {
                peak[k] = peak[k].max(w.parse::<f64>().unwrap().abs());
            }
        }
        let mut order: Vec<usize> = (0..24).collect();
        order.sort_by(|&a, &b| peak[b].total_cmp(&peak[a]).then(a.cmp(&b)));
        let want: Vec<String> = order[..4].iter().map(|k| format!("L{}", k + 1)).collect();
        let names = link_names(&svg);
        let got: Vec<String> = names.iter().map(|n| n.1.clone()).collect();
        assert_eq!(got, want);
        // The legend is right of every data line.
        let right = rightmost_data_x(&svg);
        for (x, name) in &names {
            assert!(*x > right, "{name} at x = {x}, data up to {right}");
        }
        // bodies.svg draws x, y, z of the plotted bodies, legend beside the data too.
        let right = rightmost_data_x(&bodies);
        let entries: Vec<(i32, i32, String)> = crate::report::tests_support::texts(&bodies)
            .into_iter()
            // An entry's first row (a long one wraps: `y of B1 (dashed, lies` / `on x …`).
            .filter(|t| {
                ["x of B", "y of B", "z of B"]
                    .iter()
                    .any(|p| t.2.starts_with(p))
            })
            .collect();
        assert!(!entries.is_empty() && entries.len() <= 6, "{entries:?}");
        assert!(
            entries.iter().all(|t| t.0 > right),
            "{entries:?} vs {right}"
        );
    }

    #[test]
    fn few_links_keep_one_line_each() {
        let (svg, _, trace) = grid_run(2, 2);
        let links = trace
            .lines()
            .next()
            .unwrap()
            .split(',')
            .filter(|c| c.starts_with("w_L"))
            .count();
        assert!((1..=6).contains(&links), "{links} links");
        let names: Vec<String> = link_names(&svg).into_iter().map(|n| n.1).collect();
        let want: Vec<String> = (1..=links).map(|k| format!("L{k}")).collect();
        assert_eq!(names, want);
        assert!(!svg.contains("RMS of"));
    }

    /// With `output.trace_rotation`, a spinning pendulum's run draws the plotted bodies'
    /// angular velocities (labelled axis and legend); without it, no such plot. The
    /// constraint plot names a joint's rows.
    #[test]
    fn rotation_is_plotted_when_traced() {
        let scene = |rotation: bool| {
            serde_json::json!({
                "name": format!("spin_plot_{rotation}"), "seed": 1, "duration": 0.5, "dt": 0.001,
                "integrator": "rk4",
                "model": {"gravity": [0, 0, -9.81],
                          "bodies": [{"id": 4, "mass": 1.0, "size": 0.2, "position": [1, 0, 0],
                                      "angular_velocity": [0, 0, 2]}],
                          "joints": [{"type": "hinge", "a": 4, "at": [0, 0, 0], "axis": [0, 1, 0]}]},
                "output": {"decimation": 10, "trace_rotation": rotation}
            })
        };
        for rotation in [true, false] {
            let v = scene(rotation);
            let scenario = crate::scenario::parse_str(&v.to_string(), "spin").unwrap();
            let dir = tempfile::tempdir().unwrap();
            run(&scenario, dir.path()).unwrap();
            let plot = dir.path().join("angular_velocity.svg");
            assert_eq!(plot.exists(), rotation);
            let constraints = std::fs::read_to_string(dir.path().join("constraints.svg")).unwrap();
            let names = texts(&constraints);
            assert!(names.iter().any(|t| t.2 == "J1_4"), "{names:?}");
            if rotation {
                let svg = std::fs::read_to_string(plot).unwrap();
                let t = texts(&svg);
                for want in [
                    "angular velocity [rad/s]",
                    "ωx of B4",
                    "ωy of B4",
                    "ωz of B4",
                ] {
                    assert!(t.iter().any(|x| x.2 == want), "{want} missing: {t:?}");
                }
            }
        }
    }
}
