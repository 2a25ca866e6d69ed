//! The per-cycle pipeline and the offline reference pipeline.
//!
//! [`Estimator`] owns every buffer of one cycle — geometry, the active-set tension solver,
//! the cable models and the structured modal solver — sized in [`Estimator::new`].
//! [`Estimator::update`] runs pose → kinematics → tension distribution → cable models →
//! first mode and end-effector mode, and returns an [`Estimate`] whose
//! [`Estimate::status`] says whether its numbers are valid. It never allocates, never
//! blocks, and every loop in it is bounded; bad input and non-convergence come out as
//! status codes, never as a panic, and a non-ok estimate carries NaN frequencies rather
//! than stale ones.
//!
//! [`reference_analysis`] is the offline reference of the same model: Clarabel for the
//! tensions, dense assembly and a dense generalized eigensolver for every frequency.

use crate::cable::{up_frame, CableError, CableModel};
use crate::kinematics::{Geometry, KinematicsError, Pose};
use crate::modal::{self, lambda_to_hz, ModalError, ModalParams, ModalSolver, Root};
use crate::scene::{ElementKind, Scene, MAX_CABLES};
use crate::tension::{TensionError, TensionInfo, TensionParams, TensionSolver};
use nalgebra::{Matrix3, Matrix6, Vector3};

pub use cablevib_ipc::StatusCode as Status;

/// Why a cycle's estimate is not ok (the detail behind [`Status`]). Copy, no allocation.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum EstimatorError {
    /// Input rejected before any computation.
    #[error("invalid input: {0}")]
    Input(&'static str),
    /// Kinematics failed.
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
    /// Tension distribution failed.
    #[error(transparent)]
    Tension(#[from] TensionError),
    /// Element model failed.
    #[error(transparent)]
    Cable(#[from] CableError),
    /// Eigen solver failed.
    #[error(transparent)]
    Modal(#[from] ModalError),
    /// The structure matrix has lower rank than the scene's design pose.
    #[error("structure matrix rank {rank} < {expected}: the pose is singular")]
    RankDeficient {
        /// Rank at this pose.
        rank: u32,
        /// Rank at the scene's default pose.
        expected: u32,
    },
}

impl EstimatorError {
    /// The status code this error is reported with.
    pub fn status(&self) -> Status {
        match self {
            EstimatorError::Input(msg) => {
                if msg.contains("quaternion") {
                    Status::NonUnitQuaternion
                } else if msg.contains("t_min") {
                    Status::TminOutOfRange
                } else if msg.contains("outside") {
                    Status::OutsideWorkspace
                } else {
                    Status::InvalidInput
                }
            }
            EstimatorError::Kinematics(KinematicsError::NonFinite) => Status::InvalidInput,
            EstimatorError::Kinematics(KinematicsError::CableTooShort { .. }) => {
                Status::OutsideWorkspace
            }
            EstimatorError::Tension(TensionError::Infeasible { .. }) => Status::TensionInfeasible,
            EstimatorError::Tension(TensionError::InvalidBounds { .. }) => Status::TminOutOfRange,
            EstimatorError::Tension(TensionError::NonFinite) => Status::InvalidInput,
            EstimatorError::Tension(
                TensionError::NotConverged { .. } | TensionError::ReferenceFailed { .. },
            ) => Status::NotConverged,
            EstimatorError::Cable(_) => Status::RankDeficient,
            EstimatorError::Modal(ModalError::NotPositiveDefinite(_)) => Status::RankDeficient,
            EstimatorError::Modal(_) => Status::NotConverged,
            EstimatorError::RankDeficient { .. } => Status::RankDeficient,
        }
    }
}

/// Parameters of the estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatorParams {
    /// Tension solver parameters.
    pub tension: TensionParams,
    /// Eigen solver parameters.
    pub modal: ModalParams,
    /// A pose step larger than this (m) forces a cold start.
    pub warm_jump_m: f64,
    /// A relative T_min change larger than this forces a cold start.
    pub warm_t_min_change: f64,
    /// Tolerance on the quaternion norm.
    pub quaternion_tol: f64,
    /// How far outside the anchors' bounding box (m) a position may be before it is rejected.
    pub workspace_margin_m: f64,
    /// Compute the end-effector mode (costs a scan over the string modes below it).
    pub ee_mode: bool,
}

impl Default for EstimatorParams {
    fn default() -> Self {
        EstimatorParams {
            tension: TensionParams::default(),
            modal: ModalParams::default(),
            warm_jump_m: 0.005,
            warm_t_min_change: 1e-3,
            quaternion_tol: 1e-6,
            workspace_margin_m: 0.0,
            ee_mode: true,
        }
    }
}

/// The result of one cycle. Fixed size, Copy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Whether the numbers below are valid for this pose.
    pub status: Status,
    /// The detail when `status` is not ok.
    pub error: Option<EstimatorError>,
    /// Number of cables (valid entries of `tensions_n`).
    pub n_cables: usize,
    /// Cable tensions, N (for `TensionInfeasible`: the closest achievable, flagged).
    pub tensions_n: [f64; MAX_CABLES],
    /// First natural frequency of the whole model, Hz (NaN unless ok).
    pub f1_hz: f64,
    /// End-effector participation of the first mode (0 ..= 1).
    pub f1_ee_participation: f64,
    /// Frequency of the lowest mode with end-effector participation ≥ the scene's
    /// threshold, Hz. When no mode reaches the threshold within the bounded scan (a very
    /// light end-effector, or its character split across an avoided crossing), the mode
    /// with the largest participation found — `ee_mode_participation` is then below the
    /// threshold. NaN unless ok or when not computed.
    pub ee_mode_hz: f64,
    /// Its participation.
    pub ee_mode_participation: f64,
    /// Static end-effector stiffness, translational block, N/m (NaN unless ok).
    pub stiffness_n_m: Matrix3<f64>,
    /// Static end-effector stiffness, 6 × 6 for a rigid body (N/m, N/rad, N·m/rad; the
    /// translational 3 × 3 block for a point mass, zeros elsewhere).
    pub stiffness6: Matrix6<f64>,
    /// 3 (point mass) or 6 (rigid body).
    pub stiffness_dim: usize,
    /// Tension solver: active-set changes in this cycle.
    pub tension_iterations: u32,
    /// Tension solver: the previous active set was optimal again.
    pub tension_warm: bool,
    /// Evaluations of the dynamic stiffness D(λ) in this cycle.
    pub eigen_evaluations: u32,
    /// Relative residual |μ₁(D(λ₁))| / ‖D‖ of the first root.
    pub eigen_residual: f64,
    /// The first-mode iteration started cold.
    pub cold_start: bool,
}

impl Estimate {
    fn empty(n: usize) -> Estimate {
        Estimate {
            status: Status::NoPoseYet,
            error: None,
            n_cables: n,
            tensions_n: [f64::NAN; MAX_CABLES],
            f1_hz: f64::NAN,
            f1_ee_participation: f64::NAN,
            ee_mode_hz: f64::NAN,
            ee_mode_participation: f64::NAN,
            stiffness_n_m: Matrix3::repeat(f64::NAN),
            stiffness6: Matrix6::repeat(f64::NAN),
            stiffness_dim: 3,
            tension_iterations: 0,
            tension_warm: false,
            eigen_evaluations: 0,
            eigen_residual: f64::NAN,
            cold_start: true,
        }
    }
    /// Tensions of the cables, N.
    pub fn tensions(&self) -> &[f64] {
        &self.tensions_n[..self.n_cables]
    }
    /// True when the status is ok.
    pub fn is_ok(&self) -> bool {
        self.status == Status::Ok
    }
}

/// What `element = "auto"` picked, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct AutoChoice {
    /// The model picked.
    pub element: ElementKind,
    /// Elements per cable of the pick (1 for massless and continuous).
    pub elements_per_cable: usize,
    /// Its largest relative f1 error against the reference over the sample poses.
    pub predicted_error: f64,
    /// The tolerance it had to meet.
    pub tolerance: f64,
    /// Every candidate tried, cheapest first: (model, N, largest relative f1 error).
    pub candidates: Vec<(ElementKind, usize, f64)>,
    /// The reference: the catenary element with this many elements per cable.
    pub reference_elements: usize,
    /// Sample poses used (the default pose and feasible poses on the 0.75 m circle).
    pub poses: usize,
    /// Largest Irvine parameter λ² = (γ⊥ L / T)² · EA / T over the cables at the default
    /// pose (sag matters when it is not ≪ 1).
    pub irvine_lambda2: f64,
    /// Total cable mass over end-effector mass.
    pub mass_ratio: f64,
}

