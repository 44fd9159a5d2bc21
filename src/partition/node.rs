//! One computing node: its own bodies, its ghosts, its links, and the held values of
//! what it last received.

use std::collections::BTreeMap;

use nalgebra::{Quaternion, Vector3};

mod lines;
mod passivity;
mod start;

pub use start::WholeStart;

use super::com::ComReference;
use super::coupling::{Correction, Extrapolated, GhostHistory, GhostSample, PortAccount};
use super::line::{initial_wave, LineEnd, LineSet};
use super::momentum::MomentumLedger;
use super::Layout;
use crate::kernel::SimTime;
use crate::multibody::{RowLoad, State, System};
use crate::network::{Payload, StepRate};
use crate::scenario::model::{BodyModel, Coupling, GhostMode, Integrator, LoadAt, Scenario};

/// A border force received from another node: held until the next arrival (`reset`),
/// or extrapolated with its rate (`predict`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
struct HeldForce {
    /// Global link index.
    link: usize,
    /// Sending node.
    from: usize,
    /// Local body index it acts on.
    body: usize,
    /// The last received value, its rate and sample time.
    value: Extrapolated,
}

/// How this node couples to its neighbours (see [`super::coupling`]).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct CouplingState {
    scheme: Coupling,
    /// Per ghost (`predict` with integrated ghosts): its recent past.
    history: Vec<GhostHistory>,
    /// Per ghost (`predict`): the owner-side load with its rate.
    ghost_loads: Vec<Extrapolated>,
    /// `passive`, per ghost: this node's side (link owner) of the ghost's port.
    ports_out: Vec<PortAccount>,
    /// `passive`, per (local owned body, ghosting node): the body owner's side.
    ports_in: Vec<(usize, usize, PortAccount)>,
    /// `passive`, per entry of `ports_in`: its held forces (indices into `held_forces`).
    port_forces: Vec<Vec<usize>>,
    /// Scratch: each held force's value at the current step (force, torque).
    held_now: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// Scratch (`passive`): the power of each port side, `ports_in` then `ports_out`.
    side_powers: Vec<f64>,
    /// Scratch (`passive`): (ghost port, far end, power) of every border link's own end.
    end_powers: Vec<(usize, usize, f64)>,
    /// `passive` with a tank sized by share: each owned body's mass [kg] and principal
    /// inertia [kg·m²]; empty otherwise.
    own_masses: Vec<(f64, Vector3<f64>)>,
    /// `passive` with a tank sized by share: the largest kinetic energy the owned
    /// bodies have held so far, against the centre of mass's velocity [J].
    peak_kinetic: f64,
    /// `passive` with a tank sized by share: the work the scene's forces and
    /// connections' inputs have done on the owned bodies where it was positive [J].
    driven_in: f64,
}

/// A ghost's last received state (for the `hold` mode).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
struct HeldState {
    p: Vector3<f64>,
    v: Vector3<f64>,
    q: Option<Quaternion<f64>>,
    omega: Option<Vector3<f64>>,
}

/// A computing node.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Node {
    /// Node index (0-based; printed as `index + 1`).
    pub index: usize,
    /// The node's multi-body system: owned bodies first (body order), then ghosts.
    pub system: System,
    /// The node's state, same local order.
    pub state: State,
    /// Global index of each local body.
    pub bodies: Vec<usize>,
    /// Number of owned bodies (the first `owned` local bodies).
    pub owned: usize,
    /// Global index of each local link.
    pub links: Vec<usize>,
    local_body: BTreeMap<usize, usize>,
    /// Local links touching each local body.
    incident: Vec<Vec<usize>>,
    ghosts: GhostMode,
    held_forces: Vec<HeldForce>,
    held_states: Vec<HeldState>,
    coupling: CouplingState,
    /// This node's ends of transmission lines (`partition::line`), in link order.
    lines: Vec<LineEnd>,
    /// The centre-of-mass velocity the lines measure against (a node with lines).
    com: Option<ComReference>,
    /// A predicting coupling's momentum account (`partition::momentum`).
    momentum: Option<MomentumAccount>,
    /// Whether ghosts carry their owners' reaction stiffness
    /// (`Scenario::ghosts_carry_reactions`).
    #[serde(default)]
    reactions: bool,
    /// Per ghost: whether rows of another node hold its body (its owner's load on it
    /// then answers this node's force, and a slope carried across a sample's age would
    /// close the loop of method §2.1 through it).
    #[serde(default)]
    held_elsewhere: Vec<bool>,
}

/// Per ghost of node `index`: whether a row owned by another node holds its body (see
/// `Node::held_elsewhere`). One pass over the rows; empty where no slope is sent.
fn held_elsewhere(scenario: &Scenario, layout: &Layout, index: usize) -> Vec<bool> {
    if !scenario.slopes_multipliers() {
        return Vec::new();
    }
    let mut held = vec![false; scenario.bodies.len()];
    for (l, link) in scenario.links.iter().enumerate() {
        if layout.link_owner[l] != index {
            held[link.a] = true;
            if !link.world {
                held[link.b] = true;
            }
        }
    }
    layout.ghosts[index].iter().map(|&g| held[g]).collect()
}

