//! The [`CoSim`] world and its event handlers.

use std::sync::Arc;

use nalgebra::{Quaternion, Vector3};
use rayon::prelude::*;

use super::fmus::FmuUnit;
use super::{Event, TdmaLink, Unit};
use crate::control::CostMeter;
use crate::error::{Divergence, Error, Place, Result};
use crate::kernel::{EventClass, Kernel, SimTime};
use crate::multibody::invariants::Invariants;
use crate::network::route::Route;
use crate::network::tdma::{tdma_node, CycleReport, TdmaError};
use crate::network::{Channel, Message, Payload};
use crate::partition::line::LineSet;
use crate::partition::node::WholeStart;
use crate::partition::{Layout, Node};
use crate::scenario::model::{
    BodyModel, BodySpec, DataKind, NetworkSpec, Scenario, SignalSink, SignalSource,
};

/// The values of one step, as observers (trace recorder, digest) see them: the whole
/// model, gathered from the nodes that own each link and body.
pub struct StepValues<'a> {
    /// Step index k (t = k dt).
    pub step: u64,
    /// Time of the step.
    pub time: SimTime,
    /// Whether this is the last step of the run.
    pub last: bool,
    /// Constraint values w per link [m].
    pub w: &'a [f64],
    /// Link tensions f per link [N] (positive when pulling the bodies together).
    pub f: &'a [f64],
    /// Body positions [m].
    pub p: &'a [Vector3<f64>],
    /// Body velocities [m/s].
    pub v: &'a [Vector3<f64>],
    /// Body orientations (body → world, unit quaternions); empty on the point-mass path.
    pub q: &'a [Quaternion<f64>],
    /// Body angular velocities in the world frame [rad/s]; empty on the point-mass path.
    pub omega: &'a [Vector3<f64>],
    /// Largest `|w|` over the links at this step [m] (0 without links).
    pub max_w: f64,
    /// The bodies (masses and inertias, for [`StepValues::invariants`]).
    pub bodies: &'a [BodySpec],
    /// The traced FMU outputs at this step, FMU by FMU in scenario order (each FMU's
    /// value at its last communication point at or before this step, of its FMI type;
    /// an array's elements in row-major order); empty without FMUs.
    pub signals: &'a [crate::fmu::Value],
}

impl StepValues<'_> {
    /// The net's momenta and kinetic energy at this step, from the owner copy of every
    /// body. Computed on demand (the recorder asks on the rows it keeps), not on every
    /// step.
    pub fn invariants(&self) -> Invariants {
        Invariants::of(self.bodies, self.p, self.v, self.q, self.omega)
    }
}

/// The values one step records, owned: [`CoSim::observe`]'s answer.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    /// The step's time.
    pub time: SimTime,
    /// Constraint values w per row (links, then joints' rows, in file order) [m].
    pub w: Vec<f64>,
    /// Row forces f [N].
    pub f: Vec<f64>,
    /// Body positions [m], in the scenario's body order.
    pub p: Vec<Vector3<f64>>,
    /// Body velocities [m/s].
    pub v: Vec<Vector3<f64>>,
    /// Body orientations (body → world); empty on the point-mass path.
    pub q: Vec<Quaternion<f64>>,
    /// Body angular velocities in the world frame [rad/s]; empty on the point-mass path.
    pub omega: Vec<Vector3<f64>>,
    /// Largest `|w|` [m] (0 without rows).
    pub max_w: f64,
    /// The traced FMU outputs, in trace column order.
    pub signals: Vec<crate::fmu::Value>,
}

/// The observer of [`CoSim::observe`]'s fork: keeps the first step's values.
struct Seen(Option<Observation>);

impl Observer for Seen {
    fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
        if self.0.is_none() {
            self.0 = Some(Observation {
                time: s.time,
                w: s.w.to_vec(),
                f: s.f.to_vec(),
                p: s.p.to_vec(),
                v: s.v.to_vec(),
                q: s.q.to_vec(),
                omega: s.omega.to_vec(),
                max_w: s.max_w,
                signals: s.signals.to_vec(),
            });
        }
        Ok(())
    }
}

/// Something that watches every step (the recorder; nothing for a what-if fork).
pub trait Observer {
    /// Called once per step with the values at the step's start.
    fn on_step(&mut self, values: &StepValues) -> std::io::Result<()>;

    /// Called once per TDMA cycle, when it is computed (at its start).
    fn on_cycle(&mut self, _report: &CycleReport) -> std::io::Result<()> {
        Ok(())
    }

    /// Called when a message reaches its receiver at `t` (tests and tools; nothing of
    /// it reaches the trace).
    fn on_delivery(&mut self, _t: SimTime, _msg: &Message) {}

    /// Called when a measurement window closes (its `Measurement` event), with the
    /// world's columns of its epochs.csv row.
    fn on_epoch(&mut self, _epoch: &EpochRecord) {}

    /// Called when a controller has run a window on the live world (after
    /// [`Observer::on_epoch`] of that window), with the controller's columns of its
    /// epochs.csv row. Forks report nothing.
    fn on_window(&mut self, _report: &crate::control::experiment::WindowReport) {}
}

/// Every observer takes the controller's window reports through
/// [`Observer::on_window`].
impl<T: Observer + ?Sized> crate::control::WindowSink for T {
    fn on_window(&mut self, report: &crate::control::experiment::WindowReport) {
        Observer::on_window(self, report);
    }
}

/// The co-simulation is the plant the delay controller steers.
impl crate::control::Plant for CoSim {
    type Observer = dyn Observer;

    fn scenario(&self) -> &Scenario {
        CoSim::scenario(self)
    }

