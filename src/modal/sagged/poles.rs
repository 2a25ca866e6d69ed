//! The sagged chains' poles (their blocked eigenvalues), each found by its own chain's
//! count and followed from one load to the next ([`SagPoles`]).
//!
//! **What a pole is.** Pole j of chain i is the j-th eigenvalue of chain i with its end
//! held: the λ where chain i's blocked count (`SagChainEval::below`, Wittrick–Williams on
//! the chain alone) steps from j − 1 to j, and where its end stiffness S_i(λ) blows up.
//! The poles of D(λ) are the union over the chains.
//!
//! **The search** ([`pole_search`]). G(λ) = blockdiag(S_in, s_out)⁻¹ (the chain's end
//! flexibility in (h, up, n)) is smooth through a pole, G' = −G S' G is positive
//! semidefinite (S' is minus a mass), so each eigenvalue g_k of G increases with λ and
//! vanishes exactly where S_i blows up: every zero of a g_k is a pole of chain i, crossed
//! from below. Newton on the g_k nearest its zero on the side of the target (from x with
//! count c ≥ j: a g_k > 0, downwards to pole c; from c < j: a g_k < 0, upwards to pole
//! c + 1) converges to the pole quadratically (g is nearly linear there: S ≈ r/(p − λ));
//! every iterate's count keeps a bracket lo < p ≤ hi, and a step leaving it bisects. The
//! answer is accepted when a Newton step is below [`POLE_STEP`] at an iterate whose count
//! is j (going down) or j − 1 (going up): then no pole of the chain lies between it and
//! the answer. A pole with no residue at the end (S_i stays finite) is found by the
//! bisection alone, to [`COLLAPSE_ULPS`] ulps.
//!
//! **Following.** Each computed pole is memoized for the load and kept as the next load's
//! start (a pose moves a millimetre a cycle: two or three chain evaluations from there).
//! The memo is atomic (relaxed) so that the loaded problem stays read-only and shareable.
//! Every chain evaluation is counted; [`SagPoles::evaluations`] converts them into
//! evaluations of D (one per `n` chains) so that the cycle's budget covers them.

use crate::cable::sagged::SagChainEval;
use nalgebra::{Matrix2, SymmetricEigen};
use std::sync::atomic::{AtomicU64, Ordering};

/// A pole search's Newton step below this (relative) ends it: the iterate is then within
/// ~step² of the pole (quadratic convergence on a nearly linear g).
const POLE_STEP: f64 = 1e-12;
/// The scan's walk over the pole intervals (no cycle budget) accepts a pole search's
/// Newton update once a step is below this (relative): g is nearly linear next to the pole
/// (S ≈ r/(p − λ)), so the update is within ~step² (1e-16, relative) of it, well inside the
/// 1e-10 the searches that use the poles need; the last steps to [`POLE_STEP`], which
/// bounce in g's rounding, cost one to three chain evaluations more a pole. (1e-6 would
/// save one chain evaluation on most poles from the string-scaled start, but lost the
/// end-effector mode at one point of suspended-8's sagged map.)
const WALK_POLE_STEP: f64 = 1e-8;
/// ... or its count bracket narrower than this (relative). Why: next to a pole S is
/// capped by the recurrence's pivot nudge (ε·the largest element stiffness) and its
/// rounding, so g bottoms out at ~1e-17..1e-13 of its scale and Newton's last steps
/// bounce at ~1e-12..3e-11 of λ (measured on the paper robot with sag); the searches
/// that use the poles start 1e-9 (relative) across a pole, so a pole known to
/// 1e-10 is on the right side of every such point.
const POLE_BRACKET: f64 = 1e-10;
/// Chain evaluations one pole search takes at most (Newton, else bisection: ~60 halvings
/// reach [`COLLAPSE_ULPS`] from a finite bracket, ~40 doublings more from none).
const POLE_MAX_EVALUATIONS: u32 = 160;
/// A walk step past a pole that is not the target goes this much (relative) beyond the
/// Newton estimate of that pole, so that the next iterate is across it.
const WALK_PUSH: f64 = 1e-3;
/// Without a start, a search above a known pole begins this far (relative) above it.
const START_ABOVE: f64 = 1e-9;
/// A search with no upper bracket and no start begins at this λ, rad²/s² (then doubles).
const POLE_START: f64 = 1.0;

