//! The channel stage: `network` and `channels` checked, and every message route of the
//! partition matched to exactly one channel.
//!
//! A route is a kind of data crossing one border (an unordered pair of nodes joined by
//! at least one border link): states flow from a body's owner to the node ghosting it,
//! forces back from the link's owner, so every border carries both kinds.

use std::collections::{BTreeMap, BTreeSet};

use super::checks::{num, positive, time, whole_nanos};
use crate::error::{Error, Result};
use crate::kernel::SimTime;
use crate::scenario::file::{ChannelFile, DataKindFile};
use crate::scenario::model::{ChannelSpec, DataKind, LinkSpec, PartitionSpec};

/// The borders of a partition: node pairs (0-based, smaller first) joined by at least
/// one link, in order.
pub(super) fn borders(p: &PartitionSpec, links: &[LinkSpec]) -> BTreeSet<(usize, usize)> {
    links
        .iter()
        .map(|l| (p.node_of[l.a], p.node_of[l.b]))
        .filter(|(a, b)| a != b)
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect()
}

/// A border as messages name it: `2–3` (1-based nodes).
fn border_name((a, b): (usize, usize)) -> String {
    format!("{}–{}", a + 1, b + 1)
}

/// The `channels` section: each channel checked, then the routing (every route of the
/// partition on exactly one channel, every channel used).
pub(super) fn channels(
    list: &[ChannelFile],
    partition: Option<&PartitionSpec>,
    links: &[LinkSpec],
    dt: SimTime,
    signals: &[&str],
) -> Result<Vec<ChannelSpec>> {
    if partition.is_none() && !list.is_empty() && signals.is_empty() {
        return Err(Error::invalid(
            "channels",
            format!(
                "needs a `partition` section or `connections` (got {} channel(s) on a \
                 monolithic model)",
                list.len()
            ),
        ));
    }
    let (nodes, borders) = match partition {
        Some(p) => (p.nodes, borders(p, links)),
        None => (1, BTreeSet::new()),
    };
    if list.is_empty() && !borders.is_empty() {
        let border_links = partition.map_or(0, |p| {
            links
                .iter()
                .filter(|l| p.node_of[l.a] != p.node_of[l.b])
                .count()
        });
        return Err(Error::invalid(
            "channels",
            format!(
                "a partition with border links needs channels (got none; {border_links} \
                 border links join {} pairs of nodes)",
                borders.len()
            ),
        ));
    }
    let mut names = BTreeMap::new();
    let mut specs = Vec::with_capacity(list.len());
    for (i, c) in list.iter().enumerate() {
        let path = format!("channels[{i}]");
        if let Some(first) = names.insert(c.name.as_str(), i) {
            return Err(Error::invalid(
                format!("{path}.name"),
                format!("duplicate name {:?} (also channels[{first}].name)", c.name),
            ));
        }
        specs.push(channel(&path, c, nodes, &borders, dt)?);
    }
    routes(&specs, &borders, signals)?;
    Ok(specs)
}

/// One channel: values checked, borders 0-based.
fn channel(
    path: &str,
    c: &ChannelFile,
    nodes: usize,
    borders: &BTreeSet<(usize, usize)>,
    dt: SimTime,
) -> Result<ChannelSpec> {
    let name_path = format!("{path}.name");
    if c.name.is_empty() {
        return Err(Error::invalid(name_path, "must not be empty"));
    }
    if !c
        .name
        .chars()
        .all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
    {
        return Err(Error::invalid(
            name_path,
            format!(
                "must be made of letters, digits and _ (got {:?}); it becomes part of CSV \
                 column names",
                c.name
            ),
        ));
    }
    let tau_path = format!("{path}.tau");
    positive(&tau_path, c.tau)?;
    let tau = time(&tau_path, c.tau)?;
    // Any period of at least one step: a channel samples at the first step at or after
    // each multiple of it (method §4).
    if tau < dt {
        return Err(Error::invalid(
            tau_path,
            format!(
                "must be at least one step, dt = {} s (got {} s)",
                num(dt.as_secs_f64()),
                num(c.tau)
            ),
        ));
    }
    let latency = match c.latency {
        Some(secs) => Some(whole_nanos(&format!("{path}.latency"), secs)?),
        None => None,
    };
    let phase = match c.phase {
        Some(secs) => whole_nanos(&format!("{path}.phase"), secs)?,
        None => SimTime::ZERO,
    };
    if phase >= tau {
        return Err(Error::invalid(
            format!("{path}.phase"),
            format!(
                "must be below the period τ = {} s (got {} s)",
                num(tau.as_secs_f64()),
                num(phase.as_secs_f64())
            ),
        ));
    }
    // Within the magnitude range a bandwidth k/τ (τ ≥ 1 ns) and its sum stay finite: at
    // k = 1e308 `bandwidth` was inf in epochs.csv and null in summary.json.
    let k = super::checks::positive_magnitude(&format!("{path}.k"), c.k)?;
    let borders = match &c.borders {
        Some(list) => Some(channel_borders(
            &format!("{path}.borders"),
            list,
            nodes,
            borders,
        )?),
        None => None,
    };
    let kinds = match &c.kinds {
        Some(list) => Some(kinds(&format!("{path}.kinds"), list)?),
        None => None,
    };
    Ok(ChannelSpec {
        name: c.name.clone(),
        tau,
        latency,
        phase,
        k,
        borders,
        kinds,
    })
}

