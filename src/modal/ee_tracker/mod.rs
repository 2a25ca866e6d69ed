//! The end-effector mode tracker: the lowest mode whose end-effector participation reaches
//! [`ModalParams::ee_participation_min`](super::ModalParams::ee_participation_min), followed
//! from cycle to cycle and certified by the participation sum rules (see
//! [`ModalSolver::ee_mode_tracked`](super::ModalSolver::ee_mode_tracked) for the method).
//!
//! - [`bound`]: the sum-rule bound on the unwatched modes (the certificate);
//! - [`member`]: one watched mode, its predictor, the watch list;
//! - [`scan`]: the scan over the pole intervals (cold start and rescans);
//! - [`follow`]: one warm cycle (follow, partner and neighbour searches, certificate);
//! - [`gap`]: the neighbour searches where the count alone shows the poles;
//! - [`track`]: the Newton searches it uses (follow a root, a neighbour, a partner);
//! - [`phases`]: one cycle's work within the budget (track, scan, continue, certify).
//!
//! The tuning constants below decide only the cost: every warm answer is certified.
//!
//! Every search stops at the cycle's evaluation budget; a warm cycle cut short is tried
//! again in the next one (`RescanReason::Starved`, not a rescan), a scan cut short is kept
//! in `EeTracker::scan` and continued (`scan::ScanState`).

mod bound;
mod follow;
mod gap;
mod member;
mod phases;
mod scan;
mod track;

use super::engine::{Condensed, SumRules};
use super::first_mode::RootFinder;
use super::{ModalError, Root};
use member::{predict, Member};
use scan::{ScanState, ScanStep};
use track::track_root;

/// Largest number of watched modes (a fixed array, no allocation; when full, the weakest
/// gives way to a stronger one).
const MAX_MEMBERS: usize = 16;
/// Modes found with at least this participation are watched (the modes of the paper's
/// spatial robot below 0.05 hold at most 0.16 together along the circle, dense reference).
const P_ADD: f64 = 0.05;
/// A watched mode whose participation falls below this is dropped (what it holds then
/// counts against the sum-rule bound).
const P_DROP: f64 = 0.02;
/// When the sum-rule bound on the unwatched modes (counting the watched modes not followed
/// this cycle with their last participation) exceeds this, a spectral neighbour of the
/// watched mode whose participation changed most is searched (ahead of need: the bound
/// must stay below the threshold less [`CERT_MARGIN`]). Most participation moves are caught
/// earlier by the partner searches ([`P_PARTNER`]).
const SEARCH_BOUND: f64 = 0.4;
/// ... and that mode's participation must have changed at least this much since its
/// neighbours were searched (else the one searched longest ago is taken).
const SEARCH_LOSS: f64 = 0.02;
/// A scan from cold goes on past the answer until the bound is below this.
const SCAN_BOUND: f64 = 0.15;
/// Allowance for the participation error of the watched modes followed by one Newton step
/// (their participation is that of the predicted point, within ~1e-5 of the root): the
/// answer is certified when the bound plus this is below the threshold.
const CERT_MARGIN: f64 = 0.05;
/// A watched mode is followed by Newton's method from its prediction until a step is
/// below this (relative, usually the first); its participation is that of the last
/// evaluated point, within ~1e-5 of the root.
const CHEAP_ACCEPT: f64 = 1e-5;
/// A watched mode whose approximate participation is within this of the threshold is
/// solved to full accuracy before it is compared with the threshold.
const P_MARGIN: f64 = 0.02;
/// The answer is taken from its tracking step when that step was below this (relative):
/// Newton's error is then ~step² · λ/w ≤ 1e-14 · λ/w (w the distance to the nearer pole;
/// the warm path equals a cold solve to 1e-10 on every cycle of the circle, tested).
const ANSWER_ACCEPT: f64 = 1e-7;
/// Watched modes below this participation are followed one per cycle (the one followed
/// longest ago); the others every cycle. A mode not followed this cycle does not count in
/// the certificate; when that fails, all are followed before anything is rescanned.
const P_LAZY: f64 = 0.15;
/// A watched mode with at least this participation ...
const P_STRONG: f64 = 0.15;
/// ... whose kinetic energy is at least this much in one chain is mixing with that chain's
/// string mode (an avoided crossing): the partner across the chain's nearest pole is
/// searched and watched (two-level model: it holds about that share).
const P_PARTNER: f64 = 0.03;
/// Partner searches per cycle (bounds a warm cycle's cost; the rest wait a cycle).
const PARTNER_SEARCHES: usize = 1;
/// Modes a neighbour search may walk past (weak ones) on each side (bounds its cost).
const NEIGHBOUR_WALK: usize = 3;
/// Pole intervals a neighbour search may cross (bounds its cost; a neighbour farther away
/// is left to the rescan).
const NEIGHBOUR_INTERVALS: usize = 4;
/// A weakly followed mode (no mode reached the threshold at the last full scan) is the
/// same mode while its root stays within this (relative) of its prediction.
const WEAK_FOLLOW_TOL: f64 = 2e-3;
/// Cycles a weak mode is followed before the full scan is retried.
const WEAK_RESCAN_CYCLES: u32 = 16;
/// Phases (a warm cycle, a scan, the warm cycle that certifies a scan found over several
/// cycles) one cycle may go through before it stops; each one also stops at the budget.
const PHASES_PER_CYCLE: usize = 4;
/// A rescan starts at this fraction of the lowest watched mode's λ (the participation
/// moves among the watched modes; the modes below stay covered by the bound).
const RESCAN_WINDOW: f64 = 0.9;
/// Where the count alone shows the poles, a window rescan records the modes (past the
/// answer) up to this multiple of the highest watched mode's λ: the participation the
/// watched modes lose goes to their neighbours in avoided crossings (on the paper's
/// spatial robot with sag, within 1.1× of the highest watched mode; dense reference).
const RECORD_ABOVE: f64 = 1.1;

