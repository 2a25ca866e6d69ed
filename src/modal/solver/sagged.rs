//! What only the sagged solver has: building it for FEM or continuous chains, setting each
//! cable's chain on its catenary (its hidden cable, its swivel pulley) and loading the
//! pose, and its mode shapes from the cables' frames.

use super::{SagModalSolver, Solver};
use crate::cable::sagged::{SagChain, SagContMesh, SagContinuousParams, SagSupport};
use crate::elastic_catenary::Catenary;
use crate::modal::engine::DynEval;
use crate::modal::frf::FrfError;
use crate::modal::sagged::{HangingCable, SagCableFrame, SagChains, SagEndEffector, SagLoadError};
use crate::modal::shapes::{mode_shapes, ModeShapes, SagSystem, ShapeError, ShapeParams};
use crate::modal::ModalParams;
use crate::scene::Damping;
use nalgebra::{Matrix3, Matrix6, Vector3};
use num_complex::Complex64;

impl Solver<SagChains> {
    /// Room for `n_cables` cables of up to `n_el_max` FEM elements each (the only
    /// allocation).
    pub fn new(params: ModalParams, n_cables: usize, n_el_max: usize) -> SagModalSolver {
        Self::with_problem(params, SagChains::new(n_cables, n_el_max, None))
    }

    /// Room for `n_cables` continuous (N → ∞) cables with the mesh rule `cont` (the only
    /// allocation); set each with [`Self::set_continuous`] before [`Self::load`].
    pub fn new_continuous(
        params: ModalParams,
        n_cables: usize,
        cont: SagContinuousParams,
    ) -> SagModalSolver {
        Self::with_problem(params, SagChains::new(n_cables, 1, Some(cont)))
    }

    /// Cable i's chain, to be set (e.g. [`SagChain::set_fem`]) before [`Self::load`].
    pub fn chain_mut(&mut self, i: usize) -> &mut SagChain {
        self.problem.chain_mut(i)
    }

    /// Cable i's chain.
    pub fn chain(&self, i: usize) -> &SagChain {
        &self.problem.chains[i]
    }

    /// Whether the solver holds continuous cables ([`Self::new_continuous`]).
    pub fn is_continuous(&self) -> bool {
        self.problem.continuous
    }

    /// Set cable i's continuous chain on catenary `cat` with mass `mu_kg_m` per unstretched
    /// length (a solver built by [`Self::new_continuous`]). No allocation.
    pub fn set_continuous(
        &mut self,
        i: usize,
        cat: &Catenary,
        mu_kg_m: f64,
    ) -> Result<SagContMesh, SagLoadError> {
        self.problem.set_continuous(i, cat, mu_kg_m)
    }

    /// Put cable i's continuous chain (set by [`Self::set_continuous`]) on the hidden cable
    /// `support` ([`crate::cable::sagged::SagContinuous::set_support`]). No allocation.
    pub fn support_continuous(
        &mut self,
        i: usize,
        support: Option<SagSupport>,
    ) -> Result<(), SagLoadError> {
        self.problem.support_continuous(i, support)
    }

    /// Cable i's exit point moves with the end-effector (a swivel pulley): `map` is
    /// X = (I − τ_a sᵀ) ∂A/∂B (3 × 3; τ_a the catenary's unit tangent at the exit point, s
    /// the chord's unit direction, ∂A/∂B [`crate::kinematics::PulleyExit::exit_jacobian`]),
    /// None for a fixed anchor. The next [`Self::load`] adds the term it makes to D(λ).
    /// Kept until changed. A map with a non-finite entry is refused (`BadFrame`), a cable
    /// index beyond the solver's (`CableCount`). No allocation.
    pub fn set_exit_motion(
        &mut self,
        i: usize,
        map: Option<Matrix3<f64>>,
    ) -> Result<(), SagLoadError> {
        self.problem.set_exit_motion(i, map)
    }

    /// Load a pose whose chains 0 .. frames.len() are set: each cable's frame, the unit
    /// `up` (−g/|g|) and the end-effector. No allocation.
    pub fn load(
        &mut self,
        frames: &[SagCableFrame],
        up: &Vector3<f64>,
        ee: &SagEndEffector,
    ) -> Result<(), SagLoadError> {
        self.problem
            .load_with(frames.len(), up, ee, |_, i| Ok(frames[i]))
    }

