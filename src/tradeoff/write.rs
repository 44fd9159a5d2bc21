//! The study's files: `tradeoff.csv`, `tradeoff.md`, `work_precision.svg`, `pareto.svg`.

use std::fmt::Write as _;
use std::path::Path;

use super::{Status, Study, Variant};
use crate::error::Result;
use crate::output::{create_dir_all, write_atomic};
use crate::report::{write_line_plot, LinePlot, Scale, Series};

/// Writes every file of `study` into `out` (created if needed).
pub fn write_study(out: &Path, study: &Study) -> Result<()> {
    create_dir_all(out)?;
    write_atomic(&out.join("tradeoff.csv"), csv(study).as_bytes())?;
    write_atomic(&out.join("tradeoff.md"), markdown(study).as_bytes())?;
    plots(out, study)
}

/// A CSV field: numbers in shortest round-trip form, NaN as empty.
fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        String::new()
    }
}

/// A CSV text field, quoted (errors contain commas). Always quoted, as the stored
/// tradeoff.csv files have it; `csv::Writer` quotes per writer, not per field
/// (`QuoteStyle::Necessary` would unquote `knob` and `setting` and change the stored
/// bytes), so this table keeps its own writer.
fn text(s: &str) -> String {
    format!("\"{}\"", s.replace('"', "\"\""))
}

fn csv(study: &Study) -> String {
    let mut s = String::from(
        "knob,setting,is_base,dt,integrator,status,error,max_position_error,\
         rms_position_error,base_distance,max_constraint_violation,mean_cost,cost_error,wall_seconds,\
         repeats,body_steps_per_second,pareto\n",
    );
    for row in &study.rows {
        let v = &study.variants[row.variant];
        let m = &v.measured;
        let integrator = v.scenario.as_ref().map_or("", |s| s.integrator.name());
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            text(row.knob),
            text(&row.setting),
            row.is_base,
            num(v.dt()),
            integrator,
            m.status.name(),
            text(m.status.error()),
            num(v.max_position_error),
            num(v.rms_position_error),
            num(v.base_distance),
            num(m.max_violation),
            num(m.mean_cost),
            num(v.cost_error),
            num(m.wall_seconds),
            m.repeats,
            num(v.body_steps_per_second()),
            v.pareto
        );
    }
    s
}

/// Three significant digits in scientific form, `—` for NaN.
fn sci(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.2e}")
    } else {
        "—".into()
    }
}

