//! SVG plots of a run: line plots of signals over time ([`LinePlot`]), the
//! grid-search heatmap with an optimizer's path ([`Heatmap`]) and the TDMA slot
//! timeline ([`SlotTimeline`]).
//!
//! Plots are drawn with `plotters` into an in-memory string and written with
//! [`crate::output::write_atomic`]. Without font features plotters estimates text sizes
//! itself and emits real SVG `<text>` elements, so titles, axis labels, tick labels and
//! legends stay searchable text and the output does not depend on the fonts installed.
//!
//! Everything drawn is a pure function of the input: ranges, ticks, colours and
//! decimation involve no randomness, clock or hash order, so the same data gives the
//! same bytes.
//!
//! Every legend sits in its own panel beside or below the plot area, never over the
//! data.
//!
//! Inside: `axis` (ranges from data, ticks and tick labels for linear and log axes),
//! `line` (line plots, staircases for delays, decimation of long series), `legend`
//! (legend panels), `labels` (text beside points, placed to avoid overlaps),
//! [`envelope`] (many series summed up as min/RMS/max plus the worst few) and `heatmap`
//! (coloured grid cells with a colour bar or a legend of categories, path overlay).

mod axis;
pub mod envelope;
mod heatmap;
mod labels;
mod legend;
mod line;
pub mod timeline;

use std::path::Path;

use plotters::style::RGBColor;

use crate::error::Error;

pub use heatmap::{heatmap_svg, write_heatmap, CellClass, Heatmap};
pub use line::{line_plot_svg, write_line_plot, write_panels, LinePlot, Series};
pub use timeline::{slot_timeline_svg, write_slot_timeline, SlotTimeline};

/// How values are placed along an axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scale {
    /// Evenly spaced values.
    #[default]
    Linear,
    /// Evenly spaced decades; values `<= 0` are not drawn.
    Log,
}

/// Size of every plot [px]: 960 × 540, a 16:9 frame that stays legible on a page.
const SIZE: (u32, u32) = (960, 540);

/// `text` with its first letter in capitals: a plot's title starts a sentence.
pub fn capitalized(text: &str) -> String {
    let mut chars = text.chars();
    match chars.next() {
        Some(first) => first.to_uppercase().chain(chars).collect(),
        None => String::new(),
    }
}

/// Font family of all text; the SVG viewer picks the actual face.
const FONT: &str = "sans-serif";

/// Font sizes as plotters takes them (the SVG gets them divided by 1.24) [px]: title,
/// axis labels, tick labels, legend.
const TITLE_PX: f64 = 26.0;
/// See [`TITLE_PX`].
const DESC_PX: f64 = 20.0;
/// See [`TITLE_PX`].
const TICK_PX: f64 = 18.0;
/// See [`TITLE_PX`].
const LEGEND_PX: f64 = 17.0;

/// Series colours, in order: Tableau 10 plus black and indigo, all distinct on white.
const PALETTE: [RGBColor; 12] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x7f, 0x7f, 0x7f),
    RGBColor(0xbc, 0xbd, 0x22),
    RGBColor(0x17, 0xbe, 0xcf),
    RGBColor(0x00, 0x00, 0x00),
    RGBColor(0x39, 0x3b, 0x79),
];

/// Palette colour `i` (cycling) as `[r, g, b]`, mixed with white by `white` (0 the
/// colour itself, 1 white): for a series set back behind a highlighted one.
pub(crate) fn palette(i: usize, white: f64) -> [u8; 3] {
    let c = PALETTE[i % PALETTE.len()];
    let mix = |v: u8| (f64::from(v) + (255.0 - f64::from(v)) * white.clamp(0.0, 1.0)).round() as u8;
    [mix(c.0), mix(c.1), mix(c.2)]
}

/// Colour of grid lines.
const GRID: RGBColor = RGBColor(0xdd, 0xdd, 0xdd);

/// Converts a plotters error into an [`Error::Io`] naming the file being drawn
/// (`<svg>` when drawing into memory).
fn plot_error<E: std::fmt::Display>(target: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| Error::io(target, std::io::Error::other(format!("drawing plot: {e}")))
}

/// Width [px] that plotters' built-in font metrics give `text` at `size` [px].
fn text_width(text: &str, size: f64) -> u32 {
    let em = size / 1.24 / 1.24;
    (em * 0.7 * text.len() as f64).round() as u32
}

