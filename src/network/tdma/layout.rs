//! The cycle layout (which slot is what, and when it starts) and the slot list that
//! fills the dynamic part.
//!
//! ```text
//!  cycle k, starting at k·cycle
//!  ┌──────┬────────┬─────────┬─────┬──────────┬─────────┬─────────┬─────┬───────────┐
//!  │ sync │ stat 0 │ stat 1  │ ... │ stat n   │ dyn 0   │ dyn 1   │ ... │ dyn K − 1 │
//!  │  (0) │ server │ client 1│     │ client n │ list[0] │ list[1] │     │ list[K−1] │
//!  └──────┴────────┴─────────┴─────┴──────────┴─────────┴─────────┴─────┴───────────┘
//!  slot s starts at k·cycle + s·slot; each slot ends with `guard` of silence;
//!  list entries may be idle, and slots past the end of the list are idle
//! ```

use super::config::TdmaConfig;
use super::error::TdmaError;
use super::frame::{entries_per_fragment, list_broadcast_bytes, transmission_time, FrameSizes};
use crate::kernel::SimTime;
pub use crate::scenario::model::tdma::{SlotEntry, SlotList};

impl SlotList {
    /// A list with no idle slot in between.
    pub fn from_entries(entries: impl IntoIterator<Item = SlotEntry>) -> SlotList {
        SlotList {
            entries: entries.into_iter().map(Some).collect(),
        }
    }

    /// Number of entries (idle ones included).
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the list is empty.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The entry of dynamic slot `j`, if it sends.
    pub fn get(&self, j: usize) -> Option<SlotEntry> {
        self.entries.get(j).copied().flatten()
    }

    /// Dynamic slots (ascending) where `sender` sends `channel`.
    pub fn positions(&self, sender: usize, channel: usize) -> Vec<usize> {
        let want = SlotEntry { sender, channel };
        (0..self.entries.len())
            .filter(|&j| self.entries[j] == Some(want))
            .collect()
    }

    /// Checks the list against the cycle and the scene: it fits the dynamic part, and
    /// names existing nodes and channels.
    pub fn validate(&self, layout: &CycleLayout, channels: usize) -> Result<(), TdmaError> {
        if self.len() > layout.capacity() {
            return Err(TdmaError::CycleTooShort {
                len: self.len(),
                capacity: layout.capacity(),
                cycle: layout.cycle_len(),
                slot: layout.slot_len(),
                statics: layout.clients() + 1,
            });
        }
        for (index, e) in self.entries.iter().enumerate() {
            let Some(e) = e else { continue };
            if e.sender > layout.clients() {
                return Err(TdmaError::UnknownNode {
                    index,
                    node: e.sender,
                    max: layout.clients(),
                });
            }
            if e.channel >= channels {
                return Err(TdmaError::UnknownChannel {
                    index,
                    channel: e.channel,
                    channels,
                });
            }
        }
        Ok(())
    }

    /// Checks that every frame the list sends fits the usable part of a slot (`slot −
    /// guard`), and that a static frame can carry at least one entry of its broadcast
    /// (a longer list is broadcast in fragments, see [`super::confirm`]).
    pub fn check_frames(&self, cfg: &TdmaConfig, frames: &FrameSizes) -> Result<(), TdmaError> {
        let too_long = |what: String, bytes: u64| {
            let needed = transmission_time(bytes, cfg.link_rate);
            (needed > cfg.usable()).then_some(TdmaError::FrameTooLong {
                what,
                bytes,
                needed,
                slot: cfg.slot,
                guard: cfg.guard,
            })
        };
        if !self.is_empty() && entries_per_fragment(cfg) == Some(0) {
            let bytes = list_broadcast_bytes(1, cfg.header_bytes);
            if let Some(e) = too_long("broadcast of one slot-list entry".into(), bytes) {
                return Err(e);
            }
        }
        for e in self.entries.iter().flatten() {
            let bytes = frames.bytes(e.sender, e.channel);
            if let Some(err) =
                too_long(format!("node {} on channel {}", e.sender, e.channel), bytes)
            {
                return Err(err);
            }
        }
        Ok(())
    }
}

/// What a slot of the cycle is for.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum SlotKind {
    /// The server's sync frame (slot 0).
    Sync,
    /// A node's static slot (protocol traffic: list broadcast, confirmations).
    Static {
        /// The node (0 = server).
        node: usize,
    },
    /// Dynamic slot `index`, following slot-list entry `index`.
    Dynamic {
        /// Index in the slot list.
        index: usize,
    },
}

