//! The landscape of a two-channel constrained run (`controller.surface_window`): the
//! window cost over every grid pair of delays, the budget ignored, written as
//! landscape.csv, drawn as landscape.svg with the budget line and the window's DSM
//! candidates, and summarized in summary.json (`landscape`).
//!
//! The constrained problem only ever runs on the budget line; the landscape shows what
//! lies off it: whether the line's optimum is a valley of the whole space crossing it or
//! a slope running into it, and how far equal delays are from either.

use std::fmt::Write as _;
use std::path::Path;

use serde_json::{json, Value};

use crate::control::experiment::{channel_names, Candidate, Experiment};
use crate::control::problem::Delays;
use crate::cosim::CoSim;
use crate::error::Result;
use crate::output::write_atomic;
use crate::report::{write_heatmap, Heatmap};

/// The best finite point of `points`.
fn best(points: &[Candidate]) -> Option<&Candidate> {
    points
        .iter()
        .filter(|c| c.objective.is_finite())
        .min_by(|a, b| a.objective.total_cmp(&b.objective))
}

/// Adds `landscape` to summary.json: its window, size, the best pair overall and the
/// best pair on the budget line (the grid optimum of that window).
pub(super) fn summarize(world: &CoSim, exp: &Experiment, summary: &mut Value) {
    let Some((t, points)) = &exp.landscape else {
        return;
    };
    let pair = |c: &Candidate| json!({"taus_s": c.x, "cost_m": c.objective});
    let window = exp.windows.iter().find(|w| w.t_start == *t);
    let on_budget = window.and_then(|w| w.grid_best.as_ref()).and_then(|g| {
        let spec = world.scenario().controller.as_ref()?;
        let delays = Delays::new(spec, &world.scenario().channels, world.scenario().dt);
        let taus = delays.taus(&g.x)?;
        Some(json!({"taus_s": taus, "cost_m": g.objective}))
    });
    summary["landscape"] = json!({
        "t_start": t.as_secs_f64(),
        "t_end": window.map(|w| w.t_end.as_secs_f64()),
        "points": points.len(),
        "diverged_points": points.iter().filter(|c| c.objective.is_infinite()).count(),
        "best": best(points).map(pair),
        "best_on_budget_line": on_budget,
    });
}

/// Writes landscape.csv and landscape.svg (nothing without a landscape).
pub(super) fn write(out: &Path, world: &CoSim, exp: &Experiment) -> Result<()> {
    let Some((t, points)) = &exp.landscape else {
        return Ok(());
    };
    let Some(spec) = world.scenario().controller.as_ref() else {
        return Ok(());
    };
    let names = channel_names(&world.scenario().channels);
    let mut csv = format!("tau_{}_s,tau_{}_s,cost_m\n", names[0], names[1]);
    for c in points {
        // A diverged fork scores +∞: written as `inf`, the one non-finite value here.
        let _ = writeln!(csv, "{},{},{}", c.x[0], c.x[1], c.objective);
    }
    write_atomic(&out.join("landscape.csv"), csv.as_bytes())?;

    let (xs_ms, ys_ms, values) = super::controlled::cells_ms(points);
    let delays = Delays::new(spec, &world.scenario().channels, world.scenario().dt);
    let (lo, hi) = (spec.tau_min, spec.tau_max);
    // The budget line inside the square, sampled along both axes (it is steep at one
    // end and flat at the other; the budget is symmetric in the two channels' roles).
    let samples = (0..=400).map(|i| lo + (hi - lo) * f64::from(i) / 400.0);
    let mut budget: Vec<(f64, f64)> = samples
        .clone()
        .filter_map(|t1| Some((t1, delays.budget_partner(0, t1)?)))
        .chain(samples.filter_map(|t2| Some((delays.budget_partner(1, t2)?, t2))))
        .filter(|&(t1, t2)| (lo..=hi).contains(&t1) && (lo..=hi).contains(&t2))
        .map(|(t1, t2)| (t1 * 1e3, t2 * 1e3))
        .collect();
    budget.sort_by(|a, b| a.0.total_cmp(&b.0));
    let window = exp.windows.iter().find(|w| w.t_start == *t);
    let path: Vec<(f64, f64)> = window
        .map(|w| {
            w.dsm_path
                .iter()
                .filter_map(|c| delays.taus(&c.x))
                .map(|taus| (taus[0] * 1e3, taus[1] * 1e3))
                .collect()
        })
        .unwrap_or_default();
    let t0 = t.as_secs_f64();
    let t1 = window.map_or(t0, |w| w.t_end.as_secs_f64());
    let title = format!("Window cost over [{t0}, {t1}) s");
    write_heatmap(
        &out.join("landscape.svg"),
        &Heatmap {
            title: &title,
            x_label: &format!(
                "delay {} [ms]   (white: budget line; red: DSM candidates; grey: fork diverged)",
                names[0]
            ),
            y_label: &format!("delay {} [ms]", names[1]),
            value_label: "window cost C [m]",
            x: &xs_ms,
            y: &ys_ms,
            values: &values,
            path_overlay: &path,
            line_overlay: &budget,
            categories: [None, None],
            classes: None,
        },
    )
}
