//! Natural frequencies of a robot whose cables sag: the structured solver on the sagged
//! FEM chains ([`crate::cable::sagged`]) and its dense reference.
//!
//! **D(λ).** Cable i hangs in the plane (h_i, up), n_i = h_i × up; its chain, condensed
//! onto its end, gives S_in,i(λ) (2 × 2 in (h_i, up)) and s_out,i(λ). With E_i = [h_i up]
//! (3 × 2), the end-effector's dynamic stiffness is
//!
//! ```text
//!     D(λ) = Σ_i [E_i S_in,i Eᵢᵀ + s_out,i n_i n_iᵀ] − λ m I                    (point mass)
//!     D(λ) = Σ_i G_iᵀ [E_i S_in,i Eᵢᵀ + s_out,i n_i n_iᵀ] G_i + K_geo − λ M₆     (rigid body)
//! ```
//!
//! with G_i = [I, −\[r_i\]×] the attachment map of arm r_i and K_geo = Σ_i (f_i·r_i) I −
//! sym(f_i r_iᵀ) the rotational geometric stiffness of the end forces
//! f_i = −(H_i h_i + V_e,i up) (along the end tangent, not the chord). A cable on a swivel
//! pulley adds the pulleys' own term to both, the symmetric part of −S_i(0) X_i (mapped
//! through G_i on a rigid body; X_i its exit point's motion,
//! [`SagModalSolver::set_exit_motion`]), the same at every λ. One evaluation is one O(N)
//! recurrence per cable. The Wittrick–Williams count J(λ) = Σ_i below_i(λ) + (negative
//! eigenvalues of D(λ)) is the exact number of natural frequencies below λ.
//!
//! **Lockstep evaluation.** When every loaded FEM chain has the same element count, `load`
//! packs them into a [`crate::cable::sagged::SagBatch`] and each evaluation runs all the
//! recurrences side by side (bit-identical to one chain after the other,
//! [`SagModalSolver::eval_reference`]); count-only evaluations skip S'.
//!
//! **First root** ([`SagModalSolver::first_root`]): the taut solver's first root
//! (`modal::first_mode`, written once over the condensed problem). The chains are not
//! uniform, so their blocked eigenvalues (the poles of D) are not known in closed form; the
//! count shows where they are. The first natural frequency lies at or below the lowest
//! pole, where μ₁(D(λ)) falls monotonically from μ₁(D(0)) > 0: safeguarded Newton on μ₁
//! from the last root (warm) or the Rayleigh guess (cold), inside a bracket kept by the
//! signs of μ₁ and by the blocked count (an iterate with a pole below it is an upper
//! bound); a bracket that collapses onto a pole (a mode with the end-effector still) is
//! reported there with participation 0. The count certifies the root on cold starts and
//! every 256th warm one. At most min(`max_evaluations`, `cycle_evaluations`) evaluations
//! per call, else `NoConvergence`; a search cut by the cycle's budget is continued by the
//! next call (bracket and all on the same loaded problem, from its last iterate on
//! another), up to `max_evaluations` over the calls.
//!
//! **First K modes** ([`SagModalSolver::modes`]): the count brackets mode k; bisection on
//! the count while the blocked count differs at the bracket's ends (a pole inside), then,
//! once it is equal (the bracket is pole-free: the blocked count only steps at poles),
//! safeguarded Newton on branch k − below of D's sorted eigenvalues. Multiplicity from the
//! count over λ(1 ∓ δ); a cluster's participations are the eigenvalues of
//! M₆^{1/2} V G⁻¹ Vᵀ M₆^{1/2}, V the unit eigenvectors of its branches, G = Vᵀ(−D')V.
//!
//! **Static stiffness** ([`SagModalSolver::static_stiffness`]): D(0), N/m (N·m/rad in the
//! rotational block), from each chain's cached S(0).
//!
//! Files: `problem` (the loaded pose, D(λ)), `modes` (first K),
//! `dense` (the assembled reference).

mod dense;
mod modes;
mod problem;

pub use dense::{assemble_sagged, sagged_assembled_dof, SagDenseCable};

use super::ee_tracker::{EeTracker, RescanCounts, SumMatrices, SumRules};
use super::first_mode::{FirstRootState, RootFinder};
use super::{ModalError, ModalParams, Root};
use crate::cable::sagged::{
    SagChain, SagChainError, SagContError, SagContMesh, SagContinuousParams,
};
use crate::elastic_catenary::Catenary;
use crate::modal::DynEval;
use nalgebra::{Matrix3, Matrix6, Vector3};
use problem::{SagProblem, SagView};

