//! The FMU stage: `fmus` and `connections` checked against each FMU's model description.
//!
//! Each FMU is unpacked and its description read here, once, so that a run never starts
//! with a variable that does not exist, a connection from an input, or a binary for
//! another platform: every such error names the FMU, the variable and what is wrong.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::bodies::Ids;
use super::checks::{num, whole_nanos};
use crate::error::{Error, Result};
use crate::fmu::{Causality, Fmu, ModelDescription, ScalarVariable, VarKind, Variability};
use crate::kernel::SimTime;
use crate::scenario::file::{ConnectionFile, FmuFile};
use crate::scenario::model::{
    ChannelSpec, ConnectionSpec, DataKind, FmuSpec, FmuStart, FmuValueKind, FmuVar, Measure,
    Scenario, SignalSink, SignalSource,
};

/// At most this many FMUs in a scenario: each is unpacked into its own directory and
/// holds a loaded library (and one instance per fork).
pub const MAX_FMUS: usize = 64;

/// At most this many connections (each is a route sampled every τ).
pub const MAX_CONNECTIONS: usize = 4096;

/// The `fmus` and `connections` sections: each FMU loaded and described, each
/// connection matched to an output, an input and a channel.
pub(super) struct Fmus {
    pub specs: Vec<FmuSpec>,
    pub connections: Vec<ConnectionSpec>,
    /// `measurement.signals` as (FMU, index into its outputs).
    pub cost_signals: Vec<(usize, usize)>,
}

