//! The invariants a coupling must keep, each against physics or against the monolithic
//! run with the same integrator (never against the coupling's own output): linear and
//! angular momentum, kinetic energy, the same relative motion in every inertial frame,
//! and the integrator's order when the delay is one step.

use dsmcosim::cosim::{CoSim, Observer, StepValues};
use dsmcosim::scenario::parse_str;
use nalgebra::Vector3;
use serde_json::{json, Value};

/// Per step: total momentum, angular momentum about the centre of mass, kinetic
/// energy, every body's position relative to the centre of mass; the largest |w|.
#[derive(Default)]
struct Invariants {
    masses: Vec<f64>,
    momentum: Vec<Vector3<f64>>,
    angular: Vec<Vector3<f64>>,
    kinetic: Vec<f64>,
    relative: Vec<Vec<Vector3<f64>>>,
    absolute: Vec<Vec<Vector3<f64>>>,
    max_w: f64,
}

impl Observer for Invariants {
    fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
        let total: f64 = self.masses.iter().sum();
        let (mut p, mut c, mut ke) = (Vector3::zeros(), Vector3::zeros(), 0.0);
        for ((x, v), m) in s.p.iter().zip(s.v).zip(&self.masses) {
            p += v * *m;
            c += x * *m;
            ke += 0.5 * m * v.norm_squared();
        }
        c /= total;
        let vc = p / total;
        let mut l = Vector3::zeros();
        for ((x, v), m) in s.p.iter().zip(s.v).zip(&self.masses) {
            l += (x - c).cross(&(v - vc)) * *m;
        }
        self.momentum.push(p);
        self.angular.push(l);
        self.kinetic.push(ke);
        self.relative.push(s.p.iter().map(|x| x - c).collect());
        self.absolute.push(s.p.to_vec());
        for w in s.w {
            self.max_w = self.max_w.max(w.abs());
        }
        Ok(())
    }
}

/// The largest distance between the same body of two runs at the same step [m].
fn farthest(a: &[Vec<Vector3<f64>>], b: &[Vec<Vector3<f64>>]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).norm()))
        .fold(0.0, f64::max)
}

fn run(v: &Value) -> (Invariants, Option<String>) {
    let s = parse_str(&v.to_string(), "<test>").unwrap_or_else(|e| panic!("scenario: {e}"));
    let mut inv = Invariants {
        masses: s.bodies.iter().map(|b| b.mass).collect(),
        ..Invariants::default()
    };
    let error = CoSim::new(&s)
        .run_to_end(&mut inv)
        .err()
        .map(|e| e.to_string());
    (inv, error)
}

/// The thesis net (4×4, 1.8 m, 1 kg) on its 4 quadrant nodes, every body moving at
/// `velocity`, body 1 driven by 20 N at 2 rad/s until `until` (none: undriven), both
/// channels at τ with latency τ; `coupling` "mono" drops the partition.
fn net(coupling: &str, tau: f64, until: Option<f64>, duration: f64, velocity: [f64; 3]) -> Value {
    let (mut bodies, mut links) = (Vec::new(), Vec::new());
    for r in 0..4 {
        for c in 0..4 {
            let id = r * 4 + c + 1;
            bodies.push(json!({"id": id, "mass": 1.0, "size": 0.2,
                "position": [c as f64 * 1.8, r as f64 * 1.8, 0.0], "velocity": velocity}));
            if c < 3 {
                links.push(json!({"a": id, "b": id + 1}));
            }
            if r < 3 {
                links.push(json!({"a": id, "b": id + 4}));
            }
        }
    }
    let mut v = json!({
        "name": "net", "seed": 7, "duration": duration, "dt": 0.001,
        "model": {"bodies": bodies, "links": links},
        "partition": {"nodes": [[1, 2, 5, 6], [3, 4, 7, 8], [11, 12, 15, 16], [9, 10, 13, 14]]},
        "channels": [{"name": "tau1", "tau": tau, "borders": [[1, 2], [1, 4]]},
                     {"name": "tau2", "tau": tau, "borders": [[2, 3], [3, 4]]}]
    });
    if let Some(until) = until {
        v["forces"] = json!([{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0, "until": until}]);
    }
    match coupling {
        "mono" => {
            let o = v.as_object_mut().expect("object");
            o.remove("partition");
            o.remove("channels");
        }
        "default" => {}
        c => v["partition"]["coupling"] = json!(c),
    }
    v
}

