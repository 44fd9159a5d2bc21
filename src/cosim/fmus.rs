//! FMUs as nodes of the co-simulation: each steps in lock-step with the kernel, its
//! connected outputs sampled by channels and its inputs set by deliveries.
//!
//! The call sequence per FMU, as libcosim's slave documents its own: instantiate,
//! `fmi2SetupExperiment(0)`, the start values, enter and exit initialization (the
//! outputs at 0 are read there), then per communication step: the held inputs set,
//! `fmi2DoStep(t, h)`, the outputs read. Outputs of a step that ends at `t + h` become
//! visible to channels and the trace only when the lock-step reaches `t + h`, so no
//! one ever sees an FMU's future; an input delivered between two communication points
//! is held until the next (zero-order hold, the co-simulation's convention). The calls
//! are named here as FMI 2.0 names them; an FMI 3.0 FMU gets its version's calls through
//! the same [`Instance`] methods (`fmi3EnterInitializationMode` with the start time,
//! `fmi3DoStep`, …), so nothing here depends on the version.
//!
//! An FMU that asks to end the simulation ([`StepEnd::Stopped`]) is stepped no more;
//! the world ends the run at the last communication point it completed
//! ([`FmuUnit::stop_request`]).
//!
//! A fork (`Clone`) or a checkpoint carries the FMU's state as bytes
//! (`fmi2SerializeFMUstate`); the fork instantiates its own instance on its first event
//! and restores them. An FMU without `canGetAndSetFMUstate` and `canSerializeFMUstate`
//! cannot be forked: the fork's first event fails naming the FMU and the capability,
//! so lookahead measurement and checkpoints are refused while online measurement works.

use std::sync::{Arc, Mutex};

use super::unit::Unit;
use crate::error::{Divergence, Error, Place, Result};
use crate::fmu::{Fmu, Instance, StepEnd, Value, VarKind};
use crate::kernel::SimTime;
use crate::network::route::Route;
use crate::network::{Message, Payload};
use crate::scenario::model::{FmuSpec, FmuVar, Scenario, SignalSink, SignalSource};

/// One FMU's place in the world: its live instance (not in a fork until its first
/// event) and what the co-simulation holds of it.
pub struct FmuUnit {
    /// The FMU's communication time: it has stepped up to here.
    time: SimTime,
    /// The outputs channels and the trace see (those at the last communication point
    /// the lock-step has reached), in `FmuSpec::outputs` order: each output's values
    /// (one for a scalar, an array's elements in row-major order).
    published: Vec<Vec<Value>>,
    /// The outputs at `time`, published when the lock-step reaches it.
    pending: Vec<Vec<Value>>,
    /// The inputs as last delivered (their start values before), in `FmuSpec::inputs`
    /// order.
    inputs: Vec<Value>,
    /// A state to restore when the instance is made (a fork's or a resumed run's).
    saved: Option<Arc<Vec<u8>>>,
    /// Why this fork cannot run (its source could not hand over its state).
    broken: Option<String>,
    /// The FMU asked to end the simulation: the communication point it completed last,
    /// and how it asked. It is stepped no more.
    stop: Option<(SimTime, String)>,
    /// The loaded FMU, shared by a run and its forks.
    fmu: Option<Arc<Fmu>>,
    /// The instance; a mutex so that a fork (`&self`) can ask it for its state.
    live: Option<Mutex<Instance>>,
    /// `FmuSpec::outputs` and `inputs` grouped by type, gathered once when the instance
    /// is made, for the calls of every step.
    reads: Vec<Group>,
    writes: Vec<Group>,
    /// The values of one read, reused.
    scratch: Vec<Value>,
}

/// The variables of one type that one FMI call reads or sets.
#[derive(Debug, Clone)]
struct Group {
    kind: VarKind,
    vrs: Vec<u32>,
    /// The values in all (an array counts its elements).
    count: usize,
    /// The index (into `FmuSpec::outputs` or `inputs`) of each variable.
    members: Vec<usize>,
    /// Scalar Reals (every FMU's usual case): the values of one call, reused, so a step
    /// reads and sets them without allocating.
    reals: Option<Vec<f64>>,
}

/// `vars` grouped by type, in order of first appearance (the calls' order).
fn groups(vars: &[FmuVar]) -> Vec<Group> {
    let mut out: Vec<Group> = Vec::new();
    for (k, v) in vars.iter().enumerate() {
        let i = match out.iter().position(|g| g.kind == v.kind) {
            Some(i) => i,
            None => {
                out.push(Group {
                    kind: v.kind,
                    vrs: Vec::new(),
                    count: 0,
                    members: Vec::new(),
                    reals: None,
                });
                out.len() - 1
            }
        };
        let g = &mut out[i];
        g.vrs.push(v.vr);
        g.count += v.len();
        g.members.push(k);
    }
    for g in &mut out {
        if g.kind == VarKind::Real && g.count == g.vrs.len() {
            g.reals = Some(vec![0.0; g.count]);
        }
    }
    out
}

