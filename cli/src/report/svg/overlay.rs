//! What a heat map draws over its cells: contour lines of the values (marching squares on
//! the grid of cell centres), the robot's frame (the anchors' bounding box projected on the
//! map's plane) and the anchors' projections.
//!
//! Marching squares: each square of four neighbouring cell centres whose values all exist
//! is classified by which corners lie at or above the level; the contour crosses the edges
//! whose ends differ, at the point where the linear interpolation of the values equals the
//! level. A saddle (opposite corners on the same side) is resolved by the mean of the four
//! values. Squares with a missing value draw no contour: the hatching shows why.

use std::fmt::Write as _;

/// Stroke of the contour lines: white, thin, half transparent, readable on every viridis
/// colour without hiding the cells.
const CONTOUR_STYLE: &str =
    r##"fill="none" stroke="#ffffff" stroke-width="0.9" stroke-opacity="0.75""##;
/// Stroke of the frame: dark grey, dashed.
const FRAME_STYLE: &str =
    r##"fill="none" stroke="#333333" stroke-width="1.2" stroke-dasharray="5 3""##;
/// Half the side of an anchor's square, px.
const ANCHOR_HALF_PX: f64 = 3.5;

/// A segment in data coordinates.
pub type DataSegment = ((f64, f64), (f64, f64));

/// The contour segments at `level` of `values` (row-major, `values[iy * x.len() + ix]`) on
/// the grid of cell centres `x` × `y`.
pub fn contour(x: &[f64], y: &[f64], values: &[Option<f64>], level: f64) -> Vec<DataSegment> {
    let (nx, ny) = (x.len(), y.len());
    let mut out = Vec::new();
    if nx < 2 || ny < 2 || values.len() != nx * ny {
        return out;
    }
    let at = |ix: usize, iy: usize| values[iy * nx + ix].filter(|v| v.is_finite());
    for iy in 0..ny - 1 {
        for ix in 0..nx - 1 {
            // Corners counter-clockwise from the bottom left.
            let c = [(ix, iy), (ix + 1, iy), (ix + 1, iy + 1), (ix, iy + 1)];
            let (Some(v0), Some(v1), Some(v2), Some(v3)) = (
                at(ix, iy),
                at(ix + 1, iy),
                at(ix + 1, iy + 1),
                at(ix, iy + 1),
            ) else {
                continue;
            };
            let v = [v0, v1, v2, v3];
            let p = c.map(|(i, j)| (x[i], y[j]));
            square(&p, &v, level, &mut out);
        }
    }
    out
}

/// The contour segments of one square with corners `p` (counter-clockwise) and values `v`.
fn square(p: &[(f64, f64); 4], v: &[f64; 4], level: f64, out: &mut Vec<DataSegment>) {
    let above = v.map(|x| x >= level);
    // Crossing points on the edges (k, k+1) whose ends differ, in edge order.
    let cross: Vec<(usize, (f64, f64))> = (0..4)
        .filter(|&k| above[k] != above[(k + 1) % 4])
        .map(|k| {
            let (a, b) = (p[k], p[(k + 1) % 4]);
            let t = (level - v[k]) / (v[(k + 1) % 4] - v[k]);
            (k, (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)))
        })
        .collect();
    match cross.len() {
        2 => out.push((cross[0].1, cross[1].1)),
        4 => {
            // Saddle: the centre's side decides which corners the contours cut off.
            let centre_above = v.iter().sum::<f64>() / 4.0 >= level;
            let (e0, e1, e2, e3) = (cross[0].1, cross[1].1, cross[2].1, cross[3].1);
            if centre_above == above[0] {
                // Corners 1 and 3 are cut off: edges (0,1)-(1,2) and (2,3)-(3,0).
                out.push((e0, e1));
                out.push((e2, e3));
            } else {
                // Corners 0 and 2 are cut off: edges (3,0)-(0,1) and (1,2)-(2,3).
                out.push((e3, e0));
                out.push((e1, e2));
            }
        }
        _ => {}
    }
}