impl std::fmt::Display for AutoChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = |el: ElementKind, n: usize| {
            if el.is_discrete() {
                format!("{} × {n}", el.as_str())
            } else {
                el.as_str().to_string()
            }
        };
        write!(
            f,
            "auto picked {}: predicted f1 error {:.2e} (tolerance {:.1e}; largest over {} poses against catenary × {}; Irvine λ² ≤ {:.2e}, cable/end-effector mass ratio {:.3}). Tried:",
            name(self.element, self.elements_per_cable),
            self.predicted_error,
            self.tolerance,
            self.poses,
            self.reference_elements,
            self.irvine_lambda2,
            self.mass_ratio
        )?;
        for (el, n, err) in &self.candidates {
            write!(f, " {} {:.2e};", name(*el, *n), err)?;
        }
        Ok(())
    }
}

/// Resolve `element = "auto"`: evaluate, at the default pose and at feasible poses of the
/// 0.75 m circle, the f1 of each candidate model in order of per-cycle cost — massless
/// cables, the continuous string (the N → ∞ limit of FEM, at the same cost as any FEM N),
/// the catenary element at N = 4 and 16 — against the converged reference (catenary,
/// N = 64), and pick the first whose largest relative error is within
/// `model.f1_tolerance`. The reference itself is the fallback. Allocates: set-up only.
pub fn resolve_auto(scene: &Scene) -> Result<(Scene, AutoChoice), BuildError> {
    const REF_N: usize = 64;
    let tol = scene.model.f1_tolerance;
    let reference = scene.with_model(ElementKind::Catenary, REF_N);
    let frame = up_frame(&scene.gravity_m_s2);
    let mut poses = vec![Pose {
        position_m: scene.ee_position_m,
        orientation_wxyz: scene.ee_orientation_wxyz,
    }];
    for k in 0..8 {
        let th = k as f64 * std::f64::consts::FRAC_PI_4;
        poses.push(Pose {
            position_m: scene.ee_position_m
                + frame.column(0) * (0.75 * th.cos())
                + frame.column(1) * (0.75 * th.sin()),
            orientation_wxyz: scene.ee_orientation_wxyz,
        });
    }
    let f1_of = |s: &Scene, pose: &Pose| -> Option<f64> {
        let p = EstimatorParams {
            ee_mode: false,
            ..EstimatorParams::default()
        };
        let mut est = Estimator::with_params(s, p).ok()?;
        let e = est.update(pose, s.t_min_n);
        e.is_ok().then_some(e.f1_hz)
    };
    let refs: Vec<(Pose, f64)> = poses
        .iter()
        .filter_map(|pose| f1_of(&reference, pose).map(|f| (*pose, f)))
        .collect();
    if refs.is_empty() {
        Estimator::with_params(&reference, EstimatorParams::default())?;
        return Err(BuildError::DefaultPose {
            scene: scene.name.clone(),
            reason: EstimatorError::Input("no feasible pose to choose the auto model"),
        });
    }
    let mut massless = scene.with_model(ElementKind::Massless, 1);
    massless.model.geometric_stiffness = true;
    let list = [
        massless,
        scene.with_model(ElementKind::Continuous, 1),
        scene.with_model(ElementKind::Catenary, 4),
        scene.with_model(ElementKind::Catenary, 16),
    ];
    let mut candidates = Vec::new();
    let mut pick: Option<(Scene, f64)> = None;
    for cand in list {
        let worst = refs
            .iter()
            .map(|(pose, fr)| f1_of(&cand, pose).map_or(f64::INFINITY, |f| (f - fr).abs() / fr))
            .fold(0.0f64, f64::max);
        candidates.push((cand.model.element, cand.model.elements_per_cable, worst));
        if pick.is_none() && worst <= tol {
            pick = Some((cand, worst));
        }
    }
    let (chosen, err) = pick.unwrap_or((reference, 0.0));
    // Diagnostics at the default pose.
    let mut g = Geometry::new(scene.n_cables());
    let _ = g.update(
        scene.cables.iter().map(|c| &c.anchor_m),
        &scene.ee_position_m,
    );
    let t = crate::tension::clarabel_reference(&g, &scene.wrench_n(), scene.t_min_n, scene.t_max_n)
        .unwrap_or_default();
    let gn = scene.gravity_m_s2.norm();
    let down = if gn > 0.0 {
        scene.gravity_m_s2 / gn
    } else {
        Vector3::zeros()
    };
    let mut irvine = 0.0f64;
    let mut cable_mass = 0.0;
    for (i, c) in scene.cables.iter().enumerate() {
        let l = g.length_m[i];
        cable_mass += c.mass_per_length_kg_m * l;
        if let Some(&ti) = t.get(i) {
            let s = g.unit[i];
            let perp = (down - s * s.dot(&down)).norm();
            let gam = c.mass_per_length_kg_m * gn * perp;
            irvine = irvine.max((gam * l / ti).powi(2) * c.ea_n() / ti);
        }
    }
    let choice = AutoChoice {
        element: chosen.model.element,
        elements_per_cable: chosen.model.elements_per_cable,
        predicted_error: err,
        tolerance: tol,
        candidates,
        reference_elements: REF_N,
        poses: refs.len(),
        irvine_lambda2: irvine,
        mass_ratio: cable_mass / scene.ee_mass_kg,
    };
    Ok((chosen, choice))
}

