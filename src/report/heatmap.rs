//! Heatmaps of a value over a 2-D grid (the grid-search cost surface), with a colour
//! bar and an optional overlaid path (the optimizer's trajectory).

use std::io;
use std::path::Path;

use plotters::prelude::*;

use super::axis::Axis;
use super::{plot_error, text_width, Scale, DESC_PX, FONT, SIZE, TICK_PX, TITLE_PX};
use crate::error::{Error, Result};
use crate::output::write_atomic;

/// Width [px] of the colour-bar panel at the right.
const BAR_PANEL: u32 = 130;
/// Rectangles the colour bar is drawn with.
const BAR_STEPS: usize = 64;
/// Colour of cells without a value.
const MISSING: RGBColor = RGBColor(0xb4, 0xb4, 0xb4);
/// Colour of the overlaid path.
const PATH: RGBColor = RGBColor(0xd6, 0x27, 0x28);

/// Viridis at nine evenly spaced stops: perceptually uniform, readable in grey.
const VIRIDIS: [(u8, u8, u8); 9] = [
    (0x44, 0x01, 0x54),
    (0x47, 0x2d, 0x7b),
    (0x3b, 0x52, 0x8b),
    (0x2c, 0x72, 0x8e),
    (0x21, 0x91, 0x8c),
    (0x28, 0xae, 0x80),
    (0x5e, 0xc9, 0x62),
    (0xad, 0xdc, 0x30),
    (0xfd, 0xe7, 0x25),
];

/// A value over a grid of `x` × `y` cells.
#[derive(Clone, Copy, Debug)]
pub struct Heatmap<'a> {
    /// Title above the plot.
    pub title: &'a str,
    /// Text under the x axis, with the unit.
    pub x_label: &'a str,
    /// Text beside the y axis, with the unit.
    pub y_label: &'a str,
    /// Text beside the colour bar, with the unit: `mean cost J`.
    pub value_label: &'a str,
    /// Cell centres along x, finite and strictly increasing.
    pub x: &'a [f64],
    /// Cell centres along y, finite and strictly increasing.
    pub y: &'a [f64],
    /// `values[iy][ix]` at `(x[ix], y[iy])`: `y.len()` rows of `x.len()` values. A
    /// non-finite value marks a missing cell, drawn grey.
    pub values: &'a [Vec<f64>],
    /// A path drawn over the cells as a line with markers, its end marked larger (an
    /// optimizer's trajectory); empty for none. Non-finite points are skipped.
    pub path_overlay: &'a [(f64, f64)],
    /// A curve drawn over the cells as a plain white line (a constraint's boundary, such
    /// as a budget line); empty for none. Non-finite points are skipped.
    pub line_overlay: &'a [(f64, f64)],
    /// Names of the cells along x and y for a categorical axis (then `x` or `y` are
    /// the indices 0, 1, … and every cell is equally wide); `None` for a numeric axis.
    pub categories: [Option<&'a [String]>; 2],
}

/// Renders `map` as an SVG document.
///
/// Errors are [`Error::Io`] naming `<svg>`; a grid whose sizes do not match or whose
/// centres are not finite and strictly increasing is an `InvalidInput` error.
pub fn heatmap_svg(map: &Heatmap) -> Result<String> {
    render(map, Path::new("<svg>"))
}

/// Renders `map` and writes it to `path` atomically.
pub fn write_heatmap(path: &Path, map: &Heatmap) -> Result<()> {
    let svg = render(map, path)?;
    write_atomic(path, svg.as_bytes())
}

