//! Line plots of signals over time: one line per series, a legend, linear or log axes,
//! optional zero-order-hold staircases and markers, and decimation of long series.

use std::path::Path;

use plotters::prelude::*;

use super::axis::{plottable, Axis};
use super::{
    plot_error, text_width, Scale, DESC_PX, FONT, GRID, LEGEND_PX, PALETTE, SIZE, TICK_PX, TITLE_PX,
};
use crate::error::Result;
use crate::output::write_atomic;

/// At most this many series get a legend entry; the rest are summed up in one entry.
const LEGEND_MAX: usize = 12;
/// A series with more points than this (after the staircase) is decimated for drawing.
const DECIMATE_ABOVE: usize = 4000;
/// Columns the x range is cut into for decimation; more than the plot's width [px] so
/// decimation never shows.
const COLUMNS: usize = 1000;
/// Columns for decimating markers: one marker per 4 px at most keeps files small.
const MARKER_COLUMNS: usize = 250;
/// Tick labels requested along x and y.
const X_TICKS: usize = 10;
/// See [`X_TICKS`].
const Y_TICKS: usize = 8;

/// One named line of a [`LinePlot`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    /// Legend text (with the unit if series of one plot differ in unit).
    pub label: String,
    /// Points `(x, y)` in drawing order. Non-finite points (and non-positive ones on a
    /// log axis) are skipped and break the line.
    pub points: Vec<(f64, f64)>,
    /// Vertical bars `(x, low, high)` drawn in the series' colour (a range around each
    /// point, e.g. min–max over repeated draws); empty for none.
    pub bars: Vec<(f64, f64, f64)>,
    /// Drawn as crosses without a line (points set apart from the lines, such as
    /// diverged runs), in black.
    pub crosses: bool,
}

impl Series {
    /// A series named `label`.
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            label: label.into(),
            points,
            bars: Vec::new(),
            crosses: false,
        }
    }

    /// Points drawn as black crosses, no line (see [`Series::crosses`]).
    pub fn crosses(label: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            crosses: true,
            ..Series::new(label, points)
        }
    }

    /// The series with vertical bars `(x, low, high)`.
    pub fn with_bars(mut self, bars: Vec<(f64, f64, f64)>) -> Series {
        self.bars = bars;
        self
    }
}

/// A 960 × 540 px plot of one or more series against a common x axis.
#[derive(Clone, Copy, Debug)]
pub struct LinePlot<'a> {
    /// Title above the plot.
    pub title: &'a str,
    /// Text under the x axis, with the unit: `time t [s]`.
    pub x_label: &'a str,
    /// Text beside the y axis, with the unit: `delay τ [ms]`.
    pub y_label: &'a str,
    /// The lines, drawn in order with colours from a fixed palette of 12.
    pub series: &'a [Series],
    /// Scale of the x axis.
    pub x_scale: Scale,
    /// Scale of the y axis.
    pub y_scale: Scale,
    /// Draw each series as a zero-order-hold staircase: a value holds until the next
    /// point's x (for delays and other piecewise-constant settings).
    pub step: bool,
    /// Draw a marker at every point (at most one per 4 px column on long series).
    pub markers: bool,
}

impl<'a> LinePlot<'a> {
    /// A plot with linear axes, straight lines and no markers.
    pub fn new(
        title: &'a str,
        x_label: &'a str,
        y_label: &'a str,
        series: &'a [Series],
    ) -> LinePlot<'a> {
        LinePlot {
            title,
            x_label,
            y_label,
            series,
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            step: false,
            markers: false,
        }
    }
}

/// Renders `plot` as an SVG document.
///
/// Series with more than 4000 points are decimated to the smallest and largest value
/// per 1/1000 of the x range, which keeps a 30 000-point trace's file small without a
/// visible change. Errors are [`crate::Error::Io`] naming `<svg>`.
pub fn line_plot_svg(plot: &LinePlot) -> Result<String> {
    render(plot, Path::new("<svg>"))
}

