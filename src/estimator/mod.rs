//! The per-cycle pipeline and the offline reference pipeline.
//!
//! One cycle ([`Estimator::update`]) takes a pose — centroid position p (m) and orientation
//! quaternion — and the lower tension bounds T_min,i (N): the scene's own per cable
//! ([`Tmin::Scene`]), one value for every cable ([`Tmin::Uniform`]) or one per cable
//! ([`Tmin::PerCable`]), and computes:
//!
//! 1. the cable geometry: unit directions s_i and lengths L_i (m) from the anchors to the
//!    end-effector (to its attachment points for a rigid body);
//! 2. the tension distribution T (N): minimise ½‖T‖² subject to A T = w (w = m g, N, when
//!    the cables carry the weight) and T_min,i ≤ T_i ≤ T_max,i, with the active-set solver
//!    warm-started from the last cycle;
//! 3. the cable models at those tensions (stiffness N/m, mass kg; the scene's element);
//! 4. the first natural frequency f1 = √λ₁ / 2π (Hz, λ in rad²/s²) by the structured
//!    solver, warm-started from a quadratic prediction of the last three cycles' λ₁; its
//!    end-effector participation (0 ..= 1); and, when enabled, the end-effector mode;
//! 5. the static end-effector stiffness (N/m; N/rad and N·m/rad blocks for a rigid body).
//!
//! **Budget.** With [`ModalParams::cycle_evaluations`] finite (the real-time preset,
//! [`EstimatorParams::realtime`]: [`crate::modal::CYCLE_EVALUATIONS`] = 32) a cycle never evaluates
//! D(λ) more often than that: f1 is solved exactly first, the end-effector mode with what is
//! left, and the end-effector work that does not fit is continued in the next cycles; the
//! estimate then carries the last answer and its age ([`EeMode::age_cycles`]).
//! The default ([`EstimatorParams::default`]) is unlimited, for offline analyses.
//!
//! [`Estimator`] owns every buffer of the cycle, sized in [`Estimator::new`]; the cycle
//! returns an [`Estimate`] whose [`Estimate::status`] says whether its numbers are valid.
//! It never allocates, never blocks, and every loop in it is bounded; bad input and
//! non-convergence come out as status codes ([`EstimatorError::status`]), never as a panic,
//! and a non-ok estimate carries NaN frequencies rather than stale ones. The inverse query
//! [`Estimator::t_min_for_f1`] runs the same forward pipeline on its own buffers.
//!
//! **Sagging cables** (`[effects] sag`, the `sagged` pipeline): step 2 is the tension
//! distribution on the cables' elastic catenaries (the least Σ T² on the exact sagged
//! equilibrium, a bounded SQP; the bounds apply to the end-effector-end tension), steps 3-4 the
//! chains about each sagged profile (fem: N elements on the catenary; continuous: the exact
//! N → ∞ limit) and the structured solver of `modal::sagged`; step 5 is D(0) of those chains.
//! A pose where a cable would go slack is the status `CableSlack`. The end-effector mode is
//! found with sag by an ascending sweep of the sagged spectrum (the chains' poles are not
//! known in closed form), spread over the cycles by the cycle's evaluation budget, the
//! last answer reported with its age meanwhile; `modes` gives every mode's participation
//! offline. [`sag_warning`] says when a scene with sag off should have it on.
//!
//! [`reference_analysis`] is the offline reference of the same model: Clarabel for the
//! tensions, dense assembly and a dense generalized eigensolver for every frequency. It
//! reads a [`PoseModel`] (one pose's geometry, tensions, cable models and [`EndEffector`]),
//! built from the same pieces as the cycle's forward model; so does `cablevib modes`.
//! [`resolve_auto`] picks the model of `element = "auto"` scenes. Both allocate.

mod auto;
mod dense_sag_basis;
mod dof_shapes;
mod error;
mod estimate;
mod forward;
mod inverse;
mod modes;
mod params;
mod path_field;
mod pose_model;
mod reference;
mod ritz_basis;
mod sag_check;
mod t_min;

