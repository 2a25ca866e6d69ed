//! `cablevib calibrate --svg`: measured against model frequency, before and after the fit,
//! with the line model = measured.

use super::svg::{Axis, LinePlot, Mark, Series, PALETTE};
use crate::calibration::Report;

/// The figure of `r`.
pub fn calibration_svg(r: &Report) -> String {
    let mut p = LinePlot::new(
        &format!(
            "Calibration of {}: model against measured frequency",
            r.scene
        ),
        Axis::linear("measured f (Hz)"),
        Axis::linear("model f (Hz)"),
    );
    p.subtitle = format!(
        "{} modes at {} poses, model {}; χ²/dof {:.3} before, {:.3} after: {}",
        r.frequencies,
        r.poses,
        r.model,
        r.chi2_per_dof_before,
        r.chi2_per_dof,
        if r.fits {
            "fits within the stated noise"
        } else {
            "does not fit the stated noise"
        }
    );
    let before: Vec<(f64, f64)> = r
        .residuals
        .iter()
        .map(|x| (x.measured_hz, x.model_before_hz))
        .collect();
    let after: Vec<(f64, f64)> = r
        .residuals
        .iter()
        .map(|x| (x.measured_hz, x.model_after_hz))
        .collect();
    let (lo, hi) = before
        .iter()
        .chain(&after)
        .flat_map(|&(a, b)| [a, b])
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if lo.is_finite() {
        p.series.push(
            Series::new("model = measured", vec![(lo, lo), (hi, hi)], Mark::Dashed)
                .color("#888888"),
        );
    }
    p.series
        .push(Series::new("before (nominal parameters)", before, Mark::Points).color(PALETTE[1]));
    p.series
        .push(Series::new("after (calibrated)", after, Mark::Points).color(PALETTE[0]));
    p.to_svg()
}
