//! What a run's summary.json says about its invariants and its SMC boundary layer:
//! accumulated by the recorder step by step (and checkpointed with it, so a resumed run
//! reports the same), reported as `invariants` and `boundary_layer`.
//!
//! - [`InvariantLog`]: the net's [`Invariants`] at the first step, at the last trace row
//!   and at both ends of every undriven stretch, and their drift between those.
//! - [`LayerWatch`]: the steps at which some link's `|w|` is outside the SMC boundary
//!   layer `ε`, and the worst `|w|`.

use nalgebra::Vector3;
use serde_json::{json, Map, Value};

use super::Invariants;
use crate::kernel::SimTime;
use crate::scenario::model::{Scenario, Stabilizer};

/// The invariants at one step.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sample {
    /// Time of the step.
    pub t: SimTime,
    /// The invariants there.
    pub at: Invariants,
}

/// An undriven stretch: its first and last step, and the invariants there once reached.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
struct Stretch {
    from: u64,
    to: u64,
    start: Option<Sample>,
    end: Option<Sample>,
}

/// The steps `(from, to)` of every undriven stretch of `scenario`: the maximal time
/// intervals in which no scenario force is active (each force is active on
/// `[from, until)`), cut to the steps over which the net is free whatever the
/// integrator evaluates inside a step (RK4 evaluates the forces at `t_k`,
/// `t_k + dt/2` and `t_k+1`): from the first step at or after the interval's start to
/// the last step before the next force switches on (or the run's last step), so that
/// every step between them runs with no force at all. Stretches with fewer than one
/// step are left out.
pub fn undriven_stretches(scenario: &Scenario) -> Vec<(u64, u64)> {
    // Gravity drives the net all the time, and so may a force a connection sets.
    let connected_force = scenario
        .connections
        .iter()
        .any(|c| matches!(c.to, crate::scenario::model::SignalSink::BodyForce { .. }));
    if scenario.gravity.is_some() || connected_force {
        return Vec::new();
    }
    let (dt, end) = (scenario.dt.0, scenario.duration.0);
    // Active intervals [from, until) in ns, sorted by start, empty ones dropped.
    let mut active: Vec<(u64, u64)> = scenario
        .forces
        .iter()
        .map(|f| (f.from.0, f.until.map_or(u64::MAX, |u| u.0)))
        .filter(|(a, b)| a < b)
        .collect();
    active.sort_unstable();
    let mut free = Vec::new();
    let mut at = 0; // no force is active on [at, next start)
    for (a, b) in active {
        if a > at {
            free.push((at, Some(a)));
        }
        at = at.max(b);
    }
    if at <= end {
        free.push((at, None));
    }
    free.into_iter()
        .filter_map(|(a, b)| {
            let first = a.div_ceil(dt);
            let last = match b {
                // The last step strictly before `b`.
                Some(b) => b.div_ceil(dt).checked_sub(1)?.min(scenario.steps),
                None => scenario.steps,
            };
            (last > first).then_some((first, last))
        })
        .collect()
}

/// The net's invariants at the steps summary.json reports them, and their drift.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InvariantLog {
    /// At the first step recorded (t = 0).
    start: Option<Sample>,
    /// At the last trace row (the run's last step; on a diverged run the last row
    /// written before it diverged).
    end: Option<Sample>,
    stretches: Vec<Stretch>,
}

impl InvariantLog {
    /// A log that also follows the undriven stretches `stretches` (steps, from
    /// [`undriven_stretches`]).
    pub fn new(stretches: &[(u64, u64)]) -> InvariantLog {
        InvariantLog {
            start: None,
            end: None,
            stretches: stretches
                .iter()
                .map(|&(from, to)| Stretch {
                    from,
                    to,
                    start: None,
                    end: None,
                })
                .collect(),
        }
    }

