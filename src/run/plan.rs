//! A run's plan, before it runs (`dsmcosim validate`): who owns what, what crosses the
//! network at which period, the TDMA cycle with its slot list, the controller, and what
//! the run will cost — all from the scenario, without stepping it.
//!
//! The same content is printed as text and written as JSON (`validate --json`).

use serde::Serialize;
use serde_json::Value;

use super::budget::Estimate;
use crate::cosim::world::network_of;
use crate::error::{Error, Result};
use crate::partition::layout::Layout;
use crate::scenario::model::{DataKind, NetworkSpec, Scenario};

/// One computing node: what it owns and what it ghosts.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NodePlan {
    /// Node number (1-based, as printed everywhere).
    pub node: usize,
    /// Ids of the bodies it owns.
    pub bodies: Vec<u32>,
    /// Ids of the far-end bodies it integrates as ghosts.
    pub ghosts: Vec<u32>,
    /// The links it owns (`L3`).
    pub links: Vec<String>,
}

/// One channel: its period requested and achieved, latency and load.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelPlan {
    /// Channel name.
    pub name: String,
    /// Period the scenario asks for [s].
    pub tau_requested: f64,
    /// Period the network delivers [s]: the whole number of steps on ideal channels, the
    /// worst gap of the slot list on TDMA; `None` where a sender is never served.
    pub tau_achieved: Option<f64>,
    /// Delivery latency [s] (ideal channels; on TDMA it follows from the slots).
    pub latency: Option<f64>,
    /// Bandwidth weight `k`.
    pub k: f64,
    /// Bandwidth `k / τ` at the achieved period [1/s].
    pub bandwidth: Option<f64>,
    /// State routes (body samples) it carries.
    pub state_routes: usize,
    /// Force routes (border-link forces) it carries.
    pub force_routes: usize,
    /// FMU connections it carries.
    pub signal_routes: usize,
}

/// One dynamic slot of the TDMA cycle.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SlotPlan {
    /// Slot number in the cycle (0 = sync).
    pub slot: usize,
    /// Start within the cycle [s].
    pub start: f64,
    /// Sending TDMA node (0 = server), or `None` for an idle slot.
    pub sender: Option<usize>,
    /// The channel it serves.
    pub channel: Option<String>,
}

/// The TDMA cycle in force at the start.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TdmaPlan {
    /// Cycle length [s].
    pub cycle: f64,
    /// Slot length [s].
    pub slot: f64,
    /// Slots per cycle.
    pub slots: usize,
    /// First dynamic slot (after sync and one static slot per node).
    pub first_dynamic: usize,
    /// The dynamic slots the list uses, in order (idle ones included up to its end).
    pub list: Vec<SlotPlan>,
}

/// What the run will cost.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CostPlan {
    /// Integration steps.
    pub steps: u64,
    /// FMU communication steps, all FMUs together.
    pub fmu_steps: u64,
    /// Messages sent (ideal channels: every route every period; TDMA: every route every
    /// achieved period, an estimate — drift and losses move it).
    pub messages: u64,
    /// Kernel events: steps, samples or TDMA cycles, deliveries, window ends.
    pub events: u64,
    /// Rows of trace.csv.
    pub trace_rows: u64,
    /// Upper bound on trace.csv [bytes].
    pub trace_bytes: u64,
    /// Estimated peak memory [bytes] ([`Estimate::memory_bytes`]).
    pub memory_bytes: u64,
}

/// Everything `validate` reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunPlan {
    /// Scenario name.
    pub scenario: String,
    /// Bodies, links and external forces.
    pub bodies: usize,
    /// Links.
    pub links: usize,
    /// External forces.
    pub forces: usize,
    /// Step [s] and duration [s].
    pub dt: f64,
    /// Simulated time [s].
    pub duration: f64,
    /// `point_mass` or `rigid`.
    pub body_model: String,
    /// Integrator name.
    pub integrator: String,
    /// Stabilizer and solver, as in summary.json.
    pub stabilizer: Value,
    /// The multiplier solve.
    pub solver: Value,
    /// Coupling scheme of a partitioned scene.
    pub coupling: Option<String>,
    /// Border links that are transmission lines: (link name, impedance `Z` [N·s/m]).
    pub lines: Vec<(String, f64)>,
    /// Network kind.
    pub network: String,
    /// Computing nodes.
    pub nodes: Vec<NodePlan>,
    /// Channels.
    pub channels: Vec<ChannelPlan>,
    /// The TDMA cycle (TDMA networks).
    pub tdma: Option<TdmaPlan>,
    /// The controller as the scenario gives it (times in ns).
    pub controller: Option<Value>,
    /// The cost.
    pub cost: CostPlan,
    /// The FMUs, one line each: name, node, step, model and what it exchanges.
    pub fmus: Vec<String>,
}

