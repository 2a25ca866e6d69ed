//! The inverse query: the smallest uniform T_min (N) for which f1 at a pose reaches a
//! required frequency f (Hz). Runs the forward model ([`Forward`](super::forward::Forward)) on
//! the estimator's second set of buffers, so the cycle's warm state is untouched. No
//! allocation; at most [`MAX_EVALUATIONS`] forward evaluations (tension distribution + f1).
//!
//! # The problem
//!
//! Write F(t) for f1 at the pose with every cable's lower bound t (upper bounds the scene's),
//! "ok" when the forward model answers there. Two facts shape the search:
//!
//! - **The ok set is a window [a, b], not [0, b].** With rigid (chord) cables every small t
//!   is feasible, but a sagging cable (`[effects] sag`) at a small end tension is slack (its
//!   tension would reach zero along it): below the window's floor a is "not reached yet",
//!   above its ceiling b the tension distribution is infeasible. On `suspended-8` at
//!   (4, 2.5, 1.5) m the window is about [21.9, 72.4] N of t ∈ (0, 8000] N, and it has a gap:
//!   the sagged tension distribution does not converge from 32.3 to 36.1 N. So the window is
//!   not assumed to be one interval below the answer.
//! - **F is not monotone.** The tension distribution is piecewise affine in t (one piece per
//!   active set: which cables sit at a bound), and when a cable leaves its bound the free
//!   cables' tensions can fall, and F with them. The paper robot at (0.0127, 0.2136, 0.1794) m
//!   has F = 9.08 Hz at 33 N, falling to 8.97 Hz at 74 N, then rising again. Within one piece
//!   the cable models are linear in the tensions (massless, fem and continuous elements: the
//!   geometric stiffness T/L; the rigid body's tension stiffness), so F² ∝ λ₁ = min over
//!   shapes of a Rayleigh quotient affine in t is concave in t: the requirement is met on one
//!   interval per piece, and F dips only where the active set changes.
//!
//! With sag every evaluation starts the tension distribution cold (from the chords), so F
//! is exactly the function a fresh estimator computes and an answer can be checked by
//! anyone. (The sagged distribution, the least Σ T² on the exact sagged equilibrium, has one
//! answer per pose; the cold start costs a few SQP iterations and removes any dependence on
//! the search's path.)
//!
//! # The search
//!
//! 1. **An ok point.** The forward model is tried at the hint (the T_min in force), the
//!    scene's T_min, t₀ = 10⁻⁶ T_max, T_max, then at [`SWEEP_POINTS`] points geometrically
//!    spaced between t₀ and T_max (ratio 10^(6/32) ≈ 1.54), until one is ok. None ok: the
//!    pose fails at every T_min (the first probe's error).
//! 2. **The top of the scan.** The smallest ok probe that meets the requirement (so the
//!    answer never exceeds a hint that already meets it); when none does, the ceiling b of
//!    the ok window: T_max when not infeasible, else bisection on "tensions infeasible or
//!    not" between the largest ok probe and the smallest infeasible one above it (T_max),
//!    geometric midpoints while the bracket spans a ratio above 2, then arithmetic ones,
//!    until it is narrower than 10⁻⁹ of its upper end (at most [`EDGE_BISECTIONS`] steps).
//!    Other failures do not end the window: the sagged solve fails to converge on gaps
//!    inside it (`fast-like` at (76.0, −35.9, 62.9) m: at 63.0 and 66.5 kN, ok from 68 to
//!    97 kN, where f1 rises from the 0.185 Hz it has below).
//! 3. **The scan.** F at t₀ and at [`SCAN_CELLS`] equal steps h = (top − t₀)/64 up to the
//!    top; the first ok point with F ≥ f ends it (t₀ itself: the answer). Points where the
//!    model is not ok (below the sagged window's floor, or in a gap of it) count as not
//!    meeting f, so the scan also finds the floor, at resolution h, without assuming the ok
//!    set is one interval. No point meets f: [`TminQueryError::Unreachable`] with the
//!    largest F seen.
//! 4. **The crossing.** Regula falsi (Illinois) on F² − f², nearly linear in t (f1 ∝ √t),
//!    between the last scan point and the first one meeting f; bisection while the lower
//!    end is not ok (that finds the floor when f is met there), and a failed evaluation
//!    moves the lower end. At most [`REFINE_MAX_STEPS`] steps, until F is within 10⁻¹⁰ of f
//!    above it or the bracket is narrower than 10⁻¹² of its upper end.
//!
//! # What the answer guarantees
//!
//! F ≥ f at the answer (the upper end of the last bracket), and F < f or not ok at every
//! scan point below it and at the crossing's lower end (within 10⁻¹² relative, or 10⁻¹⁰ in
//! F, below it). A smaller T_min can reach f only on a range narrower than the scan step h
//! ([`TminAnswer::resolution_n`]) between two scan points: the answer is the smallest at
//! resolution h. For taut cables such a range needs F to rise above f and fall back within
//! one step, i.e. an active-set change inside the step (F² is concave between them); the
//! pieces of F on the paper robot are tens of newtons wide, against h ≈ 0.9 N for its 31 N
//! answer with 60 N in force. docs/inverse.md gives the checks over random poses.
//!
//! Unreachable assumes the window ends where the tensions become infeasible: ok ranges above
//! an infeasible range are not scanned.
//!
//! Bound: [`MAX_EVALUATIONS`] = probes (4 + 31) + ceiling (1 + 48) + scan 64 + crossing 60
//! = 208 forward evaluations. Usually far fewer: the hint is ok and, when it meets the
//! requirement, the top (no ceiling search), leaving ≤ 64 scan points and ~5-10 crossing
//! steps (56-60 evaluations at the median on the shipped scenes, docs/inverse.md).