/// Each output's values before anything is read: its start value, or an array's
/// elements at zero.
fn initial(outputs: &[FmuVar]) -> Vec<Vec<Value>> {
    outputs
        .iter()
        .map(|v| {
            if v.shape.is_empty() {
                vec![v.start.clone()]
            } else {
                vec![Value::zero(v.kind); v.len()]
            }
        })
        .collect()
}

/// Reads every output of `reads` into `into` (`scratch` holds one call's values).
fn read(
    inst: &Instance,
    reads: &mut [Group],
    scratch: &mut Vec<Value>,
    into: &mut [Vec<Value>],
) -> std::result::Result<(), crate::fmu::FmuError> {
    for g in reads {
        if let Some(buf) = &mut g.reals {
            inst.get_real(&g.vrs, buf)?;
            for (&k, &x) in g.members.iter().zip(buf.iter()) {
                into[k][0] = Value::Float(x);
            }
            continue;
        }
        let kind = g.kind;
        scratch.clear();
        inst.get_values(kind, &g.vrs, g.count, scratch)?;
        let mut values = scratch.drain(..);
        for &k in &g.members {
            for slot in into[k].iter_mut() {
                if let Some(v) = values.next() {
                    *slot = v;
                }
            }
        }
    }
    Ok(())
}

impl std::fmt::Debug for FmuUnit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FmuUnit")
            .field("time", &self.time)
            .field("published", &self.published)
            .field("inputs", &self.inputs)
            .field("live", &self.live.is_some())
            .finish()
    }
}