#[test]
fn a_uniformly_translating_net_stays_rigid_under_every_scheme() {
    // No force, every body at (1, 0.5, 0) m/s: a rigid translation, which every
    // coupling must carry exactly, however late its data (`reset` lags by v·age by
    // construction and is left out).
    let v0 = Vector3::new(1.0, 0.5, 0.0);
    for coupling in ["predict", "passive", "tlm", "default"] {
        for tau in [0.005, 0.05] {
            let (inv, error) = run(&net(coupling, tau, None, 3.0, [1.0, 0.5, 0.0]));
            let verr = inv
                .momentum
                .iter()
                .map(|p| (p / 16.0 - v0).norm())
                .fold(0.0, f64::max);
            assert!(error.is_none(), "{coupling}, τ = {tau}: {error:?}");
            assert!(
                verr <= 1e-9 && inv.max_w <= 1e-9,
                "{coupling}, τ = {tau}: velocity error {verr:e} m/s, max |w| {:e} m",
                inv.max_w
            );
        }
    }
}

#[test]
fn a_uniform_velocity_added_changes_no_relative_motion() {
    // The thesis net driven until 2 s, then free; the same run with every body moving
    // at an extra uniform velocity (out of plane, as the review's −1.034 m/s, and in
    // plane) must give the same positions relative to the centre of mass.
    for coupling in ["default", "tlm", "predict"] {
        for tau in [0.005, 0.02, 0.05] {
            let (a, ea) = run(&net(coupling, tau, Some(2.0), 3.0, [0.0; 3]));
            for shift in [[0.0, 0.0, -1.034], [0.7, -0.4, 0.0]] {
                let (b, eb) = run(&net(coupling, tau, Some(2.0), 3.0, shift));
                assert!(
                    ea.is_none() && eb.is_none(),
                    "{coupling}, τ = {tau}: {ea:?} {eb:?}"
                );
                let worst = farthest(&a.relative, &b.relative);
                assert!(
                    worst <= 1e-6,
                    "{coupling}, τ = {tau}, shift {shift:?}: relative positions differ by {worst:e} m"
                );
            }
        }
    }
}

#[test]
fn the_undriven_thesis_net_keeps_its_momentum_and_energy_under_the_default() {
    // Driven until 2 s, then free to 6 s. The monolithic run keeps its momentum to
    // round-off and gains kinetic energy only through explicit Euler's own drift; the
    // partitioned run may differ from it by a bounded momentum in flight (the border
    // forces' impulse over one age) but must neither drift nor drain: kinetic energy
    // change within 2 % above and 5 % below the monolithic run's change. Momentum
    // within 1 kg·m/s of the monolithic run's at every step of 2–6 s: the coupling's
    // momentum account (`partition::momentum`) gives back what the predicted forces
    // missed and the brake took, up to the impulse of the reports in flight; that holds
    // at 1, 5 and 10 ms, and at 20 ms the swing between reports is larger (measured in
    // docs/method.md), so the test asserts it where it holds and prints the rest.
    let (mono, _) = run(&net("mono", 0.001, Some(2.0), 6.0, [0.0; 3]));
    let (k2, k6) = (2000, 6000);
    let p_mono = mono.momentum[k2];
    let drift_mono = mono.kinetic[k6] / mono.kinetic[k2] - 1.0;
    assert!(
        (mono.momentum[k6] - p_mono).norm() < 1e-9,
        "monolithic momentum"
    );
    for tau in [0.001, 0.005, 0.010, 0.020] {
        let (inv, error) = run(&net("default", tau, Some(2.0), 6.0, [0.0; 3]));
        assert!(error.is_none(), "τ = {tau}: {error:?}");
        let worst = inv.momentum[k2..=k6]
            .iter()
            .map(|p| (p - p_mono).norm())
            .fold(0.0, f64::max);
        let drift = inv.kinetic[k6] / inv.kinetic[k2] - 1.0;
        eprintln!(
            "τ = {tau}: momentum off by ≤ {worst:.3} kg·m/s, kinetic energy {:+.2} % \
             (monolithic {:+.2} %)",
            100.0 * drift,
            100.0 * drift_mono
        );
        if tau <= 0.010 {
            assert!(worst <= 1.0, "τ = {tau}: momentum off by {worst} kg·m/s");
        }
        assert!(
            drift <= drift_mono + 0.02 && drift >= drift_mono - 0.05,
            "τ = {tau}: kinetic energy changed {drift:+} against the monolithic {drift_mono:+}"
        );
    }
}

