//! The TDMA part of a run's outputs: the `network` section of summary.json, the
//! slot-timeline plot and the list-switch lag plot. Nothing on an ideal network.

use std::path::Path;

use serde_json::{json, Value};

use crate::cosim::CoSim;
use crate::error::Result;
use crate::network::tdma::Jitter;
use crate::report::timeline::{write_slot_timeline, SlotTimeline};
use crate::report::{write_line_plot, LinePlot, Scale, Series};
use crate::trace::Recorder;

/// Adds `network` (the TDMA configuration, frames, losses and list switches) to a
/// summary.
pub(super) fn summarize(world: &CoSim, summary: &mut Value) {
    let Some(link) = world.tdma() else {
        summary["network"] = json!({"kind": "ideal"});
        return;
    };
    let net = link.network();
    let cfg = net.config();
    let secs = |t: crate::kernel::SimTime| t.as_secs_f64();
    let jitter = match cfg.jitter {
        Jitter::None => json!(null),
        Jitter::Uniform { max } => json!({"kind": "uniform", "max": secs(max)}),
        Jitter::Exponential { mean } => json!({"kind": "exponential", "mean": secs(mean)}),
    };
    let switches: Vec<Value> = link
        .switches()
        .iter()
        .map(|s| {
            json!({
                "version": s.version,
                "decided_at": secs(s.decided_at),
                "first_broadcast_cycle": s.first_broadcast,
                "confirmed_in_cycle": s.confirmed_in,
                "effective_cycle": s.effective_cycle,
                "effective_at": secs(s.effective_at),
                "lag": secs(s.lag),
            })
        })
        .collect();
    let lags: Vec<f64> = link.switches().iter().map(|s| secs(s.lag)).collect();
    let layout = net.layout();
    summary["network"] = json!({
        "kind": "tdma",
        "slot": secs(cfg.slot),
        "cycle": secs(cfg.cycle),
        "guard": secs(cfg.guard),
        "dynamic_slots": layout.capacity(),
        "link_rate": if cfg.link_rate.is_finite() { json!(cfg.link_rate) } else { json!("instantaneous") },
        "propagation": secs(cfg.propagation),
        "header_bytes": cfg.header_bytes,
        "drift_ppm": cfg.drift_ppm,
        "random_walk_ppm": cfg.random_walk_ppm,
        "sync_error": secs(cfg.sync_error),
        "jitter": jitter,
        "decision_lag": secs(link.decision_lag()),
        "cycles": net.next_cycle(),
        "lost_frames": net.lost(),
        "random_words_drawn": net.words_drawn() as u64,
        "list_version": net.lists().version(),
        "list_entries": net.lists().active().len(),
        "list_switches": switches,
        "list_switch_lag_mean": (!lags.is_empty()).then(|| lags.iter().sum::<f64>() / lags.len() as f64),
        "list_switch_lag_max": lags.iter().copied().fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.max(x)))),
    });
}

/// `timeline.svg` (a few cycles: who sends when, sync, guard, collisions) and, when
/// lists switched, `list_lag.svg` (decision-to-effect lag of every switch).
pub(super) fn write_plots(out: &Path, world: &CoSim, rec: &Recorder) -> Result<()> {
    let (Some(link), Some(log)) = (world.tdma(), rec.network()) else {
        return Ok(());
    };
    let names: Vec<String> = world
        .channels()
        .iter()
        .map(|c| c.spec.name.clone())
        .collect();
    let cycles = log.timeline();
    if !cycles.is_empty() {
        let first = cycles[0].cycle;
        let title = format!(
            "TDMA slot timeline, cycles {first}–{}",
            first + cycles.len() as u64 - 1
        );
        write_slot_timeline(
            &out.join("timeline.svg"),
            &SlotTimeline {
                title: &title,
                layout: link.network().layout(),
                guard: link.network().config().guard,
                cycles,
                channel_names: &names,
            },
        )?;
    }
    let switches = link.switches();
    if switches.is_empty() {
        return Ok(());
    }
    let points = switches
        .iter()
        .map(|s| (s.decided_at.as_secs_f64(), s.lag.as_secs_f64() * 1e3))
        .collect();
    write_line_plot(
        &out.join("list_lag.svg"),
        &LinePlot {
            title: &String::from("Slot-list switch lag (decision → in force)"),
            x_label: "decision time t [s]",
            y_label: "lag [ms]",
            series: &[Series::new("list switch lag", points)],
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            step: false,
            markers: true,
        },
    )
}
