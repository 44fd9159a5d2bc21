//! What a node does with border data that arrives late (`partition.coupling`).
//!
//! A sample taken at `t_s` reaches its receiver at `t_a`; its **age** at a later step
//! time `t` is `t − t_s`. Under the thesis's reading of delay (latency = τ) the age runs
//! from τ to 2τ between arrivals.
//!
//! - **`reset`** (the thesis's ghost equations, kept bit-identical): an arriving state
//!   overwrites the ghost's position and velocity; an arriving force is held until the
//!   next arrival. The overwrite is almost purely a velocity jump (the ghost was driven
//!   by the link force at once, the real body only `age` later), and a jump in `ẇ`
//!   enters the sliding surface directly: the stiff SMC loop pumps energy into the net
//!   and the run diverges once the age reaches a few milliseconds.
//! - **`predict`**: the ghost keeps its own trajectory. On arrival the node compares the
//!   sample with what the ghost itself was at `t_s` ([`GhostHistory`]) and shifts the
//!   ghost (and its recorded past from `t_s` on) by that error carried to now:
//!   `p += e_p + e_v·(t − t_s)`, `v += e_v` (orientation: the rotation error, angular
//!   velocity: its error). Forces travel with their rates, `Ḟ = ṅ z + n ż` for a link
//!   (the exact derivative of the link load; `ż` is the SMC law's rate that the
//!   integrator used over the step ending at `t_s`) plus the external forces' analytic
//!   rates; the receiver applies `F + Ḟ·age` ([`Extrapolated`]), so a force that is τ
//!   old is wrong to second order in τ instead of first.
//!
//! A sample older than the node's horizon (twice the longest age the network can
//! produce) is a lost one: the history has no entry for it, so it is compared with the
//! oldest entry, and an extrapolation stops growing at the horizon (it is never carried
//! further forward than a sample could legitimately be old).

use std::collections::VecDeque;

/// One side's energy account of a border port (`passive`).
///
/// A port is a ghosted body `B` and the node that ghosts it (the link owner, side 1),
/// seen from both ends: side 1 applies the port's link forces to its own bodies (the
/// far ends `A` of its border links to `B`), side 2 (`B`'s owner) applies the received
/// border forces to `B`. Each side books the power `P = F·v + T·ω` it applies to its
/// bodies every step: what its bodies give to the port is `taken`, what the port gives
/// to them is `given`. Each side may give only what the other side has reported taken
/// (`received`, cumulative, so a late or lost report only delays the credit) plus half
/// the initial tank: `given ≤ received + tank/2`. Summed over both sides the coupling's
/// net work on the bodies, `given₁ + given₂ − taken₁ − taken₂`, can then never exceed
/// the tank, whatever the delay, jitter or loss. Where the predicted force would give
/// more, a passivity controller removes the excess with a force against the body's
/// velocity (it dissipates exactly the power the tank cannot pay).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PortAccount {
    /// Energy this side's bodies put into the port [J] (cumulative `∫max(−P, 0) dt`).
    pub taken: f64,
    /// Energy the port gave this side's bodies [J] (cumulative `∫max(P, 0) dt`).
    pub given: f64,
    /// The other side's `taken` as last reported [J].
    pub received: f64,
    /// Energy the passivity controller removed on this side [J].
    pub dissipated: f64,
}

impl PortAccount {
    /// What this side may still give [J].
    pub fn available(&self, tank: f64) -> f64 {
        self.received + 0.5 * tank - self.given
    }

    /// Books power `p` [W] applied over `dt` [s]; returns the power the tank allows
    /// (`p` itself unless `p > 0` exceeds what is available).
    pub fn book(&mut self, p: f64, dt: f64, tank: f64) -> f64 {
        if p <= 0.0 {
            self.taken -= p * dt;
            return p;
        }
        let allowed = p.min((self.available(tank) / dt).max(0.0));
        self.given += allowed * dt;
        self.dissipated += (p - allowed) * dt;
        allowed
    }

    /// A report of the other side's `taken` (reports may arrive out of order).
    pub fn report(&mut self, taken: f64) {
        self.received = self.received.max(taken);
    }
}

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::kernel::SimTime;

