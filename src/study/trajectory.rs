//! The first natural frequencies (f1 .. fK) and the end-effector mode along a trajectory,
//! for one or several T_min values.

use super::points::{evaluate_jobs_with, status_histogram, valid, PointResult, Workers};
use super::{estimator_params, StudyError};
use crate::estimator::Tmin;
use crate::scene::Scene;
use crate::stats::StatusHistogram;
use crate::trajectory::{Circle, Samples};
use std::path::PathBuf;

/// Longest circle period, s (one hour of 1 ms samples is already 3.6 million poses).
pub const MAX_PERIOD_S: f64 = 3600.0;

/// Where the poses come from.
#[derive(Debug, Clone)]
pub enum PathSource {
    /// A CSV with columns t,x,y,z or t,x,y,z,qw,qx,qy,qz (s, m, unit quaternion); see
    /// [`Samples::read_csv`]. Without quaternion columns the poses take the scene's
    /// orientation.
    Csv(PathBuf),
    /// The paper's circle around the scene's position, sampled every 1 ms.
    Circle {
        /// Radius, m.
        radius_m: f64,
        /// Time per revolution, s.
        period_s: f64,
    },
}

/// What to evaluate.
#[derive(Debug, Clone)]
pub struct TrajectoryConfig {
    /// The poses.
    pub path: PathSource,
    /// T_min values, N, one curve each, every cable at that value (empty: one curve at the
    /// scene's own per-cable bounds).
    pub t_mins_n: Vec<f64>,
    /// Compute the end-effector mode too.
    pub ee_mode: bool,
    /// Modes kept per pose (1 ..= `points::MAX_MODES`).
    pub modes: usize,
    /// Worker threads, T_min curves spread over them (0: one per core).
    pub threads: usize,
    /// Show a progress bar on stderr (a terminal only).
    pub progress: bool,
}

/// A computed trajectory study.
#[derive(Debug, Clone)]
pub struct TrajectoryStudy {
    /// The poses (with their angle along the circle when the path is the circle).
    pub samples: Samples,
    /// The T_min of each curve, N (for the scene's own bounds, the lowest of its cables'
    /// lower bounds).
    pub t_mins_n: Vec<f64>,
    /// Results, T_min-major: curve k is `points[k * n..(k + 1) * n]` for n poses.
    pub points: Vec<PointResult>,
}

impl TrajectoryStudy {
    /// Whether the poses are the circle (x axis: angle) rather than a CSV (x axis: time).
    pub fn is_circle(&self) -> bool {
        !self.samples.angle_deg.is_empty()
    }
    /// The results of curve `k`.
    pub fn curve(&self, k: usize) -> &[PointResult] {
        let n = self.samples.position_m.len();
        &self.points[k * n..(k + 1) * n]
    }
    /// The summary of curve `k`.
    pub fn summary(&self, k: usize) -> CurveSummary {
        let rows = self.curve(k);
        let ok: Vec<f64> = rows
            .iter()
            .map(|r| valid(&r.estimate, r.estimate.f1_hz))
            .filter(|f| f.is_finite())
            .collect();
        CurveSummary {
            f1_min_hz: ok.iter().copied().fold(f64::INFINITY, f64::min),
            f1_max_hz: ok.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            counts: status_histogram(rows),
        }
    }
}

/// The range of f1 along one curve and its statuses.
#[derive(Debug, Clone, Copy)]
pub struct CurveSummary {
    /// Smallest valid f1, Hz (+∞ when none is valid).
    pub f1_min_hz: f64,
    /// Largest valid f1, Hz (−∞ when none is valid).
    pub f1_max_hz: f64,
    /// How many poses have each status.
    pub counts: StatusHistogram,
}

/// Evaluate a trajectory for each T_min (one run per T_min, consecutive poses so the
/// estimator warm-starts); results are T_min-major. The first mode only;
/// [`evaluate_with`] keeps more.
pub fn evaluate(
    s: &Scene,
    tr: &Samples,
    t_mins: &[Tmin<'static>],
    ee_mode: bool,
    threads: usize,
    progress: Option<&str>,
) -> Result<Vec<PointResult>, StudyError> {
    let w = Workers {
        params: estimator_params(s, ee_mode),
        threads,
        progress,
        n_modes: 1,
    };
    evaluate_with(s, tr, t_mins, &w)
}

/// [`evaluate`] with the workers `w` (and their mode count).
pub fn evaluate_with(
    s: &Scene,
    tr: &Samples,
    t_mins: &[Tmin<'static>],
    w: &Workers,
) -> Result<Vec<PointResult>, StudyError> {
    let n = tr.position_m.len();
    let poses = tr.poses(s);
    evaluate_jobs_with(s, t_mins.len(), n * t_mins.len(), w, |k| {
        poses.iter().map(|p| (*p, t_mins[k])).collect()
    })
}

/// Check the T_min values, make or read the poses and evaluate every curve.
pub fn run(s: &Scene, cfg: &TrajectoryConfig) -> Result<TrajectoryStudy, StudyError> {
    if let Some(t) = cfg
        .t_mins_n
        .iter()
        .find(|t| !(t.is_finite() && **t >= 0.0 && **t <= s.t_max_n))
    {
        return Err(StudyError::Usage(format!(
            "--t-mins {t:?}: must be within [0, t_max = {:?} N]",
            s.t_max_n
        )));
    }
    let tr = match &cfg.path {
        PathSource::Csv(p) => Samples::read_csv(p)?,
        &PathSource::Circle { radius_m, period_s } => {
            if !(period_s.is_finite()
                && period_s > 0.0
                && period_s <= MAX_PERIOD_S
                && radius_m.is_finite()
                && radius_m >= 0.0)
            {
                return Err(StudyError::Usage(
                    "--period-s must be in (0, 3600] and --radius-m finite and >= 0".into(),
                ));
            }
            Circle::new(s, radius_m, period_s)?.sampled(s)
        }
    };
    let w = Workers {
        params: estimator_params(s, cfg.ee_mode),
        threads: cfg.threads,
        progress: cfg.progress.then_some("trajectory"),
        n_modes: cfg.modes,
    };
    let curves: Vec<Tmin<'static>> = if cfg.t_mins_n.is_empty() {
        vec![Tmin::Scene]
    } else {
        cfg.t_mins_n.iter().map(|&t| Tmin::Uniform(t)).collect()
    };
    let points = evaluate_with(s, &tr, &curves, &w)?;
    Ok(TrajectoryStudy {
        samples: tr,
        t_mins_n: curves.iter().map(|t| t.lowest_n(s)).collect(),
        points,
    })
}
