//! The TDMA network inside the co-simulation (method §4, issue "TDMA network
//! model"): equivalence with ideal channels, losses beyond the guard, seeds, list
//! decisions through the confirmation protocol.

use dsmcosim::cosim::{CoSim, Observer, StepValues};
use dsmcosim::kernel::SimTime;
use dsmcosim::network::Message;
use dsmcosim::scenario::{parse_str, Scenario};
use dsmcosim::trace::Digest;
use serde_json::{json, Value};

/// Four bodies in a row on two nodes (B1 B2 | B3 B4), body 1 driven. The border link
/// L2 belongs to node 1, so node 2 sends B3's state (channel `states`, TDMA node 2)
/// and node 1 sends L2's force (channel `forces`, TDMA node 1).
fn row(duration: f64) -> Value {
    json!({
        "name": "row4", "seed": 7, "duration": duration, "dt": 0.001, "integrator": "euler",
        "stabilizer": {"kind": "smc", "mu": 0.05, "k": 10.0, "epsilon": 0.1},
        "model": {"grid": {"rows": 1, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0, "phase": 0.0,
                    "from": 0.0, "until": 12.0}],
        "partition": {"nodes": [[1, 2], [3, 4]]},
        "output": {"decimation": 100}
    })
}

/// `row` on ideal channels with zero latency, period τ and the given phases [s].
fn row_ideal(duration: f64, tau: f64, phase_states: f64, phase_forces: f64) -> Value {
    let mut v = row(duration);
    v["channels"] = json!([
        {"name": "states", "tau": tau, "latency": 0.0, "phase": phase_states, "kinds": ["state"]},
        {"name": "forces", "tau": tau, "latency": 0.0, "phase": phase_forces, "kinds": ["force"]}
    ]);
    v
}

/// `row` on a TDMA network with one slot per dt and a cycle of τ: sync, three static
/// slots, then node 2's states at 4 ms and node 1's forces at 5 ms into each cycle.
fn row_tdma(duration: f64, tau: f64) -> Value {
    let mut v = row(duration);
    v["channels"] = json!([
        {"name": "states", "tau": tau, "kinds": ["state"]},
        {"name": "forces", "tau": tau, "kinds": ["force"]}
    ]);
    v["network"] = json!({
        "kind": "tdma", "slot": 0.001, "cycle": tau,
        "slot_list": [{"node": 2, "channel": "states"}, {"node": 1, "channel": "forces"}]
    });
    v
}

/// The thesis 4×4 scene on 4 quadrant nodes, space channels at 5 ms, on a TDMA
/// network with `extra` keys.
fn thesis_tdma(duration: f64, extra: Value) -> Value {
    let mut v = json!({
        "name": "tdma4", "seed": 7, "duration": duration, "dt": 0.001, "integrator": "euler",
        "stabilizer": {"kind": "smc", "mu": 0.05, "k": 10.0, "epsilon": 0.1},
        "model": {"grid": {"rows": 4, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0, "phase": 0.0,
                    "from": 0.0, "until": 12.0}],
        // `reset` sends the smallest frames (no force rates, no energy reports): the
        // 100 µs slots below were laid out for them.
        "partition": {"quadrants": true, "coupling": "reset"},
        "channels": [
            {"name": "tau1", "tau": 0.005, "borders": [[1, 2], [1, 4]]},
            {"name": "tau2", "tau": 0.005, "borders": [[2, 3], [3, 4]]}
        ],
        "network": {"kind": "tdma", "slot": 0.0001, "cycle": 0.005, "guard": 0.00001,
                    "link_rate": 100e6, "header_bytes": 26},
        "output": {"decimation": 100}
    });
    for (k, x) in extra.as_object().expect("an object").iter() {
        v["network"][k] = x.clone();
    }
    v
}

fn scenario(v: &Value) -> Scenario {
    parse_str(&v.to_string(), "<test>").unwrap_or_else(|e| panic!("scenario: {e}"))
}

/// Digest over the steps only (the TDMA cycle records are not part of it) and every
/// delivery (time, from, to, channel, sample time).
#[derive(Default)]
struct Watch {
    steps: Digest,
    deliveries: Vec<(SimTime, usize, usize, usize, SimTime)>,
}

impl Observer for Watch {
    fn on_step(&mut self, s: &StepValues) -> std::io::Result<()> {
        self.steps.time(s.time.as_nanos());
        self.steps.values(s.w);
        self.steps.values(s.f);
        for p in s.p {
            self.steps.values(p.as_slice());
        }
        self.steps.end_step();
        Ok(())
    }

    fn on_delivery(&mut self, t: SimTime, m: &Message) {
        self.deliveries.push((t, m.from, m.to, m.channel, m.sent));
    }
}

fn watch(v: &Value) -> (CoSim, Watch) {
    let mut world = CoSim::new(&scenario(v));
    let mut w = Watch::default();
    world.run_to_end(&mut w).expect("the run completes");
    (world, w)
}