/// Renders `plot` and writes it to `path` atomically.
pub fn write_line_plot(path: &Path, plot: &LinePlot) -> Result<()> {
    let svg = render(plot, path)?;
    write_atomic(path, svg.as_bytes())
}

/// What is drawn of one series.
struct Prepared {
    /// Unbroken runs of points (staircased and decimated as asked).
    lines: Vec<Vec<(f64, f64)>>,
    /// Marker positions (empty unless asked for).
    markers: Vec<(f64, f64)>,
}

/// Splits `points` into maximal runs of points both axes can show.
fn runs(points: &[(f64, f64)], x: Scale, y: Scale) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current = Vec::new();
    for &(px, py) in points {
        if plottable(x, px) && plottable(y, py) {
            current.push((px, py));
        } else if !current.is_empty() {
            out.push(std::mem::take(&mut current));
        }
    }
    if !current.is_empty() {
        out.push(current);
    }
    out
}

/// The zero-order hold through `run`: each value holds until the next point's x.
fn staircase(run: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(run.len() * 2);
    for (i, &p) in run.iter().enumerate() {
        if i > 0 {
            out.push((p.0, run[i - 1].1));
        }
        out.push(p);
    }
    out
}

/// Keeps, of each group of consecutive points in the same one of `columns` slices of
/// the x axis, the point with the smallest and the one with the largest y, in their
/// original order (first occurrence on ties). For x increasing that is a per-pixel-column
/// min/max, which draws the same picture as the full series.
fn decimate(run: &[(f64, f64)], x_axis: &Axis, columns: usize) -> Vec<(f64, f64)> {
    let column = |x: f64| ((x_axis.fraction(x) * columns as f64) as usize).min(columns - 1);
    let mut out = Vec::new();
    let mut start = 0;
    while start < run.len() {
        let c = column(run[start].0);
        let mut end = start + 1;
        while end < run.len() && column(run[end].0) == c {
            end += 1;
        }
        let (mut lo, mut hi) = (start, start);
        for i in start + 1..end {
            if run[i].1 < run[lo].1 {
                lo = i;
            }
            if run[i].1 > run[hi].1 {
                hi = i;
            }
        }
        out.push(run[lo.min(hi)]);
        if lo != hi {
            out.push(run[lo.max(hi)]);
        }
        start = end;
    }
    out
}

fn prepare(series: &Series, plot: &LinePlot, x_axis: &Axis) -> Prepared {
    let runs = runs(&series.points, plot.x_scale, plot.y_scale);
    let mut lines: Vec<Vec<(f64, f64)>> = if plot.step {
        runs.iter().map(|r| staircase(r)).collect()
    } else {
        runs.clone()
    };
    let drawn: usize = lines.iter().map(Vec::len).sum();
    if drawn > DECIMATE_ABOVE {
        lines = lines.iter().map(|l| decimate(l, x_axis, COLUMNS)).collect();
    }
    let mut markers = Vec::new();
    if plot.markers {
        let count: usize = runs.iter().map(Vec::len).sum();
        for r in &runs {
            if count > DECIMATE_ABOVE {
                markers.extend(decimate(r, x_axis, MARKER_COLUMNS));
            } else {
                markers.extend_from_slice(r);
            }
        }
    }
    Prepared { lines, markers }
}

