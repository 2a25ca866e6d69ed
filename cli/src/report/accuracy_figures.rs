//! `cablevib accuracy`: the CSVs of the study and its figures (error against N, error
//! against per-cycle time, mode 3 against N).

use super::csv::{num, scene_meta, Column, Csv};
use super::svg::{Axis, HLine, LinePlot, Mark, Series, PALETTE};
use crate::scene::{ElementKind, Scene};
use crate::study::accuracy::{AccuracyReport, AccuracyRow, Mode3Row};
use crate::trajectory::CIRCLE_RADIUS_M;

/// The scene name as a file-name part: anything but ASCII letters, digits, `-` and `_`
/// becomes `_`.
pub fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Columns of the accuracy CSV: (name, unit, meaning).
const ACCURACY_COLUMNS: [(&str, &str, &str); 15] = [
    ("model", "", "model label"),
    ("element", "", "element kind"),
    (
        "n",
        "",
        "elements per cable (empty for the models without N)",
    ),
    (
        "geometric_stiffness",
        "",
        "T/l geometric stiffness included (true/false)",
    ),
    ("status", "", "estimator status at the study pose"),
    ("f1_hz", "Hz", "first natural frequency"),
    (
        "err_ref",
        "1",
        "(f1 - f1,ref) / f1,ref against the converged catenary reference",
    ),
    (
        "err_continuous",
        "1",
        "(f1 - f1,cont) / f1,cont against the continuous model",
    ),
    ("ee_mode_hz", "Hz", "end-effector mode"),
    (
        "ee_err_ref",
        "1",
        "relative error of the end-effector mode against the reference",
    ),
    ("f1_p50_ns", "ns", "median per-cycle time, f1 only"),
    ("f1_p99_ns", "ns", "99th percentile per-cycle time, f1 only"),
    (
        "ee_p50_ns",
        "ns",
        "median per-cycle time with the end-effector mode",
    ),
    (
        "ee_p99_ns",
        "ns",
        "99th percentile per-cycle time with the end-effector mode",
    ),
    (
        "evaluations_p50",
        "",
        "median D(lambda) evaluations per cycle",
    ),
];

/// The CSV of the accuracy rows of scene `s`.
pub fn accuracy_csv(s: &Scene, r: &AccuracyReport) -> Csv {
    let cols = ACCURACY_COLUMNS
        .iter()
        .map(|(n, u, d)| Column::new(*n, u, *d))
        .collect();
    let mut meta = scene_meta("accuracy", s);
    meta.insert("f1_ref_hz".into(), serde_json::json!(r.f1_ref_hz));
    meta.insert(
        "f1_continuous_hz".into(),
        serde_json::json!(r.f1_continuous_hz),
    );
    let mut csv = Csv::new(cols, meta);
    for x in &r.rows {
        csv.row([
            x.label(),
            x.element.as_str().to_string(),
            x.n.map(|n| n.to_string()).unwrap_or_default(),
            x.geometric_stiffness.to_string(),
            x.status.as_str().to_string(),
            num(x.f1_hz),
            num(x.err_ref),
            num(x.err_continuous),
            num(x.ee_mode_hz),
            num(x.ee_err_ref),
            x.f1_ns.0.to_string(),
            x.f1_ns.1.to_string(),
            x.ee_ns.0.to_string(),
            x.ee_ns.1.to_string(),
            x.evaluations.to_string(),
        ]);
    }
    csv
}

/// The CSV of the dense mode-3 study of scene `s`.
pub fn mode3_csv(s: &Scene, mode3: &[Mode3Row]) -> Csv {
    let cols = vec![
        Column::new("element", "", "element kind"),
        Column::new("n", "", "elements per cable"),
        Column::new("dof", "", "degrees of freedom of the dense model"),
        Column::new("mode1_hz", "Hz", "mode 1 of the dense reference"),
        Column::new("mode2_hz", "Hz", "mode 2 of the dense reference"),
        Column::new("mode3_hz", "Hz", "mode 3 of the dense reference"),
        Column::new("dense_seconds", "s", "time of the dense eigensolve"),
    ];
    let mut m = Csv::new(cols, scene_meta("accuracy", s));
    for x in mode3 {
        m.row([
            x.element.as_str().to_string(),
            x.n.to_string(),
            x.dof.to_string(),
            num(x.modes_hz[0]),
            num(x.modes_hz[1]),
            num(x.modes_hz[2]),
            x.seconds.to_string(),
        ]);
    }
    m
}

/// The figures of the study: error vs N, error vs per-cycle time, and mode 3 vs N (none
/// without the dense study).
pub fn accuracy_svgs(
    s: &Scene,
    r: &AccuracyReport,
    mode3: &[Mode3Row],
) -> (String, String, Option<String>) {
    (
        error_vs_n(s, r),
        cost(s, r),
        (!mode3.is_empty()).then(|| mode3_svg(s, mode3)),
    )
}

/// The rows of one element family.
fn family(r: &AccuracyReport, el: ElementKind) -> Vec<&AccuracyRow> {
    r.rows.iter().filter(|x| x.element == el).collect()
}

/// Colour of a model without N (continuous, massless with and without T/l).
fn single_model_color(row: &AccuracyRow) -> &'static str {
    match row.element {
        ElementKind::Continuous => PALETTE[3],
        _ if row.geometric_stiffness => PALETTE[4],
        _ => PALETTE[6],
    }
}