/// The slot geometry of a validated configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct CycleLayout {
    slot: SimTime,
    cycle: SimTime,
    clients: usize,
    slots: usize,
}

impl CycleLayout {
    /// The layout of `cfg` (validated here).
    pub fn new(cfg: &TdmaConfig) -> Result<CycleLayout, TdmaError> {
        cfg.validate()?;
        Ok(CycleLayout {
            slot: cfg.slot,
            cycle: cfg.cycle,
            clients: cfg.clients,
            slots: usize::try_from(cfg.cycle.0 / cfg.slot.0).unwrap_or(usize::MAX),
        })
    }

    /// Cycle length.
    pub fn cycle_len(&self) -> SimTime {
        self.cycle
    }

    /// Slot length.
    pub fn slot_len(&self) -> SimTime {
        self.slot
    }

    /// Number of clients.
    pub fn clients(&self) -> usize {
        self.clients
    }

    /// Slots per cycle (sync, static and dynamic).
    pub fn slots(&self) -> usize {
        self.slots
    }

    /// Index of the first dynamic slot (`clients + 2`).
    pub fn first_dynamic(&self) -> usize {
        self.clients + 2
    }

    /// Dynamic slots per cycle: the longest list the cycle holds.
    pub fn capacity(&self) -> usize {
        self.slots - self.first_dynamic()
    }

    /// The static slot of `node`.
    pub fn static_slot(&self, node: usize) -> usize {
        1 + node
    }

    /// The slot index of dynamic slot `j`.
    pub fn dynamic_slot(&self, j: usize) -> usize {
        self.first_dynamic() + j
    }

    /// What slot `s` is for (`None` past the last slot).
    pub fn kind(&self, s: usize) -> Option<SlotKind> {
        match s {
            0 => Some(SlotKind::Sync),
            s if s < self.first_dynamic() => Some(SlotKind::Static { node: s - 1 }),
            s if s < self.slots => Some(SlotKind::Dynamic {
                index: s - self.first_dynamic(),
            }),
            _ => None,
        }
    }

    /// The entry a slot follows in `list` (only dynamic slots with a sending entry).
    pub fn entry(&self, list: &SlotList, s: usize) -> Option<SlotEntry> {
        match self.kind(s)? {
            SlotKind::Dynamic { index } => list.get(index),
            _ => None,
        }
    }

    /// Start of slot `s` from the start of its cycle.
    pub fn offset(&self, s: usize) -> SimTime {
        SimTime(self.slot.0 * s as u64)
    }

    /// Nominal (server-clock) start of cycle `k`; `None` past the range of time.
    pub fn cycle_start(&self, k: u64) -> Option<SimTime> {
        self.cycle.checked_mul(k)
    }

    /// Nominal start of slot `s` of cycle `k`; `None` for a slot past the cycle's last
    /// or past the range of time.
    pub fn slot_start(&self, k: u64, s: usize) -> Option<SimTime> {
        if s >= self.slots {
            return None;
        }
        self.cycle_start(k)?.checked_add(self.offset(s))
    }

    /// The cycle and slot a nominal time falls in.
    pub fn locate(&self, t: SimTime) -> (u64, usize) {
        let k = t.0 / self.cycle.0;
        let s = usize::try_from((t.0 % self.cycle.0) / self.slot.0).unwrap_or(usize::MAX);
        (k, s)
    }