pub(super) fn fmus(
    list: &[FmuFile],
    connections: &[ConnectionFile],
    model: &ModelView,
    cost: Option<&[String]>,
    base: Option<&Path>,
    (dt, duration): (SimTime, SimTime),
    channels: &[ChannelSpec],
) -> Result<Fmus> {
    if list.len() > MAX_FMUS {
        return Err(Error::invalid(
            "fmus",
            format!("{} FMUs; at most {MAX_FMUS}", list.len()),
        ));
    }
    if connections.len() > MAX_CONNECTIONS {
        return Err(Error::invalid(
            "connections",
            format!(
                "{} connections; at most {MAX_CONNECTIONS}",
                connections.len()
            ),
        ));
    }
    if list.is_empty() && !connections.is_empty() {
        return Err(Error::invalid(
            "connections",
            "connect FMUs (or FMUs and bodies), and the scenario has no `fmus`",
        ));
    }
    let mut names = BTreeMap::new();
    let mut loaded = Vec::with_capacity(list.len());
    for (i, f) in list.iter().enumerate() {
        let path = format!("fmus[{i}]");
        name(&format!("{path}.name"), &f.name)?;
        if let Some(first) = names.insert(f.name.as_str(), i) {
            return Err(Error::invalid(
                format!("{path}.name"),
                format!("duplicate name {:?} (also fmus[{first}].name)", f.name),
            ));
        }
        loaded.push(load(&path, f, base, dt, duration)?);
    }
    // Which variables the connections use, per FMU, before the specs list them.
    let mut wired_out: Vec<Vec<String>> = vec![Vec::new(); list.len()];
    let mut wired_in: Vec<Vec<String>> = vec![Vec::new(); list.len()];
    let mut ends = Vec::with_capacity(connections.len());
    let mut fed: BTreeMap<String, usize> = BTreeMap::new();
    // (FMU, value reference) of each input a connection feeds: the connection and the
    // input's name. Two inputs that share a value reference are one variable in the
    // FMU, so two connections to them would overwrite each other.
    let mut fed_refs: BTreeMap<(usize, u32), (usize, String)> = BTreeMap::new();
    for (i, c) in connections.iter().enumerate() {
        let path = format!("connections[{i}]");
        let from_path = format!("{path}.from");
        let from = match body_end(&from_path, &c.from, model, true)? {
            Some((body, quantity)) => End::Body(body, quantity),
            None => {
                let (f, out) = endpoint(&from_path, &c.from, &names, &loaded)?;
                check_causality(&from_path, &list[f].name, out, Causality::Output)?;
                wired_out[f].push(out.name.clone());
                End::Fmu(f, out.name.clone())
            }
        };
        let to_path = format!("{path}.to");
        let to = match body_end(&to_path, &c.to, model, false)? {
            Some((body, axis)) => End::Body(body, axis),
            None => {
                let (f, inp) = endpoint(&to_path, &c.to, &names, &loaded)?;
                check_causality(&to_path, &list[f].name, inp, Causality::Input)?;
                let vr = inp.value_reference;
                if let Some((first, other)) = fed_refs.get(&(f, vr)) {
                    if *other != inp.name {
                        return Err(Error::invalid(
                            to_path,
                            format!(
                                "input {:?} of FMU {:?} has value reference {vr}, as input \
                                 {other:?} fed by connections[{first}] does: the FMU holds \
                                 one value for both, so one of the two connections would be \
                                 lost",
                                inp.name, list[f].name
                            ),
                        ));
                    }
                }
                fed_refs.insert((f, vr), (i, inp.name.clone()));
                wired_in[f].push(inp.name.clone());
                End::Fmu(f, inp.name.clone())
            }
        };
        if let Some(first) = fed.insert(c.to.clone(), i) {
            return Err(Error::invalid(
                to_path,
                format!("{:?} is already fed by connections[{first}]", c.to),
            ));
        }
        let channel = channels
            .iter()
            .position(|ch| ch.name == c.channel)
            .ok_or_else(|| {
                let known: Vec<&str> = channels.iter().map(|c| c.name.as_str()).collect();
                Error::invalid(
                    format!("{path}.channel"),
                    format!(
                        "unknown channel {:?} (channels: {})",
                        c.channel,
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    ),
                )
            })?;
        if channels[channel]
            .kinds
            .as_ref()
            .is_some_and(|k| !k.contains(&DataKind::Signal))
        {
            return Err(Error::invalid(
                format!("{path}.channel"),
                format!("channel {:?} lists its kinds without \"signal\"", c.channel),
            ));
        }
        ends.push((from, to, channel));
    }
    let mut cost_ends = Vec::new();
    for (i, text) in cost.unwrap_or(&[]).iter().enumerate() {
        let path = format!("measurement.signals[{i}]");
        if list.is_empty() {
            return Err(Error::invalid(
                path,
                "names an FMU output, and the scenario has no `fmus`",
            ));
        }
        let (f, out) = endpoint(&path, text, &names, &loaded)?;
        check_causality(&path, &list[f].name, out, Causality::Output)?;
        if cost_ends
            .iter()
            .any(|(g, n): &(usize, String)| *g == f && *n == out.name)
        {
            return Err(Error::invalid(path, format!("{text:?} is listed twice")));
        }
        wired_out[f].push(out.name.clone());
        cost_ends.push((f, out.name.clone()));
    }
    if cost.is_some_and(<[String]>::is_empty) {
        return Err(Error::invalid(
            "measurement.signals",
            "must name at least one FMU output (got []); leave it out for the links' cost",
        ));
    }
    let mut specs = Vec::with_capacity(list.len());
    for (i, (f, (fmu, path))) in list.iter().zip(loaded).enumerate() {
        specs.push(spec(
            &format!("fmus[{i}]"),
            f,
            &fmu,
            path,
            &wired_out[i],
            &wired_in[i],
            dt,
        )?);
    }
    let connections = ends
        .into_iter()
        .map(|(from, to, channel)| ConnectionSpec {
            from: match from {
                End::Fmu(fmu, name) => SignalSource::Fmu {
                    fmu,
                    output: index_of(&specs[fmu].outputs, &name),
                },
                End::Body(body, quantity) => SignalSource::Body { body, quantity },
            },
            to: match to {
                End::Fmu(fmu, name) => SignalSink::Fmu {
                    fmu,
                    input: index_of(&specs[fmu].inputs, &name),
                },
                End::Body(body, axis) => SignalSink::BodyForce { body, axis },
            },
            channel,
        })
        .collect();
    let cost_signals = cost_ends
        .into_iter()
        .map(|(f, name)| (f, index_of(&specs[f].outputs, &name)))
        .collect();
    Ok(Fmus {
        specs,
        connections,
        cost_signals,
    })
}

/// A connection end as validated: an FMU's variable, or a body's quantity or axis.
enum End {
    Fmu(usize, String),
    Body(usize, usize),
}

/// What the FMU stage needs of the multibody model: body ids, and whether it is split.
pub(super) struct ModelView<'a> {
    pub ids: &'a Ids,
    pub partitioned: bool,
}

/// The body quantities a connection reads (`B<id>.px` …) and the force axes it sets.
const BODY_OUTPUTS: [&str; 6] = ["px", "py", "pz", "vx", "vy", "vz"];
const BODY_INPUTS: [&str; 3] = ["fx", "fy", "fz"];

