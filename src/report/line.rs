//! Line plots of signals over time: one line (or set of markers) per series, a legend
//! in a panel right of the plot area (never over the data), linear or log axes,
//! optional zero-order-hold staircases, markers and labels beside points, and
//! decimation of long series.

use std::path::Path;

use plotters::prelude::*;

use super::axis::{plottable, Axis};
use super::legend::{self, Entry, Shape, Swatch};
use super::{
    labels, plot_error, text_width, Scale, DESC_PX, FONT, GRID, PALETTE, SIZE, TICK_PX, TITLE_PX,
};
use crate::error::Result;
use crate::output::write_atomic;

/// Font size of the labels beside points [px, as plotters takes it].
const POINT_LABEL_PX: f64 = 14.0;
/// A series with more points than this (after the staircase) is decimated for drawing.
const DECIMATE_ABOVE: usize = 4000;
/// Columns the x range is cut into for decimation; more than the plot's width [px] so
/// decimation never shows.
const COLUMNS: usize = 1000;
/// Columns for decimating markers: one marker per 4 px at most keeps files small.
const MARKER_COLUMNS: usize = 250;
/// Colour of the thin line from a point to its label when the label sits apart.
const LEADER: RGBColor = RGBColor(0x80, 0x80, 0x80);
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
    /// A shaded band `(x, low, high)` behind the line, in a light shade of the series'
    /// colour (a range such as min–max over many series); empty for none. Bands are
    /// drawn before every line; a non-finite or unplottable point breaks the band.
    pub band: Vec<(f64, f64, f64)>,
    /// Drawn as crosses without a line (points set apart from the lines, such as
    /// diverged runs), in black.
    pub crosses: bool,
    /// Drawn as markers without a line (points that are not a continuum, such as one
    /// run per configuration).
    pub points_only: bool,
    /// Text next to each point (`labels[i]` beside `points[i]`, empty for none); placed
    /// to overlap other labels and markers as little as possible. Empty for no labels.
    pub labels: Vec<String>,
    /// Colour `[r, g, b]` instead of the next palette colour.
    pub colour: Option<[u8; 3]>,
    /// Line width [px] instead of 2.
    pub width: Option<u32>,
}

