//! What accuracy costs in time: f1 and the end-effector mode of every model the scene can
//! use (massless springs, the continuous string, FEM and catenary elements for a range of N)
//! against a Richardson-extrapolated catenary reference, with per-cycle timings along the
//! circle; and the dense convergence of mode 3 against N (paper Figs. 5 and 10).

use super::points::{ee_mode_hz, valid};
use super::{build, estimator_params, Param, ParamError, StudyError};
use crate::estimator::{reference_analysis, Estimate, Status, Tmin};
use crate::kinematics::Pose;
use crate::modal::lambda_to_hz;
use crate::scene::{ElementKind, Scene};
use crate::stats::percentile;
use crate::trajectory::circle_pose;
use std::time::Instant;

/// Most elements per cable of the study (the dense mode-3 study grows as N³).
pub const MAX_ELEMENTS: usize = 2000;

/// What to run.
#[derive(Debug, Clone)]
pub struct AccuracyConfig {
    /// Elements per cable of the FEM and catenary models (see [`element_counts`]).
    pub element_counts: Vec<usize>,
    /// Timed cycles per model along the circle (f1 only and with the end-effector mode).
    pub cycles: usize,
    /// Timing rounds over all models; each model reports its fastest round's median.
    pub rounds: usize,
    /// Period of one revolution of the timing circle, s (poses 1 ms apart).
    pub period_s: f64,
}

impl AccuracyConfig {
    /// The study for N up to `max_elements` (see [`element_counts`]); checks the values
    /// (they come from the command line: the messages name its options).
    pub fn new(
        max_elements: usize,
        all_n: bool,
        cycles: usize,
        rounds: usize,
        period_s: f64,
    ) -> Result<AccuracyConfig, StudyError> {
        if max_elements == 0 || max_elements > MAX_ELEMENTS {
            let rule = format!("must be in 1..={MAX_ELEMENTS}");
            return Err(ParamError::invalid(Param::MaxElements, max_elements, rule).into());
        }
        if !(period_s.is_finite() && period_s > 0.0) {
            return Err(ParamError::invalid(Param::PeriodS, period_s, "must be > 0").into());
        }
        Ok(AccuracyConfig {
            element_counts: element_counts(max_elements, all_n),
            cycles,
            rounds,
            period_s,
        })
    }
}

/// The N of the dense mode-3 study: the standard counts up to `dense_max` (none for 0).
pub fn dense_element_counts(dense_max: usize) -> Vec<usize> {
    element_counts(dense_max.max(1), false)
        .into_iter()
        .filter(|&n| dense_max > 0 && n <= dense_max)
        .collect()
}

/// The element counts of the study: 1, 2, 3, 4, 5, 6, 8, …, 80 up to `max` (or every N
/// up to `max` with `all`), plus max/2 and max (the reference's extrapolation points).
pub fn element_counts(max: usize, all: bool) -> Vec<usize> {
    const LIST: [usize; 17] = [1, 2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 25, 32, 40, 50, 64, 80];
    let mut v: Vec<usize> = if all {
        (1..=max).collect()
    } else {
        LIST.iter().copied().filter(|&n| n <= max).collect()
    };
    for extra in [max / 2, max] {
        if extra >= 1 && !v.contains(&extra) {
            v.push(extra);
        }
    }
    v.sort_unstable();
    v
}
/// One model of the accuracy study.
#[derive(Debug, Clone)]
pub struct AccuracyRow {
    /// Element kind.
    pub element: ElementKind,
    /// Elements per cable (FEM, catenary), else `None`.
    pub n: Option<usize>,
    /// Transverse geometric stiffness T/l on.
    pub geometric_stiffness: bool,
    /// Status at the study pose.
    pub status: Status,
    /// Why, when not ok.
    pub reason: String,
    /// f1 at the study pose, Hz.
    pub f1_hz: f64,
    /// End-effector mode at the study pose, Hz.
    pub ee_mode_hz: f64,
    /// (f1 − f1_ref)/f1_ref.
    pub err_ref: f64,
    /// (f1 − f1_continuous)/f1_continuous.
    pub err_continuous: f64,
    /// (f_ee − f_ee,ref)/f_ee,ref.
    pub ee_err_ref: f64,
    /// Per-cycle time along the circle, f1 only: median and p99, ns.
    pub f1_ns: (u64, u64),
    /// Per-cycle time with the end-effector mode: median and p99, ns.
    pub ee_ns: (u64, u64),
    /// Median D(λ) evaluations per cycle (with the end-effector mode).
    pub evaluations: u64,
}

impl AccuracyRow {
    /// A short model name ("fem N=10", "massless, no geometric stiffness", ...).
    pub fn label(&self) -> String {
        match (self.element, self.n) {
            (ElementKind::Massless, _) if !self.geometric_stiffness => {
                "massless springs, axial only".into()
            }
            (ElementKind::Massless, _) => "massless springs + T/l".into(),
            (ElementKind::Continuous, _) => "continuous (N → ∞)".into(),
            (k, Some(n)) => format!("{} N={n}", k.as_str()),
            (k, None) => k.as_str().into(),
        }
    }
}

