//! The scan over the pole intervals of D in ascending order: every root in each interval,
//! until one reaches the participation threshold (and, while recording, until the sum-rule
//! bound is low enough).
//!
//! Where the poles are known in closed form (taut chains) the intervals are theirs. Where
//! each chain's poles are found by its own count (sagged FEM chains,
//! [`Condensed::poles_searched`]) the scan walks the intervals between the found poles, and
//! the blocked count at an interval's two evaluation points proves it pole-free (equal at
//! both); an interval that fails this check, or whose root search fails, hands the scan
//! over to the sweep of the spectrum by the count from its lower end. Where the count alone
//! shows the poles (continuous sagged chains) the scan is that sweep from the start.
//!
//! Why the searched poles (paper robot with sag, N = 40, a cold start at one pose): the
//! sweep solves each of the 28 modes below the end-effector mode by bisecting on the count
//! until its bracket is pole-free, ~25 evaluations a mode (700 to the answer); between
//! found poles a mode costs its interval's two end evaluations and a few Newton steps, and
//! a pole a few evaluations of one chain (an eighth of D's on eight cables).

use super::member::Member;
use super::{EeTracker, CHEAP_ACCEPT, MAX_MEMBERS, P_ADD, P_MARGIN, SCAN_BOUND};
use crate::modal::engine::{quad, Condensed, DynEval, EigD, PoleCursor, MAX_CHAINS};
use crate::modal::first_mode::RootFinder;
use crate::modal::spectrum::{SpectrumSearch, SweepState};
use crate::modal::{ModalError, Root, SpectrumParams};

/// Where the count alone shows the poles, a mode of the sweep that the cycle's budget cut
/// in this many cycles running is skipped (`ScanState::skipped`).
const STUCK_CYCLES: u32 = 3;
/// A window rescan that sweeps by the count stops recording past its answer once the
/// sum-rule bound (trace form, the watched modes counted with their participation when
/// found) is below this, where a scan from zero waits for `SCAN_BOUND`: each mode it
/// records costs ~15-20 evaluations, and the warm cycle that must certify its answer needs
/// the bound (matrix form, at one pose) below the threshold less `CERT_MARGIN`, 0.45 by
/// default. Along the paper's spatial robot's circle with continuous sagged cables (3 000
/// cycles) 0.3 took the end-effector answer's age p99 from 12 to 11 cycles and its largest
/// from 20 to 15 (0.15 and 0.25: 12; 0.35: 11).
const WINDOW_SWEEP_BOUND: f64 = 0.3;
/// Roots within this (relative) of the scan's `skip_to` count as already known.
const SKIP_TOL: f64 = 1e-9;
/// A rescan from a window skips roots up to this much (relative) below the window, so
/// that a root exactly at it is found.
pub(super) const WINDOW_EDGE: f64 = 1e-12;
/// Evaluation points sit this far (relative to the pole) inside a pole interval ...
const INSET_REL: f64 = 1e-9;
/// ... but never past this fraction of a narrow interval.
const INSET_MAX_FRACTION: f64 = 0.25;
/// The participation error a scan's root may carry, for the plain sum rule's stop
/// ([`ScanState::none_above`]): a weak root is read within ~1e-5·|dp/d ln λ| ≲ 2e-4 of
/// its root (`first_mode::weak_root`), every other one to ~1e-8.
const P_ROOT_ERR: f64 = 2e-4;
/// A root's Newton search starts at one end's Newton step (where its branch stays finite)
/// when that lands within this fraction of the interval's width from the end. Why: a mode
/// of a nearly decoupled chain sits a hair below that chain's pole (p ~ 1e-5), where the
/// secant from the interval's far end took 11-18 evaluations of D (the branch bends at the
/// avoided crossing with the eigenvalue that blows up there); its end step lands within
/// ~1e-4 of it. Measured over `map spatial-paper --step 0.25 --z 1.0` with sag (1 420
/// roots): 4.93 evaluations a root with the secant alone, 4.09 at this fraction (4.13 at
/// 0.02, 4.21 at 0.05, 4.28 at 0.001).
const END_NEWTON: f64 = 0.005;
/// An eigenvalue of D at δ from a pole with |μ'| δ ≥ this share of |μ| is the pole's
/// (`blowing_up`; ≈ 1 for the pole's, ~δ/width ≪ 1 for the others).
const BLOW_UP_SHARE: f64 = 0.5;

