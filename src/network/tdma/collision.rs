//! Frames on the wire and the collision rule.
//!
//! **Rule.** A frame occupies the shared medium from its actual start (when its
//! sender's clock says its slot begins) for its transmission time: `[start, start +
//! duration)`, at least one nanosecond. Two frames whose intervals overlap collide and
//! are both lost, for every receiver (a frame is heard by all nodes or by none, the
//! sender included). A frame that drifts into the guard at the end of its own slot, or
//! into a neighbour slot nobody uses, loses nothing; with every frame at most
//! `slot − guard` long, frames of adjacent slots collide exactly when the earlier one
//! is late and the later one early by more than the guard (plus the unused part of the
//! earlier slot) together. The same propagation delay applies to every pair of nodes,
//! so overlap at the senders is overlap at every receiver.

use super::confirm::Fragment;
use crate::kernel::SimTime;

/// What a frame carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum FrameKind {
    /// The server's sync frame (clients re-align to it).
    Sync,
    /// A static-slot frame: the server's may broadcast (a fragment of) a pending slot
    /// list, a client's may confirm one.
    Static {
        /// The list broadcast (server only).
        broadcast: Option<Fragment>,
        /// Version of the list confirmed (clients only).
        confirms: Option<u32>,
    },
    /// Channel data in a dynamic slot.
    Dynamic {
        /// Channel index.
        channel: usize,
    },
}

/// One frame sent in a cycle.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Transmission {
    /// Cycle.
    pub cycle: u64,
    /// Slot in the cycle.
    pub slot: usize,
    /// Sending node.
    pub sender: usize,
    /// What it carries.
    pub kind: FrameKind,
    /// Size [B].
    pub bytes: u64,
    /// Nominal start of the slot (server clock).
    pub nominal: SimTime,
    /// Actual start: when the sender's clock read `nominal`; also the time the data
    /// it carries are sampled.
    pub start: SimTime,
    /// Transmission time.
    pub duration: SimTime,
    /// When every receiver has it (start + duration + propagation + jitter); `None`
    /// if it was lost.
    pub delivery: Option<SimTime>,
}

impl Transmission {
    /// End of the frame on the wire (at least one ns after its start).
    pub fn end(&self) -> SimTime {
        SimTime(self.start.0.saturating_add(self.duration.0.max(1)))
    }

    /// Whether it was lost.
    pub fn lost(&self) -> bool {
        self.delivery.is_none()
    }

    /// Latency of a delivered frame: delivery minus actual start.
    pub fn latency(&self) -> Option<SimTime> {
        self.delivery.map(|d| SimTime(d.0 - self.start.0))
    }

    /// Signed start error against the nominal slot start [ns] (positive = late).
    pub fn start_error(&self) -> i64 {
        (i128::from(self.start.0) - i128::from(self.nominal.0)) as i64
    }
}

/// Marks every frame that overlaps another on the wire as lost (`delivery = None`),
/// per the module's rule; returns how many were newly lost. The outcome does not
/// depend on the order of `frames`.
pub fn mark_collisions(frames: &mut [Transmission]) -> usize {
    let mut order: Vec<usize> = (0..frames.len()).collect();
    order.sort_by_key(|&i| {
        (
            frames[i].start,
            frames[i].cycle,
            frames[i].slot,
            frames[i].sender,
        )
    });
    let mut collided = vec![false; frames.len()];
    // Frames still on the wire at the current start.
    let mut active: Vec<usize> = Vec::new();
    for &i in &order {
        let start = frames[i].start;
        active.retain(|&a| frames[a].end() > start);
        if !active.is_empty() {
            collided[i] = true;
            for &a in &active {
                collided[a] = true;
            }
        }
        active.push(i);
    }
    let mut newly = 0;
    for (f, c) in frames.iter_mut().zip(collided) {
        if c && f.delivery.is_some() {
            f.delivery = None;
            newly += 1;
        }
    }
    newly
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(slot: usize, start: u64, duration: u64) -> Transmission {
        Transmission {
            cycle: 0,
            slot,
            sender: slot,
            kind: FrameKind::Dynamic { channel: 0 },
            bytes: 0,
            nominal: SimTime(slot as u64 * 100),
            start: SimTime(start),
            duration: SimTime(duration),
            delivery: Some(SimTime(start + duration)),
        }
    }

    fn lost(frames: &[Transmission]) -> Vec<bool> {
        frames.iter().map(Transmission::lost).collect()
    }

    #[test]
    fn touching_frames_do_not_collide_overlapping_ones_do() {
        // Slots of 100, guard 10, frames of 90: slot 1 late by 10 touches slot 2.
        let mut f = vec![frame(1, 110, 90), frame(2, 200, 90), frame(3, 300, 90)];
        assert_eq!(mark_collisions(&mut f), 0);
        // Late by 11: slots 1 and 2 are lost, slot 3 is not.
        let mut f = vec![frame(1, 111, 90), frame(2, 200, 90), frame(3, 300, 90)];
        assert_eq!(mark_collisions(&mut f), 2);
        assert_eq!(lost(&f), vec![true, true, false]);
        // Early by 6 and late by 5: together beyond the guard.
        let mut f = vec![frame(1, 105, 90), frame(2, 194, 90)];
        assert_eq!(mark_collisions(&mut f), 2);
    }

    #[test]
    fn drifting_into_an_unused_slot_loses_nothing() {
        let mut f = vec![frame(1, 150, 90), frame(3, 300, 90)];
        assert_eq!(mark_collisions(&mut f), 0);
    }

    #[test]
    fn the_outcome_does_not_depend_on_the_order() {
        let base = vec![
            frame(1, 100, 90),
            frame(2, 185, 90),
            frame(3, 300, 90),
            frame(4, 360, 200),
            frame(5, 500, 90),
        ];
        let mut a = base.clone();
        mark_collisions(&mut a);
        assert_eq!(lost(&a), vec![true, true, true, true, true]);
        let mut b: Vec<_> = base.into_iter().rev().collect();
        mark_collisions(&mut b);
        b.reverse();
        assert_eq!(a, b);
    }

    #[test]
    fn instantaneous_frames_occupy_one_nanosecond() {
        let mut f = vec![frame(1, 100, 0), frame(2, 100, 0), frame(3, 101, 0)];
        assert_eq!(mark_collisions(&mut f), 2);
        assert_eq!(lost(&f), vec![true, true, false]);
        assert_eq!(f[2].latency(), Some(SimTime::ZERO));
        assert_eq!(frame(2, 195, 90).start_error(), -5);
    }
}
