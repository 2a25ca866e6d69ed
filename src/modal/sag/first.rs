//! The first root of the sagged problem: safeguarded Newton on μ₁(D(λ)) inside a bracket
//! kept by the sign of μ₁ and the blocked count (see the module docs).

use super::problem::SagProblem;
use crate::modal::dynamic_stiffness::quad;
use crate::modal::engine::{BRACKET_GROWTH, BRACKET_MIN, NOISE_STEP};
use crate::modal::first_mode::relative_residual;
use crate::modal::{ModalError, ModalParams, Root};
use nalgebra::Matrix6;

// Without a pole above, the bracket's upper end is unknown: a step that leaves the
// bracket multiplies the iterate by BRACKET_GROWTH instead of bisecting. The cold start's
// Rayleigh guess is at least BRACKET_MIN (a scale when D' vanishes). A warm Newton step at
// or below NOISE_STEP (relative) is accepted whatever the previous one: steps of rounding
// noise do not shrink, and Newton's quadratic rate leaves ~K·step² ≪ 1e-12
// (K = |μ₁''/2μ₁'|·λ, large only within ~1e-8 of a pole).

/// A warm Newton iterate (after the first evaluation) is accepted without one more
/// evaluation once its step is below [`ModalParams::newton_accept`] (relative) and either
/// the error it leaves, estimated as step²/(previous step) (the worst case of a merely
/// linear rate; the quadratic rate leaves far less), is below [`ModalParams::rel_tol`], or
/// the step is at the noise floor ([`NOISE_STEP`]).
#[inline]
fn fast_accept(step: f64, last_step: f64, x: f64, params: &ModalParams) -> bool {
    last_step.is_finite()
        && step <= params.newton_accept * x
        && (step * step <= params.rel_tol * x * last_step || step <= NOISE_STEP * x)
}

/// A first-root search in progress: the iterate, the bracket and Newton's history. Kept
/// between cycles when a cycle's budget cuts the search ([`Pending`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Search {
    /// The next iterate, rad²/s².
    x: f64,
    /// The bracket [lo, hi] of the first root, rad²/s² (hi = ∞: no upper end known yet).
    lo: f64,
    hi: f64,
    /// The previous Newton step (NaN: none yet, so the first step is never fast-accepted).
    last_step: f64,
    /// Newton's next iterate from the upper end of the bracket when μ₁ < 0 there (NaN:
    /// none): where Newton from below overshoots (μ₁ concave), the step from above does not.
    from_hi: f64,
    /// Started from a predicted λ (warm acceptance rule).
    fast: bool,
    /// Evaluations spent on this search over all the cycles it ran in.
    spent: u32,
}

impl Search {
    /// A search from `x` with no bracket yet (`fast`: the warm acceptance rule).
    fn from(x: f64, fast: bool) -> Search {
        Search {
            x,
            lo: 0.0,
            hi: f64::INFINITY,
            last_step: f64::NAN,
            from_hi: f64::NAN,
            fast,
            spent: 0,
        }
    }
}

/// A search the cycle's budget cut, with the loaded problem it belongs to: D(0) and D'(0)
/// of the static evaluation, bit for bit (the chains' static end stiffness and mass, the
/// end-effector's mass and geometric stiffness).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Pending {
    search: Search,
    d0: Matrix6<f64>,
    dd0: Matrix6<f64>,
}

