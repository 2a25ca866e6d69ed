//! The end-effector's dynamic deviation from its quasi-static pose along a trajectory
//! (`cablevib simulate`), and input shaping of a path from the estimated modes
//! (`cablevib shape`).
//!
//! **Model.** The robot follows the commanded path quasi-statically (each sample's pose is
//! the equilibrium the estimator solves); what vibrates is the deviation u from it. About
//! each pose the structure is linear (the estimator's model: stiffness, mass, tensions of
//! that pose), so M ü + C u̇ + K u = −M r a with the inertial load of the quasi-static
//! motion of the whole robot: every cable node carried along with the end-effector by the
//! influence field r (taut cables: the static one, anchors held, lengths fixed), M the
//! whole robot's mass, a the
//! path's acceleration by central differences of the samples
//! ([`crate::modal::quasi_static`]: the modes' participation factors φ_kᵀ M r and the
//! quasi-static mass rᵀ M r, taken by the response as load shapes of the end-effector
//! force −M_ee [a; 0]). Included: that load on every mode, through the first K modes of
//! the pose (the structured engine's frequencies and mass-normalised shapes, taut or
//! sagging), the damping of the scene (each mode's ratio [`Damping::modal_ratio`]), the
//! static correction of the modes left out (mode-acceleration method,
//! [`ModalResponse`](crate::modal::response::ModalResponse)). On sagging cables the field is
//! the path's instead (the nodes follow the sagged equilibrium with the winches' lengths
//! re-solved at each pose, [`crate::estimator::sag_path_field_applies`]), and its convective
//! term −M ∂²x/∂p²[ṗ, ṗ] (ṗ by central differences of the samples) loads the same modes
//! through a response of its own on the same modes ([`added_load`]). Left out: the rotational load −I·α − ω×Iω (the paths here
//! keep the orientation fixed: it is zero for them), gravity's change with the pose (it is
//! in the quasi-static pose), and the winches' dynamics.
//!
//! **Along the path.** Every `update_every` samples the estimator solves the pose and the
//! basis is replaced, the modal state carried across by the mass overlap of the old and
//! new whole shapes ([`ModalResponse::set_basis_projected`](crate::modal::response::ModalResponse::set_basis_projected): the motion of every mode the
//! new basis holds is kept, the cable-borne ones too); the end-effector's state alone
//! ([`ModalResponse::set_basis`](crate::modal::response::ModalResponse::set_basis)) where the shapes are the dense model's;
//! between updates the last basis holds.
//!
//! **Residual vibration.** After each stop (the commanded path at rest from one sample to
//! the next, after motion), peak-to-peak per axis and RMS of |u| until the path moves
//! again or ends.

use super::{Param, ParamError, ParamName, StudyError};
use crate::estimator::{Estimator, EstimatorParams, Status, Tmin};
use crate::kinematics::Pose;
use crate::modal::response::MAX_RESPONSE_MODES;
use crate::scene::{Damping, Scene};
use crate::trajectory::shaping::{OnlineShaper, ShaperKind, DEFAULT_MIN_FREQUENCY_HZ};
use crate::trajectory::{Samples, Trajectory};
use nalgebra::{Vector3, Vector6};

pub use path_spec::{simulate_shaped, PathSpec, ShapedRun};

pub mod added_load;
pub mod path_spec;
pub mod pilot;
mod propagate;
pub mod updates;

/// Default largest path acceleration accepted, m/s² (20 g: a path sampled from a jump
/// exceeds it).
pub const DEFAULT_MAX_ACCELERATION_M_S2: f64 = 200.0;
/// Most samples a simulated path may have.
pub const MAX_SAMPLES: usize = 10_000_000;
/// A sample is at rest when it moved less than this from the previous one, m.
const REST_EPS_M: f64 = 1e-12;

/// A path sampled every `dt_s`.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledPath {
    /// Sample period, s.
    pub dt_s: f64,
    /// Positions, m.
    pub positions_m: Vec<Vector3<f64>>,
    /// Whether the path is at rest before its first sample and after its last (a move, a
    /// file); false for a path already moving at both ends (the circle: its acceleration
    /// at the ends is its neighbours').
    pub at_rest_ends: bool,
}

