//! The scheduler: requested periods → slot list, and the achieved period of any list.
//!
//! **Achieved period.** Each (channel, sender) pair delivers that sender's data of the
//! channel once per slot it holds; its period is the worst gap between the starts of
//! two consecutive such slots over a cycle, the gap across the cycle boundary included
//! (a pair holding one slot per cycle has period = cycle). Without jitter every frame
//! of a pair has the same latency, so these are also the gaps between deliveries. A
//! channel's achieved period is the worst over its senders; `None` when it has no
//! sender or a sender holds no slot (its data never arrives).
//!
//! **Rule.** A request `τ` is rounded up to the slot grid, `G = ⌈τ / slot⌉ · slot`
//! (capped at the cycle). Every sender of the channel gets the fewest slots per cycle
//! that keep each of its gaps ≤ `G`, placed `G` apart where the free slots allow (so
//! the worst gap is `G` itself whenever a free slot lies exactly there). Hence, for
//! every channel of a successful schedule, `achieved ≤ G < τ + slot`: never more than
//! one slot above the request. It is `≥ τ` in the usual case (worst gap = `G`), and
//! may be below `τ` when `τ` exceeds the cycle (a list is per cycle: the channel is
//! served once per cycle, achieved = cycle) or when the slots at distance `G` were
//! taken and a shorter gap had to do.
//!
//! Pairs are placed most demanding first (smallest `G`, then channel, then sender).
//! A pair's gap across the cycle boundary (which holds the sync and static part) is
//! made as close to `G` as the grid allows and its other slots are spread evenly in
//! between, each first slot tried in turn (keep the fewest slots, then the worst gap
//! closest to `G`, then the earliest), so channels with equal periods interleave
//! (`A B A B` rather than `A A B B`).

use super::error::TdmaError;
use super::layout::{CycleLayout, SlotEntry, SlotList};
use crate::kernel::SimTime;

/// What one channel asks of the scheduler.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ChannelRequest {
    /// Requested period τ; > 0.
    pub tau: SimTime,
    /// Its sending TDMA nodes (from the routes, see [`super::frame::senders`]).
    pub senders: Vec<usize>,
}

/// A slot list with the periods it was asked for and the ones it achieves.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Schedule {
    /// The list.
    pub list: SlotList,
    /// Requested period per channel.
    pub requested: Vec<SimTime>,
    /// Achieved period per channel (see the module docs; `None` = no sender).
    pub achieved: Vec<Option<SimTime>>,
}

/// Worst gap between consecutive slots of `(sender, channel)` in `list`, wrap-around
/// included; `None` if the pair holds no slot.
pub fn pair_period(
    layout: &CycleLayout,
    list: &SlotList,
    sender: usize,
    channel: usize,
) -> Option<SimTime> {
    worst_gap(layout, &list.positions(sender, channel))
}

/// Achieved period of every channel of `list` (`senders[c]` = the senders of channel
/// `c`); see the module docs.
pub fn achieved_periods(
    layout: &CycleLayout,
    list: &SlotList,
    senders: &[Vec<usize>],
) -> Vec<Option<SimTime>> {
    senders
        .iter()
        .enumerate()
        .map(|(c, ss)| {
            let mut worst: Option<SimTime> = None;
            for &s in ss {
                let g = pair_period(layout, list, s, c)?;
                worst = Some(worst.map_or(g, |w| w.max(g)));
            }
            worst
        })
        .collect()
}

/// Worst circular gap of sorted dynamic-slot positions.
fn worst_gap(layout: &CycleLayout, positions: &[usize]) -> Option<SimTime> {
    let (&first, &last) = (positions.first()?, positions.last()?);
    let l = layout.slot_len().0;
    let inner = positions
        .windows(2)
        .map(|w| (w[1] - w[0]) as u64 * l)
        .max()
        .unwrap_or(0);
    let wrap = layout.cycle_len().0 - (last - first) as u64 * l;
    Some(SimTime(inner.max(wrap)))
}

/// One (channel, sender) pair to place.
struct Pair {
    channel: usize,
    sender: usize,
    requested: SimTime,
    /// Largest gap allowed [ns].
    bound: u64,
}