use super::{Estimator, EstimatorError, RejectedInput, Status, TminQueryError};
use crate::kinematics::Pose;
use crate::modal::lambda_to_hz;
use crate::scene::MAX_CABLES;

/// Low end of the full range, as a fraction of T_max: positive, so every cable keeps a
/// tension floor, and so small that an answer there means T_min ≈ 0 suffices.
const RANGE_LO_FRACTION: f64 = 1e-6;
/// Points of the geometric sweep for an ok T_min strictly between 10⁻⁶ T_max and T_max
/// (32 ratios of 10^(6/32) ≈ 1.54 from one to the other).
pub const SWEEP_POINTS: usize = 31;
/// The probes: hint, scene's T_min, 10⁻⁶ T_max, T_max and the sweep.
const MAX_PROBES: usize = 4 + SWEEP_POINTS;
/// Bisection steps at most on the ceiling of the ok window: from a ratio of 10⁶ to 2 takes
/// 5 geometric steps, from 2 to [`EDGE_TOL_REL`] 30 arithmetic ones.
pub const EDGE_BISECTIONS: usize = 48;
/// An edge of the ok window is resolved when its bracket is this narrow (relative).
const EDGE_TOL_REL: f64 = 1e-9;
/// A bracket spanning more than this ratio is halved geometrically.
const GEOMETRIC_RATIO: f64 = 2.0;
/// Equal steps of the scan from 10⁻⁶ T_max to the top: the answer's resolution is 1/64 of
/// the range below the top.
pub const SCAN_CELLS: usize = 64;
/// Width, relative to its upper end, at which a crossing's bracket is resolved.
const T_MIN_TOL_REL: f64 = 1e-12;
/// Regula-falsi steps at most on the crossing: Illinois converges superlinearly, so this
/// bound is only hit when the forward model is not smooth in T_min.
pub const REFINE_MAX_STEPS: usize = 60;
/// An f1 at or above the requirement by at most this much (relative) is the answer; the
/// eigen solver resolves f1 to ~1e-12 relative, so this is reachable.
const F1_TOL_REL: f64 = 1e-10;
/// Illinois modification: the residual of an end kept twice in a row is scaled by this, so
/// regula falsi does not stall with one end fixed.
const ILLINOIS_SCALE: f64 = 0.5;
/// The inverse query accepts the tensions at any structure-matrix rank.
const ANY_RANK: u32 = 0;
/// Forward evaluations of one query at most: probes, the ceiling (a look at T_max and its
/// bisections), the scan (its last point is the top, already known) and the crossing.
pub const MAX_EVALUATIONS: u32 =
    (MAX_PROBES + 1 + EDGE_BISECTIONS + SCAN_CELLS + REFINE_MAX_STEPS) as u32;

