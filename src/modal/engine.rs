//! The condensed problem D(λ) behind one trait, and the numerical constants its searches
//! share.
//!
//! Both structured solvers reduce the free vibration problem to the end-effector's dynamic
//! stiffness D(λ) (3 × 3 or 6 × 6), its derivative D'(λ) = −(a mass matrix) and the blocked
//! count of the chains (Wittrick–Williams). The taut chains ([`TautView`]: uniform chains,
//! their blocked eigenvalues known in closed form) and the sagged ones (`sagged::problem::SagView`:
//! non-uniform chains, their poles only seen through the count) implement [`Condensed`];
//! the first root (`first_mode`), the end-effector tracker (`ee_tracker`) and the spectrum
//! search (`spectrum`) are written once over it and monomorphised for each (no dynamic
//! dispatch, no allocation).

use super::dynamic_stiffness::{quad, DynEval, EvalScratch, LoadedChains};
use nalgebra::{Matrix6, Vector6};

/// The first upper bracket of a search starts here when no better scale is known,
/// rad²/s² (and a cold first root's Rayleigh guess is at least this).
///
/// Why: the Rayleigh scale μ₁(0)/(−μ₁'(0)) is the natural start, but when D'(0) vanishes
/// (massless chains, a degenerate end-effector) it is 0 or infinite; a bracket must start
/// at a positive λ, and 1e-12 rad²/s² (≈ 1.6e-7 Hz) is below any frequency a robot has,
/// so growth ([`BRACKET_GROWTH`]) reaches the first mode from below without skipping it.
pub(in crate::modal) const BRACKET_MIN: f64 = 1e-12;

/// An upper bracket grows by this factor per count probe (and a sagged first-root iterate
/// with no upper bound yet doubles).
///
/// Why: doubling keeps the bracket within a factor 2 of the mode (bisection then needs
/// ~52 halvings at worst to reach ε, Newton far fewer), while reaching any finite λ from
/// [`BRACKET_MIN`] in at most ~1100 probes; a larger factor saves probes only on a cold
/// start, at the cost of wider brackets every time.
pub(in crate::modal) const BRACKET_GROWTH: f64 = 2.0;

/// A bracket counts as collapsed when it is narrower than this many ε relative to λ.
///
/// Why: below a few ulps the bracket's ends are consecutive (or nearly) floating-point
/// numbers; μ's sign there is rounding, so no further evaluation can narrow it. Four ulps
/// leaves room for the rounding of (lo + hi)/2 and of the relative comparison itself.
pub(in crate::modal) const COLLAPSE_ULPS: f64 = 4.0;

/// A Newton step below this (relative) that also shows superlinear convergence (below
/// [`SUPERLINEAR_RATIO`] times the previous step; for a warm sagged first root, at any
/// rate) is accepted.
///
/// Why: the eigenvalue μ of D(λ) carries rounding noise of ~1e-13..1e-12 of λ on stiff,
/// heavy robots, so Newton steps of that size do not shrink: a stopping rule of 1e-14
/// alone would bounce until the evaluation budget ran out. A step of 1e-10 after a much
/// larger one means quadratic convergence: the next iterate is within ~(1e-10)² of the
/// root, far below the target.
pub(in crate::modal) const NOISE_STEP: f64 = 1e-10;

/// See [`NOISE_STEP`]: a step at most this fraction of the previous one shows
/// superlinear convergence.
///
/// Why: a linearly converging iteration (a multiple root, a bad start) shrinks its step
/// by a roughly constant factor, rarely below 1/10; quadratic convergence shrinks it by
/// orders of magnitude per step. 1e-2 separates the two with room on both sides.
pub(in crate::modal) const SUPERLINEAR_RATIO: f64 = 1e-2;

