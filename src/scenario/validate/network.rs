//! The network stage: the `network` section checked against the partition and the
//! channels. A `tdma` network is checked once more on the finished scenario
//! ([`check_tdma`]), when frame sizes (from the message routes) and the controller's
//! bounds are known.

use super::checks::{foreign, non_negative, num, positive, required, time, whole_nanos};
use crate::cosim::fit::{check_tdma as check_fit, Misfit};
use crate::error::{Error, Result};
use crate::kernel::SimTime;
use crate::network::tdma::{Jitter, SlotEntry, SlotList, TdmaConfig, TdmaError};
use crate::scenario::file::{JitterFile, JitterKind, NetworkFile, NetworkKind, SlotEntryFile};
use crate::scenario::model::{ChannelSpec, NetworkSpec, PartitionSpec, Scenario, TdmaSpec};

/// The `network` section.
pub(super) fn network(
    n: &NetworkFile,
    partition: Option<&PartitionSpec>,
    fmu_nodes: usize,
    channels: &[ChannelSpec],
) -> Result<NetworkSpec> {
    match n.kind {
        NetworkKind::Ideal => {
            ideal_has_no_tdma_keys(n)?;
            Ok(NetworkSpec::Ideal)
        }
        NetworkKind::Tdma => {
            tdma(n, partition, fmu_nodes, channels).map(|t| NetworkSpec::Tdma(Box::new(t)))
        }
    }
}

fn ideal_has_no_tdma_keys(n: &NetworkFile) -> Result<()> {
    let present = [
        ("slot", n.slot.is_some()),
        ("cycle", n.cycle.is_some()),
        ("guard", n.guard.is_some()),
        ("link_rate", n.link_rate.is_some()),
        ("propagation", n.propagation.is_some()),
        ("header_bytes", n.header_bytes.is_some()),
        ("drift_ppm", n.drift_ppm.is_some()),
        ("random_walk_ppm", n.random_walk_ppm.is_some()),
        ("sync_error", n.sync_error.is_some()),
        ("jitter", n.jitter.is_some()),
        ("slot_list", n.slot_list.is_some()),
        ("decision_lag", n.decision_lag.is_some()),
        ("sample", n.sample.is_some()),
    ];
    match present.iter().find(|(_, p)| *p) {
        Some((key, _)) => Err(foreign(&format!("network.{key}"), "ideal")),
        None => Ok(()),
    }
}

/// A `tdma` network over the partition's nodes, or as many as the FMUs run on
/// (`fmu_nodes`, the highest FMU node number), whichever is more.
fn tdma(
    n: &NetworkFile,
    partition: Option<&PartitionSpec>,
    fmu_nodes: usize,
    channels: &[ChannelSpec],
) -> Result<TdmaSpec> {
    let nodes = partition.map_or(0, |p| p.nodes).max(fmu_nodes);
    if partition.is_none() && fmu_nodes < 2 {
        return Err(Error::invalid(
            "network.kind",
            "\"tdma\" needs a `partition` section or FMUs on two nodes or more (a \
             monolithic model sends no messages)",
        ));
    }
    for (i, c) in channels.iter().enumerate() {
        if c.latency.is_some() {
            return Err(Error::invalid(
                format!("channels[{i}].latency"),
                "is not used by a \"tdma\" network (latency is transmission + propagation \
                 + jitter there)",
            ));
        }
    }
    let secs = |key: &str, v: Option<f64>| -> Result<Option<SimTime>> {
        v.map(|s| whole_nanos(&format!("network.{key}"), s))
            .transpose()
    };
    let slot = secs("slot", n.slot)?.ok_or_else(|| required("network.slot", "tdma"))?;
    let cycle = secs("cycle", n.cycle)?.ok_or_else(|| required("network.cycle", "tdma"))?;
    let mut cfg = TdmaConfig::new(nodes, slot, cycle);
    if let Some(g) = secs("guard", n.guard)? {
        cfg.guard = g;
    }
    if let Some(rate) = n.link_rate {
        cfg.link_rate = positive("network.link_rate", rate)?;
    }
    if let Some(d) = secs("propagation", n.propagation)? {
        cfg.propagation = d;
    }
    cfg.header_bytes = n.header_bytes.unwrap_or(0);
    if let Some(ppm) = n.drift_ppm {
        cfg.drift_ppm = non_negative("network.drift_ppm", ppm)?;
    }
    if let Some(ppm) = n.random_walk_ppm {
        cfg.random_walk_ppm = non_negative("network.random_walk_ppm", ppm)?;
    }
    if let Some(e) = n.sync_error {
        cfg.sync_error = time("network.sync_error", e)?;
    }
    if let Some(j) = &n.jitter {
        cfg.jitter = jitter(j)?;
    }
    cfg.validate().map_err(tdma_error)?;
    let slot_list = n
        .slot_list
        .as_ref()
        .map(|l| slot_list(l, nodes, channels))
        .transpose()?;
    let decision_lag = secs("decision_lag", n.decision_lag)?.unwrap_or(SimTime::ZERO);
    Ok(TdmaSpec {
        config: cfg,
        slot_list,
        decision_lag,
        sample: n.sample.unwrap_or_default(),
    })
}