/// Evaluation point inset from a pole at x into an interval of width w: never past a
/// quarter of a narrow interval (nearly coincident poles of different chains).
pub(super) fn inset(w: f64, x: f64) -> f64 {
    (INSET_REL * x).min(INSET_MAX_FRACTION * w)
}

/// The roots of the pole interval (a, b), evaluated at `lo` (a⁺) and `hi_eval` (b⁻): the
/// blocked count at each end (0 at a = 0; at b = ∞, that at a⁺), the branches [na, nb)
/// that have a root in it, and D's eigenvalues at each end (NaN where not evaluated; two
/// evaluations at most).
fn interval_branches<P: Condensed>(
    f: &mut RootFinder<'_, P>,
    a: f64,
    b: f64,
    lo: f64,
    hi_eval: f64,
) -> IntervalEnds {
    let mut below = [0; 2];
    let mut mu = [[f64::NAN; 6]; 2];
    let mut blows = [[false; 6]; 2];
    let mut dmu = [[f64::NAN; 6]; 2];
    let na = if a == 0.0 {
        0
    } else {
        let e = f.eval(lo);
        below[0] = e.below;
        let eg = e.eig();
        mu[0] = eg.values;
        (blows[0], dmu[0]) = blowing_up(&e, &eg, lo - a);
        eg.negatives()
    };
    below[1] = below[0];
    let nb = if b.is_finite() {
        let e = f.eval(hi_eval);
        below[1] = e.below;
        let eg = e.eig();
        mu[1] = eg.values;
        (blows[1], dmu[1]) = blowing_up(&e, &eg, b - hi_eval);
        eg.negatives()
    } else {
        f.view.dim()
    };
    IntervalEnds {
        below,
        branches: (na, nb),
        mu,
        blows,
        dmu,
    }
}

/// Which of D's eigenvalues μ_k at a point `delta` from a pole are that pole's (blow up
/// there): μ_k ≈ ρ/δ has |μ_k'| δ ≈ |μ_k|, where an eigenvalue that stays finite has
/// |μ_k'| δ ≪ |μ_k| (δ is 1e-9 of the pole, or a quarter of a narrow interval). With each
/// μ_k' (Hellmann–Feynman: v_kᵀ D' v_k).
fn blowing_up(e: &DynEval, eg: &EigD, delta: f64) -> ([bool; 6], [f64; 6]) {
    let mut out = [false; 6];
    let mut slopes = [f64::NAN; 6];
    for (k, o) in out.iter_mut().enumerate().take(eg.n) {
        let dmu = quad(&e.dd, &eg.vectors[k], e.dim);
        *o = dmu.abs() * delta >= BLOW_UP_SHARE * eg.values[k].abs();
        slopes[k] = dmu;
    }
    (out, slopes)
}

/// What [`interval_branches`] read at the two ends of a pole interval.
struct IntervalEnds {
    below: [u32; 2],
    branches: (usize, usize),
    mu: [[f64; 6]; 2],
    /// Which eigenvalues blow up at each end's pole ([`blowing_up`]) ...
    blows: [[bool; 6]; 2],
    /// ... and each eigenvalue's slope μ_k' there (NaN where not evaluated).
    dmu: [[f64; 6]; 2],
}