/// Helpers for tests that read the SVG text of a plot.
#[cfg(test)]
pub(crate) mod tests_support {
    /// `(x, width, fill)` of every `<rect>` (plotters writes x, y, width, height,
    /// opacity, fill in this order).
    pub(crate) fn rects(svg: &str) -> Vec<(i32, i32, String)> {
        let attr = |tag: &str, name: &str| -> Option<String> {
            let at = tag.find(&format!(" {name}=\""))? + name.len() + 3;
            let len = tag[at..].find('"')?;
            Some(tag[at..at + len].to_string())
        };
        svg.split("<rect")
            .skip(1)
            .filter_map(|rest| {
                let tag = &rest[..rest.find('>')?];
                Some((
                    attr(tag, "x")?.parse().ok()?,
                    attr(tag, "width")?.parse().ok()?,
                    attr(tag, "fill")?,
                ))
            })
            .collect()
    }

    /// The approximate box `(x0, y0, x1, y1)` [px] of every non-empty `<text>`, with
    /// its text: from the anchor (`x`, `y`), `text-anchor`, the `dy` plotters writes
    /// for a top (`0.76em`), centred (`0.5ex`) or bottom (`-0.5ex`) anchor, the
    /// `font-size` (a glyph 0.56 em wide on average, as DejaVu Sans draws lower-case
    /// text and digits; 0.9 em tall, ascender to descender) and a `rotate(90|270, …)`.
    pub(crate) fn text_boxes(svg: &str) -> Vec<(String, (f64, f64, f64, f64))> {
        let attr = attribute;
        let num = |tag: &str, name: &str| attr(tag, name).and_then(|v| v.parse::<f64>().ok());
        text_elements(svg)
            .filter_map(|(tag, body)| {
                let body = body
                    .replace("&lt;", "<")
                    .replace("&gt;", ">")
                    .replace("&amp;", "&")
                    .replace("&quot;", "\"");
                if body.is_empty() {
                    return None;
                }
                let (x, y, fs) = (num(tag, "x")?, num(tag, "y")?, num(tag, "font-size")?);
                let w = 0.56 * fs * body.chars().count() as f64;
                let h = 0.9 * fs;
                // Offsets of the unrotated box from the anchor.
                let (dx0, dx1) = match attr(tag, "text-anchor") {
                    Some("middle") => (-w / 2.0, w / 2.0),
                    Some("end") => (-w, 0.0),
                    _ => (0.0, w),
                };
                let (dy0, dy1) = match attr(tag, "dy") {
                    Some("0.76em") => (0.0, h),
                    Some("-0.5ex") => (-h, 0.0),
                    _ => (-h / 2.0, h / 2.0),
                };
                let angle = attr(tag, "transform")
                    .and_then(|t| {
                        t.strip_prefix("rotate(")?
                            .split(',')
                            .next()?
                            .trim()
                            .parse::<f64>()
                            .ok()
                    })
                    .unwrap_or(0.0);
                let b = match angle as i32 {
                    // (dx, dy) turns into (dy, -dx).
                    270 => (x + dy0, y - dx1, x + dy1, y - dx0),
                    // (dx, dy) turns into (-dy, dx).
                    90 => (x - dy1, y + dx0, x - dy0, y + dx1),
                    _ => (x + dx0, y + dy0, x + dx1, y + dy1),
                };
                Some((body, b))
            })
            .collect()
    }

    /// Panics naming the first two texts of `svg` whose [`text_boxes`] intersect.
    pub(crate) fn assert_no_text_overlaps(svg: &str) {
        let boxes = text_boxes(svg);
        for (i, (a, ra)) in boxes.iter().enumerate() {
            for (b, rb) in &boxes[i + 1..] {
                let hit = ra.0 < rb.2 && rb.0 < ra.2 && ra.1 < rb.3 && rb.1 < ra.3;
                assert!(!hit, "text {a:?} at {ra:?} overlaps {b:?} at {rb:?}");
            }
        }
    }

    /// `(x, y, text)` of every `<text>` element (plotters writes the text on its own
    /// line between the tag and `</text>`).
    pub(crate) fn texts(svg: &str) -> Vec<(i32, i32, String)> {
        let at = |tag: &str, name: &str| -> Option<i32> {
            attribute(tag, name)?.parse::<f64>().ok().map(|v| v as i32)
        };
        text_elements(svg)
            .filter_map(|(tag, body)| Some((at(tag, "x")?, at(tag, "y")?, body.to_string())))
            .collect()
    }

    /// Every `<text>` element of `svg`: its opening tag's attributes and its trimmed
    /// text (plotters writes the text on its own line between the tag and `</text>`).
    fn text_elements(svg: &str) -> impl Iterator<Item = (&str, &str)> {
        svg.split("<text").skip(1).filter_map(|rest| {
            let end = rest.find('>')?;
            Some((&rest[..end], rest[end + 1..rest.find("</text>")?].trim()))
        })
    }

    /// The value of attribute `name` in an element's opening `tag`.
    fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
        let at = tag.find(&format!(" {name}=\""))? + name.len() + 3;
        let len = tag[at..].find('"')?;
        Some(&tag[at..at + len])
    }
}
