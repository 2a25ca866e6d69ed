//! What sag changes: every pose on a line through the scene's default pose evaluated twice,
//! with the chord model (straight cables, `sag = false`) and with the sagged model (cables
//! on their elastic catenary, `sag = true`), the same element kind and count for both.
//!
//! The line is x_k = p + o_k e_axis, o_k = A + k (B − A)/(n − 1), k = 0 .. n − 1, with p the
//! scene's position, e_axis a world axis and [A, B] the span of offsets (m). A line, not a
//! grid: the two models' curves are drawn over each other on shared axes, which a heat map
//! cannot do (a map per model gives the grid).
//!
//! Each (pose, model) is evaluated exactly as the analysis of the scene moved to x_k with that model
//! does (the structured path of [`super::analysis`]): an estimator built for the scene at
//! that pose, one cycle, then the first mode by `Estimator::modes`. So every number equals
//! `analyze`'s bit for bit, and does not depend on the order nor on the thread that
//! evaluated it (no warm start carries over between points). Where the estimator cannot be
//! built at the pose (outside the workspace, slack), a copy of the one built at the scene's
//! default pose runs the cycle, and the row keeps the status that names the cause (as
//! the real-time estimator does).
//!
//! Per model and pose: f1 (Hz), k_min = the smallest principal value of the static
//! end-effector stiffness's translational block (N/m, [`super::points::stiffness_min_n_m`]),
//! the cables' tensions at the end-effector end (N), the smallest tension along any cable
//! (N; the chord model's cables are uniform), and for the sagged model the largest Irvine
//! λ² and the largest mid-span sag (m) over the cables.

use super::map::Interval;
use super::points::{stiffness_min_n_m, MAX_THREADS};
use super::progress::Progress;
use super::{build, Param, ParamError, StudyError};
use crate::estimator::{Estimator, EstimatorParams, Status, Tmin};
use crate::input_file::message_number;
use crate::kinematics::Pose;
use crate::modal::Mode;
use crate::scene::Scene;
use nalgebra::Vector3;
use rayon::prelude::*;

/// Most poses on the line (each costs two estimator builds).
pub const MAX_POINTS: usize = 10_000;
/// Largest offset from the scene's position along the axis, m (either end of the span): a
/// thousand kilometres holds any cable robot's frame many times over, and keeps the span's
/// length, its steps and every position finite.
pub const MAX_OFFSET_M: f64 = 1e6;
/// The default span covers the central 80 % of the frame along the axis: this is half of it.
const DEFAULT_HALF_SPAN_SHARE: f64 = 0.4;

/// What to compute.
#[derive(Debug, Clone, Copy)]
pub struct SagCompareConfig {
    /// World axis of the line: 0 = x, 1 = y, 2 = z.
    pub axis: usize,
    /// Offsets from the scene's position along the axis, m; `None`: the central 80 % of the
    /// anchors' extent along the axis (refused when the anchors have no extent there).
    pub span_m: Option<Interval>,
    /// Poses on the line (2 ..= [`MAX_POINTS`]).
    pub points: usize,
    /// Worker threads (0: one per core).
    pub threads: usize,
    /// A progress bar on a terminal.
    pub progress: bool,
}

/// One model's answer at one pose.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelPoint {
    /// The estimator's status (numbers are NaN unless ok).
    pub status: Status,
    /// First natural frequency, Hz (`Estimator::modes`' first, as `analyze` prints).
    pub f1_hz: f64,
    /// Smallest principal value of the static translational stiffness, N/m.
    pub stiffness_min_n_m: f64,
    /// Each cable's tension at the end-effector end, N.
    pub tensions_n: Vec<f64>,
    /// Smallest tension along any cable, N.
    pub tension_min_n: f64,
    /// Largest Irvine λ² over the cables (sagged model; NaN for the chord model).
    pub irvine_lambda2_max: f64,
    /// Largest mid-span sag over the cables, m (sagged model; NaN for the chord model).
    pub sag_max_m: f64,
}

impl ModelPoint {
    /// Whether the model gave an answer here.
    pub fn is_ok(&self) -> bool {
        self.status == Status::Ok
    }
    /// The largest end-effector-end tension, N (NaN unless ok).
    pub fn tension_max_n(&self) -> f64 {
        if !self.is_ok() {
            return f64::NAN;
        }
        self.tensions_n.iter().copied().fold(f64::NAN, f64::max)
    }
}