/// How one cable of a pose attaches to the end-effector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagCableFrame {
    /// Unit horizontal h of the cable's plane (from the anchor toward the end), world frame.
    pub h: Vector3<f64>,
    /// Attachment arm from the centroid, world frame, m (rigid end-effector only).
    pub arm_m: Vector3<f64>,
    /// Force of the cable on the end-effector, −(H h + V_e up), N (rigid end-effector
    /// only: its rotational geometric stiffness).
    pub end_force_n: Vector3<f64>,
}

/// One sagging cable of a pose, for [`SagModalSolver::load_catenaries`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HangingCable {
    /// The static profile.
    pub catenary: Catenary,
    /// Mass per unstretched length, kg/m.
    pub mu_kg_m: f64,
    /// Unit horizontal h of the cable's plane, world frame.
    pub h: Vector3<f64>,
    /// Attachment arm from the centroid, world frame, m (rigid end-effector only).
    pub arm_m: Vector3<f64>,
}

/// The end-effector: a point mass (3 DOF) or a rigid body (6 DOF).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SagEndEffector {
    /// Point mass, kg.
    Point {
        /// Mass, kg.
        mass_kg: f64,
    },
    /// Rigid body: mass and world-frame inertia about the centroid.
    Rigid {
        /// Mass, kg.
        mass_kg: f64,
        /// Inertia, kg·m².
        inertia_kg_m2: Matrix3<f64>,
    },
}

/// Errors of [`SagModalSolver::load`].
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SagLoadError {
    /// More cables than the solver was built for.
    #[error("{given} cables, the solver holds {capacity}")]
    CableCount {
        /// Cables given.
        given: usize,
        /// Cables the solver was built for.
        capacity: usize,
    },
    /// Cable i's basis is not orthonormal (h unit and horizontal, up unit) or not finite.
    #[error("cable {0}: its frame is not a finite orthonormal basis")]
    BadFrame(usize),
    /// The end-effector's mass or inertia is not positive definite and finite.
    #[error("end-effector mass or inertia not positive and finite")]
    BadMass,
    /// Cable i's chain could not be set.
    #[error("cable {0}: {1}")]
    Chain(usize, SagChainError),
    /// Cable i's continuous chain could not be set.
    #[error("cable {0}: {1}")]
    Continuous(usize, SagContError),
}

/// The robot-level structured solver for sagged cables: built once, loaded per pose.
#[derive(Debug, Clone)]
pub struct SagModalSolver {
    params: ModalParams,
    problem: SagProblem,
    evaluations: u32,
    /// The last first root, rad²/s² (NaN: none; the warm start).
    last_lambda1: f64,
    /// The first root's state between calls (certificate schedule, weighted sum rule, a
    /// search the last cycle's budget cut).
    first: FirstRootState,
    /// The evaluation counter when this cycle's first root began (the cycle's budget
    /// counts from there).
    cycle_base: u32,
    /// The end-effector mode tracker's state between cycles.
    tracker: EeTracker,
    loaded: bool,
}

impl SagModalSolver {
    /// Room for `n_cables` cables of up to `n_el_max` elements each (the only allocation).
    pub fn new(params: ModalParams, n_cables: usize, n_el_max: usize) -> SagModalSolver {
        Self::with_problem(params, SagProblem::new(n_cables, n_el_max, None))
    }

    /// A solver on `problem`, nothing loaded.
    fn with_problem(params: ModalParams, problem: SagProblem) -> SagModalSolver {
        SagModalSolver {
            params,
            problem,
            evaluations: 0,
            last_lambda1: f64::NAN,
            first: FirstRootState::new(),
            cycle_base: 0,
            tracker: EeTracker::new(),
            loaded: false,
        }
    }

    /// Room for `n_cables` continuous (N → ∞) cables with the mesh rule `cont` (the only
    /// allocation); set each with [`Self::set_continuous`] before [`Self::load`].
    pub fn new_continuous(
        params: ModalParams,
        n_cables: usize,
        cont: SagContinuousParams,
    ) -> SagModalSolver {
        Self::with_problem(params, SagProblem::new(n_cables, 1, Some(cont)))
    }

    /// Cable i's chain, to be set (e.g. [`SagChain::set_fem`]) before [`Self::load`].
    pub fn chain_mut(&mut self, i: usize) -> &mut SagChain {
        self.loaded = false;
        &mut self.problem.chains[i]
    }

    /// Cable i's chain.
    pub fn chain(&self, i: usize) -> &SagChain {
        &self.problem.chains[i]
    }