/// A dumbbell (2 × 1 kg, 1.8 m) spinning at ±10 m/s, RK4, split over two nodes with
/// samples every step and no latency (or monolithic).
fn dumbbell(dt: f64, split: bool) -> Value {
    let mut v = json!({"name": "dumbbell", "seed": 1, "duration": 5.0, "dt": dt, "integrator": "rk4",
        "model": {"bodies": [
            {"id": 1, "mass": 1.0, "size": 0.2, "position": [0, 0, 0], "velocity": [0, 10, 0]},
            {"id": 2, "mass": 1.0, "size": 0.2, "position": [1.8, 0, 0], "velocity": [0, -10, 0]}],
          "links": [{"a": 1, "b": 2}]},
        "partition": {"nodes": [[1], [2]]},
        "channels": [{"name": "c", "tau": dt, "latency": 0.0}]});
    if !split {
        let o = v.as_object_mut().expect("object");
        o.remove("partition");
        o.remove("channels");
    }
    v
}

#[test]
fn a_partition_keeps_rk4_at_second_order_with_no_delay() {
    // Border values held over RK4's stages made the split dumbbell gain 44 % kinetic
    // energy in 5 s (first order); carried to each stage's time by their rates, it
    // keeps it within 1 % and the error falls at least as dt². Under both laws (under
    // Baumgarte the border force sampled at t = 0 read the multipliers before any
    // evaluation, zero, and the split fell to first order).
    for law in [Value::Null, json!({"kind": "baumgarte"})] {
        rk4_order_with_no_delay(law);
    }
}

/// [`a_partition_keeps_rk4_at_second_order_with_no_delay`] under `law` (null: the
/// default).
fn rk4_order_with_no_delay(law: Value) {
    let with = |mut v: Value| {
        if !law.is_null() {
            v["stabilizer"] = law.clone();
        }
        v
    };
    let mut gains = Vec::new();
    for dt in [0.002, 0.001, 0.0005] {
        let (m, _) = run(&with(dumbbell(dt, false)));
        let (s, error) = run(&with(dumbbell(dt, true)));
        assert!(error.is_none(), "{law}, dt = {dt}: {error:?}");
        let mono_gain = m.kinetic.last().expect("steps") / m.kinetic[0] - 1.0;
        let gain = s.kinetic.last().expect("steps") / s.kinetic[0] - 1.0;
        assert!(
            mono_gain.abs() < 1e-7,
            "{law}: monolithic RK4 keeps its energy: {mono_gain:e}"
        );
        assert!(
            gain.abs() < 0.01,
            "{law}, dt = {dt}: kinetic energy {gain:+e}"
        );
        // Under the exact law the energy error changes sign between steps, so its
        // ratios say nothing of an order: there the measure is what the split adds to
        // the monolithic run at the same step, the largest distance between the runs'
        // bodies.
        let apart = farthest(&m.absolute, &s.absolute);
        gains.push(if law.is_null() { gain.abs() } else { apart });
    }
    let orders: Vec<f64> = gains.windows(2).map(|p| (p[0] / p[1]).log2()).collect();
    eprintln!("{law}: split dumbbell errors {gains:?}, orders {orders:?}");
    for order in orders {
        assert!(
            order >= 1.8,
            "{law}: error order {order:.2} in dt ({gains:?})"
        );
    }
}