    fn advance_to(&mut self, t: SimTime, obs: &mut (dyn Observer + 'static)) -> Result<()> {
        CoSim::advance_to(self, t, obs)
    }

    fn advance_unobserved(&mut self, t: SimTime) -> Result<()> {
        CoSim::advance_to(self, t, &mut ())
    }

    fn set_taus(
        &mut self,
        at: SimTime,
        requested: &[f64],
        achieved: &[SimTime],
    ) -> std::result::Result<Vec<SimTime>, String> {
        CoSim::set_taus(self, at, requested, achieved).map_err(|e| e.to_string())
    }

    fn last_window(&self) -> Option<(SimTime, f64)> {
        self.epochs.last().map(|e| (e.t_end, e.cost))
    }

    fn finished(&self) -> bool {
        CoSim::finished(self)
    }
}

/// The channels of `scenario` over `layout`'s routes and, on a TDMA network, the
/// network with its initial slot list, each channel's period set to what that list
/// achieves (`u64::MAX` ns for a channel a sender of which it never serves).
pub fn network_of(
    scenario: &Scenario,
    layout: &Layout,
) -> std::result::Result<(Vec<Channel>, Option<TdmaLink>), TdmaError> {
    let mut channels = channels_of(scenario, layout);
    let tdma = match &scenario.network {
        NetworkSpec::Ideal => None,
        NetworkSpec::Tdma(_) => {
            let link = TdmaLink::new(scenario, &channels)?;
            for (ch, tau) in channels.iter_mut().zip(link.nominal_periods()) {
                ch.tau = tau;
            }
            Some(link)
        }
    };
    Ok((channels, tdma))
}

/// The channels of `scenario`, each with the routes of `layout` it matches and then the
/// routes of the FMU connections that name it (kind `Signal`, `body` = the connection).
pub fn channels_of(scenario: &Scenario, layout: &Layout) -> Vec<Channel> {
    let mut channels: Vec<Channel> = scenario
        .channels
        .iter()
        .map(|c| Channel::new(c, &layout.routes))
        .collect();
    for (i, c) in scenario.connections.iter().enumerate() {
        channels[c.channel].routes.push(Route {
            kind: DataKind::Signal,
            from: c.from_node(scenario),
            to: c.to_node(scenario),
            body: i,
            link: None,
        });
    }
    channels
}

/// A watcher that watches nothing.
impl Observer for () {
    fn on_step(&mut self, _: &StepValues) -> std::io::Result<()> {
        Ok(())
    }
}

/// One closed measurement window with the network settings in force over it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EpochRecord {
    /// Window start.
    pub t_start: SimTime,
    /// Window end.
    pub t_end: SimTime,
    /// Cost C over the window [m].
    pub cost: f64,
    /// Requested and achieved period per channel [s].
    pub taus: Vec<(f64, f64)>,
    /// Bandwidth used `Σ k/τ` [units/s].
    pub bandwidth: f64,
}

/// An FMU's request that ended the run before its duration ([`CoSim::stopped`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Stopped {
    /// The FMU's name.
    pub fmu: String,
    /// The run's last step: the lock-step at or before the last communication point the
    /// FMU completed.
    pub time: SimTime,
    /// How it asked, in the FMI's words.
    pub reason: String,
}

impl std::fmt::Display for Stopped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "stopped by FMU '{}' at t = {} s ({})",
            self.fmu,
            self.time.as_secs_f64(),
            self.reason
        )
    }
}

/// The whole co-simulation. `Clone` is a fork: the clone continues independently and
/// bit-identically to the original.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct CoSim {
    scenario: Arc<Scenario>,
    layout: Arc<Layout>,
    kernel: Kernel<Event>,
    nodes: Vec<Node>,
    channels: Vec<Channel>,
    /// The TDMA network, on a `tdma` scene.
    tdma: Option<Box<TdmaLink>>,
    meter: CostMeter,
    epochs: Vec<EpochRecord>,
    /// (node, local index) holding each link's values (not for lines).
    link_home: Vec<(usize, usize)>,
    /// Per link that is a transmission line: (node, end index) of its ends `a` and `b`.
    line_ends: Vec<Option<[(usize, usize); 2]>>,
    /// (node, local index) of each body's owner copy.
    body_home: Vec<(usize, usize)>,
    w: Vec<f64>,
    f: Vec<f64>,
    p: Vec<Vector3<f64>>,
    v: Vec<Vector3<f64>>,
    /// Each body's orientation and angular velocity, gathered like `p` and `v` (empty on
    /// the point-mass path).
    q: Vec<Quaternion<f64>>,
    omega: Vec<Vector3<f64>>,
    steps_done: u64,
    /// The next lock-step, the one pending event of class `PartitionStep`. It is kept
    /// beside the queue rather than in it: nothing else has that class, so it runs when
    /// no queued event is at or before its time, exactly where the kernel would pop it,
    /// and the commonest event of every run costs no heap push and pop.
    next_step: Option<SimTime>,
    messages: u64,
    events: u64,
    max_violation: f64,
    /// The FMUs, in scenario order.
    fmus: Vec<FmuUnit>,
    /// The traced FMU outputs of the current step (see [`StepValues::signals`]).
    signals: Vec<crate::fmu::Value>,
    /// An FMU asked to end the run: it ends after the step at this time. Not in a
    /// checkpoint: none is written once a run has stopped.
    #[serde(skip)]
    stopped: Option<Stopped>,
    /// Links per lock-step (over every node's system) from which the nodes step in
    /// parallel on rayon ([`PARALLEL_MIN_LINKS`] unless set). Not part of the world's
    /// state: a checkpoint does not store it, and it changes no bit of a run.
    #[serde(skip, default = "parallel_min_links_default")]
    parallel_min_links: usize,
}

/// Links per lock-step (summed over the nodes' own systems, ghosts' links included) from
/// which the nodes of a world with two or more nodes step in parallel when rayon has more
/// than one thread. Below it a step is too short for rayon's fork and join to pay: on
/// this 2-core machine (`cargo bench --bench parallel`) the thesis scene (24 links)
/// took 1.6–1.7× as long on two threads and an 8×8 grid on 16 nodes (112 links)
/// 1.2×, while 16×16 grids (480 links) on 4 or 16 nodes gained up to 1.8× (one case at
/// par); docs/performance.md, "Parallel lock-step".
pub const PARALLEL_MIN_LINKS: usize = 480;

fn parallel_min_links_default() -> usize {
    PARALLEL_MIN_LINKS
}

impl CoSim {
    /// Builds the world of a validated scenario, with its first events scheduled.
    pub fn new(scenario: &Scenario) -> CoSim {
        CoSim::shared(Arc::new(scenario.clone()))
    }