/// A node's side of the momentum account (`partition::momentum`): what it measures.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct MomentumAccount {
    ledger: MomentumLedger,
    /// Whether ghosts integrate (their momentum measures the links' impulse on them).
    ports: bool,
    /// Per incoming port (an own body and a node that ghosts it): the body, the node,
    /// the impulse its border forces have applied [N·s], and that impulse at each of
    /// the port's force samples still in flight.
    incoming: Vec<IncomingPort>,
    /// Per held force: its incoming port.
    port_of: Vec<usize>,
    /// Per ghost: the impulse this node's links have put on it [N·s].
    ghost_impulse: Vec<Vector3<f64>>,
    /// Per ghost, over the current step: its velocity at the start and the impulse of
    /// its owner-side load.
    ghost_step: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// Per ghost: its mass [kg].
    ghost_mass: Vec<f64>,
    /// Per line end (`Node::lines`): its slot in the ledger where this end books the
    /// line's momentum (the end that is not the link owner's), else `None`.
    line_slot: Vec<Option<usize>>,
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct IncomingPort {
    body: usize,
    from: usize,
    applied: Vector3<f64>,
    history: std::collections::VecDeque<(SimTime, Vector3<f64>)>,
}

impl Node {
    /// Builds node `index` of `layout` for `scenario`, with `lines` as transmission
    /// lines (out of the node's constraint system).
    pub fn new(scenario: &Scenario, layout: &Layout, index: usize, lines: &LineSet) -> Node {
        let owned = layout.owned[index].len();
        let bodies: Vec<usize> = layout.owned[index]
            .iter()
            .chain(&layout.ghosts[index])
            .copied()
            .collect();
        let local_body: BTreeMap<usize, usize> =
            bodies.iter().enumerate().map(|(l, &g)| (g, l)).collect();
        let links: Vec<usize> = layout.links[index]
            .iter()
            .copied()
            .filter(|&l| !lines.is_line(l))
            .collect();
        let mut sub = scenario.clone();
        // A node that holds the whole model in the file's order (a monolithic run's)
        // shares the scenario's bodies and links: the model is held once.
        let whole = bodies.len() == scenario.bodies.len()
            && bodies.iter().enumerate().all(|(l, &g)| l == g)
            && links.len() == scenario.links.len()
            && links.iter().enumerate().all(|(k, &g)| k == g);
        if !whole {
            sub.bodies = bodies.iter().map(|&g| scenario.bodies[g].clone()).collect();
            sub.links = links
                .iter()
                .map(|&l| {
                    let mut spec = scenario.links[l].clone();
                    spec.a = local_body[&spec.a];
                    spec.b = local_body[&spec.b];
                    spec
                })
                .collect();
        }
        sub.forces = scenario
            .forces
            .iter()
            .filter(|f| local_body.get(&f.body).is_some_and(|&l| l < owned))
            .map(|f| {
                let mut f = f.clone();
                f.body = local_body[&f.body];
                f
            })
            .collect();
        // A spring's two bodies share a node (validation): its node computes it, on
        // its own bodies only (a ghost feels it through its owner's load).
        sub.springs = scenario
            .springs
            .iter()
            .filter(|s| local_body.get(&s.a).is_some_and(|&l| l < owned))
            .map(|s| {
                let mut s = s.clone();
                s.a = local_body[&s.a];
                s.b = s.b.map(|b| local_body[&b]);
                s
            })
            .collect();
        sub.partition = None;
        sub.channels.clear();
        let mut system = System::new(&sub);
        let state = State::initial(&sub);
        let mut incident = vec![Vec::new(); bodies.len()];
        for (l, link) in sub.links.iter().enumerate() {
            incident[link.a].push(l);
            incident[link.b].push(l);
        }
        let ghosts = scenario
            .partition
            .as_ref()
            .map_or(GhostMode::Integrate, |p| p.ghosts);
        let held_states = (owned..bodies.len())
            .map(|g| HeldState {
                p: state.p[g],
                v: state.v[g],
                q: state.q.get(g).copied(),
                omega: state.omega.get(g).copied(),
            })
            .collect();
        if ghosts == GhostMode::Hold {
            for g in owned..bodies.len() {
                system.set_immovable(g);
            }
        }
        // Border forces this node will receive: one per route into it.
        let held_forces = layout
            .routes
            .iter()
            .filter(|r| r.to == index && r.link.is_some_and(|l| !lines.is_line(l)))
            .filter_map(|r| {
                Some(HeldForce {
                    link: r.link?,
                    from: r.from,
                    body: local_body[&r.body],
                    value: Extrapolated::zero(),
                })
            })
            .collect::<Vec<HeldForce>>();
        let scheme = scenario
            .partition
            .as_ref()
            .map_or(Coupling::Reset, |p| p.coupling);
        let ghost_count = bodies.len() - owned;
        let predict_ghosts = scheme.predicts() && ghosts == GhostMode::Integrate;
        let coupling = CouplingState {
            scheme,
            history: if predict_ghosts {
                vec![GhostHistory::default(); ghost_count]
            } else {
                Vec::new()
            },
            ghost_loads: if scheme.predicts() {
                vec![Extrapolated::zero(); ghost_count]
            } else {
                Vec::new()
            },
            ports_out: if scheme.tank().is_some() {
                vec![PortAccount::default(); ghost_count]
            } else {
                Vec::new()
            },
            ports_in: Vec::new(),
            port_forces: Vec::new(),
            held_now: Vec::new(),
            side_powers: Vec::new(),
            end_powers: Vec::new(),
            own_masses: if scheme.tank().and_then(|t| t.share()).is_some() {
                bodies[..owned]
                    .iter()
                    .map(|&g| {
                        let b = &scenario.bodies[g];
                        (b.mass, b.inertia)
                    })
                    .collect()
            } else {
                Vec::new()
            },
            peak_kinetic: 0.0,
            driven_in: 0.0,
        };
        let mut coupling = coupling;
        if scheme.tank().is_some() {
            for (i, h) in held_forces.iter().enumerate() {
                match coupling
                    .ports_in
                    .iter()
                    .position(|p| p.0 == h.body && p.1 == h.from)
                {
                    Some(p) => coupling.port_forces[p].push(i),
                    None => {
                        coupling
                            .ports_in
                            .push((h.body, h.from, PortAccount::default()));
                        coupling.port_forces.push(vec![i]);
                    }
                }
            }
        }
        if scheme.predicts() {
            coupling.held_now = vec![(Vector3::zeros(), Vector3::zeros()); held_forces.len()];
        }
        let line_ends = line_ends(scenario, layout, index, lines, &local_body, owned);
        let momentum = (scheme.predicts() && layout.nodes > 1)
            .then(|| momentum_account(scenario, layout, index, (&held_forces, &line_ends), ghosts));
        Node {
            index,
            system,
            state,
            bodies,
            owned,
            links,
            local_body,
            incident,
            ghosts,
            held_forces,
            held_states,
            coupling,
            com: (!line_ends.is_empty() || scheme.tank().is_some())
                .then(|| ComReference::new(scenario)),
            momentum,
            lines: line_ends,
            reactions: scenario.ghosts_carry_reactions(),
            held_elsewhere: held_elsewhere(scenario, layout, index),
        }
    }

