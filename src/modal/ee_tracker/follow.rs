//! One warm cycle of the tracker: follow the watched modes, search the partners of strong
//! ones and the neighbours where participation is missing, pick the answer and certify it
//! with the sum-rule bound.

use super::member::{predict, SearchSide};
use super::track::{neighbour, partner, track_root};
use super::{
    EeTracker, RescanReason, ANSWER_ACCEPT, CERT_MARGIN, CHEAP_ACCEPT, NEIGHBOUR_WALK,
    PARTNER_SEARCHES, P_ADD, P_DROP, P_LAZY, P_MARGIN, P_PARTNER, P_STRONG, SEARCH_BOUND,
    SEARCH_LOSS,
};
use crate::modal::engine::Condensed;
use crate::modal::first_mode::RootFinder;
use crate::modal::Root;

/// A followed root farther than this (relative) from its prediction is another mode that
/// Newton converged to: still a mode, but without a history.
const JUMP_TOL: f64 = 2e-2;
/// The two-level model's 1 − share is floored at this (a share near 1 would put the
/// partner at infinity).
const TWO_LEVEL_MIN_GAP: f64 = 0.05;
/// A partner counts as watched when a watched mode across the pole lies within this many
/// times the predicted distance from the pole ...
const PARTNER_REACH: f64 = 2.0;
/// ... (plus this much of the pole, relative, for a prediction at the pole) ...
const PARTNER_REACH_MIN: f64 = 1e-6;
/// ... and holds at least this fraction of the share it is expected to hold.
const PARTNER_HELD: f64 = 0.5;
/// The partner across one pole is searched again only once the share has grown by this
/// factor since the last search.
const PARTNER_REGROWTH: f64 = 2.0;

