//! The delay controller (method §5): forks never disturb the live run, threads
//! never change a result, every live choice respects the bounds and the budget.

use dsmcosim::control::experiment::{self, Experiment};
use dsmcosim::control::Verdict;
use dsmcosim::cosim::CoSim;
use dsmcosim::scenario::{parse_str, Scenario};
use dsmcosim::trace::Recorder;
use serde_json::{json, Value};

/// The thesis scene on 4 nodes, space distribution, sample-and-hold channels with the
/// `reset` coupling (the reading the thesis claims below were measured in).
fn scene(duration: f64, controller: Option<Value>) -> Scenario {
    let v = scene_json(duration, controller);
    parse_str(&v.to_string(), "<test>").unwrap_or_else(|e| panic!("scenario: {e}"))
}

/// [`scene`] as JSON.
fn scene_json(duration: f64, controller: Option<Value>) -> Value {
    let mut v = json!({
        "name": "ctl", "seed": 7, "duration": duration, "dt": 0.001,
        "model": {"grid": {"rows": 4, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0, "until": 12.0}],
        "partition": {"quadrants": true, "coupling": "reset"},
        "channels": [
            {"name": "tau1", "tau": 0.005, "latency": 0.0, "borders": [[1, 2], [1, 4]]},
            {"name": "tau2", "tau": 0.005, "latency": 0.0, "borders": [[2, 3], [3, 4]]}
        ]
    });
    if let Some(c) = controller {
        v["controller"] = c;
    }
    v
}

/// The run's digest (everything recorded), its dynamics digest (steps only) and what it
/// measured.
fn run_digests(s: &Scenario) -> (String, String, Experiment) {
    let ids: Vec<u32> = s.bodies.iter().map(|b| b.id).collect();
    let mut rec = Recorder::new(None, 1, s.links.len(), &ids, &[], &[]).expect("recorder");
    let mut world = CoSim::new(s);
    let mut exp = Experiment::default();
    experiment::run(&mut world, &mut rec, &mut exp).unwrap_or_else(|e| panic!("run: {e}"));
    (rec.digest(), rec.dynamics_digest(), exp)
}

fn run(s: &Scenario) -> (String, Experiment) {
    let (digest, _, exp) = run_digests(s);
    (digest, exp)
}

#[test]
fn baseline_forks_never_change_the_live_run() {
    let plain = scene(3.0, None);
    let controlled = scene(
        3.0,
        Some(json!({
            "method": "fixed", "problem": "cp", "budget": 400.0, "tau_max": 0.03,
            "initial": [0.005], "baselines": ["grid", "no_opt", "nelder_mead"], "grid_step": 0.004
        })),
    );
    let (a, a_dynamics, _) = run_digests(&plain);
    let (b, b_dynamics, exp) = run_digests(&controlled);
    assert_eq!(
        a_dynamics, b_dynamics,
        "forks must not disturb the live run's bytes"
    );
    // The full digest also covers the baselines' objectives in epochs.csv.
    assert_ne!(a, b, "the baselines' measurements are recorded values");
    assert_eq!(exp.windows.len(), 3);
    assert!(exp.windows.iter().all(|w| w.baselines.len() == 3));
}