    /// The centre-of-mass velocity the border ports and lines measure against [m/s]
    /// (see [`ComReference`]; zero on a node that needs none).
    fn reference_velocity(&self) -> Vector3<f64> {
        self.com
            .as_ref()
            .map_or_else(Vector3::zeros, ComReference::velocity)
    }

    /// Local index of global body `g`, if this node holds it.
    pub fn local(&self, g: usize) -> Option<usize> {
        self.local_body.get(&g).copied()
    }

    /// A coordinate of owned body `g`'s state now: position x, y, z [m] for `quantity`
    /// 0–2, velocity [m/s] for 3–5 (a connection's `B<id>.px` … `B<id>.vz`).
    pub fn body_value(&self, g: usize, quantity: usize) -> f64 {
        let b = self
            .local(g)
            .expect("ok: a body connection samples on the body's own node");
        match quantity {
            0..=2 => self.state.p[b][quantity],
            _ => self.state.v[b][quantity - 3],
        }
    }

    /// A delivered force component on owned body `g` [N], held until the next.
    pub fn set_input_force(&mut self, g: usize, axis: usize, value: f64) {
        let b = self
            .local(g)
            .expect("ok: a body force is delivered to the body's own node");
        self.system.set_input_force(b, axis, value);
    }

    /// The state message for owned body `g` (global) to node `receiver`, at time `t`:
    /// the body's state and the owner-side load, i.e. the external force plus every link
    /// force on the body that the receiver does not compute itself (this node's links
    /// and the border forces received from nodes other than the receiver), with the
    /// load's rate when the coupling sends rates.
    pub fn state_payload(&self, t: SimTime, g: usize, receiver: usize) -> Payload {
        let i = self.local_body[&g];
        let rates = self.coupling.scheme.predicts();
        let mut force = Vector3::zeros();
        let mut torque = Vector3::zeros();
        let mut force_rate = Vector3::zeros();
        let mut torque_rate = Vector3::zeros();
        let mut step_rate = StepRate::default();
        for f in self.system.forces.iter().filter(|f| f.body == i) {
            if f.applied == LoadAt::Centre {
                force += f.at(t);
                if rates {
                    force_rate += f.rate_at(t);
                }
                continue;
            }
            let rotation = nalgebra::UnitQuaternion::new_normalize(self.state.q[i]);
            let (f_now, t_now) = f.load(t, &rotation);
            force += f_now;
            torque += t_now;
            if rates {
                let (fr, tr) = f.load_rate(t, &rotation, &self.state.omega[i]);
                force_rate += fr;
                torque_rate += tr;
            }
        }
        // The springs on it (held over the sample's age: a spring's force is the
        // state's, which the receiver's ghost carries forward).
        let (f, tq) = self.system.spring_load_on(&self.state, i);
        force += f;
        torque += tq;
        for &l in &self.incident[i] {
            if rates {
                let load = self.system.link_load_and_rate_on(&self.state, l, i);
                force += load.force;
                torque += load.torque;
                force_rate += load.force_rate;
                torque_rate += load.torque_rate;
                step_rate.force += load.step_force_rate;
                step_rate.torque += load.step_torque_rate;
            } else {
                let (f, tq) = self.system.link_load_on(&self.state, l, i);
                force += f;
                torque += tq;
            }
        }
        for h in self
            .held_forces
            .iter()
            .filter(|h| h.body == i && h.from != receiver)
        {
            let (f, tq) = self.held_load(h, t);
            force += f;
            torque += tq;
            if rates {
                force_rate += h.value.force_rate;
                torque_rate += h.value.torque_rate;
                let relayed = h.value.step_rate_at(t, self.coupling.scheme.extrapolate());
                step_rate.force += relayed.force;
                step_rate.torque += relayed.torque;
            }
        }
        for end in self.lines.iter().filter(|e| e.body == i) {
            force += end.load.0;
            torque += end.load.1;
        }
        // How this node's rows answer a load on the body: the receiver's ghost answers its
        // own rows' force through it, so the load sent leaves out the answer to the
        // force the receiver sent (`ΔL = −K M⁻¹ F_r`, added back here).
        let reaction = self
            .reactions
            .then(|| self.system.reaction_of(&self.state, i))
            .flatten();
        if let Some(k) = &reaction {
            let (mut f_r, mut t_r) = (Vector3::zeros(), Vector3::zeros());
            for h in self
                .held_forces
                .iter()
                .filter(|h| h.body == i && h.from == receiver)
            {
                let (f, tq) = self.held_load(h, t);
                f_r += f;
                t_r += tq;
            }
            let back = self.system.reaction_answer(&self.state, i, k, (f_r, t_r));
            force += back.0;
            torque += back.1;
        }
        let own = self.body_sample(i);
        Payload::State {
            body: g,
            p: own.p,
            v: own.v,
            q: own.q,
            omega: own.omega,
            force,
            torque,
            force_rate,
            torque_rate,
            step_rate,
            reaction: reaction.map(Box::new),
            energy: self
                .coupling
                .ports_in
                .iter()
                .find(|p| p.0 == i && p.1 == receiver)
                .map_or(0.0, |p| p.2.taken),
            lines: Vec::new(),
        }
    }

