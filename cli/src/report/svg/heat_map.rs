//! Heat maps on a grid of cell centres, several panels sharing one colour bar.

use super::axis::{tick_labels, ticks, Axis};
use super::overlay;
use super::{escape, header, rich, subtitle_lines, title};
use std::fmt::Write as _;

/// One heat map: values on a regular grid of cell centres.
#[derive(Debug, Clone)]
pub struct HeatMap {
    /// Panel caption (e.g. "z = 0.55 m").
    pub caption: String,
    /// Cell centres along the horizontal axis, ascending.
    pub x: Vec<f64>,
    /// Cell centres along the vertical axis, ascending.
    pub y: Vec<f64>,
    /// Row-major values, `values[iy * x.len() + ix]`; `None` marks a point without a
    /// valid value (drawn grey and hatched).
    pub values: Vec<Option<f64>>,
    /// Points to mark with a cross and a text (e.g. the maximum).
    pub markers: Vec<(f64, f64, String)>,
}

/// One or several heat maps sharing a colour scale, with a colour bar.
#[derive(Debug, Clone)]
pub struct HeatPanel {
    /// Title on top.
    pub title: String,
    /// Smaller second line (may be empty).
    pub subtitle: String,
    /// Horizontal axis label.
    pub x_label: String,
    /// Vertical axis label.
    pub y_label: String,
    /// Colour bar label.
    pub value_label: String,
    /// Legend text of the hatched cells.
    pub invalid_label: String,
    /// The maps, laid out row by row.
    pub maps: Vec<HeatMap>,
    /// Maps per row.
    pub columns: usize,
    /// Fixed colour range; `None` spans the valid values.
    pub range: Option<(f64, f64)>,
    /// The robot's frame in the maps' coordinates (x0, y0, x1, y1), drawn dashed; the
    /// panels grow to show it.
    pub frame: Option<[f64; 4]>,
    /// The anchors in the maps' coordinates, drawn as squares (inside the panels' view).
    pub anchors: Vec<(f64, f64)>,
    /// Contour lines at the colour bar's labelled values.
    pub contours: bool,
}

/// Where the panels, the colour bar and the document edges are (px).
struct Layout {
    cols: usize,
    rows: usize,
    single: bool,
    /// Panel width and height.
    pw: f64,
    ph: f64,
    /// Left margin, top of the first caption row, caption height.
    ml: f64,
    mt0: f64,
    cap: f64,
    gap_x: f64,
    gap_y: f64,
}

impl Layout {
    /// Top-left corner of panel `k`.
    fn origin(&self, k: usize) -> (f64, f64) {
        let (r, c) = (k / self.cols, k % self.cols);
        let x0 = self.ml + c as f64 * (self.pw + self.gap_x);
        let y0 = self.mt0 + self.cap + r as f64 * (self.ph + self.cap + self.gap_y);
        (x0, y0)
    }
}

impl HeatPanel {
    /// Render to a standalone SVG document.
    pub fn to_svg(&self) -> String {
        let cols = self.columns.clamp(1, self.maps.len().max(1));
        let rows = self.maps.len().div_ceil(cols).max(1);
        let single = self.maps.len() == 1;
        // Panel geometry: keep cells square in data units where possible.
        let (span_x, span_y) = self
            .maps
            .first()
            .map(|m| self.view(m))
            .unwrap_or(((0.0, 1.0), (0.0, 1.0)));
        let aspect = ((span_y.1 - span_y.0) / (span_x.1 - span_x.0)).clamp(0.25, 4.0);
        let pw = if single { 460.0 } else { 230.0 };
        let ph = pw * aspect;
        let (ml, mt0) = (64.0, 0.0);
        let cap = if single { 0.0 } else { 18.0 };
        let gap_x = 26.0;
        let gap_y = 48.0;
        let bar_w = 100.0;
        let w = ml + cols as f64 * pw + (cols - 1) as f64 * gap_x + 30.0 + bar_w;
        let h = mt0 + rows as f64 * (ph + cap) + (rows - 1) as f64 * gap_y + 70.0;
        let (vmin, vmax) = self.value_range();
        let nsub = subtitle_lines(w, &self.subtitle).len() as f64;
        let mt0 = mt0 + 46.0 + 15.0 * nsub;
        let h = h + 46.0 + 15.0 * nsub;
        // Room for the colour bar's key rows under it.
        let key = KEY_PX + KEY_ROW_PX * self.key_rows() as f64;
        let h = h.max(mt0 + cap + colour_bar_height(rows, ph, cap, gap_y) + key);
        let l = Layout {
            cols,
            rows,
            single,
            pw,
            ph,
            ml,
            mt0,
            cap,
            gap_x,
            gap_y,
        };
        let mut o = header(w, h);
        title(&mut o, w, &self.title, &self.subtitle);
        let _ = writeln!(
            o,
            r##"<defs><pattern id="hatch" patternUnits="userSpaceOnUse" width="6" height="6" patternTransform="rotate(45)"><rect width="6" height="6" fill="#c8c8c8"/><line x1="0" y1="0" x2="0" y2="6" stroke="#7a7a7a" stroke-width="2"/></pattern></defs>"##
        );
        for k in 0..self.maps.len() {
            self.panel(&mut o, &l, k, (vmin, vmax));
        }
        self.colour_bar(&mut o, &l, (vmin, vmax));
        o.push_str("</svg>\n");
        o
    }