    /// Whether step `step` needs its invariants even if the trace does not keep it: the
    /// first step, and either end of an undriven stretch.
    #[inline]
    pub fn wants(&self, step: u64) -> bool {
        self.start.is_none()
            || self
                .stretches
                .iter()
                .any(|s| s.from == step || s.to == step)
    }

    /// Records the invariants `at` of step `step` at `t`; `row`: the trace keeps it.
    pub fn record(&mut self, step: u64, t: SimTime, at: Invariants, row: bool) {
        let sample = Sample { t, at };
        if self.start.is_none() {
            self.start = Some(sample);
        }
        if row {
            self.end = Some(sample);
        }
        for s in &mut self.stretches {
            if s.from == step {
                s.start = Some(sample);
            }
            if s.to == step {
                s.end = Some(sample);
            }
        }
    }

    /// summary.json's `invariants`: the values at the start and the end of the run, the
    /// drift between them, and (where the scenario has any that the run completed) the
    /// drift over each undriven stretch. `None` before any step was recorded.
    pub fn summary(&self) -> Option<Value> {
        let (start, end) = (self.start?, self.end?);
        let mut out = Map::new();
        out.insert("start".into(), sample_json(&start));
        out.insert("end".into(), sample_json(&end));
        out.extend(drift_json(&start.at, &end.at));
        let undriven: Vec<Value> = self
            .stretches
            .iter()
            .filter_map(|s| {
                let (a, b) = (s.start?, s.end?);
                let mut o = Map::new();
                o.insert("from".into(), json!(a.t.as_secs_f64()));
                o.insert("to".into(), json!(b.t.as_secs_f64()));
                o.extend(drift_json(&a.at, &b.at));
                Some(Value::Object(o))
            })
            .collect();
        if !undriven.is_empty() {
            out.insert("undriven".into(), Value::Array(undriven));
        }
        Some(Value::Object(out))
    }
}

fn vector(v: &Vector3<f64>) -> Value {
    json!([v.x, v.y, v.z])
}

fn sample_json(s: &Sample) -> Value {
    json!({
        "t": s.t.as_secs_f64(),
        "momentum": vector(&s.at.momentum),
        "angular_momentum": vector(&s.at.angular_momentum),
        "kinetic_energy": s.at.kinetic_energy,
    })
}

/// A net momentum smaller than this share of its gross scale (`Σ m|v|`, or the same
/// sum of moments for `L`) is taken for zero: the bodies' momenta cancel, and what is
/// left is round-off (1e-15 of the gross scale per body), not a value to divide by.
pub const NIL_SHARE: f64 = 1e-9;

/// `|d| / |from|`, or `None` (JSON null) where `from` is zero, or (for momenta, with
/// their `gross` scale) nil against it: a monolithic net started at rest had a
/// momentum of 1e-14 kg·m/s and reported a relative drift of 1.3e13.
fn relative(d: f64, from: f64, gross: Option<f64>) -> Option<f64> {
    let nil = gross.map_or(0.0, |g| NIL_SHARE * g);
    (from.abs() > nil).then(|| d / from)
}

/// The drift fields from `a` to `b`: each quantity's signed change, and its size
/// relative to the value at `a` (the norms for the vectors, signed for the energy).
fn drift_json(a: &Invariants, b: &Invariants) -> Map<String, Value> {
    let dp = b.momentum - a.momentum;
    let dl = b.angular_momentum - a.angular_momentum;
    let de = b.kinetic_energy - a.kinetic_energy;
    let mut m = Map::new();
    m.insert("momentum_drift".into(), vector(&dp));
    m.insert(
        "momentum_drift_relative".into(),
        json!(relative(
            dp.norm(),
            a.momentum.norm(),
            Some(a.gross_momentum)
        )),
    );
    m.insert("angular_momentum_drift".into(), vector(&dl));
    m.insert(
        "angular_momentum_drift_relative".into(),
        json!(relative(
            dl.norm(),
            a.angular_momentum.norm(),
            Some(a.gross_angular_momentum)
        )),
    );
    m.insert("kinetic_energy_drift".into(), json!(de));
    m.insert(
        "kinetic_energy_drift_relative".into(),
        json!(relative(de, a.kinetic_energy, None)),
    );
    m
}

