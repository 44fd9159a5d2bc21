//! A node's ends of transmission lines: their tension every step, their samples and
//! what arrives from their far ends (the line itself is [`crate::partition::line`]).

use nalgebra::{UnitQuaternion, Vector3};

use super::Node;
use crate::kernel::SimTime;
use crate::network::LineSample;

impl Node {
    /// World position and velocity of the anchor `r` (body frame) of local body `b`,
    /// and its world offset from the body's centre (zero on point masses).
    fn anchor(&self, b: usize, r: &Vector3<f64>) -> [Vector3<f64>; 3] {
        if self.state.is_rigid() {
            let rr = UnitQuaternion::new_normalize(self.state.q[b]) * r;
            [
                self.state.p[b] + rr,
                self.state.v[b] + self.state.omega[b].cross(&rr),
                rr,
            ]
        } else {
            [self.state.p[b], self.state.v[b], Vector3::zeros()]
        }
    }

    /// Before the step at `t`: every line end's tension, applied to its body.
    pub(super) fn step_lines(&mut self, t: SimTime) {
        if self.lines.is_empty() {
            return;
        }
        let h = self.system.dt().as_secs_f64();
        let rigid = self.state.is_rigid();
        let reference = self.reference_velocity();
        for k in 0..self.lines.len() {
            let b = self.lines[k].body;
            let [p, v, r] = self.anchor(b, &self.lines[k].anchor);
            let f = self.lines[k].step(t, h, (p, v), reference);
            let tq = r.cross(&f);
            self.lines[k].load = (f, tq);
            self.system.extra_force[b] += f;
            if rigid {
                self.system.extra_torque[b] += tq;
            }
        }
    }

    /// Index of this node's end of line `l` (global link), if it holds one.
    pub fn line_index(&self, l: usize) -> Option<usize> {
        self.lines.iter().position(|e| e.link == l)
    }

    /// The sample of this node's end of line `l` at `t` (the link owner's end, sent on
    /// the link's force route); starts the end's next window.
    pub fn line_sample(&mut self, t: SimTime, l: usize) -> Option<LineSample> {
        let k = self.line_index(l)?;
        let [p, v, _] = self.anchor(self.lines[k].body, &self.lines[k].anchor);
        Some(self.lines[k].sample(t, p, v))
    }

    /// The samples at `t` of the lines from owned global body `g` to node `receiver`'s
    /// bodies (sent with `g`'s state), in link order; each starts its next window.
    pub fn line_samples_to(&mut self, t: SimTime, g: usize, receiver: usize) -> Vec<LineSample> {
        let Some(i) = self.local(g) else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for k in 0..self.lines.len() {
            let e = &self.lines[k];
            if e.body != i || e.far_node != receiver || e.owner_side {
                continue;
            }
            let [p, v, _] = self.anchor(i, &e.anchor);
            out.push(self.lines[k].sample(t, p, v));
        }
        out
    }

    /// A far end's sample taken at `sent`, applied from `now`. At the end that is not
    /// the link owner's, the owner end's impulse as of `sent` and this end's then are
    /// the momentum the line has made (`partition::momentum`).
    pub(super) fn receive_line(&mut self, sent: SimTime, now: SimTime, s: &LineSample) {
        let Some(k) = self.lines.iter().position(|e| e.link == s.link) else {
            return;
        };
        let e = &mut self.lines[k];
        e.receive(sent, now, s);
        let slot = self.momentum.as_ref().and_then(|m| m.line_slot[k]);
        let Some(slot) = slot else { return };
        let Some(&(_, own)) = e.impulse_history.iter().find(|(t, _)| *t == sent) else {
            return;
        };
        while e.impulse_history.front().is_some_and(|(t, _)| *t <= sent) {
            e.impulse_history.pop_front();
        }
        if let Some(m) = &mut self.momentum {
            m.ledger.port(slot, own + s.impulse, now);
        }
    }

    /// The owner end of line `l` (global link) samples it at `t`: this node's end
    /// keeps its impulse of that time, to compare when the sample arrives.
    pub fn snapshot_line(&mut self, l: usize, t: SimTime) {
        if self.momentum.is_none() {
            return;
        }
        if let Some(e) = self.lines.iter_mut().find(|e| e.link == l && !e.owner_side) {
            if e.impulse_history.back().is_none_or(|(s, _)| *s < t) {
                e.impulse_history.push_back((t, e.impulse));
            }
        }
    }

    /// This node's line end `k` (see [`Node::line_index`]): its anchor's world
    /// position and its tension [N].
    pub fn line_end(&self, k: usize) -> (Vector3<f64>, f64) {
        let e = &self.lines[k];
        (self.anchor(e.body, &e.anchor)[0], e.tension)
    }

    /// The most energy the lines' initial waves can give this node's bodies [J], at
    /// `now` (see [`crate::partition::line::LineEnd::initial_energy`]).
    pub fn line_initial_energy(&self, now: SimTime) -> f64 {
        let h = self.system.dt().as_secs_f64();
        self.lines.iter().map(|e| e.initial_energy(now, h)).sum()
    }

    /// Energy the lines gave this node's bodies so far, `Σ ∫ −T s dt` [J] (negative:
    /// the lines took it).
    pub fn line_work(&self) -> f64 {
        self.lines.iter().map(|e| e.given).sum()
    }
}
