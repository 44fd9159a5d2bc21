//! The speed–accuracy trade (`dsmcosim tradeoff`) and the stability map
//! (`dsmcosim stability-map`).
//!
//! **Work-precision study.** Starting from a scenario (the *base*), every accuracy knob
//! is turned one at a time ([`knobs`]): `dt`, integrator, `dt` under each other
//! integrator, the `J_s` solve, the stabilizer, the SMC gain, and on partitioned scenes
//! the ghost mode and the network. Every variant is an edit of the scenario's JSON, re-parsed and
//! validated like a user's file, so a variant the format refuses is recorded as
//! `invalid` with the validator's message, and one that diverges is recorded as
//! `diverged` with the divergence error — neither stops the study.
//!
//! ```text
//!   scenario.json ──(--duration)──▶ base ──edit per knob setting──▶ variants (validated)
//!        │                                                             │ run, sample p
//!        └──▶ reference: monolithic RK4, Cholesky, dt_ref = dt/20 ─────┤ compare every 8 dt
//!                                                                      ▼
//!     errors vs reference, max |w|, cost error; wall time, body-steps/s; Pareto front
//!        ──▶ tradeoff.csv, tradeoff.md, work_precision.svg, pareto.svg
//! ```
//!
//! The reference keeps the scenario's forces, bodies, links and stabilizer, drops the
//! partition (and its network and controller) and integrates with classical RK4 and
//! the exact solve at `dt_ref = dt/20`, which divides every `dt` of the sweep. Body
//! positions are compared at every multiple of the largest `dt` of the sweep (the
//! common time grid). The reference is run a second time at `dt_ref/2`; the distance
//! between the two is reported as the reference's own error, the floor below which the
//! study's errors mean nothing.
//!
//! Wall time is the fastest of `r` repetitions of the simulation alone (world building
//! excluded), `r` chosen so that the repetitions of a variant take about
//! [`measure::MIN_TIMED_SECONDS`] (at most [`measure::MAX_REPEATS`]), run round-robin
//! over the variants so that a change of machine load hits them alike: runs of a few
//! milliseconds are otherwise dominated by scheduler noise. Wall times are the only
//! non-deterministic numbers the study writes; the variants run one after the other,
//! never in parallel, so they do not compete for the cores they are timed on.
//!
//! **Stability map** ([`stability`]): the scenario over a grid of SMC `μ` × `dt`, each
//! cell classified as 0 (ran, `max |w| ≤ ε`), 1 (ran, `max |w| > ε`) or 2 (diverged).

pub mod knobs;
pub mod measure;
pub mod stability;
mod write;

use std::path::Path;

use serde_json::Value;

use crate::error::{Error, Result};
use crate::kernel::SimTime;
use crate::scenario::{parse_str, Scenario};

pub use knobs::{Knob, Setting, KNOBS};
pub use measure::{Measured, Status};
pub use stability::{stability_map, StabilityMap};

/// The reference step is the base `dt` divided by this (it must divide every `dt` of the
/// sweep: `dt/4 = 5 dt_ref`).
pub const REFERENCE_DIVISOR: u64 = 20;

/// One row of the study: a knob setting and what its run measured.
#[derive(Debug, Clone)]
pub struct Row {
    /// Knob name (`dt`, `integrator`, …).
    pub knob: &'static str,
    /// Setting label (`0.25 ms`, `rk4`, `cg 5`, …).
    pub setting: String,
    /// Whether this setting is the base scenario itself.
    pub is_base: bool,
    /// Index into [`Study::variants`].
    pub variant: usize,
}

/// A distinct variant that was run (several rows may share one).
#[derive(Debug, Clone)]
pub struct Variant {
    /// The validated scenario (`None` if the edit was refused).
    pub scenario: Option<Scenario>,
    /// What the run measured.
    pub measured: Measured,
    /// Max body-position error against the reference over the horizon [m].
    pub max_position_error: f64,
    /// RMS body-position error over all compared times and bodies [m].
    pub rms_position_error: f64,
    /// `|mean cost − reference mean cost|` [m].
    pub cost_error: f64,
    /// Max body-position distance from the base variant's run [m]: the knob's own
    /// effect, without the base's discretization error.
    pub base_distance: f64,
    /// On the Pareto front of (wall time, max position error).
    pub pareto: bool,
}

impl Variant {
    /// `dt` of the variant [s] (NaN if invalid).
    pub fn dt(&self) -> f64 {
        self.scenario
            .as_ref()
            .map_or(f64::NAN, |s| s.dt.as_secs_f64())
    }

    /// Body-steps per wall second (NaN unless the run finished).
    pub fn body_steps_per_second(&self) -> f64 {
        match (&self.scenario, &self.measured.status) {
            (Some(s), Status::Ok) => {
                (s.bodies.len() as f64 * s.steps as f64) / self.measured.wall_seconds
            }
            _ => f64::NAN,
        }
    }
}