/// `tradeoff.md`. The table is written by hand rather than with `comfy-table` or
/// `tabled`, for a measured reason: both (comfy-table 7 `ASCII_MARKDOWN`, tabled 0.20
/// `Style::markdown()`) pad every cell to its column's width and write the rule as
/// `|------|`, so every stored tradeoff.md would change bytes, and a row with a long
/// error in `status` would widen every row; the unpadded `| a | b |` rows with a `|---|`
/// rule render the same.
fn markdown(study: &Study) -> String {
    let mut s = String::new();
    let r = &study.reference;
    let _ = writeln!(
        s,
        "# Speed–accuracy trade: {}\n\nHorizon {} s; {} bodies. Reference: monolithic RK4, \
         exact solve, dt_ref = {} µs, same forces and stabilizer; mean cost {:.4e} m, \
         max |w| {:.3e} m, {:.3} s wall. The reference at dt_ref/2 differs from it by at \
         most {:.2e} m (the floor of every error below). Positions compared every {} ms.\n",
        study.name,
        study.horizon.as_secs_f64(),
        study.bodies,
        study.reference_dt.as_nanos() as f64 / 1e3,
        r.mean_cost,
        r.max_violation,
        r.wall_seconds,
        study.reference_error,
        study.compare_every.as_nanos() as f64 / 1e6,
    );
    let _ = writeln!(
        s,
        "Errors are distances of body positions from the reference's [m]; `vs base` is \
         the largest distance from the base run's positions (the knob's own effect); wall \
         time is the fastest of `repeats` runs of the simulation alone. ★ = on the Pareto front of \
         (wall time, max position error); **bold** = the base scenario.\n"
    );
    s.push_str(
        "| knob | setting | dt [ms] | status | max pos. error [m] | RMS pos. error [m] | \
         vs base [m] | max \\|w\\| [m] | cost error [m] | wall [ms] | body-steps/s | front |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for row in &study.rows {
        let v = &study.variants[row.variant];
        let m = &v.measured;
        let setting = if row.is_base {
            format!("**{}**", row.setting)
        } else {
            row.setting.clone()
        };
        let status = match &m.status {
            Status::Ok => "ok".to_string(),
            other => format!("{}: {}", other.name(), other.error().replace('|', "\\|")),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            row.knob,
            setting,
            if v.dt().is_finite() {
                format!("{}", v.dt() * 1e3)
            } else {
                "—".into()
            },
            status,
            sci(v.max_position_error),
            sci(v.rms_position_error),
            sci(v.base_distance),
            sci(m.max_violation),
            sci(v.cost_error),
            if m.wall_seconds.is_finite() {
                format!("{:.2}", m.wall_seconds * 1e3)
            } else {
                "—".into()
            },
            sci(v.body_steps_per_second()),
            if v.pareto { "★" } else { "" },
        );
    }
    if !study.notes.is_empty() {
        s.push_str("\nNotes:\n\n");
        for n in &study.notes {
            let _ = writeln!(s, "- {n}");
        }
    }
    s
}

/// The variants of each knob as (wall time, max error) points, in setting order.
fn knob_series(study: &Study) -> Vec<Series> {
    let mut series: Vec<Series> = Vec::new();
    for row in &study.rows {
        let v = &study.variants[row.variant];
        let point = point(v);
        match series.last_mut() {
            Some(s) if s.label == row.knob => s.points.push(point),
            _ => series.push(Series::new(row.knob, vec![point])),
        }
    }
    series
}

fn point(v: &Variant) -> (f64, f64) {
    match v.measured.status {
        Status::Ok => (v.measured.wall_seconds, v.max_position_error),
        _ => (f64::NAN, f64::NAN),
    }
}

/// `points` with a NaN between each pair, so a line plot draws only their markers.
fn scatter(points: impl IntoIterator<Item = (f64, f64)>) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for p in points {
        if !out.is_empty() {
            out.push((f64::NAN, f64::NAN));
        }
        out.push(p);
    }
    out
}

fn plots(out: &Path, study: &Study) -> Result<()> {
    let series = knob_series(study);
    let title = format!(
        "{} — work-precision over {} s (one knob at a time)",
        study.name,
        study.horizon.as_secs_f64()
    );
    let x_label = "wall time of the run [s]";
    let y_label = "max body-position error vs RK4 reference [m]";
    write_line_plot(
        &out.join("work_precision.svg"),
        &LinePlot {
            title: &title,
            x_label,
            y_label,
            series: &series,
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            step: false,
            markers: true,
        },
    )?;
    let mut front: Vec<(f64, f64)> = study
        .variants
        .iter()
        .filter(|v| v.pareto)
        .map(point)
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let all = scatter(study.variants.iter().map(point));
    let pareto = [
        Series::new("every variant", all),
        Series::new("Pareto front", front),
    ];
    let title = format!("{} — Pareto front of wall time and error", study.name);
    write_line_plot(
        &out.join("pareto.svg"),
        &LinePlot {
            title: &title,
            x_label,
            y_label,
            series: &pareto,
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            step: true,
            markers: true,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scatter_separates_points() {
        let s = scatter([(1.0, 2.0), (3.0, 4.0)]);
        assert_eq!(s.len(), 3);
        assert!(s[1].0.is_nan());
        assert_eq!(text("a,\"b\""), "\"a,\"\"b\"\"\"");
        assert_eq!(num(f64::NAN), "");
    }
}
