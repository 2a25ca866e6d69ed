//! The first natural frequency: the root of μ₁(D(λ)) below the lowest pole by safeguarded
//! Newton, and its Wittrick-Williams certificate, written once over the condensed problem
//! ([`Condensed`]) for taut and sagged chains.
//!
//! Where the chains' poles are known in closed form (taut) the bracket's upper end is the
//! lowest pole and Newton runs on μ₁(λ)(λ_p − λ) with the pole removed. Where only the
//! count shows them (sagged) the bracket starts open above and an iterate with a pole
//! below it (blocked count > 0) is an upper bound: the step from there is a bisection (or
//! a doubling while no upper end is known), and a bracket that collapses onto a pole (a
//! mode with the end-effector still) is reported there with participation 0.
//!
//! A [`RootFinder`] bundles what one search reads (the [`ModalParams`]) and the problem's
//! view (evaluations written), with the cycle's budget. The first root's own state between
//! cycles is [`FirstRootState`]: the certificate's schedule, the weighted sum rule, and a
//! search the cycle's budget cut ([`Pending`]), continued by the next call.

use super::engine::{
    pole_free, quad, Condensed, DynEval, EigD, BRACKET_GROWTH, BRACKET_MIN, COLLAPSE_ULPS,
};
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

/// What the root finders work on: the parameters (read only) and the problem's view (its
/// evaluations counted), with the cycle's budget.
pub(super) struct RootFinder<'a, P: Condensed> {
    pub(super) params: &'a ModalParams,
    pub(super) view: P,
    /// The cycle's budget: evaluations allowed from the counter value `budget_base`
    /// (`u32::MAX`: unlimited). Every loop that evaluates D(λ) checks [`Self::left`] first.
    pub(super) budget_base: u32,
    pub(super) budget: u32,
}

/// A root search in progress: its bracket [lo, hi] (hi = ∞: no upper end known yet), the
/// next iterate, and the evaluations spent on it over all the calls it ran in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Bracket {
    pub(super) lo: f64,
    pub(super) hi: f64,
    pub(super) x: f64,
    pub(super) spent: u32,
}

/// A first-root search the cycle's budget cut, with the loaded problem it belongs to: D(0)
/// and D'(0) of the uncounted static evaluation, bit for bit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Pending {
    search: Bracket,
    /// Started from a predicted λ (the warm acceptance rule).
    fast: bool,
    d0: Matrix6<f64>,
    dd0: Matrix6<f64>,
}

/// State of the first-root solver between calls.
#[derive(Debug, Clone)]
pub(super) struct FirstRootState {
    /// First roots solved (schedules the periodic count certificate).
    pub(super) roots: u64,
    /// tr(M_ee D(0)⁻¹) = Σ_k p_k/λ_k (s²/rad², the weighted sum rule), from `first_root`.
    pub(super) flex0: f64,
    /// A search the last call's budget cut (continued by the next call).
    pub(super) pending: Option<Pending>,
}

impl FirstRootState {
    /// Nothing solved yet.
    pub(super) fn new() -> FirstRootState {
        FirstRootState {
            roots: 0,
            flex0: f64::NAN,
            pending: None,
        }
    }
}

