//! Joints across a partition: a border joint (its rows' bodies on two nodes) under each
//! predicting scheme follows the monolithic run, and keeps its energy as the monolithic
//! run does.

use dsmcosim::cosim::{CoSim, Observer, StepValues};
use nalgebra::Vector3;
use serde_json::{json, Value};

use super::scenario;

const G: f64 = 9.81;

/// Two uniform rods (1 kg, 1 m) on ball joints, the first pinned at the origin,
/// released horizontal under gravity; with `split`, each rod on its own node, so the
/// middle joint is a border joint.
fn double_pendulum(split: Option<(&str, f64)>) -> Value {
    double_pendulum_at(split, 0.001)
}

/// [`double_pendulum`] at step `dt`, its border sampled every step when split at τ = dt.
fn double_pendulum_at(split: Option<(&str, f64)>, dt: f64) -> Value {
    let rod = |id: u32, x: f64| {
        json!({"id": id, "mass": 1.0, "size": 0.05, "inertia": [1e-3, 1.0 / 12.0, 1.0 / 12.0],
               "position": [x, 0, 0]})
    };
    let mut v = json!({
        "name": "double", "seed": 1, "duration": 3.0, "dt": dt, "integrator": "rk4",
        "model": {
            "gravity": [0, 0, -G],
            "bodies": [rod(1, 0.5), rod(2, 1.5)],
            "joints": [{"type": "ball", "a": 1, "at": [0, 0, 0]},
                       {"type": "ball", "a": 1, "b": 2, "at": [1, 0, 0]}]
        }
    });
    if let Some((coupling, tau)) = split {
        v["partition"] = json!({"nodes": [[1], [2]], "coupling": coupling});
        v["channels"] = json!([{"name": "border", "tau": tau, "latency": 0.0}]);
    }
    v
}

/// The scene `v` under `law`: the default (null) or a stabilizer by name.
fn under(law: &Value, mut v: Value) -> Value {
    if !law.is_null() {
        v["stabilizer"] = law.clone();
    }
    v
}

/// Positions and total energy (kinetic, rotational included, plus gravity's potential)
/// per step.
#[derive(Default)]
struct Record {
    positions: Vec<[Vector3<f64>; 2]>,
    energy: Vec<f64>,
}

impl Observer for Record {
    fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
        self.positions.push([s.p[0], s.p[1]]);
        let potential: f64 =
            s.p.iter()
                .zip(s.bodies)
                .map(|(p, b)| b.mass * G * p.z)
                .sum();
        self.energy.push(s.invariants().kinetic_energy + potential);
        Ok(())
    }
}

fn record(v: &Value) -> Record {
    let mut r = Record::default();
    CoSim::new(&scenario(v))
        .run_to_end(&mut r)
        .unwrap_or_else(|e| panic!("{e}"));
    r
}

/// The largest distance between either rod of two runs at the same step [m].
fn farthest(a: &Record, b: &Record) -> f64 {
    a.positions
        .iter()
        .zip(&b.positions)
        .map(|(a, b)| (a[0] - b[0]).norm().max((a[1] - b[1]).norm()))
        .fold(0.0, f64::max)
}

/// The largest |E(t) − E(0)| [J].
fn energy_drift(r: &Record) -> f64 {
    r.energy
        .iter()
        .map(|e| (e - r.energy[0]).abs())
        .fold(0.0, f64::max)
}

#[test]
fn a_border_joint_follows_the_monolithic_run_at_tau_dt_and_keeps_its_energy() {
    let mono = record(&double_pendulum(None));
    let mono_drift = energy_drift(&mono);
    // The swing's largest kinetic energy: the scale of the energy bounds.
    let swing = mono.energy[0]
        - mono
            .positions
            .iter()
            .map(|p| G * (p[0].z + p[1].z))
            .fold(f64::INFINITY, f64::min);
    for scheme in ["predict", "passive", "tlm"] {
        let split = record(&double_pendulum(Some((scheme, 0.001))));
        let worst = farthest(&mono, &split);
        let drift = energy_drift(&split);
        eprintln!(
            "{scheme}: {worst:.3e} m from monolithic over 3 s; energy drift {drift:.3e} J \
             (monolithic {mono_drift:.3e} J, swing {swing:.2} J)"
        );
        // The partitioning floor of the thesis scene's bound (1e-2 m).
        assert!(worst < 1e-2, "{scheme}: {worst} m from the monolithic run");
        // Both ways: the monolithic drift (the SMC law's own, 10 % of the swing with the
        // thesis's μ = 0.05) plus 2 % of the swing's energy, and no less than it minus
        // 5 % (no dissipation hiding a border's error).
        assert!(
            drift < mono_drift + 0.02 * swing,
            "{scheme}: energy drift {drift} J"
        );
        assert!(
            drift > mono_drift - 0.05 * swing,
            "{scheme}: energy drift {drift} J"
        );
    }
}

