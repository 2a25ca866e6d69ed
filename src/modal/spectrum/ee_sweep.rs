//! The end-effector mode by an ascending sweep of the spectrum: the lowest mode whose
//! participation reaches the threshold, written once over [`Condensed`] and spread over
//! cycles by a per-cycle evaluation budget.
//!
//! The sweep solves modes 0, 1, 2, ... with the spectrum search and stops at the first
//! whose participation reaches the threshold: exact by construction (every mode below it
//! was solved and read), needing no sum rule. It costs what the modes below the answer
//! cost (a few tens of evaluations each), so it serves problems whose poles are not known
//! in closed form (sagged chains), where the pole-interval scan of the taut tracker has no
//! intervals to walk.
//!
//! **Budget.** Each call spends at most `budget` evaluations; a mode the budget cuts keeps
//! its narrowed bracket, and the next call re-probes its ends on that call's problem and
//! goes on from there (else it solves the mode afresh). A sweep over several cycles runs on
//! each cycle's problem in turn: the answer (λ and participation) is that of the pose of
//! the cycle that reports it, the modes below it were read at the poses of the cycles the
//! sweep passed them in. At most `max_modes` modes per sweep (each within the spectrum
//! search's own per-mode bound), over all its calls.

use super::search::{SpectrumSearch, SweepState};
use super::{Mode, SpectrumParams};
use crate::modal::engine::Condensed;
use crate::modal::ModalError;

/// A sweep in progress (plain data, kept between cycles).
#[derive(Debug, Clone, Copy)]
pub(in crate::modal) struct EeSweep {
    st: SweepState,
    /// The next mode to solve (0-based).
    next: usize,
    /// The bracket of `next` that the last call's budget cut (NaN: none).
    lo: f64,
    hi: f64,
}

/// What one call of [`ee_sweep`] did.
#[derive(Debug, Clone, Copy)]
pub(in crate::modal) enum SweepStep {
    /// The end-effector mode (its participation reaches the threshold).
    Done(Mode),
    /// The budget ran out: the sweep goes on in the next call.
    Paused,
}

/// Continue the sweep in `sweep` (start one when None) on problem `p` for at most `budget`
/// evaluations (`u32::MAX`: unlimited), until a mode's participation reaches `threshold`.
/// Errors: the search's own ([`ModalError::CountMismatch`], a per-mode
/// `NoConvergence`), and [`ModalError::NoEeMode`] when the modes (or `max_modes`) run out
/// first; `sweep` is None after an answer or an error.
pub(in crate::modal) fn ee_sweep<P: Condensed>(
    p: P,
    params: &SpectrumParams,
    threshold: f64,
    budget: u32,
    max_modes: u32,
    sweep: &mut Option<EeSweep>,
) -> Result<SweepStep, ModalError> {
    let carried = sweep.take();
    let mut w = carried.unwrap_or(EeSweep {
        st: SweepState::new(),
        next: 0,
        lo: f64::NAN,
        hi: f64::NAN,
    });
    let mut s = SpectrumSearch::resume(p, params, w.st);
    s.set_cycle_budget(budget);
    if carried.is_none() {
        s.start()?;
    }
    let total = s.problem().total_modes();
    loop {
        if w.next >= total || w.next >= max_modes as usize {
            return Err(ModalError::NoEeMode(w.next.min(u32::MAX as usize) as u32));
        }
        let r = if w.lo.is_finite() {
            s.mode_within(w.next, w.lo, w.hi)
        } else {
            s.mode(w.next)
        };
        match r {
            Ok(m) if m.ee_participation >= threshold => return Ok(SweepStep::Done(m)),
            Ok(_) => {
                w.next += 1;
                (w.lo, w.hi) = (f64::NAN, f64::NAN);
            }
            Err(ModalError::NoConvergence { lo, hi, .. }) if s.cut => {
                w.st = s.state();
                (w.lo, w.hi) = if lo > 0.0 && hi.is_finite() && lo < hi {
                    (lo, hi)
                } else {
                    (f64::NAN, f64::NAN)
                };
                *sweep = Some(w);
                return Ok(SweepStep::Paused);
            }
            Err(e) => return Err(e),
        }
    }
}