/// A DSM run's decisions, written down as a `schedule` (each window's requested
/// periods, as epochs.csv holds them), replay its live dynamics bit for bit: the
/// scheduled scene's `dynamics_digest` is the controlled run's. A schedule that moves
/// one decision by a millisecond is another run.
#[test]
fn a_schedule_of_the_dsm_s_decisions_replays_its_dynamics() {
    let with = |key: &str, value: Value| {
        let mut v = scene_json(4.0, None);
        v["measurement"] = json!({"period": 0.5});
        v[key] = value;
        parse_str(&v.to_string(), "<test>").unwrap_or_else(|e| panic!("scenario: {e}"))
    };
    let controlled = with(
        "controller",
        json!({"method": "dsm", "problem": "cp", "budget": 400.0, "tau_max": 0.03,
               "initial": [0.005], "dsm": {"size": 0.002}}),
    );
    let ids: Vec<u32> = controlled.bodies.iter().map(|b| b.id).collect();
    let links = controlled.links.len();
    let mut rec = Recorder::new(None, 1, links, &ids, &[], &[]).expect("recorder");
    let mut world = CoSim::new(&controlled);
    let mut exp = Experiment::default();
    experiment::run(&mut world, &mut rec, &mut exp).unwrap_or_else(|e| panic!("run: {e}"));
    let decisions: Vec<Value> = world
        .epochs()
        .iter()
        .map(|e| {
            let tau: Vec<f64> = e.taus.iter().map(|t| t.0).collect();
            json!({"at": e.t_start.as_secs_f64(), "tau": tau})
        })
        .collect();
    assert_eq!(decisions.len(), 8);
    let distinct: std::collections::BTreeSet<String> =
        decisions.iter().map(|d| d["tau"].to_string()).collect();
    assert!(distinct.len() > 1, "the DSM moved: {decisions:?}");
    let replay = |decisions: &[Value]| run_digests(&with("schedule", json!(decisions))).1;
    assert_eq!(replay(&decisions), rec.dynamics_digest());
    let mut moved = decisions.clone();
    let tau = moved[5]["tau"][0].as_f64().unwrap();
    moved[5]["tau"][0] = json!(tau + 0.001);
    assert_ne!(replay(&moved), rec.dynamics_digest());
}

#[test]
fn grid_search_is_byte_identical_on_one_and_two_threads() {
    let s = scene(
        2.0,
        Some(json!({
            "method": "grid", "problem": "up", "penalty": 5e-4, "tau_max": 0.02,
            "grid_step": 0.004, "baselines": ["no_opt"]
        })),
    );
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| run(&s))
    };
    let (d1, e1) = on(1);
    let (d2, e2) = on(2);
    assert_eq!(d1, d2);
    assert_eq!(format!("{e1:?}"), format!("{e2:?}"));
}

#[test]
fn live_choices_respect_bounds_and_budget_and_the_grid_is_the_best_grid_point() {
    let s = scene(
        4.0,
        Some(json!({
            "method": "dsm", "problem": "cp", "budget": 400.0, "tau_max": 0.03,
            "initial": [0.006], "dsm": {"size": 0.004, "reflections": 3},
            "baselines": ["grid", "no_opt"], "grid_step": 0.002, "dsm_delta": 0.002
        })),
    );
    let (_, exp) = run(&s);
    for w in &exp.windows {
        let tau1 = w.live.x[0];
        assert!((0.001..=0.03).contains(&tau1), "{tau1}");
        assert!(1.0 / tau1 < 400.0, "the last channel needs some budget");
        let grid = w.grid_best.as_ref().expect("grid searched");
        // The grid's choice is at least as good as every other grid point measured:
        // no_opt (τ = 5 ms) is not on a 2 ms grid from 1 ms, so compare with the grid
        // baseline's own objective.
        let g = &w
            .baselines
            .iter()
            .find(|b| b.name == "grid")
            .expect("grid")
            .candidate;
        assert_eq!(g.objective, grid.objective);
        // DSM measured m_r + 1 = 4 candidates per iteration (2 initially), each feasible.
        assert!(w.dsm_path.len() <= 4 && !w.dsm_path.is_empty());
        assert!(w.dsm_path.iter().all(|c| c.objective.is_finite()));
        // DSM ± δ are named after the controlled channel.
        assert!(w.baselines.iter().any(|b| b.name == "dsm_tau1_plus"));
    }
    assert!(exp.mean("dsm", "dsm").is_some());
}