    /// The loaded problem's dynamic stiffness D(λ) at a complex λ, N/m (N·m/rad in the
    /// rotational block): each FEM chain's recurrences at complex λ (O(N) per cable). None
    /// for continuous cables (no complex form) or before a load. Point mass: the leading
    /// 3 × 3 block. Does not count as an evaluation.
    pub fn dynamic_stiffness_at(
        &self,
        lambda: num_complex::Complex64,
    ) -> Option<Matrix6<num_complex::Complex64>> {
        if !self.loaded {
            return None;
        }
        self.problem.d_complex(lambda)
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
        self.loaded = false;
        let p = &mut self.problem;
        p.check_continuous_index(i)?;
        let mesh = p.cont[i]
            .set(cat, mu_kg_m)
            .map_err(|e| SagLoadError::Continuous(i, e))?;
        p.cont_static[i] = p.cont[i].static_eval();
        Ok(mesh)
    }

    /// Put cable i's continuous chain (set by [`Self::set_continuous`]) on the hidden cable
    /// `support` ([`SagContinuous::set_support`]). No allocation.
    pub fn support_continuous(
        &mut self,
        i: usize,
        support: Option<crate::cable::sagged::SagSupport>,
    ) -> Result<(), SagLoadError> {
        self.loaded = false;
        let p = &mut self.problem;
        p.check_continuous_index(i)?;
        p.cont[i]
            .set_support(support)
            .map_err(|e| SagLoadError::Chain(i, e))?;
        p.cont_static[i] = p.cont[i].static_eval();
        Ok(())
    }

    /// Cable i's exit point moves with the end-effector (a swivel pulley): `map` is
    /// X = (I − τ_a sᵀ) ∂A/∂B (3 × 3; τ_a the catenary's unit tangent at the exit point, s
    /// the chord's unit direction, ∂A/∂B [`crate::kinematics::PulleyExit::exit_jacobian`]),
    /// None for a fixed anchor. The next [`Self::load`] adds the term it makes to D(λ)
    /// (`problem::add_exit_term`). Kept until changed. A map with a non-finite entry is
    /// refused (`BadFrame`), a cable index beyond the solver's (`CableCount`). No allocation.
    pub fn set_exit_motion(
        &mut self,
        i: usize,
        map: Option<Matrix3<f64>>,
    ) -> Result<(), SagLoadError> {
        self.loaded = false;
        let capacity = self.problem.exit_map.len();
        let slot = self
            .problem
            .exit_map
            .get_mut(i)
            .ok_or(SagLoadError::CableCount {
                given: i + 1,
                capacity,
            })?;
        if map.is_some_and(|x| !x.iter().all(|v| v.is_finite())) {
            return Err(SagLoadError::BadFrame(i));
        }
        *slot = map;
        Ok(())
    }

    /// Load a pose whose chains 0 .. frames.len() are set: each cable's frame, the unit
    /// `up` (−g/|g|) and the end-effector. No allocation.
    pub fn load(
        &mut self,
        frames: &[SagCableFrame],
        up: &Vector3<f64>,
        ee: &SagEndEffector,
    ) -> Result<(), SagLoadError> {
        self.load_with(frames.len(), up, ee, |_, i| Ok(frames[i]))
    }

    /// Load `n` cables, cable i's chain set and its frame given by `cable(problem, i)`.
    fn load_with(
        &mut self,
        n: usize,
        up: &Vector3<f64>,
        ee: &SagEndEffector,
        mut cable: impl FnMut(&mut SagProblem, usize) -> Result<SagCableFrame, SagLoadError>,
    ) -> Result<(), SagLoadError> {
        self.loaded = false;
        self.check_count(n)?;
        self.problem.set_end_effector(ee)?;
        for i in 0..n {
            let frame = cable(&mut self.problem, i)?;
            self.problem.set_cable(i, &frame, up)?;
        }
        self.problem.n = n;
        self.problem.pack();
        self.problem.add_exit_term();
        self.loaded = true;
        Ok(())
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
        self.load_with(cables.len(), up, ee, |p, i| {
            let c = &cables[i];
            p.chains[i]
                .set_fem(&c.catenary, c.mu_kg_m, n_el)
                .map_err(|e| SagLoadError::Chain(i, e))?;
            Ok(SagCableFrame {
                h: c.h,
                arm_m: c.arm_m,
                end_force_n: -(c.h * c.catenary.h_n + up * c.catenary.v_end_n()),
            })
        })
    }

    fn check_count(&self, given: usize) -> Result<(), SagLoadError> {
        let capacity = self.problem.chains.len();
        if given > capacity {
            return Err(SagLoadError::CableCount { given, capacity });
        }
        Ok(())
    }