/// The real-time estimator of one scene.
#[derive(Debug, Clone)]
pub struct Estimator {
    scene: Scene,
    params: EstimatorParams,
    frame: Matrix3<f64>,
    geometry: Geometry,
    tension: TensionSolver,
    models: Vec<CableModel>,
    modal: ModalSolver,
    expected_rank: u32,
    bounds: (Vector3<f64>, Vector3<f64>),
    last_ok_position: Option<Vector3<f64>>,
    last_lambda1: f64,
    prev_lambda1: f64,
    last_t_min_n: f64,
    estimate: Estimate,
    /// Scratch solvers of the inverse query (so it leaves the cycle's warm state alone).
    inv_geometry: Geometry,
    inv_tension: TensionSolver,
    inv_models: Vec<CableModel>,
    inv_modal: ModalSolver,
    auto: Option<AutoChoice>,
}

/// The answer to "which T_min reaches f1 ≥ f_required at this pose".
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TminAnswer {
    /// The smallest T_min found, N (within the bracket tolerance).
    pub t_min_n: f64,
    /// f1 at that T_min, Hz (≥ the requirement up to 1e-9 relative).
    pub f1_hz: f64,
    /// Evaluations of the forward model (tensions + f1) spent.
    pub evaluations: u32,
}

/// Errors of the inverse T_min query.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum TminQueryError {
    /// The requirement is not finite and positive.
    #[error("required f1 {0} Hz must be finite and > 0")]
    BadRequirement(f64),
    /// Even the largest feasible T_min does not reach the requirement.
    #[error("f1 ≥ {required_hz:.4} Hz is unreachable: the largest feasible T_min {t_min_n:.3} N gives {f1_max_hz:.4} Hz")]
    Unreachable {
        /// Required, Hz.
        required_hz: f64,
        /// Best f1, Hz.
        f1_max_hz: f64,
        /// At this T_min, N.
        t_min_n: f64,
    },
    /// The pose itself is invalid or infeasible at every T_min.
    #[error(transparent)]
    Pose(#[from] EstimatorError),
}