#[test]
fn a_list_realizing_the_periods_reproduces_the_ideal_run_bit_for_bit() {
    // τ = 10 ms; the TDMA data slots start 4 ms and 5 ms into each cycle, on step
    // boundaries, so ideal channels sampled with those phases and zero latency must see
    // the very same deliveries and produce the very same trajectory.
    let (ideal_world, ideal) = watch(&row_ideal(3.0, 0.01, 0.004, 0.005));
    let (tdma_world, tdma) = watch(&row_tdma(3.0, 0.01));
    assert_eq!(ideal_world.messages(), 600, "2 routes × 300 periods");
    assert_eq!(ideal.deliveries, tdma.deliveries);
    assert_eq!(ideal.steps.hex(), tdma.steps.hex());
    let net = tdma_world.tdma().expect("a tdma world").network();
    assert_eq!((net.lost(), net.words_drawn()), (0, 0));
    // Nominal and measured periods: exactly the cycle.
    for e in tdma_world.epochs() {
        assert_eq!(e.taus, vec![(0.01, 0.01), (0.01, 0.01)]);
    }
    // A phase off by one step is another run: the comparison can fail.
    let (_, shifted) = watch(&row_ideal(3.0, 0.01, 0.003, 0.005));
    assert_ne!(shifted.steps.hex(), tdma.steps.hex());
}

#[test]
fn previous_slot_frames_reproduce_ideal_channels_at_latency_tau_bit_for_bit() {
    // `network.sample: "previous_slot"`: each frame carries the sample its pair took at
    // its previous frame, one cycle (τ = 10 ms) earlier: the thesis's x(t − τ) reading,
    // which ideal channels give with latency = τ (the default) and the same phases.
    let mut ideal = row_ideal(3.0, 0.01, 0.004, 0.005);
    for c in 0..2 {
        ideal["channels"][c]["latency"] = json!(0.01);
    }
    let (ideal_world, ideal) = watch(&ideal);
    let mut v = row_tdma(3.0, 0.01);
    v["network"]["sample"] = json!("previous_slot");
    let (tdma_world, tdma) = watch(&v);
    assert_eq!(ideal.deliveries, tdma.deliveries);
    assert_eq!(ideal.steps.hex(), tdma.steps.hex());
    assert_eq!(ideal_world.messages(), tdma_world.messages());
    for (t, _, _, _, sent) in &tdma.deliveries {
        assert_eq!(t.as_nanos() - sent.as_nanos(), 10_000_000, "one period old");
    }
    // The default (`"slot"`) is another reading and another run.
    let (_, now) = watch(&row_tdma(3.0, 0.01));
    assert_ne!(now.steps.hex(), tdma.steps.hex());
}

#[test]
fn a_lost_previous_slot_frame_loses_the_older_sample_and_the_next_carries_a_fresh_one() {
    // Drift far beyond the guard: frames collide. Under "previous_slot" a sender still
    // samples at every frame, lost or not, so no delivered sample is older than the
    // worst gap between two of the pair's frames, and no sample is delivered twice.
    let lossy = json!({"drift_ppm": 80000.0, "link_rate": 20e6, "sample": "previous_slot"});
    let (world, w) = watch(&thesis_tdma(2.0, lossy));
    let net = world.tdma().expect("a tdma world").network();
    assert!(net.lost() > 0, "the drift must lose frames for this test");
    assert!(
        !w.deliveries.is_empty(),
        "frames that did not collide deliver"
    );
    // (from, to, channel) → (delivery, sample time) of its last frame.
    let mut last = std::collections::BTreeMap::new();
    for &(t, from, to, channel, sent) in &w.deliveries {
        assert!(t > sent, "a previous-slot sample is older than its frame");
        assert!(
            t.as_nanos() - sent.as_nanos() < 6_000_000,
            "age {} ns at {t:?} is more than one 5 ms cycle plus the frame",
            t.as_nanos() - sent.as_nanos()
        );
        // A frame carries several messages of one sample; a later frame a newer one.
        if let Some((t0, sent0)) = last.insert((from, to, channel), (t, sent)) {
            assert!(t == t0 || sent > sent0, "a sample delivered in two frames");
        }
    }
}

#[test]
fn off_grid_frames_carry_the_state_of_the_next_step_boundary() {
    // A 100 µs slot puts the data frames between step boundaries (0.4 and 0.5 ms into
    // each cycle): the sender has already computed the state at the next boundary
    // (1 ms), which is what an ideal channel sampling at 1 ms carries.
    let mut v = row_tdma(1.0, 0.01);
    v["network"]["slot"] = json!(0.0001);
    // Forces first: node 2 samples its states after node 1's force arrived, as it does
    // on ideal channels, where both samples precede every delivery at 1 ms (a state
    // message excludes the receiver's own force, so the order is then immaterial).
    v["network"]["slot_list"] = json!([
        {"node": 1, "channel": "forces"}, {"node": 2, "channel": "states"}
    ]);
    let (_, tdma) = watch(&v);
    let (_, ideal) = watch(&row_ideal(1.0, 0.01, 0.001, 0.001));
    assert_eq!(tdma.steps.hex(), ideal.steps.hex());
    for (t, _, _, _, sent) in &tdma.deliveries {
        assert_eq!(sent.as_nanos() % 1_000_000, 0, "sampled on a step boundary");
        assert!(
            t.as_nanos() % 10_000_000 < 1_000_000,
            "delivered within the first ms"
        );
    }
}

