//! Text labels next to plotted points, placed so that they never overlap each other
//! and overlap the markers and the plot's edges as little as a greedy search can
//! manage.
//!
//! Each label tries, in order, right of its point, left, above, below and the four
//! diagonals, first close and then farther out, and then rows stacked above and below
//! its point, and takes the first place that touches nothing already placed; failing
//! that the place with the fewest collisions, another label counting more than
//! anything else. A label set farther than [`LEADER_FROM`] from its point gets a thin
//! leader line back to it. Labels are placed in input order, so the same input gives the
//! same picture. The boxes the search keeps apart are the estimated text extents plus
//! [`PAD`] on every side, wider than the text a viewer draws in a common sans-serif.

use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::text_width;

/// Distance [px] between a point and the near edge of its label (first round; the
/// second round doubles it).
const OFFSET: i32 = 7;
/// Radius [px] around a marker that a label should keep free.
const MARKER_R: i32 = 4;
/// Free space [px] kept around each label's estimated text box.
const PAD: i32 = 2;
/// A label whose near edge is farther than this from its point [px] gets a leader line.
const LEADER_FROM: i32 = 3 * OFFSET;
/// Rows tried above and below a point once the ring of places around it is full.
const STACK_ROWS: i32 = 24;

/// A pixel rectangle `(x0, y0, x1, y1)`, `x0 <= x1`, `y0 <= y1`.
type Rect = (i32, i32, i32, i32);

/// Where one label is drawn: its anchor point and how the text hangs from it.
#[derive(Clone)]
pub(crate) struct Placed {
    /// The text.
    pub text: String,
    /// Anchor [px].
    pub at: (i32, i32),
    /// How the text sits relative to `at`.
    pub pos: Pos,
    /// The labelled point [px], when the label sits far from it and a leader line
    /// should join them.
    pub leader: Option<(i32, i32)>,
}

impl Placed {
    /// The point on the label's box nearest to `p` (where a leader line ends).
    pub fn nearest_edge(&self, p: (i32, i32), size: f64) -> (i32, i32) {
        let r = bounds(&self.text, size, self.at, self.pos);
        (p.0.clamp(r.0, r.2), p.1.clamp(r.1, r.3))
    }
}

fn overlaps(a: Rect, b: Rect) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

/// The box of `text` at `size` anchored at `at` with `pos`, with [`PAD`] around the
/// estimated text (a tenth wider than [`text_width`], which is tuned for layout, so
/// that digit-heavy labels drawn a little wide still fit).
fn bounds(text: &str, size: f64, at: (i32, i32), pos: Pos) -> Rect {
    let w = (text_width(text, size) * 11 / 10) as i32;
    let h = (size / 1.24).round() as i32;
    let x0 = match pos.h_pos {
        HPos::Left => at.0,
        HPos::Right => at.0 - w,
        HPos::Center => at.0 - w / 2,
    };
    let y0 = match pos.v_pos {
        VPos::Top => at.1,
        VPos::Bottom => at.1 - h,
        VPos::Center => at.1 - h / 2,
    };
    (x0 - PAD, y0 - PAD, x0 + w + PAD, y0 + h + PAD)
}

