//! A tiny, dependency-free SVG writer for the offline figures: line and scatter plots with
//! linear or logarithmic axes and a legend ([`LinePlot`]), and heat maps with a colour bar,
//! one or several panels sharing one colour scale ([`HeatPanel`]).
//!
//! Everything renders to a `String` holding one standalone `<svg>` document; text is
//! XML-escaped. Cells without a value (infeasible or invalid points) are drawn grey and
//! hatched, never left out, so a reader sees where the model has no answer.

use std::fmt::Write as _;

/// Default colours of successive series (colour-blind-safe palette, Okabe–Ito).
pub const PALETTE: [&str; 8] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442",
];

/// Escape text for SVG content and attribute values.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            _ => o.push(c),
        }
    }
    o
}

/// One plot axis.
#[derive(Debug, Clone, Default)]
pub struct Axis {
    /// Label under / beside the axis (unit in brackets by convention).
    pub label: String,
    /// Logarithmic (base 10) axis; non-positive values are not drawn.
    pub log: bool,
    /// Fixed range; `None` fits the data (with a small margin on linear axes).
    pub range: Option<(f64, f64)>,
}

impl Axis {
    /// A linear axis fitted to the data.
    pub fn linear(label: &str) -> Axis {
        Axis {
            label: label.into(),
            log: false,
            range: None,
        }
    }
    /// A log axis fitted to the data.
    pub fn log(label: &str) -> Axis {
        Axis {
            label: label.into(),
            log: true,
            range: None,
        }
    }
    /// With a fixed range.
    pub fn with_range(mut self, lo: f64, hi: f64) -> Axis {
        self.range = Some((lo, hi));
        self
    }
}

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
        let usable = |a: &Axis, v: f64| v.is_finite() && (!a.log || v > 0.0);
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
        let xr = fit_range(&self.x, &xs);
        let yr = fit_range(&self.y, &ys);
        let xmap = Mapper::new(&self.x, xr, ml, ml + pw);
        let ymap = Mapper::new(&self.y, yr, mt + ph, mt);

        let mut o = header(w, h);
        title(&mut o, w, &self.title, &self.subtitle);
        let mut pts_px: Vec<(f64, f64)> = Vec::new();
        for s in &self.series {
            let mut prev: Option<(f64, f64)> = None;
            for &(x, y) in &s.points {
                if usable(&self.x, x) && usable(&self.y, y) {
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
        for l in &self.hlines {
            if usable(&self.y, l.y) {
                let py = ymap.map(l.y);
                for k in 0..=40 {
                    pts_px.push((ml + pw * k as f64 / 40.0, py));
                }
            }
        }
        // Frame, grid and ticks.
        let _ = writeln!(
            o,
            r##"<rect x="{ml:.1}" y="{mt:.1}" width="{pw:.1}" height="{ph:.1}" fill="#ffffff" stroke="#444" stroke-width="1"/>"##
        );
        for (v, major) in ticks(&self.x, xr) {
            let px = xmap.map(v);
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
                    tick_label(&self.x, v)
                );
            }
        }
        for (v, major) in ticks(&self.y, yr) {
            let py = ymap.map(v);
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
                    tick_label(&self.y, v)
                );
            }
        }
        let _ = writeln!(
            o,
            r#"<text x="{:.1}" y="{:.1}" font-size="13" text-anchor="middle">{}</text>"#,
            ml + pw / 2.0,
            h - 14.0,
            escape(&self.x.label)
        );
        let _ = writeln!(
            o,
            r#"<text x="16" y="{:.1}" font-size="13" text-anchor="middle" transform="rotate(-90 16 {:.1})">{}</text>"#,
            mt + ph / 2.0,
            mt + ph / 2.0,
            escape(&self.y.label)
        );
        // Clip data to the plot area.
        let _ = writeln!(
            o,
            r#"<defs><clipPath id="plotarea"><rect x="{ml:.1}" y="{mt:.1}" width="{pw:.1}" height="{ph:.1}"/></clipPath></defs>"#
        );
        let _ = writeln!(o, r#"<g clip-path="url(#plotarea)">"#);
        let mut legend: Vec<(String, String, Mark)> = Vec::new();
        for l in &self.hlines {
            if !usable(&self.y, l.y) {
                continue;
            }
            let py = ymap.map(l.y);
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
        for s in &self.series {
            let color = match &s.color {
                Some(c) => c.clone(),
                None => {
                    let c = PALETTE[next % PALETTE.len()].to_string();
                    next += 1;
                    c
                }
            };
            let col = escape(&color);
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
                    if usable(&self.x, x) && usable(&self.y, y) {
                        let _ = write!(seg, "{:.2},{:.2} ", xmap.map(x), ymap.map(y));
                    } else {
                        flush(&mut seg, &mut o);
                    }
                }
                flush(&mut seg, &mut o);
            }
            if matches!(s.mark, Mark::Points | Mark::LinePoints) {
                for &(x, y) in &s.points {
                    if usable(&self.x, x) && usable(&self.y, y) {
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
                if usable(&self.x, x) && usable(&self.y, y) {
                    // Skip a label that would overprint one already placed.
                    let (lx, ly) = (xmap.map(x), ymap.map(y));
                    if placed.iter().any(|&(px, py): &(f64, f64)| {
                        (px - lx).abs() < 30.0 && (py - ly).abs() < 11.0
                    }) {
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
            if !s.name.is_empty() {
                legend.push((s.name.clone(), color, s.mark));
            }
        }
        let _ = writeln!(o, "</g>");
        // Legend, top right inside the plot.
        if !legend.is_empty() {
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
                let col = escape(color);
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
                        let dash = if *mark == Mark::Dashed {
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
                        if *mark == Mark::LinePoints {
                            let _ = writeln!(
                                o,
                                r#"<circle cx="{:.1}" cy="{:.1}" r="3" fill="{col}"/>"#,
                                lx + 17.0,
                                yy - 4.0
                            );
                        }
                    }
                }
                let _ = writeln!(
                    o,
                    r#"<text x="{:.1}" y="{yy:.1}" font-size="12">{}</text>"#,
                    lx + 34.0,
                    escape(name)
                );
            }
        }
        o.push_str("</svg>\n");
        o
    }
}

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
            .map(|m| (extent(&m.x), extent(&m.y)))
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
        let valid: Vec<f64> = self
            .maps
            .iter()
            .flat_map(|m| m.values.iter().flatten().copied())
            .filter(|v| v.is_finite())
            .collect();
        let (vmin, vmax) = match self.range {
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
        };
        let nsub = subtitle_lines(w, &self.subtitle).len() as f64;
        let mt0 = mt0 + 46.0 + 15.0 * nsub;
        let h = h + 46.0 + 15.0 * nsub;
        let mut o = header(w, h);
        title(&mut o, w, &self.title, &self.subtitle);
        let _ = writeln!(
            o,
            r##"<defs><pattern id="hatch" patternUnits="userSpaceOnUse" width="6" height="6" patternTransform="rotate(45)"><rect width="6" height="6" fill="#c8c8c8"/><line x1="0" y1="0" x2="0" y2="6" stroke="#7a7a7a" stroke-width="2"/></pattern></defs>"##
        );
        for (k, m) in self.maps.iter().enumerate() {
            let (r, c) = (k / cols, k % cols);
            let x0 = ml + c as f64 * (pw + gap_x);
            let y0 = mt0 + cap + r as f64 * (ph + cap + gap_y);
            let ex = extent(&m.x);
            let ey = extent(&m.y);
            let nx = m.x.len();
            let ny = m.y.len();
            let sx = pw / (ex.1 - ex.0);
            let sy = ph / (ey.1 - ey.0);
            let px = |x: f64| x0 + (x - ex.0) * sx;
            let py = |y: f64| y0 + ph - (y - ey.0) * sy;
            if !single {
                let _ = writeln!(
                    o,
                    r#"<text x="{:.1}" y="{:.1}" font-size="12" text-anchor="middle">{}</text>"#,
                    x0 + pw / 2.0,
                    y0 - 5.0,
                    escape(&m.caption)
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
            let _ = writeln!(
                o,
                r##"<rect x="{x0:.1}" y="{y0:.1}" width="{pw:.1}" height="{ph:.1}" fill="none" stroke="#444" stroke-width="1"/>"##
            );
            for (mx, my, text) in &m.markers {
                let (cx, cy) = (px(*mx), py(*my));
                let _ = writeln!(
                    o,
                    r##"<path d="M{:.1},{:.1}L{:.1},{:.1}M{:.1},{:.1}L{:.1},{:.1}" stroke="#ffffff" stroke-width="3"/><path d="M{:.1},{:.1}L{:.1},{:.1}M{:.1},{:.1}L{:.1},{:.1}" stroke="#d00000" stroke-width="1.6"/>"##,
                    cx - 5.0,
                    cy - 5.0,
                    cx + 5.0,
                    cy + 5.0,
                    cx - 5.0,
                    cy + 5.0,
                    cx + 5.0,
                    cy - 5.0,
                    cx - 5.0,
                    cy - 5.0,
                    cx + 5.0,
                    cy + 5.0,
                    cx - 5.0,
                    cy + 5.0,
                    cx + 5.0,
                    cy - 5.0
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
            // Axis ticks: a few nice values.
            let xa = Axis::linear("").with_range(ex.0, ex.1);
            for (v, major) in ticks(&xa, ex) {
                if !major {
                    continue;
                }
                let _ = writeln!(
                    o,
                    r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#444"/><text x="{:.1}" y="{:.1}" font-size="11" text-anchor="middle">{}</text>"##,
                    px(v),
                    y0 + ph,
                    px(v),
                    y0 + ph + 4.0,
                    px(v),
                    y0 + ph + 16.0,
                    fmt_num(v)
                );
            }
            let ya = Axis::linear("").with_range(ey.0, ey.1);
            for (v, major) in ticks(&ya, ey) {
                if !major {
                    continue;
                }
                let _ = writeln!(
                    o,
                    r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#444"/><text x="{:.1}" y="{:.1}" font-size="11" text-anchor="end">{}</text>"##,
                    x0 - 4.0,
                    py(v),
                    x0,
                    py(v),
                    x0 - 6.0,
                    py(v) + 4.0,
                    fmt_num(v)
                );
            }
            if r == rows - 1 || k + cols >= self.maps.len() {
                let _ = writeln!(
                    o,
                    r#"<text x="{:.1}" y="{:.1}" font-size="12" text-anchor="middle">{}</text>"#,
                    x0 + pw / 2.0,
                    y0 + ph + 32.0,
                    escape(&self.x_label)
                );
            }
            if c == 0 {
                let (tx, ty) = (x0 - 44.0, y0 + ph / 2.0);
                let _ = writeln!(
                    o,
                    r#"<text x="{tx:.1}" y="{ty:.1}" font-size="12" text-anchor="middle" transform="rotate(-90 {tx:.1} {ty:.1})">{}</text>"#,
                    escape(&self.y_label)
                );
            }
        }
        // Colour bar.
        let bx = ml + cols as f64 * pw + (cols - 1) as f64 * gap_x + 24.0;
        let by = mt0 + cap;
        let bh = (rows as f64 * (ph + cap) + (rows - 1) as f64 * gap_y - cap).min(320.0);
        let steps = 64;
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
        let ba = Axis::linear("").with_range(vmin, vmax);
        for (v, major) in ticks(&ba, (vmin, vmax)) {
            if !major {
                continue;
            }
            let yy = by + bh * (1.0 - (v - vmin) / (vmax - vmin));
            let _ = writeln!(
                o,
                r##"<line x1="{:.1}" y1="{yy:.1}" x2="{:.1}" y2="{yy:.1}" stroke="#444"/><text x="{:.1}" y="{:.1}" font-size="11">{}</text>"##,
                bx + 16.0,
                bx + 20.0,
                bx + 22.0,
                yy + 4.0,
                fmt_num(v)
            );
        }
        let (tx, ty) = (bx + 8.0, by + bh + 18.0);
        let _ = writeln!(
            o,
            r#"<text x="{tx:.1}" y="{ty:.1}" font-size="12" text-anchor="middle">{}</text>"#,
            escape(&self.value_label)
        );
        let _ = writeln!(
            o,
            r##"<rect x="{bx:.1}" y="{:.1}" width="16" height="12" fill="url(#hatch)" stroke="#888"/><text x="{:.1}" y="{:.1}" font-size="11">{}</text>"##,
            ty + 12.0,
            bx,
            ty + 38.0,
            escape(&self.invalid_label)
        );
        o.push_str("</svg>\n");
        o
    }
}

fn header(w: f64, h: f64) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" viewBox=\"0 0 {w:.0} {h:.0}\" font-family=\"Helvetica, Arial, sans-serif\">\n<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n"
    )
}

/// Split a subtitle at "; " into lines of at most `max` characters (greedy).
fn wrap(sub: &str, max: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for part in sub.split("; ") {
        match lines.last_mut() {
            Some(l) if l.chars().count() + 2 + part.chars().count() <= max => {
                l.push_str("; ");
                l.push_str(part);
            }
            _ => lines.push(part.to_string()),
        }
    }
    lines
}

fn subtitle_lines(w: f64, sub: &str) -> Vec<String> {
    if sub.is_empty() {
        return Vec::new();
    }
    wrap(sub, ((w - 20.0) / 6.6).max(20.0) as usize)
}

/// Title and subtitle; returns the height they take (px).
fn title(o: &mut String, w: f64, t: &str, sub: &str) -> f64 {
    let _ = writeln!(
        o,
        r#"<text x="{:.1}" y="24" font-size="16" font-weight="bold" text-anchor="middle">{}</text>"#,
        w / 2.0,
        escape(t)
    );
    let lines = subtitle_lines(w, sub);
    for (i, l) in lines.iter().enumerate() {
        let _ = writeln!(
            o,
            r##"<text x="{:.1}" y="{:.0}" font-size="12" fill="#333" text-anchor="middle">{}</text>"##,
            w / 2.0,
            42.0 + 15.0 * i as f64,
            escape(l)
        );
    }
    40.0 + 15.0 * lines.len() as f64
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

fn fit_range(a: &Axis, v: &[f64]) -> (f64, f64) {
    if let Some(r) = a.range {
        return r;
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() {
        return if a.log { (1.0, 10.0) } else { (0.0, 1.0) };
    }
    if a.log {
        let (l, h) = (lo.log10().floor(), hi.log10().ceil());
        let h = if h <= l { l + 1.0 } else { h };
        (10f64.powf(l), 10f64.powf(h))
    } else if hi > lo {
        let m = 0.05 * (hi - lo);
        (lo - m, hi + m)
    } else {
        let m = if lo == 0.0 { 1.0 } else { 0.05 * lo.abs() };
        (lo - m, hi + m)
    }
}

struct Mapper {
    log: bool,
    d0: f64,
    d1: f64,
    p0: f64,
    p1: f64,
}

impl Mapper {
    fn new(a: &Axis, r: (f64, f64), p0: f64, p1: f64) -> Mapper {
        let (d0, d1) = if a.log {
            (
                r.0.max(f64::MIN_POSITIVE).log10(),
                r.1.max(f64::MIN_POSITIVE).log10(),
            )
        } else {
            r
        };
        let d1 = if d1 > d0 { d1 } else { d0 + 1.0 };
        Mapper {
            log: a.log,
            d0,
            d1,
            p0,
            p1,
        }
    }
    fn map(&self, v: f64) -> f64 {
        let v = if self.log { v.log10() } else { v };
        self.p0 + (v - self.d0) / (self.d1 - self.d0) * (self.p1 - self.p0)
    }
}

/// Tick positions (value, is_major) within the range.
fn ticks(a: &Axis, r: (f64, f64)) -> Vec<(f64, bool)> {
    let mut t = Vec::new();
    if a.log {
        let (l, h) = (r.0.log10().floor() as i32, r.1.log10().ceil() as i32);
        let decades = (h - l).max(1);
        let every = (decades as f64 / 8.0).ceil().max(1.0) as i32;
        for e in l..=h {
            let base = 10f64.powi(e);
            if base >= r.0 * (1.0 - 1e-9) && base <= r.1 * (1.0 + 1e-9) && (e - l) % every == 0 {
                t.push((base, true));
            }
            if decades <= 6 {
                for k in 2..10 {
                    let v = base * k as f64;
                    if v > r.0 && v < r.1 {
                        t.push((v, false));
                    }
                }
            }
        }
        return t;
    }
    let span = r.1 - r.0;
    if !(span > 0.0 && span.is_finite()) {
        return t;
    }
    let raw = span / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| span / s <= 7.5)
        .unwrap_or(10.0 * mag);
    let mut v = (r.0 / step).ceil() * step;
    while v <= r.1 + step * 1e-9 {
        let vv = if v.abs() < step * 1e-9 { 0.0 } else { v };
        t.push((vv, true));
        v += step;
    }
    t
}

fn tick_label(a: &Axis, v: f64) -> String {
    if a.log {
        let e = v.log10().round() as i32;
        if (-2..=3).contains(&e) {
            return fmt_num(v);
        }
        return format!(r#"10<tspan dy="-6" font-size="9">{e}</tspan>"#);
    }
    fmt_num(v)
}

/// Compact number formatting for tick labels.
pub fn fmt_num(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.0e}");
    }
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn balanced(s: &str) -> bool {
        // Every <tag ...> is closed by </tag> or self-closed.
        let mut stack: Vec<String> = Vec::new();
        let mut rest = s;
        while let Some(i) = rest.find('<') {
            let j = match rest[i..].find('>') {
                Some(j) => i + j,
                None => return false,
            };
            let tag = &rest[i + 1..j];
            if let Some(name) = tag.strip_prefix('/') {
                if stack.pop().as_deref() != Some(name.trim()) {
                    return false;
                }
            } else if !tag.ends_with('/') {
                let name = tag.split_whitespace().next().unwrap_or("").to_string();
                stack.push(name);
            }
            rest = &rest[j + 1..];
        }
        stack.is_empty()
    }

    #[test]
    fn plots_are_well_formed() {
        let mut p = LinePlot::new("a < b & c", Axis::log("N"), Axis::log("err"));
        p.series.push(Series::new(
            "fem",
            vec![(1.0, 1e-1), (10.0, 1e-3), (0.0, 1.0), (f64::NAN, 1.0)],
            Mark::LinePoints,
        ));
        p.hlines.push(HLine {
            name: "cont".into(),
            y: 1e-4,
            color: "#000".into(),
        });
        let s = p.to_svg();
        assert!(s.starts_with("<svg"));
        assert!(balanced(&s), "{s}");
        assert!(s.contains("a &lt; b &amp; c"));
        let h = HeatPanel {
            title: "t".into(),
            subtitle: String::new(),
            x_label: "x".into(),
            y_label: "y".into(),
            value_label: "f1 (Hz)".into(),
            invalid_label: "infeasible".into(),
            maps: vec![HeatMap {
                caption: "z".into(),
                x: vec![0.0, 1.0],
                y: vec![0.0, 1.0],
                values: vec![Some(1.0), None, Some(2.0), Some(3.0)],
                markers: vec![(1.0, 1.0, "max".into())],
            }],
            columns: 3,
            range: None,
        };
        let s = h.to_svg();
        assert!(balanced(&s), "{s}");
        assert!(s.contains("url(#hatch)"));
    }

    #[test]
    fn colormap_ends() {
        assert_eq!(colormap(0.0), "#440154");
        assert_eq!(colormap(1.0), "#fde725");
    }
}