/// Why a sampled path cannot be simulated or shaped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PathError {
    /// No samples.
    #[error("the path has no samples")]
    Empty,
    /// Fewer than two rows, or no time between them.
    #[error("the path lasts {duration_s} s ({rows} row(s)): it needs at least two rows, over a time > 0")]
    TooShort {
        /// Its duration, s.
        duration_s: f64,
        /// Its rows.
        rows: usize,
    },
    /// More samples than [`MAX_SAMPLES`].
    #[error("the path would have {samples} samples at {dt_s} s (at most {MAX_SAMPLES})")]
    TooManySamples {
        /// The count, as computed (may be infinite).
        samples: f64,
        /// The sample period, s.
        dt_s: f64,
    },
    /// A position that is not finite.
    #[error("sample {sample} (t = {t_s:.6} s) is not finite")]
    NotFinite {
        /// Its index.
        sample: usize,
        /// Its time, s.
        t_s: f64,
    },
    /// An acceleration above the largest accepted (a jump).
    #[error("{}", self.render(&Param::name))]
    Jump {
        /// Where, s.
        t_s: f64,
        /// The acceleration there, m/s².
        acceleration_m_s2: f64,
        /// The largest accepted, m/s².
        max_m_s2: f64,
    },
}

impl PathError {
    /// The message with the parameter of the acceleration bound called `name(param)`.
    pub fn render(&self, name: &dyn Fn(Param) -> &'static str) -> String {
        match self {
            PathError::Jump {
                t_s,
                acceleration_m_s2,
                max_m_s2,
            } => format!(
                "the path jumps at t = {t_s:.6} s: acceleration {acceleration_m_s2:.4e} m/s² over {max_m_s2} m/s² ({})",
                name(Param::MaxAccelerationMS2)
            ),
            other => other.to_string(),
        }
    }
}

impl SampledPath {
    /// Samples of a file, resampled every `dt_s` from its first to its last time
    /// (linear interpolation).
    pub fn from_samples(s: &Samples, dt_s: f64) -> Result<SampledPath, StudyError> {
        check_dt(dt_s)?;
        let t0 = s.t_s[0];
        let dur = s.duration_s();
        if !(dur.is_finite() && dur > 0.0) {
            // One row: nothing to simulate (a circle or move of duration 0 is refused alike).
            return Err(PathError::TooShort {
                duration_s: dur,
                rows: s.t_s.len(),
            }
            .into());
        }
        let n = (dur / dt_s).round();
        if !(n < MAX_SAMPLES as f64) {
            return Err(PathError::TooManySamples { samples: n, dt_s }.into());
        }
        let positions_m = (0..=n as usize)
            .map(|k| {
                let t = (t0 + k as f64 * dt_s).min(t0 + dur);
                s.position_at(t - t0)
                    .unwrap_or(s.position_m[s.position_m.len() - 1])
            })
            .collect();
        Ok(SampledPath {
            dt_s,
            positions_m,
            at_rest_ends: true,
        })
    }

    /// The paper's circle of `trajectory` for `duration_s`, every `dt_s`.
    pub fn from_trajectory(
        trajectory: &Trajectory,
        duration_s: f64,
        dt_s: f64,
        at_rest_ends: bool,
    ) -> Result<SampledPath, StudyError> {
        check_dt(dt_s)?;
        if !(duration_s.is_finite() && duration_s > 0.0) {
            let rule = "must be finite and > 0";
            return Err(
                ParamError::invalid(Param::DurationS, format!("{duration_s} s"), rule).into(),
            );
        }
        let n = (duration_s / dt_s).round();
        if !(n < MAX_SAMPLES as f64) {
            return Err(PathError::TooManySamples { samples: n, dt_s }.into());
        }
        let last = trajectory.position_at(0.0).unwrap_or_default();
        let positions_m = (0..=n as usize)
            .map(|k| trajectory.position_at(k as f64 * dt_s).unwrap_or(last))
            .collect();
        Ok(SampledPath {
            dt_s,
            positions_m,
            at_rest_ends,
        })
    }