/// Errors building an estimator.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The scene's default pose is not solvable: the robot is unusable as described.
    #[error("scene `{scene}` at its default pose: {reason}")]
    DefaultPose {
        /// Scene name.
        scene: String,
        /// Why.
        reason: EstimatorError,
    },
}

impl Estimator {
    /// Build for a scene with default parameters (the scene's participation threshold).
    pub fn new(scene: &Scene) -> Result<Estimator, BuildError> {
        let mut p = EstimatorParams::default();
        p.modal.ee_participation_min = scene.model.ee_participation_min;
        Self::with_params(scene, p)
    }

    /// Build with explicit parameters. Allocates everything the cycle needs and checks
    /// the scene's default pose.
    pub fn with_params(scene: &Scene, params: EstimatorParams) -> Result<Estimator, BuildError> {
        if scene.model.element == ElementKind::Auto {
            let (resolved, choice) = resolve_auto(scene)?;
            let mut est = Self::with_params(&resolved, params)?;
            est.auto = Some(choice);
            return Ok(est);
        }
        let n = scene.n_cables();
        let zero = placeholder_model();
        let mut est = Estimator {
            scene: scene.clone(),
            params,
            frame: up_frame(&scene.gravity_m_s2),
            geometry: Geometry::new(n),
            tension: TensionSolver::new(n, params.tension),
            models: vec![zero; n],
            modal: ModalSolver::new(params.modal),
            expected_rank: 0,
            bounds: scene.frame_bounds_m(),
            last_ok_position: None,
            last_lambda1: f64::NAN,
            prev_lambda1: f64::NAN,
            last_t_min_n: f64::NAN,
            estimate: Estimate::empty(n),
            inv_geometry: Geometry::new(n),
            inv_tension: TensionSolver::new(n, params.tension),
            inv_models: vec![zero; n],
            inv_modal: ModalSolver::new(ModalParams {
                certify: false,
                ..params.modal
            }),
            auto: None,
        };
        // Expected rank: the rank at the default pose.
        let default_pose = |e: EstimatorError| BuildError::DefaultPose {
            scene: scene.name.clone(),
            reason: e,
        };
        let pose = Pose {
            position_m: scene.ee_position_m,
            orientation_wxyz: scene.ee_orientation_wxyz,
        };
        update_geometry(scene, &mut est.geometry, &pose).map_err(|e| default_pose(e.into()))?;
        est.tension
            .solve_wrench(&est.geometry, &wrench6(scene), scene.t_min_n, scene.t_max_n)
            .map_err(|e| default_pose(e.into()))?;
        est.expected_rank = est.tension.info().rank;
        est.tension.reset_warm_start();
        Ok(est)
    }

    /// What `element = "auto"` picked (None for an explicit model).
    pub fn auto_choice(&self) -> Option<&AutoChoice> {
        self.auto.as_ref()
    }

    /// The scene (with the `auto` model resolved).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The parameters.
    pub fn params(&self) -> &EstimatorParams {
        &self.params
    }

    /// The last estimate.
    pub fn estimate(&self) -> &Estimate {
        &self.estimate
    }

    /// The cable models of the last successful cycle.
    pub fn cable_models(&self) -> &[CableModel] {
        &self.models
    }

    /// The structured eigen solver as loaded at the last pose (its sum rules, counters).
    pub fn modal(&self) -> &ModalSolver {
        &self.modal
    }

    /// End-effector bookkeeping counters (see [`ModalSolver::rescan_counts`]).
    pub fn rescan_counts(&self) -> modal::RescanCounts {
        self.modal.rescan_counts()
    }

    /// Info of the last tension solve.
    pub fn tension_info(&self) -> TensionInfo {
        self.tension.info()
    }

    /// Forget every warm start: the next cycle starts cold.
    pub fn reset(&mut self) {
        self.last_ok_position = None;
        self.last_lambda1 = f64::NAN;
        self.tension.reset_warm_start();
    }