/// A curve of the error figure: legend, rows, the error drawn, mark.
type Curve<'a> = (
    &'a str,
    &'a [&'a AccuracyRow],
    fn(&AccuracyRow) -> f64,
    Mark,
);

/// |f1 error| against N, FEM and catenary; the models without N as horizontal lines.
fn error_vs_n(s: &Scene, r: &AccuracyReport) -> String {
    let fem = family(r, ElementKind::Fem);
    let cat = family(r, ElementKind::Catenary);
    let pt = |v: &[&AccuracyRow], f: &dyn Fn(&AccuracyRow) -> f64| -> Vec<(f64, f64)> {
        v.iter()
            .map(|x| (x.n.unwrap_or(0) as f64, f(x).abs()))
            .collect()
    };
    let mut p = LinePlot::new(
        &format!("{}: f1 error against elements per cable", s.name),
        Axis::log("elements per cable N"),
        Axis::log("|f1 − f1,ref| / f1,ref"),
    );
    p.subtitle = format!(
        "pose ({}, {}, {}) m, T_min {}; reference f1,ref = {:.9} Hz (catenary N = {}, Richardson)",
        s.ee_position_m.x,
        s.ee_position_m.y,
        s.ee_position_m.z,
        s.t_min_label(),
        r.f1_ref_hz,
        r.max_elements
    );
    let curves: [Curve; 3] = [
        ("FEM vs reference", &fem, |x| x.err_ref, Mark::LinePoints),
        (
            "catenary vs reference",
            &cat,
            |x| x.err_ref,
            Mark::LinePoints,
        ),
        (
            "FEM vs its continuous limit",
            &fem,
            |x| x.err_continuous,
            Mark::Dashed,
        ),
    ];
    for (k, (name, rows, f, mark)) in curves.into_iter().enumerate() {
        p.series
            .push(Series::new(name, pt(rows, &f), mark).color(PALETTE[k]));
    }
    for row in &r.rows {
        if row.n.is_none() && row.err_ref.is_finite() {
            p.hlines.push(HLine {
                name: format!("{}: {:.1e}", row.label(), row.err_ref.abs()),
                y: row.err_ref.abs(),
                color: single_model_color(row).into(),
            });
        }
    }
    p.to_svg()
}

/// |f1 error| against the median per-cycle time (f1 only), every model.
fn cost(s: &Scene, r: &AccuracyReport) -> String {
    let mut q = LinePlot::new(
        &format!("{}: what accuracy costs", s.name),
        Axis::log("median per-cycle time of the real-time path, f1 only (µs)"),
        Axis::log("|f1 − f1,ref| / f1,ref"),
    );
    q.subtitle = format!(
        "{} cycles along the r = {} m circle per model; error at ({}, {}, {}) m, T_min {}",
        "timed",
        CIRCLE_RADIUS_M,
        s.ee_position_m.x,
        s.ee_position_m.y,
        s.ee_position_m.z,
        s.t_min_label()
    );
    // N labelled next to their points: the ends and a few in between.
    let lab_ns = [1usize, 4, 10, 40, r.max_elements];
    let scatter = |v: &[&AccuracyRow]| -> (Vec<(f64, f64)>, Vec<Option<String>>) {
        v.iter()
            .filter(|x| x.f1_ns.0 > 0)
            .map(|x| {
                (
                    (x.f1_ns.0 as f64 / 1e3, x.err_ref.abs()),
                    x.n.filter(|n| lab_ns.contains(n)).map(|n| format!("N={n}")),
                )
            })
            .unzip()
    };
    for (k, (name, el)) in [
        ("FEM", ElementKind::Fem),
        ("catenary", ElementKind::Catenary),
    ]
    .into_iter()
    .enumerate()
    {
        let (a, la) = scatter(&family(r, el));
        q.series.push(
            Series::new(name, a, Mark::Points)
                .color(PALETTE[k])
                .labels(la),
        );
    }
    for row in r.rows.iter().filter(|x| x.n.is_none()) {
        if row.f1_ns.0 > 0 && row.err_ref.is_finite() {
            q.series.push(
                Series::new(
                    &row.label(),
                    vec![(row.f1_ns.0 as f64 / 1e3, row.err_ref.abs())],
                    Mark::Points,
                )
                .color(single_model_color(row)),
            );
        }
    }
    q.to_svg()
}

/// Mode 3 against N from the dense study, FEM and catenary.
fn mode3_svg(s: &Scene, mode3: &[Mode3Row]) -> String {
    let mut m = LinePlot::new(
        &format!(
            "{}: convergence of mode 3 with the number of elements",
            s.name
        ),
        Axis::linear("elements per cable N"),
        Axis::linear("frequency of mode 3 (Hz)"),
    );
    m.subtitle = format!(
        "dense reference (all modes), pose ({}, {}, {}) m, T_min {}",
        s.ee_position_m.x,
        s.ee_position_m.y,
        s.ee_position_m.z,
        s.t_min_label()
    );
    for (k, el) in [ElementKind::Fem, ElementKind::Catenary].iter().enumerate() {
        let pts: Vec<(f64, f64)> = mode3
            .iter()
            .filter(|x| x.element == *el)
            .map(|x| (x.n as f64, x.modes_hz[2]))
            .collect();
        m.series.push(
            Series::new(&format!("{} element", el.as_str()), pts, Mark::LinePoints)
                .color(PALETTE[k]),
        );
    }
    m.to_svg()
}
