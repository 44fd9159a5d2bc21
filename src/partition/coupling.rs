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
//! - **`predict`**: the ghost keeps its own trajectory. The node keeps its ghost's
//!   state of every sample time until that sample arrives ([`GhostHistory`]); on
//!   arrival it shifts the ghost (and the states it still keeps from `t_s` on) by the
//!   sample's error against the ghost's own state at `t_s`, carried to now:
//!   `p += e_p + e_v·(t − t_s)`, `v += e_v` (orientation: the rotation error, angular
//!   velocity: its error). Forces travel with their rates, `Ḟ = ṅ z + n ż` for a link
//!   (the exact derivative of the link load; `ż` is the SMC law's rate that the
//!   integrator used over the step ending at `t_s`) plus the external forces' analytic
//!   rates; the receiver applies `F + Ḟ·min(age, extrapolate)` ([`Extrapolated`]), so a
//!   force that is τ old is wrong to second order in τ instead of first. Past
//!   `extrapolate` (default 10 ms) the force is held: a straight line through a force
//!   that the SMC loop turns around within a few milliseconds does more harm than good
//!   further out, and on the thesis scene a 100-ms extrapolation gave border bodies
//!   forces of the wrong sign (both ends of a link gaining energy at once).
//! - **`passive`**: `predict` over an energy account per border port ([`PortAccount`];
//!   the booking and the passivity controller are in `node/passivity.rs`), and
//!   transmission lines ([`super::line`]) on the border links whose samples can be
//!   older than `lines_above`.
//! - **`tlm`**: every border link is a transmission line ([`super::line`]).
//!
//! A sample whose snapshot is gone (it arrived after a later sample of its route, which
//! only a jitter larger than the sampling period can do) is compared with the ghost's
//! current state.

use std::collections::VecDeque;

/// One side's energy account of a border port (`passive`).
///
/// A port is a ghosted body `B` and the node that ghosts it (the link owner, side 1),
/// seen from both ends: side 1 applies the port's link forces to its own bodies (the
/// far ends `A` of its border links to `B`), side 2 (`B`'s owner) applies the received
/// border forces to `B`. Each side books the power `P = F·v + T·ω` it applies to its
/// bodies every step: what its bodies give to the port is `taken`, what the port gives
/// to them is `given`. The other side's `taken` is reported to it (`received`,
/// cumulative, so a late or lost report only delays the credit). A node's sides share
/// one account: together they may give only what their other sides have reported taken
/// plus half of each port's tank, `Σ given ≤ Σ (received + tank/2)` over the node's
/// sides. Summed over every node the coupling's net work on the bodies,
/// `Σ given − Σ taken`, can then never exceed the tanks, whatever the delay, jitter or
/// loss. Where the predicted forces would give more, a passivity controller removes the
/// excess with forces against the giving bodies' velocities (it dissipates exactly the
/// power the account cannot pay).
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

    /// Books power `p` [W] applied over `dt` [s] of which the node's account pays the
    /// fraction `keep` if `p > 0` (the rest is dissipated); returns the power applied.
    pub fn book(&mut self, p: f64, dt: f64, keep: f64) -> f64 {
        if p <= 0.0 {
            self.taken -= p * dt;
            return p;
        }
        let allowed = p * keep;
        self.given += allowed * dt;
        self.dissipated += (p - allowed) * dt;
        allowed
    }

    /// Books power `p > 0` [W] applied over `dt` [s] of which the brake removed
    /// `removed` [W] (less than the account asked for: the brake's cap).
    pub fn book_removed(&mut self, p: f64, dt: f64, removed: f64) {
        let removed = removed.clamp(0.0, p);
        self.given += (p - removed) * dt;
        self.dissipated += removed * dt;
    }

    /// A report of the other side's `taken` (reports may arrive out of order).
    pub fn report(&mut self, taken: f64) {
        self.received = self.received.max(taken);
    }
}

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::kernel::SimTime;
use crate::network::StepRate;

