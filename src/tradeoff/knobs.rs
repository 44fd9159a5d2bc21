//! The accuracy knobs of the study, as a table: each [`Knob`] lists its settings, and a
//! [`Setting`] is a list of [`Edit`]s to the scenario's JSON (a JSON pointer and the
//! value to put there, or a key to remove). Adding a knob or a setting is adding an
//! entry here; the study, the tables and the plots pick it up.
//!
//! The `network` knob (partitioned scenes) has four settings, each meaning the same
//! whatever the base's network is:
//!
//! | setting | network | channels |
//! |---|---|---|
//! | `ideal` | `{"kind": "ideal"}` | as in the base (an ideal base is unchanged; on a TDMA base no channel has `latency`, so it defaults to τ: the thesis's `x(t − τ)`) |
//! | `ideal, latency 0` | `{"kind": "ideal"}` | every `latency` 0: sample and hold, what TDMA's microsecond latencies approximate |
//! | `tdma` | [`tdma_network`] without drift or jitter | `latency`, `phase` removed (TDMA refuses them) |
//! | `tdma_drift_jitter` | the same with drift, random walk, sync error and jitter | the same |
//!
//! The TDMA settings replace the base's whole `network` section (an explicit
//! `slot_list` or `decision_lag` of a TDMA base included) with [`tdma_network`].

use serde_json::{json, Value};

use crate::error::Result;
use crate::kernel::SimTime;
use crate::multibody::solver::DENSE_MAX_LINKS;
use crate::scenario::model::{Integrator, Stabilizer};
use crate::scenario::{parse_str, Scenario};

/// The `dt` settings as fractions `(numerator, denominator)` of the base `dt`: 0.25× to
/// 8×, a factor 32. The largest one sets the common comparison grid.
pub const DT_FACTORS: [(u64, u64); 6] = [(1, 4), (1, 2), (1, 1), (2, 1), (4, 1), (8, 1)];

/// CG iteration budgets (tolerance 0: exactly that many iterations per solve).
pub const CG_BUDGETS: [usize; 4] = [2, 5, 10, 40];

/// Baumgarte coefficients α = β [1/s] of the comparison stabilizer.
pub const BAUMGARTE: [f64; 3] = [5.0, 20.0, 50.0];

/// The most links a node owns (all of them on a monolithic scene).
fn largest_node_links(s: &Scenario) -> usize {
    let Some(p) = &s.partition else {
        return s.links.len();
    };
    let mut per_node = vec![0usize; p.nodes];
    for &n in &p.link_owner {
        per_node[n] += 1;
    }
    per_node.into_iter().max().unwrap_or(0)
}

/// One accuracy knob.
pub struct Knob {
    /// Name in the tables and the plot legend.
    pub name: &'static str,
    /// When the knob applies (printed when it is skipped).
    pub when: &'static str,
    /// Whether the knob applies to the base scenario.
    pub applies: fn(&Scenario) -> bool,
    /// Whether the settings are steps along one numeric scale (`dt`, a gain), so the
    /// work-precision plot may join them by a line; categorical settings (integrators,
    /// solvers, stabilizers) are drawn as separate markers.
    pub ordered: bool,
    /// The settings around the base scenario.
    pub settings: fn(&Scenario) -> Vec<Setting>,
}

/// One edit of the scenario's JSON. Pointers are `/a/b/0/c`: keys, or indices of
/// existing array elements (`/channels/1/latency`); no `~` escapes (no key of the format
/// needs one).
#[derive(Debug, Clone, PartialEq)]
pub enum Edit {
    /// Writes the value at the pointer, creating missing objects on the way.
    Set(String, Value),
    /// Removes the key at the pointer; nothing if it is absent.
    Remove(String),
}

/// One setting of a knob.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    /// Label in the tables (`0.25 ms`, `cg 5`).
    pub label: String,
    /// Edits applied in order to the base scenario's JSON.
    pub edits: Vec<Edit>,
}

