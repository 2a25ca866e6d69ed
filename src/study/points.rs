//! Parallel evaluation of poses: one real-time estimator per worker thread, results in
//! input order, a throttled progress line on stderr.
//!
//! Each point keeps, besides the estimate, the frequencies of the first K modes
//! (`Estimator::modes` right after the update, K ≤ [`MAX_MODES`]) and the smallest principal
//! value of the static end-effector stiffness, k_min = min eig(K_ee) (N/m, the
//! translational 3 × 3 block `Estimate::stiffness_n_m`, symmetric: its eigenvalues are
//! real): the stiffness of the softest direction.

use super::{build, StudyError};
use crate::estimator::{Estimate, Estimator, EstimatorParams};
use crate::kinematics::Pose;
use crate::modal::Mode;
use crate::scene::Scene;
use crate::service::stats::StatusHistogram;
use nalgebra::Vector3;
use std::io::Write as _;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Most worker threads a study starts (more only contend for the same cores).
pub const MAX_THREADS: usize = 64;
/// Most modes a study keeps per point (`--modes`): the spatial robot's first string cluster
/// has 8 modes, so 16 covers it and the modes above it, for 128 bytes more per point (a
/// point is ~0.5 kB).
pub const MAX_MODES: usize = 16;
/// Shortest time between two progress updates: at most 4 lines a second.
const PROGRESS_INTERVAL: Duration = Duration::from_millis(250);
/// How often the main thread looks at the workers' progress.
const POLL_INTERVAL: Duration = Duration::from_millis(20);

/// One evaluated point of a study.
#[derive(Debug, Clone, Copy)]
pub struct PointResult {
    /// End-effector position, m.
    pub position_m: Vector3<f64>,
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
        Err(StudyError::Usage(format!(
            "--modes {k}: must be within 1..={MAX_MODES}"
        )))
    }
}

/// The smallest eigenvalue of the symmetric stiffness `e.stiffness_n_m`, N/m (NaN unless
/// the estimate is ok and the matrix finite).
pub fn stiffness_min_n_m(e: &Estimate) -> f64 {
    let k = e.stiffness_n_m;
    if !e.is_ok() || !k.iter().all(|x| x.is_finite()) {
        return f64::NAN;
    }
    // Symmetrised: the sum of the cables' symmetric stiffnesses is symmetric up to rounding.
    let sym = (k + k.transpose()) * 0.5;
    sym.symmetric_eigenvalues().min()
}

/// One study point: `est.update` at `position_m` and `t_min_n`, then the first `n_modes`
/// modes of that pose (`n_modes` already checked by [`check_modes`]).
pub fn evaluate_one(
    est: &mut Estimator,
    position_m: Vector3<f64>,
    t_min_n: f64,
    n_modes: usize,
) -> PointResult {
    let estimate = *est.update(&Pose::at(position_m), t_min_n);
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
        position_m,
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

/// How many of `rows` have each status.
pub fn status_histogram(rows: &[PointResult]) -> StatusHistogram {
    let mut h = StatusHistogram::default();
    for r in rows {
        h.record(r.estimate.status);
    }
    h
}

/// Throttled progress line on stderr.
struct Progress<'a> {
    label: Option<&'a str>,
    total: usize,
    last: Instant,
    last_pct: usize,
}

impl<'a> Progress<'a> {
    fn new(label: Option<&'a str>, total: usize) -> Self {
        Progress {
            label,
            total,
            last: Instant::now(),
            last_pct: usize::MAX,
        }
    }
    fn show(&mut self, done: usize, force: bool) {
        let Some(l) = self.label else { return };
        let pct = (done * 100).checked_div(self.total).unwrap_or(100);
        if pct != self.last_pct && (force || self.last.elapsed() >= PROGRESS_INTERVAL) {
            eprint!("\r{l}: {pct:>3}% ({done}/{} points)", self.total);
            let _ = std::io::stderr().flush();
            self.last = Instant::now();
            self.last_pct = pct;
        }
    }
    fn finish(&mut self) {
        if self.label.is_some() {
            self.show(self.total, true);
            eprintln!();
        }
    }
}

/// How a pool of workers evaluates points.
#[derive(Debug, Clone, Copy)]
pub struct Workers<'a> {
    /// Estimator parameters (one estimator per worker).
    pub params: EstimatorParams,
    /// Worker threads (clamped to 1 ..= [`MAX_THREADS`] and to the number of jobs).
    pub threads: usize,
    /// `Some(label)`: a percentage on stderr, at most 4 times a second.
    pub progress: Option<&'a str>,
    /// Modes kept per point (1 ..= [`MAX_MODES`]).
    pub n_modes: usize,
}