/// Two cubes on a ball joint, split over two nodes, translating together at
/// (1, 0.5, 0) m/s with no force: a border joint must not tell the frame apart, so the
/// pair stays rigid and keeps its velocity under every scheme, at τ = 5 ms.
#[test]
fn a_translating_pair_on_a_border_joint_stays_rigid_in_any_frame() {
    let u = Vector3::new(1.0, 0.5, 0.0);
    for scheme in ["predict", "passive", "tlm", "reset"] {
        let cube = |id: u32, x: f64| {
            json!({"id": id, "mass": 1.0, "size": 1.0, "position": [x, 0, 0],
                   "velocity": [u.x, u.y, u.z]})
        };
        let v = json!({
            "name": "pair", "seed": 1, "duration": 3.0, "dt": 0.001, "integrator": "rk4",
            "model": {"bodies": [cube(1, -0.5), cube(2, 0.5)],
                      "joints": [{"type": "ball", "a": 1, "b": 2, "at": [0, 0, 0]}]},
            "partition": {"nodes": [[1], [2]], "coupling": scheme},
            "channels": [{"name": "border", "tau": 0.005}]
        });
        struct Rigid(f64, f64, Vector3<f64>);
        impl Observer for Rigid {
            fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
                for w in s.w {
                    self.0 = self.0.max(w.abs());
                }
                for v in s.v {
                    self.1 = self.1.max((v - self.2).norm());
                }
                Ok(())
            }
        }
        let mut r = Rigid(0.0, 0.0, u);
        CoSim::new(&scenario(&v))
            .run_to_end(&mut r)
            .unwrap_or_else(|e| panic!("{e}"));
        // `reset` overwrites a ghost with a state `age` old: in a moving frame its
        // anchor lags by v·age, by construction (the thesis's scheme).
        if scheme == "reset" {
            assert!(r.0 > 1e-4, "reset: its lag should show ({} m)", r.0);
            continue;
        }
        assert!(
            r.0 <= 1e-9 && r.1 <= 1e-9,
            "{scheme}: max |w| {} m, velocity error {} m/s",
            r.0,
            r.1
        );
    }
}

/// A border joint's rows cross as one force message: one force route per border
/// joint, not one per row, and refusing an owner override of a joint's row.
#[test]
fn a_border_joint_crosses_as_one_message() {
    let s = scenario(&double_pendulum(Some(("predict", 0.005))));
    let layout = dsmcosim::partition::Layout::new(&s);
    let forces: Vec<_> = layout
        .routes
        .iter()
        .filter(|r| r.kind == dsmcosim::scenario::model::DataKind::Force)
        .collect();
    // Joint 2 (rows 3, 4, 5) joins rod 1 (node 1) to rod 2 (node 2).
    assert_eq!(forces.len(), 1, "{forces:?}");
    assert_eq!(forces[0].link, Some(3));
    let mut v = double_pendulum(Some(("predict", 0.005)));
    v["partition"]["link_owners"] = json!([{"link": 4, "node": 2}]);
    let e = dsmcosim::scenario::parse_str(&v.to_string(), "<t>")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("partition.link_owners[0].link: 4 is a row of joint J2"),
        "{e}"
    );
}

/// The shipped hanging chain's rods (ten 1 kg, 1 m rods on ball joints from a world
/// pivot, gravity), at rest and kicked sideways at its top rod by 0.5 N for 0.2 s, then
/// free for 10 s; with `split`, rods 1–5 and 6–10 on two nodes under `predict` at τ.
fn kicked_chain(split: Option<f64>) -> Value {
    let n = 10;
    let bodies: Vec<Value> = (0..n)
        .map(|i| {
            json!({"id": i + 1, "mass": 1.0, "size": 0.2,
                   "inertia": [1.0 / 12.0, 1.0 / 12.0, 0.2 * 0.2 / 6.0],
                   "position": [0, 0, -0.5 - i as f64]})
        })
        .collect();
    let mut joints = vec![json!({"type": "ball", "a": 1, "at": [0, 0, 0]})];
    for i in 1..n {
        joints.push(json!({"type": "ball", "a": i, "b": i + 1, "at": [0, 0, -(i as f64)]}));
    }
    let mut v = json!({
        "name": "kicked chain", "seed": 1, "duration": 10.0, "dt": 0.001, "integrator": "rk4",
        "model": {"gravity": [0, 0, -G], "bodies": bodies, "joints": joints},
        "forces": [{"body": 1, "amplitude": [0.5, 0, 0], "omega": 0.0,
                    "phase": std::f64::consts::FRAC_PI_2, "until": 0.2}]
    });
    if let Some(tau) = split {
        v["partition"] = json!({"nodes": [[1, 2, 3, 4, 5], [6, 7, 8, 9, 10]],
                                "coupling": "predict"});
        v["channels"] = json!([{"name": "border", "tau": tau}]);
    }
    v
}

/// The largest speed of body 6 (the border's far body) over the last second [m/s].
fn late_speed_of_body_6(v: &Value) -> f64 {
    struct Late(f64, usize);
    impl Observer for Late {
        fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
            self.1 += 1;
            if self.1 > 9000 {
                self.0 = self.0.max(s.v[5].norm());
            }
            Ok(())
        }
    }
    let mut late = Late(0.0, 0);
    CoSim::new(&scenario(v))
        .run_to_end(&mut late)
        .unwrap_or_else(|e| panic!("{e}"));
    late.0
}

