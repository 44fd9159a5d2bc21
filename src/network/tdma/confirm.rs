//! List confirmation: how a new slot list goes into force without splitting the nodes
//! between two lists.
//!
//! 1. The server decides a new list (version `v`) at time `t_d`.
//! 2. From the next cycle on, the server's static frame broadcasts `v` every cycle
//!    until it is confirmed. A list longer than one static frame holds
//!    ([`super::frame::entries_per_fragment`]) is sent in fragments, one per cycle,
//!    round-robin (fragment `(k − first) mod F` in cycle `k`).
//! 3. A client that has heard every fragment (this cycle or earlier) confirms `v` in
//!    its own static slot, which comes after the server's in the same cycle.
//! 4. Once every client's confirmation has been heard (at the end of cycle `k`), `v`
//!    is in force for every node from the start of cycle `k + 1`; the lag is
//!    `start(k + 1) − t_d`.
//!
//! A lost broadcast or confirmation (a collision) only delays step 4 to a later cycle.
//! On the shared medium a frame is heard by every node or by none (the sender knows
//! when its frame collided), so every node knows the same set of confirmations and
//! switches at the same boundary. A newer decision before step 4 replaces the pending
//! one (its confirmations start over); one taken after step 4 waits its turn.

use super::frame::broadcast_fragments;
use super::layout::SlotList;
use crate::kernel::SimTime;

/// A list that went into force.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Switch {
    /// Its version (the initial list is 0).
    pub version: u32,
    /// When the server decided it.
    pub decided_at: SimTime,
    /// First cycle that broadcast it.
    pub first_broadcast: u64,
    /// Cycle in which the last missing confirmation was heard.
    pub confirmed_in: u64,
    /// First cycle that follows it (`confirmed_in + 1`).
    pub effective_cycle: u64,
    /// Start of that cycle.
    pub effective_at: SimTime,
    /// `effective_at − decided_at`.
    pub lag: SimTime,
}

/// One static frame's part of a list broadcast.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Fragment {
    /// Version of the list.
    pub version: u32,
    /// Which fragment (0-based).
    pub index: usize,
    /// Fragments in all.
    pub of: usize,
    /// Entries it carries.
    pub entries: usize,
}

/// A decided list on its way into force.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
struct Pending {
    version: u32,
    list: SlotList,
    decided_at: SimTime,
    first_broadcast: Option<u64>,
    /// Number of fragments.
    fragments: usize,
    /// Per client (index `node − 1`), per fragment: heard.
    heard: Vec<Vec<bool>>,
    /// Per client: its confirmation was heard.
    confirmed: Vec<bool>,
}

/// The list in force and the one being confirmed.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ListSwitch {
    active: SlotList,
    version: u32,
    next_version: u32,
    pending: Option<Pending>,
    /// Confirmed, in force from `effective_cycle`.
    committed: Option<(Pending, u64)>,
    clients: usize,
    /// Entries per broadcast fragment (`None` = any number).
    per_fragment: Option<usize>,
    superseded: u64,
}

impl ListSwitch {
    /// `initial` in force from cycle 0 (version 0) for `clients` clients; a broadcast
    /// frame carries at most `per_fragment` entries (`None` = any number).
    pub fn new(initial: SlotList, clients: usize, per_fragment: Option<usize>) -> ListSwitch {
        ListSwitch {
            active: initial,
            version: 0,
            next_version: 1,
            pending: None,
            committed: None,
            clients,
            per_fragment,
            superseded: 0,
        }
    }

    /// The list in force.
    pub fn active(&self) -> &SlotList {
        &self.active
    }

    /// Its version.
    pub fn version(&self) -> u32 {
        self.version
    }

    /// Version of the list being broadcast, if any.
    pub fn pending_version(&self) -> Option<u32> {
        self.pending.as_ref().map(|p| p.version)
    }

    /// Pending lists replaced by a newer decision before they were confirmed.
    pub fn superseded(&self) -> u64 {
        self.superseded
    }

