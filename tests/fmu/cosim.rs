//! FMUs as nodes of a co-simulation: a mass–spring–damper FMU and a PD controller FMU
//! on two nodes, their connections carried by channels. References are built here:
//! the closed form of the undelayed closed loop, a sampled-data integration of the
//! delayed loop written in this file, and the stability boundary of the delayed PD
//! loop from its characteristic equation.

use std::path::Path;

use dsmcosim::run::{run_with, RunOptions};
use serde_json::{json, Value};

use crate::fmus::scratch;

use crate::fmu_build::build_test_fmu;

/// The plant's parameters (msd.xml's defaults are overridden with these).
const M: f64 = 1.0;
const K: f64 = 4.0;
const C: f64 = 0.4;
const X0: f64 = 1.0;
/// The controller's gains.
const KP: f64 = 10.0;
const KD: f64 = 2.0;

/// Builds msd.fmu and pd.fmu into `dir`.
fn fmus(dir: &Path) {
    for id in ["msd", "pd"] {
        build_test_fmu(id, dir).unwrap_or_else(|e| panic!("{id}.fmu: {e}"));
    }
}

/// The closed loop: plant on node 1, controller on node 2; `sense` carries x and v to
/// the controller, `act` carries u back, each with its period and latency [s].
pub(crate) fn closed_loop(dt: f64, duration: f64, sense: (f64, f64), act: (f64, f64)) -> Value {
    json!({
        "name": "pd_loop",
        "seed": 1,
        "duration": duration,
        "dt": dt,
        "measurement": {"period": duration},
        "output": {"decimation": 1},
        "fmus": [
            {"name": "plant", "path": "msd.fmu", "node": 1,
             "start": {"m": M, "k": K, "c": C, "x0": X0, "v0": 0.0}},
            {"name": "ctrl", "path": "pd.fmu", "node": 2,
             "start": {"kp": KP, "kd": KD, "r": 0.0}}
        ],
        "channels": [
            {"name": "sense", "tau": sense.0, "latency": sense.1},
            {"name": "act", "tau": act.0, "latency": act.1}
        ],
        "connections": [
            {"from": "plant.x", "to": "ctrl.x", "channel": "sense"},
            {"from": "plant.v", "to": "ctrl.v", "channel": "sense"},
            {"from": "ctrl.u", "to": "plant.F", "channel": "act"}
        ]
    })
}

/// Writes `v` as `dir/scenario.json`, runs it into `dir/out`, and returns (t, column)
/// of trace.csv for each named column, and the run's digest.
pub(crate) fn run(dir: &Path, v: &Value, columns: &[&str]) -> (Vec<f64>, Vec<Vec<f64>>, String) {
    let path = dir.join("scenario.json");
    std::fs::write(&path, serde_json::to_string_pretty(v).unwrap()).unwrap();
    let s = dsmcosim::scenario::load(&path).unwrap_or_else(|e| panic!("scenario: {e}"));
    let out = dir.join("out");
    let outcome = run_with(&s, &out, RunOptions::default()).unwrap_or_else(|e| panic!("run: {e}"));
    let mut r = csv::Reader::from_path(out.join("trace.csv")).expect("trace.csv");
    let head = r.headers().unwrap().clone();
    let at = |name: &str| {
        head.iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {head:?}"))
    };
    let idx: Vec<usize> = columns.iter().map(|c| at(c)).collect();
    let (mut t, mut cols) = (Vec::new(), vec![Vec::new(); columns.len()]);
    for rec in r.records() {
        let rec = rec.unwrap();
        t.push(rec[0].parse::<f64>().unwrap());
        for (c, &i) in cols.iter_mut().zip(&idx) {
            c.push(rec[i].parse::<f64>().unwrap());
        }
    }
    (t, cols, outcome.digest)
}

/// The undelayed closed loop `m ẍ + (c + kd) ẋ + (k + kp) x = 0` from (x0, 0).
fn closed_form(t: f64) -> f64 {
    let (c, k) = (C + KD, K + KP);
    let w = (k / M).sqrt();
    let zeta = c / (2.0 * (k * M).sqrt());
    let wd = w * (1.0 - zeta * zeta).sqrt();
    (-zeta * w * t).exp() * (X0 * (wd * t).cos() + (zeta * w * X0 / wd) * (wd * t).sin())
}