/// A small kick sets the chain swinging as the monolithic run swings (a conservative
/// chain keeps swinging: the check is the amplitude, both ways, not a decay). Started
/// from an inconsistent border (a node's first samples read multipliers it had not
/// evaluated), the chain at 5 ms ended at 1.0 m/s, the border joint's 1/(4τ) loop
/// excited; started from the whole model's initial multipliers it ends as the
/// monolithic run does at 3, 4 and 5 ms. At 8 ms the loop still ran it up to 2.5 m/s
/// until the ghost carried its owner's reaction (method §2.1): now within 1.6× of the
/// monolithic swing there. 10 and 20 ms are printed.
#[test]
fn a_kicked_chain_split_at_a_border_joint_swings_as_the_monolithic_one() {
    let mono = late_speed_of_body_6(&kicked_chain(None));
    for tau in [0.003, 0.004, 0.005, 0.008, 0.01, 0.02] {
        let split = late_speed_of_body_6(&kicked_chain(Some(tau)));
        eprintln!(
            "kicked chain, predict at τ = {} ms: body 6 up to {split:.3e} m/s over the last \
             second (monolithic {mono:.3e} m/s)",
            tau * 1e3
        );
        let within = if tau <= 0.005 { 1.5 } else { 2.0 };
        if tau <= 0.008 {
            assert!(
                split < within * mono && split > mono / within,
                "τ = {tau}: {split} m/s against {mono} m/s"
            );
        }
    }
}

/// The kicked chain on three nodes (bodies 1–3, 4–7, 8–10): two border joints, and a
/// middle node that both ghosts a body it receives forces for and sends the reaction of
/// its own rows, which include its ghost's reaction from the third node. It swings as
/// the monolithic run does at 3 and 5 ms (without the ghosts' reactions it ended at
/// 6.5e-2 and 1.6 m/s; method §2.1); 8 ms is printed.
#[test]
fn a_kicked_chain_on_three_nodes_swings_as_the_monolithic_one() {
    let mono = late_speed_of_body_6(&kicked_chain(None));
    for tau in [0.003, 0.005, 0.008] {
        let mut v = kicked_chain(Some(tau));
        v["partition"]["nodes"] = json!([[1, 2, 3], [4, 5, 6, 7], [8, 9, 10]]);
        let split = late_speed_of_body_6(&v);
        eprintln!(
            "kicked chain on three nodes at τ = {} ms: body 6 up to {split:.3e} m/s over the \
             last second (monolithic {mono:.3e} m/s)",
            tau * 1e3
        );
        if tau <= 0.005 {
            assert!(
                split < 1.5 * mono && split > mono / 1.5,
                "τ = {tau}: {split} m/s against {mono} m/s"
            );
        }
    }
}

/// The chain released at rest on its joints, split at the border joint: a static
/// equilibrium must be a fixed point of the coupling at every delay it accepts. Each
/// joint carries the weight below it (within 1 %) and nothing moves (|v| ≤ 1e-3 m/s)
/// after 10 s, under every predicting scheme, at 4, 5 and 20 ms.
#[test]
fn a_chain_at_rest_split_at_a_border_joint_stays_at_rest() {
    struct End(Vec<f64>, f64);
    impl Observer for End {
        fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
            self.0 = s.f.to_vec();
            self.1 = s.v.iter().fold(0.0f64, |m, v| m.max(v.norm()));
            Ok(())
        }
    }
    // An empty share-sized tank brakes every joule the predictor would give: the
    // brake works on a chain at rest, where its explicit damper must not overshoot
    // (uncapped, it diverged at 0.13 s at 4 ms).
    let empty = json!({"scheme": "passive", "tank_share": 0.0});
    for scheme in [json!("predict"), json!("passive"), json!("tlm"), empty] {
        for tau in [0.004, 0.005, 0.02] {
            let mut v = kicked_chain(Some(tau));
            v["forces"] = json!([]);
            v["partition"]["coupling"] = scheme.clone();
            let mut end = End(Vec::new(), f64::MAX);
            CoSim::new(&scenario(&v))
                .run_to_end(&mut end)
                .unwrap_or_else(|e| panic!("{scheme}, τ = {tau}: {e}"));
            for j in 0..10 {
                // Joint j's vertical row (its third) carries the weight of the bodies
                // from j down.
                let (f, below) = (end.0[3 * j + 2].abs(), (10 - j) as f64 * G);
                assert!(
                    (f - below).abs() <= 0.01 * below,
                    "{scheme}, τ = {tau}: joint {} carries {f} N, the weight below is {below} N",
                    j + 1
                );
            }
            assert!(
                end.1 <= 1e-3,
                "{scheme}, τ = {tau}: a body moves at {} m/s",
                end.1
            );
        }
    }
}

