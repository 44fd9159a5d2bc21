//! A monolithic run: one [`System`] integrated from 0 to `duration`, recorded, measured
//! and written to an output directory (SPEC section 8).
//!
//! Per step k (why in this order: the values at `t_k` exist only after the first rate
//! evaluation, and must be checked before they are recorded):
//! 1. `begin_step(t_k)`: rates at `(t_k, x_k)` give `w_k`, `ẇ_k`;
//! 2. divergence check of `w_k`, `z_k` and the state;
//! 3. record: digest, decimated trace row, cost window;
//! 4. `finish_step`: the integrator produces `x_{k+1}`.
//!
//! Step `k = steps` (t = duration) runs stages 1–3 only.

use std::path::Path;
use std::time::Instant;

use serde_json::json;

use crate::control::CostMeter;
use crate::error::{Divergence, Error, Place, Result};
use crate::kernel::SimTime;
use crate::multibody::dynamics::EvalError;
use crate::multibody::{State, System};
use crate::output::{create_dir_all, write_atomic, AtomicFile};
use crate::report::{write_line_plot, LinePlot, Scale, Series};
use crate::scenario::model::{Scenario, Solver, Stabilizer};
use crate::trace::recorder::{Recorder, StepValues};

/// What a finished (or diverged) run measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Trace digest (hex).
    pub digest: String,
    /// Steps integrated.
    pub steps: u64,
    /// Largest `|w|` over the run [m].
    pub max_constraint_violation: f64,
    /// Mean window cost [m].
    pub mean_cost: f64,
    /// Wall-clock seconds the simulation took (not part of anything digested).
    pub wall_seconds: f64,
}

/// Runs `scenario` and writes summary.json, trace.csv, epochs.csv and the plots into
/// `out`. A diverged run still writes everything up to the last sane step, then
/// returns the divergence error.
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
    let mut meter = CostMeter::new(
        scenario.links.len(),
        scenario.dt,
        scenario.measurement_period,
    );
    let started = Instant::now();
    let result = simulate(scenario, &mut recorder, &mut meter, &trace_path);
    let wall_seconds = started.elapsed().as_secs_f64();
    meter.finish();
    recorder.commit()?;
    let outcome = Outcome {
        digest: recorder.digest(),
        steps: result.as_ref().map_or_else(|(k, _)| *k, |k| *k),
        max_constraint_violation: recorder.max_violation(),
        mean_cost: meter.mean_cost(),
        wall_seconds,
    };
    let error = result.as_ref().err().map(|(_, e)| e.to_string());
    write_epochs(out, &meter)?;
    write_summary(out, scenario, &outcome, error.as_deref())?;
    write_plots(out, scenario, &recorder, &meter)?;
    match result {
        Ok(_) => Ok(outcome),
        Err((_, e)) => Err(e),
    }
}

/// Integrates and records; returns the number of steps completed, or that number and
/// the error that stopped the run.
fn simulate(
    scenario: &Scenario,
    recorder: &mut Recorder,
    meter: &mut CostMeter,
    trace_path: &Path,
) -> std::result::Result<u64, (u64, Error)> {
    let mut system = System::new(scenario);
    let mut state = State::initial(scenario);
    let mut f = vec![0.0; scenario.links.len()];
    let mut progress = crate::progress::Progress::new(scenario.steps);
    for k in 0..=scenario.steps {
        let t = SimTime(k * scenario.dt.0);
        let fail = |e| (k, e);
        system
            .begin_step(t, &state)
            .map_err(|e| fail(eval_error(t, e, scenario)))?;
        check(t, &system, &state, scenario).map_err(fail)?;
        for (l, f) in f.iter_mut().enumerate() {
            *f = system.tension(&state, l);
        }
        let values = StepValues {
            step: k,
            time: t,
            last: k == scenario.steps,
            w: system.violations(),
            f: &f,
            state: &state,
        };
        recorder
            .record(&values)
            .map_err(|e| fail(Error::io(trace_path, e)))?;
        if k == scenario.steps {
            break;
        }
        meter.add(t, system.violations());
        system
            .finish_step(t, &mut state)
            .map_err(|e| fail(eval_error(t, e, scenario)))?;
        progress.tick(k + 1);
    }
    progress.finish();
    Ok(scenario.steps)
}

