//! The accuracy knobs of the study, as a table: each [`Knob`] lists its settings, and a
//! [`Setting`] is a list of edits to the scenario's JSON (a JSON pointer and the value
//! to put there). Adding a knob or a setting is adding an entry here; the study, the
//! tables and the plots pick it up.
//!
//! Network models other than `ideal` (TDMA, with and without clock drift and jitter)
//! become settings of the `network` knob when the scenario format gains them.

use serde_json::{json, Value};

use crate::error::Result;
use crate::kernel::SimTime;
use crate::scenario::model::{Integrator, Stabilizer};
use crate::scenario::{parse_str, Scenario};

/// The `dt` settings as fractions `(numerator, denominator)` of the base `dt`: 0.25× to
/// 8×, a factor 32. The largest one sets the common comparison grid.
pub const DT_FACTORS: [(u64, u64); 6] = [(1, 4), (1, 2), (1, 1), (2, 1), (4, 1), (8, 1)];

/// CG iteration budgets (tolerance 0: exactly that many iterations per solve).
pub const CG_BUDGETS: [usize; 4] = [2, 5, 10, 40];

/// Baumgarte coefficients α = β [1/s] of the comparison stabilizer.
pub const BAUMGARTE: [f64; 3] = [5.0, 20.0, 50.0];

/// One accuracy knob.
pub struct Knob {
    /// Name in the tables and the plot legend.
    pub name: &'static str,
    /// When the knob applies (printed when it is skipped).
    pub when: &'static str,
    /// Whether the knob applies to the base scenario.
    pub applies: fn(&Scenario) -> bool,
    /// The settings around the base scenario.
    pub settings: fn(&Scenario) -> Vec<Setting>,
}

/// One setting of a knob.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    /// Label in the tables (`0.25 ms`, `cg 5`).
    pub label: String,
    /// `(JSON pointer, value)` pairs written into the base scenario's JSON.
    pub edits: Vec<(&'static str, Value)>,
}

