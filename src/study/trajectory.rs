//! The first natural frequencies (f1 .. fK) and the end-effector mode along a trajectory,
//! for one or several T_min values.
//!
//! [`run`] streams: it reads a CSV twice (once to check every row and count them, once to
//! evaluate), [`CHUNK_POSES`] poses at a time, hands each chunk's results to a sink (the
//! command writes them out) and keeps only what is bounded: per curve one estimator, the
//! summary (accumulated), and at most [`FIGURE_MAX_POINTS`] points for the figure. Memory is
//! therefore independent of the number of poses: per chunk [`CHUNK_POSES`] poses and
//! [`CHUNK_POSES`] results per curve (872 bytes each: 3.6 MB per curve), plus the figure's
//! points (at most 8.7 MB per curve), plus one estimator per curve, plus one line of the file
//! ([`crate::trajectory::samples::MAX_LINE_BYTES`]).

use super::points::{
    check_modes, ee_mode_missing, evaluate_jobs_with, evaluate_one, status_histogram, valid,
    PointResult, Workers,
};
use super::progress::Progress;
use super::{build, estimator_params, Param, ParamError, StudyError};
use crate::estimator::{Estimator, Tmin};
use crate::kinematics::Pose;
use crate::scene::Scene;
use crate::stats::StatusHistogram;
use crate::trajectory::samples::{visit_csv, Row};
use crate::trajectory::{Circle, Samples, TrajectoryError};
use rayon::prelude::*;
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

/// Poses evaluated per chunk by [`run`].
pub const CHUNK_POSES: usize = 4096;
/// Most points per curve [`run`] keeps for the figure: with more poses it keeps every
/// ⌈poses / this⌉-th one and the last (the summaries still count every pose).
pub const FIGURE_MAX_POINTS: usize = 10_000;

/// A computed trajectory study.
#[derive(Debug, Clone)]
pub struct TrajectoryStudy {
    /// The poses (with their angle along the circle when the path is the circle); from
    /// [`run`], the poses kept for the figure (at most [`FIGURE_MAX_POINTS`]).
    pub samples: Samples,
    /// Poses evaluated per curve (from [`run`], more than `samples` holds when the
    /// trajectory has more than [`FIGURE_MAX_POINTS`] poses).
    pub poses: usize,
    /// The summary of each curve over every pose, when computed while streaming (empty:
    /// [`TrajectoryStudy::summary`] computes it from `points`).
    pub summaries: Vec<CurveSummary>,
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
        if let Some(c) = self.summaries.get(k) {
            return *c;
        }
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
            ee_mode_missing: rows.iter().filter(|r| ee_mode_missing(&r.estimate)).count(),
        }
    }
}

/// The range of f1 along one curve and its statuses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveSummary {
    /// Smallest valid f1, Hz (+∞ when none is valid).
    pub f1_min_hz: f64,
    /// Largest valid f1, Hz (−∞ when none is valid).
    pub f1_max_hz: f64,
    /// How many poses have each status.
    pub counts: StatusHistogram,
    /// How many ok poses have no end-effector mode ([`super::points::ee_mode_missing`]).
    pub ee_mode_missing: usize,
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

/// One chunk of consecutive poses of [`run`].
#[derive(Debug, Clone, Default)]
pub struct Chunk {
    /// Times, s.
    pub t_s: Vec<f64>,
    /// Angles along the circle, deg (empty for a CSV).
    pub angle_deg: Vec<f64>,
    /// The poses.
    pub poses: Vec<Pose>,
    /// Poses per curve in the whole trajectory.
    pub total_poses: usize,
    /// The T_min of each curve, N (as in [`TrajectoryStudy::t_mins_n`]).
    pub t_mins_n: Vec<f64>,
    /// Modes per pose.
    pub modes: usize,
}

impl Chunk {
    fn clear(&mut self) {
        self.t_s.clear();
        self.angle_deg.clear();
        self.poses.clear();
    }
}

/// An error of the second reading of a CSV in [`run`]: the file's or the sink's.
enum ReadOrSink<E> {
    Read(TrajectoryError),
    Sink(E),
}

