//! Parallel evaluation of poses: one real-time estimator per worker thread, results in
//! input order, a throttled progress line on stderr.

use super::{build, StudyError};
use crate::estimator::{Estimate, EstimatorParams};
use crate::kinematics::Pose;
use crate::scene::Scene;
use crate::service::stats::StatusHistogram;
use nalgebra::Vector3;
use std::io::Write as _;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Most worker threads a study starts (more only contend for the same cores).
pub const MAX_THREADS: usize = 64;
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

/// Evaluate `points` (positions, m) at `t_min_n` on `threads` threads, one estimator per
/// thread. Work is handed out in runs of `chunk` consecutive points (so a thread's
/// estimator may warm-start along a run); the result keeps the order of `points`. With
/// `progress = Some(label)` a percentage is printed on stderr (at most 4 times a second).
pub fn evaluate_points(
    scene: &Scene,
    points: &[Vector3<f64>],
    t_min_n: f64,
    params: EstimatorParams,
    threads: usize,
    chunk: usize,
    progress: Option<&str>,
) -> Result<Vec<PointResult>, StudyError> {
    let jobs: Vec<(usize, usize)> = (0..points.len())
        .step_by(chunk.max(1))
        .map(|a| (a, (a + chunk.max(1)).min(points.len())))
        .collect();
    let rows = evaluate_jobs(
        scene,
        &jobs,
        threads,
        progress,
        points.len(),
        |k| {
            let (a, b) = jobs[k];
            (a..b).map(|i| (points[i], t_min_n)).collect()
        },
        params,
    )?;
    Ok(rows)
}

/// Shared worker pool: job k yields its (position, T_min) list; results are concatenated
/// in job order. `total` is the number of points over all jobs (for the progress line).
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
                            let e = *est.update(&Pose::at(p), t);
                            out.push(PointResult {
                                position_m: p,
                                t_min_n: t,
                                estimate: e,
                            });
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
