//! [`ModalSolver`]: the structured real-time solver, composed of the loaded problem
//! ([`LoadedChains`]), the evaluation scratch ([`EvalScratch`]), the first root's state
//! ([`FirstRootState`]) and the end-effector tracker ([`EeTracker`]).

use super::dynamic_stiffness::{DynEval, EvalScratch, LoadedChains};
use super::ee_tracker::{EeTracker, RescanCounts, SumRules};
use super::engine::TautView;
use super::first_mode::{FirstRootState, RootFinder, TautFinder};
use super::{ModalError, ModalParams, Root};
use crate::cable::CableModel;
use nalgebra::{Matrix3, Matrix6, Vector3};

/// The structured real-time eigen solver. `new` sizes everything; `load` copies the
/// chains of one pose; the root finders never allocate and are bounded.
#[derive(Debug, Clone)]
pub struct ModalSolver {
    params: ModalParams,
    /// What `load` computes; read-only on the hot path.
    pub(in crate::modal) problem: LoadedChains,
    /// What one evaluation of D(λ) writes.
    pub(in crate::modal) scratch: EvalScratch,
    /// The first root's state between cycles (certificate schedule, weighted sum rule).
    first: FirstRootState,
    /// The end-effector mode tracker's state between cycles.
    tracker: EeTracker,
    /// The cycle's evaluation budget (`u32::MAX`: unlimited) and the evaluation counter
    /// when it began ([`Self::begin_cycle`]).
    budget: u32,
    budget_base: u32,
}

impl ModalSolver {
    /// A solver with the given parameters.
    pub fn new(params: ModalParams) -> ModalSolver {
        ModalSolver {
            params,
            problem: LoadedChains::new(),
            scratch: EvalScratch::new(),
            first: FirstRootState::new(),
            tracker: EeTracker::new(),
            budget: u32::MAX,
            budget_base: 0,
        }
    }

    /// Start a cycle with a budget of `evaluations` evaluations of D(λ) (`u32::MAX`:
    /// unlimited): [`Self::first_root`] and [`Self::ee_mode_tracked`] stop there, whatever
    /// is left of the end-effector work is continued in the next cycle. Until the first
    /// call the solver is unlimited.
    pub fn begin_cycle(&mut self, evaluations: u32) {
        self.budget = evaluations;
        self.budget_base = self.scratch.evaluations;
    }