    /// The acceleration of sample k, m/s² (central second difference; at rest beyond the ends
    /// when `at_rest_ends`, else the neighbour's value).
    pub fn acceleration(&self, k: usize) -> Vector3<f64> {
        let n = self.positions_m.len();
        let p = &self.positions_m;
        let h2 = self.dt_s * self.dt_s;
        if n < 3 && !self.at_rest_ends {
            return Vector3::zeros();
        }
        if self.at_rest_ends {
            let prev = if k == 0 { p[0] } else { p[k - 1] };
            let next = if k + 1 >= n { p[n - 1] } else { p[k + 1] };
            (next - 2.0 * p[k] + prev) / h2
        } else {
            let k = k.clamp(1, n - 2);
            (p[k + 1] - 2.0 * p[k] + p[k - 1]) / h2
        }
    }

    /// The velocity of sample k, m/s (central difference, the ends as
    /// [`Self::acceleration`]'s).
    pub fn velocity(&self, k: usize) -> Vector3<f64> {
        let n = self.positions_m.len();
        let p = &self.positions_m;
        if n < 3 && !self.at_rest_ends {
            return Vector3::zeros();
        }
        let k = if self.at_rest_ends {
            k
        } else {
            k.clamp(1, n - 2)
        };
        let prev = if k == 0 { p[0] } else { p[k - 1] };
        let next = if k + 1 >= n { p[n - 1] } else { p[k + 1] };
        (next - prev) / (2.0 * self.dt_s)
    }

    /// Refuses non-finite positions and accelerations above `max_m_s2` (a jump).
    pub fn check(&self, max_m_s2: f64) -> Result<(), StudyError> {
        if self.positions_m.is_empty() {
            return Err(PathError::Empty.into());
        }
        for (k, p) in self.positions_m.iter().enumerate() {
            if !p.iter().all(|v| v.is_finite()) {
                return Err(PathError::NotFinite {
                    sample: k,
                    t_s: k as f64 * self.dt_s,
                }
                .into());
            }
        }
        for k in 0..self.positions_m.len() {
            let a = self.acceleration(k).norm();
            if a > max_m_s2 {
                return Err(PathError::Jump {
                    t_s: k as f64 * self.dt_s,
                    acceleration_m_s2: a,
                    max_m_s2,
                }
                .into());
            }
        }
        Ok(())
    }
}

fn check_dt(dt_s: f64) -> Result<(), StudyError> {
    if !(dt_s.is_finite() && dt_s > 0.0 && dt_s <= 0.1) {
        let rule = "must be in (0, 0.1]";
        return Err(ParamError::invalid(Param::DtS, format!("{dt_s} s"), rule).into());
    }
    Ok(())
}

/// Configuration of [`simulate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimulateConfig {
    /// Modes K in the superposition (1 ..= [`MAX_RESPONSE_MODES`]; a cluster cut by K is
    /// completed); None: the fewest whose estimated truncation error meets `tolerance`
    /// ([`pilot`]).
    pub modes: Option<usize>,
    /// Samples between two updates of the modal basis (≥ 1); None: chosen along the path
    /// so that a held basis meets `tolerance` ([`updates`]).
    pub update_every: Option<usize>,
    /// The error allowed on the end-effector's deviation, relative to its peak, in
    /// [[`pilot::MIN_TOLERANCE`], [`pilot::MAX_TOLERANCE`]]; default
    /// [`pilot::DEFAULT_TOLERANCE`].
    pub tolerance: f64,
    /// Time simulated at rest after a path that ends at rest, s (≥ 0).
    pub settle_s: f64,
    /// Largest path acceleration accepted, m/s².
    pub max_acceleration_m_s2: f64,
    /// Label of the progress bar drawn on a terminal (None: no bar).
    pub progress: Option<&'static str>,
}

impl Default for SimulateConfig {
    fn default() -> Self {
        SimulateConfig {
            modes: None,
            update_every: None,
            tolerance: pilot::DEFAULT_TOLERANCE,
            settle_s: 2.0,
            max_acceleration_m_s2: DEFAULT_MAX_ACCELERATION_M_S2,
            progress: None,
        }
    }
}

