//! The frequency response of one pose, the one orchestration behind `cablevib frf` and the
//! Python `frf`: the receptance H(ω) at the end-effector over a band
//! (`modal::frf`: exact at a complex λ for loss-factor and Rayleigh damping, modal
//! superposition with static correction for modal damping), the natural frequencies the
//! end-effector feels in the band, and on request the dense check of the same models
//! ([`dense`]).
//!
//! - Taut (chord) cables: the structured solver of the pose model ([`PoseModel`]: Clarabel
//!   tensions at the scene's pose), [`crate::modal::receptance_over`]; modal damping superposes the modes
//!   below [`MODAL_CUTOFF_RATIO`] × `to_hz`.
//! - Sagging cables (FEM chains on the catenary): the estimator's sagged tension solve at the
//!   scene's pose, then the sagged solver's D at the complex λ of each frequency; modal
//!   damping superposes the sagged structured shapes below the same cut-off (the basis
//!   doubled from 16 modes until one lies above it, at most [`MAX_FRF_MODES`]) with the
//!   residual flexibility of the rest ([`ModalBasis::from_modes`]). The continuous sagged
//!   model has no complex form and is refused.
//!
//! The work's memory is checked against the one budget before it allocates and its
//! estimated time handed to the caller ([`frf_announced`], [`super::cost`]); the exact
//! damped forms go in chunks with a progress bar on a terminal ([`FrfConfig::progress`]).
//!
//! Refusals name the parameter ([`Param`]): a bad band, a damping value out of range, two
//! dampings given, the dense LU with modal damping.

pub mod dense;

pub use dense::{Checked, DenseCheck, LuSpot};

use super::cost::{estimate_cost, frf_chunk, in_chunks, receptance, Work, WorkEstimate};
use super::{Param, ParamError, ParamName, StudyError};
use crate::estimator::{Estimator, PoseModel, Tmin};
use crate::input_file::message_number;
use crate::kinematics::Pose;
use crate::modal::{
    frequency_grid, hz_to_lambda, lambda_to_hz, FrfError, ModalBasis, ModalParams, ModalSolver,
    Mode, MAX_FRF_HZ, MAX_FRF_MODES, MAX_FRF_POINTS,
};
use crate::scene::{
    Damping, ElementKind, Scene, MAX_LOSS_FACTOR, MAX_MODAL_RATIO, MAX_RAYLEIGH_ALPHA_PER_S,
    MAX_RAYLEIGH_BETA_S,
};
use nalgebra::{DMatrix, Matrix6};
use num_complex::Complex64;
use std::time::Instant;

/// The modal-damping basis's cut-off over the band's top: the modes below 4 × `to_hz` are
/// superposed, the others taken quasi-statically (a left-out mode r errs by ≈ ω²/λ_r +
/// 2ζω/ω_r, ≤ 1/16 + ζ/2 at the band's top).
pub const MODAL_CUTOFF_RATIO: f64 = 4.0;
/// Natural frequencies listed: the modes with at least this end-effector participation.
pub const MARK_PARTICIPATION: f64 = 0.01;
/// Most modes searched for the listed natural frequencies of a taut pose.
const MARK_MODES: usize = 1000;
/// Most modes searched for them with sag (the sagged solver's lowest ones).
const SAG_MARK_MODES: usize = 400;

/// The damping asked for: at most one of these, else the scene's `[damping]`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DampingChoice {
    /// Loss factor η, 0 ≤ η < [`MAX_LOSS_FACTOR`].
    pub loss_factor: Option<f64>,
    /// Rayleigh α (1/s) and β (s).
    pub rayleigh: Option<(f64, f64)>,
    /// Modal damping ratio ζ in every mode, 0 ≤ ζ < [`MAX_MODAL_RATIO`].
    pub modal_ratio: Option<f64>,
    /// No damping: H is infinite on a natural frequency.
    pub undamped: bool,
}