    /// Evaluations left in the current cycle's budget (`u32::MAX` when unlimited).
    pub fn budget_left(&self) -> u32 {
        if self.budget == u32::MAX {
            return u32::MAX;
        }
        let spent = self.scratch.evaluations.wrapping_sub(self.budget_base);
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

    /// The root finders' view (parameters and problem read, scratch written), and beside
    /// it the first root's state and the tracker (disjoint borrows).
    fn parts(&mut self) -> (TautFinder<'_>, &mut FirstRootState, &mut EeTracker) {
        let finder = RootFinder {
            params: &self.params,
            view: TautView {
                p: &self.problem,
                s: &mut self.scratch,
            },
            budget_base: self.budget_base,
            budget: self.budget,
        };
        (finder, &mut self.first, &mut self.tracker)
    }

    /// The sum rules of the loaded pose as known now (the weighted one from the last
    /// [`Self::first_root`]).
    fn sums(&self) -> SumRules {
        SumRules::traces(self.problem.p_total, self.first.flex0)
    }

    /// Load the chains of the cable models at one pose and the end-effector mass (kg).
    /// Chains that contribute nothing (zero spring and zero mass: a switched-off effect)
    /// are not loaded, so they cost nothing per evaluation.
    pub fn load(&mut self, models: &[CableModel], ee_mass_kg: f64) {
        self.problem.load(models, ee_mass_kg, None);
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
            .load(models, ee_mass_kg, Some((inertia_kg_m2, arms_m, k_geo_rot)));
    }

    /// Add a constant stiffness at the end-effector's DOFs (the leading 3 × 3 or 6 × 6
    /// block of `k`: N/m, N/rad, N·m/rad) to the loaded pose, until the next load: the
    /// swivel pulleys' own term ([`crate::kinematics::Geometry::pulley_stiffness`]), which
    /// holds at every λ since the pulleys' geometry carries no mass.
    pub fn add_ee_stiffness(&mut self, k: &Matrix6<f64>) {
        self.problem.add_ee_stiffness(k);
    }

    /// D(λ), D'(λ) and the blocked count.
    #[inline]
    pub fn eval(&mut self, lambda: f64) -> DynEval {
        self.scratch.eval(&self.problem, lambda)
    }

    /// Number of natural frequencies strictly below λ (Wittrick-Williams).
    pub fn count_below(&mut self, lambda: f64) -> u32 {
        self.parts().0.count_below(lambda)
    }

    /// Static end-effector stiffness D(0), translational block, N/m.
    pub fn static_stiffness(&mut self) -> Matrix3<f64> {
        self.eval(0.0).d.fixed_view::<3, 3>(0, 0).into_owned()
    }

    /// Static end-effector stiffness D(0) (6 × 6 for a rigid body; top-left 3 × 3 else).
    pub fn static_stiffness6(&mut self) -> Matrix6<f64> {
        self.eval(0.0).d
    }

    /// The sum of the end-effector participation over all modes of the loaded model,
    /// tr(M_ee M_∞⁻¹) with M_∞ = lim −D(λ)/λ as λ → −∞ (the end-effector's mass plus the
    /// chains' end masses): the modes are complete, so Σ_k p_k = Σ_k φ_kᵀ M_ee φ_k equals it.
    /// `dim` for continuous or massless cables, slightly less for discrete ones.
    pub fn participation_total(&self) -> f64 {
        self.problem.p_total
    }

    /// Σ_k p_k/λ_k over all modes, s²/rad²: tr(M_ee D(0)⁻¹), from the last
    /// [`Self::first_root`] (NaN before it or when D(0) is not positive definite).
    pub fn participation_over_lambda(&self) -> f64 {
        self.first.flex0
    }

    /// 3 (point mass) or 6 (rigid body).
    pub fn dim(&self) -> usize {
        self.problem.dim
    }

    /// The lowest blocked eigenvalue over all chains, rad²/s² (∞ when none).
    pub fn lowest_pole(&self) -> f64 {
        self.problem.lowest_pole()
    }

    /// The pole-free interval (a, b) of D around λ: the nearest blocked eigenvalues of all
    /// chains below and above (0 and ∞ when there are none), rad²/s².
    pub fn pole_interval(&self, lambda: f64) -> (f64, f64) {
        self.problem.pole_interval(lambda)
    }

    /// The first natural frequency's λ (rad²/s²), warm-started from `warm` when given.
    pub fn first_root(&mut self, warm: Option<f64>) -> Result<Root, ModalError> {
        let (mut f, first, _) = self.parts();
        f.first_root(first, warm)
    }

    /// The lowest mode whose end-effector participation is at least
    /// [`ModalParams::ee_participation_min`]: scans the intervals between the chains'
    /// blocked eigenvalues in ascending order and solves for each root of D in them.
    /// `first` is the already-known first root (not solved again).
    /// Not bounded by the cycle's budget (an offline call; the scan's own bounds hold).
    pub fn ee_mode(&mut self, first: &Root) -> Result<Root, ModalError> {
        let sums = self.sums();
        let (mut f, _, tracker) = self.parts();
        f.budget = u32::MAX;
        tracker.ee_mode(&mut f, sums, first)
    }

    /// Static end-effector stiffness D(0) in closed form (each chain's static end stiffness;
    /// no evaluation of D(λ) counted): 6 × 6 for a rigid body, the top-left 3 × 3 else.
    pub fn static_stiffness6_closed(&self) -> Matrix6<f64> {
        self.problem.static_eval().d
    }

    /// A scan for the end-effector mode is in progress over the cycles.
    pub fn ee_scanning(&self) -> bool {
        self.tracker.scanning()
    }

    /// The relative residual of λ (rad²/s²) as a natural frequency of the loaded model:
    /// min_i |μ_i(D(λ))| / (|λ|·max_jk |D'(λ)_jk|) (see [`Root::residual`]); one evaluation.
    pub fn residual_at(&mut self, lambda: f64) -> f64 {
        let e = self.eval(lambda);
        let eg = e.eig();
        let mu = eg.values[..eg.n]
            .iter()
            .fold(f64::INFINITY, |m, v| m.min(v.abs()));
        super::first_mode::relative_residual(mu, lambda, &e.dd)
    }

    /// Forget the tracked end-effector mode (the next [`Self::ee_mode_tracked`] scans).
    pub fn reset_tracking(&mut self) {
        self.tracker.reset();
    }

    /// The end-effector mode, tracked from the last cycle when `warm`.
    ///
    /// **Certificate.** The modes are complete, so the end-effector participation summed
    /// over all of them is [`Self::participation_total`] (sum rule), and weighted by 1/λ it
    /// is tr(M_ee D(0)⁻¹) (the static flexibility, known from the first root). If a set W of
    /// distinct modes with known participation is *watched*, every other mode holds at most
    /// Σ_all p − Σ_W p, and every other mode below λ_A at most λ_A (tr(M_ee D(0)⁻¹) −
    /// Σ_W p_k/λ_k). When the smaller bound is below the threshold, the lowest watched mode
    /// that reaches the threshold is the end-effector mode: no unwatched mode can be.
    /// These are the traces of matrix sum rules (Σ φ_k φ_kᵀ = M_∞⁻¹, Σ φ_k φ_kᵀ/λ_k =
    /// D(0)⁻¹, φ_k the end-effector part of the mass-normalised mode): the sagged solver
    /// also bounds one mode by the largest eigenvalue of the residual matrices, which counts
    /// only the most-loaded end-effector direction (`ee_tracker::bound`); here the traces
    /// alone certify.
    ///
    /// **Tracking.** A scan from cold watches every mode it meets with participation ≥ 0.05
    /// and goes on past the answer until the bound is below 0.15. A warm cycle follows the
    /// watched modes from their predictions (quadratic through the last three cycles) by
    /// Newton's method on their branch of D with both bounding poles removed, until a step is
    /// below 1e-5 (relative); the answer, and a mode within 0.02 of the threshold, to full
    /// accuracy (a tracking step below 1e-7 already is). Modes with participation ≥ 0.15 are
    /// followed every cycle, weaker ones one per cycle (the one followed longest ago): a
    /// mode not followed this cycle does not count in the bound, and when the bound does not
    /// certify, all are followed before anything is rescanned. Each mode's index in the
    /// spectrum (the blocked count of its pole interval plus its branch) keeps the watched
    /// modes distinct and carries its history.
    ///
    /// **Avoided crossings.** Along a trajectory the string modes of the cables pass through
    /// the end-effector modes and the participation moves between modes. Each strong watched
    /// mode (≥ 0.15) reads, from its own last evaluation, the chain that holds the largest
    /// share σ of its kinetic-energy norm vᵀ(−D')v; with σ ≥ 0.03 it is mixing with that
    /// chain's string mode, and a two-level model (the mode and the string mode across the
    /// chain's nearest pole P) places the partner at λ − (λ − P)/(1 − σ), holding about σ.
    /// The partner is found by Newton from there and watched before the participation moves
    /// (at most one such search per cycle, and once per pole until σ doubles). When the bound
    /// still exceeds 0.4, a spectral neighbour (index ± 1) of the watched mode whose
    /// participation changed most is searched across up to 4 pole intervals. Modes below 0.02
    /// are dropped. When the bound plus an allowance of 0.05 for the participations read
    /// within 1e-5 of the root is not below the threshold, or no watched mode reaches it, the
    /// band from 10 % below the lowest watched mode is scanned again, and everything from zero
    /// if that does not certify.
    ///
    /// The heuristics (what to watch, where to search) only decide the cost: the answer
    /// returned by a warm cycle is always certified by the bound.
    ///
    /// **Budget.** Everything stops at the cycle's evaluation budget ([`Self::begin_cycle`]);
    /// Ok(None) says the end-effector work did not fit and is continued in the next cycle: a
    /// scan resumes from the pole interval where it stopped (on the next cycle's problem:
    /// it only discovers the modes to watch), and an answer found over several cycles is
    /// certified by a warm cycle at the pose of the cycle that reports it. An answer below
    /// the threshold (no mode reaches it within the scan's bounds) is the most
    /// end-effector-like mode found.
    pub fn ee_mode_tracked(
        &mut self,
        first: &Root,
        warm: bool,
    ) -> Result<Option<Root>, ModalError> {
        let sums = self.sums();
        let (mut f, _, tracker) = self.parts();
        tracker.ee_mode_tracked(&mut f, sums, first, warm)
    }

    /// Counters of the end-effector bookkeeping: full scans by reason, watched modes lost
    /// and dropped, neighbour and partner searches.
    pub fn rescan_counts(&self) -> RescanCounts {
        self.tracker.counts()
    }

    /// Evaluations of D(λ) since the solver was built (a counter for statistics).
    pub fn evaluations(&self) -> u32 {
        self.scratch.evaluations
    }
}