/// The shipped mechanism `scenarios/mechanisms/<name>.json` (two nodes, one border
/// joint, 3 s) with its channel at τ under the default coupling, or on one node.
fn shipped_split(name: &str, split: Option<f64>) -> Value {
    let path = format!(
        "{}/scenarios/mechanisms/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut v: Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("shipped")).expect("JSON");
    match split {
        Some(tau) => v["channels"][0]["tau"] = json!(tau),
        None => {
            let o = v.as_object_mut().expect("object");
            o.remove("partition");
            o.remove("channels");
        }
    }
    v
}

/// Five uniform rods on four ball joints, tumbling with no gravity
/// (`free_chain5.json`: rods 1–2 and 3–5 on two nodes).
fn free_chain(split: Option<f64>) -> Value {
    shipped_split("free_chain5", split)
}

/// The targets of a split run's drifts `(|ΔP|, |ΔL|/|L|, ΔKE)` against its monolithic
/// run's `(|ΔL|/|L|, ΔKE)`: momentum within 1 kg·m/s, |L| within 3 points, kinetic
/// energy within −5/+2 points.
fn drifts_as_monolithic(law: &Value, tau: f64, (p, l, e): (f64, f64, f64), (l0, e0): (f64, f64)) {
    assert!(p <= 1.0, "{law}, τ = {tau}: |ΔP| {p}");
    assert!(
        (l - l0).abs() <= 0.03,
        "{law}, τ = {tau}: |ΔL|/|L| {l} vs {l0}"
    );
    assert!(
        e - e0 <= 0.02 && e - e0 >= -0.05,
        "{law}, τ = {tau}: ΔKE {e} vs {e0}"
    );
}

/// The largest `|ΔP|` [kg·m/s], `|ΔL|/|L₀|` and signed `ΔKE/KE₀` (the one of largest
/// size) over a run.
fn drifts(v: &Value) -> (f64, f64, f64) {
    struct Drift(
        Option<dsmcosim::multibody::invariants::Invariants>,
        f64,
        f64,
        f64,
    );
    impl Observer for Drift {
        fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
            let now = s.invariants();
            let first = self.0.get_or_insert(now);
            self.1 = self.1.max((now.momentum - first.momentum).norm());
            self.2 = self.2.max(
                (now.angular_momentum - first.angular_momentum).norm()
                    / first.angular_momentum.norm(),
            );
            let ke = now.kinetic_energy / first.kinetic_energy - 1.0;
            if ke.abs() > self.3.abs() {
                self.3 = ke;
            }
            Ok(())
        }
    }
    let mut d = Drift(None, 0.0, 0.0, 0.0);
    CoSim::new(&scenario(v))
        .run_to_end(&mut d)
        .unwrap_or_else(|e| panic!("{e}"));
    (d.1, d.2, d.3)
}

/// A free chain split at a border joint drifts as its monolithic run with the same law
/// does: momentum within 1 kg·m/s, |L| within 3 points, kinetic energy within −5/+2
/// points of the monolithic run's, at 1, 5 and 20 ms, under the default (exact) law and
/// the thesis's SMC law by name (whose monolithic run itself loses angular momentum:
/// method §2.1).
#[test]
fn a_free_chain_split_at_a_border_joint_keeps_its_invariants() {
    for law in [Value::Null, json!({"kind": "smc"})] {
        let with = |v: Value| under(&law, v);
        let (p0, l0, e0) = drifts(&with(free_chain(None)));
        for tau in [0.001, 0.005, 0.02] {
            let (p, l, e) = drifts(&with(free_chain(Some(tau))));
            eprintln!(
                "free chain ({law}) at τ = {} ms: |ΔP| {p:.3e} kg·m/s, |ΔL|/|L| {:.2} %, \
                 ΔKE {:+.2} % (monolithic {p0:.1e}, {:.2} %, {:+.2} %)",
                tau * 1e3,
                100.0 * l,
                100.0 * e,
                100.0 * l0,
                100.0 * e0
            );
            drifts_as_monolithic(&law, tau, (p, l, e), (l0, e0));
        }
    }
}

/// The double pendulum released horizontal (a chaotic swing of about 20 J), split at
/// its middle joint, under `predict` and the default `passive`: at 5 ms its energy stays
/// within 2 J of the monolithic run's (the exact law: 0.44 J, and 0.60 J at 6 ms; the SMC law by name:
/// 2.22 J against its own monolithic 1.98 J). At 20 ms it stays bounded, but its energy
/// moves 7.0 J under the default (its tank a tenth of the pendulum's energy; 43 J with
/// the 40 J tank it had) and 51 J under `predict`, which has no tank; under SMC 5.3 and
/// 55 J: printed, open (method §2.1).
#[test]
fn a_double_pendulum_split_at_its_middle_joint_keeps_its_energy_under_delay() {
    for law in [Value::Null, json!({"kind": "smc"})] {
        let with = |v: Value| under(&law, v);
        let mono = record(&with(double_pendulum(None)));
        let mono_drift = energy_drift(&mono);
        for (scheme, tau) in [
            ("passive", 0.005),
            ("passive", 0.006),
            ("passive", 0.02),
            ("predict", 0.005),
            ("predict", 0.02),
        ] {
            let mut v = with(double_pendulum(Some((scheme, tau))));
            v["channels"][0].as_object_mut().unwrap().remove("latency");
            let split = record(&v);
            let worst = farthest(&mono, &split);
            let drift = energy_drift(&split);
            eprintln!(
                "double pendulum ({law}), {scheme} at τ = {} ms: {worst:.3e} m from \
                 monolithic over 3 s, energy drift {drift:.3e} J (monolithic {mono_drift:.3e} J)",
                tau * 1e3,
            );
            // The exact law holds to 6 ms (0.79 J; 2.5 J at 8 ms, method §2.1), SMC to 5.
            if tau <= 0.005 || (tau <= 0.006 && law.is_null()) {
                assert!(
                    (drift - mono_drift).abs() <= 2.0,
                    "{law}, {scheme}, τ = {tau}: energy drift {drift} J"
                );
            }
        }
    }
}