/// `B<id>.<q>`: a body end (body index, quantity or axis), or `None` for an FMU end.
fn body_end(
    path: &str,
    text: &str,
    model: &ModelView,
    output: bool,
) -> Result<Option<(usize, usize)>> {
    let Some((head, q)) = text.split_once('.') else {
        return Ok(None);
    };
    let Some(id) = head
        .strip_prefix('B')
        .filter(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
    else {
        return Ok(None);
    };
    let id: u32 = id
        .parse()
        .map_err(|_| Error::invalid(path, format!("body id out of range in {text:?}")))?;
    let body = model.ids.index(path, id)?;
    let (names, what): (&[&str], &str) = if output {
        (
            &BODY_OUTPUTS,
            "a source reads a body's px, py, pz, vx, vy or vz",
        )
    } else {
        (&BODY_INPUTS, "a target sets a body's force fx, fy or fz")
    };
    let Some(k) = names.iter().position(|n| *n == q) else {
        return Err(Error::invalid(path, format!("{what} (got {text:?})")));
    };
    if !output && model.partitioned {
        return Err(Error::invalid(
            path,
            format!(
                "a force on a body of a partitioned model is not supported: the other \
                 nodes' coupling would not see it (got {text:?}); run the model on one node"
            ),
        ));
    }
    Ok(Some((body, k)))
}

fn index_of(vars: &[FmuVar], name: &str) -> usize {
    vars.iter()
        .position(|v| v.name == name)
        .expect("ok: every wired variable is listed in its FMU's spec")
}

/// An FMU's name: non-empty letters, digits and `_`.
fn name(path: &str, name: &str) -> Result<()> {
    if name.is_empty() {
        return Err(Error::invalid(path, "must not be empty"));
    }
    if name
        .strip_prefix('B')
        .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
    {
        return Err(Error::invalid(
            path,
            format!("{name:?} reads as a body (B<id>.px …); give the FMU another name"),
        ));
    }
    if !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(Error::invalid(
            path,
            format!(
                "must be made of letters, digits and _ (got {name:?}); it names trace \
                 columns and connection ends"
            ),
        ));
    }
    Ok(())
}

/// The FMUs that `cargo run --release --example build_fmus -- DIR` builds from
/// `tests/fmus/` (`TEST_FMUS` of `tests/support/fmu_build.rs`): the shipped scenes read
/// them from `scenarios/fmu/`, which a fresh clone does not hold.
const BUILT_TEST_FMUS: [&str; 5] = ["msd.fmu", "pd.fmu", "faulty.fmu", "msd3.fmu", "quirks.fmu"];

/// For a missing file that is one of [`BUILT_TEST_FMUS`], how to build it into the
/// folder it is looked for in; else nothing.
fn build_hint(resolved: &Path) -> String {
    let name = resolved.file_name().and_then(|n| n.to_str());
    if resolved.exists() || !name.is_some_and(|n| BUILT_TEST_FMUS.contains(&n)) {
        return String::new();
    }
    let dir = match resolved.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.display().to_string(),
        _ => ".".to_string(),
    };
    format!(
        "; it is one of dsmcosim's test FMUs, which a checkout does not hold: build them \
         into that folder with `cargo run --release --example build_fmus -- {dir}` (needs a C \
         compiler)"
    )
}

/// Unpacks and describes `fmus[i]`, checking its node and step.
fn load(
    path: &str,
    f: &FmuFile,
    base: Option<&Path>,
    dt: SimTime,
    duration: SimTime,
) -> Result<(Fmu, PathBuf)> {
    if f.node == 0 {
        return Err(Error::invalid(
            format!("{path}.node"),
            "nodes are numbered from 1 (got 0)",
        ));
    }
    if f.node > crate::scenario::model::MAX_FMU_NODE {
        return Err(Error::invalid(
            format!("{path}.node"),
            format!(
                "node {}; at most {}",
                f.node,
                crate::scenario::model::MAX_FMU_NODE
            ),
        ));
    }
    if let Some(step) = f.step {
        let p = format!("{path}.step");
        let h = whole_nanos(&p, step)?;
        let (h, d) = (h.as_nanos(), dt.as_nanos());
        let fits = h > 0 && (d % h == 0 || h % d == 0);
        if !fits {
            return Err(Error::invalid(
                p,
                format!(
                    "must divide dt or be a whole multiple of it (got {} s with dt {} s)",
                    num(step),
                    num(dt.as_secs_f64())
                ),
            ));
        }
        if !duration.as_nanos().is_multiple_of(h) {
            return Err(Error::invalid(
                p,
                format!(
                    "must divide the duration {} s (got {} s)",
                    num(duration.as_secs_f64()),
                    num(step)
                ),
            ));
        }
    }
    let file = Path::new(&f.path);
    let resolved = match base {
        Some(dir) if file.is_relative() => dir.join(file),
        _ => file.to_path_buf(),
    };
    let fmu = Fmu::load(&f.name, &resolved).map_err(|e| {
        Error::invalid(
            format!("{path}.path"),
            format!("{e}{}", build_hint(&resolved)),
        )
    })?;
    Ok((fmu, resolved))
}