#[test]
fn drift_inside_the_guard_loses_nothing_and_beyond_it_loses_frames() {
    // Slots of 100 µs with a 10 µs guard; at 20 Mbit/s the largest frame (218 B) takes
    // 87 µs, so a frame collides once two neighbours' clock errors sum to more than
    // ~13 µs. Clocks re-align every cycle and a data slot starts at most 1.2 ms into
    // it: 50 ppm gives errors up to 60 ns (inside the guard), 20 000 ppm up to 24 µs.
    let link = |ppm: f64| json!({"drift_ppm": ppm, "link_rate": 20e6});
    let (world, _) = watch(&thesis_tdma(2.0, link(50.0)));
    assert_eq!(world.tdma().unwrap().network().lost(), 0);
    let beyond = thesis_tdma(2.0, link(20000.0));
    let (world, _) = watch(&beyond);
    let lost = world.tdma().unwrap().network().lost();
    assert!(lost > 0, "frames beyond the guard collide");
    // Lost data shows as a longer measured period than the list's nominal one.
    let worst = world
        .epochs()
        .iter()
        .flat_map(|e| e.taus.iter().map(|t| t.1))
        .fold(0.0, f64::max);
    assert!(worst > 0.005, "measured period {worst} s");
    // Deterministic with the seed.
    let (again, _) = watch(&beyond);
    assert_eq!(again.tdma().unwrap().network().lost(), lost);
}

#[test]
fn changing_the_seed_changes_a_run_only_where_randomness_is_configured() {
    let digest = |v: &Value, seed: u64| {
        let mut v = v.clone();
        v["seed"] = json!(seed);
        let (world, w) = watch(&v);
        (w.steps.hex(), world.tdma().unwrap().network().words_drawn())
    };
    let plain = thesis_tdma(1.0, json!({"propagation": 1e-6}));
    let (a, drawn) = digest(&plain, 7);
    assert_eq!(drawn, 0, "no random source configured, nothing drawn");
    assert_eq!(digest(&plain, 8).0, a);
    // Jitter large enough to move deliveries across step boundaries.
    let noisy = thesis_tdma(
        1.0,
        json!({"drift_ppm": 50.0, "jitter": {"kind": "exponential", "mean": 0.0003}}),
    );
    let (b, drawn) = digest(&noisy, 7);
    assert!(drawn > 0);
    assert_eq!(digest(&noisy, 7).0, b, "same seed, same run");
    assert_ne!(digest(&noisy, 8).0, b, "another seed, other jitter");
}

#[test]
fn a_controller_decision_switches_every_node_at_one_cycle_boundary() {
    // Request new periods at t = 0.5 s: the list is broadcast, confirmed and in force
    // from one cycle boundary on, and the measured periods follow.
    let mut v = thesis_tdma(1.0, json!({"decision_lag": 0.002}));
    v["measurement"] = json!({"period": 0.25});
    let mut world = CoSim::new(&scenario(&v));
    let mut w = Watch::default();
    let half = SimTime(500_000_000);
    world.advance_to(half, &mut w).unwrap();
    let achieved = world
        .set_taus(half, &[0.002, 0.01], &[])
        .expect("schedulable");
    assert_eq!(achieved, vec![SimTime(2_000_000), SimTime(5_000_000)]);
    world.run_to_end(&mut w).unwrap();
    let link = world.tdma().unwrap();
    let [switch] = link.switches() else {
        panic!("one switch, got {:?}", link.switches())
    };
    assert_eq!(
        switch.decided_at,
        SimTime(502_000_000),
        "after the decision lag"
    );
    assert_eq!(
        switch.effective_at.as_nanos() % 5_000_000,
        0,
        "a cycle boundary"
    );
    assert!(switch.lag <= SimTime(10_000_000), "lag {}", switch.lag);
    // Before the switch node-1 data (tau1) came every 5 ms; after, every 2 ms or less.
    let tau1_after: Vec<SimTime> = w
        .deliveries
        .iter()
        .filter(|d| d.3 == 0 && d.1 == 0 && d.0 > switch.effective_at)
        .map(|d| d.0)
        .collect();
    let worst = tau1_after
        .windows(2)
        .map(|p| p[1].as_nanos() - p[0].as_nanos())
        .filter(|&g| g > 0)
        .max()
        .unwrap();
    assert!(worst <= 2_000_000, "worst gap after the switch {worst} ns");
    let last = world.epochs().last().unwrap();
    assert_eq!(last.taus[0].0, 0.002);
    assert!(last.taus[0].1 <= 0.0021, "measured {}", last.taus[0].1);
}

#[test]
fn an_unschedulable_request_is_refused_with_the_channel_named() {
    let v = thesis_tdma(0.2, json!({}));
    let mut world = CoSim::new(&scenario(&v));
    let e = world
        .set_taus(SimTime::ZERO, &[0.00005, 0.005], &[])
        .unwrap_err();
    assert!(e.to_string().starts_with("tau[0]"), "{e}");
}
