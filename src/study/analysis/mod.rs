//! The analysis of one pose that `cablevib analyze` prints (and a Python binding calls):
//! tensions, static stiffness and the first K natural frequencies with their end-effector
//! participations, by the structured engine ([`crate::modal::ModalSolver::modes`], every
//! model, O(1) in the element count) or by the dense reference
//! ([`crate::estimator::reference_analysis`]: Clarabel tensions, assembled K and M, a dense
//! eigensolver; refused beyond [`crate::modal::DENSE_MEMORY_BUDGET_BYTES`]).
//!
//! With [`AnalyzeOptions::compare_dense`] the structured answer is also checked against the
//! dense spectrum of exactly the same models (the structured path's tensions), in the same
//! process: both times, their ratio, and the largest relative difference of the K
//! eigenvalues next to the dense solver's own bound ε·λ_max/λ.

mod compare;

use super::{Param, ParamError};
use crate::estimator::{
    check_mechanism, reference_analysis_at, resolve_auto, Estimate, Estimator, Tmin,
};
use crate::kinematics::Pose;
use crate::modal::{dense_relative_accuracy, lambda_to_hz, Mode};
use crate::scene::{ElementKind, Scene};
use serde::Serialize;
use std::time::Instant;

/// Largest number of modes one analysis computes (the report holds them all; 10⁵ modes
/// take seconds with the structured engine).
pub const MAX_ANALYZE_MODES: usize = 100_000;

/// Which eigensolver answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SolverChoice {
    /// Wittrick-Williams count and Newton on the condensed problem (default).
    Structured,
    /// Dense assembly and a dense generalised eigensolver (the reference).
    Dense,
}

impl SolverChoice {
    /// `structured` or `dense`.
    pub fn as_str(self) -> &'static str {
        match self {
            SolverChoice::Structured => "structured",
            SolverChoice::Dense => "dense",
        }
    }
}

/// What to compute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalyzeOptions {
    /// Number of natural frequencies (the model may have fewer).
    pub modes: usize,
    /// Which eigensolver.
    pub solver: SolverChoice,
    /// Also run the dense reference on the structured path's models and compare (structured
    /// solver only).
    pub compare_dense: bool,
}

impl Default for AnalyzeOptions {
    fn default() -> Self {
        AnalyzeOptions {
            modes: 10,
            solver: SolverChoice::Structured,
            compare_dense: false,
        }
    }
}

/// The structured engine against the dense reference on the same models.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DenseComparison {
    /// Median time of the structured K modes, s.
    pub structured_seconds: f64,
    /// Time of the dense assembly and eigen-solve (with mode shapes for the
    /// participations), s.
    pub dense_seconds: f64,
    /// dense_seconds / structured_seconds.
    pub speedup: f64,
    /// Largest relative difference of the K eigenvalues λ (structured vs dense).
    pub max_rel_diff_lambda: f64,
    /// The dense solver's bound ε·λ_max/λ at the mode where the difference is largest.
    pub dense_bound_there: f64,
    /// Largest difference of the participations summed over each cluster.
    pub max_abs_diff_cluster_participation: f64,
}