/// `<fmu>.<variable>` of a connection end.
fn endpoint<'a>(
    path: &str,
    text: &str,
    names: &BTreeMap<&str, usize>,
    loaded: &'a [(Fmu, PathBuf)],
) -> Result<(usize, &'a ScalarVariable)> {
    let Some((fmu, var)) = text.split_once('.') else {
        return Err(Error::invalid(
            path,
            format!("must read <fmu>.<variable> (got {text:?})"),
        ));
    };
    let Some(&i) = names.get(fmu) else {
        let known: Vec<&str> = names.keys().copied().collect();
        return Err(Error::invalid(
            path,
            format!("unknown FMU {fmu:?} (fmus: {})", known.join(", ")),
        ));
    };
    let description = loaded[i].0.description();
    let v = variable(path, fmu, description, var)?;
    if v.kind != VarKind::Real {
        return Err(Error::invalid(
            path,
            format!(
                "FMU {fmu:?}: variable {var:?} is {}; connections carry Real variables \
                 (FMI 3.0: scalar Float64)",
                v.kind
            ),
        ));
    }
    Ok((i, v))
}

/// A variable by name, or an error naming the FMU and the nearest names.
fn variable<'a>(
    path: &str,
    fmu: &str,
    d: &'a ModelDescription,
    var: &str,
) -> Result<&'a ScalarVariable> {
    d.variable(var).ok_or_else(|| {
        let nearest = d
            .variables
            .iter()
            .map(|v| (strsim::levenshtein(&v.name, var), v.name.as_str()))
            .min();
        let hint = match nearest {
            Some((dist, n)) if dist <= 3 => format!("; did you mean {n:?}?"),
            _ => String::new(),
        };
        Error::invalid(path, format!("FMU {fmu:?} has no variable {var:?}{hint}"))
    })
}

fn check_causality(path: &str, fmu: &str, v: &ScalarVariable, want: Causality) -> Result<()> {
    if v.causality != want {
        return Err(Error::invalid(
            path,
            format!(
                "FMU {fmu:?}: variable {:?} has causality {:?}; a connection {} an {:?}",
                v.name,
                v.causality,
                if want == Causality::Output {
                    "reads"
                } else {
                    "writes"
                },
                want
            ),
        ));
    }
    if want == Causality::Input && v.variability == Variability::Constant {
        return Err(Error::invalid(
            path,
            format!("FMU {fmu:?}: input {:?} is constant", v.name),
        ));
    }
    Ok(())
}

