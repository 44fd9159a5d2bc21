//! The event queue of the kernel: pending events in a total order.
//!
//! # Ordering guarantee
//!
//! Every event carries an [`EventKey`] `(time, class, seq)` and events leave the queue
//! in increasing key order:
//!
//! 1. **time** — earlier simulated time first ([`SimTime`], integer nanoseconds, so two
//!    times are equal or not, never "almost");
//! 2. **class** — at equal time, in the fixed [`EventClass`] order
//!
//!    ```text
//!    Measurement < Controller < ClockSync < Slot < Sample < Delivery < PartitionStep
//!         0             1           2        3       4         5            6
//!    ```
//!
//! 3. **seq** — at equal time and class, in insertion order (FIFO): `seq` is a counter
//!    bumped on every insert, so no two pending events share a key and the order is
//!    total.
//!
//! The kernel refuses to schedule an event before the last popped `(time, class)` (see
//! [`Kernel::schedule`]), so over a whole run — events scheduled while others are being
//! processed included — the popped keys strictly increase.
//!
//! This order is a documented guarantee of the crate: a run is a pure function of its
//! scenario, and changing the order would change its bytes.
//!
//! ## Why this class order
//!
//! At a time `t`:
//!
//! - **Measurement** first: the measurement window ending at `t` is closed. Every
//!   partition step *before* `t` has been popped already (it has a smaller time), and no
//!   step *from* `t` has run yet (steps sort last), so the window covers exactly
//!   `[t − T, t)` of integration.
//! - **Controller** next: with that window's cost known, the controller decides the
//!   delays for the window starting at `t`.
//! - Then the **network** acts, in protocol order: **ClockSync** (clients re-align their
//!   clocks to the master before anything is timed against them), **Slot** (TDMA slot
//!   starts, under the clocks just synchronized and the slot list just decided),
//!   **Sample** (channels sample the state at `t`, which is the state after every step
//!   ending at `t`, since steps from `t` have not run).
//! - **Delivery**: messages due at `t` reach their receivers — including messages
//!   sampled at `t` with zero latency, which were scheduled by the Sample events above.
//! - **PartitionStep** last: the partitions integrate from `t`, so a node stepping at
//!   `t` sees exactly what was delivered up to and including `t`.
//!
//! # Implementation
//!
//! The queue is a [`priority_queue::PriorityQueue`] whose *items* are slot indices
//! (`usize`) into a payload slab (`Vec<Option<E>>` with a free list) and whose
//! *priorities* are `Reverse<EventKey>` (the crate's queue is a max-heap). Payloads are
//! never hashed, compared or moved by the heap. The priority-queue crate keeps its items
//! in a hash map (an `IndexMap`), but that map only locates an item's heap position: pop
//! order is decided by comparing priorities alone, and since every key is unique (the
//! `seq` counter) there are no ties for the map's layout or hasher to break. The map
//! hashes the slot indices with a fixed multiplicative hasher (no per-process seed, and
//! in the hold benchmark `benches/kernel.rs` 1.3–1.7× faster than the default SipHash). Slot
//! indices are reused in free-list order, which is a function of the operation sequence
//! only, and anyway never visible in the pop order.
//!
//! The kernel never reads the wall clock; [`Kernel::now`] is the time of the last popped
//! event.

use std::cmp::Reverse;
use std::fmt;
use std::hash::{BuildHasherDefault, Hasher};

use priority_queue::PriorityQueue;

use super::SimTime;

/// The kind of an event, which fixes its order among events at the same time.
///
/// The discriminants are the order (see the [module docs](self) for the reasons):
/// `Measurement (0) < Controller (1) < ClockSync (2) < Slot (3) < Sample (4) <
/// Delivery (5) < PartitionStep (6)`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
#[repr(u8)]
pub enum EventClass {
    /// Close the measurement window ending at this time (cost of the window).
    Measurement = 0,
    /// The controller decides for the window starting at this time.
    Controller = 1,
    /// A client clock re-synchronizes to the master (TDMA synchronization slot).
    ClockSync = 2,
    /// A TDMA slot starts.
    Slot = 3,
    /// A channel samples the state at this time.
    Sample = 4,
    /// A message due at this time reaches its receiver.
    Delivery = 5,
    /// A partition integrates one step from this time.
    PartitionStep = 6,
}

impl EventClass {
    /// Every class, in order.
    pub const ALL: [EventClass; 7] = [
        EventClass::Measurement,
        EventClass::Controller,
        EventClass::ClockSync,
        EventClass::Slot,
        EventClass::Sample,
        EventClass::Delivery,
        EventClass::PartitionStep,
    ];
}

