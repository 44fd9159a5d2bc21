//! The work the constraint law does on the joints' rows: an ideal joint does none.
//!
//! A row's multiplier `z` acts on the bodies as `Jᵀ z`, whose power is `z ẇ`: zero while
//! the row holds (`ẇ = 0`), work while the law lets it open and close. Under the exact
//! multipliers (the default on a scene with joints) a joint stays closed to the
//! integrator's truncation and this work is round-off; under the SMC law by name it can
//! be a visible share of the mechanism's energy (docs/method.md §2.1), and a run says so
//! as it says when the boundary layer was left.
//!
//! Measured from what every step records, the rows' tensions `f = −z` and values `w`:
//! `W = −∫ f dw`, by the trapezoid rule between consecutive steps.

use serde_json::{json, Value};

use crate::kernel::SimTime;
use crate::scenario::model::{Scenario, Stabilizer};

/// A run's law is said to do measurable work on its joints when the net work exceeds
/// this share of the largest kinetic energy the mechanism had [1].
pub const MEASURABLE_SHARE: f64 = 0.01;

/// The joints' rows and the work done on them so far.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointWork {
    /// The rows of the model's joints (indices into the links).
    rows: Vec<usize>,
    /// `(f, w)` of each row at the last step (empty before the first).
    last: Vec<(f64, f64)>,
    /// Net work of the rows' forces on the bodies [J].
    pub net: f64,
    /// `∫ |z ẇ| dt` [J]: work done either way.
    pub gross: f64,
    /// Largest kinetic energy at the steps whose invariants the recorder computes (the
    /// trace's rows and summary.json's steps) [J].
    pub kinetic_max: f64,
    /// Time of the step with the largest net work so far, and that work [J].
    pub worst: (SimTime, f64),
    /// What the warning names as the likely cause.
    cause: Cause,
}

/// Why a run's joints may do work.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
enum Cause {
    /// The SMC law, whose multipliers lag.
    Smc,
    /// A partitioned run: a border joint's force crosses the network late.
    Border,
    /// Neither (the exact law on one node: the integrator's drift).
    Integration,
}

impl JointWork {
    /// The watch of `scenario`'s joints; `None` on a scene without joints.
    pub fn new(scenario: &Scenario) -> Option<JointWork> {
        let rows: Vec<usize> = (0..scenario.links.len())
            .filter(|&l| scenario.links[l].joint.is_some())
            .collect();
        let cause = if matches!(scenario.stabilizer, Stabilizer::Smc { .. }) {
            Cause::Smc
        } else if scenario.partition.is_some() {
            Cause::Border
        } else {
            Cause::Integration
        };
        (!rows.is_empty()).then_some(JointWork {
            cause,
            rows,
            last: Vec::new(),
            net: 0.0,
            gross: 0.0,
            kinetic_max: 0.0,
            worst: (SimTime::ZERO, 0.0),
        })
    }

    /// Counts the step at `t` with every link's tension `f` [N] and value `w`.
    pub fn record(&mut self, t: SimTime, f: &[f64], w: &[f64]) {
        if self.last.is_empty() {
            self.last = self.rows.iter().map(|&l| (f[l], w[l])).collect();
            return;
        }
        for (&l, last) in self.rows.iter().zip(&mut self.last) {
            let (f0, w0) = *last;
            let work = -0.5 * (f0 + f[l]) * (w[l] - w0);
            self.net += work;
            self.gross += work.abs();
            *last = (f[l], w[l]);
        }
        if self.net.abs() > self.worst.1.abs() {
            self.worst = (t, self.net);
        }
    }

    /// Counts the net's kinetic energy [J] at a step.
    pub fn kinetic(&mut self, energy: f64) {
        self.kinetic_max = self.kinetic_max.max(energy);
    }

    /// The net work as a share of the largest kinetic energy (0 when nothing moved).
    pub fn share(&self) -> f64 {
        if self.kinetic_max > 0.0 {
            self.net.abs() / self.kinetic_max
        } else {
            0.0
        }
    }

    /// summary.json's `joint_work`.
    pub fn summary(&self) -> Value {
        json!({
            "net": self.net,
            "gross": self.gross,
            "kinetic_energy_max": self.kinetic_max,
            "share_of_kinetic_energy": self.share(),
            "largest_net": self.worst.1,
            "largest_net_time": self.worst.0.as_secs_f64(),
        })
    }

    /// The line the command line prints when the law did measurable work on the
    /// joints; `None` if it did not.
    pub fn warning(&self) -> Option<String> {
        (self.share() > MEASURABLE_SHARE).then(|| {
            let why = match self.cause {
                Cause::Smc => {
                    "the SMC law lags on joints; the default on a scene with joints, \
                     {\"kind\": \"baumgarte\"}, does not"
                }
                Cause::Border => {
                    "a border joint's force crosses the network late (docs/method.md \
                     §2.1 measures where that holds: about 10 ms on a chain, 6 ms on a \
                     fast swing; a shorter τ or latency)"
                }
                Cause::Integration => "a smaller dt or RK4 keeps the joints closer",
            };
            format!(
                "the joints' forces did {:+.3e} J of work ({:.1} % of the largest kinetic \
                 energy, {:.3e} J; up to {:+.3e} J at t = {} s): an ideal joint does none; \
                 {why} (summary.json: joint_work)",
                self.net,
                100.0 * self.share(),
                self.kinetic_max,
                self.worst.1,
                self.worst.0.as_secs_f64(),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pendulum(stabilizer: &str) -> Scenario {
        let v = json!({
            "name": "p", "seed": 1, "duration": 1.0, "dt": 0.001,
            "stabilizer": serde_json::from_str::<Value>(stabilizer).unwrap(),
            "model": {"bodies": [{"id": 1, "mass": 1.0, "size": 0.1, "position": [1, 0, 0]}],
                      "joints": [{"type": "ball", "a": 1, "at": [0, 0, 0]}]}
        });
        crate::scenario::parse_str(&v.to_string(), "<test>").unwrap()
    }

    #[test]
    fn a_row_that_opens_against_its_force_is_work_and_a_closed_one_is_none() {
        let s = pendulum(r#"{"kind": "smc"}"#);
        let mut watch = JointWork::new(&s).expect("a joint");
        // Three rows; row 0 opens by 1 mm against a tension of 10 N: −10 × 1e-3 J.
        watch.kinetic(0.5);
        watch.record(SimTime(0), &[10.0, 5.0, 1.0], &[0.0, 0.0, 0.0]);
        watch.record(SimTime(1), &[10.0, 5.0, 1.0], &[1e-3, 0.0, 0.0]);
        assert!((watch.net + 1e-2).abs() < 1e-15, "{}", watch.net);
        assert!(watch.warning().is_some());
        // Closing again under the same tension gives it back: no net work, and gross
        // counts both.
        watch.record(SimTime(2), &[10.0, 5.0, 1.0], &[0.0, 0.0, 0.0]);
        assert!(watch.net.abs() < 1e-15 && (watch.gross - 2e-2).abs() < 1e-15);
        assert!(watch.warning().is_none());
    }

    #[test]
    fn a_scene_without_joints_has_no_watch() {
        let v = json!({
            "name": "g", "seed": 1, "duration": 1.0, "dt": 0.001,
            "model": {"grid": {"rows": 1, "cols": 2, "spacing": 1.0, "mass": 1.0, "size": 0.2}}
        });
        let s = crate::scenario::parse_str(&v.to_string(), "<test>").unwrap();
        assert!(JointWork::new(&s).is_none());
    }
}
