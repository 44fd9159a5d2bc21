use super::*;
use crate::network::tdma::config::TdmaConfig;
use proptest::prelude::*;

const US: u64 = 1_000;
const MS: u64 = 1_000_000;

fn layout(clients: usize, slot: u64, cycle: u64) -> CycleLayout {
    CycleLayout::new(&TdmaConfig::new(clients, SimTime(slot), SimTime(cycle))).unwrap()
}

fn req(tau: u64, senders: &[usize]) -> ChannelRequest {
    ChannelRequest {
        tau: SimTime(tau),
        senders: senders.to_vec(),
    }
}

#[test]
fn a_list_realizes_the_requested_rates_within_one_slot() {
    // 4 clients, 100 µs slots, 5 ms cycle: 44 dynamic slots.
    let l = layout(4, 100 * US, 5 * MS);
    let reqs = [
        req(MS, &[1, 2]),
        req(2500 * US, &[3, 4]),
        req(1230 * US, &[1]),
        req(700 * US, &[2]),
    ];
    let s = schedule(&l, &reqs).unwrap();
    s.list.validate(&l, reqs.len()).unwrap();
    for (c, r) in reqs.iter().enumerate() {
        let a = s.achieved[c].unwrap();
        assert!(
            r.tau <= a && a.0 < r.tau.0 + 100 * US,
            "channel {c}: requested {} achieved {a}",
            r.tau
        );
        for &sender in &r.senders {
            assert!(
                pair_period(&l, &s.list, sender, c).unwrap() <= a,
                "channel {c} sender {sender}"
            );
        }
    }
    assert_eq!(
        s.achieved[2],
        Some(SimTime(1300 * US)),
        "1.23 ms rounds up to 13 slots"
    );
    assert_eq!(s.requested[1], SimTime(2500 * US));
}

#[test]
fn periods_dividing_the_cycle_are_met_exactly_and_interleave() {
    let l = layout(2, 100 * US, 4 * MS);
    let s = schedule(&l, &[req(MS, &[1]), req(MS, &[2])]).unwrap();
    assert_eq!(s.achieved, vec![Some(SimTime(MS)); 2]);
    let e = |sender, channel| Some(SlotEntry { sender, channel });
    assert_eq!(&s.list.entries[..2], &[e(1, 0), e(2, 1)], "A B, not A A");
    assert_eq!(s.list.positions(1, 0), vec![0, 10, 20, 30]);
    assert_eq!(s.list.positions(2, 1), vec![1, 11, 21, 31]);
}

#[test]
fn a_period_beyond_the_cycle_is_served_once_per_cycle() {
    let l = layout(1, 100 * US, 2 * MS);
    let s = schedule(&l, &[req(5 * MS, &[1])]).unwrap();
    assert_eq!(s.list.positions(1, 0).len(), 1);
    assert_eq!(s.achieved, vec![Some(SimTime(2 * MS))]);
}

#[test]
fn a_channel_without_senders_takes_no_slot() {
    let l = layout(1, 100 * US, 2 * MS);
    let s = schedule(&l, &[req(MS, &[]), req(MS, &[1])]).unwrap();
    assert_eq!(s.achieved, vec![None, Some(SimTime(MS))]);
    assert_eq!(s.list.entries.iter().flatten().count(), 2);
}

#[test]
fn bad_requests_give_clear_errors() {
    let l = layout(1, 100 * US, MS); // 7 dynamic slots, min wrap 400 µs
    let msg = |r: &[ChannelRequest]| schedule(&l, r).unwrap_err().to_string();
    assert_eq!(
        msg(&[req(0, &[1])]),
        "tau[0]: the requested period must be > 0"
    );
    assert!(msg(&[req(MS, &[1]), req(300 * US, &[1])]).starts_with(
        "tau[1]: requested 0.000300000 s is below 0.000400000 s, the shortest period"
    ));
    assert_eq!(
        msg(&[req(400 * US, &[0, 1]), req(500 * US, &[1])]),
        "tau: the requested periods need 8 dynamic slots per cycle, the cycle has 7"
    );
    // Two pairs needing slots 0 and 6 (the only way to keep the wrap gap within 4
    // slots): the count fits, the placement cannot.
    let e = schedule(&l, &[req(400 * US, &[1]), req(400 * US, &[1])]).unwrap_err();
    assert!(
        matches!(
            e,
            TdmaError::Unschedulable {
                channel: 1,
                sender: 1,
                free: 4,
                ..
            }
        ),
        "{e}"
    );
    assert!(
        e.to_string()
            .starts_with("tau[1]: no placement of node 1's slots"),
        "{e}"
    );
}