impl EventClass {
    /// Lower-case name, e.g. `partition step`.
    pub fn name(self) -> &'static str {
        match self {
            EventClass::Measurement => "measurement",
            EventClass::Controller => "controller",
            EventClass::ClockSync => "clock sync",
            EventClass::Slot => "slot",
            EventClass::Sample => "sample",
            EventClass::Delivery => "delivery",
            EventClass::PartitionStep => "partition step",
        }
    }
}

impl fmt::Display for EventClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The total-order key of a scheduled event: time, then class, then insertion order.
///
/// The derived `Ord` compares the fields in declaration order.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
pub struct EventKey {
    /// When the event happens.
    pub time: SimTime,
    /// Its class (order among events at the same time).
    pub class: EventClass,
    /// Insertion counter of the kernel (FIFO among equal `(time, class)`).
    pub seq: u64,
}

/// Why an event could not be scheduled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum KernelError {
    /// The requested time is before the kernel's current time.
    #[error("cannot schedule an event at {time}: the kernel is already at {now}")]
    Past {
        /// The requested time.
        time: SimTime,
        /// The kernel's current time.
        now: SimTime,
    },
    /// The requested time is the kernel's current time, but the class sorts before the
    /// class of the event being processed: that point of the order has passed.
    #[error(
        "cannot schedule a {class} event at {time}: {current} events at that time are already being processed"
    )]
    EarlierClass {
        /// The requested (and current) time.
        time: SimTime,
        /// The requested class.
        class: EventClass,
        /// The class of the last popped event.
        current: EventClass,
    },
    /// `now + delay` does not fit in a [`SimTime`].
    #[error("cannot schedule an event {delay} after {now}: simulated time overflows")]
    Overflow {
        /// The kernel's current time.
        now: SimTime,
        /// The requested delay.
        delay: SimTime,
    },
}

/// Hasher of the queue's items, which are dense slot indices: a Fibonacci
/// (multiplicative) hash. Odd-constant multiplication is a bijection on the low bits, so
/// consecutive indices land in distinct buckets, and it mixes into the high bits the
/// hash table uses as tags. Fixed (no per-process seed), and an order of magnitude
/// cheaper than the default SipHash; it never influences pop order either way. Public
/// so that `benches/kernel.rs` can give a bare `priority-queue` the same hasher.
#[derive(Clone, Copy, Default, Debug)]
pub struct SlotHasher(u64);

impl Hasher for SlotHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        // Not reached for `usize` items; a plain byte-wise fallback keeps it total.
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    #[inline]
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }

    #[inline]
    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }

    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
}

/// The heap of pending events: slot index → reversed key.
type Queue = PriorityQueue<usize, Reverse<EventKey>, BuildHasherDefault<SlotHasher>>;

/// The pending events of a simulation, popped in [`EventKey`] order.
///
/// `Clone` yields an identical, independent queue (same pending events, same `now`, same
/// next `seq`), which is how a simulation is forked for a what-if evaluation.
#[derive(Clone)]
pub struct Kernel<E> {
    /// Slot index into `slab` → its key (reversed: the crate's queue pops the maximum).
    queue: Queue,
    /// Payloads; `None` marks a free slot.
    slab: Vec<Option<E>>,
    /// Free slots of `slab`, reused last-freed first.
    free: Vec<usize>,
    /// Time of the last popped event.
    now: SimTime,
    /// Class of the last popped event (`Measurement`, the first class, before any pop).
    now_class: EventClass,
    /// `seq` of the next insert.
    next_seq: u64,
}

impl<E> Default for Kernel<E> {
    fn default() -> Self {
        Self::new()
    }
}

impl<E> Kernel<E> {
    /// An empty kernel at time zero.
    pub fn new() -> Self {
        Self::with_capacity(0)
    }

    /// An empty kernel at time zero with room for `capacity` pending events.
    pub fn with_capacity(capacity: usize) -> Self {
        Kernel {
            queue: Queue::with_capacity_and_default_hasher(capacity),
            slab: Vec::with_capacity(capacity),
            free: Vec::with_capacity(capacity),
            now: SimTime::ZERO,
            now_class: EventClass::Measurement,
            next_seq: 0,
        }
    }

    /// The time of the last popped event (zero before the first pop).
    #[inline]
    pub fn now(&self) -> SimTime {
        self.now
    }