impl Series {
    /// A series named `label`.
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            label: label.into(),
            points,
            ..Series::default()
        }
    }

    /// Points drawn as black crosses, no line (see [`Series::crosses`]).
    pub fn crosses(label: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            crosses: true,
            ..Series::new(label, points)
        }
    }

    /// Points drawn as markers, no line (see [`Series::points_only`]).
    pub fn points(label: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            points_only: true,
            ..Series::new(label, points)
        }
    }

    /// The series with vertical bars `(x, low, high)`.
    pub fn with_bars(mut self, bars: Vec<(f64, f64, f64)>) -> Series {
        self.bars = bars;
        self
    }

    /// The series with a shaded band `(x, low, high)` (see [`Series::band`]).
    pub fn with_band(mut self, band: Vec<(f64, f64, f64)>) -> Series {
        self.band = band;
        self
    }

    /// The series with a text beside each point (see [`Series::labels`]).
    pub fn with_labels(mut self, labels: Vec<String>) -> Series {
        self.labels = labels;
        self
    }

    /// The series in colour `[r, g, b]` with lines `width` px wide.
    pub fn styled(mut self, colour: [u8; 3], width: u32) -> Series {
        self.colour = Some(colour);
        self.width = Some(width);
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
    /// The lines, drawn in order with colours from a fixed palette of 12 (series with
    /// their own colour skip the palette). The legend lists them in this order, as many
    /// as fit beside the plot area and then `… and N more`.
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

/// Panels drawn side by side in one SVG document, two to a row, each a 960 × 540 px
/// [`LinePlot`] with its own axes: quantities of different units (an FMU's position,
/// velocity and force) each on their own scale. The panels are the plots' own SVG
/// documents nested at their offsets, so each reads as it would alone.
pub fn write_panels(path: &Path, panels: &[LinePlot]) -> Result<()> {
    let (w, h) = SIZE;
    let columns = panels.len().clamp(1, 2) as u32;
    let rows = (panels.len() as u32).div_ceil(columns).max(1);
    let (width, height) = (w * columns, h * rows);
    let mut svg = format!(
        "<svg width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {width} {height}\" \
         xmlns=\"http://www.w3.org/2000/svg\">\n"
    );
    for (k, panel) in panels.iter().enumerate() {
        let inner = render(panel, path)?;
        let (x, y) = ((k as u32 % columns) * w, (k as u32 / columns) * h);
        // `<svg width=…` becomes `<svg x=… y=… width=…`: the panel at its place.
        let placed = inner.replacen("<svg ", &format!("<svg x=\"{x}\" y=\"{y}\" "), 1);
        svg.push_str(&placed);
        svg.push('\n');
    }
    svg.push_str("</svg>\n");
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
    if series.points_only {
        lines.clear();
    }
    let mut markers = Vec::new();
    if plot.markers || series.points_only {
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

/// The colour of each series: its own, or the palette colour of its index among the
/// series without one.
fn colours(series: &[Series]) -> Vec<RGBColor> {
    let mut next = 0;
    series
        .iter()
        .map(|s| match s.colour {
            Some([r, g, b]) => RGBColor(r, g, b),
            None => {
                next += 1;
                PALETTE[(next - 1) % PALETTE.len()]
            }
        })
        .collect()
}

/// The light shade of `colour` a band is filled with: 25 % colour on white.
fn shade(colour: RGBColor) -> RGBColor {
    let mix = |c: u8| ((u16::from(c) + 3 * 255) / 4) as u8;
    RGBColor(mix(colour.0), mix(colour.1), mix(colour.2))
}

/// Outlines of the unbroken runs of `band`: the highs left to right, then the lows
/// back. A run longer than 4000 points keeps, per 1/1000 of the x range, the lowest
/// low and highest high at the column's first x.
fn band_runs(band: &[(f64, f64, f64)], plot: &LinePlot, x_axis: &Axis) -> Vec<Vec<(f64, f64)>> {
    let ok = |&(x, lo, hi): &(f64, f64, f64)| {
        plottable(plot.x_scale, x) && plottable(plot.y_scale, lo) && plottable(plot.y_scale, hi)
    };
    let mut runs: Vec<Vec<(f64, f64, f64)>> = Vec::new();
    let mut current = Vec::new();
    for b in band {
        if ok(b) {
            current.push(*b);
        } else if !current.is_empty() {
            runs.push(std::mem::take(&mut current));
        }
    }
    if !current.is_empty() {
        runs.push(current);
    }
    let column = |x: f64| ((x_axis.fraction(x) * COLUMNS as f64) as usize).min(COLUMNS - 1);
    runs.into_iter()
        .map(|run| {
            let run = if run.len() > DECIMATE_ABOVE {
                let mut merged: Vec<(f64, f64, f64)> = Vec::new();
                for (x, lo, hi) in run {
                    match merged.last_mut() {
                        Some(m) if column(m.0) == column(x) => {
                            m.1 = m.1.min(lo);
                            m.2 = m.2.max(hi);
                        }
                        _ => merged.push((x, lo, hi)),
                    }
                }
                merged
            } else {
                run
            };
            let mut outline: Vec<(f64, f64)> = run.iter().map(|b| (b.0, b.2)).collect();
            outline.extend(run.iter().rev().map(|b| (b.0, b.1)));
            outline
        })
        .collect()
}

/// Dash patterns (on, off [px]) and markers of series that lie on an earlier one, in
/// turn: the first such series is dashed 9/5 with triangles, the next 3/4 with squares,
/// the next 14/4 with crosses, then again.
const COINCIDING: [((u32, u32), Shape); 3] = [
    ((9, 5), Shape::Triangle),
    ((3, 4), Shape::Square),
    ((14, 4), Shape::Cross),
];

/// For each series, the earlier series it lies on, if any: at least half of its drawn
/// segments coincide with segments of that one (ends equal to 1/500 of each axis), so
/// that drawn solid it would hide it or be hidden. Such a series is drawn dashed with
/// other markers ([`COINCIDING`]) and its legend row says which line it lies on.
fn lies_on(
    plot: &LinePlot,
    prepared: &[Prepared],
    x_axis: &Axis,
    y_axis: &Axis,
) -> Vec<Option<usize>> {
    type Key = ((i64, i64), (i64, i64));
    let q = |p: &(f64, f64)| {
        (
            (x_axis.fraction(p.0) * 500.0).round() as i64,
            (y_axis.fraction(p.1) * 500.0).round() as i64,
        )
    };
    let mut seen: std::collections::HashMap<Key, usize> = std::collections::HashMap::new();
    let mut out = Vec::with_capacity(prepared.len());
    for (i, (series, drawn)) in plot.series.iter().zip(prepared).enumerate() {
        let segments: Vec<Key> = drawn
            .lines
            .iter()
            .flat_map(|l| l.windows(2))
            .map(|w| {
                let (a, b) = (q(&w[0]), q(&w[1]));
                if a <= b {
                    (a, b)
                } else {
                    (b, a)
                }
            })
            .filter(|(a, b)| a != b)
            .collect();
        let mut shared: std::collections::BTreeMap<usize, usize> = Default::default();
        for seg in &segments {
            if let Some(&j) = seen.get(seg) {
                *shared.entry(j).or_default() += 1;
            }
        }
        let on = shared
            .iter()
            .find(|(_, &n)| 2 * n >= segments.len())
            .map(|(&j, _)| j);
        let drawn_as_line = !series.crosses && !series.points_only && !segments.is_empty();
        out.push(on.filter(|_| drawn_as_line));
        for seg in segments {
            seen.entry(seg).or_insert(i);
        }
    }
    out
}

/// The dash and marker of each series: `None` for a plain line with dots.
fn dashes(on: &[Option<usize>]) -> Vec<Option<((u32, u32), Shape)>> {
    let mut k = 0;
    on.iter()
        .map(|o| {
            o.map(|_| {
                k += 1;
                COINCIDING[(k - 1) % COINCIDING.len()]
            })
        })
        .collect()
}

/// One legend row per series, in order.
fn legend_entries(
    plot: &LinePlot,
    colours: &[RGBColor],
    on: &[Option<usize>],
    dashes: &[Option<((u32, u32), Shape)>],
) -> Vec<Entry> {
    plot.series
        .iter()
        .zip(colours)
        .enumerate()
        .map(|(i, (s, &colour))| Entry {
            text: match on[i] {
                Some(j) => format!("{} (dashed, lies on {})", s.label, plot.series[j].label),
                None => s.label.clone(),
            },
            swatch: if let Some((dash, shape)) = dashes[i] {
                Swatch::Dashed {
                    colour,
                    width: s.width.unwrap_or(2),
                    dash,
                    shape: plot.markers.then_some(shape),
                }
            } else if s.crosses {
                Swatch::Cross
            } else if !s.band.is_empty() {
                Swatch::Band {
                    fill: shade(colour),
                    colour,
                }
            } else if s.points_only {
                Swatch::Marker(colour)
            } else {
                Swatch::Line {
                    colour,
                    width: s.width.unwrap_or(2),
                    marker: plot.markers,
                }
            },
        })
        .collect()
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
        .flat_map(|s| s.bars.iter().chain(&s.band))
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
    let colours = colours(plot.series);
    let on = lies_on(plot, &prepared, &x_axis, &y_axis);
    let dashes = dashes(&on);
    let entries = legend_entries(plot, &colours, &on, &dashes);
    // The legend panel at the right, outside the plot area.
    let legend_w = if entries.is_empty() {
        0
    } else {
        legend::panel_width(&entries)
    };

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
        let body = root.titled(plot.title, (FONT, TITLE_PX)).map_err(&err)?;
        let (main, _legend_panel) = body.split_horizontally(SIZE.0 - legend_w);
        let mut chart = ChartBuilder::on(&main)
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

        // Bands first, so that every line is drawn over them.
        for (series, &colour) in plot.series.iter().zip(&colours) {
            let fill = shade(colour).filled();
            chart
                .draw_series(
                    band_runs(&series.band, plot, &x_axis)
                        .into_iter()
                        .map(|outline| Polygon::new(outline, fill)),
                )
                .map_err(&err)?;
        }
        for (((series, drawn), &colour), dash) in
            plot.series.iter().zip(&prepared).zip(&colours).zip(&dashes)
        {
            if series.crosses {
                let style = BLACK.stroke_width(2);
                let points: Vec<(f64, f64)> = runs(&series.points, plot.x_scale, plot.y_scale)
                    .into_iter()
                    .flatten()
                    .collect();
                chart
                    .draw_series(points.iter().map(|&p| Cross::new(p, 5, style)))
                    .map_err(&err)?;
                continue;
            }
            let style = colour.stroke_width(series.width.unwrap_or(2));
            match dash {
                None => chart
                    .draw_series(
                        drawn
                            .lines
                            .iter()
                            .map(|l| PathElement::new(l.clone(), style)),
                    )
                    .map_err(&err)?,
                Some(((on, off), _)) => chart
                    .draw_series(drawn.lines.iter().map(|l| {
                        plotters::element::DashedPathElement::new(l.clone(), *on, *off, style)
                    }))
                    .map_err(&err)?,
            };
            let bars = series.bars.iter().filter(|&&(x, lo, hi)| {
                plottable(plot.x_scale, x)
                    && plottable(plot.y_scale, lo)
                    && plottable(plot.y_scale, hi)
            });
            let thin = colour.stroke_width(1);
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
            let radius = if series.points_only { 4 } else { 3 };
            match dash {
                None => {
                    chart
                        .draw_series(
                            drawn
                                .markers
                                .iter()
                                .map(|&p| Circle::new(p, radius, colour.filled())),
                        )
                        .map_err(&err)?;
                }
                Some((_, shape)) => {
                    for p in &drawn.markers {
                        shape
                            .draw(&root, chart.backend_coord(p), colour)
                            .map_err(&err)?;
                    }
                }
            }
        }

        let (xr, yr) = chart.plotting_area().get_pixel_range();
        let area = (xr.start, yr.start, xr.end, yr.end);

        // Point labels, placed around the markers.
        let shown = |&(x, y): &(f64, f64)| plottable(plot.x_scale, x) && plottable(plot.y_scale, y);
        let texts: Vec<(String, (i32, i32))> = plot
            .series
            .iter()
            .flat_map(|s| s.points.iter().zip(&s.labels))
            .filter(|(p, text)| shown(p) && !text.is_empty())
            .map(|(p, text)| (text.clone(), chart.backend_coord(p)))
            .collect();
        if !texts.is_empty() {
            // Labels keep clear of markers and of the lines (points every 4 px).
            let markers: Vec<(i32, i32)> = prepared
                .iter()
                .flat_map(|d| d.markers.iter())
                .map(|p| chart.backend_coord(p))
                .collect();
            let mut line_points = Vec::new();
            for line in prepared.iter().flat_map(|d| d.lines.iter()) {
                let pixels: Vec<(i32, i32)> = line.iter().map(|p| chart.backend_coord(p)).collect();
                for seg in pixels.windows(2) {
                    let (a, b) = (seg[0], seg[1]);
                    let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()) / 4).max(1);
                    line_points.extend(
                        (0..steps).map(|k| {
                            (a.0 + (b.0 - a.0) * k / steps, a.1 + (b.1 - a.1) * k / steps)
                        }),
                    );
                }
            }
            let style = TextStyle::from((FONT, POINT_LABEL_PX).into_font()).color(&BLACK);
            for placed in labels::place(&texts, &markers, &line_points, area, POINT_LABEL_PX) {
                if let Some(point) = placed.leader {
                    let end = placed.nearest_edge(point, POINT_LABEL_PX);
                    root.draw(&PathElement::new(vec![point, end], LEADER.stroke_width(1)))
                        .map_err(&err)?;
                }
                root.draw(&Text::new(
                    placed.text,
                    placed.at,
                    style.clone().pos(placed.pos),
                ))
                .map_err(&err)?;
            }
        }

        // The legend: its own panel right of the plot area, its top at the area's top.
        let entries = legend::fit(legend::wrap(entries, legend_w), area.3 - area.1);
        legend::draw(
            &root,
            &entries,
            ((SIZE.0 - legend_w) as i32 + legend::INSET, area.1),
        )
        .map_err(&err)?;
        root.present().map_err(&err)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;
    use crate::report::tests_support::texts;

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
        crate::report::tests_support::assert_no_text_overlaps(&svg);
        // Same input, same bytes.
        assert_eq!(svg, line_plot_svg(&plot).unwrap());
    }

    /// Largest x of the points of every `<polyline>` with more than `min_points`
    /// points (data lines, not legend swatches).
    fn rightmost_line_x(svg: &str, min_points: usize) -> i32 {
        svg.split("<polyline")
            .skip(1)
            .filter_map(|rest| {
                let at = rest.find(" points=\"")? + 9;
                let len = rest[at..].find('"')?;
                let points: Vec<i32> = rest[at..at + len]
                    .split_whitespace()
                    .filter_map(|p| p.split(',').next()?.parse().ok())
                    .collect();
                (points.len() > min_points).then(|| points.into_iter().max())?
            })
            .max()
            .unwrap_or(0)
    }

    #[test]
    fn crowded_point_labels_do_not_overlap() {
        // Twenty labelled variants around one base point (the tradeoff's picture), on
        // log axes, plus a line through them: no two texts' boxes intersect.
        let points: Vec<(f64, f64)> = (0..20)
            .map(|i| {
                (
                    0.01 * (1.0 + 0.01 * i as f64),
                    0.03 * (1.0 + 0.02 * (i % 5) as f64),
                )
            })
            .collect();
        let labels: Vec<String> = (0..20).map(|i| format!("baumgarte α = β = {i}")).collect();
        let series = [
            Series::points("variants", points).with_labels(labels),
            Series::new("dt", vec![(0.005, 0.02), (0.02, 0.04)]),
        ];
        let mut plot = LinePlot::new("Crowd", "wall [s]", "error [m]", &series);
        plot.x_scale = Scale::Log;
        plot.y_scale = Scale::Log;
        let svg = line_plot_svg(&plot).unwrap();
        for i in 0..20 {
            assert!(
                svg.contains(&format!("baumgarte α = β = {i}\n")),
                "label {i}"
            );
        }
        crate::report::tests_support::assert_no_text_overlaps(&svg);
        // Labels set apart from their point are joined to it by a grey leader line.
        assert!(svg.contains("#808080"), "leader lines");
    }

    #[test]
    fn coinciding_series_are_dashed_and_say_so_in_the_legend() {
        let a: Vec<(f64, f64)> = (1..=6).map(|i| (i as f64, 1e-2 * i as f64)).collect();
        let mut b = a.clone();
        b.push((7.0, 1.0));
        let series = [
            Series::new("predict", a.clone()),
            Series::new("passive", b),
            Series::new("passive, no lines", a),
            Series::new("reset", vec![(1.0, 0.5), (6.0, 0.6)]),
        ];
        let mut plot = LinePlot::new("Coupling", "τ [ms]", "error [m]", &series);
        plot.markers = true;
        let svg = line_plot_svg(&plot).unwrap();
        let t = texts(&svg);
        let has = |s: &str| t.iter().any(|x| x.2.contains(s));
        assert!(has("predict") && has("reset"), "{t:?}");
        // The legend wraps long rows: look for the words.
        assert!(has("(dashed, lies on"), "{t:?}");
        assert!(
            !t.iter().any(|x| x.2.starts_with("predict (dashed")),
            "{t:?}"
        );
        assert!(!t.iter().any(|x| x.2.starts_with("reset (dashed")), "{t:?}");
        assert!(
            t.iter().any(|x| x.2.starts_with("passive (dashed")),
            "{t:?}"
        );
        // Different markers for the two that lie on `predict`: triangles and squares.
        assert!(svg.contains("<polygon"), "triangle markers");
        assert!(svg.contains("fill=\"none\""), "open squares");
        assert_eq!(
            lies_on(
                &plot,
                &series
                    .iter()
                    .map(|s| prepare(s, &plot, &Axis::fit(Scale::Linear, [1.0, 7.0])))
                    .collect::<Vec<_>>(),
                &Axis::fit(Scale::Linear, [1.0, 7.0]),
                &Axis::fit(Scale::Linear, [0.0, 1.0]),
            ),
            vec![None, Some(0), Some(0), None]
        );
        crate::report::tests_support::assert_no_text_overlaps(&svg);
    }

    #[test]
    fn legend_sits_right_of_the_plot_area() {
        // A spike at the right end, where a legend inside the plot would sit.
        let mut series = vec![sine("w_L1 [m]", 500, 0.0), sine("w_L2 [m]", 500, 1.0)];
        series[0].points.push((0.5, 1.0));
        let plot = LinePlot::new("Legend", "time t [s]", "w [m]", &series);
        let svg = line_plot_svg(&plot).unwrap();
        let data_right = rightmost_line_x(&svg, 2);
        assert!(data_right > 600, "{data_right}");
        for label in ["w_L1 [m]", "w_L2 [m]"] {
            let (x, _, _) = texts(&svg)
                .into_iter()
                .find(|t| t.2 == label)
                .unwrap_or_else(|| panic!("no legend text {label:?}"));
            // The plot area ends 5 % of the x span right of the data.
            assert!(
                x > data_right + (data_right / 20),
                "{label} at x = {x}, data up to {data_right}"
            );
        }
    }

    #[test]
    fn a_legend_longer_than_the_plot_is_summed_up() {
        let series: Vec<Series> = (0..40)
            .map(|i| sine(&format!("body B{i}"), 50, i as f64))
            .collect();
        let mut plot = LinePlot::new("Bodies", "time t [s]", "x [m]", &series);
        plot.markers = true;
        let svg = line_plot_svg(&plot).unwrap();
        assert_svg(&svg);
        let texts = texts(&svg);
        let shown = texts.iter().filter(|t| t.2.starts_with("body B")).count();
        assert!((12..40).contains(&shown), "{shown} entries");
        assert!(texts
            .iter()
            .any(|t| t.2 == format!("… and {} more", 40 - shown)));
        // Fifteen fit without a summary.
        let plot = LinePlot::new("Bodies", "time t [s]", "x [m]", &series[..15]);
        let svg = line_plot_svg(&plot).unwrap();
        assert!(svg.contains("body B14") && !svg.contains("more"));
    }

    #[test]
    fn points_only_series_have_markers_labels_and_no_line() {
        let series = [
            Series::points("integrator", vec![(1.0, 1e-2), (2.0, 1e-5), (4.0, 1e-9)]).with_labels(
                vec!["euler".into(), "symplectic_euler".into(), "rk4".into()],
            ),
            Series::new("dt, rk4", vec![(4.0, 1e-9), (8.0, 1e-11)]),
        ];
        let mut plot = LinePlot::new("Work", "wall [s]", "error [m]", &series);
        plot.x_scale = Scale::Log;
        plot.y_scale = Scale::Log;
        let svg = line_plot_svg(&plot).unwrap();
        let blue = svg
            .lines()
            .filter(|l| l.contains("<polyline") && l.contains("#1F77B4"))
            .count();
        assert_eq!(blue, 0, "no line joins the integrators");
        let red_lines = svg
            .lines()
            .filter(|l| l.contains("<polyline") && l.contains("#D62728"))
            .count();
        assert_eq!(red_lines, 2, "the dt sweep's line and its legend swatch");
        assert_eq!(
            svg.matches("<circle").count(),
            3 + 1,
            "markers and a swatch"
        );
        let texts = texts(&svg);
        for label in ["euler", "symplectic_euler", "rk4", "integrator", "dt, rk4"] {
            assert!(texts.iter().any(|t| t.2 == label), "missing {label:?}");
        }
        crate::report::tests_support::assert_no_text_overlaps(&svg);
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