/// Steps at which the largest `|w|` is outside the SMC boundary layer `ε`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LayerWatch {
    /// `stabilizer.epsilon` [m].
    pub epsilon: f64,
    /// Steps recorded.
    pub steps: u64,
    /// Steps at which some link had `|w| > ε`.
    pub outside: u64,
    /// Largest `|w|` at any recorded step [m].
    pub worst: f64,
    /// Time of the first step with that `|w|`.
    pub worst_time: Option<SimTime>,
}

impl LayerWatch {
    /// A watch of `scenario`'s boundary layer; `None` unless its stabilizer is SMC.
    pub fn new(scenario: &Scenario) -> Option<LayerWatch> {
        match scenario.stabilizer {
            Stabilizer::Smc { epsilon, .. } => Some(LayerWatch {
                epsilon,
                steps: 0,
                outside: 0,
                worst: 0.0,
                worst_time: None,
            }),
            Stabilizer::Baumgarte { .. } => None,
        }
    }

    /// Counts a step at `t` whose largest `|w|` is `max_w` [m].
    #[inline]
    pub fn record(&mut self, t: SimTime, max_w: f64) {
        self.steps += 1;
        if max_w > self.epsilon {
            self.outside += 1;
        }
        if max_w > self.worst || self.worst_time.is_none() {
            self.worst = max_w;
            self.worst_time = Some(t);
        }
    }

    /// Share of the recorded steps outside the layer [1].
    pub fn share_outside(&self) -> f64 {
        self.outside as f64 / self.steps.max(1) as f64
    }

    /// summary.json's `boundary_layer`.
    pub fn summary(&self) -> Value {
        json!({
            "epsilon": self.epsilon,
            "steps_outside": self.outside,
            "share_outside": self.share_outside(),
            "worst": self.worst,
            "worst_time": self.worst_time.map(SimTime::as_secs_f64),
        })
    }