    /// Set every cable's chain to `n_el` FEM elements on its catenary and load the pose
    /// (the end force of cable i is −(H h_i + V_e up)). No allocation.
    pub fn load_catenaries(
        &mut self,
        cables: &[HangingCable],
        n_el: usize,
        up: &Vector3<f64>,
        ee: &SagEndEffector,
    ) -> Result<(), SagLoadError> {
        self.problem.load_with(cables.len(), up, ee, |p, i| {
            let c = &cables[i];
            p.chain_mut(i)
                .set_fem(&c.catenary, c.mu_kg_m, n_el)
                .map_err(|e| SagLoadError::Chain(i, e))?;
            Ok(SagCableFrame {
                h: c.h,
                arm_m: c.arm_m,
                end_force_n: -(c.h * c.catenary.h_n + up * c.catenary.v_end_n()),
            })
        })
    }

    /// Number of cables of the loaded pose (0 before any load).
    pub fn loaded_cables(&self) -> usize {
        self.problem.loaded_cables()
    }

    /// D(λ), D'(λ) and the blocked count by each chain's own recurrence, one chain after
    /// the other ([`SagChain::eval`]): the reference of the lockstep evaluation
    /// [`Self::eval`] uses (counted as an evaluation too).
    pub fn eval_reference(&mut self, lambda: f64) -> DynEval {
        self.problem.eval_reference(lambda)
    }

    /// The mass-normalised mode shapes of the loaded pose (FEM chains) at the eigenvalues
    /// `modes` = (λ in rad²/s², multiplicity), e.g. from [`Self::eigen_clusters`]: for
    /// each, `multiplicity` shapes, M-orthonormal, ordered by descending end-effector
    /// participation (`modal::shapes`' docs). `h` is each cable's unit horizontal (world
    /// frame), `up` the unit vertical, `arms_m` the attachment arms of a rigid end-effector
    /// (ignored for a point mass): the frames the pose was loaded with. A cable's nodes are
    /// at the fractions j/N of its unstretched length ([`ModeShapes::fractions`]); on a
    /// hidden cable node 0 is the junction's motion and the hidden cable's mass is in the
    /// normalisation. Continuous cables: [`ShapeError::SagContinuous`]. Allocates; never on
    /// the real-time path.
    pub fn mode_shapes(
        &mut self,
        h: &[Vector3<f64>],
        up: &Vector3<f64>,
        arms_m: &[Vector3<f64>],
        modes: &[(f64, u32)],
        params: &ShapeParams,
    ) -> Result<ModeShapes, ShapeError> {
        let (mut sys, mut out) = SagSystem::new(&mut self.problem, h, up, arms_m, params)?;
        mode_shapes(&mut sys, modes, params, &mut out)?;
        Ok(out)
    }

    /// The quasi-static influence field of the loaded pose on its sagging FEM chains, as
    /// [`ModalSolver::influence_field`](crate::modal::ModalSolver::influence_field); `h`,
    /// `up`, `arms_m` and `params` as [`Self::mode_shapes`]. A cable whose static end map
    /// is singular (no stiffness) is [`ShapeError::NotAnEigenvalue`] at λ = 0. Allocates;
    /// never on the real-time path.
    pub fn influence_field(
        &mut self,
        h: &[Vector3<f64>],
        up: &Vector3<f64>,
        arms_m: &[Vector3<f64>],
        params: &ShapeParams,
    ) -> Result<ModeShapes, ShapeError> {
        let (sys, mut out) = SagSystem::new(&mut self.problem, h, up, arms_m, params)?;
        sys.influence_field(&mut out)?;
        Ok(out)
    }

    /// [`Self::receptance`] at each frequency of `freqs_hz` (Hz).
    pub fn receptance_over(
        &mut self,
        damping: &Damping,
        freqs_hz: &[f64],
    ) -> Result<Vec<Matrix6<Complex64>>, FrfError> {
        freqs_hz
            .iter()
            .map(|&f| self.receptance(damping, 2.0 * std::f64::consts::PI * f))
            .collect()
    }
}