/// What the accuracy controls of [`simulate`] chose and estimated.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Accuracy {
    /// The tolerance asked for, relative to the peak deviation.
    pub tolerance: f64,
    /// Whether K was chosen for the tolerance (false: given).
    pub modes_chosen: bool,
    /// The truncation estimate of the K kept, relative to the pilot's peak, the largest
    /// over the pilot poses ([`pilot`]).
    pub modes_estimate: f64,
    /// Whether that estimate met the tolerance at every pilot pose.
    pub modes_met: bool,
    /// The pilot's peak deviation, m (the scale of the tolerance).
    pub peak_m: f64,
    /// Modes of the pilot's largest basis (what its memory held).
    pub pilot_modes: usize,
    /// Whether the update interval was chosen for the tolerance (false: given).
    pub updates_chosen: bool,
    /// The largest predicted error of one interval between basis updates, relative to
    /// the pilot's peak ([`updates`]).
    pub interval_estimate: f64,
    /// The sum of the intervals' predicted errors, relative to the pilot's peak (a bound
    /// when every interval's phase error adds up).
    pub interval_estimate_sum: f64,
    /// Basis updates made by Rayleigh–Ritz from the previous basis ([`updates`]; the rest
    /// by the structured shapes).
    pub ritz_updates: usize,
    /// The largest relative residual ρ of a mode of those updates
    /// ([`crate::modal::ritz`]).
    pub ritz_residual: f64,
}

/// Residual vibration after one stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StopResidual {
    /// When the path came to rest, s.
    pub t_start_s: f64,
    /// When it moved again or the simulation ended, s.
    pub t_end_s: f64,
    /// Peak-to-peak deviation per axis, m.
    pub peak_to_peak_m: Vector3<f64>,
    /// RMS of |u| over the window, m.
    pub rms_m: f64,
}

impl StopResidual {
    /// The largest per-axis peak-to-peak, m.
    pub fn peak_to_peak_max_m(&self) -> f64 {
        self.peak_to_peak_m.max()
    }
}

/// What [`simulate`] computed.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulateResult {
    /// Times, s.
    pub t_s: Vec<f64>,
    /// Commanded positions, m.
    pub command_m: Vec<Vector3<f64>>,
    /// Deviation of the end-effector from its quasi-static pose (translation), m.
    pub deviation_m: Vec<Vector3<f64>>,
    /// Residual vibration after each stop.
    pub stops: Vec<StopResidual>,
    /// Updates of the modal basis.
    pub updates: usize,
    /// Modes in the last basis (K, clusters completed).
    pub modes: usize,
    /// Lowest and highest first frequency met along the path, Hz.
    pub f1_range_hz: (f64, f64),
    /// Whether the shapes came from the structured engine (taut cables, or sagging FEM
    /// cables); false: the dense model.
    pub structured: bool,
    /// What the accuracy controls chose and estimated.
    pub accuracy: Accuracy,
}

/// The estimator a simulation or shaping drives (the scene's participation threshold);
/// with `ee_mode` false it does not look for the end-effector mode at each pose (a time
/// response takes its modes from the basis, not from the estimate).
fn estimator(scene: &Scene, ee_mode: bool) -> Result<Estimator, StudyError> {
    let mut p = EstimatorParams::default();
    p.modal.ee_participation_min = scene.model.ee_participation_min;
    p.ee_mode = ee_mode;
    Estimator::with_params(scene, p).map_err(|e| StudyError::Build(e.to_string()))
}

fn solve_pose(
    est: &mut Estimator,
    scene: &Scene,
    p: &Vector3<f64>,
    t: f64,
) -> Result<(), StudyError> {
    let e = est.update(&Pose::in_scene(scene, *p), Tmin::Scene);
    if e.status != Status::Ok {
        let why = e.error.map(|e| e.to_string()).unwrap_or_default();
        return Err(StudyError::Build(format!(
            "t = {t:.4} s, position ({:.4}, {:.4}, {:.4}) m: {} {why}",
            p.x,
            p.y,
            p.z,
            e.status.as_str()
        )));
    }
    Ok(())
}

