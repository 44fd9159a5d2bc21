//! The `passive` coupling's side of a node: booking each border port's power every step
//! and the passivity controller that removes what the port's account cannot pay
//! (method §3.1; the account itself is [`PortAccount`]).

use nalgebra::Vector3;

use super::Node;
use crate::partition::coupling::PortAccount;

impl Node {
    /// `passive`: this node's port accounts summed (both sides); zero otherwise.
    pub fn port_energy(&self) -> PortAccount {
        let mut sum = PortAccount::default();
        let ins = self.coupling.ports_in.iter().map(|p| &p.2);
        for p in self.coupling.ports_out.iter().chain(ins) {
            sum.taken += p.taken;
            sum.given += p.given;
            sum.received += p.received;
            sum.dissipated += p.dissipated;
        }
        sum
    }

    /// `passive`: books each port side's power for the step and, where this node's
    /// sides together would give their bodies more than the node's account holds, adds
    /// the passivity controller's forces `−c v` (and torques `−c ω`) that remove exactly
    /// the excess, every giving body the same fraction of its power.
    ///
    /// *Why one account per node*: a predictor's energy error differs in sign from port
    /// to port. Per port, a port that gives more than it takes is braked once its tank
    /// is spent while the energy another port takes more than it gives is lost, so the
    /// brake drained the net one-sidedly (measured in method §3.1); pooled, the net's
    /// guarantee is the same (`Σ given − Σ taken` never exceeds the tanks).
    pub(super) fn passivity(&mut self, tank: f64) {
        let h = self.system.dt().as_secs_f64();
        let rigid = self.state.is_rigid();
        let mut sides = std::mem::take(&mut self.coupling.side_powers);
        let mut ends = std::mem::take(&mut self.coupling.end_powers);
        sides.clear();
        ends.clear();
        // Side 2: the border forces this node applies to its own bodies, per port.
        for p in 0..self.coupling.ports_in.len() {
            let b = self.coupling.ports_in[p].0;
            let (mut f, mut tq) = (Vector3::zeros(), Vector3::zeros());
            for &i in &self.coupling.port_forces[p] {
                let (df, dt) = self.coupling.held_now[i];
                f += df;
                tq += dt;
            }
            let (v, w) = self.velocities(b);
            sides.push(f.dot(&v) + if rigid { tq.dot(&w) } else { 0.0 });
        }
        // Side 1: this node's border links to each ghost, on their own-body ends.
        for k in 0..self.coupling.ports_out.len() {
            let g = self.owned + k;
            let first = ends.len();
            for &l in &self.incident[g] {
                ends.push((k, self.far_end(l, g), self.end_power(l, g)));
            }
            sides.push(ends[first..].iter().map(|e| e.2).sum());
        }
        let ins = self.coupling.ports_in.len();
        let available: f64 = self
            .coupling
            .ports_in
            .iter()
            .map(|p| &p.2)
            .chain(&self.coupling.ports_out)
            .map(|a| a.available(tank))
            .sum();
        let giving: f64 = sides.iter().map(|p| p.max(0.0)).sum::<f64>() * h;
        let keep = if giving > available.max(0.0) {
            available.max(0.0) / giving
        } else {
            1.0
        };
        for (i, &power) in sides.iter().enumerate() {
            let account = if i < ins {
                &mut self.coupling.ports_in[i].2
            } else {
                &mut self.coupling.ports_out[i - ins]
            };
            account.book(power, h, keep);
        }
        if keep < 1.0 {
            for (i, &power) in sides[..ins].iter().enumerate() {
                let b = self.coupling.ports_in[i].0;
                self.damp(b, power, 1.0 - keep);
            }
            // On side 1 only the giving ends of a giving port are braked, each the same
            // fraction of its power. A port's ends are contiguous in `ends`.
            let mut first = 0;
            while first < ends.len() {
                let k = ends[first].0;
                let last = first + ends[first..].iter().take_while(|e| e.0 == k).count();
                let port = &ends[first..last];
                if sides[ins + k] > 0.0 {
                    let positive: f64 = port.iter().map(|e| e.2.max(0.0)).sum();
                    let fraction = sides[ins + k] * (1.0 - keep) / positive;
                    for &(_, a, p_l) in port.iter().filter(|e| e.2 > 0.0) {
                        self.damp(a, p_l, fraction);
                    }
                }
                first = last;
            }
        }
        self.coupling.side_powers = sides;
        self.coupling.end_powers = ends;
    }

    /// Velocity of local body `b` relative to the centre of mass's, and its angular
    /// velocity (zero ω on point masses). Powers booked and braked at these velocities
    /// are the same in every inertial frame, and the brake leaves the net's motion as
    /// a whole alone.
    fn velocities(&self, b: usize) -> (Vector3<f64>, Vector3<f64>) {
        let w = self
            .state
            .omega
            .get(b)
            .copied()
            .unwrap_or_else(Vector3::zeros);
        (self.state.v[b] - self.reference_velocity(), w)
    }

    /// The end of local link `l` that is not `g`.
    fn far_end(&self, l: usize, g: usize) -> usize {
        let link = &self.system.links()[l];
        if link.a == g {
            link.b
        } else {
            link.a
        }
    }

    /// Power [W] link `l` delivers to its end opposite ghost `g`.
    fn end_power(&self, l: usize, g: usize) -> f64 {
        let a = self.far_end(l, g);
        let (f, tq) = self.system.link_load_on(&self.state, l, a);
        let (v, w) = self.velocities(a);
        f.dot(&v)
            + if self.state.is_rigid() {
                tq.dot(&w)
            } else {
                0.0
            }
    }

    /// Adds to body `b` the force `−c v` (torque `−c ω`) that removes `fraction` of
    /// `excess` [W] of power.
    fn damp(&mut self, b: usize, excess: f64, fraction: f64) {
        if excess <= 0.0 {
            return;
        }
        let (v, w) = self.velocities(b);
        let rigid = self.state.is_rigid();
        let speed2 = v.norm_squared() + if rigid { w.norm_squared() } else { 0.0 };
        if speed2 == 0.0 {
            return;
        }
        let c = excess * fraction / speed2;
        self.system.extra_force[b] -= v * c;
        if let Some(m) = &mut self.momentum {
            m.ledger.brake(-v * (c * self.system.dt().as_secs_f64()));
        }
        if rigid {
            self.system.extra_torque[b] -= w * c;
        }
    }
}
