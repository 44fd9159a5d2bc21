//! Frame sizes and transmission times: a frame is a header plus 8 bytes per `f64`
//! carried; one frame per (sender, channel) carries that sender's data for every route
//! of the channel (the medium is a broadcast bus, every receiver hears it).

use std::collections::BTreeMap;

pub use super::config::transmission_time;
use super::config::TdmaConfig;
use super::tdma_node;
use crate::network::route::Route;
use crate::network::Channel;
use crate::scenario::model::{Coupling, DataKind};

/// Bytes per `f64` on the wire.
pub const BYTES_PER_FLOAT: u64 = 8;

/// Bytes per entry of a broadcast slot list (a `u16` sender and a `u16` channel).
pub const LIST_ENTRY_BYTES: u64 = 4;

/// Size of a frame carrying `floats` values [B].
pub fn frame_bytes(floats: usize, header_bytes: u64) -> u64 {
    header_bytes.saturating_add((floats as u64).saturating_mul(BYTES_PER_FLOAT))
}

/// Size of a server static frame carrying `entries` slot-list entries [B].
pub fn list_broadcast_bytes(entries: usize, header_bytes: u64) -> u64 {
    header_bytes.saturating_add((entries as u64).saturating_mul(LIST_ENTRY_BYTES))
}

/// Most bytes a static frame is ever counted to carry: more than a slot list of every
/// (sender, channel) pair of `u16` ids needs (2³² entries of [`LIST_ENTRY_BYTES`]).
/// A faster link changes nothing past it, so the search below stops there.
pub const MAX_FRAGMENT_BYTES: u64 = 1 << 40;

/// Slot-list entries one static frame can carry at most: `None` for any number (an
/// instantaneous link), `Some(0)` when not even one fits beside the header.
///
/// The largest byte count whose [`transmission_time`] fits the usable slot, found by
/// bisection over `[0, MAX_FRAGMENT_BYTES]` (transmission time does not decrease with
/// bytes): at most 41 probes whatever the rate. (Stepping from the rate's estimate
/// wrapped `u64::MAX + 1` at rates of 10²⁵ bit/s and beyond and never ended.)
pub fn entries_per_fragment(cfg: &TdmaConfig) -> Option<usize> {
    if cfg.link_rate.is_infinite() {
        return None;
    }
    let usable = cfg.usable();
    let fits = |b: u64| transmission_time(b, cfg.link_rate) <= usable;
    // Invariant: fits(lo) (0 bytes take no time), and hi + 1 does not fit or hi is the cap.
    let (mut lo, mut hi) = (0u64, MAX_FRAGMENT_BYTES);
    if fits(hi) {
        lo = hi;
    }
    while lo < hi {
        let mid = lo + (hi - lo).div_ceil(2);
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    let entries = lo.saturating_sub(cfg.header_bytes) / LIST_ENTRY_BYTES;
    Some(usize::try_from(entries).unwrap_or(usize::MAX))
}

/// Number of static frames (one per cycle) a list of `entries` entries takes to
/// broadcast, with `per` entries per frame (see [`entries_per_fragment`]); at least one.
pub fn broadcast_fragments(entries: usize, per: Option<usize>) -> usize {
    match per {
        Some(per) if per > 0 => entries.div_ceil(per).max(1),
        _ => 1,
    }
}

/// Number of `f64` values of a sender's momentum account (`partition::momentum`),
/// carried once per frame under a predicting coupling.
pub const MOMENTUM_FLOATS: usize = 3;

/// Number of `f64` values a route puts on the wire per transfer (the same counts as
/// [`crate::network::Payload::floats`]).
/// A state is position, velocity and the owner-side force (9 values; 19 with
/// orientation, angular velocity and torque); a force is 3 values (6 with the torque);
/// a coupling that sends rates adds one rate per force and torque value and, on a
/// force, the impulse on the sender's ghost (three values), and the `passive` one its
/// energy report (one value). Such a coupling's frame also carries its sender's
/// momentum account once ([`MOMENTUM_FLOATS`]). Where it sends step rates
/// ([`WireExtras::step_rates`]) a force or state adds one more per force and torque
/// value, and where ghosts carry reactions ([`WireExtras::reactions`]) a state adds the
/// reaction stiffness ([`REACTION_FLOATS`]).
pub fn floats_per_route(
    kind: DataKind,
    rigid: bool,
    coupling: Coupling,
    extras: WireExtras,
    lines: usize,
) -> usize {
    // A transmission line's sample: wave and window length, and on a force route the
    // anchor's position and velocity (a state route's receiver has them from the state
    // it carries: the same values).
    // A predicting coupling: a force also carries the impulse the sender's links put on
    // its ghost (three values, `partition::momentum`).
    let impulse = if coupling.predicts() { 3 } else { 0 };
    if kind == DataKind::Force && lines > 0 {
        // Under a predicting coupling with the owner end's impulse.
        return 8 + impulse;
    }
    // An FMU connection carries its one value.
    if kind == DataKind::Signal {
        return 1;
    }
    let loads = if rigid { 6 } else { 3 };
    let base = match (kind, rigid) {
        (DataKind::State, false) => 9,
        (DataKind::State, true) => 19,
        (DataKind::Force, false) => 3,
        (DataKind::Force, true) => 6,
        (DataKind::Signal, _) => 1,
    };
    let rates = match (coupling.predicts(), extras.step_rates) {
        (false, _) => 0,
        (true, false) => loads,
        (true, true) => 2 * loads,
    };
    let energy = usize::from(coupling.tank().is_some());
    let impulse = if kind == DataKind::Force { impulse } else { 0 };
    let reaction = if kind == DataKind::State && extras.reactions {
        REACTION_FLOATS
    } else {
        0
    };
    base + rates + energy + impulse + reaction + lines * 2
}

/// What a scene's border messages carry beyond its coupling's own values.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WireExtras {
    /// Exact multipliers' slopes as step rates (`Scenario::slopes_multipliers`).
    pub step_rates: bool,
    /// A ghost's reaction stiffness with its state (`Scenario::ghosts_carry_reactions`).
    pub reactions: bool,
}

