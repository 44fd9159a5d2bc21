//! The `passive` coupling's side of a node: booking each border port's power every step
//! and the passivity controller that removes what the port's account cannot pay
//! (method §3.1; the account itself is [`PortAccount`]).

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use super::Node;
use crate::kernel::SimTime;
use crate::partition::coupling::PortAccount;
use crate::scenario::model::Tank;

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
    /// The node may give beyond what its ports' other sides reported taken: half a
    /// fixed tank per port side, or its share of the largest kinetic energy its own
    /// bodies have held ([`Tank`]).
    ///
    /// *Why one account per node*: a predictor's energy error differs in sign from port
    /// to port. Per port, a port that gives more than it takes is braked once its tank
    /// is spent while the energy another port takes more than it gives is lost, so the
    /// brake drained the net one-sidedly (measured in method §3.1); pooled, the net's
    /// guarantee is the same (`Σ given − Σ taken` never exceeds the tanks).
    pub(super) fn passivity(&mut self, tank: Tank, t: SimTime) {
        let h = self.system.dt().as_secs_f64();
        if tank.share().is_some() {
            let now = self.own_kinetic_energy();
            self.coupling.peak_kinetic = self.coupling.peak_kinetic.max(now);
            self.coupling.driven_in += self.drive_power(t).max(0.0) * h;
        }
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
        let mut available: f64 = self
            .coupling
            .ports_in
            .iter()
            .map(|p| &p.2)
            .chain(&self.coupling.ports_out)
            .map(|a| a.available(tank.per_port()))
            .sum();
        if let Some(share) = tank.share() {
            available += share * self.energy_scale();
        }
        let giving: f64 = sides.iter().map(|p| p.max(0.0)).sum::<f64>() * h;
        let keep = if giving > available.max(0.0) {
            available.max(0.0) / giving
        } else {
            1.0
        };
        // What the brake removed from each giving side [W], where it could not remove
        // all it was asked to (see `damp`); `None`: every side as asked.
        let mut short: Option<Vec<f64>> = None;
        if keep < 1.0 {
            let capped = tank.share().is_some();
            let mut removed = vec![0.0; sides.len()];
            for (i, &power) in sides[..ins].iter().enumerate() {
                let b = self.coupling.ports_in[i].0;
                removed[i] = self.damp(b, power, 1.0 - keep, capped);
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
                        removed[ins + k] += self.damp(a, p_l, fraction, capped);
                    }
                }
                first = last;
            }
            let asked = |p: f64| p.max(0.0) * (1.0 - keep);
            if sides
                .iter()
                .zip(&removed)
                .any(|(&p, &r)| r < asked(p) * (1.0 - 1e-12))
            {
                short = Some(removed);
            }
        }
        for (i, &power) in sides.iter().enumerate() {
            let account = if i < ins {
                &mut self.coupling.ports_in[i].2
            } else {
                &mut self.coupling.ports_out[i - ins]
            };
            match &short {
                Some(removed) if power > 0.0 => account.book_removed(power, h, removed[i]),
                _ => {
                    account.book(power, h, keep);
                }
            }
        }
        self.coupling.side_powers = sides;
        self.coupling.end_powers = ends;
    }

    /// `passive` with a tank sized by share: the node's energy scale [J], the largest
    /// kinetic energy its own bodies have held so far (against the centre of mass's
    /// velocity) plus the positive work the scene's forces and inputs have done on
    /// them; zero otherwise. The node's tank is `tank_share` of it.
    pub fn energy_scale(&self) -> f64 {
        self.coupling.peak_kinetic + self.coupling.driven_in
    }

    /// The power of the scene's forces and the connections' input forces on the owned
    /// bodies at `t`, against the centre of mass's velocity [W] (gravity's work shows
    /// in the kinetic energy it makes).
    fn drive_power(&self, t: SimTime) -> f64 {
        let rigid = self.state.is_rigid();
        let mut power = 0.0;
        for f in self.system.forces.iter().filter(|f| f.body < self.owned) {
            let rotation = if rigid {
                UnitQuaternion::new_normalize(self.state.q[f.body])
            } else {
                UnitQuaternion::identity()
            };
            let (force, torque) = f.load(t, &rotation);
            let (v, w) = self.velocities(f.body);
            power += force.dot(&v) + if rigid { torque.dot(&w) } else { 0.0 };
        }
        for (b, input) in self.system.input_force.iter().enumerate().take(self.owned) {
            power += input.dot(&self.velocities(b).0);
        }
        power
    }

    /// Kinetic energy of the owned bodies against the centre of mass's velocity [J]
    /// (the spin term on the rigid-body path).
    fn own_kinetic_energy(&self) -> f64 {
        let rigid = self.state.is_rigid();
        let mut twice = 0.0;
        for (b, &(mass, inertia)) in self.coupling.own_masses.iter().enumerate() {
            let (v, w) = self.velocities(b);
            twice += mass * v.norm_squared();
            if rigid {
                let r = UnitQuaternion::new_normalize(self.state.q[b]).to_rotation_matrix();
                let world = r.matrix() * Matrix3::from_diagonal(&inertia) * r.matrix().transpose();
                twice += w.dot(&(world * w));
            }
        }
        0.5 * twice
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
    /// `excess` [W] of power, and returns the power it removes.
    ///
    /// The force is held over the step, so it is an explicit damper. With `capped`
    /// (the tank sized by share, whose brake works on mechanisms near rest) `c` is at
    /// most twice the body's mass (and smallest principal inertia) over the step, the
    /// most an explicit damper takes before it reverses the motion it damps and grows
    /// it: uncapped, a body nearly at rest asked to give up a small excess got
    /// `c = excess / |v|²` large enough to reverse its velocity and grow it step by step
    /// (a chain hanging at rest with a share-sized tank diverged in 0.13 s). What the
    /// capped brake cannot remove this step stays on the node's account as given, and
    /// the brake works on it next step. Under a fixed tank (nets of links) the brake
    /// stays uncapped: there a body's links carry most of its brake force to its
    /// neighbours, so its own mass understates what the brake moves, and the cap changed
    /// the 16-node scene at τ = 20 ms from bounded (max |w| 0.93 m) to diverged at 10.3 s
    /// (measured; method §3.1).
    fn damp(&mut self, b: usize, excess: f64, fraction: f64, capped: bool) -> f64 {
        if excess <= 0.0 {
            return 0.0;
        }
        let (v, w) = self.velocities(b);
        let rigid = self.state.is_rigid();
        let speed2 = v.norm_squared() + if rigid { w.norm_squared() } else { 0.0 };
        let h = self.system.dt().as_secs_f64();
        let mass = &self.system.mass;
        // The largest acceleration per unit force or torque: 1/m and ‖I⁻¹‖ (Frobenius,
        // at least the largest eigenvalue).
        let mut mobility = mass.inv_mass[b];
        if rigid {
            mobility = mobility.max(mass.inv_inertia[b].norm());
        }
        if speed2 == 0.0 || (capped && mobility == 0.0) {
            return 0.0;
        }
        let mut c = excess * fraction / speed2;
        if capped {
            c = c.min(2.0 / (mobility * h));
        }
        self.system.extra_force[b] -= v * c;
        if let Some(m) = &mut self.momentum {
            m.ledger.brake(-v * (c * h));
        }
        if rigid {
            self.system.extra_torque[b] -= w * c;
        }
        c * speed2
    }
}