/// The condensed problem of one loaded pose: what the searches need of D(λ).
///
/// Every evaluation is counted ([`Self::evaluations`]), so the callers can hold a search
/// to a budget; none allocates.
pub(in crate::modal) trait Condensed {
    /// D(λ), D'(λ) and the blocked count (one evaluation).
    fn eval(&mut self, lambda: f64) -> DynEval;
    /// An evaluation for the count only: D' may be left out (one evaluation).
    fn count_eval(&mut self, lambda: f64) -> DynEval;
    /// D(0) and D'(0) to start a search (the taut problem evaluates them, the sagged one
    /// reads its cached static evaluation).
    fn zero_eval(&mut self) -> DynEval;
    /// Evaluations so far (a wrapping counter; differences give a search's cost).
    fn evaluations(&self) -> u32;
    /// 3 (point mass) or 6 (rigid body).
    fn dim(&self) -> usize;
    /// The end-effector's mass matrix diag(m I, I), kg and kg·m² (rotational block zero
    /// for a point mass).
    fn ee_mass(&self) -> &Matrix6<f64>;
    /// Number of natural frequencies of the loaded pose (large for continuous chains).
    fn total_modes(&self) -> usize;
    /// The pole-free interval (a, b) of D around λ (0 and ∞ when there is no pole below or
    /// above), when the chains' blocked eigenvalues are known in closed form; None when
    /// only the count shows them (the searches then bisect on the blocked count).
    fn pole_interval(&self, lambda: f64) -> Option<(f64, f64)>;
    /// Whether [`Self::pole_interval`] knows the poles (else the count alone shows them).
    fn poles_known(&self) -> bool;
    /// The lowest pole of D, rad²/s² (∞: none), when the poles are known.
    fn lowest_pole(&self) -> Option<f64>;
    /// D(0) without a counted evaluation: from the chains' static end stiffness (D'(0) is
    /// left zero where that needs an evaluation of the chains).
    fn static_eval(&self) -> DynEval;

    /// The pole-free interval around the λ of the last evaluation (the chains' blocked
    /// counts there), when the poles are known.
    fn last_pole_interval(&self) -> Option<(f64, f64)>;
    /// The taut problem itself, for what walks its closed-form poles (the end-effector
    /// tracker's pole-interval scan and neighbour search); None for the others.
    fn taut(&mut self) -> Option<TautView<'_>>;
    /// The chain holding the largest share of the kinetic-energy norm of mode shape v at
    /// the last evaluation (at x, D' = `dd`): (share, its pole nearest x, whether above,
    /// the pole's key); (0, NaN, false, `u32::MAX`) where the poles are not known.
    fn coupling(&self, x: f64, dd: &Matrix6<f64>, v: &Vector6<f64>) -> (f64, f64, bool, u32) {
        let _ = (x, dd, v);
        (0.0, f64::NAN, false, u32::MAX)
    }

    /// The end-effector participation of the mode with unit null vector v at a root where
    /// D' = `dd`: the end-effector's share vᵀ M_ee v / vᵀ(−D')v of the mode's kinetic-energy
    /// norm (0 when that norm is not positive).
    #[inline]
    fn participation(&self, dd: &Matrix6<f64>, v: &Vector6<f64>) -> f64 {
        let dim = self.dim();
        let kin = -quad(dd, v, dim);
        let own = quad(self.ee_mass(), v, dim);
        if kin > 0.0 {
            (own / kin).min(1.0)
        } else {
            0.0
        }
    }

    /// Number of natural frequencies strictly below λ (Wittrick–Williams), with the
    /// blocked count: (J(λ), blocked).
    #[inline]
    fn count(&mut self, lambda: f64) -> (u32, u32) {
        let e = self.count_eval(lambda);
        (e.below + e.eig().negatives() as u32, e.below)
    }
}

/// The [`Condensed`] methods read from the loaded problem `self.p` (its `dim`, `m6` and
/// `total_modes()`), the same for the taut and the sagged view.
macro_rules! ee_from_problem {
    () => {
        #[inline]
        fn dim(&self) -> usize {
            self.p.dim
        }
        #[inline]
        fn ee_mass(&self) -> &nalgebra::Matrix6<f64> {
            &self.p.m6
        }
        #[inline]
        fn total_modes(&self) -> usize {
            self.p.total_modes()
        }
    };
}
pub(in crate::modal) use ee_from_problem;