/// The values of a reaction stiffness on the wire: a symmetric 6 × 6 matrix.
pub const REACTION_FLOATS: usize = 21;

/// The sending TDMA nodes of each channel (sorted, without repeats), from its routes.
pub fn senders(channels: &[Channel]) -> Vec<Vec<usize>> {
    channels
        .iter()
        .map(|ch| {
            let mut s: Vec<usize> = ch.routes.iter().map(|r| tdma_node(r.from)).collect();
            s.sort_unstable();
            s.dedup();
            s
        })
        .collect()
}

/// The size of every (sender, channel) frame [B]; a pair that carries nothing sends a
/// bare header.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(into = "FrameSizesFile", from = "FrameSizesFile")]
pub struct FrameSizes {
    header: u64,
    bytes: BTreeMap<(usize, usize), u64>,
}

/// How [`FrameSizes`] is saved: JSON maps need string keys, so pairs go in a list.
#[derive(serde::Serialize, serde::Deserialize)]
struct FrameSizesFile {
    header: u64,
    frames: Vec<(usize, usize, u64)>,
}

impl From<FrameSizes> for FrameSizesFile {
    fn from(f: FrameSizes) -> FrameSizesFile {
        FrameSizesFile {
            header: f.header,
            frames: f.bytes.into_iter().map(|((s, c), b)| (s, c, b)).collect(),
        }
    }
}

impl From<FrameSizesFile> for FrameSizes {
    fn from(f: FrameSizesFile) -> FrameSizes {
        FrameSizes {
            header: f.header,
            bytes: f.frames.into_iter().map(|(s, c, b)| ((s, c), b)).collect(),
        }
    }
}

impl FrameSizes {
    /// No data yet: every frame is a bare header.
    pub fn new(header_bytes: u64) -> FrameSizes {
        FrameSizes {
            header: header_bytes,
            bytes: BTreeMap::new(),
        }
    }