impl IntervalEnds {
    /// A first iterate for branch k's root in (lo, hi) between the poles pa ≤ lo and
    /// pb ≥ hi: the zero of the secant of the pole-free function μ_k(λ)(λ − pa)(pb − λ)
    /// through the two ends (NaN where an end was not evaluated). Why: between searched
    /// poles Newton from the interval's middle takes ~5 evaluations a root; from the secant
    /// (the poles removed, nearly linear) one or two fewer.
    fn secant(&self, k: usize, (lo, hi): (f64, f64), (pa, pb): (f64, f64)) -> f64 {
        // Only the poles branch k has: a branch that stays finite at an end (the eigenvalue
        // blowing up there is another one) times the distance to that end's pole would be
        // ~1e-9 of its size there, and the secant's zero would sit at that end.
        let (ba, bb) = (self.blows[0][k], self.blows[1][k]);
        let g = |x: f64, mu: f64| {
            let fa = if ba { x - pa } else { 1.0 };
            let fb = if bb { pb - x } else { 1.0 };
            mu * fa * fb
        };
        let (g0, g1) = (g(lo, self.mu[0][k]), g(hi, self.mu[1][k]));
        let secant = if g0 > 0.0 && g1 < 0.0 {
            lo + (hi - lo) * g0 / (g0 - g1)
        } else {
            f64::NAN
        };
        // A root next to an end where branch k stays finite: Newton's step from that end
        // (μ_k is smooth there) lands within END_NEWTON of the interval's width from it.
        let w = hi - lo;
        for (end, x, sign) in [(1, hi, -1.0), (0, lo, 1.0)] {
            if self.blows[end][k] {
                continue;
            }
            let xn = x - self.mu[end][k] / self.dmu[end][k];
            if xn > lo && xn < hi && sign * (xn - x) <= END_NEWTON * w {
                return xn;
            }
        }
        secant
    }
}

/// A scan in progress: where it stands, what it found. Plain data (no allocation); a scan
/// that runs out of the cycle's evaluation budget is continued from here in the next cycle,
/// on that cycle's problem (the poles move a little between cycles: the interval's lower
/// pole is followed by its identity, the chain and pole number).
#[derive(Debug, Clone, Copy)]
pub(super) struct ScanState {
    /// The lower end of the current pole interval: a fixed λ (rad²/s², the scan's start) ...
    a_fixed: f64,
    /// ... or, once the scan passed a pole, that pole's (chain, number).
    a_key: Option<(usize, usize)>,
    /// Each chain's next pole number (the scan's cursor).
    next_pole: PoleCursor,
    /// The first branch of the current interval not solved yet ...
    branch: usize,
    /// ... and where its root search stood when the budget ran out (the middle of its
    /// bracket, rad²/s²; NaN: not started): the next cycle's search starts there.
    guess: f64,
    /// Roots at or below this λ (rad²/s²) count as known.
    skip_to: f64,
    /// The scan gives up above this λ (rad²/s²).
    limit: f64,
    /// Started from a window below the watched modes (a partial rescan), not from zero.
    pub(super) window: bool,
    answer: Option<Root>,
    best: Option<Root>,
    /// Evaluations and pole intervals spent over all its cycles.
    spent: u32,
    intervals: u32,
    /// The most pole intervals (or swept modes) it may pass ([`ScanState::cap`]; 0: not
    /// set yet, set at its first step).
    max_intervals: u32,
    /// Σ p_k over every mode the scan has solved, and how many: while it is exact (a scan
    /// from zero that has read every mode in order, `p_exact`), the plain sum rule bounds
    /// the participation of every mode above ([`ScanState::none_above`]).
    p_sum: f64,
    p_count: u32,
    p_exact: bool,
    /// Cycles it was continued in after the one it started in.
    pub(super) resumed: u32,
    /// Where the poles are seen only through the count, the scan is an ascending sweep of
    /// the spectrum from `start`: the sweep's state, whether it started, the next mode's
    /// index, and the bracket of that mode a cycle's budget cut (NaN: none).
    modes: SweepState,
    /// Evaluations the sweep had spent when it found the answer (it goes on past the
    /// answer, recording, for as many more at most).
    to_answer: u32,
    started: bool,
    start: f64,
    next: usize,
    cut: (f64, f64),
    /// Where the count alone shows the poles: past the answer, the sweep records at least
    /// the modes up to this λ (rad²/s²; 0: no such floor), and the λ of the last mode it
    /// solved.
    pub(super) record_to: f64,
    last: f64,
    /// Cycles the sweep's current mode has been cut in by the budget.
    cut_cycles: u32,
    /// The scan sweeps the spectrum by the count (the poles seen through it alone, or a
    /// searched pole interval failed its count check) instead of walking pole intervals.
    by_count: bool,
    /// A cold scan from zero with no cycle budget where the poles are not in closed form:
    /// it answers as soon as it finds the answer (exact: every mode below was read) and
    /// records past it only when the tracker is called again warm (`deferred` then), since
    /// a study's next point is often cold again (a map's grid) and the recording would be
    /// lost. Why: past the answer the recording costs as much as finding it did.
    pub(super) defer: bool,
    pub(super) deferred: bool,
    /// The sweep skipped a mode it could not isolate within [`STUCK_CYCLES`] cycles: its
    /// answer is not known to be the lowest until the sum rules certify it.
    pub(super) skipped: bool,
    /// A window sweep by the count that has found its answer stops there once: the next
    /// cycle tries to certify it by a warm cycle of the watched modes before the sweep
    /// records past it (`cert_next`; `cert_tried`: done once).
    pub(super) cert_next: bool,
    cert_tried: bool,
}

