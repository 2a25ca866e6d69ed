//! Line and scatter plots with a legend.

use super::axis::{fit_range, tick_labels, ticks, Axis, Mapper};
pub use super::legend::Mark;

use super::legend::{self, LegendEntry, Segment};
use super::{escape, header, rich, subtitle_lines, title, PALETTE};
use std::fmt::Write as _;

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
        let entries = c.legend_entries();
        let place = legend::place(&entries, (ml, mt, pw, ph), &c.drawn_segments());
        // A legend outside widens the document by its width (the plot keeps its size).
        let w = if place.outside {
            place.x + place.w + mr
        } else {
            w
        };
        let mut o = header(w, h);
        title(&mut o, w, &self.title, &self.subtitle);
        c.frame_and_ticks(&mut o, xr, yr, h);
        c.data(&mut o);
        legend::draw(&mut o, &entries, &place);
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

    /// The drawn data in px: line segments, points (segments of length 0) and the
    /// reference lines, so that the legend can avoid them.
    fn drawn_segments(&self) -> Vec<Segment> {
        let mut out: Vec<Segment> = Vec::new();
        for s in &self.plot.series {
            let mut prev: Option<(f64, f64)> = None;
            for &(x, y) in &s.points {
                if !self.usable(x, y) {
                    prev = None;
                    continue;
                }
                let p = (self.xmap.map(x), self.ymap.map(y));
                match prev {
                    Some(q) if s.mark != Mark::Points => out.push((q, p)),
                    _ => out.push((p, p)),
                }
                prev = Some(p);
            }
        }
        for l in &self.plot.hlines {
            if usable(&self.plot.y, l.y) {
                let py = self.ymap.map(l.y);
                out.push(((self.ml, py), (self.ml + self.pw, py)));
            }
        }
        out
    }

    /// The legend rows: reference lines first, then the named series (palette colours
    /// assigned in order to the series without one).
    fn legend_entries(&self) -> Vec<LegendEntry> {
        let mut out = Vec::new();
        for l in &self.plot.hlines {
            if usable(&self.plot.y, l.y) {
                out.push(LegendEntry {
                    name: l.name.clone(),
                    color: l.color.clone(),
                    mark: Mark::Dashed,
                    dash: String::new(),
                });
            }
        }
        for (s, color) in self.plot.series.iter().zip(self.series_colors()) {
            if !s.name.is_empty() {
                out.push(LegendEntry {
                    name: s.name.clone(),
                    color,
                    mark: s.mark,
                    dash: String::new(),
                });
            }
        }
        out
    }

    /// Each series' colour: its own, or the next palette colour.
    fn series_colors(&self) -> Vec<String> {
        let mut next = 0usize;
        self.plot
            .series
            .iter()
            .map(|s| match &s.color {
                Some(c) => c.clone(),
                None => {
                    next += 1;
                    PALETTE[(next - 1) % PALETTE.len()].to_string()
                }
            })
            .collect()
    }

    /// Frame, grid, tick labels and axis labels.
    fn frame_and_ticks(&self, o: &mut String, xr: (f64, f64), yr: (f64, f64), h: f64) {
        let (ml, mt, pw, ph) = (self.ml, self.mt, self.pw, self.ph);
        let (px_axis, py_axis) = (&self.plot.x, &self.plot.y);
        let _ = writeln!(
            o,
            r##"<rect x="{ml:.1}" y="{mt:.1}" width="{pw:.1}" height="{ph:.1}" fill="#ffffff" stroke="#444" stroke-width="1"/>"##
        );
        for (axis, r, vertical) in [(px_axis, xr, false), (py_axis, yr, true)] {
            self.grid_and_labels(o, axis, r, vertical);
        }
        let _ = writeln!(
            o,
            r#"<text x="{:.1}" y="{:.1}" font-size="13" text-anchor="middle">{}</text>"#,
            ml + pw / 2.0,
            h - 14.0,
            rich(&px_axis.label, 13.0)
        );
        let _ = writeln!(
            o,
            r#"<text x="16" y="{:.1}" font-size="13" text-anchor="middle" transform="rotate(-90 16 {:.1})">{}</text>"#,
            mt + ph / 2.0,
            mt + ph / 2.0,
            rich(&py_axis.label, 13.0)
        );
    }

    /// The grid lines of one axis and the labels of its major ticks (one style per axis).
    fn grid_and_labels(&self, o: &mut String, axis: &Axis, r: (f64, f64), vertical: bool) {
        let (ml, mt, pw, ph) = (self.ml, self.mt, self.pw, self.ph);
        let t = ticks(axis, r);
        let majors: Vec<f64> = t.iter().filter(|x| x.1).map(|x| x.0).collect();
        let labels = tick_labels(axis, r, &majors);
        for &(v, major) in &t {
            let stroke = if major { "#d0d0d0" } else { "#ececec" };
            let (x1, y1, x2, y2) = if vertical {
                let py = self.ymap.map(v);
                (ml, py, ml + pw, py)
            } else {
                let px = self.xmap.map(v);
                (px, mt, px, mt + ph)
            };
            let _ = writeln!(
                o,
                r#"<line x1="{x1:.1}" y1="{y1:.1}" x2="{x2:.1}" y2="{y2:.1}" stroke="{stroke}" stroke-width="1"/>"#
            );
        }
        for (v, label) in majors.iter().zip(&labels) {
            let (x, y, anchor) = if vertical {
                (ml - 6.0, self.ymap.map(*v) + 4.0, "end")
            } else {
                (self.xmap.map(*v), mt + ph + 16.0, "middle")
            };
            let _ = writeln!(
                o,
                r#"<text x="{x:.1}" y="{y:.1}" font-size="12" text-anchor="{anchor}" class="tick">{label}</text>"#
            );
        }
    }

    /// Series, then the reference lines over them (dashed, so what they cross shows
    /// through), clipped to the plot area.
    fn data(&self, o: &mut String) {
        let (ml, mt, pw, ph) = (self.ml, self.mt, self.pw, self.ph);
        let _ = writeln!(
            o,
            r#"<defs><clipPath id="plotarea"><rect x="{ml:.1}" y="{mt:.1}" width="{pw:.1}" height="{ph:.1}"/></clipPath></defs>"#
        );
        let _ = writeln!(o, r#"<g class="data" clip-path="url(#plotarea)">"#);
        let mut placed: Vec<(f64, f64)> = Vec::new();
        for (s, color) in self.plot.series.iter().zip(self.series_colors()) {
            self.series(o, s, &escape(&color), &mut placed);
        }
        let n = self.plot.hlines.len();
        for (k, l) in self.plot.hlines.iter().enumerate() {
            if !usable(&self.plot.y, l.y) {
                continue;
            }
            let py = self.ymap.map(l.y);
            let (dash, offset) = hline_dash(k, n);
            let _ = writeln!(
                o,
                r#"<line x1="{ml:.1}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="{}" stroke-width="1.8" stroke-dasharray="{dash}" stroke-dashoffset="{offset}"/>"#,
                ml + pw,
                escape(&l.color)
            );
        }
        let _ = writeln!(o, "</g>");
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
}

/// Dash length of the reference lines, px.
const HLINE_DASH_PX: f64 = 7.0;

/// `stroke-dasharray` and `stroke-dashoffset` of reference line `k` of `n`: dashes of
/// [`HLINE_DASH_PX`] with gaps that leave room for the other n − 1, each line shifted by
/// one dash, so reference lines at the same value alternate instead of hiding each other.
fn hline_dash(k: usize, n: usize) -> (String, String) {
    let gap = HLINE_DASH_PX * (n.max(2) - 1) as f64;
    (
        format!("{HLINE_DASH_PX} {gap}"),
        format!("{}", -HLINE_DASH_PX * k as f64),
    )
}