/// The default tank on a scene with joints is a share of the mechanism's own energy
/// (each node's largest kinetic energy plus the work the scene's forces did on it), not
/// a fixed 40 J per port: split at its middle joint at 10 and 20 ms, the double
/// pendulum (about 22 J of swing) may be given by its ports at most that share. (The
/// account books each port's power at the step's start; the energy rose 4.3 J at 20 ms
/// where the ports were booked 1.4 J, the rest moved within the steps: printed, method
/// §3.1.) Both ways:
/// a fixed 40 J tank, which exceeds the whole mechanism's energy, let the ports create
/// 35 J and the energy move 43 J at 20 ms; the share keeps the energy within 7.1 J
/// (measured 7.03 J; 3.04 J at 10 ms against 5.34 J).
#[test]
fn the_default_tank_of_a_mechanism_is_a_share_of_its_own_energy() {
    let share = dsmcosim::scenario::validate::DEFAULT_TANK_SHARE;
    for tau in [0.01, 0.02] {
        let mut drifts = Vec::new();
        for coupling in [json!("passive"), json!({"scheme": "passive", "tank": 40.0})] {
            let mut v = double_pendulum(Some(("passive", tau)));
            v["partition"]["coupling"] = coupling.clone();
            v["channels"][0].as_object_mut().unwrap().remove("latency");
            let r = record(&v);
            let rise = r.energy.iter().map(|e| e - r.energy[0]).fold(0.0, f64::max);
            let (world, _, error) = super::run(&v, &[]);
            assert!(error.is_none(), "{coupling}, τ = {tau}: {error:?}");
            let (mut given, mut taken, mut tanks) = (0.0, 0.0, 0.0);
            for n in world.nodes() {
                let e = n.port_energy();
                given += e.given;
                taken += e.taken;
                tanks += match coupling.as_str() {
                    Some(_) => share * n.energy_scale(),
                    None => 40.0 * (n.bodies.len() - n.owned) as f64,
                };
            }
            let drift = energy_drift(&r);
            eprintln!(
                "double pendulum, {coupling} at τ = {} ms: ports gave {:.3} J net (tanks \
                 {tanks:.3} J), energy rose up to {rise:.3} J, drift {drift:.3} J",
                tau * 1e3,
                given - taken
            );
            assert!(given - taken <= tanks + 1e-9, "{coupling}, τ = {tau}");
            drifts.push(drift);
        }
        // The share's tanks are below the mechanism's energy, and they hold it closer.
        assert!(drifts[0] < drifts[1], "τ = {tau}: {drifts:?}");
        if tau >= 0.02 {
            assert!(drifts[0] <= 7.1 && drifts[1] >= 40.0, "{drifts:?}");
        }
    }
}

/// A 10 kg platform tumbling in space with a 2 kg rotor on a hinge spinning at
/// 20 rad/s relative to it (`platform_rotor.json`: platform and rotor on two nodes).
fn platform_and_rotor(split: Option<f64>) -> Value {
    shipped_split("platform_rotor", split)
}

/// The hinge between the platform and its rotor split over two nodes keeps the
/// invariants as the monolithic run does (momentum within 1 kg·m/s, |L| within 3
/// points, kinetic energy within −5/+2 points) and its axes together (within 1e-2 rad)
/// at 1 and 5 ms. (The hinge's alignment rows turn with the rotor's spin and their
/// multipliers change to keep the couple steady: sent without the multipliers' slope,
/// the couple the rotor felt turned at its spin, and |L| drifted 12.5 % at 5 ms.) At
/// 20 ms the axes stay together while |L| drifts 4.5 %: printed, open (method §2.1).
#[test]
fn a_hinge_across_a_partition_keeps_its_axes_and_the_invariants() {
    for law in [Value::Null, json!({"kind": "smc"})] {
        let with = |v: Value| under(&law, v);
        let (p0, l0, e0) = drifts(&with(platform_and_rotor(None)));
        for tau in [0.001, 0.005, 0.02] {
            let v = with(platform_and_rotor(Some(tau)));
            let (p, l, e) = drifts(&v);
            struct Axes(f64);
            impl Observer for Axes {
                fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
                    let axis =
                        |i: usize| nalgebra::UnitQuaternion::new_normalize(s.q[i]) * Vector3::z();
                    self.0 = self.0.max(axis(0).angle(&axis(1)));
                    Ok(())
                }
            }
            let mut axes = Axes(0.0);
            CoSim::new(&scenario(&v))
                .run_to_end(&mut axes)
                .unwrap_or_else(|e| panic!("{e}"));
            eprintln!(
                "platform | rotor ({law}) at τ = {} ms: axes up to {:.3e} rad apart, \
                 |ΔP| {p:.3e} kg·m/s, |ΔL|/|L| {:.2} %, ΔKE {:+.2} % (monolithic {p0:.1e}, \
                 {:.2e} %, {:+.2e} %)",
                tau * 1e3,
                axes.0,
                100.0 * l,
                100.0 * e,
                100.0 * l0,
                100.0 * e0
            );
            // At 20 ms the axes stay together under the exact law (3.6e-3 rad measured)
            // while |L| and the kinetic energy drift 4.5 % and +2.3 %, just outside the
            // targets: printed.
            if tau <= 0.005 || law.is_null() {
                assert!(
                    axes.0 <= 1e-2,
                    "{law}, τ = {tau}: axes {} rad apart",
                    axes.0
                );
            }
            if tau <= 0.005 {
                drifts_as_monolithic(&law, tau, (p, l, e), (l0, e0));
            }
        }
    }
}

