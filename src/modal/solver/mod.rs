//! [`Solver`]: the one structured real-time solver, generic over the loaded condensed
//! problem ([`Condensed`]: the taut chains [`TautChains`], the sagged ones
//! [`SagChains`](crate::modal::sagged::SagChains)). It composes the problem, the first
//! root's state ([`FirstRootState`]), the end-effector tracker ([`EeTracker`]) and the
//! cycle's evaluation budget; every search is written once, over the trait. What only one
//! model has (how a pose is loaded, the taut closed forms, the sagged chains' set-up) is in
//! `taut` and `sagged`.

mod sagged;
mod taut;

pub use taut::receptance_over;

use super::ee_tracker::{EeTracker, RescanCounts};
use super::engine::{Condensed, DynEval};
use super::first_mode::{relative_residual, FirstRootState, RootFinder};
use super::frf::{receptance, FrfError};
use super::shapes::{clusters_by_count, ShapeError, ShapeParams};
use super::spectrum::{modes_into, Mode, SpectrumParams};
use super::{ModalError, ModalParams, Root, TautChains};
use crate::scene::Damping;
use nalgebra::Matrix6;
use num_complex::Complex64;

/// The structured real-time eigen solver on the loaded problem `P`: `new` sizes everything,
/// the problem's `load` sets one pose, the root finders never allocate and are bounded.
/// [`ModalSolver`] on taut chains, [`SagModalSolver`] on sagging ones.
#[derive(Debug, Clone)]
pub struct Solver<P> {
    params: ModalParams,
    /// The loaded problem and its evaluation buffers.
    pub(in crate::modal) problem: P,
    /// The first root's state between cycles (certificate schedule, weighted sum rule, a
    /// search the cycle's budget cut).
    first: FirstRootState,
    /// The end-effector mode tracker's state between cycles.
    tracker: EeTracker,
    /// The cycle's evaluation budget (`u32::MAX`: unlimited) and the evaluation counter
    /// when it began ([`Self::begin_cycle`]).
    budget: u32,
    budget_base: u32,
    /// The last first root, rad²/s² (NaN: none; [`Self::first_root_warm`]'s start).
    last_lambda1: f64,
}

/// The structured solver on taut chains (straight cables: uniform chains, their blocked
/// eigenvalues in closed form).
pub type ModalSolver = Solver<TautChains>;

/// The structured solver on sagging cables (the chains about their elastic catenaries:
/// their blocked eigenvalues seen only through the count).
pub type SagModalSolver = Solver<crate::modal::sagged::SagChains>;

impl<P: Condensed> Solver<P> {
    /// A solver on `problem`, nothing solved yet, its budget unlimited.
    fn with_problem(params: ModalParams, problem: P) -> Solver<P> {
        Solver {
            params,
            problem,
            first: FirstRootState::new(),
            tracker: EeTracker::new(),
            budget: u32::MAX,
            budget_base: 0,
            last_lambda1: f64::NAN,
        }
    }

    /// Start a cycle with a budget of `evaluations` evaluations of D(λ) (`u32::MAX`:
    /// unlimited): [`Self::first_root`] and [`Self::ee_mode_tracked`] stop there, whatever
    /// is left of the end-effector work is continued in the next cycle. Until the first
    /// call the solver is unlimited.
    pub fn begin_cycle(&mut self, evaluations: u32) {
        self.budget = evaluations;
        self.budget_base = self.problem.evaluations();
    }

    /// Evaluations left in the current cycle's budget (`u32::MAX` when unlimited).
    pub fn budget_left(&self) -> u32 {
        if self.budget == u32::MAX {
            return u32::MAX;
        }
        let spent = self.problem.evaluations().wrapping_sub(self.budget_base);
        self.budget.saturating_sub(spent)
    }

    /// Parameters.
    pub fn params(&self) -> &ModalParams {
        &self.params
    }

    /// Replace the parameters.
    pub fn set_params(&mut self, p: ModalParams) {
        self.params = p;
    }

    /// The root finders' view (parameters read, problem evaluated, the cycle's budget), and
    /// beside it the first root's state and the tracker (disjoint borrows).
    fn parts(&mut self) -> (RootFinder<'_, &mut P>, &mut FirstRootState, &mut EeTracker) {
        let finder = RootFinder {
            params: &self.params,
            view: &mut self.problem,
            budget_base: self.budget_base,
            budget: self.budget,
        };
        (finder, &mut self.first, &mut self.tracker)
    }

    /// NotLoaded before a pose is loaded.
    fn require_loaded(&self) -> Result<(), ModalError> {
        if self.problem.is_loaded() {
            Ok(())
        } else {
            Err(ModalError::NotLoaded)
        }
    }