    /// Schedules `event` at `time` (which may equal [`now`](Self::now)) and returns its
    /// key.
    ///
    /// # Errors
    /// The past cannot be scheduled, so that pops never go back in the order:
    /// - [`KernelError::Past`] if `time` is before `now`;
    /// - [`KernelError::EarlierClass`] if `time` is `now` and `class` sorts before the
    ///   class of the last popped event (e.g. a `Measurement` at `t` scheduled while the
    ///   `PartitionStep`s at `t` run). The same or a later class at `now` is fine: it
    ///   pops after the current event (FIFO among equal classes), which is how a
    ///   zero-latency delivery is scheduled from a sample.
    #[inline]
    pub fn schedule(
        &mut self,
        time: SimTime,
        class: EventClass,
        event: E,
    ) -> Result<EventKey, KernelError> {
        if time <= self.now {
            if time < self.now {
                return Err(KernelError::Past {
                    time,
                    now: self.now,
                });
            }
            if class < self.now_class {
                return Err(KernelError::EarlierClass {
                    time,
                    class,
                    current: self.now_class,
                });
            }
        }
        let key = EventKey {
            time,
            class,
            seq: self.next_seq,
        };
        // 2^64 inserts would take centuries at one per nanosecond.
        self.next_seq += 1;
        self.insert(key, event);
        Ok(key)
    }

    /// Puts `event` in the queue under `key` (no checks: callers guarantee the order).
    #[inline]
    fn insert(&mut self, key: EventKey, event: E) {
        let slot = match self.free.pop() {
            Some(slot) => {
                self.slab[slot] = Some(event);
                slot
            }
            None => {
                self.slab.push(Some(event));
                self.slab.len() - 1
            }
        };
        self.queue.push(slot, Reverse(key));
    }

    /// Schedules `event` at `now + delay`.
    ///
    /// # Errors
    /// [`KernelError::Overflow`] if `now + delay` overflows.
    #[inline]
    pub fn schedule_in(
        &mut self,
        delay: SimTime,
        class: EventClass,
        event: E,
    ) -> Result<EventKey, KernelError> {
        let time = self.now.checked_add(delay).ok_or(KernelError::Overflow {
            now: self.now,
            delay,
        })?;
        self.schedule(time, class, event)
    }

    /// Removes the earliest pending event and advances [`now`](Self::now) to its time.
    #[inline]
    pub fn pop(&mut self) -> Option<(EventKey, E)> {
        let (slot, Reverse(key)) = self.queue.pop()?;
        let event = self.slab[slot].take()?;
        self.free.push(slot);
        self.now = key.time;
        self.now_class = key.class;
        Some((key, event))
    }

    /// The key of the earliest pending event.
    #[inline]
    pub fn peek(&self) -> Option<&EventKey> {
        self.queue.peek().map(|(_, Reverse(key))| key)
    }

    /// Number of pending events.
    #[inline]
    pub fn len(&self) -> usize {
        self.queue.len()
    }

    /// Whether no event is pending.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }

    /// The pending events in key order (the order [`pop`](Self::pop) would return them),
    /// for checkpoints and debugging. Allocates and sorts.
    pub fn pending(&self) -> impl Iterator<Item = (EventKey, &E)> {
        let mut pending: Vec<(EventKey, &E)> = self
            .queue
            .iter()
            .filter_map(|(&slot, &Reverse(key))| Some((key, self.slab[slot].as_ref()?)))
            .collect();
        // Keys are unique, so an unstable sort is deterministic.
        pending.sort_unstable_by_key(|&(key, _)| key);
        pending.into_iter()
    }

    /// Removes every pending event for which `cancel` returns `true` and returns how
    /// many were removed. `cancel` sees the pending events in slot order, which depends
    /// only on the sequence of operations on this kernel, so a `cancel` with side
    /// effects is deterministic too. Does not change [`now`](Self::now) or the keys of
    /// the remaining events.
    pub fn cancel_if<F>(&mut self, mut cancel: F) -> usize
    where
        F: FnMut(&E) -> bool,
    {
        let mut removed = 0;
        for (slot, entry) in self.slab.iter_mut().enumerate() {
            if entry.as_ref().is_some_and(&mut cancel) {
                *entry = None;
                self.free.push(slot);
                removed += 1;
            }
        }
        if removed > 0 {
            let slab = &self.slab;
            self.queue.retain(|&slot, _| slab[slot].is_some());
        }
        removed
    }
}

