//! `cablevib sweep-tmin`: the CSV and the figure of f1 against T_min with the √T_min fit.

use super::csv::{num, scene_comment, Csv};
use super::ee_curve_differs;
use super::svg::{Axis, LinePlot, Mark, Series, PALETTE};
use crate::estimator::Estimate;
use crate::scene::Scene;
use crate::study::points::valid;
use crate::study::tmin::TminSweep;

/// Segments of the drawn fit curve a·√T_min.
const FIT_CURVE_SEGMENTS: usize = 200;

/// Points measured elsewhere, drawn for comparison.
#[derive(Debug, Clone, Copy)]
pub struct Compared<'a> {
    /// Legend text.
    pub label: &'a str,
    /// (T_min in N, f in Hz).
    pub points: &'a [(f64, f64)],
}

/// The CSV: one row per T_min with the fitted value.
pub fn tmin_csv(s: &Scene, r: &TminSweep) -> String {
    let comment = format!(
        "{}, position ({}, {}, {}) m; fit f1 = {:.6} sqrt(T_min)",
        scene_comment("sweep-tmin", s),
        s.ee_position_m.x,
        s.ee_position_m.y,
        s.ee_position_m.z,
        r.a
    );
    let mut csv = Csv::new(Some(&comment), "t_min_n,status,f1_hz,ee_mode_hz,fit_hz");
    for p in &r.points {
        csv.row(&format!(
            "{},{},{},{},{}",
            p.t_min_n,
            p.estimate.status.as_str(),
            num(p.estimate.f1_hz),
            num(p.estimate.ee_mode_hz),
            num(r.a * p.t_min_n.sqrt())
        ));
    }
    csv.into_string()
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
    let ee = pts(|e| e.ee_mode_hz);
    let fine: Vec<(f64, f64)> = (0..=FIT_CURVE_SEGMENTS)
        .map(|i| {
            let t = from_n + (to_n - from_n) * i as f64 / FIT_CURVE_SEGMENTS as f64;
            (t, r.a * t.sqrt())
        })
        .collect();
    let mut plot = LinePlot::new(
        &format!("{}: first natural frequency against T_min", s.name),
        Axis::linear("T_min (N)"),
        Axis::linear("f (Hz)"),
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
    if let Some(c) = compare {
        plot.series
            .push(Series::new(c.label, c.points.to_vec(), Mark::Points).color(PALETTE[6]));
    }
    plot.to_svg()
}