/// The finished study.
#[derive(Debug, Clone)]
pub struct Study {
    /// Scenario name.
    pub name: String,
    /// Horizon [s].
    pub horizon: SimTime,
    /// Common comparison period [s] (the largest `dt` of the sweep).
    pub compare_every: SimTime,
    /// Reference step.
    pub reference_dt: SimTime,
    /// The reference run.
    pub reference: Measured,
    /// Max distance between the reference and the reference at half its step [m].
    pub reference_error: f64,
    /// Body count.
    pub bodies: usize,
    /// Distinct variants.
    pub variants: Vec<Variant>,
    /// Rows in knob order.
    pub rows: Vec<Row>,
    /// Notes for the report (horizon rounding, skipped knobs).
    pub notes: Vec<String>,
}

/// Options of the study.
#[derive(Debug, Clone, Copy, Default)]
pub struct Options {
    /// Horizon [s]; `None` = the scenario's duration.
    pub duration: Option<f64>,
}

/// Reads a scenario file: the raw JSON (to edit) and the validated base.
pub fn load_json(path: &Path, sets: &[String]) -> Result<(Value, Scenario)> {
    let (scenario, text) = crate::scenario::load_with(path, sets)?;
    let mut json: Value = serde_json::from_str(&text)
        .map_err(|e| Error::invalid(path.display().to_string(), format!("not JSON: {e}")))?;
    crate::scenario::anchor_fmu_paths(&mut json, path);
    Ok((json, scenario))
}

/// Sets the horizon of `json` to `duration` [s] (capping an explicit measurement period
/// at it) and validates the result; `flag` names the option in errors.
pub fn with_horizon(json: &Value, duration: f64, flag: &str) -> Result<(Value, Scenario)> {
    if !(duration.is_finite() && duration > 0.0) {
        return Err(Error::invalid(
            flag,
            format!(
                "must be a positive number of seconds (got {})",
                crate::error::num(duration)
            ),
        ));
    }
    let mut v = json.clone();
    v["duration"] = Value::from(duration);
    if let Some(p) = v.pointer_mut("/measurement/period") {
        if p.as_f64().is_some_and(|p| p > duration) {
            *p = Value::from(duration);
        }
    }
    let s = parse_str(&v.to_string(), flag).map_err(|e| Error::invalid(flag, e.to_string()))?;
    Ok((v, s))
}

/// Runs the work-precision study of the scenario file `path` (with the `--set`
/// overrides `sets` applied) and writes its outputs into `out`.
pub fn tradeoff(path: &Path, sets: &[String], out: &Path, options: Options) -> Result<Study> {
    crate::output::refuse_foreign_outputs(out, "tradeoff.csv", |n| {
        matches!(n, "tradeoff.md" | "work_precision.svg" | "pareto.svg")
    })?;
    let (json, scenario) = load_json(path, sets)?;
    let study = study(&json, &scenario, options)?;
    write::write_study(out, &study)?;
    Ok(study)
}

/// `dsmcosim tradeoff`: runs the study, writes it, prints a one-line summary.
pub fn command_tradeoff(
    path: &Path,
    sets: &[String],
    out: &Path,
    duration: Option<f64>,
) -> Result<()> {
    let study = tradeoff(path, sets, out, Options { duration })?;
    let count = |f: &dyn Fn(&Status) -> bool| {
        study
            .variants
            .iter()
            .filter(|v| f(&v.measured.status))
            .count()
    };
    crate::console::say(format_args!(
        "{}: {} variants over {} s ({} ok, {} diverged, {} invalid), reference error {:.2e} m",
        study.name,
        study.variants.len(),
        study.horizon.as_secs_f64(),
        count(&|s| *s == Status::Ok),
        count(&|s| matches!(s, Status::Diverged(_))),
        count(&|s| matches!(s, Status::Invalid(_))),
        study.reference_error
    ));
    crate::console::say(format_args!("wrote {}", out.display()));
    Ok(())
}

/// `dsmcosim stability-map`: runs the map, writes it, prints a one-line summary.
pub fn command_stability_map(
    path: &Path,
    sets: &[String],
    out: &Path,
    duration: Option<f64>,
) -> Result<()> {
    let map = stability_map(path, sets, out, duration)?;
    let count = |o: u8| map.cells.iter().filter(|c| c.outcome == Some(o)).count();
    crate::console::say(format_args!(
        "{}: {} cells over {} s: {} within ε, {} beyond ε, {} diverged",
        map.name,
        map.cells.len(),
        map.horizon.as_secs_f64(),
        count(0),
        count(1),
        count(2)
    ));
    crate::console::say(format_args!("wrote {}", out.display()));
    Ok(())
}

