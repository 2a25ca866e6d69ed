//! Parallel evaluation of poses on a rayon pool (all cores unless told otherwise): one
//! real-time estimator per worker, results in input order and equal bit for bit to the
//! one-thread result, a progress bar with ETA on a terminal ([`super::progress`]).
//!
//! Each point keeps, besides the estimate, the frequencies of the first K modes
//! (`Estimator::modes` right after the update, K ≤ [`MAX_MODES`]) and the smallest principal
//! value of the static end-effector stiffness, k_min = min eig(K_ee) (N/m, the
//! translational 3 × 3 block `Estimate::stiffness_n_m`, symmetric: its eigenvalues are
//! real): the stiffness of the softest direction.

use super::progress::Progress;
use super::{build, Param, ParamError, StudyError};
use crate::estimator::{Estimate, Estimator, EstimatorParams, Tmin};
use crate::kinematics::Pose;
use crate::modal::Mode;
use crate::scene::Scene;
use crate::stats::StatusHistogram;
use nalgebra::Vector3;
use rayon::prelude::*;

/// Most worker threads a study starts (more only contend for the same cores).
pub const MAX_THREADS: usize = 64;
/// Most modes a study keeps per point (`modes`): the spatial robot's first string cluster
/// has 8 modes, so 16 covers it and the modes above it, for 128 bytes more per point (a
/// point is ~0.5 kB).
pub const MAX_MODES: usize = 16;

/// One evaluated point of a study.
#[derive(Debug, Clone, Copy)]
pub struct PointResult {
    /// End-effector position, m.
    pub position_m: Vector3<f64>,
    /// End-effector orientation, unit quaternion [w, x, y, z] (the identity's or the
    /// scene's for a point mass, where it has no effect).
    pub orientation_wxyz: [f64; 4],
    /// T_min used, N.
    pub t_min_n: f64,
    /// What the real-time estimator returned (status, f1, end-effector mode, tensions).
    pub estimate: Estimate,
    /// How many modes were asked for (1 ..= [`MAX_MODES`]); `modes_hz[..n_modes]` hold them.
    pub n_modes: usize,
    /// Frequencies of the first `n_modes` modes in ascending order, Hz, from
    /// `Estimator::modes` (with `n_modes` = 1: `estimate.f1_hz`); NaN unless the estimate is
    /// ok, and where the solver returned fewer. The CSVs' `f1_hz` column is always
    /// `estimate.f1_hz`, `f2_hz` .. `fK_hz` are entries 1 .. K − 1.
    pub modes_hz: [f64; MAX_MODES],
    /// Smallest principal value of the static end-effector stiffness (translational block),
    /// N/m; NaN unless the estimate is ok.
    pub stiffness_min_n_m: f64,
}

impl PointResult {
    /// Frequency of mode `k` (1-based: `mode_hz(1)` is the first mode), Hz; NaN when not
    /// computed or not valid.
    pub fn mode_hz(&self, k: usize) -> f64 {
        if (1..=self.n_modes).contains(&k) {
            valid(&self.estimate, self.modes_hz[k - 1])
        } else {
            f64::NAN
        }
    }
}

/// Check a requested mode count: 1 ..= [`MAX_MODES`].
pub fn check_modes(k: usize) -> Result<usize, StudyError> {
    if (1..=MAX_MODES).contains(&k) {
        Ok(k)
    } else {
        let rule = format!("must be within 1..={MAX_MODES}");
        Err(ParamError::invalid(Param::Modes, k, rule).into())
    }
}

/// The end-effector mode's frequency of `e` as a table's cell, Hz: NaN when there is none
/// (or the estimate is not ok).
pub fn ee_mode_hz(e: &Estimate) -> f64 {
    valid(e, e.ee_mode.map_or(f64::NAN, |m| m.frequency_hz))
}

/// The smallest eigenvalue of the symmetric translational stiffness of `e`, N/m (NaN unless
/// the estimate is ok and the matrix finite).
pub fn stiffness_min_n_m(e: &Estimate) -> f64 {
    let k = e.stiffness.translational_n_m();
    if !e.is_ok() || !k.iter().all(|x| x.is_finite()) {
        return f64::NAN;
    }
    // Symmetrised: the sum of the cables' symmetric stiffnesses is symmetric up to rounding.
    let sym = (k + k.transpose()) * 0.5;
    sym.symmetric_eigenvalues().min()
}

/// One study point: `est.update` at `pose` and the lower bounds `t_min`, then the first
/// `n_modes` modes of that pose (`n_modes` already checked by [`check_modes`]).
pub fn evaluate_one(
    est: &mut Estimator,
    pose: &Pose,
    t_min: Tmin<'_>,
    n_modes: usize,
) -> PointResult {
    let estimate = *est.update(pose, t_min);
    let t_min_n = t_min.lowest_n(est.scene());
    let mut modes_hz = [f64::NAN; MAX_MODES];
    if estimate.is_ok() {
        if n_modes >= 2 {
            first_modes_hz(est, &mut modes_hz[..n_modes]);
        } else {
            // One mode: the cycle's own f1, and no extra work (the default sweeps cost
            // what they did before modes were added).
            modes_hz[0] = estimate.f1_hz;
        }
    }
    PointResult {
        position_m: pose.position_m,
        orientation_wxyz: pose.orientation_wxyz,
        t_min_n,
        estimate,
        n_modes,
        modes_hz,
        stiffness_min_n_m: stiffness_min_n_m(&estimate),
    }
}