/// The dynamic deviation along `path` (module docs).
///
/// ```
/// use cablevib::prelude::*;
/// use cablevib::trajectory::moves::{Move, Profile};
///
/// let scene = Scene::load("spatial-paper")?;
/// // 0.1 m along x in 0.5 s (s-curve), sampled every ms, then 0.5 s at rest.
/// let dx = Vector3::new(0.1, 0.0, 0.0);
/// let mv = Move::new(scene.ee_position_m, dx, 0.5, Profile::SCurve)?;
/// let path = SampledPath::from_samples(&mv.sampled(1e-3, 0.5)?, 1e-3)?;
/// let cfg = SimulateConfig { modes: Some(4), settle_s: 0.0, ..SimulateConfig::default() };
/// let r = simulate(&scene, &path, &cfg)?;
/// assert_eq!(r.deviation_m.len(), r.t_s.len());
/// // The move excites the robot; the deviation is small beside the move itself.
/// let peak = r.deviation_m.iter().map(|u| u.norm()).fold(0.0, f64::max);
/// assert!(peak > 0.0 && peak < 1e-2 * dx.norm());
/// assert_eq!(r.stops.len(), 1);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn simulate(
    scene: &Scene,
    path: &SampledPath,
    cfg: &SimulateConfig,
) -> Result<SimulateResult, StudyError> {
    run(scene, path, cfg)
}

/// What [`simulate_forced`] computed.
#[derive(Debug, Clone, PartialEq)]
pub struct ForcedResult {
    /// [`simulate`]'s result under the force.
    pub response: SimulateResult,
    /// The deviation's acceleration at each sample, m/s², from the modal state
    /// ([`crate::modal::response::ModalResponse::acceleration`]: the K modes' q̈, not differences of the deviation).
    pub acceleration_m_s2: Vec<Vector3<f64>>,
}

/// [`simulate`] with an external force on the end-effector besides the path's inertial
/// load: `force_n(k)` (N, base frame) at sample k, held linearly between samples like the
/// load (e.g. white noise standing for the disturbances a real robot feels, which keep its
/// modes ringing); also the deviation's acceleration. The same loop as [`simulate`]
/// (`propagate::run`: K and the update interval given or chosen for `cfg.tolerance`).
/// The force acts on the end-effector: each mode takes φ_kᵀ P and the static answer F P
/// ([`added_load`]), not the inertial load's shapes. `force_n` is called once per sample,
/// in order, before the run (its values are held:
/// 24 B per sample, within [`simulate`]'s memory budget per sample).
pub fn simulate_forced(
    scene: &Scene,
    path: &SampledPath,
    cfg: &SimulateConfig,
    force_n: impl FnMut(usize) -> Vector3<f64>,
) -> Result<ForcedResult, StudyError> {
    let path = settled_path(path, cfg)?;
    let n = path.positions_m.len();
    super::cost::estimate_cost(scene, &simulate_work(n, cfg)).check_memory()?;
    let forces: Vec<Vector3<f64>> = (0..n).map(force_n).collect();
    let mut acceleration_m_s2 = Vec::with_capacity(n);
    let response = run_settled(
        scene,
        &path,
        cfg,
        |k| {
            let mut f = Vector6::zeros();
            f.fixed_rows_mut::<3>(0).copy_from(&forces[k]);
            f
        },
        |_, state| acceleration_m_s2.push(state.acceleration()),
    )?;
    Ok(ForcedResult {
        response,
        acceleration_m_s2,
    })
}

/// The path as simulated, the configuration checked first (the same refusals for
/// [`simulate`] and [`simulate_forced`]): the path itself, then the samples held at its
/// end for `cfg.settle_s` when it ends at rest.
fn settled_path(path: &SampledPath, cfg: &SimulateConfig) -> Result<SampledPath, StudyError> {
    if let Some(k) = cfg.modes {
        if !(1..=MAX_RESPONSE_MODES).contains(&k) {
            let rule = format!("must be in 1..={MAX_RESPONSE_MODES}");
            return Err(ParamError::invalid(Param::Modes, k, rule).into());
        }
    }
    if cfg.update_every == Some(0) {
        return Err(ParamError::invalid(Param::UpdateEvery, 0, "must be ≥ 1").into());
    }
    if !(cfg.tolerance.is_finite()
        && (pilot::MIN_TOLERANCE..=pilot::MAX_TOLERANCE).contains(&cfg.tolerance))
    {
        let rule = format!(
            "must be in [{}, {}] (relative to the peak deviation)",
            pilot::MIN_TOLERANCE,
            pilot::MAX_TOLERANCE
        );
        return Err(ParamError::invalid(Param::Tolerance, cfg.tolerance, rule).into());
    }
    if !(cfg.settle_s.is_finite() && cfg.settle_s >= 0.0 && cfg.settle_s <= 3600.0) {
        let value = format!("{} s", cfg.settle_s);
        return Err(ParamError::invalid(Param::SettleS, value, "must be in [0, 3600]").into());
    }
    path.check(cfg.max_acceleration_m_s2)?;
    let mut path = path.clone();
    if path.at_rest_ends {
        let last = path.positions_m[path.positions_m.len() - 1];
        let extra = (cfg.settle_s / path.dt_s).round() as usize;
        path.positions_m.extend(std::iter::repeat_n(last, extra));
    }
    Ok(path)
}

