//! `cablevib sag-compare`: the CSV of the chord and the sagged model along a line, and the
//! four-panel figure (f1; the softest static stiffness, log; the largest end-effector-end
//! tension; the largest Irvine λ², log).
//!
//! Numbers in the CSV are written in the shortest form that reads back to the same f64
//! (`{:e}`), so a row equals `cablevib analyze --json --position … --sag …` bit for bit.

use super::csv::{scene_meta, Column, Csv};
use super::svg::{escape, header, Axis, LinePlot, Mark, Series, PALETTE};
use crate::scene::Scene;
use crate::service::stats::StatusHistogram;
use crate::study::sag_compare::{ComparePoint, ModelPoint, SagCompare};
use serde_json::json;
use std::fmt::Write as _;

/// Panels per row of the figure.
const PANEL_COLUMNS: usize = 2;
/// Height of the figure's own title band above the panels, px.
const TITLE_BAND_PX: f64 = 34.0;
/// Size of one panel, px (two fit side by side on a page).
const PANEL_SIZE_PX: (f64, f64) = (560.0, 380.0);
/// Colours: chord model, sagged model.
const CHORD_COLOR: &str = PALETTE[0];
const SAG_COLOR: &str = PALETTE[1];

/// A finite value as its shortest round-trip form (reads back bit for bit), else `NaN`.
pub fn exact(x: f64) -> String {
    if x.is_finite() {
        format!("{x:e}")
    } else {
        "NaN".into()
    }
}

/// The columns of one model (`prefix` = `chord` or `sag`) for `n` cables.
fn model_columns(prefix: &str, what: &str, n: usize) -> Vec<Column> {
    let c = |name: &str, unit: &'static str, d: &str| {
        Column::new(format!("{prefix}_{name}"), unit, format!("{what}: {d}"))
    };
    let mut cols =
        vec![
        c("status", "", "estimator status; its numbers are NaN unless ok"),
        c("f1_hz", "Hz", "first natural frequency (analyze's frequencies_hz[0])"),
        c(
            "stiffness_min_n_m",
            "N/m",
            "smallest principal value of the static end-effector stiffness (translational block)",
        ),
        c("tension_max_n", "N", "largest cable tension at the end-effector end"),
        c("tension_min_n", "N", "smallest tension along any cable"),
    ];
    for i in 1..=n {
        cols.push(c(
            &format!("tension{i}_n"),
            "N",
            &format!("cable {i}'s tension at the end-effector end (analyze's tensions_n)"),
        ));
    }
    cols
}

fn model_fields(m: &ModelPoint) -> Vec<String> {
    let mut row = vec![
        m.status.as_str().to_string(),
        exact(m.f1_hz),
        exact(m.stiffness_min_n_m),
        exact(m.tension_max_n()),
        exact(m.tension_min_n),
    ];
    row.extend(m.tensions_n.iter().map(|&t| exact(t)));
    row
}

/// The CSV: one row per pose, offset then position, the chord model's columns (`chord_…`),
/// the sagged model's (`sag_…`), then the sagged cables' largest λ² and sag.
pub fn sag_compare_csv(s: &Scene, r: &SagCompare) -> Csv {
    let mut meta = scene_meta("sag-compare", s);
    let p = s.ee_position_m;
    meta.insert("position_m".into(), json!([p.x, p.y, p.z]));
    meta.insert("axis".into(), json!(r.axis_name()));
    meta.insert("span_m".into(), json!([r.span_m.lo, r.span_m.hi]));
    meta.insert(
        "models".into(),
        json!("chord: sag = false; sag: sag = true; same element kind and count"),
    );
    let n = s.n_cables();
    let mut cols = vec![
        Column::new(
            "offset_m",
            "m",
            "offset from the scene's position along the axis",
        ),
        Column::new("x_m", "m", "end-effector position x"),
        Column::new("y_m", "m", "end-effector position y"),
        Column::new("z_m", "m", "end-effector position z"),
    ];
    cols.extend(model_columns("chord", "chord model", n));
    cols.extend(model_columns("sag", "sagged model", n));
    cols.push(Column::new(
        "sag_irvine_lambda2_max",
        "1",
        "sagged model: largest Irvine λ² over the cables",
    ));
    cols.push(Column::new(
        "sag_sag_max_m",
        "m",
        "sagged model: largest distance of a cable from its chord",
    ));
    let mut csv = Csv::new(cols, meta);
    for q in &r.points {
        let x = q.position_m;
        let mut row = vec![exact(q.offset_m), exact(x.x), exact(x.y), exact(x.z)];
        row.extend(model_fields(&q.chord));
        row.extend(model_fields(&q.sag));
        row.push(exact(q.sag.irvine_lambda2_max));
        row.push(exact(q.sag.sag_max_m));
        csv.row(row);
    }
    csv
}

/// How many poses of each status a model has.
pub fn statuses(r: &SagCompare, pick: fn(&ComparePoint) -> &ModelPoint) -> StatusHistogram {
    let mut h = StatusHistogram::default();
    for q in &r.points {
        h.record(pick(q).status);
    }
    h
}

/// (offset, value) of each pose, NaN where the model has no answer (a gap in the line).
fn curve(
    r: &SagCompare,
    pick: fn(&ComparePoint) -> &ModelPoint,
    f: fn(&ModelPoint) -> f64,
) -> Vec<(f64, f64)> {
    r.points
        .iter()
        .map(|q| {
            let m = pick(q);
            (q.offset_m, if m.is_ok() { f(m) } else { f64::NAN })
        })
        .collect()
}