pub use auto::{resolve_auto, AutoChoice};
pub use dense_sag_basis::{dense_sag_pays, DENSE_DOF3_PER_MODE, MAX_DENSE_SAG_DOF};
pub use error::{BuildError, EstimatorError, ReferenceError, RejectedInput, TminQueryError};
pub use estimate::{EeMode, Estimate, Status, Stiffness};
pub use forward::{EndEffector, BEHIND_EXIT_COMPLIANCE_FLOOR};
pub use inverse::{TminAnswer, MAX_EVALUATIONS as TMIN_QUERY_MAX_EVALUATIONS};
pub use modes::{
    check_shapes_memory, shape_nodes, shapes_memory_bytes, BasisError, EeModalBasis, SHAPES_REMEDY,
    SHAPE_BYTES_PER_NODE,
};
pub use params::{EstimatorParams, ParamsError, SagModelParams};
pub use path_field::{
    convective_input, sag_path_field_applies, PathFields, PATH_FIELD_STEP, SECOND_FIELD_PAIRS,
};
pub use pose_model::{build_models, PoseModel};
pub use reference::{
    reference_analysis, reference_analysis_at, structured_analysis, ReferenceAnalysis,
};
pub use ritz_basis::{RitzBasis, RITZ_SWEEPS};
pub use sag_check::{cables_can_sag, sag_warning, sagged_reference, SagWarning};
pub use t_min::Tmin;

use crate::cable::CableModel;
use crate::kinematics::Pose;
use crate::modal::{lambda_to_hz, ModalParams, ModalSolver};
use crate::scene::{is_valid_t_min, ElementKind, Scene, MAX_CABLES};
use crate::tension::TensionInfo;
use forward::{Forward, ForwardParams};
use nalgebra::{Matrix6, Vector3};

/// The real-time estimator of one scene.
#[derive(Debug, Clone)]
pub struct Estimator {
    scene: Scene,
    params: EstimatorParams,
    /// The cycle's forward model (its warm state carries from cycle to cycle).
    cycle: Forward,
    expected_rank: u32,
    last_ok_position: Option<Vector3<f64>>,
    /// The pose of the last ok cycle (what the offline queries of its model refer to).
    loaded_pose: Pose,
    /// λ₁ of the last three warm cycles (rad²/s²; NaN where there is none): the predictor's
    /// history, newest first.
    last_lambda1: f64,
    prev_lambda1: f64,
    prev2_lambda1: f64,
    /// The lower bounds (N) of the last ok cycle, one per cable (the warm-start test).
    last_t_min_n: [f64; MAX_CABLES],
    /// The lower bounds (N) of the current cycle, one per cable.
    t_min_n: [f64; MAX_CABLES],
    /// Each cable's upper bound (N), from the scene.
    t_max_n: [f64; MAX_CABLES],
    estimate: Estimate,
    /// The inverse query's forward model (so it leaves the cycle's warm state alone).
    inverse: Forward,
    auto: Option<AutoChoice>,
    /// The last end-effector answer (Hz, participation, age in cycles), None when unknown.
    last_ee: Option<(f64, f64, u32)>,
}

impl Estimator {
    /// Build for a scene with default parameters (the scene's participation threshold).
    pub fn new(scene: &Scene) -> Result<Estimator, BuildError> {
        Self::with_params(scene, EstimatorParams::default().for_scene(scene))
    }

    /// [`Self::new`] with the real-time preset ([`EstimatorParams::realtime`]), as the
    /// service runs it.
    pub fn realtime(scene: &Scene) -> Result<Estimator, BuildError> {
        Self::with_params(scene, EstimatorParams::realtime().for_scene(scene))
    }

