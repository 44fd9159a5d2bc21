//! One run of a scenario: the [`CoSim`] world driven to the end, recorded, measured
//! and written to an output directory (SPEC section 8). A monolithic scenario is the
//! one-node world.
//!
//! Written files: `trace.csv` (streamed, decimated), `epochs.csv`, `summary.json` and
//! the plots. A diverged run still writes everything up to the last sane step, then
//! returns the divergence error.

use std::path::Path;
use std::time::Instant;

use serde_json::json;

use crate::control::experiment::Experiment;
use crate::cosim::CoSim;
use crate::error::{Error, Result};
use crate::kernel::SimTime;
use crate::output::{create_dir_all, write_atomic, AtomicFile};
use crate::report::{write_line_plot, LinePlot, Scale, Series};
use crate::scenario::model::{Scenario, Solver, Stabilizer};
use crate::trace::Recorder;

mod controlled;

/// What a finished (or diverged) run measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Trace digest (hex).
    pub digest: String,
    /// Steps integrated (recorded steps: `steps + 1` rows including t = 0 on success).
    pub steps: u64,
    /// Largest `|w|` over the run [m].
    pub max_constraint_violation: f64,
    /// Mean window cost [m].
    pub mean_cost: f64,
    /// Wall-clock seconds the simulation took (not part of anything digested).
    pub wall_seconds: f64,
    /// Messages delivered between nodes.
    pub messages: u64,
    /// Kernel events processed.
    pub events: u64,
}

/// Runs `scenario` and writes its outputs into `out`.
pub fn run(scenario: &Scenario, out: &Path) -> Result<Outcome> {
    create_dir_all(out)?;
    let trace_path = out.join("trace.csv");
    let file = AtomicFile::create(&trace_path)?;
    let ids: Vec<u32> = scenario.bodies.iter().map(|b| b.id).collect();
    let mut recorder = Recorder::new(
        Some(file),
        scenario.output.decimation,
        scenario.links.len(),
        &ids,
        &scenario.output.trace_bodies,
        &scenario.output.plot_bodies,
    )
    .map_err(|e| Error::io(&trace_path, e))?;
    let mut world = CoSim::new(scenario);
    let started = Instant::now();
    let mut experiment = Experiment::default();
    let result = if scenario.controller.is_some() {
        crate::control::experiment::run(&mut world, &mut recorder, &mut experiment)
    } else {
        drive(&mut world, &mut recorder)
    };
    let wall_seconds = started.elapsed().as_secs_f64();
    recorder.commit()?;
    let outcome = Outcome {
        digest: recorder.digest(),
        steps: world.steps_done().saturating_sub(1),
        max_constraint_violation: world.max_violation(),
        mean_cost: world.mean_cost(),
        wall_seconds,
        messages: world.messages(),
        events: world.events(),
    };
    let error = result.as_ref().err().map(ToString::to_string);
    write_epochs(out, &world, &experiment)?;
    write_summary(out, &world, &outcome, error.as_deref(), &experiment)?;
    write_plots(out, &world, &recorder)?;
    if world.scenario().controller.is_some() {
        controlled::write_plots(out, &world, &experiment)?;
    }
    result.map(|()| outcome)
}

/// Drives the world to its end in slices of simulated time, showing progress on a
/// terminal when the run is long.
fn drive(world: &mut CoSim, recorder: &mut Recorder) -> Result<()> {
    let s = world.scenario();
    let (steps, dt, end) = (s.steps, s.dt, s.duration);
    let mut progress = crate::progress::Progress::new(steps);
    let slice = SimTime(dt.0 * 1024);
    let mut t = SimTime::ZERO;
    while t < end {
        t = SimTime(t.0 + slice.0).min(end);
        world.advance_to(t, recorder)?;
        progress.tick(world.steps_done());
    }
    world.run_to_end(recorder)?;
    progress.finish();
    Ok(())
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

fn write_summary(
    out: &Path,
    world: &CoSim,
    outcome: &Outcome,
    error: Option<&str>,
    exp: &Experiment,
) -> Result<()> {
    let scenario = world.scenario();
    let stabilizer = match scenario.stabilizer {
        Stabilizer::Smc { mu, k, epsilon } => {
            json!({"kind": "smc", "mu": mu, "k": k, "epsilon": epsilon})
        }
        Stabilizer::Baumgarte { alpha, beta } => {
            json!({"kind": "baumgarte", "alpha": alpha, "beta": beta})
        }
    };
    let solver = match scenario.solver {
        Solver::Cholesky => json!({"kind": "cholesky"}),
        Solver::ConjugateGradient {
            max_iterations,
            tolerance,
        } => json!({"kind": "cg", "max_iterations": max_iterations, "tolerance": tolerance}),
    };
    let sim_seconds = SimTime(outcome.steps * scenario.dt.0).as_secs_f64();
    let channels: Vec<_> = world
        .channels()
        .iter()
        .map(|c| {
            json!({
                "name": c.spec.name,
                "tau": c.tau.as_secs_f64(),
                "latency": c.latency().as_secs_f64(),
                "k": c.spec.k,
                "routes": c.routes.len(),
            })
        })
        .collect();
    let summary = json!({
        "scenario": scenario.name,
        "seed": scenario.seed,
        "status": if error.is_some() { "diverged" } else { "ok" },
        "error": error,
        "digest": outcome.digest,
        "digest_algorithm": "blake3 over every step's t [ns] and the bits of w, f, p, v (see trace::digest)",
        "steps": outcome.steps,
        "sim_seconds": sim_seconds,
        "wall_seconds": outcome.wall_seconds,
        "real_time_factor": sim_seconds / outcome.wall_seconds.max(1e-12),
        "max_constraint_violation": outcome.max_constraint_violation,
        "mean_cost": outcome.mean_cost,
        "bodies": scenario.bodies.len(),
        "links": scenario.links.len(),
        "nodes": world.layout().nodes,
        "messages": outcome.messages,
        "events": outcome.events,
        "channels": channels,
        "body_model": scenario.body_model.name(),
        "integrator": scenario.integrator.name(),
        "dt": scenario.dt.as_secs_f64(),
        "stabilizer": stabilizer,
        "solver": solver,
    });
    let mut summary = summary;
    controlled::summarize(world, exp, &mut summary);
    let mut text = serde_json::to_string_pretty(&summary).unwrap_or_default();
    text.push('\n');
    write_atomic(&out.join("summary.json"), text.as_bytes())
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

fn write_plots(out: &Path, world: &CoSim, rec: &Recorder) -> Result<()> {
    let name = &world.scenario().name;
    let title = |what: &str| format!("{name} — {what}");
    let time = "time t [s]";
    plot(
        out,
        "constraints.svg",
        &title("constraint values"),
        time,
        "constraint value w [m]",
        &rec.constraint_series(),
        false,
    )?;
    plot(
        out,
        "bodies.svg",
        &title("body coordinates"),
        time,
        "position [m]",
        &rec.body_series(),
        false,
    )?;
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
        Series { label, points }
    };
    let period = world.scenario().measurement_period.as_secs_f64();
    plot(
        out,
        "cost.svg",
        &title(&format!("cost per window (T = {period} s)")),
        "time t [s]",
        "cost C [m]",
        &[per_epoch("cost C".into(), &|e| e.cost)],
        true,
    )?;
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