    /// The frames of a scene's channels: each route adds [`floats_per_route`] values
    /// to the frame of its sender (TDMA node) on its channel, and a predicting
    /// coupling's frame its sender's momentum account ([`MOMENTUM_FLOATS`]).
    pub fn from_channels(
        channels: &[Channel],
        (rigid, coupling, extras): (bool, Coupling, WireExtras),
        header_bytes: u64,
        lines: &dyn Fn(&Route) -> usize,
    ) -> FrameSizes {
        let mut floats: BTreeMap<(usize, usize), usize> = BTreeMap::new();
        for (c, ch) in channels.iter().enumerate() {
            for r in &ch.routes {
                *floats.entry((tdma_node(r.from), c)).or_default() +=
                    floats_per_route(r.kind, rigid, coupling, extras, lines(r));
            }
        }
        let account = if coupling.predicts() {
            MOMENTUM_FLOATS
        } else {
            0
        };
        let mut sizes = FrameSizes::new(header_bytes);
        for ((sender, channel), n) in floats {
            sizes.set(sender, channel, n + account);
        }
        sizes
    }

    /// Sets the frame of `sender` on `channel` to carry `floats` values.
    pub fn set(&mut self, sender: usize, channel: usize, floats: usize) {
        self.bytes
            .insert((sender, channel), frame_bytes(floats, self.header));
    }

    /// Header size [B].
    pub fn header(&self) -> u64 {
        self.header
    }

    /// Size of `sender`'s frame on `channel` [B].
    pub fn bytes(&self, sender: usize, channel: usize) -> u64 {
        self.bytes
            .get(&(sender, channel))
            .copied()
            .unwrap_or(self.header)
    }

