//! Neighbour searches where the count alone shows the poles (the sagged chains) and a
//! cycle's budget holds: the unwatched spectral neighbour of a watched mode, searched in the
//! gap between the watched modes around it.
//!
//! The participation the watched modes lose goes to their spectral neighbours (avoided
//! crossings with the chains' string modes): on the paper's spatial robot with sag every
//! uncertified cycle along the circle had its missing participation in a mode one or two
//! indices from a watched one (the window rescans that followed found it there). Without
//! the chains' poles in closed form there are no pole intervals to walk (`track::neighbour`);
//! mode i is instead found by the spectrum search's count bisection and pole-free Newton
//! inside (λ of the nearest watched mode below i, λ of the nearest above), a bracket of a
//! few modes, then read by one step of `track::track_root` (its shape for the certificate,
//! its index checked). A search the cycle's budget cuts keeps its narrowed bracket and goes
//! on in the next cycle (widened by the pose's motion), so a search costs what it needs,
//! not what one cycle leaves. The same searches run when no watched mode reaches the
//! threshold (`EeTracker::answer_by_gaps`): the participation went to a neighbour there
//! too.

use super::member::SearchSide;
use super::track::track_root;
use super::{EeTracker, RescanReason, CERT_MARGIN, SEARCH_LOSS};
use crate::modal::engine::Condensed;
use crate::modal::first_mode::RootFinder;
use crate::modal::spectrum::SpectrumSearch;
use crate::modal::{ModalError, Root, SpectrumParams};

/// A certified warm cycle whose bound exceeds this searches one neighbour ahead of need
/// (the certificate fails at the threshold less `CERT_MARGIN`, 0.45 by default).
const GAP_BOUND: f64 = 0.3;
/// Searches an uncertified warm cycle may make (each ~10-20 evaluations; the budget stops
/// them first) ...
const GAP_SEARCHES: usize = 4;
/// ... and the cycles running it may go on in (the answer stale meanwhile) before the
/// window rescan takes over.
const GAP_CYCLES: u32 = 3;
/// A neighbour with no watched mode beyond it is searched within this factor (in λ) of the
/// watched mode it is the neighbour of (the participation the watched modes lose goes to
/// modes within ~1.4× of the answer on the paper's spatial robot with sag, dense
/// reference).
const GAP_SPAN: f64 = 1.5;
/// A search starts only with more than this many evaluations left in the cycle (its two
/// count probes and the evaluations kept for its end).
const GAP_MIN_LEFT: u32 = 5;
/// A cut search's bracket is widened by this (relative, each side) in the next cycle: a
/// mode moves by ~1e-4 per 1 ms cycle along the bench's circle.
const GAP_WIDEN: f64 = 1e-3;

/// A gap search the cycle's budget cut: mode `target` within (lo, hi), rad²/s².
#[derive(Debug, Clone, Copy)]
pub(super) struct GapCut {
    target: u32,
    lo: f64,
    hi: f64,
}

