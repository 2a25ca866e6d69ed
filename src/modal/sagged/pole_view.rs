//! The sagged chains' poles as the searches see them (`condensed`, while the tracker runs):
//! pole intervals, the next pole of a scan, a mode's coupling to one chain; each pole from
//! [`SagPoles`](super::poles::SagPoles), found by its chain's own count.

use super::poles::POLE_MERGE;
use super::problem::SagChains;
use crate::modal::engine::{nearest_keyed_pole, quad, PoleCursor};
use crate::scene::MAX_CABLES;
use nalgebra::{Matrix6, Vector6};

/// The chains' poles as the searches see them (`condensed`: while `follow` is set).
impl SagChains {
    /// The poles are shown to the searches: the tracker asked for them and the chains are
    /// FEM chains (the continuous ones are seen through the count alone).
    #[inline]
    pub(super) fn poles_shown(&self) -> bool {
        self.follow && self.loaded && !self.continuous
    }

    /// Pole j (1-based; 0 gives 0, ∞ past the chain's last) of chain i of the loaded pose;
    /// a search never done before starts at `near` (rad²/s², NaN: none), a λ next to it
    /// (where the chain's count was j or j − 1).
    /// NaN when the cycle's budget (`Condensed::follow_poles`) ends before it is found.
    pub(super) fn chain_pole(&self, i: usize, j: usize, near: f64) -> f64 {
        let chain = &self.chains[i];
        let allowance = self.pole_allowance();
        self.poles
            .get(i, j, chain.blocked_modes(), near, allowance, |x| {
                chain.eval(x)
            })
    }

    /// Chain evaluations left before the cycle's budget ends (`u32::MAX`: unlimited).
    fn pole_allowance(&self) -> u32 {
        match self.pole_budget_end {
            None => u32::MAX,
            Some(end) => {
                let now = self.evaluations.wrapping_add(self.pole_evaluations());
                let left = end.wrapping_sub(now);
                // Past the end the difference wraps to a huge value: nothing left.
                if left > u32::MAX / 2 {
                    0
                } else {
                    left.saturating_mul(self.n.max(1) as u32)
                }
            }
        }
    }

    /// Evaluations of D spent on the pole searches (one per `n` chain evaluations).
    pub(super) fn pole_evaluations(&self) -> u32 {
        (self.poles.chain_evaluations() / self.n.max(1) as u64) as u32
    }

    /// The pole-free interval (a, b) around λ: each chain's poles next to its own count at
    /// λ (one count-only evaluation of the chains).
    pub(super) fn pole_interval_at(&self, lambda: f64) -> (f64, f64) {
        let mut below = [0u32; MAX_CABLES];
        if self.n > MAX_CABLES || self.pole_allowance() < self.n as u32 {
            return (f64::NAN, f64::NAN);
        }
        self.evaluate_into(lambda, false, |i, e| below[i] = e.below);
        self.poles.spend(self.n as u64);
        self.interval_of(&below[..self.n], lambda)
    }

    /// The pole-free interval around the last counted evaluation's λ.
    pub(super) fn last_interval(&self) -> (f64, f64) {
        self.interval_of(&self.last_below[..self.n], self.last_lambda)
    }

    /// The pole-free interval of the chains' counts `below` at `near` (rad²/s²):
    /// (max_i pole(i, below_i), min_i pole(i, below_i + 1)).
    fn interval_of(&self, below: &[u32], near: f64) -> (f64, f64) {
        (
            self.extreme(below, near, false),
            self.extreme(below, near, true),
        )
    }

