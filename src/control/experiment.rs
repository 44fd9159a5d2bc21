//! A controlled run: every measurement window the controller picks the delays the live
//! plant runs at, and every baseline is evaluated on the same window from the same
//! state (method §5).
//!
//! Per window `[t, t + T)`, at the window boundary (kernel class `Controller`: after the
//! window ending at t is measured, before anything at t is sampled):
//! 1. the grid search, when needed, forks the world once per grid point (in parallel;
//!    results are collected in grid order, so threads cannot change a bit);
//! 2. the live method decides: DSM with `lookahead` runs one iteration, each candidate
//!    measured on a fork over `[t, t + T)`; with `online` it asks for one candidate,
//!    which the live plant runs and the window then measures;
//! 3. each baseline's choice is measured on a fork over the same window;
//! 4. the live world runs the window at the chosen delays.
//!
//! Forks are clones of the world: they never touch the live run, whose digest is the
//! same with or without baselines. A fork that diverges scores `+∞`.

use std::sync::OnceLock;

use rayon::prelude::*;

use super::dsm::{Dsm, DsmConfig};
use super::nelder_mead::{NelderMead, NelderMeadConfig};
use super::paired::Paired;
use super::plant::{Plant, WindowSink};
use super::problem::Delays;
use crate::error::{Error, Result};
use crate::kernel::SimTime;
use crate::scenario::model::{ControllerSpec, Measure, Method};
use crate::scenario::Scenario;

/// A measured point of the delay space.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Candidate {
    /// Controlled delays [s].
    pub x: Vec<f64>,
    /// Objective over the window (CP: cost C [m]; UP: C + bΣk/τ).
    pub objective: f64,
}

/// One baseline's result in one window.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BaselineResult {
    /// Method name (`grid`, `no_opt`, `dsm_tau1_plus`, …).
    pub name: String,
    /// Its choice and objective (`NaN` when the choice was infeasible).
    pub candidate: Candidate,
}

/// What happened in one window.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WindowReport {
    /// Window start.
    pub t_start: SimTime,
    /// Window end.
    pub t_end: SimTime,
    /// The live method's choice and the objective the live plant measured.
    pub live: Candidate,
    /// Baselines, in the scenario's order (then DSM ± δ).
    pub baselines: Vec<BaselineResult>,
    /// The grid optimum of this window, when the grid was searched.
    pub grid_best: Option<Candidate>,
    /// Candidates the DSM measured in this window (lookahead), in order.
    pub dsm_path: Vec<Candidate>,
}

/// Everything a controlled run measured.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Experiment {
    /// One report per window, in time order.
    pub windows: Vec<WindowReport>,
    /// The whole grid of the surface window, with its start.
    pub surface: Option<(SimTime, Vec<Candidate>)>,
    /// A constrained problem over two channels: the window cost over every grid pair
    /// `(τ_1, τ_2)` of the surface window, the budget ignored (`x` holds both delays),
    /// with the window's start.
    pub landscape: Option<(SimTime, Vec<Candidate>)>,
}