/// RK4's order on a partitioned joint mechanism: the double pendulum split at its
/// middle joint, sampled every step with no latency, departs from the monolithic run at
/// the same step by an amount that falls as dt² over 1 s under both laws.
#[test]
fn a_double_pendulum_split_at_a_joint_keeps_second_order_in_dt() {
    for law in [Value::Null, json!({"kind": "smc"})] {
        let mut apart = Vec::new();
        for dt in [0.002, 0.001, 0.0005] {
            let with = |mut v: Value| {
                v["duration"] = json!(1.0);
                under(&law, v)
            };
            let mono = record(&with(double_pendulum_at(None, dt)));
            let split = record(&with(double_pendulum_at(Some(("predict", dt)), dt)));
            apart.push(farthest(&mono, &split));
        }
        let orders: Vec<f64> = apart.windows(2).map(|p| (p[0] / p[1]).log2()).collect();
        eprintln!(
            "split double pendulum ({law}): {apart:?} m from monolithic, orders {orders:.2?}"
        );
        // SMC: 2.00, 2.00 measured. The exact law: 2.04, 2.02, its offset rows'
        // multiplier slope carried over the step after each sample (a step rate); sent
        // as a rate without it, the force was held over RK4's stages (1.03, 1.01).
        for order in orders {
            assert!(order >= 1.8, "{law}: order {order} ({apart:?})");
        }
    }
}

/// A border joint tells no frame apart: the shipped free chain split at a joint at
/// 5 ms, with every body given an extra (1, −0.5, 0.3) m/s, moves relative to its
/// centre of mass as without it, under every predicting scheme.
#[test]
fn a_free_chain_split_at_a_joint_moves_alike_in_every_inertial_frame() {
    struct Relative(Vec<Vec<Vector3<f64>>>);
    impl Observer for Relative {
        fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
            let total: f64 = s.bodies.iter().map(|b| b.mass).sum();
            let c =
                s.p.iter()
                    .zip(s.bodies)
                    .map(|(p, b)| p * b.mass)
                    .sum::<Vector3<f64>>()
                    / total;
            self.0.push(s.p.iter().map(|p| p - c).collect());
            Ok(())
        }
    }
    let relative = |v: &Value| {
        let mut r = Relative(Vec::new());
        CoSim::new(&scenario(v))
            .run_to_end(&mut r)
            .unwrap_or_else(|e| panic!("{e}"));
        r.0
    };
    for scheme in ["predict", "passive", "tlm"] {
        let mut v = shipped_split("free_chain5", Some(0.005));
        v["partition"]["coupling"] = json!(scheme);
        let rest = relative(&v);
        for body in v["model"]["bodies"].as_array_mut().expect("bodies") {
            let u = &mut body["velocity"];
            *u = json!([
                u[0].as_f64().unwrap() + 1.0,
                u[1].as_f64().unwrap() - 0.5,
                u[2].as_f64().unwrap() + 0.3
            ]);
        }
        let moving = relative(&v);
        let worst = rest
            .iter()
            .zip(&moving)
            .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).norm()))
            .fold(0.0, f64::max);
        let moved = rest
            .iter()
            .map(|x| (x[0] - rest[0][0]).norm())
            .fold(0.0, f64::max);
        eprintln!("free chain, {scheme}: relative motion in a moving frame within {worst:.3e} m (rod 1 moved {moved:.2} m)");
        assert!(moved > 0.1, "{scheme}: the chain barely moved");
        assert!(worst <= 1e-9, "{scheme}: {worst} m apart");
    }
}