    /// D(λ), D'(λ) and the blocked count of the loaded pose (one evaluation).
    #[inline]
    pub fn eval(&mut self, lambda: f64) -> DynEval {
        self.problem.eval(lambda)
    }

    /// Number of natural frequencies strictly below λ (Wittrick-Williams; one evaluation).
    pub fn count_below(&mut self, lambda: f64) -> u32 {
        self.problem.count(lambda).0
    }

    /// Evaluations of D(λ) since the solver was built (a counter for statistics).
    pub fn evaluations(&self) -> u32 {
        self.problem.evaluations()
    }

    /// 3 (point mass) or 6 (rigid body).
    pub fn dim(&self) -> usize {
        self.problem.dim()
    }

    /// Number of natural frequencies of the loaded model (large, `usize::MAX` or the
    /// sagged continuous model's bound, for continuous chains).
    pub fn total_modes(&self) -> usize {
        self.problem.total_modes()
    }

    /// The loaded end-effector's mass matrix diag(m I, I_world) (kg, kg·m²; the rotational
    /// block is zero for a point mass) and its constant stiffness besides the chains (a
    /// rigid body's rotational geometric stiffness, N·m/rad, and the swivel pulleys' term):
    /// what a dense assembly of the same pose needs besides the cables.
    pub fn ee_matrices(&self) -> (Matrix6<f64>, Matrix6<f64>) {
        (*self.problem.ee_mass(), *self.problem.ee_stiffness())
    }

    /// The static end-effector stiffness D(0) of the loaded pose (its leading 3 × 3 or
    /// 6 × 6 block), N/m (N·m/rad in the rotational block), from the chains' static end
    /// stiffnesses (no evaluation of D(λ) counted).
    pub fn static_stiffness(&self) -> Result<Matrix6<f64>, ModalError> {
        self.require_loaded()?;
        Ok(self.problem.static_eval().d)
    }

    /// Σ_k p_k/λ_k over all modes, s²/rad²: tr(M_ee D(0)⁻¹), from the last
    /// [`Self::first_root`] (NaN before it or when D(0) is not positive definite).
    pub fn participation_over_lambda(&self) -> f64 {
        self.first.flex0
    }

    /// The first natural frequency's λ (rad²/s²), Newton started from `warm` (a predicted
    /// λ, accepted once a step is below [`ModalParams::newton_accept`] with a rate that
    /// leaves an error below [`ModalParams::rel_tol`]) or from the Rayleigh guess (None:
    /// cold), certified by the count on cold starts and every 256th warm one. Within the
    /// cycle's budget ([`Self::begin_cycle`]) and [`ModalParams::max_evaluations`]: a root
    /// that does not fit is `NoConvergence` (with its bracket), never a longer cycle, and
    /// the search is continued by the next call (from where it stopped on the same loaded
    /// problem, from its last iterate on another) until a root is found or
    /// `max_evaluations` are spent on it over the calls.
    pub fn first_root(&mut self, warm: Option<f64>) -> Result<Root, ModalError> {
        self.require_loaded()?;
        let (mut f, first, _) = self.parts();
        let r = f.first_root(first, warm);
        self.last_lambda1 = r.as_ref().map_or(f64::NAN, |r| r.lambda);
        r
    }

    /// The first natural frequency, warm-started from the last one found (cold when none).
    pub fn first_root_warm(&mut self) -> Result<Root, ModalError> {
        let warm = self.last_lambda1;
        self.first_root(warm.is_finite().then_some(warm))
    }

    /// The first natural frequency from the Rayleigh guess (ignores the last root).
    pub fn first_root_cold(&mut self) -> Result<Root, ModalError> {
        self.first_root(None)
    }

    /// Forget a first-root search the cycle's budget cut (the next call starts afresh).
    pub fn forget_pending(&mut self) {
        self.first.pending = None;
    }

    /// The relative residual of λ (rad²/s²) as a natural frequency of the loaded model:
    /// min_i |μ_i(D(λ))| / (|λ|·max_jk |D'(λ)_jk|) (see [`Root::residual`]); one evaluation.
    pub fn residual_at(&mut self, lambda: f64) -> f64 {
        let e = self.eval(lambda);
        let eg = e.eig();
        let mu = eg.values[..eg.n]
            .iter()
            .fold(f64::INFINITY, |m, v| m.min(v.abs()));
        relative_residual(mu, lambda, &e.dd)
    }

    /// The lowest mode whose end-effector participation is at least
    /// [`ModalParams::ee_participation_min`], by a scan from zero (over the pole intervals
    /// where the poles are known, an ascending sweep of the spectrum where the count alone
    /// shows them). `first` is the already-known first root (not solved again). Offline:
    /// not bounded by the cycle's budget (the scan's own bounds hold).
    pub fn ee_mode(&mut self, first: &Root) -> Result<Root, ModalError> {
        self.require_loaded()?;
        let flex0 = self.first.flex0;
        let sums = self.problem.sum_rules(flex0, true);
        self.problem.follow_poles(Some(u32::MAX));
        let (mut f, _, tracker) = self.parts();
        f.budget = u32::MAX;
        let r = tracker.ee_mode(&mut f, sums, first);
        self.problem.follow_poles(None);
        r
    }