    /// The smallest T_min (N) for which f1 at `pose` reaches `f_required_hz` (the paper's
    /// conclusion 4), on the fast path: regula falsi (Illinois) on f1(T)² − f², which is
    /// nearly linear in T_min (f1 ∝ √T_min), bracketed in [10⁻⁶ T_max, T_max] (or the largest
    /// feasible T_min below T_max), at most 80 forward evaluations. Uses its own scratch
    /// solvers: the cycle's warm state is untouched. No allocation.
    pub fn t_min_for_f1(
        &mut self,
        pose: &Pose,
        f_required_hz: f64,
    ) -> Result<TminAnswer, TminQueryError> {
        self.t_min_for_f1_near(pose, f_required_hz, None)
    }

    /// [`Self::t_min_for_f1`] warm-started from `hint` (N: the last answer, or the current
    /// T_min): a ±2 % bracket around it is tried first (two evaluations, then a few
    /// regula-falsi steps), the full search only when the answer is not in it. A service
    /// answering margin requests every cycle pays a few evaluations per request.
    pub fn t_min_for_f1_near(
        &mut self,
        pose: &Pose,
        f_required_hz: f64,
        hint: Option<f64>,
    ) -> Result<TminAnswer, TminQueryError> {
        if !(f_required_hz.is_finite() && f_required_hz > 0.0) {
            return Err(TminQueryError::BadRequirement(f_required_hz));
        }
        if !pose.is_finite() {
            return Err(EstimatorError::Input("non-finite pose").into());
        }
        if !pose.has_unit_quaternion(self.params.quaternion_tol) {
            return Err(EstimatorError::Input("quaternion is not of unit norm").into());
        }
        update_geometry(&self.scene, &mut self.inv_geometry, pose).map_err(EstimatorError::from)?;
        self.inv_tension.reset_warm_start();
        let mut evals = 0u32;
        let mut warm = None;
        let t_max = self.scene.t_max_n;
        let lo0 = 1e-6 * t_max;
        if let Some(h) = hint.filter(|h| h.is_finite() && *h > lo0 && *h < t_max) {
            let (a, b) = ((0.98 * h).max(lo0), (1.02 * h).min(t_max));
            if let (Ok(fa), Ok(fb)) = (
                self.inverse_f1(pose, a, &mut warm, &mut evals),
                self.inverse_f1(pose, b, &mut warm, &mut evals),
            ) {
                if fa < f_required_hz && fb >= f_required_hz {
                    return self.inverse_refine(
                        pose,
                        f_required_hz,
                        (a, fa),
                        (b, fb),
                        &mut warm,
                        &mut evals,
                    );
                }
            }
        }
        // Largest feasible T_min: T_max itself, or bisect the feasibility boundary.
        let mut hi = t_max;
        let mut f_hi = self.inverse_f1(pose, hi, &mut warm, &mut evals);
        if f_hi.is_err() {
            let mut ok = lo0;
            let first = self.inverse_f1(pose, ok, &mut warm, &mut evals)?;
            let mut f_ok = first;
            let mut bad = t_max;
            for _ in 0..50 {
                let mid = 0.5 * (ok + bad);
                match self.inverse_f1(pose, mid, &mut warm, &mut evals) {
                    Ok(f) => {
                        ok = mid;
                        f_ok = f;
                    }
                    Err(_) => bad = mid,
                }
                if bad - ok <= 1e-12 * t_max {
                    break;
                }
            }
            hi = ok;
            f_hi = Ok(f_ok);
        }
        let f_hi = f_hi?;
        if f_hi < f_required_hz {
            return Err(TminQueryError::Unreachable {
                required_hz: f_required_hz,
                f1_max_hz: f_hi,
                t_min_n: hi,
            });
        }
        let lo = lo0;
        let f_lo = self.inverse_f1(pose, lo, &mut warm, &mut evals)?;
        if f_lo >= f_required_hz {
            return Ok(TminAnswer {
                t_min_n: lo,
                f1_hz: f_lo,
                evaluations: evals,
            });
        }
        self.inverse_refine(
            pose,
            f_required_hz,
            (lo, f_lo),
            (hi, f_hi),
            &mut warm,
            &mut evals,
        )
    }

    /// Regula falsi (Illinois) on f1(T)² − f² inside a bracket with f1(lo) < f ≤ f1(hi).
    fn inverse_refine(
        &mut self,
        pose: &Pose,
        f_required_hz: f64,
        (mut lo, f_lo): (f64, f64),
        (mut hi, f_hi): (f64, f64),
        warm: &mut Option<f64>,
        evals: &mut u32,
    ) -> Result<TminAnswer, TminQueryError> {
        let t_max = self.scene.t_max_n;
        let target = f_required_hz * f_required_hz;
        let mut g_lo = f_lo * f_lo - target;
        let mut g_hi = f_hi * f_hi - target;
        let mut best = (hi, f_hi);
        let mut side = 0i8;
        for _ in 0..80 {
            let t = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
            let t = if t > lo && t < hi { t } else { 0.5 * (lo + hi) };
            let f = self.inverse_f1(pose, t, warm, evals)?;
            let g = f * f - target;
            if g >= 0.0 {
                hi = t;
                g_hi = g;
                best = (t, f);
                if side == 1 {
                    g_lo *= 0.5;
                }
                side = 1;
            } else {
                lo = t;
                g_lo = g;
                if side == -1 {
                    g_hi *= 0.5;
                }
                side = -1;
            }
            if (best.1 - f_required_hz) <= 1e-10 * f_required_hz || hi - lo <= 1e-12 * t_max {
                break;
            }
        }
        Ok(TminAnswer {
            t_min_n: best.0,
            f1_hz: best.1,
            evaluations: *evals,
        })
    }