impl EeTracker {
    /// The neighbour searches of a warm cycle whose answer is `answer`. Certified by the
    /// bound but with the bound above [`GAP_BOUND`]: one search, ahead of need. Not
    /// certified: search (the neighbours of the watched modes whose participation changed
    /// first: where it went) until the bound certifies, at most [`GAP_SEARCHES`];
    /// Err(Starved) when the budget cut a search (it goes on next cycle, the finds
    /// watched), for at most [`GAP_CYCLES`] cycles running. `bound`: the certificate's bound
    /// for `answer`; returns the answer and its bound after the searches (the caller
    /// certifies it).
    pub(super) fn certify_by_gaps<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        thr: f64,
        mut answer: Root,
        mut bound: f64,
    ) -> Result<(Root, f64), RescanReason> {
        if bound + CERT_MARGIN < thr {
            self.gap_cycles = 0;
            if bound > GAP_BOUND && self.search_gap(f) {
                answer = self.select_answer(f, thr)?;
                bound = self.unwatched_bound(answer.lambda);
            }
            return Ok((answer, bound));
        }
        if self.gap_cycles >= GAP_CYCLES {
            self.gap_cycles = 0;
            self.gap_cut = None;
            return Ok((answer, bound));
        }
        self.gap_cycles += 1;
        for _ in 0..GAP_SEARCHES {
            if !self.search_gap(f) {
                break;
            }
            answer = self.select_answer(f, thr)?;
            bound = self.unwatched_bound(answer.lambda);
            if bound + CERT_MARGIN < thr {
                break;
            }
            if self.gap_cut.is_some() || f.exhausted() {
                // The budget cut the search: it goes on next cycle.
                return Err(RescanReason::Starved);
            }
        }
        Ok((answer, bound))
    }

    /// A warm cycle where no watched mode reached the threshold: the participation they
    /// lost went to their spectral neighbours (avoided crossings), so those are searched
    /// (the mode that lost most first, at most [`GAP_SEARCHES`]) before the window rescan,
    /// for at most [`GAP_CYCLES`] cycles running, as for an uncertified answer. The answer
    /// found still needs the certificate. Err(NoneReached) when the searches did not find
    /// it (the rescan follows); Err(Starved) when the budget cut a search (it goes on next
    /// cycle).
    pub(super) fn answer_by_gaps<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        thr: f64,
    ) -> Result<Root, RescanReason> {
        if self.gap_cycles >= GAP_CYCLES {
            self.gap_cycles = 0;
            self.gap_cut = None;
            return Err(RescanReason::NoneReached);
        }
        self.gap_cycles += 1;
        for _ in 0..GAP_SEARCHES {
            if !self.search_gap(f) {
                break;
            }
            match self.select_answer(f, thr) {
                Err(RescanReason::NoneReached) => {}
                r => return r,
            }
            if self.gap_cut.is_some() || f.exhausted() {
                return Err(RescanReason::Starved);
            }
        }
        Err(RescanReason::NoneReached)
    }

    /// One neighbour search (a cut one first); false when there is none to make.
    pub(super) fn search_gap<P: Condensed>(&mut self, f: &mut RootFinder<'_, P>) -> bool {
        if let Some(c) = self.gap_cut.take() {
            if !self.watched(c.target) {
                let (lo, hi) = (c.lo * (1.0 - GAP_WIDEN), c.hi * (1.0 + GAP_WIDEN));
                self.gap_root(f, c.target, lo, hi);
                return true;
            }
        }
        let Some((k, up)) = self.pick_gap() else {
            return false;
        };
        self.counts.neighbour_searches += 1;
        self.search_count += 1;
        let m = self.members[k];
        if m.last_side != SearchSide::None {
            // Both sides searched: settled until its participation changes.
            self.members[k].gap_ref = m.p;
        }
        self.members[k].last_side = if up {
            SearchSide::Above
        } else {
            SearchSide::Below
        };
        self.members[k].searched = self.search_count;
        let target = if up { m.index + 1 } else { m.index - 1 };
        let ms = &self.members[..self.n_members];
        let (lo, hi) = if up {
            let hi = ms
                .iter()
                .find(|x| x.index > target)
                .map_or(GAP_SPAN * m.lambda, |x| x.lambda);
            (m.lambda, hi)
        } else {
            let lo = ms
                .iter()
                .rev()
                .find(|x| x.index < target)
                .map_or(m.lambda / GAP_SPAN, |x| x.lambda);
            (lo, m.lambda)
        };
        self.gap_root(f, target, lo, hi);
        true
    }

    /// The watched mode whose neighbours to search and the side: the one whose
    /// participation changed most since it was found or its neighbours were searched (a
    /// loss counted fully, a gain half; at least [`SEARCH_LOSS`]), on a side whose
    /// neighbour is not watched (above first, then alternately); None when no watched mode
    /// qualifies.
    fn pick_gap(&mut self) -> Option<(usize, bool)> {
        let mut pick = None;
        let mut change = SEARCH_LOSS;
        for (k, m) in self.members[..self.n_members].iter().enumerate() {
            // What it lost counts fully, what it gained half (taken from neighbours that
            // may be watched already).
            let d = m.gap_ref - m.p;
            let c = if d.is_nan() {
                0.0
            } else {
                d.max(0.0) + 0.5 * (-d).max(0.0)
            };
            let open_up = !self.watched(m.index + 1);
            let open_down = m.index > 0 && !self.watched(m.index - 1);
            if !(open_up || open_down) || c < change {
                continue;
            }
            if c > change || pick.is_none() {
                let up = match m.last_side {
                    SearchSide::Above => !open_down,
                    _ => open_up,
                };
                change = c;
                pick = Some((k, up));
            }
        }
        pick
    }

    /// Whether mode `index` is watched.
    fn watched(&self, index: u32) -> bool {
        self.members[..self.n_members]
            .iter()
            .any(|x| x.index == index)
    }

    /// Search mode `target` in (lo, hi) and watch it; a search the budget cut is kept for
    /// the next cycle ([`GapCut`]).
    fn gap_root<P: Condensed>(&mut self, f: &mut RootFinder<'_, P>, target: u32, lo: f64, hi: f64) {
        if !(lo >= 0.0 && lo < hi && hi.is_finite()) {
            return;
        }
        if f.left() <= GAP_MIN_LEFT {
            // Too little left to probe the bracket: next cycle.
            self.gap_cut = Some(GapCut { target, lo, hi });
            return;
        }
        let params = SpectrumParams::default();
        let budget = f.left();
        let mut s = SpectrumSearch::new(&mut f.view, &params);
        s.set_cycle_budget(budget);
        let r = s.root_in(target as usize, lo, hi);
        let cut = s.cut;
        let lambda = match r {
            Ok(Some(l)) => l,
            Err(ModalError::NoConvergence { lo, hi, .. }) if cut => {
                self.gap_cut = Some(GapCut { target, lo, hi });
                return;
            }
            _ => return,
        };
        let exact = f.params.newton_accept;
        if let Some(t) = track_root(f, lambda, exact).filter(|t| t.index == target) {
            // Watched even when weak (dropped when next followed below `P_DROP`): the
            // other side's search does not look for it again meanwhile.
            self.insert_member(t.member(f64::NAN));
        }
    }
}
