//! The first natural frequency: the root of μ₁(D(λ)) below the lowest pole by safeguarded
//! Newton, and its Wittrick-Williams certificate.
//!
//! One evaluation of D(λ) reads only the [`LoadedChains`] and writes only the
//! [`EvalScratch`]; a [`RootFinder`] bundles exactly these (and the [`ModalParams`], read
//! only). The first root's own state between cycles is [`FirstRootState`].

use super::dynamic_stiffness::{quad, DynEval, EvalScratch, LoadedChains};
use super::engine::{BRACKET_MIN, COLLAPSE_ULPS};
use super::{ModalError, ModalParams, Root};
use nalgebra::{Matrix6, Vector6};

/// The count certificate runs on every cold start and on every this-many-th warm one.
const CERTIFY_EVERY: u64 = 256;
/// The certificate probes the count this far (relative) below and above the root: well
/// outside Newton's error, well inside the gap to any neighbouring mode.
const CERT_PROBE: f64 = 1e-10;
/// The cold start's Rayleigh guess is kept below this fraction of the lowest pole (the
/// Newton function vanishes at the pole).
const RAYLEIGH_CAP: f64 = 0.999;
/// Without poles (massless cables) the upper bracket starts at twice the guess (at least
/// [`BRACKET_MIN`]) and grows by this factor per probe (D is linear in λ there, so no mode
/// can be skipped, and 4 reaches the root in half the probes of 2) ...
const UPPER_BRACKET_GROWTH: f64 = 4.0;
/// ... at most this many times (4²⁰⁰ covers any finite λ).
const BRACKET_STEPS: usize = 200;

/// The relative residual of an eigenvalue μ of D(λ) at λ (D'(λ) = `dd`):
/// |μ| / (|λ|·max_ij |D'_ij|), the eigenvalue against the size of the inertia term λ·D'
/// that cancels the stiffness at a root (‖D‖ itself vanishes there when the root is
/// multiple). To first order it is the relative distance |λ − λ*|/λ to the root λ* of that
/// branch; 0 exactly at a root.
#[inline]
pub(super) fn relative_residual(mu: f64, lambda: f64, dd: &Matrix6<f64>) -> f64 {
    mu.abs() / (lambda.abs() * dd.abs().max()).max(f64::MIN_POSITIVE)
}

/// What the root finders work on: the parameters and the loaded problem (read only) and
/// the evaluation scratch (the only thing an evaluation of D(λ) writes).
pub(super) struct RootFinder<'a> {
    pub(super) params: &'a ModalParams,
    pub(super) problem: &'a LoadedChains,
    pub(super) scratch: &'a mut EvalScratch,
    /// The cycle's budget: evaluations allowed from the counter value `budget_base`
    /// (`u32::MAX`: unlimited). Every loop that evaluates D(λ) checks [`Self::left`] first.
    pub(super) budget_base: u32,
    pub(super) budget: u32,
}

/// State of the first-root solver between calls.
#[derive(Debug, Clone)]
pub(super) struct FirstRootState {
    /// First roots solved (schedules the periodic count certificate).
    pub(super) roots: u64,
    /// tr(M_ee D(0)⁻¹) = Σ_k p_k/λ_k (s²/rad², the weighted sum rule), from `first_root`.
    pub(super) flex0: f64,
}

impl FirstRootState {
    /// Nothing solved yet.
    pub(super) fn new() -> FirstRootState {
        FirstRootState {
            roots: 0,
            flex0: f64::NAN,
        }
    }
}

