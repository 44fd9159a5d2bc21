//! Slot-timeline diagrams of a few TDMA cycles: one lane per node, each slot's nominal
//! extent in its owner's lane, every frame where it actually went on the wire (clock
//! drift included), lost frames in red, cycle boundaries and a legend.
//!
//! ```text
//!  TDMA node          ┆ cycle 0                          ┆ cycle 1
//!  server (node 0)    ┆██ ░▒▒ ░                          ┆██ ░▒▒ ░
//!  client 1 (node 1)  ┆        ▒  ░     ████ ░           ┆        ▒  ░
//!  client 2 (node 2)  ┆           ▒  ░      ████ ░  XXXX ░┆           ▒  ░
//!                     └──────────────────────────────────────────── time t [ms]
//!  ██ ▒ █ frames where they went on the wire, coloured by kind (sync, static,
//!  protocol, channel); XXXX a lost frame (red, crossed out); ░ the guard band at the
//!  end of every slot (grey, across all lanes); a light box behind each slot in its
//!  owner's lane (not drawn here)
//! ```
//!
//! Like the other plots, the drawing is a pure function of the input (no randomness,
//! clock or hash order), so the same cycles give the same bytes.

use std::ops::Range;
use std::path::Path;

use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::axis::Axis;
use super::{plot_error, text_width, Scale, DESC_PX, FONT, GRID, LEGEND_PX, TICK_PX, TITLE_PX};
use crate::error::Result;
use crate::kernel::SimTime;
use crate::network::tdma::collision::{FrameKind, Transmission};
use crate::network::tdma::layout::SlotKind;
use crate::network::tdma::{CycleLayout, CycleReport};
use crate::output::write_atomic;

/// Width of the diagram [px]: wide enough for ~20 slots per cycle over 3–4 cycles.
const WIDTH: u32 = 1200;
/// Height of everything but the lanes [px] (title, axis, one legend row, margins).
const BASE_HEIGHT: u32 = 150;
/// Height added per lane (TDMA node) [px].
const LANE_PX: u32 = 60;
/// Height of one legend row [px]; a legend that wraps adds this per extra row.
const LEGEND_ROW_PX: u32 = 22;
/// Margin around the chart and the legend [px].
const MARGIN: u32 = 16;
/// Width of a legend swatch [px].
const SWATCH_W: i32 = 20;
/// Height of a legend swatch [px].
const SWATCH_H: i32 = 12;
/// Gap between a swatch and its text, and after the text [px].
const LEGEND_GAP: i32 = 6;
/// See [`LEGEND_GAP`].
const LEGEND_SPACING: i32 = 18;

/// Height of the strip above the lanes that holds the cycle labels [lanes].
const HEADER: f64 = 0.55;
/// A slot's background leaves this much of its lane free above and below [lanes].
const SLOT_PAD: f64 = 0.1;
/// A frame leaves this much of its lane free above and below [lanes].
const FRAME_PAD: f64 = 0.22;
/// Narrowest frame drawn, as a fraction of the x range: 0.4 % (≈ 4 px at 1200 px) keeps
/// the frames of an instantaneous link (duration 0) visible.
const MIN_FRAME_WIDTH: f64 = 0.004;
/// Tick labels requested along x.
const X_TICKS: usize = 12;
/// Slots narrower than this get no hairline at their start [px].
const MIN_SLOT_PX: f64 = 6.0;
/// Lost frames narrower than this get no cross, only the red fill [px].
const MIN_CROSS_PX: f64 = 8.0;