/// Runs the study on an already loaded scenario (`json` must be the file `scenario`
/// was validated from).
pub fn study(json: &Value, scenario: &Scenario, options: Options) -> Result<Study> {
    let base_dt = scenario.dt.as_nanos();
    if !base_dt.is_multiple_of(REFERENCE_DIVISOR * 2) {
        return Err(Error::invalid(
            "dt",
            format!(
                "the tradeoff study needs dt to be a multiple of {} ns (got {})",
                REFERENCE_DIVISOR * 2,
                scenario.dt
            ),
        ));
    }
    let mut notes = Vec::new();
    // The common time grid: every multiple of the largest dt of the sweep, and the
    // horizon a whole number of it (so every variant's duration is whole steps).
    let largest = knobs::DT_FACTORS
        .iter()
        .map(|&(n, d)| base_dt * n / d)
        .max()
        .unwrap_or(base_dt);
    let compare_every = SimTime(largest);
    let wanted = options.duration.map_or(scenario.duration, |d| {
        SimTime::from_secs_f64(d).unwrap_or(SimTime::ZERO)
    });
    let horizon = SimTime(wanted.as_nanos() / largest * largest);
    if horizon == SimTime::ZERO {
        return Err(Error::invalid(
            "--duration",
            format!("must be at least the largest dt of the sweep ({compare_every})"),
        ));
    }
    if horizon != wanted {
        notes.push(format!(
            "horizon {} rounded down to {} (a whole number of the largest dt, {})",
            wanted, horizon, compare_every
        ));
    }
    let (base_json, base) = with_horizon(json, horizon.as_secs_f64(), "--duration")?;

    // The variants, validated and de-duplicated.
    let mut variants: Vec<(Option<Scenario>, Option<String>)> = Vec::new();
    let mut rows = Vec::new();
    for knob in KNOBS {
        if !(knob.applies)(&base) {
            notes.push(format!(
                "knob `{}` skipped (applies when {})",
                knob.name, knob.when
            ));
            continue;
        }
        for setting in (knob.settings)(&base) {
            let v = setting.apply(&base_json);
            let parsed = parse_str(&v.to_string(), "variant");
            let index = match &parsed {
                Ok(s) => variants
                    .iter()
                    .position(|(o, _)| o.as_ref() == Some(s))
                    .unwrap_or_else(|| {
                        variants.push((Some(s.clone()), None));
                        variants.len() - 1
                    }),
                Err(e) => {
                    variants.push((None, Some(e.to_string())));
                    variants.len() - 1
                }
            };
            rows.push(Row {
                knob: knob.name,
                setting: setting.label,
                is_base: parsed.as_ref().is_ok_and(|s| *s == base),
                variant: index,
            });
        }
    }

    let reference_dt = SimTime(base_dt / REFERENCE_DIVISOR);
    let reference_scenario = knobs::reference(&base_json, reference_dt)?;
    let half_scenario = knobs::reference(&base_json, SimTime(reference_dt.as_nanos() / 2))?;
    let total: u64 = variants
        .iter()
        .filter_map(|(s, _)| s.as_ref().map(|s| s.steps.saturating_add(1)))
        .fold(0u64, u64::saturating_add)
        .saturating_add(reference_scenario.steps)
        .saturating_add(half_scenario.steps)
        .saturating_add(2);
    crate::run::budget::check_study_steps(total, "--duration")?;
    let mut progress = measure::Counter::new(total);
    let reference = measure::measure(&reference_scenario, compare_every, &mut progress);
    let half = measure::measure(&half_scenario, compare_every, &mut progress);
    for (r, what) in [(&reference, "reference"), (&half, "reference at dt_ref/2")] {
        if let (Status::Diverged(e), Some(time)) = (&r.status, r.failed_at) {
            return Err(Error::Numerical {
                time,
                message: format!(
                    "the {what} run (monolithic RK4) failed, nothing to compare against: {e}"
                ),
            });
        }
    }
    let reference_error = measure::position_errors(&half, &reference).0;

    let mut measured: Vec<Measured> = variants
        .iter()
        .map(|(scenario, invalid)| match scenario {
            Some(s) => measure::measure(s, compare_every, &mut progress),
            None => Measured::invalid(invalid.clone().unwrap_or_default()),
        })
        .collect();
    progress.finish();
    {
        let mut timed: Vec<(&Scenario, &mut Measured)> = variants
            .iter()
            .zip(measured.iter_mut())
            .filter_map(|((s, _), m)| s.as_ref().map(|s| (s, m)))
            .collect();
        measure::refine_timings(&mut timed);
    }
    let base_index = variants.iter().position(|(s, _)| s.as_ref() == Some(&base));
    let base_run = base_index.map(|i| measured[i].clone());
    let mut done = Vec::with_capacity(variants.len());
    for ((scenario, _), measured) in variants.into_iter().zip(measured) {
        let ok = measured.status == Status::Ok;
        let (max_e, rms_e) = if ok {
            measure::position_errors(&measured, &reference)
        } else {
            (f64::NAN, f64::NAN)
        };
        let cost_error = if ok {
            (measured.mean_cost - reference.mean_cost).abs()
        } else {
            f64::NAN
        };
        let base_distance = match (&base_run, ok) {
            (Some(b), true) if b.status == Status::Ok => measure::position_errors(&measured, b).0,
            _ => f64::NAN,
        };
        done.push(Variant {
            scenario,
            measured,
            max_position_error: max_e,
            rms_position_error: rms_e,
            cost_error,
            base_distance,
            pareto: false,
        });
    }
    let points: Vec<(f64, f64)> = done
        .iter()
        .map(|v| match v.measured.status {
            Status::Ok => (v.measured.wall_seconds, v.max_position_error),
            _ => (f64::NAN, f64::NAN),
        })
        .collect();
    for (v, on) in done.iter_mut().zip(pareto_front(&points)) {
        v.pareto = on;
    }
    Ok(Study {
        name: base.name.clone(),
        horizon,
        compare_every,
        reference_dt,
        reference,
        reference_error,
        bodies: base.bodies.len(),
        variants: done,
        rows,
        notes,
    })
}

