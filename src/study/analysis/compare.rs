//! The analysis's dense comparison (`compare_dense`): the structured K modes against the dense spectrum of the
//! same models, both timed in one process.

use super::{dense_bound, AnalyzeError, DenseComparison};
use crate::estimator::Estimator;
use crate::modal::Mode;
use std::time::Instant;

/// The structured solve is repeated until this much time has passed (s) ...
const REPEAT_SECONDS: f64 = 0.2;
/// ... or this many times, and the median is reported (one solve is far below the timer's
/// resolution of a shared machine's noise).
const REPEAT_MAX: usize = 1001;

/// Time the structured K modes (median of repeats) and the dense solve of the same models,
/// and compare their eigenvalues and cluster participations.
pub(super) fn compare(
    est: &mut Estimator,
    modes: &[Mode],
) -> Result<DenseComparison, AnalyzeError> {
    let k = modes.len();
    let mut out = vec![Mode::default(); k];
    let mut times = Vec::new();
    let start = Instant::now();
    while times.len() < REPEAT_MAX && start.elapsed().as_secs_f64() < REPEAT_SECONDS {
        let t0 = Instant::now();
        est.modes(k, &mut out)
            .map_err(|e| AnalyzeError::Solve(e.to_string()))?;
        times.push(t0.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let structured_seconds = times[times.len() / 2];
    let t0 = Instant::now();
    let d = est
        .dense_modes(true)
        .map_err(|e| AnalyzeError::Solve(e.to_string()))?;
    let dense_seconds = t0.elapsed().as_secs_f64();
    let (mut worst, mut bound) = (0.0f64, f64::NAN);
    for (i, m) in modes.iter().enumerate().take(d.lambda.len()) {
        let rel = (m.lambda - d.lambda[i]).abs() / d.lambda[i].abs();
        if !(rel <= worst) {
            worst = rel;
            bound = dense_bound(d.lambda[i], d.lambda_max);
        }
    }
    let mut pdiff = 0.0f64;
    let mut i = 0;
    while i < modes.len() {
        // Only whole clusters: a sum over part of a degenerate eigenspace depends on the
        // basis the dense solver happened to pick.
        let end = (modes[i].cluster_start + modes[i].multiplicity as usize).max(i + 1);
        if end > modes.len().min(d.ee_participation.len()) {
            break;
        }
        let s: f64 = modes[i..end].iter().map(|m| m.ee_participation).sum();
        let sd: f64 = d.ee_participation[i..end].iter().sum();
        pdiff = pdiff.max((s - sd).abs());
        i = end.max(i + 1);
    }
    Ok(DenseComparison {
        structured_seconds,
        dense_seconds,
        speedup: dense_seconds / structured_seconds,
        max_rel_diff_lambda: worst,
        dense_bound_there: bound,
        max_abs_diff_cluster_participation: pdiff,
    })
}