    /// The value of a held border force at `t`: as received (`reset`), or extrapolated
    /// with its rate (`predict`).
    fn held_load(&self, h: &HeldForce, t: SimTime) -> (Vector3<f64>, Vector3<f64>) {
        if self.coupling.scheme.predicts() {
            h.value.at(t, self.coupling.scheme.extrapolate())
        } else {
            (h.value.force, h.value.torque)
        }
    }

    /// The force message of owned border link `l` (global) on ghost body `g` (global),
    /// with its rate when the coupling sends rates.
    pub fn force_payload(&self, l: usize, g: usize) -> Payload {
        let ll = self.links.iter().position(|&x| x == l).unwrap_or_default();
        let body = self.local_body[&g];
        let load = |ll: usize| {
            if self.coupling.scheme.predicts() {
                self.system.link_load_and_rate_on(&self.state, ll, body)
            } else {
                let (force, torque) = self.system.link_load_on(&self.state, ll, body);
                RowLoad {
                    force,
                    torque,
                    ..RowLoad::default()
                }
            }
        };
        let mut sum = load(ll);
        // A joint's force is the sum of its rows' (consecutive here, as in the file):
        // one message for the whole joint.
        if let Some(joint) = self.system.links()[ll].joint {
            for next in ll + 1..self.links.len() {
                if self.system.links()[next].joint.map(|j| j.0) != Some(joint.0) {
                    break;
                }
                let row = load(next);
                sum.force += row.force;
                sum.torque += row.torque;
                sum.force_rate += row.force_rate;
                sum.torque_rate += row.torque_rate;
                sum.step_force_rate += row.step_force_rate;
                sum.step_torque_rate += row.step_torque_rate;
            }
        }
        // A body no other node's row holds answers this force with its own mass alone:
        // no loop runs through it, and the slopes are carried across the age as rates.
        let mut step_rate = StepRate {
            force: sum.step_force_rate,
            torque: sum.step_torque_rate,
        };
        let loop_free = !self
            .held_elsewhere
            .get(body - self.owned)
            .copied()
            .unwrap_or(true);
        if loop_free {
            sum.force_rate += step_rate.force;
            sum.torque_rate += step_rate.torque;
            step_rate = StepRate::default();
        }
        Payload::Force {
            link: l,
            body: g,
            force: sum.force,
            torque: sum.torque,
            force_rate: sum.force_rate,
            torque_rate: sum.torque_rate,
            step_rate,
            impulse: self
                .momentum
                .as_ref()
                .map_or_else(Vector3::zeros, |m| m.ghost_impulse[body - self.owned]),
            energy: self
                .coupling
                .ports_out
                .get(body - self.owned)
                .map_or(0.0, |p| p.taken),
        }
    }