/// Evaluate `points` (positions, m) at `t_min_n` on `threads` threads, one estimator per
/// thread, the first mode only. Work is handed out in runs of `chunk` consecutive points (so
/// a thread's estimator may warm-start along a run); the result keeps the order of `points`.
/// With `progress = Some(label)` a percentage is printed on stderr (at most 4 times a
/// second). [`evaluate_points_with`] keeps more modes.
pub fn evaluate_points(
    scene: &Scene,
    points: &[Vector3<f64>],
    t_min_n: f64,
    params: EstimatorParams,
    threads: usize,
    chunk: usize,
    progress: Option<&str>,
) -> Result<Vec<PointResult>, StudyError> {
    let w = Workers {
        params,
        threads,
        progress,
        n_modes: 1,
    };
    evaluate_points_with(scene, points, t_min_n, chunk, &w)
}

/// [`evaluate_points`] with the workers `w` (and their mode count).
pub fn evaluate_points_with(
    scene: &Scene,
    points: &[Vector3<f64>],
    t_min_n: f64,
    chunk: usize,
    w: &Workers,
) -> Result<Vec<PointResult>, StudyError> {
    let jobs: Vec<(usize, usize)> = (0..points.len())
        .step_by(chunk.max(1))
        .map(|a| (a, (a + chunk.max(1)).min(points.len())))
        .collect();
    evaluate_jobs_with(scene, &jobs, points.len(), w, |k| {
        let (a, b) = jobs[k];
        (a..b).map(|i| (points[i], t_min_n)).collect()
    })
}

/// Shared worker pool: job k yields its (position, T_min) list; results are concatenated
/// in job order. `total` is the number of points over all jobs (for the progress line).
/// The first mode only; [`evaluate_jobs_with`] keeps more.
pub fn evaluate_jobs<F>(
    scene: &Scene,
    jobs: &[(usize, usize)],
    threads: usize,
    progress: Option<&str>,
    total: usize,
    job_points: F,
    params: EstimatorParams,
) -> Result<Vec<PointResult>, StudyError>
where
    F: Fn(usize) -> Vec<(Vector3<f64>, f64)> + Sync,
{
    let w = Workers {
        params,
        threads,
        progress,
        n_modes: 1,
    };
    evaluate_jobs_with(scene, jobs, total, &w, job_points)
}

/// [`evaluate_jobs`] with the workers `w` (and their mode count).
pub fn evaluate_jobs_with<F>(
    scene: &Scene,
    jobs: &[(usize, usize)],
    total: usize,
    w: &Workers,
    job_points: F,
) -> Result<Vec<PointResult>, StudyError>
where
    F: Fn(usize) -> Vec<(Vector3<f64>, f64)> + Sync,
{
    let n_modes = check_modes(w.n_modes)?;
    let (params, threads, progress) = (w.params, w.threads, w.progress);
    let threads = threads.clamp(1, MAX_THREADS).min(jobs.len().max(1));
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let mut prog = Progress::new(progress, total);
    let mut per_job: Vec<Option<Vec<PointResult>>> = vec![None; jobs.len()];
    let results = std::thread::scope(|sc| {
        let handles: Vec<_> = (0..threads)
            .map(|_| {
                sc.spawn(|| -> Result<Vec<(usize, Vec<PointResult>)>, StudyError> {
                    let mut est = build(scene, params)?;
                    let mut local = Vec::new();
                    loop {
                        let k = next.fetch_add(1, Ordering::Relaxed);
                        if k >= jobs.len() {
                            break;
                        }
                        let pts = job_points(k);
                        let mut out = Vec::with_capacity(pts.len());
                        for (p, t) in pts {
                            out.push(evaluate_one(&mut est, p, t, n_modes));
                        }
                        done.fetch_add(out.len(), Ordering::Relaxed);
                        local.push((k, out));
                    }
                    Ok(local)
                })
            })
            .collect();
        while !handles.iter().all(|h| h.is_finished()) {
            prog.show(done.load(Ordering::Relaxed), false);
            std::thread::sleep(POLL_INTERVAL);
        }
        handles
            .into_iter()
            .map(|h| h.join().expect("study worker panicked"))
            .collect::<Vec<_>>()
    });
    prog.finish();
    for r in results {
        for (k, v) in r? {
            per_job[k] = Some(v);
        }
    }
    Ok(per_job.into_iter().flatten().flatten().collect())
}