    /// The line the command line prints when the run left the layer; `None` if it
    /// never did.
    pub fn warning(&self) -> Option<String> {
        (self.outside > 0).then(|| {
            format!(
                "max |w| left the SMC boundary layer ε = {} m on {} of {} steps ({:.3} %); \
                 worst |w| = {:.3e} m at t = {} s (summary.json: boundary_layer). The \
                 law's bounds hold inside the layer; RK4, a larger K or a smaller μ keeps a \
                 run there (docs/accuracy.md: choosing speed or accuracy)",
                self.epsilon,
                self.outside,
                self.steps,
                100.0 * self.share_outside(),
                self.worst,
                self.worst_time.map_or(0.0, SimTime::as_secs_f64),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(forces: Value, duration: f64) -> Scenario {
        let v = json!({
            "name": "s", "seed": 1, "duration": duration, "dt": 0.001,
            "model": {"grid": {"rows": 1, "cols": 2, "spacing": 1.0, "mass": 1.0, "size": 0.2}},
            "forces": forces
        });
        crate::scenario::parse_str(&v.to_string(), "<test>").unwrap()
    }

    fn force(from: f64, until: Option<f64>) -> Value {
        let mut f = json!({"body": 1, "amplitude": [0, 0, 1], "omega": 2.0, "from": from});
        if let Some(u) = until {
            f["until"] = json!(u);
        }
        f
    }

    fn invariants(p: [f64; 3], gross: f64, ke: f64) -> Invariants {
        Invariants {
            momentum: Vector3::from(p),
            angular_momentum: Vector3::from(p),
            kinetic_energy: ke,
            gross_momentum: gross,
            gross_angular_momentum: gross,
        }
    }

    /// Bodies whose momenta cancel (a net at rest as a whole) leave a round-off net
    /// momentum: its relative drift is null, not 1e13; a real net momentum, however
    /// small against the gross scale but above round-off, still gets one.
    #[test]
    fn a_relative_drift_is_null_from_a_momentum_that_is_round_off() {
        let d = drift_json(
            &invariants([1e-14, 0.0, 0.0], 50.0, 10.0),
            &invariants([0.13, 0.0, 0.0], 50.0, 11.0),
        );
        assert_eq!(d["momentum_drift_relative"], Value::Null);
        assert_eq!(d["angular_momentum_drift_relative"], Value::Null);
        assert_eq!(d["kinetic_energy_drift_relative"], json!(0.1));
        let d = drift_json(
            &invariants([1e-6, 0.0, 0.0], 50.0, 10.0),
            &invariants([2e-6, 0.0, 0.0], 50.0, 10.0),
        );
        assert_eq!(d["momentum_drift_relative"], json!(1.0));
        // Nothing moving at all: null, as before.
        let d = drift_json(
            &invariants([0.0; 3], 0.0, 0.0),
            &invariants([1.0, 0.0, 0.0], 1.0, 0.5),
        );
        assert_eq!(d["momentum_drift_relative"], Value::Null);
        assert_eq!(d["kinetic_energy_drift_relative"], Value::Null);
    }

    /// The thesis load: [0, 12) and [12, 24) leave [24, 30] free, steps 24000..=30000.
    #[test]
    fn the_thesis_load_leaves_its_last_six_seconds_undriven() {
        let s = scene(
            json!([force(0.0, Some(12.0)), force(12.0, Some(24.0))]),
            30.0,
        );
        assert_eq!(undriven_stretches(&s), vec![(24_000, 30_000)]);
    }

    /// Gaps between forces, overlapping forces, a force never switched off, and a gap
    /// shorter than a step.
    #[test]
    fn stretches_are_the_gaps_between_forces_cut_to_whole_free_steps() {
        let s = scene(json!([]), 1.0);
        assert_eq!(undriven_stretches(&s), vec![(0, 1000)]);
        // Free [0, 0.2), [0.5, 0.6) (overlap of the two others), [0.9, 1].
        let s = scene(
            json!([
                force(0.2, Some(0.4)),
                force(0.3, Some(0.5)),
                force(0.6, Some(0.9))
            ]),
            1.0,
        );
        assert_eq!(
            undriven_stretches(&s),
            vec![(0, 199), (500, 599), (900, 1000)]
        );
        // Switched on at 0.5 and never off: only [0, 0.5).
        let s = scene(json!([force(0.5, None)]), 1.0);
        assert_eq!(undriven_stretches(&s), vec![(0, 499)]);
        // A gap of one step [0.4, 0.401): step 400 evaluates 0.401 under RK4, so no
        // whole free step; a force from 0 to the end leaves nothing.
        let s = scene(json!([force(0.0, Some(0.4)), force(0.401, None)]), 1.0);
        assert!(undriven_stretches(&s).is_empty());
        let s = scene(json!([force(0.0, None)]), 1.0);
        assert!(undriven_stretches(&s).is_empty());
    }

    #[test]
    fn the_watch_counts_steps_outside_and_keeps_the_first_worst() {
        let mut w = LayerWatch {
            epsilon: 0.1,
            steps: 0,
            outside: 0,
            worst: 0.0,
            worst_time: None,
        };
        for (k, x) in [0.05, 0.2, 0.1, 0.3, 0.3, 0.0].into_iter().enumerate() {
            w.record(SimTime(k as u64), x);
        }
        assert_eq!((w.steps, w.outside), (6, 3));
        assert_eq!((w.worst, w.worst_time), (0.3, Some(SimTime(3))));
        assert!(w.warning().unwrap().contains("on 3 of 6 steps (50.000 %)"));
        let mut inside = w.clone();
        inside.outside = 0;
        assert!(inside.warning().is_none());
    }
}
