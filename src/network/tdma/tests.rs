//! Cross-cutting tests of the TDMA core: ideal-channel equivalence, drift against the
//! guard, list switches, seeds and draws.

use super::collision::FrameKind;
use super::engine::{CycleReport, TdmaNetwork};
use super::frame::FrameSizes;
use super::layout::{CycleLayout, SlotList};
use super::schedule::{schedule, ChannelRequest};
use super::{Jitter, TdmaConfig};
use crate::kernel::SimTime;

const US: u64 = 1_000;
const MS: u64 = 1_000_000;

/// 4 clients, 100 µs slots; channel 0 from clients 1 and 2, channel 1 from 3 and 4.
fn base(cycle: u64) -> TdmaConfig {
    TdmaConfig::new(4, SimTime(100 * US), SimTime(cycle))
}

fn requests(tau0: u64, tau1: u64) -> Vec<ChannelRequest> {
    vec![
        ChannelRequest {
            tau: SimTime(tau0),
            senders: vec![1, 2],
        },
        ChannelRequest {
            tau: SimTime(tau1),
            senders: vec![3, 4],
        },
    ]
}

/// Every pair sends `floats` values.
fn frames(header: u64, floats: usize) -> FrameSizes {
    let mut f = FrameSizes::new(header);
    for (sender, channel) in [(1, 0), (2, 0), (3, 1), (4, 1)] {
        f.set(sender, channel, floats);
    }
    f
}

fn list_for(cfg: &TdmaConfig, reqs: &[ChannelRequest]) -> SlotList {
    schedule(&CycleLayout::new(cfg).unwrap(), reqs)
        .unwrap()
        .list
}

fn run(net: &mut TdmaNetwork, cycles: u64) -> Vec<CycleReport> {
    (0..cycles).map(|_| net.run_cycle()).collect()
}

/// (start, delivery) of every frame `sender` sent on `channel`.
fn pair(reports: &[CycleReport], sender: usize, channel: usize) -> Vec<(SimTime, Option<SimTime>)> {
    let mine = |f: &&super::collision::Transmission| {
        f.sender == sender && f.kind == FrameKind::Dynamic { channel }
    };
    reports
        .iter()
        .flat_map(|r| r.frames.iter().filter(mine).map(|f| (f.start, f.delivery)))
        .collect()
}

#[test]
fn without_drift_jitter_or_latency_tdma_delivers_like_an_ideal_channel() {
    let cfg = base(5 * MS);
    let reqs = requests(MS, 2500 * US);
    let list = list_for(&cfg, &reqs);
    let mut net = TdmaNetwork::new(cfg, 7, frames(0, 9), 2, list).unwrap();
    let reports = run(&mut net, 6);
    for (sender, channel, tau) in [(1, 0, MS), (2, 0, MS), (3, 1, 2500 * US), (4, 1, 2500 * US)] {
        let got = pair(&reports, sender, channel);
        // An ideal channel sampling every τ from the pair's first slot, zero latency.
        let phase = got[0].0;
        let ideal: Vec<_> = (0..6 * 5 * MS / tau)
            .map(|i| (SimTime(phase.0 + i * tau), Some(SimTime(phase.0 + i * tau))))
            .collect();
        assert_eq!(got, ideal, "node {sender} on channel {channel}");
    }
    assert_eq!(net.words_drawn(), 0);
    assert_eq!(net.lost(), 0);
}

#[test]
fn with_fixed_latency_deliveries_stay_periodic_and_nothing_is_drawn() {
    let mut cfg = base(5 * MS);
    cfg.guard = SimTime(10 * US);
    cfg.link_rate = 8e6; // 1 byte per µs
    cfg.header_bytes = 10;
    cfg.propagation = SimTime(2 * US);
    let list = list_for(&cfg, &requests(MS, 2500 * US));
    let mut net = TdmaNetwork::new(cfg, 7, frames(10, 9), 2, list).unwrap();
    let reports = run(&mut net, 6);
    let got = pair(&reports, 2, 0);
    let phase = got[0].0;
    for (i, (start, delivery)) in got.iter().enumerate() {
        assert_eq!(*start, SimTime(phase.0 + i as u64 * MS), "frame {i}");
        // 82 bytes = 82 µs on the wire, plus 2 µs propagation.
        assert_eq!(*delivery, Some(SimTime(start.0 + 84 * US)), "frame {i}");
    }
    assert_eq!(net.words_drawn(), 0);
}