    /// The server decides `list` at `at`; returns its version.
    pub fn decide(&mut self, at: SimTime, list: SlotList) -> u32 {
        let version = self.next_version;
        self.next_version += 1;
        if self.pending.is_some() {
            self.superseded += 1;
        }
        let fragments = broadcast_fragments(list.len(), self.per_fragment);
        self.pending = Some(Pending {
            version,
            list,
            decided_at: at,
            first_broadcast: None,
            fragments,
            heard: vec![vec![false; fragments]; self.clients],
            confirmed: vec![false; self.clients],
        });
        version
    }

    /// Cycle `k` starts at `start`: a list confirmed for this boundary goes into force.
    pub fn begin_cycle(&mut self, k: u64, start: SimTime) -> Option<Switch> {
        let (_, effective) = self.committed.as_ref()?;
        if *effective != k {
            return None;
        }
        let (p, _) = self.committed.take()?;
        self.active = p.list;
        self.version = p.version;
        let first_broadcast = p.first_broadcast.unwrap_or(k);
        Some(Switch {
            version: p.version,
            decided_at: p.decided_at,
            first_broadcast,
            confirmed_in: k.saturating_sub(1),
            effective_cycle: k,
            effective_at: start,
            lag: SimTime(start.0.saturating_sub(p.decided_at.0)),
        })
    }

    /// What the server's static frame broadcasts in cycle `k`.
    pub fn broadcast(&self, k: u64) -> Option<Fragment> {
        let p = self.pending.as_ref()?;
        let since = k.saturating_sub(p.first_broadcast.unwrap_or(k));
        let index = usize::try_from(since % p.fragments as u64).unwrap_or(0);
        let per = self.per_fragment.unwrap_or(p.list.len()).max(1);
        let entries = p.list.len().saturating_sub(index * per).min(per);
        Some(Fragment {
            version: p.version,
            index,
            of: p.fragments,
            entries,
        })
    }