    /// Build with explicit parameters (refused when [`EstimatorParams::check`] fails).
    /// Allocates everything the cycle needs and checks the scene's default pose.
    pub fn with_params(scene: &Scene, params: EstimatorParams) -> Result<Estimator, BuildError> {
        params.check()?;
        if scene.model.element == ElementKind::Auto {
            let (resolved, choice) = resolve_auto(scene)?;
            let mut est = Self::with_params(&resolved, params)?;
            est.auto = Some(choice);
            return Ok(est);
        }
        let n = scene.n_cables();
        check_model_memory(scene)?;
        let mut est = Estimator {
            scene: scene.clone(),
            params,
            cycle: Forward::new(scene, &ForwardParams::cycle(&params)),
            expected_rank: 0,
            last_ok_position: None,
            loaded_pose: Pose::at(scene.ee_position_m),
            last_lambda1: f64::NAN,
            prev_lambda1: f64::NAN,
            prev2_lambda1: f64::NAN,
            last_t_min_n: [f64::NAN; MAX_CABLES],
            t_min_n: Tmin::Scene.per_cable(scene),
            t_max_n: forward::cable_t_max_n(scene),
            estimate: Estimate::empty(n),
            inverse: Forward::new(scene, &ForwardParams::t_min_query(&params)),
            auto: None,
            last_ee: None,
        };
        // Expected rank: the rank at the default pose.
        let default_pose = |e: EstimatorError| BuildError::DefaultPose {
            scene: scene.name.clone(),
            position_m: scene.ee_position_m.into(),
            reason: Box::new(e),
        };
        let pose = Pose {
            position_m: scene.ee_position_m,
            orientation_wxyz: scene.ee_orientation_wxyz,
        };
        let c = &mut est.cycle;
        c.set_pose(scene, &pose)
            .map_err(|e| default_pose(e.into()))?;
        // The structure matrix's rank is set up before feasibility is decided, so a default
        // pose the cables cannot hold (a robot whose force_min is too high there, a T_min override
        // near t_max) still gives it; such a pose is then estimated like any other, with the
        // status TensionInfeasible. Only a default pose with no rank at all is refused.
        let (solved, rank) = c.chord_tensions(scene, &est.t_min_n[..n], params.tension);
        est.expected_rank = rank;
        match solved {
            Ok(_) | Err(crate::tension::TensionError::Infeasible { .. }) => {}
            Err(e) => return Err(default_pose(e.into())),
        }
        if c.is_sagged() && solved.is_ok() {
            // The sagged statics and modes at the default pose: only a failure other than
            // the statuses of a pose (infeasible, slack) makes the robot unusable.
            let t_min = est.t_min_n;
            match c.first_root(scene, &pose, &t_min[..n], 0, None, |_| {}) {
                Ok(_) => {}
                Err(e) if matches!(e.status(), Status::TensionInfeasible | Status::CableSlack) => {}
                Err(e) => return Err(default_pose(e)),
            }
            c.reset_tension_warm_start();
        }
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

    /// The cable models of the last successful cycle (none when the cables sag: their
    /// chains live in the sagged solver, see [`Self::dense_matrices`]).
    pub fn cable_models(&self) -> &[CableModel] {
        self.cycle.cable_models()
    }

    /// The structured eigen solver of taut cables as loaded at the last pose (its sum
    /// rules, counters). When the cables sag it has no loaded pose (its queries answer
    /// `NotLoaded`); [`Self::modes`] and [`Self::dense_modes`] serve both models.
    pub fn modal(&self) -> &ModalSolver {
        static UNLOADED: std::sync::OnceLock<ModalSolver> = std::sync::OnceLock::new();
        self.cycle
            .taut_modal()
            .unwrap_or_else(|| UNLOADED.get_or_init(|| ModalSolver::new(ModalParams::default())))
    }

    /// With `[effects] sag`: the sagged structured solver as loaded at the pose of the last
    /// successful cycle (its complex D for the frequency response); None for the chord
    /// models or when the last cycle was not ok.
    pub fn sag_modal(&self) -> Option<&crate::modal::SagModalSolver> {
        if self.estimate.status != Status::Ok {
            return None;
        }
        self.cycle.sag_modal()
    }

    /// [`Self::sag_modal`], mutable, for a study that owns this estimator (the frequency
    /// response's count and receptance): they move the solver's scratch and warm starts,
    /// not the pose it holds, so no copy of a model that may fill most of the memory budget
    /// is made.
    pub(crate) fn sag_modal_mut(&mut self) -> Option<&mut crate::modal::SagModalSolver> {
        if self.estimate.status != Status::Ok {
            return None;
        }
        self.cycle.sag_modal_mut()
    }

    /// End-effector bookkeeping counters (see [`ModalSolver::rescan_counts`]).
    pub fn rescan_counts(&self) -> crate::modal::RescanCounts {
        self.cycle.rescan_counts()
    }

    /// The pose of the last cycle when it was ok (what [`Self::ee_modal_basis`],
    /// [`Self::dense_matrices`] and the other queries of its model refer to), else None.
    pub fn loaded_pose(&self) -> Option<Pose> {
        (self.estimate.status == Status::Ok).then_some(self.loaded_pose)
    }

    /// With `[effects] sag`: each cable's elastic catenary of the last cycle's tension
    /// solve (unstretched length, H, V, tensions along it, sag, Irvine's λ²); None for the
    /// chord models.
    pub fn sag_catenaries(&self) -> Option<&[crate::elastic_catenary::Catenary]> {
        self.cycle.catenaries()
    }

    /// Info of the last tension solve (with sag: its SQP iterations).
    pub fn tension_info(&self) -> TensionInfo {
        self.cycle.tension_info()
    }

    /// Forget every warm start: the next cycle starts cold.
    pub fn reset(&mut self) {
        self.last_ee = None;
        self.last_ok_position = None;
        self.last_lambda1 = f64::NAN;
        self.cycle.reset();
    }

    /// One cycle: pose and lower tension bounds → estimate. `Tmin::Scene` takes each
    /// cable's own bound from the scene (`cables[i].t_min`, else `tension.t_min`);
    /// `Tmin::Uniform(t)` gives every cable t; `Tmin::PerCable(&t)` cable i `t[i]`. No
    /// allocation.
    ///
    /// A bound the scene would refuse ([`crate::scene::check_t_min`] against the cable's
    /// T_max: not finite, not > 0, subnormal, above T_max), or a per-cable slice whose
    /// length is not the scene's cable count, gives the status `TminOutOfRange` and no
    /// numbers.
    ///
    /// ```
    /// use cablevib::prelude::*;
    ///
    /// let scene = Scene::load("spatial-paper")?;
    /// let mut est = Estimator::new(&scene)?; // allocates here, never in `update`
    /// let e = *est.update(&Pose::in_scene(&scene, Vector3::new(0.1, 0.0, 1.25)), Tmin::Scene);
    /// assert_eq!(e.status, Status::Ok);
    /// assert!(e.tensions().iter().all(|&t| t >= scene.t_min_n - 1e-9));
    /// if let Some(m) = e.ee_mode {
    ///     assert!(m.frequency_hz >= e.f1_hz && m.participation >= scene.model.ee_participation_min);
    /// }
    /// // A pose outside the frame is a status, never a panic.
    /// let bad = est.update(&Pose::in_scene(&scene, Vector3::new(50.0, 0.0, 1.25)), Tmin::Scene);
    /// assert!(!bad.is_ok() && bad.f1_hz.is_nan() && bad.ee_mode.is_none());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn update(&mut self, pose: &Pose, t_min: Tmin<'_>) -> &Estimate {
        t_min.fill(&self.scene, &mut self.t_min_n);
        self.update_loaded(pose)
    }