/// Builds a slot list for `requests` (one per channel) on `layout`; see the module
/// docs for the rule. Errors: a zero period, a period below the gap the sync and
/// static part force ([`CycleLayout::min_wrap_gap`]), more slots needed than the
/// dynamic part holds, or (rarely, when the total fits) no placement for a pair.
pub fn schedule(layout: &CycleLayout, requests: &[ChannelRequest]) -> Result<Schedule, TdmaError> {
    let (l, cycle, k) = (layout.slot_len().0, layout.cycle_len().0, layout.capacity());
    let mut pairs = Vec::new();
    let mut needed = 0usize;
    for (channel, r) in requests.iter().enumerate() {
        if r.tau == SimTime::ZERO {
            return Err(TdmaError::ZeroPeriod { channel });
        }
        if r.senders.is_empty() {
            continue;
        }
        let bound = r.tau.0.div_ceil(l).saturating_mul(l).min(cycle);
        if bound < cycle && bound < layout.min_wrap_gap().0 {
            return Err(TdmaError::PeriodTooShort {
                channel,
                requested: r.tau,
                minimum: layout.min_wrap_gap(),
            });
        }
        let mut senders = r.senders.clone();
        senders.sort_unstable();
        senders.dedup();
        for sender in senders {
            needed += usize::try_from(cycle.div_ceil(bound)).unwrap_or(usize::MAX);
            pairs.push(Pair {
                channel,
                sender,
                requested: r.tau,
                bound,
            });
        }
    }
    if needed > k {
        return Err(TdmaError::Infeasible {
            needed,
            available: k,
        });
    }
    pairs.sort_by_key(|p| (p.bound, p.channel, p.sender));
    let mut taken: Vec<Option<SlotEntry>> = vec![None; k];
    for p in &pairs {
        let Some(positions) = place(layout, &taken, p.bound) else {
            return Err(TdmaError::Unschedulable {
                channel: p.channel,
                sender: p.sender,
                requested: p.requested,
                bound: SimTime(p.bound),
                free: taken.iter().filter(|t| t.is_none()).count(),
            });
        };
        for j in positions {
            taken[j] = Some(SlotEntry {
                sender: p.sender,
                channel: p.channel,
            });
        }
    }
    while taken.last() == Some(&None) {
        taken.pop();
    }
    let list = SlotList { entries: taken };
    let senders: Vec<Vec<usize>> = requests.iter().map(|r| r.senders.clone()).collect();
    Ok(Schedule {
        achieved: achieved_periods(layout, &list, &senders),
        requested: requests.iter().map(|r| r.tau).collect(),
        list,
    })
}

/// The best positions for a pair with largest gap `bound` among the free slots of
/// `taken`. For every free first slot `f`: the last slot is the earliest free one that
/// keeps the gap across the cycle boundary within `bound` (so that gap is as close to
/// `bound` as the grid allows, and the slots at the far end of the dynamic part stay
/// free for pairs that need them); in between, the fewest slots that keep every gap
/// within `bound` (found greedily), each moved as near its evenly spaced target as the
/// free slots allow. Keeps the fewest slots, then the worst gap closest to `bound`,
/// then the earliest `f`.
fn place(layout: &CycleLayout, taken: &[Option<SlotEntry>], bound: u64) -> Option<Vec<usize>> {
    let (l, cycle) = (layout.slot_len().0, layout.cycle_len().0);
    let free = |j: usize| taken[j].is_none();
    if bound >= cycle {
        // Any single slot serves the pair once per cycle.
        return (0..taken.len()).find(|&j| free(j)).map(|j| vec![j]);
    }
    // Both are whole numbers of slots (the cycle is, see `TdmaConfig::validate`).
    let reach = usize::try_from(bound / l).unwrap_or(usize::MAX);
    let span = usize::try_from((cycle - bound) / l).unwrap_or(usize::MAX);
    let mut best: Option<(usize, u64, Vec<usize>)> = None;
    for first in (0..taken.len()).filter(|&j| free(j)) {
        let Some(last) = (first.saturating_add(span)..taken.len()).find(|&j| free(j)) else {
            break; // later first slots need even later last slots
        };
        let Some(fewest) = greedy(taken, first, last, reach) else {
            continue;
        };
        let positions = spread(taken, first, last, reach, fewest.len() - 1).unwrap_or(fewest);
        let worst = worst_gap(layout, &positions).map_or(u64::MAX, |g| g.0);
        let better = best
            .as_ref()
            .is_none_or(|(n, w, _)| positions.len() < *n || (positions.len() == *n && worst > *w));
        if better {
            best = Some((positions.len(), worst, positions));
        }
    }
    best.map(|(_, _, p)| p)
}

/// The fewest slots from `first` to `last` (`first < last`, both free) with steps of
/// at most `reach`: each the latest free slot within reach of the previous one.
fn greedy(
    taken: &[Option<SlotEntry>],
    first: usize,
    last: usize,
    reach: usize,
) -> Option<Vec<usize>> {
    let mut positions = vec![first];
    let mut cur = first;
    while last - cur > reach {
        cur = (cur + 1..=cur + reach)
            .rev()
            .find(|&j| taken[j].is_none())?;
        positions.push(cur);
    }
    positions.push(last);
    Some(positions)
}

/// `steps` steps of at most `reach` from `first` to `last` (`first < last`, both
/// free), each slot the free one nearest its evenly spaced target among those that
/// keep the rest reachable (ties to the earlier); `None` on a dead end.
fn spread(
    taken: &[Option<SlotEntry>],
    first: usize,
    last: usize,
    reach: usize,
    steps: usize,
) -> Option<Vec<usize>> {
    let length = last - first;
    let mut positions = vec![first];
    let mut prev = first;
    for i in 1..steps {
        // Target first + i·length/steps, compared in units of 1/steps slot (exact).
        let target = first * steps + i * length;
        let lo = (prev + 1).max(last.saturating_sub((steps - i) * reach));
        let hi = (prev + reach).min(last - 1);
        let j = (lo..=hi)
            .filter(|&j| taken[j].is_none())
            .min_by_key(|&j| (j * steps).abs_diff(target))?;
        positions.push(j);
        prev = j;
    }
    positions.push(last);
    Some(positions)
}

#[cfg(test)]
mod tests;