impl DampingChoice {
    /// The damping: the one given, else `scene`'s; two given or a value out of its range
    /// refused.
    pub fn resolve(&self, scene: Damping) -> Result<Damping, ParamError> {
        let given = [
            self.loss_factor.is_some(),
            self.rayleigh.is_some(),
            self.modal_ratio.is_some(),
            self.undamped,
        ];
        if given.iter().filter(|&&g| g).count() > 1 {
            return Err(ParamError::OneOf(vec![
                Param::LossFactor,
                Param::Rayleigh,
                Param::ModalRatio,
                Param::Undamped,
            ]));
        }
        let check = |param: Param, v: f64, max: f64| {
            if v.is_finite() && v >= 0.0 && v < max {
                Ok(v)
            } else {
                let rule = format!("must be finite, >= 0 and < {max}");
                Err(ParamError::invalid(param, v, rule))
            }
        };
        Ok(if let Some(eta) = self.loss_factor {
            Damping::LossFactor {
                eta: check(Param::LossFactor, eta, MAX_LOSS_FACTOR)?,
            }
        } else if let Some((a, b)) = self.rayleigh {
            Damping::Rayleigh {
                alpha_per_s: check(Param::RayleighAlpha, a, MAX_RAYLEIGH_ALPHA_PER_S)?,
                beta_s: check(Param::RayleighBeta, b, MAX_RAYLEIGH_BETA_S)?,
            }
        } else if let Some(zeta) = self.modal_ratio {
            Damping::ModalRatio {
                zeta: check(Param::ModalRatio, zeta, MAX_MODAL_RATIO)?,
            }
        } else if self.undamped {
            Damping::None
        } else {
            scene
        })
    }
}

/// The dense check of a response.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DenseCheckKind {
    /// The dense complex LU of the assembled c(K − λM) at every frequency (loss factor,
    /// Rayleigh or none).
    Lu,
    /// Summation over every mode of the assembled (K, M) at every frequency (any damping),
    /// and the dense LU at `lu_points` of the frequencies (0: none).
    Modal {
        /// Frequencies also solved by the dense LU (evenly spread, both ends included).
        lu_points: usize,
    },
}

/// What to compute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrfConfig {
    /// Lowest frequency, Hz (≥ 0; > 0 with `log`).
    pub from_hz: f64,
    /// Highest frequency, Hz (> `from_hz`).
    pub to_hz: f64,
    /// Number of frequencies, 1 ..= [`MAX_FRF_POINTS`] (both ends included).
    pub points: usize,
    /// Geometric spacing (default: even).
    pub log: bool,
    /// The damping.
    pub damping: DampingChoice,
    /// The dense check, if any.
    pub dense: Option<DenseCheckKind>,
    /// Label of the progress bar drawn on a terminal over the exact damped forms' frequencies
    /// ([`super::cost::in_chunks`]; None: no bar).
    pub progress: Option<&'static str>,
}

impl Default for FrfConfig {
    /// 0.5 .. 50 Hz, 1000 even points, the scene's damping, no dense check, no progress bar.
    fn default() -> Self {
        FrfConfig {
            from_hz: 0.5,
            to_hz: 50.0,
            points: 1000,
            log: false,
            damping: DampingChoice::default(),
            dense: None,
            progress: None,
        }
    }
}

/// The response of one pose.
#[derive(Debug, Clone)]
pub struct FrfResult {
    /// The scene as computed (the estimator's: `auto` resolved).
    pub scene: Scene,
    /// The damping used.
    pub damping: Damping,
    /// 3 (point mass) or 6 (rigid body): the leading block of each receptance.
    pub dim: usize,
    /// The frequencies, Hz.
    pub frequencies_hz: Vec<f64>,
    /// The receptance at each frequency, m/N (rad/(N·m) in the rotational block; the
    /// leading `dim` × `dim` block, translations first, zeros elsewhere).
    pub receptance: Vec<Matrix6<Complex64>>,
    /// The natural frequencies in the band whose modes the end-effector feels (first of
    /// each cluster, end-effector participation ≥ [`MARK_PARTICIPATION`]), Hz.
    pub natural_hz: Vec<f64>,
    /// Wall time of the structured receptance over the band, s.
    pub structured_s: f64,
    /// The dense check, when asked.
    pub dense: Option<DenseCheck>,
}

/// The frequencies of `cfg`'s band ([`frequency_grid`]), refusals naming the parameter.
pub fn frequencies(cfg: &FrfConfig) -> Result<Vec<f64>, StudyError> {
    let hz = |f: f64| format!("{} Hz", message_number(f));
    frequency_grid(cfg.from_hz, cfg.to_hz, cfg.points, cfg.log).map_err(|e| match e {
        FrfError::Points(n) => {
            let rule = format!("must be in 1..={MAX_FRF_POINTS}");
            ParamError::invalid(Param::Points, n, rule).into()
        }
        FrfError::LogFromZero(f) => {
            let rule = "a log-spaced band must start above 0 Hz";
            ParamError::invalid(Param::FromHz, hz(f), rule).into()
        }
        FrfError::Range { from_hz, .. } if !(from_hz.is_finite() && from_hz >= 0.0) => {
            let rule = "must be finite and >= 0";
            ParamError::invalid(Param::FromHz, hz(from_hz), rule).into()
        }
        FrfError::Range { from_hz, to_hz } => {
            let rule = format!(
                "must be finite and above the lowest frequency, {}",
                hz(from_hz)
            );
            ParamError::invalid(Param::ToHz, hz(to_hz), rule).into()
        }
        FrfError::TooHigh(to_hz) => {
            let rule = format!(
                "above the highest frequency of a response, {}",
                hz(MAX_FRF_HZ)
            );
            ParamError::invalid(Param::ToHz, hz(to_hz), rule).into()
        }
        other => StudyError::Frf(other),
    })
}

