//! Plots of a sweep: `cost_vs_<axis>.svg` (mean cost against the first numeric axis,
//! and for controlled runs with a live DSM `dsm_over_grid_vs_<axis>.svg` and
//! `dsm_over_no_opt_vs_<axis>.svg`, its mean cost over those baselines' in each run,
//! one line per combination of the other axes' values under `factorial`, averaged over
//! draw axes — those whose pointer is `/seed` — with min–max bars) and, with two
//! or more axes, `cost_heatmap.svg` (mean cost over the first two axes; cells holding
//! several points, under three or more axes, show their mean).
//!
//! An axis whose values are not all numbers is drawn at the index of each value, and
//! its label says so. Legends name a value by the axis's `labels` entry when the sweep
//! file gives one, else by the value itself when it is at most 16 characters, else by
//! `#<index>`.

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::Value;

use super::file::Combine;
use super::points::{Axis, Plan};
use super::record::Record;
use crate::error::Result;
use crate::report::{write_heatmap, write_line_plot, Heatmap, LinePlot, Series};

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

/// The ratio of the DSM's mean cost to a baseline's in one run (NaN where either is
/// missing).
fn dsm_over(r: &Record, baseline: &str) -> f64 {
    let get = |m: &str| r.row.mean_cost_by_method.get(m).copied().flatten();
    match (get("dsm"), get(baseline)) {
        (Some(d), Some(b)) => d / b,
        _ => f64::NAN,
    }
}

/// Writes the plots of `records` (sorted by index) into `out`.
pub fn write(out: &Path, plan: &Plan, records: &[Record]) -> Result<()> {
    cost_vs(out, plan, records, &Metric::COST)?;
    // Controlled runs with a live DSM: its cost over the baselines' in the same run (the
    // ratio compares methods on the same windows, where the costs themselves also move
    // with each run's own trajectory).
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
    if let Some(labels) = &axis.labels {
        return labels[v].clone();
    }
    let text = match &axis.values[v] {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    };
    if text.chars().count() <= SHORT_VALUE {
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
    let others: Vec<usize> = (0..plan.axes.len())
        .filter(|&k| k != xa && !draws.contains(&k))
        .collect();
    let grouped = plan.combine == Combine::Factorial && !others.is_empty();
    // Lines keyed by the other axes' value indices, so they come in axis order; within
    // a line, the costs of each x value (over the draws) in point order.
    let mut lines: BTreeMap<Vec<usize>, BTreeMap<usize, Vec<f64>>> = BTreeMap::new();
    for r in records {
        let idx = &plan.points[r.index];
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
    let averaged = !draws.is_empty();
    let series: Vec<Series> = lines
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
    let name = &plan.axes[xa].name;
    let mut title = format!("{} — {} vs {name}", plan.name, metric.what);
    if averaged {
        let over: Vec<&str> = draws.iter().map(|&k| plan.axes[k].name.as_str()).collect();
        title.push_str(&format!(" (mean over {}; bars: min–max)", over.join(", ")));
    }
    write_line_plot(
        &out.join(format!("{}_vs_{name}.svg", metric.file)),
        &LinePlot {
            markers: true,
            ..LinePlot::new(&title, &x_label, metric.label, &series)
        },
    )
}

/// Cell centres (sorted distinct coordinates) and, per value index, its cell.
fn cells(coords: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let mut centres = coords.to_vec();
    centres.sort_by(f64::total_cmp);
    centres.dedup();
    let cell = coords
        .iter()
        .map(|c| centres.partition_point(|x| x < c))
        .collect();
    (centres, cell)
}

/// `cost_heatmap.svg` over the first two axes.
fn heatmap(out: &Path, plan: &Plan, records: &[Record]) -> Result<()> {
    let (xs, x_label) = coordinates(&plan.axes[0]);
    let (ys, y_label) = coordinates(&plan.axes[1]);
    let (x, x_cell) = cells(&xs);
    let (y, y_cell) = cells(&ys);
    let mut sums = vec![vec![(0.0, 0usize); x.len()]; y.len()];
    let mut shared = false;
    for r in records {
        let idx = &plan.points[r.index];
        let c = cost(r);
        if c.is_finite() {
            let cell = &mut sums[y_cell[idx[1]]][x_cell[idx[0]]];
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
    let mut title = format!("{} — mean cost", plan.name);
    if shared {
        let rest: Vec<&str> = plan.axes[2..].iter().map(|a| a.name.as_str()).collect();
        if rest.is_empty() {
            title.push_str(" (mean over points with equal values)");
        } else {
            title.push_str(&format!(" (mean over {})", rest.join(", ")));
        }
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
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_sort_and_merge_equal_coordinates() {
        let (c, cell) = cells(&[2.0, 0.5, 2.0, 1.0]);
        assert_eq!(c, vec![0.5, 1.0, 2.0]);
        assert_eq!(cell, vec![2, 0, 2, 1]);
    }
}