impl Setting {
    /// A setting that writes `(JSON pointer, value)` pairs.
    fn new(label: impl Into<String>, edits: Vec<(&'static str, Value)>) -> Setting {
        Setting::with(
            label,
            edits
                .into_iter()
                .map(|(p, v)| Edit::Set(p.to_string(), v))
                .collect(),
        )
    }

    /// A setting made of any edits.
    fn with(label: impl Into<String>, edits: Vec<Edit>) -> Setting {
        Setting {
            label: label.into(),
            edits,
        }
    }

    /// The base JSON with this setting's edits applied (missing objects on the way are
    /// created).
    pub fn apply(&self, base: &Value) -> Value {
        let mut v = base.clone();
        for edit in &self.edits {
            match edit {
                Edit::Set(pointer, value) => set(&mut v, pointer, value.clone()),
                Edit::Remove(pointer) => remove(&mut v, pointer),
            }
        }
        v
    }
}

/// Writes `value` at the JSON `pointer` (`/a/b`), creating objects on the way; a key
/// that is the index of an existing array element steps into it.
fn set(root: &mut Value, pointer: &str, value: Value) {
    let mut at = root;
    for key in pointer.split('/').skip(1) {
        let index = match &*at {
            Value::Array(a) => key.parse::<usize>().ok().filter(|&i| i < a.len()),
            _ => None,
        };
        at = match index {
            Some(i) => &mut at[i],
            None => {
                if !at.is_object() {
                    *at = json!({});
                }
                at.as_object_mut()
                    .map(|o| o.entry(key.to_string()).or_insert(Value::Null))
                    .expect("ok: made an object above")
            }
        };
    }
    *at = value;
}

/// Removes the key at the JSON `pointer`, if its parent is an object that has it.
fn remove(root: &mut Value, pointer: &str) {
    let Some((parent, key)) = pointer.rsplit_once('/') else {
        return;
    };
    if let Some(o) = root.pointer_mut(parent).and_then(Value::as_object_mut) {
        o.remove(key);
    }
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

/// TDMA slot of the `tdma` settings [s]: 100 µs, so a 5 ms cycle is 50 slots.
pub const TDMA_SLOT: f64 = 100e-6;

/// TDMA guard [s]: 10 % of the slot, far above the clock error that 50 ppm of drift
/// gathers over a 5 ms cycle (250 ns) plus the sync error (200 ns), so nothing collides.
pub const TDMA_GUARD: f64 = 10e-6;

/// TDMA link rate [bit/s]: 100 Mbit/s, a frame of 300 B takes 24 µs, so deliveries land
/// well inside the 1 ms step (nearly instantaneous at the scene's time scale).
pub const TDMA_LINK_RATE: f64 = 100e6;

/// TDMA header per frame [B] (Ethernet's preamble, addresses and CRC, roughly).
pub const TDMA_HEADER_BYTES: u64 = 26;

/// TDMA cycle [s] when the base's channels do not share one period.
pub const TDMA_DEFAULT_CYCLE: f64 = 5e-3;

/// `tdma_drift_jitter`: clock rate offset bound [ppm], uniform per client.
pub const TDMA_DRIFT_PPM: f64 = 50.0;

/// `tdma_drift_jitter`: random walk of the rate [ppm/√s], a step per cycle.
pub const TDMA_RANDOM_WALK_PPM: f64 = 0.5;

/// `tdma_drift_jitter`: residual clock offset after each sync [s], uniform in ±.
pub const TDMA_SYNC_ERROR: f64 = 200e-9;

/// `tdma_drift_jitter`: mean of the exponential processing jitter per frame [s].
pub const TDMA_JITTER_MEAN: f64 = 20e-6;

/// The `network` section of the `tdma` settings for base `s`: a TDMA network that
/// realizes the base's channel periods (slot list scheduled from the channels' τ), with
/// cycle = the channels' common τ if they share one, else [`TDMA_DEFAULT_CYCLE`]; no
/// propagation delay. With `drift_jitter`, clocks drift and frames jitter
/// ([`TDMA_DRIFT_PPM`] and the constants after it). The fidelity bench builds its TDMA
/// cases from this too.
pub fn tdma_network(s: &Scenario, drift_jitter: bool) -> Value {
    let cycle = match s.channels.split_first() {
        Some((first, rest)) if rest.iter().all(|c| c.tau == first.tau) => first.tau.as_secs_f64(),
        _ => TDMA_DEFAULT_CYCLE,
    };
    let mut n = json!({
        "kind": "tdma",
        "slot": TDMA_SLOT,
        "cycle": cycle,
        "guard": TDMA_GUARD,
        "link_rate": TDMA_LINK_RATE,
        "header_bytes": TDMA_HEADER_BYTES,
    });
    if drift_jitter {
        n["drift_ppm"] = json!(TDMA_DRIFT_PPM);
        n["random_walk_ppm"] = json!(TDMA_RANDOM_WALK_PPM);
        n["sync_error"] = json!(TDMA_SYNC_ERROR);
        n["jitter"] = json!({"kind": "exponential", "mean": TDMA_JITTER_MEAN});
    }
    n
}

/// The `network` knob's settings (see the module docs).
fn network_settings(s: &Scenario) -> Vec<Setting> {
    let ideal = || Edit::Set("/network".into(), json!({"kind": "ideal"}));
    let latency_0 =
        (0..s.channels.len()).map(|i| Edit::Set(format!("/channels/{i}/latency"), json!(0.0)));
    let tdma = |drift_jitter: bool| {
        let mut edits = vec![Edit::Set("/network".into(), tdma_network(s, drift_jitter))];
        for i in 0..s.channels.len() {
            edits.push(Edit::Remove(format!("/channels/{i}/latency")));
            edits.push(Edit::Remove(format!("/channels/{i}/phase")));
        }
        edits
    };
    vec![
        Setting::with("ideal", vec![ideal()]),
        Setting::with(
            "ideal, latency 0",
            std::iter::once(ideal()).chain(latency_0).collect(),
        ),
        Setting::with("tdma", tdma(false)),
        Setting::with("tdma_drift_jitter", tdma(true)),
    ]
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
        ordered: true,
        applies: always,
        settings: |s| dt_settings(s, None),
    },
    Knob {
        name: "integrator",
        when: "always",
        ordered: false,
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
        ordered: true,
        applies: |s| s.integrator != Integrator::Euler,
        settings: |s| dt_settings(s, Some(Integrator::Euler)),
    },
    Knob {
        name: "dt, symplectic_euler",
        when: "the base integrator is not symplectic_euler",
        ordered: true,
        applies: |s| s.integrator != Integrator::SymplecticEuler,
        settings: |s| dt_settings(s, Some(Integrator::SymplecticEuler)),
    },
    Knob {
        name: "dt, rk4",
        when: "the base integrator is not rk4",
        ordered: true,
        applies: |s| s.integrator != Integrator::Rk4,
        settings: |s| dt_settings(s, Some(Integrator::Rk4)),
    },
    Knob {
        name: "solver",
        when: "always",
        ordered: false,
        applies: always,
        settings: |s| {
            let mut v = vec![Setting::new(
                "cholesky",
                vec![("/solver", json!({"kind": "cholesky"}))],
            )];
            // The reused factor differs from `cholesky` only on a node whose system is
            // above the dense path's size.
            if largest_node_links(s) > DENSE_MAX_LINKS {
                v.push(Setting::new(
                    "cholesky_pcg",
                    vec![("/solver", json!({"kind": "cholesky_pcg"}))],
                ));
            }
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
        ordered: false,
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
        ordered: true,
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
        ordered: false,
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
        ordered: false,
        applies: partitioned,
        settings: network_settings,
    },
];

/// The reference of `base`: monolithic (no partition, network or controller, and no
/// channels unless connections ride them), classical RK4, exact solve, step `dt`; same
/// bodies, links, forces, stabilizer, FMUs and connections.
///
/// A scene's connections (an FMU's inputs and outputs) are part of the model it
/// simulates, delays included, so their channels stay, on the ideal network; removed,
/// the reference of an FMU scene failed to validate ("unknown channel").
pub fn reference(base: &Value, dt: SimTime) -> Result<Scenario> {
    let mut v = base.clone();
    let connected = v
        .get("connections")
        .and_then(Value::as_array)
        .is_some_and(|c| !c.is_empty());
    if let Some(o) = v.as_object_mut() {
        for key in ["partition", "channels", "network", "controller"] {
            if key != "channels" || !connected {
                o.remove(key);
            }
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
    use crate::network::tdma::Jitter;
    use crate::scenario::model::NetworkSpec;

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

    #[test]
    fn set_steps_into_array_elements_and_remove_drops_keys() {
        let mut v = json!({"channels": [{"tau": 1, "latency": 2}, {"tau": 3, "phase": 4}]});
        set(&mut v, "/channels/1/latency", json!(0.0));
        remove(&mut v, "/channels/0/latency");
        remove(&mut v, "/channels/1/phase");
        remove(&mut v, "/channels/5/phase");
        remove(&mut v, "/nowhere/x");
        assert_eq!(
            v,
            json!({"channels": [{"tau": 1}, {"tau": 3, "latency": 0.0}]})
        );
    }

    /// The thesis's 4-node scene (grid16_space_fixed: quadrants, two channels at τ = 5
    /// ms, ideal network without `latency` keys).
    fn thesis_4_node() -> Value {
        serde_json::from_str(include_str!("../../scenarios/grid16_space_fixed.json"))
            .expect("shipped scenario is JSON")
    }

    /// The network knob's settings applied to `base`, each parsed and validated.
    fn network_variants(base: &Value) -> Vec<(String, Scenario)> {
        let scenario = parse_str(&base.to_string(), "base").expect("valid base");
        let knob = KNOBS
            .iter()
            .find(|k| k.name == "network")
            .expect("network knob");
        assert!(
            (knob.applies)(&scenario),
            "network knob applies to the base"
        );
        (knob.settings)(&scenario)
            .iter()
            .map(|setting| {
                let v = setting.apply(base);
                let s = parse_str(&v.to_string(), &setting.label)
                    .unwrap_or_else(|e| panic!("setting {}: {e}", setting.label));
                (setting.label.clone(), s)
            })
            .collect()
    }

    /// The labels of the solver knob's settings on a grid of `rows × rows` bodies,
    /// monolithic or on 2×2-body quadrant nodes.
    fn solver_labels(rows: usize, quadrants: bool) -> Vec<String> {
        let s = if quadrants {
            let mut v = thesis_4_node();
            v["model"]["grid"]["rows"] = json!(rows);
            v["model"]["grid"]["cols"] = json!(rows);
            parse_str(&v.to_string(), "quadrants")
        } else {
            let v = json!({
                "name": "s", "seed": 1, "duration": 0.1, "dt": 0.001,
                "model": {"grid": {"rows": rows, "cols": rows, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
            });
            parse_str(&v.to_string(), "grid")
        }
        .expect("valid grid");
        let knob = KNOBS.iter().find(|k| k.name == "solver").expect("knob");
        (knob.settings)(&s).into_iter().map(|s| s.label).collect()
    }

    #[test]
    fn the_reused_factor_is_offered_where_it_differs_from_cholesky() {
        // 4×4: 24 links, dense; 8×8: 112 links, sparse; the thesis's 4 nodes: at most
        // 8 links each, dense.
        let pcg = |labels: Vec<String>| labels.iter().any(|l| l == "cholesky_pcg");
        assert!(!pcg(solver_labels(4, false)));
        assert!(pcg(solver_labels(8, false)));
        assert!(!pcg(solver_labels(4, true)));
    }

    fn tdma(s: &Scenario) -> &crate::scenario::model::TdmaSpec {
        match &s.network {
            NetworkSpec::Tdma(t) => t,
            NetworkSpec::Ideal => panic!("{}: expected a tdma network", s.name),
        }
    }

    #[test]
    fn network_settings_are_valid_on_the_thesis_4_node_scene() {
        let base = thesis_4_node();
        let variants = network_variants(&base);
        let labels: Vec<&str> = variants.iter().map(|(l, _)| l.as_str()).collect();
        assert_eq!(
            labels,
            ["ideal", "ideal, latency 0", "tdma", "tdma_drift_jitter"]
        );
        let base_scenario = parse_str(&base.to_string(), "base").expect("valid base");
        assert_eq!(
            variants[0].1, base_scenario,
            "ideal on an ideal base is the base"
        );
        for c in &variants[1].1.channels {
            assert_eq!(
                c.latency,
                Some(SimTime::ZERO),
                "ideal, latency 0: {}",
                c.name
            );
        }
        let plain = tdma(&variants[2].1);
        assert_eq!(
            plain.config.cycle,
            SimTime(5_000_000),
            "tdma: cycle = common τ"
        );
        assert_eq!(plain.config.slot, SimTime(100_000), "tdma: slot");
        assert_eq!(plain.config.guard, SimTime(10_000), "tdma: guard");
        assert_eq!(plain.config.header_bytes, 26, "tdma: header");
        assert_eq!(plain.config.drift_ppm, 0.0, "tdma: no drift");
        assert_eq!(plain.config.jitter, Jitter::None, "tdma: no jitter");
        assert!(plain.slot_list.is_none(), "tdma: list scheduled from τ");
        let full = tdma(&variants[3].1);
        assert_eq!(full.config.drift_ppm, 50.0, "tdma_drift_jitter: drift");
        assert_eq!(full.config.random_walk_ppm, 0.5, "tdma_drift_jitter: walk");
        assert_eq!(
            full.config.sync_error,
            SimTime(200),
            "tdma_drift_jitter: sync"
        );
        assert_eq!(
            full.config.jitter,
            Jitter::Exponential {
                mean: SimTime(20_000)
            },
            "tdma_drift_jitter: jitter"
        );
    }

    #[test]
    fn tdma_settings_remove_channel_latency_and_phase() {
        let mut base = thesis_4_node();
        for c in base["channels"].as_array_mut().expect("channels") {
            c["latency"] = json!(0.002);
            c["phase"] = json!(0.001);
        }
        let variants = network_variants(&base);
        for (label, s) in &variants[2..] {
            assert!(matches!(s.network, NetworkSpec::Tdma(_)), "{label}");
            for c in &s.channels {
                assert_eq!(c.latency, None, "{label}: {} latency", c.name);
                assert_eq!(c.phase, SimTime::ZERO, "{label}: {} phase", c.name);
            }
        }
        for c in &variants[0].1.channels {
            assert_eq!(
                c.latency,
                Some(SimTime(2_000_000)),
                "ideal keeps {}",
                c.name
            );
        }
    }

    #[test]
    fn network_settings_are_valid_on_a_tdma_base_and_cycle_falls_back() {
        let base: Value =
            serde_json::from_str(include_str!("../../scenarios/tdma4_space_fixed.json"))
                .expect("shipped scenario is JSON");
        let variants = network_variants(&base);
        let ideal = &variants[0].1;
        assert_eq!(ideal.network, NetworkSpec::Ideal, "ideal on a tdma base");
        for c in &ideal.channels {
            assert_eq!(c.latency, None, "ideal: {} latency defaults to τ", c.name);
        }
        for c in &variants[1].1.channels {
            assert_eq!(
                c.latency,
                Some(SimTime::ZERO),
                "ideal, latency 0: {}",
                c.name
            );
        }
        assert_eq!(tdma(&variants[2].1).config.drift_ppm, 0.0, "tdma is plain");

        // Channels of different periods: the default cycle.
        let mut uneven = thesis_4_node();
        uneven["channels"][1]["tau"] = json!(0.01);
        let variants = network_variants(&uneven);
        let cycle = SimTime::from_secs_f64(TDMA_DEFAULT_CYCLE).expect("cycle");
        assert_eq!(tdma(&variants[2].1).config.cycle, cycle, "default cycle");
    }
}
