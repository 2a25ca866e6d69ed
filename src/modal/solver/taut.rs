//! What only the taut solver has: loading the cable models of a pose (point mass or rigid
//! body, the pulleys' constant term), the closed-form pole queries and the sum rule's total,
//! its mode shapes and modal basis from the cable models.

use super::{ModalSolver, Solver};
use crate::cable::CableModel;
use crate::modal::frf::{inverse_block, FrfError, ModalBasis, MAX_FRF_MODES};
use crate::modal::shapes::{mode_shapes, ModeShapes, ShapeError, ShapeParams, TautSystem};
use crate::modal::{hz_to_lambda, ModalParams, TautChains};
use crate::scene::Damping;
use nalgebra::{Matrix3, Matrix6, Vector3};
use num_complex::Complex64;

impl Solver<TautChains> {
    /// A solver with the given parameters (sizes everything: the only allocation).
    pub fn new(params: ModalParams) -> ModalSolver {
        Self::with_problem(params, TautChains::new())
    }

    /// Load the chains of the cable models at one pose and the end-effector mass (kg).
    /// Chains that contribute nothing (zero spring and zero mass: a switched-off effect)
    /// are not loaded, so they cost nothing per evaluation.
    pub fn load(&mut self, models: &[CableModel], ee_mass_kg: f64) {
        self.problem.p.load(models, ee_mass_kg, None);
    }

    /// Load for a rigid end-effector: cable i's end moves with G_i = [I, −\[r_i\]×] (arm r_i,
    /// world frame, m); `inertia_kg_m2` is the world-frame inertia about the centroid and
    /// `k_geo_rot` the rotational geometric stiffness (N·m/rad) of the tensions.
    pub fn load_rigid(
        &mut self,
        models: &[CableModel],
        ee_mass_kg: f64,
        inertia_kg_m2: &Matrix3<f64>,
        arms_m: &[Vector3<f64>],
        k_geo_rot: &Matrix3<f64>,
    ) {
        self.problem
            .p
            .load(models, ee_mass_kg, Some((inertia_kg_m2, arms_m, k_geo_rot)));
    }

    /// Add a constant stiffness at the end-effector's DOFs (the leading 3 × 3 or 6 × 6
    /// block of `k`: N/m, N/rad, N·m/rad) to the loaded pose, until the next load: the
    /// swivel pulleys' own term ([`crate::kinematics::Geometry::pulley_stiffness`]), which
    /// holds at every λ since the pulleys' geometry carries no mass.
    pub fn add_ee_stiffness(&mut self, k: &Matrix6<f64>) {
        self.problem.p.add_ee_stiffness(k);
    }

    /// The sum of the end-effector participation over all modes of the loaded model,
    /// tr(M_ee M_∞⁻¹) with M_∞ = lim −D(λ)/λ as λ → −∞ (the end-effector's mass plus the
    /// chains' end masses): the modes are complete, so Σ_k p_k = Σ_k φ_kᵀ M_ee φ_k equals it.
    /// `dim` for continuous or massless cables, slightly less for discrete ones.
    pub fn participation_total(&self) -> f64 {
        self.problem.p.p_total
    }

    /// The lowest blocked eigenvalue over all chains, rad²/s² (∞ when none).
    pub fn lowest_pole(&self) -> f64 {
        self.problem.p.lowest_pole()
    }

    /// The pole-free interval (a, b) of D around λ: the nearest blocked eigenvalues of all
    /// chains below and above (0 and ∞ when there are none), rad²/s².
    pub fn pole_interval(&self, lambda: f64) -> (f64, f64) {
        self.problem.p.pole_interval(lambda)
    }