    /// f1 (Hz) at `pose` (geometry already in `inv_geometry`) for T_min = `t_min_n`.
    fn inverse_f1(
        &mut self,
        pose: &Pose,
        t_min_n: f64,
        warm: &mut Option<f64>,
        evals: &mut u32,
    ) -> Result<f64, EstimatorError> {
        *evals += 1;
        self.inv_tension.solve_wrench(
            &self.inv_geometry,
            &wrench6(&self.scene),
            t_min_n,
            self.scene.t_max_n,
        )?;
        let t = self.inv_tension.tensions_n();
        fill_models(
            &self.scene,
            &self.frame,
            &self.inv_geometry,
            t,
            &mut self.inv_models,
        )?;
        load_modal(
            &self.scene,
            &mut self.inv_modal,
            &self.inv_models,
            &self.inv_geometry,
            t,
            pose,
        );
        let r = self.inv_modal.first_root(*warm)?;
        *warm = Some(r.lambda);
        Ok(lambda_to_hz(r.lambda))
    }

    /// One cycle: pose and T_min (N, the same for every cable) → estimate.
    pub fn update(&mut self, pose: &Pose, t_min_n: f64) -> &Estimate {
        let n = self.scene.n_cables();
        let mut e = Estimate::empty(n);
        match self.run(pose, t_min_n, &mut e) {
            Ok(()) => {
                e.status = Status::Ok;
                self.last_ok_position = Some(pose.position_m);
                self.last_t_min_n = t_min_n;
            }
            Err(err) => {
                e.status = err.status();
                e.error = Some(err);
                e.f1_hz = f64::NAN;
                e.ee_mode_hz = f64::NAN;
                e.stiffness_n_m = Matrix3::repeat(f64::NAN);
                e.stiffness6 = Matrix6::repeat(f64::NAN);
                if e.status != Status::TensionInfeasible {
                    e.tensions_n = [f64::NAN; MAX_CABLES];
                }
                self.last_ok_position = None;
                self.last_lambda1 = f64::NAN;
            }
        }
        self.estimate = e;
        &self.estimate
    }

    fn run(&mut self, pose: &Pose, t_min_n: f64, e: &mut Estimate) -> Result<(), EstimatorError> {
        let n = self.scene.n_cables();
        if !pose.is_finite() {
            return Err(EstimatorError::Input("non-finite pose"));
        }
        if !pose.has_unit_quaternion(self.params.quaternion_tol) {
            return Err(EstimatorError::Input("quaternion is not of unit norm"));
        }
        if !(t_min_n.is_finite() && t_min_n >= 0.0 && t_min_n <= self.scene.t_max_n) {
            return Err(EstimatorError::Input(
                "t_min outside [0, t_max] or not finite",
            ));
        }
        let m = self.params.workspace_margin_m;
        let p = pose.position_m;
        // Axes along which the anchors are flat (all at one height for a suspended robot,
        // a planar robot's normal) do not bound the workspace; tension feasibility does.
        let flat = |i: usize| self.bounds.1[i] - self.bounds.0[i] <= 1e-9;
        if (0..3).any(|i| !flat(i) && (p[i] < self.bounds.0[i] - m || p[i] > self.bounds.1[i] + m))
        {
            return Err(EstimatorError::Input("position outside the anchors' frame"));
        }
        update_geometry(&self.scene, &mut self.geometry, pose)?;
        let warm = match self.last_ok_position {
            Some(q) => {
                (q - p).norm() <= self.params.warm_jump_m
                    && (t_min_n - self.last_t_min_n).abs()
                        <= self.params.warm_t_min_change * self.last_t_min_n
            }
            None => false,
        };
        if !warm {
            self.tension.reset_warm_start();
            self.modal.reset_tracking();
        }
        let wrench = wrench6(&self.scene);
        let res = self
            .tension
            .solve_wrench(&self.geometry, &wrench, t_min_n, self.scene.t_max_n)
            .map(|_| ());
        let info = self.tension.info();
        e.tension_iterations = info.iterations;
        e.tension_warm = info.warm_start_accepted;
        e.tensions_n[..n].copy_from_slice(self.tension.tensions_n());
        res?;
        if info.rank < self.expected_rank {
            return Err(EstimatorError::RankDeficient {
                rank: info.rank,
                expected: self.expected_rank,
            });
        }
        fill_models(
            &self.scene,
            &self.frame,
            &self.geometry,
            &e.tensions_n[..n],
            &mut self.models,
        )?;
        load_modal(
            &self.scene,
            &mut self.modal,
            &self.models,
            &self.geometry,
            &e.tensions_n[..n],
            pose,
        );
        let start = self.modal.evaluations();
        // Predictor: linear extrapolation of the last two cycles' λ₁.
        let warm_l = if warm && self.last_lambda1.is_finite() {
            let pred = if self.prev_lambda1.is_finite() {
                2.0 * self.last_lambda1 - self.prev_lambda1
            } else {
                self.last_lambda1
            };
            Some(if pred > 0.0 { pred } else { self.last_lambda1 })
        } else {
            None
        };
        e.cold_start = warm_l.is_none();
        let r1 = self.modal.first_root(warm_l);
        let r1 = match r1 {
            Ok(r) => r,
            Err(err) => {
                e.eigen_evaluations = self.modal.evaluations() - start;
                return Err(err.into());
            }
        };
        e.f1_hz = lambda_to_hz(r1.lambda);
        e.f1_ee_participation = r1.ee_participation;
        e.eigen_residual = r1.residual;
        self.prev_lambda1 = if warm { self.last_lambda1 } else { f64::NAN };
        self.last_lambda1 = r1.lambda;
        if self.params.ee_mode {
            // No mode reaching the participation threshold within the bounded scan leaves
            // the end-effector mode unknown (NaN) without invalidating f1 and the tensions.
            if let Ok(ree) = self.modal.ee_mode_tracked(&r1, warm_l.is_some()) {
                e.ee_mode_hz = lambda_to_hz(ree.lambda);
                e.ee_mode_participation = ree.ee_participation;
            }
        }
        if self.scene.rigid {
            let k6 = self.modal.static_stiffness6();
            e.stiffness6 = k6;
            e.stiffness_n_m = k6.fixed_view::<3, 3>(0, 0).into_owned();
            e.stiffness_dim = 6;
        } else {
            let mut k = Matrix3::zeros();
            for cm in &self.models {
                k += cm.static_stiffness;
            }
            e.stiffness_n_m = k;
            e.stiffness6 = Matrix6::zeros();
            e.stiffness6.fixed_view_mut::<3, 3>(0, 0).copy_from(&k);
            e.stiffness_dim = 3;
        }
        e.eigen_evaluations = self.modal.evaluations() - start;
        Ok(())
    }
}

