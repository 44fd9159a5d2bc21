//! The invariants every run writes (trace.csv's `Px,Py,Pz,Lx,Ly,Lz,KE`, summary.json's
//! `invariants`) and the rotation columns of `output.trace_rotation`, checked against
//! mechanics: a free net keeps its momenta (symplectic Euler, isotropic inertia: exactly
//! up to round-off, see `dsmcosim::trace::invariants`), and every column equals what
//! this file computes from the trace's own state columns and the scenario's masses.
//! No expected number is copied from a run.

use std::path::{Path, PathBuf};

use dsmcosim::run::run;
use dsmcosim::scenario::{parse_str, Scenario};
use nalgebra::Vector3;
use serde_json::{json, Value};

fn scratch(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("test-scratch")
        .join(format!("invariants_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn scenario(v: &Value) -> Scenario {
    parse_str(&v.to_string(), "<test>").unwrap_or_else(|e| panic!("scenario: {e}"))
}

/// A run's trace.csv: header and rows of numbers, looked up by column name.
struct Trace {
    head: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Trace {
    fn read(dir: &Path) -> Trace {
        let text = std::fs::read_to_string(dir.join("trace.csv")).expect("trace.csv");
        let mut lines = text.lines();
        let head = lines
            .next()
            .expect("header")
            .split(',')
            .map(str::to_string)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(|x| x.parse().expect("number")).collect())
            .collect();
        Trace { head, rows }
    }

    fn col(&self, name: &str) -> usize {
        self.head
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.head))
    }

    fn has(&self, name: &str) -> bool {
        self.head.iter().any(|h| h == name)
    }

    /// The 3-vector of columns `<prefix>x, y, z` + `suffix` in row `r`.
    fn v3(&self, r: usize, prefix: &str, suffix: &str) -> Vector3<f64> {
        let c = |a: &str| self.rows[r][self.col(&format!("{prefix}{a}{suffix}"))];
        Vector3::new(c("x"), c("y"), c("z"))
    }
}

