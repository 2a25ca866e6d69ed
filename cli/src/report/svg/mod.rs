//! A tiny, dependency-free SVG writer for the offline figures: line and scatter plots with
//! linear or logarithmic axes and a legend ([`LinePlot`]), and heat maps with a colour bar,
//! one or several panels sharing one colour scale ([`HeatPanel`]).
//!
//! Everything renders to a `String` holding one standalone `<svg>` document; text is
//! XML-escaped. Cells without a value (infeasible or invalid points) are drawn grey and
//! hatched, never left out, so a reader sees where the model has no answer.
//!
//! | module | what |
//! |---|---|
//! | this one | the document (header, title, wrapped subtitle), escaping, number formatting |
//! | [`axis`] | linear and log axes, the data-to-pixel mapping, ticks |
//! | [`line_plot`] | [`LinePlot`] |
//! | [`modes`] | the mode-shape figure (axonometric panels) |
//! | [`heat_map`] | [`HeatPanel`], [`HeatMap`], the colour map |
//! | [`overlay`] | over a heat map: contour lines (marching squares), the frame, the anchors |

pub mod axis;
pub mod heat_map;
mod legend;
pub mod line_plot;
pub mod modes;
pub mod overlay;

pub use axis::Axis;
pub use heat_map::{colormap, HeatMap, HeatPanel};
pub use line_plot::{HLine, LinePlot, Mark, Series};

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

/// Letters written with a subscript after `_` (`T_min`, `k_min`, `f1,ref`): a whitelist,
/// so that names with underscores (files, scenes) keep theirs.
const SUBSCRIPT_WORDS: [&str; 5] = ["min", "max", "ref", "cont", "ee"];
/// Tails that stay in the subscript after `fN` (`f1,ref` → f with subscript "1,ref").
const SUBSCRIPT_TAILS: [&str; 2] = [",ref", ",cont"];
/// A subscript's size and drop, fractions of the text's font size.
const SUB_SIZE: f64 = 0.75;
const SUB_DROP: f64 = 0.25;

/// Escape `s` for SVG text of `font_px` and write its subscripts as subscripts: a lone
/// letter followed by `_` and one of `SUBSCRIPT_WORDS` (`T_min` → T with subscript min),
/// and `f` followed by digits (`f1` → f with subscript 1, `f1,ref` keeps ",ref" in it), each
/// standing alone (not inside a longer word). Subscripts are `tspan`s shifted with `dy` and
/// shifted back after, which every SVG renderer supports.
pub fn rich(s: &str, font_px: f64) -> String {
    let c: Vec<char> = s.chars().collect();
    let mut runs: Vec<(String, bool)> = vec![(String::new(), false)];
    let mut i = 0;
    while i < c.len() {
        let alone = i == 0 || !(c[i - 1].is_alphanumeric() || c[i - 1] == '_');
        match subscript_at(&c, i).filter(|_| alone && c[i].is_ascii_alphabetic()) {
            Some(end) => {
                let skip = usize::from(c[i + 1] == '_');
                runs.push((c[i + 1 + skip..end].iter().collect(), true));
                if let Some(r) = runs.iter_mut().rev().nth(1) {
                    r.0.push(c[i]);
                }
                runs.push((String::new(), false));
                i = end;
            }
            None => {
                if let Some(r) = runs.last_mut() {
                    r.0.push(c[i]);
                }
                i += 1;
            }
        }
    }
    let (size, drop) = (font_px * SUB_SIZE, font_px * SUB_DROP);
    let mut o = String::new();
    let mut shifted = false;
    for (text, sub) in runs.iter().filter(|r| !r.0.is_empty()) {
        let t = escape(text);
        if *sub {
            let _ = write!(
                o,
                r#"<tspan dy="{drop:.1}" font-size="{size:.1}">{t}</tspan>"#
            );
        } else if shifted {
            let _ = write!(o, r#"<tspan dy="{:.1}">{t}</tspan>"#, -drop);
        } else {
            o.push_str(&t);
        }
        shifted = *sub;
    }
    o
}

/// The end of the subscript starting after the letter at `i` (module docs of [`rich`]).
fn subscript_at(c: &[char], i: usize) -> Option<usize> {
    let ends_word = |j: usize| j >= c.len() || !(c[j].is_alphanumeric() || c[j] == '_');
    let rest: String = c[i + 1..].iter().collect();
    if let Some(r) = rest.strip_prefix('_') {
        let w = SUBSCRIPT_WORDS.iter().find(|w| r.starts_with(**w))?;
        let end = i + 2 + w.len();
        return ends_word(end).then_some(end);
    }
    if c[i] != 'f' {
        return None;
    }
    let digits = rest.chars().take_while(char::is_ascii_digit).count();
    if digits == 0 {
        return None;
    }
    let mut end = i + 1 + digits;
    let after: String = c[end..].iter().collect();
    if let Some(t) = SUBSCRIPT_TAILS.iter().find(|t| after.starts_with(**t)) {
        end += t.len();
    }
    ends_word(end).then_some(end)
}

pub(crate) fn header(w: f64, h: f64) -> String {
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

pub(crate) fn subtitle_lines(w: f64, sub: &str) -> Vec<String> {
    if sub.is_empty() {
        return Vec::new();
    }
    wrap(sub, ((w - 20.0) / 6.6).max(20.0) as usize)
}

/// Title and subtitle; returns the height they take (px).
pub(crate) fn title(o: &mut String, w: f64, t: &str, sub: &str) -> f64 {
    let _ = writeln!(
        o,
        r#"<text x="{:.1}" y="24" font-size="16" font-weight="bold" text-anchor="middle">{}</text>"#,
        w / 2.0,
        rich(t, 16.0)
    );
    let lines = subtitle_lines(w, sub);
    for (i, l) in lines.iter().enumerate() {
        let _ = writeln!(
            o,
            r##"<text x="{:.1}" y="{:.0}" font-size="12" fill="#333" text-anchor="middle">{}</text>"##,
            w / 2.0,
            42.0 + 15.0 * i as f64,
            rich(l, 12.0)
        );
    }
    40.0 + 15.0 * lines.len() as f64
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
            frame: Some([-2.0, -2.0, 2.0, 2.0]),
            anchors: vec![(-2.0, -2.0), (2.0, 2.0)],
            contours: true,
        };
        let s = h.to_svg();
        assert!(balanced(&s), "{s}");
        assert!(s.contains("url(#hatch)"));
    }

    #[test]
    fn subscripts() {
        let sub = |t: &str| format!(r#"<tspan dy="3.0" font-size="9.0">{t}</tspan>"#);
        let back = |t: &str| format!(r#"<tspan dy="-3.0">{t}</tspan>"#);
        assert_eq!(
            rich("T_min (N)", 12.0),
            format!("T{}{}", sub("min"), back(" (N)"))
        );
        assert_eq!(rich("f1", 12.0), format!("f{}", sub("1")));
        assert_eq!(
            rich("|f1 − f1,ref|", 12.0),
            format!(
                "|f{}{}{}{}",
                sub("1"),
                back(" − f"),
                sub("1,ref"),
                back("|")
            )
        );
        // Inside words, unknown subscripts and escaping: left as they are.
        assert_eq!(
            rich("fig12 my_min x_y a<b", 12.0),
            "fig12 my_min x_y a&lt;b"
        );
        assert_eq!(rich("f1x", 12.0), "f1x");
    }

    #[test]
    fn colormap_ends() {
        assert_eq!(colormap(0.0), "#440154");
        assert_eq!(colormap(1.0), "#fde725");
    }
}