/// 100 µs slots with a 10 µs guard and 90 µs data frames, 2 ms cycles.
fn tight(drift_ppm: f64, sync_error: u64) -> TdmaConfig {
    let mut cfg = base(2 * MS);
    cfg.guard = SimTime(10 * US);
    cfg.link_rate = 8e6;
    cfg.header_bytes = 10;
    cfg.drift_ppm = drift_ppm;
    cfg.sync_error = SimTime(sync_error);
    cfg
}

fn lost_over(cfg: TdmaConfig, seed: u64, cycles: u64) -> (u64, Vec<CycleReport>) {
    let list = list_for(&cfg, &requests(MS, MS));
    let mut net = TdmaNetwork::new(cfg, seed, frames(10, 10), 2, list).unwrap();
    let reports = run(&mut net, cycles);
    (net.lost(), reports)
}

#[test]
fn drift_inside_the_guard_loses_nothing_and_beyond_it_loses_frames() {
    // Offsets stay within 1000 ppm · 2 ms + 2 µs = 4 µs: two neighbours together 8 µs,
    // inside the 10 µs guard.
    for seed in 0..20 {
        assert_eq!(
            lost_over(tight(1000.0, 2 * US), seed, 100).0,
            0,
            "seed {seed}"
        );
    }
    // 8000 ppm: up to 16 µs per client by the end of a cycle.
    let (lost, a) = lost_over(tight(8000.0, 2 * US), 3, 100);
    assert!(lost > 0, "frames lost beyond the guard");
    let (again, b) = lost_over(tight(8000.0, 2 * US), 3, 100);
    assert_eq!(
        (lost, &a),
        (again, &b),
        "the same seed loses the same frames"
    );
    // Every loss is a collision: a lost frame overlaps another one (the next cycle's
    // sync frame included).
    let all: Vec<_> = a.iter().flat_map(|r| r.frames.iter()).collect();
    for f in all.iter().filter(|f| f.lost()) {
        let overlaps = all.iter().any(|g| {
            (g.cycle, g.slot) != (f.cycle, f.slot) && g.start < f.end() && f.start < g.end()
        });
        assert!(overlaps, "{f:?}");
    }
}

#[test]
fn every_client_switches_lists_at_the_same_boundary_and_a_lost_confirmation_delays_it() {
    // Long static frames (75 µs of 90 usable) and a sync error up to 20 µs: neighbours'
    // static frames collide in some cycles, so confirmations get lost.
    let mut cfg = base(2 * MS);
    cfg.guard = SimTime(10 * US);
    cfg.link_rate = 16e6; // 2 bytes per µs
    cfg.header_bytes = 150;
    cfg.sync_error = SimTime(20 * US);
    let lists = [
        list_for(&cfg, &requests(MS, MS)),
        list_for(&cfg, &requests(2 * MS, MS)),
        list_for(&cfg, &requests(MS, 2 * MS)),
    ];
    let mut net = TdmaNetwork::new(cfg, 11, frames(150, 1), 2, lists[0].clone()).unwrap();
    let mut reports = Vec::new();
    for k in 0..60u64 {
        if k == 3 || k == 30 {
            let v = net.decide(SimTime(k * 2 * MS), lists[(k / 30 + 1) as usize].clone());
            assert_eq!(v, Ok((k / 30 + 1) as u32));
        }
        reports.push(net.run_cycle());
    }
    let switches: Vec<_> = reports.iter().filter_map(|r| r.switch.clone()).collect();
    assert_eq!(switches.len(), 2);
    let mut delayed = false;
    for s in &switches {
        // Recompute from the frames: the cycle in which the last client confirmed.
        let mut heard = vec![std::collections::BTreeSet::new(); 4];
        let mut confirmed = [false; 4];
        let mut last = None;
        for r in &reports[s.first_broadcast as usize..] {
            let FrameKind::Static {
                broadcast: Some(f), ..
            } = r.frames[1].kind
            else {
                panic!("cycle {} broadcasts nothing", r.cycle);
            };
            assert_eq!(f.version, s.version);
            for i in 0..4 {
                if !r.frames[1].lost() {
                    heard[i].insert(f.index);
                }
                confirmed[i] |= heard[i].len() == f.of && !r.frames[2 + i].lost();
            }
            if confirmed.iter().all(|&c| c) {
                last = Some(r.cycle);
                // Without a loss it takes one cycle per fragment.
                delayed |= r.cycle + 1 - s.first_broadcast > f.of as u64;
                break;
            }
        }
        assert_eq!(Some(s.confirmed_in), last, "{s:?}");
        assert_eq!(s.effective_cycle, s.confirmed_in + 1);
        assert_eq!(s.lag, SimTime(s.effective_at.0 - s.decided_at.0));
    }
    assert!(
        delayed,
        "with this seed a lost frame delays a switch: {switches:?}"
    );
    // Each cycle's data frames all follow the one list in force: no node is left on
    // the other list.
    let layout = *net.layout();
    for r in &reports {
        let list = &lists[r.list_version as usize];
        for f in &r.frames {
            if let FrameKind::Dynamic { channel } = f.kind {
                let e = layout.entry(list, f.slot).unwrap();
                assert_eq!(
                    (e.sender, e.channel),
                    (f.sender, channel),
                    "cycle {}",
                    r.cycle
                );
            }
        }
        let sending = list.entries.iter().flatten().count();
        let dynamic = r
            .frames
            .iter()
            .filter(|f| matches!(f.kind, FrameKind::Dynamic { .. }));
        assert_eq!(dynamic.count(), sending, "cycle {}", r.cycle);
    }
}