/// Why the end-effector mode had to be scanned for instead of tracked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum RescanReason {
    /// A cold start (or nothing watched).
    Cold,
    /// A watched mode was lost in its exact solve.
    Lost,
    /// The sum-rule bound did not certify the answer.
    Uncertified,
    /// No watched mode reached the threshold.
    NoneReached,
    /// The cycle's evaluation budget ran out before the warm cycle was done (not a rescan:
    /// the warm cycle is tried again in the next one).
    Starved,
}

/// Counters of the end-effector bookkeeping since the solver was built.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RescanCounts {
    /// Full scans from a cold start.
    pub cold_scans: u64,
    /// Watched modes lost (their Newton search left the pole interval or did not converge),
    /// and rescans because a mode was lost in its exact solve.
    pub lost: u64,
    /// Full scans because the sum-rule bound was not certified.
    pub uncertified_scans: u64,
    /// Neighbour searches.
    pub neighbour_searches: u64,
    /// Full scans because no watched mode reached the threshold.
    pub no_mode_scans: u64,
    /// Watched modes dropped (participation below 0.02).
    pub dropped: u64,
    /// Partner searches (avoided crossings ahead).
    pub partner_searches: u64,
    /// Cycles whose end-effector work did not fit in the cycle's evaluation budget
    /// ([`ModalParams::cycle_evaluations`](super::ModalParams::cycle_evaluations)) and was
    /// continued in the next cycle.
    pub starved_cycles: u64,
    /// Scans that ran over more than one cycle.
    pub continued_scans: u64,
}

impl RescanCounts {
    /// Count one rescan for `reason`.
    fn record(&mut self, reason: RescanReason) {
        match reason {
            RescanReason::Cold => self.cold_scans += 1,
            RescanReason::Lost => self.lost += 1,
            RescanReason::Uncertified => self.uncertified_scans += 1,
            RescanReason::NoneReached => self.no_mode_scans += 1,
            RescanReason::Starved => self.starved_cycles += 1,
        }
    }
}

/// The tracker's state between cycles: the watched modes and the bookkeeping.
#[derive(Debug, Clone)]
pub(super) struct EeTracker {
    /// Watched modes, ascending in λ and in index.
    members: [Member; MAX_MEMBERS],
    n_members: usize,
    /// Record roots with participation ≥ [`P_ADD`] during a scan.
    recording: bool,
    counts: RescanCounts,
    /// Warm cycles left before a failed full scan is retried.
    ee_skip: u32,
    /// Neighbour searches so far (orders the watched modes by their last search).
    search_count: u64,
    /// The sum rules of this cycle (copied in by each call).
    sums: SumRules,
    /// A scan in progress (continued over the cycles until done).
    scan: Option<ScanState>,
    /// Where the count alone shows the poles: a window rescan was started and no warm
    /// cycle has certified an answer since (the next rescan is then from zero).
    window_pending: bool,
    /// The last scan finished skipped a mode (`scan::ScanState::skipped`).
    skipped: bool,
    /// Warm cycles running that searched neighbours by the count to certify and did not
    /// (`gap`).
    gap_cycles: u32,
    /// A neighbour search by the count the budget cut (`gap`), continued next cycle.
    gap_cut: Option<gap::GapCut>,
}