/// The simulation of [`simulate`] (module docs).
fn run(
    scene: &Scene,
    path: &SampledPath,
    cfg: &SimulateConfig,
) -> Result<SimulateResult, StudyError> {
    let path = settled_path(path, cfg)?;
    run_settled(scene, &path, cfg, |_| Vector6::zeros(), |_, _| {})
}

/// [`run`] on the path as simulated ([`settled_path`]) with the external force
/// `external_n(k)` (N, and N·m on a rigid body) and `on_sample(k, response, force)` after
/// each sample's state is reached: `propagate::run` and the progress bar.
fn run_settled(
    scene: &Scene,
    path: &SampledPath,
    cfg: &SimulateConfig,
    external_n: impl Fn(usize) -> Vector6<f64>,
    mut on_sample: impl FnMut(usize, &added_load::SampleState<'_>),
) -> Result<SimulateResult, StudyError> {
    let n = path.positions_m.len();
    // The memory of the whole run (two bases across an update, the path and its
    // deviation), refused past the one budget before anything is computed.
    super::cost::estimate_cost(scene, &simulate_work(n, cfg)).check_memory()?;
    let mut est = estimator(scene, false)?;
    let mut out = SimulateResult {
        t_s: Vec::with_capacity(n),
        command_m: Vec::with_capacity(n),
        deviation_m: Vec::with_capacity(n),
        stops: Vec::new(),
        updates: 0,
        modes: 0,
        f1_range_hz: (f64::INFINITY, f64::NEG_INFINITY),
        structured: true,
        accuracy: Accuracy::default(),
    };
    let bar = super::progress::Progress::counting(cfg.progress, n, "samples");
    propagate::run(
        &mut est,
        scene,
        path,
        cfg,
        external_n,
        |k, state| {
            on_sample(k, state);
            if k % PROGRESS_SAMPLES == 0 && k > 0 {
                bar.advance(PROGRESS_SAMPLES);
            }
        },
        &mut out,
    )?;
    bar.finish();
    out.stops = stop_residuals(&out.t_s, &out.command_m, &out.deviation_m);
    Ok(out)
}

/// The work of [`simulate`] on a path of `samples` samples (with its settling time), for
/// [`super::cost::estimate_cost`].
pub fn simulate_work(samples: usize, cfg: &SimulateConfig) -> super::cost::Work<'static> {
    super::cost::Work::Simulate {
        samples,
        // The chosen K, the pilot's growth and the interval are known only as the run goes:
        // its first pilot basis, K at least that pilot's and the first interval make this
        // estimate a lower bound (a refusal is certain); each larger pilot basis and the K
        // chosen are checked again before they are built.
        update_every: cfg.update_every.unwrap_or(updates::FIRST_INTERVAL),
        modes: cfg.modes.unwrap_or(pilot::FIRST_PILOT),
        pilot_modes: pilot::pilot_sizes(cfg.modes.unwrap_or(0))[0],
    }
}

/// Samples between two advances of the progress bar.
const PROGRESS_SAMPLES: usize = 256;

/// The samples [`simulate`] runs for `path` with `cfg`: the path's, and the settling time
/// after a path that ends at rest.
pub fn simulated_samples(path: &SampledPath, cfg: &SimulateConfig) -> usize {
    let extra = if path.at_rest_ends && cfg.settle_s.is_finite() && cfg.settle_s >= 0.0 {
        (cfg.settle_s / path.dt_s).round() as usize
    } else {
        0
    };
    path.positions_m.len() + extra
}

