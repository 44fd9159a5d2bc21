//! Plots of a sweep: `cost_vs_<axis>.svg` (mean cost against the first numeric axis,
//! and for controlled runs with a live DSM `dsm_over_grid_vs_<axis>.svg` and
//! `dsm_over_no_opt_vs_<axis>.svg`, its mean cost over those baselines' in each run over
//! the windows where both were measured,
//! one line per combination of the other axes' values under `factorial`, averaged over
//! draw axes — those whose pointer is `/seed` — with min–max bars) and, with two
//! or more axes, `cost_heatmap.svg` (mean cost over the first two axes; cells holding
//! several points, under three or more axes, show their mean).
//!
//! An axis whose values are not all numbers is drawn at the index of each value, and
//! its label says so. A numeric x axis whose values span two decades or more (a drift
//! of 0–30 000 ppm) is a log axis, 0 drawn a decade below the smallest positive value,
//! as its label says; the heatmap turns long value names under its cells. Legends name a value by the axis's `labels` entry when the sweep
//! file gives one, else by the value itself when it is at most 16 characters, else by
//! `#<index>`.
//!
//! A point whose run diverged is not data: it is left out of every mean, bar and
//! heatmap cell, drawn as a black cross at the top of the data (no higher than the cost
//! it had reached: its value would stretch the axis over the data), and counted in the
//! legend (`diverged: 6 of 600 points`) and, on the heatmap, in the title.

use std::collections::BTreeMap;
use std::path::Path;

use super::file::Combine;
use super::points::{Axis, Plan};
use super::record::Record;
use crate::error::Result;
use crate::report::{write_heatmap, write_line_plot, Heatmap, LinePlot, Scale, Series};

/// Label of the mean cost.
const COST: &str = "mean cost C [m]";

/// The unit of a scenario field, from the pointer's last token (and its first, where
/// the last alone is ambiguous); `None` where not known.
fn unit(axis: &Axis) -> Option<&'static str> {
    let tokens = axis.pointer.tokens();
    let first = tokens.first().map(String::as_str);
    let last = tokens.last().map(String::as_str)?;
    Some(match (first, last) {
        (Some("stabilizer"), "k") => "m/s",
        (Some("stabilizer"), "epsilon") => "m",
        (Some("stabilizer"), "alpha" | "beta") => "1/s",
        (Some("model"), "size" | "spacing") => "m",
        (Some("model"), "mass") => "kg",
        (Some("controller"), "size") => "s",
        (_, "duration" | "dt" | "tau" | "latency" | "period" | "offset" | "mu") => "s",
        (_, "slot" | "cycle" | "guard" | "propagation" | "sync_error" | "mean" | "max") => "s",
        (_, "tau_min" | "tau_max" | "grid_step" | "dsm_delta" | "surface_window") => "s",
        (_, "from" | "until" | "t0" | "t1" | "decision_time") => "s",
        (_, "drift_ppm") => "ppm",
        (_, "random_walk_ppm") => "ppm/√s",
        (_, "link_rate") => "bit/s",
        (_, "header_bytes") => "B",
        (_, "budget") => "1/s",
        (_, "penalty") => "m·s",
        (_, "omega") => "rad/s",
        (_, "max_violation") => "m",
        _ => return None,
    })
}

/// Coordinates of an axis's values and its label: the numbers themselves, or the
/// value indices for an axis with a non-numeric value.
fn coordinates(axis: &Axis) -> (Vec<f64>, String) {
    match axis.numbers() {
        Some(x) => {
            let label = match unit(axis) {
                Some(u) => format!("{} [{u}]", axis.name),
                None => axis.name.clone(),
            };
            (x, label)
        }
        None => (
            (0..axis.values.len()).map(|i| i as f64).collect(),
            format!("{} (index of the value; values are not numbers)", axis.name),
        ),
    }
}

/// Mean cost of a record, NaN if none.
fn cost(r: &Record) -> f64 {
    r.row.mean_cost.unwrap_or(f64::NAN)
}

/// Whether a point's run diverged (or failed otherwise): not data for means.
fn diverged(r: &Record) -> bool {
    r.row.status != "ok"
}