/// Frequencies of the first `out.len()` modes of the last updated pose into `out` (Hz),
/// by [`Estimator::modes`] (the structured solver); entries it does not return (a model with
/// fewer modes, or a mode search that failed) stay NaN.
fn first_modes_hz(est: &mut Estimator, out: &mut [f64]) {
    let mut modes = [Mode::default(); MAX_MODES];
    let k = out.len().min(MAX_MODES);
    if let Ok(n) = est.modes(k, &mut modes[..k]) {
        for (f, m) in out.iter_mut().zip(&modes[..n]) {
            *f = m.frequency_hz;
        }
    }
}

/// `value` when the estimate is ok, else NaN (a point without a valid answer).
pub fn valid(e: &Estimate, value: f64) -> f64 {
    if e.is_ok() {
        value
    } else {
        f64::NAN
    }
}

/// Whether `e` is ok but carries no end-effector mode: none reached the participation
/// threshold within the scan's bounds (`crate::modal::ModalParams::max_scan_intervals`),
/// or the end-effector mode was not asked for. The CSVs' `ee_mode_hz` is NaN there.
pub fn ee_mode_missing(e: &Estimate) -> bool {
    e.is_ok() && e.ee_mode.is_none()
}

/// How many of `rows` have each status.
pub fn status_histogram(rows: &[PointResult]) -> StatusHistogram {
    let mut h = StatusHistogram::default();
    for r in rows {
        h.record(r.estimate.status);
    }
    h
}

/// How the workers evaluate points.
#[derive(Debug, Clone, Copy)]
pub struct Workers<'a> {
    /// Estimator parameters (one estimator per worker).
    pub params: EstimatorParams,
    /// Worker threads: 0 = one per core (rayon's default), else clamped to
    /// 1 ..= [`MAX_THREADS`].
    pub threads: usize,
    /// `Some(label)`: a progress bar with ETA on stderr ([`super::progress`]: only on a
    /// terminal, and only once the sweep has run for a second).
    pub progress: Option<&'a str>,
    /// Modes kept per point (1 ..= [`MAX_MODES`]).
    pub n_modes: usize,
}

impl Workers<'_> {
    /// The number of threads these workers run on (`threads`, or one per core for 0).
    pub fn thread_count(&self) -> usize {
        match self.threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            t => t.min(MAX_THREADS),
        }
    }
}

/// Evaluate `poses` at the lower bounds `t_min` with the workers `w`, in runs of `chunk` consecutive
/// points (a run shares a warm-started estimator); the result keeps the order of `poses`.
pub fn evaluate_points_with(
    scene: &Scene,
    poses: &[Pose],
    t_min: Tmin<'static>,
    chunk: usize,
    w: &Workers,
) -> Result<Vec<PointResult>, StudyError> {
    let chunk = chunk.max(1);
    let n_jobs = poses.len().div_ceil(chunk);
    evaluate_jobs_with(scene, n_jobs, poses.len(), w, |k| {
        let (a, b) = (k * chunk, ((k + 1) * chunk).min(poses.len()));
        poses[a..b].iter().map(|p| (*p, t_min)).collect()
    })
}

/// Evaluate `n_jobs` jobs on the workers `w`: job k is the list of (pose, T_min) that
/// `job_points(k)` returns, evaluated in order by one estimator; the results are
/// concatenated in job order. `total` is the number of points over all jobs (for the
/// progress bar).
///
/// The jobs run on a rayon pool of [`Workers::thread_count`] threads, one estimator per
/// worker (`map_init`). Every job starts from the same cold estimator (a copy of one built
/// once), so a result does not depend on which worker ran its job nor on what that worker
/// ran before: any thread count gives the one-thread result, bit for bit.
pub fn evaluate_jobs_with<F>(
    scene: &Scene,
    n_jobs: usize,
    total: usize,
    w: &Workers,
    job_points: F,
) -> Result<Vec<PointResult>, StudyError>
where
    F: Fn(usize) -> Vec<(Pose, Tmin<'static>)> + Sync,
{
    let n_modes = check_modes(w.n_modes)?;
    let cold = build(scene, w.params)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(w.thread_count())
        .build()
        .map_err(|e| StudyError::Build(format!("worker threads: {e}")))?;
    let bar = Progress::new(w.progress, total);
    let per_job: Vec<Vec<PointResult>> = pool.install(|| {
        (0..n_jobs)
            .into_par_iter()
            .map_init(
                || cold.clone(),
                |est, k| {
                    est.clone_from(&cold);
                    let out: Vec<PointResult> = job_points(k)
                        .into_iter()
                        .map(|(pose, t)| evaluate_one(est, &pose, t, n_modes))
                        .collect();
                    bar.advance(out.len());
                    out
                },
            )
            .collect()
    });
    bar.finish();
    Ok(per_job.into_iter().flatten().collect())
}