/// One pose of the line, both models.
#[derive(Debug, Clone, PartialEq)]
pub struct ComparePoint {
    /// Offset from the scene's position along the axis, m.
    pub offset_m: f64,
    /// End-effector position, m.
    pub position_m: Vector3<f64>,
    /// The chord model (`sag = false`).
    pub chord: ModelPoint,
    /// The sagged model (`sag = true`).
    pub sag: ModelPoint,
}

/// The study's result.
#[derive(Debug, Clone)]
pub struct SagCompare {
    /// The config's axis (0 = x, 1 = y, 2 = z).
    pub axis: usize,
    /// The span of offsets used, m.
    pub span_m: Interval,
    /// One entry per pose, in order of increasing offset.
    pub points: Vec<ComparePoint>,
    /// Worker threads used.
    pub threads: usize,
}

/// The scene with the model `sag` on or off (the element kind and count kept).
pub fn with_sag(s: &Scene, sag: bool) -> Scene {
    let mut s = s.clone();
    s.model.sag = sag;
    s
}

/// The span of offsets: the configured one, or the central 80 % of the frame along `axis`.
fn span(s: &Scene, cfg: &SagCompareConfig) -> Result<Interval, StudyError> {
    if let Some(iv) = cfg.span_m {
        return Ok(iv);
    }
    let (lo, hi) = s.frame_bounds_m();
    let (lo, hi) = (lo[cfg.axis], hi[cfg.axis]);
    if hi - lo <= 0.0 {
        return Err(ParamError::NotApplicable {
            param: Param::Axis,
            reason: format!(
                "the anchors have no extent along {}",
                ["x", "y", "z"][cfg.axis]
            ),
            instead: Some(Param::SpanM),
        }
        .into());
    }
    let c = (lo + hi) / 2.0 - s.ee_position_m[cfg.axis];
    let r = DEFAULT_HALF_SPAN_SHARE * (hi - lo);
    Ok(Interval {
        lo: c - r,
        hi: c + r,
    })
}

/// Check the config and list the offsets of the line.
fn offsets(s: &Scene, cfg: &SagCompareConfig) -> Result<(Interval, Vec<f64>), StudyError> {
    if cfg.axis > 2 {
        return Err(ParamError::invalid(Param::Axis, cfg.axis, "must be 0, 1 or 2").into());
    }
    if !(2..=MAX_POINTS).contains(&cfg.points) {
        let rule = format!("must be within 2..={MAX_POINTS}");
        return Err(ParamError::invalid(Param::Points, cfg.points, rule).into());
    }
    let iv = span(s, cfg)?;
    if !(iv.lo.abs() <= MAX_OFFSET_M && iv.hi.abs() <= MAX_OFFSET_M && iv.lo <= iv.hi) {
        let value = format!("{},{}", message_number(iv.lo), message_number(iv.hi));
        let rule =
            format!("must be finite offsets in m with MIN <= MAX, each within ±{MAX_OFFSET_M:e}");
        return Err(ParamError::invalid(Param::SpanM, value, rule).into());
    }
    let n = cfg.points;
    let step = (iv.hi - iv.lo) / (n - 1) as f64;
    let o = (0..n)
        .map(|k| {
            if k + 1 == n {
                iv.hi
            } else {
                iv.lo + k as f64 * step
            }
        })
        .collect();
    Ok((iv, o))
}

/// Compare the chord and the sagged model of `s` (its element kind and count) along the
/// configured line.
pub fn compute(s: &Scene, cfg: &SagCompareConfig) -> Result<SagCompare, StudyError> {
    let (span_m, offs) = offsets(s, cfg)?;
    let models = [with_sag(s, false), with_sag(s, true)];
    // Built at the default pose: the fallback of the poses an estimator cannot be built at,
    // and the check that both models exist for this scene.
    let cold = [
        build(&models[0], no_ee_mode())?,
        build(&models[1], no_ee_mode())?,
    ];
    let threads = match cfg.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        t => t.min(MAX_THREADS),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| StudyError::Build(format!("worker threads: {e}")))?;
    let bar = Progress::new(cfg.progress.then_some("sag-compare"), offs.len());
    let points = pool.install(|| {
        offs.par_iter()
            .map(|&o| {
                let mut p = s.ee_position_m;
                p[cfg.axis] += o;
                let chord = evaluate_at(&models[0], &cold[0], p);
                let sag = evaluate_at(&models[1], &cold[1], p);
                bar.advance(1);
                ComparePoint {
                    offset_m: o,
                    position_m: p,
                    chord,
                    sag,
                }
            })
            .collect()
    });
    bar.finish();
    Ok(SagCompare {
        axis: cfg.axis,
        span_m,
        points,
        threads,
    })
}