impl<P: Condensed> RootFinder<'_, P> {
    /// D(λ), D'(λ) and the blocked count (one evaluation).
    #[inline]
    pub(super) fn eval(&mut self, lambda: f64) -> DynEval {
        self.view.eval(lambda)
    }

    /// Evaluations so far (a counter; differences give a search's cost).
    #[inline]
    pub(super) fn evaluations(&self) -> u32 {
        self.view.evaluations()
    }

    /// Evaluations left in the cycle's budget (`u32::MAX` when unlimited).
    #[inline]
    pub(super) fn left(&self) -> u32 {
        if self.budget == u32::MAX {
            return u32::MAX;
        }
        let spent = self.evaluations().wrapping_sub(self.budget_base);
        self.budget.saturating_sub(spent)
    }

    /// The cycle's budget is spent.
    #[inline]
    pub(super) fn exhausted(&self) -> bool {
        self.left() == 0
    }

    /// The end-effector participation of the mode with null vector v, D' = `dd`.
    #[inline]
    pub(super) fn participation(&self, dd: &Matrix6<f64>, v: &Vector6<f64>) -> f64 {
        self.view.participation(dd, v)
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
        lo: f64,
        hi: f64,
        pole_lo: f64,
        pole_hi: f64,
        guess: f64,
        fast: bool,
    ) -> Result<Root, ModalError> {
        let mut s = Bracket::from_guess(lo, hi, guess);
        self.branch_root_in(branch, &mut s, pole_lo, pole_hi, fast, None)
    }

    /// [`Self::branch_root_with`] (`fast`) between two poles a count showed
    /// (`pole_lo` = 0 or `pole_hi` = ∞: that pole is not removed from Newton's function;
    /// the bracket is never a count-only first interval), which also accepts a weak root
    /// early: `weak` = (s, p_max), see [`weak_root`].
    pub(super) fn branch_root_between(
        &mut self,
        branch: usize,
        (lo, hi): (f64, f64),
        (pole_lo, pole_hi): (f64, f64),
        guess: f64,
        weak: (f64, f64),
    ) -> Result<Root, ModalError> {
        let mut s = Bracket::from_guess(lo, hi, guess);
        self.branch_root_in(branch, &mut s, pole_lo, pole_hi, true, Some(weak))
    }

    /// [`Self::branch_root_with`] on the search `s`, left where it stopped (bracket and
    /// next iterate) when the budget or [`ModalParams::max_evaluations`] (counted over all
    /// the calls on `s`) ends it. Where the problem's poles are seen only through the count
    /// (`pole_lo` then 0 and `pole_hi` ∞), an iterate with a pole below it is an upper bound of the root
    /// (the first pole interval's branches only), and a bracket collapsed onto such a pole
    /// is a mode there with the end-effector still (participation 0).
    pub(super) fn branch_root_in(
        &mut self,
        branch: usize,
        s: &mut Bracket,
        pole_lo: f64,
        pole_hi: f64,
        fast: bool,
        weak: Option<(f64, f64)>,
    ) -> Result<Root, ModalError> {
        let start = self.evaluations();
        let (lo0, hi0) = (s.lo, s.hi);
        // A bracket between two found poles (a scan over searched poles, its interval
        // checked pole-free by the count) is no first pole interval.
        // `weak`: the bracket lies between two poles a count showed.
        let count_only =
            weak.is_none() && !self.view.poles_known() && pole_lo == 0.0 && !pole_hi.is_finite();
        let tol = self.params.rel_tol;
        // The one probe next to a bounding pole has been spent.
        let mut probed = false;
        loop {
            let (lo, hi, x) = (s.lo, s.hi, s.x);
            if s.spent >= self.params.max_evaluations || self.exhausted() {
                return Err(ModalError::NoConvergence {
                    evaluations: self.evaluations() - start,
                    lo,
                    hi,
                });
            }
            s.spent += 1;
            let e = self.eval(x);
            if count_only && e.below > 0 {
                // A pole below x: the root is below it.
                s.hi = hi.min(x);
                if s.hi - lo <= tol * s.hi {
                    // Collapsed onto the pole (the count steps there, μ does not cross
                    // zero): a mode with the end-effector still.
                    return Ok(Root {
                        lambda: s.hi,
                        ee_participation: 0.0,
                        evaluations: self.evaluations() - start,
                        residual: 0.0,
                    });
                }
                s.x = 0.5 * (lo + s.hi);
                continue;
            }
            let eg = e.eig();
            let mu = eg.values[branch];
            let v = eg.vectors[branch];
            let dmu = quad(&e.dd, &v, e.dim);
            if mu > 0.0 {
                s.lo = lo.max(x);
            } else if mu < 0.0 {
                s.hi = hi.min(x);
            }
            let (lo, hi) = (s.lo, s.hi);
            // Newton on μ(λ)(λ − pole_lo)(pole_hi − λ): the poles bounding the interval
            // removed (pole_lo = 0 and pole_hi = ∞ add nothing).
            let (g, dg) = pole_free(mu, dmu, x, pole_lo, pole_hi);
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
            if let (false, Some((ws, p_max))) = (done, weak) {
                let inside = xn > lo && xn < hi;
                if inside && weak_root(&e, &eg, branch, (x, xn), (lo0, hi0), ws) {
                    let p = self.participation(&e.dd, &v);
                    if p <= p_max {
                        return Ok(Root {
                            lambda: xn,
                            ee_participation: p,
                            evaluations: self.evaluations() - start,
                            residual: relative_residual(mu, x, &e.dd),
                        });
                    }
                }
            }
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
                    BRACKET_GROWTH * x
                };
            }
            s.x = xn;
        }
    }

    /// The first natural frequency's λ (rad²/s²), warm-started from `warm` when given;
    /// records the weighted sum rule and the root count in `state`.
    ///
    /// A search the cycle's budget cut is kept in `state.pending`. On the same problem
    /// (D(0) and D'(0) bit for bit: a static pose) the next call continues it where it
    /// stopped, bracket and all; on another problem (the pose moved) its iterate is the
    /// starting guess when there is no `warm` prediction (it is closer than the Rayleigh
    /// guess of a nearby pose). [`ModalParams::max_evaluations`] bounds a search over all
    /// the calls it runs in.
    pub(super) fn first_root(
        &mut self,
        state: &mut FirstRootState,
        warm: Option<f64>,
    ) -> Result<Root, ModalError> {
        let start = self.evaluations();
        let carried = state.pending.take();
        // D(0) without evaluating the chains on warm starts (each chain's static end
        // stiffness); the full evaluation, with D'(0), for the cold start's Rayleigh guess.
        let e0 = if warm.is_some() || carried.is_some() {
            self.view.static_eval()
        } else {
            self.view.zero_eval()
        };
        let eg0 = e0.eig();
        if !(eg0.values[0] > 0.0) {
            state.flex0 = f64::NAN;
            return Err(ModalError::NotPositiveDefinite(eg0.values[0]));
        }
        // Weighted sum rule: Σ_k p_k/λ_k = tr(M_ee D(0)⁻¹).
        let (m6, dim) = (self.view.ee_mass(), self.view.dim());
        state.flex0 = (0..dim)
            .map(|j| {
                let v = eg0.vectors[j];
                quad(m6, &v, dim) / eg0.values[j]
            })
            .sum();
        // The lowest pole (∞: none; None: seen only through the count).
        let lowest = self.view.lowest_pole();
        let lp = lowest.unwrap_or(f64::INFINITY);
        let same = carried.filter(|c| c.d0 == e0.d && c.dd0 == e0.dd);
        let (mut s, fast) = if let Some(c) = same {
            (c.search, c.fast)
        } else {
            let guess = match (warm, carried) {
                (Some(w), _) if w > 0.0 && w < lp => w,
                (None, Some(c)) if c.search.x > 0.0 && c.search.x < lp => c.search.x,
                _ => {
                    // Rayleigh estimate from λ = 0: μ(0)/(−μ'(0)).
                    let v = eg0.vectors[0];
                    let dmu = -quad(&e0.dd, &v, e0.dim);
                    let g = eg0.values[0] / dmu.max(f64::MIN_POSITIVE);
                    if lp.is_finite() {
                        g.min(RAYLEIGH_CAP * lp)
                    } else if lowest.is_none() {
                        g.max(BRACKET_MIN)
                    } else {
                        g
                    }
                }
            };
            let hi = if lp.is_finite() || lowest.is_none() {
                lp
            } else {
                self.upper_bracket(guess, start)?
            };
            (Bracket::from_guess(0.0, hi, guess), warm.is_some())
        };
        let r = self.branch_root_in(0, &mut s, 0.0, lp, fast, None);
        if let Err(ModalError::NoConvergence { .. }) = r {
            if self.exhausted() && s.spent < self.params.max_evaluations {
                state.pending = Some(self.pending(s, fast));
            }
        }
        let mut r = r?;
        let hi = s.hi;
        state.roots += 1;
        if self.params.certify && (!fast || state.roots.is_multiple_of(CERTIFY_EVERY)) {
            if self.left() < 2 {
                // The certificate's two counts do not fit in the cycle's budget: the next
                // call goes on from this root (a restart would be cut here again).
                s.x = r.lambda;
                state.pending = Some(self.pending(s, fast));
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

    /// Search `s` kept for the next call, with the loaded problem it belongs to.
    fn pending(&self, s: Bracket, fast: bool) -> Pending {
        let st = self.view.static_eval();
        Pending {
            search: s,
            fast,
            d0: st.d,
            dd0: st.dd,
        }
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

impl Bracket {
    /// A search of [lo, hi] from `guess` (the middle when the guess is outside; twice lo,
    /// at least 1, when hi is ∞).
    pub(super) fn from_guess(lo: f64, hi: f64, guess: f64) -> Bracket {
        let x = if guess > lo && guess < hi {
            guess
        } else if hi.is_finite() {
            0.5 * (lo + hi)
        } else {
            2.0 * lo.max(1.0)
        };
        Bracket {
            lo,
            hi,
            x,
            spent: 0,
        }
    }
}

/// Whether the Newton update `xn` from the iterate `x` (evaluated: `e`, its eigen-pairs
/// `eg`) of branch k in the interval (lo0, hi0) may be taken as that branch's root without
/// another evaluation (a weak root, [`RootFinder::branch_root_between`]): the step, of the
/// pole-free function and of μ_k itself, is below `ws` (relative), far from the interval's
/// ends (≤ a tenth of the way to either: D' changes little over it), and no other
/// eigenvalue of D can meet μ_k within the step (their gap exceeds twice the change their
/// slopes allow: the sorted branch k stays the same eigenvalue to its root).
fn weak_root(
    e: &DynEval,
    eg: &EigD,
    k: usize,
    (x, xn): (f64, f64),
    (lo0, hi0): (f64, f64),
    ws: f64,
) -> bool {
    let step = (xn - x).abs();
    let mu = eg.values[k];
    let dmu = quad(&e.dd, &eg.vectors[k], e.dim);
    let raw = (mu / dmu).abs();
    if !(step <= ws * x.abs() && raw <= ws * x.abs()) {
        return false;
    }
    if !(step <= 0.1 * (x - lo0) && step <= 0.1 * (hi0 - x)) {
        return false;
    }
    let reach = step.max(raw);
    (0..eg.n).filter(|&j| j != k).all(|j| {
        let dj = quad(&e.dd, &eg.vectors[j], e.dim);
        (eg.values[j] - mu).abs() > 2.0 * (dj.abs() + dmu.abs()) * reach
    })
}