/// One panel: the chord and the sagged curve of `f` on a `y` axis.
fn panel(r: &SagCompare, title: &str, y: Axis, f: fn(&ModelPoint) -> f64) -> String {
    let x = Axis::linear(&format!("offset along {} (m)", r.axis_name()));
    let mut plot = LinePlot::new(title, x, y);
    (plot.width, plot.height) = PANEL_SIZE_PX;
    let chord = curve(r, |q| &q.chord, f);
    let sag = curve(r, |q| &q.sag, f);
    plot.series
        .push(Series::new("chord (sag = false)", chord, Mark::LinePoints).color(CHORD_COLOR));
    plot.series
        .push(Series::new("sagged (sag = true)", sag, Mark::LinePoints).color(SAG_COLOR));
    plot.to_svg()
}

/// The λ² panel (the sagged model only: the chord model has no sag).
fn lambda2_panel(r: &SagCompare) -> String {
    let x = Axis::linear(&format!("offset along {} (m)", r.axis_name()));
    let mut plot = LinePlot::new(
        "largest Irvine λ² over the cables (sagged model)",
        x,
        Axis::log("λ²"),
    );
    (plot.width, plot.height) = PANEL_SIZE_PX;
    let l2 = curve(r, |q| &q.sag, |m| m.irvine_lambda2_max);
    plot.series
        .push(Series::new("sagged (sag = true)", l2, Mark::LinePoints).color(SAG_COLOR));
    plot.to_svg()
}

/// Width and height of a standalone SVG document from its root's attributes, px.
fn svg_size(doc: &str) -> (f64, f64) {
    let attr = |name: &str| -> f64 {
        let key = format!(" {name}=\"");
        doc.find(&key)
            .and_then(|i| {
                let rest = &doc[i + key.len()..];
                rest.find('"').and_then(|j| rest[..j].parse().ok())
            })
            .unwrap_or(0.0)
    };
    (attr("width"), attr("height"))
}

/// Standalone SVG documents laid out in a grid of `columns` under a title: each becomes a
/// nested `<svg>` placed at its cell (nested viewports are plain SVG 1.1).
fn compose(title: &str, subtitle: &str, panels: &[String], columns: usize) -> String {
    let sizes: Vec<(f64, f64)> = panels.iter().map(|p| svg_size(p)).collect();
    let cell_w = sizes.iter().map(|s| s.0).fold(0.0, f64::max);
    let cell_h = sizes.iter().map(|s| s.1).fold(0.0, f64::max);
    let rows = panels.len().div_ceil(columns.max(1));
    let band = TITLE_BAND_PX + if subtitle.is_empty() { 0.0 } else { 16.0 };
    let (w, h) = (cell_w * columns as f64, band + cell_h * rows as f64);
    let mut o = header(w, h);
    let _ = writeln!(
        o,
        "<text x=\"{:.1}\" y=\"22\" text-anchor=\"middle\" font-size=\"17\" font-weight=\"bold\">{}</text>",
        w / 2.0,
        escape(title)
    );
    if !subtitle.is_empty() {
        let _ = writeln!(
            o,
            "<text x=\"{:.1}\" y=\"42\" text-anchor=\"middle\" font-size=\"12\" fill=\"#444\">{}</text>",
            w / 2.0,
            escape(subtitle)
        );
    }
    for (k, p) in panels.iter().enumerate() {
        let (x, y) = (
            (k % columns) as f64 * cell_w,
            band + (k / columns) as f64 * cell_h,
        );
        let placed = p.replacen("<svg ", &format!("<svg x=\"{x:.0}\" y=\"{y:.0}\" "), 1);
        o.push_str(&placed);
    }
    o.push_str("</svg>\n");
    o
}

/// The figure: four panels, chord model and sagged model over the line's offset; a pose
/// where a model has no answer is a gap in its curve (the subtitle counts the statuses).
pub fn sag_compare_svg(s: &Scene, r: &SagCompare) -> String {
    let panels = [
        panel(
            r,
            "first natural frequency f1",
            Axis::linear("f1 (Hz)"),
            |m| m.f1_hz,
        ),
        panel(
            r,
            "softest static stiffness k_min",
            Axis::log("k_min (N/m)"),
            |m| m.stiffness_min_n_m,
        ),
        panel(
            r,
            "largest tension at the end-effector end",
            Axis::linear("T (N)"),
            ModelPoint::tension_max_n,
        ),
        lambda2_panel(r),
    ];
    let p = s.ee_position_m;
    let title = format!(
        "{}: chord vs sagged cables along {} through ({}, {}, {}) m",
        s.name,
        r.axis_name(),
        p.x,
        p.y,
        p.z
    );
    let subtitle = format!(
        "{} × {} elements/cable, T_min {}; chord: {}; sagged: {}",
        s.model.element.as_str(),
        s.model.elements_per_cable,
        s.t_min_label(),
        statuses(r, |q| &q.chord).summary(),
        statuses(r, |q| &q.sag).summary()
    );
    compose(&title, &subtitle, &panels, PANEL_COLUMNS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_reads_back_bit_for_bit() {
        for x in [0.1 + 0.2, 88426.14503075434, 1e-300, -3.0] {
            assert_eq!(exact(x).parse::<f64>().unwrap().to_bits(), x.to_bits());
        }
        assert_eq!(exact(f64::NAN), "NaN");
    }

    #[test]
    fn panels_are_placed_in_a_grid() {
        let a = header(100.0, 50.0) + "</svg>\n";
        let doc = compose("t", "", &[a.clone(), a.clone(), a], 2);
        assert_eq!(svg_size(&doc), (200.0, TITLE_BAND_PX + 100.0));
        assert!(doc.contains("<svg x=\"100\" y=\"34\" "));
        assert!(doc.contains("<svg x=\"0\" y=\"84\" "));
    }
}