/// The DSM's cost over a baseline's in one run, as the ratio of their means over the
/// windows where both were measured (NaN where the run's live method is not the DSM or
/// the pair has no window).
fn dsm_over(r: &Record, baseline: &str) -> f64 {
    if r.row.live_method.as_deref() != Some("dsm") {
        return f64::NAN;
    }
    r.row
        .paired
        .get(baseline)
        .and_then(|p| p.ratio)
        .unwrap_or(f64::NAN)
}

/// Writes the plots of `records` (sorted by index) into `out`.
pub fn write(out: &Path, plan: &Plan, records: &[Record]) -> Result<()> {
    cost_vs(out, plan, records, &Metric::COST)?;
    // Controlled runs with a live DSM: its cost over the baselines' in the same run, on
    // the windows where both were measured (the costs themselves also move with each
    // run's own trajectory).
    for m in [Metric::DSM_OVER_GRID, Metric::DSM_OVER_NO_OPT] {
        if records.iter().any(|r| (m.value)(r).is_finite()) {
            cost_vs(out, plan, records, &m)?;
        }
    }
    if plan.axes.len() >= 2 {
        heatmap(out, plan, records)?;
    }
    Ok(())
}

/// Whether `axis` only draws seeds (its pointer is `/seed`): such an axis repeats the
/// same setting on other random draws, so the line plot averages over it.
fn is_draw(axis: &Axis) -> bool {
    axis.pointer.tokens() == ["seed"]
}

/// Longest value shown as itself in a legend; longer ones are shown by index.
const SHORT_VALUE: usize = 16;

/// Legend text of value `v` of `axis`: its label from the sweep file, else the value
/// when short, else `#<index>`.
fn value_label(axis: &Axis, v: usize) -> String {
    let text = axis.label(v);
    if axis.labels.is_some() || text.chars().count() <= SHORT_VALUE {
        text
    } else {
        format!("#{v}")
    }
}

/// What a line plot of a sweep shows per point.
struct Metric {
    /// File name before `_vs_<axis>.svg`.
    file: &'static str,
    /// Title words before `vs <axis>`.
    what: &'static str,
    /// y-axis label, with the unit.
    label: &'static str,
    /// The value of one point (NaN where it has none).
    value: fn(&Record) -> f64,
}

impl Metric {
    const COST: Metric = Metric {
        file: "cost",
        what: "mean cost",
        label: COST,
        value: cost,
    };
    const DSM_OVER_GRID: Metric = Metric {
        file: "dsm_over_grid",
        what: "DSM / grid optimum (mean costs)",
        label: "DSM / grid optimum [1]",
        value: |r| dsm_over(r, "grid"),
    };
    const DSM_OVER_NO_OPT: Metric = Metric {
        file: "dsm_over_no_opt",
        what: "DSM / no optimization (mean costs)",
        label: "DSM / no optimization [1]",
        value: |r| dsm_over(r, "no_opt"),
    };
}