    /// [`CoSim::new`] on a scenario the caller hands over: the world holds it without a
    /// copy (a million-body grid's bodies and links are 360 MB).
    pub fn shared(shared: Arc<Scenario>) -> CoSim {
        let scenario = &*shared;
        let layout = Layout::new(scenario);
        let (channels, tdma) =
            network_of(scenario, &layout).expect("ok: validation built this network once already");
        // The periods each channel starts at (on TDMA what the initial list achieves).
        let periods: Vec<SimTime> = channels.iter().map(|c| c.tau).collect();
        let lines = LineSet::new(scenario, &layout.routes, &periods);
        let mut nodes: Vec<Node> = (0..layout.nodes)
            .map(|n| Node::new(scenario, &layout, n, &lines))
            .collect();
        // Under Baumgarte every node starts from the whole model's multipliers at t = 0
        // (see Node::start_consistent).
        if let Some(whole) = WholeStart::new(scenario, layout.nodes) {
            for node in &mut nodes {
                node.start_consistent(&whole, scenario);
            }
        }
        // Each line's two ends, found once: (node, end index) at `a` and at `b`.
        let line_ends = (0..scenario.links.len())
            .map(|l| {
                let link = &scenario.links[l];
                let end = |body: usize| {
                    let n = layout.node_of[body];
                    nodes[n].line_index(l).map(|k| (n, k))
                };
                Some([end(link.a)?, end(link.b)?])
            })
            .collect();
        // A line's values are gathered from both its ends; its owner is named for it.
        let mut link_home: Vec<(usize, usize)> =
            layout.link_owner.iter().map(|&n| (n, usize::MAX)).collect();
        let mut body_home = vec![(0, 0); scenario.bodies.len()];
        for node in &nodes {
            for (local, &g) in node.links.iter().enumerate() {
                link_home[g] = (node.index, local);
            }
            for (local, &g) in node.bodies[..node.owned].iter().enumerate() {
                body_home[g] = (node.index, local);
            }
        }
        let mut kernel = Kernel::with_capacity(64);
        let schedule = |k: &mut Kernel<Event>, t, class, e| {
            k.schedule(t, class, e)
                .expect("ok: initial events are at or after time zero");
        };
        match &tdma {
            None => {
                for (c, ch) in channels.iter().enumerate() {
                    if !ch.routes.is_empty() {
                        schedule(
                            &mut kernel,
                            ch.spec.phase,
                            EventClass::Sample,
                            Event::Sample { channel: c },
                        );
                    }
                }
            }
            Some(_) => schedule(
                &mut kernel,
                SimTime::ZERO,
                EventClass::ClockSync,
                Event::Cycle,
            ),
        }
        let tdma = tdma.map(Box::new);
        let first_window = scenario.measurement_period.min(scenario.duration);
        schedule(
            &mut kernel,
            first_window,
            EventClass::Measurement,
            Event::WindowEnd,
        );
        let (nl, nb) = (scenario.links.len(), scenario.bodies.len());
        let nr = if scenario.body_model == BodyModel::Rigid {
            nb
        } else {
            0
        };
        CoSim {
            meter: CostMeter::new(
                if scenario.cost_signals.is_empty() {
                    nl
                } else {
                    scenario.cost_signals.len()
                },
                scenario.dt,
            ),
            layout: Arc::new(layout),
            kernel,
            nodes,
            channels,
            tdma,
            epochs: Vec::new(),
            link_home,
            line_ends,
            body_home,
            w: vec![0.0; nl],
            f: vec![0.0; nl],
            p: vec![Vector3::zeros(); nb],
            v: vec![Vector3::zeros(); nb],
            q: vec![Quaternion::identity(); nr],
            omega: vec![Vector3::zeros(); nr],
            steps_done: 0,
            next_step: Some(SimTime::ZERO),
            messages: 0,
            events: 0,
            max_violation: 0.0,
            fmus: scenario.fmus.iter().map(FmuUnit::new).collect(),
            signals: Vec::new(),
            stopped: None,
            parallel_min_links: PARALLEL_MIN_LINKS,
            scenario: shared,
        }
    }

    /// Steps the nodes in parallel from `links` links per lock-step on (0: whenever
    /// there are two nodes and two rayon threads; `usize::MAX`: never). The result is
    /// the same bits either way; benches and tests use it to compare the two paths.
    pub fn set_parallel_min_links(&mut self, links: usize) {
        self.parallel_min_links = links;
    }

    /// Whether the next lock-step runs its nodes in parallel: two nodes or more, at
    /// least [`PARALLEL_MIN_LINKS`] (or the set threshold) links per lock-step, and more
    /// than one thread in the current rayon pool.
    pub fn steps_in_parallel(&self) -> bool {
        self.nodes.len() > 1
            && self
                .nodes
                .iter()
                .map(|n| n.system.link_count())
                .sum::<usize>()
                >= self.parallel_min_links
            && rayon::current_num_threads() > 1
    }

    /// The scenario being run.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The partition layout.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The nodes.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// FMU `f`'s outputs (`FmuSpec::outputs` order, an array's elements in row-major
    /// order) as channels and the trace see them now.
    pub fn fmu_outputs(&self, f: usize) -> Vec<crate::fmu::Value> {
        self.fmus[f].outputs().cloned().collect()
    }

    /// What FMU `f` logged at warning and above (every instance of it, this world's and
    /// its forks'), and how many such messages were not kept
    /// ([`crate::fmu::log`]); nothing before it was loaded.
    pub fn fmu_messages(&self, f: usize) -> (Vec<crate::fmu::LogEntry>, u64) {
        self.fmus[f].messages()
    }

    /// The channels.
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// The TDMA network, on a `tdma` scene.
    pub fn tdma(&self) -> Option<&TdmaLink> {
        self.tdma.as_deref()
    }

    /// Closed measurement windows.
    pub fn epochs(&self) -> &[EpochRecord] {
        &self.epochs
    }

    /// Mean window cost so far [m].
    pub fn mean_cost(&self) -> f64 {
        self.meter.mean_cost()
    }

    /// Steps integrated so far.
    pub fn steps_done(&self) -> u64 {
        self.steps_done
    }

    /// Messages delivered so far.
    pub fn messages(&self) -> u64 {
        self.messages
    }

    /// Events processed so far.
    pub fn events(&self) -> u64 {
        self.events
    }

    /// Largest `|w|` seen at any step so far [m].
    pub fn max_violation(&self) -> f64 {
        self.max_violation
    }

    /// Time of the last processed event.
    pub fn now(&self) -> SimTime {
        // The later of the last queued event and the last step (steps are not queued).
        let last_step = SimTime(self.steps_done.saturating_sub(1) * self.scenario.dt.0);
        self.kernel.now().max(last_step)
    }

    /// The time the state has reached: the bodies integrated to it, every event before
    /// it processed (and the measurement events at it, after [`advance_to`] it); the
    /// scenario's end once [`finished`]. On the step grid; [`now`] is the last event's
    /// time, one step earlier when that was a step.
    ///
    /// [`advance_to`]: Self::advance_to
    /// [`finished`]: Self::finished
    /// [`now`]: Self::now
    pub fn reached(&self) -> SimTime {
        let end = self
            .stopped
            .as_ref()
            .map_or(self.scenario.duration, |s| s.time);
        if self.finished() {
            return end;
        }
        SimTime(self.steps_done.saturating_mul(self.scenario.dt.0)).min(end)
    }