/// The taut problem: the loaded chains (read) and the evaluation scratch (written).
pub(in crate::modal) struct TautView<'a> {
    pub(in crate::modal) p: &'a LoadedChains,
    pub(in crate::modal) s: &'a mut EvalScratch,
}

impl Condensed for TautView<'_> {
    #[inline]
    fn eval(&mut self, lambda: f64) -> DynEval {
        self.s.eval(self.p, lambda)
    }
    #[inline]
    fn count_eval(&mut self, lambda: f64) -> DynEval {
        self.s.eval(self.p, lambda)
    }
    #[inline]
    fn zero_eval(&mut self) -> DynEval {
        self.s.eval(self.p, 0.0)
    }
    #[inline]
    fn evaluations(&self) -> u32 {
        self.s.evaluations
    }
    ee_from_problem!();
    #[inline]
    fn pole_interval(&self, lambda: f64) -> Option<(f64, f64)> {
        Some(self.p.pole_interval(lambda))
    }
    #[inline]
    fn poles_known(&self) -> bool {
        true
    }
    #[inline]
    fn lowest_pole(&self) -> Option<f64> {
        Some(self.p.lowest_pole())
    }
    #[inline]
    fn static_eval(&self) -> DynEval {
        self.p.static_eval()
    }
    #[inline]
    fn last_pole_interval(&self) -> Option<(f64, f64)> {
        Some(self.s.last_pole_interval(self.p))
    }
    #[inline]
    fn taut(&mut self) -> Option<TautView<'_>> {
        Some(TautView {
            p: self.p,
            s: &mut *self.s,
        })
    }
    #[inline]
    fn coupling(&self, x: f64, dd: &Matrix6<f64>, v: &Vector6<f64>) -> (f64, f64, bool, u32) {
        self.s.coupling(self.p, x, dd, v)
    }
}

/// A borrowed problem is the problem (a search may run on a view it does not own).
impl<C: Condensed> Condensed for &mut C {
    #[inline]
    fn eval(&mut self, lambda: f64) -> DynEval {
        (**self).eval(lambda)
    }
    #[inline]
    fn count_eval(&mut self, lambda: f64) -> DynEval {
        (**self).count_eval(lambda)
    }
    #[inline]
    fn zero_eval(&mut self) -> DynEval {
        (**self).zero_eval()
    }
    #[inline]
    fn evaluations(&self) -> u32 {
        (**self).evaluations()
    }
    #[inline]
    fn dim(&self) -> usize {
        (**self).dim()
    }
    #[inline]
    fn ee_mass(&self) -> &Matrix6<f64> {
        (**self).ee_mass()
    }
    #[inline]
    fn total_modes(&self) -> usize {
        (**self).total_modes()
    }
    #[inline]
    fn pole_interval(&self, lambda: f64) -> Option<(f64, f64)> {
        (**self).pole_interval(lambda)
    }
    #[inline]
    fn poles_known(&self) -> bool {
        (**self).poles_known()
    }
    #[inline]
    fn lowest_pole(&self) -> Option<f64> {
        (**self).lowest_pole()
    }
    #[inline]
    fn static_eval(&self) -> DynEval {
        (**self).static_eval()
    }
    #[inline]
    fn last_pole_interval(&self) -> Option<(f64, f64)> {
        (**self).last_pole_interval()
    }
    #[inline]
    fn taut(&mut self) -> Option<TautView<'_>> {
        (**self).taut()
    }
    #[inline]
    fn coupling(&self, x: f64, dd: &Matrix6<f64>, v: &Vector6<f64>) -> (f64, f64, bool, u32) {
        (**self).coupling(x, dd, v)
    }
}
