//! The protocol cycle by cycle: which frames are sent when, which collide, when each
//! is delivered, and how a new slot list goes into force. The co-simulation turns a
//! [`CycleReport`] into events (sample at each frame's start, deliver at its delivery).
//!
//! One call to [`TdmaNetwork::run_cycle`] computes a whole cycle, in this order:
//! 1. a list confirmed in the previous cycle goes into force (all nodes at once);
//! 2. clocks carry over to the cycle start, take a random-walk step, and re-align if
//!    this cycle's sync frame got through;
//! 3. every frame is laid out: sync (server, on time), one static frame per node (the
//!    server's broadcasts a fragment of a pending list), one frame per sending list entry, each
//!    starting when its sender's clock reads the slot start, each with its latency
//!    (jitter drawn per frame in slot order);
//! 4. collisions are marked over the cycle's frames and the next cycle's sync frame
//!    (so a late last frame can cost the next sync, and the clients then run on
//!    without re-aligning); frames further apart than that are taken not to meet
//!    (it would take a clock error of more than a slot);
//! 5. the confirmation state machine reads which static frames got through.

use super::clock::Clocks;
use super::collision::{mark_collisions, FrameKind, Transmission};
use super::config::TdmaConfig;
use super::confirm::{Fragment, ListSwitch, Switch};
use super::error::TdmaError;
use super::frame::{entries_per_fragment, list_broadcast_bytes, transmission_time, FrameSizes};
use super::latency::{latency, JitterSource};
use super::layout::{CycleLayout, SlotList};
use crate::kernel::SimTime;

/// Everything that happened in one cycle.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CycleReport {
    /// The cycle.
    pub cycle: u64,
    /// Its nominal start.
    pub start: SimTime,
    /// Version of the list in force.
    pub list_version: u32,
    /// Whether the clients re-aligned to this cycle's sync frame.
    pub synced: bool,
    /// The list that went into force at this cycle's start, if any.
    pub switch: Option<Switch>,
    /// Every frame, in slot order.
    pub frames: Vec<Transmission>,
}

impl CycleReport {
    /// Frames lost in this cycle.
    pub fn lost(&self) -> usize {
        self.frames.iter().filter(|f| f.lost()).count()
    }
}

/// A TDMA network's protocol state.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TdmaNetwork {
    cfg: TdmaConfig,
    layout: CycleLayout,
    frames: FrameSizes,
    channels: usize,
    clocks: Clocks,
    jitter: JitterSource,
    lists: ListSwitch,
    next_cycle: u64,
    /// The next cycle's sync frame collided with a frame of the last cycle.
    next_sync_lost: bool,
    lost: u64,
}