/// The bits of a memo entry not computed yet.
const MEMO_EMPTY: u64 = 0x7ff8_0000_0000_0000; // f64::NAN

/// The loaded chains' poles, memoized per load and followed between loads.
#[derive(Debug)]
pub(in crate::modal) struct SagPoles {
    /// Poles 1 ..= `per_chain` of each chain (f64 bits; NaN: not computed for this load).
    memo: Vec<AtomicU64>,
    /// The same poles at the last load where they were computed (the searches' start) ...
    hint: Vec<f64>,
    /// ... and that load's number ...
    hint_load: Vec<u32>,
    /// ... and the chain's string scale at that load (`SagChain::string_scale`, 1/s²;
    /// NaN: not known), which this load's scale divides for the walk's starts ...
    hint_scale: Vec<f64>,
    /// ... kept with each pole computed at this load (f64 bits).
    memo_scale: Vec<AtomicU64>,
    /// Loads so far (a wrapping counter).
    load: u32,
    per_chain: usize,
    /// Chain evaluations spent on pole searches.
    chain_evaluations: AtomicU64,
}

impl Clone for SagPoles {
    fn clone(&self) -> SagPoles {
        SagPoles {
            memo: self
                .memo
                .iter()
                .map(|e| AtomicU64::new(e.load(Ordering::Relaxed)))
                .collect(),
            hint: self.hint.clone(),
            hint_load: self.hint_load.clone(),
            hint_scale: self.hint_scale.clone(),
            memo_scale: self
                .memo_scale
                .iter()
                .map(|e| AtomicU64::new(e.load(Ordering::Relaxed)))
                .collect(),
            load: self.load,
            per_chain: self.per_chain,
            chain_evaluations: AtomicU64::new(self.chain_evaluations.load(Ordering::Relaxed)),
        }
    }
}

impl SagPoles {
    /// Room for `per_chain` poles of each of `n_chains` chains (the only allocation).
    pub(in crate::modal) fn new(n_chains: usize, per_chain: usize) -> SagPoles {
        SagPoles {
            memo: (0..n_chains * per_chain)
                .map(|_| AtomicU64::new(MEMO_EMPTY))
                .collect(),
            hint: vec![f64::NAN; n_chains * per_chain],
            hint_load: vec![0; n_chains * per_chain],
            hint_scale: vec![f64::NAN; n_chains * per_chain],
            memo_scale: (0..n_chains * per_chain)
                .map(|_| AtomicU64::new(MEMO_EMPTY))
                .collect(),
            load: 0,
            per_chain,
            chain_evaluations: AtomicU64::new(0),
        }
    }

    /// A new load: every computed pole becomes the next search's start.
    pub(in crate::modal) fn clear(&mut self) {
        let load = self.load;
        for (((e, h), at), (sc, msc)) in self
            .memo
            .iter_mut()
            .zip(&mut self.hint)
            .zip(&mut self.hint_load)
            .zip(self.hint_scale.iter_mut().zip(&mut self.memo_scale))
        {
            let bits = *e.get_mut();
            if bits != MEMO_EMPTY {
                *h = f64::from_bits(bits);
                *at = load;
                *sc = f64::from_bits(*msc.get_mut());
            }
            *e.get_mut() = MEMO_EMPTY;
            *msc.get_mut() = MEMO_EMPTY;
        }
        self.load = load.wrapping_add(1);
    }