    fn require_loaded(&self) -> Result<(), ModalError> {
        if self.loaded {
            Ok(())
        } else {
            Err(ModalError::NotLoaded)
        }
    }

    /// D(λ), D'(λ) and the blocked count of the loaded pose (one evaluation).
    pub fn eval(&mut self, lambda: f64) -> DynEval {
        self.evaluations = self.evaluations.wrapping_add(1);
        self.problem.eval(lambda)
    }

    /// D(λ), D'(λ) and the blocked count by each chain's own recurrence, one chain after
    /// the other ([`SagChain::eval`]): the reference of the lockstep evaluation
    /// [`Self::eval`] uses (counted as an evaluation too).
    pub fn eval_reference(&mut self, lambda: f64) -> DynEval {
        self.evaluations = self.evaluations.wrapping_add(1);
        self.problem.eval_reference(lambda)
    }

    /// Number of natural frequencies strictly below λ (Wittrick–Williams; one evaluation
    /// without D').
    pub fn count_below(&mut self, lambda: f64) -> u32 {
        self.evaluations = self.evaluations.wrapping_add(1);
        let e = self.problem.eval_with(lambda, false);
        e.below + e.eig().negatives() as u32
    }

    /// The end-effector's static stiffness D(0) (its leading 3 × 3 or 6 × 6 block), N/m
    /// (N·m/rad in the rotational block). No chain evaluation.
    pub fn static_stiffness(&self) -> Result<Matrix6<f64>, ModalError> {
        self.require_loaded()?;
        Ok(self.problem.static_eval().d)
    }

    /// Number of cables of the loaded pose (0 before any load).
    pub fn loaded_cables(&self) -> usize {
        if self.loaded {
            self.problem.n
        } else {
            0
        }
    }

    /// 3 (point mass) or 6 (rigid body).
    pub fn dim(&self) -> usize {
        self.problem.dim
    }

    /// Evaluations of D(λ) since the solver was built (a counter; differences give a
    /// solve's cost).
    pub fn evaluations(&self) -> u32 {
        self.evaluations
    }

    /// Number of natural frequencies of the loaded pose (end-effector DOF plus 3(N − 1)
    /// per cable with mass).
    pub fn total_modes(&self) -> usize {
        self.problem.total_modes()
    }

    /// The end-effector's mass matrix diag(m I, I) and its stiffness: the rigid body's
    /// rotational geometric stiffness plus the swivel pulleys' term (zero for a point mass
    /// without pulleys): what the dense reference also needs.
    pub fn ee_matrices(&self) -> (Matrix6<f64>, Matrix6<f64>) {
        (self.problem.m6, self.problem.k6)
    }

    /// The first natural frequency, warm-started from the last one found (cold when none).
    pub fn first_root_warm(&mut self) -> Result<Root, ModalError> {
        let warm = self.last_lambda1;
        self.first_root(warm.is_finite().then_some(warm))
    }

    /// Forget a first-root search the cycle's budget cut (the next call starts afresh).
    pub fn forget_pending(&mut self) {
        self.first.pending = None;
    }

    /// The first natural frequency from the Rayleigh guess (ignores the last root).
    pub fn first_root_cold(&mut self) -> Result<Root, ModalError> {
        self.first_root(None)
    }

    /// The first natural frequency, Newton started from `warm` (a predicted λ, rad²/s², e.g.
    /// the estimator's extrapolation of the last roots; accepted once a step is below
    /// [`ModalParams::newton_accept`] with a rate that leaves an error below
    /// [`ModalParams::rel_tol`]) or from the Rayleigh guess (`None`: cold). At most
    /// min([`ModalParams::max_evaluations`], [`ModalParams::cycle_evaluations`])
    /// evaluations of D(λ): one call is one cycle's first root; a root that does not fit is
    /// `NoConvergence` (with its bracket), never a longer cycle, and the search is continued
    /// by the next call: from where it stopped on the same loaded problem (a static pose),
    /// from its last iterate (when `warm` is None) on another one, until a root is found or
    /// [`ModalParams::max_evaluations`] are spent on it over the calls.
    pub fn first_root(&mut self, warm: Option<f64>) -> Result<Root, ModalError> {
        self.require_loaded()?;
        self.cycle_base = self.evaluations;
        let mut f = RootFinder {
            params: &self.params,
            view: SagView {
                p: &self.problem,
                evals: &mut self.evaluations,
            },
            budget_base: self.cycle_base,
            budget: self.params.cycle_evaluations,
        };
        let r = f.first_root(&mut self.first, warm);
        self.last_lambda1 = r.as_ref().map_or(f64::NAN, |r| r.lambda);
        r
    }