/// Cable geometry of `scene` at `pose`: rigid-body attachments rotated by the pose's
/// orientation, or all cables at the centroid. No allocation.
fn update_geometry(scene: &Scene, g: &mut Geometry, pose: &Pose) -> Result<(), KinematicsError> {
    if scene.rigid {
        let rot = crate::kinematics::rotation_of(&pose.orientation_wxyz);
        g.update_rigid(
            scene.cables.iter().map(|c| &c.anchor_m),
            scene.cables.iter().map(|c| &c.attachment_m),
            &pose.position_m,
            &rot,
        )
    } else {
        g.update(scene.cables.iter().map(|c| &c.anchor_m), &pose.position_m)
    }
}

/// The wrench the cables carry as (force N, moment N·m).
fn wrench6(scene: &Scene) -> [f64; 6] {
    let f = scene.wrench_n();
    [f.x, f.y, f.z, 0.0, 0.0, 0.0]
}

/// Cable models of `scene` for geometry `g` and tensions into `out`. No allocation.
fn fill_models(
    scene: &Scene,
    frame: &Matrix3<f64>,
    g: &Geometry,
    tensions_n: &[f64],
    out: &mut [CableModel],
) -> Result<(), CableError> {
    let gn = scene.gravity_m_s2.norm();
    for (i, (c, m)) in scene.cables.iter().zip(out.iter_mut()).enumerate() {
        *m = CableModel::build(
            scene.model.element,
            scene.model.elements_per_cable,
            &g.unit[i],
            g.length_m[i],
            tensions_n[i],
            c.ea_n(),
            c.mass_per_length_kg_m,
            c.mass_per_length_kg_m * gn,
            frame,
            scene.model.geometric_stiffness,
        )?;
    }
    Ok(())
}

/// Load `modal` with the models: a point mass, or a rigid body at `pose` (world inertia
/// R I Rᵀ and the tensions' rotational geometric stiffness). No allocation.
fn load_modal(
    scene: &Scene,
    modal: &mut ModalSolver,
    models: &[CableModel],
    g: &Geometry,
    tensions_n: &[f64],
    pose: &Pose,
) {
    if scene.rigid {
        let rot = crate::kinematics::rotation_of(&pose.orientation_wxyz);
        let inertia = rot * scene.ee_inertia_kg_m2 * rot.transpose();
        let kgeo = modal::rigid_geometric_stiffness(&g.unit, &g.arm_m, tensions_n);
        modal.load_rigid(models, scene.ee_mass_kg, &inertia, &g.arm_m, &kgeo);
    } else {
        modal.load(models, scene.ee_mass_kg);
    }
}

/// A valid stand-in cable model (a 1 N/m massless spring) for preallocated model buffers.
fn placeholder_model() -> CableModel {
    CableModel::build(
        ElementKind::Massless,
        1,
        &Vector3::x(),
        1.0,
        1.0,
        1.0,
        0.0,
        0.0,
        &Matrix3::identity(),
        true,
    )
    .expect("a unit massless spring is a valid model")
}