    /// Pole j of chain i (which has `n_poles`) as this load's search found it (`hint`:
    /// else as the last load's did); NaN: not searched (or past the memo); 0 for j = 0, ∞
    /// past the chain's poles.
    fn memo_at(&self, i: usize, j: usize, n_poles: usize, hint: bool) -> f64 {
        if j == 0 {
            return 0.0;
        }
        if j > n_poles {
            return f64::INFINITY;
        }
        if j > self.per_chain {
            return f64::NAN;
        }
        let s = i * self.per_chain + j - 1;
        let v = f64::from_bits(self.memo[s].load(Ordering::Relaxed));
        if v.is_nan() && hint {
            self.hint[s]
        } else {
            v
        }
    }

    /// Pole j of chain i (which has `n_poles`) as this load's search found it, else as the
    /// last load's that searched it did (NaN: never searched); 0 for j = 0, ∞ past the
    /// chain's poles. With the loads since it was found (0: at this load).
    pub(in crate::modal) fn estimate(&self, i: usize, j: usize, n_poles: usize) -> (f64, u32) {
        let now = self.memo_at(i, j, n_poles, false);
        if !now.is_nan() || j > self.per_chain {
            return (now, 0);
        }
        let s = i * self.per_chain + j - 1;
        (self.hint[s], self.load.wrapping_sub(self.hint_load[s]))
    }

    /// Chain evaluations spent on pole searches so far.
    pub(in crate::modal) fn chain_evaluations(&self) -> u64 {
        self.chain_evaluations.load(Ordering::Relaxed)
    }

    /// Pole j (1-based; 0 gives 0) of chain i, which has `n_poles` poles (∞ past them),
    /// from its memo or by [`pole_search`] over `eval` (chain i's evaluation), bracketed by
    /// the chain's memoized neighbours, from the last load's value or else from `near`.
    /// With `scale` (the chain's string scale at this load, 1/s², `SagChain::string_scale`,
    /// asked only where a search is needed; NaN: not scaled), the last load's value is scaled by the ratio of the chain's string
    /// scales now and at that load: a chain's poles move with its tension and length
    /// (a taut string's as T/(m L)), so a study's next point (a map's grid step away)
    /// starts within a few per cent of the pole where the unscaled value is off by the
    /// step's whole change (10-40 % on the paper robot at 0.25 m).
    #[allow(clippy::too_many_arguments)]
    pub(in crate::modal) fn get(
        &self,
        i: usize,
        j: usize,
        n_poles: usize,
        near: f64,
        allowance: u32,
        scale: impl Fn() -> f64,
        eval: impl Fn(f64) -> SagChainEval,
    ) -> f64 {
        let memo = |k: usize| self.memo_at(i, k, n_poles, false);
        let v = memo(j);
        if !v.is_nan() {
            return v;
        }
        let scale = scale();
        let scaled = !scale.is_nan();
        let slot = (j <= self.per_chain).then(|| i * self.per_chain + j - 1);
        // Bracket from the nearest memoized neighbours (a few on each side).
        let mut lo = 0.0;
        for k in (j.saturating_sub(4)..j).rev() {
            let v = memo(k);
            if !v.is_nan() {
                lo = v;
                break;
            }
        }
        let mut hi = f64::INFINITY;
        for k in j + 1..=j + 4 {
            let v = memo(k);
            if !v.is_nan() {
                hi = v;
                break;
            }
        }
        let mut hint = slot.map_or(f64::NAN, |s| self.hint[s]);
        if let (true, Some(s)) = (scaled, slot) {
            let ratio = scale / self.hint_scale[s];
            if ratio.is_finite() && ratio > 0.0 {
                hint *= ratio;
            }
        }
        let hint = if hint > lo && hint < hi { hint } else { near };
        let accept = if scaled { WALK_POLE_STEP } else { POLE_STEP };
        let (p, spent) = pole_search(&eval, j as u32, (lo, hi), hint, allowance, accept);
        self.chain_evaluations
            .fetch_add(u64::from(spent), Ordering::Relaxed);
        if let (Some(s), false) = (slot, p.is_nan()) {
            self.memo[s].store(p.to_bits(), Ordering::Relaxed);
            self.memo_scale[s].store(scale.to_bits(), Ordering::Relaxed);
        }
        p
    }
}