#[test]
fn the_undelayed_loop_converges_to_the_closed_form_at_first_order() {
    // τ = dt, latency 0: the co-simulation's own one-step lag (a Jacobi scheme: each
    // FMU steps on the other's output of the previous communication point) is all that
    // separates it from the continuous loop, so the error halves with dt.
    let dir = scratch("fmu-cosim", "undelayed");
    fmus(&dir);
    let mut errors = Vec::new();
    for dt in [2e-3, 1e-3, 5e-4] {
        let v = closed_loop(dt, 3.0, (dt, 0.0), (dt, 0.0));
        let (t, cols, _) = run(&dir, &v, &["plant.x"]);
        let err = t
            .iter()
            .zip(&cols[0])
            .map(|(&t, &x)| (x - closed_form(t)).abs())
            .fold(0.0, f64::max);
        errors.push(err);
    }
    let orders: Vec<f64> = errors.windows(2).map(|e| (e[0] / e[1]).log2()).collect();
    println!("undelayed loop: max errors {errors:?}, orders {orders:?}");
    assert!(errors[2] < 2e-2, "error at dt = 0.5 ms: {}", errors[2]);
    for o in orders {
        assert!((0.85..1.2).contains(&o), "order {o} (errors {errors:?})");
    }
}

/// The delayed loop integrated here as sampled data: the plant by the same RK4 as
/// msd.c (substeps of at most 0.1 ms, the input held over each step), x and v sampled
/// every τs and delivered Ls later, the controller's u = −kp x − kd v of the inputs it
/// holds at a step published one step later, sampled every τa and delivered La later.
/// All times in nanoseconds.
fn sampled_data(dt: u64, end: u64, sense: (u64, u64), act: (u64, u64)) -> Vec<(f64, f64)> {
    let (mut x, mut v) = (X0, 0.0);
    let (mut x_in, mut v_in) = (0.0, 0.0);
    let mut u = -KP * x_in - KD * v_in;
    let mut force = 0.0;
    let (mut pub_x, mut pub_v, mut pub_u) = (x, v, u);
    let mut to_ctrl: Vec<(u64, f64, f64)> = Vec::new();
    let mut to_plant: Vec<(u64, f64)> = Vec::new();
    let mut out = Vec::new();
    let mut t = 0;
    loop {
        if t % sense.0 == 0 && t + sense.1 <= end {
            to_ctrl.push((t + sense.1, pub_x, pub_v));
        }
        if t % act.0 == 0 && t + act.1 <= end {
            to_plant.push((t + act.1, pub_u));
        }
        for &(at, xs, vs) in to_ctrl.iter().filter(|d| d.0 <= t) {
            let _ = at;
            (x_in, v_in) = (xs, vs);
        }
        to_ctrl.retain(|d| d.0 > t);
        for &(_, us) in to_plant.iter().filter(|d| d.0 <= t) {
            force = us;
        }
        to_plant.retain(|d| d.0 > t);
        out.push((t as f64 * 1e-9, pub_x));
        if t >= end {
            return out;
        }
        let h = dt as f64 * 1e-9;
        let n = (h / 1e-4).ceil() as usize;
        let s = h / n as f64;
        let acc = |x: f64, v: f64| (-K * x - C * v + force) / M;
        for _ in 0..n {
            let (k1x, k1v) = (v, acc(x, v));
            let (k2x, k2v) = (v + 0.5 * s * k1v, acc(x + 0.5 * s * k1x, v + 0.5 * s * k1v));
            let (k3x, k3v) = (v + 0.5 * s * k2v, acc(x + 0.5 * s * k2x, v + 0.5 * s * k2v));
            let (k4x, k4v) = (v + s * k3v, acc(x + s * k3x, v + s * k3v));
            x += s / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += s / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        }
        u = -KP * x_in - KD * v_in;
        (pub_x, pub_v, pub_u) = (x, v, u);
        t += dt;
    }
}