    /// The scene's default lower bounds (N), one per cable: `cables[i].t_min`, else its
    /// `tension.t_min`.
    pub fn default_t_min_n(&self) -> [f64; MAX_CABLES] {
        Tmin::Scene.per_cable(&self.scene)
    }

    /// One cycle with the lower bounds already in `self.t_min_n`.
    fn update_loaded(&mut self, pose: &Pose) -> &Estimate {
        let n = self.scene.n_cables();
        let mut e = Estimate::empty(n);
        // The stiffness's dimension is the scene's even when the pose has no answer.
        e.stiffness = Stiffness::unknown(self.ee_dim());
        match self.run(pose, &mut e) {
            Ok(()) => {
                e.status = Status::Ok;
                self.last_ok_position = Some(pose.position_m);
                self.loaded_pose = *pose;
                self.last_t_min_n = self.t_min_n;
            }
            Err(err) => {
                e.status = err.status();
                e.error = Some(err);
                e.f1_hz = f64::NAN;
                e.f1_ee_participation = f64::NAN;
                e.ee_mode = None;
                e.stiffness = Stiffness::unknown(self.ee_dim());
                // An infeasible solve has its closest tensions, a mechanism valid ones.
                if !matches!(e.status, Status::TensionInfeasible | Status::Mechanism) {
                    e.tensions_n = [f64::NAN; MAX_CABLES];
                }
                self.last_ok_position = None;
                self.last_lambda1 = f64::NAN;
                self.last_ee = None;
            }
        }
        self.estimate = e;
        &self.estimate
    }

