//! The momentum a delayed coupling makes or takes, measured and given back to the net as
//! a whole.
//!
//! Two things in a predicting coupling are not equal-and-opposite pairs at every
//! instant. A border link's owner applies its constraint force to its own body now,
//! while the far body's owner applies the force it received, extrapolated from a sample
//! τ old: the two impulses differ by what the extrapolation missed, and that difference
//! accumulates (the thesis net driven for 24 s and left free had moved its momentum by
//! 8–13 kg·m/s at τ = 10–20 ms). And the `passive` brake, `−c (v − V)` on one body, is
//! an external force: alone it takes momentum away with the energy it removes.
//!
//! Both are measured exactly. For each border port (a ghosted body and the node that
//! ghosts it) the ghosting node integrates the impulse its links put on the ghost — the
//! ghost's momentum change over each step less its owner-side load and gravity, so the
//! stages of any integrator are counted as they were applied (a ghost carrying its
//! owner's reaction answers the links with its owner's subsystem, so there the links'
//! force itself is summed with the stages' weights) — and sends the running
//! total with each force sample; the body's owner keeps the running total of the border
//! forces it applied, as of each sample time, and books the difference when the sample
//! arrives: the momentum the port has made. The brake books its impulse as it acts.
//!
//! What a node has booked, `J_k`, rides every message it sends, so the nodes it sends to
//! learn it one channel delay later. It is given back as a **uniform acceleration**: node
//! `k` and its receivers `N_k` each push all their bodies in proportion to mass, node `i`
//! taking `M_i / M(N_k)` of `−J_k`. A uniform acceleration changes no body's motion
//! relative to the others (no link length, no constraint force, no energy of relative
//! motion), so it cannot destabilize the coupling as a force on the border body would;
//! the shares of every `J_k` sum to one, so the net's momentum is again what the
//! external forces made it, up to the impulse of the reports still in flight.

use nalgebra::Vector3;

use super::Layout;
use crate::kernel::SimTime;

/// The time constant over which a node gives back what has come due [s].
///
/// *Choice*, measured with the default coupling (latency = τ). On the thesis net driven
/// until 2 s and free to 6 s, the worst momentum error against the monolithic run at
/// τ = 5 / 10 / 20 ms and the kinetic energy change (monolithic +3.9 %):
///
/// | push time | momentum [kg·m/s] | kinetic energy |
/// |---|---|---|
/// | one step | 0.23 / 0.17 / 1.13 | +2.1 / +3.4 / −1.3 % |
/// | 10 ms | 0.35 / 0.20 / 1.21 | +2.5 / +3.7 / −0.4 % |
/// | 100 ms | 0.95 / 0.33 / 1.68 | +2.7 / +3.9 / +1.0 % |
///
/// But a push that follows the account within 10 ms follows its swings (the impulse a
/// predicted force misses and makes up a moment later) with forces of several newtons
/// per node, pushing neighbourhoods against each other: the 16-node 8×8 scene diverged
/// at 4.6 s at τ = 5 ms and the thesis scene at 9.0 s at 50 ms. At 100 ms every test
/// scene holds (max |w| 0.28 and 0.89 m there) except the 100 kg / 0.01 kg grid at
/// 20 ms (2.74 s); 120–500 ms each broke another scene or the frame test (method §3.1
/// has the whole search).
pub const PUSH_TIME: f64 = 0.1;

/// One node's account of the momentum its coupling made (see the module).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MomentumLedger {
    /// This node's index.
    index: usize,
    /// Per node `k`: this node's share of `k`'s account (zero outside `N_k`).
    shares: Vec<f64>,
    /// Per node `k`: the sample time and `J_k` of the newest report (this node's own
    /// entry is kept current by [`MomentumLedger::own`]).
    known: Vec<(SimTime, Vector3<f64>)>,
    /// What this node's brake has applied [N·s].
    braked: Vector3<f64>,
    /// Per incoming port: the momentum it made as of its newest force sample, booked
    /// for the steps from `.1` on, and the value before that [N·s].
    ports: Vec<(Vector3<f64>, SimTime, Vector3<f64>)>,
    /// The push applied to this node's bodies so far [N·s].
    applied: Vector3<f64>,
    /// Each own body's share of the node's push (its mass over the node's), in the
    /// node's local order.
    weights: Vec<f64>,
}

impl MomentumLedger {
    /// The ledger of node `index` of `layout` with `ports` incoming border ports, the
    /// bodies' masses `masses` (global order).
    pub fn new(index: usize, layout: &Layout, masses: &[f64], ports: usize) -> MomentumLedger {
        let node_mass: Vec<f64> = layout
            .owned
            .iter()
            .map(|bodies| bodies.iter().map(|&b| masses[b]).sum())
            .collect();
        let shares = (0..layout.nodes)
            .map(|k| {
                let mut members = vec![k];
                members.extend(layout.routes.iter().filter(|r| r.from == k).map(|r| r.to));
                members.sort_unstable();
                members.dedup();
                if members.binary_search(&index).is_err() {
                    return 0.0;
                }
                let total: f64 = members.iter().map(|&n| node_mass[n]).sum();
                node_mass[index] / total
            })
            .collect();
        let own = &layout.owned[index];
        MomentumLedger {
            index,
            weights: own.iter().map(|&b| masses[b] / node_mass[index]).collect(),
            shares,
            known: vec![(SimTime::ZERO, Vector3::zeros()); layout.nodes],
            braked: Vector3::zeros(),
            ports: vec![(Vector3::zeros(), SimTime::ZERO, Vector3::zeros()); ports],
            applied: Vector3::zeros(),
        }
    }