#[test]
fn a_controller_needs_valid_settings() {
    let bad = |c: Value, field: &str| {
        let mut v: Value = json!({
            "name": "x", "seed": 1, "duration": 1.0, "dt": 0.001,
            "model": {"grid": {"rows": 4, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
            "partition": {"quadrants": true},
            "channels": [
                {"name": "a", "tau": 0.005, "borders": [[1, 2], [1, 4]]},
                {"name": "b", "tau": 0.005, "borders": [[2, 3], [3, 4]]}
            ]
        });
        v["controller"] = c;
        let e = parse_str(&v.to_string(), "t")
            .expect_err("must be rejected")
            .to_string();
        assert!(e.contains(field), "{e} must name {field}");
    };
    bad(
        json!({"problem": "cp", "tau_max": 0.05}),
        "controller.budget",
    );
    bad(
        json!({"problem": "up", "tau_max": 0.05}),
        "controller.penalty",
    );
    bad(
        json!({"problem": "cp", "budget": 400, "tau_max": 0.05, "initial": [0.002]}),
        "controller.initial",
    );
    bad(
        json!({"problem": "cp", "budget": 400, "tau_max": 0.0005}),
        "controller.tau_max",
    );
    // Two channels at tau_max = 50 ms already use 40 /s: a budget of 30 /s cannot be met,
    // and with no initial given the error names the budget, not the defaulted start.
    bad(
        json!({"problem": "cp", "budget": 30, "tau_max": 0.05}),
        "controller.budget",
    );
    bad(
        json!({"problem": "cp", "budget": 400, "tau_max": 0.05, "baselines": ["dsm"]}),
        "controller.baselines[0]",
    );
    bad(
        json!({"problem": "cp", "budget": 400, "tau_max": 0.05, "surface_window": 0.5}),
        "controller.surface_window",
    );
    // Grid searches are bounded (40 000 points per window): 1 µs steps over [1, 50] ms
    // give 2.4e9 points on the landscape of two delays; 2 µs steps give 24 501 points
    // on the one controlled delay, which is allowed.
    let fine = json!({"problem": "cp", "budget": 400, "tau_max": 0.05, "grid_step": 1e-6,
                      "baselines": ["grid"], "surface_window": 0.0, "landscape": true});
    bad(fine.clone(), "controller.grid_step");
    // A landscape needs a window and two channels under CP.
    bad(
        json!({"problem": "cp", "budget": 400, "tau_max": 0.05, "landscape": true}),
        "controller.landscape",
    );
    bad(
        json!({"problem": "up", "penalty": 5e-4, "tau_max": 0.05, "surface_window": 0.0,
               "landscape": true}),
        "controller.landscape",
    );
    let mut one = fine;
    one.as_object_mut().unwrap().remove("surface_window");
    one.as_object_mut().unwrap().remove("landscape");
    one["grid_step"] = json!(2e-6);
    let mut v: Value = json!({
        "name": "x", "seed": 1, "duration": 1.0, "dt": 0.001,
        "model": {"grid": {"rows": 4, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "partition": {"quadrants": true},
        "channels": [
            {"name": "a", "tau": 0.005, "borders": [[1, 2], [1, 4]]},
            {"name": "b", "tau": 0.005, "borders": [[2, 3], [3, 4]]}
        ]
    });
    v["controller"] = one;
    parse_str(&v.to_string(), "t").expect("24 501 grid points on one delay are allowed");
}

#[test]
fn the_default_start_is_the_no_optimization_point_not_the_channels_delays() {
    // Channels at 10 and 20 ms, weights 1 and 3, budget 400 /s: equal delays at the
    // budget are (1 + 3) / 400 = 10 ms. The channels' own delays do not set the start.
    let scene = |controller: Value| {
        let v = json!({
            "name": "x", "seed": 1, "duration": 1.0, "dt": 0.001,
            "model": {"grid": {"rows": 4, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
            "partition": {"quadrants": true},
            "channels": [
                {"name": "a", "tau": 0.02, "k": 1.0, "borders": [[1, 2], [1, 4]]},
                {"name": "b", "tau": 0.01, "k": 3.0, "borders": [[2, 3], [3, 4]]}
            ],
            "controller": controller
        });
        let s = parse_str(&v.to_string(), "t").expect("valid");
        s.controller.expect("controlled").initial
    };
    let cp = scene(json!({"problem": "cp", "budget": 400, "tau_max": 0.05}));
    assert_eq!(cp.len(), 1);
    assert!(
        (cp[0] - 0.01).abs() < 1e-15,
        "CP starts at Σk/B = 10 ms, got {cp:?}"
    );
    let given = scene(json!({"problem": "cp", "budget": 400, "tau_max": 0.05, "initial": [0.009]}));
    assert_eq!(given, vec![0.009], "an explicit start is kept");
    // UP has no budget to share: it starts at the channels' delays.
    let up = scene(json!({"problem": "up", "penalty": 5e-4, "tau_max": 0.05}));
    assert_eq!(up, vec![0.02, 0.01]);
}

/// A shipped scenario file as JSON, for a test to edit.
fn shipped_json(name: &str) -> Value {
    let path = format!("{}/scenarios/{name}.json", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).expect("scenario")).expect("json")
}

/// A shipped experiment, shortened to `duration` s, with only the listed baselines.
fn shipped(name: &str, duration: f64, baselines: Value) -> Scenario {
    let mut v = shipped_json(name);
    v["duration"] = json!(duration);
    let c = v["controller"].as_object_mut().expect("controller");
    c.remove("surface_window");
    c.remove("landscape");
    c.remove("dsm_delta");
    c.insert("baselines".into(), baselines);
    parse_str(&v.to_string(), name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn time_cp_grid_optimum_gives_forces_the_smaller_delay_in_most_windows_under_sample_and_hold() {
    // Thesis: constraint forces get the smaller delay. Under the 400 Hz budget the
    // force delay is below the state delay exactly when τ_state > 5 ms. Over the 12 s
    // while body 1 is driven, in the sample-and-hold reading: with delays realized to
    // the nanosecond the grid optimum gives forces the smaller delay in 10 of 12
    // windows and states in 2 (0 s and 3 s). While every delay ran at the next whole
    // step (τ_force = 1/(400 − 1/τ_state) rounded up), it never gave states the smaller
    // one but often picked equal delays, and this test asked for "never slower".
    let (_, exp) = run(&shipped("grid16_time_cp_hold", 12.0, json!(["grid"])));
    let (mut forces_faster, mut states_faster) = (0, 0);
    for w in &exp.windows {
        let tau_state = w.grid_best.as_ref().expect("grid").x[0];
        forces_faster += usize::from(tau_state > 0.005 + 1e-12);
        states_faster += usize::from(tau_state < 0.005 - 1e-12);
    }
    eprintln!(
        "time CP sample-and-hold, 12 s: forces strictly faster in {forces_faster}, states \
         in {states_faster} of {} windows",
        exp.windows.len()
    );
    assert!(
        2 * forces_faster > exp.windows.len(),
        "forces faster in only {forces_faster} of {} windows",
        exp.windows.len()
    );
}

#[test]
fn time_cp_in_the_thesis_reading_gives_forces_the_smaller_delay_in_most_windows() {
    // Thesis reading (latency = τ, default coupling): the grid optimum over the 12 s
    // while body 1 is driven makes forces strictly faster than states (τ_state > 5 ms
    // at the 400 Hz budget) in a majority of windows and states faster in none.
    let (_, exp) = run(&shipped("grid16_time_cp", 12.0, json!(["grid"])));
    let (mut forces, mut states) = (0, 0);
    for w in &exp.windows {
        let tau_state = w.grid_best.as_ref().expect("grid").x[0];
        forces += usize::from(tau_state > 0.005 + 1e-12);
        states += usize::from(tau_state < 0.005 - 1e-12);
    }
    let n = exp.windows.len();
    eprintln!("time CP thesis reading, 12 s: forces faster in {forces}, states in {states} of {n}");
    assert_eq!(states, 0, "states faster in {states} windows");
    assert!(2 * forces > n, "forces faster in {forces} of {n} windows");
}

#[test]
fn the_landscape_covers_the_square_and_agrees_with_the_baselines_measured_beside_it() {
    // Space CP (thesis reading), 3 s, landscape of the window [2, 3) s over 1–20 ms on
    // both channels. The landscape forks the same state as the baselines: its point at
    // equal delays (5, 5) ms is the no-optimization point and must cost exactly what the
    // no-optimization baseline measured.
    let mut v = shipped_json("grid16_space_cp");
    v["duration"] = json!(3.0);
    let c = v["controller"].as_object_mut().expect("controller");
    c.insert("tau_max".into(), json!(0.02));
    c.insert("surface_window".into(), json!(2.0));
    c.insert("landscape".into(), json!(true));
    c.insert("baselines".into(), json!(["grid", "no_opt"]));
    c.remove("dsm_delta");
    let s = parse_str(&v.to_string(), "landscape").expect("valid");
    let (_, exp) = run(&s);
    let (t, points) = exp.landscape.as_ref().expect("a landscape");
    assert_eq!(t.as_nanos(), 2_000_000_000);
    assert_eq!(points.len(), 20 * 20, "1..20 ms squared");
    let window = exp
        .windows
        .iter()
        .find(|w| w.t_start == *t)
        .expect("window");
    let at = |x: [f64; 2]| {
        points
            .iter()
            .find(|c| (c.x[0] - x[0]).abs() < 1e-12 && (c.x[1] - x[1]).abs() < 1e-12)
            .unwrap_or_else(|| panic!("no landscape point {x:?}"))
            .objective
    };
    let no_opt = &window
        .baselines
        .iter()
        .find(|b| b.name == "no_opt")
        .unwrap()
        .candidate;
    assert_eq!(at([0.005, 0.005]).to_bits(), no_opt.objective.to_bits());
    // Every cost is measured (finite, or +∞ for a diverged fork), never NaN.
    assert!(points.iter().all(|c| !c.objective.is_nan()));
    let grid = window.grid_best.as_ref().expect("grid");
    let best_square = points
        .iter()
        .map(|c| c.objective)
        .fold(f64::INFINITY, f64::min);
    eprintln!(
        "landscape [2, 3) s: best {best_square:.4}, grid on the budget line {:.4}",
        grid.objective
    );
    assert!(
        best_square <= no_opt.objective,
        "the square holds the no-opt point"
    );
}

#[test]
fn time_up_grid_optimum_gives_forces_the_smaller_delay_in_most_windows() {
    // Thesis: in time UP the force delay stays below the state delay. Our grid optimum
    // does so in a majority of windows, not in all of them (results/README.md), in
    // both readings of delay; assert the majority, over windows where the two delays
    // differ and over all windows: over 10 s in sample-and-hold, over the whole 30 s
    // in the thesis reading (whose first 10 s split 5 to 4).
    for (name, duration) in [("grid16_time_up", 30.0), ("grid16_time_up_hold", 10.0)] {
        let (_, exp) = run(&shipped(name, duration, json!(["grid"])));
        let (mut forces, mut states) = (0, 0);
        for w in &exp.windows {
            let x = &w.grid_best.as_ref().expect("grid").x;
            let (tau_state, tau_force) = (x[0], x[1]);
            forces += usize::from(tau_force < tau_state);
            states += usize::from(tau_state < tau_force);
        }
        let n = exp.windows.len();
        eprintln!(
            "{name}, {duration} s: forces faster in {forces}, states faster in {states} of {n}"
        );
        assert!(
            forces > states,
            "{name}: forces {forces} vs states {states}"
        );
        assert!(
            2 * forces > n,
            "{name}: forces faster in {forces} of {n} windows"
        );
    }
}

#[test]
fn dsm_with_a_small_simplex_stays_within_fifteen_percent_of_the_grid_optimum() {
    // Ideal channels, D_s = 2 ms (the value that tracks on our scene). The DSM runs at
    // the best vertex of a 2 ms lattice, chosen on costs up to one iteration stale, while
    // the grid optimum is the best 1 ms point of each window chosen with hindsight, so
    // the DSM cannot match it; 15 % is the bound the TDMA test uses, fixed beforehand
    // (no-optimization is the point the DSM starts from). The thesis D_s = 12 ms must
    // track worse on the same windows (its simplex cannot resolve the optimum).
    let ratio = |name: &str| {
        let (_, exp) = run(&shipped(name, 8.0, json!(["grid"])));
        let dsm = exp.mean("dsm", "dsm").expect("dsm");
        let grid = exp.mean("grid", "dsm").expect("grid");
        assert!(
            dsm >= grid - 1e-12,
            "{name}: grid {grid} must bound DSM {dsm}"
        );
        dsm / grid
    };
    for reading in ["", "_hold"] {
        let small = ratio(&format!("grid16_space_cp_ds2{reading}"));
        let thesis = ratio(&format!("grid16_space_cp{reading}"));
        eprintln!(
            "space CP{reading}, 8 s: DSM/grid {small:.3} at D_s = 2 ms, {thesis:.3} at 12 ms"
        );
        assert!(small < 1.15, "DSM/grid {small} at D_s = 2 ms{reading}");
        assert!(
            small < thesis,
            "D_s 2 ms ({small}) vs 12 ms ({thesis}){reading}"
        );
    }
}

#[test]
fn online_measurement_runs_one_dsm_candidate_per_window_on_the_live_plant() {
    // `online`: no fork is measured; each window the live plant runs the one candidate
    // the DSM asks for, and the window's measured cost is told back.
    let s = scene(
        10.0,
        Some(json!({
            "method": "dsm", "problem": "cp", "budget": 400.0, "tau_max": 0.03,
            "initial": [0.006], "measure": "online", "dsm": {"size": 0.004, "reflections": 3}
        })),
    );
    let mut world = CoSim::new(&s);
    let mut ctl = experiment::Controller::new(&s)
        .expect("valid")
        .expect("a controller");
    // The same DSM, before any window: replaying the live costs into it must ask for
    // exactly the delays the live plant ran, one per window.
    let mut replay = ctl.dsm().expect("a DSM").clone();
    ctl.run_until(&mut world, &mut (), s.duration)
        .expect("runs");
    let exp = &ctl.experiment;
    assert_eq!(exp.windows.len(), 10);
    for (i, w) in exp.windows.iter().enumerate() {
        assert!(w.dsm_path.is_empty(), "window {i}: online measures no fork");
        let asked = replay.ask().expect("the DSM always asks");
        assert_eq!(asked.len(), 1);
        assert_eq!(
            asked[0].to_bits(),
            w.live.x[0].to_bits(),
            "window {i}: the live plant ran the asked candidate"
        );
        assert!(w.live.objective.is_finite(), "window {i}: measured live");
        replay.tell(w.live.objective);
        let tau1 = w.live.x[0];
        assert!((0.001..=0.03).contains(&tau1), "window {i}: τ1 {tau1}");
        let tau2 = 1.0 / (400.0 - 1.0 / tau1);
        assert!(
            (0.001..=0.03).contains(&tau2),
            "window {i}: τ2 {tau2} from the budget"
        );
    }
    let live = ctl.dsm().expect("a DSM");
    assert_eq!(live.measurements(), exp.windows.len(), "one per window");
    assert_eq!(replay.measurements(), live.measurements());
    assert_eq!(replay.best(), live.best());
    let mut taus: Vec<u64> = exp.windows.iter().map(|w| w.live.x[0].to_bits()).collect();
    taus.sort_unstable();
    taus.dedup();
    assert!(taus.len() >= 3, "the live delays change: {taus:?}");
}

#[test]
fn dsm_beats_no_optimization_on_the_unconstrained_problems_in_the_sample_and_hold_reading() {
    // In the thesis reading it does not (DSM/no-opt 1.008 and 1.006 over 30 s,
    // results/README.md).
    for name in ["grid16_space_up_hold", "grid16_time_up_hold"] {
        let (_, exp) = run(&shipped(name, 8.0, json!(["no_opt"])));
        let dsm = exp.mean("dsm", "dsm").expect("dsm");
        let no_opt = exp.mean("no_opt", "dsm").expect("no_opt");
        assert!(
            dsm < no_opt,
            "{name}: DSM {dsm} vs no-optimization {no_opt}"
        );
    }
}

#[test]
fn in_the_thesis_reading_a_small_simplex_beats_no_optimization_on_space_cp() {
    // Thesis reading (latency = τ): the delay costs accuracy, the landscape has a
    // valley off equal delays, and the DSM with D_s = 2 ms pays over no optimization
    // (results/README.md; over the whole 30 s, DSM/no-opt 0.974).
    let (_, exp) = run(&shipped("grid16_space_cp_ds2", 12.0, json!(["no_opt"])));
    let dsm = exp.mean("dsm", "dsm").expect("dsm");
    let no_opt = exp.mean("no_opt", "dsm").expect("no_opt");
    eprintln!("space CP D_s 2 ms thesis reading, 12 s: DSM {dsm:.4}, no-opt {no_opt:.4} m");
    assert!(dsm < no_opt, "DSM {dsm} vs no-optimization {no_opt}");
}

/// Windows of `exp` starting in `[from, to)` s where the grid optimum of a two-channel
/// CP at 400 Hz gives the first channel the smaller delay, and the second.
fn faster_channel_counts(exp: &Experiment, from: f64, to: f64) -> (usize, usize) {
    let (mut first, mut second) = (0, 0);
    for w in &exp.windows {
        let t = w.t_start.as_secs_f64();
        if t < from || t >= to {
            continue;
        }
        let tau1 = w.grid_best.as_ref().expect("grid").x[0];
        let tau2 = 1.0 / (400.0 - 1.0 / tau1);
        first += usize::from(tau1 < tau2 - 1e-12);
        second += usize::from(tau2 < tau1 - 1e-12);
    }
    (first, second)
}

#[test]
fn in_the_thesis_reading_the_smaller_delay_follows_the_load() {
    // Thesis reading, thesis settings (D_s 12 ms live), the load moving from body 1 to
    // body 16 (`_ramp`): the share of windows in which the grid optimum gives the near
    // borders (τ1) the smaller delay falls when the load moves away from them (4 of 9
    // in [0, 15) s, 1 of 13 in [15, 30) s in the stored run). With the momentum
    // account (`partition::momentum`) the near borders no longer get the smaller delay
    // more often than the far ones while body 1 alone is driven (τ1 faster in 3, τ2 in
    // 7 of the windows of [0, 12) s of `grid16_space_cp`, where the coupling without the
    // account gave 6 vs 2): printed here, reported in results/README.md.
    let (_, exp) = run(&shipped("grid16_space_cp", 12.0, json!(["grid"])));
    let (near, far) = faster_channel_counts(&exp, 0.0, 12.0);
    eprintln!("space CP thesis reading, [0, 12) s: τ1 faster in {near}, τ2 in {far}");
    let (_, ramp) = run(&shipped("grid16_space_cp_ramp", 30.0, json!(["grid"])));
    let (early1, early2) = faster_channel_counts(&ramp, 0.0, 15.0);
    let (late1, late2) = faster_channel_counts(&ramp, 15.0, 30.0);
    eprintln!("ramp thesis reading: [0, 15) s {early1} vs {early2}; [15, 30) s {late1} vs {late2}");
    let share = |a: usize, b: usize| a as f64 / (a + b).max(1) as f64;
    assert!(
        early1 + early2 > 0 && late1 + late2 > 0,
        "no window with a preference"
    );
    assert!(
        share(early1, early2) > share(late1, late2),
        "τ1's share: early {early1} of {}, late {late1} of {}",
        early1 + early2,
        late1 + late2
    );
}

#[test]
fn in_the_thesis_reading_space_up_no_neighbour_of_the_dsm_is_significantly_better() {
    // Thesis: on space UP the DSM beats {τ1 ± δ, τ2} and {τ1, τ2 ± δ}. Read as a paired
    // statement over the windows where both were measured (method §5): no neighbour is
    // lower than the DSM by the sign test at 5 % (the verdict; it does not say the DSM
    // beats them: results/README.md measures 20, 19, 18 and 15 of 30 windows won, none
    // significant). (Compared as unpaired means over each
    // method's own windows, τ1 + δ came out 0.2 % below the DSM once the coupling's
    // energy account went per node: a difference the windows' spread swamps.)
    let mut v = shipped_json("grid16_space_up");
    let c = v["controller"].as_object_mut().expect("controller");
    c.remove("surface_window");
    c.insert("baselines".into(), json!([]));
    let (_, exp) = run(&parse_str(&v.to_string(), "space_up").expect("valid"));
    for name in [
        "dsm_tau1_plus",
        "dsm_tau1_minus",
        "dsm_tau2_plus",
        "dsm_tau2_minus",
    ] {
        let p = exp.paired("dsm", name, "dsm");
        eprintln!(
            "space UP thesis reading, DSM vs {name}: n {} (excluded {}), DSM lower in {}, \
             higher in {}, ratio {:.4}, mean difference {:.2e}, 95 % CI {:?}, sign test \
             p {:.3}",
            p.n, p.excluded, p.wins, p.losses, p.ratio, p.mean_difference, p.ci95, p.sign_test_p
        );
        assert_eq!(p.n + p.excluded, exp.windows.len());
        assert!(p.n >= 10, "{name}: only {} paired windows", p.n);
        assert_ne!(
            p.verdict(),
            Verdict::Worse,
            "{name} is significantly better: {p:?}"
        );
    }
}

#[test]
fn a_ten_second_period_tracks_the_grid_optimum_worse_than_one_second() {
    // Thesis: with T = 10 s the DSM fails to follow. Measured as the DSM's mean cost
    // over the grid optimum's on the same windows (20 s, thesis D_s), in the
    // sample-and-hold reading (in the thesis reading the 30-s ratios are 1.470 at
    // T = 1 s and 1.370 at T = 10 s: D_s = 12 ms tracks badly at either period).
    let ratio = |name: &str| {
        let (_, exp) = run(&shipped(name, 20.0, json!(["grid"])));
        exp.mean("dsm", "dsm").expect("dsm") / exp.mean("grid", "dsm").expect("grid")
    };
    let (t1, t10) = (
        ratio("grid16_space_cp_hold"),
        ratio("grid16_space_cp_T10_hold"),
    );
    eprintln!("DSM/grid cost ratio over 20 s: T = 1 s {t1:.3}, T = 10 s {t10:.3}");
    assert!(
        t10 > t1,
        "T = 10 s ({t10}) must track worse than T = 1 s ({t1})"
    );
}

#[test]
fn through_tdma_slot_lists_dsm_follows_the_grid_optimum() {
    // Thesis chapter 4: the same behaviour when the delays come from slot lists. Every
    // decision (live and on every fork) goes through the scheduler and the list
    // confirmation; the live run's switches are in the world's TDMA state.
    // Both readings: frames that carry their pair's previous sample (the thesis's
    // x(t − τ), the shipped scene) under the default coupling, and frames that carry
    // the state at their start (sample and hold) under `reset`.
    for (name, reset) in [("tdma4_space_cp", false), ("tdma4_space_cp_hold", true)] {
        tdma_dsm_follows_the_grid_optimum(name, reset);
    }
}

fn tdma_dsm_follows_the_grid_optimum(name: &str, reset: bool) {
    let mut s = shipped(name, 8.0, json!(["grid", "no_opt"]));
    if let (true, Some(p)) = (reset, s.partition.as_mut()) {
        p.coupling = dsmcosim::scenario::model::Coupling::Reset;
    }
    let mut world = dsmcosim::cosim::CoSim::new(&s);
    let mut ctl = dsmcosim::control::experiment::Controller::new(&s)
        .expect("valid")
        .expect("a controller");
    ctl.run_until(&mut world, &mut (), s.duration)
        .expect("runs");
    let exp = &ctl.experiment;
    let dsm = exp.mean("dsm", "dsm").expect("dsm");
    let grid = exp.mean("grid", "dsm").expect("grid");
    let no_opt = exp.mean("no_opt", "dsm").expect("no_opt");
    eprintln!("{name}, 8 s: DSM {dsm:.4}, grid {grid:.4}, no-opt {no_opt:.4} m");
    assert!(
        dsm >= grid - 1e-12,
        "the grid optimum bounds the grid points"
    );
    assert!(dsm / grid < 1.15, "DSM/grid {}", dsm / grid);
    assert!(dsm < no_opt, "DSM {dsm} vs no-optimization {no_opt}");
    let link = world.tdma().expect("a tdma world");
    let switches = link.switches();
    assert!(!switches.is_empty(), "DSM changed the delays");
    let cycle = link.network().layout().cycle_len().as_nanos();
    for sw in switches {
        assert_eq!(sw.effective_at.as_nanos() % cycle, 0, "a cycle boundary");
        let lag = sw.effective_at.as_nanos() - sw.decided_at.as_nanos();
        assert!(lag <= 2 * cycle, "lag {lag} ns from the broadcast decision");
    }
}