/// The plan of a validated `scenario`.
pub fn plan(scenario: &Scenario) -> Result<RunPlan> {
    let s = scenario;
    let layout = Layout::new(s);
    let id = |b: usize| s.bodies[b].id;
    let nodes = (0..layout.nodes)
        .map(|n| NodePlan {
            node: n + 1,
            bodies: layout.owned[n].iter().map(|&b| id(b)).collect(),
            ghosts: layout.ghosts[n].iter().map(|&b| id(b)).collect(),
            links: layout.links[n]
                .iter()
                .map(|l| format!("L{}", l + 1))
                .collect(),
        })
        .collect();
    let (channels, link) =
        network_of(s, &layout).map_err(|e| Error::invalid("network", e.to_string()))?;
    // The periods the channels start at (on TDMA what the initial list achieves): the
    // lines are chosen by these.
    let periods: Vec<_> = channels.iter().map(|c| c.tau).collect();
    // A channel one of whose senders the slot list never serves has no period.
    let achieved: Vec<_> = channels
        .iter()
        .map(|c| (c.tau.0 != u64::MAX).then_some(c.tau))
        .collect();
    let tdma = link.map(|link| {
        let net = link.network();
        let cycle = net.layout();
        let list = net.lists().active();
        let slots = (0..list.len())
            .map(|j| {
                let slot = cycle.dynamic_slot(j);
                let entry = list.get(j);
                SlotPlan {
                    slot,
                    start: cycle.offset(slot).as_secs_f64(),
                    sender: entry.map(|e| e.sender),
                    channel: entry.map(|e| {
                        s.channels
                            .get(e.channel)
                            .map_or_else(|| e.channel.to_string(), |c| c.name.clone())
                    }),
                }
            })
            .collect();
        TdmaPlan {
            cycle: cycle.cycle_len().as_secs_f64(),
            slot: cycle.slot_len().as_secs_f64(),
            slots: cycle.slots(),
            first_dynamic: cycle.first_dynamic(),
            list: slots,
        }
    });
    let duration = s.duration.0;
    let per_period = |tau: crate::kernel::SimTime| duration.checked_div(tau.0).unwrap_or(0);
    let mut messages = 0u64;
    let mut samples = 0u64;
    let channel_plans = channels
        .iter()
        .zip(&achieved)
        .map(|(c, a)| {
            let count = |kind| c.routes.iter().filter(|r| r.kind == kind).count();
            if let Some(a) = a {
                let n = per_period(*a);
                samples = samples.saturating_add(n);
                messages = messages.saturating_add(n.saturating_mul(c.routes.len() as u64));
            }
            ChannelPlan {
                name: c.spec.name.clone(),
                tau_requested: c.spec.tau.as_secs_f64(),
                tau_achieved: a.map(|a| a.as_secs_f64()),
                latency: tdma.is_none().then(|| c.latency().as_secs_f64()),
                k: c.spec.k,
                bandwidth: a.map(|a| c.spec.k / a.as_secs_f64()),
                state_routes: count(DataKind::State),
                force_routes: count(DataKind::Force),
                signal_routes: count(DataKind::Signal),
            }
        })
        .collect();
    let estimate = Estimate::of(s, None);
    let windows = per_period(s.measurement_period).max(1);
    // Ideal channels: one sample event per period and channel. TDMA: per cycle, one
    // cycle event and one frame event per busy slot. Every message is one delivery;
    // every step (step 0 included) and window end one event.
    let network_events = match &tdma {
        None => samples,
        Some(t) => {
            let cycles =
                per_period(crate::kernel::SimTime::from_secs_f64(t.cycle).unwrap_or_default());
            let busy = t.list.iter().filter(|e| e.sender.is_some()).count() as u64;
            cycles.saturating_mul(1 + busy)
        }
    };
    let events = estimate
        .steps
        .saturating_add(1)
        .saturating_add(network_events)
        .saturating_add(messages)
        .saturating_add(windows);
    Ok(RunPlan {
        scenario: s.name.clone(),
        bodies: s.bodies.len(),
        links: s.links.len(),
        forces: s.forces.len(),
        dt: s.dt.as_secs_f64(),
        duration: s.duration.as_secs_f64(),
        body_model: s.body_model.name().to_string(),
        integrator: s.integrator.name().to_string(),
        stabilizer: super::stabilizer_json(s),
        solver: super::solver_json(s),
        coupling: s.partition.as_ref().map(|p| p.coupling.name().to_string()),
        lines: {
            let set = crate::partition::line::LineSet::new(s, &layout.routes, &periods);
            (0..s.links.len())
                .filter_map(|l| set.impedance(l).map(|(z, _)| (format!("L{}", l + 1), z)))
                .collect()
        },
        network: match s.network {
            NetworkSpec::Ideal => "ideal".into(),
            NetworkSpec::Tdma(_) => "tdma".into(),
        },
        nodes,
        channels: channel_plans,
        fmus: s
            .fmus
            .iter()
            .map(|f| {
                format!(
                    "{} on node {}, step {} ms: model {} (FMI {}{}), {} output(s) read, {} \
                     input(s) set",
                    f.name,
                    f.node + 1,
                    f.step.as_secs_f64() * 1e3,
                    f.model_identifier,
                    f.fmi_version,
                    if f.can_get_set_state && f.can_serialize_state {
                        ", forkable"
                    } else {
                        ", not forkable: online measurement only"
                    },
                    f.outputs.len(),
                    f.inputs.len()
                )
            })
            .collect(),
        tdma,
        controller: s
            .controller
            .as_ref()
            .and_then(|c| serde_json::to_value(c).ok()),
        cost: CostPlan {
            steps: estimate.steps,
            fmu_steps: estimate.fmu_steps.0,
            messages,
            events,
            trace_rows: estimate.trace_rows,
            trace_bytes: estimate.trace_bytes,
            memory_bytes: estimate.memory_bytes,
        },
    })
}