impl<E: fmt::Debug> fmt::Debug for Kernel<E> {
    /// The current time and the pending events in key order.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        struct Pending<'a, E>(&'a Kernel<E>);
        impl<E: fmt::Debug> fmt::Debug for Pending<'_, E> {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.debug_list().entries(self.0.pending()).finish()
            }
        }
        f.debug_struct("Kernel")
            .field("now", &self.now)
            .field("now_class", &self.now_class)
            .field("next_seq", &self.next_seq)
            .field("pending", &Pending(self))
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drain<E>(k: &mut Kernel<E>) -> Vec<(EventKey, E)> {
        std::iter::from_fn(|| k.pop()).collect()
    }

    #[test]
    fn equal_keys_pop_fifo() {
        let mut k = Kernel::new();
        for i in 0..100u32 {
            k.schedule(SimTime(5), EventClass::Delivery, i).unwrap();
        }
        let popped: Vec<u32> = drain(&mut k).into_iter().map(|(_, e)| e).collect();
        assert_eq!(popped, (0..100).collect::<Vec<_>>());
    }

    #[test]
    fn classes_pop_in_documented_order_at_equal_time() {
        let mut k = Kernel::new();
        // Insert in reverse order so insertion order cannot explain the result.
        for &class in EventClass::ALL.iter().rev() {
            k.schedule(SimTime(7), class, class).unwrap();
        }
        let popped: Vec<EventClass> = drain(&mut k).into_iter().map(|(_, e)| e).collect();
        assert_eq!(popped, EventClass::ALL.to_vec());
        let discriminants: Vec<u8> = EventClass::ALL.iter().map(|&c| c as u8).collect();
        assert_eq!(discriminants, vec![0, 1, 2, 3, 4, 5, 6]);
    }

    #[test]
    fn time_dominates_class_and_seq() {
        let mut k = Kernel::new();
        k.schedule(SimTime(30), EventClass::Measurement, 'c')
            .unwrap();
        k.schedule(SimTime(10), EventClass::PartitionStep, 'a')
            .unwrap();
        k.schedule(SimTime(20), EventClass::Measurement, 'b')
            .unwrap();
        assert_eq!(k.peek().map(|key| key.time), Some(SimTime(10)));
        let popped: Vec<(SimTime, char)> = drain(&mut k)
            .into_iter()
            .map(|(key, e)| (key.time, e))
            .collect();
        assert_eq!(
            popped,
            vec![(SimTime(10), 'a'), (SimTime(20), 'b'), (SimTime(30), 'c')]
        );
        assert_eq!(k.now(), SimTime(30));
        assert!(k.is_empty());
    }

    #[test]
    fn scheduling_in_the_past_is_an_error() {
        let mut k = Kernel::new();
        k.schedule(SimTime(100), EventClass::Slot, ()).unwrap();
        assert_eq!(k.pop().map(|(key, _)| key.time), Some(SimTime(100)));
        let err = k.schedule(SimTime(99), EventClass::Slot, ()).unwrap_err();
        assert_eq!(
            err,
            KernelError::Past {
                time: SimTime(99),
                now: SimTime(100)
            }
        );
        assert_eq!(
            err.to_string(),
            "cannot schedule an event at 0.000000099 s: the kernel is already at 0.000000100 s"
        );
        assert!(k.is_empty(), "a rejected event must not be queued");
        // The present is allowed, from the current class on.
        k.schedule(SimTime(100), EventClass::Slot, ()).unwrap();
        k.schedule_in(SimTime::ZERO, EventClass::Delivery, ())
            .unwrap();
        let earlier = k
            .schedule(SimTime(100), EventClass::Controller, ())
            .unwrap_err();
        assert_eq!(
            earlier,
            KernelError::EarlierClass {
                time: SimTime(100),
                class: EventClass::Controller,
                current: EventClass::Slot
            }
        );
        assert_eq!(
            earlier.to_string(),
            "cannot schedule a controller event at 0.000000100 s: \
             slot events at that time are already being processed"
        );
        let overflow = k
            .schedule_in(SimTime(u64::MAX), EventClass::Slot, ())
            .unwrap_err();
        assert!(matches!(overflow, KernelError::Overflow { .. }));
        assert!(overflow.to_string().contains("overflows"));
        assert_eq!(k.len(), 2);
    }

    #[test]
    fn schedule_in_is_relative_to_now() {
        let mut k = Kernel::new();
        k.schedule(SimTime(1_000), EventClass::Sample, 0).unwrap();
        k.pop().unwrap();
        let key = k
            .schedule_in(SimTime(250), EventClass::Delivery, 1)
            .unwrap();
        assert_eq!(key.time, SimTime(1_250));
        assert_eq!(key.seq, 1);
    }

    #[test]
    fn clone_is_identical_and_independent() {
        let mut k = Kernel::new();
        for i in 0..50u64 {
            let class = EventClass::ALL[(i % 7) as usize];
            k.schedule(SimTime((i * 37) % 11), class, vec![i]).unwrap();
        }
        for _ in 0..10 {
            k.pop().unwrap();
        }
        let mut fork = k.clone();
        assert_eq!(fork.now(), k.now());
        assert_eq!(
            fork.pending().collect::<Vec<_>>(),
            k.pending().collect::<Vec<_>>()
        );
        // Changing the fork leaves the original alone.
        fork.schedule_in(SimTime(1), EventClass::Controller, vec![999])
            .unwrap();
        fork.pop().unwrap();
        assert_eq!(k.len(), 40);
        assert_eq!(fork.len(), 40);
        // Same operations on both give the same keys and events.
        let mut fork = k.clone();
        let a = k
            .schedule_in(SimTime(3), EventClass::Sample, vec![7])
            .unwrap();
        let b = fork
            .schedule_in(SimTime(3), EventClass::Sample, vec![7])
            .unwrap();
        assert_eq!(a, b);
        assert_eq!(drain(&mut k), drain(&mut fork));
    }

    #[test]
    fn pending_is_in_pop_order() {
        let mut k = Kernel::new();
        for i in 0..40u64 {
            let class = EventClass::ALL[((i * 5) % 7) as usize];
            k.schedule(SimTime((i * 13) % 9), class, i).unwrap();
        }
        let pending: Vec<(EventKey, u64)> = k.pending().map(|(key, &e)| (key, e)).collect();
        assert_eq!(pending, drain(&mut k));
    }

    #[test]
    fn cancel_if_removes_only_matching_events() {
        let mut k = Kernel::new();
        for i in 0..30u64 {
            k.schedule(SimTime(i % 4), EventClass::Delivery, i).unwrap();
        }
        assert_eq!(k.cancel_if(|&e| e % 3 == 0), 10);
        assert_eq!(k.cancel_if(|&e| e % 3 == 0), 0);
        assert_eq!(k.len(), 20);
        // Freed slots are reused without disturbing the order.
        k.schedule(SimTime(0), EventClass::Delivery, 100).unwrap();
        let popped = drain(&mut k);
        assert!(popped.windows(2).all(|w| w[0].0 < w[1].0));
        let events: Vec<u64> = popped.iter().map(|&(_, e)| e).collect();
        assert!(events.iter().all(|e| e % 3 != 0 || *e == 100));
        assert_eq!(events.len(), 21);
    }

    #[test]
    fn debug_lists_pending_events_in_order() {
        let mut k = Kernel::new();
        k.schedule(SimTime(2), EventClass::Slot, "late").unwrap();
        k.schedule(SimTime(1), EventClass::Slot, "early").unwrap();
        let s = format!("{k:?}");
        let early = s.find("early").unwrap();
        let late = s.find("late").unwrap();
        assert!(early < late, "{s}");
    }
}