/// Colour of `t` in `[0, 1]` on the viridis map (clamped).
fn colour(t: f64) -> RGBColor {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let pos = t * (VIRIDIS.len() - 1) as f64;
    let i = (pos.floor() as usize).min(VIRIDIS.len() - 2);
    let f = pos - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |a: u8, b: u8| (f64::from(a) + (f64::from(b) - f64::from(a)) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Cell edges around `centres`: midpoints between neighbours, the outer edges half a
/// spacing out; a single centre `c` gets `c ± 10 %` (`± 0.5` for 0).
fn edges(centres: &[f64]) -> Vec<f64> {
    match centres {
        [] => Vec::new(),
        [c] => {
            let h = if *c == 0.0 { 0.5 } else { c.abs() * 0.1 };
            vec![c - h, c + h]
        }
        _ => {
            let n = centres.len();
            let mut e = Vec::with_capacity(n + 1);
            e.push(centres[0] - (centres[1] - centres[0]) * 0.5);
            e.extend(centres.windows(2).map(|w| w[0] * 0.5 + w[1] * 0.5));
            e.push(centres[n - 1] + (centres[n - 1] - centres[n - 2]) * 0.5);
            e
        }
    }
}

/// Checks the grid's shape and centres.
fn check(map: &Heatmap, target: &Path) -> Result<()> {
    let bad = |msg: String| Error::io(target, io::Error::new(io::ErrorKind::InvalidInput, msg));
    for (name, centres) in [("x", map.x), ("y", map.y)] {
        if let Some(i) = centres.iter().position(|v| !v.is_finite()) {
            return Err(bad(format!(
                "heatmap {name}[{i}] = {} is not finite",
                centres[i]
            )));
        }
        if let Some(i) = centres.windows(2).position(|w| w[0] >= w[1]) {
            return Err(bad(format!(
                "heatmap {name} is not strictly increasing at index {}",
                i + 1
            )));
        }
        let outer = edges(centres);
        if outer.iter().any(|e| !e.is_finite()) {
            return Err(bad(format!("heatmap {name} cell edges overflow")));
        }
    }
    if map.values.len() != map.y.len() {
        return Err(bad(format!(
            "heatmap has {} value rows for {} y values",
            map.values.len(),
            map.y.len()
        )));
    }
    if let Some((iy, row)) = map
        .values
        .iter()
        .enumerate()
        .find(|(_, r)| r.len() != map.x.len())
    {
        return Err(bad(format!(
            "heatmap value row {iy} has {} values for {} x values",
            row.len(),
            map.x.len()
        )));
    }
    Ok(())
}

/// The points of an overlay with both coordinates finite.
fn finite_points(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    points
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect()
}

fn render(map: &Heatmap, target: &Path) -> Result<String> {
    check(map, target)?;
    let err = plot_error(target);
    let (x_edges, y_edges) = (edges(map.x), edges(map.y));
    let overlay = finite_points(map.path_overlay);
    let x_axis = Axis::exact(
        Scale::Linear,
        x_edges.iter().copied().chain(overlay.iter().map(|p| p.0)),
    );
    let y_axis = Axis::exact(
        Scale::Linear,
        y_edges.iter().copied().chain(overlay.iter().map(|p| p.1)),
    );
    let v_axis = Axis::exact(Scale::Linear, map.values.iter().flatten().copied());
    let widest = |axis: &Axis| {
        axis.ticks(8)
            .iter()
            .map(|&v| text_width(&axis.label(v), TICK_PX))
            .max()
            .unwrap_or(0)
    };
    let y_width = match map.categories[1] {
        Some(names) => names
            .iter()
            .map(|n| text_width(n, TICK_PX))
            .max()
            .unwrap_or(0),
        None => widest(&y_axis),
    };
    let y_area = (y_width + 40).clamp(60, 200);
    let v_area = (widest(&v_axis) + 40).clamp(60, BAR_PANEL - 30);

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let body = root.titled(map.title, (FONT, TITLE_PX)).map_err(&err)?;
        let (main, bar) = body.split_horizontally(SIZE.0 - BAR_PANEL);

        let mut chart = ChartBuilder::on(&main)
            .margin(16)
            .x_label_area_size(55)
            .y_label_area_size(y_area)
            .build_cartesian_2d(x_axis, y_axis)
            .map_err(&err)?;
        // A categorical axis names its cells at their (integer) centres.
        let category = |names: Option<&[String]>, v: f64, axis: &Axis| match names {
            None => axis.label(v),
            Some(names) => {
                let i = v.round();
                if (v - i).abs() < 1e-9 && i >= 0.0 && (i as usize) < names.len() {
                    names[i as usize].clone()
                } else {
                    String::new()
                }
            }
        };
        let (xa, ya) = (x_axis, y_axis);
        let x_format = |v: &f64| category(map.categories[0], *v, &xa);
        let y_format = |v: &f64| category(map.categories[1], *v, &ya);
        chart
            .configure_mesh()
            .x_desc(map.x_label)
            .y_desc(map.y_label)
            .x_labels(map.categories[0].map_or(10, |c| c.len() * 2 + 1))
            .y_labels(map.categories[1].map_or(8, |c| c.len() * 2 + 1))
            .x_label_formatter(&x_format)
            .y_label_formatter(&y_format)
            .disable_mesh()
            .label_style((FONT, TICK_PX))
            .axis_desc_style((FONT, DESC_PX))
            .draw()
            .map_err(&err)?;
        let cells = map.values.iter().enumerate().flat_map(|(iy, row)| {
            let (x_edges, y_edges) = (&x_edges, &y_edges);
            let v_axis = &v_axis;
            row.iter().enumerate().map(move |(ix, &v)| {
                let fill = if v.is_finite() {
                    colour(v_axis.fraction(v))
                } else {
                    MISSING
                };
                Rectangle::new(
                    [
                        (x_edges[ix], y_edges[iy]),
                        (x_edges[ix + 1], y_edges[iy + 1]),
                    ],
                    fill.filled(),
                )
            })
        });
        chart.draw_series(cells).map_err(&err)?;
        let line = finite_points(map.line_overlay);
        if !line.is_empty() {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    line,
                    WHITE.stroke_width(3),
                )))
                .map_err(&err)?;
        }
        if !overlay.is_empty() {
            let style = PATH.stroke_width(2);
            chart
                .draw_series(std::iter::once(PathElement::new(overlay.clone(), style)))
                .map_err(&err)?;
            chart
                .draw_series(overlay.iter().map(|&p| Circle::new(p, 3, style.filled())))
                .map_err(&err)?;
            if let Some(&last) = overlay.last() {
                chart
                    .draw_series([
                        Circle::new(last, 6, PATH.filled()),
                        Circle::new(last, 6, WHITE.stroke_width(2)),
                    ])
                    .map_err(&err)?;
            }
        }
        // Colour bar: the value axis on the right of a strip of the colour map.
        let mut bar_chart = ChartBuilder::on(&bar)
            .margin_top(16)
            .margin_bottom(16 + 55)
            .margin_left(10)
            .margin_right(10)
            .right_y_label_area_size(v_area)
            .build_cartesian_2d(Axis::exact(Scale::Linear, [0.0, 1.0]), v_axis)
            .map_err(&err)?;
        bar_chart
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(map.value_label)
            .y_labels(8)
            .label_style((FONT, TICK_PX))
            .axis_desc_style((FONT, DESC_PX))
            .draw()
            .map_err(&err)?;
        let (lo, hi) = (v_axis.lo(), v_axis.hi());
        let strips = (0..BAR_STEPS).map(|i| {
            let a = lo + (hi - lo) * i as f64 / BAR_STEPS as f64;
            let b = lo + (hi - lo) * (i + 1) as f64 / BAR_STEPS as f64;
            let t = (i as f64 + 0.5) / BAR_STEPS as f64;
            Rectangle::new([(0.0, a), (1.0, b)], colour(t).filled())
        });
        bar_chart.draw_series(strips).map_err(&err)?;
        root.present().map_err(&err)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> (Vec<f64>, Vec<f64>, Vec<Vec<f64>>) {
        let x: Vec<f64> = (0..12).map(|i| 1.0 + i as f64 * 0.5).collect();
        let y: Vec<f64> = (0..9).map(|i| 2.0 + i as f64).collect();
        let values = y
            .iter()
            .map(|&b| {
                x.iter()
                    .map(|&a| {
                        if a > 5.5 && b > 9.0 {
                            f64::NAN
                        } else {
                            (a - 3.0).powi(2) + (b - 5.0).powi(2)
                        }
                    })
                    .collect()
            })
            .collect();
        (x, y, values)
    }

    #[test]
    fn renders_with_overlay() {
        let (x, y, values) = grid();
        let path = [(6.0, 9.5), (4.5, 7.0), (3.5, 5.5), (3.0, 5.0)];
        let map = Heatmap {
            title: "Grid search, window 3",
            x_label: "delay τ_1 [ms]",
            y_label: "delay τ_2 [ms]",
            value_label: "mean cost J",
            x: &x,
            y: &y,
            values: &values,
            path_overlay: &path,
            line_overlay: &[(1.0, 10.0), (6.5, 2.0)],
            categories: [None, None],
        };
        let svg = heatmap_svg(&map).unwrap();
        let white_line = |svg: &str| {
            svg.lines()
                .any(|l| l.contains("<polyline") && l.to_uppercase().contains("#FFFFFF"))
        };
        assert!(white_line(&svg), "the white line overlay");
        let none = heatmap_svg(&Heatmap {
            line_overlay: &[],
            categories: [None, None],
            ..map
        })
        .unwrap();
        assert!(!white_line(&none), "no line overlay, no white line");
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        for text in [
            "Grid search, window 3",
            "delay τ_1 [ms]",
            "delay τ_2 [ms]",
            "mean cost J",
        ] {
            assert!(svg.contains(text), "missing {text:?}");
        }
        assert!(svg.contains("<circle"), "overlay markers");
        assert!(
            svg.contains("#B4B4B4") || svg.contains("#b4b4b4"),
            "missing cells"
        );
        assert_eq!(svg, heatmap_svg(&map).unwrap());
    }

    #[test]
    fn degenerate_grids_do_not_panic() {
        let nan_row = vec![vec![f64::NAN, f64::NAN]];
        let flat = vec![vec![2.0, 2.0]];
        let one = vec![vec![0.0]];
        /// x, y, values, overlay.
        type Case<'a> = (&'a [f64], &'a [f64], &'a [Vec<f64>], &'a [(f64, f64)]);
        let cases: [Case; 5] = [
            (&[], &[], &[], &[]),
            (&[], &[], &[], &[(1.0, 1.0), (f64::NAN, 2.0)]),
            (&[0.0], &[0.0], &one, &[]),
            (&[1.0, 2.0], &[5.0], &nan_row, &[(1.5, 5.0)]),
            (&[1.0, 2.0], &[5.0], &flat, &[]),
        ];
        for (x, y, values, path_overlay) in cases {
            let map = Heatmap {
                title: "t",
                x_label: "x",
                y_label: "y",
                value_label: "v",
                x,
                y,
                values,
                path_overlay,
                line_overlay: path_overlay,
                categories: [None, None],
            };
            heatmap_svg(&map).unwrap_or_else(|e| panic!("{x:?} {y:?} {values:?}: {e}"));
        }
    }

    #[test]
    fn bad_grids_are_errors() {
        let values = vec![vec![1.0, 2.0]];
        let base = Heatmap {
            title: "t",
            x_label: "x",
            y_label: "y",
            value_label: "v",
            x: &[1.0, 2.0],
            y: &[1.0],
            values: &values,
            path_overlay: &[],
            line_overlay: &[],
            categories: [None, None],
        };
        assert!(heatmap_svg(&base).is_ok());
        for map in [
            Heatmap {
                x: &[2.0, 1.0],
                ..base
            },
            Heatmap {
                x: &[1.0, f64::NAN],
                ..base
            },
            Heatmap {
                y: &[1.0, 2.0],
                ..base
            },
            Heatmap {
                x: &[1.0, 2.0, 3.0],
                ..base
            },
            Heatmap {
                x: &[-f64::MAX, f64::MAX],
                ..base
            },
        ] {
            assert!(
                matches!(heatmap_svg(&map), Err(Error::Io { .. })),
                "{map:?}"
            );
        }
    }

    #[test]
    fn colour_map_ends() {
        assert_eq!(colour(0.0), RGBColor(0x44, 0x01, 0x54));
        assert_eq!(colour(1.0), RGBColor(0xfd, 0xe7, 0x25));
        assert_eq!(colour(f64::NAN), colour(0.0));
        assert_eq!(colour(2.0), colour(1.0));
    }
}