impl EeTracker {
    /// Nothing watched.
    pub(super) fn new() -> EeTracker {
        EeTracker {
            members: [Member::default(); MAX_MEMBERS],
            n_members: 0,
            recording: false,
            counts: RescanCounts::default(),
            ee_skip: 0,
            search_count: 0,
            sums: SumRules::traces(f64::NAN, f64::NAN),
            scan: None,
            window_pending: false,
            skipped: false,
            gap_cycles: 0,
            gap_cut: None,
        }
    }

    /// The bookkeeping counters.
    pub(super) fn counts(&self) -> RescanCounts {
        self.counts
    }

    /// Forget the watched modes (the next tracked call scans).
    pub(super) fn reset(&mut self) {
        self.n_members = 0;
        self.ee_skip = 0;
        self.scan = None;
        self.window_pending = false;
        self.gap_cycles = 0;
        self.gap_cut = None;
    }

    /// A scan is in progress (the end-effector answer is being worked on over the cycles).
    pub(super) fn scanning(&self) -> bool {
        self.scan.is_some()
    }

    /// The lowest mode whose participation reaches the threshold, by a scan from zero
    /// (`first` is the known first root, not solved again).
    pub(super) fn ee_mode<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        sums: SumRules,
        first: &Root,
    ) -> Result<Root, ModalError> {
        self.sums = sums;
        if first.ee_participation >= f.params.ee_participation_min {
            return Ok(*first);
        }
        let start = f.evaluations();
        self.scan = Some(ScanState::from_zero(&f.view, first.lambda));
        let r = match self.scan_step(f) {
            ScanStep::Done(r) => r,
            ScanStep::Paused => {
                self.scan = None;
                Err(ModalError::NoConvergence {
                    evaluations: f.evaluations() - start,
                    lo: first.lambda,
                    hi: f64::INFINITY,
                })
            }
        };
        r.map(|mut r| {
            r.evaluations = f.evaluations() - start;
            r
        })
    }

    /// The end-effector mode, tracked from the last cycle when `warm` (the method:
    /// [`ModalSolver::ee_mode_tracked`](super::ModalSolver::ee_mode_tracked)), within the
    /// evaluations left in the cycle's budget. Ok(None): the work did not fit and goes on
    /// in the next cycle (a scan in progress, or a warm cycle cut short).
    pub(super) fn ee_mode_tracked<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        sums: SumRules,
        first: &Root,
        warm: bool,
    ) -> Result<Option<Root>, ModalError> {
        self.sums = sums;
        let start = f.evaluations();
        let thr = f.params.ee_participation_min;
        if first.ee_participation >= thr {
            self.n_members = 0;
            self.ee_skip = 0;
            self.scan = None;
            return Ok(Some(*first));
        }
        if !warm {
            self.ee_skip = 0;
            self.scan = None;
            self.n_members = 0;
        } else if self.scan.is_some() {
            // A scan continued: what it watched was found at earlier poses.
            self.age_members();
        } else if self.ee_skip > 0 {
            if let Some(mut r) = self.follow_weak(f, thr) {
                r.evaluations = f.evaluations() - start;
                return Ok(Some(r));
            }
            if f.exhausted() {
                self.counts.record(RescanReason::Starved);
                return Ok(None);
            }
        }
        let r = self.ee_phases(f, first, thr);
        if let Ok(None) = r {
            self.counts.record(RescanReason::Starved);
        }
        r.map(|o| {
            o.map(|mut r| {
                r.evaluations = f.evaluations() - start;
                r
            })
        })
    }

    /// Weak episode: no mode reached the threshold at the last full scan; follow the most
    /// end-effector-like mode and rescan fully every [`WEAK_RESCAN_CYCLES`] cycles. Some(its
    /// root) while it stays below the threshold; None (nothing watched) when a scan is due.
    fn follow_weak<P: Condensed>(&mut self, f: &mut RootFinder<'_, P>, thr: f64) -> Option<Root> {
        self.ee_skip -= 1;
        if self.n_members == 1 {
            let m = self.members[0];
            let pred = predict(&m);
            let exact = f.params.newton_accept;
            if let Some(t) = track_root(f, pred, exact) {
                if (t.root.lambda - pred).abs() <= WEAK_FOLLOW_TOL * m.lambda {
                    self.members[0] = t.member(m.lambda);
                    if t.root.ee_participation < thr {
                        return Some(t.root);
                    }
                }
            }
        }
        self.ee_skip = 0;
        self.n_members = 0;
        None
    }

    /// Watch the first root: branch 0 below the lowest pole, index 0.
    fn watch_first<P: Condensed>(&mut self, f: &RootFinder<'_, P>, first: &Root) {
        let lp = f.view.lowest_pole().unwrap_or(f64::INFINITY);
        self.insert_member(Member::new(
            first.lambda,
            first.ee_participation,
            0,
            0,
            0.0,
            lp,
        ));
    }
}
