//! The study's files: `tradeoff.csv`, `tradeoff.md`, `work_precision.svg`, `pareto.svg`.

use std::fmt::Write as _;
use std::path::Path;

use super::{Status, Study, Variant};
use crate::error::Result;
use crate::output::{create_out_dir, write_atomic};
use crate::report::{write_line_plot, LinePlot, Scale, Series};

/// Writes every file of `study` into `out` (created if needed).
pub fn write_study(out: &Path, study: &Study) -> Result<()> {
    create_out_dir(out)?;
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

/// Whether the knob named `name` has ordered settings (see [`super::Knob::ordered`]).
fn ordered(name: &str) -> bool {
    super::KNOBS
        .iter()
        .find(|k| k.name == name)
        .is_some_and(|k| k.ordered)
}

/// The variants of each knob as (wall time, max error) points, in setting order: a
/// line through an ordered knob's settings (one integrator over `dt`), separate
/// labelled markers for a categorical knob's (integrators, solvers), so no line ever
/// joins two integrators. The base run, shared by every knob, is one black marker
/// labelled `base`, drawn last.
fn knob_series(study: &Study) -> Vec<Series> {
    let mut series: Vec<Series> = Vec::new();
    let mut base = None;
    for row in &study.rows {
        let v = &study.variants[row.variant];
        let point = point(v);
        if row.is_base {
            base = Some(point);
        }
        // The base point is labelled once, by its own series.
        let label = if row.is_base {
            String::new()
        } else {
            row.setting.clone()
        };
        match series.last_mut() {
            Some(s) if s.label == row.knob => {
                s.points.push(point);
                s.labels.push(label);
            }
            _ => {
                let s = if ordered(row.knob) {
                    Series::new(row.knob, vec![point])
                } else {
                    Series::points(row.knob, vec![point]).with_labels(vec![label])
                };
                series.push(s);
            }
        }
    }
    for s in &mut series {
        if !s.points_only {
            s.labels.clear();
        }
    }
    if let Some(p) = base {
        series.push(
            Series::points("base scenario", vec![p])
                .with_labels(vec!["base".into()])
                .styled([0, 0, 0], 2),
        );
    }
    series
}

fn point(v: &Variant) -> (f64, f64) {
    match v.measured.status {
        Status::Ok => (v.measured.wall_seconds, v.max_position_error),
        _ => (f64::NAN, f64::NAN),
    }
}

/// A variant's name beside its marker: `base`, the setting (`rk4`, `cg 5`), or knob
/// and setting where the setting is a bare number (`dt 0.5 ms`; `rk4 2 ms` for the
/// knob `dt, rk4`). The first row that ran the variant names it.
fn short_names(study: &Study) -> Vec<String> {
    let mut names = vec![String::new(); study.variants.len()];
    for row in &study.rows {
        let Some(name) = names.get_mut(row.variant) else {
            continue;
        };
        if !name.is_empty() {
            continue;
        }
        *name = if row.is_base {
            "base".into()
        } else if row.setting.starts_with(|c: char| c.is_ascii_digit()) {
            // `dt, rk4` + `2 ms` is `rk4 2 ms`.
            let knob = row.knob.strip_prefix("dt, ").unwrap_or(row.knob);
            format!("{knob} {}", row.setting)
        } else {
            row.setting.clone()
        };
    }
    names
}

/// The work-precision plot: one series per knob (see [`knob_series`]).
fn work_precision_plot<'a>(series: &'a [Series], title: &'a str) -> LinePlot<'a> {
    LinePlot {
        title,
        x_label: X_LABEL,
        y_label: Y_LABEL,
        series,
        x_scale: Scale::Log,
        y_scale: Scale::Log,
        step: false,
        markers: true,
    }
}

/// The Pareto plot's series: every variant as a labelled marker, and the front as a
/// staircase.
fn pareto_series(study: &Study) -> [Series; 2] {
    let mut front: Vec<(f64, f64)> = study
        .variants
        .iter()
        .filter(|v| v.pareto)
        .map(point)
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let all = study.variants.iter().map(point).collect();
    [
        Series::points("every variant", all).with_labels(short_names(study)),
        Series::new("Pareto front", front),
    ]
}

/// x label of both plots.
const X_LABEL: &str = "wall time of the run [s]";
/// y label of both plots.
const Y_LABEL: &str = "max body-position error vs RK4 reference [m]";

fn plots(out: &Path, study: &Study) -> Result<()> {
    let series = knob_series(study);
    let title = format!(
        "Work-precision over {} s (one knob at a time)",
        study.horizon.as_secs_f64()
    );
    write_line_plot(
        &out.join("work_precision.svg"),
        &work_precision_plot(&series, &title),
    )?;
    let pareto = pareto_series(study);
    let title = String::from("Pareto front of wall time and error");
    write_line_plot(
        &out.join("pareto.svg"),
        &LinePlot {
            title: &title,
            x_label: X_LABEL,
            y_label: Y_LABEL,
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

    use crate::kernel::SimTime;
    use crate::tradeoff::{Measured, Row};

    /// A study of 8 variants: dt (0.5, 1 = base, 2 ms), integrator (euler = base,
    /// symplectic_euler, rk4), dt under rk4 (0.5, 1 ms = the rk4 variant), solver
    /// (cholesky = base, cg 5), and one diverged variant (dt 4 ms).
    fn study() -> Study {
        let variant = |wall: f64, error: f64, ok: bool| {
            let mut measured = Measured::invalid(String::new());
            if ok {
                measured.status = Status::Ok;
            } else {
                measured.status = Status::Diverged("diverged".into());
            }
            measured.wall_seconds = wall;
            Variant {
                scenario: None,
                measured,
                max_position_error: error,
                rms_position_error: error,
                cost_error: 0.0,
                base_distance: 0.0,
                pareto: false,
            }
        };
        let mut variants = vec![
            variant(0.014, 0.03, true),  // 0: dt 0.5 ms
            variant(0.007, 0.06, true),  // 1: base
            variant(0.0035, 0.12, true), // 2: dt 2 ms
            variant(0.007, 0.016, true), // 3: symplectic_euler
            variant(0.028, 5e-10, true), // 4: rk4
            variant(0.056, 3e-11, true), // 5: rk4 0.5 ms
            variant(0.004, 0.06, true),  // 6: cg 5
            variant(0.002, 1.0, false),  // 7: dt 4 ms, diverged
        ];
        for i in [2, 4, 5, 6] {
            variants[i].pareto = true;
        }
        let row = |knob: &'static str, setting: &str, variant: usize| Row {
            knob,
            setting: setting.into(),
            is_base: variant == 1,
            variant,
        };
        Study {
            name: "tiny".into(),
            horizon: SimTime::from_secs_f64(1.0).unwrap(),
            compare_every: SimTime::from_secs_f64(0.008).unwrap(),
            reference_dt: SimTime::from_secs_f64(5e-5).unwrap(),
            reference: Measured::invalid(String::new()),
            reference_error: 0.0,
            bodies: 2,
            variants,
            rows: vec![
                row("dt", "0.5 ms", 0),
                row("dt", "1 ms", 1),
                row("dt", "2 ms", 2),
                row("dt", "4 ms", 7),
                row("integrator", "euler", 1),
                row("integrator", "symplectic_euler", 3),
                row("integrator", "rk4", 4),
                row("dt, rk4", "0.5 ms", 5),
                row("dt, rk4", "1 ms", 4),
                row("solver", "cholesky", 1),
                row("solver", "cg 5", 6),
            ],
            notes: Vec::new(),
        }
    }

    /// Both plots of [`study`] (work precision, Pareto), written into a directory
    /// named for the `test`.
    fn rendered(test: &str) -> (String, String) {
        let dir = std::env::temp_dir().join(format!("dsmcosim-{test}-{}", std::process::id()));
        crate::output::create_dir_all(&dir).unwrap();
        plots(&dir, &study()).unwrap();
        let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
        let out = (read("work_precision.svg"), read("pareto.svg"));
        std::fs::remove_dir_all(&dir).unwrap();
        out
    }

    fn texts(svg: &str) -> Vec<String> {
        crate::report::tests_support::texts(svg)
            .into_iter()
            .map(|t| t.2)
            .collect()
    }

    #[test]
    fn work_precision_never_joins_integrators_by_a_line() {
        let (svg, _) = rendered("work-precision");
        let texts = texts(&svg);
        for label in [
            "dt",
            "integrator",
            "dt, rk4",
            "solver",
            "base scenario",
            "symplectic_euler",
            "rk4",
            "cg 5",
            "base",
            "wall time of the run [s]",
        ] {
            assert!(texts.iter().any(|t| t == label), "missing {label:?}");
        }
        assert!(
            !texts.iter().any(|t| t == "euler"),
            "the base is labelled once"
        );
        // dt and dt under rk4 are lines (blue, green); integrator (red) and solver
        // (orange) only markers.
        let lines = |colour: &str| {
            svg.lines()
                .filter(|l| l.contains("<polyline") && l.contains(colour))
                .count()
        };
        assert!(lines("#1F77B4") >= 2, "dt: a line and its swatch");
        assert!(lines("#2CA02C") >= 2, "dt, rk4: a line and its swatch");
        assert_eq!(lines("#D62728"), 0, "integrator: no line");
        assert_eq!(lines("#FF7F0E"), 0, "solver: no line");
    }

    #[test]
    fn pareto_points_carry_their_names() {
        let (_, svg) = rendered("pareto");
        let texts = texts(&svg);
        for label in [
            "dt 0.5 ms",
            "base",
            "dt 2 ms",
            "symplectic_euler",
            "rk4",
            "rk4 0.5 ms",
            "cg 5",
            "every variant",
            "Pareto front",
        ] {
            assert!(texts.iter().any(|t| t == label), "missing {label:?}");
        }
        assert!(
            !texts.iter().any(|t| t == "dt 4 ms"),
            "a diverged run has no dot"
        );
    }

    #[test]
    fn csv_fields() {
        assert_eq!(text("a,\"b\""), "\"a,\"\"b\"\"\"");
        assert_eq!(num(f64::NAN), "");
    }
}