    /// Every (sender, channel) pair with data, with its size [B], in order.
    pub fn iter(&self) -> impl Iterator<Item = ((usize, usize), u64)> + '_ {
        self.bytes.iter().map(|(&k, &v)| (k, v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::SimTime;

    #[test]
    fn frame_is_header_plus_eight_bytes_per_float() {
        assert_eq!(frame_bytes(9, 16), 88);
        assert_eq!(list_broadcast_bytes(10, 16), 56);
    }

    #[test]
    fn long_lists_are_broadcast_in_fragments() {
        let mut cfg = TdmaConfig::new(2, SimTime(100_000), SimTime(1_000_000));
        cfg.guard = SimTime(10_000);
        cfg.link_rate = 10e6; // 90 µs = 112.5 bytes: 112 fit
        cfg.header_bytes = 16;
        assert_eq!(entries_per_fragment(&cfg), Some(24));
        assert_eq!(broadcast_fragments(0, Some(24)), 1);
        assert_eq!(broadcast_fragments(24, Some(24)), 1);
        assert_eq!(broadcast_fragments(25, Some(24)), 2);
        cfg.header_bytes = 110;
        assert_eq!(entries_per_fragment(&cfg), Some(0));
        cfg.link_rate = f64::INFINITY;
        assert_eq!(entries_per_fragment(&cfg), None);
        assert_eq!(broadcast_fragments(1000, None), 1);
    }

    /// Rates up to the largest finite `f64` give a count at once (a rate of 10²⁵ bit/s
    /// and beyond once wrapped a `u64` and spun forever), never fewer entries at a
    /// faster rate, and what fits is exactly what the transmission time allows.
    #[test]
    fn every_finite_rate_gives_a_fragment_size() {
        use proptest::prelude::*;
        let mut runner = proptest::test_runner::TestRunner::new(ProptestConfig::with_cases(512));
        let rates = (0i32..309, 1.0f64..10.0).prop_map(|(e, m)| (m * 10f64.powi(e)).min(f64::MAX));
        runner
            .run(
                &(rates, 1u64..1_000_000, 0u64..200),
                |(rate, usable_ns, header)| {
                    let mut cfg =
                        TdmaConfig::new(2, SimTime(usable_ns + 1), SimTime(1_000_000_000));
                    cfg.guard = SimTime(1);
                    cfg.header_bytes = header;
                    cfg.link_rate = rate;
                    let n = entries_per_fragment(&cfg).expect("a finite rate") as u64;
                    let bytes = header + n * LIST_ENTRY_BYTES;
                    if n > 0 {
                        prop_assert!(transmission_time(bytes, rate) <= cfg.usable());
                    }
                    // One entry more does not fit (below the cap).
                    let more = header + (n + 1) * LIST_ENTRY_BYTES;
                    if more <= MAX_FRAGMENT_BYTES {
                        prop_assert!(transmission_time(more, rate) > cfg.usable());
                    }
                    cfg.link_rate = (rate * 2.0).min(f64::MAX);
                    prop_assert!(entries_per_fragment(&cfg).expect("finite") as u64 >= n);
                    Ok(())
                },
            )
            .unwrap();
        let mut cfg = TdmaConfig::new(2, SimTime(100_000), SimTime(1_000_000));
        cfg.link_rate = 1e25;
        assert_eq!(
            entries_per_fragment(&cfg),
            Some(
                usize::try_from((MAX_FRAGMENT_BYTES - cfg.header_bytes) / LIST_ENTRY_BYTES)
                    .unwrap()
            )
        );
    }

    #[test]
    fn float_counts_are_the_values_each_payload_carries() {
        // p, v, force (3 each); rigid adds q (4), ω, torque (3 each); rates one per
        // force or torque component.
        let x = SimTime(10_000_000);
        let (r, p, e) = (
            Coupling::Reset,
            Coupling::Predict { extrapolate: x },
            Coupling::Passive {
                tank: crate::scenario::model::Tank::Fixed(1.0),
                extrapolate: x,
                lines: crate::scenario::model::Lines {
                    above: SimTime(u64::MAX),
                    impedance: None,
                },
            },
        );
        assert_eq!(
            floats_per_route(DataKind::State, false, r, WireExtras::default(), 0),
            9
        );
        assert_eq!(
            floats_per_route(DataKind::State, true, r, WireExtras::default(), 0),
            19
        );
        assert_eq!(
            floats_per_route(DataKind::Force, false, r, WireExtras::default(), 0),
            3
        );
        assert_eq!(
            floats_per_route(DataKind::Force, true, r, WireExtras::default(), 0),
            6
        );
        // A predicting coupling's force also carries the impulse on the sender's ghost
        // (3 values).
        assert_eq!(
            floats_per_route(DataKind::State, false, p, WireExtras::default(), 0),
            12
        );
        assert_eq!(
            floats_per_route(DataKind::State, true, p, WireExtras::default(), 0),
            25
        );
        assert_eq!(
            floats_per_route(DataKind::Force, false, p, WireExtras::default(), 0),
            9
        );
        assert_eq!(
            floats_per_route(DataKind::Force, true, p, WireExtras::default(), 0),
            15
        );
        assert_eq!(
            floats_per_route(DataKind::State, false, e, WireExtras::default(), 0),
            13
        );
        assert_eq!(
            floats_per_route(DataKind::Force, true, e, WireExtras::default(), 0),
            16
        );
        // A line: 2 values more per line on a state route; its own sample (and the
        // owner end's impulse) on a force route.
        assert_eq!(
            floats_per_route(DataKind::State, false, e, WireExtras::default(), 2),
            17
        );
        assert_eq!(
            floats_per_route(DataKind::Force, false, e, WireExtras::default(), 1),
            11
        );
        assert_eq!(
            floats_per_route(DataKind::Force, false, r, WireExtras::default(), 1),
            8
        );
        // Exact multipliers' step rates: one more per force and torque value where the
        // coupling sends rates, none where it does not.
        let steps = WireExtras {
            step_rates: true,
            reactions: false,
        };
        assert_eq!(floats_per_route(DataKind::Force, true, p, steps, 0), 21);
        assert_eq!(floats_per_route(DataKind::State, true, p, steps, 0), 31);
        assert_eq!(floats_per_route(DataKind::Force, true, r, steps, 0), 6);
        // A ghost's reaction stiffness rides its state, not a force.
        let both = WireExtras {
            step_rates: true,
            reactions: true,
        };
        assert_eq!(floats_per_route(DataKind::State, true, p, both, 0), 52);
        assert_eq!(floats_per_route(DataKind::Force, true, p, both, 0), 21);
    }

    #[test]
    fn pairs_without_data_send_a_header() {
        let mut f = FrameSizes::new(16);
        f.set(2, 0, 18);
        assert_eq!(f.bytes(2, 0), 16 + 144);
        assert_eq!(f.bytes(1, 0), 16);
        assert_eq!(f.iter().collect::<Vec<_>>(), vec![((2, 0), 160)]);
    }
}
