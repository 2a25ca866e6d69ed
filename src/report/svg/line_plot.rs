//! Line and scatter plots with a legend.

use super::axis::{fit_range, tick_label, ticks, Axis, Mapper};
use super::{escape, header, subtitle_lines, title, PALETTE};
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

/// One data series.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend entry (empty: not in the legend).
    pub name: String,
    /// (x, y) points; non-finite points break the line.
    pub points: Vec<(f64, f64)>,
    /// Optional text next to individual points (same length as `points`, or empty).
    pub labels: Vec<Option<String>>,
    /// Colour (CSS); `None` takes the next palette colour.
    pub color: Option<String>,
    /// How to draw it.
    pub mark: Mark,
}

impl Series {
    /// A series drawn with `mark`.
    pub fn new(name: &str, points: Vec<(f64, f64)>, mark: Mark) -> Series {
        Series {
            name: name.into(),
            points,
            labels: Vec::new(),
            color: None,
            mark,
        }
    }
    /// With a fixed colour.
    pub fn color(mut self, c: &str) -> Series {
        self.color = Some(c.into());
        self
    }
    /// With point labels.
    pub fn labels(mut self, labels: Vec<Option<String>>) -> Series {
        self.labels = labels;
        self
    }
}

/// A horizontal reference line across the plot.
#[derive(Debug, Clone)]
pub struct HLine {
    /// Legend entry.
    pub name: String,
    /// Its y value.
    pub y: f64,
    /// Colour (CSS).
    pub color: String,
}

/// A line / scatter plot.
#[derive(Debug, Clone)]
pub struct LinePlot {
    /// Title on top.
    pub title: String,
    /// Smaller second line under the title (may be empty).
    pub subtitle: String,
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// Data.
    pub series: Vec<Series>,
    /// Horizontal reference lines.
    pub hlines: Vec<HLine>,
    /// Size in px.
    pub width: f64,
    /// Size in px.
    pub height: f64,
}

impl LinePlot {
    /// An empty plot of the default size (720 × 440 px).
    pub fn new(title: &str, x: Axis, y: Axis) -> LinePlot {
        LinePlot {
            title: title.into(),
            subtitle: String::new(),
            x,
            y,
            series: Vec::new(),
            hlines: Vec::new(),
            width: 720.0,
            height: 440.0,
        }
    }

    /// Render to a standalone SVG document.
    pub fn to_svg(&self) -> String {
        let (w, h) = (self.width, self.height);
        let nsub = subtitle_lines(w, &self.subtitle).len() as f64;
        let (ml, mr, mt, mb) = (78.0, 20.0, 42.0 + 15.0 * nsub, 56.0);
        let pw = w - ml - mr;
        let ph = h - mt - mb;
        let (xr, yr) = self.ranges();
        let c = Canvas {
            plot: self,
            xmap: Mapper::new(&self.x, xr, ml, ml + pw),
            ymap: Mapper::new(&self.y, yr, mt + ph, mt),
            ml,
            mt,
            pw,
            ph,
        };
        let mut o = header(w, h);
        title(&mut o, w, &self.title, &self.subtitle);
        let pts_px = c.drawn_pixels();
        c.frame_and_ticks(&mut o, xr, yr, h);
        let legend = c.data(&mut o);
        c.legend(&mut o, &legend, &pts_px);
        o.push_str("</svg>\n");
        o
    }

    /// Axis ranges: fixed, or fitted to the drawable points and reference lines.
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        for s in &self.series {
            for &(x, y) in &s.points {
                if usable(&self.x, x) && usable(&self.y, y) {
                    xs.push(x);
                    ys.push(y);
                }
            }
        }
        for l in &self.hlines {
            if usable(&self.y, l.y) {
                ys.push(l.y);
            }
        }
        (fit_range(&self.x, &xs), fit_range(&self.y, &ys))
    }
}

