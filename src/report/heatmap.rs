//! Heatmaps of a value over a 2-D grid (the grid-search cost surface), with a colour
//! bar and an optional overlaid path (the optimizer's trajectory); or of categories
//! (a stability map's outcomes), each in its own colour with a legend naming it.

use std::io;
use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::axis::Axis;
use super::legend::{self, Entry, Swatch};
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

/// One category of cells of a categorical [`Heatmap`]: its legend name and colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellClass<'a> {
    /// Legend text: `diverged`.
    pub name: &'a str,
    /// Fill `[r, g, b]` of its cells.
    pub rgb: [u8; 3],
}

/// Legend text of the cells that hold no category (or no value) in a categorical map.
const MISSING_NAME: &str = "no value";

/// A value over a grid of `x` × `y` cells.
#[derive(Clone, Copy, Debug)]
pub struct Heatmap<'a> {
    /// Title above the plot.
    pub title: &'a str,
    /// Text under the x axis, with the unit.
    pub x_label: &'a str,
    /// Text beside the y axis, with the unit.
    pub y_label: &'a str,
    /// Text beside the colour bar, with the unit: `mean cost J`; the legend's heading
    /// on a categorical map.
    pub value_label: &'a str,
    /// Cell centres along x, finite and strictly increasing.
    pub x: &'a [f64],
    /// Cell centres along y, finite and strictly increasing.
    pub y: &'a [f64],
    /// `values[iy][ix]` at `(x[ix], y[iy])`: `y.len()` rows of `x.len()` values. A
    /// non-finite value marks a missing cell, drawn grey. On a categorical map the
    /// value is the index of the cell's class; one that is not is missing.
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
    /// Discrete cell classes: `Some` draws each cell in the colour of its class
    /// (`values` are indices into it) with a legend of swatches and names instead of
    /// the colour bar; `None` for a continuous value on the viridis map.
    pub classes: Option<&'a [CellClass<'a>]>,
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

/// Colour of `t` in `[0, 1]` on plotters' viridis map (clamped; NaN is 0, which
/// plotters' map would panic on).
fn colour(t: f64) -> RGBColor {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    ViridisRGB.get_color(t)
}

/// The class index `v` names in `classes`, if it is one.
fn class_of(v: f64, classes: &[CellClass]) -> Option<usize> {
    (v.is_finite() && v >= 0.0 && v.fract() == 0.0 && v < classes.len() as f64)
        .then_some(v as usize)
}

/// The legend of a categorical map: its heading, one swatch per class and, when a
/// cell has no class, one for those.
fn class_entries(map: &Heatmap, classes: &[CellClass]) -> Vec<Entry> {
    let mut entries = vec![Entry {
        text: map.value_label.to_string(),
        swatch: Swatch::Text,
    }];
    entries.extend(classes.iter().map(|c| Entry {
        text: c.name.to_string(),
        swatch: Swatch::Fill(RGBColor(c.rgb[0], c.rgb[1], c.rgb[2])),
    }));
    if map
        .values
        .iter()
        .flatten()
        .any(|&v| class_of(v, classes).is_none())
    {
        entries.push(Entry {
            text: MISSING_NAME.to_string(),
            swatch: Swatch::Fill(MISSING),
        });
    }
    entries
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
    // Category names along x that do not fit their cells side by side are drawn turned
    // a quarter, reading upwards, under their cells (cut with `…` past MAX_TURNED px).
    let x_names = map.categories[0].map(|names| {
        let plot_width = SIZE.0.saturating_sub(panel_width(map) + 32 + y_area);
        let cell = plot_width / names.len().max(1) as u32;
        let widest = names
            .iter()
            .map(|n| text_width(n, TICK_PX))
            .max()
            .unwrap_or(0);
        let turned = widest + 8 > cell;
        let shown: Vec<String> = if turned {
            names.iter().map(|n| cut(n, MAX_TURNED)).collect()
        } else {
            names.to_vec()
        };
        (shown, turned)
    });
    let x_area = match &x_names {
        Some((shown, true)) => {
            let longest = shown
                .iter()
                .map(|n| text_width(n, TICK_PX))
                .max()
                .unwrap_or(0);
            longest + 45
        }
        _ => 55,
    };
    let v_area = (widest(&v_axis) + 40).clamp(60, BAR_PANEL - 30);
    let class_legend = map.classes.map(|c| class_entries(map, c));
    let panel = panel_width(map);

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let body = root.titled(map.title, (FONT, TITLE_PX)).map_err(&err)?;
        let (main, bar) = body.split_horizontally(SIZE.0 - panel);

        let mut chart = ChartBuilder::on(&main)
            .margin(16)
            .x_label_area_size(x_area)
            .y_label_area_size(y_area)
            .build_cartesian_2d(x_axis, y_axis)
            .map_err(&err)?;
        let turned = matches!(x_names, Some((_, true)));
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
        let x_format = |v: &f64| {
            if turned {
                String::new()
            } else {
                category(map.categories[0], *v, &xa)
            }
        };
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
                let fill = match map.classes {
                    Some(classes) => class_of(v, classes).map_or(MISSING, |c| {
                        let [r, g, b] = classes[c].rgb;
                        RGBColor(r, g, b)
                    }),
                    None if v.is_finite() => colour(v_axis.fraction(v)),
                    None => MISSING,
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
        if let Some((names, true)) = &x_names {
            let style = TextStyle::from((FONT, TICK_PX).into_font())
                .color(&BLACK)
                .transform(FontTransform::Rotate270)
                .pos(Pos::new(HPos::Right, VPos::Center));
            let bottom = chart.plotting_area().get_pixel_range().1.end;
            for (i, name) in names.iter().enumerate() {
                let (px, _) = chart.backend_coord(&(i as f64, y_axis.lo()));
                root.draw(&Text::new(name.clone(), (px, bottom + 8), style.clone()))
                    .map_err(&err)?;
            }
        }
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
        match class_legend {
            Some(entries) => {
                // A categorical map: swatches and names instead of a colour bar, the
                // first row level with the plot area's top.
                let top = chart.plotting_area().get_pixel_range().1.start;
                let entries = legend::fit(legend::wrap(entries, panel), SIZE.1 as i32 - top);
                legend::draw(
                    &root,
                    &entries,
                    ((SIZE.0 - panel) as i32 + legend::INSET, top),
                )
                .map_err(&err)?;
            }
            None => colour_bar(&bar, map.value_label, v_axis, v_area, x_area).map_err(&err)?,
        }
        root.present().map_err(&err)?;
    }
    Ok(svg)
}