/// `channels[i].borders`: existing node pairs that share a border link, no repeats.
fn channel_borders(
    path: &str,
    list: &[[usize; 2]],
    nodes: usize,
    borders: &BTreeSet<(usize, usize)>,
) -> Result<Vec<(usize, usize)>> {
    if list.is_empty() {
        return Err(Error::invalid(
            path,
            "must list at least one border (got []); leave it out for every border",
        ));
    }
    let mut seen = BTreeMap::new();
    let mut out = Vec::with_capacity(list.len());
    for (j, &[a, b]) in list.iter().enumerate() {
        let entry = format!("{path}[{j}]");
        for n in [a, b] {
            if n == 0 || n > nodes {
                return Err(Error::invalid(
                    entry,
                    format!("no node {n} (the partition has nodes 1 to {nodes})"),
                ));
            }
        }
        if a == b {
            return Err(Error::invalid(
                entry,
                format!("a border joins two different nodes (got [{a}, {b}])"),
            ));
        }
        let border = (a.min(b) - 1, a.max(b) - 1);
        if !borders.contains(&border) {
            return Err(Error::invalid(
                entry,
                format!("nodes {a} and {b} share no border link"),
            ));
        }
        if let Some(first) = seen.insert(border, j) {
            return Err(Error::invalid(
                entry,
                format!(
                    "border {} is listed twice (also {path}[{first}])",
                    border_name(border)
                ),
            ));
        }
        out.push(border);
    }
    Ok(out)
}

/// `connections[k].channel` names `name`, which no channel has: the channels listed,
/// and the nearest name when one is close (at most a third of its letters differ, at
/// least one, as for a mistyped field).
fn unknown_channel(k: usize, name: &str, channels: &[ChannelSpec]) -> Error {
    let known: Vec<&str> = channels.iter().map(|c| c.name.as_str()).collect();
    let nearest = known
        .iter()
        .map(|c| (strsim::damerau_levenshtein(name, c), *c))
        .min();
    let hint = match nearest {
        Some((d, c)) if d <= (c.chars().count() / 3).max(1) => format!("; did you mean {c:?}?"),
        _ => String::new(),
    };
    Error::invalid(
        format!("connections[{k}].channel"),
        format!(
            "unknown channel {name:?} (channels: {}){hint}",
            if known.is_empty() {
                "none".to_string()
            } else {
                known.join(", ")
            }
        ),
    )
}

/// `channels[i].kinds`: non-empty, no repeats.
fn kinds(path: &str, list: &[DataKindFile]) -> Result<Vec<DataKind>> {
    if list.is_empty() {
        return Err(Error::invalid(
            path,
            "must list at least one kind (got []); leave it out for both",
        ));
    }
    let mut out: Vec<DataKind> = Vec::with_capacity(list.len());
    for (j, k) in list.iter().enumerate() {
        let kind = match k {
            DataKindFile::State => DataKind::State,
            DataKindFile::Force => DataKind::Force,
            DataKindFile::Signal => DataKind::Signal,
        };
        if out.contains(&kind) {
            return Err(Error::invalid(
                format!("{path}[{j}]"),
                format!("{:?} is listed twice", kind.name()),
            ));
        }
        out.push(kind);
    }
    Ok(out)
}

/// Every route on exactly one channel, and every channel on at least one route.
fn routes(
    channels: &[ChannelSpec],
    borders: &BTreeSet<(usize, usize)>,
    signals: &[&str],
) -> Result<()> {
    // A connection naming no channel first: otherwise a misspelt name would surface as
    // the channel it meant carrying no message.
    for (k, name) in signals.iter().enumerate() {
        if !channels.iter().any(|c| c.name == *name) {
            return Err(unknown_channel(k, name, channels));
        }
    }
    let named = |i: usize| format!("channels[{i}] {:?}", channels[i].name);
    let mut used: Vec<bool> = channels
        .iter()
        .map(|c| signals.contains(&c.name.as_str()))
        .collect();
    for &(a, b) in borders {
        for kind in [DataKind::State, DataKind::Force] {
            let on: Vec<usize> = (0..channels.len())
                .filter(|&i| channels[i].carries(kind, a, b))
                .collect();
            let what = format!(
                "{} messages across border {}",
                kind.name(),
                border_name((a, b))
            );
            match on.as_slice() {
                [] => {
                    return Err(Error::invalid(
                        "channels",
                        format!("no channel carries {what}"),
                    ))
                }
                [i] => used[*i] = true,
                [i, j, ..] => {
                    return Err(Error::invalid(
                        "channels",
                        format!(
                            "{what} would travel on both {} and {}; each must travel on \
                             exactly one channel",
                            named(*i),
                            named(*j)
                        ),
                    ))
                }
            }
        }
    }
    if let Some(i) = used.iter().position(|&u| !u) {
        return Err(Error::invalid(
            format!("channels[{i}]"),
            format!(
                "channel {:?} carries no message (no border link or connection uses it)",
                channels[i].name
            ),
        ));
    }
    Ok(())
}