#[test]
fn the_delayed_loop_matches_a_sampled_data_integration_of_the_delay_equation() {
    let dir = scratch("fmu-cosim", "delayed");
    fmus(&dir);
    let ms = 1_000_000u64;
    for (sense, act) in [((5, 5), (5, 5)), ((2, 7), (10, 3)), ((1, 0), (20, 20))] {
        let (sense, act) = ((sense.0 * ms, sense.1 * ms), (act.0 * ms, act.1 * ms));
        let secs = |p: (u64, u64)| (p.0 as f64 * 1e-9, p.1 as f64 * 1e-9);
        let v = closed_loop(1e-3, 4.0, secs(sense), secs(act));
        let (t, cols, _) = run(&dir, &v, &["plant.x"]);
        let reference = sampled_data(ms, 4000 * ms, sense, act);
        assert_eq!(t.len(), reference.len());
        let mut worst: f64 = 0.0;
        for ((&t, &x), &(tr, xr)) in t.iter().zip(&cols[0]).zip(&reference) {
            assert!((t - tr).abs() < 1e-12);
            worst = worst.max((x - xr).abs());
        }
        println!("sense {sense:?} act {act:?} ns: worst |x − reference| {worst:e} m");
        assert!(worst < 1e-9, "sense {sense:?} act {act:?}: {worst:e} m");
    }
}

/// The smallest delay at which `m s² + c s + k + (kp + kd s) e^{−s d} = 0` has a root
/// on the imaginary axis: where the delayed PD loop loses stability.
fn critical_delay() -> f64 {
    // |k − m ω² + j c ω| = |kp + j kd ω| as a quadratic in y = ω².
    let (a, b, c) = (M * M, C * C - 2.0 * K * M - KD * KD, K * K - KP * KP);
    let y = (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
    let w = y.sqrt();
    // e^{−jωd} = −(k − mω² + jcω) / (kp + j kd ω).
    let (nr, ni) = (-(K - M * w * w), -C * w);
    let (dr, di) = (KP, KD * w);
    let (zr, zi) = ((nr * dr + ni * di), (ni * dr - nr * di));
    let phase = zi.atan2(zr);
    let wd = (-phase).rem_euclid(2.0 * std::f64::consts::PI);
    wd / w
}

#[test]
fn the_delayed_loop_loses_stability_where_the_characteristic_equation_says() {
    let dir = scratch("fmu-cosim", "stability");
    fmus(&dir);
    let d = critical_delay();
    println!("critical loop delay {d:.4} s");
    // The loop's delay: both latencies, the controller's one step and, on average,
    // half a step of each hold (τ = dt = 1 ms): latencies + 2 ms.
    let envelope = |factor: f64| {
        let latency = ((factor * d - 2e-3) / 2.0 * 1e3).round() / 1e3;
        let v = closed_loop(1e-3, 30.0, (1e-3, latency), (1e-3, latency));
        let (t, cols, _) = run(&dir, &v, &["plant.x"]);
        let peak = |from: f64, to: f64| {
            t.iter()
                .zip(&cols[0])
                .filter(|(&t, _)| t >= from && t < to)
                .map(|(_, x)| x.abs())
                .fold(0.0, f64::max)
        };
        (peak(2.0, 7.0), peak(25.0, 30.0))
    };
    let (early, late) = envelope(0.8);
    println!("0.8 × critical: peak |x| {early:e} (2–7 s), {late:e} (25–30 s)");
    assert!(
        late < 0.5 * early,
        "below the boundary the loop must settle"
    );
    let (early, late) = envelope(1.2);
    println!("1.2 × critical: peak |x| {early:e} (2–7 s), {late:e} (25–30 s)");
    assert!(late > 2.0 * early, "above the boundary the loop must grow");
}

#[test]
fn the_same_fmus_and_scenario_give_the_same_digest() {
    let dir = scratch("fmu-cosim", "digest");
    fmus(&dir);
    let v = closed_loop(1e-3, 2.0, (5e-3, 5e-3), (5e-3, 5e-3));
    let (_, a, first) = run(&dir, &v, &["plant.x", "ctrl.u"]);
    let (_, b, second) = run(&dir, &v, &["plant.x", "ctrl.u"]);
    assert_eq!(first, second);
    assert_eq!(a, b);
    // The digest covers the FMU outputs: another latency, another digest.
    let v = closed_loop(1e-3, 2.0, (5e-3, 6e-3), (5e-3, 5e-3));
    let (_, _, other) = run(&dir, &v, &["plant.x"]);
    assert_ne!(first, other);
}

/// The delay differential equation `m ẍ = −k x − c ẋ − kp x(t − d) − kd ẋ(t − d)`,
/// from (x0, 0) with the controller's force zero before `d` (its inputs start at 0),
/// integrated by RK4 at step `h` (`d` a whole number of steps, the history read at
/// step points and, at half steps, linearly between them); x at every multiple of
/// `every` steps.
fn delay_equation(d: f64, h: f64, end: f64, every: usize) -> Vec<f64> {
    let lag = (d / h).round() as usize;
    let n = (end / h).round() as usize;
    let (mut xs, mut vs) = (vec![X0], vec![0.0]);
    let past = |xs: &[f64], vs: &[f64], i: f64| -> (f64, f64) {
        // Position and velocity at step index i − lag (fractional), zero before 0.
        let j = i - lag as f64;
        if j < 0.0 {
            return (0.0, 0.0);
        }
        let (a, f) = (j.floor() as usize, j.fract());
        let b = (a + 1).min(xs.len() - 1);
        (xs[a] + f * (xs[b] - xs[a]), vs[a] + f * (vs[b] - vs[a]))
    };
    for i in 0..n {
        let (x, v) = (xs[i], vs[i]);
        let acc = |x: f64, v: f64, at: f64| {
            let (xd, vd) = past(&xs, &vs, at);
            (-K * x - C * v - KP * xd - KD * vd) / M
        };
        let t = i as f64;
        let (k1x, k1v) = (v, acc(x, v, t));
        let (k2x, k2v) = (
            v + 0.5 * h * k1v,
            acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v, t + 0.5),
        );
        let (k3x, k3v) = (
            v + 0.5 * h * k2v,
            acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v, t + 0.5),
        );
        let (k4x, k4v) = (v + h * k3v, acc(x + h * k3x, v + h * k3v, t + 1.0));
        xs.push(x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x));
        vs.push(v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v));
    }
    xs.into_iter().step_by(every).collect()
}

