//! Where a node's border starts under Baumgarte's exact multipliers: at the whole
//! model's multipliers at t = 0 (see [`Node::start_consistent`]).

use std::collections::BTreeSet;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::Node;
use crate::kernel::SimTime;
use crate::multibody::{State, System};
use crate::partition::coupling::Extrapolated;
use crate::scenario::model::{Scenario, Stabilizer};

/// A force [N] and a torque [N·m].
type Load = (Vector3<f64>, Vector3<f64>);

/// The whole model evaluated once at t = 0, with what every node reads of it gathered
/// per body in one pass over the model (so a node's start costs its own size, not the
/// model's).
pub struct WholeStart {
    system: System,
    initial: State,
    /// The rows incident to each body (world rows under their body only).
    rows_of_body: Vec<Vec<usize>>,
    /// The external forces and springs on each body at t = 0.
    loads: Vec<Load>,
}

impl WholeStart {
    /// The whole model of a partitioned Baumgarte `scenario` at t = 0; `None` under SMC,
    /// on one node, or when the evaluation fails (the first step then reports it).
    pub fn new(scenario: &Scenario, nodes: usize) -> Option<WholeStart> {
        if nodes < 2 || !matches!(scenario.stabilizer, Stabilizer::Baumgarte { .. }) {
            return None;
        }
        let initial = State::initial(scenario);
        let mut system = System::new(scenario);
        system.begin_step(SimTime::ZERO, &initial).ok()?;
        let mut rows_of_body = vec![Vec::new(); scenario.bodies.len()];
        for (r, link) in scenario.links.iter().enumerate() {
            rows_of_body[link.a].push(r);
            if !link.world {
                rows_of_body[link.b].push(r);
            }
        }
        let mut loads: Vec<Load> = (0..scenario.bodies.len())
            .map(|g| system.spring_load_on(&initial, g))
            .collect();
        for f in &scenario.forces {
            let q = initial
                .q
                .get(f.body)
                .copied()
                .unwrap_or_else(Quaternion::identity);
            let (force, torque) = f.load(SimTime::ZERO, &UnitQuaternion::new_normalize(q));
            loads[f.body].0 += force;
            loads[f.body].1 += torque;
        }
        Some(WholeStart {
            system,
            initial,
            rows_of_body,
            loads,
        })
    }

    /// The load of `rows` on body `g` at t = 0 (lines, which carry waves, left out).
    fn rows_on(&self, node: &Node, rows: impl Iterator<Item = usize>, g: usize) -> Load {
        rows.filter(|&r| node.line_index(r).is_none())
            .map(|r| self.system.link_load_on(&self.initial, r, g))
            .fold((Vector3::zeros(), Vector3::zeros()), |a, b| {
                (a.0 + b.0, a.1 + b.1)
            })
    }
}

impl Node {
    /// Starts the border from the whole model's initial multipliers: this node's rows'
    /// multipliers, the border forces it holds and its ghosts' owner-side loads as
    /// `whole` has them at t = 0.
    ///
    /// Why: under Baumgarte the multipliers are algebraic, and at t = 0 a node knows
    /// neither the forces of the rows it does not hold nor the loads on its ghosts
    /// before a message brings them, a sample period later. Its first samples (taken
    /// before the first step) then carried no force, or one that left out the load
    /// behind a ghost: a hanging chain split at a border joint started with its lower
    /// half unsupported, the error was of order dt (a partitioned RK4 run fell to first
    /// order), and a chain at rest was set swinging. The monolithic solve at t = 0 is
    /// what every node would agree on with an instant network; from there on each
    /// node's own law and messages take over. Under SMC the multipliers are state and
    /// start at zero on every node alike, so this is not used (and the thesis scenes
    /// keep their digests).
    pub fn start_consistent(&mut self, whole: &WholeStart, scenario: &Scenario) {
        let joint_of = |r: usize| scenario.links[r].joint.map(|(j, _)| j);
        // The rows of the link or joint whose first row is `l` (a joint's rows are
        // consecutive).
        let rows_of = |l: usize| {
            let j = joint_of(l);
            (l..scenario.links.len())
                .take_while(move |&r| r == l || (j.is_some() && joint_of(r) == j))
        };
        let held_here: BTreeSet<usize> = self.links.iter().copied().collect();
        let z: Vec<f64> = self
            .links
            .iter()
            .map(|&l| whole.system.multiplier(&whole.initial, l))
            .collect();
        let held: Vec<Load> = self
            .held_forces
            .iter()
            .map(|h| whole.rows_on(self, rows_of(h.link), self.bodies[h.body]))
            .collect();
        // A ghost's owner-side load: every load on it but the rows this node holds.
        let ghosts: Vec<Load> = (self.owned..self.bodies.len())
            .map(|k| {
                let g = self.bodies[k];
                let others = whole.rows_of_body[g]
                    .iter()
                    .copied()
                    .filter(|r| !held_here.contains(r));
                let (force, torque) = whole.rows_on(self, others, g);
                (force + whole.loads[g].0, torque + whole.loads[g].1)
            })
            .collect();
        self.system.set_multipliers(&z);
        for (h, (force, torque)) in self.held_forces.iter_mut().zip(held) {
            h.value = Extrapolated {
                force,
                torque,
                ..Extrapolated::zero()
            };
        }
        for (load, (force, torque)) in self.coupling.ghost_loads.iter_mut().zip(ghosts) {
            *load = Extrapolated {
                force,
                torque,
                ..Extrapolated::zero()
            };
        }
    }
}
