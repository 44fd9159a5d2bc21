//! A multibody partition as a [`Unit`] of the world: it sends its border bodies' states
//! and its border links' loads (or transmission-line waves) and a body's quantity for
//! a signal connection, takes what its neighbours and FMUs send it, and steps in two
//! halves — border loads and rates at `t` (the observers then see the step), then the
//! integration to `t + dt`.

use rayon::prelude::*;

use super::unit::Unit;
use crate::error::{Divergence, Error, Result};
use crate::kernel::SimTime;
use crate::multibody::dynamics::EvalError;
use crate::multibody::solver::BATCH;
use crate::multibody::System;
use crate::network::route::Route;
use crate::network::{Message, Payload};
use crate::partition::Node;
use crate::scenario::model::{DataKind, Scenario, SignalSink, SignalSource};

impl Unit for Node {
    fn sample(
        &mut self,
        t: SimTime,
        channel: usize,
        route: &Route,
        scenario: &Scenario,
    ) -> Option<Message> {
        let payload = match (route.kind, route.link) {
            (DataKind::Signal, _) => {
                let SignalSource::Body { body, quantity } = scenario.connections[route.body].from
                else {
                    return None;
                };
                let value = self.body_value(body, quantity);
                let connection = route.body;
                let payload = Payload::Signal { connection, value };
                return Some(Message::on(route, channel, t, payload, None));
            }
            (DataKind::State, _) => {
                let mut payload = self.state_payload(t, route.body, route.to);
                if let Payload::State { lines, .. } = &mut payload {
                    *lines = self.line_samples_to(t, route.body, route.to);
                }
                payload
            }
            (DataKind::Force, Some(l)) if self.line_index(l).is_some() => {
                Payload::Line(self.line_sample(t, l)?)
            }
            (DataKind::Force, Some(l)) => self.force_payload(l, route.body),
            (DataKind::Force, None) => return None,
        };
        Some(Message::on(
            route,
            channel,
            t,
            payload,
            self.momentum_made(t),
        ))
    }

    fn sampled(&mut self, msg: &Message) {
        match msg.payload {
            Payload::State { body, .. } => self.snapshot_ghost(body, msg.sent),
            Payload::Force { body, .. } => self.snapshot_port(body, msg.from, msg.sent),
            Payload::Line(sample) => self.snapshot_line(sample.link, msg.sent),
            Payload::Signal { .. } => {}
        }
    }

    fn deliver(&mut self, msg: &Message, state_time: SimTime, scenario: &Scenario) {
        if let Payload::Signal { connection, value } = msg.payload {
            if let SignalSink::BodyForce { body, axis } = scenario.connections[connection].to {
                self.set_input_force(body, axis, value);
            }
            return;
        }
        if let Some(made) = msg.momentum {
            self.receive_momentum(msg.from, msg.sent, made);
        }
        self.apply(msg.from, msg.sent, state_time, &msg.payload);
    }

    /// The nodes' rate evaluations batched (results and first error as if evaluated
    /// one after another in node order), on rayon when `parallel`; a monolithic
    /// world's one node has no border to prepare.
    fn begin_steps(
        nodes: &mut [Node],
        t: SimTime,
        scenario: &Scenario,
        parallel: bool,
    ) -> Result<()> {
        let result = if parallel {
            begin_parallel(nodes, t)
        } else if let [node] = &mut nodes[..] {
            node.system.begin_step(t, &node.state).map_err(|e| (0, e))
        } else {
            for node in nodes.iter_mut() {
                node.prepare_step(t);
            }
            let systems = nodes.iter_mut().map(|n| (&mut n.system, &n.state));
            System::begin_steps(t, systems)
        };
        result.map_err(|(n, e)| eval_error(&nodes[n], t, e, scenario))
    }

    fn finish_steps(
        nodes: &mut [Node],
        t: SimTime,
        _dt: SimTime,
        scenario: &Scenario,
        parallel: bool,
    ) -> Result<()> {
        if parallel {
            return finish_parallel(nodes, t)
                .map_err(|(n, e)| eval_error(&nodes[n], t, e, scenario));
        }
        for node in nodes.iter_mut() {
            finish_node(node, t).map_err(|e| eval_error(node, t, e, scenario))?;
        }
        Ok(())
    }
}

/// The second half of node `node`'s step at `t` (the first error stops it where the
/// serial lock-step stops).
fn finish_node(node: &mut Node, t: SimTime) -> std::result::Result<(), EvalError> {
    node.system.finish_step(t, &mut node.state)?;
    node.book_ghost_impulses();
    node.restore_held_ghosts();
    Ok(())
}