#[test]
fn the_thesis_net_partitioned_at_zero_delay_converges_at_second_order_in_dt() {
    // RK4, μ = 0.02 s, τ = dt, no latency, body 1 over 0–3 s: the differences between
    // successive halvings of dt fall at order ≥ 1.8 (they fell as dt before), to the
    // partitioning floor; the floor itself (a property of solving each node's links
    // apart) is below 1 mm against the monolithic run here.
    let scene = |dt: f64, coupling: &str| {
        let mut v = net(coupling, dt, Some(12.0), 3.0, [0.0; 3]);
        v["dt"] = json!(dt);
        v["integrator"] = json!("rk4");
        v["stabilizer"] = json!({"kind": "smc", "mu": 0.02, "k": 10.0, "epsilon": 0.1});
        if coupling != "mono" {
            v["channels"][0]["latency"] = json!(0.0);
            v["channels"][1]["latency"] = json!(0.0);
        }
        v
    };
    let body1 = |inv: &Invariants, stride: usize| -> Vec<Vector3<f64>> {
        inv.absolute.iter().step_by(stride).map(|p| p[0]).collect()
    };
    let rms = |a: &[Vector3<f64>], b: &[Vector3<f64>]| {
        let n = a.len().min(b.len());
        ((0..n).map(|i| (a[i] - b[i]).norm_squared()).sum::<f64>() / n as f64).sqrt()
    };
    for coupling in ["default", "predict"] {
        let runs: Vec<Invariants> = [0.002, 0.001, 0.0005]
            .iter()
            .map(|&dt| run(&scene(dt, coupling)).0)
            .collect();
        let d1 = rms(&body1(&runs[0], 1), &body1(&runs[1], 2));
        let d2 = rms(&body1(&runs[1], 1), &body1(&runs[2], 2));
        let order = (d1 / d2).log2();
        let (mono, _) = run(&scene(0.0005, "mono"));
        let floor = rms(&body1(&runs[2], 1), &body1(&mono, 1));
        eprintln!("{coupling}: self-differences {d1:.3e}, {d2:.3e} m (order {order:.2}); floor {floor:.3e} m");
        assert!(order >= 1.8, "{coupling}: order {order:.2} in dt");
        assert!(
            floor < 1e-3,
            "{coupling}: {floor} m from the monolithic run"
        );
    }
}

/// Total energy (kinetic plus the potential of the constant pushes) and the outer bob's
/// position, per step, of the double pendulum below.
#[derive(Default)]
struct Pendulum {
    energy: Vec<f64>,
    outer: Vec<Vector3<f64>>,
    max_w: f64,
}

impl Observer for Pendulum {
    fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
        // Bobs 2 and 3 (1 kg) under a constant 9.81 N push along −y: U = 9.81 y.
        let e: f64 = (1..3)
            .map(|b| 0.5 * s.v[b].norm_squared() + 9.81 * s.p[b].y)
            .sum();
        self.energy.push(e);
        self.outer.push(s.p[2]);
        for w in s.w {
            self.max_w = self.max_w.max(w.abs());
        }
        Ok(())
    }
}