/// Whether `v` can be drawn on axis `a` (finite; positive on a log axis).
fn usable(a: &Axis, v: f64) -> bool {
    v.is_finite() && (!a.log || v > 0.0)
}

/// A legend entry: name, colour, mark.
type LegendEntry = (String, String, Mark);

/// A plot being drawn: its data-to-pixel maps and plot area (px).
struct Canvas<'a> {
    plot: &'a LinePlot,
    xmap: Mapper,
    ymap: Mapper,
    ml: f64,
    mt: f64,
    pw: f64,
    ph: f64,
}

impl Canvas<'_> {
    /// Whether the point can be drawn on both axes.
    fn usable(&self, x: f64, y: f64) -> bool {
        usable(&self.plot.x, x) && usable(&self.plot.y, y)
    }

    /// Pixels covered by the data (points, segments sampled, reference lines), so the
    /// legend can avoid them.
    fn drawn_pixels(&self) -> Vec<(f64, f64)> {
        let (xmap, ymap) = (&self.xmap, &self.ymap);
        let mut pts_px: Vec<(f64, f64)> = Vec::new();
        for s in &self.plot.series {
            let mut prev: Option<(f64, f64)> = None;
            for &(x, y) in &s.points {
                if self.usable(x, y) {
                    let p = (xmap.map(x), ymap.map(y));
                    // Sample along segments too, so the legend avoids lines, not just points.
                    if let Some(q) = prev {
                        for k in 1..8 {
                            let t = k as f64 / 8.0;
                            pts_px.push((q.0 + (p.0 - q.0) * t, q.1 + (p.1 - q.1) * t));
                        }
                    }
                    pts_px.push(p);
                    prev = if s.mark == Mark::Points {
                        None
                    } else {
                        Some(p)
                    };
                } else {
                    prev = None;
                }
            }
        }
        for l in &self.plot.hlines {
            if usable(&self.plot.y, l.y) {
                let py = ymap.map(l.y);
                for k in 0..=40 {
                    pts_px.push((self.ml + self.pw * k as f64 / 40.0, py));
                }
            }
        }
        pts_px
    }

    /// Frame, grid, tick labels and axis labels.
    fn frame_and_ticks(&self, o: &mut String, xr: (f64, f64), yr: (f64, f64), h: f64) {
        let (ml, mt, pw, ph) = (self.ml, self.mt, self.pw, self.ph);
        let (px_axis, py_axis) = (&self.plot.x, &self.plot.y);
        let _ = writeln!(
            o,
            r##"<rect x="{ml:.1}" y="{mt:.1}" width="{pw:.1}" height="{ph:.1}" fill="#ffffff" stroke="#444" stroke-width="1"/>"##
        );
        for (v, major) in ticks(px_axis, xr) {
            let px = self.xmap.map(v);
            let (stroke, dash) = if major {
                ("#d0d0d0", "")
            } else {
                ("#ececec", "")
            };
            let _ = writeln!(
                o,
                r#"<line x1="{px:.1}" y1="{mt:.1}" x2="{px:.1}" y2="{:.1}" stroke="{stroke}" stroke-width="1"{dash}/>"#,
                mt + ph
            );
            if major {
                let _ = writeln!(
                    o,
                    r#"<text x="{px:.1}" y="{:.1}" font-size="12" text-anchor="middle">{}</text>"#,
                    mt + ph + 16.0,
                    tick_label(px_axis, v)
                );
            }
        }
        for (v, major) in ticks(py_axis, yr) {
            let py = self.ymap.map(v);
            let stroke = if major { "#d0d0d0" } else { "#ececec" };
            let _ = writeln!(
                o,
                r#"<line x1="{ml:.1}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="{stroke}" stroke-width="1"/>"#,
                ml + pw
            );
            if major {
                let _ = writeln!(
                    o,
                    r#"<text x="{:.1}" y="{:.1}" font-size="12" text-anchor="end">{}</text>"#,
                    ml - 6.0,
                    py + 4.0,
                    tick_label(py_axis, v)
                );
            }
        }
        let _ = writeln!(
            o,
            r#"<text x="{:.1}" y="{:.1}" font-size="13" text-anchor="middle">{}</text>"#,
            ml + pw / 2.0,
            h - 14.0,
            escape(&px_axis.label)
        );
        let _ = writeln!(
            o,
            r#"<text x="16" y="{:.1}" font-size="13" text-anchor="middle" transform="rotate(-90 16 {:.1})">{}</text>"#,
            mt + ph / 2.0,
            mt + ph / 2.0,
            escape(&py_axis.label)
        );
    }

    /// Reference lines and series, clipped to the plot area; returns the legend entries.
    fn data(&self, o: &mut String) -> Vec<LegendEntry> {
        let (ml, mt, pw, ph) = (self.ml, self.mt, self.pw, self.ph);
        let _ = writeln!(
            o,
            r#"<defs><clipPath id="plotarea"><rect x="{ml:.1}" y="{mt:.1}" width="{pw:.1}" height="{ph:.1}"/></clipPath></defs>"#
        );
        let _ = writeln!(o, r#"<g clip-path="url(#plotarea)">"#);
        let mut legend: Vec<LegendEntry> = Vec::new();
        for l in &self.plot.hlines {
            if !usable(&self.plot.y, l.y) {
                continue;
            }
            let py = self.ymap.map(l.y);
            let _ = writeln!(
                o,
                r#"<line x1="{ml:.1}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="{}" stroke-width="1.5" stroke-dasharray="8 4"/>"#,
                ml + pw,
                escape(&l.color)
            );
            legend.push((l.name.clone(), l.color.clone(), Mark::Dashed));
        }
        let mut next = 0usize;
        let mut placed: Vec<(f64, f64)> = Vec::new();
        for s in &self.plot.series {
            let color = match &s.color {
                Some(c) => c.clone(),
                None => {
                    let c = PALETTE[next % PALETTE.len()].to_string();
                    next += 1;
                    c
                }
            };
            let col = escape(&color);
            self.series(o, s, &col, &mut placed);
            if !s.name.is_empty() {
                legend.push((s.name.clone(), color, s.mark));
            }
        }
        let _ = writeln!(o, "</g>");
        legend
    }

    /// One series: its lines, its circles and its point labels (a label that would
    /// overprint one in `placed` is skipped).
    fn series(&self, o: &mut String, s: &Series, col: &str, placed: &mut Vec<(f64, f64)>) {
        let (xmap, ymap) = (&self.xmap, &self.ymap);
        if matches!(s.mark, Mark::Line | Mark::Dashed | Mark::LinePoints) {
            let dash = if s.mark == Mark::Dashed {
                r#" stroke-dasharray="6 4""#
            } else {
                ""
            };
            let mut seg = String::new();
            let flush = |seg: &mut String, o: &mut String| {
                if seg.matches(' ').count() >= 1 {
                    let _ = writeln!(
                        o,
                        r#"<polyline points="{}" fill="none" stroke="{col}" stroke-width="1.8"{dash}/>"#,
                        seg.trim()
                    );
                }
                seg.clear();
            };
            for &(x, y) in &s.points {
                if self.usable(x, y) {
                    let _ = write!(seg, "{:.2},{:.2} ", xmap.map(x), ymap.map(y));
                } else {
                    flush(&mut seg, o);
                }
            }
            flush(&mut seg, o);
        }
        if matches!(s.mark, Mark::Points | Mark::LinePoints) {
            for &(x, y) in &s.points {
                if self.usable(x, y) {
                    let _ = writeln!(
                        o,
                        r##"<circle cx="{:.2}" cy="{:.2}" r="3.2" fill="{col}" fill-opacity="0.85" stroke="#fff" stroke-width="0.6"/>"##,
                        xmap.map(x),
                        ymap.map(y)
                    );
                }
            }
        }
        for (i, l) in s.labels.iter().enumerate() {
            let (Some(l), Some(&(x, y))) = (l, s.points.get(i)) else {
                continue;
            };
            if self.usable(x, y) {
                // Skip a label that would overprint one already placed.
                let (lx, ly) = (xmap.map(x), ymap.map(y));
                if placed
                    .iter()
                    .any(|&(px, py): &(f64, f64)| (px - lx).abs() < 30.0 && (py - ly).abs() < 11.0)
                {
                    continue;
                }
                placed.push((lx, ly));
                let _ = writeln!(
                    o,
                    r#"<text x="{:.1}" y="{:.1}" font-size="10" fill="{col}">{}</text>"#,
                    xmap.map(x) + 5.0,
                    ymap.map(y) - 5.0,
                    escape(l)
                );
            }
        }
    }

    /// The legend box, in the candidate position covering the fewest drawn pixels.
    fn legend(&self, o: &mut String, legend: &[LegendEntry], pts_px: &[(f64, f64)]) {
        if legend.is_empty() {
            return;
        }
        let (ml, mt, pw, ph) = (self.ml, self.mt, self.pw, self.ph);
        let lw = legend
            .iter()
            .map(|(n, _, _)| n.chars().count())
            .max()
            .unwrap_or(0) as f64
            * 6.6
            + 42.0;
        let lh = legend.len() as f64 * 17.0 + 8.0;
        // The corner whose box covers the fewest drawn points.
        let (right, left, midx) = (ml + pw - lw - 8.0, ml + 8.0, ml + (pw - lw) / 2.0);
        let (top, bottom, midy) = (mt + 8.0, mt + ph - lh - 8.0, mt + (ph - lh) / 2.0);
        let corners = [
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
        let cover = |&(x, y): &(f64, f64)| {
            pts_px
                .iter()
                .filter(|p| p.0 >= x && p.0 <= x + lw && p.1 >= y && p.1 <= y + lh)
                .count()
        };
        let (lx, ly) = corners
            .iter()
            .copied()
            .min_by_key(|c| cover(c))
            .unwrap_or(corners[0]);
        let _ = writeln!(
            o,
            r##"<rect x="{lx:.1}" y="{ly:.1}" width="{lw:.1}" height="{lh:.1}" fill="#ffffff" fill-opacity="0.9" stroke="#999" stroke-width="0.8"/>"##
        );
        for (i, (name, color, mark)) in legend.iter().enumerate() {
            let yy = ly + 14.0 + i as f64 * 17.0;
            legend_mark(o, lx, yy, &escape(color), *mark);
            let _ = writeln!(
                o,
                r#"<text x="{:.1}" y="{yy:.1}" font-size="12">{}</text>"#,
                lx + 34.0,
                escape(name)
            );
        }
    }
}

/// The sample mark of one legend entry at (`lx`, `yy`).
fn legend_mark(o: &mut String, lx: f64, yy: f64, col: &str, mark: Mark) {
    match mark {
        Mark::Points => {
            let _ = writeln!(
                o,
                r#"<circle cx="{:.1}" cy="{:.1}" r="3.5" fill="{col}"/>"#,
                lx + 17.0,
                yy - 4.0
            );
        }
        _ => {
            let dash = if mark == Mark::Dashed {
                r#" stroke-dasharray="6 4""#
            } else {
                ""
            };
            let _ = writeln!(
                o,
                r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{col}" stroke-width="2"{dash}/>"#,
                lx + 6.0,
                yy - 4.0,
                lx + 28.0,
                yy - 4.0
            );
            if mark == Mark::LinePoints {
                let _ = writeln!(
                    o,
                    r#"<circle cx="{:.1}" cy="{:.1}" r="3" fill="{col}"/>"#,
                    lx + 17.0,
                    yy - 4.0
                );
            }
        }
    }
}
