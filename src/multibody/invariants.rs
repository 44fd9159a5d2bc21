//! The whole net's mechanical invariants — total linear momentum, angular momentum about
//! the centre of mass and kinetic energy — from the gathered owner copy of every body.
//!
//! They are derived values (like `w` from the positions): trace.csv writes them beside
//! the state on every kept row and summary.json reports how they drift, but the digest
//! does not hash them ([`super::digest`]); the state they come from is hashed already.
//!
//! With no external force the exact dynamics keeps `P` and `L` (the links pull both
//! ends along the line between their anchors, and a net of rigid distance links does
//! no work on itself), so their drift measures what the discretization, the constraint
//! stabilization and, on a partitioned run, the coupling across nodes put in or take
//! out. A monolithic run under symplectic Euler keeps `P`, and for bodies of isotropic
//! inertia `L`, to round-off (tests/physics); explicit Euler and RK4 do not keep `L`
//! exactly.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

use crate::scenario::model::BodySpec;

/// Total linear momentum, angular momentum about the centre of mass and kinetic energy
/// of a net at one instant.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Invariants {
    /// `P = Σ m v` [kg·m/s].
    pub momentum: Vector3<f64>,
    /// `L = Σ (p − c) × m v + Σ I_world ω` about the centre of mass `c = Σ m p / Σ m`
    /// [kg·m²/s]; the spin term `I_world ω = R diag(I) Rᵀ ω` only on the rigid-body
    /// path (point masses have no rotation state).
    pub angular_momentum: Vector3<f64>,
    /// `½ Σ m |v|² + ½ Σ ωᵀ I_world ω` [J].
    pub kinetic_energy: f64,
    /// `Σ m |v|` [kg·m/s]: the momentum the bodies carry before they cancel, the
    /// scale below which `|P|` is round-off of cancelling terms.
    pub gross_momentum: f64,
    /// `Σ |(p − c) × m v| + Σ |I_world ω|` [kg·m²/s]: the same scale for `L`.
    pub gross_angular_momentum: f64,
}

impl Invariants {
    /// The invariants of bodies `bodies` (masses, principal inertias) at positions `p`
    /// [m], velocities `v` [m/s] and, on the rigid-body path, orientations `q` (body →
    /// world; normalized here) and world angular velocities `omega` [rad/s]; `q` and
    /// `omega` empty on the point-mass path.
    ///
    /// Two passes: the centre of mass first, then the moments about it, so that a net
    /// far from the origin does not lose `L`'s digits to `Σ p × m v − c × P`.
    pub fn of(
        bodies: &[BodySpec],
        p: &[Vector3<f64>],
        v: &[Vector3<f64>],
        q: &[Quaternion<f64>],
        omega: &[Vector3<f64>],
    ) -> Invariants {
        let (mut mass, mut first) = (0.0, Vector3::zeros());
        for (b, p) in bodies.iter().zip(p) {
            mass += b.mass;
            first += p * b.mass;
        }
        let c = if mass > 0.0 {
            first / mass
        } else {
            Vector3::zeros()
        };
        let (mut momentum, mut angular, mut twice_ke) = (Vector3::zeros(), Vector3::zeros(), 0.0);
        let (mut gross, mut gross_angular) = (0.0, 0.0);
        for ((b, p), v) in bodies.iter().zip(p).zip(v) {
            let mv = v * b.mass;
            let moment = (p - c).cross(&mv);
            momentum += mv;
            angular += moment;
            twice_ke += mv.dot(v);
            gross += mv.norm();
            gross_angular += moment.norm();
        }
        for ((b, q), w) in bodies.iter().zip(q).zip(omega) {
            let spin = spin(&b.inertia, q, w);
            angular += spin;
            twice_ke += w.dot(&spin);
            gross_angular += spin.norm();
        }
        Invariants {
            momentum,
            angular_momentum: angular,
            kinetic_energy: 0.5 * twice_ke,
            gross_momentum: gross,
            gross_angular_momentum: gross_angular,
        }
    }
}

/// A body's spin angular momentum `R diag(I) Rᵀ ω` [kg·m²/s] for principal inertia `I`
/// [kg·m²], orientation `q` (body → world) and world angular velocity `ω` [rad/s]: the
/// world inertia the dynamics builds (`multibody::dynamics`, stage 1), applied to `ω`.
fn spin(inertia: &Vector3<f64>, q: &Quaternion<f64>, w: &Vector3<f64>) -> Vector3<f64> {
    let r = *UnitQuaternion::new_normalize(*q)
        .to_rotation_matrix()
        .matrix();
    r * Matrix3::from_diagonal(inertia) * r.transpose() * w
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(mass: f64, inertia: [f64; 3]) -> BodySpec {
        BodySpec {
            id: 1,
            mass,
            size: 0.2,
            inertia: Vector3::from(inertia),
            position: Vector3::zeros(),
            velocity: Vector3::zeros(),
            orientation: UnitQuaternion::identity(),
            angular_velocity: Vector3::zeros(),
        }
    }

    /// Two point masses circling their centre of mass: P = 0, |L| = Σ m r v, KE = ½Σ m v²,
    /// the same wherever the pair sits (L is taken about the centre of mass).
    #[test]
    fn a_circling_pair_has_the_textbook_momenta_anywhere() {
        let bodies = [body(1.0, [1.0; 3]), body(3.0, [1.0; 3])];
        // Centre of mass at `o`; radii 1.5 and 0.5, speeds 3 and 1 (same angular rate 2).
        for o in [Vector3::zeros(), Vector3::new(1e6, -2e6, 3e5)] {
            let p = [
                o + Vector3::new(1.5, 0.0, 0.0),
                o + Vector3::new(-0.5, 0.0, 0.0),
            ];
            let v = [Vector3::new(0.0, 3.0, 0.0), Vector3::new(0.0, -1.0, 0.0)];
            let i = Invariants::of(&bodies, &p, &v, &[], &[]);
            assert_eq!(i.momentum, Vector3::zeros());
            let l = 1.0 * 1.5 * 3.0 + 3.0 * 0.5 * 1.0;
            assert!(
                (i.angular_momentum - Vector3::new(0.0, 0.0, l)).norm() < 1e-9 * l,
                "{o}: {}",
                i.angular_momentum
            );
            assert_eq!(i.kinetic_energy, 0.5 * (9.0 + 3.0));
        }
    }

    /// A body spinning about a principal axis turned into the world: its spin is
    /// `I_axis ω` along that world axis, and its rotational energy `½ I_axis ω²`.
    #[test]
    fn spin_uses_the_world_inertia_of_the_turned_body() {
        let bodies = [body(2.0, [1.0, 2.0, 3.0])];
        // Body z axis (I = 3) turned onto world x.
        let q = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
        let w = Vector3::new(0.5, 0.0, 0.0);
        let i = Invariants::of(
            &bodies,
            &[Vector3::new(4.0, 5.0, 6.0)],
            &[Vector3::zeros()],
            &[*q.quaternion()],
            &[w],
        );
        assert!((i.angular_momentum - Vector3::new(1.5, 0.0, 0.0)).norm() < 1e-15);
        assert!((i.kinetic_energy - 0.5 * 3.0 * 0.25).abs() < 1e-15);
    }
}