/// Fill of sync frames.
const SYNC: RGBColor = RGBColor(0x39, 0x3b, 0x79);
/// Fill of static frames that carry only a header.
const STATIC: RGBColor = RGBColor(0x94, 0x67, 0xbd);
/// Fill of static frames that carry protocol data (list broadcast or confirmation).
const PROTOCOL: RGBColor = RGBColor(0xe3, 0x77, 0xc2);
/// Fill of lost frames (collisions), whatever they carry.
const LOST: RGBColor = RGBColor(0xd6, 0x27, 0x28);
/// The cross over a lost frame.
const LOST_CROSS: RGBColor = RGBColor(0x5a, 0x00, 0x00);
/// Background of a slot's usable part in its owner's lane.
const SLOT_BG: RGBColor = RGBColor(0xe2, 0xea, 0xf4);
/// Outline of the slot-background swatch in the legend (the fill alone is too light).
const SLOT_EDGE: RGBColor = RGBColor(0x9a, 0xaa, 0xbf);
/// The guard band at the end of every slot.
const GUARD: RGBColor = RGBColor(0xc4, 0xc4, 0xc4);
/// Cycle boundaries.
const BOUNDARY: RGBColor = RGBColor(0x40, 0x40, 0x40);
/// Channel colours (Tableau 10 without the red of lost frames and the purple, pink and
/// grey used above); channel `c` takes `CHANNELS[c % 6]`, darkened on each repeat.
const CHANNELS: [RGBColor; 6] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x17, 0xbe, 0xcf),
    RGBColor(0xbc, 0xbd, 0x22),
    RGBColor(0x8c, 0x56, 0x4b),
];

/// A few consecutive TDMA cycles to draw as a slot timeline.
#[derive(Clone, Copy, Debug)]
pub struct SlotTimeline<'a> {
    /// Title above the diagram.
    pub title: &'a str,
    /// The slot geometry the cycles ran with.
    pub layout: &'a CycleLayout,
    /// Guard time [ns]: the silent end of every slot ([`crate::network::tdma::TdmaConfig::guard`]).
    pub guard: SimTime,
    /// The cycles, in order (typically 2–4 consecutive ones).
    pub cycles: &'a [CycleReport],
    /// Name of channel `c` (legend text); a channel without a name is `channel c`.
    pub channel_names: &'a [String],
}

/// Renders `t` as an SVG document of 1200 × (150 + 60 · nodes) px (taller by a row
/// when the legend wraps).
///
/// The x axis is the time the cycles span [ms] (widened to every frame's actual extent);
/// one lane per TDMA node, the server at the top. Errors are [`crate::Error::Io`]
/// naming `<svg>`.
pub fn slot_timeline_svg(t: &SlotTimeline) -> Result<String> {
    render(t, Path::new("<svg>"))
}

/// Renders `t` and writes it to `path` atomically.
pub fn write_slot_timeline(path: &Path, t: &SlotTimeline) -> Result<()> {
    let svg = render(t, path)?;
    write_atomic(path, svg.as_bytes())
}

/// `t` in milliseconds.
fn to_ms(t: SimTime) -> f64 {
    t.0 as f64 * 1e-6
}

/// Lane text of TDMA node `node`.
fn lane_name(node: usize) -> String {
    if node == 0 {
        "server (node 0)".to_string()
    } else {
        format!("client {node} (node {node})")
    }
}

/// Name of channel `c` in the legend.
fn channel_name(names: &[String], c: usize) -> String {
    names
        .get(c)
        .cloned()
        .unwrap_or_else(|| format!("channel {c}"))
}

/// Colour of channel `c`: the base colours, darkened on every round through them.
fn channel_colour(c: usize) -> RGBColor {
    let RGBColor(r, g, b) = CHANNELS[c % CHANNELS.len()];
    let round = (c / CHANNELS.len()).min(3) as f64;
    let k = 1.0 - 0.28 * round;
    let dim = |v: u8| (f64::from(v) * k).round() as u8;
    RGBColor(dim(r), dim(g), dim(b))
}

/// Fill of a frame: red when lost, else by what it carries.
fn frame_colour(f: &Transmission) -> RGBColor {
    if f.lost() {
        return LOST;
    }
    match f.kind {
        FrameKind::Sync => SYNC,
        FrameKind::Static {
            broadcast: None,
            confirms: None,
        } => STATIC,
        FrameKind::Static { .. } => PROTOCOL,
        FrameKind::Dynamic { channel } => channel_colour(channel),
    }
}

/// The node whose lane shows slot `s` of cycle `r`: fixed for sync and static slots,
/// the list entry's sender (read off the frame sent in it) for a dynamic one, `None` for
/// an idle dynamic slot.
fn owner(layout: &CycleLayout, r: &CycleReport, s: usize) -> Option<usize> {
    match layout.kind(s)? {
        SlotKind::Sync => Some(0),
        SlotKind::Static { node } => Some(node),
        SlotKind::Dynamic { .. } => r.frames.iter().find(|f| f.slot == s).map(|f| f.sender),
    }
}