impl Experiment {
    /// Mean objective of a method over the windows where it was measured (finite): not
    /// a comparison between methods, whose windows can differ ([`Experiment::paired`]
    /// compares).
    pub fn mean(&self, name: &str, live_name: &str) -> Option<f64> {
        let values: Vec<f64> = self
            .objectives(name, live_name)
            .into_iter()
            .filter(|v| v.is_finite())
            .collect();
        (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
    }

    /// The objective of method `name` in every window, in time order (`NaN` where it
    /// was not measured or its choice was infeasible).
    pub fn objectives(&self, name: &str, live_name: &str) -> Vec<f64> {
        self.windows
            .iter()
            .map(|w| {
                if name == live_name {
                    w.live.objective
                } else {
                    w.baselines
                        .iter()
                        .find(|b| b.name == name)
                        .map_or(f64::NAN, |b| b.candidate.objective)
                }
            })
            .collect()
    }

    /// Method `a` against method `b` over the windows where both were measured.
    pub fn paired(&self, a: &str, b: &str, live_name: &str) -> Paired {
        Paired::new(
            &self.objectives(a, live_name),
            &self.objectives(b, live_name),
        )
    }

    /// Names of the baselines, in column order.
    pub fn baseline_names(&self) -> Vec<String> {
        self.windows
            .first()
            .map(|w| w.baselines.iter().map(|b| b.name.clone()).collect())
            .unwrap_or_default()
    }
}

/// Measures `x` on a fork of `world` over `[t, t_end)` ([`evaluate_taus`]).
fn evaluate<P: Plant>(
    world: &P,
    delays: &Delays,
    x: &[f64],
    (t, t_end): (SimTime, SimTime),
    fmu_failure: &OnceLock<Error>,
) -> f64 {
    let Some(taus) = delays.taus(x) else {
        return f64::NAN;
    };
    evaluate_taus(world, delays, &taus, (t, t_end), fmu_failure)
}

/// Measures every channel at delays `taus` [s] on a fork of `world` over `[t, t_end)`.
/// A fork that diverges or whose network cannot serve the delays costs infinity: the
/// candidate is bad. A fork that fails in an FMU (it cannot be made because an FMU
/// cannot save or restore its state, or an FMU call fails in it) says nothing about the
/// candidate: the first such error goes to `fmu_failure`, and the window's caller stops
/// the run with it rather than deciding on costs that were never measured.
fn evaluate_taus<P: Plant>(
    world: &P,
    delays: &Delays,
    taus: &[f64],
    (t, t_end): (SimTime, SimTime),
    fmu_failure: &OnceLock<Error>,
) -> f64 {
    let mut fork = world.clone();
    let Ok(achieved) = fork.set_taus(t, taus, &delays.achieved(taus)) else {
        return f64::INFINITY;
    };
    match fork.advance_unobserved(t_end) {
        Ok(()) => match fork.last_window() {
            Some((end, cost)) if end == t_end => delays.objective(cost, &achieved),
            _ => f64::INFINITY,
        },
        Err(Error::Fmu(why)) => {
            let _ = fmu_failure.set(Error::Fmu(format!(
                "{why} (measuring a candidate on a fork of the run for the window from t = \
                 {} s)",
                t.as_secs_f64()
            )));
            f64::INFINITY
        }
        Err(_) => f64::INFINITY,
    }
}

fn argmin(points: &[Candidate]) -> Option<Candidate> {
    points
        .iter()
        .filter(|c| c.objective.is_finite())
        .min_by(|a, b| a.objective.total_cmp(&b.objective))
        .cloned()
}

fn controller_error(e: impl std::fmt::Display) -> Error {
    Error::invalid("controller", format!("cannot start the simplex: {e}"))
}

/// Runs a controlled scenario to its end, recording the live world with `obs`; fills
/// `exp` as windows complete (so a diverged run keeps what it measured).
pub fn run<P: Plant>(world: &mut P, obs: &mut P::Observer, exp: &mut Experiment) -> Result<()> {
    let end = world.scenario().duration;
    let Some(mut controller) = Controller::new(world.scenario())? else {
        return world.advance_to(end, obs);
    };
    let result = controller.run_until(world, obs, end);
    *exp = controller.experiment.clone();
    result?;
    world.advance_to(end, obs)
}

/// The controller's whole state between windows: the simplex searches and what was
/// measured so far. Serializable, so a checkpoint can carry it.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Controller {
    dsm: Option<Dsm>,
    nm: Option<NelderMead>,
    next: SimTime,
    /// Everything measured so far.
    pub experiment: Experiment,
}

impl Controller {
    /// The controller of `scenario` (`None` when it has none), before its first window.
    pub fn new(scenario: &crate::scenario::Scenario) -> Result<Option<Controller>> {
        let Some(spec) = scenario.controller.as_ref() else {
            return Ok(None);
        };
        let delays = Delays::new(spec, &scenario.channels, scenario.dt);
        let feasible = delays.feasible().map_err(controller_error)?;
        let dsm_config = DsmConfig {
            size: spec.dsm_size,
            reflections: spec.reflections,
        };
        let dsm = match spec.method {
            Method::Dsm => Some(
                Dsm::new(dsm_config, &spec.initial, feasible.clone()).map_err(controller_error)?,
            ),
            _ => None,
        };
        let wants_nm =
            spec.method == Method::NelderMead || spec.baselines.contains(&Method::NelderMead);
        let nm = if wants_nm {
            let config = NelderMeadConfig {
                size: spec.dsm_size,
                x_tolerance: scenario.dt.as_secs_f64(),
                f_tolerance: 0.0,
            };
            Some(NelderMead::new(config, &spec.initial, feasible).map_err(controller_error)?)
        } else {
            None
        };
        Ok(Some(Controller {
            dsm,
            nm,
            next: SimTime::ZERO,
            experiment: Experiment::default(),
        }))
    }