/// Places `labels` (text, point [px]) inside `area`, avoiding (in this order of
/// weight) each other, the area's edges, the `markers` and the points along drawn
/// lines `line_points` [px]. Empty texts are skipped.
pub(crate) fn place(
    labels: &[(String, (i32, i32))],
    markers: &[(i32, i32)],
    line_points: &[(i32, i32)],
    area: Rect,
    size: f64,
) -> Vec<Placed> {
    let around = |&(x, y): &(i32, i32)| (x - MARKER_R, y - MARKER_R, x + MARKER_R, y + MARKER_R);
    let marker_boxes: Vec<Rect> = markers.iter().map(around).collect();
    let line_boxes: Vec<Rect> = line_points.iter().map(around).collect();
    let mut taken: Vec<Rect> = Vec::new();
    let mut out = Vec::new();
    for (text, (x, y)) in labels {
        if text.is_empty() {
            continue;
        }
        let mut best: Option<(usize, Placed, Rect)> = None;
        let h = (size / 1.24).round() as i32 + 2 * PAD;
        let mut candidates = Vec::new();
        for d in [OFFSET, 2 * OFFSET, 3 * OFFSET, 5 * OFFSET, 8 * OFFSET] {
            let e = d * 7 / 10;
            candidates.extend([
                ((x + d, *y), HPos::Left, VPos::Center, d),
                ((x - d, *y), HPos::Right, VPos::Center, d),
                ((*x, y - d), HPos::Center, VPos::Bottom, d),
                ((*x, y + d), HPos::Center, VPos::Top, d),
                ((x + e, y - e), HPos::Left, VPos::Bottom, d),
                ((x + e, y + e), HPos::Left, VPos::Top, d),
                ((x - e, y - e), HPos::Right, VPos::Bottom, d),
                ((x - e, y + e), HPos::Right, VPos::Top, d),
            ]);
        }
        // Then rows stacked above and below the point, right and left of it.
        for k in 1..=STACK_ROWS {
            for dy in [-k * h, k * h] {
                candidates.push(((x + OFFSET, y + dy), HPos::Left, VPos::Center, dy.abs()));
                candidates.push(((x - OFFSET, y + dy), HPos::Right, VPos::Center, dy.abs()));
            }
        }
        for (at, hpos, vpos, d) in candidates {
            let pos = Pos::new(hpos, vpos);
            let r = bounds(text, size, at, pos);
            let outside = r.0 < area.0 || r.1 < area.1 || r.2 > area.2 || r.3 > area.3;
            // Another label costs most, then leaving the area; crossing a line costs
            // the same however long the crossing; each further OFFSET from the point
            // costs 1, so a label goes far (with a leader) only to avoid a collision.
            let cost = 100_000 * taken.iter().filter(|t| overlaps(**t, r)).count()
                + 10_000 * usize::from(outside)
                + 20 * marker_boxes.iter().filter(|m| overlaps(**m, r)).count()
                + 15 * usize::from(line_boxes.iter().any(|m| overlaps(*m, r)))
                + (d / OFFSET - 1).max(0) as usize;
            if best.as_ref().is_none_or(|b| cost < b.0) {
                let placed = Placed {
                    text: text.clone(),
                    at,
                    pos,
                    leader: (d > LEADER_FROM).then_some((*x, *y)),
                };
                best = Some((cost, placed, r));
            }
            if cost == 0 {
                break;
            }
        }
        if let Some((_, placed, r)) = best {
            taken.push(r);
            out.push(placed);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_of_close_points_do_not_overlap() {
        let labels: Vec<(String, (i32, i32))> = (0..6)
            .map(|i| (format!("config {i}"), (300 + 4 * i, 200 + 3 * i)))
            .collect();
        let markers: Vec<(i32, i32)> = labels.iter().map(|l| l.1).collect();
        let placed = place(&labels, &markers, &[], (0, 0, 800, 500), 13.0);
        assert_eq!(placed.len(), 6);
        let boxes: Vec<Rect> = placed
            .iter()
            .map(|p| bounds(&p.text, 13.0, p.at, p.pos))
            .collect();
        for (i, a) in boxes.iter().enumerate() {
            assert!(a.0 >= 0 && a.2 <= 800 && a.1 >= 0 && a.3 <= 500, "{a:?}");
            for b in &boxes[i + 1..] {
                assert!(!overlaps(*a, *b), "{a:?} overlaps {b:?}");
            }
        }
    }

    #[test]
    fn labels_stay_inside_the_area() {
        let labels = vec![("right edge".to_string(), (795, 250))];
        let placed = place(&labels, &[], &[], (0, 0, 800, 500), 13.0);
        let r = bounds(&placed[0].text, 13.0, placed[0].at, placed[0].pos);
        assert!(r.2 <= 800, "{r:?}");
        assert!(place(&[(String::new(), (1, 1))], &[], &[], (0, 0, 10, 10), 13.0).is_empty());
    }
}