/// The answer to "which T_min reaches f1 ≥ f_required at this pose".
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TminAnswer {
    /// The smallest T_min, N, at resolution `resolution_n` (within 10⁻¹² relative of a
    /// crossing, or of the floor of the range where the model is ok when f1 there already
    /// reaches the requirement).
    pub t_min_n: f64,
    /// f1 at that T_min, Hz (≥ the requirement, by at most 10⁻¹⁰ relative after a crossing).
    pub f1_hz: f64,
    /// Evaluations of the forward model (tensions + f1) spent, at most [`MAX_EVALUATIONS`].
    pub evaluations: u32,
    /// The scan step, N: f1 is below the requirement (or the model is not ok) at every scan
    /// point below `t_min_n`, from 10⁻⁶ T_max up in steps of this size; a smaller T_min can
    /// reach the requirement only on a range narrower than this between two of them.
    pub resolution_n: f64,
}

/// The state of one query: the last root (warm start of the next) and the evaluations spent.
struct Search<'p> {
    pose: &'p Pose,
    warm: Option<f64>,
    evals: u32,
}

/// One forward evaluation: T_min (N) and f1 (Hz), `None` when the model failed there;
/// `infeasible` when it failed because no tension distribution exists (above the ceiling).
#[derive(Debug, Clone, Copy)]
struct Probe {
    t: f64,
    f: Option<f64>,
    infeasible: bool,
}

impl Probe {
    /// The probe of one evaluation at `t` (N).
    fn of(t: f64, r: Result<f64, EstimatorError>) -> Probe {
        Probe {
            t,
            f: r.ok(),
            infeasible: r.is_err_and(|e| e.status() == Status::TensionInfeasible),
        }
    }
}

impl Estimator {
    /// The smallest uniform T_min (N) for which f1 at `pose` reaches `f_required_hz` (the
    /// paper's conclusion 4), at resolution [`TminAnswer::resolution_n`]: a scan of 64
    /// steps up to the smallest tried T_min that meets it (or the largest feasible one),
    /// where T_min at which the model is not ok (a sagging cable slack) count as not
    /// meeting it, then regula falsi on the first crossing (the module doc gives the
    /// algorithm and its guarantee). At most
    /// [`MAX_EVALUATIONS`] forward evaluations, on its own scratch solvers: the cycle's warm
    /// state is untouched. No allocation.
    ///
    /// The query is uniform: the answer is one T_min for every cable (with each cable's
    /// upper bound from the scene), whatever per-cable lower bounds the cycle was given
    /// ([`Self::update`] with [`super::Tmin::PerCable`]) and whatever per-cable t_min the scene has.
    pub fn t_min_for_f1(
        &mut self,
        pose: &Pose,
        f_required_hz: f64,
    ) -> Result<TminAnswer, TminQueryError> {
        self.t_min_for_f1_near(pose, f_required_hz, None)
    }