/// A closed loop across a border: the hinge four-bar (two cranks on world hinges 1.5 m
/// apart, a coupler on two more) with its cranks on node 1 and the coupler on node 2,
/// both coupler hinges border joints: at τ = 1 ms its energy stays within 5 % of the
/// swing's largest kinetic energy of the monolithic run's.
#[test]
fn a_closed_loop_split_across_a_border_keeps_its_energy() {
    let crank = |id: u32, x: f64| {
        json!({"id": id, "mass": 1.0, "size": 0.05, "inertia": [1.0 / 12.0, 1.0 / 12.0, 1e-4],
               "position": [x, 0, -0.5], "velocity": [-1.0, 0, 0], "angular_velocity": [0, 2.0, 0]})
    };
    let scene = |tau: Option<f64>| {
        let mut v = json!({
            "name": "four-bar", "seed": 1, "duration": 3.0, "dt": 0.001, "integrator": "rk4",
            "model": {
                "gravity": [0, 0, -G],
                "bodies": [crank(1, 0.0), crank(2, 1.5),
                    {"id": 3, "mass": 2.0, "size": 0.05, "inertia": [1e-4, 0.375, 0.375],
                     "position": [0.75, 0, -1], "velocity": [-2.0, 0, 0]}],
                "joints": [
                    {"type": "hinge", "a": 1, "at": [0, 0, 0], "axis": [0, 1, 0]},
                    {"type": "hinge", "a": 2, "at": [1.5, 0, 0], "axis": [0, 1, 0]},
                    {"type": "hinge", "a": 1, "b": 3, "at": [0, 0, -1], "axis": [0, 1, 0]},
                    {"type": "hinge", "a": 2, "b": 3, "at": [1.5, 0, -1], "axis": [0, 1, 0]}
                ]
            }
        });
        if let Some(tau) = tau {
            v["partition"] = json!({"nodes": [[1, 2], [3]]});
            v["channels"] = json!([{"name": "border", "tau": tau}]);
        }
        v
    };
    // Total energy per step, and the kinetic energy at the start: the swing's largest,
    // the loop starting at its lowest position.
    struct Energy(Vec<f64>, Option<f64>);
    impl Observer for Energy {
        fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
            let potential: f64 =
                s.p.iter()
                    .zip(s.bodies)
                    .map(|(p, b)| b.mass * G * p.z)
                    .sum();
            let kinetic = s.invariants().kinetic_energy;
            self.1.get_or_insert(kinetic);
            self.0.push(kinetic + potential);
            Ok(())
        }
    }
    let energy = |v: &Value| {
        let mut e = Energy(Vec::new(), None);
        CoSim::new(&scenario(v))
            .run_to_end(&mut e)
            .unwrap_or_else(|e| panic!("{e}"));
        let drift = e.0.iter().map(|x| (x - e.0[0]).abs()).fold(0.0, f64::max);
        (drift, e.1.unwrap_or(0.0))
    };
    let (mono, swing) = energy(&scene(None));
    for tau in [0.001, 0.005] {
        let (drift, _) = energy(&scene(Some(tau)));
        eprintln!("closed loop split at τ = {} ms: energy within {drift:.3e} J (monolithic {mono:.3e} J, swing {swing:.2} J)", tau * 1e3);
        // 2.7e-4 and 1.5e-2 J measured (6.2e-3 J at 5 ms with a 40 J tank): the coupler, which no row of its own node holds,
        // receives its hinges' forces with their multipliers' slopes as rates (0.037 and
        // 0.55 J when they were carried one step only).
        if tau <= 0.005 {
            assert!(
                drift <= mono + 0.05 * swing,
                "τ = {tau}: energy moved {drift} J of a {swing} J swing"
            );
        }
    }
}

/// Two free bodies on a prismatic joint tumbling about an oblique axis while `a` slides
/// along `b`'s axis (the physics tests' pair), with `a` and `b` on two nodes when
/// `split`: the slide's normals turn with `b`, so the border carries both a force whose
/// direction turns and the weld's couples.
fn prismatic_pair(split: Option<(f64, Option<f64>)>) -> Value {
    let omega = Vector3::new(0.4, -0.7, 1.1);
    let (pa, pb) = (Vector3::new(0.6, 0.1, 0.0), Vector3::new(-0.3, 0.0, 0.0));
    let (vb, slide) = (Vector3::new(0.05, 0.1, -0.2), 0.3);
    let va = vb + omega.cross(&(pa - pb)) + Vector3::x() * slide;
    let vec = |v: Vector3<f64>| json!([v.x, v.y, v.z]);
    let mut v = json!({
        "name": "prismatic pair", "seed": 1, "duration": 3.0, "dt": 0.001, "integrator": "rk4",
        "model": {
            "bodies": [
                {"id": 1, "mass": 0.7, "size": 0.1, "inertia": [0.002, 0.003, 0.004],
                 "position": vec(pa), "velocity": vec(va), "angular_velocity": vec(omega)},
                {"id": 2, "mass": 1.5, "size": 0.2, "inertia": [0.02, 0.05, 0.04],
                 "position": vec(pb), "velocity": vec(vb), "angular_velocity": vec(omega)}
            ],
            "joints": [{"type": "prismatic", "a": 1, "b": 2, "at": [0.5, 0.1, 0.0],
                        "axis": [1, 0, 0]}]
        }
    });
    if let Some((tau, latency)) = split {
        v["partition"] = json!({"nodes": [[1], [2]]});
        v["channels"] = json!([{"name": "border", "tau": tau}]);
        if let Some(latency) = latency {
            v["channels"][0]["latency"] = json!(latency);
        }
    }
    v
}