#[test]
fn the_delayed_loop_converges_to_the_delay_differential_equation() {
    // Latencies of 50 ms each way, τ = dt: the loop's delay is both latencies plus
    // one and a half steps (the controller's step, and the plant's hold of its input,
    // whose mean lies half a step later). Against the DDE with that delay the error
    // shrinks with dt.
    let dir = scratch("fmu-cosim", "dde");
    fmus(&dir);
    let mut errors = Vec::new();
    for dt in [2e-3, 1e-3, 5e-4] {
        let v = closed_loop(dt, 4.0, (dt, 0.05), (dt, 0.05));
        let (_, cols, _) = run(&dir, &v, &["plant.x"]);
        let h = dt / 20.0;
        let reference = delay_equation(0.1 + 1.5 * dt, h, 4.0, 20);
        assert_eq!(reference.len(), cols[0].len());
        let err = cols[0]
            .iter()
            .zip(&reference)
            .map(|(x, r)| (x - r).abs())
            .fold(0.0, f64::max);
        errors.push(err);
    }
    let orders: Vec<f64> = errors.windows(2).map(|e| (e[0] / e[1]).log2()).collect();
    println!("delayed loop vs DDE: max errors {errors:?}, orders {orders:?}");
    assert!(errors[2] < 1e-3, "error at dt = 0.5 ms: {}", errors[2]);
    for o in orders {
        assert!(o > 0.8, "order {o} (errors {errors:?})");
    }
}

/// The networked-control case: the multibody model's body 1 (1 kg, free, at x = 1 m)
/// on node 1, the PD controller FMU on node 2 reading its position and velocity and
/// setting the force on it, over two channels.
fn body_loop(dt: f64, duration: f64) -> Value {
    json!({
        "name": "body_pd_loop",
        "seed": 1,
        "duration": duration,
        "dt": dt,
        "integrator": "rk4",
        "measurement": {"period": duration},
        "output": {"decimation": 1},
        "model": {"bodies": [{"id": 1, "mass": M, "size": 0.1, "position": [X0, 0.0, 0.0]}]},
        "fmus": [
            {"name": "ctrl", "path": "pd.fmu", "node": 2,
             "start": {"kp": KP, "kd": KD, "r": 0.0}}
        ],
        "channels": [
            {"name": "sense", "tau": dt, "latency": 0.0},
            {"name": "act", "tau": dt, "latency": 0.0}
        ],
        "connections": [
            {"from": "B1.px", "to": "ctrl.x", "channel": "sense"},
            {"from": "B1.vx", "to": "ctrl.v", "channel": "sense"},
            {"from": "ctrl.u", "to": "B1.fx", "channel": "act"}
        ]
    })
}

