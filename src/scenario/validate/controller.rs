//! The controller stage: `controller` checked against the channels it drives.

use std::collections::BTreeSet;

use super::checks::{foreign, num, positive, required, time};
use crate::error::{Error, Result};
use crate::kernel::SimTime;
use crate::scenario::file::{ControllerFile, MeasureFile, MethodFile, ProblemKind, RampFile};
use crate::scenario::model::{ChannelSpec, ControllerSpec, Measure, Method, Problem, Ramp};

/// Most points a grid search may measure in one window (the grid baseline or method over
/// the controlled delays, and the surface window's landscape over both delays of a
/// two-channel constrained problem); each point is a fork of the whole co-simulation
/// run over the window.
pub const MAX_GRID_POINTS: f64 = 40_000.0;

/// Most reflections per DSM iteration (`m_r`; the thesis uses 5): each one is measured
/// on a fork run over a whole window.
pub const MAX_REFLECTIONS: usize = 1_000;

fn method(m: MethodFile) -> Method {
    match m {
        MethodFile::Dsm => Method::Dsm,
        MethodFile::Grid => Method::Grid,
        MethodFile::NoOpt => Method::NoOptimization,
        MethodFile::Fixed => Method::Fixed,
        MethodFile::NelderMead => Method::NelderMead,
    }
}

/// A force's `ramp`.
pub(super) fn ramp(path: &str, r: &RampFile) -> Result<Ramp> {
    let t0 = time(&format!("{path}.t0"), r.t0)?;
    let t1 = time(&format!("{path}.t1"), r.t1)?;
    if t1 <= t0 {
        return Err(Error::invalid(
            format!("{path}.t1"),
            format!(
                "must be after t0 (got t1 {} s ≤ t0 {} s)",
                num(r.t1),
                num(r.t0)
            ),
        ));
    }
    for (key, v) in [("a0", r.a0), ("a1", r.a1)] {
        super::checks::magnitude(&format!("{path}.{key}"), v)?;
    }
    Ok(Ramp {
        t0,
        t1,
        a0: r.a0,
        a1: r.a1,
    })
}