/// The analysis of one pose (every field serialisable; the CLI prints it as JSON).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AnalysisReport {
    /// Scene name.
    pub scene: String,
    /// End-effector position, m.
    pub position_m: [f64; 3],
    /// End-effector orientation, unit quaternion [w, x, y, z] (the scene's; a point mass
    /// has no orientation and keeps the identity).
    pub orientation_wxyz: [f64; 4],
    /// The scene-wide lower tension bound (`[tension] t_min`), N.
    pub t_min_n: f64,
    /// Each cable's lower tension bound used, N (its own `t_min`, else `t_min_n`).
    pub cable_t_min_n: Vec<f64>,
    /// The lower bounds for the report's header line (`"60 N"`, `"4.06-10 N per cable"`).
    #[serde(skip)]
    pub t_min_label: String,
    /// Cable tensions, N.
    pub tensions_n: Vec<f64>,
    /// The first K natural frequencies, Hz, ascending.
    pub frequencies_hz: Vec<f64>,
    /// Their end-effector participations (0 ..= 1).
    pub ee_participation: Vec<f64>,
    /// Each mode's cluster size from the eigenvalue count (structured solver only).
    pub multiplicity: Option<Vec<u32>>,
    /// Index of the first mode of each mode's cluster (structured solver only).
    pub cluster_start: Option<Vec<usize>>,
    /// Degrees of freedom of the assembled model (None for continuous cables).
    pub dof: Option<usize>,
    /// Element model (resolved when the scene said `auto`).
    pub element: String,
    /// Elements per cable.
    pub elements_per_cable: usize,
    /// Static end-effector stiffness, K = ∂(restoring wrench)/∂(displacement), as rows:
    /// 3 × 3 (N/m) for a point mass; 6 × 6 for a rigid end-effector over the displacement
    /// (x, y, z in m, then small rotations θx, θy, θz in rad about the world axes through
    /// the centroid) and the wrench (force in N, then moment in N·m about the centroid):
    /// blocks [[K_tt (N/m), K_tr (N/rad)], [K_rt (N·m/m), K_rr (N·m/rad)]]. The top-left
    /// 3 × 3 block is the translational stiffness a point mass would report.
    pub stiffness_n_m: Vec<Vec<f64>>,
    /// `structured` or `dense`.
    pub solver: &'static str,
    /// Time of the eigen-solve, s (structured: the K modes; dense: assembly and solve).
    pub solve_seconds: f64,
    /// Time of the dense reference, s (dense solver or comparison only).
    pub dense_seconds: Option<f64>,
    /// The comparison with the dense reference (when asked).
    pub compare_dense: Option<DenseComparison>,
    /// Whether the cables sag (`[effects] sag`): then `tensions_n` are the tensions at the
    /// end-effector end, and the fields below describe each cable's elastic catenary.
    pub sag: bool,
    /// Sagging cables: the tension at the anchor end of each cable, N.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tensions_anchor_n: Option<Vec<f64>>,
    /// Sagging cables: the smallest tension along each cable, N.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tensions_min_n: Option<Vec<f64>>,
    /// Sagging cables: the largest distance of each cable from its chord, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sag_m: Option<Vec<f64>>,
    /// Sagging cables: Irvine's λ² of each cable (dimensionless; sag matters when it is
    /// not ≪ 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub irvine_lambda2: Option<Vec<f64>>,
    /// Sagging cables: each cable's unstretched length L0, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unstretched_length_m: Option<Vec<f64>>,
}