    /// Applies a message from node `from`, sampled at `sent`, delivered while the
    /// node's state is that of time `state_time` (the next step's time).
    pub fn apply(&mut self, from: usize, sent: SimTime, state_time: SimTime, payload: &Payload) {
        match payload {
            Payload::State {
                body,
                p,
                v,
                q,
                omega,
                force,
                torque,
                force_rate,
                torque_rate,
                step_rate,
                reaction,
                energy,
                lines,
            } => {
                for sample in lines {
                    self.receive_line(sent, state_time, sample);
                }
                let Some(g) = self.local(*body) else { return };
                let k = g - self.owned;
                let rigid = self.state.is_rigid();
                if self.reactions {
                    self.system.set_reaction(g, reaction.as_deref().copied());
                }
                if let Some(port) = self.coupling.ports_out.get_mut(k) {
                    port.report(*energy);
                }
                match self.coupling.scheme {
                    Coupling::Predict { .. } | Coupling::Passive { .. } | Coupling::Tlm { .. } => {
                        self.coupling.ghost_loads[k] = Extrapolated {
                            force: *force,
                            torque: *torque,
                            force_rate: *force_rate,
                            torque_rate: *torque_rate,
                            step_rate: *step_rate,
                            step: self.system.dt(),
                            sent,
                        };
                    }
                    Coupling::Reset => {
                        self.system.extra_force[g] = *force;
                        if rigid {
                            self.system.extra_torque[g] = *torque;
                        }
                    }
                }
                let received = GhostSample {
                    p: *p,
                    v: *v,
                    q: *q,
                    omega: *omega,
                };
                let current = self.body_sample(g);
                if let Some(history) = self.coupling.history.get_mut(k) {
                    // Predict: shift the ghost (and its past from `sent` on) by the
                    // sample's error against the ghost's own state at `sent`.
                    let own = history.at(sent).cloned().unwrap_or(current);
                    let c = Correction::new(sent, &received, &own, rigid);
                    history.correct(&c, rigid);
                    let (ps, vs) = (&mut self.state.p[g], &mut self.state.v[g]);
                    if rigid {
                        let rot = Some((&mut self.state.q[g], &mut self.state.omega[g]));
                        c.apply(state_time, ps, vs, rot);
                    } else {
                        c.apply(state_time, ps, vs, None);
                    }
                } else {
                    self.state.p[g] = *p;
                    self.state.v[g] = *v;
                    if rigid {
                        self.state.q[g] = *q;
                        self.state.omega[g] = *omega;
                    }
                }
                let held = &mut self.held_states[k];
                held.p = *p;
                held.v = *v;
                held.q = self.state.q.get(g).copied();
                held.omega = self.state.omega.get(g).copied();
            }
            Payload::Line(sample) => self.receive_line(sent, state_time, sample),
            // The world hands FMU signals to the FMUs; no partition receives one.
            Payload::Signal { .. } => {}
            Payload::Force {
                link,
                force,
                torque,
                force_rate,
                torque_rate,
                step_rate,
                energy,
                body,
                impulse,
            } => {
                self.receive_port_impulse(from, (sent, state_time), *body, *impulse);
                if let Some(g) = self.local(*body) {
                    if let Some(p) = self
                        .coupling
                        .ports_in
                        .iter_mut()
                        .find(|p| p.0 == g && p.1 == from)
                    {
                        p.2.report(*energy);
                    }
                }
                let Some(h) = self
                    .held_forces
                    .iter_mut()
                    .find(|h| h.link == *link && h.from == from)
                else {
                    return;
                };
                h.value = Extrapolated {
                    force: *force,
                    torque: *torque,
                    force_rate: *force_rate,
                    torque_rate: *torque_rate,
                    step_rate: *step_rate,
                    step: self.system.dt(),
                    sent,
                };
                if self.coupling.scheme == Coupling::Reset {
                    let body = h.body;
                    let (mut f, mut t) = (Vector3::zeros(), Vector3::zeros());
                    for h in self.held_forces.iter().filter(|h| h.body == body) {
                        f += h.value.force;
                        t += h.value.torque;
                    }
                    self.system.extra_force[body] = f;
                    if self.state.is_rigid() {
                        self.system.extra_torque[body] = t;
                    }
                }
            }
        }
    }