    /// Reject a pose or T_min before any computation. There is no geometric pre-test of
    /// the position: whether the robot can hold a pose is the tension distribution's answer
    /// (`TensionInfeasible`), and a pose at an anchor is the kinematics' (`CableTooShort`).
    fn check_input(&self, pose: &Pose) -> Result<(), RejectedInput> {
        if !pose.is_finite() {
            return Err(RejectedInput::NonFinitePose);
        }
        if !pose.has_unit_quaternion(self.params.quaternion_tol) {
            return Err(RejectedInput::NonUnitQuaternion);
        }
        if !self.scene.rigid && !pose.has_identity_orientation() {
            return Err(RejectedInput::OrientationOnPointMass);
        }
        let n = self.scene.n_cables();
        let bounds = self.t_min_n[..n].iter().zip(&self.t_max_n[..n]);
        if !bounds.into_iter().all(|(&lo, &hi)| is_valid_t_min(lo, hi)) {
            return Err(RejectedInput::TminOutOfRange);
        }
        Ok(())
    }

    /// The cycle's warm start of λ₁ (rad²/s²): the quadratic extrapolation of the last
    /// three cycles' λ₁, 3λ₋₁ − 3λ₋₂ + λ₋₃ (error ~ the third difference), or the linear one
    /// of the last two, or the last one (and the last one when the extrapolation is not
    /// positive); None cold. A better start saves Newton evaluations: on a 1 m circle of a
    /// sagging robot the linear prediction is off by ~6e-7 relative, which takes three
    /// evaluations to bring to 1e-12, the quadratic one by ~1e-9, which takes two.
    fn predict_lambda1(&self, warm: bool) -> Option<f64> {
        if warm && self.last_lambda1.is_finite() {
            let (l1, l2, l3) = (self.last_lambda1, self.prev_lambda1, self.prev2_lambda1);
            let pred = if l2.is_finite() && l3.is_finite() {
                3.0 * (l1 - l2) + l3
            } else if l2.is_finite() {
                2.0 * l1 - l2
            } else {
                l1
            };
            Some(if pred > 0.0 { pred } else { self.last_lambda1 })
        } else {
            None
        }
    }

    /// Whether the cycle's lower bounds are close enough to the last ok cycle's for a warm
    /// start: each within `warm_t_min_change` (relative) of its last value.
    fn t_min_close_to_last(&self) -> bool {
        let n = self.scene.n_cables();
        let k = self.params.warm_t_min_change;
        (0..n).all(|i| (self.t_min_n[i] - self.last_t_min_n[i]).abs() <= k * self.last_t_min_n[i])
    }

    fn run(&mut self, pose: &Pose, e: &mut Estimate) -> Result<(), EstimatorError> {
        let n = self.scene.n_cables();
        self.check_input(pose)?;
        let p = pose.position_m;
        self.cycle.set_pose(&self.scene, pose)?;
        let warm = match self.last_ok_position {
            Some(q) => (q - p).norm() <= self.params.warm_jump_m && self.t_min_close_to_last(),
            None => false,
        };
        if !warm {
            self.cycle.start_cold();
        }
        let warm_l = self.predict_lambda1(warm);
        let root = self.cycle.first_root(
            &self.scene,
            pose,
            &self.t_min_n[..n],
            self.expected_rank,
            warm_l,
            |report| {
                e.tension_iterations = report.iterations;
                e.tension_warm = report.warm;
                e.tensions_n[..n].copy_from_slice(report.tensions_n);
            },
        );
        let r1 = match root {
            Ok(r) => r,
            Err(err) => {
                // Only the root search fails with a modal error: it was started and spent
                // evaluations.
                if let EstimatorError::Modal(_) = err {
                    e.cold_start = warm_l.is_none();
                    e.eigen_evaluations = self.cycle.evaluations_since_load();
                }
                return Err(err);
            }
        };
        e.cold_start = warm_l.is_none();
        e.f1_hz = lambda_to_hz(r1.lambda);
        e.f1_ee_participation = r1.ee_participation;
        e.eigen_residual = r1.residual;
        self.prev2_lambda1 = if warm { self.prev_lambda1 } else { f64::NAN };
        self.prev_lambda1 = if warm { self.last_lambda1 } else { f64::NAN };
        self.last_lambda1 = r1.lambda;
        self.write_stiffness(e);
        e.eigen_evaluations = self.cycle.evaluations_since_load();
        check_mechanism(&self.scene, pose, &e.stiffness.k6, r1.lambda)?;
        let (m6, _) = self.cycle.ee_mass();
        check_answer(
            r1.lambda,
            r1.residual,
            r1.ee_participation,
            &e.stiffness.k6,
            &m6,
        )?;
        if self.params.ee_mode {
            self.ee_mode(&r1, warm_l.is_some(), e);
            e.eigen_evaluations = self.cycle.evaluations_since_load();
        }
        Ok(())
    }