    /// End of cycle `k`: whether the server's broadcast was heard, and whether each
    /// client's static frame was (`static_heard[node − 1]`). Returns what each client's
    /// static frame confirmed (the pending version, if the client had heard every
    /// fragment by its slot).
    pub fn end_cycle(
        &mut self,
        k: u64,
        broadcast_heard: bool,
        static_heard: &[bool],
    ) -> Vec<Option<u32>> {
        let Some(index) = self.broadcast(k).map(|f| f.index) else {
            return vec![None; self.clients];
        };
        let Some(p) = self.pending.as_mut() else {
            return vec![None; self.clients];
        };
        p.first_broadcast.get_or_insert(k);
        let mut confirms = vec![None; self.clients];
        let clients = p.heard.iter_mut().zip(&mut p.confirmed).zip(&mut confirms);
        for (i, ((heard, confirmed), confirms)) in clients.enumerate() {
            heard[index] |= broadcast_heard;
            if heard.iter().all(|&h| h) {
                *confirms = Some(p.version);
                *confirmed |= static_heard.get(i).copied().unwrap_or(false);
            }
        }
        if p.confirmed.iter().all(|&c| c) && self.committed.is_none() {
            let done = self.pending.take();
            self.committed = done.map(|p| (p, k + 1));
        }
        confirms
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::network::tdma::layout::SlotEntry;

    fn list(sender: usize) -> SlotList {
        SlotList::from_entries([SlotEntry { sender, channel: 0 }])
    }

    #[test]
    fn a_confirmed_list_goes_into_force_at_the_next_boundary() {
        let mut s = ListSwitch::new(list(1), 3, None);
        assert_eq!(s.begin_cycle(0, SimTime(0)), None);
        assert_eq!(s.decide(SimTime(5), list(2)), 1);
        let all = Fragment {
            version: 1,
            index: 0,
            of: 1,
            entries: 1,
        };
        assert_eq!(s.broadcast(1), Some(all));
        assert_eq!(s.begin_cycle(1, SimTime(100)), None);
        let confirms = s.end_cycle(1, true, &[true, true, true]);
        assert_eq!(confirms, vec![Some(1); 3]);
        assert_eq!(s.version(), 0, "still the old list until the boundary");
        let sw = s.begin_cycle(2, SimTime(200)).unwrap();
        assert_eq!((sw.version, sw.first_broadcast, sw.confirmed_in), (1, 1, 1));
        assert_eq!(
            (sw.effective_cycle, sw.effective_at, sw.lag),
            (2, SimTime(200), SimTime(195))
        );
        assert_eq!((s.version(), s.active()), (1, &list(2)));
        assert_eq!(s.broadcast(2), None);
    }

    #[test]
    fn a_lost_confirmation_delays_the_switch() {
        let mut s = ListSwitch::new(list(1), 3, None);
        s.decide(SimTime(0), list(2));
        // Cycle 0: client 2's confirmation collides.
        s.end_cycle(0, true, &[true, false, true]);
        assert_eq!(s.begin_cycle(1, SimTime(100)), None);
        assert_eq!(s.version(), 0);
        // Cycle 1: the broadcast is lost, but client 2 heard it before and confirms.
        let confirms = s.end_cycle(1, false, &[false, true, false]);
        assert_eq!(confirms, vec![Some(1); 3]);
        let sw = s.begin_cycle(2, SimTime(200)).unwrap();
        assert_eq!(
            (sw.first_broadcast, sw.confirmed_in, sw.lag),
            (0, 1, SimTime(200))
        );
    }

    #[test]
    fn a_client_that_never_heard_the_list_does_not_confirm_it() {
        let mut s = ListSwitch::new(list(1), 2, None);
        s.decide(SimTime(0), list(2));
        let confirms = s.end_cycle(0, false, &[true, true]);
        assert_eq!(confirms, vec![None, None]);
        assert_eq!(s.begin_cycle(1, SimTime(100)), None);
        s.end_cycle(1, true, &[true, true]);
        assert!(s.begin_cycle(2, SimTime(200)).is_some());
    }

    #[test]
    fn a_newer_decision_replaces_a_pending_one_and_waits_for_a_committed_one() {
        let mut s = ListSwitch::new(list(1), 1, None);
        s.decide(SimTime(0), list(2));
        s.end_cycle(0, true, &[false]);
        assert_eq!(s.decide(SimTime(150), list(3)), 2);
        assert_eq!(s.superseded(), 1);
        s.end_cycle(1, true, &[true]);
        // Version 2 confirmed in cycle 1; version 3 decided before the boundary waits.
        assert_eq!(s.decide(SimTime(180), list(1)), 3);
        let sw = s.begin_cycle(2, SimTime(200)).unwrap();
        assert_eq!(
            (sw.version, sw.first_broadcast, sw.lag),
            (2, 1, SimTime(50))
        );
        assert_eq!(s.broadcast(2).map(|f| f.version), Some(3));
        s.end_cycle(2, true, &[true]);
        assert_eq!(s.begin_cycle(3, SimTime(300)).unwrap().version, 3);
    }

    #[test]
    fn a_long_list_is_confirmed_once_every_fragment_was_heard() {
        // 5 entries, 2 per frame: fragments of 2, 2 and 1 entries.
        let mut s = ListSwitch::new(list(1), 2, Some(2));
        s.decide(
            SimTime(0),
            SlotList::from_entries(vec![list(2).entries[0].unwrap(); 5]),
        );
        let f: Vec<_> = (0..4)
            .map(|k| s.broadcast(k).map(|f| (f.index, f.of, f.entries)))
            .collect();
        assert_eq!(f[0], Some((0, 3, 2)));
        assert_eq!(s.end_cycle(0, true, &[true, true]), vec![None, None]);
        assert_eq!(s.broadcast(1).map(|f| f.index), Some(1));
        s.end_cycle(1, false, &[true, true]); // fragment 1 lost
        assert_eq!(s.broadcast(2).map(|f| (f.index, f.entries)), Some((2, 1)));
        s.end_cycle(2, true, &[true, true]);
        assert_eq!(s.broadcast(3).map(|f| f.index), Some(0), "round-robin");
        s.end_cycle(3, true, &[true, true]);
        assert_eq!(s.begin_cycle(4, SimTime(400)), None);
        assert_eq!(s.broadcast(4).map(|f| f.index), Some(1));
        assert_eq!(s.end_cycle(4, true, &[true, true]), vec![Some(1), Some(1)]);
        assert_eq!(s.begin_cycle(5, SimTime(500)).unwrap().confirmed_in, 4);
    }
}