    /// A force sample of the port (own body `g` global, node `from`) taken at `sent`,
    /// delivered while the node's state is that of `state_time`, says the sender's links
    /// had put `impulse` on their ghost of `g` by then: the port has made the difference
    /// to what this node had applied by then.
    fn receive_port_impulse(
        &mut self,
        from: usize,
        (sent, state_time): (SimTime, SimTime),
        g: usize,
        impulse: Vector3<f64>,
    ) {
        let Some(b) = self.local(g) else { return };
        let Some(m) = &mut self.momentum else { return };
        if !m.ports {
            return;
        }
        let Some(p) = m
            .incoming
            .iter()
            .position(|p| p.body == b && p.from == from)
        else {
            return;
        };
        let port = &mut m.incoming[p];
        let Some(&(_, applied)) = port.history.iter().find(|(t, _)| *t == sent) else {
            return;
        };
        while port.history.front().is_some_and(|(t, _)| *t <= sent) {
            port.history.pop_front();
        }
        m.ledger.port(p, applied - impulse, state_time);
    }

    /// The owner of global body `g` samples it for this node at `t` (the message leaves
    /// now): under `predict` and `passive` the node keeps its ghost's state of that time
    /// until the sample arrives. `t` is the time whose state the sample carries, which is
    /// also the time of this node's state.
    pub fn snapshot_ghost(&mut self, g: usize, t: SimTime) {
        let Some(local) = self.local(g) else { return };
        if local < self.owned || self.coupling.history.is_empty() {
            return;
        }
        let sample = self.body_sample(local);
        self.coupling.history[local - self.owned].snapshot(t, sample);
    }

    /// Local body `g`'s current state (identity orientation and zero angular velocity
    /// on point masses).
    fn body_sample(&self, g: usize) -> GhostSample {
        let rigid = self.state.is_rigid();
        GhostSample {
            p: self.state.p[g],
            v: self.state.v[g],
            q: if rigid {
                self.state.q[g]
            } else {
                Quaternion::identity()
            },
            omega: if rigid {
                self.state.omega[g]
            } else {
                Vector3::zeros()
            },
        }
    }

    /// Before the step at `t` (after every delivery at `t`): under `predict`, sets the
    /// extrapolated border forces and owner-side loads for this step and records the
    /// ghosts' states at `t`. Nothing under `reset`, whose loads change only on arrival,
    /// nor on a node without a border.
    pub fn prepare_step(&mut self, t: SimTime) {
        // Reset writes border forces as they arrive; a node with no border (a
        // monolithic scene) has no force to set, and its extra forces stay zero.
        let border = !self.held_forces.is_empty()
            || !self.coupling.ghost_loads.is_empty()
            || !self.lines.is_empty();
        if self.coupling.scheme == Coupling::Reset || !border {
            return;
        }
        let rigid = self.state.is_rigid();
        for b in 0..self.owned {
            self.system.extra_force[b] = Vector3::zeros();
            if rigid {
                self.system.extra_torque[b] = Vector3::zeros();
            }
        }
        let cap = self.coupling.scheme.extrapolate();
        for (h, now) in self.held_forces.iter().zip(&mut self.coupling.held_now) {
            *now = h.value.at(t, cap);
            self.system.extra_force[h.body] += now.0;
            if rigid {
                self.system.extra_torque[h.body] += now.1;
            }
        }
        for (k, load) in self.coupling.ghost_loads.iter().enumerate() {
            let g = self.owned + k;
            let (f, tq) = load.at(t, cap);
            self.system.extra_force[g] = f;
            if rigid {
                self.system.extra_torque[g] = tq;
            }
        }
        self.stage_rates(t, cap);
        if let Some(com) = &mut self.com {
            com.advance(t);
        }
        self.book_step_impulses(t, cap);
        if let Some(tank) = self.coupling.scheme.tank() {
            self.passivity(tank, t);
        }
        self.give_back_momentum();
        self.step_lines(t);
    }

    /// On a multi-stage integrator (RK4), the rates at which the border loads set for
    /// the step at `t` move over the step's stages: each held force and owner-side
    /// load carried by its own rate, as [`Extrapolated::at`] carries it between steps.
    /// Held over the stages instead, they would make a partitioned RK4 run first order.
    fn stage_rates(&mut self, t: SimTime, cap: SimTime) {
        if !self.system.is_multistage() {
            return;
        }
        let rate = &mut self.system.extra_rate;
        rate.from = t;
        rate.force.clear();
        rate.force.resize(self.bodies.len(), Vector3::zeros());
        rate.torque.clear();
        if self.state.is_rigid() {
            rate.torque.resize(self.bodies.len(), Vector3::zeros());
        }
        for h in &self.held_forces {
            let (f, tq) = h.value.rate_at(t, cap);
            rate.force[h.body] += f;
            if let Some(r) = rate.torque.get_mut(h.body) {
                *r += tq;
            }
        }
        for (k, load) in self.coupling.ghost_loads.iter().enumerate() {
            let g = self.owned + k;
            let (f, tq) = load.rate_at(t, cap);
            rate.force[g] = f;
            if let Some(r) = rate.torque.get_mut(g) {
                *r = tq;
            }
        }
    }

