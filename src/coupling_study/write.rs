//! The study's files: coupling.csv, coupling.md and the two log-x plots.

use std::path::Path;

use super::{Cell, DISTRIBUTIONS, SCHEMES};
use crate::error::{Error, Result};
use crate::output::write_atomic;
use crate::report::{capitalized, write_line_plot, LinePlot, Scale, Series};

/// Wall time per step of `cell` relative to `reset` at the same τ and distribution.
fn cost_ratio(cells: &[Cell], cell: &Cell) -> f64 {
    cells
        .iter()
        .find(|c| c.scheme == "reset" && c.distribution == cell.distribution && c.tau == cell.tau)
        .map_or(f64::NAN, |r| cell.wall_per_step / r.wall_per_step)
}

pub(super) fn write_csv(out: &Path, cells: &[Cell]) -> Result<()> {
    let path = out.join("coupling.csv");
    let csv_error = |e: csv::Error| Error::io(path.display().to_string(), std::io::Error::other(e));
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "scheme",
        "distribution",
        "tau",
        "bounded",
        "max_w",
        "err_vs_monolithic_0_3s",
        "err_vs_tau_dt_0_3s",
        "energy_drift_undriven",
        "momentum_drift_undriven",
        "angular_momentum_drift_undriven",
        "cost_per_step_vs_reset",
        "error",
    ])
    .map_err(csv_error)?;
    for c in cells {
        w.write_record([
            c.scheme.to_string(),
            c.distribution.to_string(),
            c.tau.to_string(),
            c.bounded().to_string(),
            c.max_w.to_string(),
            c.err_mono.to_string(),
            c.err_dt.to_string(),
            c.energy_drift.to_string(),
            c.momentum_drift.to_string(),
            c.angular_drift.to_string(),
            cost_ratio(cells, c).to_string(),
            c.error.clone().unwrap_or_default(),
        ])
        .map_err(csv_error)?;
    }
    let text = w
        .into_inner()
        .map_err(|e| Error::io(path.display().to_string(), e.into_error()))?;
    write_atomic(&path, &text)
}

pub(super) fn fmt(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.2e}")
    } else {
        "–".into()
    }
}

/// `coupling.md`; its table is written by hand for the reason given at
/// `tradeoff::write::markdown` (the table crates pad cells, changing the stored bytes).
pub(super) fn write_markdown(
    out: &Path,
    name: &str,
    reference: &str,
    cells: &[Cell],
) -> Result<()> {
    let mut text = format!(
        "# Coupling study of {name}\n\nEach sample arrives τ late (latency = τ). Errors: RMS \
         over 0–3 s of the position error of the first and last body (the larger). \
         Over the undriven tail: energy drift (relative change of kinetic energy, signed; \
         under gravity the change of kinetic plus potential energy relative to the kinetic), \
         momentum drift (|ΔP| [kg·m/s]) and angular-momentum drift (|ΔL|/|L|, about the \
         centre of mass; – where gravity or a joint to a world point acts on the net). Cost: wall time per step relative to `reset` at the same τ. \
         {reference}\n\n\
         | scheme | distribution | τ [ms] | bounded | max \\|w\\| [m] | err vs monolithic [m] \
         | err vs τ = dt [m] | energy drift | momentum drift | angular-momentum drift \
         | cost vs reset |\n|---|---|---|---|---|---|---|---|---|---|---|\n"
    );
    for c in cells {
        let bounded = match &c.error {
            None => "yes".to_string(),
            Some(e) => format!("no ({})", e.split(" on node").next().unwrap_or(e)),
        };
        text.push_str(&format!(
            "| {} | {} | {} | {} | {:.3} | {} | {} | {} | {} | {} | {:.2} |\n",
            c.scheme,
            c.distribution,
            c.tau * 1e3,
            bounded,
            c.max_w,
            fmt(c.err_mono),
            fmt(c.err_dt),
            fmt(c.energy_drift),
            fmt(c.momentum_drift),
            fmt(c.angular_drift),
            cost_ratio(cells, c)
        ));
    }
    text.push_str(
        "\nFitted order in τ of the error vs τ = dt (least squares on the logs over the \
         bounded cells of each row):\n\n| scheme | distribution | order in τ | bounded cells |\n\
         |---|---|---|---|\n",
    );
    for &(scheme, _) in &SCHEMES {
        for &distribution in &DISTRIBUTIONS {
            let points: Vec<(f64, f64)> = cells
                .iter()
                .filter(|c| c.scheme == scheme && c.distribution == distribution)
                .filter(|c| c.bounded() && c.err_dt > 0.0 && c.err_dt.is_finite())
                .map(|c| (c.tau.ln(), c.err_dt.ln()))
                .collect();
            text.push_str(&format!(
                "| {scheme} | {distribution} | {} | {} |\n",
                fitted_slope(&points).map_or("–".into(), |s| format!("{s:.2}")),
                points.len()
            ));
        }
    }
    write_atomic(&out.join("coupling.md"), text.as_bytes())
}