    /// The live Dynamic Simplex (`None` unless the method is `dsm`).
    pub fn dsm(&self) -> Option<&Dsm> {
        self.dsm.as_ref()
    }

    /// Start of the next window to decide.
    pub fn next_window(&self) -> SimTime {
        self.next
    }

    /// Decides and runs every window that starts before `stop`.
    pub fn run_until<P: Plant>(
        &mut self,
        world: &mut P,
        obs: &mut P::Observer,
        stop: SimTime,
    ) -> Result<()> {
        let scenario = world.scenario().clone();
        let Some(spec) = scenario.controller.clone() else {
            return Ok(());
        };
        let delays = Delays::new(&spec, &scenario.channels, scenario.dt);
        let wants_grid = spec.method == Method::Grid || spec.baselines.contains(&Method::Grid);
        let grid_points = if wants_grid || spec.surface_window.is_some() {
            delays.grid(spec.grid_step)
        } else {
            Vec::new()
        };
        let landscape_points = if spec.landscape {
            delays.landscape(spec.grid_step)
        } else {
            Vec::new()
        };
        let no_opt = delays.equal(&spec.initial);
        let names = channel_names(&scenario.channels);
        let period = scenario.measurement_period;
        let windows = scenario.duration.0.div_ceil(period.0);
        let mut progress = crate::progress::Progress::with_unit(windows, "windows");
        let (dsm, nm, exp) = (&mut self.dsm, &mut self.nm, &mut self.experiment);
        let mut t = self.next;
        while t < scenario.duration && t < stop {
            let t_end = SimTime(t.0.saturating_add(period.0)).min(scenario.duration);
            world.advance_to(t, obs)?;
            if world.finished() {
                break; // an FMU asked to stop: no window is left to decide
            }
            let live_world: &P = world;
            let fmu_failure = OnceLock::new();
            let eval = |x: &[f64]| evaluate(live_world, &delays, x, (t, t_end), &fmu_failure);
            let surface_here = spec.surface_window == Some(t);
            let grid: Option<Vec<Candidate>> = (wants_grid || surface_here).then(|| {
                let objectives: Vec<f64> = grid_points.par_iter().map(|x| eval(x)).collect();
                grid_points
                    .iter()
                    .zip(objectives)
                    .map(|(x, objective)| Candidate {
                        x: x.clone(),
                        objective,
                    })
                    .collect()
            });
            let grid_best = grid.as_deref().and_then(argmin);
            let mut dsm_path = Vec::new();
            let live_x = match spec.method {
                Method::Dsm => {
                    let d = dsm.as_mut().expect("ok: built for the DSM method");
                    match spec.measure {
                        Measure::Lookahead => {
                            d.iterate(|x| {
                                let objective = eval(x);
                                dsm_path.push(Candidate {
                                    x: x.to_vec(),
                                    objective,
                                });
                                objective
                            });
                            d.best().to_vec()
                        }
                        Measure::Online => d.ask().unwrap_or_else(|| d.best().to_vec()),
                    }
                }
                Method::Grid => grid_best
                    .as_ref()
                    .map_or_else(|| spec.initial.clone(), |c| c.x.clone()),
                Method::NoOptimization => no_opt.clone(),
                Method::Fixed => spec.initial.clone(),
                Method::NelderMead => {
                    let n = nm.as_mut().expect("ok: built for Nelder–Mead");
                    nelder_mead_window(n, spec.reflections + 1, &eval);
                    n.best().to_vec()
                }
            };
            let mut baselines = Vec::new();
            for &b in &spec.baselines {
                let candidate = match b {
                    Method::Grid => grid_best.clone().unwrap_or(Candidate {
                        x: Vec::new(),
                        objective: f64::NAN,
                    }),
                    Method::NelderMead => {
                        let n = nm.as_mut().expect("ok: built for Nelder–Mead");
                        nelder_mead_window(n, spec.reflections + 1, &eval);
                        measured(n.best(), &eval)
                    }
                    Method::NoOptimization => measured(&no_opt, &eval),
                    Method::Fixed => measured(&spec.initial, &eval),
                    Method::Dsm => measured(&live_x, &eval),
                };
                baselines.push(BaselineResult {
                    name: b.name().to_string(),
                    candidate,
                });
            }
            if let Some(delta) = spec.dsm_delta {
                for i in 0..live_x.len() {
                    for (sign, word) in [(1.0, "plus"), (-1.0, "minus")] {
                        let mut x = live_x.clone();
                        x[i] += sign * delta;
                        baselines.push(BaselineResult {
                            name: format!("dsm_{}_{word}", names[i]),
                            candidate: measured(&x, &eval),
                        });
                    }
                }
            }
            if surface_here {
                exp.surface = grid.clone().map(|g| (t, g));
                if !landscape_points.is_empty() {
                    let costs: Vec<f64> = landscape_points
                        .par_iter()
                        .map(|taus| {
                            evaluate_taus(live_world, &delays, taus, (t, t_end), &fmu_failure)
                        })
                        .collect();
                    let points = landscape_points.iter().zip(costs);
                    exp.landscape = Some((
                        t,
                        points
                            .map(|(x, objective)| Candidate {
                                x: x.clone(),
                                objective,
                            })
                            .collect(),
                    ));
                }
            }
            if let Some(e) = fmu_failure.into_inner() {
                return Err(e);
            }
            // Every method picks a feasible point (DSM and Nelder–Mead only ask feasible
            // ones, the grid holds only feasible ones, `initial` is validated); rounding
            // at a bound is the one way left to miss, and it is an error, not a panic.
            let taus = delays.taus(&live_x).ok_or_else(|| Error::Numerical {
                time: t,
                message: format!(
                    "the {} choice {live_x:?} [s] is outside the delay bounds or the budget",
                    spec.method.name()
                ),
            })?;
            let achieved = world
                .set_taus(t, &taus, &delays.achieved(&taus))
                .map_err(|e| crate::error::Error::Numerical {
                    time: t,
                    message: format!("the TDMA cycle cannot serve the decided delays: {e}"),
                })?;
            let run = world.advance_to(t_end, obs);
            let objective = match (&run, world.last_window()) {
                (Ok(()), Some((end, cost))) if end == t_end => delays.objective(cost, &achieved),
                _ => f64::INFINITY,
            };
            if let (Method::Dsm, Measure::Online, Some(d)) =
                (spec.method, spec.measure, dsm.as_mut())
            {
                d.tell(objective);
            }
            exp.windows.push(WindowReport {
                t_start: t,
                t_end,
                live: Candidate {
                    x: live_x,
                    objective,
                },
                baselines,
                grid_best,
                dsm_path,
            });
            run?;
            // The window's epochs.csv row is complete: its controller columns go to the
            // recorder (digest) only for a window the live world closed.
            if let Some(w) = exp.windows.last() {
                obs.on_window(w);
            }
            progress.tick(exp.windows.len() as u64);
            t = t_end;
            self.next = t;
            // Ctrl-C under `run`: stop at this window's end; the caller reports it.
            if crate::interrupt::requested() {
                break;
            }
        }
        progress.finish();
        Ok(())
    }
}

/// Up to `budget` Nelder–Mead measurements in this window (none once it has converged).
fn nelder_mead_window(n: &mut NelderMead, budget: usize, eval: &dyn Fn(&[f64]) -> f64) {
    for _ in 0..budget {
        let Some(x) = n.ask() else { break };
        n.tell(eval(&x));
    }
}

fn measured(x: &[f64], eval: &dyn Fn(&[f64]) -> f64) -> Candidate {
    Candidate {
        x: x.to_vec(),
        objective: eval(x),
    }
}

/// Names of the controlled coordinates (the channels' names, in order).
pub fn channel_names(channels: &[crate::scenario::model::ChannelSpec]) -> Vec<String> {
    channels.iter().map(|c| c.name.clone()).collect()
}

/// The controller spec of a scenario, if any (for writers).
pub fn spec(scenario: &Scenario) -> Option<&ControllerSpec> {
    scenario.controller.as_ref()
}