    /// The state at [`reached`](Self::reached) as the step there records it — the
    /// bodies, every constraint row's `w` and `f`, the traced FMU outputs — measured on
    /// a fork (this world is untouched, its digest unchanged): an embedding's look
    /// between two calls (the Python package's `CoSim.observe`). Once
    /// [`finished`](Self::finished), the last step's values.
    pub fn observe(&self) -> Result<Observation> {
        if self.finished() {
            return Ok(Observation {
                time: self.reached(),
                w: self.w.clone(),
                f: self.f.clone(),
                p: self.p.clone(),
                v: self.v.clone(),
                q: self.q.clone(),
                omega: self.omega.clone(),
                max_w: self.w.iter().fold(0.0, |m, w| m.max(w.abs())),
                signals: self.signals.clone(),
            });
        }
        let mut probe = self.clone();
        let mut seen = Seen(None);
        let before = probe.steps_done;
        while probe.steps_done == before {
            let Some((_, class)) = probe.next_key() else {
                break;
            };
            probe.next_event(class, &mut seen)?;
        }
        seen.0.ok_or_else(|| Error::Numerical {
            time: self.reached(),
            message: "no step left to observe".to_string(),
        })
    }

    /// Whether every event up to the end of the run has been processed: the scenario's
    /// duration, or where an FMU's request [`stopped`](Self::stopped) it.
    pub fn finished(&self) -> bool {
        self.steps_done > self.last_step()
    }

    /// The FMU's request that ended the run before its duration, if one did.
    pub fn stopped(&self) -> Option<&Stopped> {
        self.stopped.as_ref()
    }

    /// The index of the run's last step: the scenario's last, or the one an FMU's stop
    /// request ends the run at.
    fn last_step(&self) -> u64 {
        let dt = self.scenario.dt.0;
        self.stopped
            .as_ref()
            .map_or(self.scenario.steps, |s| s.time.0 / dt)
    }

    /// Takes note of the FMUs' stop requests after the FMUs stepped from `t`: the
    /// earliest (the first FMU in scenario order on a tie) ends the run at the lock-step
    /// at or before the point it completed. Whether that is `t` itself, whose step is
    /// recorded already (the FMU could not complete the step it was asked for).
    fn note_stop(&mut self, t: SimTime) -> bool {
        let dt = self.scenario.dt.0;
        let request = self
            .fmus
            .iter()
            .zip(&self.scenario.fmus)
            .filter_map(|(unit, spec)| {
                let (at, why) = unit.stop_request()?;
                Some((SimTime(at.0 / dt * dt).max(t), spec, why))
            })
            .min_by_key(|(at, _, _)| *at);
        if let Some((at, spec, why)) = request {
            if self.stopped.as_ref().is_none_or(|s| at < s.time) {
                self.stopped = Some(Stopped {
                    fmu: spec.name.clone(),
                    time: at,
                    reason: why.clone(),
                });
            }
        }
        self.stopped.as_ref().is_some_and(|s| s.time <= t)
    }

    /// Sets the channel periods from time `at` on (a controller decision): `requested[c]`
    /// is what was asked [s], `achieved[c]` the period an ideal channel runs at. Each
    /// ideal channel's pending sample is replaced by one at `at`, so the new period
    /// starts there; messages already in flight are delivered as scheduled. On a TDMA
    /// network the requested periods are scheduled into a slot list that the server
    /// broadcasts after the decision lag and that goes into force once every client
    /// has confirmed it. Returns the periods the decision achieves (on TDMA, the
    /// list's nominal periods); an error if the TDMA cycle cannot serve the request.
    pub fn set_taus(
        &mut self,
        at: SimTime,
        requested: &[f64],
        achieved: &[SimTime],
    ) -> std::result::Result<Vec<SimTime>, TdmaError> {
        if let Some(link) = &mut self.tdma {
            let same = self
                .channels
                .iter()
                .zip(requested)
                .all(|(c, &r)| c.requested == r);
            let sched = link.schedule_secs(requested)?;
            let periods: Vec<SimTime> = sched
                .achieved
                .iter()
                .map(|p| p.unwrap_or(SimTime(u64::MAX)))
                .collect();
            if same {
                return Ok(periods);
            }
            for (ch, &r) in self.channels.iter_mut().zip(requested) {
                ch.requested = r;
            }
            let lag = link.decision_lag();
            if lag == SimTime::ZERO {
                link.decide(at, sched.list)?;
            } else if at.0.saturating_add(lag.0) < self.scenario.duration.0 {
                let requested = requested.to_vec();
                self.schedule(
                    SimTime(at.0 + lag.0),
                    EventClass::Controller,
                    Event::Decide { requested },
                );
            }
            return Ok(periods);
        }
        for (c, ch) in self.channels.iter_mut().enumerate() {
            if ch.tau == achieved[c] && ch.requested == requested[c] {
                continue;
            }
            ch.requested = requested[c];
            if ch.tau == achieved[c] {
                continue;
            }
            ch.tau = achieved[c];
            ch.since = at;
            ch.taken = 0;
            if ch.routes.is_empty() {
                continue;
            }
            self.kernel
                .cancel_if(|e| matches!(e, Event::Sample { channel } if *channel == c));
            if at < self.scenario.duration {
                self.kernel
                    .schedule(at, EventClass::Sample, Event::Sample { channel: c })
                    .expect("ok: a controller acts at the current window boundary");
            }
        }
        Ok(achieved.to_vec())
    }

    /// The `schedule` entry at `t`, if there is one, put in force as a controller's
    /// decision at `t` (the requested periods; an ideal channel runs each to the
    /// nanosecond, at least one step).
    fn apply_schedule(&mut self, t: SimTime) -> Result<()> {
        let Ok(i) = self.scenario.schedule.binary_search_by_key(&t, |e| e.at) else {
            return Ok(());
        };
        let requested = self.scenario.schedule[i].tau.clone();
        let dt = self.scenario.dt;
        let achieved: Vec<SimTime> = requested
            .iter()
            .map(|&r| crate::network::channel::achieved_period(r, dt))
            .collect();
        self.set_taus(t, &requested, &achieved)
            .map(|_| ())
            .map_err(|e| Error::Numerical {
                time: t,
                message: format!("schedule[{i}]: the TDMA cycle cannot serve its periods: {e}"),
            })
    }

    /// Processes every event before `t`, and the measurement events at `t` (so the
    /// window ending at `t` is closed and a controller can decide at `t`).
    pub fn advance_to(&mut self, t: SimTime, obs: &mut dyn Observer) -> Result<()> {
        while let Some((time, class)) = self.next_key() {
            if time > t || (time == t && class > EventClass::Measurement) || self.finished() {
                break;
            }
            self.next_event(class, obs)?;
        }
        Ok(())
    }