/// The response of `scene` at its own pose and T_min (module docs).
///
/// ```
/// use cablevib::prelude::*;
///
/// let scene = Scene::load("spatial-paper")?;
/// let cfg = FrfConfig {
///     from_hz: 0.0,
///     to_hz: 20.0,
///     points: 5,
///     damping: DampingChoice { undamped: true, ..Default::default() },
///     ..FrfConfig::default()
/// };
/// let r = frf(&scene, &cfg)?;
/// assert_eq!((r.dim, r.receptance.len()), (3, 5));
/// // At 0 Hz the receptance is the static flexibility: the inverse of the stiffness the
/// // estimator reports at the same pose.
/// let mut est = Estimator::new(&scene)?;
/// let e = est.update(&Pose::in_scene(&scene, scene.ee_position_m), Tmin::Scene);
/// let k_inv = e.stiffness.translational_n_m().try_inverse().unwrap();
/// for i in 0..3 {
///     for j in 0..3 {
///         let h = r.receptance[0][(i, j)];
///         assert!((h.re - k_inv[(i, j)]).abs() <= 1e-8 * k_inv.norm() && h.im == 0.0);
///     }
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn frf(scene: &Scene, cfg: &FrfConfig) -> Result<FrfResult, StudyError> {
    frf_announced(scene, cfg, |_| {})
}

/// [`frf`], with the work's estimate ([`super::cost::estimate_cost`]: refused past the
/// memory budget before it allocates) handed to `announce` before the response is computed
/// (the command line prints a long one's on stderr: [`WorkEstimate::announcement`]).
pub fn frf_announced(
    scene: &Scene,
    cfg: &FrfConfig,
    announce: impl FnMut(&WorkEstimate),
) -> Result<FrfResult, StudyError> {
    let freqs = frequencies(cfg)?;
    let damping = cfg.damping.resolve(scene.damping)?;
    if cfg.dense == Some(DenseCheckKind::Lu) && matches!(damping, Damping::ModalRatio { .. }) {
        return Err(ParamError::NotApplicable {
            param: Param::Dense,
            reason:
                "modal damping has no damping matrix to assemble (loss factor, Rayleigh or none)"
                    .into(),
            instead: Some(Param::DenseModal),
        }
        .into());
    }
    if scene.model.sag {
        respond(&mut Sagged::new(scene)?, cfg, damping, freqs, announce)
    } else {
        respond(&mut Taut::new(scene)?, cfg, damping, freqs, announce)
    }
}

/// What differs between the models of a response: their set-up at the pose (in `new`),
/// the natural frequencies, the structured receptance and the assembled dense problem.
trait ResponseModel {
    /// The scene as computed.
    fn scene(&self) -> &Scene;
    /// 3 (point mass) or 6 (rigid body).
    fn dim(&self) -> usize;
    /// The natural frequencies to list ([`marked`]), Hz.
    fn natural_hz(&mut self, cfg: &FrfConfig) -> Result<Vec<f64>, StudyError>;
    /// The structured receptance at each of `freqs`, its cost checked first
    /// ([`check_cost`]).
    fn receptance(
        &mut self,
        cfg: &FrfConfig,
        damping: &Damping,
        freqs: &[f64],
        announce: &mut dyn FnMut(&WorkEstimate),
    ) -> Result<Vec<Matrix6<Complex64>>, StudyError>;
    /// The assembled (K, M) of the same model.
    fn dense_matrices(&self) -> Result<(DMatrix<f64>, DMatrix<f64>), String>;
}