impl ScanState {
    /// A scan upward from the pole interval containing `start` (rad²/s²), skipping roots at
    /// or below `skip_to`, giving up above `limit`.
    pub(super) fn new<P: Condensed>(
        p: &P,
        start: f64,
        skip_to: f64,
        limit: f64,
        window: bool,
    ) -> Self {
        let searched = !p.poles_known() && p.poles_searched();
        // Searched poles: the first interval is (start, the next pole above it).
        let a = p
            .pole_interval(start)
            .map_or(if searched { start } else { 0.0 }, |(a, _)| a);
        ScanState {
            by_count: !(p.poles_known() || searched),
            defer: false,
            deferred: false,
            a_fixed: a,
            a_key: None,
            next_pole: [1; MAX_CHAINS],
            branch: 0,
            guess: f64::NAN,
            skip_to,
            limit,
            window,
            answer: None,
            best: None,
            spent: 0,
            intervals: 0,
            max_intervals: 0,
            p_sum: 0.0,
            p_count: 0,
            p_exact: start == 0.0 && !window,
            resumed: 0,
            modes: SweepState::new(),
            to_answer: 0,
            started: false,
            start,
            next: 0,
            cut: (f64::NAN, f64::NAN),
            record_to: 0.0,
            last: 0.0,
            cut_cycles: 0,
            skipped: false,
            cert_next: false,
            cert_tried: false,
        }
    }

    /// A scan from zero, skipping the known first root at `first` (rad²/s²).
    pub(super) fn from_zero<P: Condensed>(p: &P, first: f64) -> Self {
        Self::new(p, 0.0, first, f64::INFINITY, false)
    }

    /// Past the answer, recording where the poles are not in closed form (`now`: the
    /// evaluations of this cycle's share so far): the recording stops once it has cost what
    /// finding the answer did (a mode costs tens of evaluations in the sweep, several
    /// between searched poles, not two as between closed-form poles) and has reached
    /// `record_to`.
    fn past_answer(&self, now: u32) -> bool {
        let spent = self.spent + now;
        self.answer.is_some()
            && spent - self.to_answer > self.to_answer
            && self.last >= self.record_to
    }

    /// The most pole intervals (or swept modes) this scan may pass:
    /// [`ModalParams::max_scan_intervals`], except where no cycle budget holds it and the
    /// chains' poles are searched (FEM sagged chains, finitely many modes): there at least
    /// the model's count of modes, so that the answer is reached wherever it is. Why: the
    /// searched poles of N-element chains give ~3(N − 1) pole intervals a cable below the
    /// top of the spectrum, and the end-effector mode of a large sagging robot sits deep in
    /// it (suspended-8 at N = 40: index ~200-400 of ~940 over most of its workspace), where
    /// a cap of 400 left NaN at 37 of 88 ok points of its map. Still bounded: each interval
    /// lies between two of the model's poles, so a walk has at most as many as its modes
    /// (the blocked modes plus the end-effector's), each interval a bounded number of
    /// evaluations (two ends, at most six roots of at most `max_evaluations`, its pole).
    ///
    /// [`ModalParams::max_scan_intervals`]: crate::modal::ModalParams::max_scan_intervals
    fn cap<P: Condensed>(f: &RootFinder<'_, P>) -> u32 {
        let cap = f.params.max_scan_intervals;
        if f.budget == u32::MAX && !f.view.poles_known() && f.view.poles_searched() {
            let modes = u32::try_from(f.view.total_modes()).unwrap_or(u32::MAX);
            cap.max(modes)
        } else {
            cap
        }
    }

    /// A mode the scan solved (its participation, for the plain sum rule).
    fn solved(&mut self, p: f64) {
        self.p_sum += p;
        self.p_count += 1;
    }