/// The lanes along y: node `i` of `nodes` spans `[nodes − 1 − i, nodes − i]` (the server
/// on top), with a strip of [`HEADER`] above the lanes for the cycle labels. Ticks sit
/// at the lane centres and are labelled with the node's name.
#[derive(Clone, Copy, Debug)]
struct Lanes {
    nodes: usize,
}

impl Lanes {
    /// The y range `[bottom, top)` of `node`'s lane.
    fn span(&self, node: usize) -> (f64, f64) {
        let bottom = (self.nodes - 1 - node) as f64;
        (bottom, bottom + 1.0)
    }

    /// Top of the lanes (bottom of the header strip).
    fn lanes_top(&self) -> f64 {
        self.nodes as f64
    }

    /// Top of the whole y range.
    fn top(&self) -> f64 {
        self.nodes as f64 + HEADER
    }
}

impl Ranged for Lanes {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let f = (value / self.top()).clamp(0.0, 1.0);
        let f = if f.is_nan() { 0.0 } else { f };
        limit.0 + (f * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        let max = hint.max_num_points();
        if max == 0 {
            return Vec::new();
        }
        let stride = self.nodes.div_ceil(max).max(1);
        (0..self.nodes)
            .step_by(stride)
            .map(|node| self.span(node).0 + 0.5)
            .collect()
    }

    fn range(&self) -> Range<f64> {
        0.0..self.top()
    }
}

impl ValueFormatter<f64> for Lanes {
    fn format_ext(&self, value: &f64) -> String {
        if !(0.0..self.lanes_top()).contains(value) {
            return String::new();
        }
        lane_name(self.nodes - 1 - *value as usize)
    }
}

/// How a legend entry's swatch looks.
#[derive(Clone, Copy, Debug)]
enum Swatch {
    /// A filled box.
    Fill(RGBColor),
    /// A filled box with an outline (for a fill too light to see on white).
    Outlined(RGBColor, RGBColor),
    /// A lost frame: red with a cross.
    Lost,
}

/// The legend: sync, static, protocol, every channel, lost, slot, guard. (The cycle
/// boundaries carry their own labels.)
fn legend_entries(t: &SlotTimeline) -> Vec<(String, Swatch)> {
    let used = t
        .cycles
        .iter()
        .flat_map(|r| &r.frames)
        .filter_map(|f| match f.kind {
            FrameKind::Dynamic { channel } => Some(channel + 1),
            _ => None,
        })
        .max()
        .unwrap_or(0);
    let channels = t.channel_names.len().max(used);
    let mut out = vec![
        ("sync".to_string(), Swatch::Fill(SYNC)),
        ("static".to_string(), Swatch::Fill(STATIC)),
        (
            "list broadcast / confirmation".to_string(),
            Swatch::Fill(PROTOCOL),
        ),
    ];
    out.extend((0..channels).map(|c| {
        (
            channel_name(t.channel_names, c),
            Swatch::Fill(channel_colour(c)),
        )
    }));
    out.extend([
        ("lost (collision)".to_string(), Swatch::Lost),
        (
            "nominal slot".to_string(),
            Swatch::Outlined(SLOT_BG, SLOT_EDGE),
        ),
        ("guard".to_string(), Swatch::Fill(GUARD)),
    ]);
    out
}

/// Positions `(x, row)` of the legend entries, left to right, wrapped to `width` [px].
fn legend_layout(entries: &[(String, Swatch)], width: i32) -> Vec<(i32, u32)> {
    let mut out = Vec::with_capacity(entries.len());
    let (mut x, mut row) = (0i32, 0u32);
    for (text, _) in entries {
        let w = SWATCH_W + LEGEND_GAP + text_width(text, LEGEND_PX) as i32;
        if x > 0 && x + w > width {
            x = 0;
            row += 1;
        }
        out.push((x, row));
        x += w + LEGEND_SPACING;
    }
    out
}