/// The response of one model: natural frequencies, receptance, the dense check asked for.
fn respond(
    model: &mut impl ResponseModel,
    cfg: &FrfConfig,
    damping: Damping,
    freqs: Vec<f64>,
    mut announce: impl FnMut(&WorkEstimate),
) -> Result<FrfResult, StudyError> {
    let natural_hz = model.natural_hz(cfg)?;
    let t0 = Instant::now();
    let h = model.receptance(cfg, &damping, &freqs, &mut announce)?;
    let structured_s = t0.elapsed().as_secs_f64();
    let dense = match cfg.dense {
        None => None,
        Some(kind) => {
            let param = match kind {
                DenseCheckKind::Lu => Param::Dense,
                DenseCheckKind::Modal { .. } => Param::DenseModal,
            };
            let (k, m) = model
                .dense_matrices()
                .map_err(|e| StudyError::Solve(format!("{}: {e}", param.name())))?;
            let checked = Checked {
                k: &k,
                m: &m,
                dim: model.dim(),
                damping: &damping,
                freqs: &freqs,
                h: &h,
            };
            Some(match kind {
                DenseCheckKind::Lu => checked.lu_every()?,
                DenseCheckKind::Modal { lu_points } => checked.modal_every(lu_points)?,
            })
        }
    };
    Ok(FrfResult {
        scene: model.scene().clone(),
        damping,
        dim: model.dim(),
        frequencies_hz: freqs,
        receptance: h,
        natural_hz,
        structured_s,
        dense,
    })
}

/// The cost of `points` frequencies with `damping` (a modal basis of `basis_modes` modes,
/// at most [`MAX_FRF_MODES`]): refused past the memory budget, else given to `announce`.
fn check_cost(
    s: &Scene,
    damping: &Damping,
    points: usize,
    basis_modes: usize,
    announce: &mut dyn FnMut(&WorkEstimate),
) -> Result<(), StudyError> {
    let work = Work::Frf {
        damping,
        points,
        basis_modes: basis_modes.min(MAX_FRF_MODES),
    };
    let estimate = estimate_cost(s, &work);
    estimate.check_memory()?;
    announce(&estimate);
    Ok(())
}

/// The natural frequencies to list: first of each cluster, end-effector participation at
/// least [`MARK_PARTICIPATION`], within the band.
fn marked(cfg: &FrfConfig, modes: &[Mode]) -> Vec<f64> {
    modes
        .iter()
        .enumerate()
        .filter(|(i, m)| m.cluster_start == *i && m.ee_participation >= MARK_PARTICIPATION)
        .map(|(_, m)| lambda_to_hz(m.lambda))
        .filter(|&f| f >= cfg.from_hz && f <= cfg.to_hz)
        .collect()
}

/// Taut (chord) cables: the structured solver of the pose model.
struct Taut {
    /// The pose: Clarabel tensions at the scene's pose.
    pose: PoseModel,
    /// Its structured solver, loaded.
    solver: ModalSolver,
}

impl Taut {
    fn new(s: &Scene) -> Result<Self, StudyError> {
        let pose = PoseModel::new(s).map_err(|e| StudyError::Solve(e.to_string()))?;
        let mut solver = ModalSolver::new(ModalParams::default());
        pose.load(&mut solver);
        Ok(Taut { pose, solver })
    }
}

impl ResponseModel for Taut {
    fn scene(&self) -> &Scene {
        &self.pose.scene
    }

    fn dim(&self) -> usize {
        self.pose.dim()
    }

    fn natural_hz(&mut self, cfg: &FrfConfig) -> Result<Vec<f64>, StudyError> {
        let n_band = self.solver.count_below(hz_to_lambda(cfg.to_hz)) as usize;
        let mut modes = vec![Mode::default(); n_band.min(MARK_MODES)];
        let nm = self
            .solver
            .modes(modes.len(), &mut modes)
            .map_err(|e| StudyError::Solve(e.to_string()))?;
        Ok(marked(cfg, &modes[..nm]))
    }

    fn receptance(
        &mut self,
        cfg: &FrfConfig,
        damping: &Damping,
        freqs: &[f64],
        announce: &mut dyn FnMut(&WorkEstimate),
    ) -> Result<Vec<Matrix6<Complex64>>, StudyError> {
        let cutoff_hz = MODAL_CUTOFF_RATIO * cfg.to_hz;
        let basis_modes = match damping {
            Damping::ModalRatio { .. } => self.solver.count_below(hz_to_lambda(cutoff_hz)) as usize,
            _ => 0,
        };
        check_cost(
            &self.pose.scene,
            damping,
            freqs.len(),
            basis_modes,
            announce,
        )?;
        receptance(
            &self.pose,
            &mut self.solver,
            damping,
            freqs,
            cutoff_hz,
            cfg.progress,
        )
    }

    fn dense_matrices(&self) -> Result<(DMatrix<f64>, DMatrix<f64>), String> {
        self.pose.dense().map_err(|e| e.to_string())
    }
}

