//! Random scenes a user could write — bodies on joints and links, gravity, a partition
//! with its channel, a schedule, an FMU on a node of its own — run through the binary:
//! whatever validation accepts ends in a run that is ok, a divergence naming its time
//! and element, or a refusal before anything is written; never a panic, a signal, an
//! out-of-memory misread, or a change to a file of the user's in the output directory.

use std::sync::OnceLock;
use std::time::Duration;

use proptest::prelude::*;
use serde_json::{json, Value};

use super::{said, scratch, write_json};

/// The msd test FMU, built once for every case.
fn msd() -> &'static std::path::Path {
    static FMU: OnceLock<std::path::PathBuf> = OnceLock::new();
    FMU.get_or_init(|| {
        let dir = scratch("random-scenes-fmu");
        super::fmu_build::build_test_fmu("msd", &dir).expect("build msd")
    })
}

#[derive(Debug, Clone)]
struct Scene {
    masses: Vec<f64>,
    spins: Vec<f64>,
    /// Per neighbour pair: 0 link, 1 ball, 2 hinge, 3 weld, 4 prismatic.
    joints: Vec<u8>,
    pinned: bool,
    gravity: bool,
    /// Bodies on node 1 (the rest on node 2); `None`: one node.
    split: Option<usize>,
    tau_ms: u32,
    integrator: u8,
    stabilizer: u8,
    schedule: Option<u32>,
    fmu: bool,
}

fn scene() -> impl Strategy<Value = Scene> {
    (2usize..6).prop_flat_map(|n| {
        (
            proptest::collection::vec(0.2f64..5.0, n),
            proptest::collection::vec(-3.0f64..3.0, n),
            proptest::collection::vec(0u8..5, n - 1),
            any::<bool>(),
            any::<bool>(),
            proptest::option::of(1usize..n),
            1u32..12,
            0u8..3,
            0u8..3,
            proptest::option::of(1u32..12),
            any::<bool>(),
        )
            .prop_map(
                |(
                    masses,
                    spins,
                    joints,
                    pinned,
                    gravity,
                    split,
                    tau_ms,
                    integrator,
                    stabilizer,
                    schedule,
                    fmu,
                )| Scene {
                    masses,
                    spins,
                    joints,
                    pinned,
                    gravity,
                    split,
                    tau_ms,
                    integrator,
                    stabilizer,
                    schedule,
                    fmu,
                },
            )
    })
}

fn scenario(s: &Scene) -> Value {
    let n = s.masses.len();
    let bodies: Vec<Value> = (0..n)
        .map(|i| json!({"id": i + 1, "mass": s.masses[i], "size": 0.2, "position": [i as f64, 0, 0],
                        "angular_velocity": [0, 0, s.spins[i]], "velocity": [0, s.spins[i] * i as f64, 0]}))
        .collect();
    let (mut links, mut joints) = (Vec::new(), Vec::new());
    for (i, &k) in s.joints.iter().enumerate() {
        let (a, b, at) = (i + 1, i + 2, [i as f64 + 0.5, 0.0, 0.0]);
        match k {
            0 => links.push(json!({"a": a, "b": b})),
            1 => joints.push(json!({"type": "ball", "a": a, "b": b, "at": at})),
            2 => joints.push(json!({"type": "hinge", "a": a, "b": b, "at": at, "axis": [0, 0, 1]})),
            3 => joints.push(json!({"type": "weld", "a": a, "b": b, "at": at})),
            _ => joints
                .push(json!({"type": "prismatic", "a": a, "b": b, "at": at, "axis": [1, 0, 0]})),
        }
    }
    if s.pinned {
        joints.push(json!({"type": "ball", "a": 1, "at": [-0.5, 0, 0]}));
    }
    let mut model = json!({"bodies": bodies, "links": links, "joints": joints});
    if s.gravity {
        model["gravity"] = json!([0, 0, -9.81]);
    }
    let integrator = ["euler", "rk4", "symplectic_euler"][s.integrator as usize];
    let mut v = json!({
        "name": "random", "seed": 3, "duration": 0.05, "dt": 0.001,
        "integrator": integrator,
        "model": model, "measurement": {"period": 0.01}
    });
    match s.stabilizer {
        1 => v["stabilizer"] = json!({"kind": "smc", "mu": 0.01, "k": 100}),
        2 => v["stabilizer"] = json!({"kind": "baumgarte"}),
        _ => {}
    }
    let mut channels = Vec::new();
    if let Some(k) = s.split {
        v["partition"] =
            json!({"nodes": [(1..=k).collect::<Vec<_>>(), (k + 1..=n).collect::<Vec<_>>()]});
        channels.push(json!({"name": "border", "tau": s.tau_ms as f64 / 1000.0}));
    }
    if s.fmu {
        v["fmus"] = json!([{"name": "plant", "path": msd().display().to_string(), "node": 3}]);
        channels.push(json!({"name": "sense", "tau": 0.002, "kinds": ["signal"]}));
        v["connections"] = json!([{"from": "B1.px", "to": "plant.F", "channel": "sense"}]);
    }
    if !channels.is_empty() {
        v["channels"] = json!(channels);
    }
    if let (Some(t), false) = (s.schedule, channels.is_empty()) {
        v["schedule"] = json!([{"at": 0.02, "tau": vec![t as f64 / 1000.0; channels.len()]}]);
    }
    v
}

proptest! {
    #![proptest_config(ProptestConfig { timeout: 300_000, ..ProptestConfig::with_cases(40) })]

    #[test]
    fn a_scene_validation_accepts_runs_to_a_verdict(s in scene()) {
        let dir = scratch(&format!("random-scene-{}", std::process::id()));
        let file = write_json(&dir, "s.json", &scenario(&s));
        let out = dir.join("out");
        std::fs::create_dir_all(&out).expect("mkdir");
        std::fs::write(out.join("notes.txt"), "the user's own\n").expect("write");
        let o = super::limits::bounded(
            &["run", file.to_str().unwrap(), "--out", out.to_str().unwrap()],
            Duration::from_secs(300),
        );
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        prop_assert!(!err.contains("panicked"), "{s:?}: {}", said(&o));
        let notes = std::fs::read_to_string(out.join("notes.txt")).ok();
        prop_assert_eq!(notes.as_deref(), Some("the user's own\n"));
        match o.status.code() {
            Some(0) => prop_assert_eq!(&super::summary(&out)["status"], &json!("ok")),
            Some(2) => {
                // Refused: one line naming a field, and nothing of a run written.
                prop_assert!(err.starts_with("error: "), "{s:?}: {}", said(&o));
                prop_assert!(!out.join("summary.json").exists(), "{s:?}: {}", said(&o));
            }
            Some(3) => {
                let named = err.contains("diverged at t = ")
                    && [" link L", " joint J", " body B"].iter().any(|p| err.contains(p))
                    || err.contains("numerical failure at t = ") && err.contains("node ");
                prop_assert!(named, "{s:?}: {}", said(&o));
                prop_assert_eq!(&super::summary(&out)["status"], &json!("diverged"));
            }
            code => prop_assert!(false, "{s:?}: exit {code:?}: {}", said(&o)),
        }
    }
}