#[test]
fn a_partitioned_double_pendulum_keeps_its_energy_and_follows_the_monolithic_run() {
    // Not a grid: a double pendulum of 1 kg bobs on 1 m links, a 1e9 kg body as the
    // pivot, a constant 9.81 N push on each bob, released horizontal (total energy 0).
    // Pivot and inner bob on one node, the outer bob on the other, RK4 at 1 ms,
    // latency = τ. The default must hold the energy within 1 J over 4 s at 5 ms, keep the
    // outer bob within 1 cm of the monolithic run over 0–0.5 s, and stay bounded at 20
    // and 50 ms.
    let scene = |tau: Option<f64>| {
        let mut v = json!({"name": "pendulum", "seed": 1, "duration": 4.0, "dt": 0.001,
            "integrator": "rk4",
            "model": {"bodies": [
                {"id": 1, "mass": 1e9, "size": 0.2, "position": [0, 0, 0]},
                {"id": 2, "mass": 1.0, "size": 0.2, "position": [1, 0, 0]},
                {"id": 3, "mass": 1.0, "size": 0.2, "position": [2, 0, 0]}],
              "links": [{"a": 1, "b": 2}, {"a": 2, "b": 3}]},
            "forces": [
                {"body": 2, "amplitude": [0, -9.81, 0], "omega": 0, "phase": std::f64::consts::FRAC_PI_2},
                {"body": 3, "amplitude": [0, -9.81, 0], "omega": 0, "phase": std::f64::consts::FRAC_PI_2}]});
        if let Some(tau) = tau {
            v["partition"] = json!({"nodes": [[1, 2], [3]]});
            v["channels"] = json!([{"name": "c", "tau": tau}]);
        }
        v
    };
    let go = |v: &Value| {
        let s = parse_str(&v.to_string(), "<test>").unwrap_or_else(|e| panic!("{e}"));
        let mut p = Pendulum::default();
        let error = CoSim::new(&s)
            .run_to_end(&mut p)
            .err()
            .map(|e| e.to_string());
        (p, error)
    };
    let (mono, _) = go(&scene(None));
    for tau in [0.005, 0.02, 0.05] {
        let (p, error) = go(&scene(Some(tau)));
        assert!(error.is_none() && p.max_w < 1.0, "τ = {tau}: {error:?}");
        if tau == 0.005 {
            let worst = p.energy.iter().map(|e| e.abs()).fold(0.0, f64::max);
            let off = p
                .outer
                .iter()
                .zip(&mono.outer)
                .take(501)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            eprintln!("τ = 5 ms: |E| ≤ {worst:.3} J, outer bob ≤ {off:.2e} m off");
            assert!(worst <= 1.0, "total energy reached {worst} J");
            assert!(off <= 1e-2, "outer bob {off} m from the monolithic run");
        }
    }
}

#[test]
fn a_free_spinning_ring_keeps_its_angular_momentum_and_energy() {
    // 12 bodies of 1 kg on a ring of 1.8 m links spinning at 2 rad/s, no force, on 3
    // nodes of 4 consecutive bodies, explicit Euler, 3 s. The monolithic run changes
    // |L| by +1.2 % and the kinetic energy by +2.4 % (Euler's own drift); the default
    // must hold both within 3 % at 5 and 10 ms (at 50 ms, where the border links are
    // lines, |L| moves 5.05 %: printed, not met).
    let n = 12;
    let radius = 1.8 / (2.0 * (std::f64::consts::PI / n as f64).sin());
    let (mut bodies, mut links) = (Vec::new(), Vec::new());
    for k in 0..n {
        let a = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
        bodies.push(json!({"id": k + 1, "mass": 1.0, "size": 0.2,
            "position": [radius * a.cos(), radius * a.sin(), 0.0],
            "velocity": [-2.0 * radius * a.sin(), 2.0 * radius * a.cos(), 0.0]}));
        links.push(json!({"a": k + 1, "b": (k + 1) % n + 1, "length": 1.8}));
    }
    let scene = |tau: Option<f64>| {
        let mut v = json!({"name": "ring", "seed": 1, "duration": 3.0, "dt": 0.001,
            "model": {"bodies": bodies, "links": links}});
        if let Some(tau) = tau {
            v["partition"] = json!({"nodes": [[1, 2, 3, 4], [5, 6, 7, 8], [9, 10, 11, 12]]});
            v["channels"] = json!([{"name": "all", "tau": tau}]);
        }
        v
    };
    let change = |inv: &Invariants| {
        let last = inv.kinetic.len() - 1;
        (
            inv.angular[last].norm() / inv.angular[0].norm() - 1.0,
            inv.kinetic[last] / inv.kinetic[0] - 1.0,
        )
    };
    let (mono, _) = run(&scene(None));
    let (l_mono, ke_mono) = change(&mono);
    assert!(
        l_mono.abs() < 0.03 && ke_mono.abs() < 0.03,
        "monolithic {l_mono} {ke_mono}"
    );
    for tau in [0.005, 0.01, 0.02, 0.03, 0.04, 0.05] {
        let (inv, error) = run(&scene(Some(tau)));
        assert!(error.is_none(), "τ = {tau}: {error:?}");
        let (l, ke) = change(&inv);
        eprintln!(
            "τ = {tau}: |L| {:+.2} %, KE {:+.2} % (monolithic {:+.2} %, {:+.2} %)",
            100.0 * l,
            100.0 * ke,
            100.0 * l_mono,
            100.0 * ke_mono
        );
        // Within 3 % to 10 ms (+1.08 %, +2.15 % measured); from 20 ms |L| leaves it
        // (+3.29 % at 20 and 30 ms, +4.24 % at 40, +5.05 % at 50, lines from 30 ms):
        // printed, open (method §3.1).
        if tau <= 0.01 {
            assert!(
                l.abs() <= 0.03 && ke.abs() <= 0.03,
                "τ = {tau}: |L| {l:+}, KE {ke:+}"
            );
        }
    }
}

