//! The outputs a controlled run adds: per-method columns in epochs.csv, per-method mean
//! costs in summary.json, and the controller's plots.

use std::path::Path;

use serde_json::{json, Value};

use crate::control::experiment::{channel_names, Candidate, Experiment};
use crate::cosim::CoSim;
use crate::error::Result;
use crate::report::{write_heatmap, write_line_plot, Heatmap, LinePlot, Scale, Series};
use crate::scenario::model::{ControllerSpec, Measure, Problem};

fn spec(world: &CoSim) -> Option<&ControllerSpec> {
    world.scenario().controller.as_ref()
}

/// Names of the controlled coordinates (CP: all channels but the last).
fn controlled_names(world: &CoSim) -> Vec<String> {
    let names = channel_names(&world.scenario().channels);
    match spec(world).map(|s| s.problem) {
        Some(Problem::Constrained { .. }) => names[..names.len() - 1].to_vec(),
        _ => names,
    }
}

/// Extra epochs.csv header columns (empty without a controller).
pub(super) fn epoch_header(world: &CoSim, exp: &Experiment) -> String {
    let Some(spec) = spec(world) else {
        return String::new();
    };
    let mut h = format!(",objective_{}", spec.method.name());
    for b in exp.baseline_names() {
        h.push_str(&format!(",objective_{b}"));
    }
    if exp.windows.iter().any(|w| w.grid_best.is_some()) {
        for n in controlled_names(world) {
            h.push_str(&format!(",grid_opt_tau_{n}"));
        }
    }
    h.push_str(",measurements");
    h
}

/// Extra epochs.csv columns of window `i`.
pub(super) fn epoch_row(world: &CoSim, exp: &Experiment, i: usize) -> String {
    if spec(world).is_none() {
        return String::new();
    }
    let grid = exp.windows.iter().any(|w| w.grid_best.is_some());
    let dims = controlled_names(world).len();
    let Some(w) = exp.windows.get(i) else {
        let blanks = 1 + exp.baseline_names().len() + if grid { dims } else { 0 } + 1;
        return ",".repeat(blanks);
    };
    let mut r = format!(",{}", w.live.objective);
    for b in &w.baselines {
        r.push_str(&format!(",{}", b.candidate.objective));
    }
    if grid {
        match &w.grid_best {
            Some(c) => c.x.iter().for_each(|x| r.push_str(&format!(",{x}"))),
            None => r.push_str(&",".repeat(dims)),
        }
    }
    r.push_str(&format!(",{}", w.dsm_path.len()));
    r
}

/// Adds the controller's settings and `unpaired_mean_cost_<method>` keys to summary.json.
pub(super) fn summarize(world: &CoSim, exp: &Experiment, summary: &mut Value) {
    let Some(spec) = spec(world) else { return };
    let live = spec.method.name();
    let problem = match spec.problem {
        Problem::Constrained { budget } => json!({"kind": "cp", "budget": budget}),
        Problem::Unconstrained { penalty } => json!({"kind": "up", "penalty": penalty}),
    };
    summary["controller"] = json!({
        "method": live,
        "problem": problem,
        "measure": match spec.measure { Measure::Lookahead => "lookahead", Measure::Online => "online" },
        "dsm_size": spec.dsm_size,
        "reflections": spec.reflections,
        "tau_min": spec.tau_min,
        "tau_max": spec.tau_max,
        "windows": exp.windows.len(),
        "cost_meaning": match spec.problem {
            Problem::Constrained { .. } => "window cost C [m]",
            Problem::Unconstrained { .. } => "C + b Σ k/τ (the UP objective)",
        },
    });
    let mut names = vec![live.to_string()];
    names.extend(exp.baseline_names());
    for n in &names {
        if let Some(m) = exp.mean(n, live) {
            summary[format!("unpaired_mean_cost_{n}")] = json!(m);
        }
    }
    // The live method against each baseline over the windows where both were measured
    // (method §5): what a ratio or a verdict may be read from.
    let mut paired = serde_json::Map::new();
    for n in &names[1..] {
        let p = exp.paired(live, n, live);
        let mut v = json!(p);
        v["verdict"] = json!(p.verdict());
        paired.insert(n.clone(), v);
    }
    summary["paired"] = Value::Object(paired);
}

fn step_series(label: String, exp: &Experiment, f: &dyn Fn(usize) -> f64) -> Series {
    let mut points: Vec<(f64, f64)> = exp
        .windows
        .iter()
        .enumerate()
        .map(|(i, w)| (w.t_start.as_secs_f64(), f(i)))
        .collect();
    if let Some(w) = exp.windows.last() {
        points.push((w.t_end.as_secs_f64(), f(exp.windows.len() - 1)));
    }
    Series::new(label, points)
}