/// The Newton candidates of one chain evaluation: each eigenvalue g_k of the end
/// flexibility G = blockdiag(S_in, s_out)⁻¹ with g_k' = −(u_kᵀ S' u_k) g_k² (u_k its unit
/// eigenvector in S's basis); None where S has a zero eigenvalue (G is infinite there).
fn flexibility_branches(e: &SagChainEval) -> [Option<(f64, f64)>; 3] {
    let s = Matrix2::new(e.s_in[0], e.s_in[1], e.s_in[1], e.s_in[2]);
    let ds = Matrix2::new(e.ds_in[0], e.ds_in[1], e.ds_in[1], e.ds_in[2]);
    let eg = SymmetricEigen::new(s);
    let mut out = [None; 3];
    for k in 0..2 {
        let sigma = eg.eigenvalues[k];
        let u = eg.eigenvectors.column(k);
        if sigma != 0.0 && sigma.is_finite() {
            let g = 1.0 / sigma;
            out[k] = Some((g, -(u.transpose() * ds * u)[(0, 0)] * g * g));
        }
    }
    if e.s_out != 0.0 && e.s_out.is_finite() {
        let g = 1.0 / e.s_out;
        out[2] = Some((g, -e.ds_out * g * g));
    }
    out
}

/// Pole j (1-based) of the chain evaluated by `eval`, searched in (lo, hi] (lo below it,
/// hi at or above it; ∞ when unknown) from `start` (NaN: none), as the module docs say
/// (a Newton step below `accept`, relative, ends it), with at most `allowance` chain
/// evaluations. Returns the pole, rad²/s² (NaN: the
/// allowance ran out first), and the chain evaluations spent.
pub(super) fn pole_search(
    eval: &impl Fn(f64) -> SagChainEval,
    j: u32,
    (mut lo, mut hi): (f64, f64),
    start: f64,
    allowance: u32,
    accept: f64,
) -> (f64, u32) {
    let mid = |lo: f64, hi: f64| {
        if hi.is_finite() {
            0.5 * (lo + hi)
        } else {
            (2.0 * lo).max(POLE_START)
        }
    };
    let mut x = if start > lo && start < hi {
        start
    } else if lo > 0.0 && !hi.is_finite() {
        // Just above the pole below (the scan's order): Newton goes up to the next one.
        lo * (1.0 + START_ABOVE)
    } else {
        mid(lo, hi)
    };
    for it in 1..=POLE_MAX_EVALUATIONS {
        if it > allowance {
            return (f64::NAN, it - 1);
        }
        let e = eval(x);
        let down = e.below >= j;
        if down {
            hi = x;
        } else {
            lo = x;
        }
        if hi.is_finite() && hi - lo <= POLE_BRACKET * hi {
            return (hi, it);
        }
        // Newton on the branch nearest its zero on the target's side: next to the target
        // (no pole of the chain between x and it) to the target itself; farther away, a
        // little past the nearest pole that way (a walk from pole to pole).
        let adjacent = if down { e.below == j } else { e.below + 1 == j };
        let mut step = f64::NAN;
        for (g, dg) in flexibility_branches(&e).into_iter().flatten() {
            if !(dg > 0.0) || (g > 0.0) != down {
                continue;
            }
            let s = -g / dg;
            if !(step.abs() <= s.abs()) {
                step = s;
            }
        }
        if !adjacent {
            step *= 1.0 + WALK_PUSH;
        }
        let xn = x + step;
        if adjacent && step.is_finite() && step.abs() <= accept * x && xn >= lo && xn <= hi {
            return (xn, it);
        }
        x = if xn > lo && xn < hi { xn } else { mid(lo, hi) };
    }
    (hi, POLE_MAX_EVALUATIONS)
}