/// Build the cable models of a scene for given geometry and tensions (allocates a Vec).
pub fn build_models(
    scene: &Scene,
    geometry: &Geometry,
    tensions_n: &[f64],
) -> Result<Vec<CableModel>, CableError> {
    let frame = up_frame(&scene.gravity_m_s2);
    let mut out = vec![placeholder_model(); scene.n_cables()];
    fill_models(scene, &frame, geometry, tensions_n, &mut out)?;
    Ok(out)
}

/// Errors of the reference pipeline.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    /// Kinematics.
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
    /// Tensions.
    #[error(transparent)]
    Tension(#[from] TensionError),
    /// Element models.
    #[error(transparent)]
    Cable(#[from] CableError),
    /// Eigen solve.
    #[error(transparent)]
    Modal(#[from] ModalError),
    /// The auto model could not be resolved.
    #[error("auto model: {0}")]
    Auto(String),
}

/// Everything the dense reference computes for one pose.
#[derive(Debug, Clone)]
pub struct ReferenceAnalysis {
    /// Tensions from Clarabel, N.
    pub tensions_n: Vec<f64>,
    /// Every mode (dense).
    pub modes: modal::DenseModes,
    /// Degrees of freedom of the assembled model.
    pub dof: usize,
    /// Static end-effector stiffness, N/m.
    pub stiffness_n_m: Matrix3<f64>,
}

/// The offline reference: Clarabel tensions, dense K and M, dense eigen-solve (with
/// participations when `vectors`). For `continuous` scenes use the structured solver.
pub fn reference_analysis(
    scene: &Scene,
    position_m: &Vector3<f64>,
    t_min_n: f64,
    vectors: bool,
) -> Result<ReferenceAnalysis, AnalysisError> {
    let pose = Pose {
        position_m: *position_m,
        orientation_wxyz: scene.ee_orientation_wxyz,
    };
    reference_analysis_at(scene, &pose, t_min_n, vectors)
}

/// [`reference_analysis`] at a full pose (orientation matters for a rigid end-effector).
pub fn reference_analysis_at(
    scene: &Scene,
    pose: &Pose,
    t_min_n: f64,
    vectors: bool,
) -> Result<ReferenceAnalysis, AnalysisError> {
    if scene.model.element == ElementKind::Auto {
        let resolved = resolve_auto(scene)
            .map(|(s, _)| s)
            .map_err(|e| AnalysisError::Auto(e.to_string()))?;
        return reference_analysis_at(&resolved, pose, t_min_n, vectors);
    }
    let mut g = Geometry::new(scene.n_cables());
    let rot = crate::kinematics::rotation_of(&pose.orientation_wxyz);
    update_geometry(scene, &mut g, pose)?;
    let t = crate::tension::clarabel_reference_wrench(&g, &wrench6(scene), t_min_n, scene.t_max_n)?;
    let models = build_models(scene, &g, &t)?;
    let mut ee = Matrix6::zeros();
    ee.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Matrix3::identity() * scene.ee_mass_kg));
    let (k, m) = if scene.rigid {
        let inertia = rot * scene.ee_inertia_kg_m2 * rot.transpose();
        let kgeo = modal::rigid_geometric_stiffness(&g.unit, &g.arm_m, &t);
        ee.fixed_view_mut::<3, 3>(3, 3).copy_from(&inertia);
        modal::assemble_rigid(&models, scene.ee_mass_kg, &inertia, &g.arm_m, &kgeo)?
    } else {
        modal::assemble(&models, scene.ee_mass_kg)?
    };
    let dof = k.nrows();
    let dim = if scene.rigid { 6 } else { 3 };
    let modes = modal::dense_modes_ee(&k, &m, &ee, dim, vectors)?;
    let stiffness_n_m = if scene.rigid {
        modal::condense_static(&k, dim)
            .fixed_view::<3, 3>(0, 0)
            .into_owned()
    } else {
        models
            .iter()
            .fold(Matrix3::zeros(), |a, cm| a + cm.static_stiffness)
    };
    Ok(ReferenceAnalysis {
        tensions_n: t,
        modes,
        dof,
        stiffness_n_m,
    })
}

/// The structured solver run once (allocating; for offline use): tensions from the
/// active-set solver, then f1 and the end-effector mode.
pub fn structured_analysis(scene: &Scene, position_m: &Vector3<f64>, t_min_n: f64) -> Estimate {
    match Estimator::new(scene) {
        Ok(mut est) => *est.update(
            &Pose {
                position_m: *position_m,
                orientation_wxyz: scene.ee_orientation_wxyz,
            },
            t_min_n,
        ),
        Err(BuildError::DefaultPose { reason, .. }) => {
            let mut e = Estimate::empty(scene.n_cables());
            e.status = reason.status();
            e.error = Some(reason);
            e
        }
    }
}

/// First root of the structured solver for given cable models (offline helper for tests).
pub fn first_root_of(
    models: &[CableModel],
    ee_mass_kg: f64,
    params: ModalParams,
) -> Result<Root, ModalError> {
    let mut s = ModalSolver::new(params);
    s.load(models, ee_mass_kg);
    s.first_root(None)
}