/// Which of `points` (cost, error) are on the Pareto front: finite, and no other
/// finite point is at most as costly and at most as wrong while strictly better in one.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    points
        .iter()
        .map(|p| {
            finite(p)
                && !points
                    .iter()
                    .any(|q| finite(q) && q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn study_records_every_knob_and_diverged_variants_as_rows() {
        // μ = 1.5 ms: explicit Euler holds for dt < 2μ = 3 ms, so the 4 and 8 ms
        // variants of the sweep must diverge — and be rows, not a failed study.
        let v = json!({
            "name": "db", "seed": 1, "duration": 0.4, "dt": 0.001,
            "stabilizer": {"kind": "smc", "mu": 0.0015},
            "model": {
                "bodies": [
                    {"id": 1, "mass": 1.0, "size": 0.2, "position": [0.9, 0, 0], "velocity": [0, 3, 0]},
                    {"id": 2, "mass": 1.0, "size": 0.2, "position": [-0.9, 0, 0], "velocity": [0, -3, 0]}
                ],
                "links": [{"a": 1, "b": 2}]
            },
            "forces": [{"body": 1, "amplitude": [0, 0, 1], "omega": 3.0}]
        });
        let s = parse_str(&v.to_string(), "test").unwrap();
        let study = study(&v, &s, Options { duration: None }).unwrap();
        assert!(study.reference_error < 1e-9, "{}", study.reference_error);
        let row = |knob: &str, setting: &str| {
            let r = study
                .rows
                .iter()
                .find(|r| r.knob == knob && r.setting == setting)
                .unwrap_or_else(|| panic!("no row {knob} {setting}"));
            &study.variants[r.variant]
        };
        for dt in ["4 ms", "8 ms"] {
            let v = row("dt", dt);
            assert!(
                matches!(v.measured.status, Status::Diverged(_)),
                "dt {dt}: {:?}",
                v.measured.status
            );
            assert!(v.max_position_error.is_nan() && !v.pareto);
        }
        let (euler, rk4) = (row("integrator", "euler"), row("integrator", "rk4"));
        assert_eq!(euler.measured.status, Status::Ok);
        assert!(rk4.max_position_error < euler.max_position_error / 100.0);
        assert!(study
            .rows
            .iter()
            .any(|r| r.is_base && r.knob == "dt" && r.setting == "1 ms"));
        assert!(study.notes.iter().any(|n| n.contains("ghosts")));
        let dir = std::env::temp_dir().join(format!("dsmcosim-tradeoff-{}", std::process::id()));
        write::write_study(&dir, &study).unwrap();
        let csv = std::fs::read_to_string(dir.join("tradeoff.csv")).unwrap();
        assert_eq!(csv.lines().count(), study.rows.len() + 1);
        assert!(csv.contains(",diverged,\"diverged at t = "));
        for f in ["tradeoff.md", "work_precision.svg", "pareto.svg"] {
            assert!(dir.join(f).is_file(), "{f}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn pareto_front_keeps_only_undominated_finite_points() {
        let pts = [
            (1.0, 10.0),
            (2.0, 5.0),
            (3.0, 5.0),
            (2.5, 1.0),
            (f64::NAN, 0.1),
            (0.5, f64::NAN),
            (1.0, 10.0),
        ];
        assert_eq!(
            pareto_front(&pts),
            vec![true, true, false, true, false, false, true]
        );
    }
}