/// The serialized form of a [`Kernel`]: its clock and its pending events in pop order.
/// Slot indices are not part of it: pop order depends only on the keys, so a restored
/// kernel pops exactly what the original would have.
#[derive(serde::Serialize)]
struct KernelImageRef<'a, E> {
    now: SimTime,
    now_class: EventClass,
    next_seq: u64,
    pending: Vec<(EventKey, &'a E)>,
}

#[derive(serde::Deserialize)]
struct KernelImage<E> {
    now: SimTime,
    now_class: EventClass,
    next_seq: u64,
    pending: Vec<(EventKey, E)>,
}

impl<E: serde::Serialize> serde::Serialize for Kernel<E> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        KernelImageRef {
            now: self.now,
            now_class: self.now_class,
            next_seq: self.next_seq,
            pending: self.pending().collect(),
        }
        .serialize(serializer)
    }
}

impl<'de, E: serde::Deserialize<'de>> serde::Deserialize<'de> for Kernel<E> {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let image = KernelImage::<E>::deserialize(deserializer)?;
        let mut k = Kernel::with_capacity(image.pending.len());
        k.now = image.now;
        k.now_class = image.now_class;
        k.next_seq = image.next_seq;
        for (key, event) in image.pending {
            if key.seq >= image.next_seq || (key.time, key.class) < (k.now, k.now_class) {
                return Err(serde::de::Error::custom(format!(
                    "pending event {key:?} is inconsistent with the kernel clock"
                )));
            }
            k.insert(key, event);
        }
        Ok(k)
    }
}
