//! `cablevib sweep-tmin`: the CSV and the figure of f1 against T_min with the √T_min fit.

use super::csv::{num, num_p, scene_meta, Column, Csv};
use super::ee_curve_differs;
use super::svg::{Axis, LinePlot, Mark, Series, PALETTE};
use crate::estimator::Estimate;
use crate::scene::Scene;
use crate::study::points::{ee_mode_hz, valid};
use crate::study::tmin::TminSweep;
use serde_json::json;

/// Segments of the drawn fit curve a·√T_min.
const FIT_CURVE_SEGMENTS: usize = 200;

/// Colours of the modes f2 .. fK (the palette's entries not taken by f1, the fit, the
/// end-effector mode and the compared points), cycled.
const MODE_COLORS: [&str; 4] = [PALETTE[3], PALETTE[4], PALETTE[5], PALETTE[7]];

/// The frequency axis: linear for f1 alone, logarithmic with more modes (f2 may be tens of
/// times f1, which would flatten f1 on a linear axis).
pub(crate) fn freq_axis(modes: usize) -> Axis {
    if modes > 1 {
        Axis::log("f (Hz)")
    } else {
        Axis::linear("f (Hz)")
    }
}

/// Points measured elsewhere, drawn for comparison.
#[derive(Debug, Clone, Copy)]
pub struct Compared<'a> {
    /// Legend text.
    pub label: &'a str,
    /// (T_min in N, f in Hz).
    pub points: &'a [(f64, f64)],
}

/// The CSV: one row per T_min with the fitted value, then f2 .. fK and the smallest
/// stiffness.
pub fn tmin_csv(s: &Scene, r: &TminSweep) -> Csv {
    let modes = r.points.first().map_or(1, |p| p.n_modes);
    let mut meta = scene_meta("sweep-tmin", s);
    // The swept values are the t_min_n column, not the scene's T_min.
    meta.remove("t_min_n");
    let p = s.ee_position_m;
    meta.insert("position_m".into(), json!([p.x, p.y, p.z]));
    meta.insert("fit".into(), json!("f1 = a * sqrt(T_min), least squares"));
    meta.insert("fit_a_hz_per_sqrt_n".into(), json!(r.a));
    meta.insert("max_rel_residual".into(), json!(r.max_rel_residual));
    meta.insert("modes".into(), json!(modes));
    let mut cols = vec![
        Column::new("t_min_n", "N", "lower tension bound of every cable"),
        Column::new("status", "", "estimator status; numbers are NaN unless ok"),
        Column::new("f1_hz", "Hz", "first natural frequency (mode 1)"),
        Column::new("ee_mode_hz", "Hz", "end-effector mode"),
        Column::new("fit_hz", "Hz", "the fit a * sqrt(T_min)"),
    ];
    for j in 2..=modes {
        cols.push(Column::new(
            format!("f{j}_hz"),
            "Hz",
            format!("natural frequency of mode {j}"),
        ));
    }
    cols.push(Column::new(
        "stiffness_min_n_m",
        "N/m",
        "smallest principal value of the static end-effector stiffness (translational block)",
    ));
    let mut csv = Csv::new(cols, meta);
    for p in &r.points {
        let mut row = vec![
            p.t_min_n.to_string(),
            p.estimate.status.as_str().to_string(),
            num(p.estimate.f1_hz),
            num(ee_mode_hz(&p.estimate)),
            num(r.a * p.t_min_n.sqrt()),
        ];
        row.extend((2..=p.n_modes).map(|j| num(p.mode_hz(j))));
        row.push(num_p(p.stiffness_min_n_m, 6));
        csv.row(row);
    }
    csv
}

/// The figure: the fit from `from_n` to `to_n` N, f1, the end-effector mode where it differs
/// from f1 (with `ee_mode`), and the compared points.
pub fn tmin_svg(
    s: &Scene,
    r: &TminSweep,
    (from_n, to_n): (f64, f64),
    ee_mode: bool,
    compare: Option<Compared>,
) -> String {
    let pts = |f: fn(&Estimate) -> f64| -> Vec<(f64, f64)> {
        r.points
            .iter()
            .map(|p| (p.t_min_n, valid(&p.estimate, f(&p.estimate))))
            .collect()
    };
    let f1 = pts(|e| e.f1_hz);
    let ee = pts(ee_mode_hz);
    let fine: Vec<(f64, f64)> = (0..=FIT_CURVE_SEGMENTS)
        .map(|i| {
            let t = from_n + (to_n - from_n) * i as f64 / FIT_CURVE_SEGMENTS as f64;
            (t, r.a * t.sqrt())
        })
        .collect();
    let modes = r.points.first().map_or(1, |p| p.n_modes);
    let mut plot = LinePlot::new(
        &format!(
            "{}: {} against T_min",
            s.name,
            if modes > 1 {
                format!("the first {modes} natural frequencies")
            } else {
                "first natural frequency".into()
            }
        ),
        Axis::linear("T_min (N)"),
        freq_axis(modes),
    );
    plot.subtitle = format!(
        "{} × {} elements/cable at ({}, {}, {}) m; fit f1 = {:.5}·√T_min (max deviation {:.1e})",
        s.model.element.as_str(),
        s.model.elements_per_cable,
        s.ee_position_m.x,
        s.ee_position_m.y,
        s.ee_position_m.z,
        r.a,
        r.max_rel_residual
    );
    plot.series
        .push(Series::new(&format!("fit {:.5}·√T_min", r.a), fine, Mark::Line).color(PALETTE[1]));
    let differs = ee_curve_differs(&f1, &ee);
    plot.series
        .push(Series::new("f1 (estimator)", f1, Mark::Points).color(PALETTE[0]));
    if ee_mode && differs {
        plot.series
            .push(Series::new("end-effector mode", ee, Mark::LinePoints).color(PALETTE[2]));
    }
    for j in 2..=modes {
        let fj: Vec<(f64, f64)> = r.points.iter().map(|p| (p.t_min_n, p.mode_hz(j))).collect();
        let color = MODE_COLORS[(j - 2) % MODE_COLORS.len()];
        plot.series
            .push(Series::new(&format!("f{j}"), fj, Mark::Line).color(color));
    }
    if let Some(c) = compare {
        plot.series
            .push(Series::new(c.label, c.points.to_vec(), Mark::Points).color(PALETTE[6]));
    }
    plot.to_svg()
}