/// What is drawn for one frame: its box and whether it is crossed out.
struct FrameBox {
    x: (f64, f64),
    y: (f64, f64),
    fill: RGBColor,
    lost: bool,
}

fn render(t: &SlotTimeline, target: &Path) -> Result<String> {
    let err = plot_error(target);
    let lanes = Lanes {
        nodes: t.layout.clients() + 1,
    };
    let frames: Vec<&Transmission> = t
        .cycles
        .iter()
        .flat_map(|r| &r.frames)
        .filter(|f| f.sender < lanes.nodes)
        .collect();
    let (slot, cycle) = (to_ms(t.layout.slot_len()), to_ms(t.layout.cycle_len()));
    let guard = to_ms(t.guard.min(t.layout.slot_len()));
    let x_axis = Axis::exact(
        Scale::Linear,
        t.cycles
            .iter()
            .flat_map(|r| [to_ms(r.start), to_ms(r.start) + cycle])
            .chain(frames.iter().flat_map(|f| [to_ms(f.start), to_ms(f.end())])),
    );
    let min_width = (x_axis.hi() - x_axis.lo()) * MIN_FRAME_WIDTH;
    let boxes: Vec<FrameBox> = frames
        .iter()
        .map(|f| {
            let (bottom, top) = lanes.span(f.sender);
            let x0 = to_ms(f.start);
            let x1 = (x0 + to_ms(f.duration)).max(x0 + min_width);
            FrameBox {
                x: (x0, x1),
                y: (bottom + FRAME_PAD, top - FRAME_PAD),
                fill: frame_colour(f),
                lost: f.lost(),
            }
        })
        .collect();

    let legend = legend_entries(t);
    let legend_width = (WIDTH - 2 * MARGIN) as i32;
    let places = legend_layout(&legend, legend_width);
    let rows = places.last().map_or(1, |p| p.1 + 1);
    let lanes_px = LANE_PX.saturating_mul(u32::try_from(lanes.nodes).unwrap_or(u32::MAX));
    let height = BASE_HEIGHT
        .saturating_add(lanes_px)
        .saturating_add(LEGEND_ROW_PX.saturating_mul(rows - 1));
    let legend_height = LEGEND_ROW_PX * rows + MARGIN;
    let widest = (0..lanes.nodes)
        .map(|n| text_width(&lane_name(n), TICK_PX))
        .max()
        .unwrap_or(0);
    let y_area = (widest + 45).clamp(60, 300);

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let body = root.titled(t.title, (FONT, TITLE_PX)).map_err(&err)?;
        let body_height = body.dim_in_pixel().1;
        let (main, legend_area) = body.split_vertically(body_height.saturating_sub(legend_height));

        let mut chart = ChartBuilder::on(&main)
            .margin(MARGIN)
            .margin_top(4)
            .x_label_area_size(48)
            .y_label_area_size(y_area)
            .build_cartesian_2d(x_axis, lanes)
            .map_err(&err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("time t [ms]")
            .y_desc("TDMA node")
            .x_labels(X_TICKS)
            .y_labels(lanes.nodes)
            .label_style((FONT, TICK_PX))
            .axis_desc_style((FONT, DESC_PX))
            .draw()
            .map_err(&err)?;

        let (x_lo, x_hi) = (x_axis.lo(), x_axis.hi());
        let px_per_ms = f64::from(chart.plotting_area().dim_in_pixel().0) / (x_hi - x_lo);
        // Lane separators first, everything else on top.
        chart
            .draw_series((1..lanes.nodes).map(|i| {
                let y = i as f64;
                PathElement::new(vec![(x_lo, y), (x_hi, y)], GRID.stroke_width(1))
            }))
            .map_err(&err)?;

        // Each slot: the guard band across all lanes, the usable part in its owner's
        // lane, a white hairline at its start to part neighbours of one owner. Guards
        // under a pixel and hairlines in slots under [`MIN_SLOT_PX`] are left out: they
        // would only draw rounding noise.
        let slots: Vec<(f64, Option<usize>)> = t
            .cycles
            .iter()
            .flat_map(|r| {
                (0..t.layout.slots()).map(move |s| {
                    (
                        to_ms(r.start) + to_ms(t.layout.offset(s)),
                        owner(t.layout, r, s),
                    )
                })
            })
            .collect();
        if guard * px_per_ms >= 1.0 {
            chart
                .draw_series(slots.iter().map(|&(start, _)| {
                    Rectangle::new(
                        [
                            (start + slot - guard, 0.0),
                            (start + slot, lanes.lanes_top()),
                        ],
                        GUARD.filled(),
                    )
                }))
                .map_err(&err)?;
        }
        chart
            .draw_series(slots.iter().filter_map(|&(start, node)| {
                let (bottom, top) = lanes.span(node?);
                Some(Rectangle::new(
                    [
                        (start, bottom + SLOT_PAD),
                        (start + slot - guard, top - SLOT_PAD),
                    ],
                    SLOT_BG.filled(),
                ))
            }))
            .map_err(&err)?;
        let hairlines = if slot * px_per_ms >= MIN_SLOT_PX {
            &slots[..]
        } else {
            &[]
        };
        chart
            .draw_series(hairlines.iter().map(|&(start, _)| {
                PathElement::new(
                    vec![(start, 0.0), (start, lanes.lanes_top())],
                    WHITE.stroke_width(1),
                )
            }))
            .map_err(&err)?;

        // The frames where they actually went on the wire; lost ones crossed out when
        // wide enough for a cross to read (narrower ones are plain red).
        chart
            .draw_series(
                boxes
                    .iter()
                    .map(|b| Rectangle::new([(b.x.0, b.y.0), (b.x.1, b.y.1)], b.fill.filled())),
            )
            .map_err(&err)?;
        chart
            .draw_series(
                boxes
                    .iter()
                    .filter(|b| b.lost && (b.x.1 - b.x.0) * px_per_ms >= MIN_CROSS_PX)
                    .flat_map(|b| {
                        let style = LOST_CROSS.stroke_width(2);
                        [
                            PathElement::new(vec![(b.x.0, b.y.0), (b.x.1, b.y.1)], style),
                            PathElement::new(vec![(b.x.0, b.y.1), (b.x.1, b.y.0)], style),
                        ]
                    }),
            )
            .map_err(&err)?;

        // Cycle boundaries, labelled in the strip above the lanes.
        let mut bounds: Vec<f64> = t.cycles.iter().map(|r| to_ms(r.start)).collect();
        if let Some(last) = t.cycles.last() {
            bounds.push(to_ms(last.start) + cycle);
        }
        chart
            .draw_series(bounds.iter().map(|&x| {
                DashedPathElement::new(
                    vec![(x, 0.0), (x, lanes.top())],
                    6,
                    4,
                    BOUNDARY.stroke_width(1),
                )
            }))
            .map_err(&err)?;
        let label_style = TextStyle::from((FONT, TICK_PX).into_font())
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center));
        let label_y = lanes.lanes_top() + HEADER * 0.5;
        chart
            .draw_series(t.cycles.iter().map(|r| {
                let mut text = format!("cycle {}", r.cycle);
                if !r.synced {
                    text.push_str(" (no sync)");
                }
                if let Some(s) = &r.switch {
                    text.push_str(&format!(" · list v{} in force", s.version));
                }
                EmptyElement::at((to_ms(r.start), label_y))
                    + Text::new(text, (5, 0), label_style.clone())
            }))
            .map_err(&err)?;

        // The legend below the chart, wrapped into rows.
        let text_style = TextStyle::from((FONT, LEGEND_PX).into_font())
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center));
        let (x0, y0) = (MARGIN as i32, 4 + LEGEND_ROW_PX as i32 / 2);
        for ((text, swatch), &(x, row)) in legend.iter().zip(&places) {
            let (x, y) = (x0 + x, y0 + (row * LEGEND_ROW_PX) as i32);
            let corners = [(x, y - SWATCH_H / 2), (x + SWATCH_W, y + SWATCH_H / 2)];
            match *swatch {
                Swatch::Fill(c) => {
                    legend_area
                        .draw(&Rectangle::new(corners, c.filled()))
                        .map_err(&err)?;
                }
                Swatch::Outlined(fill, edge) => {
                    legend_area
                        .draw(&Rectangle::new(corners, fill.filled()))
                        .map_err(&err)?;
                    legend_area
                        .draw(&Rectangle::new(corners, edge.stroke_width(1)))
                        .map_err(&err)?;
                }
                Swatch::Lost => {
                    legend_area
                        .draw(&Rectangle::new(corners, LOST.filled()))
                        .map_err(&err)?;
                    let style = LOST_CROSS.stroke_width(2);
                    let [(a, b), (c, d)] = corners;
                    legend_area
                        .draw(&PathElement::new(vec![(a, b), (c, d)], style))
                        .map_err(&err)?;
                    legend_area
                        .draw(&PathElement::new(vec![(a, d), (c, b)], style))
                        .map_err(&err)?;
                }
            }
            legend_area
                .draw(&Text::new(
                    text.as_str(),
                    (x + SWATCH_W + LEGEND_GAP, y),
                    text_style.clone(),
                ))
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
    use crate::network::tdma::frame::FrameSizes;
    use crate::network::tdma::{schedule, ChannelRequest, TdmaConfig, TdmaNetwork};

    const US: u64 = 1_000;
    const MS: u64 = 1_000_000;

    /// 4 clients, 100 µs slots with a 10 µs guard, 2 ms cycles; channel 0 from clients 1
    /// and 2, channel 1 from 3 and 4, each every 1 ms; 90 µs data frames, 10 µs headers.
    /// `rate = ∞` makes every frame instantaneous.
    fn network(rate: f64) -> TdmaNetwork {
        let mut cfg = TdmaConfig::new(4, SimTime(100 * US), SimTime(2 * MS));
        cfg.guard = SimTime(10 * US);
        cfg.link_rate = rate;
        cfg.header_bytes = 10;
        let requests = [
            ChannelRequest {
                tau: SimTime(MS),
                senders: vec![1, 2],
            },
            ChannelRequest {
                tau: SimTime(MS),
                senders: vec![3, 4],
            },
        ];
        let list = schedule(&CycleLayout::new(&cfg).unwrap(), &requests)
            .unwrap()
            .list;
        let mut frames = FrameSizes::new(10);
        for (sender, channel) in [(1, 0), (2, 0), (3, 1), (4, 1)] {
            frames.set(sender, channel, 10);
        }
        TdmaNetwork::new(cfg, 7, frames, 2, list).unwrap()
    }

    fn names() -> Vec<String> {
        vec!["forces L1".to_string(), "states B2".to_string()]
    }

    fn cycles(net: &mut TdmaNetwork, n: usize) -> Vec<CycleReport> {
        (0..n).map(|_| net.run_cycle()).collect()
    }

    fn timeline<'a>(
        net: &'a TdmaNetwork,
        reports: &'a [CycleReport],
        names: &'a [String],
    ) -> SlotTimeline<'a> {
        SlotTimeline {
            title: "TDMA slots, cycles 0–2",
            layout: net.layout(),
            guard: net.config().guard,
            cycles: reports,
            channel_names: names,
        }
    }

    /// `(width, fill)` of every `<rect>`.
    fn rects(svg: &str) -> Vec<(i32, String)> {
        crate::report::tests_support::rects(svg)
            .into_iter()
            .map(|(_, width, fill)| (width, fill))
            .collect()
    }

    /// Number of `<rect>`s filled with `colour`.
    fn filled(svg: &str, colour: RGBColor) -> usize {
        let hex = format!("#{:02X}{:02X}{:02X}", colour.0, colour.1, colour.2);
        rects(svg).iter().filter(|r| r.1 == hex).count()
    }

    /// Frames of `reports` that match `pick`.
    fn count(reports: &[CycleReport], pick: impl Fn(&Transmission) -> bool) -> usize {
        reports
            .iter()
            .flat_map(|r| &r.frames)
            .filter(|f| pick(f))
            .count()
    }

    #[test]
    fn svg_has_title_axes_lanes_legend_and_a_box_per_frame() {
        let mut net = network(8e6);
        let reports = cycles(&mut net, 3);
        let names = names();
        let t = timeline(&net, &reports, &names);
        let svg = slot_timeline_svg(&t).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("width=\"1200\"") && svg.contains("height=\"450\""));
        for text in [
            "TDMA slots, cycles 0–2",
            "time t [ms]",
            "TDMA node",
            "server (node 0)",
            "client 1 (node 1)",
            "client 4 (node 4)",
            "forces L1",
            "states B2",
            "sync",
            "list broadcast / confirmation",
            "lost (collision)",
            "guard",
            "cycle 0",
            "cycle 1",
            "cycle 2",
        ] {
            assert!(svg.contains(text), "missing {text:?}");
        }
        // The legend sits below the chart, under the x axis label, not over the lanes.
        let texts = crate::report::tests_support::texts(&svg);
        let y_of = |s: &str| texts.iter().find(|t| t.2 == s).map(|t| t.1);
        let axis = y_of("time t [ms]").unwrap();
        for entry in ["sync", "forces L1", "lost (collision)", "guard"] {
            let y = y_of(entry).unwrap();
            assert!(
                y > axis,
                "{entry} at y = {y}, above the axis label at {axis}"
            );
        }
        assert_eq!(net.lost(), 0, "no drift: nothing lost");
        // One box per frame in its kind's colour, plus the legend swatch.
        let sync = count(&reports, |f| f.kind == FrameKind::Sync);
        let stat = count(&reports, |f| matches!(f.kind, FrameKind::Static { .. }));
        let ch0 = count(&reports, |f| f.kind == FrameKind::Dynamic { channel: 0 });
        let ch1 = count(&reports, |f| f.kind == FrameKind::Dynamic { channel: 1 });
        assert_eq!((sync, stat, ch0, ch1), (3, 15, 12, 12));
        assert_eq!(filled(&svg, SYNC), sync + 1, "sync boxes");
        assert_eq!(filled(&svg, STATIC), stat + 1, "static boxes");
        assert_eq!(
            filled(&svg, RGBColor(0x1f, 0x77, 0xb4)),
            ch0 + 1,
            "channel 0"
        );
        assert_eq!(
            filled(&svg, RGBColor(0x2c, 0xa0, 0x2c)),
            ch1 + 1,
            "channel 1"
        );
        assert_eq!(filled(&svg, LOST), 1, "only the legend is red");
        // Idle dynamic slots are not shaded: one background per sending slot.
        let owned = 3 * (1 + 5 + 8);
        assert_eq!(filled(&svg, SLOT_BG), owned + 1, "slot backgrounds");
        assert_eq!(filled(&svg, GUARD), 3 * 20 + 1, "a guard band per slot");
        crate::report::tests_support::assert_no_text_overlaps(&svg);
        // Same input, same bytes.
        assert_eq!(svg, slot_timeline_svg(&t).unwrap());
    }

    #[test]
    fn a_decided_list_shows_its_broadcast_confirmations_and_switch() {
        let mut net = network(8e6);
        let list = net.lists().active().clone();
        net.decide(SimTime::ZERO, list).unwrap();
        let reports = cycles(&mut net, 3);
        let protocol = count(&reports, |f| {
            matches!(
                f.kind,
                FrameKind::Static {
                    broadcast: Some(_),
                    ..
                } | FrameKind::Static {
                    confirms: Some(_),
                    ..
                }
            )
        });
        assert!(protocol >= 5, "a broadcast and four confirmations");
        let names = names();
        let svg = slot_timeline_svg(&timeline(&net, &reports, &names)).unwrap();
        assert_eq!(filled(&svg, PROTOCOL), protocol + 1, "protocol boxes");
        assert!(svg.contains("list v1 in force"), "the switch is labelled");
    }

    #[test]
    fn frames_lost_to_drift_beyond_the_guard_are_red() {
        let mut net = network(8e6);
        // ±20 000 ppm: 20 µs of offset per ms, against a 10 µs guard.
        for node in 1..=4 {
            let ppm = if node % 2 == 0 { 20_000.0 } else { -20_000.0 };
            net.clocks_mut().set_rate_ppm(node, ppm);
        }
        let reports = cycles(&mut net, 3);
        let lost = count(&reports, Transmission::lost);
        assert!(lost > 0, "drift beyond the guard loses frames");
        let names = names();
        let svg = slot_timeline_svg(&timeline(&net, &reports, &names)).unwrap();
        assert_eq!(filled(&svg, LOST), lost + 1, "every lost frame is red");
        let ch0 = count(&reports, |f| {
            !f.lost() && f.kind == FrameKind::Dynamic { channel: 0 }
        });
        assert_eq!(
            filled(&svg, RGBColor(0x1f, 0x77, 0xb4)),
            ch0 + 1,
            "lost frames are not drawn in their channel's colour"
        );
        // Each lost frame is crossed out: two strokes in the cross colour per frame
        // plus the legend's two.
        let cross = svg.matches("stroke=\"#5A0000\"").count();
        assert_eq!(cross, 2 * lost + 2, "crosses");
    }

    #[test]
    fn instantaneous_frames_get_a_visible_width() {
        let mut net = network(f64::INFINITY);
        let reports = cycles(&mut net, 2);
        assert!(reports
            .iter()
            .flat_map(|r| &r.frames)
            .all(|f| f.duration == SimTime::ZERO));
        let names = names();
        let svg = slot_timeline_svg(&timeline(&net, &reports, &names)).unwrap();
        let boxes: Vec<i32> = rects(&svg)
            .into_iter()
            .filter(|r| r.1 == "#1F77B4")
            .map(|r| r.0)
            .collect();
        assert_eq!(boxes.len(), 8 + 1);
        // 0.4 % of a plot area of about 1000 px.
        assert!(boxes.iter().all(|&w| w >= 3), "{boxes:?}");
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        let mut net = network(8e6);
        let reports = cycles(&mut net, 1);
        let none: [String; 0] = [];
        let many: Vec<String> = (0..15)
            .map(|c| format!("a long channel name {c}"))
            .collect();
        for (cycles, names) in [
            (&reports[..0], &none[..]),
            (&reports[..], &none[..]),
            (&reports[..], &many[..]),
        ] {
            let t = SlotTimeline {
                title: "",
                layout: net.layout(),
                guard: SimTime(u64::MAX),
                cycles,
                channel_names: names,
            };
            let svg = slot_timeline_svg(&t).unwrap();
            assert!(svg.trim_end().ends_with("</svg>"));
        }
        // Unnamed channels are named by index; a long legend wraps and adds a row.
        let t = SlotTimeline {
            cycles: &reports,
            channel_names: &none,
            ..timeline(&net, &reports, &none)
        };
        let svg = slot_timeline_svg(&t).unwrap();
        assert!(svg.contains("channel 0") && svg.contains("channel 1"));
        let t = SlotTimeline {
            channel_names: &many,
            ..t
        };
        let svg = slot_timeline_svg(&t).unwrap();
        assert!(svg.contains("a long channel name 14"));
        assert!(!svg.contains("height=\"450\""), "the legend wrapped");
    }

    #[test]
    fn write_goes_to_the_file_and_names_a_missing_directory() {
        let mut net = network(8e6);
        let reports = cycles(&mut net, 2);
        let names = names();
        let t = timeline(&net, &reports, &names);
        let dir = std::env::temp_dir().join(format!("dsmcosim-timeline-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("timeline.svg");
        write_slot_timeline(&path, &t).unwrap();
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            slot_timeline_svg(&t).unwrap()
        );
        std::fs::remove_dir_all(&dir).unwrap();
        match write_slot_timeline(&path, &t) {
            Err(Error::Io { path: p, .. }) => assert_eq!(p, path),
            other => panic!("expected an Io error, got {other:?}"),
        }
    }

    /// Writes an example with drift into the temporary directory
    /// (`/tmp/timeline_example.svg` on Linux) to look at.
    #[test]
    #[ignore = "writes an example file for a human to look at"]
    fn example() {
        let mut net = network(8e6);
        net.clocks_mut().set_rate_ppm(2, 12_000.0);
        net.clocks_mut().set_rate_ppm(3, -12_000.0);
        let list = net.lists().active().clone();
        net.decide(SimTime::ZERO, list).unwrap();
        let reports = cycles(&mut net, 3);
        let names = names();
        let path = std::env::temp_dir().join("timeline_example.svg");
        write_slot_timeline(&path, &timeline(&net, &reports, &names)).unwrap();
    }
}
