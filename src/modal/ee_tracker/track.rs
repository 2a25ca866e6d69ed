//! The tracker's Newton searches: follow a root from a prediction ([`track_root`]), find a
//! watched mode's spectral neighbour ([`neighbour`]) or its avoided-crossing partner
//! ([`partner`]).

use super::member::{Member, Tracked};
use super::scan::inset;
use super::{CHEAP_ACCEPT, NEIGHBOUR_INTERVALS, P_PARTNER, P_STRONG};
use crate::modal::engine::{pole_free, quad, Condensed, DynEval, EigD};
use crate::modal::first_mode::{relative_residual, RootFinder};
use crate::modal::Root;

/// Newton steps (evaluations) a followed root may take, at most.
const TRACK_MAX_EVALUATIONS: u32 = 12;
/// A partner search starts at least this far (relative) across the pole.
const ACROSS_POLE: f64 = 1e-9;

/// The branch of D(λ) closest to vanishing: the smallest |μ_i| / |μ_i'|.
fn nearest_branch(e: &DynEval, eg: &EigD) -> usize {
    let mut branch = 0;
    let mut best = f64::INFINITY;
    for i in 0..eg.n {
        let v = eg.vectors[i];
        let d = -quad(&e.dd, &v, e.dim);
        let dist = eg.values[i].abs() / d.max(f64::MIN_POSITIVE);
        if dist < best {
            best = dist;
            branch = i;
        }
    }
    branch
}

/// The spectral neighbour of watched mode `m`: the mode of index m.index + 1 (`up`) or
/// m.index − 1 (or the first beyond the modes sitting exactly at a pole, which have no
/// participation), searched across at most [`NEIGHBOUR_INTERVALS`] pole intervals; None when
/// it is not found there. In a pole interval (a, b) with blocked count B the roots are
/// those of branches j with D's j-th eigenvalue positive at a⁺ and negative at b⁻, in
/// order, and the root of branch j has index B + j. It walks the pole intervals: None
/// where the poles are not known.
pub(super) fn neighbour<P: Condensed>(
    f: &mut RootFinder<'_, P>,
    m: &Member,
    up: bool,
) -> Option<Tracked> {
    let mut target = if up {
        m.index + 1
    } else {
        m.index.checked_sub(1)?
    };
    let (mut a, mut b) = (m.a, m.b);
    let mut below = m.index.checked_sub(m.branch as u32)?;
    // The end of the interval where the target's branch is known to have the right sign
    // (≥ 0 below the root when going up, ≤ 0 above it when going down).
    let mut known = m.lambda;
    for _ in 0..NEIGHBOUR_INTERVALS {
        if target >= below && ((target - below) as usize) < f.view.dim() {
            let j = (target - below) as usize;
            // The other end: b⁻ (∞ when there is no pole above: D → −λ M_∞ there) or
            // a⁺ (0 when a = 0: D(0) is positive definite).
            let other = if up {
                b.is_finite().then(|| b - inset(b - a, b))
            } else {
                (a > 0.0).then(|| a + inset(b - a, a))
            };
            let holds = match other {
                None => true,
                Some(x) => {
                    if f.exhausted() {
                        return None;
                    }
                    let v = f.eval(x).eig().values[j];
                    if up {
                        v < 0.0
                    } else {
                        v > 0.0
                    }
                }
            };
            if holds {
                let (lo, hi) = if up {
                    (known, other.unwrap_or(f64::INFINITY))
                } else {
                    (other.unwrap_or(0.0), known)
                };
                let guess = if hi.is_finite() {
                    0.5 * (lo + hi)
                } else {
                    2.0 * lo.max(1.0)
                };
                let r = f.branch_root_with(j, lo, hi, a, b, guess, true).ok()?;
                return Some(Tracked {
                    root: r,
                    branch: j,
                    index: target,
                    a,
                    b,
                    share: 0.0,
                    pole: f64::NAN,
                    pole_up: false,
                    pole_key: u32::MAX,
                    step: 0.0,
                    phi: None,
                });
            }
        }
        // Not in this interval: the next one in the search direction.
        let x = if up {
            if !b.is_finite() {
                return None;
            }
            b + inset(b - a, b)
        } else {
            if a == 0.0 {
                return None;
            }
            a - inset(b - a, a)
        };
        if f.exhausted() {
            return None;
        }
        let e = f.eval(x);
        (a, b) = f.view.last_pole_interval()?;
        if !(x > a && x < b) {
            return None;
        }
        below = e.below;
        let count = below + e.eig().negatives() as u32;
        // Modes between x and the pole just crossed sit at that pole (several chains
        // blocked at one λ: the end-effector is still in them, participation 0): the
        // neighbour is the next mode beyond them.
        if up && count > target {
            target = count;
        } else if !up && count <= target {
            target = count.checked_sub(1)?;
        }
        known = x;
    }
    None
}