    /// The shortest possible gap across a cycle boundary: from the last dynamic slot of
    /// one cycle to the first of the next (the sync and static part lie in between). No
    /// channel's period can be below it.
    pub fn min_wrap_gap(&self) -> SimTime {
        let span = self.slot.0 * self.capacity().saturating_sub(1) as u64;
        SimTime(self.cycle.0 - span)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout() -> CycleLayout {
        // 2 clients, 1 ms slots, 10 ms cycle: sync, 3 static, 6 dynamic.
        CycleLayout::new(&TdmaConfig::new(2, SimTime(1_000_000), SimTime(10_000_000))).unwrap()
    }

    #[test]
    fn slots_are_sync_static_dynamic_then_idle() {
        let l = layout();
        assert_eq!((l.slots(), l.first_dynamic(), l.capacity()), (10, 4, 6));
        assert_eq!(l.kind(0), Some(SlotKind::Sync));
        assert_eq!(l.kind(1), Some(SlotKind::Static { node: 0 }));
        assert_eq!(l.kind(3), Some(SlotKind::Static { node: 2 }));
        assert_eq!(l.kind(4), Some(SlotKind::Dynamic { index: 0 }));
        assert_eq!(l.kind(9), Some(SlotKind::Dynamic { index: 5 }));
        assert_eq!(l.kind(10), None);
        assert_eq!(l.static_slot(2), 3);
        assert_eq!(l.dynamic_slot(1), 5);
    }

    #[test]
    fn slot_starts_and_locate_agree() {
        let l = layout();
        assert_eq!(l.slot_start(0, 0), Some(SimTime::ZERO));
        assert_eq!(l.slot_start(2, 5), Some(SimTime(25_000_000)));
        assert_eq!(l.slot_start(2, 10), None);
        assert_eq!(l.locate(SimTime(25_999_999)), (2, 5));
        assert_eq!(l.locate(SimTime(9_000_000)), (0, 9));
        // Last dynamic slot starts at 9 ms; next cycle's first at 14 ms.
        assert_eq!(l.min_wrap_gap(), SimTime(5_000_000));
    }

    #[test]
    fn entries_map_to_dynamic_slots() {
        let l = layout();
        let list = SlotList {
            entries: vec![
                Some(SlotEntry {
                    sender: 1,
                    channel: 0,
                }),
                None,
            ],
        };
        assert_eq!(
            l.entry(&list, 4),
            Some(SlotEntry {
                sender: 1,
                channel: 0
            })
        );
        assert_eq!(l.entry(&list, 5), None);
        assert_eq!(l.entry(&list, 6), None);
        assert_eq!(l.entry(&list, 1), None);
        assert_eq!(list.positions(1, 0), vec![0]);
    }

    #[test]
    fn bad_lists_name_the_field() {
        let l = layout();
        let e = |sender, channel| SlotEntry { sender, channel };
        let long = SlotList::from_entries(vec![e(1, 0); 7]);
        let msg = long.validate(&l, 1).unwrap_err().to_string();
        assert!(msg.starts_with("slot_list: 7 entries do not fit"), "{msg}");
        let unknown = SlotList::from_entries([e(1, 0), e(3, 0)]);
        let msg = unknown.validate(&l, 1).unwrap_err().to_string();
        assert_eq!(
            msg,
            "slot_list[1].sender: unknown node 3 (nodes are 0 (server) to 2)"
        );
        let bad_channel = SlotList::from_entries([e(1, 2)]);
        let msg = bad_channel.validate(&l, 2).unwrap_err().to_string();
        assert!(
            msg.starts_with("slot_list[0].channel: unknown channel 2"),
            "{msg}"
        );
        assert_eq!(
            SlotList::from_entries(vec![e(2, 1); 6]).validate(&l, 2),
            Ok(())
        );
    }

    #[test]
    fn a_frame_longer_than_the_slot_is_rejected() {
        let mut cfg = TdmaConfig::new(2, SimTime(100_000), SimTime(10_000_000));
        cfg.guard = SimTime(10_000);
        cfg.link_rate = 10e6; // 90 µs usable = 112.5 bytes
        cfg.header_bytes = 16;
        let mut frames = FrameSizes::new(16);
        frames.set(1, 0, 12); // 112 bytes: fits
        frames.set(2, 0, 13); // 120 bytes: does not
        let e = |sender| SlotEntry { sender, channel: 0 };
        assert_eq!(
            SlotList::from_entries([e(1)]).check_frames(&cfg, &frames),
            Ok(())
        );
        let msg = SlotList::from_entries([e(1), e(2)])
            .check_frames(&cfg, &frames)
            .unwrap_err()
            .to_string();
        assert!(
            msg.starts_with("slot: 0.000100000 s minus the guard"),
            "{msg}"
        );
        assert!(msg.contains("node 2 on channel 0: 120 bytes"), "{msg}");
        // Any list can be broadcast in fragments, unless not one entry fits.
        assert_eq!(
            SlotList::from_entries(vec![e(1); 100]).check_frames(&cfg, &frames),
            Ok(())
        );
        cfg.header_bytes = 110;
        let msg = SlotList::from_entries([e(1)])
            .check_frames(&cfg, &FrameSizes::new(110))
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("broadcast of one slot-list entry: 114 bytes"),
            "{msg}"
        );
    }
}
