//! Transmission-line (TLM) border links: a coupling that cannot create energy, whatever
//! the delay (`partition.coupling`: `tlm`, and `passive` above its `lines_above` age).
//!
//! A line replaces a border link's constraint. Each end applies to its own body a
//! tension along the link,
//!
//! ```text
//! T = c + Z s,        s = −n · (Ṗ − V)  (this end's extension rate),
//! ```
//!
//! where `n` points from the end's anchor `P` to the other end, `V` is the model's
//! centre-of-mass velocity ([`super::com`], the same at every node at the same time),
//! `Z` is the line's impedance and `c` the wave that arrived from the other end. Each
//! end sends back the wave `c + 2 Z s`. The power a line takes from an end's body
//! (measured against `V`) is `T s = (b² − c²)/4Z` for the outgoing wave `b`: what a
//! line gives its bodies is what earlier went in as waves, so it stores energy (a
//! spring of stiffness `Z / T` with a parasitic mass `Z T` for a one-way delay `T`)
//! and never makes any. Measured against `V` rather than absolutely, the line is the
//! same in every inertial frame, also while it turns (with absolute velocities a
//! uniform velocity shifts the waves by `∓Z n·δ`, and a link that turns while its
//! wave travels receives a different shift than was sent: the review's translating
//! net slowed down, an asymmetric spinning dumbbell gained momentum). What it does
//! not make exact is momentum in a net that turns: each end's `n` moves while a wave
//! travels, and a link whose ends slide along it (any link not through the centre of
//! mass of a spinning net) books a wave shift that arrives turned. docs/method.md
//! gives the measured drift.
//!
//! The waves travel on the border's messages, which are point samples taken every τ. A
//! point sample of a wave held for τ is not passive (it repeats a value the sender had
//! for an instant), so an end sends the **window average** of its outgoing wave since
//! its previous sample, with the window's length `span`, and the receiver applies it
//! for `span` after it arrives and then zero: by Cauchy–Schwarz the energy of a held
//! average, `span · avg²`, never exceeds the energy that went in over the window. A
//! lost sample, one that arrives late, or one overtaken by a newer sample only leaves
//! energy out. The averaging adds half a window on each side, so the line's one-way
//! delay is `T = τ + latency` of the channel carrying the wave, the mean over the two
//! directions, fixed from the scenario's channels. `Z` does not depend on the delay
//! ([`default_impedance`]), so the line's stiffness `Z/T` grows and its parasitic mass
//! `Z T` shrinks as the delay goes to zero: the line converges to the rigid link.
//!
//! Directions: the link owner's end sends on the link's force route, the other end on
//! its body's state route to the owner (under the `time` distribution the first wave
//! travels with the forces on τ2, the second with the states on τ1). A sample also
//! carries its end's anchor position and velocity, from which the other end
//! extrapolates where the far anchor is now to set `n`: a line needs no ghost.
//!
//! At the start each end holds the wave `c₀ = (Z/T) w₀ − Z s₀` ([`initial_wave`]) of
//! the link's initial extension `w₀` and the end's initial extension rate `s₀` until
//! the first wave arrives, so a line starts with the tension of a spring stretched by
//! `w₀`, as the constraint it replaces would pull, and a net in uniform motion starts
//! in its steady state. A wave that is lost or past its hold is replaced by the one
//! that makes the end's tension zero.

use nalgebra::Vector3;