/// Sagging cables (FEM chains on the catenary): the estimator's sagged tension solve at
/// the scene's pose, then the sagged structured solver's D at the complex λ of each
/// frequency, or its shapes' superposition for modal damping.
struct Sagged {
    /// The estimator, updated at the scene's pose; its sagged structured solver (the count
    /// and the receptance move its scratch, not its pose) is used in place: a copy would
    /// double a model that may fill most of the memory budget before the budget is checked.
    est: Estimator,
    /// Degrees of freedom of its model.
    total: usize,
    /// 3 (point mass) or 6 (rigid body).
    dim: usize,
}

impl Sagged {
    fn new(s: &Scene) -> Result<Self, StudyError> {
        if s.model.element == ElementKind::Continuous {
            return Err(FrfError::SagContinuous.into());
        }
        let mut est = Estimator::new(s).map_err(|e| StudyError::Build(e.to_string()))?;
        let pose = Pose::in_scene(s, s.ee_position_m);
        let e = *est.update(&pose, Tmin::Scene);
        if !e.status.is_ok() {
            let why = e.error.map(|x| x.to_string()).unwrap_or_default();
            return Err(StudyError::Solve(format!("sagged pose: {why}")));
        }
        let total = est.model_dof().unwrap_or(0);
        let dim = est.sag_modal().ok_or_else(no_sagged_pose)?.dim();
        Ok(Sagged { est, total, dim })
    }
}

impl ResponseModel for Sagged {
    fn scene(&self) -> &Scene {
        self.est.scene()
    }

    fn dim(&self) -> usize {
        self.dim
    }

    /// The modes below the band's top (the count's, as for taut cables; at most
    /// [`SAG_MARK_MODES`], never more than the model has).
    fn natural_hz(&mut self, cfg: &FrfConfig) -> Result<Vec<f64>, StudyError> {
        let n_band = self
            .est
            .sag_modal_mut()
            .ok_or_else(no_sagged_pose)?
            .count_below(hz_to_lambda(cfg.to_hz)) as usize;
        let mut modes = vec![Mode::default(); n_band.min(SAG_MARK_MODES).min(self.total)];
        let nm = self
            .est
            .modes(modes.len(), &mut modes)
            .map_err(|e| StudyError::Solve(e.to_string()))?;
        Ok(marked(cfg, &modes[..nm]))
    }

    fn receptance(
        &mut self,
        cfg: &FrfConfig,
        damping: &Damping,
        freqs: &[f64],
        announce: &mut dyn FnMut(&WorkEstimate),
    ) -> Result<Vec<Matrix6<Complex64>>, StudyError> {
        if let Damping::ModalRatio { zeta } = *damping {
            let cutoff_hz = MODAL_CUTOFF_RATIO * cfg.to_hz;
            return sagged_modal(&mut self.est, zeta, cutoff_hz, self.total, freqs);
        }
        check_cost(self.est.scene(), damping, freqs.len(), 0, announce)?;
        let chunk = frf_chunk(self.est.scene(), damping);
        let sag = self.est.sag_modal_mut().ok_or_else(no_sagged_pose)?;
        let h = in_chunks(cfg.progress, freqs.len(), chunk, |r| {
            sag.receptance_over(damping, &freqs[r])
        })?;
        Ok(h)
    }

    fn dense_matrices(&self) -> Result<(DMatrix<f64>, DMatrix<f64>), String> {
        self.est.dense_matrices().map_err(|e| e.to_string())
    }
}

/// The error of a sagged solver that has no pose loaded.
fn no_sagged_pose() -> StudyError {
    StudyError::Solve("no sagged pose loaded".into())
}

/// Modal damping with sag: modal superposition of the sagged structured shapes below
/// `cutoff_hz` with the residual flexibility of the rest.
fn sagged_modal(
    est: &mut Estimator,
    zeta: f64,
    cutoff_hz: f64,
    total: usize,
    freqs: &[f64],
) -> Result<Vec<Matrix6<Complex64>>, StudyError> {
    let cap = MAX_FRF_MODES.min(total).max(1);
    let mut k = 16usize.min(cap);
    let basis = loop {
        let b = est
            .ee_modal_basis(k)
            .map_err(|e| StudyError::Solve(format!("modal basis with sag: {e}")))?;
        let top = b.lambda.last().map_or(0.0, |&l| lambda_to_hz(l));
        if top > cutoff_hz || k >= cap {
            break b;
        }
        k = (2 * k).min(cap);
    };
    let mb = ModalBasis::from_modes(basis.lambda, basis.phi_ee, &basis.flexibility, basis.dim)?;
    Ok(freqs
        .iter()
        .map(|&f| mb.receptance(zeta, 2.0 * std::f64::consts::PI * f))
        .collect())
}
