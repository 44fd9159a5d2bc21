//! Legends drawn in a panel of their own beside the plot area, never over the data:
//! one row per entry, a swatch (line, marker, cross or filled box) and its text.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{text_width, FONT, LEGEND_PX};

/// Height of one legend row [px].
pub(crate) const ROW_PX: i32 = 22;
/// Width of a swatch [px].
const SWATCH_W: i32 = 22;
/// Gap between a swatch and its text [px].
const GAP: i32 = 8;
/// Space left and right of the entries inside the panel [px].
const PAD: i32 = 16;
/// Narrowest and widest legend panel [px].
const WIDTH: (u32, u32) = (110, 230);

/// What is drawn before an entry's text.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Swatch {
    /// A line of this colour and width [px], with a dot in its middle if `marker`.
    Line {
        /// Colour of the line.
        colour: RGBColor,
        /// Stroke width [px].
        width: u32,
        /// A dot in the middle.
        marker: bool,
    },
    /// A dashed line of this colour and width [px] (on, off [px]) with a marker of
    /// `shape` in its middle (if the plot draws markers): a series drawn on top of
    /// another it coincides with.
    Dashed {
        /// Colour of the line.
        colour: RGBColor,
        /// Stroke width [px].
        width: u32,
        /// Dash length and gap [px].
        dash: (u32, u32),
        /// The marker in the middle.
        shape: Option<Shape>,
    },
    /// A dot of this colour, no line.
    Marker(RGBColor),
    /// A black cross.
    Cross,
    /// A filled box (a category of cells).
    Fill(RGBColor),
    /// A line of `colour` across a box filled with `fill` (a line with a shaded band).
    Band {
        /// Fill of the box.
        fill: RGBColor,
        /// Colour of the line.
        colour: RGBColor,
    },
    /// Nothing: a heading or a summary row.
    Text,
    /// Nothing, text indented as after a swatch: the next line of a wrapped entry.
    Continued,
}

/// The marker drawn at the points of a series that lies on another (the others get
/// filled dots).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Shape {
    /// A filled triangle, point up.
    Triangle,
    /// An open square.
    Square,
    /// A diagonal cross.
    Cross,
}

impl Shape {
    /// Draws the marker of this shape centred on `at` [px] (3 px to its edge).
    pub(crate) fn draw<DB: DrawingBackend>(
        self,
        area: &DrawingArea<DB, Shift>,
        at: (i32, i32),
        colour: RGBColor,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        match self {
            Shape::Triangle => area.draw(&TriangleMarker::new(at, 5, colour.filled())),
            Shape::Square => area.draw(&Rectangle::new(
                [(at.0 - 4, at.1 - 4), (at.0 + 4, at.1 + 4)],
                colour.stroke_width(2),
            )),
            Shape::Cross => area.draw(&Cross::new(at, 4, colour.stroke_width(2))),
        }
    }
}

/// One legend row.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Entry {
    /// The text.
    pub text: String,
    /// The swatch before it.
    pub swatch: Swatch,
}

/// Width [px] of a panel that holds `entries` (clamped to 120–300 px).
pub(crate) fn panel_width(entries: &[Entry]) -> u32 {
    let widest = entries
        .iter()
        .map(|e| text_width(&e.text, LEGEND_PX) as i32 + SWATCH_W + GAP)
        .max()
        .unwrap_or(0);
    ((widest + 2 * PAD).max(0) as u32).clamp(WIDTH.0, WIDTH.1)
}

/// `entries` with every text wider than a panel `panel` px wide allows broken at
/// spaces into several rows (a word wider than the row stays whole).
pub(crate) fn wrap(entries: Vec<Entry>, panel: u32) -> Vec<Entry> {
    let room = panel as i32 - 2 * PAD - SWATCH_W - GAP;
    let fits = |t: &str| text_width(t, LEGEND_PX) as i32 <= room;
    let mut out = Vec::new();
    for entry in entries {
        if fits(&entry.text) {
            out.push(entry);
            continue;
        }
        let mut swatch = entry.swatch;
        let mut line = String::new();
        for word in entry.text.split(' ') {
            let longer = if line.is_empty() {
                word.to_string()
            } else {
                format!("{line} {word}")
            };
            if fits(&longer) || line.is_empty() {
                line = longer;
            } else {
                out.push(Entry {
                    text: std::mem::replace(&mut line, word.to_string()),
                    swatch,
                });
                swatch = Swatch::Continued;
            }
        }
        out.push(Entry { text: line, swatch });
    }
    out
}

/// The entries that fit into `height` px: all of them, or as many as fit less one
/// and a last row `… and N more`.
pub(crate) fn fit(mut entries: Vec<Entry>, height: i32) -> Vec<Entry> {
    let rows = (height / ROW_PX).max(1) as usize;
    if entries.len() > rows {
        let kept = rows - 1;
        let more = entries.len() - kept;
        entries.truncate(kept);
        entries.push(Entry {
            text: format!("… and {more} more"),
            swatch: Swatch::Text,
        });
    }
    entries
}