/// Residual vibration after each stop of `command` (module docs).
pub fn stop_residuals(
    t_s: &[f64],
    command_m: &[Vector3<f64>],
    deviation_m: &[Vector3<f64>],
) -> Vec<StopResidual> {
    let n = command_m.len();
    let moving = |k: usize| k > 0 && (command_m[k] - command_m[k - 1]).norm() > REST_EPS_M;
    let mut stops = Vec::new();
    let mut k = 1;
    while k < n {
        if !moving(k) && moving(k - 1) {
            let start = k;
            let mut end = k;
            while end + 1 < n && !moving(end + 1) {
                end += 1;
            }
            let mut lo = Vector3::repeat(f64::INFINITY);
            let mut hi = Vector3::repeat(f64::NEG_INFINITY);
            let mut sq = 0.0;
            for u in &deviation_m[start..=end] {
                lo = lo.inf(u);
                hi = hi.sup(u);
                sq += u.norm_squared();
            }
            stops.push(StopResidual {
                t_start_s: t_s[start],
                t_end_s: t_s[end],
                peak_to_peak_m: hi - lo,
                rms_m: (sq / (end - start + 1) as f64).sqrt(),
            });
            k = end + 1;
        } else {
            k += 1;
        }
    }
    stops
}

/// Which mode a shaper follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShapeMode {
    /// The end-effector mode (the lowest with the scene's participation), the estimator's
    /// `ee_mode`.
    EndEffector,
    /// The first mode, `f1_hz`.
    First,
}

/// What [`shape`] produced.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeResult {
    /// The shaped path (same sample period; longer by the last impulse time at the end).
    pub path: SampledPath,
    /// The design frequency at each output sample, Hz.
    pub design_hz: Vec<f64>,
    /// Time added to the move, s.
    pub added_s: f64,
}

/// Shape `path` with a time-varying shaper of `kind` following `mode` at the pose of each
/// output sample (the estimator at the previous output pose, as online), damping ratio
/// from the scene at that frequency. The path is continued at its last sample until the
/// output has settled there.
pub fn shape(
    scene: &Scene,
    path: &SampledPath,
    kind: ShaperKind,
    mode: ShapeMode,
) -> Result<ShapeResult, StudyError> {
    path.check(f64::INFINITY)?;
    let mut est = estimator(scene, true)?;
    let mut shaper =
        OnlineShaper::new(kind, path.dt_s, DEFAULT_MIN_FREQUENCY_HZ).map_err(StudyError::from)?;
    let damping: Damping = scene.damping;
    let last = path.positions_m[path.positions_m.len() - 1];
    let mut out = Vec::with_capacity(path.positions_m.len());
    let mut design = Vec::with_capacity(path.positions_m.len());
    let mut y = path.positions_m[0];
    let tol = 1e-9;
    let mut k = 0usize;
    let max = path.positions_m.len() + (1.0 / (DEFAULT_MIN_FREQUENCY_HZ * path.dt_s)) as usize * 2;
    loop {
        let t = k as f64 * path.dt_s;
        solve_pose(&mut est, scene, &y, t)?;
        let e = est.estimate();
        let f = match mode {
            ShapeMode::EndEffector => super::points::ee_mode_hz(e),
            ShapeMode::First => e.f1_hz,
        };
        let zeta = damping.modal_ratio(2.0 * std::f64::consts::PI * f);
        let x = path.positions_m.get(k).copied().unwrap_or(last);
        y = shaper.push(x, f, zeta);
        out.push(y);
        design.push(shaper.design().map(|d| d.0).unwrap_or(f64::NAN));
        k += 1;
        if k >= path.positions_m.len() && (y - last).norm() <= tol {
            // settled: the output holds the last sample exactly from here on
            out.push(last);
            design.push(*design.last().unwrap_or(&f64::NAN));
            break;
        }
        if k > max {
            return Err(StudyError::Build(
                "the shaped path did not settle at the path's end (no valid mode estimate?)".into(),
            ));
        }
    }
    let added_s = (out.len() as f64 - path.positions_m.len() as f64) * path.dt_s;
    Ok(ShapeResult {
        path: SampledPath {
            dt_s: path.dt_s,
            positions_m: out,
            at_rest_ends: path.at_rest_ends,
        },
        design_hz: design,
        added_s: added_s.max(0.0),
    })
}