    /// max_i pole(i, below_i) (`upper` false) or min_i pole(i, below_i + 1) (true), with as
    /// few pole searches as it can: the chain whose pole is estimated extreme (from this
    /// load's searches or the last ones') is searched, and every other chain is checked
    /// against that value by its count there (one count-only evaluation of all the chains):
    /// below_i poles strictly below it (lower side) or at most below_i (upper side) prove
    /// that chain's pole is not beyond it; only the chains it does not prove are searched.
    /// Each search can only move the extreme outward, so one check suffices.
    fn extreme(&self, below: &[u32], near: f64, upper: bool) -> f64 {
        let n = below.len();
        let idx = |i: usize| below[i] as usize + usize::from(upper);
        let mut best = if upper { f64::INFINITY } else { 0.0 };
        // Search chain i's pole and take it when beyond `best`; false when the budget cut
        // it (NaN: the extreme is unknown).
        let take = |i: usize, best: &mut f64| {
            let v = self.chain_pole(i, idx(i), near);
            if (upper && v < *best) || (!upper && v > *best) {
                *best = v;
            }
            !v.is_nan()
        };
        if n > MAX_CABLES {
            for i in 0..n {
                if !take(i, &mut best) {
                    return f64::NAN;
                }
            }
            return best;
        }
        let mut done = [false; MAX_CABLES];
        let mut lead: Option<(usize, f64)> = None;
        for i in 0..n {
            let est = self
                .poles
                .estimate(i, idx(i), self.chains[i].blocked_modes());
            if est.is_nan() {
                done[i] = true;
                if !take(i, &mut best) {
                    return f64::NAN;
                }
            } else if lead.is_none_or(|(_, e)| if upper { est < e } else { est > e }) {
                lead = Some((i, est));
            }
        }
        if let Some((k, _)) = lead {
            done[k] = true;
            if !take(k, &mut best) {
                return f64::NAN;
            }
        }
        let all = done[..n].iter().all(|&d| d);
        if all || !(best > 0.0 && best.is_finite()) {
            for i in (0..n).filter(|&i| !done[i]) {
                if !take(i, &mut best) {
                    return f64::NAN;
                }
            }
            return best;
        }
        if self.pole_allowance() < n as u32 {
            return f64::NAN;
        }
        let mut at = [0u32; MAX_CABLES];
        self.evaluate_into(best, false, |i, e| at[i] = e.below);
        self.poles.spend(n as u64);
        for i in (0..n).filter(|&i| !done[i]) {
            let proven = if upper {
                at[i] <= below[i]
            } else {
                at[i] >= below[i]
            };
            if !proven && !take(i, &mut best) {
                return f64::NAN;
            }
        }
        best
    }

    /// The lowest pole over the chains (NaN: the budget cut a search).
    pub(super) fn lowest(&self) -> f64 {
        let mut low = f64::INFINITY;
        for i in 0..self.n {
            let p = self.chain_pole(i, 1, f64::NAN);
            if p.is_nan() {
                return p;
            }
            low = low.min(p);
        }
        low
    }

    /// The next distinct pole above `a` over all chains, advancing each chain's cursor
    /// (first moved back to its first pole above `a`): (pole, chain, number).
    pub(super) fn next_distinct(&self, cursor: &mut PoleCursor, a: f64) -> (f64, usize, usize) {
        let mut b = (f64::INFINITY, 0, 0);
        for i in 0..self.n.min(cursor.len()) {
            let mut j = cursor[i].max(1);
            while j > 1 && self.chain_pole(i, j - 1, a) > a * (1.0 + POLE_MERGE) {
                j -= 1;
            }
            let mut pole = self.chain_pole(i, j, a);
            while pole <= a * (1.0 + POLE_MERGE) && pole.is_finite() {
                j += 1;
                pole = self.chain_pole(i, j, pole);
            }
            cursor[i] = j;
            if pole < b.0 {
                b = (pole, i, j);
            }
        }
        b
    }

    /// The chain holding the largest share of the kinetic-energy norm vᵀ(−D'(x))v of mode
    /// shape v at the last counted evaluation (at x, D' = `dd`): (share, that chain's pole
    /// nearest x, whether above x, its key chain << 16 | number).
    pub(super) fn chain_coupling(
        &self,
        x: f64,
        dd: &Matrix6<f64>,
        v: &Vector6<f64>,
    ) -> (f64, f64, bool, u32) {
        let none = (0.0, f64::NAN, false, u32::MAX);
        let kin = -quad(dd, v, self.dim);
        if !(kin > 0.0) {
            return none;
        }
        let mut best = (0.0, usize::MAX);
        for i in 0..self.n {
            let q = -self.chain_quad(i, &self.last_ds[i], v);
            if q > best.0 {
                best = (q, i);
            }
        }
        let i = best.1;
        if i == usize::MAX {
            return none;
        }
        let j = self.last_below[i] as usize;
        let (lo, hi) = (self.chain_pole(i, j, x), self.chain_pole(i, j + 1, x));
        nearest_keyed_pole(best.0 / kin, x, i, j, lo, hi)
    }
}