    /// Processes every remaining event: the run to its end.
    pub fn run_to_end(&mut self, obs: &mut dyn Observer) -> Result<()> {
        while let Some((_, class)) = self.next_key() {
            if self.finished() {
                break;
            }
            self.next_event(class, obs)?;
        }
        Ok(())
    }

    /// Whether the pending step comes before the queue's first event: the step's
    /// class, `PartitionStep`, is the last and no queued event has it, so the step goes
    /// first exactly when every queued event is later.
    fn step_is_next(&self) -> Option<SimTime> {
        let ts = self.next_step?;
        match self.kernel.peek() {
            Some(key) if key.time <= ts => None,
            _ => Some(ts),
        }
    }

    /// `(time, class)` of the next event, queued or step.
    fn next_key(&self) -> Option<(SimTime, EventClass)> {
        match self.step_is_next() {
            Some(ts) => Some((ts, EventClass::PartitionStep)),
            None => self.kernel.peek().map(|k| (k.time, k.class)),
        }
    }

    /// Processes the next event, of `class` as [`next_key`](Self::next_key) just said:
    /// the pending step when that is `PartitionStep` (no queued event has that class),
    /// else the queue's first.
    fn next_event(&mut self, class: EventClass, obs: &mut dyn Observer) -> Result<()> {
        // A new world's (or a fork's, or a resumed run's) FMUs are made before its
        // first event: channels may sample their outputs at time 0.
        if self.fmus.iter().any(|u| !u.is_live()) {
            for (unit, spec) in self.fmus.iter_mut().zip(&self.scenario.fmus) {
                unit.start(spec)?;
            }
        }
        if self.events == 0 {
            // A schedule entry at 0 goes into force before anything happens, as a
            // decision made at 0 (`advance_to(0)` processes nothing but windows).
            self.apply_schedule(SimTime::ZERO)?;
        }
        if class == EventClass::PartitionStep {
            if let Some(ts) = self.next_step.take() {
                self.events += 1;
                return self.step(ts, obs);
            }
        }
        let Some((key, event)) = self.kernel.pop() else {
            return Ok(());
        };
        self.events += 1;
        let t = key.time;
        match event {
            Event::Sample { channel } => {
                self.sample(t, channel);
                Ok(())
            }
            Event::Deliver(msg) => {
                self.messages += 1;
                obs.on_delivery(t, &msg);
                // The units' state is that of the next step's time.
                let state_time = SimTime(self.steps_done * self.scenario.dt.0);
                let scenario = &*self.scenario;
                receiver(&mut self.nodes, &mut self.fmus, scenario, &msg)
                    .deliver(&msg, state_time, scenario);
                Ok(())
            }
            Event::WindowEnd => {
                self.window_end(t);
                if let Some(e) = self.epochs.last() {
                    obs.on_epoch(e);
                }
                // The window boundary is where a controller (or a Python script, after
                // `advance_to(t)`) decides: a scheduled change goes into force here, so
                // a schedule replays such decisions bit for bit.
                self.apply_schedule(t)
            }
            Event::Cycle => self.cycle(t, obs),
            Event::Frame {
                channel,
                sender,
                delivery,
            } => {
                self.frame(t, channel, sender, delivery);
                Ok(())
            }
            Event::Decide { requested } => {
                let link = self
                    .tdma
                    .as_mut()
                    .expect("ok: only tdma scenes decide lists");
                let decided = link
                    .schedule_secs(&requested)
                    .and_then(|s| link.decide(t, s.list));
                decided.map(|_| ()).map_err(|e| Error::Numerical {
                    time: t,
                    message: format!("TDMA server: the decided periods cannot be scheduled: {e}"),
                })
            }
        }
    }

    /// A TDMA cycle starts at `t`: computed, traced, its data frames scheduled.
    fn cycle(&mut self, t: SimTime, obs: &mut dyn Observer) -> Result<()> {
        let link = self
            .tdma
            .as_mut()
            .expect("ok: only tdma scenes have cycles");
        let report = link.run_cycle();
        if report.switch.is_some() {
            for (ch, tau) in self.channels.iter_mut().zip(link.nominal_periods()) {
                ch.tau = tau;
            }
        }
        obs.on_cycle(&report)
            .map_err(|e| Error::io("network.csv", e))?;
        let end = self.scenario.duration;
        let lost_frames_sample = link.pipelined();
        for f in &report.frames {
            let crate::network::tdma::collision::FrameKind::Dynamic { channel } = f.kind else {
                continue;
            };
            if f.start >= end || (f.delivery.is_none() && !lost_frames_sample) {
                continue;
            }
            // A frame is never computed before its cycle starts; only a clock far
            // beyond any sane drift could start one earlier.
            let at = f.start.max(t);
            let sender = f.sender;
            self.schedule(
                at,
                EventClass::Slot,
                Event::Frame {
                    channel,
                    sender,
                    delivery: f.delivery.map(|d| d.max(at)),
                },
            );
        }
        let cycle = self
            .tdma
            .as_ref()
            .map(|l| l.network().layout().cycle_len())
            .unwrap_or(SimTime(u64::MAX));
        let next = SimTime(report.start.0.saturating_add(cycle.0));
        if next < end {
            self.schedule(next, EventClass::ClockSync, Event::Cycle);
        }
        Ok(())
    }

    /// A TDMA data frame of `sender` on channel `c` starts at `t`: the sender samples
    /// what it has at `t` — its state at the next step boundary `⌈t/dt⌉·dt` (the
    /// lock-step has already computed it), exactly what an ideal channel sampling at
    /// that boundary would carry. The frame carries that sample (`network.sample:
    /// "slot"`) or the one taken at the pair's previous frame (`"previous_slot"`), and
    /// arrives at `delivery` (`None`: it collided, and what it carried is lost).
    fn frame(&mut self, t: SimTime, c: usize, sender: usize, delivery: Option<SimTime>) {
        let dt = self.scenario.dt.0;
        let sampled = SimTime(t.0.div_ceil(dt) * dt);
        let mut fresh = Vec::new();
        for r in 0..self.channels[c].routes.len() {
            let route = self.channels[c].routes[r];
            if tdma_node(route.from) != sender {
                continue;
            }
            if let Some(msg) = self.message(sampled, c, r) {
                self.snapshot(&msg);
                fresh.push(msg);
            }
        }
        let link = self
            .tdma
            .as_mut()
            .expect("ok: only tdma scenes have frames");
        let carried = link.carry(c, sender, fresh);
        let Some(delivery) = delivery else { return };
        link.delivered(c, sender, delivery);
        if delivery > self.scenario.duration {
            return;
        }
        for msg in carried {
            self.schedule(
                delivery,
                EventClass::Delivery,
                Event::Deliver(Box::new(msg)),
            );
        }
    }