/// Longest turned category name along x [px]; longer ones are cut with `…`.
const MAX_TURNED: u32 = 200;

/// Width [px] of the panel right of the cells: the colour bar's, or the class legend's.
fn panel_width(map: &Heatmap) -> u32 {
    map.classes
        .map(|c| class_entries(map, c))
        .as_deref()
        .map_or(BAR_PANEL, |e| legend::panel_width(e).max(BAR_PANEL))
}

/// `name`, cut to at most `px` wide at `TICK_PX` with a trailing `…`.
fn cut(name: &str, px: u32) -> String {
    if text_width(name, TICK_PX) <= px {
        return name.to_string();
    }
    let mut out: String = name.to_string();
    while !out.is_empty() && text_width(&format!("{out}…"), TICK_PX) > px {
        out.pop();
    }
    format!("{out}…")
}

/// Draws the colour bar into `area`: the value axis on the right of a strip of the
/// colour map.
fn colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    value_label: &str,
    v_axis: Axis,
    v_area: u32,
    x_area: u32,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    // As tall as the cells beside it.
    let mut bar_chart = ChartBuilder::on(area)
        .margin_top(16)
        .margin_bottom(16 + x_area)
        .margin_left(10)
        .margin_right(10)
        .right_y_label_area_size(v_area)
        .build_cartesian_2d(Axis::exact(Scale::Linear, [0.0, 1.0]), v_axis)?;
    bar_chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(value_label)
        .y_labels(8)
        .label_style((FONT, TICK_PX))
        .axis_desc_style((FONT, DESC_PX))
        .draw()?;
    let (lo, hi) = (v_axis.lo(), v_axis.hi());
    let strips = (0..BAR_STEPS).map(|i| {
        let a = lo + (hi - lo) * i as f64 / BAR_STEPS as f64;
        let b = lo + (hi - lo) * (i + 1) as f64 / BAR_STEPS as f64;
        let t = (i as f64 + 0.5) / BAR_STEPS as f64;
        Rectangle::new([(0.0, a), (1.0, b)], colour(t).filled())
    });
    bar_chart.draw_series(strips)?;
    Ok(())
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
            classes: None,
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
        crate::report::tests_support::assert_no_text_overlaps(&svg);
    }

    #[test]
    fn long_category_names_along_x_are_turned_and_do_not_overlap() {
        // The slot-layout sweep's picture: ten long names under ten cells.
        let names: Vec<String> = (0..10)
            .map(|i| format!("{i} blocked_5ms_off_step_{}", "x".repeat(i)))
            .collect();
        let drift: Vec<String> = ["0", "300", "1000"].map(String::from).to_vec();
        let x: Vec<f64> = (0..10).map(f64::from).collect();
        let y = [0.0, 1.0, 2.0];
        let values: Vec<Vec<f64>> = (0..3)
            .map(|r| (0..10).map(|c| (r * c) as f64).collect())
            .collect();
        let map = Heatmap {
            title: "layouts",
            x_label: "layout",
            y_label: "drift [ppm]",
            value_label: "mean cost C [m]",
            x: &x,
            y: &y,
            values: &values,
            path_overlay: &[],
            line_overlay: &[],
            categories: [Some(&names), Some(&drift)],
            classes: None,
        };
        let svg = heatmap_svg(&map).unwrap();
        let turned = svg.matches("transform=\"rotate(270").count();
        // Ten names and the y axis label (and the colour bar's).
        assert!(turned >= 11, "{turned} turned texts");
        assert!(
            svg.contains("0 blocked_5ms_off_step_\n"),
            "a short name whole"
        );
        assert!(svg.contains("…"), "the longest names cut");
        crate::report::tests_support::assert_no_text_overlaps(&svg);
        // Short names stay level.
        let short: Vec<String> = (0..10).map(|i| format!("L{i}")).collect();
        let svg = heatmap_svg(&Heatmap {
            categories: [Some(&short), Some(&drift)],
            ..map
        })
        .unwrap();
        assert!(!svg.contains(">\nL3\n</text>") || !svg.contains("rotate(270, 3"));
        assert_eq!(svg.matches("transform=\"rotate(270").count(), turned - 10);
        crate::report::tests_support::assert_no_text_overlaps(&svg);
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
                classes: None,
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
            classes: None,
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
    fn categorical_map_has_a_legend_of_classes_beside_the_cells() {
        let classes = [
            CellClass {
                name: "stable",
                rgb: [0x2c, 0x7f, 0xb8],
            },
            CellClass {
                name: "diverged",
                rgb: [0x7f, 0x00, 0x00],
            },
        ];
        // Two stable, two diverged, two without a class (NaN, 7).
        let values = vec![vec![0.0, 1.0, 1.0], vec![f64::NAN, 0.0, 7.0]];
        let map = Heatmap {
            title: "Stability",
            x_label: "log10 dt [s]",
            y_label: "log10 μ [s]",
            value_label: "outcome",
            x: &[1.0, 2.0, 3.0],
            y: &[1.0, 2.0],
            values: &values,
            path_overlay: &[],
            line_overlay: &[],
            categories: [None, None],
            classes: Some(&classes),
        };
        let svg = heatmap_svg(&map).unwrap();
        let texts = crate::report::tests_support::texts(&svg);
        for name in ["stable", "diverged", "no value", "outcome", "log10 dt [s]"] {
            assert!(texts.iter().any(|t| t.2 == name), "missing {name:?}");
        }
        let boxes = crate::report::tests_support::rects(&svg);
        let filled = |fill: &str| boxes.iter().filter(|r| r.2 == fill).count();
        // Cells plus one legend swatch each; no colour bar of viridis strips.
        assert_eq!(filled("#2C7FB8"), 2 + 1);
        assert_eq!(filled("#7F0000"), 2 + 1);
        assert_eq!(filled("#B4B4B4"), 2 + 1);
        assert!(boxes.len() < 20, "no colour bar: {} rects", boxes.len());
        let cells_right = boxes
            .iter()
            .filter(|r| r.1 > 40)
            .filter(|r| r.2 != "#FFFFFF")
            .map(|r| r.0 + r.1)
            .max()
            .unwrap();
        for name in ["stable", "diverged"] {
            let x = texts.iter().find(|t| t.2 == name).unwrap().0;
            assert!(x > cells_right, "{name} at {x}, cells up to {cells_right}");
        }
        // Every cell has a class: no "no value" entry.
        let all = vec![vec![0.0, 1.0, 1.0], vec![1.0, 0.0, 0.0]];
        let svg = heatmap_svg(&Heatmap {
            values: &all,
            ..map
        })
        .unwrap();
        assert!(svg.contains("stable") && !svg.contains("no value"));
        // A continuous map keeps its colour bar.
        let svg = heatmap_svg(&Heatmap {
            classes: None,
            ..map
        })
        .unwrap();
        assert!(
            !svg.contains("stable") && crate::report::tests_support::rects(&svg).len() > BAR_STEPS
        );
    }

    #[test]
    fn colour_map_ends() {
        assert_eq!(colour(0.0), RGBColor(0x44, 0x01, 0x54));
        assert_eq!(colour(1.0), RGBColor(0xfe, 0xe8, 0x25));
        assert_eq!(colour(f64::NAN), colour(0.0));
        assert_eq!(colour(2.0), colour(1.0));
    }
}