    /// The data range a panel shows: its grid, grown to the frame and the anchors.
    fn view(&self, m: &HeatMap) -> ((f64, f64), (f64, f64)) {
        let (mut ex, mut ey) = (extent(&m.x), extent(&m.y));
        let frame = self.frame.map(|[a, b, c, d]| [(a, b), (c, d)]);
        for (x, y) in frame.iter().flatten().chain(&self.anchors) {
            if x.is_finite() && y.is_finite() {
                ex = (ex.0.min(*x), ex.1.max(*x));
                ey = (ey.0.min(*y), ey.1.max(*y));
            }
        }
        // A margin so that the frame and the anchors' squares are not cut by the border.
        let grew = ex != extent(&m.x) || ey != extent(&m.y);
        let pad = if grew {
            VIEW_PAD * (ex.1 - ex.0).max(ey.1 - ey.0)
        } else {
            0.0
        };
        ((ex.0 - pad, ex.1 + pad), (ey.0 - pad, ey.1 + pad))
    }

    /// Rows of the colour bar's key besides the hatched cells: contour, frame, anchor.
    fn key_rows(&self) -> usize {
        usize::from(self.contours) + 2 * usize::from(self.frame.is_some())
    }

    /// The contour levels: the colour bar's labelled values strictly inside the range.
    fn levels(&self, (vmin, vmax): (f64, f64)) -> Vec<f64> {
        if !self.contours {
            return Vec::new();
        }
        major_ticks((vmin, vmax))
            .into_iter()
            .map(|(v, _)| v)
            .filter(|&v| v > vmin && v < vmax)
            .collect()
    }

    /// The colour range: fixed, or spanning the valid values.
    fn value_range(&self) -> (f64, f64) {
        let valid: Vec<f64> = self
            .maps
            .iter()
            .flat_map(|m| m.values.iter().flatten().copied())
            .filter(|v| v.is_finite())
            .collect();
        match self.range {
            Some(r) => r,
            None => {
                let lo = valid.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = valid.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                if lo.is_finite() {
                    (lo, if hi > lo { hi } else { lo + 1.0 })
                } else {
                    (0.0, 1.0)
                }
            }
        }
    }

