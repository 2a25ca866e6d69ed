//! The inverse query: the smallest T_min (N) for which f1 at a pose reaches a required
//! frequency (Hz). Runs the forward [`Pipeline`](super::pipeline::Pipeline) on the
//! estimator's second set of buffers, so the cycle's warm state is untouched. No allocation.

use super::{Estimator, EstimatorError, InputError, TminQueryError};
use crate::kinematics::Pose;
use crate::modal::lambda_to_hz;
use crate::scene::MAX_CABLES;

/// Low end of the full bracket, as a fraction of T_max: positive, so every cable keeps a
/// tension floor, and so small that an answer there means T_min ≈ 0 suffices.
const BRACKET_LO_FRACTION: f64 = 1e-6;
/// Lower end of the bracket tried first around a hint (the answer moves little between
/// successive requests).
const HINT_LO_FACTOR: f64 = 0.98;
/// Upper end of the bracket tried first around a hint.
const HINT_HI_FACTOR: f64 = 1.02;
/// Bisection steps on the feasibility boundary when T_max itself is infeasible: 2⁻⁵⁰ of the
/// bracket is finer than [`T_MIN_TOL_REL`], which usually stops it first.
const FEASIBILITY_BISECTIONS: usize = 50;
/// Width, relative to T_max, at which a T_min bracket is resolved (a few ulps of T_max).
const T_MIN_TOL_REL: f64 = 1e-12;
/// Regula-falsi steps at most: Illinois converges superlinearly, so this bound is only hit
/// when the forward model is not smooth in T_min.
const REFINE_MAX_STEPS: usize = 80;
/// An f1 at or above the requirement by at most this much (relative) is the answer; the
/// eigen solver resolves f1 to ~1e-12 relative, so this is reachable.
const F1_TOL_REL: f64 = 1e-10;
/// Illinois modification: the residual of an end kept twice in a row is scaled by this, so
/// regula falsi does not stall with one end fixed.
const ILLINOIS_SCALE: f64 = 0.5;
/// The inverse query accepts the tensions at any structure-matrix rank.
const ANY_RANK: u32 = 0;

/// The answer to "which T_min reaches f1 ≥ f_required at this pose".
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TminAnswer {
    /// The smallest T_min found, N (within the bracket tolerance).
    pub t_min_n: f64,
    /// f1 at that T_min, Hz (≥ the requirement up to 1e-9 relative).
    pub f1_hz: f64,
    /// Evaluations of the forward model (tensions + f1) spent.
    pub evaluations: u32,
}

/// The state of one query: the last root (warm start of the next) and the evaluations spent.
struct Search<'p> {
    pose: &'p Pose,
    warm: Option<f64>,
    evals: u32,
}

impl Estimator {
    /// The smallest T_min (N) for which f1 at `pose` reaches `f_required_hz` (the paper's
    /// conclusion 4), on the fast path: regula falsi (Illinois) on f1(T)² − f², which is
    /// nearly linear in T_min (f1 ∝ √T_min), bracketed in [10⁻⁶ T_max, T_max] (or the largest
    /// feasible T_min below T_max), at most 80 forward evaluations. Uses its own scratch
    /// solvers: the cycle's warm state is untouched. No allocation.
    ///
    /// The query is uniform: the answer is one T_min for every cable (with each cable's
    /// upper bound from the scene), whatever per-cable lower bounds the cycle was given
    /// ([`Self::update_with_bounds`]) and whatever per-cable t_min the scene has.
    pub fn t_min_for_f1(
        &mut self,
        pose: &Pose,
        f_required_hz: f64,
    ) -> Result<TminAnswer, TminQueryError> {
        self.t_min_for_f1_near(pose, f_required_hz, None)
    }