/// Each node's border loads and rates at `t`, the nodes spread over rayon's threads;
/// the error of the lowest node that fails, as the serial lock-step reports it.
///
/// Nodes with the dense exact solve go in chunks of [`BATCH`] (their solves interleave
/// as in [`System::begin_steps`]), any other node on its own. Every node is prepared
/// and evaluated, and the errors are reduced to the lowest node's, whatever thread
/// finished first. Unlike the serial loop, nodes after a failing one have been
/// evaluated too, which nothing reads: the run stops with that error, and an
/// evaluation touches only the node's system (its workspace), not its state or its
/// port accounts; every node is prepared, as in the serial lock-step.
fn begin_parallel(nodes: &mut [Node], t: SimTime) -> std::result::Result<(), (usize, EvalError)> {
    let chunk = if nodes.iter().all(|n| n.system.solver.is_dense()) {
        BATCH
    } else {
        1
    };
    let first = nodes
        .par_chunks_mut(chunk)
        .enumerate()
        .filter_map(|(c, group)| {
            for node in group.iter_mut() {
                node.prepare_step(t);
            }
            let systems = group.iter_mut().map(|n| (&mut n.system, &n.state));
            System::begin_steps(t, systems)
                .err()
                .map(|(i, e)| (c * chunk + i, e))
        })
        .min_by_key(|&(n, _)| n);
    first.map_or(Ok(()), Err)
}

/// [`finish_node`] of every node, spread over rayon's threads; the lowest failing
/// node's error (the run stops with it: the states of the nodes after it, stepped here
/// and not in the serial loop, are not read).
fn finish_parallel(nodes: &mut [Node], t: SimTime) -> std::result::Result<(), (usize, EvalError)> {
    let first = nodes
        .par_iter_mut()
        .enumerate()
        .filter_map(|(n, node)| finish_node(node, t).err().map(|e| (n, e)))
        .min_by_key(|&(n, _)| n);
    first.map_or(Ok(()), Err)
}

/// Node `node`'s evaluation error at `t` as the run's error, naming the node and the
/// link.
fn eval_error(node: &Node, t: SimTime, e: EvalError, scenario: &Scenario) -> Error {
    let n = node.index;
    match e {
        EvalError::NonFinite { link } => {
            let g = node.links[link];
            let l = &scenario.links[g];
            let a = format!("B{}", scenario.bodies[l.a].id);
            let b = if l.world {
                "the world".to_string()
            } else {
                format!("B{}", scenario.bodies[l.b].id)
            };
            // The first quantity of the node's state that is not finite, if any: what
            // overflowed, and on which body.
            let st = &node.state;
            let bad = (0..node.bodies.len()).find_map(|i| {
                let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
                let what = [
                    ("position", finite(st.p[i].as_slice())),
                    ("velocity", finite(st.v[i].as_slice())),
                    ("orientation", st.q.get(i).is_none_or(|q| finite(q.coords.as_slice()))),
                    (
                        "angular velocity",
                        st.omega.get(i).is_none_or(|w| finite(w.as_slice())),
                    ),
                ]
                .into_iter()
                .find(|(_, ok)| !ok)?;
                Some(format!(
                    "B{}'s {} is not finite",
                    scenario.bodies[node.bodies[i]].id,
                    what.0
                ))
            });
            let what = match (bad, l.joint.is_some()) {
                (Some(bad), _) => format!("non-finite state ({bad}) on the row of {a} and {b}"),
                (None, true) => format!("non-finite kinematics of the joint between {a} and {b}"),
                (None, false) => format!(
                    "non-finite kinematics (the anchors of {a} and {b} coincide, so the link \
                     has no direction)"
                ),
            };
            Error::Diverged(Divergence {
                time: t,
                node: n + 1,
                place: scenario.place_of_row(g),
                what,
            })
        }
        EvalError::Solve(crate::multibody::solver::SolveError::CgBudget {
            iterations,
            residual,
            worst,
            solves,
            link,
            violation,
            bound,
        }) => Error::Numerical {
            time: t,
            message: format!(
                "node {}: the CG budget (solver.max_iterations = {iterations} per solve) cannot hold \
                 the constraints: {solves} consecutive solves stopped at the budget with a \
                 residual that alone holds a link off by {residual:.3e} m (SMC: ε μ²‖r‖∞/K; \
                 worst {worst:.3e} m), and link L{} now has |w| = {violation:.3e} m, \
                 beyond divergence.max_violation = {bound} m; raise solver.max_iterations or \
                 use \"solver\": {{\"kind\": \"cholesky\"}}",
                n + 1,
                node.links[link] + 1
            ),
        },
        EvalError::NonFiniteBody { body, what } => Error::Diverged(Divergence {
            time: t,
            node: n + 1,
            place: crate::error::Place::Body(scenario.bodies[node.bodies[body]].id),
            what: format!(
                "non-finite {what}: the body's loads or spin overflow f64 (its torques or \
                 forces, or the gyroscopic couple of its spin)"
            ),
        }),
        EvalError::Solve(crate::multibody::solver::SolveError::OutOfMemory { rows }) => {
            Error::OutOfMemory {
                what: format!(
                    "the exact solve's factorization of {rows} constraint rows (its analysis, \
                     work buffers and factor) could not be allocated at t = {t}, node {}: \
                     raise the process's memory limit, or use \"solver\": {{\"kind\": \"cg\"}}, \
                     which needs no factor",
                    n + 1
                ),
            }
        }
        EvalError::Solve(_) => Error::Numerical {
            time: t,
            message: format!(
                "node {}: the multiplier matrix J M⁻¹ Jᵀ is not positive definite \
                 (redundant links or degenerate geometry)",
                n + 1
            ),
        },
    }
}