/// Least-squares slope of `y` against `x` (none below two distinct points).
fn fitted_slope(points: &[(f64, f64)]) -> Option<f64> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxy: f64 = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = points.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Whether two point lists are the same bit for bit (NaN gaps included).
fn same_bits(a: &[(f64, f64)], b: &[(f64, f64)]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(p, q)| p.0.to_bits() == q.0.to_bits() && p.1.to_bits() == q.1.to_bits())
}

/// One line per scheme and distribution of `value` over τ [ms]; a distribution whose
/// cells equal the space distribution's bit for bit (equal τ on every channel routes
/// every message alike) is named in the space line's label instead of drawn on top of
/// it.
fn scheme_series(cells: &[Cell], value: &dyn Fn(&Cell) -> f64) -> Vec<Series> {
    let mut all = Vec::new();
    for &(scheme, _) in &SCHEMES {
        let points = |distribution: &str| -> Vec<(f64, f64)> {
            // A diverged cell is a gap (NaN breaks the line): a line drawn straight
            // across it would show a bounded run where there is none.
            cells
                .iter()
                .filter(|c| c.scheme == scheme && c.distribution == distribution)
                .map(|c| (c.tau * 1e3, if c.bounded() { value(c) } else { f64::NAN }))
                .collect()
        };
        let space = points(DISTRIBUTIONS[0]);
        let mut same = Vec::new();
        let mut other = Vec::new();
        for &distribution in &DISTRIBUTIONS[1..] {
            let p = points(distribution);
            if same_bits(&p, &space) {
                same.push(distribution);
            } else {
                other.push(Series::new(format!("{scheme}, {distribution}"), p));
            }
        }
        let label = if same.is_empty() {
            format!("{scheme}, space")
        } else {
            format!("{scheme}, space = {}", same.join(" = "))
        };
        all.push(Series::new(label, space));
        all.extend(other);
    }
    all
}

pub(super) fn write_plots(out: &Path, cells: &[Cell]) -> Result<()> {
    let series = |value: &dyn Fn(&Cell) -> f64| scheme_series(cells, value);
    // Every plot: delay on a log axis, bounded cells only (a diverged one is a gap in
    // its line), one line per scheme.
    let plot = |file: &str, what: &str, y_label: &str, y_scale: Scale, series: &[Series]| {
        let title = format!("{} vs delay (bounded runs only)", capitalized(what));
        write_line_plot(
            &out.join(file),
            &LinePlot {
                title: &title,
                x_label: "delay τ = latency [ms]",
                y_label,
                series,
                x_scale: Scale::Log,
                y_scale,
                step: false,
                markers: true,
            },
        )
    };
    plot(
        "error_vs_tau.svg",
        "error per coupling",
        "RMS position error vs monolithic, 0–3 s [m]",
        Scale::Log,
        &series(&|c| c.err_mono),
    )?;
    plot(
        "max_w_vs_tau.svg",
        "largest constraint violation",
        "max |w| over the run [m]",
        Scale::Linear,
        &series(&|c| c.max_w),
    )?;
    plot(
        "energy_vs_tau.svg",
        "energy drift over the undriven tail",
        "relative energy change (kinetic; with gravity + potential) [1]",
        Scale::Linear,
        &series(&|c| c.energy_drift),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell(scheme: &'static str, distribution: &'static str, tau: f64, ok: bool) -> Cell {
        Cell {
            scheme,
            distribution,
            tau,
            error: (!ok).then(|| "diverged".to_string()),
            max_w: 0.1,
            err_mono: tau,
            err_dt: tau,
            energy_drift: 0.0,
            momentum_drift: 0.0,
            angular_drift: 0.0,
            wall_per_step: 1e-6,
        }
    }

    /// A diverged cell between bounded ones is a gap in its line, not a straight
    /// segment across it; a distribution equal to space's (gaps included) is merged.
    #[test]
    fn a_diverged_cell_breaks_its_line() {
        let mut cells = Vec::new();
        for d in DISTRIBUTIONS {
            for (tau, ok) in [(0.003, true), (0.010, false), (0.050, true)] {
                cells.push(cell("predict", d, tau, ok));
            }
        }
        let series = scheme_series(&cells, &|c| c.err_mono);
        let predict: Vec<&Series> = series
            .iter()
            .filter(|s| s.label.starts_with("predict"))
            .collect();
        assert_eq!(predict.len(), 1, "time equals space, gap included");
        assert_eq!(predict[0].label, "predict, space = time");
        let y: Vec<f64> = predict[0].points.iter().map(|p| p.1).collect();
        assert_eq!(y[0], 0.003);
        assert!(y[1].is_nan());
        assert_eq!(y[2], 0.05);
    }

    #[test]
    fn the_fitted_order_of_a_power_law_is_its_exponent() {
        let points: Vec<(f64, f64)> = [0.003f64, 0.01, 0.05]
            .iter()
            .map(|t| (t.ln(), (7.0 * t * t).ln()))
            .collect();
        assert!((fitted_slope(&points).expect("three points") - 2.0).abs() < 1e-12);
        assert_eq!(fitted_slope(&points[..1]), None);
    }
}