/// The whole accuracy study of one scene and pose.
#[derive(Debug, Clone)]
pub struct AccuracyReport {
    /// Rows: massless ×2, continuous, FEM per N, catenary per N.
    pub rows: Vec<AccuracyRow>,
    /// Reference f1: catenary Richardson-extrapolated from N = max/2 and max, Hz.
    pub f1_ref_hz: f64,
    /// Reference end-effector mode, the same way, Hz.
    pub ee_ref_hz: f64,
    /// The continuous limit of the straight-cable FEM, Hz.
    pub f1_continuous_hz: f64,
    /// Observed convergence order of the catenary f1 from N = max/4, max/2, max.
    pub catenary_order: f64,
    /// Largest N.
    pub max_elements: usize,
}

fn timing(
    s: &Scene,
    ee_mode: bool,
    cycles: usize,
    period_s: f64,
) -> Result<((u64, u64), u64), StudyError> {
    if cycles == 0 {
        return Ok(((0, 0), 0));
    }
    let mut est = build(s, estimator_params(s, ee_mode))?;
    est.update(&circle_pose(s, 0, period_s), Tmin::Scene);
    let mut ns = Vec::with_capacity(cycles);
    let mut ev = Vec::with_capacity(cycles);
    let mut ok = 0usize;
    for k in 1..=cycles {
        let pose = circle_pose(s, k, period_s);
        let t0 = Instant::now();
        let e = est.update(&pose, Tmin::Scene);
        ns.push(t0.elapsed().as_nanos() as u64);
        ev.push(e.eigen_evaluations as u64);
        ok += e.is_ok() as usize;
    }
    if ok == 0 {
        return Ok(((0, 0), 0));
    }
    ns.sort_unstable();
    ev.sort_unstable();
    Ok((
        (percentile(&ns, 0.5), percentile(&ns, 0.99)),
        percentile(&ev, 0.5),
    ))
}

fn at_pose(s: &Scene) -> Result<Estimate, StudyError> {
    let mut est = build(s, estimator_params(s, true))?;
    let e = *est.update(&Pose::in_scene(s, s.ee_position_m), Tmin::Scene);
    if e.is_ok() {
        return Ok(e);
    }
    // The end-effector mode may be what failed; f1 alone may still be valid.
    let mut est = build(s, estimator_params(s, false))?;
    let e1 = *est.update(&Pose::in_scene(s, s.ee_position_m), Tmin::Scene);
    Ok(if e1.is_ok() { e1 } else { e })
}

/// The models of the study: massless springs without and with T/l, the continuous string,
/// then FEM and catenary for every N in `ns`.
fn models(base: &Scene, ns: &[usize]) -> Vec<Scene> {
    let mut models: Vec<Scene> = Vec::new();
    let mut ml = base.with_model(ElementKind::Massless, 1);
    ml.model.geometric_stiffness = false;
    models.push(ml);
    models.push(base.with_model(ElementKind::Massless, 1));
    models.push(base.with_model(ElementKind::Continuous, 1));
    for &n in ns {
        models.push(base.with_model(ElementKind::Fem, n));
    }
    for &n in ns {
        models.push(base.with_model(ElementKind::Catenary, n));
    }
    models
}

/// Best round of a model: ((p50, p99) f1 only, (p50, p99) with EE mode, evaluations).
type Best = ((u64, u64), (u64, u64), u64);

/// `cfg.rounds` rounds, each timing every model in turn; the best round per model.
fn best_timings(models: &[Scene], cfg: &AccuracyConfig) -> Result<Vec<Option<Best>>, StudyError> {
    let (cycles, period_s) = (cfg.cycles, cfg.period_s);
    let mut best: Vec<Option<Best>> = vec![None; models.len()];
    for _ in 0..cfg.rounds.max(1) {
        for (k, s) in models.iter().enumerate() {
            let (f1, _) = timing(s, false, cycles, period_s)?;
            let (ee, ev) = timing(s, true, cycles, period_s)?;
            let b = best[k].get_or_insert((f1, ee, ev));
            if f1.0 > 0 && f1.0 < b.0 .0 {
                b.0 = f1;
            }
            if ee.0 > 0 && ee.0 < b.1 .0 {
                b.1 = ee;
                b.2 = ev;
            }
        }
    }
    Ok(best)
}