/// Time constant of the low-pass filter on a line's incoming wave [s]: `max(1.5 T, 4h)`
/// for a line of one-way delay `T` stepped every `h`.
///
/// A lossless line between masses rings at the multiples of `1 / 2T`, and a force held
/// over a step gives a body `h²|F|²/2m` more kinetic energy than the work the line
/// books (the energy error of any explicit step): nothing in a lossless line takes it
/// out again, so the ringing grew without bound on two free bodies at τ = 1 and 5 ms
/// (kinetic energy 0.045 J → 68 J and 9 J in 20 s). A first-order low-pass filter on
/// the incoming wave (the damped TLM element of Krus) takes it out, and is passive
/// itself: `y² ≤ α y₋² + (1 − α) x²` step by step, so the filtered wave never carries
/// more energy than the wave that arrived. Measured on the undriven 4×4 net (60 s,
/// RK4, `tlm`, τ = 1–50 ms): `T` let the net gain 2.6 J at τ = 3 ms, `1.5 T` and `2T`
/// (with the 4-step floor, which τ = 1 ms needs) gain nothing. A longer filter
/// lengthens the line, whose parasitic mass grows with its delay: on the driven
/// thesis scene at τ = 25 ms the 0–3 s error is 1.05 / 1.26 / 1.46 m for `T` / `1.5 T`
/// / `2T`, so `1.5 T` is the shortest that holds.
pub fn filter_time(delay: f64, h: f64) -> f64 {
    (1.5 * delay).max(4.0 * h)
}

use crate::kernel::SimTime;
use crate::network::LineSample;
use crate::partition::layout::Route;
use crate::scenario::model::{DataKind, Scenario, Stabilizer};

/// Which border links are lines, with their impedances and delays.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LineSet {
    /// Per global link, when it is a line: its impedance `Z` [N·s/m] and one-way delay
    /// `T` [s].
    impedance: Vec<Option<(f64, f64)>>,
}

/// The default impedance of a line between bodies of masses `ma` and `mb` [kg] under
/// `stabilizer` [N·s/m]: the reduced mass `m_r` times the bandwidth `ω_c` up to which the
/// stabilizer holds a link rigid (`2/μ` under SMC, whose sliding surface is a critically
/// damped second-order law of natural frequency `1/μ`; `β` under Baumgarte, `α` if `β`
/// is zero). At `ω_c` the line's spring (`Z/T`) and its parasitic mass (`Z·T`) then err
/// alike, each by about `ω_c·T` relative, and both vanish with the delay.
pub fn default_impedance(ma: f64, mb: f64, stabilizer: &Stabilizer) -> f64 {
    let reduced = ma * mb / (ma + mb);
    let bandwidth = match *stabilizer {
        Stabilizer::Smc { mu, .. } => 2.0 / mu,
        Stabilizer::Baumgarte { alpha, beta } => {
            if beta > 0.0 {
                beta
            } else {
                alpha
            }
        }
    };
    reduced * bandwidth
}

impl LineSet {
    /// The lines of `scenario` (none unless its coupling has lines): each border link
    /// whose oldest sample (`τ + latency` of the channels carrying its force and its
    /// far body's state, `τ` the period channel `i` starts at, `periods[i]`: on a TDMA
    /// network what its initial slot list achieves, not what the file requests) is
    /// older than the coupling's `above`.
    pub fn new(scenario: &Scenario, routes: &[Route], periods: &[SimTime]) -> LineSet {
        let mut impedance = vec![None; scenario.links.len()];
        let Some(lines) = scenario.partition.as_ref().and_then(|p| p.coupling.lines()) else {
            return LineSet { impedance };
        };
        let lag = |r: &Route| {
            scenario
                .channels
                .iter()
                .zip(periods)
                .find(|(c, _)| c.carries(r.kind, r.from, r.to))
                .map(|(c, &tau)| tau.0.saturating_add(c.latency_for(tau).0))
        };
        for r in routes.iter().filter(|r| r.kind == DataKind::Force) {
            let Some(l) = r.link else { continue };
            // A line is a distance link's wave model; a joint's rows stay in the
            // constraint system under the scheme's other parts.
            if scenario.links[l].joint.is_some() {
                continue;
            }
            let state = routes.iter().find(|s| {
                s.kind == DataKind::State && s.from == r.to && s.to == r.from && s.body == r.body
            });
            let (Some(forward), Some(back)) = (lag(r), state.and_then(lag)) else {
                continue;
            };
            if forward.max(back) > lines.above.0 {
                let t = 0.5 * (SimTime(forward).as_secs_f64() + SimTime(back).as_secs_f64());
                let link = &scenario.links[l];
                let (ma, mb) = (scenario.bodies[link.a].mass, scenario.bodies[link.b].mass);
                let z = lines
                    .impedance
                    .unwrap_or_else(|| default_impedance(ma, mb, &scenario.stabilizer));
                impedance[l] = Some((z, t));
            }
        }
        LineSet { impedance }
    }