    /// Map `k`: caption, cells, frame, markers, ticks and the axis labels of the outer
    /// panels.
    fn panel(&self, o: &mut String, l: &Layout, k: usize, (vmin, vmax): (f64, f64)) {
        let m = &self.maps[k];
        let (pw, ph) = (l.pw, l.ph);
        let (x0, y0) = l.origin(k);
        let (ex, ey) = self.view(m);
        let nx = m.x.len();
        let ny = m.y.len();
        let sx = pw / (ex.1 - ex.0);
        let sy = ph / (ey.1 - ey.0);
        let px = |x: f64| x0 + (x - ex.0) * sx;
        let py = |y: f64| y0 + ph - (y - ey.0) * sy;
        if !l.single {
            let _ = writeln!(
                o,
                r#"<text x="{:.1}" y="{:.1}" font-size="12" text-anchor="middle">{}</text>"#,
                x0 + pw / 2.0,
                y0 - 5.0,
                rich(&m.caption, 12.0)
            );
        }
        for iy in 0..ny {
            let (ylo, yhi) = cell_edges(&m.y, iy);
            for ix in 0..nx {
                let (xlo, xhi) = cell_edges(&m.x, ix);
                let fill = match m.values.get(iy * nx + ix).copied().flatten() {
                    Some(v) if v.is_finite() => {
                        colormap(((v - vmin) / (vmax - vmin)).clamp(0.0, 1.0))
                    }
                    _ => "url(#hatch)".to_string(),
                };
                // Valid cells overlap their neighbours by 0.4 px: no hairline seams
                // from anti-aliasing. Cells without a value get a thin grey outline.
                let invalid = fill.starts_with('u');
                let pad = if invalid { 0.0 } else { 0.6 };
                let _ = writeln!(
                    o,
                    r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{fill}"{}/>"#,
                    px(xlo),
                    py(yhi),
                    (xhi - xlo) * sx + pad,
                    (yhi - ylo) * sy + pad,
                    if invalid {
                        r##" stroke="#888" stroke-width="0.3""##
                    } else {
                        ""
                    }
                );
            }
        }
        for level in self.levels((vmin, vmax)) {
            let segs = overlay::contour(&m.x, &m.y, &m.values, level);
            overlay::draw_contours(o, &segs, &px, &py);
        }
        overlay::draw_frame(o, self.frame, &self.anchors, &px, &py);
        let _ = writeln!(
            o,
            r##"<rect x="{x0:.1}" y="{y0:.1}" width="{pw:.1}" height="{ph:.1}" fill="none" stroke="#444" stroke-width="1"/>"##
        );
        for (mx, my, text) in &m.markers {
            marker(o, (px(*mx), py(*my)), (x0, y0, pw), text);
        }
        // Axis ticks: a few nice values.
        for (v, label) in major_ticks(ex) {
            let x = px(v);
            let line = (x, y0 + ph, x, y0 + ph + 4.0);
            tick(o, line, (x, y0 + ph + 16.0), MIDDLE, &label);
        }
        for (v, label) in major_ticks(ey) {
            let y = py(v);
            tick(o, (x0 - 4.0, y, x0, y), (x0 - 6.0, y + 4.0), END, &label);
        }
        let (row, col) = (k / l.cols, k % l.cols);
        if row == l.rows - 1 || k + l.cols >= self.maps.len() {
            let _ = writeln!(
                o,
                r#"<text x="{:.1}" y="{:.1}" font-size="12" text-anchor="middle">{}</text>"#,
                x0 + pw / 2.0,
                y0 + ph + 32.0,
                rich(&self.x_label, 12.0)
            );
        }
        if col == 0 {
            let (tx, ty) = (x0 - 44.0, y0 + ph / 2.0);
            let _ = writeln!(
                o,
                r#"<text x="{tx:.1}" y="{ty:.1}" font-size="12" text-anchor="middle" transform="rotate(-90 {tx:.1} {ty:.1})">{}</text>"#,
                rich(&self.y_label, 12.0)
            );
        }
    }

    /// The colour bar right of the panels, its ticks, its label and the hatched-cell key.
    fn colour_bar(&self, o: &mut String, l: &Layout, (vmin, vmax): (f64, f64)) {
        let (cols, rows) = (l.cols, l.rows);
        let bx = l.ml + cols as f64 * l.pw + (cols - 1) as f64 * l.gap_x + 24.0;
        let by = l.mt0 + l.cap;
        let bh = colour_bar_height(rows, l.ph, l.cap, l.gap_y);
        let steps = COLOUR_BAR_STEPS;
        for i in 0..steps {
            let t0 = i as f64 / steps as f64;
            let _ = writeln!(
                o,
                r#"<rect x="{bx:.1}" y="{:.2}" width="16" height="{:.2}" fill="{}"/>"#,
                by + bh * (1.0 - t0 - 1.0 / steps as f64),
                bh / steps as f64 + 0.3,
                colormap(t0 + 0.5 / steps as f64)
            );
        }
        let _ = writeln!(
            o,
            r##"<rect x="{bx:.1}" y="{by:.1}" width="16" height="{bh:.1}" fill="none" stroke="#444"/>"##
        );
        for (v, label) in major_ticks((vmin, vmax)) {
            let yy = by + bh * (1.0 - (v - vmin) / (vmax - vmin));
            tick(
                o,
                (bx + 16.0, yy, bx + 20.0, yy),
                (bx + 22.0, yy + 4.0),
                "",
                &label,
            );
        }
        let (tx, ty) = (bx + 8.0, by + bh + 18.0);
        let _ = writeln!(
            o,
            r#"<text x="{tx:.1}" y="{ty:.1}" font-size="12" text-anchor="middle">{}</text>"#,
            rich(&self.value_label, 12.0)
        );
        let _ = writeln!(
            o,
            r##"<rect x="{bx:.1}" y="{:.1}" width="16" height="12" fill="url(#hatch)" stroke="#888"/><text x="{:.1}" y="{:.1}" font-size="11">{}</text>"##,
            ty + 12.0,
            bx,
            ty + 38.0,
            escape(&self.invalid_label)
        );
        for v in self.levels((vmin, vmax)) {
            let yy = by + bh * (1.0 - (v - vmin) / (vmax - vmin));
            let seg = [((0.0, yy), (16.0, yy))];
            overlay::draw_contours(o, &seg, &|x| bx + x, &|y| y);
        }
        let at = (bx, ty + 48.0);
        overlay::draw_key(o, at, self.contours, self.frame.is_some());
    }
}

/// Height of the colour bar beside `rows` rows of panels of height `ph`, px (at most
/// 320 px: a taller bar reads no better).
fn colour_bar_height(rows: usize, ph: f64, cap: f64, gap_y: f64) -> f64 {
    (rows as f64 * (ph + cap) + (rows - 1) as f64 * gap_y - cap).min(320.0)
}