impl FmuUnit {
    /// The unit of `spec`, not instantiated yet.
    pub fn new(spec: &FmuSpec) -> FmuUnit {
        let starts = initial(&spec.outputs);
        FmuUnit {
            time: SimTime::ZERO,
            published: starts.clone(),
            pending: starts,
            inputs: spec.inputs.iter().map(|v| v.start.clone()).collect(),
            saved: None,
            broken: None,
            stop: None,
            fmu: None,
            live: None,
            reads: Vec::new(),
            writes: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// The FMU's request to end the simulation, if it made one: the last communication
    /// point it completed, and how it asked.
    pub fn stop_request(&self) -> Option<&(SimTime, String)> {
        self.stop.as_ref()
    }

    /// Whether the instance exists.
    pub fn is_live(&self) -> bool {
        self.live.is_some()
    }

    /// What the FMU logged at warning and above, and how many such messages were not
    /// kept; nothing before it was loaded.
    pub fn messages(&self) -> (Vec<crate::fmu::LogEntry>, u64) {
        self.fmu.as_ref().map(|f| f.messages()).unwrap_or_default()
    }

    /// Scalar output `k` as channels and the trace see it.
    pub fn output(&self, k: usize) -> &Value {
        &self.published[k][0]
    }

    /// Scalar output `k` as a number, for a cost (which validation lets name numbers
    /// and Booleans only).
    pub fn output_number(&self, k: usize) -> f64 {
        self.output(k).as_f64().unwrap_or(f64::NAN)
    }

    /// Every output's values as channels and the trace see them, in `FmuSpec::outputs`
    /// order, an array's elements in row-major order.
    pub fn outputs(&self) -> impl Iterator<Item = &Value> {
        self.published.iter().flatten()
    }

    /// The traced outputs' values (an array's elements in row-major order), appended to
    /// `out`.
    pub fn traced(&self, spec: &FmuSpec, out: &mut Vec<Value>) {
        for (v, x) in spec.outputs.iter().zip(&self.published) {
            if v.traced {
                out.extend(x.iter().cloned());
            }
        }
    }

    /// A delivery: input `k` holds `value` from the next communication point on.
    pub fn set_input(&mut self, k: usize, value: Value) {
        self.inputs[k] = value;
    }

    /// Makes the instance: a fresh one initialized from the start values, or one
    /// restored to the state this unit carries.
    pub fn start(&mut self, spec: &FmuSpec) -> Result<()> {
        if self.live.is_some() {
            return Ok(());
        }
        if let Some(why) = &self.broken {
            return Err(Error::Fmu(why.clone()));
        }
        let fmu = match &self.fmu {
            Some(f) => f.clone(),
            None => {
                let f = Fmu::load(&spec.name, &spec.path).map_err(fmu_error)?;
                if f.hash() != spec.hash {
                    return Err(Error::Fmu(format!(
                        "FMU '{}': {} changed since the scenario was validated (BLAKE3 {} \
                         instead of {})",
                        spec.name,
                        spec.path.display(),
                        f.hash(),
                        spec.hash
                    )));
                }
                Arc::new(f)
            }
        };
        // Kept before the instance is made, so what the FMU logs while failing to
        // instantiate or initialize reaches summary.json.
        self.fmu = Some(Arc::clone(&fmu));
        self.reads = groups(&spec.outputs);
        self.writes = groups(&spec.inputs);
        let mut inst = fmu
            .instantiate(&spec.name, spec.logging)
            .map_err(fmu_error)?;
        inst.setup_experiment(0.0, None).map_err(fmu_error)?;
        for s in &spec.start {
            inst.set_values(s.kind, &[s.vr], std::slice::from_ref(&s.value))
                .map_err(fmu_error)?;
        }
        inst.enter_initialization_mode().map_err(fmu_error)?;
        inst.exit_initialization_mode().map_err(fmu_error)?;
        match self.saved.take() {
            Some(bytes) => {
                let state = inst.deserialize_state(&bytes).map_err(fmu_error)?;
                inst.set_state(&state).map_err(fmu_error)?;
            }
            None => {
                read(&inst, &mut self.reads, &mut self.scratch, &mut self.pending)
                    .map_err(fmu_error)?;
                finite(spec, self.time, &self.pending)?;
                self.published.clone_from(&self.pending);
            }
        }
        self.live = Some(Mutex::new(inst));
        Ok(())
    }

    /// The lock-step at `t` (of length `dt`): the communication steps that start in
    /// `[t, t + dt)`, then the outputs of the point the next lock-step reaches
    /// published.
    pub fn step(&mut self, spec: &FmuSpec, t: SimTime, dt: SimTime) -> Result<()> {
        let h = spec.step;
        let end = SimTime(t.0.saturating_add(dt.0));
        if self.stop.is_none() && self.time >= t && self.time < end {
            let inst = self
                .live
                .as_mut()
                .expect("ok: the world starts every FMU before its first event")
                .get_mut()
                .unwrap_or_else(|poisoned| poisoned.into_inner());
            // The inputs hold over the lock-step: set once for all its communication
            // steps.
            for g in &mut self.writes {
                if let Some(buf) = &mut g.reals {
                    for (x, &k) in buf.iter_mut().zip(&g.members) {
                        *x = self.inputs[k].as_f64().unwrap_or(f64::NAN);
                    }
                    inst.set_real(&g.vrs, buf).map_err(fmu_error)?;
                    continue;
                }
                let kind = g.kind;
                self.scratch.clear();
                let held = g.members.iter().map(|&k| self.inputs[k].clone());
                self.scratch.extend(held);
                inst.set_values(kind, &g.vrs, &self.scratch)
                    .map_err(fmu_error)?;
            }
            while self.time < end {
                let (from, over) = (self.time.as_secs_f64(), h.as_secs_f64());
                let done = inst.do_step(from, over).map_err(fmu_error)?;
                if let StepEnd::Stopped { reached, reason } = done {
                    // A stop request: the step counts as done only if the FMU reached
                    // its end (compared as the FMU computed it, `from + over`); else it
                    // stays at the point before, whose outputs are read already.
                    if reached >= from + over {
                        self.time = SimTime(self.time.0.saturating_add(h.0));
                        read(inst, &mut self.reads, &mut self.scratch, &mut self.pending)
                            .map_err(fmu_error)?;
                        finite(spec, self.time, &self.pending)?;
                    }
                    self.stop = Some((self.time, reason));
                    break;
                }
                self.time = SimTime(self.time.0.saturating_add(h.0));
            }
            if self.stop.is_none() {
                read(inst, &mut self.reads, &mut self.scratch, &mut self.pending)
                    .map_err(fmu_error)?;
                finite(spec, self.time, &self.pending)?;
            }
        }
        if self.time == end {
            self.published.clone_from(&self.pending);
        }
        Ok(())
    }

    /// The instance's state as bytes, for a fork or a checkpoint.
    fn capture(&self) -> std::result::Result<Option<Arc<Vec<u8>>>, String> {
        let Some(live) = &self.live else {
            return Ok(self.saved.clone());
        };
        if let Some(why) = &self.broken {
            return Err(why.clone());
        }
        let inst = live.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let state = inst.get_state().map_err(|e| e.to_string())?;
        let bytes = inst.serialize_state(&state).map_err(|e| e.to_string())?;
        Ok(Some(Arc::new(bytes)))
    }
}

/// The outputs `values` that `spec`'s FMU gave for `time` are finite, or the run
/// diverged there: a NaN or an infinity would pass into the trace, the channels and the
/// controller's cost as a number. The error names the time the outputs belong to, the
/// FMU's node and the first such output (in `FmuSpec::outputs` order; an array's
/// element as its trace column names it, `y[2]`), as the multibody model's divergence
/// names a link or a body.
fn finite(spec: &FmuSpec, time: SimTime, values: &[Vec<Value>]) -> Result<()> {
    for (var, x) in spec.outputs.iter().zip(values) {
        let Some(e) = x.iter().position(Value::is_non_finite) else {
            continue;
        };
        let variable = var.element_names().swap_remove(e);
        return Err(Error::Diverged(Divergence {
            time,
            node: spec.node + 1,
            place: Place::FmuOutput {
                fmu: spec.name.clone(),
                variable: variable.clone(),
            },
            what: format!("non-finite output {variable} = {}", x[e]),
        }));
    }
    Ok(())
}

fn fmu_error(e: crate::fmu::FmuError) -> Error {
    Error::Fmu(e.to_string())
}

impl Clone for FmuUnit {
    /// A fork: the same held values and the instance's state as bytes, restored into a
    /// new instance on the fork's first event. An FMU that cannot hand over its state
    /// gives a fork that fails there, naming why.
    fn clone(&self) -> FmuUnit {
        let (saved, broken) = match self.capture() {
            Ok(saved) => (saved, self.broken.clone()),
            Err(why) => (
                None,
                Some(format!(
                    "{why}: the FMU's state cannot be carried into a fork"
                )),
            ),
        };
        FmuUnit {
            time: self.time,
            published: self.published.clone(),
            pending: self.pending.clone(),
            inputs: self.inputs.clone(),
            saved,
            broken,
            stop: self.stop.clone(),
            fmu: self.fmu.clone(),
            live: None,
            reads: Vec::new(),
            writes: Vec::new(),
            scratch: Vec::new(),
        }
    }
}

/// What a checkpoint stores of a unit.
#[derive(serde::Serialize, serde::Deserialize)]
struct Stored {
    time: SimTime,
    published: Vec<Vec<Value>>,
    pending: Vec<Vec<Value>>,
    inputs: Vec<Value>,
    state: Option<Vec<u8>>,
}

impl serde::Serialize for FmuUnit {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let state = self
            .capture()
            .map_err(|why| serde::ser::Error::custom(format!("cannot checkpoint: {why}")))?;
        Stored {
            time: self.time,
            published: self.published.clone(),
            pending: self.pending.clone(),
            inputs: self.inputs.clone(),
            state: state.map(|b| b.as_ref().clone()),
        }
        .serialize(s)
    }
}

impl<'de> serde::Deserialize<'de> for FmuUnit {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = Stored::deserialize(d)?;
        Ok(FmuUnit {
            time: s.time,
            published: s.published,
            pending: s.pending,
            inputs: s.inputs,
            saved: s.state.map(Arc::new),
            broken: None,
            // A checkpoint is written only while the run goes on: no stop was asked.
            stop: None,
            fmu: None,
            live: None,
            reads: Vec::new(),
            writes: Vec::new(),
            scratch: Vec::new(),
        })
    }
}