/// Divergence check of the values at `t`: finite state and multipliers, `|w|` within
/// the scenario's bound.
fn check(t: SimTime, system: &System, state: &State, scenario: &Scenario) -> Result<()> {
    let bound = scenario.max_violation;
    let diverged = |place, what: String| {
        Err(Error::Diverged(Divergence {
            time: t,
            node: 0,
            place,
            what,
        }))
    };
    for (l, &w) in system.violations().iter().enumerate() {
        let f = system.tension(state, l);
        if !w.is_finite() || !f.is_finite() {
            return diverged(Place::Link(l + 1), format!("non-finite w = {w} or f = {f}"));
        }
        if w.abs() > bound {
            return diverged(
                Place::Link(l + 1),
                format!("|w| = {} m exceeds the bound {bound} m", w.abs()),
            );
        }
    }
    if !state.is_finite() {
        let i = (0..state.bodies())
            .find(|&i| {
                !(state.p[i]
                    .iter()
                    .chain(state.v[i].iter())
                    .all(|x| x.is_finite()))
            })
            .unwrap_or(0);
        return diverged(
            Place::Body(scenario.bodies[i].id),
            "non-finite position, velocity or orientation".into(),
        );
    }
    Ok(())
}

fn eval_error(t: SimTime, e: EvalError, scenario: &Scenario) -> Error {
    match e {
        EvalError::NonFinite { link } => {
            let l = &scenario.links[link];
            Error::Diverged(Divergence {
                time: t,
                node: 0,
                place: Place::Link(link + 1),
                what: format!(
                    "non-finite kinematics (anchors of B{} and B{} coincide or the state is not finite)",
                    scenario.bodies[l.a].id, scenario.bodies[l.b].id
                ),
            })
        }
        EvalError::Solve(_) => Error::Numerical {
            time: t,
            message: "the multiplier matrix J M⁻¹ Jᵀ is not positive definite \
                      (redundant links or degenerate geometry)"
                .into(),
        },
    }
}

fn write_epochs(out: &Path, meter: &CostMeter) -> Result<()> {
    let mut s = String::from("t_start,t_end,cost\n");
    for e in meter.epochs() {
        s.push_str(&format!(
            "{},{},{}\n",
            e.t_start.as_secs_f64(),
            e.t_end.as_secs_f64(),
            e.cost
        ));
    }
    write_atomic(&out.join("epochs.csv"), s.as_bytes())
}

fn write_summary(
    out: &Path,
    scenario: &Scenario,
    outcome: &Outcome,
    error: Option<&str>,
) -> Result<()> {
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
    let summary = json!({
        "scenario": scenario.name,
        "seed": scenario.seed,
        "status": if error.is_some() { "diverged" } else { "ok" },
        "error": error,
        "digest": outcome.digest,
        "digest_algorithm": "blake3 over every step's t [ns] and the bits of w, f, p, v (see trace::digest)",
        "steps": outcome.steps,
        "sim_seconds": SimTime(outcome.steps * scenario.dt.0).as_secs_f64(),
        "wall_seconds": outcome.wall_seconds,
        "real_time_factor": SimTime(outcome.steps * scenario.dt.0).as_secs_f64() / outcome.wall_seconds.max(1e-12),
        "max_constraint_violation": outcome.max_constraint_violation,
        "mean_cost": outcome.mean_cost,
        "bodies": scenario.bodies.len(),
        "links": scenario.links.len(),
        "body_model": scenario.body_model.name(),
        "integrator": scenario.integrator.name(),
        "dt": scenario.dt.as_secs_f64(),
        "stabilizer": stabilizer,
        "solver": solver,
    });
    let mut text = serde_json::to_string_pretty(&summary).unwrap_or_default();
    text.push('\n');
    write_atomic(&out.join("summary.json"), text.as_bytes())
}

fn write_plots(out: &Path, scenario: &Scenario, rec: &Recorder, meter: &CostMeter) -> Result<()> {
    let title = |what: &str| format!("{} — {what}", scenario.name);
    write_line_plot(
        &out.join("constraints.svg"),
        &LinePlot {
            title: &title("constraint values"),
            x_label: "time t [s]",
            y_label: "constraint value w [m]",
            series: &rec.constraint_series(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            step: false,
            markers: false,
        },
    )?;
    write_line_plot(
        &out.join("bodies.svg"),
        &LinePlot {
            title: &title("body coordinates"),
            x_label: "time t [s]",
            y_label: "position [m]",
            series: &rec.body_series(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            step: false,
            markers: false,
        },
    )?;
    let cost = Series {
        label: "cost C per window".into(),
        points: meter
            .epochs()
            .iter()
            .map(|e| (e.t_start.as_secs_f64(), e.cost))
            .collect(),
    };
    write_line_plot(
        &out.join("cost.svg"),
        &LinePlot {
            title: &title(&format!(
                "cost per window (T = {} s)",
                scenario.measurement_period.as_secs_f64()
            )),
            x_label: "window start t [s]",
            y_label: "cost C [m]",
            series: std::slice::from_ref(&cost),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            step: true,
            markers: true,
        },
    )
}