/// The `controller` section, given the validated channels, `dt`, duration and period.
pub(super) fn controller(
    c: &ControllerFile,
    channels: &[ChannelSpec],
    dt: SimTime,
    duration: SimTime,
    period: SimTime,
) -> Result<ControllerSpec> {
    let n = channels.len();
    let problem = match c.problem {
        ProblemKind::Cp => {
            if c.penalty.is_some() {
                return Err(foreign("controller.penalty", "cp"));
            }
            let budget = c
                .budget
                .ok_or_else(|| required("controller.budget", "cp"))?;
            if n < 2 {
                return Err(Error::invalid(
                    "controller.problem",
                    format!("cp controls n − 1 delays and needs at least 2 channels (got {n})"),
                ));
            }
            Problem::Constrained {
                budget: positive("controller.budget", budget)?,
            }
        }
        ProblemKind::Up => {
            if c.budget.is_some() {
                return Err(foreign("controller.budget", "up"));
            }
            let penalty = c
                .penalty
                .ok_or_else(|| required("controller.penalty", "up"))?;
            if !(penalty.is_finite() && penalty >= 0.0) {
                return Err(Error::invalid(
                    "controller.penalty",
                    format!("must be ≥ 0 (got {})", num(penalty)),
                ));
            }
            // Within the magnitude range, penalty × bandwidth (≤ 1e100 × 1e109 per
            // channel) stays finite: at 1e308 every objective was infinite and the DSM
            // drove every delay to tau_min.
            super::checks::magnitude("controller.penalty", penalty)?;
            if n < 1 {
                return Err(Error::invalid(
                    "controller",
                    "needs channels to control (the scenario has none)",
                ));
            }
            Problem::Unconstrained { penalty }
        }
    };
    let dt_s = dt.as_secs_f64();
    let tau_min = positive("controller.tau_min", c.tau_min.unwrap_or(dt_s))?;
    if tau_min < dt_s {
        return Err(Error::invalid(
            "controller.tau_min",
            format!("must be ≥ dt = {} s (got {})", num(dt_s), num(tau_min)),
        ));
    }
    let tau_max = positive("controller.tau_max", c.tau_max)?;
    if tau_max <= tau_min {
        return Err(Error::invalid(
            "controller.tau_max",
            format!(
                "must exceed tau_min {} s (got {})",
                num(tau_min),
                num(tau_max)
            ),
        ));
    }
    let controlled = match problem {
        Problem::Constrained { .. } => n - 1,
        Problem::Unconstrained { .. } => n,
    };
    // The default start is the no-optimization point: for CP every controlled delay at
    // the equal share of the budget (so the DSM's first simplex is centred on it), for
    // UP the channels' own delays.
    let initial = match (
        &c.initial,
        problem.equal_share(channels.iter().map(|ch| ch.k)),
    ) {
        (Some(v), _) => v.clone(),
        (None, Some(tau)) => vec![tau.clamp(tau_min, tau_max); controlled],
        (None, None) => channels[..controlled]
            .iter()
            .map(|ch| ch.tau.as_secs_f64())
            .collect(),
    };
    if initial.len() != controlled {
        return Err(Error::invalid(
            "controller.initial",
            format!(
                "needs {controlled} values (one per controlled channel) (got {})",
                initial.len()
            ),
        ));
    }
    for (i, &x) in initial.iter().enumerate() {
        if !(x.is_finite() && x >= tau_min && x <= tau_max) {
            return Err(Error::invalid(
                format!("controller.initial[{i}]"),
                format!(
                    "must lie in [tau_min, tau_max] = [{}, {}] s (got {})",
                    num(tau_min),
                    num(tau_max),
                    num(x)
                ),
            ));
        }
    }
    if let Problem::Constrained { budget } = problem {
        let used: f64 = initial.iter().zip(channels).map(|(x, ch)| ch.k / x).sum();
        let last = &channels[n - 1];
        let left = budget - used;
        let slowest: f64 = channels.iter().map(|ch| ch.k / tau_max).sum();
        if c.initial.is_none() && budget < slowest {
            return Err(Error::invalid(
                "controller.budget",
                format!(
                    "cannot be met: even every channel at tau_max {} s uses {} /s (got {})",
                    num(tau_max),
                    num(slowest),
                    num(budget)
                ),
            ));
        }
        if !(left > 0.0 && last.k / left <= tau_max) {
            return Err(Error::invalid(
                "controller.initial",
                format!(
                    "infeasible: the controlled channels use {} of the budget {} /s, leaving \
                     the last channel a delay above tau_max {} s",
                    num(used),
                    num(budget),
                    num(tau_max)
                ),
            ));
        }
    }
    let dsm_size = positive("controller.dsm.size", c.dsm.size)?;
    if c.dsm.reflections == 0 || c.dsm.reflections > MAX_REFLECTIONS {
        return Err(Error::invalid(
            "controller.dsm.reflections",
            format!(
                "must be from 1 to {MAX_REFLECTIONS} (got {}; each reflection is a fork run \
                 over a whole window)",
                c.dsm.reflections
            ),
        ));
    }
    let live = method(c.method);
    let mut seen = BTreeSet::new();
    let mut baselines = Vec::new();
    for (i, &b) in c.baselines.iter().enumerate() {
        let m = method(b);
        if m == live {
            return Err(Error::invalid(
                format!("controller.baselines[{i}]"),
                format!("\"{}\" is the live method already", m.name()),
            ));
        }
        if !seen.insert(m) {
            return Err(Error::invalid(
                format!("controller.baselines[{i}]"),
                format!("\"{}\" is listed twice", m.name()),
            ));
        }
        baselines.push(m);
    }
    let dsm_delta = match c.dsm_delta {
        None => None,
        Some(d) => {
            if live != Method::Dsm {
                return Err(Error::invalid(
                    "controller.dsm_delta",
                    "needs \"method\": \"dsm\"",
                ));
            }
            let d = positive("controller.dsm_delta", d)?;
            // DSM ± δ must be able to stay in [tau_min, tau_max] for one sign at least;
            // from the box's width on, both leave it and their columns are always NaN.
            if d >= tau_max - tau_min {
                return Err(Error::invalid(
                    "controller.dsm_delta",
                    format!(
                        "must be below tau_max − tau_min = {} s, the width of the delay box \
                         (got {} s; DSM ± δ would always leave the box)",
                        num(tau_max - tau_min),
                        num(d)
                    ),
                ));
            }
            Some(d)
        }
    };
    let grid_step = positive("controller.grid_step", c.grid_step)?;
    let surface_window = match c.surface_window {
        None => None,
        Some(s) => {
            let t = time("controller.surface_window", s)?;
            if t >= duration || t.0 % period.0 != 0 {
                return Err(Error::invalid(
                    "controller.surface_window",
                    format!(
                        "must be the start of a measurement window before the end (got {} s; \
                         windows start every {} s)",
                        num(s),
                        num(period.as_secs_f64())
                    ),
                ));
            }
            Some(t)
        }
    };
    let landscape_possible = matches!(problem, Problem::Constrained { .. }) && n == 2;
    if c.landscape && !(landscape_possible && surface_window.is_some()) {
        return Err(Error::invalid(
            "controller.landscape",
            "needs a constrained problem over two channels and a surface_window",
        ));
    }
    let wants_grid = live == Method::Grid || baselines.contains(&Method::Grid);
    if wants_grid || surface_window.is_some() {
        let count = ((tau_max - tau_min) / grid_step + 1e-9).floor() + 1.0;
        let controlled = match problem {
            Problem::Constrained { .. } => n - 1,
            Problem::Unconstrained { .. } => n,
        };
        let dims = if c.landscape { 2 } else { controlled };
        let points = count.powi(dims as i32);
        if points > MAX_GRID_POINTS {
            return Err(Error::invalid(
                "controller.grid_step",
                format!(
                    "gives {} grid values per delay over [tau_min, tau_max], {} points over \
                     {dims} delays; at most {} points per window are measured (raise \
                     grid_step or narrow the bounds)",
                    num(count),
                    num(points),
                    num(MAX_GRID_POINTS)
                ),
            ));
        }
    }
    Ok(ControllerSpec {
        method: live,
        problem,
        measure: match c.measure {
            MeasureFile::Lookahead => Measure::Lookahead,
            MeasureFile::Online => Measure::Online,
        },
        tau_min,
        tau_max,
        initial,
        dsm_size,
        reflections: c.dsm.reflections,
        baselines,
        dsm_delta,
        grid_step,
        surface_window,
        landscape: c.landscape,
    })
}