    /// The end-effector mode within what is left of the cycle's budget, into `e`: this
    /// cycle's answer (age 0), or while the work goes on over the cycles the last answer
    /// with its age; None when no mode reaching the participation
    /// threshold is known — a mode below the threshold is never reported. Neither case
    /// invalidates f1 and the tensions.
    fn ee_mode(&mut self, r1: &crate::modal::Root, warm: bool, e: &mut Estimate) {
        if !warm {
            // A cold start (a jump): the last answer belongs to another pose.
            self.last_ee = None;
        }
        let thr = self.params.modal.ee_participation_min;
        match self.cycle.ee_mode_tracked(r1, warm) {
            // A mode without a finite, positive λ is no answer (check_answer's rule).
            Ok(Some((lambda, p))) if p >= thr && lambda.is_finite() && lambda > 0.0 => {
                self.last_ee = Some((lambda_to_hz(lambda), p, 0));
            }
            // Still being worked on: the last answer, one cycle older.
            Ok(None) => {
                if let Some(l) = self.last_ee.as_mut() {
                    l.2 = l.2.saturating_add(1);
                }
            }
            // None reaches the threshold within the scan's bounds, or the scan failed.
            Ok(Some(_)) | Err(_) => self.last_ee = None,
        }
        e.ee_mode = self.last_ee.map(|(hz, p, age)| EeMode {
            frequency_hz: hz,
            participation: p,
            age_cycles: age,
        });
    }

    /// The end-effector's degrees of freedom: 6 for a rigid body, 3 for a point mass.
    fn ee_dim(&self) -> usize {
        if self.scene.rigid {
            6
        } else {
            3
        }
    }

    /// The static end-effector stiffness of the loaded models into `e`.
    fn write_stiffness(&mut self, e: &mut Estimate) {
        e.stiffness = Stiffness {
            k6: self.cycle.static_stiffness(&self.scene),
            dim: self.ee_dim(),
        };
    }
}

/// Memory a sagging FEM cable's model holds per element, bytes (its chords, tensions and
/// recurrence state, preallocated when the estimator is built): 180 measured on the paper
/// robot at N = 10⁵ and 3·10⁵ (154 and 442 MB resident for 8 cables), with margin.
pub const SAG_BYTES_PER_ELEMENT: u64 = 200;

/// Refuse an estimator whose preallocated model would be over the one memory budget: the
/// sagging FEM cables' O(N) state (the taut models are O(1) in N).
fn check_model_memory(scene: &Scene) -> Result<(), crate::memory_budget::OverBudget> {
    if !scene.model.sag || scene.model.element == ElementKind::Continuous {
        return Ok(());
    }
    let (n, c) = (scene.model.elements_per_cable, scene.n_cables());
    let bytes = (n as u64)
        .saturating_mul(c as u64)
        .saturating_mul(SAG_BYTES_PER_ELEMENT);
    crate::memory_budget::check(
        || format!("the sagged model of {c} cables × {n} elements"),
        bytes,
        "use fewer elements per cable (the sagged FEM converges as 1/N²: docs/sag.md)",
    )
}

/// Largest relative residual of the first eigenvalue an ok estimate may carry
/// ([`crate::modal::Root::residual`]) beyond what rounding in D(λ) explains: 1e-6, a
/// thousand times what the root search accepts (a Newton step below
/// `ModalParams::newton_accept`, 1e-9, leaves a residual of a few 1e-9 at most).
pub const MAX_EIGEN_RESIDUAL: f64 = 1e-6;

