//! The schedule stage: `schedule` checked against the channels and the windows.

use super::checks::{num, positive, time, whole_nanos};
use crate::error::{Error, Result};
use crate::kernel::SimTime;
use crate::scenario::file::ScheduleEntryFile;
use crate::scenario::model::{ChannelSpec, ScheduledPeriods};

/// The scenario's fixed schedule of periods: each entry at a window boundary (a whole
/// multiple of `period`) before `duration`, later than the one before, with one
/// positive period per channel. Not beside a controller, which makes these decisions
/// itself. The entry count needs no limit of its own: strictly increasing window
/// boundaries before the end are at most the run's window count.
pub(super) fn schedule(
    entries: &[ScheduleEntryFile],
    channels: &[ChannelSpec],
    has_controller: bool,
    (period, duration): (SimTime, SimTime),
) -> Result<Vec<ScheduledPeriods>> {
    if entries.is_empty() {
        return Ok(Vec::new());
    }
    if has_controller {
        return Err(Error::invalid(
            "schedule",
            "is not used beside a `controller`, which decides the periods itself (give one \
             or the other)",
        ));
    }
    if channels.is_empty() {
        return Err(Error::invalid(
            "schedule",
            "needs `channels` whose periods it sets (this scene has none)",
        ));
    }
    let mut out: Vec<ScheduledPeriods> = Vec::new();
    for (i, e) in entries.iter().enumerate() {
        let path = format!("schedule[{i}]");
        let at = whole_nanos(&format!("{path}.at"), e.at)?;
        if at.0 % period.0 != 0 || at >= duration {
            return Err(Error::invalid(
                format!("{path}.at"),
                format!(
                    "must be a measurement window boundary (a multiple of measurement.period \
                     = {} s) before duration = {} s (got {} s)",
                    num(period.as_secs_f64()),
                    num(duration.as_secs_f64()),
                    num(e.at)
                ),
            ));
        }
        if let Some(before) = out.last() {
            if at <= before.at {
                return Err(Error::invalid(
                    format!("{path}.at"),
                    format!(
                        "must be later than schedule[{}].at = {} s (got {} s)",
                        i - 1,
                        num(before.at.as_secs_f64()),
                        num(e.at)
                    ),
                ));
            }
        }
        if e.tau.len() != channels.len() {
            return Err(Error::invalid(
                format!("{path}.tau"),
                format!(
                    "needs one period per channel, {} (got {})",
                    channels.len(),
                    e.tau.len()
                ),
            ));
        }
        for (c, &tau) in e.tau.iter().enumerate() {
            let field = format!("{path}.tau[{c}]");
            positive(&field, tau)?;
            time(&field, tau)?;
        }
        out.push(ScheduledPeriods {
            at,
            tau: e.tau.clone(),
        });
    }
    Ok(out)
}