/// A force (and torque) with its rate, sampled at `sent`, applied as `F + Ḟ·age`, and
/// the part of its rate measured over the sender's last step ([`StepRate`]) carried for
/// one step at most.
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
    /// The rate measured over the sender's last step, carried while the age is below
    /// [`Extrapolated::step`].
    pub step_rate: StepRate,
    /// The sender's step (every node steps alike).
    pub step: SimTime,
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
            step_rate: StepRate::default(),
            step: SimTime::ZERO,
            sent: SimTime::ZERO,
        }
    }

    /// `(Ḟ, Ṫ)` at `t` while the age is below `cap` (the step rate while it is below
    /// the step too), zero once the value is held: the slope of [`Extrapolated::at`]
    /// going forward from `t`.
    pub fn rate_at(&self, t: SimTime, cap: SimTime) -> (Vector3<f64>, Vector3<f64>) {
        let age = t.0.saturating_sub(self.sent.0);
        let mut rate = (Vector3::zeros(), Vector3::zeros());
        if age < cap.0 {
            rate = (self.force_rate, self.torque_rate);
            if age < self.step.0 && self.step_rate != StepRate::default() {
                rate.0 += self.step_rate.force;
                rate.1 += self.step_rate.torque;
            }
        }
        rate
    }

    /// The step rate at `t`: while the age is below the step and `cap`, else zero.
    pub fn step_rate_at(&self, t: SimTime, cap: SimTime) -> StepRate {
        let age = t.0.saturating_sub(self.sent.0);
        if age < cap.0.min(self.step.0) {
            self.step_rate
        } else {
            StepRate::default()
        }
    }

    /// `(F + Ḟ·age + Ḟ_step·min(age, step), …)` at `t`, the age capped at `cap` (never
    /// negative).
    pub fn at(&self, t: SimTime, cap: SimTime) -> (Vector3<f64>, Vector3<f64>) {
        let age = SimTime(t.0.saturating_sub(self.sent.0).min(cap.0));
        let (mut force, mut torque) = (
            self.force + self.force_rate * age.as_secs_f64(),
            self.torque + self.torque_rate * age.as_secs_f64(),
        );
        // Nothing added when there is no step rate, so the bits stay as they were.
        if self.step_rate != StepRate::default() {
            let carried = SimTime(age.0.min(self.step.0)).as_secs_f64();
            force += self.step_rate.force * carried;
            torque += self.step_rate.torque * carried;
        }
        (force, torque)
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

/// The ghost's own states at the times its body was sampled for it, kept until those
/// samples arrive: a sample is compared with what the ghost itself was at the sample's
/// time.
///
/// The co-simulation takes a snapshot of the receiving node's ghost whenever the owner
/// samples the body for it (the event that sends the message), so the history holds one
/// entry per sample in flight — not one per step — and its length is bounded by the
/// samples the network can have in flight, whatever τ and latency are. Samples of one
/// route arrive in the order they were taken, so an arrival consumes its snapshot and
/// every older one.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GhostHistory {
    /// (sample time, the ghost's state then), oldest first.
    snapshots: VecDeque<(SimTime, GhostSample)>,
}

impl GhostHistory {
    /// Records the ghost's state at sample time `t` (not before the last snapshot).
    pub fn snapshot(&mut self, t: SimTime, sample: GhostSample) {
        self.snapshots.push_back((t, sample));
    }

    /// The snapshot taken at `t`, if it is kept.
    pub fn at(&self, t: SimTime) -> Option<&GhostSample> {
        self.snapshots
            .iter()
            .find(|(time, _)| *time == t)
            .map(|(_, s)| s)
    }

    /// Applies `c` to every snapshot at or after its sample time, then forgets the
    /// snapshots up to that time (their samples have arrived or never will).
    pub fn correct(&mut self, c: &Correction, rigid: bool) {
        for (t, s) in self.snapshots.iter_mut() {
            if *t >= c.sent {
                let rot = rigid.then_some((&mut s.q, &mut s.omega));
                c.apply(*t, &mut s.p, &mut s.v, rot);
            }
        }
        while self.snapshots.front().is_some_and(|(t, _)| *t <= c.sent) {
            self.snapshots.pop_front();
        }
    }