    /// The end-effector mode, tracked from the last cycle when `warm`, within what is left
    /// of the cycle's budget: the watched modes followed by Newton on their branch of D and
    /// the answer certified by the participation sum rules, scans spread over the cycles
    /// (the method: `modal`'s docs, "The end-effector mode"). Ok(None) while the work goes
    /// on over the cycles (`first`: this cycle's first root). An answer below the
    /// threshold (no mode reaches it within the scan's bounds) is the most
    /// end-effector-like mode found. No allocation.
    pub fn ee_mode_tracked(
        &mut self,
        first: &Root,
        warm: bool,
    ) -> Result<Option<Root>, ModalError> {
        self.require_loaded()?;
        let thr = self.params.ee_participation_min;
        let evaluate = first.ee_participation < thr && self.budget_left() > 0;
        let flex0 = self.first.flex0;
        let sums = self.problem.sum_rules(flex0, evaluate);
        self.problem.follow_poles(Some(self.budget_left()));
        let (mut f, _, tracker) = self.parts();
        let r = tracker.ee_mode_tracked(&mut f, sums, first, warm);
        self.problem.follow_poles(None);
        r
    }

    /// Forget the tracked end-effector mode (the next [`Self::ee_mode_tracked`] scans).
    pub fn reset_tracking(&mut self) {
        self.tracker.reset();
    }

    /// A scan for the end-effector mode is in progress over the cycles.
    pub fn ee_scanning(&self) -> bool {
        self.tracker.scanning()
    }

    /// Counters of the end-effector bookkeeping: full scans by reason, watched modes lost
    /// and dropped, neighbour and partner searches.
    pub fn rescan_counts(&self) -> RescanCounts {
        self.tracker.counts()
    }

    /// The first `k` natural frequencies of the loaded problem (ascending) into `out`, with
    /// [`SpectrumParams::default`]. Returns how many were written: min(k, out.len(), the
    /// number of modes the model has).
    pub fn modes(&mut self, k: usize, out: &mut [Mode]) -> Result<usize, ModalError> {
        self.modes_with(k, &SpectrumParams::default(), out)
    }

    /// [`Self::modes`] with explicit parameters (`pole_probe` is the relative width at
    /// which a bisection across a pole stops and reports the mode at the pole).
    pub fn modes_with(
        &mut self,
        k: usize,
        params: &SpectrumParams,
        out: &mut [Mode],
    ) -> Result<usize, ModalError> {
        self.require_loaded()?;
        modes_into(&mut self.problem, k, params, out)
    }

    /// The lowest eigenvalues of the loaded model as clusters (λ in rad²/s², multiplicity),
    /// ascending, until at least `k` modes are covered (at most every mode of the model):
    /// bisection on the count J(λ) to a relative width of 4ε, modes within
    /// [`ShapeParams::cluster_rel`] of each other grouped. The count is exact at and next to
    /// the chains' poles, where modes with the end-effector still sit; the shapes' input
    /// when no other eigenvalue source is at hand. About 55 count evaluations per cluster.
    pub fn eigen_clusters(
        &mut self,
        k: usize,
        params: &ShapeParams,
    ) -> Result<Vec<(f64, u32)>, ShapeError> {
        self.require_loaded()?;
        let k = k.min(self.total_modes());
        clusters_by_count(|x| self.problem.count(x).0, k, params)
    }

    /// The loaded problem's dynamic stiffness D(λ) at a complex λ, N/m (N·m/rad in the
    /// rotational block): the chains' recurrences at complex λ (O(N) per discrete chain; a
    /// point mass fills the leading 3 × 3 block). None before a load and for the sagged
    /// continuous chains (no complex form). Not counted as an evaluation.
    pub fn dynamic_stiffness_at(&self, lambda: Complex64) -> Option<Matrix6<Complex64>> {
        self.problem.d_complex(lambda)
    }

    /// The receptance H(ω) of the loaded problem at ω (rad/s) with loss-factor, Rayleigh or
    /// no damping (exact, `frf`'s docs): m/N, the leading `dim` × `dim` block. Modal
    /// damping: [`FrfError::NeedsModes`] (it goes by a modal basis).
    pub fn receptance(
        &mut self,
        damping: &Damping,
        omega_rad_s: f64,
    ) -> Result<Matrix6<Complex64>, FrfError> {
        receptance(&mut self.problem, damping, omega_rad_s)
    }
}