#[test]
fn the_momentum_the_brake_takes_is_given_back_and_its_energy_stays_removed() {
    // An empty tank at 5 ms: the passivity brake works hard on the undriven net (it
    // removes energy, asserted below, so the test would pass vacuously without it).
    // Its force −c (v − V) alone takes momentum, `braked` in all; the account gives it
    // back as a uniform push. Both ways: energy removed (the brake's own figure) and
    // the momentum kept, on average and at the end, to a tenth of what the brake took
    // (without the account the error would end at |braked| itself).
    let mut v = net("passive", 0.005, Some(2.0), 6.0, [0.0; 3]);
    v["partition"]["coupling"] = json!({"scheme": "passive", "tank": 0.0});
    let s = parse_str(&v.to_string(), "<test>").expect("scenario");
    let mut inv = Invariants {
        masses: s.bodies.iter().map(|b| b.mass).collect(),
        ..Invariants::default()
    };
    let mut world = CoSim::new(&s);
    world.run_to_end(&mut inv).expect("bounded");
    let dissipated: f64 = world
        .nodes()
        .iter()
        .map(|n| n.port_energy().dissipated)
        .sum();
    let braked: Vector3<f64> = world
        .nodes()
        .iter()
        .map(|n| n.brake_impulse().expect("an account"))
        .sum();
    let (mono, _) = run(&net("mono", 0.001, Some(2.0), 6.0, [0.0; 3]));
    // The brake works in bursts, and a burst's impulse is given back over the push
    // time once its reports arrive: the error swings (2.7 kg·m/s at 5 s, measured) but
    // does not accumulate.
    let errors: Vec<f64> = (2000..=6000)
        .map(|k| (inv.momentum[k] - mono.momentum[k]).norm())
        .collect();
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    let end = errors[errors.len() - 1];
    eprintln!(
        "brake dissipated {dissipated:.2} J and took {:.2} kg·m/s; momentum off by \
         {mean:.3} kg·m/s on average over 2–6 s, {end:.3} at 6 s",
        braked.norm()
    );
    assert!(dissipated > 10.0, "the brake removed only {dissipated} J");
    assert!(
        mean <= 0.1 * braked.norm() && end <= 0.1 * braked.norm(),
        "momentum off by {mean} kg·m/s on average, {end} at the end; the brake took {}",
        braked.norm()
    );
}

/// The free ring of [`a_free_spinning_ring_keeps_its_angular_momentum_and_energy`], a
/// little out of plane so its links also move along z, on 3 nodes under `coupling` at
/// τ, with uniform `gravity`.
fn falling_ring(coupling: &str, tau: f64, gravity: Option<[f64; 3]>) -> Value {
    let n = 12;
    let radius = 1.8 / (2.0 * (std::f64::consts::PI / n as f64).sin());
    let (mut bodies, mut links) = (Vec::new(), Vec::new());
    for k in 0..n {
        let a = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
        bodies.push(
            json!({"id": k + 1, "mass": 1.0 + 0.25 * (k % 3) as f64, "size": 0.2,
            "position": [radius * a.cos(), radius * a.sin(), 0.0],
            "velocity": [-2.0 * radius * a.sin(), 2.0 * radius * a.cos(), 0.8 * (2.0 * a).sin()]}),
        );
        links.push(json!({"a": k + 1, "b": (k + 1) % n + 1, "length": 1.8}));
    }
    let mut v = json!({"name": "ring", "seed": 1, "duration": 3.0, "dt": 0.001,
        "model": {"bodies": bodies, "links": links},
        "partition": {"nodes": [[1, 2, 3, 4], [5, 6, 7, 8], [9, 10, 11, 12]]},
        "channels": [{"name": "all", "tau": tau}]});
    if coupling != "default" {
        v["partition"]["coupling"] = json!(coupling);
    }
    if let Some(g) = gravity {
        v["model"]["gravity"] = json!(g);
    }
    v
}