    /// Number of snapshots kept.
    pub fn len(&self) -> usize {
        self.snapshots.len()
    }

    /// Whether no snapshot is kept.
    pub fn is_empty(&self) -> bool {
        self.snapshots.is_empty()
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
    fn a_correction_shifts_later_snapshots_and_consumes_the_arrived_ones() {
        let ms = |k: u64| SimTime(k * 1_000_000);
        let mut h = GhostHistory::default();
        for k in [0, 5, 10] {
            h.snapshot(ms(k), sample(k as f64));
        }
        assert_eq!(h.at(ms(5)).unwrap().p.x, 5.0);
        assert!(h.at(ms(3)).is_none(), "only sample times are kept");
        // The sample taken at 5 ms says the body was 0.5 m further and 2 m/s faster.
        let mut received = sample(5.5);
        received.v.x = 3.0;
        let c = Correction::new(ms(5), &received, h.at(ms(5)).unwrap(), false);
        h.correct(&c, false);
        // 0 and 5 ms are consumed; 10 ms is shifted by 0.5 m + 2 m/s · 5 ms.
        assert_eq!(h.len(), 1);
        let later = h.at(ms(10)).unwrap();
        assert!((later.p.x - (10.5 + 2.0 * 0.005)).abs() < 1e-12);
        assert_eq!(later.v.x, 3.0);
    }

    #[test]
    fn extrapolation_stops_growing_at_its_cap() {
        let e = Extrapolated {
            force: Vector3::new(1.0, 0.0, 0.0),
            torque: Vector3::zeros(),
            force_rate: Vector3::new(10.0, 0.0, 0.0),
            torque_rate: Vector3::zeros(),
            sent: SimTime(1_000_000_000),
            ..Extrapolated::zero()
        };
        let h = SimTime(100_000_000);
        assert!((e.at(SimTime(1_050_000_000), h).0.x - 1.5).abs() < 1e-12);
        assert!((e.at(SimTime(5_000_000_000), h).0.x - 2.0).abs() < 1e-12);
        assert_eq!(e.at(SimTime(0), h).0.x, 1.0, "never extrapolated backwards");
    }

    #[test]
    fn a_step_rate_is_carried_for_one_step_then_held() {
        let e = Extrapolated {
            force: Vector3::new(1.0, 0.0, 0.0),
            force_rate: Vector3::new(10.0, 0.0, 0.0),
            step_rate: StepRate {
                force: Vector3::new(100.0, 0.0, 0.0),
                torque: Vector3::new(0.0, 0.0, -100.0),
            },
            step: SimTime(1_000_000),
            sent: SimTime(1_000_000_000),
            ..Extrapolated::zero()
        };
        let cap = SimTime(10_000_000);
        // Half a step on: both rates carry it.
        let (f, t) = e.at(SimTime(1_000_500_000), cap);
        assert!((f.x - (1.0 + 10.0 * 5e-4 + 100.0 * 5e-4)).abs() < 1e-12);
        assert!((t.z + 100.0 * 5e-4).abs() < 1e-12);
        assert_eq!(e.rate_at(SimTime(1_000_500_000), cap).0.x, 110.0);
        // Three steps on: the step rate's one step is held, the rate carries on.
        let (f, _) = e.at(SimTime(1_003_000_000), cap);
        assert!((f.x - (1.0 + 10.0 * 3e-3 + 100.0 * 1e-3)).abs() < 1e-12);
        assert_eq!(e.rate_at(SimTime(1_003_000_000), cap).0.x, 10.0);
        assert_eq!(
            e.step_rate_at(SimTime(1_003_000_000), cap),
            StepRate::default()
        );
        // A cap shorter than the step stops both.
        let short = SimTime(200_000);
        let (f, _) = e.at(SimTime(1_000_500_000), short);
        assert!((f.x - (1.0 + 110.0 * 2e-4)).abs() < 1e-12);
    }
}