#[test]
fn explicit_lists_report_their_achieved_periods() {
    // 1 client, 1 ms slots, 10 ms cycle: dynamic slots 3..=9 (7 of them).
    let l = layout(1, MS, 10 * MS);
    let e = |sender, channel| Some(SlotEntry { sender, channel });
    let list = SlotList {
        entries: vec![e(1, 0), e(1, 1), None, e(1, 0), e(0, 1), e(1, 0)],
    };
    list.validate(&l, 2).unwrap();
    // Channel 0 by node 1 at 0, 3, 5: gaps 3, 2 and 10 − 5 = 5 ms.
    assert_eq!(pair_period(&l, &list, 1, 0), Some(SimTime(5 * MS)));
    // Channel 1 by node 1 once (cycle), by node 0 once: worst is the cycle.
    let senders = vec![vec![1], vec![0, 1]];
    assert_eq!(
        achieved_periods(&l, &list, &senders),
        vec![Some(SimTime(5 * MS)), Some(SimTime(10 * MS))]
    );
    // A sender that holds no slot never delivers.
    assert_eq!(achieved_periods(&l, &list, &[vec![0, 1]]), vec![None]);
}

/// A random geometry and request set whose minimal slot count fits comfortably.
fn feasible() -> impl Strategy<Value = (CycleLayout, Vec<ChannelRequest>)> {
    (1usize..6, 50u64..200, 20usize..120).prop_flat_map(|(clients, slot_us, slots)| {
        let slot = slot_us * US;
        let slots = slots.max(clients + 4);
        let l = layout(clients, slot, slot * slots as u64);
        let lo = l.min_wrap_gap().0;
        let hi = 2 * l.cycle_len().0;
        let channel = (lo..=hi, proptest::collection::btree_set(0..=clients, 1..=2))
            .prop_map(|(tau, s)| req(tau, &s.into_iter().collect::<Vec<_>>()));
        (Just(l), proptest::collection::vec(channel, 1..4)).prop_filter(
            "load at most a third",
            |(l, reqs)| {
                let slot = l.slot_len().0;
                let need: u64 = reqs
                    .iter()
                    .map(|r| {
                        let g = r.tau.0.div_ceil(slot) * slot;
                        l.cycle_len().0.div_ceil(g.min(l.cycle_len().0)) * r.senders.len() as u64
                    })
                    .sum();
                3 * need <= l.capacity() as u64
            },
        )
    })
}

proptest! {
    // A fixed seed: "at least the request" is the usual outcome, not a guarantee (a
    // crowded list may force a shorter gap), so this test must not wander.
    #![proptest_config(ProptestConfig {
        cases: 400,
        rng_seed: proptest::test_runner::RngSeed::Fixed(4),
        ..ProptestConfig::default()
    })]

    /// The documented guarantee: every channel's achieved period is at most its request
    /// rounded up to whole slots (less than one slot above it); on these light loads also
    /// at least the request when it is within the cycle; the list is valid and the
    /// scheduler deterministic.
    #[test]
    fn achieved_is_within_one_slot_above_the_request((l, reqs) in feasible()) {
        let s = schedule(&l, &reqs).unwrap();
        prop_assert_eq!(&s, &schedule(&l, &reqs).unwrap());
        prop_assert!(s.list.validate(&l, reqs.len()).is_ok());
        let slot = l.slot_len().0;
        for (c, r) in reqs.iter().enumerate() {
            let a = s.achieved[c].unwrap().0;
            let bound = (r.tau.0.div_ceil(slot) * slot).min(l.cycle_len().0);
            prop_assert!(a <= bound, "channel {}: requested {} achieved {} bound {}", c, r.tau.0, a, bound);
            prop_assert!(a < r.tau.0 + slot);
            if r.tau <= l.cycle_len() {
                prop_assert!(a >= r.tau.0, "channel {}: requested {} achieved {}", c, r.tau.0, a);
            }
        }
    }

}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Any outcome is either a schedule within the bound or one of the documented errors.
    #[test]
    fn any_request_is_scheduled_within_the_bound_or_rejected(
        (l, reqs) in (1usize..4, 10usize..40).prop_flat_map(|(clients, slots)| {
            let l = layout(clients, 100 * US, 100 * US * slots.max(clients + 3) as u64);
            let channel = (1u64..=2 * l.cycle_len().0, proptest::collection::btree_set(0..=clients, 1..=3))
                .prop_map(|(tau, s)| req(tau, &s.into_iter().collect::<Vec<_>>()));
            (Just(l), proptest::collection::vec(channel, 1..5))
        })
    ) {
        match schedule(&l, &reqs) {
            Ok(s) => {
                for (c, r) in reqs.iter().enumerate() {
                    prop_assert!(s.achieved[c].unwrap().0 < r.tau.0 + 100 * US);
                }
            }
            Err(TdmaError::Infeasible { needed, available }) => prop_assert!(needed > available),
            Err(TdmaError::PeriodTooShort { requested, minimum, .. }) => prop_assert!(requested < minimum),
            Err(TdmaError::Unschedulable { .. }) => {}
            Err(e) => prop_assert!(false, "unexpected error {}", e),
        }
    }
}