impl TdmaNetwork {
    /// A network per `cfg` for the scenario `seed`, with `frames` for its `channels`
    /// channels and `initial` in force from cycle 0. Validates everything; draws the
    /// clock drifts (if any).
    pub fn new(
        cfg: TdmaConfig,
        seed: u64,
        frames: FrameSizes,
        channels: usize,
        initial: SlotList,
    ) -> Result<TdmaNetwork, TdmaError> {
        let layout = CycleLayout::new(&cfg)?;
        initial.validate(&layout, channels)?;
        initial.check_frames(&cfg, &frames)?;
        Ok(TdmaNetwork {
            clocks: Clocks::new(&cfg, seed),
            jitter: JitterSource::new(cfg.jitter, cfg.nodes(), seed),
            lists: ListSwitch::new(initial, cfg.clients, entries_per_fragment(&cfg)),
            layout,
            frames,
            channels,
            cfg,
            next_cycle: 0,
            next_sync_lost: false,
            lost: 0,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &TdmaConfig {
        &self.cfg
    }

    /// The slot geometry.
    pub fn layout(&self) -> &CycleLayout {
        &self.layout
    }

    /// The clocks.
    pub fn clocks(&self) -> &Clocks {
        &self.clocks
    }

    /// The clocks, to change (what-if studies and tests).
    pub fn clocks_mut(&mut self) -> &mut Clocks {
        &mut self.clocks
    }

    /// The list in force and the one being confirmed.
    pub fn lists(&self) -> &ListSwitch {
        &self.lists
    }

    /// The next cycle [`TdmaNetwork::run_cycle`] computes.
    pub fn next_cycle(&self) -> u64 {
        self.next_cycle
    }

    /// Frames lost so far.
    pub fn lost(&self) -> u64 {
        self.lost
    }

    /// 32-bit words drawn from every random stream so far.
    pub fn words_drawn(&self) -> u128 {
        self.clocks.words_drawn() + self.jitter.words_drawn()
    }

    /// The server decides `list` at `at`: it is checked, then broadcast from the next
    /// cycle computed; returns its version.
    pub fn decide(&mut self, at: SimTime, list: SlotList) -> Result<u32, TdmaError> {
        list.validate(&self.layout, self.channels)?;
        list.check_frames(&self.cfg, &self.frames)?;
        Ok(self.lists.decide(at, list))
    }

    /// Computes the next cycle (see the module docs for the order).
    pub fn run_cycle(&mut self) -> CycleReport {
        let k = self.next_cycle;
        let start = self.layout.cycle_start(k).unwrap_or(SimTime(u64::MAX));
        let switch = self.lists.begin_cycle(k, start);
        let list_version = self.lists.version();
        let synced = !self.next_sync_lost;
        self.clocks.begin_cycle(start, synced);

        let header = self.cfg.header_bytes;
        let mut frames = Vec::with_capacity(self.layout.slots() + 1);
        frames.push(self.frame(k, 0, 0, FrameKind::Sync, header));
        let broadcast = self.lists.broadcast(k);
        for node in 0..self.cfg.nodes() {
            let (kind, bytes) = match (node, broadcast) {
                (0, Some(f)) => (
                    static_kind(Some(f), None),
                    list_broadcast_bytes(f.entries, header),
                ),
                _ => (static_kind(None, None), header),
            };
            frames.push(self.frame(k, self.layout.static_slot(node), node, kind, bytes));
        }
        let list = self.lists.active().clone();
        for (j, e) in list.entries.iter().enumerate() {
            let Some(e) = e else { continue };
            let kind = FrameKind::Dynamic { channel: e.channel };
            let bytes = self.frames.bytes(e.sender, e.channel);
            frames.push(self.frame(k, self.layout.dynamic_slot(j), e.sender, kind, bytes));
        }
        // The next cycle's sync frame, to find a collision across the boundary (no
        // jitter drawn: it is drawn again, once, when that cycle is computed).
        let next_start = self.layout.cycle_start(k + 1).unwrap_or(SimTime(u64::MAX));
        let duration = transmission_time(header, self.cfg.link_rate);
        frames.push(Transmission {
            cycle: k + 1,
            slot: 0,
            sender: 0,
            kind: FrameKind::Sync,
            bytes: header,
            nominal: next_start,
            start: next_start,
            duration,
            delivery: Some(next_start),
        });
        if !synced {
            frames[0].delivery = None;
        }
        mark_collisions(&mut frames);
        self.next_sync_lost = frames.pop().is_some_and(|f| f.lost());

        // Which protocol frames got through.
        let heard = |node: usize| !frames[1 + node].lost();
        let static_heard: Vec<bool> = (1..=self.cfg.clients).map(heard).collect();
        let confirms = self
            .lists
            .end_cycle(k, broadcast.is_some() && heard(0), &static_heard);
        for (i, c) in confirms.into_iter().enumerate() {
            frames[2 + i].kind = static_kind(None, c);
        }

        let report = CycleReport {
            cycle: k,
            start,
            list_version,
            synced,
            switch,
            frames,
        };
        self.lost += report.lost() as u64;
        self.next_cycle += 1;
        report
    }

    /// One frame of cycle `k` in `slot` by `sender`: it starts when the sender's clock
    /// reads the slot start; its latency takes one jitter draw.
    fn frame(
        &mut self,
        k: u64,
        slot: usize,
        sender: usize,
        kind: FrameKind,
        bytes: u64,
    ) -> Transmission {
        let nominal = self.layout.slot_start(k, slot).unwrap_or(SimTime(u64::MAX));
        let start = self.clocks.global_time_of_local(sender, nominal);
        let duration = transmission_time(bytes, self.cfg.link_rate);
        let jitter = self.jitter.draw(sender);
        let delay = latency(duration, self.cfg.propagation, jitter);
        Transmission {
            cycle: k,
            slot,
            sender,
            kind,
            bytes,
            nominal,
            start,
            duration,
            delivery: Some(SimTime(start.0.saturating_add(delay.0))),
        }
    }
}

fn static_kind(broadcast: Option<Fragment>, confirms: Option<u32>) -> FrameKind {
    FrameKind::Static {
        broadcast,
        confirms,
    }
}