    /// No lines at all.
    pub fn none(links: usize) -> LineSet {
        LineSet {
            impedance: vec![None; links],
        }
    }

    /// Impedance [N·s/m] and one-way delay [s] of link `l` if it is a line.
    pub fn impedance(&self, l: usize) -> Option<(f64, f64)> {
        self.impedance.get(l).copied().flatten()
    }

    /// Whether link `l` is a line.
    pub fn is_line(&self, l: usize) -> bool {
        self.impedance(l).is_some()
    }

    /// Whether any link is a line.
    pub fn any(&self) -> bool {
        self.impedance.iter().any(Option::is_some)
    }

    /// Line samples route `r` carries: its link's on a force route, one per line from
    /// the body to the receiver's bodies on a state route.
    pub fn on_route(&self, scenario: &Scenario, node_of: &[usize], r: &Route) -> usize {
        match (r.kind, r.link) {
            (DataKind::Force, Some(l)) => usize::from(self.is_line(l)),
            (DataKind::Force, None) | (DataKind::Signal, _) => 0,
            (DataKind::State, _) => scenario
                .links
                .iter()
                .enumerate()
                .filter(|(l, k)| {
                    self.is_line(*l)
                        && ((k.a == r.body && node_of[k.b] == r.to)
                            || (k.b == r.body && node_of[k.a] == r.to))
                })
                .count(),
        }
    }
}

/// The wave an end holds until the first wave arrives [N]: the one that gives the
/// line the tension `T₀ = (Z/T) w₀` of its initial stretch `w₀` [m] (a spring of the
/// line's stiffness) at the end's initial extension rate `s₀ = −n·(Ṗ − V)` [m/s],
/// `c₀ = T₀ − Z s₀`. It is the wave the line would carry had its ends always moved so:
/// a net moving as a rigid body starts with no transient, in every inertial frame (a
/// zero initial wave braked each end's absolute velocity until the first wave came).
pub fn initial_wave(impedance: f64, delay: f64, stretch: f64, rate: f64) -> f64 {
    impedance / delay * stretch - impedance * rate
}

/// Where the far end of a line was when it was last sampled.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
struct FarEnd {
    p: Vector3<f64>,
    v: Vector3<f64>,
    sent: SimTime,
}

/// One end of a line, held by the node that owns the end's body.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LineEnd {
    /// Global link index.
    pub link: usize,
    /// Local index of this end's body.
    pub body: usize,
    /// This end's anchor in the body frame [m].
    pub anchor: Vector3<f64>,
    /// Global index of the far end's body.
    pub far_body: usize,
    /// Node owning the far end's body.
    pub far_node: usize,
    /// Whether this end is the link owner's (its waves go on the link's force route).
    pub owner_side: bool,
    /// Impedance `Z` [N·s/m].
    pub impedance: f64,
    /// One-way delay `T` [s].
    delay: f64,
    /// The incoming wave after the low-pass filter [N].
    filtered: f64,
    far: FarEnd,
    /// The wave being applied [N] and until when (exclusive).
    incoming: f64,
    hold_until: SimTime,
    /// Sample time of the last wave received (none yet: `None`).
    last_received: Option<SimTime>,
    /// The initial wave `c₀` [N] and when the first wave replaced it.
    initial_wave: f64,
    first_wave: Option<SimTime>,
    /// `∫ b dt` of the outgoing wave since `window_from` [N·s].
    acc: f64,
    window_from: SimTime,
    /// Tension of the last step [N] (positive pulls the ends together).
    pub tension: f64,
    /// Force and torque applied to the body at the last step.
    pub load: (Vector3<f64>, Vector3<f64>),
    /// Energy the line gave this end's body so far, `∫ −T s dt` [J] (negative: taken).
    pub given: f64,
    /// The impulse the line has applied to this end's body so far [N·s].
    pub impulse: Vector3<f64>,
    /// The non-owner end: its `impulse` at each of the owner end's samples still in
    /// flight, to compare with the owner end's when the sample arrives
    /// (`partition::momentum`).
    pub impulse_history: std::collections::VecDeque<(SimTime, Vector3<f64>)>,
    /// Uniform gravity [m/s²] the far body falls with between its samples, and the
    /// integrator's lag [s] in that fall (see [`LineEnd::falling`]); `None`: none.
    gravity: Option<(Vector3<f64>, f64)>,
}