/// An FMU as a [`Unit`] of the world: it sends the outputs its connections name, takes
/// the inputs they deliver (held to its next communication point), and computes in the
/// second half of each lock-step, from one communication point to the next.
impl Unit for FmuUnit {
    fn sample(
        &mut self,
        t: SimTime,
        channel: usize,
        route: &Route,
        scenario: &Scenario,
    ) -> Option<Message> {
        let connection = route.body;
        let SignalSource::Fmu { fmu, output } = scenario.connections[connection].from else {
            return None;
        };
        let kind = scenario.fmus[fmu].outputs[output].kind;
        let value = self
            .output(output)
            .to_carrier(kind)
            .expect("ok: validation lets only numbers and Booleans into connections");
        let payload = Payload::Signal { connection, value };
        Some(Message::on(route, channel, t, payload, None))
    }

    fn deliver(&mut self, msg: &Message, _state_time: SimTime, scenario: &Scenario) {
        if let Payload::Signal { connection, value } = msg.payload {
            if let SignalSink::Fmu { fmu, input } = scenario.connections[connection].to {
                let kind = scenario.fmus[fmu].inputs[input].kind;
                self.set_input(input, Value::from_carrier(kind, value));
            }
        }
    }

    fn finish_steps(
        units: &mut [FmuUnit],
        t: SimTime,
        dt: SimTime,
        scenario: &Scenario,
        _parallel: bool,
    ) -> Result<()> {
        for (unit, spec) in units.iter_mut().zip(&scenario.fmus) {
            unit.step(spec, t, dt)?;
        }
        Ok(())
    }
}