/// The row of model `s` (errors still NaN) from its estimate at the pose and its timings.
fn row(s: &Scene, b: Option<Best>) -> Result<AccuracyRow, StudyError> {
    let e = at_pose(s)?;
    let (f1_ns, ee_ns, evals) = b.unwrap_or_default();
    Ok(AccuracyRow {
        element: s.model.element,
        n: s.model
            .element
            .is_discrete()
            .then_some(s.model.elements_per_cable),
        geometric_stiffness: s.model.geometric_stiffness,
        status: e.status,
        reason: e.error.map(|x| x.to_string()).unwrap_or_default(),
        f1_hz: valid(&e, e.f1_hz),
        ee_mode_hz: ee_mode_hz(&e),
        err_ref: f64::NAN,
        err_continuous: f64::NAN,
        ee_err_ref: f64::NAN,
        f1_ns,
        ee_ns,
        evaluations: evals,
    })
}

/// Run the study (no files): f1 and the end-effector mode at the scene's pose and T_min
/// for every model, errors against the reference, and per-cycle timings along the circle.
///
/// Timings: `rounds` rounds, each timing every model for `cycles` cycles in turn; a
/// model reports the round with the smallest median (its p99 from the same round), so
/// that a burst of unrelated load on the machine does not land on one model only.
pub fn compute(base: &Scene, cfg: &AccuracyConfig) -> Result<AccuracyReport, StudyError> {
    let ns = &cfg.element_counts;
    let max = ns.iter().copied().max().unwrap_or(1);
    let models = models(base, ns);
    let best = best_timings(&models, cfg)?;
    let mut rows = Vec::new();
    for (s, b) in models.iter().zip(best) {
        rows.push(row(s, b)?);
    }
    let cat = |n: usize, ee: bool| {
        rows.iter()
            .find(|r| r.element == ElementKind::Catenary && r.n == Some(n))
            .map(|r| if ee { r.ee_mode_hz } else { r.f1_hz })
            .unwrap_or(f64::NAN)
    };
    // Richardson: the catenary error falls as 1/N², so f(N) + (f(N) − f(N/2))/3.
    let rich = |ee: bool| {
        let (a, b) = (cat(max / 2, ee), cat(max, ee));
        if max >= 2 {
            b + (b - a) / 3.0
        } else {
            b
        }
    };
    let f1_ref_hz = rich(false);
    let ee_ref_hz = rich(true);
    let catenary_order = if max >= 4 {
        let (a, b, c) = (cat(max / 4, false), cat(max / 2, false), cat(max, false));
        ((a - b) / (b - c)).abs().log2()
    } else {
        f64::NAN
    };
    let f1_continuous_hz = rows
        .iter()
        .find(|r| r.element == ElementKind::Continuous)
        .map(|r| r.f1_hz)
        .unwrap_or(f64::NAN);
    for r in &mut rows {
        r.err_ref = (r.f1_hz - f1_ref_hz) / f1_ref_hz;
        r.err_continuous = (r.f1_hz - f1_continuous_hz) / f1_continuous_hz;
        r.ee_err_ref = (r.ee_mode_hz - ee_ref_hz) / ee_ref_hz;
    }
    Ok(AccuracyReport {
        rows,
        f1_ref_hz,
        ee_ref_hz,
        f1_continuous_hz,
        catenary_order,
        max_elements: max,
    })
}

/// Mode 3 (index 2 of the dense spectrum) against N, paper Figs. 5 and 10.
#[derive(Debug, Clone)]
pub struct Mode3Row {
    /// Element kind.
    pub element: ElementKind,
    /// Elements per cable.
    pub n: usize,
    /// Frequencies of modes 1-3 (NaN when the model has fewer modes), Hz.
    pub modes_hz: [f64; 3],
    /// Degrees of freedom.
    pub dof: usize,
    /// Wall time of the dense reference, s.
    pub seconds: f64,
}

/// The dense convergence study: modes 1-3 for FEM and catenary, N in `ns`.
pub fn compute_mode3(s: &Scene, ns: &[usize]) -> Result<Vec<Mode3Row>, StudyError> {
    let mut out = Vec::new();
    for el in [ElementKind::Fem, ElementKind::Catenary] {
        for &n in ns {
            let m = s.with_model(el, n);
            let t0 = Instant::now();
            let r = reference_analysis(&m, &m.ee_position_m, Tmin::Scene, false).map_err(|e| {
                StudyError::Build(format!("dense reference, {} N={n}: {e}", el.as_str()))
            })?;
            let seconds = t0.elapsed().as_secs_f64();
            let mut modes_hz = [f64::NAN; 3];
            for (k, l) in r.modes.lambda.iter().take(3).enumerate() {
                modes_hz[k] = lambda_to_hz(*l);
            }
            out.push(Mode3Row {
                element: el,
                n,
                modes_hz,
                dof: r.dof,
                seconds,
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts() {
        assert_eq!(
            element_counts(80, false),
            vec![1, 2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 25, 32, 40, 50, 64, 80]
        );
        assert_eq!(element_counts(6, false), vec![1, 2, 3, 4, 5, 6]);
        assert_eq!(element_counts(7, false), vec![1, 2, 3, 4, 5, 6, 7]);
    }
}