    /// The message of route `r` of channel `c`, sampled at `t` by the route's source.
    fn message(&mut self, t: SimTime, c: usize, r: usize) -> Option<Message> {
        let route = self.channels[c].routes[r];
        let scenario = &*self.scenario;
        source(&mut self.nodes, &mut self.fmus, scenario, &route).sample(t, c, &route, scenario)
    }

    /// Puts `msg` in flight, to arrive at `at`. A state message also makes its receiver
    /// keep its ghost's state of the sample time, for the coupling to compare the sample
    /// with when it arrives.
    fn send(&mut self, at: SimTime, msg: Message) {
        self.snapshot(&msg);
        self.schedule(at, EventClass::Delivery, Event::Deliver(Box::new(msg)));
    }

    /// `msg` is sampled now: its receiver keeps what it will compare it with (a
    /// partition: its ghost's state of the sample time).
    fn snapshot(&mut self, msg: &Message) {
        receiver(&mut self.nodes, &mut self.fmus, &self.scenario, msg).sampled(msg);
    }

    fn schedule(&mut self, t: SimTime, class: EventClass, event: Event) {
        // Every event is scheduled at or after the current one, in a later or equal
        // class at equal time: the kernel cannot refuse it.
        self.kernel
            .schedule(t, class, event)
            .expect("ok: events are only scheduled forward in time");
    }

    /// A channel samples its routes at `t`.
    fn sample(&mut self, t: SimTime, c: usize) {
        let latency = self.channels[c].latency();
        // Saturating, here and below: times near the end of simulated time (u64 ns)
        // must not wrap to the start.
        let arrive = SimTime(t.0.saturating_add(latency.0));
        for r in 0..self.channels[c].routes.len() {
            if arrive > self.scenario.duration {
                break;
            }
            if let Some(msg) = self.message(t, c, r) {
                self.send(arrive, msg);
            }
        }
        let ch = &mut self.channels[c];
        ch.taken = ch.taken.saturating_add(1);
        let next = ch.next_sample(self.scenario.dt);
        if next < self.scenario.duration {
            self.schedule(next, EventClass::Sample, Event::Sample { channel: c });
        }
    }

    /// Closes the measurement window ending at `t`.
    fn window_end(&mut self, t: SimTime) {
        let e = self.meter.close(t).clone();
        let measured = self.tdma.as_mut().map(|l| l.close_window(t));
        self.epochs.push(EpochRecord {
            t_start: e.t_start,
            t_end: e.t_end,
            cost: e.cost,
            taus: self
                .channels
                .iter()
                .enumerate()
                .map(|(i, c)| {
                    let achieved = measured.as_ref().map_or(c.tau, |m| m[i]);
                    (c.requested, achieved.as_secs_f64())
                })
                .collect(),
            bandwidth: self
                .channels
                .iter()
                .map(Channel::bandwidth)
                .fold(0.0, |a, b| a + b),
        });
        if t < self.scenario.duration {
            let next = SimTime(t.0.saturating_add(self.scenario.measurement_period.0))
                .min(self.scenario.duration);
            self.schedule(next, EventClass::Measurement, Event::WindowEnd);
        }
    }

    /// The lock-step of every node at `t`.
    fn step(&mut self, t: SimTime, obs: &mut dyn Observer) -> Result<()> {
        let k = self.steps_done;
        let last = k == self.last_step();
        let parallel = self.steps_in_parallel();
        // The units share nothing during a step: each kind does its first half together
        // (the partitions batch their rate evaluations, on rayon when the step is large
        // enough), with the bits and the first error of a serial loop in unit order.
        let scenario = &*self.scenario;
        Unit::begin_steps(&mut self.nodes, t, scenario, parallel)?;
        Unit::begin_steps(&mut self.fmus, t, scenario, false)?;
        let max_w = if parallel {
            self.gather_check_parallel(t)?
        } else {
            self.gather();
            self.check(t)?
        };
        self.signals.clear();
        for (unit, spec) in self.fmus.iter().zip(&self.scenario.fmus) {
            unit.traced(spec, &mut self.signals);
        }
        let values = StepValues {
            signals: &self.signals,
            step: k,
            time: t,
            last,
            w: &self.w,
            f: &self.f,
            p: &self.p,
            v: &self.v,
            q: &self.q,
            omega: &self.omega,
            max_w,
            bodies: &self.scenario.bodies,
        };
        obs.on_step(&values)
            .map_err(|e| Error::io("trace.csv", e))?;
        self.steps_done += 1;
        if last {
            return Ok(());
        }
        if self.scenario.cost_signals.is_empty() {
            self.meter.add(self.w.iter().copied());
        } else {
            // The window's cost is the RMS of the named FMU outputs at the steps' starts,
            // as the links' cost takes their w.
            let fmus = &self.fmus;
            let signals = self.scenario.cost_signals.iter();
            self.meter
                .add(signals.map(|&(f, k)| fmus[f].output_number(k)));
        }
        let (dt, scenario) = (self.scenario.dt, &*self.scenario);
        Unit::finish_steps(&mut self.fmus, t, dt, scenario, false)?;
        if self.fmus.iter().any(|u| u.stop_request().is_some()) && self.note_stop(t) {
            // An FMU could not complete its step from t and asked to stop: the run
            // ends at t, whose step is recorded; the nodes do not step past it.
            return Ok(());
        }
        let scenario = &*self.scenario;
        Unit::finish_steps(&mut self.nodes, t, dt, scenario, parallel)?;
        self.next_step = Some(SimTime(t.0.saturating_add(self.scenario.dt.0)));
        Ok(())
    }

    /// Copies each link's and body's values from the node that owns it.
    fn gather(&mut self) {
        // A monolithic world's one node holds every link and body at its own index
        // (no ghosts, no lines): plain slice copies, as bare integrator steps would
        // make them.
        if let [node] = &self.nodes[..] {
            self.w.copy_from_slice(node.system.violations());
            for (l, f) in self.f.iter_mut().enumerate() {
                *f = node.system.tension(&node.state, l);
            }
            self.p.copy_from_slice(&node.state.p);
            self.v.copy_from_slice(&node.state.v);
            self.q.copy_from_slice(&node.state.q);
            self.omega.copy_from_slice(&node.state.omega);
            return;
        }
        for l in 0..self.w.len() {
            (self.w[l], self.f[l]) = link_values(
                &self.nodes,
                &self.scenario,
                self.link_home[l],
                self.line_ends[l],
                l,
            );
        }
        for (b, &(n, lb)) in self.body_home.iter().enumerate() {
            self.p[b] = self.nodes[n].state.p[lb];
            self.v[b] = self.nodes[n].state.v[lb];
        }
        gather_rotations(&mut self.q, &mut self.omega, &self.nodes, &self.body_home);
    }