    /// The root finder on the loaded problem with this cycle's budget (counted from the
    /// start of this cycle's [`Self::first_root`]), and beside it the tracker and the
    /// sum rules (the plain one from one evaluation far below zero).
    fn tracker_parts(&mut self, budget: u32) -> (RootFinder<'_, SagView<'_>>, &mut EeTracker) {
        let f = RootFinder {
            params: &self.params,
            view: SagView {
                p: &self.problem,
                evals: &mut self.evaluations,
            },
            budget_base: self.cycle_base,
            budget,
        };
        (f, &mut self.tracker)
    }

    /// The sum rules of the loaded pose, traces and matrices (`modal::ee_tracker`'s bound):
    /// the plain one from one evaluation far below zero, the weighted one from the last
    /// first root (its trace) and the chains' cached static evaluations (its matrix, D(0)⁻¹).
    fn sums(&mut self, budget: u32) -> SumRules {
        let over_lambda = self.first.flex0;
        let flex = self.static_flexibility();
        let (m6, m_sqrt, dim) = (self.problem.m6, self.problem.m6_sqrt, self.problem.dim);
        let (mut f, _) = self.tracker_parts(budget);
        let m_inf_inv = if f.left() > 0 {
            f.view.mass_limit_inverse()
        } else {
            None
        };
        let Some(m_inf_inv) = m_inf_inv else {
            return SumRules::traces(f64::INFINITY, over_lambda);
        };
        SumRules {
            total: (m6 * m_inf_inv).trace(),
            over_lambda,
            matrices: Some(SumMatrices {
                m_inf_inv,
                flex,
                m_sqrt,
                dim,
            }),
        }
    }

    /// D(0)⁻¹ (its leading `dim` block, zeros elsewhere) from the chains' cached static
    /// evaluations; NaN when D(0) is not positive definite.
    fn static_flexibility(&self) -> Matrix6<f64> {
        let eg = self.problem.static_eval().eig();
        if !(eg.values[0] > 0.0) {
            return Matrix6::repeat(f64::NAN);
        }
        let mut flex = Matrix6::zeros();
        for j in 0..eg.n {
            let v = eg.vectors[j];
            flex += v * v.transpose() / eg.values[j];
        }
        flex
    }

    /// The end-effector mode of the loaded pose: the lowest mode whose participation is at
    /// least [`ModalParams::ee_participation_min`], by the taut solver's tracker
    /// ([`crate::modal::ModalSolver::ee_mode_tracked`]) on the sagged problem: its scan is
    /// an ascending sweep of the spectrum (every mode below the answer solved and read; at
    /// most [`ModalParams::max_scan_intervals`] modes). `first` is this pose's first root
    /// (not solved again). Offline use: not bounded by the cycle's budget.
    pub fn ee_mode(&mut self, first: &Root) -> Result<Root, ModalError> {
        self.require_loaded()?;
        let sums = self.sums(u32::MAX);
        let (mut f, tracker) = self.tracker_parts(u32::MAX);
        tracker.ee_mode(&mut f, sums, first)
    }

    /// The end-effector mode, tracked from the last cycle when `warm`, within what is left
    /// of this cycle's budget ([`ModalParams::cycle_evaluations`], counted from the start of
    /// this cycle's [`Self::first_root`]): the method of
    /// [`crate::modal::ModalSolver::ee_mode_tracked`] (watched modes followed by Newton on
    /// their branch of D, certified by the sum rules; scans spread over the cycles), where
    /// the poles are seen only through the count: a followed mode that crosses a pole is
    /// lost (the next scan finds it again), and there are no partner or neighbour searches
    /// (they walk closed-form poles). Ok(None) while the work goes on over the cycles
    /// (`first`: this cycle's first root). No allocation.
    pub fn ee_mode_tracked(
        &mut self,
        first: &Root,
        warm: bool,
    ) -> Result<Option<Root>, ModalError> {
        self.require_loaded()?;
        let budget = self.params.cycle_evaluations;
        let thr = self.params.ee_participation_min;
        let sums = if first.ee_participation >= thr {
            SumRules::traces(f64::INFINITY, self.first.flex0)
        } else {
            self.sums(budget)
        };
        let (mut f, tracker) = self.tracker_parts(budget);
        tracker.ee_mode_tracked(&mut f, sums, first, warm)
    }

    /// Forget the tracked end-effector mode (the next [`Self::ee_mode_tracked`] scans).
    pub fn reset_tracking(&mut self) {
        self.tracker.reset();
    }

    /// Counters of the end-effector bookkeeping (scans by reason, modes lost and dropped).
    pub fn rescan_counts(&self) -> RescanCounts {
        self.tracker.counts()
    }
}