impl RootFinder<'_> {
    /// D(λ), D'(λ) and the blocked count (one evaluation).
    #[inline]
    pub(super) fn eval(&mut self, lambda: f64) -> DynEval {
        self.scratch.eval(self.problem, lambda)
    }

    /// Evaluations so far (a counter; differences give a search's cost).
    #[inline]
    pub(super) fn evaluations(&self) -> u32 {
        self.scratch.evaluations
    }

    /// Evaluations left in the cycle's budget (`u32::MAX` when unlimited).
    #[inline]
    pub(super) fn left(&self) -> u32 {
        if self.budget == u32::MAX {
            return u32::MAX;
        }
        let spent = self.scratch.evaluations.wrapping_sub(self.budget_base);
        self.budget.saturating_sub(spent)
    }

    /// The cycle's budget is spent.
    #[inline]
    pub(super) fn exhausted(&self) -> bool {
        self.left() == 0
    }

    /// The pole-free interval (a, b) around the λ of the last evaluation.
    #[inline]
    pub(super) fn last_pole_interval(&self) -> (f64, f64) {
        self.scratch.last_pole_interval(self.problem)
    }

    /// The end-effector participation of the mode with null vector v, D' = `dd`.
    #[inline]
    pub(super) fn participation(&self, dd: &Matrix6<f64>, v: &Vector6<f64>) -> f64 {
        self.problem.participation(dd, v)
    }

    /// Number of natural frequencies strictly below λ (Wittrick-Williams).
    pub(super) fn count_below(&mut self, lambda: f64) -> u32 {
        let e = self.eval(lambda);
        e.below + e.eig().negatives() as u32
    }

    /// Root of the `branch`-th smallest eigenvalue of D on (lo, hi), where it is positive at
    /// lo and negative at hi. `pole_lo` (≤ lo, may be 0) and `pole_hi` (≥ hi, may be ∞) are
    /// the poles bounding the interval; Newton runs on μ(λ)(λ − pole_lo)(pole_hi − λ) to
    /// remove them. `guess` starts the iteration. `fast` accepts an iterate once a Newton
    /// step is below [`ModalParams::newton_accept`] (warm starts), else only below `rel_tol`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn branch_root_with(
        &mut self,
        branch: usize,
        mut lo: f64,
        mut hi: f64,
        pole_lo: f64,
        pole_hi: f64,
        guess: f64,
        fast: bool,
    ) -> Result<Root, ModalError> {
        let start = self.evaluations();
        let mut x = if guess > lo && guess < hi {
            guess
        } else if hi.is_finite() {
            0.5 * (lo + hi)
        } else {
            2.0 * lo.max(1.0)
        };
        let tol = self.params.rel_tol;
        // The one probe next to a bounding pole has been spent.
        let mut probed = false;
        loop {
            if self.evaluations() - start >= self.params.max_evaluations || self.exhausted() {
                return Err(ModalError::NoConvergence {
                    evaluations: self.evaluations() - start,
                    lo,
                    hi,
                });
            }
            let e = self.eval(x);
            let eg = e.eig();
            let mu = eg.values[branch];
            let v = eg.vectors[branch];
            let dmu = quad(&e.dd, &v, e.dim);
            if mu > 0.0 {
                lo = lo.max(x);
            } else if mu < 0.0 {
                hi = hi.min(x);
            }
            // Newton on μ(λ)(λ − pole_lo)(pole_hi − λ): the poles bounding the interval
            // removed (pole_lo = 0 and pole_hi = ∞ add nothing).
            let (mut g, mut dg) = (mu, dmu);
            if pole_hi.is_finite() {
                let w = pole_hi - x;
                (g, dg) = (g * w, dg * w - g);
            }
            if pole_lo > 0.0 {
                let w = x - pole_lo;
                (g, dg) = (g * w, dg * w + g);
            }
            // D' overflows within rounding of a pole (its entries grow as 1/(pole − λ)²): no
            // Newton step from a non-finite slope.
            let mut xn = if dg < 0.0 && dg.is_finite() {
                x - g / dg
            } else {
                f64::NAN
            };
            let collapsed = hi.is_finite() && (hi - lo) <= COLLAPSE_ULPS * f64::EPSILON * x.abs();
            let step = (xn - x).abs();
            let accept = if fast && self.evaluations() - start > 1 {
                self.params.newton_accept
            } else {
                tol
            };
            let done =
                mu == 0.0 || collapsed || (xn.is_finite() && step <= accept.max(tol) * x.abs());
            if done {
                let lambda = if mu == 0.0 || !(xn > lo && xn < hi) && collapsed {
                    x
                } else {
                    xn
                };
                return Ok(Root {
                    lambda,
                    ee_participation: self.participation(&e.dd, &v),
                    evaluations: self.evaluations() - start,
                    residual: relative_residual(mu, x, &e.dd),
                });
            }
            if !(xn > lo && xn < hi) {
                xn = if !probed && hi == pole_hi && !(xn < hi) {
                    // Newton puts the root at or past the pole above, or has no step (D'
                    // overflowed next to it): the root may be closer to the pole than the
                    // bracket resolves (a cable nearly slack: its string mode, the
                    // end-effector still, a hair below the pole). Probe inside the collapse
                    // width below the pole: μ > 0 there collapses the bracket, μ < 0 moves
                    // its upper end (Newton then runs inside it).
                    probed = true;
                    hi * (1.0 - 0.5 * COLLAPSE_ULPS * f64::EPSILON)
                } else if !probed && lo == pole_lo && lo > 0.0 && !(xn > lo) {
                    // The same a hair above the pole below.
                    probed = true;
                    lo * (1.0 + 0.5 * COLLAPSE_ULPS * f64::EPSILON)
                } else if hi.is_finite() {
                    0.5 * (lo + hi)
                } else {
                    2.0 * x
                };
            }
            x = xn;
        }
    }

    /// The first natural frequency's λ (rad²/s²), warm-started from `warm` when given;
    /// records the weighted sum rule and the root count in `state`.
    pub(super) fn first_root(
        &mut self,
        state: &mut FirstRootState,
        warm: Option<f64>,
    ) -> Result<Root, ModalError> {
        let start = self.evaluations();
        // D(0) in closed form on warm starts (each chain's static end stiffness); the full
        // evaluation, with D'(0), only for the cold start's Rayleigh guess.
        let e0 = if warm.is_some() {
            self.problem.static_eval()
        } else {
            self.eval(0.0)
        };
        let eg0 = e0.eig();
        if !(eg0.values[0] > 0.0) {
            state.flex0 = f64::NAN;
            return Err(ModalError::NotPositiveDefinite(eg0.values[0]));
        }
        // Weighted sum rule: Σ_k p_k/λ_k = tr(M_ee D(0)⁻¹).
        let (m6, dim) = (&self.problem.m6, self.problem.dim);
        state.flex0 = (0..dim)
            .map(|j| {
                let v = eg0.vectors[j];
                quad(m6, &v, dim) / eg0.values[j]
            })
            .sum();
        let lp = self.problem.lowest_pole();
        let guess = match warm {
            Some(w) if w > 0.0 && w < lp => w,
            _ => {
                // Rayleigh estimate from λ = 0: μ(0)/(−μ'(0)).
                let v = eg0.vectors[0];
                let dmu = -quad(&e0.dd, &v, e0.dim);
                let g = eg0.values[0] / dmu.max(f64::MIN_POSITIVE);
                if lp.is_finite() {
                    g.min(RAYLEIGH_CAP * lp)
                } else {
                    g
                }
            }
        };
        let hi = if lp.is_finite() {
            lp
        } else {
            self.upper_bracket(guess, start)?
        };
        let fast = warm.is_some();
        let mut r = self.branch_root_with(0, 0.0, hi, 0.0, lp, guess, fast)?;
        state.roots += 1;
        if self.params.certify && (!fast || state.roots.is_multiple_of(CERTIFY_EVERY)) {
            if self.left() < 2 {
                // The certificate's two counts do not fit in the cycle's budget.
                return Err(ModalError::NoConvergence {
                    evaluations: self.evaluations() - start,
                    lo: 0.0,
                    hi,
                });
            }
            let mut certified = self.certify_first(r.lambda);
            if !certified && fast {
                // A relaxed warm answer may sit outside the certificate's ±1e-10 probe in
                // an ill-conditioned case: solve strictly before reporting anything.
                r = self.branch_root_with(0, 0.0, hi, 0.0, lp, r.lambda, false)?;
                certified = self.certify_first(r.lambda);
            }
            if !certified {
                return Err(ModalError::CountMismatch(r.lambda));
            }
        }
        r.evaluations = self.evaluations() - start;
        Ok(r)
    }

    /// No poles: D = K − λ M_d is linear, μ₁ crosses zero; find an upper bracket above
    /// `guess` (`start`: the evaluation count at the start of the solve, for the error).
    fn upper_bracket(&mut self, guess: f64, start: u32) -> Result<f64, ModalError> {
        let mut h = guess.max(BRACKET_MIN) * 2.0;
        for _ in 0..BRACKET_STEPS {
            if self.exhausted() {
                break;
            }
            let e = self.eval(h);
            if e.eig().values[0] < 0.0 {
                return Ok(h);
            }
            h *= UPPER_BRACKET_GROWTH;
        }
        Err(ModalError::NoConvergence {
            evaluations: self.evaluations() - start,
            lo: 0.0,
            hi: h,
        })
    }

    /// The Wittrick-Williams certificate of a first root: no eigenvalue below λ(1 − 1e-10),
    /// at least one below λ(1 + 1e-10).
    fn certify_first(&mut self, lambda: f64) -> bool {
        self.count_below(lambda * (1.0 - CERT_PROBE)) == 0
            && self.count_below(lambda * (1.0 + CERT_PROBE)) > 0
    }
}