/// Seconds in milliseconds for the text form (`5`, `5.13`).
fn ms(x: f64) -> String {
    format!("{}", (x * 1e6).round() / 1e3)
}

impl RunPlan {
    /// The plan as text, one fact per line.
    pub fn text(&self) -> String {
        let mut out = Vec::new();
        if self.bodies == 0 {
            // A scene of FMUs only: no body model, integrator, law or solve runs.
            out.push(format!(
                "no bodies; {} steps of {} s ({} s)",
                self.cost.steps, self.dt, self.duration
            ));
        } else {
            out.push(format!(
                "{} bodies, {} links, {} forces; {} steps of {} s ({} s); {} path, {} integrator",
                self.bodies,
                self.links,
                self.forces,
                self.cost.steps,
                self.dt,
                self.duration,
                self.body_model,
                self.integrator
            ));
            out.push(format!(
                "stabilizer {}; solver {}",
                self.stabilizer, self.solver
            ));
        }
        if self.nodes.len() > 1 {
            out.push(format!(
                "{} nodes, coupling {}:",
                self.nodes.len(),
                self.coupling.as_deref().unwrap_or("reset")
            ));
            for n in &self.nodes {
                out.push(format!(
                    "  node {}: bodies {:?}, ghosts {:?}, links {}",
                    n.node,
                    n.bodies,
                    n.ghosts,
                    n.links.join(" ")
                ));
            }
            if !self.lines.is_empty() {
                let names: Vec<&str> = self.lines.iter().map(|l| l.0.as_str()).collect();
                let (lo, hi) = self
                    .lines
                    .iter()
                    .fold((f64::MAX, 0.0f64), |(a, b), l| (a.min(l.1), b.max(l.1)));
                let z = if lo == hi {
                    format!("{lo}")
                } else {
                    format!("{lo}–{hi}")
                };
                out.push(format!(
                    "  transmission lines (Z = {z} N·s/m): {}",
                    names.join(" ")
                ));
            }
        }
        if !self.fmus.is_empty() {
            out.push("FMUs:".into());
            for f in &self.fmus {
                out.push(format!("  {f}"));
            }
        }
        if !self.channels.is_empty() {
            out.push(format!("{} network, channels:", self.network));
            out.push(
                "  name | τ requested [ms] | τ achieved [ms] | latency [ms] | k | bandwidth [1/s] | routes (state + force + signal)"
                    .into(),
            );
            for c in &self.channels {
                out.push(format!(
                    "  {} | {} | {} | {} | {} | {} | {} + {} + {}",
                    c.name,
                    ms(c.tau_requested),
                    c.tau_achieved.map_or("never served".into(), ms),
                    c.latency.map_or("from the slots".into(), ms),
                    c.k,
                    c.bandwidth.map_or("–".into(), |b| format!("{b:.1}")),
                    c.state_routes,
                    c.force_routes,
                    c.signal_routes
                ));
            }
        }
        if let Some(t) = &self.tdma {
            out.push(format!(
                "TDMA cycle {} ms of {} slots of {} µs (sync 0, static 1–{}, dynamic from {}); slot list:",
                ms(t.cycle),
                t.slots,
                (t.slot * 1e9).round() / 1e3,
                t.first_dynamic - 1,
                t.first_dynamic
            ));
            out.push("  slot | start [ms] | sender | channel".into());
            for e in &t.list {
                out.push(format!(
                    "  {} | {} | {} | {}",
                    e.slot,
                    ms(e.start),
                    e.sender.map_or("idle".into(), |s| s.to_string()),
                    e.channel.as_deref().unwrap_or("–")
                ));
            }
        }
        if let Some(c) = &self.controller {
            out.push(format!("controller: {c}"));
        }
        out.push(format!(
            "a run takes {} steps{}, about {} messages and {} kernel events (at the scenario's τ), writes {} trace rows (trace.csv at most {} bytes), and needs about {} MB of memory",
            self.cost.steps,
            if self.cost.fmu_steps > 0 {
                format!(" and {} FMU steps", self.cost.fmu_steps)
            } else {
                String::new()
            },
            self.cost.messages,
            self.cost.events,
            self.cost.trace_rows,
            self.cost.trace_bytes,
            self.cost.memory_bytes.div_ceil(1_000_000)
        ));
        out.join("\n")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped(name: &str, duration: f64) -> Scenario {
        let path = format!("{}/scenarios/{name}.json", env!("CARGO_MANIFEST_DIR"));
        let mut v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        v["duration"] = serde_json::json!(duration);
        crate::scenario::parse_str(&v.to_string(), name).expect("valid")
    }

    /// The plan's counts against what a run does: exact on ideal channels, within the
    /// samples still in flight at the end on TDMA.
    #[test]
    fn the_estimate_matches_a_run() {
        for (name, exact) in [("grid16_space_fixed", true), ("tdma4_space_fixed", false)] {
            let s = shipped(name, 2.0);
            let p = plan(&s).unwrap();
            let dir =
                std::env::temp_dir().join(format!("dsmcosim-plan-{name}-{}", std::process::id()));
            let outcome = crate::run::run(&s, &dir).expect("runs");
            let _ = std::fs::remove_dir_all(&dir);
            assert_eq!(p.cost.steps, outcome.steps);
            if exact {
                assert_eq!(
                    (p.cost.messages, p.cost.events),
                    (outcome.messages, outcome.events)
                );
            } else {
                let near = |a: u64, b: u64| a.abs_diff(b) as f64 <= 0.01 * b as f64;
                assert!(
                    near(p.cost.messages, outcome.messages),
                    "{} vs {}",
                    p.cost.messages,
                    outcome.messages
                );
                assert!(
                    near(p.cost.events, outcome.events),
                    "{} vs {}",
                    p.cost.events,
                    outcome.events
                );
            }
        }
    }

    #[test]
    fn the_plan_names_the_transmission_lines() {
        // At 5 ms (age up to 10 ms) the default coupling has no lines; at 50 ms every
        // border link is one, of impedance m_r · 2/μ = 0.5 kg · 2 / 0.05 s = 20 N·s/m.
        let p = plan(&shipped("grid16_space_fixed", 1.0)).unwrap();
        assert!(p.lines.is_empty());
        let mut v: Value = serde_json::from_str(
            &std::fs::read_to_string(format!(
                "{}/scenarios/grid16_space_fixed.json",
                env!("CARGO_MANIFEST_DIR")
            ))
            .unwrap(),
        )
        .unwrap();
        v["channels"][0]["tau"] = serde_json::json!(0.05);
        v["channels"][1]["tau"] = serde_json::json!(0.05);
        let p = plan(&crate::scenario::parse_str(&v.to_string(), "t").unwrap()).unwrap();
        let names: Vec<&str> = p.lines.iter().map(|l| l.0.as_str()).collect();
        assert_eq!(
            names,
            ["L3", "L9", "L10", "L11", "L13", "L14", "L17", "L23"]
        );
        assert!(p.lines.iter().all(|l| (l.1 - 20.0).abs() < 1e-9));
        assert!(p
            .text()
            .contains("transmission lines (Z = 20 N·s/m): L3 L9"));
    }

    #[test]
    fn the_plan_names_nodes_channels_and_slots() {
        let p = plan(&shipped("tdma4_space_fixed", 1.0)).unwrap();
        assert_eq!(p.nodes.len(), 4);
        assert_eq!(p.nodes[0].bodies, [1, 2, 5, 6]);
        assert_eq!(p.nodes[0].ghosts, [3, 7]);
        let t = p.tdma.as_ref().expect("a TDMA plan");
        // Every channel is served, at its 5 ms, by slots after the static ones.
        assert!(p.channels.iter().all(|c| c.tau_achieved == Some(0.005)));
        assert!(t.list.iter().all(|e| e.slot >= t.first_dynamic));
        assert_eq!(t.list.iter().filter(|e| e.sender.is_some()).count(), 6);
        let text = p.text();
        assert!(
            text.contains("node 1: bodies [1, 2, 5, 6], ghosts [3, 7]"),
            "{text}"
        );
        assert!(
            text.contains("slot | start [ms] | sender | channel"),
            "{text}"
        );
    }
}