fn jitter(j: &JitterFile) -> Result<Jitter> {
    let secs = |key: &str, v: Option<f64>| -> Result<SimTime> {
        let path = format!("network.jitter.{key}");
        let kind = match j.kind {
            JitterKind::Uniform => "uniform",
            JitterKind::Exponential => "exponential",
        };
        let v = v.ok_or_else(|| required(&path, kind))?;
        whole_nanos(&path, v)
    };
    match j.kind {
        JitterKind::Uniform => {
            if j.mean.is_some() {
                return Err(foreign("network.jitter.mean", "uniform"));
            }
            Ok(Jitter::Uniform {
                max: secs("max", j.max)?,
            })
        }
        JitterKind::Exponential => {
            if j.max.is_some() {
                return Err(foreign("network.jitter.max", "exponential"));
            }
            Ok(Jitter::Exponential {
                mean: secs("mean", j.mean)?,
            })
        }
    }
}

fn slot_list(list: &[SlotEntryFile], nodes: usize, channels: &[ChannelSpec]) -> Result<SlotList> {
    let mut entries = Vec::with_capacity(list.len());
    for (i, e) in list.iter().enumerate() {
        let path = format!("network.slot_list[{i}]");
        let entry = match (e.idle, e.node, &e.channel) {
            (Some(true), None, None) => None,
            (Some(true), _, _) => {
                return Err(Error::invalid(
                    path,
                    "an idle slot names no `node` and no `channel`",
                ))
            }
            (Some(false), _, _) => {
                return Err(Error::invalid(
                    format!("{path}.idle"),
                    "is only written as `true` (leave it out for a sending slot)",
                ))
            }
            (None, Some(node), Some(name)) => {
                if node > nodes {
                    return Err(Error::invalid(
                        format!("{path}.node"),
                        format!("unknown node {node} (nodes are 0 (server) to {nodes})"),
                    ));
                }
                let channel = channels
                    .iter()
                    .position(|c| &c.name == name)
                    .ok_or_else(|| {
                        let names: Vec<&str> = channels.iter().map(|c| c.name.as_str()).collect();
                        Error::invalid(
                            format!("{path}.channel"),
                            format!(
                                "unknown channel \"{name}\" (channels: {})",
                                names.join(", ")
                            ),
                        )
                    })?;
                // A data slot is a partition node's (1 to N): the server (0) has no
                // data, and a node none of whose borders the channel carries has
                // nothing to send on it.
                if node == 0 {
                    return Err(Error::invalid(
                        format!("{path}.node"),
                        format!(
                            "node 0 is the server, which sends no data; a slot of channel \
                             \"{name}\" goes to one of nodes 1 to {nodes}"
                        ),
                    ));
                }
                if let Some(borders) = &channels[channel].borders {
                    let n = node - 1;
                    if !borders.iter().any(|&(a, b)| a == n || b == n) {
                        return Err(Error::invalid(
                            format!("{path}.node"),
                            format!(
                                "node {node} has no border on channel \"{name}\", so nothing \
                                 to send on it"
                            ),
                        ));
                    }
                }
                Some(SlotEntry {
                    sender: node,
                    channel,
                })
            }
            (None, None, _) => return Err(required(&format!("{path}.node"), "slot entry")),
            (None, Some(_), None) => {
                return Err(required(&format!("{path}.channel"), "slot entry"))
            }
        };
        entries.push(entry);
    }
    Ok(SlotList { entries })
}

/// A TDMA error as a scenario error: its leading field goes under `network.`
/// (scheduler requests, `tau[i]`, under `channels[i].tau`).
pub(in crate::scenario) fn tdma_error(e: TdmaError) -> Error {
    let text = e.to_string();
    let (field, message) = text.split_once(": ").unwrap_or(("", &text));
    let path = match field.strip_prefix("tau[") {
        Some(rest) => format!("channels[{}].tau", rest.trim_end_matches(']')),
        None if field == "tau" => "channels".into(),
        None => format!("network.{field}"),
    };
    Error::invalid(path, message)
}

/// The finished scenario's TDMA network carries it (the world's check,
/// [`crate::cosim::fit::check_tdma`]: every frame fits its slot, the initial list fits
/// the cycle, every `schedule` entry and a controller's every choice can be scheduled),
/// its findings named by the scenario's fields.
pub(super) fn check_tdma(s: &Scenario) -> Result<()> {
    check_fit(s).map_err(|misfit| match misfit {
        Misfit::Network { error, predicts } => {
            // A frame that is too long under a predicting coupling may fit under
            // `reset`, whose messages carry no force rates and no energy reports: say so.
            let hint = matches!(error, TdmaError::FrameTooLong { .. }) && predicts;
            match tdma_error(error) {
                Error::Invalid { path, message } if hint => Error::Invalid {
                    path,
                    message: format!(
                        "{message}; the partition's coupling sends force rates (and, passive, \
                         energy reports and the waves of its transmission lines) with every \
                         message: widen the slot, raise the link rate, or use \"coupling\": \
                         \"reset\""
                    ),
                },
                other => other,
            }
        }
        Misfit::Schedule { entry, error } => Error::invalid(
            format!("schedule[{entry}].tau"),
            format!("the TDMA cycle cannot serve these periods ({error})"),
        ),
        Misfit::Controller { taus, error } => {
            let shown: Vec<String> = taus.iter().map(|&t| num(t)).collect();
            Error::invalid(
                "controller.tau_min",
                format!(
                    "the TDMA cycle cannot serve the delays [{}] s that the controller may \
                     choose within its bounds ({error})",
                    shown.join(", ")
                ),
            )
        }
    })
}
