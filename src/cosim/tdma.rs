//! The TDMA network inside a co-simulation: the protocol core
//! ([`crate::network::tdma`]) driven one cycle per `ClockSync` event, each data frame
//! turned into a `Slot` event at its actual start (the sender samples its data then)
//! whose messages are delivered, like ideal-channel messages, at the frame's delivery
//! time; a lost frame delivers nothing.
//!
//! **Achieved τ.** Each channel's nominal period is that of the list in force
//! ([`crate::network::tdma::schedule`]); epochs.csv reports the *measured* one: the
//! worst gap between two consecutive deliveries of any (channel, sender) pair that ends
//! in the window (or is still open at its end), so lost frames, jitter and list
//! switches show. Every pair counts as delivered at t = 0 (ghosts start from the true
//! initial state).

use crate::kernel::SimTime;
use crate::network::tdma::confirm::Switch;
use crate::network::tdma::frame::{senders, FrameSizes};
use crate::network::tdma::schedule::achieved_periods;
use crate::network::tdma::{
    schedule, ChannelRequest, CycleReport, Schedule, SlotList, TdmaError, TdmaNetwork,
};
use crate::network::{Channel, Message};
use crate::partition::line::LineSet;
use crate::scenario::model::{NetworkSpec, Scenario, TdmaSample, TdmaSpec};

/// A co-simulation's TDMA network and what it has delivered.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TdmaLink {
    net: TdmaNetwork,
    /// Sending TDMA nodes of each channel.
    senders: Vec<Vec<usize>>,
    /// Last delivery per channel, per sender (in `senders` order).
    last: Vec<Vec<SimTime>>,
    /// Worst delivery gap per channel in the current window.
    worst: Vec<SimTime>,
    decision_lag: SimTime,
    switches: Vec<Switch>,
    /// `network.sample: "previous_slot"`: per channel, per sender (in `senders` order),
    /// the messages sampled at the pair's last frame, carried by its next one.
    pending: Option<Vec<Vec<Vec<Message>>>>,
}

impl TdmaLink {
    /// The network of a scenario with a `tdma` network (panics otherwise) over its
    /// `channels`, with the initial list in force: the scenario's, or scheduled from
    /// the channels' τ.
    pub fn new(s: &Scenario, channels: &[Channel]) -> Result<TdmaLink, TdmaError> {
        let NetworkSpec::Tdma(spec) = &s.network else {
            panic!("TdmaLink::new on a scenario without a tdma network");
        };
        let cfg = spec.config.clone();
        let rigid = s.body_model == crate::scenario::model::BodyModel::Rigid;
        let coupling = s
            .partition
            .as_ref()
            .map_or(crate::scenario::model::Coupling::Reset, |p| p.coupling);
        let routes: Vec<_> = channels
            .iter()
            .flat_map(|c| c.routes.iter().copied())
            .collect();
        let senders = senders(channels);
        let (layout, initial) = initial_list(spec, channels)?;
        // Lines are chosen by the periods the initial list achieves, not the requested
        // ones (a request the list cannot serve runs at what it can).
        let periods = periods_of(&layout, &initial, &senders);
        let lines = LineSet::new(s, &routes, &periods);
        let node_of = s
            .partition
            .as_ref()
            .map(|p| p.node_of.clone())
            .unwrap_or_default();
        let extras = crate::network::tdma::frame::WireExtras {
            step_rates: s.slopes_multipliers(),
            reactions: s.ghosts_carry_reactions(),
        };
        let wire = (rigid, coupling, extras);
        let frames = FrameSizes::from_channels(channels, wire, cfg.header_bytes, &|r| {
            lines.on_route(s, &node_of, r)
        });
        let net = TdmaNetwork::new(cfg, s.seed, frames, channels.len(), initial)?;
        Ok(TdmaLink {
            last: senders
                .iter()
                .map(|s| vec![SimTime::ZERO; s.len()])
                .collect(),
            worst: vec![SimTime::ZERO; channels.len()],
            net,
            decision_lag: spec.decision_lag,
            switches: Vec::new(),
            pending: (spec.sample == TdmaSample::PreviousSlot)
                .then(|| senders.iter().map(|s| vec![Vec::new(); s.len()]).collect()),
            senders,
        })
    }

    /// The protocol state.
    pub fn network(&self) -> &TdmaNetwork {
        &self.net
    }

    /// Every list switch so far (decision, effect, lag).
    pub fn switches(&self) -> &[Switch] {
        &self.switches
    }

    /// Time from a decision to its hand-over to the server's broadcast.
    pub fn decision_lag(&self) -> SimTime {
        self.decision_lag
    }