    /// [`Self::t_min_for_f1`] given `hint` (N), the T_min in force: it is tried first, and
    /// when f1 there already reaches the requirement the answer is at most `hint` (the scan
    /// then covers only the range below it).
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
            return Err(RejectedInput::NonFinitePose.into());
        }
        if !pose.has_unit_quaternion(self.params.quaternion_tol) {
            return Err(RejectedInput::NonUnitQuaternion.into());
        }
        if !self.scene.rigid && !pose.has_identity_orientation() {
            return Err(RejectedInput::OrientationOnPointMass.into());
        }
        self.inverse
            .set_pose(&self.scene, pose)
            .map_err(EstimatorError::from)?;
        self.inverse.reset_tension_warm_start();
        let mut s = Search {
            pose,
            warm: None,
            evals: 0,
        };
        let t_max = self.scene.t_max_n;
        let t0 = RANGE_LO_FRACTION * t_max;
        let in_range = |t: f64| t.is_finite() && t >= t0 && t <= t_max;

        // 1. Probes until one is ok.
        let mut probes = [Probe::of(0.0, Ok(0.0)); MAX_PROBES];
        let mut n = 0;
        let mut first_err = None;
        let sweep = (1..=SWEEP_POINTS)
            .map(|k| t0 * (t_max / t0).powf(k as f64 / (SWEEP_POINTS + 1) as f64));
        let candidates = [hint, Some(self.scene.t_min_n), Some(t0), Some(t_max)]
            .into_iter()
            .flatten()
            .chain(sweep);
        for t in candidates {
            if !in_range(t) || probes[..n].iter().any(|p| p.t == t) {
                continue;
            }
            let r = self.inverse_f1(&mut s, t);
            if let Err(e) = r {
                first_err.get_or_insert(e);
            }
            probes[n] = Probe::of(t, r);
            n += 1;
            if r.is_ok() {
                break;
            }
        }
        let probes = &probes[..n];
        let ok = |p: &&Probe| p.f.is_some();
        let Some(&lowest_ok) = probes.iter().filter(ok).min_by(|a, b| a.t.total_cmp(&b.t)) else {
            // Not ok at any probe (10⁻⁶ T_max and T_max are always among them).
            return Err(first_err
                .unwrap_or(RejectedInput::TminOutOfRange.into())
                .into());
        };

        // 2. The top of the scan: the smallest ok probe meeting the requirement, else the
        // ceiling of the ok window.
        let meets = |p: &&Probe| p.f.is_some_and(|f| f >= f_required_hz);
        let top = match probes
            .iter()
            .filter(meets)
            .min_by(|a, b| a.t.total_cmp(&b.t))
        {
            Some(&p) => p,
            None => {
                let highest_ok = *probes
                    .iter()
                    .filter(ok)
                    .max_by(|a, b| a.t.total_cmp(&b.t))
                    .unwrap_or(&lowest_ok);
                let above = probes
                    .iter()
                    .filter(|p| p.infeasible && p.t > highest_ok.t)
                    .map(|p| p.t)
                    .min_by(f64::total_cmp);
                self.ceiling(&mut s, highest_ok, above, t_max)
            }
        };

        // 3. The scan from 10⁻⁶ T_max up to the top: the first ok point meeting the
        // requirement ends it.
        let h = (top.t - t0) / SCAN_CELLS as f64;
        let mut prev: Option<Probe> = None;
        let mut best = (f64::NEG_INFINITY, top.t);
        for k in 0..=SCAN_CELLS {
            let p = if k == SCAN_CELLS {
                top
            } else {
                let t = t0 + k as f64 * h;
                Probe::of(t, self.inverse_f1(&mut s, t))
            };
            match (p.f, prev) {
                (Some(f), None) if f >= f_required_hz => {
                    return Ok(TminAnswer {
                        t_min_n: p.t,
                        f1_hz: f,
                        evaluations: s.evals,
                        resolution_n: h,
                    });
                }
                (Some(f), Some(below)) if f >= f_required_hz => {
                    return Ok(self.crossing(&mut s, f_required_hz, below, (p.t, f), h));
                }
                (Some(f), _) if f > best.0 => best = (f, p.t),
                _ => {}
            }
            prev = Some(p);
        }
        Err(TminQueryError::Unreachable {
            required_hz: f_required_hz,
            f1_max_hz: best.0,
            t_min_n: best.1,
        })
    }

    /// The ceiling of the ok window: `inside` is ok, `outside` (N) the nearest known T_min
    /// above it where the tensions are infeasible, if any; `end` (N, T_max) is tried when
    /// none is known. Bisection on "infeasible or not" (geometric midpoints while the bracket
    /// spans a ratio above 2) to [`EDGE_TOL_REL`]; returns the last point below the
    /// infeasibility (ok, or failed for another reason: a gap in the window, such as a
    /// sagged solve that does not converge, is not taken for its ceiling).
    fn ceiling(
        &mut self,
        s: &mut Search<'_>,
        inside: Probe,
        outside: Option<f64>,
        end: f64,
    ) -> Probe {
        let mut ok = inside;
        let mut bad = match outside {
            Some(t) => t,
            None if inside.t == end => return inside,
            None => match Probe::of(end, self.inverse_f1(s, end)) {
                p if p.infeasible => end,
                p => return p,
            },
        };
        for _ in 0..EDGE_BISECTIONS {
            let (lo, hi) = (ok.t.min(bad), ok.t.max(bad));
            if hi - lo <= EDGE_TOL_REL * hi {
                break;
            }
            let mid = if hi > GEOMETRIC_RATIO * lo {
                (lo * hi).sqrt()
            } else {
                0.5 * (lo + hi)
            };
            match Probe::of(mid, self.inverse_f1(s, mid)) {
                p if p.infeasible => bad = mid,
                p => ok = p,
            }
        }
        ok
    }

    /// Regula falsi (Illinois) on f1(T)² − f² between `lo` (below the requirement, or not
    /// ok: then bisection until an ok point below it is found) and `hi` with f1(hi) ≥ f.
    /// `h` (N) is the scan step, the answer's resolution.
    fn crossing(
        &mut self,
        s: &mut Search<'_>,
        f_required_hz: f64,
        lo: Probe,
        (mut hi, f_hi): (f64, f64),
        h: f64,
    ) -> TminAnswer {
        let target = f_required_hz * f_required_hz;
        let mut lo_t = lo.t;
        let mut g_lo = lo.f.map(|f| f * f - target);
        let mut g_hi = f_hi * f_hi - target;
        let mut best = (hi, f_hi);
        let mut side = 0i8;
        for _ in 0..REFINE_MAX_STEPS {
            if (best.1 - f_required_hz) <= F1_TOL_REL * f_required_hz
                || hi - lo_t <= T_MIN_TOL_REL * hi
            {
                break;
            }
            let t = match g_lo {
                Some(g_lo) => (lo_t * g_hi - hi * g_lo) / (g_hi - g_lo),
                None => f64::NAN,
            };
            let t = if t > lo_t && t < hi {
                t
            } else {
                0.5 * (lo_t + hi)
            };
            match self.inverse_f1(s, t) {
                Ok(f) if f >= f_required_hz => {
                    hi = t;
                    g_hi = f * f - target;
                    best = (t, f);
                    if side == 1 {
                        g_lo = g_lo.map(|g| g * ILLINOIS_SCALE);
                    }
                    side = 1;
                }
                r => {
                    lo_t = t;
                    g_lo = r.ok().map(|f| f * f - target);
                    if side == -1 {
                        g_hi *= ILLINOIS_SCALE;
                    }
                    side = -1;
                }
            }
        }
        TminAnswer {
            t_min_n: best.0,
            f1_hz: best.1,
            evaluations: s.evals,
            resolution_n: h,
        }
    }

    /// f1 (Hz) at the search's pose (geometry already set) for T_min = `t_min_n`.
    fn inverse_f1(&mut self, s: &mut Search<'_>, t_min_n: f64) -> Result<f64, EstimatorError> {
        s.evals += 1;
        if self.inverse.is_sagged() {
            // Cold: F is then what a fresh estimator computes (see the module doc).
            self.inverse.reset_tension_warm_start();
        }
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