impl LineEnd {
    /// The end at local body `body` of link `link`, with the far anchor's initial
    /// position and velocity, the line's impedance `Z` and one-way delay `T` [s], and
    /// the initial wave `c₀` held until the first wave arrives (see [`initial_wave`]).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        link: usize,
        body: usize,
        anchor: Vector3<f64>,
        far: (usize, usize, Vector3<f64>, Vector3<f64>),
        owner_side: bool,
        (impedance, delay): (f64, f64),
        initial_wave: f64,
    ) -> LineEnd {
        let (far_body, far_node, p, v) = far;
        LineEnd {
            link,
            body,
            anchor,
            far_body,
            far_node,
            owner_side,
            impedance,
            delay,
            filtered: initial_wave,
            far: FarEnd {
                p,
                v,
                sent: SimTime::ZERO,
            },
            incoming: initial_wave,
            hold_until: SimTime(u64::MAX),
            last_received: None,
            initial_wave,
            first_wave: None,
            acc: 0.0,
            window_from: SimTime::ZERO,
            tension: initial_wave,
            load: (Vector3::zeros(), Vector3::zeros()),
            given: 0.0,
            impulse: Vector3::zeros(),
            impulse_history: std::collections::VecDeque::new(),
            gravity: None,
        }
    }

    /// The end with uniform gravity `g` [m/s²] acting on the far body, which then
    /// falls between its samples as every body does: `g age (age + lag) / 2` from a
    /// sample `age` old, as the integrator integrates it (`lag` = −dt for explicit
    /// Euler, +dt for symplectic Euler, 0 for RK4, which is exact for a constant
    /// acceleration). The continuous `g age² / 2` under Euler left a falling net's
    /// lines `g dt age / 2` off (2.4e-5 m at 5 ms).
    pub fn falling(mut self, g: Option<Vector3<f64>>, lag: f64) -> LineEnd {
        self.gravity = g.map(|g| (g, lag));
        self
    }

    /// Where the far anchor is estimated to be at `t`: its last sample carried forward
    /// with its velocity, and with the fall uniform gravity gives every body (left
    /// out, a falling net's lines saw each far end `g age²/2` above where it is).
    pub fn far_anchor(&self, t: SimTime) -> Vector3<f64> {
        let age = SimTime(t.0.saturating_sub(self.far.sent.0)).as_secs_f64();
        let p = self.far.p + self.far.v * age;
        match self.gravity {
            Some((g, lag)) => p + g * (0.5 * age * (age + lag)),
            None => p,
        }
    }

    /// The step of length `h` [s] at `t`, this end's anchor at `p` moving at `v`: sets
    /// the tension, books the outgoing wave and the energy, and returns the force on the
    /// anchor (the caller adds the torque `r × F` on a rigid body).
    pub fn step(
        &mut self,
        t: SimTime,
        h: f64,
        (p, v): (Vector3<f64>, Vector3<f64>),
        reference: Vector3<f64>,
    ) -> Vector3<f64> {
        let d = self.far_anchor(t) - p;
        let len = d.norm();
        let n = if len > 0.0 { d / len } else { Vector3::zeros() };
        // The port velocity: half the extension rate this end sees, its own velocity
        // against the far end's last sampled one. Relative, so a uniform velocity of
        // the whole net changes no wave and no tension, also while the link turns.
        let s = -n.dot(&(v - reference));
        // Without a wave in force (lost, late, or past its hold) the end applies the
        // wave that makes its tension zero: it then neither gives nor takes energy.
        let held = self.held(t).unwrap_or(-self.impedance * s);
        // The low-pass filter of the incoming wave.
        let tf = filter_time(self.delay, h);
        let alpha = tf / (tf + h);
        self.filtered = alpha * self.filtered + (1.0 - alpha) * held;
        let c = self.filtered;
        let z = self.impedance;
        self.tension = c + z * s;
        self.acc += (c + 2.0 * z * s) * h;
        // The work on the body itself, at its own velocity; the impulse (the force is
        // held over the step).
        self.given -= self.tension * s * h;
        self.impulse += n * (self.tension * h);
        n * self.tension
    }

    /// The received wave in force at `t` (before the filter): the last one within its
    /// hold, else none.
    pub fn held(&self, t: SimTime) -> Option<f64> {
        (t < self.hold_until).then_some(self.incoming)
    }

    /// The sample this end sends at `t`: the mean outgoing wave since the previous
    /// sample, and the anchor's position `p` and velocity `v`. Starts a new window.
    pub fn sample(&mut self, t: SimTime, p: Vector3<f64>, v: Vector3<f64>) -> LineSample {
        let span = SimTime(t.0.saturating_sub(self.window_from.0));
        let wave = if span.0 > 0 {
            self.acc / span.as_secs_f64()
        } else {
            0.0
        };
        self.acc = 0.0;
        self.window_from = t;
        LineSample {
            link: self.link,
            wave,
            span,
            p,
            v,
            // Only the owner end's impulse is compared (by the other end).
            impulse: if self.owner_side {
                self.impulse
            } else {
                Vector3::zeros()
            },
        }
    }

    /// A sample of the far end taken at `sent`, applied from `now` (the next step's
    /// time). An older sample than the last one received is ignored; an empty window
    /// (`span` 0) updates only the far anchor.
    pub fn receive(&mut self, sent: SimTime, now: SimTime, s: &LineSample) {
        if self.last_received.is_some_and(|last| sent <= last) {
            return;
        }
        self.last_received = Some(sent);
        self.far = FarEnd {
            p: s.p,
            v: s.v,
            sent,
        };
        if s.span.0 > 0 {
            self.first_wave.get_or_insert(now);
            self.incoming = s.wave;
            self.hold_until = SimTime(now.0.saturating_add(s.span.0));
        }
    }

    /// The most energy the initial wave can give this end's body [J]: `c₀²` over its
    /// hold (until the first wave arrives, or `now`) and the filter's time constant,
    /// divided by `4Z` (what a line filled with `c₀` holds for this end).
    pub fn initial_energy(&self, now: SimTime, h: f64) -> f64 {
        let hold = self.first_wave.unwrap_or(now).as_secs_f64();
        let tf = filter_time(self.delay, h);
        self.initial_wave * self.initial_wave * (hold + tf) / (4.0 * self.impedance)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(k: u64) -> SimTime {
        SimTime(k * 1_000_000)
    }

    fn end(z: f64, c0: f64) -> LineEnd {
        LineEnd::new(
            0,
            0,
            Vector3::zeros(),
            (1, 1, Vector3::new(1.0, 0.0, 0.0), Vector3::zeros()),
            true,
            (z, z / 400.0),
            c0,
        )
    }

    #[test]
    fn an_end_pulled_away_feels_its_impedance_and_sends_twice_its_rate() {
        // The far end sits at +x; this end moves towards −x at 1 m/s: it extends the
        // line at 1 m/s, so T = Z·1 pulls it back (+x) and the wave sent is 2Z.
        let mut e = end(10.0, 0.0);
        let f = e.step(
            ms(0),
            0.001,
            (Vector3::zeros(), Vector3::new(-1.0, 0.0, 0.0)),
            Vector3::zeros(),
        );
        assert!((f - Vector3::new(10.0, 0.0, 0.0)).norm() < 1e-12);
        assert!(
            (e.given + 10.0 * 0.001).abs() < 1e-12,
            "the body gives T s h"
        );
        let s = e.sample(ms(1), Vector3::zeros(), Vector3::zeros());
        assert!((s.wave - 20.0).abs() < 1e-9);
        assert_eq!(s.span, ms(1));
    }

    #[test]
    fn a_received_wave_is_held_for_its_window_then_dropped_to_no_tension() {
        let mut e = end(10.0, 5.0);
        // Before any arrival the initial wave holds (and the filter starts from it).
        let f = e.step(
            ms(3),
            0.001,
            (Vector3::zeros(), Vector3::zeros()),
            Vector3::zeros(),
        );
        assert_eq!(f.x, 5.0);
        let sample = LineSample {
            link: 0,
            wave: 7.0,
            span: ms(2),
            p: Vector3::new(1.0, 0.0, 0.0),
            v: Vector3::zeros(),
            impulse: Vector3::zeros(),
        };
        e.receive(ms(4), ms(5), &sample);
        assert_eq!(
            (e.held(ms(5)), e.held(ms(6)), e.held(ms(7))),
            (Some(7.0), Some(7.0), None)
        );
        // The filter moves the tension towards the held wave, never past it.
        let f = e
            .step(
                ms(5),
                0.001,
                (Vector3::zeros(), Vector3::zeros()),
                Vector3::zeros(),
            )
            .x;
        assert!(f > 5.0 && f < 7.0, "{f}");
        // An older sample arriving late changes nothing.
        e.receive(
            ms(3),
            ms(8),
            &LineSample {
                wave: 9.0,
                ..sample
            },
        );
        assert_eq!(e.held(ms(8)), None);
    }

    #[test]
    fn without_a_wave_the_end_pulls_nothing_in_any_frame() {
        // Past its hold the end applies the wave of zero tension: no force, whatever
        // the end's velocity against the reference, and the same for any reference
        // shifted with it.
        let mut e = end(10.0, 0.0);
        e.receive(
            ms(1),
            ms(1),
            &LineSample {
                link: 0,
                wave: 4.0,
                span: ms(1),
                p: Vector3::new(1.0, 0.0, 0.0),
                v: Vector3::zeros(),
                impulse: Vector3::zeros(),
            },
        );
        // Hold long over and the filter settled: the tension decays to zero.
        let mut f = Vector3::zeros();
        for k in 10..1500 {
            let v = Vector3::new(-0.3, 0.2, 0.0);
            f = e.step(
                ms(k),
                0.001,
                (Vector3::zeros(), v + Vector3::new(5.0, 0.0, 0.0)),
                Vector3::new(5.0, 0.0, 0.0),
            );
        }
        assert!(f.norm() < 1e-6, "{f}");
    }

    #[test]
    fn the_initial_wave_gives_a_stretched_line_its_spring_tension_at_rest_in_any_frame() {
        // Z = 10 N·s/m, T = 5 ms: a spring of 2000 N/m; 1 mm stretched: 2 N, and an end
        // moving with the reference (s₀ = 0) starts with exactly that tension.
        let c0 = initial_wave(10.0, 0.005, 0.001, 0.0);
        assert!((c0 - 2.0).abs() < 1e-12);
        // An end receding at 0.5 m/s along the link holds c₀ = 2 − Z·0.5.
        assert!((initial_wave(10.0, 0.005, 0.001, 0.5) - (2.0 - 5.0)).abs() < 1e-12);
    }

    #[test]
    fn a_held_window_average_never_carries_more_energy_than_went_in() {
        // Any wave history: span · mean² ≤ ∫ b² dt (the energy the receiver can get
        // from a window is at most what the sender put in over it).
        let mut e = end(3.0, 0.0);
        let mut energy_in = 0.0;
        for k in 0..20u64 {
            let v = Vector3::new((k as f64 * 0.7).sin(), 0.0, 0.0);
            let b = 2.0 * 3.0 * -v.x; // c = 0, s = −n·v with n = +x
            energy_in += b * b * 0.001;
            e.step(ms(k), 0.001, (Vector3::zeros(), v), Vector3::zeros());
        }
        let s = e.sample(ms(20), Vector3::zeros(), Vector3::zeros());
        assert!(s.span.as_secs_f64() * s.wave * s.wave <= energy_in + 1e-12);
        assert!(s.wave != 0.0);
    }
}