#[test]
fn uniform_gravity_changes_no_relative_motion_under_any_scheme() {
    // A uniform field accelerates every body alike: in the frame falling with the
    // centre of mass nothing changes. Every reference the coupling keeps (the centre
    // of mass's velocity its lines and energy books measure against) must fall too;
    // left out, the brake saw the fall as border power and took energy.
    for coupling in ["default", "passive", "predict", "tlm"] {
        for tau in [0.005, 0.02] {
            let (a, ea) = run(&falling_ring(coupling, tau, None));
            let (b, eb) = run(&falling_ring(coupling, tau, Some([0.0, 0.0, -9.81])));
            assert!(
                ea.is_none() && eb.is_none(),
                "{coupling}, τ = {tau}: {ea:?} {eb:?}"
            );
            let worst = farthest(&a.relative, &b.relative);
            // Both ways: the ring did fall (44 m in 3 s) and did move relative to its
            // centre (it spins), so agreement is not two frozen runs.
            let fell = a.absolute.last().unwrap()[0].z - b.absolute.last().unwrap()[0].z;
            eprintln!("{coupling}, τ = {tau}: relative motion with and without gravity within {worst:.3e} m (fell {fell:.2} m)");
            assert!(fell > 40.0, "{coupling}, τ = {tau}: fell {fell} m");
            // Every reference falls with the net: the centre of mass's velocity, and a
            // line's far anchor between samples as the integrator makes it fall (taken
            // as the continuous `g age²/2` under Euler it left `tlm` 2.4e-5 m off).
            let bound = 1e-9;
            assert!(
                worst <= bound,
                "{coupling}, τ = {tau}: relative positions differ by {worst:e} m"
            );
        }
    }
}

/// A spring inside a node of a partitioned scene: body 1 hangs on a spring from body 2,
/// which a border link ties to body 3 on the other node. The ghost of body 2 on node 2
/// feels the spring through its owner's load, so with samples every step and no
/// latency the split follows the monolithic run to its partitioning floor.
#[test]
fn a_spring_inside_a_node_crosses_a_border_in_its_bodys_load() {
    let scene = |split: bool| {
        let mut v = json!({
            "name": "spring and link", "seed": 1, "duration": 2.0, "dt": 0.001,
            "integrator": "rk4",
            "model": {
                "bodies": [
                    {"id": 1, "mass": 1.0, "size": 0.2, "position": [0, -1.2, 0], "velocity": [0.3, 0, 0]},
                    {"id": 2, "mass": 1.0, "size": 0.2, "position": [0, 0, 0]},
                    {"id": 3, "mass": 1.0, "size": 0.2, "position": [1.8, 0, 0], "velocity": [0, 0.5, 0]}
                ],
                "links": [{"a": 2, "b": 3}],
                "springs": [{"a": 1, "b": 2, "stiffness": 40.0, "length": 1.0}]
            }
        });
        if split {
            v["partition"] = json!({"nodes": [[1, 2], [3]]});
            v["channels"] = json!([{"name": "c", "tau": 0.001, "latency": 0.0}]);
        }
        v
    };
    let (mono, _) = run(&scene(false));
    let (split, error) = run(&scene(true));
    assert!(error.is_none(), "{error:?}");
    let worst = farthest(&mono.absolute, &split.absolute);
    // Body 1 swings on its spring (it moves by decimetres): the check is not of a
    // scene at rest.
    let swung = mono
        .absolute
        .iter()
        .map(|x| (x[0] - mono.absolute[0][0]).norm())
        .fold(0.0, f64::max);
    eprintln!("spring beside a border: split within {worst:.3e} m of monolithic (body 1 moved {swung:.2} m)");
    assert!(swung > 0.1, "body 1 moved {swung} m");
    assert!(worst < 1e-3, "split {worst} m from the monolithic run");
}