    /// [`Self::t_min_for_f1`] warm-started from `hint` (N: the last answer, or the current
    /// T_min): a ±2 % bracket around it is tried first (two evaluations, then a few
    /// regula-falsi steps), the full search only when the answer is not in it. A service
    /// answering margin requests every cycle pays a few evaluations per request.
    pub fn t_min_for_f1_near(
        &mut self,
        pose: &Pose,
        f_required_hz: f64,
        hint: Option<f64>,
    ) -> Result<TminAnswer, TminQueryError> {
        if !(f_required_hz.is_finite() && f_required_hz > 0.0) {
            return Err(TminQueryError::BadRequirement(f_required_hz));
        }
        if !pose.is_finite() {
            return Err(InputError::NonFinitePose.into());
        }
        if !pose.has_unit_quaternion(self.params.quaternion_tol) {
            return Err(InputError::NonUnitQuaternion.into());
        }
        self.inverse
            .set_pose(&self.scene, pose)
            .map_err(EstimatorError::from)?;
        self.inverse.tension.reset_warm_start();
        let mut s = Search {
            pose,
            warm: None,
            evals: 0,
        };
        let t_max = self.scene.t_max_n;
        let lo0 = BRACKET_LO_FRACTION * t_max;
        if let Some(h) = hint.filter(|h| h.is_finite() && *h > lo0 && *h < t_max) {
            let (a, b) = (
                (HINT_LO_FACTOR * h).max(lo0),
                (HINT_HI_FACTOR * h).min(t_max),
            );
            if let (Ok(fa), Ok(fb)) = (self.inverse_f1(&mut s, a), self.inverse_f1(&mut s, b)) {
                if fa < f_required_hz && fb >= f_required_hz {
                    return self.inverse_refine(&mut s, f_required_hz, (a, fa), (b, fb));
                }
            }
        }
        let (hi, f_hi) = self.largest_feasible(&mut s, lo0)?;
        if f_hi < f_required_hz {
            return Err(TminQueryError::Unreachable {
                required_hz: f_required_hz,
                f1_max_hz: f_hi,
                t_min_n: hi,
            });
        }
        let lo = lo0;
        let f_lo = self.inverse_f1(&mut s, lo)?;
        if f_lo >= f_required_hz {
            return Ok(TminAnswer {
                t_min_n: lo,
                f1_hz: f_lo,
                evaluations: s.evals,
            });
        }
        self.inverse_refine(&mut s, f_required_hz, (lo, f_lo), (hi, f_hi))
    }

    /// The largest feasible T_min (N) and its f1 (Hz): T_max itself, or bisect the
    /// feasibility boundary between `lo0` (which must be feasible) and T_max.
    fn largest_feasible(
        &mut self,
        s: &mut Search<'_>,
        lo0: f64,
    ) -> Result<(f64, f64), EstimatorError> {
        let t_max = self.scene.t_max_n;
        if let Ok(f) = self.inverse_f1(s, t_max) {
            return Ok((t_max, f));
        }
        let mut ok = lo0;
        let mut f_ok = self.inverse_f1(s, ok)?;
        let mut bad = t_max;
        for _ in 0..FEASIBILITY_BISECTIONS {
            let mid = 0.5 * (ok + bad);
            match self.inverse_f1(s, mid) {
                Ok(f) => {
                    ok = mid;
                    f_ok = f;
                }
                Err(_) => bad = mid,
            }
            if bad - ok <= T_MIN_TOL_REL * t_max {
                break;
            }
        }
        Ok((ok, f_ok))
    }

    /// Regula falsi (Illinois) on f1(T)² − f² inside a bracket with f1(lo) < f ≤ f1(hi).
    fn inverse_refine(
        &mut self,
        s: &mut Search<'_>,
        f_required_hz: f64,
        (mut lo, f_lo): (f64, f64),
        (mut hi, f_hi): (f64, f64),
    ) -> Result<TminAnswer, TminQueryError> {
        let t_max = self.scene.t_max_n;
        let target = f_required_hz * f_required_hz;
        let mut g_lo = f_lo * f_lo - target;
        let mut g_hi = f_hi * f_hi - target;
        let mut best = (hi, f_hi);
        let mut side = 0i8;
        for _ in 0..REFINE_MAX_STEPS {
            let t = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
            let t = if t > lo && t < hi { t } else { 0.5 * (lo + hi) };
            let f = self.inverse_f1(s, t)?;
            let g = f * f - target;
            if g >= 0.0 {
                hi = t;
                g_hi = g;
                best = (t, f);
                if side == 1 {
                    g_lo *= ILLINOIS_SCALE;
                }
                side = 1;
            } else {
                lo = t;
                g_lo = g;
                if side == -1 {
                    g_hi *= ILLINOIS_SCALE;
                }
                side = -1;
            }
            if (best.1 - f_required_hz) <= F1_TOL_REL * f_required_hz
                || hi - lo <= T_MIN_TOL_REL * t_max
            {
                break;
            }
        }
        Ok(TminAnswer {
            t_min_n: best.0,
            f1_hz: best.1,
            evaluations: s.evals,
        })
    }

    /// f1 (Hz) at the search's pose (geometry already set) for T_min = `t_min_n`.
    fn inverse_f1(&mut self, s: &mut Search<'_>, t_min_n: f64) -> Result<f64, EstimatorError> {
        s.evals += 1;
        // The query is uniform: the same T_min for every cable (per-cable set-points do not
        // enter it).
        let uniform = [t_min_n; MAX_CABLES];
        let n = self.scene.n_cables();
        let r = self.inverse.first_root(
            &self.scene,
            s.pose,
            &uniform[..n],
            ANY_RANK,
            s.warm,
            |_| {},
        )?;
        s.warm = Some(r.lambda);
        Ok(lambda_to_hz(r.lambda))
    }
}
