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
use crate::fmu::{Causality, Fmu, ModelDescription, ScalarVariable, Value, VarKind, Variability};
use crate::kernel::SimTime;
use crate::scenario::file::{ConnectionFile, FmuFile, StartValue};
use crate::scenario::model::{
    ChannelSpec, ConnectionSpec, DataKind, FmuSpec, FmuStart, FmuVar, Measure, Scenario,
    SignalSink, SignalSource,
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
        // What each end is, for a message refusing two types: `FMU "A" output "y"
        // (Int32)`, `body B1's px (Real)`.
        let from_kind;
        let from = match body_end(&from_path, &c.from, model, true)? {
            Some((body, quantity)) => {
                from_kind = (VarKind::Real, format!("{:?} (a body's Real)", c.from));
                End::Body(body, quantity)
            }
            None => {
                let (f, out) = endpoint(&from_path, &c.from, &names, &loaded)?;
                check_causality(&from_path, &list[f].name, out, Causality::Output)?;
                carried(&from_path, &list[f].name, out)?;
                from_kind = (out.kind, described(&list[f].name, "output", out));
                wired_out[f].push(out.name.clone());
                End::Fmu(f, out.name.clone())
            }
        };
        let to_path = format!("{path}.to");
        let to_kind;
        let to = match body_end(&to_path, &c.to, model, false)? {
            Some((body, axis)) => {
                to_kind = (VarKind::Real, format!("{:?} (a body's Real)", c.to));
                End::Body(body, axis)
            }
            None => {
                let (f, inp) = endpoint(&to_path, &c.to, &names, &loaded)?;
                check_causality(&to_path, &list[f].name, inp, Causality::Input)?;
                carried(&to_path, &list[f].name, inp)?;
                to_kind = (inp.kind, described(&list[f].name, "input", inp));
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
        if from_kind.0 != to_kind.0 {
            return Err(Error::invalid(
                path,
                format!(
                    "{} cannot feed {}: a connection carries a value of one type unchanged \
                     (Real to Real, Integer to Integer, Int64 to Int64, …; FMI 2.0's Real is \
                     FMI 3.0's Float64, its Integer FMI 3.0's Int32)",
                    from_kind.1, to_kind.1
                ),
            ));
        }
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
        carried(&path, &list[f].name, out)?;
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
const BUILT_TEST_FMUS: [&str; 7] = [
    "msd.fmu",
    "pd.fmu",
    "faulty.fmu",
    "msd3.fmu",
    "quirks.fmu",
    "types.fmu",
    "types3.fmu",
];

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
    Ok((i, v))
}

/// `FMU "A" output "y" (Int32)`: a connection end as a message names it.
fn described(fmu: &str, role: &str, v: &ScalarVariable) -> String {
    format!("FMU {fmu:?} {role} {:?} ({})", v.name, v.type_name)
}

/// A connection end or a cost signal is a scalar number or Boolean: what a message
/// carries and a cost measures. A String, a Binary, a Clock or an array is refused,
/// naming the variable and its type.
fn carried(path: &str, fmu: &str, v: &ScalarVariable) -> Result<()> {
    if !v.dimensions.is_empty() {
        return Err(Error::invalid(
            path,
            format!(
                "FMU {fmu:?}: {:?} is a {} array; connections and costs take scalars (an \
                 array output is traced, as {}[1], {}[2], …)",
                v.name, v.type_name, v.name, v.name
            ),
        ));
    }
    if !v.kind.is_numeric() {
        return Err(Error::invalid(
            path,
            format!(
                "FMU {fmu:?}: {:?} is a {}; connections and costs take numbers and Booleans \
                 (a String or Binary output is traced)",
                v.name, v.type_name
            ),
        ));
    }
    Ok(())
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
    for (name, value) in &f.start {
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
        if !v.dimensions.is_empty() {
            return Err(Error::invalid(
                p,
                format!(
                    "FMU {:?}: {name:?} is a {} array; start values are set on scalars",
                    f.name, v.type_name
                ),
            ));
        }
        let value = start_value(&p, &f.name, d, v, value)?;
        start.push(FmuStart {
            name: name.clone(),
            vr: v.value_reference,
            kind: v.kind,
            value,
        });
    }
    let traced: Vec<String> = match &f.trace {
        Some(list) => {
            let mut out = Vec::with_capacity(list.len());
            for (k, name) in list.iter().enumerate() {
                let p = format!("{path}.trace[{k}]");
                let v = variable(&p, &f.name, d, name)?;
                if v.causality != Causality::Output {
                    return Err(Error::invalid(
                        p,
                        format!(
                            "FMU {:?}: {name:?} is not an output (causality {:?}, type {})",
                            f.name, v.causality, v.type_name
                        ),
                    ));
                }
                if v.kind == VarKind::Clock {
                    return Err(Error::invalid(
                        p,
                        format!(
                            "FMU {:?}: {name:?} is a Clock, which is not traced (it needs \
                             event mode)",
                            f.name
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
            .filter(|v| v.causality == Causality::Output && v.kind != VarKind::Clock)
            .map(|v| v.name.clone())
            .collect(),
    };
    let value_of = |v: &ScalarVariable| {
        start
            .iter()
            .find(|s| s.name == v.name)
            .map(|s| s.value.clone())
            .or_else(|| v.start.clone())
            .unwrap_or_else(|| Value::zero(v.kind))
    };
    let shape_of = |v: &ScalarVariable| -> Result<Vec<usize>> {
        d.shape(v).map_err(|e| {
            Error::invalid(
                format!("{path}.trace"),
                format!("FMU {:?}: output {:?}: {e}", f.name, v.name),
            )
        })
    };
    let outputs = d
        .variables
        .iter()
        .filter(|v| traced.contains(&v.name) || wired_out.contains(&v.name))
        .map(|v| {
            Ok(FmuVar {
                name: v.name.clone(),
                vr: v.value_reference,
                kind: v.kind,
                traced: traced.contains(&v.name),
                start: value_of(v),
                shape: shape_of(v)?,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let inputs = d
        .variables
        .iter()
        .filter(|v| wired_in.contains(&v.name))
        .map(|v| FmuVar {
            name: v.name.clone(),
            vr: v.value_reference,
            kind: v.kind,
            traced: false,
            start: value_of(v),
            shape: Vec::new(),
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

/// The start value `given` for the scalar `v` of FMU `fmu` in its type's form, or an
/// error naming the type and what it takes: a number within the type's range for the
/// numeric types (a whole one for integers, 64-bit ones read without loss), a Boolean
/// (or 0/1), a string for a String, hex digits for a Binary.
fn start_value(
    p: &str,
    fmu: &str,
    d: &ModelDescription,
    v: &ScalarVariable,
    given: &StartValue,
) -> Result<Value> {
    let (name, ty) = (&v.name, v.type_name);
    let wrong = |what: &str| {
        let got = match given {
            StartValue::Bool(b) => b.to_string(),
            StartValue::Number(n) => n.to_string(),
            StartValue::Text(t) => format!("{t:?}"),
        };
        Error::invalid(
            p,
            format!("FMU {fmu:?}: {name:?} is {ty}: {what} (got {got})"),
        )
    };
    // A whole number, exact: a JSON integer as written, or a float with no fraction
    // within ±2^53 (where every whole f64 is exact).
    let whole = |n: &serde_json::Number| -> Option<i128> {
        if let Some(i) = n.as_i64() {
            return Some(i.into());
        }
        if let Some(u) = n.as_u64() {
            return Some(u.into());
        }
        n.as_f64()
            .filter(|x| x.fract() == 0.0 && x.abs() <= 9_007_199_254_740_992.0)
            .map(|x| x as i128)
    };
    let int_range = |lo: i128, hi: i128| -> Result<i128> {
        match given {
            StartValue::Number(n) => whole(n)
                .filter(|i| (lo..=hi).contains(i))
                .ok_or_else(|| wrong(&format!("a whole number from {lo} to {hi}"))),
            _ => Err(wrong(&format!("a whole number from {lo} to {hi}"))),
        }
    };
    let signed = |lo: i64, hi: i64| int_range(lo.into(), hi.into()).map(|i| Value::Int(i as i64));
    let unsigned = |hi: u64| int_range(0, hi.into()).map(|i| Value::UInt(i as u64));
    Ok(match v.kind {
        VarKind::Real | VarKind::Float32 => {
            let x = match given {
                StartValue::Number(n) => n.as_f64(),
                _ => None,
            }
            .filter(|x| x.is_finite())
            .ok_or_else(|| wrong("a finite number"))?;
            if v.kind == VarKind::Real {
                Value::Float(x)
            } else if (x as f32).is_finite() {
                Value::Float32(x as f32)
            } else {
                return Err(wrong("a number within Float32's range"));
            }
        }
        VarKind::Boolean => match given {
            StartValue::Bool(b) => Value::Bool(*b),
            StartValue::Number(n) if whole(n) == Some(0) => Value::Bool(false),
            StartValue::Number(n) if whole(n) == Some(1) => Value::Bool(true),
            _ => return Err(wrong("true or false (or 0 or 1)")),
        },
        VarKind::String => match given {
            StartValue::Text(t) if !t.contains('\0') => Value::Text(t.clone()),
            _ => return Err(wrong("a JSON string without NUL characters")),
        },
        VarKind::Binary => match given {
            StartValue::Text(t) => Value::Bytes(
                crate::fmu::value::parse_hex(t)
                    .map_err(|e| wrong(&format!("a string of hex bytes ({e})")))?,
            ),
            _ => return Err(wrong("a string of hex bytes (\"00ff\")")),
        },
        // FMI 2.0 passes an Enumeration as an int, FMI 3.0 as an Int64.
        VarKind::Enumeration if d.is_fmi3() => signed(i64::MIN, i64::MAX)?,
        VarKind::Integer | VarKind::Enumeration => signed(i32::MIN.into(), i32::MAX.into())?,
        VarKind::Int8 => signed(i8::MIN.into(), i8::MAX.into())?,
        VarKind::Int16 => signed(i16::MIN.into(), i16::MAX.into())?,
        VarKind::Int64 => signed(i64::MIN, i64::MAX)?,
        VarKind::UInt8 => unsigned(u8::MAX.into())?,
        VarKind::UInt16 => unsigned(u16::MAX.into())?,
        VarKind::UInt32 => unsigned(u32::MAX.into())?,
        VarKind::UInt64 => unsigned(u64::MAX)?,
        VarKind::Clock => return Err(wrong("not set by dsmcosim (a Clock needs event mode)")),
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