#[test]
fn a_controller_fmu_steers_a_body_of_the_multibody_model_over_the_network() {
    // m ẍ = −kp x − kd ẋ: the closed form with the plant's own spring and damper zero.
    let closed = |t: f64| {
        let w = (KP / M).sqrt();
        let zeta = KD / (2.0 * (KP * M).sqrt());
        let wd = w * (1.0 - zeta * zeta).sqrt();
        (-zeta * w * t).exp() * (X0 * (wd * t).cos() + (zeta * w * X0 / wd) * (wd * t).sin())
    };
    let dir = scratch("fmu-cosim", "body");
    fmus(&dir);
    let mut errors = Vec::new();
    for dt in [2e-3, 1e-3, 5e-4] {
        let (t, cols, _) = run(&dir, &body_loop(dt, 3.0), &["px_B1", "ctrl.u"]);
        let err = t
            .iter()
            .zip(&cols[0])
            .map(|(&t, &x)| (x - closed(t)).abs())
            .fold(0.0, f64::max);
        errors.push(err);
    }
    let orders: Vec<f64> = errors.windows(2).map(|e| (e[0] / e[1]).log2()).collect();
    println!("body loop: max errors {errors:?}, orders {orders:?}");
    assert!(errors[2] < 2e-2, "error at dt = 0.5 ms: {}", errors[2]);
    for o in orders {
        assert!((0.85..1.2).contains(&o), "order {o} (errors {errors:?})");
    }
}

#[test]
fn a_loop_of_fmus_runs_over_a_tdma_network_with_the_same_digest_on_any_thread_count() {
    let dir = scratch("fmu-cosim", "tdma");
    fmus(&dir);
    let mut v = closed_loop(1e-3, 3.0, (5e-3, 0.0), (5e-3, 0.0));
    for c in v["channels"].as_array_mut().unwrap() {
        c.as_object_mut().unwrap().remove("latency");
    }
    v["network"] = json!({
        "kind": "tdma", "slot": 0.0001, "cycle": 0.005, "guard": 1e-05,
        "link_rate": 1e8, "propagation": 5e-07, "header_bytes": 26, "drift_ppm": 50.0,
        "random_walk_ppm": 0.5, "sync_error": 2e-07,
        "jitter": {"kind": "exponential", "mean": 2e-05}
    });
    let path = dir.join("scenario.json");
    std::fs::write(&path, v.to_string()).unwrap();
    let digest = |jobs: &str, out: &str| {
        let out = dir.join(out);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
            .args(["-j", jobs, "run", path.to_str().unwrap(), "--out"])
            .arg(&out)
            .output()
            .expect("dsmcosim");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s: Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        (s["digest"].as_str().unwrap().to_string(), out)
    };
    let (one, out) = digest("1", "j1");
    let (two, _) = digest("2", "j2");
    assert_eq!(one, two, "thread counts gave different digests");
    // Both nodes sent frames, and the loop (delays of a few ms) settles as the ideal one.
    let mut net = csv::Reader::from_path(out.join("network.csv")).expect("network.csv");
    let sender = net
        .headers()
        .unwrap()
        .iter()
        .position(|h| h == "sender")
        .unwrap();
    let mut senders: Vec<String> = net
        .records()
        .map(|r| r.unwrap()[sender].to_string())
        .collect();
    senders.sort();
    senders.dedup();
    // Node 0 is the TDMA server (its static frames carry the slot list).
    assert_eq!(senders, ["0", "1", "2"], "senders {senders:?}");
    let (t, cols, _) = run(&dir, &v, &["plant.x"]);
    let late = t
        .iter()
        .zip(&cols[0])
        .filter(|(&t, _)| t > 2.5)
        .map(|(_, x)| x.abs())
        .fold(0.0, f64::max);
    assert!(late < 0.05, "peak |x| after 2.5 s: {late}");
}