    /// Divergence check of the gathered values at `t`; the step's largest `|w|`.
    fn check(&mut self, t: SimTime) -> Result<f64> {
        let bound = self.scenario.max_violation;
        let mut max = 0.0f64;
        for (l, (&w, &f)) in self.w.iter().zip(&self.f).enumerate() {
            match link_fault(w, f, bound) {
                None => max = max.max(w.abs()),
                Some(what) => {
                    // The failing link's own |w| counts (when finite): it is the step
                    // the divergence error reports.
                    self.max_violation = self.max_violation.max(max).max(finite_abs(w));
                    return Err(self.link_diverged(t, l, what));
                }
            }
        }
        self.max_violation = self.max_violation.max(max);
        // One pass over the bodies: position and velocity, then (rigid bodies) the
        // rotation, which a link through the centre does not feel.
        for (b, (p, v)) in self.p.iter().zip(&self.v).enumerate() {
            if !body_finite(p, v) {
                return Err(self.body_diverged(t, b));
            }
            if let Some(what) = self.rotation_fault(b) {
                return Err(self.rotation_diverged(t, b, what));
            }
        }
        Ok(max)
    }

    /// [`gather`](Self::gather) and [`check`](Self::check) on rayon's threads, in chunks
    /// of links and of bodies: the same copies, and the same reduction in link then
    /// body order after the parallel part (the largest `|w|` of the links before the
    /// first that fails, which is exact in any grouping, then that link's error, else
    /// the first non-finite body's); the step's largest `|w|`.
    fn gather_check_parallel(&mut self, t: SimTime) -> Result<f64> {
        const CHUNK: usize = 512;
        let bound = self.scenario.max_violation;
        let (nodes, scenario) = (&self.nodes, &*self.scenario);
        let (link_home, line_ends) = (&self.link_home, &self.line_ends);
        let body_home = &self.body_home;
        let (w, f, p, v) = (&mut self.w, &mut self.f, &mut self.p, &mut self.v);
        let (q, omega) = (&mut self.q, &mut self.omega);
        let (links, bodies) = rayon::join(
            || {
                w.par_chunks_mut(CHUNK)
                    .zip(f.par_chunks_mut(CHUNK))
                    .enumerate()
                    .map(|(c, (w, f))| {
                        let (mut max, mut fault) = (0.0f64, None);
                        for (i, (w, f)) in w.iter_mut().zip(f.iter_mut()).enumerate() {
                            let l = c * CHUNK + i;
                            (*w, *f) = link_values(nodes, scenario, link_home[l], line_ends[l], l);
                            if fault.is_some() {
                                continue;
                            }
                            match link_fault(*w, *f, bound) {
                                None => max = max.max(w.abs()),
                                Some(what) => fault = Some((l, what, finite_abs(*w))),
                            }
                        }
                        (max, fault)
                    })
                    .collect::<Vec<_>>()
            },
            || {
                let faults = p
                    .par_chunks_mut(CHUNK)
                    .zip(v.par_chunks_mut(CHUNK))
                    .enumerate()
                    .map(|(c, (p, v))| {
                        let mut fault = None;
                        for (i, (p, v)) in p.iter_mut().zip(v.iter_mut()).enumerate() {
                            let b = c * CHUNK + i;
                            let (n, lb) = body_home[b];
                            *p = nodes[n].state.p[lb];
                            *v = nodes[n].state.v[lb];
                            if fault.is_none() && !body_finite(p, v) {
                                fault = Some(b);
                            }
                        }
                        fault
                    })
                    .collect::<Vec<_>>();
                // Rotations: copies only, nothing to check (serial: a rigid scene large
                // enough to step in parallel spends far more per step on its solve).
                gather_rotations(q, omega, nodes, body_home);
                faults
            },
        );
        let mut step_max = 0.0f64;
        for (max, fault) in links {
            step_max = step_max.max(max);
            if let Some((l, what, w)) = fault {
                self.max_violation = self.max_violation.max(step_max).max(w);
                return Err(self.link_diverged(t, l, what));
            }
        }
        self.max_violation = self.max_violation.max(step_max);
        match bodies.into_iter().flatten().next() {
            Some(b) => Err(self.body_diverged(t, b)),
            None => {
                self.check_rotations(t)?;
                Ok(step_max)
            }
        }
    }

    /// The gathered rotations at `t` (empty on point masses), after the parallel gather
    /// of positions and velocities: a torque too large for `f64` spins a body to an
    /// infinite rate while a link through its centre feels nothing, so the links alone
    /// would not see it.
    fn check_rotations(&self, t: SimTime) -> Result<()> {
        for b in 0..self.q.len() {
            if let Some(what) = self.rotation_fault(b) {
                return Err(self.rotation_diverged(t, b, what));
            }
        }
        Ok(())
    }

    /// Which of body `b`'s gathered rotation quantities is not finite (none on point
    /// masses, which gather no rotation).
    fn rotation_fault(&self, b: usize) -> Option<&'static str> {
        let finite = |x: &[f64]| x.iter().all(|v| v.is_finite());
        if self.omega.get(b).is_some_and(|w| !finite(w.as_slice())) {
            Some("angular velocity")
        } else if self.q.get(b).is_some_and(|q| !finite(q.coords.as_slice())) {
            Some("orientation")
        } else {
            None
        }
    }

    /// Body `b`'s `what` (a rotation quantity) is not finite at `t`.
    fn rotation_diverged(&self, t: SimTime, b: usize, what: &str) -> Error {
        Error::Diverged(Divergence {
            time: t,
            node: self.body_home[b].0 + 1,
            place: Place::Body(self.scenario.bodies[b].id),
            what: format!("non-finite {what} (the loads on it overflow f64)"),
        })
    }

    /// Link `l` diverged at `t`: `what`.
    fn link_diverged(&self, t: SimTime, l: usize, what: String) -> Error {
        Error::Diverged(Divergence {
            time: t,
            node: self.link_home[l].0 + 1,
            place: self.scenario.place_of_row(l),
            what,
        })
    }

    /// Body `b`'s position or velocity is not finite at `t`.
    fn body_diverged(&self, t: SimTime, b: usize) -> Error {
        Error::Diverged(Divergence {
            time: t,
            node: self.body_home[b].0 + 1,
            place: Place::Body(self.scenario.bodies[b].id),
            what: "non-finite position or velocity".into(),
        })
    }
}