    /// No mode above the ones solved can reach the threshold `thr`: by the plain sum rule
    /// (`bound`'s docs), every mode above holds at most Σ_k p_k over all modes (`total`)
    /// less what the solved ones hold, each of those within [`P_ROOT_ERR`]. Only for a
    /// scan from zero without a cycle budget that has read every mode below, with no
    /// answer yet. Why: where no
    /// mode reaches the threshold the walk would otherwise go on to the model's cap; on
    /// suspended-8 at N = 40 the plain rule's remainder drops below 0.5 near mode 300-470
    /// of 939.
    fn none_above(&self, total: f64, thr: f64) -> bool {
        self.p_exact
            && self.answer.is_none()
            && total.is_finite()
            && total - self.p_sum + P_ROOT_ERR * f64::from(self.p_count) < thr
    }

    /// The lower end of the current interval on the loaded problem, rad²/s².
    fn a<P: Condensed>(&self, p: &P) -> f64 {
        self.a_key
            .and_then(|(c, j)| p.keyed_pole(c, j))
            .unwrap_or(self.a_fixed)
    }
}

/// What one cycle's share of a scan came to.
pub(super) enum ScanStep {
    /// The cycle's budget ran out: continued next cycle.
    Paused,
    /// Finished: the answer (or the most end-effector-like mode found, below the threshold),
    /// or why none was found.
    Done(Result<Root, ModalError>),
}

impl EeTracker {
    /// Continue the scan in progress (`self.scan`) within the cycle's budget: upward over
    /// the pole intervals for the first root with participation ≥ the threshold. While
    /// recording, every root with participation ≥ [`P_ADD`] is watched and the scan goes on
    /// past the answer until the sum-rule bound is below [`SCAN_BOUND`] (within the scan's
    /// bounds, [`ModalParams::max_scan_intervals`] and
    /// [`ModalParams::max_scan_evaluations`] over all its cycles); the answer is the same.
    ///
    /// [`ModalParams::max_scan_intervals`]: crate::modal::ModalParams::max_scan_intervals
    /// [`ModalParams::max_scan_evaluations`]: crate::modal::ModalParams::max_scan_evaluations
    pub(super) fn scan_step<P: Condensed>(&mut self, f: &mut RootFinder<'_, P>) -> ScanStep {
        let Some(mut st) = self.scan else {
            return ScanStep::Done(Err(ModalError::NoEeMode(0)));
        };
        let begin = f.evaluations();
        if st.max_intervals == 0 {
            st.max_intervals = ScanState::cap(f);
            // The sum rule's stop only without a cycle budget (the real-time scans keep
            // theirs).
            st.p_exact &= f.budget == u32::MAX;
        }
        if st.spent == 0 && !f.view.poles_known() && f.budget != u32::MAX {
            // Within a cycle's budget the sweep: the poles a walk needs are searched again
            // at each cycle's load, by single-chain evaluations that cost more than their
            // share of a lockstep evaluation of D.
            st.by_count = true;
        }
        // Where the poles are known or searched the scan walks the pole intervals (two
        // evaluations and one Newton search per root); where the count alone shows them
        // (or a searched interval failed its count check), it sweeps the spectrum mode by
        // mode.
        let mut done = None;
        if !st.by_count {
            done = self.scan_intervals(f, &mut st, begin);
        }
        if st.by_count && done.is_none() && !f.exhausted() {
            // The sweep sees the count alone (its brackets by the count, as its docs say).
            f.view.follow_poles(None);
            done = self.scan_modes(f, &mut st, begin);
            f.view.follow_poles(Some(f.left()));
        }
        st.spent = st.spent.saturating_add(f.evaluations() - begin);
        match done {
            None => {
                self.scan = Some(st);
                ScanStep::Paused
            }
            Some(r) if st.defer && r.is_ok() && st.answer.is_some() => {
                // Answered; the recording goes on at the next (warm) call, which then
                // certifies at its pose as a scan found over several cycles.
                st.defer = false;
                st.deferred = true;
                st.resumed = 1;
                self.scan = Some(st);
                ScanStep::Done(r)
            }
            Some(r) => {
                self.scan = None;
                self.skipped = st.skipped;
                ScanStep::Done(r)
            }
        }
    }