/// A force (and torque) with its rate, sampled at `sent`, applied as `F + Ḟ·age`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Extrapolated {
    /// Force at `sent` [N].
    pub force: Vector3<f64>,
    /// Torque at `sent` [N·m].
    pub torque: Vector3<f64>,
    /// Force rate [N/s].
    pub force_rate: Vector3<f64>,
    /// Torque rate [N·m/s].
    pub torque_rate: Vector3<f64>,
    /// Sample time.
    pub sent: SimTime,
}

impl Extrapolated {
    /// Nothing received yet: zero force, no rate.
    pub fn zero() -> Extrapolated {
        Extrapolated {
            force: Vector3::zeros(),
            torque: Vector3::zeros(),
            force_rate: Vector3::zeros(),
            torque_rate: Vector3::zeros(),
            sent: SimTime::ZERO,
        }
    }

    /// `(F + Ḟ·age, T + Ṫ·age)` at `t`, the age capped at `horizon`.
    pub fn at(&self, t: SimTime, horizon: SimTime) -> (Vector3<f64>, Vector3<f64>) {
        let age = SimTime(t.0.saturating_sub(self.sent.0).min(horizon.0)).as_secs_f64();
        (
            self.force + self.force_rate * age,
            self.torque + self.torque_rate * age,
        )
    }
}

/// One recorded ghost state.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GhostSample {
    /// Position [m].
    pub p: Vector3<f64>,
    /// Velocity [m/s].
    pub v: Vector3<f64>,
    /// Orientation (rigid path; identity on point masses).
    pub q: Quaternion<f64>,
    /// Angular velocity [rad/s] (rigid path; zero on point masses).
    pub omega: Vector3<f64>,
}

/// A received sample compared with the ghost's own state at the sample's time: the
/// correction to apply to every ghost state from then on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correction {
    /// Sample time.
    pub sent: SimTime,
    /// Position error [m].
    pub dp: Vector3<f64>,
    /// Velocity error [m/s].
    pub dv: Vector3<f64>,
    /// Rotation error `q_received ⊗ q_ghost⁻¹`.
    pub dq: UnitQuaternion<f64>,
    /// Angular velocity error [rad/s].
    pub dw: Vector3<f64>,
}

impl Correction {
    /// The error of `received` against `ghost` (both at `sent`); the rotation error only
    /// where the bodies rotate (`rigid`).
    pub fn new(
        sent: SimTime,
        received: &GhostSample,
        ghost: &GhostSample,
        rigid: bool,
    ) -> Correction {
        let dq = if rigid {
            UnitQuaternion::new_normalize(received.q)
                * UnitQuaternion::new_normalize(ghost.q).inverse()
        } else {
            UnitQuaternion::identity()
        };
        Correction {
            sent,
            dp: received.p - ghost.p,
            dv: received.v - ghost.v,
            dq,
            dw: received.omega - ghost.omega,
        }
    }

    /// Shifts a ghost state of time `t ≥ sent` onto the corrected trajectory.
    pub fn apply(
        &self,
        t: SimTime,
        p: &mut Vector3<f64>,
        v: &mut Vector3<f64>,
        rot: Option<(&mut Quaternion<f64>, &mut Vector3<f64>)>,
    ) {
        let age = SimTime(t.0.saturating_sub(self.sent.0)).as_secs_f64();
        *p += self.dp + self.dv * age;
        *v += self.dv;
        if let Some((q, w)) = rot {
            *q = *(self.dq * UnitQuaternion::new_normalize(*q)).quaternion();
            *w += self.dw;
        }
    }
}

/// The recent past of one ghost: its state at every step time from `first` on, so that
/// a sample can be compared with what the ghost was at the sample's time.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GhostHistory {
    /// Time of `samples[0]`.
    first: SimTime,
    /// States at `first`, `first + dt`, …
    samples: VecDeque<GhostSample>,
    /// Most entries kept.
    capacity: usize,
}

impl GhostHistory {
    /// An empty history keeping at most `capacity` steps (at least one).
    pub fn new(capacity: usize) -> GhostHistory {
        GhostHistory {
            first: SimTime::ZERO,
            samples: VecDeque::with_capacity(capacity.max(1)),
            capacity: capacity.max(1),
        }
    }