/// The unit that sends on `route`: for a signal, the FMU or the partition its
/// connection reads; for border data, the partition of the sending node.
fn source<'a>(
    nodes: &'a mut [Node],
    fmus: &'a mut [FmuUnit],
    scenario: &Scenario,
    route: &Route,
) -> &'a mut dyn Unit {
    if route.kind == DataKind::Signal {
        if let SignalSource::Fmu { fmu, .. } = scenario.connections[route.body].from {
            return &mut fmus[fmu];
        }
    }
    &mut nodes[route.from]
}

/// The unit `msg` is for: for a signal, the FMU or the partition its connection sets;
/// for border data, the partition of the receiving node.
fn receiver<'a>(
    nodes: &'a mut [Node],
    fmus: &'a mut [FmuUnit],
    scenario: &Scenario,
    msg: &Message,
) -> &'a mut dyn Unit {
    if let Payload::Signal { connection, .. } = msg.payload {
        if let SignalSink::Fmu { fmu, .. } = scenario.connections[connection].to {
            return &mut fmus[fmu];
        }
    }
    &mut nodes[msg.to]
}

/// Link `l`'s gathered values `(w, f)`; `(owner, ll)` its `link_home` (the node named
/// for it, its local index there), `line` its ends (node, end index) if it is a
/// transmission line.
///
/// Always inlined: called once per link and step, as a call (which `#[inline]` left it)
/// it cost the monolithic thesis scene about 80 ns per 2.4 µs step (3.4 % of the
/// profile), the overhead `git bisect` traced to the commit that introduced it.
#[inline(always)]
fn link_values(
    nodes: &[Node],
    scenario: &Scenario,
    (owner, ll): (usize, usize),
    line: Option<[(usize, usize); 2]>,
    l: usize,
) -> (f64, f64) {
    if let Some([(na, ka), (nb, kb)]) = line {
        // A line: its true length from both ends' anchors, the owner's tension.
        let (pa, ta) = nodes[na].line_end(ka);
        let (pb, tb) = nodes[nb].line_end(kb);
        let w = (pa - pb).norm() - scenario.links[l].length;
        return (w, if owner == na { ta } else { tb });
    }
    let node = &nodes[owner];
    (
        node.system.violations()[ll],
        node.system.tension(&node.state, ll),
    )
}

/// `|w|` if finite, else 0 (a non-finite `|w|` is reported by the divergence error, not
/// as the run's largest violation).
fn finite_abs(w: f64) -> f64 {
    if w.is_finite() {
        w.abs()
    } else {
        0.0
    }
}

/// What is wrong with a link's gathered `w` and `f` at the divergence bound, if anything.
/// Inlined, with the message built out of line, for the reason given at
/// [`link_values`].
#[inline(always)]
fn link_fault(w: f64, f: f64, bound: f64) -> Option<String> {
    if w.is_finite() && f.is_finite() && w.abs() <= bound {
        None
    } else {
        Some(link_fault_text(w, f, bound))
    }
}

/// The message of [`link_fault`] for a faulty link.
#[cold]
#[inline(never)]
fn link_fault_text(w: f64, f: f64, bound: f64) -> String {
    use crate::error::num;
    if !w.is_finite() || !f.is_finite() {
        format!("non-finite w = {} or f = {}", num(w), num(f))
    } else {
        format!(
            "|w| = {} m exceeds the bound {} m",
            num(w.abs()),
            num(bound)
        )
    }
}

/// Copies each body's orientation and angular velocity from its owner copy (nothing on
/// the point-mass path, where `q` and `omega` are empty).
fn gather_rotations(
    q: &mut [Quaternion<f64>],
    omega: &mut [Vector3<f64>],
    nodes: &[Node],
    body_home: &[(usize, usize)],
) {
    for ((q, w), &(n, lb)) in q.iter_mut().zip(omega.iter_mut()).zip(body_home) {
        *q = nodes[n].state.q[lb];
        *w = nodes[n].state.omega[lb];
    }
}

/// Whether a body's gathered position and velocity are finite.
fn body_finite(p: &Vector3<f64>, v: &Vector3<f64>) -> bool {
    p.iter().chain(v.iter()).all(|x| x.is_finite())
}

#[cfg(test)]
mod tests {
    use super::{link_fault, CoSim};
    use std::sync::Arc;

    fn grid(partition: bool) -> crate::scenario::Scenario {
        let mut v = serde_json::json!({
            "name": "g", "seed": 1, "duration": 0.01, "dt": 0.001,
            "model": {"grid": {"rows": 4, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
            "measurement": {"period": 0.01}
        });
        if partition {
            v["partition"] = serde_json::json!({"quadrants": true});
            v["channels"] = serde_json::json!([{"name": "c", "tau": 0.005,
                "borders": [[1, 2], [1, 4], [2, 3], [3, 4]]}]);
        }
        crate::scenario::parse_str(&v.to_string(), "g").expect("a valid scene")
    }

    #[test]
    fn a_monolithic_world_holds_the_model_once() {
        let scenario = Arc::new(grid(false));
        let world = CoSim::shared(Arc::clone(&scenario));
        // The world, its one node's system and the caller share one scenario, one copy
        // of the bodies and one of the links.
        assert!(Arc::ptr_eq(&world.scenario, &scenario));
        let system = &world.nodes[0].system;
        assert!(Arc::ptr_eq(&system.links, &scenario.links));
        // A fork shares them too.
        let fork = world.clone();
        assert!(Arc::ptr_eq(&fork.nodes[0].system.links, &scenario.links));
        // A partitioned world's nodes hold their own parts, in their own numbering.
        let parted = CoSim::new(&grid(true));
        assert!(parted.nodes.len() == 4);
        assert!(parted
            .nodes
            .iter()
            .all(|n| !Arc::ptr_eq(&n.system.links, &parted.scenario.links)));
    }

    #[test]
    fn a_link_fault_prints_short_numbers() {
        let text = link_fault(-2.5e55, 1.0, 1.0).expect("a fault");
        assert_eq!(text, "|w| = 2.5e55 m exceeds the bound 1 m");
        let text = link_fault(f64::NAN, 1e300, 1.0).expect("a fault");
        assert_eq!(text, "non-finite w = NaN or f = 1e300");
        assert_eq!(link_fault(0.5, 3.0, 1.0), None);
    }
}