/// Draws `entries` top-down onto `area`, the first row centred `top + ROW_PX / 2` px
/// below the area's top, swatches starting `left` px from its left edge.
pub(crate) fn draw<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
    (left, top): (i32, i32),
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let text_style = TextStyle::from((FONT, LEGEND_PX).into_font())
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    for (row, entry) in entries.iter().enumerate() {
        let y = top + ROW_PX / 2 + row as i32 * ROW_PX;
        let (x0, x1) = (left, left + SWATCH_W);
        let mid = (x0 + x1) / 2;
        match entry.swatch {
            Swatch::Line {
                colour,
                width,
                marker,
            } => {
                let style = colour.stroke_width(width);
                area.draw(&PathElement::new(vec![(x0, y), (x1, y)], style))?;
                if marker {
                    area.draw(&Circle::new((mid, y), 3, colour.filled()))?;
                }
            }
            Swatch::Dashed {
                colour,
                width,
                dash,
                shape,
            } => {
                area.draw(&plotters::element::DashedPathElement::new(
                    vec![(x0, y), (x1, y)],
                    dash.0,
                    dash.1,
                    colour.stroke_width(width),
                ))?;
                if let Some(shape) = shape {
                    shape.draw(area, (mid, y), colour)?;
                }
            }
            Swatch::Marker(colour) => area.draw(&Circle::new((mid, y), 4, colour.filled()))?,
            Swatch::Cross => area.draw(&Cross::new((mid, y), 5, BLACK.stroke_width(2)))?,
            Swatch::Fill(colour) => {
                let corners = [(x0, y - 7), (x1, y + 7)];
                area.draw(&Rectangle::new(corners, colour.filled()))?;
                area.draw(&Rectangle::new(corners, BLACK.mix(0.5).stroke_width(1)))?;
            }
            Swatch::Band { fill, colour } => {
                area.draw(&Rectangle::new([(x0, y - 7), (x1, y + 7)], fill.filled()))?;
                area.draw(&PathElement::new(
                    vec![(x0, y), (x1, y)],
                    colour.stroke_width(2),
                ))?;
            }
            Swatch::Text | Swatch::Continued => {}
        }
        let x = match entry.swatch {
            Swatch::Text => x0,
            _ => x1 + GAP,
        };
        area.draw(&Text::new(entry.text.as_str(), (x, y), text_style.clone()))?;
    }
    Ok(())
}

/// Left margin [px] of the entries inside a panel.
pub(crate) const INSET: i32 = PAD;

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(text: &str) -> Entry {
        Entry {
            text: text.to_string(),
            swatch: Swatch::Cross,
        }
    }

    #[test]
    fn long_legends_are_cut_with_a_count() {
        let entries: Vec<Entry> = (0..10).map(|i| entry(&format!("e{i}"))).collect();
        assert_eq!(fit(entries.clone(), 10 * ROW_PX), entries);
        let cut = fit(entries, 4 * ROW_PX);
        assert_eq!(cut.len(), 4);
        assert_eq!(cut[3].text, "… and 7 more");
        assert_eq!(fit(vec![entry("a"), entry("b")], 0)[0].text, "… and 2 more");
    }

    #[test]
    fn long_texts_wrap_at_spaces() {
        let long = "diverged: 4 of 12 points (left out; value unknown)";
        let rows = wrap(vec![entry(long), entry("short")], WIDTH.1);
        assert!(rows.len() > 2, "{rows:?}");
        assert_eq!(rows[0].swatch, Swatch::Cross);
        assert_eq!(rows[1].swatch, Swatch::Continued);
        assert_eq!(rows.last().unwrap().text, "short");
        let joined: Vec<&str> = rows[..rows.len() - 1]
            .iter()
            .map(|r| r.text.as_str())
            .collect();
        assert_eq!(joined.join(" "), long);
        for r in &rows[..rows.len() - 1] {
            let w = text_width(&r.text, LEGEND_PX) as i32 + SWATCH_W + GAP + 2 * PAD;
            assert!(w <= WIDTH.1 as i32, "{r:?}: {w} px");
        }
        // One word wider than the panel stays whole.
        let word = "x".repeat(100);
        assert_eq!(wrap(vec![entry(&word)], WIDTH.1)[0].text, word);
    }

    #[test]
    fn panel_width_follows_the_text() {
        assert_eq!(panel_width(&[]), WIDTH.0);
        assert!(panel_width(&[entry(&"x".repeat(20))]) > WIDTH.0);
        assert_eq!(panel_width(&[entry(&"x".repeat(200))]), WIDTH.1);
    }
}