#[test]
fn changing_the_seed_changes_only_random_quantities() {
    let with = |drift: f64, jitter: Jitter, seed: u64| {
        let mut cfg = tight(drift, 0);
        cfg.jitter = jitter;
        lost_over(cfg, seed, 20).1
    };
    let starts = |r: &[CycleReport]| -> Vec<_> {
        r.iter()
            .flat_map(|r| r.frames.iter().map(|f| f.start))
            .collect()
    };
    let deliveries = |r: &[CycleReport]| -> Vec<_> {
        r.iter()
            .flat_map(|r| r.frames.iter().map(|f| f.delivery))
            .collect()
    };
    let nominal = |r: &[CycleReport]| -> Vec<_> {
        r.iter()
            .flat_map(|r| r.frames.iter().map(|f| (f.slot, f.sender, f.nominal)))
            .collect()
    };
    // Nothing random: the seed changes nothing.
    assert_eq!(with(0.0, Jitter::None, 1), with(0.0, Jitter::None, 2));
    // Jitter only: the same sends, other deliveries.
    let j = Jitter::Exponential {
        mean: SimTime(5 * US),
    };
    let (a, b) = (with(0.0, j, 1), with(0.0, j, 2));
    assert_eq!(starts(&a), starts(&b));
    assert_ne!(deliveries(&a), deliveries(&b));
    // Drift only: the same schedule, other send times.
    let (c, d) = (with(500.0, Jitter::None, 1), with(500.0, Jitter::None, 2));
    assert_eq!(nominal(&c), nominal(&d));
    assert_ne!(starts(&c), starts(&d));
    // Adding jitter does not move the drift's draws.
    assert_eq!(starts(&c), starts(&with(500.0, j, 1)));
}

#[test]
fn bad_lists_are_rejected_when_built_and_when_decided() {
    let cfg = tight(0.0, 0);
    let list = list_for(&cfg, &requests(MS, MS));
    // 11 floats = 98 bytes = 98 µs: longer than the 90 µs usable.
    let msg = TdmaNetwork::new(cfg.clone(), 1, frames(10, 11), 2, list.clone()).unwrap_err();
    assert!(
        msg.to_string().contains("node 1 on channel 0: 98 bytes"),
        "{msg}"
    );
    let mut net = TdmaNetwork::new(cfg, 1, frames(10, 10), 2, list).unwrap();
    let bad = SlotList::from_entries([super::layout::SlotEntry {
        sender: 9,
        channel: 0,
    }]);
    let msg = net.decide(SimTime::ZERO, bad).unwrap_err().to_string();
    assert_eq!(
        msg,
        "slot_list[0].sender: unknown node 9 (nodes are 0 (server) to 4)"
    );
    assert_eq!(net.lists().pending_version(), None);
}

#[test]
fn a_network_saved_mid_run_resumes_identically() {
    let mut cfg = tight(3000.0, 2 * US);
    cfg.random_walk_ppm = 5.0;
    cfg.jitter = Jitter::Uniform {
        max: SimTime(3 * US),
    };
    let list = list_for(&cfg, &requests(MS, MS));
    let mut net = TdmaNetwork::new(cfg, 5, frames(10, 10), 2, list).unwrap();
    run(&mut net, 7);
    net.decide(
        SimTime(14 * MS),
        list_for(net.config(), &requests(2 * MS, MS)),
    )
    .unwrap();
    net.run_cycle();
    let saved = serde_json::to_string(&net).unwrap();
    let mut back: TdmaNetwork = serde_json::from_str(&saved).unwrap();
    assert_eq!(back, net);
    assert_eq!(run(&mut back, 20), run(&mut net, 20));
}