/// A prismatic joint across a border: at τ = dt with no latency the pair moves as the
/// monolithic run does (within 1e-4 m over 3 s), and at 1, 5 and 20 ms (latency = τ,
/// the default coupling) it keeps the invariants as the other border joints do
/// (|ΔP| ≤ 1 kg·m/s, |ΔL|/|L| within 3 points, kinetic energy within −5/+2 points of
/// the monolithic run) with its rows closed (within 1e-2 m and 1e-2 in cosine).
#[test]
fn a_prismatic_joint_across_a_border_keeps_the_pair_sliding_as_one() {
    struct Path(Vec<[Vector3<f64>; 2]>, f64);
    impl Observer for Path {
        fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
            self.0.push([s.p[0], s.p[1]]);
            self.1 = self.1.max(s.max_w);
            Ok(())
        }
    }
    let path = |v: &Value| {
        let mut p = Path(Vec::new(), 0.0);
        CoSim::new(&scenario(v))
            .run_to_end(&mut p)
            .unwrap_or_else(|e| panic!("{e}"));
        p
    };
    let mono = path(&prismatic_pair(None));
    let near = path(&prismatic_pair(Some((0.001, Some(0.0)))));
    let apart = mono
        .0
        .iter()
        .zip(&near.0)
        .map(|(a, b)| (a[0] - b[0]).norm().max((a[1] - b[1]).norm()))
        .fold(0.0, f64::max);
    eprintln!("prismatic pair split at τ = dt, no latency: {apart:.3e} m from monolithic");
    assert!(apart < 1e-4, "{apart} m from the monolithic run");
    let (p0, l0, e0) = drifts(&prismatic_pair(None));
    for tau in [0.001, 0.005, 0.02] {
        let v = prismatic_pair(Some((tau, None)));
        let (p, l, e) = drifts(&v);
        let open = path(&v).1;
        eprintln!(
            "prismatic pair at τ = {} ms: rows within {open:.3e}, |ΔP| {p:.3e} kg·m/s, \
             |ΔL|/|L| {:.2} %, ΔKE {:+.2} % (monolithic {p0:.1e}, {:.2e} %, {:+.2e} %)",
            tau * 1e3,
            100.0 * l,
            100.0 * e,
            100.0 * l0,
            100.0 * e0
        );
        assert!(open <= 1e-2, "τ = {tau}: rows open by {open}");
        assert!(p <= 1.0, "τ = {tau}: |ΔP| {p}");
        assert!((l - l0).abs() <= 0.03, "τ = {tau}: |ΔL|/|L| {l} vs {l0}");
        assert!(
            e - e0 <= 0.02 && e - e0 >= -0.05,
            "τ = {tau}: ΔKE {e} vs {e0}"
        );
    }
}

/// A load-bearing slide across a border: a 2 kg rod spinning at 3 rad/s on a world
/// hinge about z (node 1) with a 0.5 kg bead sliding out along it on a prismatic joint
/// (node 2). The slide's rows carry the bead's centripetal force and the rod's couple
/// on it while the rod slows (the physics tests' bead, whose equations it follows
/// monolithic to 2.6e-10 m). Split, the angular momentum about the hinge axis is
/// kept within 1 % and the bead stays within 1e-2 m of the monolithic path at 1 and
/// 5 ms (latency = τ); 20 ms is printed.
#[test]
fn a_bead_sliding_on_a_rod_across_a_border_follows_the_monolithic_run() {
    let (rod_i, bead_i) = (2.0 / 12.0, 0.5 * 0.05 * 0.05 / 6.0);
    let bead = |split: Option<f64>| {
        let mut v = json!({
            "name": "bead", "seed": 1, "duration": 2.0, "dt": 0.001, "integrator": "rk4",
            "model": {
                "bodies": [
                    {"id": 1, "mass": 2.0, "size": 0.05, "inertia": [1e-3, rod_i, rod_i],
                     "position": [0, 0, 0], "angular_velocity": [0, 0, 3.0]},
                    {"id": 2, "mass": 0.5, "size": 0.05, "position": [0.2, 0, 0],
                     "velocity": [0.1, 0.6, 0], "angular_velocity": [0, 0, 3.0]}
                ],
                "joints": [
                    {"type": "hinge", "a": 1, "at": [0, 0, 0], "axis": [0, 0, 1]},
                    {"type": "prismatic", "a": 2, "b": 1, "at": [0.2, 0, 0], "axis": [1, 0, 0]}
                ]
            }
        });
        if let Some(tau) = split {
            v["partition"] = json!({"nodes": [[1], [2]]});
            v["channels"] = json!([{"name": "border", "tau": tau}]);
        }
        v
    };
    struct Spin(Vec<Vector3<f64>>, Vec<f64>, [f64; 2]);
    impl Observer for Spin {
        fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
            self.0.push(s.p[1]);
            let lz: f64 = (0..2)
                .map(|i| s.bodies[i].mass * s.p[i].cross(&s.v[i]).z + self.2[i] * s.omega[i].z)
                .sum();
            self.1.push(lz);
            Ok(())
        }
    }
    let run = |v: &Value| {
        let mut s = Spin(Vec::new(), Vec::new(), [rod_i, bead_i]);
        CoSim::new(&scenario(v))
            .run_to_end(&mut s)
            .unwrap_or_else(|e| panic!("{e}"));
        s
    };
    let mono = run(&bead(None));
    for tau in [0.001, 0.005, 0.02] {
        let split = run(&bead(Some(tau)));
        let apart = mono
            .0
            .iter()
            .zip(&split.0)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        let l0 = split.1[0];
        let dl = split
            .1
            .iter()
            .map(|l| ((l - l0) / l0).abs())
            .fold(0.0, f64::max);
        let out = split.0.last().map_or(0.0, |p| p.norm());
        eprintln!(
            "bead on a rod split at τ = {} ms: out to {out:.3} m, {apart:.3e} m from \
             monolithic, L_z within {:.3} %",
            tau * 1e3,
            100.0 * dl
        );
        if tau <= 0.005 {
            assert!(
                apart <= 1e-2,
                "τ = {tau}: {apart} m from the monolithic run"
            );
            assert!(dl <= 0.01, "τ = {tau}: L_z moved by {dl}");
        }
    }
}
