//! The first natural frequency against the minimum cable tension at one pose, and the
//! least-squares fit f1 = a·√T_min.

use super::points::{check_modes, evaluate_one, valid, PointResult};
use super::{build, estimator_params, Param, ParamError, StudyError};
use crate::estimator::Tmin;
use crate::kinematics::Pose;
use crate::scene::Scene;

/// Most T_min values of one sweep.
pub const MAX_STEPS: usize = 100_000;

/// What to sweep.
#[derive(Debug, Clone, Copy)]
pub struct TminConfig {
    /// First T_min, N.
    pub from_n: f64,
    /// Last T_min, N.
    pub to_n: f64,
    /// Number of T_min values (evenly spaced, both ends included).
    pub steps: usize,
    /// Compute the end-effector mode too.
    pub ee_mode: bool,
    /// Modes kept per T_min (1 ..= `points::MAX_MODES`).
    pub modes: usize,
}

/// f1 against T_min.
#[derive(Debug, Clone)]
pub struct TminSweep {
    /// One result per T_min.
    pub points: Vec<PointResult>,
    /// Fitted a in f1 = a·√T_min, Hz/√N.
    pub a: f64,
    /// Largest |f1 − a√T|/f1 over the valid points.
    pub max_rel_residual: f64,
}

/// Least-squares coefficient a of f = a·√T through the origin: a = Σ f√T / Σ T, over the
/// finite pairs.
pub fn sqrt_fit(t_min_n: &[f64], f_hz: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (&t, &f) in t_min_n.iter().zip(f_hz) {
        if t.is_finite() && f.is_finite() && t >= 0.0 {
            num += f * t.sqrt();
            den += t;
        }
    }
    if den > 0.0 {
        num / den
    } else {
        f64::NAN
    }
}

/// The first of the sweep's bounds that breaks 0 ≤ from ≤ to ≤ t_max, 1 ≤ steps ≤
/// [`MAX_STEPS`].
fn tmin_range_error(from: f64, to: f64, steps: usize, t_max_n: f64) -> ParamError {
    if !(1..=MAX_STEPS).contains(&steps) {
        return ParamError::invalid(Param::Steps, steps, format!("must be in 1..={MAX_STEPS}"));
    }
    if !(from.is_finite() && from >= 0.0 && from <= t_max_n) {
        let rule = format!("must be within [0, t_max = {t_max_n} N]");
        return ParamError::invalid(Param::FromN, format!("{from} N"), rule);
    }
    let rule = format!("must be within [{from}, {t_max_n}] N (the lowest T_min, t_max)");
    ParamError::invalid(Param::ToN, format!("{to} N"), rule)
}

/// Compute f1 against T_min at the scene's position (one estimator, warm-started from one
/// T_min to the next).
pub fn compute(s: &Scene, cfg: &TminConfig) -> Result<TminSweep, StudyError> {
    let TminConfig {
        from_n: from,
        to_n: to,
        steps,
        ee_mode,
        modes,
    } = *cfg;
    let modes = check_modes(modes)?;
    if !(from.is_finite() && to.is_finite() && from >= 0.0 && from <= to && to <= s.t_max_n)
        || steps == 0
        || steps > MAX_STEPS
    {
        return Err(tmin_range_error(from, to, steps, s.t_max_n).into());
    }
    let ts: Vec<f64> = (0..steps)
        .map(|i| {
            if steps == 1 {
                from
            } else {
                from + (to - from) * i as f64 / (steps - 1) as f64
            }
        })
        .collect();
    let mut est = build(s, estimator_params(s, ee_mode))?;
    let pose = Pose::in_scene(s, s.ee_position_m);
    let points: Vec<PointResult> = ts
        .iter()
        .map(|&t| evaluate_one(&mut est, &pose, Tmin::Uniform(t), modes))
        .collect();
    let f: Vec<f64> = points
        .iter()
        .map(|p| valid(&p.estimate, p.estimate.f1_hz))
        .collect();
    let a = sqrt_fit(&ts, &f);
    let max_rel_residual = ts
        .iter()
        .zip(&f)
        .filter(|(_, f)| f.is_finite() && **f > 0.0)
        .map(|(t, f)| (f - a * t.sqrt()).abs() / f)
        .fold(0.0, f64::max);
    Ok(TminSweep {
        points,
        a,
        max_rel_residual,
    })
}