/// Why an analysis failed (one line each).
#[derive(Debug, thiserror::Error)]
pub enum AnalyzeError {
    /// The estimator could not be built for the scene.
    #[error("{0}")]
    Build(String),
    /// The pose has no valid estimate (status and reason).
    #[error("status {status}: {reason}")]
    Status {
        /// The estimate's status.
        status: &'static str,
        /// Why.
        reason: String,
    },
    /// The eigen-solve or the dense reference failed (or was refused).
    #[error("{0}")]
    Solve(String),
    /// A parameter refused (out of range, or a combination that cannot be honoured).
    #[error(transparent)]
    Param(#[from] ParamError),
}

impl AnalyzeError {
    /// The message with each parameter called `name(param)` (the command line passes its
    /// option names); equal to the `Display` text with each parameter's own name.
    pub fn render(&self, name: &dyn Fn(Param) -> &'static str) -> String {
        match self {
            AnalyzeError::Param(e) => e.render(name),
            other => other.to_string(),
        }
    }
}

/// Analyse the scene at its own pose (`ee_position_m`, `ee_orientation_wxyz`) and T_min.
pub fn analyze(scene: &Scene, opts: &AnalyzeOptions) -> Result<AnalysisReport, AnalyzeError> {
    if opts.modes > MAX_ANALYZE_MODES {
        let rule = format!("at most {MAX_ANALYZE_MODES}");
        return Err(ParamError::invalid(Param::Modes, opts.modes, rule).into());
    }
    match opts.solver {
        SolverChoice::Structured => structured(scene, opts),
        SolverChoice::Dense if opts.compare_dense => Err(ParamError::Conflict {
            param: Param::CompareDense,
            with: Param::Solver,
            with_value: "dense".into(),
            reason: "the comparison runs the structured solver beside the dense one".into(),
        }
        .into()),
        SolverChoice::Dense => dense(scene, opts),
    }
}

fn pose_of(scene: &Scene) -> Pose {
    Pose {
        position_m: scene.ee_position_m,
        orientation_wxyz: scene.ee_orientation_wxyz,
    }
}

/// The leading `dim` × `dim` block of `m` as rows (3: a point mass, 6: a rigid body).
fn rows(m: &nalgebra::Matrix6<f64>, dim: usize) -> Vec<Vec<f64>> {
    (0..dim)
        .map(|r| (0..dim).map(|c| m[(r, c)]).collect())
        .collect()
}

/// The report's frame: everything but the modes and the times.
fn report_frame(s: &Scene, solver: SolverChoice) -> AnalysisReport {
    let p = s.ee_position_m;
    AnalysisReport {
        scene: s.name.clone(),
        position_m: [p.x, p.y, p.z],
        orientation_wxyz: s.ee_orientation_wxyz,
        t_min_n: s.t_min_n,
        cable_t_min_n: (0..s.n_cables()).map(|i| s.cable_t_min_n(i)).collect(),
        t_min_label: s.t_min_label(),
        tensions_n: Vec::new(),
        frequencies_hz: Vec::new(),
        ee_participation: Vec::new(),
        multiplicity: None,
        cluster_start: None,
        dof: None,
        element: s.model.element.as_str().to_string(),
        elements_per_cable: s.model.elements_per_cable,
        stiffness_n_m: Vec::new(),
        solver: solver.as_str(),
        solve_seconds: f64::NAN,
        dense_seconds: None,
        compare_dense: None,
        sag: s.model.sag,
        tensions_anchor_n: None,
        tensions_min_n: None,
        sag_m: None,
        irvine_lambda2: None,
        unstretched_length_m: None,
    }
}

/// The sagging cables' fields of the report from the estimator's last cycle (nothing for
/// the chord models).
fn fill_sag(r: &mut AnalysisReport, est: &Estimator) {
    if let Some(cats) = est.sag_catenaries() {
        let of =
            |f: fn(&crate::elastic_catenary::Catenary) -> f64| Some(cats.iter().map(f).collect());
        r.tensions_anchor_n = of(|c| c.tension_anchor_n());
        r.tensions_min_n = of(|c| c.tension_min_n());
        r.sag_m = of(|c| c.sag_m());
        r.irvine_lambda2 = of(|c| c.irvine_lambda2());
        r.unstretched_length_m = of(|c| c.l0_m);
    }
}

/// The estimator built for `scene` and its estimate at the scene's own pose and T_min; a
/// failed build or an estimate that is not ok is the error.
fn estimate_at_scene_pose(scene: &Scene) -> Result<(Estimator, Estimate), AnalyzeError> {
    let mut est = Estimator::new(scene).map_err(|e| AnalyzeError::Build(e.to_string()))?;
    let e = *est.update(&pose_of(scene), Tmin::Scene);
    if let Some(err) = e.error {
        return Err(AnalyzeError::Status {
            status: e.status.as_str(),
            reason: err.to_string(),
        });
    }
    Ok((est, e))
}

/// The structured path: the estimator's cycle at the pose, then its K modes.
fn structured(scene: &Scene, opts: &AnalyzeOptions) -> Result<AnalysisReport, AnalyzeError> {
    let (mut est, e) = estimate_at_scene_pose(scene)?;
    let s = est.scene().clone();
    let mut modes = vec![Mode::default(); opts.modes];
    let t0 = Instant::now();
    let n = est
        .modes(opts.modes, &mut modes)
        .map_err(|e| AnalyzeError::Solve(e.to_string()))?;
    let secs = t0.elapsed().as_secs_f64();
    modes.truncate(n);
    let mut r = report_frame(&s, SolverChoice::Structured);
    r.tensions_n = e.tensions().to_vec();
    r.frequencies_hz = modes.iter().map(|m| m.frequency_hz).collect();
    r.ee_participation = modes.iter().map(|m| m.ee_participation).collect();
    r.multiplicity = Some(modes.iter().map(|m| m.multiplicity).collect());
    r.cluster_start = Some(modes.iter().map(|m| m.cluster_start).collect());
    r.dof = est.model_dof();
    r.stiffness_n_m = rows(&e.stiffness.k6, e.stiffness.dim);
    r.solve_seconds = secs;
    fill_sag(&mut r, &est);
    if opts.compare_dense {
        let c = compare::compare(&mut est, &modes)?;
        r.dense_seconds = Some(c.dense_seconds);
        r.compare_dense = Some(c);
    }
    Ok(r)
}

/// The dense reference: Clarabel tensions, assembled K and M, a dense eigensolver.
fn dense(scene: &Scene, opts: &AnalyzeOptions) -> Result<AnalysisReport, AnalyzeError> {
    if scene.model.element == ElementKind::Continuous {
        return Err(ParamError::invalid(
            Param::Solver,
            "dense",
            "the continuous model has no finite assembly (use the structured solver)",
        )
        .into());
    }
    if scene.model.element == ElementKind::Auto {
        let (resolved, _) = resolve_auto(scene).map_err(|e| AnalyzeError::Build(e.to_string()))?;
        return dense(&resolved, opts);
    }
    if scene.model.sag {
        return dense_sagged(scene, opts);
    }
    let t0 = Instant::now();
    let a = reference_analysis_at(scene, &pose_of(scene), Tmin::Scene, true)
        .map_err(|e| AnalyzeError::Solve(e.to_string()))?;
    let lambda1 = a.modes.lambda.first().copied().unwrap_or(f64::NAN);
    if let Err(err) = check_mechanism(scene, &pose_of(scene), &a.stiffness6, lambda1) {
        return Err(AnalyzeError::Status {
            status: err.status().as_str(),
            reason: err.to_string(),
        });
    }
    let secs = t0.elapsed().as_secs_f64();
    let k = opts.modes.min(a.modes.lambda.len());
    check_dense(&a.modes.lambda[..k], a.modes.lambda_max)?;
    let mut r = report_frame(scene, SolverChoice::Dense);
    r.tensions_n = a.tensions_n.clone();
    r.frequencies_hz = a.modes.lambda[..k]
        .iter()
        .map(|&l| lambda_to_hz(l))
        .collect();
    r.ee_participation = a.modes.ee_participation[..k].to_vec();
    r.dof = Some(a.dof);
    r.stiffness_n_m = rows(&a.stiffness6, if scene.rigid { 6 } else { 3 });
    r.solve_seconds = secs;
    r.dense_seconds = Some(secs);
    Ok(r)
}

/// The dense reference of the sagged model: the same sagged tension distribution, then
/// the whole robot assembled (straight elements between nodes on each catenary) and a
/// dense generalised eigensolver.
fn dense_sagged(scene: &Scene, opts: &AnalyzeOptions) -> Result<AnalysisReport, AnalyzeError> {
    let (est, e) = estimate_at_scene_pose(scene)?;
    let t0 = Instant::now();
    let d = est
        .dense_modes(true)
        .map_err(|e| AnalyzeError::Solve(e.to_string()))?;
    let secs = t0.elapsed().as_secs_f64();
    let k = opts.modes.min(d.lambda.len());
    check_dense(&d.lambda[..k], d.lambda_max)?;
    let mut r = report_frame(scene, SolverChoice::Dense);
    r.tensions_n = e.tensions().to_vec();
    r.frequencies_hz = d.lambda[..k].iter().map(|&l| lambda_to_hz(l)).collect();
    r.ee_participation = d.ee_participation[..k].to_vec();
    r.dof = est.model_dof();
    r.stiffness_n_m = rows(&e.stiffness.k6, e.stiffness.dim);
    r.solve_seconds = secs;
    r.dense_seconds = Some(secs);
    fill_sag(&mut r, &est);
    Ok(r)
}

/// Largest accuracy bound ε·λ_max/λ₁ of an answer of the dense reference (1: beyond it
/// not one digit of the lowest eigenvalue is guaranteed). A model with a very stiff, very
/// light part (micrometres of cable behind a pulley: springs 10⁶ times the free cable's
/// on masses 10⁶ times lighter) puts λ_max 10¹⁹ times above λ₁, and the dense solve's
/// lowest eigenvalues are then rounding noise, negative or NaN.
pub const DENSE_MAX_BOUND: f64 = 1.0;

/// The dense reference's reported eigenvalues `lambda` (rad²/s², ascending) checked before
/// they are printed: each finite and > 0, and the bound ε·λ_max/λ₁ at most
/// [`DENSE_MAX_BOUND`]; else the dense solver refused in one line ([`Param::Solver`]),
/// naming the structured one.
fn check_dense(lambda: &[f64], lambda_max: f64) -> Result<(), AnalyzeError> {
    if let Some((j, &l)) = lambda
        .iter()
        .enumerate()
        .find(|(_, l)| !(l.is_finite() && **l > 0.0))
    {
        let rule = format!(
            "the dense eigen-solve gave λ = {l:.3e} rad²/s² for mode {} (rounding: the model's stiffness spans more than f64 resolves densely); use the structured solver",
            j + 1
        );
        return Err(ParamError::invalid(Param::Solver, "dense", rule).into());
    }
    if let Some(&l1) = lambda.first() {
        let bound = dense_bound(l1, lambda_max);
        if !(bound <= DENSE_MAX_BOUND) {
            let rule = format!(
                "its accuracy bound ε·λ_max/λ₁ = {bound:.1e} (λ_max = {lambda_max:.1e}, λ₁ = {l1:.1e} rad²/s²) leaves no correct digit: a very stiff, light part of the model (e.g. micrometres of cable behind a pulley); use the structured solver"
            );
            return Err(ParamError::invalid(Param::Solver, "dense", rule).into());
        }
    }
    Ok(())
}

/// The dense bound ε·λ_max/λ (re-exported for the comparison).
pub(super) fn dense_bound(lambda: f64, lambda_max: f64) -> f64 {
    dense_relative_accuracy(lambda, lambda_max)
}

/// The assembled K (N/m) and M (kg) of the structured path's models at the scene's pose
/// (same tensions as [`analyze`] with the structured solver), for external references.
/// DOF order: the end-effector's 3 (or 6) first, then each cable's interior nodes from the
/// anchor. Refused beyond [`crate::modal::DENSE_MEMORY_BUDGET_BYTES`].
pub fn assembled_matrices(
    scene: &Scene,
) -> Result<(nalgebra::DMatrix<f64>, nalgebra::DMatrix<f64>), AnalyzeError> {
    let (est, _) = estimate_at_scene_pose(scene)?;
    est.dense_matrices()
        .map_err(|e| AnalyzeError::Solve(e.to_string()))
}
