//! The scan over the pole intervals of D in ascending order: every root in each interval,
//! until one reaches the participation threshold (and, while recording, until the sum-rule
//! bound is low enough).

use super::member::Member;
use super::{EeTracker, MAX_MEMBERS, P_ADD, SCAN_BOUND};
use crate::modal::dynamic_stiffness::{LoadedChains, MAX_CHAINS};
use crate::modal::first_mode::RootFinder;
use crate::modal::{ModalError, Root};

/// Poles of different chains closer than this (relative) are one pole of the scan.
const POLE_MERGE: f64 = 1e-12;
/// Roots within this (relative) of the scan's `skip_to` count as already known.
const SKIP_TOL: f64 = 1e-9;
/// A rescan from a window skips roots up to this much (relative) below the window, so
/// that a root exactly at it is found.
pub(super) const WINDOW_EDGE: f64 = 1e-12;
/// Evaluation points sit this far (relative to the pole) inside a pole interval ...
const INSET_REL: f64 = 1e-9;
/// ... but never past this fraction of a narrow interval.
const INSET_MAX_FRACTION: f64 = 0.25;

/// Evaluation point inset from a pole at x into an interval of width w: never past a
/// quarter of a narrow interval (nearly coincident poles of different chains).
pub(super) fn inset(w: f64, x: f64) -> f64 {
    (INSET_REL * x).min(INSET_MAX_FRACTION * w)
}

/// The next distinct pole above `a` over all chains, advancing each chain's pole cursor
/// `next_pole` past `a`.
fn next_distinct_pole(p: &LoadedChains, next_pole: &mut [usize; MAX_CHAINS], a: f64) -> f64 {
    let mut b = f64::INFINITY;
    for i in 0..p.n_chains {
        let mut j = next_pole[i];
        let mut pole = p.chains[i].pole(j);
        while pole <= a * (1.0 + POLE_MERGE) && pole.is_finite() {
            j += 1;
            pole = p.chains[i].pole(j);
        }
        next_pole[i] = j;
        b = b.min(pole);
    }
    b
}

/// The roots of the pole interval (a, b), evaluated at `lo` (a⁺) and `hi_eval` (b⁻): the
/// blocked count there and the branches [na, nb) that have a root in it.
fn interval_branches(
    f: &mut RootFinder<'_>,
    a: f64,
    b: f64,
    lo: f64,
    hi_eval: f64,
) -> (u32, usize, usize) {
    let mut below = 0;
    let na = if a == 0.0 {
        0
    } else {
        let e = f.eval(lo);
        below = e.below;
        e.eig().negatives()
    };
    let nb = if b.is_finite() {
        let e = f.eval(hi_eval);
        below = e.below;
        e.eig().negatives()
    } else {
        f.problem.dim
    };
    (below, na, nb)
}

impl EeTracker {
    /// Scan upward from the pole interval containing `start` (rad²/s²) for the first root
    /// with participation ≥ the threshold, skipping roots at or below `skip_to`, and giving
    /// up above `limit`. While recording, every root with participation ≥ [`P_ADD`] is
    /// watched and the scan goes on past the answer until the sum-rule bound is below
    /// [`SCAN_BOUND`] (within the same bounds); the answer is the same.
    pub(super) fn ee_scan(
        &mut self,
        f: &mut RootFinder<'_>,
        start: f64,
        skip_to: f64,
        limit: f64,
    ) -> Result<Root, ModalError> {
        let begin = f.evaluations();
        let thr = f.params.ee_participation_min;
        let mut best: Option<Root> = None;
        let mut answer: Option<Root> = None;
        let mut a = 0.0f64;
        // Each chain's next pole number (the scan's cursor).
        let mut next_pole = [1usize; MAX_CHAINS];
        for i in 0..f.problem.n_chains {
            let (lo, _) = f.problem.chains[i].poles_around(start);
            a = a.max(lo);
        }
        'scan: for _ in 0..f.params.max_scan_intervals {
            if f.evaluations() - begin > f.params.max_scan_evaluations {
                break;
            }
            let b = next_distinct_pole(f.problem, &mut next_pole, a);
            if a > limit {
                break;
            }
            // Evaluation points just inside (a, b): never past the middle of a narrow
            // interval (nearly coincident poles of different chains).
            let lo = if a == 0.0 { 0.0 } else { a + inset(b - a, a) };
            let hi_eval = if b.is_finite() {
                b - inset(b - a, b)
            } else {
                f64::INFINITY
            };
            let skip_interval = b.is_finite() && hi_eval <= skip_to * (1.0 + SKIP_TOL);
            if !skip_interval {
                // Blocked count of the interval (index of its lowest root).
                let (below, na, nb) = interval_branches(f, a, b, lo, hi_eval);
                for branch in na..nb {
                    let hi = if b.is_finite() {
                        hi_eval
                    } else {
                        f64::INFINITY
                    };
                    let guess = if hi.is_finite() {
                        0.5 * (lo + hi)
                    } else {
                        2.0 * lo.max(skip_to).max(1.0)
                    };
                    let mut r = match f.branch_root_with(branch, lo, hi, 0.0, b, guess, true) {
                        Ok(r) => r,
                        // Collecting past the answer: keep what was found.
                        Err(_) if answer.is_some() => break 'scan,
                        Err(e) => return Err(e),
                    };
                    if r.lambda <= skip_to * (1.0 + SKIP_TOL) {
                        continue;
                    }
                    if self.recording && r.ee_participation >= P_ADD {
                        self.insert_member(Member::new(
                            r.lambda,
                            r.ee_participation,
                            below + branch as u32,
                            branch,
                            a,
                            b,
                        ));
                    }
                    if answer.is_none() && r.ee_participation >= thr {
                        r.evaluations = f.evaluations() - begin;
                        if !self.recording {
                            return Ok(r);
                        }
                        answer = Some(r);
                    }
                    if let Some(ans) = answer {
                        if self.unwatched_bound(ans.lambda) < SCAN_BOUND
                            || self.n_members == MAX_MEMBERS
                        {
                            break 'scan;
                        }
                    }
                    if best.is_none_or(|b| r.ee_participation > b.ee_participation) {
                        best = Some(r);
                    }
                }
            }
            if !b.is_finite() {
                break;
            }
            a = b;
        }
        if let Some(mut r) = answer {
            r.evaluations = f.evaluations() - begin;
            return Ok(r);
        }
        // No mode reaches the threshold within the bounds: the most end-effector-like mode
        // found (its participation, below the threshold, says so).
        match best {
            Some(mut r) => {
                r.evaluations = f.evaluations() - begin;
                Ok(r)
            }
            None => Err(ModalError::NoEeMode(f.params.max_scan_intervals)),
        }
    }
}
