//! The legend of a line plot: placed where it covers no data. Candidate boxes inside the
//! plot area are tried in a fixed order (corners, edge middles, centre); the first that no
//! drawn segment or point comes near is taken. When every candidate covers data, the legend
//! goes outside, right of the plot area, and the document grows by its width: it never
//! covers a curve.

use super::rich;
use std::fmt::Write as _;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mark {
    /// A solid polyline.
    Line,
    /// A dashed polyline.
    Dashed,
    /// Circles at the points.
    Points,
    /// A polyline with circles.
    LinePoints,
}

/// Clearance between the legend box and any drawn line or point, px (half a stroke plus a
/// point's radius, rounded up).
const CLEARANCE_PX: f64 = 5.0;
/// Gap between the legend and the plot frame, px.
const INSET_PX: f64 = 8.0;
/// Height of one legend row, px.
const ROW_PX: f64 = 17.0;
/// Width of one character of 12 px text (Helvetica / Liberation Sans average), px.
const CHAR_PX: f64 = 6.6;
/// Width of the sample mark and the gaps around the text, px.
const MARK_PX: f64 = 42.0;

/// One legend row.
#[derive(Debug, Clone)]
pub(super) struct LegendEntry {
    /// Text.
    pub name: String,
    /// Colour (CSS).
    pub color: String,
    /// How the sample is drawn.
    pub mark: Mark,
    /// `stroke-dasharray` of the sample (empty: the mark's default).
    pub dash: String,
}

/// A segment in px; a point is a segment of length 0.
pub(super) type Segment = ((f64, f64), (f64, f64));

/// Where the legend goes (px); `outside` when right of the plot area.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct LegendBox {
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
    pub outside: bool,
}

/// The plot area (left, top, width, height), px.
pub(super) type Area = (f64, f64, f64, f64);

/// The legend's place for `entries` in the plot area, avoiding `drawn` (module docs).
pub(super) fn place(
    entries: &[LegendEntry],
    (ml, mt, pw, ph): Area,
    drawn: &[Segment],
) -> LegendBox {
    let chars = entries
        .iter()
        .map(|e| e.name.chars().count())
        .max()
        .unwrap_or(0);
    let (w, h) = (
        chars as f64 * CHAR_PX + MARK_PX,
        entries.len() as f64 * ROW_PX + 8.0,
    );
    let (right, left, midx) = (ml + pw - w - INSET_PX, ml + INSET_PX, ml + (pw - w) / 2.0);
    let (top, bottom, midy) = (mt + INSET_PX, mt + ph - h - INSET_PX, mt + (ph - h) / 2.0);
    let candidates = [
        (right, top),
        (left, top),
        (right, bottom),
        (left, bottom),
        (right, midy),
        (left, midy),
        (midx, top),
        (midx, bottom),
        (midx, midy),
    ];
    let fits = w + 2.0 * INSET_PX <= pw && h + 2.0 * INSET_PX <= ph;
    let free = |&(x, y): &(f64, f64)| {
        let r = (
            x - CLEARANCE_PX,
            y - CLEARANCE_PX,
            x + w + CLEARANCE_PX,
            y + h + CLEARANCE_PX,
        );
        !drawn.iter().any(|s| segment_hits(*s, r))
    };
    match candidates.iter().find(|c| fits && free(c)) {
        Some(&(x, y)) => LegendBox {
            x,
            y,
            w,
            h,
            outside: false,
        },
        None => LegendBox {
            x: ml + pw + 2.0 * INSET_PX,
            y: mt,
            w,
            h,
            outside: true,
        },
    }
}

/// Whether segment `s` meets the rectangle (x0, y0, x1, y1) (Liang–Barsky clipping).
pub(super) fn segment_hits(
    ((ax, ay), (bx, by)): Segment,
    (x0, y0, x1, y1): (f64, f64, f64, f64),
) -> bool {
    let (dx, dy) = (bx - ax, by - ay);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [(-dx, ax - x0), (dx, x1 - ax), (-dy, ay - y0), (dy, y1 - ay)] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t0 <= t1
}

/// Draw the legend box `b` with its rows.
pub(super) fn draw(o: &mut String, entries: &[LegendEntry], b: &LegendBox) {
    if entries.is_empty() {
        return;
    }
    let _ = writeln!(
        o,
        r##"<rect class="legend" x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="#ffffff" fill-opacity="0.9" stroke="#999" stroke-width="0.8"/>"##,
        b.x, b.y, b.w, b.h
    );
    for (i, e) in entries.iter().enumerate() {
        let yy = b.y + 14.0 + i as f64 * ROW_PX;
        mark(o, b.x, yy, e);
        let _ = writeln!(
            o,
            r#"<text x="{:.1}" y="{yy:.1}" font-size="12">{}</text>"#,
            b.x + 34.0,
            rich(&e.name, 12.0)
        );
    }
}

/// The sample mark of one legend row at (`lx`, `yy`).
fn mark(o: &mut String, lx: f64, yy: f64, e: &LegendEntry) {
    let col = super::escape(&e.color);
    if e.mark != Mark::Points {
        let dash = match (e.mark, e.dash.is_empty()) {
            (_, false) => format!(r#" stroke-dasharray="{}""#, e.dash),
            (Mark::Dashed, true) => r#" stroke-dasharray="6 4""#.to_string(),
            _ => String::new(),
        };
        let _ = writeln!(
            o,
            r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{col}" stroke-width="2"{dash}/>"#,
            lx + 6.0,
            yy - 4.0,
            lx + 28.0,
            yy - 4.0
        );
    }
    if matches!(e.mark, Mark::Points | Mark::LinePoints) {
        let r = if e.mark == Mark::Points { 3.5 } else { 3.0 };
        let _ = writeln!(
            o,
            r#"<circle cx="{:.1}" cy="{:.1}" r="{r}" fill="{col}"/>"#,
            lx + 17.0,
            yy - 4.0
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_meet_rectangles() {
        let r = (0.0, 0.0, 10.0, 10.0);
        assert!(segment_hits(((-5.0, 5.0), (15.0, 5.0)), r), "crossing");
        assert!(segment_hits(((2.0, 2.0), (2.0, 2.0)), r), "a point inside");
        assert!(!segment_hits(((-5.0, -1.0), (15.0, -1.0)), r), "above");
        assert!(
            !segment_hits(((-5.0, 0.0), (0.0, -5.0)), (0.1, 0.1, 10.0, 10.0)),
            "past the corner"
        );
        assert!(
            segment_hits(((-5.0, 6.0), (6.0, -5.0)), r),
            "through the corner"
        );
    }
}
