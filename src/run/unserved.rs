//! Requested delays a network did not realize.
//!
//! An ideal channel runs any requested period of at least one step, to the nanosecond
//! (a shorter one runs at one step, dt). A TDMA slot list
//! quantizes it: to whole slots, and to at most one cycle, since the list serves every
//! channel at least once per cycle. A request of 50 ms on a 5-ms cycle runs at 5 ms,
//! and a run that says nothing about it reads as a 50-ms experiment. Every window where
//! a channel's achieved period (measured from its deliveries) differs from its request
//! by more than 10 % and more than one slot is reported, on the terminal and in
//! `summary.json`. (10 %: clock drift and jitter move a served 5-ms period on the
//! shipped TDMA scenes by about 2.5 %; a slot's quantization at 1 ms on 100-µs slots is
//! 10 %.)

use serde::Serialize;

use crate::cosim::{CoSim, EpochRecord};

/// One channel whose requested delay was not realized in some windows.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Unserved {
    /// Channel name.
    pub channel: String,
    /// Windows where the achieved period missed the request.
    pub windows: usize,
    /// Windows in the run.
    pub of: usize,
    /// The request in the first such window [s].
    pub requested: f64,
    /// What ran in that window [s].
    pub achieved: f64,
    /// Why, for the terminal: a TDMA slot list's quantization, or (`None`) an ideal
    /// channel's floor of one step, `dt` [s].
    #[serde(skip)]
    pub floor: Option<f64>,
}

impl Unserved {
    /// The terminal's line for it.
    pub fn warning(&self) -> String {
        let why = match self.floor {
            Some(dt) => format!(
                "an ideal channel sends at most once per step, dt = {} s",
                crate::error::num(dt)
            ),
            None => "a TDMA slot list serves a channel in whole slots and at least once per \
                     cycle"
                .to_string(),
        };
        format!(
            "channel {} asked for τ = {} s and ran at {} s in {} of {} windows ({why}); \
             its delays are the achieved ones",
            self.channel,
            crate::error::num(self.requested),
            crate::error::num(self.achieved),
            self.windows,
            self.of
        )
    }
}

/// The channels of `world` whose requests its windows did not realize.
pub fn unserved(world: &CoSim) -> Vec<Unserved> {
    let slot = world
        .tdma()
        .map_or(0.0, |l| l.network().layout().slot_len().as_secs_f64());
    let epochs = world.epochs();
    let floor = world
        .tdma()
        .is_none()
        .then(|| world.scenario().dt.as_secs_f64());
    world
        .channels()
        .iter()
        .enumerate()
        .filter_map(|(i, c)| {
            let missed: Vec<&EpochRecord> = epochs
                .iter()
                .filter(|e| {
                    let (r, a) = e.taus[i];
                    a.is_finite() && (a - r).abs() > (0.1 * r).max(slot)
                })
                .collect();
            let first = missed.first()?;
            Some(Unserved {
                channel: c.spec.name.clone(),
                windows: missed.len(),
                of: epochs.len(),
                requested: first.taus[i].0,
                achieved: first.taus[i].1,
                floor,
            })
        })
        .collect()
}