impl<E> From<TrajectoryError> for ReadOrSink<E> {
    fn from(e: TrajectoryError) -> Self {
        ReadOrSink::Read(e)
    }
}

/// The state [`run`] keeps between chunks: bounded whatever the number of poses.
struct Stream<'a, F> {
    scene: &'a Scene,
    curves: &'a [Tmin<'static>],
    n_modes: usize,
    pool: rayon::ThreadPool,
    /// One estimator per curve, warm from the curve's previous chunk.
    estimators: Vec<Estimator>,
    bar: Progress,
    chunk: Chunk,
    /// Poses evaluated so far per curve.
    done: usize,
    /// Keep every `stride`-th pose (and the last, `poses - 1`) for the figure.
    stride: usize,
    poses: usize,
    figure: Samples,
    /// Whether the poses have their own orientation (kept for the figure's samples).
    orientation: bool,
    figure_points: Vec<Vec<PointResult>>,
    summaries: Vec<CurveSummary>,
    sink: F,
}

impl<F, E> Stream<'_, F>
where
    F: FnMut(&Chunk, &[Vec<PointResult>]) -> Result<(), E>,
{
    fn push(&mut self, t_s: f64, angle_deg: Option<f64>, pose: Pose) -> Result<(), E> {
        self.chunk.t_s.push(t_s);
        self.chunk.angle_deg.extend(angle_deg);
        self.chunk.poses.push(pose);
        if self.chunk.poses.len() == CHUNK_POSES {
            self.flush()?;
        }
        Ok(())
    }

    /// Evaluates the chunk (each curve on its own worker, in pose order), accumulates the
    /// summaries and the figure's points, hands the results to the sink.
    fn flush(&mut self) -> Result<(), E> {
        let (chunk, n_modes) = (&self.chunk, self.n_modes);
        if chunk.poses.is_empty() {
            return Ok(());
        }
        let bar = &self.bar;
        let estimators = &mut self.estimators;
        let curves = self.curves;
        let results: Vec<Vec<PointResult>> = self.pool.install(|| {
            estimators
                .par_iter_mut()
                .zip(curves.par_iter())
                .map(|(est, &t)| {
                    let out: Vec<PointResult> = chunk
                        .poses
                        .iter()
                        .map(|p| evaluate_one(est, p, t, n_modes))
                        .collect();
                    bar.advance(out.len());
                    out
                })
                .collect()
        });
        for (i, pose) in chunk.poses.iter().enumerate() {
            let j = self.done + i;
            if j.is_multiple_of(self.stride) || j + 1 == self.poses {
                self.figure.t_s.push(chunk.t_s[i]);
                self.figure.position_m.push(pose.position_m);
                if self.orientation {
                    self.figure.orientation_wxyz.push(pose.orientation_wxyz);
                }
                if let Some(&a) = chunk.angle_deg.get(i) {
                    self.figure.angle_deg.push(a);
                }
                for (fig, r) in self.figure_points.iter_mut().zip(&results) {
                    fig.push(r[i]);
                }
            }
        }
        for (c, rows) in self.summaries.iter_mut().zip(&results) {
            for r in rows {
                let f = valid(&r.estimate, r.estimate.f1_hz);
                if f.is_finite() {
                    c.f1_min_hz = c.f1_min_hz.min(f);
                    c.f1_max_hz = c.f1_max_hz.max(f);
                }
                c.counts.record(r.estimate.status);
                c.ee_mode_missing += usize::from(ee_mode_missing(&r.estimate));
            }
        }
        self.done += chunk.poses.len();
        (self.sink)(chunk, &results)?;
        self.chunk.clear();
        Ok(())
    }
}