    /// The momentum this node's coupling has made (`J`, `partition::momentum`) as the
    /// state of step time `t` carries it, sent with its every message sampled at `t`;
    /// `None` where the coupling keeps no account.
    pub fn momentum_made(&self, t: SimTime) -> Option<Vector3<f64>> {
        self.momentum.as_ref().map(|m| m.ledger.own_at(t))
    }

    /// The impulse this node's passivity brake has applied so far (`None` where the
    /// coupling keeps no momentum account): what the net's momentum would be missing
    /// without the account's push.
    pub fn brake_impulse(&self) -> Option<Vector3<f64>> {
        self.momentum.as_ref().map(|m| m.ledger.braked())
    }

    /// Node `from`'s `J` as of its sample time `sent`.
    pub fn receive_momentum(&mut self, from: usize, sent: SimTime, made: Vector3<f64>) {
        if let Some(m) = &mut self.momentum {
            m.ledger.receive(from, sent, made);
        }
    }

    /// Node `from` samples its border forces on own body `g` (global) at `t`: keeps the
    /// impulse the port's forces have applied by then, to compare with the sender's
    /// when the sample arrives.
    pub fn snapshot_port(&mut self, g: usize, from: usize, t: SimTime) {
        let Some(b) = self.local(g) else { return };
        // Without integrating ghosts no port is booked, and nothing is kept for one.
        let Some(m) = self.momentum.as_mut().filter(|m| m.ports) else {
            return;
        };
        if let Some(p) = m
            .incoming
            .iter_mut()
            .find(|p| p.body == b && p.from == from)
        {
            if p.history.back().is_none_or(|(s, _)| *s < t) {
                p.history.push_back((t, p.applied));
            }
        }
    }

    /// Books, for the step at `t`, the impulse of the border forces this node applies
    /// to its own bodies (each port's) and of the owner-side loads on its ghosts (after
    /// [`Node::stage_rates`]), and
    /// keeps the ghosts' velocities at the step's start: a held force acts as
    /// `F + Ḟ·(t_stage − t)`, whose stages average `F h + Ḟ h²/2` over RK4 and `F h`
    /// over a single-stage step.
    fn book_step_impulses(&mut self, t: SimTime, cap: SimTime) {
        let Some(m) = &mut self.momentum else { return };
        if !m.ports {
            return;
        }
        let h = self.system.dt().as_secs_f64();
        let half = if self.system.is_multistage() {
            0.5 * h * h
        } else {
            0.0
        };
        for ((held, now), &p) in self
            .held_forces
            .iter()
            .zip(&self.coupling.held_now)
            .zip(&m.port_of)
        {
            m.incoming[p].applied += now.0 * h + held.value.rate_at(t, cap).0 * half;
        }
        // A ghost's extra force is its owner-side load, set (with its stage rate on a
        // multi-stage step) earlier in `prepare_step`.
        let rate = &self.system.extra_rate.force;
        for (k, step) in m.ghost_step.iter_mut().enumerate() {
            let g = self.owned + k;
            let r = rate.get(g).copied().unwrap_or_else(Vector3::zeros);
            *step = (self.state.v[g], self.system.extra_force[g] * h + r * half);
        }
    }

    /// After the step: the impulse this node's links put on each ghost over it, its
    /// momentum change less its owner-side load's impulse and gravity's.
    pub fn book_ghost_impulses(&mut self) {
        let Some(m) = &mut self.momentum else { return };
        if !m.ports {
            return;
        }
        let h = self.system.dt().as_secs_f64();
        let gravity = self.system.gravity.unwrap_or_else(Vector3::zeros);
        for (k, (v0, load)) in m.ghost_step.iter().enumerate() {
            let mass = m.ghost_mass[k];
            if self.system.mass.inv_mass[self.owned + k] == 0.0 {
                continue;
            }
            // A ghost carrying its owner's reaction answers this node's rows with its
            // owner's subsystem, not its own mass: their impulse is booked as applied.
            if let Some(impulse) = self.system.row_impulse(self.owned + k) {
                m.ghost_impulse[k] += impulse;
                continue;
            }
            let dv = self.state.v[self.owned + k] - v0;
            m.ghost_impulse[k] += dv * mass - load - gravity * (mass * h);
        }
    }

    /// Pushes this node's own bodies, in proportion to their masses, by the share of
    /// the coupling's momentum that has come due, as a constant force over the step
    /// (`partition::momentum`).
    fn give_back_momentum(&mut self) {
        let Some(m) = &mut self.momentum else {
            return;
        };
        let ledger = &mut m.ledger;
        let h = self.system.dt().as_secs_f64();
        let due = ledger.due(h);
        if due == Vector3::zeros() {
            return;
        }
        for (b, w) in ledger.weights().iter().enumerate() {
            self.system.extra_force[b] += due * (w / h);
        }
    }