    /// The nominal period of every channel under the list in force (a channel without
    /// a slot for one of its senders never delivers: `SimTime::MAX`-like `u64::MAX`).
    pub fn nominal_periods(&self) -> Vec<SimTime> {
        periods_of(self.net.layout(), self.net.lists().active(), &self.senders)
    }

    /// The schedule of requested periods `taus` [s].
    pub fn schedule_secs(&self, taus: &[f64]) -> Result<Schedule, TdmaError> {
        let ns = taus
            .iter()
            .map(|&t| SimTime::from_secs_f64(t).unwrap_or(SimTime(u64::MAX)));
        schedule(self.net.layout(), &requests(&self.senders, ns))
    }

    /// The server decides `list` at `at` (broadcast from the next cycle).
    pub fn decide(&mut self, at: SimTime, list: SlotList) -> Result<u32, TdmaError> {
        self.net.decide(at, list)
    }

    /// Computes the next cycle; a list switch in it is kept.
    pub fn run_cycle(&mut self) -> CycleReport {
        let report = self.net.run_cycle();
        if let Some(s) = &report.switch {
            self.switches.push(s.clone());
        }
        report
    }

    /// Notes a delivery of `sender`'s data on `channel` at `at`.
    pub fn delivered(&mut self, channel: usize, sender: usize, at: SimTime) {
        let Some(i) = self.senders[channel].iter().position(|&s| s == sender) else {
            return;
        };
        let last = &mut self.last[channel][i];
        let gap = SimTime(at.0.saturating_sub(last.0));
        *last = (*last).max(at);
        self.worst[channel] = self.worst[channel].max(gap);
    }

    /// Closes a window at `t`: the measured period of every channel (worst gap ended in
    /// the window or still open at `t`), and a fresh start for the next window.
    pub fn close_window(&mut self, t: SimTime) -> Vec<SimTime> {
        let measured = self
            .worst
            .iter()
            .zip(&self.last)
            .map(|(&w, last)| {
                let open = last.iter().map(|l| SimTime(t.0.saturating_sub(l.0))).max();
                w.max(open.unwrap_or(SimTime::ZERO))
            })
            .collect();
        self.worst.iter_mut().for_each(|w| *w = SimTime::ZERO);
        measured
    }

    /// Whether frames carry the sample of the pair's previous frame
    /// (`network.sample: "previous_slot"`).
    pub fn pipelined(&self) -> bool {
        self.pending.is_some()
    }

    /// What a frame of `sender` on `channel` carries, given the messages `fresh` it
    /// sampled at its start: those (`"slot"`), or the ones sampled at the pair's
    /// previous frame, `fresh` being kept for its next (`"previous_slot"`; the first
    /// frame of a pair carries nothing, its ghosts start from the true initial state).
    pub fn carry(&mut self, channel: usize, sender: usize, fresh: Vec<Message>) -> Vec<Message> {
        let Some(pending) = &mut self.pending else {
            return fresh;
        };
        match self.senders[channel].iter().position(|&s| s == sender) {
            Some(i) => std::mem::replace(&mut pending[channel][i], fresh),
            None => Vec::new(),
        }
    }

    /// Whether `sender` (TDMA node) sends on `channel`.
    pub fn sends(&self, channel: usize, sender: usize) -> bool {
        self.senders[channel].contains(&sender)
    }
}

/// The cycle layout of a `tdma` network and its initial slot list: the scenario's, or
/// scheduled from the channels' requested τ.
fn initial_list(
    spec: &TdmaSpec,
    channels: &[Channel],
) -> Result<(crate::network::tdma::CycleLayout, SlotList), TdmaError> {
    let layout = crate::network::tdma::CycleLayout::new(&spec.config)?;
    let list = match &spec.slot_list {
        Some(list) => list.clone(),
        None => {
            let requests = requests(&senders(channels), channels.iter().map(|c| c.spec.tau));
            schedule(&layout, &requests)?.list
        }
    };
    Ok((layout, list))
}

/// The nominal period of every channel under `list` (`u64::MAX` ns for a channel one of
/// whose senders it never serves).
fn periods_of(
    layout: &crate::network::tdma::CycleLayout,
    list: &SlotList,
    senders: &[Vec<usize>],
) -> Vec<SimTime> {
    achieved_periods(layout, list, senders)
        .into_iter()
        .map(|p| p.unwrap_or(SimTime(u64::MAX)))
        .collect()
}

fn requests(senders: &[Vec<usize>], taus: impl Iterator<Item = SimTime>) -> Vec<ChannelRequest> {
    senders
        .iter()
        .zip(taus)
        .map(|(s, tau)| ChannelRequest {
            tau,
            senders: s.clone(),
        })
        .collect()
}
