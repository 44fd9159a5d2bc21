//! The model's centre-of-mass velocity as every node knows it without a message.
//!
//! Only the scenario's external forces and uniform gravity change the total momentum of
//! a free net; every node has the scenario, so every node can integrate
//! `P(t) = P(0) + ∫ (Σ F_ext + M g) dt` itself and agree, bit for bit, on the centre of
//! mass's velocity `P / M` at each step. Gravity belongs in it: left out, the reference
//! falls behind the net it measures, and a uniform field that changes no relative
//! motion would show up as border power the account brakes. A scene held to the world
//! (a joint to a fixed point) is not free: the world's unknown reaction carries its
//! weight, so there the reference leaves gravity out, as it leaves out that reaction. The
//! transmission lines ([`super::line`]) measure their ends' velocities against it:
//! a reference that is the same at both ends of every line at the same time, moves
//! with any uniform velocity added to the net (so the lines are the same in every
//! inertial frame), and is what the monolithic net's centre of mass does.

use nalgebra::Vector3;

use crate::kernel::SimTime;
use crate::scenario::model::{ForceSpec, Scenario};

/// The centre-of-mass velocity, integrated from the external forces alone.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ComReference {
    /// Total mass [kg].
    mass: f64,
    /// Total linear momentum at `at` [kg·m/s].
    momentum: Vector3<f64>,
    /// Every external force of the model.
    forces: Vec<ForceSpec>,
    /// Uniform gravity [m/s²] on a free scene (every body of a scenario is movable);
    /// `None`: none, or a scene held to the world.
    gravity: Option<Vector3<f64>>,
    /// Time of `momentum`.
    at: SimTime,
}

impl ComReference {
    /// The reference of `scenario` at time zero.
    pub fn new(scenario: &Scenario) -> ComReference {
        ComReference {
            mass: scenario.bodies.iter().map(|b| b.mass).sum(),
            momentum: scenario
                .bodies
                .iter()
                .map(|b| b.velocity * b.mass)
                .fold(Vector3::zeros(), |a, b| a + b),
            forces: scenario.forces.clone(),
            // A mechanism held to the world does not fall: the world's reaction, which
            // no node knows without a message, carries its weight. Its frame is the
            // world's, and the reference stays what its loads alone make it.
            gravity: scenario
                .gravity
                .filter(|_| !scenario.links.iter().any(|l| l.world)),
            at: SimTime::ZERO,
        }
    }

    /// Carries the momentum to `t` (a step later), the forces held over the step as
    /// an Euler step holds them (the reference needs to be the same everywhere, not
    /// more accurate than the integrator).
    pub fn advance(&mut self, t: SimTime) {
        if t <= self.at {
            return;
        }
        let h = SimTime(t.0 - self.at.0).as_secs_f64();
        for f in &self.forces {
            self.momentum += f.at(self.at) * h;
        }
        if let Some(g) = self.gravity {
            self.momentum += g * (self.mass * h);
        }
        self.at = t;
    }

    /// The centre of mass's velocity [m/s].
    pub fn velocity(&self) -> Vector3<f64> {
        self.momentum / self.mass
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::parse_str;

    #[test]
    fn a_constant_push_changes_the_velocity_by_its_impulse_over_the_mass() {
        let s = parse_str(
            r#"{"name": "c", "seed": 1, "duration": 1.0, "dt": 0.001,
                "model": {"bodies": [
                    {"id": 1, "mass": 1.0, "size": 0.2, "position": [0, 0, 0], "velocity": [1, 0, 0]},
                    {"id": 2, "mass": 3.0, "size": 0.2, "position": [1, 0, 0], "velocity": [1, 0, 0]}],
                  "links": [{"a": 1, "b": 2}]},
                "forces": [{"body": 2, "amplitude": [0, 8, 0], "omega": 0, "phase": 1.5707963267948966}]}"#,
            "<test>",
        )
        .expect("valid scenario");
        let mut r = ComReference::new(&s);
        assert_eq!(r.velocity(), Vector3::new(1.0, 0.0, 0.0));
        for k in 1..=500u64 {
            r.advance(SimTime(k * 1_000_000));
        }
        // 8 N for 0.5 s on 4 kg: 1 m/s along y.
        assert!((r.velocity() - Vector3::new(1.0, 1.0, 0.0)).norm() < 1e-12);
    }
}