/// The validated spec of one FMU.
fn spec(
    path: &str,
    f: &FmuFile,
    fmu: &Fmu,
    resolved: PathBuf,
    wired_out: &[String],
    wired_in: &[String],
    dt: SimTime,
) -> Result<FmuSpec> {
    let d = fmu.description();
    let cs = d
        .co_simulation
        .as_ref()
        .expect("ok: Fmu::load refuses an FMU without co-simulation");
    let mut start = Vec::with_capacity(f.start.len());
    for (name, &value) in &f.start {
        let p = format!("{path}.start.{name}");
        let v = variable(&p, &f.name, d, name)?;
        if !matches!(v.causality, Causality::Parameter | Causality::Input) {
            return Err(Error::invalid(
                p,
                format!(
                    "FMU {:?}: {name:?} has causality {:?}; only parameters and inputs \
                     take start values",
                    f.name, v.causality
                ),
            ));
        }
        if v.variability == Variability::Constant {
            return Err(Error::invalid(
                p,
                format!("FMU {:?}: {name:?} is a constant", f.name),
            ));
        }
        if !value.is_finite() {
            return Err(Error::invalid(
                p,
                format!("must be finite (got {})", num(value)),
            ));
        }
        let kind = match v.kind {
            VarKind::Real => FmuValueKind::Real,
            VarKind::Integer | VarKind::Enumeration => FmuValueKind::Integer,
            VarKind::Boolean => FmuValueKind::Boolean,
            VarKind::String => {
                return Err(Error::invalid(
                    p,
                    format!(
                        "FMU {:?}: {name:?} is a String; start values are numbers",
                        f.name
                    ),
                ))
            }
            VarKind::Other(_) | VarKind::Array(_) => {
                return Err(Error::invalid(
                    p,
                    format!(
                        "FMU {:?}: {name:?} is {}; start values are set on Real, Integer, \
                         Boolean and Enumeration scalars only (FMI 3.0: Float64, Int32, \
                         Boolean, Enumeration)",
                        f.name, v.kind
                    ),
                ))
            }
        };
        let whole = value.fract() == 0.0 && value.abs() <= i32::MAX as f64;
        if kind == FmuValueKind::Integer && !whole {
            return Err(Error::invalid(
                p,
                format!(
                    "FMU {:?}: {name:?} is an Integer (got {})",
                    f.name,
                    num(value)
                ),
            ));
        }
        if kind == FmuValueKind::Boolean && value != 0.0 && value != 1.0 {
            return Err(Error::invalid(
                p,
                format!(
                    "FMU {:?}: {name:?} is a Boolean: 0 or 1 (got {})",
                    f.name,
                    num(value)
                ),
            ));
        }
        start.push(FmuStart {
            name: name.clone(),
            vr: v.value_reference,
            kind,
            value,
        });
    }
    let traced: Vec<String> = match &f.trace {
        Some(list) => {
            let mut out = Vec::with_capacity(list.len());
            for (k, name) in list.iter().enumerate() {
                let p = format!("{path}.trace[{k}]");
                let v = variable(&p, &f.name, d, name)?;
                if v.causality != Causality::Output || v.kind != VarKind::Real {
                    return Err(Error::invalid(
                        p,
                        format!(
                            "FMU {:?}: {name:?} is not a Real output (causality {:?}, type \
                             {})",
                            f.name, v.causality, v.kind
                        ),
                    ));
                }
                if out.contains(name) {
                    return Err(Error::invalid(p, format!("{name:?} is listed twice")));
                }
                out.push(name.clone());
            }
            out
        }
        None => d
            .variables
            .iter()
            .filter(|v| v.causality == Causality::Output && v.kind == VarKind::Real)
            .map(|v| v.name.clone())
            .collect(),
    };
    let value_of = |v: &ScalarVariable| f.start.get(&v.name).copied().or(v.start).unwrap_or(0.0);
    let outputs = d
        .variables
        .iter()
        .filter(|v| traced.contains(&v.name) || wired_out.contains(&v.name))
        .map(|v| FmuVar {
            name: v.name.clone(),
            vr: v.value_reference,
            traced: traced.contains(&v.name),
            start: value_of(v),
        })
        .collect();
    let inputs = d
        .variables
        .iter()
        .filter(|v| wired_in.contains(&v.name))
        .map(|v| FmuVar {
            name: v.name.clone(),
            vr: v.value_reference,
            traced: false,
            start: value_of(v),
        })
        .collect();
    let step = match f.step {
        Some(s) => whole_nanos(&format!("{path}.step"), s)?,
        None => dt,
    };
    Ok(FmuSpec {
        name: f.name.clone(),
        path: resolved,
        hash: fmu.hash().to_string(),
        node: f.node - 1,
        step,
        fmi_version: d.fmi_version.clone(),
        model_identifier: cs.model_identifier.clone(),
        guid: d.guid.clone(),
        generation_tool: d.generation_tool.clone(),
        can_get_set_state: cs.can_get_and_set_fmu_state,
        can_serialize_state: cs.can_serialize_fmu_state,
        only_once_per_process: cs.can_be_instantiated_only_once_per_process,
        start,
        outputs,
        inputs,
        logging: f.logging,
    })
}

/// A controller that measures on forks (lookahead, baselines) needs every FMU to hand
/// over its state: refused here, naming the FMU and the capability it lacks, rather than
/// at the first window.
pub(super) fn forks_possible(s: &Scenario) -> Result<()> {
    let Some(c) = &s.controller else {
        return Ok(());
    };
    let (path, why) = if c.measure == Measure::Lookahead {
        (
            "controller.measure",
            "lookahead measurement runs every candidate on a fork",
        )
    } else if !c.baselines.is_empty() {
        ("controller.baselines", "baselines are measured on forks")
    } else {
        return Ok(());
    };
    for f in &s.fmus {
        let missing = if !f.can_get_set_state {
            "canGetAndSetFMUstate"
        } else if !f.can_serialize_state {
            "canSerializeFMUstate"
        } else if f.only_once_per_process {
            "several instances per process (it declares canBeInstantiatedOnlyOncePerProcess)"
        } else {
            continue;
        };
        return Err(Error::invalid(
            path,
            format!(
                "{why}, and FMU {:?} cannot be forked: it lacks {missing}; use \
                 \"measure\": \"online\" without baselines",
                f.name
            ),
        ));
    }
    Ok(())
}
