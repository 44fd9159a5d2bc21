//! One computing node: its own bodies, its ghosts, its links, and the held values of
//! what it last received.

use std::collections::BTreeMap;

use nalgebra::{Quaternion, Vector3};

use super::Layout;
use crate::kernel::SimTime;
use crate::multibody::{State, System};
use crate::network::Payload;
use crate::scenario::model::{GhostMode, Scenario};

/// A border force received from another node, held until the next arrival.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
struct HeldForce {
    /// Global link index.
    link: usize,
    /// Sending node.
    from: usize,
    /// Local body index it acts on.
    body: usize,
    force: Vector3<f64>,
    torque: Vector3<f64>,
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
}

impl Node {
    /// Builds node `index` of `layout` for `scenario`.
    pub fn new(scenario: &Scenario, layout: &Layout, index: usize) -> Node {
        let owned = layout.owned[index].len();
        let bodies: Vec<usize> = layout.owned[index]
            .iter()
            .chain(&layout.ghosts[index])
            .copied()
            .collect();
        let local_body: BTreeMap<usize, usize> =
            bodies.iter().enumerate().map(|(l, &g)| (g, l)).collect();
        let links = layout.links[index].clone();
        let mut sub = scenario.clone();
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
            .filter(|r| r.to == index && r.link.is_some())
            .filter_map(|r| {
                Some(HeldForce {
                    link: r.link?,
                    from: r.from,
                    body: local_body[&r.body],
                    force: Vector3::zeros(),
                    torque: Vector3::zeros(),
                })
            })
            .collect();
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
        }
    }

    /// Local index of global body `g`, if this node holds it.
    pub fn local(&self, g: usize) -> Option<usize> {
        self.local_body.get(&g).copied()
    }

    /// The state message for owned body `g` (global) to node `receiver`, at time `t`:
    /// the body's state and the owner-side load, i.e. the external force plus every link
    /// force on the body that the receiver does not compute itself (this node's links
    /// and the border forces held from nodes other than the receiver).
    pub fn state_payload(&self, t: SimTime, g: usize, receiver: usize) -> Payload {
        let i = self.local_body[&g];
        let mut force = Vector3::zeros();
        let mut torque = Vector3::zeros();
        for f in self.system.forces.iter().filter(|f| f.body == i) {
            force += f.at(t);
        }
        for &l in &self.incident[i] {
            let (f, tq) = self.system.link_load_on(&self.state, l, i);
            force += f;
            torque += tq;
        }
        for h in self
            .held_forces
            .iter()
            .filter(|h| h.body == i && h.from != receiver)
        {
            force += h.force;
            torque += h.torque;
        }
        Payload::State {
            body: g,
            p: self.state.p[i],
            v: self.state.v[i],
            q: self
                .state
                .q
                .get(i)
                .copied()
                .unwrap_or_else(Quaternion::identity),
            omega: self
                .state
                .omega
                .get(i)
                .copied()
                .unwrap_or_else(Vector3::zeros),
            force,
            torque,
        }
    }

    /// The force message of owned border link `l` (global) on ghost body `g` (global).
    pub fn force_payload(&self, l: usize, g: usize) -> Payload {
        let ll = self.links.iter().position(|&x| x == l).unwrap_or_default();
        let (force, torque) = self
            .system
            .link_load_on(&self.state, ll, self.local_body[&g]);
        Payload::Force {
            link: l,
            body: g,
            force,
            torque,
        }
    }

    /// Applies a delivered message from node `from`.
    pub fn apply(&mut self, from: usize, payload: &Payload) {
        match payload {
            Payload::State {
                body,
                p,
                v,
                q,
                omega,
                force,
                torque,
            } => {
                let Some(g) = self.local(*body) else { return };
                self.state.p[g] = *p;
                self.state.v[g] = *v;
                if self.state.is_rigid() {
                    self.state.q[g] = *q;
                    self.state.omega[g] = *omega;
                    self.system.extra_torque[g] = *torque;
                }
                self.system.extra_force[g] = *force;
                let held = &mut self.held_states[g - self.owned];
                held.p = *p;
                held.v = *v;
                held.q = self.state.q.get(g).copied();
                held.omega = self.state.omega.get(g).copied();
            }
            Payload::Force {
                link,
                force,
                torque,
                ..
            } => {
                let Some(h) = self
                    .held_forces
                    .iter_mut()
                    .find(|h| h.link == *link && h.from == from)
                else {
                    return;
                };
                h.force = *force;
                h.torque = *torque;
                let body = h.body;
                let (mut f, mut t) = (Vector3::zeros(), Vector3::zeros());
                for h in self.held_forces.iter().filter(|h| h.body == body) {
                    f += h.force;
                    t += h.torque;
                }
                self.system.extra_force[body] = f;
                if self.state.is_rigid() {
                    self.system.extra_torque[body] = t;
                }
            }
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