/// Check the T_min values, make or read the poses and evaluate every curve, streaming (see
/// the module docs): `sink` gets each chunk of poses with its results, one list per curve
/// in the order of the T_min values; the study returned holds the exact summaries and the
/// figure's points. The results equal [`evaluate_with`]'s bit for bit (each curve runs its
/// poses in order on one estimator, from the same cold start).
pub fn run<E, F>(s: &Scene, cfg: &TrajectoryConfig, sink: F) -> Result<TrajectoryStudy, E>
where
    E: From<StudyError>,
    F: FnMut(&Chunk, &[Vec<PointResult>]) -> Result<(), E>,
{
    if let Some(t) = cfg
        .t_mins_n
        .iter()
        .find(|t| !(t.is_finite() && **t >= 0.0 && **t <= s.t_max_n))
    {
        let rule = format!("must be within [0, t_max = {:?} N]", s.t_max_n);
        return Err(
            StudyError::from(ParamError::invalid(Param::TMinsN, format!("{t:?}"), rule)).into(),
        );
    }
    let circle = match &cfg.path {
        // First pass: every row checked (and counted) before anything is evaluated or written.
        PathSource::Csv(p) => {
            let shape =
                visit_csv(p, |_| Ok::<(), TrajectoryError>(())).map_err(StudyError::from)?;
            Err((p, shape))
        }
        &PathSource::Circle { radius_m, period_s } => {
            if !(period_s.is_finite() && period_s > 0.0 && period_s <= MAX_PERIOD_S) {
                let rule = format!("must be in (0, {MAX_PERIOD_S}] s");
                let e = ParamError::invalid(Param::PeriodS, period_s, rule);
                return Err(StudyError::from(e).into());
            }
            if !(radius_m.is_finite() && radius_m >= 0.0) {
                let e = ParamError::invalid(Param::RadiusM, radius_m, "must be finite and >= 0");
                return Err(StudyError::from(e).into());
            }
            Ok(Circle::new(s, radius_m, period_s).map_err(StudyError::from)?)
        }
    };
    let poses = match &circle {
        Ok(c) => c.sample_count(),
        Err((_, shape)) => shape.rows,
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
    let n_modes = check_modes(w.n_modes)?;
    let cold = build(s, w.params)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(w.thread_count())
        .build()
        .map_err(|e| StudyError::Build(format!("worker threads: {e}")))?;
    let empty = CurveSummary {
        f1_min_hz: f64::INFINITY,
        f1_max_hz: f64::NEG_INFINITY,
        counts: StatusHistogram::default(),
        ee_mode_missing: 0,
    };
    let mut st = Stream {
        scene: s,
        curves: &curves,
        n_modes,
        pool,
        estimators: vec![cold; curves.len()],
        bar: Progress::new(w.progress, poses * curves.len()),
        chunk: Chunk {
            total_poses: poses,
            t_mins_n: curves.iter().map(|t| t.lowest_n(s)).collect(),
            modes: n_modes,
            ..Chunk::default()
        },
        done: 0,
        stride: poses.div_ceil(FIGURE_MAX_POINTS).max(1),
        poses,
        figure: Samples::default(),
        orientation: false,
        figure_points: vec![Vec::new(); curves.len()],
        summaries: vec![empty; curves.len()],
        sink,
    };
    match &circle {
        Ok(c) => {
            for k in 0..poses {
                let (t_s, p, angle) = c.sample(s, k);
                st.push(t_s, Some(angle), Pose::in_scene(s, p))?;
            }
        }
        Err((p, shape)) => {
            st.orientation = shape.orientation;
            let again = visit_csv(p, |r: Row| {
                st.push(r.t_s, None, r.pose(st.scene))
                    .map_err(ReadOrSink::Sink)
            })
            .map_err(|e| match e {
                ReadOrSink::Read(t) => E::from(StudyError::from(t)),
                ReadOrSink::Sink(e) => e,
            })?;
            if again != *shape {
                return Err(StudyError::FileChanged {
                    path: p.to_path_buf(),
                    before: shape.rows,
                    after: again.rows,
                }
                .into());
            }
        }
    }
    st.flush()?;
    st.bar.finish();
    let points = st.figure_points.concat();
    Ok(TrajectoryStudy {
        samples: st.figure,
        poses,
        summaries: st.summaries,
        t_mins_n: st.chunk.t_mins_n,
        points,
    })
}