fn render(plot: &LinePlot, target: &Path) -> Result<String> {
    let err = plot_error(target);
    let valid = plot
        .series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|&&(x, y)| plottable(plot.x_scale, x) && plottable(plot.y_scale, y));
    let bar_ends = plot
        .series
        .iter()
        .flat_map(|s| s.bars.iter())
        .flat_map(|&(x, lo, hi)| [(x, lo), (x, hi)])
        .filter(|&(x, y)| plottable(plot.x_scale, x) && plottable(plot.y_scale, y));
    let x_axis = Axis::fit(plot.x_scale, valid.clone().map(|p| p.0));
    let y_axis = Axis::fit(
        plot.y_scale,
        valid.map(|p| p.1).chain(bar_ends.map(|p| p.1)),
    );
    let prepared: Vec<Prepared> = plot
        .series
        .iter()
        .map(|s| prepare(s, plot, &x_axis))
        .collect();

    // The y label area must hold the widest tick label and the rotated axis label.
    let widest = y_axis
        .ticks(Y_TICKS)
        .iter()
        .map(|&v| text_width(&y_axis.label(v), TICK_PX))
        .max()
        .unwrap_or(0);
    let y_area = (widest + 40).clamp(60, 200);

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(plot.title, (FONT, TITLE_PX))
            .margin(16)
            .x_label_area_size(55)
            .y_label_area_size(y_area)
            .build_cartesian_2d(x_axis, y_axis)
            .map_err(&err)?;
        chart
            .configure_mesh()
            .x_desc(plot.x_label)
            .y_desc(plot.y_label)
            .x_labels(X_TICKS)
            .y_labels(Y_TICKS)
            .max_light_lines(0)
            .bold_line_style(GRID)
            .label_style((FONT, TICK_PX))
            .axis_desc_style((FONT, DESC_PX))
            .draw()
            .map_err(&err)?;

        for (i, (series, drawn)) in plot.series.iter().zip(&prepared).enumerate() {
            if series.crosses {
                let style = BLACK.stroke_width(2);
                let points: Vec<(f64, f64)> = drawn.lines.iter().flatten().copied().collect();
                let anno = chart
                    .draw_series(points.iter().map(|&p| Cross::new(p, 5, style)))
                    .map_err(&err)?;
                if i < LEGEND_MAX {
                    anno.label(series.label.as_str())
                        .legend(move |(x, y)| Cross::new((x + 10, y), 5, style));
                }
                continue;
            }
            let style = PALETTE[i % PALETTE.len()].stroke_width(2);
            let anno = chart
                .draw_series(
                    drawn
                        .lines
                        .iter()
                        .map(|l| PathElement::new(l.clone(), style)),
                )
                .map_err(&err)?;
            if i < LEGEND_MAX {
                anno.label(series.label.as_str());
                if plot.markers {
                    anno.legend(move |(x, y)| {
                        EmptyElement::at((x, y))
                            + PathElement::new(vec![(0, 0), (20, 0)], style)
                            + Circle::new((10, 0), 3, style.filled())
                    });
                } else {
                    anno.legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
                }
            }
            let bars = series.bars.iter().filter(|&&(x, lo, hi)| {
                plottable(plot.x_scale, x)
                    && plottable(plot.y_scale, lo)
                    && plottable(plot.y_scale, hi)
            });
            let thin = PALETTE[i % PALETTE.len()].stroke_width(1);
            let bars: Vec<(f64, f64, f64)> = bars.copied().collect();
            chart
                .draw_series(
                    bars.iter()
                        .map(|&(x, lo, hi)| PathElement::new(vec![(x, lo), (x, hi)], thin)),
                )
                .map_err(&err)?;
            // 4 px caps at both ends.
            chart
                .draw_series(
                    bars.iter()
                        .flat_map(|&(x, lo, hi)| [(x, lo), (x, hi)])
                        .map(|p| {
                            EmptyElement::at(p) + PathElement::new(vec![(-4, 0), (4, 0)], thin)
                        }),
                )
                .map_err(&err)?;
            if plot.markers {
                chart
                    .draw_series(
                        drawn
                            .markers
                            .iter()
                            .map(|&p| Circle::new(p, 3, style.filled())),
                    )
                    .map_err(&err)?;
            }
        }
        if plot.series.len() > LEGEND_MAX {
            chart
                .draw_series(std::iter::empty::<EmptyElement<(f64, f64), _>>())
                .map_err(&err)?
                .label(format!("… and {} more", plot.series.len() - LEGEND_MAX))
                .legend(EmptyElement::at);
        }
        if !plot.series.is_empty() {
            // The legend goes into the plot corner that covers the fewest drawn points
            // (line vertices, points along each segment, markers).
            let entries = plot.series.len().min(LEGEND_MAX + 1) as i32;
            let label_w = plot
                .series
                .iter()
                .take(LEGEND_MAX)
                .map(|s| text_width(&s.label, LEGEND_PX))
                .max()
                .unwrap_or(0) as i32;
            let (w, h) = (label_w + 50, entries * (LEGEND_PX as i32 + 6) + 16);
            let ((left, top), (right, bottom)) = {
                let (xr, yr) = chart.plotting_area().get_pixel_range();
                ((xr.start, yr.start), (xr.end, yr.end))
            };
            let corners = [
                (SeriesLabelPosition::UpperRight, (right - w - 8, top + 8)),
                (SeriesLabelPosition::UpperLeft, (left + 8, top + 8)),
                (
                    SeriesLabelPosition::LowerRight,
                    (right - w - 8, bottom - h - 8),
                ),
                (SeriesLabelPosition::LowerLeft, (left + 8, bottom - h - 8)),
            ];
            let mut covered = [0usize; 4];
            for drawn in &prepared {
                let points = drawn.lines.iter().flat_map(|l| {
                    l.windows(2).flat_map(|seg| {
                        (0..8).map(move |k| {
                            let u = f64::from(k) / 8.0;
                            (
                                seg[0].0 + (seg[1].0 - seg[0].0) * u,
                                seg[0].1 + (seg[1].1 - seg[0].1) * u,
                            )
                        })
                    })
                });
                for p in points
                    .chain(drawn.markers.iter().copied())
                    .chain(drawn.lines.iter().filter_map(|l| l.last().copied()))
                {
                    let (px, py) = chart.backend_coord(&p);
                    for (c, &(_, (x0, y0))) in corners.iter().enumerate() {
                        if px >= x0 && px <= x0 + w && py >= y0 && py <= y0 + h {
                            covered[c] += 1;
                        }
                    }
                }
            }
            let best = (0..4).min_by_key(|&c| covered[c]).unwrap_or(0);
            chart
                .configure_series_labels()
                .position(corners[best].0.clone())
                .margin(8)
                .label_font((FONT, LEGEND_PX))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.4))
                .draw()
                .map_err(&err)?;
        }
        root.present().map_err(&err)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;

    fn sine(label: &str, n: usize, phase: f64) -> Series {
        Series::new(
            label,
            (0..n)
                .map(|k| {
                    let t = k as f64 * 1e-3;
                    (t, (40.0 * t + phase).sin() * 0.01)
                })
                .collect(),
        )
    }

    fn assert_svg(svg: &str) {
        assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(200)]);
        assert!(svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("<text"));
    }

    #[test]
    fn svg_has_title_labels_and_legend() {
        let series = [sine("w_L1 [m]", 500, 0.0), sine("w_L2 [m]", 500, 1.0)];
        let plot = LinePlot::new(
            "Constraint values",
            "time t [s]",
            "violation w [m]",
            &series,
        );
        let svg = line_plot_svg(&plot).unwrap();
        assert_svg(&svg);
        for text in [
            "Constraint values",
            "time t [s]",
            "violation w [m]",
            "w_L1 [m]",
            "w_L2 [m]",
        ] {
            assert!(svg.contains(text), "missing {text:?}");
        }
        assert!(svg.contains("#1F77B4") || svg.contains("#1f77b4"));
        // Same input, same bytes.
        assert_eq!(svg, line_plot_svg(&plot).unwrap());
    }

    #[test]
    fn more_than_twelve_series_are_summed_up() {
        let series: Vec<Series> = (0..15)
            .map(|i| sine(&format!("body B{i}"), 50, i as f64))
            .collect();
        let mut plot = LinePlot::new("Bodies", "time t [s]", "x [m]", &series);
        plot.markers = true;
        let svg = line_plot_svg(&plot).unwrap();
        assert_svg(&svg);
        assert!(svg.contains("body B11"));
        assert!(!svg.contains("body B12"));
        assert!(svg.contains("… and 3 more"));
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        let cases: Vec<Vec<Series>> = vec![
            vec![],
            vec![Series::new("empty", vec![])],
            vec![Series::new("one", vec![(1.0, 2.0)])],
            vec![Series::new(
                "flat",
                vec![(0.0, 3.0), (1.0, 3.0), (2.0, 3.0)],
            )],
            vec![Series::new("vertical", vec![(1.0, 0.0), (1.0, 5.0)])],
            vec![Series::new(
                "nan",
                vec![
                    (f64::NAN, 1.0),
                    (0.0, f64::INFINITY),
                    (1.0, f64::NEG_INFINITY),
                ],
            )],
            vec![Series::new(
                "gaps",
                vec![(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0), (3.0, 4.0)],
            )],
            vec![Series::new(
                "huge",
                vec![(-f64::MAX, f64::MAX), (f64::MAX, -f64::MAX)],
            )],
            vec![Series::new("tiny", vec![(0.0, 1e-300), (1e-310, 2e-300)])],
            vec![Series::new(
                "neg",
                vec![(-1.0, -5.0), (0.0, 0.0), (1.0, -1.0)],
            )],
        ];
        for series in &cases {
            for x_scale in [Scale::Linear, Scale::Log] {
                for y_scale in [Scale::Linear, Scale::Log] {
                    for (step, markers) in [(false, false), (true, true)] {
                        let plot = LinePlot {
                            title: "degenerate",
                            x_label: "x",
                            y_label: "y",
                            series,
                            x_scale,
                            y_scale,
                            step,
                            markers,
                        };
                        let svg = line_plot_svg(&plot)
                            .unwrap_or_else(|e| panic!("{series:?} {x_scale:?} {y_scale:?}: {e}"));
                        assert_svg(&svg);
                    }
                }
            }
        }
    }

    #[test]
    fn long_series_is_decimated() {
        let series = [sine("w_L1 [m]", 30_000, 0.0), sine("w_L2 [m]", 30_000, 2.0)];
        for step in [false, true] {
            let mut plot = LinePlot::new("Long", "time t [s]", "w [m]", &series);
            plot.step = step;
            plot.markers = step;
            let svg = line_plot_svg(&plot).unwrap();
            assert_svg(&svg);
            assert!(svg.len() < 300_000, "step {step}: {} bytes", svg.len());
        }
    }

    #[test]
    fn decimation_keeps_extremes_in_order() {
        let axis = Axis::fit(Scale::Linear, [0.0, 1.0]);
        let run: Vec<(f64, f64)> = (0..=10_000)
            .map(|k| {
                let t = k as f64 / 10_000.0;
                (t, if k == 5_000 { 9.0 } else { t })
            })
            .collect();
        let d = decimate(&run, &axis, COLUMNS);
        assert!(d.len() <= 2 * COLUMNS && d.len() > COLUMNS / 2);
        assert!(d.contains(&(0.5, 9.0)));
        assert!(d.contains(&(0.0, 0.0)) && d.contains(&(1.0, 1.0)));
        assert!(d.windows(2).all(|w| w[0].0 <= w[1].0));
    }

    #[test]
    fn staircase_holds_values() {
        assert_eq!(
            staircase(&[(0.0, 1.0), (1.0, 2.0), (3.0, 0.5)]),
            vec![(0.0, 1.0), (1.0, 1.0), (1.0, 2.0), (3.0, 2.0), (3.0, 0.5)]
        );
    }

    #[test]
    fn write_names_missing_directory() {
        let path = std::env::temp_dir()
            .join(format!("dsmcosim-report-missing-{}", std::process::id()))
            .join("plot.svg");
        let series = [sine("a", 10, 0.0)];
        let plot = LinePlot::new("t", "x", "y", &series);
        match write_line_plot(&path, &plot) {
            Err(Error::Io { path: p, .. }) => assert_eq!(p, path),
            other => panic!("expected an Io error, got {other:?}"),
        }
    }
}