/// Draw `segments` (data coordinates, mapped by `px`, `py`) as one path.
pub fn draw_contours(
    o: &mut String,
    segments: &[DataSegment],
    px: &dyn Fn(f64) -> f64,
    py: &dyn Fn(f64) -> f64,
) {
    if segments.is_empty() {
        return;
    }
    let mut d = String::new();
    for ((x0, y0), (x1, y1)) in segments {
        let _ = write!(
            d,
            "M{:.1},{:.1}L{:.1},{:.1}",
            px(*x0),
            py(*y0),
            px(*x1),
            py(*y1)
        );
    }
    let _ = writeln!(o, r#"<path class="contour" d="{d}" {CONTOUR_STYLE}/>"#);
}

/// Draw the frame rectangle (x0, y0, x1, y1) and the anchors (data coordinates).
pub fn draw_frame(
    o: &mut String,
    frame: Option<[f64; 4]>,
    anchors: &[(f64, f64)],
    px: &dyn Fn(f64) -> f64,
    py: &dyn Fn(f64) -> f64,
) {
    if let Some([x0, y0, x1, y1]) = frame {
        let (a, b) = ((px(x0), py(y1)), (px(x1), py(y0)));
        let _ = writeln!(
            o,
            r#"<rect class="frame" x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" {FRAME_STYLE}/>"#,
            a.0,
            a.1,
            (b.0 - a.0).max(0.0),
            (b.1 - a.1).max(0.0)
        );
    }
    let h = ANCHOR_HALF_PX;
    for &(x, y) in anchors {
        let _ = writeln!(
            o,
            r##"<rect class="anchor" x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="#ffffff" stroke="#000000" stroke-width="1.2"/>"##,
            px(x) - h,
            py(y) - h,
            2.0 * h,
            2.0 * h
        );
    }
}

/// The legend rows under the colour bar: contour, frame, anchor, from (`x`, `y`) down;
/// returns the height used, px.
pub fn draw_key(o: &mut String, (x, y): (f64, f64), contours: bool, frame: bool) -> f64 {
    let mut rows: Vec<(&str, String)> = Vec::new();
    let mid = |k: usize| y + KEY_ROW_PX * k as f64 + 6.0;
    if contours {
        let m = mid(rows.len());
        rows.push((
            "contour",
            format!(
                r##"<rect x="{x:.1}" y="{:.1}" width="16" height="12" fill="#3b528b"/><line x1="{x:.1}" y1="{m:.1}" x2="{:.1}" y2="{m:.1}" {CONTOUR_STYLE}/>"##,
                m - 6.0,
                x + 16.0
            ),
        ));
    }
    if frame {
        let m = mid(rows.len());
        rows.push((
            "frame",
            format!(
                r#"<line x1="{x:.1}" y1="{m:.1}" x2="{:.1}" y2="{m:.1}" {FRAME_STYLE}/>"#,
                x + 16.0
            ),
        ));
        let (m, h) = (mid(rows.len()), ANCHOR_HALF_PX);
        rows.push((
            "anchor",
            format!(
                r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="#ffffff" stroke="#000000" stroke-width="1.2"/>"##,
                x + 8.0 - h,
                m - h,
                2.0 * h,
                2.0 * h
            ),
        ));
    }
    for (k, (text, sample)) in rows.iter().enumerate() {
        let _ = writeln!(
            o,
            r#"{sample}<text x="{:.1}" y="{:.1}" font-size="11">{text}</text>"#,
            x + 22.0,
            mid(k) + 4.0
        );
    }
    KEY_ROW_PX * rows.len() as f64
}

/// Height of one row of the key, px.
const KEY_ROW_PX: f64 = 16.0;

#[cfg(test)]
mod tests {
    use super::*;

    /// A plane v = x + 2y: every contour is the straight line x + 2y = level, so every
    /// segment end must lie on it (linear interpolation is exact for a linear field;
    /// tolerance: rounding of a few operations on O(1) numbers).
    #[test]
    fn contours_of_a_plane_lie_on_its_level_line() {
        let x: Vec<f64> = (0..5).map(|i| i as f64 * 0.5).collect();
        let y: Vec<f64> = (0..4).map(|i| i as f64 * 0.5).collect();
        let v: Vec<Option<f64>> = y
            .iter()
            .flat_map(|yy| x.iter().map(move |xx| Some(xx + 2.0 * yy)))
            .collect();
        let segs = contour(&x, &y, &v, 1.75);
        assert!(!segs.is_empty());
        for (a, b) in &segs {
            for p in [a, b] {
                assert!((p.0 + 2.0 * p.1 - 1.75).abs() < 1e-12, "{p:?}");
            }
        }
        // A missing value removes the four squares around it, no more.
        let mut holes = v.clone();
        holes[2 * x.len() + 2] = None;
        assert!(contour(&x, &y, &holes, 1.75).len() < segs.len());
    }

    /// A saddle: corners 0 and 2 at +1, 1 and 3 at −1, the centre (mean 0) counts as at
    /// the level 0, i.e. above: the contours cut off the low corners 1 and 3, crossing each
    /// edge at its middle (exact in binary).
    #[test]
    fn saddle_cuts_off_the_corners_on_the_other_side_than_the_centre() {
        let v = [Some(1.0), Some(-1.0), Some(-1.0), Some(1.0)]; // row-major: (0,0) (1,0) (0,1) (1,1)
        let segs = contour(&[0.0, 1.0], &[0.0, 1.0], &v, 0.0);
        let expected = vec![((0.5, 0.0), (1.0, 0.5)), ((0.5, 1.0), (0.0, 0.5))];
        assert_eq!(segs, expected);
    }
}