/// `<metric>_vs_<axis>.svg`: a metric (mean cost, or the DSM's ratio to a baseline)
/// against the first numeric axis that is not a draw axis, one line per combination of
/// the other non-draw axes (under `factorial`). Draw axes (pointer `/seed`) are averaged
/// over: each marker is the mean of the finite values over the draws, with a bar from
/// their minimum to their maximum.
fn cost_vs(out: &Path, plan: &Plan, records: &[Record], metric: &Metric) -> Result<()> {
    let draws: Vec<usize> = (0..plan.axes.len())
        .filter(|&k| plan.combine == Combine::Factorial && is_draw(&plan.axes[k]))
        .collect();
    let xa = (0..plan.axes.len())
        .find(|&k| !draws.contains(&k) && plan.axes[k].numbers().is_some())
        .or_else(|| (0..plan.axes.len()).find(|k| !draws.contains(k)))
        .unwrap_or(0);
    let draws: Vec<usize> = draws.into_iter().filter(|&k| k != xa).collect();
    let (x, x_label) = coordinates(&plan.axes[xa]);
    let (x, x_label, x_scale) = match plan.axes[xa].numbers().and_then(|_| log_axis(&x)) {
        Some((x, note)) => (x, format!("{x_label}, {note}"), Scale::Log),
        None => (x, x_label, Scale::Linear),
    };
    let others: Vec<usize> = (0..plan.axes.len())
        .filter(|&k| k != xa && !draws.contains(&k))
        .collect();
    let grouped = plan.combine == Combine::Factorial && !others.is_empty();
    // Lines keyed by the other axes' value indices, so they come in axis order; within
    // a line, the costs of each x value (over the draws) in point order.
    let mut lines: BTreeMap<Vec<usize>, BTreeMap<usize, Vec<f64>>> = BTreeMap::new();
    let mut failed = Vec::new();
    for r in records {
        let idx = &plan.points[r.index];
        if diverged(r) {
            failed.push((x[idx[xa]], (metric.value)(r)));
            continue;
        }
        let key = if grouped {
            others.iter().map(|&k| idx[k]).collect()
        } else {
            Vec::new()
        };
        lines
            .entry(key)
            .or_default()
            .entry(idx[xa])
            .or_default()
            .push((metric.value)(r));
    }
    let averaged = !draws.is_empty() || plan.repeat > 1;
    let mut series: Vec<Series> = lines
        .into_iter()
        .map(|(key, by_x)| {
            let mut points = Vec::new();
            let mut bars = Vec::new();
            for (xi, costs) in by_x {
                let finite: Vec<f64> = costs.into_iter().filter(|c| c.is_finite()).collect();
                if finite.is_empty() {
                    points.push((x[xi], f64::NAN));
                    continue;
                }
                let mean = finite.iter().sum::<f64>() / finite.len() as f64;
                points.push((x[xi], mean));
                if averaged {
                    let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
                    let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    bars.push((x[xi], lo, hi));
                }
            }
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            let label = if grouped {
                others
                    .iter()
                    .zip(&key)
                    .map(|(&k, &v)| {
                        format!("{} = {}", plan.axes[k].name, value_label(&plan.axes[k], v))
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            } else {
                metric.what.to_string()
            };
            Series::new(label, points).with_bars(bars)
        })
        .collect();
    if !failed.is_empty() {
        // Drawn at the data's top edge, not at the cost a run had reached when it
        // diverged: those values (10-100x the data) stretched the axis until the
        // layouts' lines were one band.
        let top = series
            .iter()
            .flat_map(|s| {
                s.points
                    .iter()
                    .map(|p| p.1)
                    .chain(s.bars.iter().map(|b| b.2))
            })
            .filter(|y| y.is_finite())
            .fold(f64::NEG_INFINITY, f64::max);
        let failed = if top.is_finite() {
            failed
                .into_iter()
                .map(|(x, y)| (x, if y.is_finite() { y.min(top) } else { top }))
                .collect()
        } else {
            failed
        };
        series.push(Series::crosses(
            format!(
                "diverged: {} of {} points (left out; at the cost reached, capped at the top)",
                failed.len(),
                records.len()
            ),
            failed,
        ));
    }
    let name = &plan.axes[xa].name;
    let mut title = format!("{} vs {name}", crate::report::capitalized(metric.what));
    if averaged {
        let mut over: Vec<&str> = draws.iter().map(|&k| plan.axes[k].name.as_str()).collect();
        if plan.repeat > 1 {
            over.push("rep");
        }
        title.push_str(&format!(" (mean over {}; bars: min–max)", over.join(", ")));
    }
    write_line_plot(
        &out.join(format!("{}_vs_{name}.svg", metric.file)),
        &LinePlot {
            markers: true,
            x_scale,
            ..LinePlot::new(&title, &x_label, metric.label, &series)
        },
    )
}

/// Values that span two decades or more (largest over smallest positive ≥ 100) and are
/// never negative go on a log axis, which a linear one would squeeze into a sliver at
/// its left; a value 0, which a log axis cannot place, is drawn a decade below the
/// smallest positive value and the axis label says so. Returns the coordinates and that
/// note, or `None` for a linear axis.
fn log_axis(x: &[f64]) -> Option<(Vec<f64>, String)> {
    if x.iter().any(|&v| v < 0.0 || !v.is_finite()) {
        return None;
    }
    let positive = x.iter().copied().filter(|&v| v > 0.0);
    let lo = positive.clone().fold(f64::INFINITY, f64::min);
    let hi = positive.fold(0.0, f64::max);
    if !(lo.is_finite() && hi / lo >= 100.0) {
        return None;
    }
    let zero_at = lo / 10.0;
    let note = if x.contains(&0.0) {
        format!("log axis (0 drawn at {})", crate::error::num(zero_at))
    } else {
        "log axis".to_string()
    };
    let x = x
        .iter()
        .map(|&v| if v == 0.0 { zero_at } else { v })
        .collect();
    Some((x, note))
}

/// `cost_heatmap.svg` over the first two axes: one equally wide cell per value of
/// each, named by the value's label (a linear axis would make the cells of uneven
/// values uneven, and cannot place values that are not numbers).
fn heatmap(out: &Path, plan: &Plan, records: &[Record]) -> Result<()> {
    let names =
        |a: &Axis| -> Vec<String> { (0..a.values.len()).map(|v| value_label(a, v)).collect() };
    let label = |a: &Axis| match unit(a) {
        Some(u) if a.numbers().is_some() => format!("{} [{u}]", a.name),
        _ => a.name.clone(),
    };
    let (x_names, y_names) = (names(&plan.axes[0]), names(&plan.axes[1]));
    let (x_label, y_label) = (label(&plan.axes[0]), label(&plan.axes[1]));
    let x: Vec<f64> = (0..x_names.len()).map(|i| i as f64).collect();
    let y: Vec<f64> = (0..y_names.len()).map(|i| i as f64).collect();
    let mut sums = vec![vec![(0.0, 0usize); x.len()]; y.len()];
    let mut shared = false;
    let failed = records.iter().filter(|r| diverged(r)).count();
    for r in records.iter().filter(|r| !diverged(r)) {
        let idx = &plan.points[r.index];
        let c = cost(r);
        if c.is_finite() {
            let cell = &mut sums[idx[1]][idx[0]];
            shared |= cell.1 > 0;
            cell.0 += c;
            cell.1 += 1;
        }
    }
    let values: Vec<Vec<f64>> = sums
        .iter()
        .map(|row| {
            row.iter()
                .map(|&(s, n)| if n == 0 { f64::NAN } else { s / n as f64 })
                .collect()
        })
        .collect();
    let mut title = String::from("Mean cost");
    if shared {
        let mut rest: Vec<&str> = plan.axes[2..].iter().map(|a| a.name.as_str()).collect();
        if plan.repeat > 1 {
            rest.push("rep");
        }
        if rest.is_empty() {
            title.push_str(" (mean over points with equal values)");
        } else {
            title.push_str(&format!(" (mean over {})", rest.join(", ")));
        }
    }
    if failed > 0 {
        title.push_str(&format!(
            "; {failed} of {} diverged, left out",
            records.len()
        ));
    }
    write_heatmap(
        &out.join("cost_heatmap.svg"),
        &Heatmap {
            title: &title,
            x_label: &x_label,
            y_label: &y_label,
            value_label: COST,
            x: &x,
            y: &y,
            values: &values,
            path_overlay: &[],
            line_overlay: &[],
            categories: [Some(&x_names), Some(&y_names)],
            classes: None,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::log_axis;

    #[test]
    fn values_over_decades_go_on_a_log_axis_with_zero_a_decade_below() {
        let drift = [0.0, 300.0, 1000.0, 3000.0, 10000.0, 30000.0];
        let (x, note) = log_axis(&drift).expect("a log axis");
        assert_eq!(x, [30.0, 300.0, 1000.0, 3000.0, 10000.0, 30000.0]);
        assert_eq!(note, "log axis (0 drawn at 30)");
        let (x, note) = log_axis(&[1.0, 10.0, 100.0]).unwrap();
        assert_eq!((x, note.as_str()), (vec![1.0, 10.0, 100.0], "log axis"));
        // Less than two decades, a negative value or nothing positive: linear.
        assert!(log_axis(&[0.002, 0.004, 0.008]).is_none());
        assert!(log_axis(&[-1.0, 10.0, 1000.0]).is_none());
        assert!(log_axis(&[0.0, 0.0]).is_none());
        assert!(log_axis(&[]).is_none());
    }
}