/// The estimator's defaults without the end-effector mode: the comparison reports f1 and
/// the statics only, and with sagging cables the end-effector mode is a sweep of the
/// spectrum that would cost most of each point's time.
fn no_ee_mode() -> EstimatorParams {
    EstimatorParams {
        ee_mode: false,
        ..EstimatorParams::default()
    }
}

/// One model at position `p`, as the analysis of the scene moved to `p` computes it.
pub fn evaluate_at(model: &Scene, cold: &Estimator, p: Vector3<f64>) -> ModelPoint {
    let mut at = model.clone();
    at.ee_position_m = p;
    let mut est = Estimator::with_params(&at, no_ee_mode()).unwrap_or_else(|_| cold.clone());
    let pose = Pose {
        position_m: p,
        orientation_wxyz: at.ee_orientation_wxyz,
    };
    let e = *est.update(&pose, Tmin::Scene);
    let n = at.n_cables();
    let mut r = ModelPoint {
        status: e.status,
        f1_hz: f64::NAN,
        stiffness_min_n_m: f64::NAN,
        tensions_n: vec![f64::NAN; n],
        tension_min_n: f64::NAN,
        irvine_lambda2_max: f64::NAN,
        sag_max_m: f64::NAN,
    };
    if !e.is_ok() {
        return r;
    }
    r.tensions_n = e.tensions().to_vec();
    r.stiffness_min_n_m = stiffness_min_n_m(&e);
    let mut modes = [Mode::default(); 1];
    if let Ok(1) = est.modes(1, &mut modes) {
        r.f1_hz = modes[0].frequency_hz;
    }
    r.tension_min_n = r.tensions_n.iter().copied().fold(f64::NAN, f64::min);
    if let Some(cats) = est.sag_catenaries() {
        let max = |f: fn(&crate::elastic_catenary::Catenary) -> f64| {
            cats.iter().map(f).fold(f64::NAN, f64::max)
        };
        r.tension_min_n = cats
            .iter()
            .map(|c| c.tension_min_n())
            .fold(f64::NAN, f64::min);
        r.irvine_lambda2_max = max(|c| c.irvine_lambda2());
        r.sag_max_m = max(|c| c.sag_m());
    }
    r
}

impl SagCompare {
    /// The axis' name (`x`, `y`, `z`).
    pub fn axis_name(&self) -> &'static str {
        ["x", "y", "z"][self.axis.min(2)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_end_exactly_on_the_span() {
        let s = Scene::load("spatial-paper").unwrap();
        let cfg = SagCompareConfig {
            axis: 0,
            span_m: Some(Interval { lo: -0.3, hi: 0.7 }),
            points: 7,
            threads: 1,
            progress: false,
        };
        let (_, o) = offsets(&s, &cfg).unwrap();
        assert_eq!(o.len(), 7);
        assert_eq!((o[0], o[6]), (-0.3, 0.7));
        let bad = SagCompareConfig { points: 1, ..cfg };
        assert!(offsets(&s, &bad).is_err());
        // Ends at the bound are taken; beyond it (or not finite after subtraction) refused.
        let at = |lo: f64, hi: f64| SagCompareConfig {
            span_m: Some(Interval { lo, hi }),
            ..cfg
        };
        let (_, o) = offsets(&s, &at(-MAX_OFFSET_M, MAX_OFFSET_M)).unwrap();
        assert!(o.iter().all(|x| x.is_finite()));
        for (lo, hi) in [(-1e308, 1e308), (0.0, 1.0000001e6), (f64::NAN, 1.0)] {
            let e = offsets(&s, &at(lo, hi)).unwrap_err().to_string();
            assert!(e.contains("±1e6"), "{e}");
        }
    }
}
