//! The sagged chains' poles as the end-effector tracker sees them (`condensed`, while it
//! runs): a mode's coupling to one chain and that chain's poles by their keys; each pole
//! from [`SagPoles`](super::poles::SagPoles), found by its chain's own count.

use super::problem::SagChains;
use crate::modal::engine::{nearest_keyed_pole, quad, Coupling, PoleCursor};
use nalgebra::{Matrix6, Vector6};

/// A pole a mode couples to is searched again once its last search is more than this many
/// loads old (where the mode's share may start a partner search). Both poles next to the
/// mode are: which one is nearer decides the side of the partner search.
///
/// Why (bench circles, 3000 cycles, measured side by side): searching both at every load
/// costs up to 1.8× per cycle (the chains' one-by-one recurrence; spatial-paper N = 40 p50
/// 31.6 → 57.5 µs) and the extra partner searches starve the budget (age p99 22 → 52);
/// never searching them again leaves them stale by hundreds of cycles and the partner
/// searches miss (suspended-8 N = 10: age p99 22, 0 with this refresh); refreshing only the
/// nearer one: p99 14. Every 8 loads: p99 0 there, the other circles within ±1 cycle of the
/// count-only tracker's ages.
const REFRESH_LOADS: u32 = 8;
/// Poles of different chains closer than this (relative) are one pole of a scan over the
/// pole intervals. Why: each pole is found to 1e-10 (relative, `poles::POLE_BRACKET`), so
/// two equal poles (mirror-image cables) may come out that far apart; the scan evaluates
/// D 1e-9 (relative) inside each interval (`ee_tracker::scan`), past every pole merged.
const SCAN_POLE_MERGE: f64 = 5e-10;

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
    /// `scaled`: the last load's value scaled by pole j − 1's move since (`SagPoles::get`).
    pub(super) fn chain_pole(&self, i: usize, j: usize, near: f64, scaled: bool) -> f64 {
        let chain = &self.chains[i];
        let allowance = self.pole_allowance();
        let scale = || {
            if scaled {
                chain.string_scale()
            } else {
                f64::NAN
            }
        };
        self.poles
            .get(i, j, chain.blocked_modes(), near, allowance, scale, |x| {
                chain.eval(x)
            })
    }

    /// The next distinct pole above `a` over all chains (the scan over the pole intervals,
    /// [`Condensed::next_pole`](crate::modal::Condensed::next_pole)): each chain's cursor
    /// moved to its first pole above `a` (back first: the poles move between the cycles of
    /// a scan), poles of different chains within [`SCAN_POLE_MERGE`] (relative) of each
    /// other taken as one. (NaN, chain, number) when the cycle's budget ends before a pole
    /// it needs is found (the cursors then stand where they got).
    pub(super) fn chain_next_pole(&self, cursor: &mut PoleCursor, a: f64) -> (f64, usize, usize) {
        if !self.poles_shown() {
            return (f64::INFINITY, 0, 0);
        }
        let top = a * (1.0 + SCAN_POLE_MERGE);
        let mut b = (f64::INFINITY, 0, 0);
        for (i, next) in cursor.iter_mut().enumerate().take(self.n) {
            let mut j = (*next).max(1);
            while j > 1 {
                let p = self.chain_pole(i, j - 1, a, true);
                if p.is_nan() {
                    return (f64::NAN, i, j - 1);
                }
                if p <= top {
                    break;
                }
                j -= 1;
            }
            let mut pole = self.chain_pole(i, j, a, true);
            while pole <= top {
                j += 1;
                pole = self.chain_pole(i, j, a, true);
            }
            *next = j;
            if pole.is_nan() {
                return (f64::NAN, i, j);
            }
            if pole < b.0 {
                b = (pole, i, j);
            }
        }
        b
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

    /// The chain holding the largest share of the kinetic-energy norm vᵀ(−D'(x))v of mode
    /// shape v at the last counted evaluation (at x, D' = `dd`): (share, that chain's pole
    /// nearest x, whether above x, its key chain << 16 | number). The pole's identity is
    /// the chain's count at x; its value is the last search's (the poles move little
    /// between cycles), searched at this load when that search is more than
    /// [`REFRESH_LOADS`] loads old. Below `share_min` (no partner search starts from the
    /// mode) no pole: (share, NaN, false, `u32::MAX`).
    pub(super) fn chain_coupling(
        &self,
        x: f64,
        dd: &Matrix6<f64>,
        v: &Vector6<f64>,
        share_min: f64,
    ) -> Coupling {
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
        let poles = self.chains[i].blocked_modes();
        let share = best.0 / kin;
        if share < share_min {
            // No partner search starts from this mode: its pole is not needed.
            return (share, f64::NAN, false, u32::MAX);
        }
        // As the last search found it; searched at this load where that search is older
        // than REFRESH_LOADS loads (or never).
        let pole = |k: usize| {
            let (v, age) = self.poles.estimate(i, k, poles);
            if v.is_nan() || age > REFRESH_LOADS {
                self.chain_pole(i, k, x, false)
            } else {
                v
            }
        };
        nearest_keyed_pole(share, x, i, j, pole(j), pole(j + 1))
    }
}