    /// Records the ghost's state at step time `t` (one step after the last record).
    pub fn record(&mut self, t: SimTime, dt: SimTime, sample: GhostSample) {
        if self.samples.is_empty() {
            self.first = t;
        }
        if self.samples.len() == self.capacity {
            self.samples.pop_front();
            self.first = SimTime(self.first.0 + dt.0);
        }
        self.samples.push_back(sample);
    }

    /// The recorded state at `t` (the oldest one when `t` is older than the history);
    /// `None` when nothing at or before `t` is recorded.
    pub fn at(&self, t: SimTime, dt: SimTime) -> Option<&GhostSample> {
        if t < self.first {
            return self.samples.front();
        }
        let k = ((t.0 - self.first.0) / dt.0) as usize;
        self.samples.get(k)
    }

    /// Applies `c` to every recorded state at or after its sample time.
    pub fn correct(&mut self, c: &Correction, dt: SimTime, rigid: bool) {
        let skip = (c.sent.0.saturating_sub(self.first.0) / dt.0) as usize;
        for (k, s) in self.samples.iter_mut().enumerate().skip(skip) {
            let t = SimTime(self.first.0 + k as u64 * dt.0);
            let rot = rigid.then_some((&mut s.q, &mut s.omega));
            c.apply(t, &mut s.p, &mut s.v, rot);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(x: f64) -> GhostSample {
        GhostSample {
            p: Vector3::new(x, 0.0, 0.0),
            v: Vector3::new(1.0, 0.0, 0.0),
            q: Quaternion::identity(),
            omega: Vector3::zeros(),
        }
    }

    #[test]
    fn history_finds_each_step_and_forgets_the_oldest() {
        let dt = SimTime(1_000_000);
        let mut h = GhostHistory::new(3);
        for k in 0..5u64 {
            h.record(SimTime(k * dt.0), dt, sample(k as f64));
        }
        // Kept: steps 2, 3, 4.
        assert_eq!(h.at(SimTime(3 * dt.0), dt).unwrap().p.x, 3.0);
        assert_eq!(h.at(SimTime(4 * dt.0), dt).unwrap().p.x, 4.0);
        assert_eq!(
            h.at(SimTime(0), dt).unwrap().p.x,
            2.0,
            "too old: the oldest"
        );
        assert!(h.at(SimTime(5 * dt.0), dt).is_none(), "not recorded yet");
    }

    #[test]
    fn a_correction_carries_the_velocity_error_forward_in_time() {
        let dt = SimTime(1_000_000);
        let mut h = GhostHistory::new(10);
        for k in 0..4u64 {
            h.record(SimTime(k * dt.0), dt, sample(k as f64));
        }
        let mut received = sample(1.5);
        received.v.x = 3.0;
        let c = Correction::new(
            SimTime(dt.0),
            &received,
            h.at(SimTime(dt.0), dt).unwrap(),
            false,
        );
        h.correct(&c, dt, false);
        // Step 0 untouched; from step 1 on: +0.5 m + 2 m/s · age.
        assert_eq!(h.at(SimTime(0), dt).unwrap().p.x, 0.0);
        assert_eq!(h.at(SimTime(dt.0), dt).unwrap().p.x, 1.5);
        assert!((h.at(SimTime(3 * dt.0), dt).unwrap().p.x - (3.5 + 2.0 * 0.002)).abs() < 1e-15);
        assert_eq!(h.at(SimTime(3 * dt.0), dt).unwrap().v.x, 3.0);
    }

    #[test]
    fn extrapolation_stops_growing_at_the_horizon() {
        let e = Extrapolated {
            force: Vector3::new(1.0, 0.0, 0.0),
            torque: Vector3::zeros(),
            force_rate: Vector3::new(10.0, 0.0, 0.0),
            torque_rate: Vector3::zeros(),
            sent: SimTime(1_000_000_000),
        };
        let h = SimTime(100_000_000);
        assert!((e.at(SimTime(1_050_000_000), h).0.x - 1.5).abs() < 1e-12);
        assert!((e.at(SimTime(5_000_000_000), h).0.x - 2.0).abs() < 1e-12);
        assert_eq!(e.at(SimTime(0), h).0.x, 1.0, "never extrapolated backwards");
    }
}