impl Setting {
    fn new(label: impl Into<String>, edits: Vec<(&'static str, Value)>) -> Setting {
        Setting {
            label: label.into(),
            edits,
        }
    }

    /// The base JSON with this setting's edits applied (missing objects on the way are
    /// created).
    pub fn apply(&self, base: &Value) -> Value {
        let mut v = base.clone();
        for (pointer, value) in &self.edits {
            set(&mut v, pointer, value.clone());
        }
        v
    }
}

/// Writes `value` at the JSON `pointer` (`/a/b`), creating objects on the way.
fn set(root: &mut Value, pointer: &str, value: Value) {
    let mut at = root;
    for key in pointer.split('/').skip(1) {
        if !at.is_object() {
            *at = json!({});
        }
        at = at
            .as_object_mut()
            .map(|o| o.entry(key.to_string()).or_insert(Value::Null))
            .expect("ok: made an object above");
    }
    *at = value;
}

fn always(_: &Scenario) -> bool {
    true
}

fn partitioned(s: &Scenario) -> bool {
    s.partition.is_some()
}

fn smc(s: &Scenario) -> bool {
    matches!(s.stabilizer, Stabilizer::Smc { .. })
}

/// `dt` [s] as a JSON number, `factor` × the base.
fn dt_value(s: &Scenario, (n, d): (u64, u64)) -> (String, Value) {
    let dt = SimTime(s.dt.as_nanos() * n / d);
    (
        format!("{} ms", dt.as_nanos() as f64 / 1e6),
        Value::from(dt.as_secs_f64()),
    )
}

fn dt_settings(s: &Scenario, integrator: Option<Integrator>) -> Vec<Setting> {
    DT_FACTORS
        .iter()
        .map(|&f| {
            let (label, dt) = dt_value(s, f);
            let mut edits = vec![("/dt", dt)];
            if let Some(i) = integrator {
                edits.push(("/integrator", json!(i.name())));
            }
            Setting::new(label, edits)
        })
        .collect()
}

const INTEGRATORS: [Integrator; 3] = [
    Integrator::Euler,
    Integrator::SymplecticEuler,
    Integrator::Rk4,
];

/// The knobs, in table order.
pub const KNOBS: &[Knob] = &[
    Knob {
        name: "dt",
        when: "always",
        applies: always,
        settings: |s| dt_settings(s, None),
    },
    Knob {
        name: "integrator",
        when: "always",
        applies: always,
        settings: |_| {
            INTEGRATORS
                .iter()
                .map(|i| Setting::new(i.name(), vec![("/integrator", json!(i.name()))]))
                .collect()
        },
    },
    Knob {
        name: "dt, euler",
        when: "the base integrator is not euler",
        applies: |s| s.integrator != Integrator::Euler,
        settings: |s| dt_settings(s, Some(Integrator::Euler)),
    },
    Knob {
        name: "dt, symplectic_euler",
        when: "the base integrator is not symplectic_euler",
        applies: |s| s.integrator != Integrator::SymplecticEuler,
        settings: |s| dt_settings(s, Some(Integrator::SymplecticEuler)),
    },
    Knob {
        name: "dt, rk4",
        when: "the base integrator is not rk4",
        applies: |s| s.integrator != Integrator::Rk4,
        settings: |s| dt_settings(s, Some(Integrator::Rk4)),
    },
    Knob {
        name: "solver",
        when: "always",
        applies: always,
        settings: |_| {
            let mut v = vec![Setting::new(
                "cholesky",
                vec![("/solver", json!({"kind": "cholesky"}))],
            )];
            v.extend(CG_BUDGETS.iter().map(|&n| {
                Setting::new(
                    format!("cg {n}"),
                    vec![(
                        "/solver",
                        json!({"kind": "cg", "max_iterations": n, "tolerance": 0.0}),
                    )],
                )
            }));
            v
        },
    },
    Knob {
        name: "stabilizer",
        when: "always",
        applies: always,
        settings: |s| {
            let (mu, k, epsilon) = match s.stabilizer {
                Stabilizer::Smc { mu, k, epsilon } => (mu, k, epsilon),
                Stabilizer::Baumgarte { .. } => (
                    crate::scenario::file::DEFAULT_SMC_MU,
                    crate::scenario::file::DEFAULT_SMC_K,
                    crate::scenario::file::DEFAULT_SMC_EPSILON,
                ),
            };
            let mut v = vec![Setting::new(
                format!("smc μ {mu} K {k} ε {epsilon}"),
                vec![(
                    "/stabilizer",
                    json!({"kind": "smc", "mu": mu, "k": k, "epsilon": epsilon}),
                )],
            )];
            v.extend(BAUMGARTE.iter().map(|&a| {
                Setting::new(
                    format!("baumgarte α = β = {a}"),
                    vec![(
                        "/stabilizer",
                        json!({"kind": "baumgarte", "alpha": a, "beta": a}),
                    )],
                )
            }));
            v
        },
    },
    Knob {
        name: "smc K",
        when: "the stabilizer is smc",
        applies: smc,
        settings: |s| {
            let Stabilizer::Smc { mu, epsilon, .. } = s.stabilizer else {
                return Vec::new();
            };
            [3.0, 10.0, 30.0, 100.0]
                .iter()
                .map(|&k| {
                    Setting::new(
                        format!("K {k}"),
                        vec![(
                            "/stabilizer",
                            json!({"kind": "smc", "mu": mu, "k": k, "epsilon": epsilon}),
                        )],
                    )
                })
                .collect()
        },
    },
    Knob {
        name: "ghosts",
        when: "the scenario is partitioned",
        applies: partitioned,
        settings: |_| {
            ["integrate", "hold"]
                .iter()
                .map(|g| Setting::new(*g, vec![("/partition/ghosts", json!(g))]))
                .collect()
        },
    },
    Knob {
        name: "network",
        when: "the scenario is partitioned",
        applies: partitioned,
        // `tdma`, and `tdma` with drift and jitter, join this list with the TDMA model.
        settings: |_| {
            vec![Setting::new(
                "ideal",
                vec![("/network", json!({"kind": "ideal"}))],
            )]
        },
    },
];

/// The reference of `base`: monolithic (no partition, channels, network or
/// controller), classical RK4, exact solve, step `dt`; same bodies, links, forces and
/// stabilizer.
pub fn reference(base: &Value, dt: SimTime) -> Result<Scenario> {
    let mut v = base.clone();
    if let Some(o) = v.as_object_mut() {
        for key in ["partition", "channels", "network", "controller"] {
            o.remove(key);
        }
    }
    set(&mut v, "/integrator", json!("rk4"));
    set(&mut v, "/solver", json!({"kind": "cholesky"}));
    set(&mut v, "/dt", Value::from(dt.as_secs_f64()));
    parse_str(&v.to_string(), "reference")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_creates_missing_objects_and_overwrites() {
        let mut v = json!({"a": 1, "partition": {"quadrants": true}});
        set(&mut v, "/partition/ghosts", json!("hold"));
        set(&mut v, "/x/y/z", json!(2));
        set(&mut v, "/a", json!("b"));
        assert_eq!(
            v,
            json!({"a": "b", "partition": {"quadrants": true, "ghosts": "hold"}, "x": {"y": {"z": 2}}})
        );
    }
}