fn summary(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// A triangle of three rigid cubes linked between off-centre anchors (so the rigid-body
/// path runs), moving and spinning, with no force: only the links act, and they pull
/// along the line between their anchors.
fn spinning_triangle(integrator: &str) -> Value {
    json!({
        "name": "triangle", "seed": 1, "duration": 1.0, "dt": 0.001,
        "integrator": integrator,
        "model": {
            "bodies": [
                {"id": 1, "mass": 1.0, "size": 0.2, "position": [0, 0, 0],
                 "velocity": [0.3, 0, 0.1], "angular_velocity": [0, 0, 2.0]},
                {"id": 2, "mass": 2.0, "size": 0.3, "position": [2, 0, 0],
                 "velocity": [-0.2, 0.4, 0], "angular_velocity": [1.0, 0, 0]},
                {"id": 3, "mass": 1.5, "size": 0.25, "position": [1, 1.7, 0.3],
                 "velocity": [0, -0.1, 0.5], "angular_velocity": [0, 0.5, 0.5]}
            ],
            "links": [
                {"a": 1, "b": 2, "anchor_a": [0.1, 0, 0], "anchor_b": [-0.15, 0, 0.05]},
                {"a": 2, "b": 3, "anchor_a": [0, 0.15, 0], "anchor_b": [0.1, -0.1, 0]},
                {"a": 3, "b": 1, "anchor_a": [-0.1, 0, 0.1], "anchor_b": [0, 0.1, 0]}
            ]
        },
        "output": {"decimation": 10, "trace_rotation": true}
    })
}

/// `(P, L about the centre of mass, KE)` of point masses from positions and
/// velocities, the textbook sums.
fn point_sums(
    m: &[f64],
    p: &[Vector3<f64>],
    v: &[Vector3<f64>],
) -> (Vector3<f64>, Vector3<f64>, f64) {
    let total: f64 = m.iter().sum();
    let c = m.iter().zip(p).map(|(m, p)| p * *m).sum::<Vector3<f64>>() / total;
    let mut out = (Vector3::zeros(), Vector3::zeros(), 0.0);
    for ((m, p), v) in m.iter().zip(p).zip(v) {
        out.0 += v * *m;
        out.1 += (p - c).cross(&(v * *m));
        out.2 += 0.5 * m * v.norm_squared();
    }
    out
}

/// The cube's inertia `m s²/6` on every axis (the default): isotropic, so the spin
/// angular momentum is `I ω` and the rotational energy `½ I |ω|²` in any orientation.
fn cube_inertia(mass: f64, size: f64) -> f64 {
    mass * size * size / 6.0
}

#[test]
fn a_free_spinning_net_keeps_its_momenta_to_round_off() {
    let v = spinning_triangle("symplectic_euler");
    let s = scenario(&v);
    assert_eq!(
        s.body_model.name(),
        "rigid",
        "off-centre anchors need rotation"
    );
    let dir = scratch("free_triangle");
    run(&s, &dir).expect("runs");
    let t = Trace::read(&dir);
    let ids = [1, 2, 3];
    let bodies = &v["model"]["bodies"];
    let m: Vec<f64> = (0..3)
        .map(|i| bodies[i]["mass"].as_f64().unwrap())
        .collect();
    let inertia: Vec<f64> = (0..3)
        .map(|i| cube_inertia(m[i], bodies[i]["size"].as_f64().unwrap()))
        .collect();
    let p = |r: usize| ids.map(|i| t.v3(r, "p", &format!("_B{i}")));
    let vel = |r: usize| ids.map(|i| t.v3(r, "v", &format!("_B{i}")));
    let w = |r: usize| ids.map(|i| t.v3(r, "w", &format!("_B{i}")));
    // At t = 0 the columns are the textbook sums of the initial state.
    let (p0, l0_orbit, ke0) = point_sums(&m, &p(0), &vel(0));
    let spin0: Vector3<f64> = (0..3).map(|i| w(0)[i] * inertia[i]).sum();
    let rot0: f64 = (0..3)
        .map(|i| 0.5 * inertia[i] * w(0)[i].norm_squared())
        .sum();
    let (big_p, big_l) = (t.v3(0, "P", ""), t.v3(0, "L", ""));
    assert!(
        (big_p - p0).norm() <= 1e-15 * p0.norm(),
        "P(0) = {big_p}, Σ m v = {p0}"
    );
    let l0 = l0_orbit + spin0;
    assert!(
        (big_l - l0).norm() <= 1e-14 * l0.norm(),
        "L(0) = {big_l}, want {l0}"
    );
    let ke = t.rows[0][t.col("KE")];
    assert!((ke - (ke0 + rot0)).abs() <= 1e-14 * ke, "KE(0) = {ke}");
    // Every row: the same P and L to round-off, while the bodies trade momentum and
    // the orbital part of L trades with the spins (so neither column is constant
    // because nothing happens).
    let (mut traded_p, mut traded_l): (f64, f64) = (0.0, 0.0);
    for r in 0..t.rows.len() {
        let time = t.rows[r][0];
        let (big_p, big_l) = (t.v3(r, "P", ""), t.v3(r, "L", ""));
        assert!(
            (big_p - p0).norm() <= 1e-12 * p0.norm(),
            "t = {time}: P = {big_p} drifted from {p0}"
        );
        assert!(
            (big_l - l0).norm() <= 1e-12 * l0.norm(),
            "t = {time}: L = {big_l} drifted from {l0}"
        );
        traded_p = traded_p.max((vel(r)[0] * m[0] - vel(0)[0] * m[0]).norm() / p0.norm());
        let (_, orbit, _) = point_sums(&m, &p(r), &vel(r));
        traded_l = traded_l.max((orbit - l0_orbit).norm() / l0.norm());
    }
    assert!(t.rows.len() == 101, "rows at 0, 0.01, …, 1 s");
    assert!(
        traded_p > 1e-2,
        "the links must move the bodies ({traded_p})"
    );
    assert!(traded_l > 1e-3, "spin and orbit must trade ({traded_l})");
    // summary.json reports the same: no drift beyond round-off, no undriven stretch
    // other than the whole run, whose drift is the run's.
    let s = summary(&dir);
    let inv = &s["invariants"];
    assert!(inv["momentum_drift_relative"].as_f64().unwrap() <= 1e-12);
    assert!(inv["angular_momentum_drift_relative"].as_f64().unwrap() <= 1e-12);
    let undriven = inv["undriven"]
        .as_array()
        .expect("a force-free run is undriven");
    assert_eq!(undriven.len(), 1);
    assert_eq!(
        (undriven[0]["from"].as_f64(), undriven[0]["to"].as_f64()),
        (Some(0.0), Some(1.0))
    );
    assert_eq!(undriven[0]["momentum_drift"], inv["momentum_drift"]);
}

/// The same net under explicit Euler does not keep `L` (it adds `h² Σ v × F` per
/// step): the columns show the drift rather than hiding it.
#[test]
fn explicit_euler_shows_its_angular_momentum_drift() {
    let dir = scratch("euler_triangle");
    run(&scenario(&spinning_triangle("euler")), &dir).expect("runs");
    let t = Trace::read(&dir);
    let (l0, l1) = (t.v3(0, "L", ""), t.v3(t.rows.len() - 1, "L", ""));
    assert!(
        (l1 - l0).norm() > 1e-9 * l0.norm(),
        "explicit Euler drifts L: {l0} → {l1}"
    );
    let inv = &summary(&dir)["invariants"];
    let drift = &inv["angular_momentum_drift"];
    for (k, x) in (l1 - l0).iter().enumerate() {
        assert_eq!(drift[k].as_f64(), Some(*x), "drift is end − start");
    }
}

/// A driven point-mass grid: every invariant column equals the sums this test makes
/// from the row's own position and velocity columns and the scenario's masses.
#[test]
fn point_mass_invariant_columns_are_the_sums_of_the_traced_state() {
    let v = json!({
        "name": "grid", "seed": 7, "duration": 1.0, "dt": 0.001,
        "model": {"grid": {"rows": 3, "cols": 3, "spacing": 1.8, "mass": 1.5, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0, "phase": 0.7}],
        "output": {"decimation": 25}
    });
    let s = scenario(&v);
    assert_eq!(s.body_model.name(), "point_mass");
    let dir = scratch("grid_sums");
    run(&s, &dir).expect("runs");
    let t = Trace::read(&dir);
    assert!(!t.has("qw_B1"), "no rotation columns unless asked");
    let m = vec![1.5; 9];
    let mut moving = 0.0f64;
    for r in 0..t.rows.len() {
        let p: Vec<_> = (1..=9).map(|i| t.v3(r, "p", &format!("_B{i}"))).collect();
        let vel: Vec<_> = (1..=9).map(|i| t.v3(r, "v", &format!("_B{i}"))).collect();
        let (big_p, big_l, ke) = point_sums(&m, &p, &vel);
        let close = |a: Vector3<f64>, b: Vector3<f64>, scale: f64| (a - b).norm() <= 1e-13 * scale;
        let time = t.rows[r][0];
        let scale = vel.iter().map(|v| 1.5 * v.norm()).sum::<f64>();
        assert!(close(t.v3(r, "P", ""), big_p, scale), "t = {time}: P");
        let lever = scale * p.iter().map(|p| p.norm()).fold(0.0, f64::max);
        assert!(close(t.v3(r, "L", ""), big_l, lever), "t = {time}: L");
        let col = t.rows[r][t.col("KE")];
        assert!(
            (col - ke).abs() <= 1e-14 * ke,
            "t = {time}: KE {col} vs ½Σmv² {ke}"
        );
        moving = moving.max(ke);
    }
    assert!(
        moving > 0.1,
        "the force must move the grid (KE up to {moving} J)"
    );
    // The summary's end is the last row; a force never switched off leaves no stretch.
    let inv = &summary(&dir)["invariants"];
    let last = t.rows.len() - 1;
    assert_eq!(inv["end"]["t"].as_f64(), Some(t.rows[last][0]));
    assert_eq!(
        inv["end"]["kinetic_energy"].as_f64(),
        Some(t.rows[last][t.col("KE")])
    );
    assert_eq!(inv["start"]["kinetic_energy"].as_f64(), Some(0.0));
    assert!(inv.get("undriven").is_none());
}

/// `trace_rotation` adds qw..wz per traced body after the invariants: unit quaternions
/// that start at the scenario's orientation, ω starting at its angular velocity; on a
/// point-mass scene identity and zero.
#[test]
fn rotation_columns_hold_unit_quaternions_and_appear_only_when_asked() {
    let mut v = spinning_triangle("rk4");
    v["model"]["bodies"][1]["orientation"] = json!([0.5, 0.5, 0.5, 0.5]);
    v["output"]["trace_bodies"] = json!([3, 2]);
    let dir = scratch("rotation");
    run(&scenario(&v), &dir).expect("runs");
    let t = Trace::read(&dir);
    let tail: Vec<&str> = t.head[t.col("KE") + 1..]
        .iter()
        .map(String::as_str)
        .collect();
    let want: Vec<String> = [3, 2]
        .iter()
        .flat_map(|id| ["qw", "qx", "qy", "qz", "wx", "wy", "wz"].map(|a| format!("{a}_B{id}")))
        .collect();
    assert_eq!(tail, want, "after KE, per traced body in trace order");
    let q = |r: usize, id: u32| {
        ["qw", "qx", "qy", "qz"].map(|a| t.rows[r][t.col(&format!("{a}_B{id}"))])
    };
    assert_eq!(q(0, 2), [0.5, 0.5, 0.5, 0.5]);
    assert_eq!(q(0, 3), [1.0, 0.0, 0.0, 0.0]);
    assert_eq!(t.v3(0, "w", "_B2"), Vector3::new(1.0, 0.0, 0.0));
    let mut turned = 0.0f64;
    for r in 0..t.rows.len() {
        for id in [2, 3] {
            let n = q(r, id).iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(
                (n - 1.0).abs() <= 4.0 * f64::EPSILON,
                "t = {}: |q_B{id}| = {n}",
                t.rows[r][0]
            );
        }
        turned = turned.max((q(r, 3)[0] - 1.0).abs());
    }
    assert!(turned > 1e-3, "body 3 spins, so its orientation changes");
    // Without the option the same run has no rotation column; a point-mass scene with
    // it has identity and zero.
    v["output"]["trace_rotation"] = json!(false);
    let plain = scratch("rotation_off");
    run(&scenario(&v), &plain).expect("runs");
    let t = Trace::read(&plain);
    assert_eq!(t.head.last().map(String::as_str), Some("KE"));
    let points = json!({
        "name": "pair", "seed": 1, "duration": 0.1, "dt": 0.001,
        "model": {"grid": {"rows": 1, "cols": 2, "spacing": 1.0, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 1, 0], "omega": 0.0, "phase": 1.0}],
        "output": {"trace_rotation": true}
    });
    let dir = scratch("rotation_points");
    run(&scenario(&points), &dir).expect("runs");
    let t = Trace::read(&dir);
    for r in 0..t.rows.len() {
        for id in [1, 2] {
            let c = |a: &str| t.rows[r][t.col(&format!("{a}_B{id}"))];
            assert_eq!(
                ["qw", "qx", "qy", "qz", "wx", "wy", "wz"].map(c),
                [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
            );
        }
    }
}

/// A partitioned rigid run takes each body's position, velocity, orientation and spin
/// from its owner node: at t = 0 its invariants are the monolithic run's to the bit
/// (the same initial state, summed in the same order), and the nodes stepped in
/// parallel gather the same values as stepped one after another.
#[test]
fn a_partitioned_run_gathers_every_rotation_from_its_owner_serially_and_in_parallel() {
    use dsmcosim::cosim::CoSim;
    use dsmcosim::trace::Recorder;
    let mut v = spinning_triangle("rk4");
    v["duration"] = json!(0.2);
    // Body 3 first in its node, body 1 second: local indices differ from global ones.
    v["partition"] = json!({"nodes": [[3, 1], [2]]});
    v["channels"] = json!([{"name": "all", "tau": 0.002}]);
    let s = scenario(&v);
    let summary = |s: &Scenario, threads: usize, min_links: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let mut world = CoSim::new(s);
            world.set_parallel_min_links(min_links);
            assert_eq!(
                world.steps_in_parallel(),
                threads > 1 && s.partition.is_some()
            );
            let mut rec = Recorder::for_scenario(None, s).expect("recorder");
            world.run_to_end(&mut rec).expect("runs");
            rec.invariants_summary().expect("steps recorded")
        })
    };
    let serial = summary(&s, 1, 0);
    let parallel = summary(&s, 2, 0);
    assert_eq!(serial, parallel, "1 and 2 threads");
    let mut mono = v.clone();
    mono.as_object_mut().unwrap().remove("partition");
    mono.as_object_mut().unwrap().remove("channels");
    let mono = summary(&scenario(&mono), 1, usize::MAX);
    assert_eq!(serial["start"], mono["start"], "t = 0: the same state");
    assert_ne!(
        serial["start"]["angular_momentum"],
        json!([0.0, 0.0, 0.0]),
        "the spins count"
    );
}