    /// After a step in `hold` mode, puts every ghost back at its held state.
    pub fn restore_held_ghosts(&mut self) {
        if self.ghosts != GhostMode::Hold {
            return;
        }
        for (k, h) in self.held_states.iter().enumerate() {
            let g = self.owned + k;
            self.state.p[g] = h.p;
            self.state.v[g] = h.v;
            if let (Some(q), Some(w)) = (h.q, h.omega) {
                self.state.q[g] = q;
                self.state.omega[g] = w;
            }
        }
    }
}

/// Node `index`'s momentum account: one ledger slot per incoming port (an own body and
/// the node sending held forces on it) and per line end that is not the link owner's;
/// its ghosts' masses (order of `layout.ghosts`).
fn momentum_account(
    scenario: &Scenario,
    layout: &Layout,
    index: usize,
    (held, lines): (&[HeldForce], &[LineEnd]),
    ghosts: GhostMode,
) -> MomentumAccount {
    let mut incoming: Vec<IncomingPort> = Vec::new();
    let mut port_of = Vec::with_capacity(held.len());
    for h in held {
        let p = incoming
            .iter()
            .position(|p| p.body == h.body && p.from == h.from)
            .unwrap_or_else(|| {
                incoming.push(IncomingPort {
                    body: h.body,
                    from: h.from,
                    applied: Vector3::zeros(),
                    history: Default::default(),
                });
                incoming.len() - 1
            });
        port_of.push(p);
    }
    let masses: Vec<f64> = scenario.bodies.iter().map(|b| b.mass).collect();
    let ghost_count = layout.ghosts[index].len();
    let mut slots = incoming.len();
    let line_slot = lines
        .iter()
        .map(|e| {
            (!e.owner_side).then(|| {
                slots += 1;
                slots - 1
            })
        })
        .collect();
    MomentumAccount {
        ledger: MomentumLedger::new(index, layout, &masses, slots),
        line_slot,
        ports: ghosts == GhostMode::Integrate,
        incoming,
        port_of,
        ghost_impulse: vec![Vector3::zeros(); ghost_count],
        ghost_step: vec![(Vector3::zeros(), Vector3::zeros()); ghost_count],
        ghost_mass: layout.ghosts[index].iter().map(|&g| masses[g]).collect(),
    }
}

/// Node `index`'s ends of the lines in `lines`: one per line whose body it owns.
fn line_ends(
    scenario: &Scenario,
    layout: &Layout,
    index: usize,
    lines: &LineSet,
    local_body: &BTreeMap<usize, usize>,
    owned: usize,
) -> Vec<LineEnd> {
    if !lines.any() {
        return Vec::new();
    }
    let rigid = scenario.body_model == BodyModel::Rigid;
    let anchor_at = |b: usize, r: &Vector3<f64>| {
        let body = &scenario.bodies[b];
        if rigid {
            let rr = body.orientation * r;
            (
                body.position + rr,
                body.velocity + body.angular_velocity.cross(&rr),
            )
        } else {
            (body.position, body.velocity)
        }
    };
    let reference = ComReference::new(scenario).velocity();
    // How far the integrator's fall lags the continuous one (see LineEnd::falling).
    let dt = scenario.dt.as_secs_f64();
    let gravity_lag = match scenario.integrator {
        Integrator::Euler => -dt,
        Integrator::SymplecticEuler => dt,
        Integrator::Rk4 => 0.0,
    };
    let mut ends = Vec::new();
    for (l, link) in scenario.links.iter().enumerate() {
        let Some((z, delay)) = lines.impedance(l) else {
            continue;
        };
        let (pa, va) = anchor_at(link.a, &link.anchor_a);
        let (pb, vb) = anchor_at(link.b, &link.anchor_b);
        let stretch = (pa - pb).norm() - link.length;
        let n_ab = (pb - pa).normalize();
        for (own, anchor, far, far_anchor) in [
            (link.a, link.anchor_a, link.b, link.anchor_b),
            (link.b, link.anchor_b, link.a, link.anchor_a),
        ] {
            let Some(&local) = local_body.get(&own).filter(|&&b| b < owned) else {
                continue;
            };
            let (p, v) = anchor_at(far, &far_anchor);
            let far_node = layout.node_of[far];
            // This end's port velocity: half the link's extension rate.
            let rate = if own == link.a {
                -n_ab.dot(&(va - reference))
            } else {
                n_ab.dot(&(vb - reference))
            };
            ends.push(
                LineEnd::new(
                    l,
                    local,
                    anchor,
                    (far, far_node, p, v),
                    layout.link_owner[l] == index,
                    (z, delay),
                    initial_wave(z, delay, stretch, rate),
                )
                .falling(scenario.gravity, gravity_lag),
            );
        }
    }
    ends
}