    /// The mass-normalised mode shapes at the eigenvalues `modes` = (λ in rad²/s²,
    /// multiplicity), e.g. from [`Self::eigen_clusters`] or the dense reference: for each,
    /// `multiplicity` shapes, M-orthonormal, ordered by descending end-effector participation.
    ///
    /// The solver must be loaded ([`Self::load`] or [`Self::load_rigid`]) with the same
    /// `models`; `arms_m` are the attachment arms (world frame, m) of a rigid end-effector
    /// (ignored for a point mass). Continuous cables are sampled at
    /// [`ShapeParams::continuous_samples`] points. Allocates; never on the real-time path.
    pub fn mode_shapes(
        &mut self,
        models: &[CableModel],
        arms_m: &[Vector3<f64>],
        modes: &[(f64, u32)],
        params: &ShapeParams,
    ) -> Result<ModeShapes, ShapeError> {
        let (mut sys, mut out) = TautSystem::new(&mut self.problem, models, arms_m, params)?;
        mode_shapes(&mut sys, modes, params, &mut out)?;
        Ok(out)
    }

    /// The quasi-static influence field of the loaded pose: one entry of
    /// [`ModeShapes::modes`] per end-effector DOF (3, or 6 for a rigid body), its `ee` the
    /// unit displacement (m, or rad), its `cables` every node's static displacement (m per
    /// m, or m per rad) with the anchors held (the `shapes` module's `influence`). `models`,
    /// `arms_m` and `params` as [`Self::mode_shapes`]. Allocates; never on the real-time
    /// path.
    pub fn influence_field(
        &mut self,
        models: &[CableModel],
        arms_m: &[Vector3<f64>],
        params: &ShapeParams,
    ) -> Result<ModeShapes, ShapeError> {
        let (sys, mut out) = TautSystem::new(&mut self.problem, models, arms_m, params)?;
        sys.influence_field(&mut out);
        Ok(out)
    }

    /// The modes of the loaded pose (loaded with `models`, arms `arms_m` for a rigid
    /// end-effector) up to `max_hz` (at most `max_modes`, clusters completed), their
    /// end-effector shapes, and the residual flexibility of the others: the basis of the
    /// frequency response with modal damping.
    pub fn modal_basis(
        &mut self,
        models: &[CableModel],
        arms_m: &[Vector3<f64>],
        max_hz: f64,
        max_modes: usize,
    ) -> Result<ModalBasis, FrfError> {
        let dim = self.dim();
        let params = ShapeParams::default();
        let below = self.count_below(hz_to_lambda(max_hz)) as usize;
        let k = below.clamp(1, max_modes.clamp(1, MAX_FRF_MODES));
        let err = |e: ShapeError| FrfError::Modes(e.to_string());
        let clusters = self.eigen_clusters(k, &params).map_err(err)?;
        let shapes = self
            .mode_shapes(models, arms_m, &clusters, &params)
            .map_err(err)?;
        let d0 = self.eval(0.0).d;
        let flex = inverse_block(&d0.map(|x| Complex64::new(x, 0.0)), dim).map(|z| z.re);
        let lambda = shapes.modes.iter().map(|m| m.lambda).collect();
        let ee = shapes.modes.iter().map(|m| m.ee).collect();
        ModalBasis::from_modes(lambda, ee, &flex, dim)
    }
}

/// The receptance at each frequency of `freqs_hz` (Hz) of the loaded `solver` (loaded with
/// `models`, arms `arms_m` for a rigid end-effector) with `damping`: exact at a complex λ
/// for loss-factor, Rayleigh or no damping; for modal damping by [`ModalBasis`] over the
/// modes below `modal_cutoff_hz` (at most [`MAX_FRF_MODES`]) with the static correction.
/// The taut computation of the frequency-response study (`study::frf`), behind `cablevib frf`
/// and the Python `frf`.
pub fn receptance_over(
    solver: &mut ModalSolver,
    models: &[CableModel],
    arms_m: &[Vector3<f64>],
    damping: &Damping,
    freqs_hz: &[f64],
    modal_cutoff_hz: f64,
) -> Result<Vec<Matrix6<Complex64>>, FrfError> {
    let w = |f: f64| 2.0 * std::f64::consts::PI * f;
    if let Damping::ModalRatio { zeta } = *damping {
        let basis = solver.modal_basis(models, arms_m, modal_cutoff_hz, MAX_FRF_MODES)?;
        return Ok(freqs_hz
            .iter()
            .map(|&f| basis.receptance(zeta, w(f)))
            .collect());
    }
    freqs_hz
        .iter()
        .map(|&f| solver.receptance(damping, w(f)))
        .collect()
}