/// The partner of a watched mode in an avoided crossing: the mode across `pole`
/// (rad²/s²; above it when `up`) nearest `pred` (the two-level model's estimate), by
/// [`track_root`] from `pred` (or from just across the pole when `pred` is on the
/// wrong side). Whatever mode it converges to is a root with its index counted afresh.
pub(super) fn partner<P: Condensed>(
    f: &mut RootFinder<'_, P>,
    pole: f64,
    up: bool,
    pred: f64,
) -> Option<Tracked> {
    let x = if up {
        pred.max(pole * (1.0 + ACROSS_POLE))
    } else {
        pred.min(pole * (1.0 - ACROSS_POLE))
    };
    track_root(f, x, CHEAP_ACCEPT)
}

/// Newton from `l0` on the branch of D closest to vanishing there, kept inside the pole
/// interval of l0; None when it leaves it or does not converge in the bound. The next
/// iterate is accepted once a step is below `accept` (relative; the iterate is then
/// within ~step² of the root). Returns the root, its branch, its pole interval, its index
/// in the spectrum (the interval's blocked count plus the branch) and, for a mode with
/// participation ≥ [`P_STRONG`], the chain it shares most energy with.
pub(super) fn track_root<P: Condensed>(
    f: &mut RootFinder<'_, P>,
    l0: f64,
    accept: f64,
) -> Option<Tracked> {
    if f.exhausted() {
        return None;
    }
    let mut x = l0;
    let mut e = f.eval(x);
    // Where the poles are seen only through the count, the interval is (0, ∞) for Newton
    // and the blocked count tells when an iterate left it.
    let (mut a, mut b) = f.view.last_pole_interval().unwrap_or((0.0, f64::INFINITY));
    let below = e.below;
    if !(x > a && x < b) {
        return None;
    }
    let mut eg = e.eig();
    let mut branch = nearest_branch(&e, &eg);
    let mut hopped = false;
    let mut it = 0;
    while it < f.params.max_evaluations.min(TRACK_MAX_EVALUATIONS) {
        let v = eg.vectors[branch];
        let mu = eg.values[branch];
        let dmu = quad(&e.dd, &v, e.dim);
        // Newton on μ(λ)(λ − a)(b − λ): both poles removed (a = 0 and b = ∞ add nothing).
        let (g, dg) = pole_free(mu, dmu, x, a, b);
        if !(dg < 0.0) {
            return None;
        }
        let xn = x - g / dg;
        if !(xn > a && xn < b) {
            // A weakly coupled pole passed through the mode since the last cycle: follow
            // it into the neighbouring interval, once, from the mirror point.
            if hopped {
                return None;
            }
            hopped = true;
            x = if xn >= b { b + (b - x) } else { a - (x - a) };
            if !(x > 0.0) || f.exhausted() {
                return None;
            }
            e = f.eval(x);
            (a, b) = f.view.last_pole_interval().unwrap_or((0.0, f64::INFINITY));
            if !(x > a && x < b) {
                return None;
            }
            eg = e.eig();
            branch = nearest_branch(&e, &eg);
            it += 1;
            continue;
        }
        if mu == 0.0 || (xn - x).abs() <= accept.max(f.params.rel_tol) * x {
            let p = f.participation(&e.dd, &v);
            // φ = v/√(vᵀ(−D')v): the end-effector part of the mass-normalised shape.
            let kin = -quad(&e.dd, &v, e.dim);
            let phi = (kin > 0.0).then(|| v / kin.sqrt());
            let (share, pole, pole_up, pole_key) = if p >= P_STRONG {
                f.view.coupling(x, &e.dd, &v, P_PARTNER)
            } else {
                (0.0, f64::NAN, false, u32::MAX)
            };
            return Some(Tracked {
                root: Root {
                    lambda: xn,
                    ee_participation: p,
                    evaluations: 0,
                    residual: relative_residual(mu, x, &e.dd),
                },
                branch,
                index: e.below + branch as u32,
                a,
                b,
                share,
                pole,
                pole_up,
                pole_key,
                step: (xn - x).abs() / x,
                phi,
            });
        }
        if f.exhausted() {
            return None;
        }
        x = xn;
        e = f.eval(x);
        if e.below != below && !f.view.poles_known() {
            // A pole crossed: the mode is not in the interval it was followed in.
            return None;
        }
        eg = e.eig();
        it += 1;
    }
    None
}