/// cost_methods.svg, delays_optimum.svg and (with a surface window) surface.svg and
/// surface.csv.
pub(super) fn write_plots(out: &Path, world: &CoSim, exp: &Experiment) -> Result<()> {
    let Some(spec) = spec(world) else {
        return Ok(());
    };
    if exp.windows.is_empty() {
        return Ok(());
    }
    let live = spec.method.name();
    let cost_label = match spec.problem {
        Problem::Constrained { .. } => "cost C [m]",
        Problem::Unconstrained { .. } => "objective C + bΣk/τ [m]",
    };
    // The live method stands out (black, 3 px, drawn last so that nothing covers it);
    // the baselines it is measured against stay distinguishable but set back (their
    // palette colours, lighter, 1 px).
    let mut series = Vec::new();
    for (j, b) in exp.baseline_names().into_iter().enumerate() {
        series.push(
            step_series(b, exp, &|i| {
                exp.windows[i]
                    .baselines
                    .get(j)
                    .map_or(f64::NAN, |b| b.candidate.objective)
            })
            .styled(crate::report::palette(j + 1, 0.25), 1),
        );
    }
    series.push(
        step_series(format!("{live} (live)"), exp, &|i| {
            exp.windows[i].live.objective
        })
        .styled([0, 0, 0], 3),
    );
    write_line_plot(
        &out.join("cost_methods.svg"),
        &LinePlot {
            title: &String::from("Cost per window by method (black: the live one)"),
            x_label: "time t [s]",
            y_label: cost_label,
            series: &series,
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            step: true,
            markers: false,
        },
    )?;
    let names = controlled_names(world);
    let mut delays = Vec::new();
    for (d, n) in names.iter().enumerate() {
        delays.push(step_series(format!("{live}: {n}"), exp, &|i| {
            exp.windows[i].live.x.get(d).map_or(f64::NAN, |x| x * 1e3)
        }));
        if exp.windows.iter().any(|w| w.grid_best.is_some()) {
            delays.push(step_series(format!("grid optimum: {n}"), exp, &|i| {
                exp.windows[i]
                    .grid_best
                    .as_ref()
                    .and_then(|c| c.x.get(d))
                    .map_or(f64::NAN, |x| x * 1e3)
            }));
        }
    }
    write_line_plot(
        &out.join("delays_optimum.svg"),
        &LinePlot {
            title: &String::from("Controlled delays and the grid optimum"),
            x_label: "time t [s]",
            y_label: "delay τ [ms]",
            series: &delays,
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            step: true,
            markers: false,
        },
    )?;
    write_surface(out, exp, &names)
}

/// The cells of a heatmap over two-delay points: the distinct first and second delays
/// [ms], ascending, and each cell's objective (`values[iy][ix]`; NaN where no point).
pub(super) fn cells_ms(points: &[Candidate]) -> (Vec<f64>, Vec<f64>, Vec<Vec<f64>>) {
    let axis = |k: usize| {
        let mut v: Vec<f64> = points.iter().map(|c| c.x[k]).collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let (xs, ys) = (axis(0), axis(1));
    let at = |axis: &[f64], x: f64| axis.binary_search_by(|v| v.total_cmp(&x)).ok();
    let mut values = vec![vec![f64::NAN; xs.len()]; ys.len()];
    for c in points {
        if let (Some(ix), Some(iy)) = (at(&xs, c.x[0]), at(&ys, c.x[1])) {
            values[iy][ix] = c.objective;
        }
    }
    let ms = |v: Vec<f64>| v.into_iter().map(|x| x * 1e3).collect();
    (ms(xs), ms(ys), values)
}

fn write_surface(out: &Path, exp: &Experiment, names: &[String]) -> Result<()> {
    let Some((t, grid)) = &exp.surface else {
        return Ok(());
    };
    let window = exp.windows.iter().find(|w| w.t_start == *t);
    // The points themselves, for the numbers the plot only shows: the grid, then the
    // DSM's candidates of the window in the order it measured them.
    let mut csv = String::from("method,");
    csv.extend(names.iter().map(|n| format!("tau_{n}_s,")));
    csv.push_str("objective\n");
    let dsm = window.map_or(&[][..], |w| &w.dsm_path[..]);
    let rows = grid
        .iter()
        .map(|c| ("grid", c))
        .chain(dsm.iter().map(|c| ("dsm", c)));
    for (method, c) in rows {
        csv.push_str(method);
        for x in &c.x {
            csv.push_str(&format!(",{x}"));
        }
        csv.push_str(&format!(",{}\n", c.objective));
    }
    crate::output::write_atomic(&out.join("surface.csv"), csv.as_bytes())?;
    let path: Vec<(f64, f64)> = window
        .map(|w| {
            w.dsm_path
                .iter()
                .map(|c| (c.x[0] * 1e3, c.objective))
                .collect()
        })
        .unwrap_or_default();
    let t0 = t.as_secs_f64();
    let t1 = window.map_or(t0, |w| w.t_end.as_secs_f64());
    let title = format!("Cost surface over [{t0}, {t1}) s with the DSM path");
    if names.len() == 1 {
        let curve = Series::new(
            "grid search",
            grid.iter().map(|c| (c.x[0] * 1e3, c.objective)).collect(),
        );
        let dsm = Series::new("DSM candidates (in order)", path);
        return write_line_plot(
            &out.join("surface.svg"),
            &LinePlot {
                title: &title,
                x_label: &format!("controlled delay {} [ms]", names[0]),
                y_label: "window objective [m]",
                series: &[curve, dsm],
                x_scale: Scale::Linear,
                y_scale: Scale::Linear,
                step: false,
                markers: true,
            },
        );
    }
    if names.len() != 2 {
        return Ok(());
    }
    // 2-D: a heatmap over the grid axes; infeasible cells stay missing.
    let (xs_ms, ys_ms, values) = cells_ms(grid);
    let overlay: Vec<(f64, f64)> = window
        .map(|w| {
            w.dsm_path
                .iter()
                .map(|c| (c.x[0] * 1e3, c.x[1] * 1e3))
                .collect()
        })
        .unwrap_or_default();
    write_heatmap(
        &out.join("surface.svg"),
        &Heatmap {
            title: &title,
            x_label: &format!("{} [ms]", names[0]),
            y_label: &format!("{} [ms]", names[1]),
            value_label: "window objective [m]",
            x: &xs_ms,
            y: &ys_ms,
            values: &values,
            path_overlay: &overlay,
            line_overlay: &[],
            categories: [None, None],
            classes: None,
        },
    )
}