    /// Each own body's share of the node's push, in the node's local order.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// What this node's brake has applied so far [N·s].
    pub fn braked(&self) -> Vector3<f64> {
        self.braked
    }

    /// Books an impulse of this node's brake [N·s].
    pub fn brake(&mut self, impulse: Vector3<f64>) {
        self.braked += impulse;
    }

    /// Sets the momentum incoming port `p` has made, as of its newest sample, for the
    /// steps from `from` (the node's next step) on [N·s].
    pub fn port(&mut self, p: usize, made: Vector3<f64>, from: SimTime) {
        let entry = &mut self.ports[p];
        if from > entry.1 {
            entry.2 = entry.0;
            entry.1 = from;
        }
        entry.0 = made;
    }

    /// This node's `J` now [N·s].
    pub fn own(&self) -> Vector3<f64> {
        self.ports.iter().map(|p| p.0).sum::<Vector3<f64>>() + self.braked
    }

    /// This node's `J` as the state of step time `t` carries it, for a message sampled
    /// at `t`: a port booked for the steps from `t` on is counted at its previous value,
    /// so the message is the same whether the channel samples before or after that
    /// booking's delivery at `t` (an ideal channel samples at the boundary, a TDMA
    /// frame between boundaries) [N·s].
    pub fn own_at(&self, t: SimTime) -> Vector3<f64> {
        let ports: Vector3<f64> = self
            .ports
            .iter()
            .map(|&(now, from, before)| if from < t { now } else { before })
            .sum();
        ports + self.braked
    }

    /// Node `from`'s `J` as of sample time `sent` (reports may arrive out of order: the
    /// newest is kept).
    pub fn receive(&mut self, from: usize, sent: SimTime, made: Vector3<f64>) {
        let entry = &mut self.known[from];
        if from != self.index && sent >= entry.0 {
            *entry = (sent, made);
        }
    }

    /// The push this node's bodies take over a step of `h` [s]: the share of the
    /// coupling's momentum due to them and not yet applied, spread over
    /// [`PUSH_TIME`] (a first-order approach, so nodes that learn of a booking one
    /// or two delays apart push together and the net does not jolt) [N·s]; counted as
    /// applied.
    pub fn due(&mut self, h: f64) -> Vector3<f64> {
        self.known[self.index].1 = self.own();
        let target: Vector3<f64> = self
            .known
            .iter()
            .zip(&self.shares)
            .map(|((_, j), s)| -j * *s)
            .sum();
        let due = (target - self.applied) * (h / PUSH_TIME).min(1.0);
        self.applied += due;
        due
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::partition::layout::Route;
    use crate::scenario::model::DataKind;

    /// Three nodes in a line, 0 → 1 → 2 and back, of masses 1, 2 and 3 kg.
    fn line_layout() -> Layout {
        let route = |from, to| Route {
            kind: DataKind::State,
            from,
            to,
            body: to,
            link: None,
        };
        Layout {
            nodes: 3,
            node_of: vec![0, 1, 2],
            link_owner: Vec::new(),
            owned: vec![vec![0], vec![1], vec![2]],
            ghosts: vec![Vec::new(); 3],
            links: vec![Vec::new(); 3],
            routes: vec![route(0, 1), route(1, 0), route(1, 2), route(2, 1)],
        }
    }

    #[test]
    fn what_a_node_books_is_given_back_whole_once_its_reports_arrive() {
        let layout = line_layout();
        let masses = [1.0, 2.0, 3.0];
        let mut nodes: Vec<MomentumLedger> = (0..3)
            .map(|i| MomentumLedger::new(i, &layout, &masses, 1))
            .collect();
        // Node 0's brake takes 6 N·s, node 1's port made 15 N·s and its brake took 3.
        nodes[0].brake(Vector3::new(6.0, 0.0, 0.0));
        nodes[1].port(0, Vector3::new(15.0, 0.0, 0.0), SimTime::ZERO);
        nodes[1].brake(Vector3::new(-3.0, 0.0, 0.0));
        let now: Vec<Vector3<f64>> = nodes.iter_mut().map(|n| n.due(1.0)).collect();
        // Before any report, each node gives back its own share of its own account:
        // node 0's N = {0, 1} (1 of 3 kg), node 1's N = {0, 1, 2} (2 of 6 kg).
        assert!((now[0].x + 2.0).abs() < 1e-12);
        assert!((now[1].x + 4.0).abs() < 1e-12);
        assert_eq!(now[2], Vector3::zeros());
        // The reports arrive (node 0's at node 1, node 1's at nodes 0 and 2).
        let ms = SimTime(1_000_000);
        let (j0, j1) = (nodes[0].own(), nodes[1].own());
        nodes[1].receive(0, ms, j0);
        nodes[0].receive(1, ms, j1);
        nodes[2].receive(1, ms, j1);
        let later: Vec<Vector3<f64>> = nodes.iter_mut().map(|n| n.due(1.0)).collect();
        let total: Vector3<f64> = now.iter().chain(&later).sum();
        assert!((total.x + 18.0).abs() < 1e-12, "given back {total}");
        // A port's account is replaced, not added: a newer sample of the same port.
        nodes[1].port(0, Vector3::new(10.0, 0.0, 0.0), SimTime::ZERO);
        assert!((nodes[1].own().x - 7.0).abs() < 1e-12);
        // A stale report does not roll back, and nothing is given twice.
        nodes[0].receive(1, SimTime::ZERO, Vector3::zeros());
        assert_eq!(nodes[0].due(1.0), Vector3::zeros());
    }
}