/// Space under the colour bar for its label and the hatched-cell key, px.
const KEY_PX: f64 = 72.0;
/// One more row of the key, px.
const KEY_ROW_PX: f64 = 16.0;
/// Margin of a view grown to the frame, as a fraction of its larger side.
const VIEW_PAD: f64 = 0.03;

/// Colour-bar bands: enough that the steps of the piecewise-linear map do not show.
const COLOUR_BAR_STEPS: usize = 64;

/// `text-anchor` attributes of tick labels.
const MIDDLE: &str = r#" text-anchor="middle""#;
const END: &str = r#" text-anchor="end""#;

/// The major ticks of a linear axis spanning `range`, with their labels (one style).
fn major_ticks(range: (f64, f64)) -> Vec<(f64, String)> {
    let a = Axis::linear("").with_range(range.0, range.1);
    let v: Vec<f64> = ticks(&a, range)
        .into_iter()
        .filter(|&(_, major)| major)
        .map(|(v, _)| v)
        .collect();
    let labels = tick_labels(&a, range, &v);
    v.into_iter().zip(labels).collect()
}

/// One tick: a short line (x1, y1, x2, y2) and its value at `at`.
fn tick(o: &mut String, line: (f64, f64, f64, f64), at: (f64, f64), anchor: &str, v: &str) {
    let _ = writeln!(
        o,
        r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#444"/><text x="{:.1}" y="{:.1}" font-size="11"{anchor}>{}</text>"##,
        line.0, line.1, line.2, line.3, at.0, at.1, v
    );
}

/// A cross at (`cx`, `cy`) with `text` beside it, kept inside the panel (x0, y0, width).
fn marker(o: &mut String, (cx, cy): (f64, f64), (x0, y0, pw): (f64, f64, f64), text: &str) {
    let d = format!(
        "M{:.1},{:.1}L{:.1},{:.1}M{:.1},{:.1}L{:.1},{:.1}",
        cx - 5.0,
        cy - 5.0,
        cx + 5.0,
        cy + 5.0,
        cx - 5.0,
        cy + 5.0,
        cx + 5.0,
        cy - 5.0
    );
    let _ = writeln!(
        o,
        r##"<path d="{d}" stroke="#ffffff" stroke-width="3"/><path d="{d}" stroke="#d00000" stroke-width="1.6"/>"##
    );
    let anchor = if cx > x0 + pw * 0.6 { "end" } else { "start" };
    let dx = if anchor == "end" { -7.0 } else { 7.0 };
    let ty = if cy < y0 + 14.0 { cy + 14.0 } else { cy - 6.0 };
    let _ = writeln!(
        o,
        r##"<text x="{:.1}" y="{ty:.1}" font-size="11" text-anchor="{anchor}" fill="#000" stroke="#fff" stroke-width="3" paint-order="stroke">{}</text>"##,
        cx + dx,
        escape(text)
    );
}

/// The viridis colour map at t ∈ [0, 1] as `#rrggbb` (piecewise-linear through 9 stops).
pub fn colormap(t: f64) -> String {
    const STOPS: [(f64, f64, f64); 9] = [
        (68.0, 1.0, 84.0),
        (71.0, 44.0, 122.0),
        (59.0, 81.0, 139.0),
        (44.0, 113.0, 142.0),
        (33.0, 144.0, 141.0),
        (39.0, 173.0, 129.0),
        (92.0, 200.0, 99.0),
        (170.0, 220.0, 50.0),
        (253.0, 231.0, 37.0),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * (STOPS.len() - 1) as f64;
    let i = (s.floor() as usize).min(STOPS.len() - 2);
    let f = s - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let c = |x: f64, y: f64| (x + (y - x) * f).round().clamp(0.0, 255.0) as u8;
    format!("#{:02x}{:02x}{:02x}", c(a.0, b.0), c(a.1, b.1), c(a.2, b.2))
}

fn extent(c: &[f64]) -> (f64, f64) {
    match c.len() {
        0 => (0.0, 1.0),
        1 => (c[0] - 0.5, c[0] + 0.5),
        n => {
            let d0 = (c[1] - c[0]) / 2.0;
            let d1 = (c[n - 1] - c[n - 2]) / 2.0;
            (c[0] - d0, c[n - 1] + d1)
        }
    }
}

fn cell_edges(c: &[f64], i: usize) -> (f64, f64) {
    let n = c.len();
    let (e0, e1) = extent(c);
    let lo = if i == 0 { e0 } else { (c[i - 1] + c[i]) / 2.0 };
    let hi = if i + 1 == n {
        e1
    } else {
        (c[i] + c[i + 1]) / 2.0
    };
    (lo, hi)
}