/// The rounding allowance of the residual check, in units of ε·max|K|/(λ₁·max M_ii) (K the
/// static stiffness, M the end-effector's mass matrix): 1e6. The residual is
/// |μ|/(λ·max|D'|), and rounding leaves |μ| ~ ε·‖D(λ₁)‖ ≲ 2ε‖K‖ (λ₁ is at most a Rayleigh
/// quotient of K) with max|D'| ≥ max M_ii, so a root λ₁ far below the stiffness's scale
/// (T_min = 1e-100 N: λ₁ ~ 1e-98 rad²/s², exact to 1e-12 of its closed form, residual
/// 2e75) is within rounding of a root; 1e6 covers the chains' accumulated rounding, and at
/// the usual scale (λ₁ ~ 1e3, ‖K‖ ~ 1e6) the allowance is ~1e-9, below the threshold.
pub const EIGEN_RESIDUAL_ROUNDING: f64 = 1e6;

/// The estimator's check of its own answer before it calls it ok: λ₁ (rad²/s²) finite and
/// positive; its relative `residual` at most [`MAX_EIGEN_RESIDUAL`] plus what rounding explains
/// ([`EIGEN_RESIDUAL_ROUNDING`] · ε·max|K|/(λ₁·max M_ii), `k6` the static stiffness, `m6` the
/// end-effector's mass matrix); its end-effector `participation` finite; every entry of
/// `k6` finite. Else [`EstimatorError::Unverified`] naming what failed. The guard behind
/// every ok (the cycle, the service, the offline modes), so an overflow anywhere in the
/// model is a status, never a number. No allocation.
pub fn check_answer(
    lambda: f64,
    residual: f64,
    participation: f64,
    k6: &Matrix6<f64>,
    m6: &Matrix6<f64>,
) -> Result<(), EstimatorError> {
    let fail = |what: &'static str, value: f64| Err(EstimatorError::Unverified { what, value });
    if !(lambda.is_finite() && lambda > 0.0) {
        return fail("the first eigenvalue (rad²/s²)", lambda);
    }
    if let Some(&x) = k6.iter().find(|x| !x.is_finite()) {
        return fail("the static stiffness", x);
    }
    let m_max = m6.diagonal().max();
    let rounding = EIGEN_RESIDUAL_ROUNDING * f64::EPSILON * k6.abs().max() / (lambda * m_max);
    if !(residual <= MAX_EIGEN_RESIDUAL + rounding) {
        return fail("the first eigenvalue's relative residual", residual);
    }
    if !participation.is_finite() {
        return fail("the end-effector participation", participation);
    }
    Ok(())
}

/// A mechanism of `scene` at `pose` — a motion of a rigid end-effector that moves none of
/// its attachments ([`crate::modal::free_direction`]) — is the error
/// [`EstimatorError::Mechanism`] naming that motion, never an f1 ≈ 0. Only a λ₁ (rad²/s²)
/// that the cheap pre-test [`crate::modal::may_be_mechanism`] lets through against the
/// static stiffness `k6` (N/m, N/rad, N·m/m, N·m/rad blocks) pays for the test. A point mass
/// has no mechanism. No allocation (fixed-size matrices). The estimator's cycle and the
/// dense reference analysis both call it.
pub fn check_mechanism(
    scene: &Scene,
    pose: &Pose,
    k6: &Matrix6<f64>,
    lambda1: f64,
) -> Result<(), EstimatorError> {
    if !scene.rigid {
        return Ok(());
    }
    let m = EndEffector::of_body(scene, pose).mass6();
    if !crate::modal::may_be_mechanism(lambda1, k6, &m, 6) {
        return Ok(());
    }
    let rot = crate::kinematics::rotation_of(&pose.orientation_wxyz);
    let mut arms = [Vector3::zeros(); MAX_CABLES];
    for (a, c) in arms.iter_mut().zip(&scene.cables) {
        *a = rot * c.attachment_m;
    }
    match crate::modal::free_direction(&arms[..scene.n_cables()]) {
        Some(d) => Err(EstimatorError::Mechanism {
            direction: [d[0], d[1], d[2], d[3], d[4], d[5]],
        }),
        None => Ok(()),
    }
}