/// The first natural frequency's λ of `p`, from `warm` (a predicted λ, e.g. the last
/// root) or from the Rayleigh guess. `evals` counts the evaluations of D; at most
/// `cycle_evaluations` are spent in this call and `max_evaluations` over the search.
///
/// `pending` carries a search the previous call's cycle budget cut. On the same problem
/// (D(0) and D'(0) bit for bit: a static pose) it is continued where it stopped, bracket
/// and all; on another problem (the pose moved) its iterate is the starting guess when
/// there is no `warm` prediction (it is closer than the Rayleigh guess of a nearby pose).
/// When this call's budget cuts the search again it is left in `pending` (the error is
/// `NoConvergence`); when the search ends (a root, or `max_evaluations` spent over the
/// cycles) `pending` is cleared.
pub(super) fn first_root(
    p: &SagProblem,
    params: &ModalParams,
    evals: &mut u32,
    warm: Option<f64>,
    pending: &mut Option<Pending>,
) -> Result<Root, ModalError> {
    let e0 = p.static_eval();
    let eg0 = e0.eig();
    let carried = pending.take();
    if !(eg0.values[0] > 0.0) {
        return Err(ModalError::NotPositiveDefinite(eg0.values[0]));
    }
    let mut s = match (carried, warm) {
        (Some(c), _) if c.d0 == e0.d && c.dd0 == e0.dd => c.search,
        (_, Some(w)) if w > 0.0 && w.is_finite() => Search::from(w, true),
        (Some(c), _) => Search::from(c.search.x, false),
        _ => {
            let kin = -quad(&e0.dd, &eg0.vectors[0], e0.dim);
            Search::from(
                (eg0.values[0] / kin.max(f64::MIN_POSITIVE)).max(BRACKET_MIN),
                false,
            )
        }
    };
    let r = search(p, params, evals, &mut s);
    if let Err(ModalError::NoConvergence { .. }) = r {
        if s.spent < params.max_evaluations {
            *pending = Some(Pending {
                search: s,
                d0: e0.d,
                dd0: e0.dd,
            });
        }
    }
    r
}

/// Continue search `s` for at most `cycle_evaluations` evaluations (and `max_evaluations`
/// over the whole search).
fn search(
    p: &SagProblem,
    params: &ModalParams,
    evals: &mut u32,
    s: &mut Search,
) -> Result<Root, ModalError> {
    let start = *evals;
    loop {
        let used = evals.wrapping_sub(start);
        if used >= params.cycle_evaluations || s.spent >= params.max_evaluations {
            return Err(ModalError::NoConvergence {
                evaluations: used,
                lo: s.lo,
                hi: s.hi,
            });
        }
        *evals = evals.wrapping_add(1);
        s.spent += 1;
        let x = s.x;
        let e = p.eval(x);
        let eg = e.eig();
        let (mu, v) = (eg.values[0], eg.vectors[0]);
        let dmu = quad(&e.dd, &v, e.dim);
        let mut next = f64::NAN;
        if e.below > 0 {
            // A pole below x: the first root is below it.
            if x < s.hi {
                s.hi = x;
                s.from_hi = f64::NAN;
            }
        } else {
            if mu > 0.0 {
                s.lo = s.lo.max(x);
            } else if x < s.hi {
                s.hi = x;
                s.from_hi = if dmu < 0.0 { x - mu / dmu } else { f64::NAN };
            }
            if mu == 0.0 {
                return Ok(root(p, x, x, mu, &e, &v, *evals - start));
            }
            if dmu < 0.0 {
                next = x - mu / dmu;
                let step = (next - x).abs();
                let accept = step <= params.rel_tol * x
                    || s.fast && fast_accept(step, s.last_step, x, params);
                // Inclusive: a step that rounds to 0 at the bracket's end is a root there.
                if accept && next >= s.lo && next <= s.hi {
                    return Ok(root(p, next, x, mu, &e, &v, *evals - start));
                }
                s.last_step = step;
            }
        }
        let (lo, hi) = (s.lo, s.hi);
        if hi.is_finite() && hi - lo <= params.rel_tol * hi {
            // Collapsed onto a pole (the count steps there, μ₁ does not cross zero): a
            // mode with the end-effector still.
            return Ok(Root {
                lambda: hi,
                ee_participation: 0.0,
                evaluations: *evals - start,
                residual: 0.0,
            });
        }
        if !(next > lo && next < hi) && s.from_hi > lo && s.from_hi < hi {
            next = s.from_hi;
        }
        if !(next > lo && next < hi) {
            next = if hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                BRACKET_GROWTH * x
            };
        }
        s.x = next;
    }
}

/// The root at λ, from the evaluation at its last iterate x (μ₁ there, D', unit vector v).
fn root(
    p: &SagProblem,
    lambda: f64,
    x: f64,
    mu: f64,
    e: &crate::modal::DynEval,
    v: &nalgebra::Vector6<f64>,
    evaluations: u32,
) -> Root {
    let kin = -quad(&e.dd, v, e.dim);
    let own = quad(&p.m6, v, e.dim);
    Root {
        lambda,
        ee_participation: if kin > 0.0 { (own / kin).min(1.0) } else { 0.0 },
        evaluations,
        residual: relative_residual(mu, x, &e.dd),
    }
}