    /// The scan's loop over the intervals; None when the budget ran out (state in `st`).
    fn scan_intervals<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        st: &mut ScanState,
        begin: u32,
    ) -> Option<Result<Root, ModalError>> {
        let thr = f.params.ee_participation_min;
        let searched = !f.view.poles_known();
        // Between searched poles an interval costs several evaluations, not two: as the
        // sweep, the walk is bounded by its intervals (each by its two evaluations, its
        // roots' searches and its poles' searches), not by the closed-form scan's total.
        while st.intervals < st.max_intervals
            && (searched || st.spent + (f.evaluations() - begin) <= f.params.max_scan_evaluations)
        {
            let a = st.a(&f.view);
            // A searched pole not found within the cycle's budget: go on next cycle.
            if a.is_nan() {
                return None;
            }
            let (b, bc, bj) = f.view.next_pole(&mut st.next_pole, a);
            if b.is_nan() {
                return None;
            }
            if a > st.limit {
                break;
            }
            if searched && st.past_answer(f.evaluations() - begin) {
                break;
            }
            if st.none_above(self.sums.total, thr) {
                break;
            }
            // The sum rule's tally where this interval began (a sweep from its lower end
            // solves its roots again).
            let tally = (st.p_sum, st.p_count, st.branch == 0);
            match self.scan_interval(f, st, (a, b), thr, begin) {
                IntervalEnd::Paused => return None,
                IntervalEnd::Stop => break,
                IntervalEnd::Failed(e) => return Some(Err(e)),
                IntervalEnd::Sweep => {
                    // Sweep on by the count from this interval's lower end.
                    st.by_count = true;
                    st.start = a;
                    (st.p_sum, st.p_count) = (tally.0, tally.1);
                    st.p_exact &= tally.2;
                    return None;
                }
                IntervalEnd::Next => {}
            }
            if !b.is_finite() {
                break;
            }
            st.a_key = Some((bc, bj));
            st.branch = 0;
            st.guess = f64::NAN;
            st.intervals += 1;
        }
        if let Some(r) = st.answer {
            return Some(Ok(r));
        }
        // No mode reaches the threshold within the bounds: the most end-effector-like mode
        // found (its participation, below the threshold, says so).
        Some(st.best.ok_or(ModalError::NoEeMode(st.max_intervals)))
    }
    /// The roots of one pole interval (a, b) from branch `st.branch` on (`begin`: the
    /// evaluation counter where this cycle's share of the scan began).
    fn scan_interval<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        st: &mut ScanState,
        (a, b): (f64, f64),
        thr: f64,
        begin: u32,
    ) -> IntervalEnd {
        let searched = !f.view.poles_known();
        // Evaluation points just inside (a, b): never past the middle of a narrow interval
        // (nearly coincident poles of different chains).
        let lo = if a == 0.0 { 0.0 } else { a + inset(b - a, a) };
        let hi_eval = if b.is_finite() {
            b - inset(b - a, b)
        } else {
            f64::INFINITY
        };
        if b.is_finite() && hi_eval <= st.skip_to * (1.0 + SKIP_TOL) {
            return IntervalEnd::Next;
        }
        if f.left() < 2 {
            return IntervalEnd::Paused;
        }
        // Blocked count of the interval (index of its lowest root).
        let ends = interval_branches(f, a, b, lo, hi_eval);
        let (belows, (na, nb)) = (ends.below, ends.branches);
        let below = belows[1];
        if searched && belows[0] != belows[1] {
            // A pole inside: the searched poles missed one (or one moved past its end).
            return IntervalEnd::Sweep;
        }
        for branch in na.max(st.branch)..nb {
            let resumed = branch == st.branch && st.guess > lo && st.guess < hi_eval;
            let secant = if searched && !resumed {
                ends.secant(branch, (lo, hi_eval), (a, b))
            } else {
                f64::NAN
            };
            let guess = if resumed {
                st.guess
            } else if secant > lo && secant < hi_eval {
                secant
            } else if hi_eval.is_finite() {
                0.5 * (lo + hi_eval)
            } else {
                2.0 * lo.max(st.skip_to).max(1.0)
            };
            // The closed-form scan removes the pole above from Newton's function.
            let r = if searched {
                // Newton removes only the poles this branch blows up at (a factor (λ − a)
                // on a branch finite at a would put a false zero at a).
                let pa = if ends.blows[0][branch] { a } else { 0.0 };
                let pb = if ends.blows[1][branch] {
                    b
                } else {
                    f64::INFINITY
                };
                // A root whose participation is clearly below the threshold is read once
                // its Newton step is below CHEAP_ACCEPT, where no other branch can cross it
                // (`first_mode::weak_root`): its participation is then within ~1e-5·|dp/d
                // ln λ| ≲ 2e-4 of the root's, far inside P_MARGIN. The answer, and a root
                // near the threshold, are solved to full accuracy.
                let weak = (CHEAP_ACCEPT, thr - P_MARGIN);
                f.branch_root_between(branch, (lo, hi_eval), (pa, pb), guess, weak)
            } else {
                f.branch_root_with(branch, lo, hi_eval, 0.0, b, guess, true)
            };
            if f.exhausted() {
                if let Err(ModalError::NoConvergence { lo: l, hi: h, .. }) = r {
                    st.branch = branch;
                    st.guess = if h.is_finite() {
                        0.5 * (l + h)
                    } else {
                        2.0 * l
                    };
                    return IntervalEnd::Paused;
                }
            }
            st.guess = f64::NAN;
            let r = match r {
                Ok(r) => r,
                // Collecting past the answer: keep what was found.
                Err(_) if st.answer.is_some() => return IntervalEnd::Stop,
                Err(_) if searched => return IntervalEnd::Sweep,
                Err(e) => return IntervalEnd::Failed(e),
            };
            st.solved(r.ee_participation);
            if r.lambda <= st.skip_to * (1.0 + SKIP_TOL) {
                continue;
            }
            st.last = r.lambda;
            if self.recording && r.ee_participation >= P_ADD {
                // Searched poles: watched as the sweep watches its modes (by index; the
                // warm cycles see no pole intervals).
                let (br, ma, mb) = if searched {
                    (0, 0.0, f64::INFINITY)
                } else {
                    (branch, a, b)
                };
                self.insert_member(Member::new(
                    r.lambda,
                    r.ee_participation,
                    below + branch as u32,
                    br,
                    ma,
                    mb,
                ));
            }
            let had = st.answer.is_some();
            if self.take_root(st, r, thr) {
                // A deferred recording goes on from the next root.
                st.branch = branch + 1;
                return IntervalEnd::Stop;
            }
            if !had && st.answer.is_some() {
                st.to_answer = st.spent + (f.evaluations() - begin);
            }
        }
        IntervalEnd::Next
    }

    /// A root the scan found (recorded already): the answer when it is the first to reach
    /// the threshold, else the best so far. True when the scan is done: the answer found and
    /// (recording) the sum-rule bound low enough or the watch list full.
    fn take_root(&mut self, st: &mut ScanState, r: Root, thr: f64) -> bool {
        if st.answer.is_none() && r.ee_participation >= thr {
            st.answer = Some(r);
            if !self.recording || st.defer {
                return true;
            }
        }
        if let Some(ans) = st.answer {
            // Modes watched in earlier cycles of a continued scan count with their
            // participation then (the certificate comes later, at one pose).
            let stop = if st.window && st.by_count {
                WINDOW_SWEEP_BOUND
            } else {
                SCAN_BOUND
            };
            if self.unwatched_bound_with(ans.lambda, true) < stop || self.n_members == MAX_MEMBERS {
                return true;
            }
        }
        if st
            .best
            .is_none_or(|x| r.ee_participation > x.ee_participation)
        {
            st.best = Some(r);
        }
        false
    }

    /// The scan where the poles are seen only through the count: an ascending sweep of the
    /// spectrum by the spectrum search (modes solved in order from the first at or above
    /// the scan's start, each read for its participation; past the answer, recording, for
    /// at most as many evaluations as the answer took, or up to `ScanState::record_to`; a
    /// mode cut in [`STUCK_CYCLES`] cycles running is skipped), at most
    /// [`ModalParams::max_scan_intervals`] modes, each within the spectrum search's own
    /// bound ([`SpectrumParams::max_evaluations_per_mode`]: the modes below a sagged robot's
    /// end-effector mode cost ~30 evaluations each, so the pole-interval scan's total bound
    /// would stop a sweep far short of it); None when the budget ran out (the mode it cut
    /// keeps its narrowed bracket, re-probed on the next cycle's problem).
    ///
    /// [`ModalParams::max_scan_intervals`]: crate::modal::ModalParams::max_scan_intervals
    fn scan_modes<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        st: &mut ScanState,
        begin: u32,
    ) -> Option<Result<Root, ModalError>> {
        let thr = f.params.ee_participation_min;
        let max_modes = st.max_intervals as usize;
        let budget = f.left();
        let params = SpectrumParams::default();
        let mut s = SpectrumSearch::resume(&mut f.view, &params, st.modes);
        s.set_cycle_budget(budget);
        if !st.started {
            if let Err(e) = s.start() {
                return Some(Err(e));
            }
            if st.start > 0.0 {
                st.next = s.skip_to(st.start);
            }
            st.started = true;
        }
        let total = s.problem().total_modes();
        while st.next < total && (st.intervals as usize) < max_modes {
            if st.past_answer(s.problem().evaluations() - begin) {
                break;
            }
            if st.none_above(self.sums.total, thr) {
                break;
            }
            let i = st.next;
            if st.cut.0.is_finite() && st.cut_cycles >= STUCK_CYCLES {
                // A mode the budget cut in several cycles running: it sits so close to a
                // pole that the count's bisection, widened again each cycle by the pose's
                // motion, does not isolate it within a cycle. Skip it; the answer then
                // needs the sum rules' certificate (the skipped mode is unwatched).
                st.cut = (f64::NAN, f64::NAN);
                st.cut_cycles = 0;
                st.skipped = true;
                st.p_exact = false;
                st.next += 1;
                st.intervals += 1;
                continue;
            }
            let r = if st.cut.0.is_finite() {
                s.mode_within(i, st.cut.0, st.cut.1)
            } else {
                s.mode(i)
            };
            let m = match r {
                Ok(m) => m,
                Err(ModalError::NoConvergence { lo, hi, .. }) if s.cut => {
                    st.modes = s.state();
                    st.cut_cycles += 1;
                    st.cut = if lo > 0.0 && hi.is_finite() && lo < hi {
                        (lo, hi)
                    } else {
                        (f64::NAN, f64::NAN)
                    };
                    return None;
                }
                // Collecting past the answer: keep what was found.
                Err(_) if st.answer.is_some() => break,
                Err(e) => return Some(Err(e)),
            };
            st.cut = (f64::NAN, f64::NAN);
            st.cut_cycles = 0;
            st.last = m.lambda;
            st.next += 1;
            st.intervals += 1;
            st.solved(m.ee_participation);
            if m.lambda <= st.skip_to * (1.0 + SKIP_TOL) {
                continue;
            }
            let r = Root {
                lambda: m.lambda,
                ee_participation: m.ee_participation,
                evaluations: 0,
                residual: f64::NAN,
            };
            if self.recording && r.ee_participation >= P_ADD {
                self.insert_member(Member::new(
                    r.lambda,
                    r.ee_participation,
                    i as u32,
                    0,
                    0.0,
                    f64::INFINITY,
                ));
            }
            let had = st.answer.is_some();
            if self.take_root(st, r, thr) {
                break;
            }
            if !had && st.answer.is_some() {
                st.to_answer = st.spent + (s.problem().evaluations() - begin);
                if st.window && self.recording && !st.cert_tried {
                    // Try the certificate first, at the next cycle's pose with its whole
                    // budget: the modes below the answer are read (the recording past it
                    // costs as much again).
                    st.cert_tried = true;
                    st.cert_next = true;
                    st.modes = s.state();
                    return None;
                }
            }
        }
        // Kept for a deferred recording (it goes on from here).
        st.modes = s.state();
        if let Some(r) = st.answer {
            return Some(Ok(r));
        }
        Some(st.best.ok_or(ModalError::NoEeMode(max_modes as u32)))
    }
}

/// How one interval of a scan ended.
enum IntervalEnd {
    /// Go on with the next interval.
    Next,
    /// The scan is finished (answer found and certified, or an error).
    Stop,
    /// The cycle's budget ran out.
    Paused,
    /// A root search failed before any answer.
    Failed(ModalError),
    /// Searched poles: the interval failed its count check (or its root search failed);
    /// the scan sweeps on by the count from its lower end.
    Sweep,
}