impl EeTracker {
    /// One warm cycle of the watched modes; Err(reason) when a full scan is needed.
    pub(super) fn track_watched<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        thr: f64,
    ) -> Result<Root, RescanReason> {
        self.follow_members(f, false);
        self.partners_and_answer(f, thr)
    }

    /// Follow the watched modes one step: every one with participation ≥ [`P_LAZY`] and
    /// the weak one followed longest ago (`stale_only`: those not followed this cycle).
    /// Then keep them in index order, distinct, and drop the weak ones.
    fn follow_members<P: Condensed>(&mut self, f: &mut RootFinder<'_, P>, stale_only: bool) {
        let mut rr = usize::MAX;
        if !stale_only {
            let mut oldest = 0;
            for (k, m) in self.members[..self.n_members].iter_mut().enumerate() {
                m.age += 1;
                if m.p < P_LAZY && m.age > oldest {
                    oldest = m.age;
                    rr = k;
                }
            }
        }
        let mut i = 0;
        while i < self.n_members {
            let m = self.members[i];
            let follow = if stale_only {
                m.age > 0
            } else {
                m.p >= P_LAZY || i == rr
            };
            if !follow {
                i += 1;
                continue;
            }
            let pred = predict(&m);
            match track_root(f, pred, CHEAP_ACCEPT) {
                Some(t) => {
                    // A root far from the prediction is another mode that Newton converged
                    // to: still a mode, but without a history.
                    let jumped =
                        t.index != m.index || (t.root.lambda - pred).abs() > JUMP_TOL * m.lambda;
                    let mut n = t.member(if jumped { f64::NAN } else { m.lambda });
                    if !jumped {
                        n.p_ref = m.p_ref;
                        n.gap_ref = m.gap_ref;
                        n.searched = m.searched;
                        n.last_side = m.last_side;
                        n.partner_key = m.partner_key;
                        n.partner_share = m.partner_share;
                        if m.age > 1 {
                            // The λ one cycle ago, interpolated over the gap.
                            n.prev = t.root.lambda - (t.root.lambda - m.lambda) / m.age as f64;
                            n.prev2 = f64::NAN;
                        } else {
                            n.prev2 = m.prev;
                        }
                    }
                    self.members[i] = n;
                    i += 1;
                }
                // The cycle's budget ran out: the rest stay unfollowed this cycle.
                None if f.exhausted() => break,
                None => {
                    self.counts.lost += 1;
                    self.remove_member(i);
                }
            }
        }
        self.tidy_members();
    }

    /// Keep the watched modes in index order and distinct (two that converged to one mode
    /// are one), and drop those followed this cycle below [`P_DROP`].
    fn tidy_members(&mut self) {
        for i in 1..self.n_members {
            let mut k = i;
            while k > 0 && self.members[k - 1].index > self.members[k].index {
                self.members.swap(k - 1, k);
                k -= 1;
            }
        }
        let mut i = 1;
        while i < self.n_members {
            if self.members[i].index == self.members[i - 1].index {
                // Keep the one followed this cycle.
                let stale = if self.members[i].age > 0 { i } else { i - 1 };
                self.remove_member(stale);
            } else {
                i += 1;
            }
        }
        let mut i = 0;
        while i < self.n_members {
            if self.members[i].age == 0 && self.members[i].p < P_DROP {
                self.counts.dropped += 1;
                self.remove_member(i);
            } else {
                i += 1;
            }
        }
    }

    /// The rest of a warm cycle after [`Self::follow_members`]: partners of strong modes,
    /// the answer, neighbour searches, the certificate.
    fn partners_and_answer<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        thr: f64,
    ) -> Result<Root, RescanReason> {
        self.search_partners(f);
        let by_count = !f.view.poles_known() && f.budget != u32::MAX;
        let mut answer = match self.select_answer(f, thr) {
            // Where the count alone shows the poles: the neighbours searched by the count
            // first (`gap`).
            Err(RescanReason::NoneReached) if by_count => self.answer_by_gaps(f, thr)?,
            r => r?,
        };
        // The neighbour search walks the closed-form poles: only where they are known.
        if f.view.poles_known() && self.unwatched_bound_with(answer.lambda, true) > SEARCH_BOUND {
            self.search_neighbours(f);
            answer = self.select_answer(f, thr)?;
        }
        // The certificate's bound (computed once per change of the watched modes: each is
        // three 6 × 6 symmetric eigen-solves).
        let mut bound = self.unwatched_bound(answer.lambda);
        if bound + CERT_MARGIN >= thr && self.members[..self.n_members].iter().any(|m| m.age > 0) {
            // Follow the rest too before giving up.
            self.follow_members(f, true);
            answer = self.select_answer(f, thr)?;
            bound = self.unwatched_bound(answer.lambda);
        }
        if by_count && bound + CERT_MARGIN >= thr {
            // Where the count alone shows the poles and a cycle's budget holds: the bound
            // split below the answer (the local form, `bound`) ...
            if self
                .split_bound(f, answer.lambda, thr - CERT_MARGIN)
                .is_some_and(|b| b + CERT_MARGIN < thr)
            {
                return Ok(answer);
            }
        }
        if by_count {
            // ... and the unwatched neighbours searched by the count (`gap`).
            (answer, bound) = self.certify_by_gaps(f, thr, answer, bound)?;
        }
        if bound + CERT_MARGIN >= thr {
            return Err(RescanReason::Uncertified);
        }
        Ok(answer)
    }

    /// Avoided crossings ahead: a strong watched mode that shares enough of its kinetic
    /// energy with one chain is mixing with that chain's string mode, which sits just
    /// across the chain's nearest pole; watch it before the participation moves there (at
    /// most [`PARTNER_SEARCHES`] searches).
    fn search_partners<P: Condensed>(&mut self, f: &mut RootFinder<'_, P>) {
        let mut searches = 0;
        let mut i = 0;
        while i < self.n_members && searches < PARTNER_SEARCHES {
            let m = self.members[i];
            i += 1;
            if m.age > 0 || m.p < P_STRONG || m.share < P_PARTNER || !m.pole.is_finite() {
                continue;
            }
            // Two-level model (the mode and the chain's string mode): the partner sits at
            // λ_m − (λ_m − pole)/(1 − share), across the pole.
            let pred = m.lambda - (m.lambda - m.pole) / (1.0 - m.share).max(TWO_LEVEL_MIN_GAP);
            let reach = PARTNER_REACH * (pred - m.pole).abs() + PARTNER_REACH_MIN * m.pole;
            let watched = self.members[..self.n_members].iter().any(|x| {
                (if m.pole_up {
                    x.lambda > m.pole
                } else {
                    x.lambda < m.pole
                }) && (x.lambda - m.pole).abs() <= reach
                    && x.p >= PARTNER_HELD * m.share
            });
            if watched
                || (m.pole_key == m.partner_key && m.share < PARTNER_REGROWTH * m.partner_share)
            {
                continue;
            }
            self.members[i - 1].partner_key = m.pole_key;
            self.members[i - 1].partner_share = m.share;
            searches += 1;
            self.counts.partner_searches += 1;
            // The pole at this load, by its key (the coupling may give the value a search
            // found at an earlier load: the sagged chains); the two-level estimate moves
            // with it. Not found within the budget: this partner search is skipped (as one
            // that found nothing; retrying it each cycle measured worse along suspended-8's
            // circle at N = 40, where the sweeps need the budget).
            let (c, j) = ((m.pole_key >> 16) as usize, (m.pole_key & 0xffff) as usize);
            let pole = f.view.keyed_pole(c, j).unwrap_or(m.pole);
            if !pole.is_finite() {
                continue;
            }
            let pred = pred + (pole - m.pole);
            if let Some(t) = partner(f, pole, m.pole_up, pred) {
                let known = self.members[..self.n_members]
                    .iter()
                    .any(|x| x.index == t.index);
                if !known && t.root.ee_participation >= P_DROP {
                    self.insert_member(t.member(f64::NAN));
                    // Restart: insertion shifted the members.
                    i = 0;
                }
            }
        }
    }

    /// Search the neighbours of the watched mode whose participation changed most since
    /// its neighbours were last searched (first those never searched): a flood fill towards
    /// the participation the watched modes miss.
    fn search_neighbours<P: Condensed>(&mut self, f: &mut RootFinder<'_, P>) {
        let mut pick = None;
        let mut change = SEARCH_LOSS;
        let mut oldest = (u64::MAX, 0);
        for (k, m) in self.members[..self.n_members].iter().enumerate() {
            let c = if m.p_ref.is_nan() {
                f64::INFINITY
            } else {
                (m.p - m.p_ref).abs()
            };
            if c >= change {
                change = c;
                pick = Some(k);
            }
            if m.searched < oldest.0 {
                oldest = (m.searched, k);
            }
        }
        // Nothing changed: the one searched longest ago.
        let k = pick.unwrap_or(oldest.1);
        self.counts.neighbour_searches += 1;
        self.search_count += 1;
        let m = self.members[k];
        // One side per search: first towards the nearer pole (an avoided crossing
        // partner sits across it), then alternately.
        let up = match m.last_side {
            SearchSide::None => m.b - m.lambda < m.lambda - m.a,
            SearchSide::Below => true,
            SearchSide::Above => false,
        };
        self.members[k].last_side = if up {
            SearchSide::Above
        } else {
            SearchSide::Below
        };
        // Both sides searched: the mode is settled until its participation changes.
        if m.last_side != SearchSide::None {
            self.members[k].p_ref = m.p;
        }
        self.members[k].searched = self.search_count;
        // Walk past weak modes (up to NEIGHBOUR_WALK) to the first one worth watching.
        let mut from = m;
        for _ in 0..NEIGHBOUR_WALK {
            let target = if up {
                from.index + 1
            } else if from.index > 0 {
                from.index - 1
            } else {
                break;
            };
            if self.members[..self.n_members]
                .iter()
                .any(|x| x.index == target)
            {
                break;
            }
            let found = neighbour(f, &from, up);
            let Some(t) = found else {
                break;
            };
            let mut n = t.member(f64::NAN);
            if t.root.ee_participation >= P_ADD {
                n.p_ref = f64::NAN;
                self.insert_member(n);
                break;
            }
            from = n;
        }
    }

    /// The lowest watched mode with participation ≥ the threshold, solved to full accuracy
    /// (and so is any watched mode below it within [`P_MARGIN`] of the threshold);
    /// Err(NoneReached) when there is none, Err(Lost) when an exact solve fails.
    pub(super) fn select_answer<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        thr: f64,
    ) -> Result<Root, RescanReason> {
        let exact = f.params.newton_accept;
        for i in 0..self.n_members {
            let m = self.members[i];
            if m.age > 0 || m.p < thr - P_MARGIN {
                continue;
            }
            if m.step <= ANSWER_ACCEPT {
                // Followed this cycle by a Newton step this small: λ is within ~step² of
                // the root already.
                if m.p >= thr {
                    return Ok(Root {
                        lambda: m.lambda,
                        ee_participation: m.p,
                        evaluations: 0,
                        residual: m.residual,
                    });
                }
                continue;
            }
            let t = track_root(f, m.lambda, exact).ok_or(RescanReason::Lost)?;
            if t.index != m.index {
                return Err(RescanReason::Lost);
            }
            self.members[i].lambda = t.root.lambda;
            self.members[i].p = t.root.ee_participation;
            self.members[i].step = t.step;
            self.members[i].residual = t.root.residual;
            self.members[i].phi = t.phi;
            if t.root.ee_participation >= thr {
                return Ok(t.root);
            }
        }
        Err(RescanReason::NoneReached)
    }
}
