//! Holding f1: the T_min set-point a controller publishes from the service's margin answers
//! so that the first natural frequency stays at or above a requirement (the hold of the
//! example controllers and of `cablevib demo`).
//!
//! The margin answer carries f1 at the latest pose and `t_min_required_n`, the smallest
//! uniform T_min at which f1 reaches the *requested* frequency (computed beside the loop, at a
//! pose `t_min_required_age_cycles` estimates old). [`F1Hold`] turns a sequence of answers
//! into set-points:
//!
//! - The controller asks for the T_min of `required + guard` ([`HoldParams::request_hz`]): the
//!   guard covers the pose's motion between the pose the answer's T_min was computed at and
//!   the poses the set-point applies to.
//! - **Raise** (f1 < required + guard): at once (a step: f1 below the requirement is what the
//!   hold exists to end; a ramp would leave it below for the ramp's duration). A fresh answer
//!   (age 0) sets the answer's T_min, even when lower (f1 is not monotone in T_min:
//!   docs/inverse.md; the answer is the T_min that reaches the request at this very pose).
//!   An older answer is the T_min of an earlier pose, while f1 is of the latest one: the
//!   set-point becomes the largest of itself, the answer's T_min, and set-point ×
//!   (request / f1)², the T_min that brings this f1 to the request if f1 ∝ √T_min. Within one
//!   set of cables at their bound f1² is concave in T_min (docs/inverse.md), so that step
//!   never overshoots there; repeated at each answer it closes the gap from below. (The
//!   inverse search takes milliseconds to a few tenths of a second on a loaded machine,
//!   while f1 along the paper's circle moves by up to 2 Hz/s: the step keeps f1 above the
//!   requirement between two searches.) A step may be counted twice when the next answer
//!   comes before the set-point applied; the relax takes the excess back.
//! - **Relax** (f1 ≥ required + relax band): the set-point falls towards the answer's T_min at
//!   most [`HoldParams::relax_rate_n_per_s`] per second of the service's clock (the answers'
//!   `timestamp_ns`), so the cables' tensions fall smoothly.
//! - **Hold** in between: the hysteresis band (guard, relax band) keeps the set-point from
//!   chattering between raise and relax as f1 moves about the requirement.
//! - The set-point stays within [floor, ceiling]: the floor is the T_min the hold relaxes to
//!   (the scene's), the ceiling the smallest of the cables' t_max (a uniform set-point above a
//!   cable's t_max is refused by the service). An answer above the ceiling gives the ceiling;
//!   an unreachable requirement (`t_min_required_n` = +∞) leaves the set-point as it is (no
//!   feasible T_min reaches it; more T_min only risks infeasible tensions); the action says
//!   which.
//! - An answer whose status is `tension_infeasible` while the set-point is above the floor
//!   sends it back to the floor (the next ok answer raises it to a feasible T_min again).
//! - Answers that are not ok, or carry no T_min yet (NaN), change nothing.
//!
//! One implementation, used by `cablevib demo` and `service/examples/controller.rs`;
//! `examples/python/hold_f1.py` mirrors it and `examples/python/hold_f1_cases.json` (written
//! and checked by this module's tests, checked by python/tests/test_hold_f1.py) holds a fixed
//! sequence both must reproduce.

use cablevib_ipc::{MarginResponse, StatusCode, REQUIRED_F1_MAX_HZ, REQUIRED_F1_MIN_HZ};

/// Default guard above the requirement, Hz ([`HoldParams::guard_hz`]): on the paper's circle
/// (4 s per revolution) f1 at a fixed T_min moves by up to 2 Hz/s (measured, the demo
/// holding 9.5 Hz), 0.002 Hz per 1 kHz cycle; the √T_min step corrects it at each answer, so 0.1 Hz covers 50
/// ms without an answer (the controller's longest stalls on this shared 2-core machine were
/// ~20 ms).
pub const DEFAULT_GUARD_HZ: f64 = 0.1;
/// Default relax band, Hz ([`HoldParams::relax_band_hz`]): relax only when f1 is at least this far
/// above the requirement. It must exceed the guard: a raise lands f1 at the guard, and a relax
/// that began right above it would lower f1 back under it at the next step, so that raise and
/// relax alternated at every answer; 0.15 Hz above the guard is 75 ms of the circle's fastest
/// drift.
pub const DEFAULT_RELAX_BAND_HZ: f64 = 0.25;
/// Default relax rate, N/s ([`HoldParams::relax_rate_n_per_s`]): 20 N/s takes a 60 N set-point from
/// 120 N back to 60 N in 3 s, slow against the robot's modes (periods of 0.1 s and shorter).
pub const DEFAULT_RELAX_RATE_N_PER_S: f64 = 20.0;
/// Largest guard or relax band, Hz (a band wider than any requirement is a typo).
pub const MAX_BAND_HZ: f64 = 1e3;
/// Largest relax rate, N/s (above it the "rate limit" limits nothing at any cycle rate).
pub const MAX_RELAX_RATE_N_PER_S: f64 = 1e9;

/// What the hold acts on. [`HoldParams::new`] checks every value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldParams {
    /// The first natural frequency to hold, Hz.
    pub required_hz: f64,
    /// Guard above the requirement, Hz: the margin query asks for `required + guard`.
    pub guard_hz: f64,
    /// The set-point relaxes only when f1 ≥ required + this, Hz (> guard).
    pub relax_band_hz: f64,
    /// Largest decrease of the set-point per second, N/s.
    pub relax_rate_n_per_s: f64,
    /// Lowest set-point (the T_min the hold relaxes to: the scene's), N.
    pub floor_n: f64,
    /// Highest set-point (the smallest of the cables' t_max), N.
    pub ceiling_n: f64,
}

/// A bad hold parameter (one line).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HoldError {
    /// A value outside its range.
    #[error("{what} {value:?} must be {bound}")]
    OutOfRange {
        /// The option or field.
        what: &'static str,
        /// The value given.
        value: f64,
        /// The range it must be in.
        bound: String,
    },
}

fn check(what: &'static str, value: f64, ok: bool, bound: String) -> Result<(), HoldError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(HoldError::OutOfRange { what, value, bound })
    }
}

impl HoldParams {
    /// Holds `required_hz` between `floor_n` and `ceiling_n` with the default guard, band and
    /// rate.
    pub fn new(required_hz: f64, floor_n: f64, ceiling_n: f64) -> Result<HoldParams, HoldError> {
        HoldParams {
            required_hz,
            guard_hz: DEFAULT_GUARD_HZ,
            relax_band_hz: DEFAULT_RELAX_BAND_HZ,
            relax_rate_n_per_s: DEFAULT_RELAX_RATE_N_PER_S,
            floor_n,
            ceiling_n,
        }
        .checked()
    }

    /// `self` when every value is in range, else the first one that is not.
    pub fn checked(self) -> Result<HoldParams, HoldError> {
        let p = self;
        check(
            "hold-f1 (Hz)",
            p.required_hz,
            p.required_hz >= REQUIRED_F1_MIN_HZ && p.required_hz <= REQUIRED_F1_MAX_HZ,
            format!("in [{REQUIRED_F1_MIN_HZ}, {REQUIRED_F1_MAX_HZ}] Hz"),
        )?;
        check(
            "hold guard (Hz)",
            p.guard_hz,
            (0.0..=MAX_BAND_HZ).contains(&p.guard_hz)
                && p.required_hz + p.guard_hz <= REQUIRED_F1_MAX_HZ,
            format!("in [0, {MAX_BAND_HZ}] Hz, with hold-f1 + guard ≤ {REQUIRED_F1_MAX_HZ} Hz"),
        )?;
        check(
            "hold relax band (Hz)",
            p.relax_band_hz,
            p.relax_band_hz > p.guard_hz && p.relax_band_hz <= MAX_BAND_HZ,
            format!("> the guard ({} Hz) and ≤ {MAX_BAND_HZ} Hz", p.guard_hz),
        )?;
        check(
            "hold relax rate (N/s)",
            p.relax_rate_n_per_s,
            p.relax_rate_n_per_s > 0.0 && p.relax_rate_n_per_s <= MAX_RELAX_RATE_N_PER_S,
            format!("in (0, {MAX_RELAX_RATE_N_PER_S}] N/s"),
        )?;
        check(
            "hold ceiling (N)",
            p.ceiling_n,
            p.ceiling_n > 0.0,
            "finite and > 0 N (the smallest cable t_max)".into(),
        )?;
        check(
            "hold floor (N)",
            p.floor_n,
            p.floor_n > 0.0 && p.floor_n <= p.ceiling_n,
            format!(
                "in (0, {}] N (the ceiling, the smallest cable t_max)",
                p.ceiling_n
            ),
        )?;
        Ok(p)
    }

    /// The frequency the margin query asks for, Hz: required + guard.
    pub fn request_hz(&self) -> f64 {
        self.required_hz + self.guard_hz
    }
}

/// The parts of a margin answer the hold reads (the fields of [`MarginResponse`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldInput {
    /// The answer's status is ok.
    pub ok: bool,
    /// f1 at the latest pose, Hz.
    pub f1_hz: f64,
    /// The smallest T_min reaching [`HoldParams::request_hz`], N (+∞ unreachable, NaN unknown).
    pub t_min_required_n: f64,
    /// How many estimates old `t_min_required_n` is.
    pub t_min_required_age_cycles: u32,
    /// The service's clock when answering, ns.
    pub timestamp_ns: u64,
    /// The pose sequence of the estimate the answer is of.
    pub pose_sequence: u64,
    /// The answer's status is `tension_infeasible` (no tension distribution within
    /// [T_min, t_max] at the latest pose).
    pub tension_infeasible: bool,
}

impl From<&MarginResponse> for HoldInput {
    fn from(r: &MarginResponse) -> HoldInput {
        HoldInput {
            ok: r.is_ok(),
            f1_hz: r.f1_hz,
            t_min_required_n: r.t_min_required_n,
            t_min_required_age_cycles: r.t_min_required_age_cycles,
            timestamp_ns: r.timestamp_ns,
            pose_sequence: r.pose_sequence,
            tension_infeasible: r.status == StatusCode::TensionInfeasible.as_u32(),
        }
    }
}

/// What one answer did to the set-point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HoldAction {
    /// Not ok, or no T_min known yet: nothing changes.
    NoAnswer,
    /// f1 within the band: the set-point stays.
    Held,
    /// f1 under required + guard: the set-point became the answer's T_min.
    Raised,
    /// f1 ≥ required + relax band: the set-point fell towards the answer's T_min (rate-limited).
    Relaxed,
    /// The answer's T_min is above the ceiling (a cable's t_max below the scene's): the
    /// set-point is the ceiling (f1 may stay below the requirement).
    Ceiling,
    /// No feasible T_min reaches the request at the answer's pose (`t_min_required_n` = +∞):
    /// the set-point stays (raising it further buys no f1 there and may make the tensions
    /// infeasible).
    Unreachable,
    /// The latest pose's tensions are infeasible above the floor: the set-point went back to
    /// the floor (the next ok answer raises it to a feasible T_min again).
    Infeasible,
}

impl HoldAction {
    /// Every action, in the order of their `as usize` values (for counting them).
    pub const ALL: [HoldAction; 7] = [
        HoldAction::NoAnswer,
        HoldAction::Held,
        HoldAction::Raised,
        HoldAction::Relaxed,
        HoldAction::Ceiling,
        HoldAction::Unreachable,
        HoldAction::Infeasible,
    ];

    /// "raised 12, relaxed 3": the non-zero counts of `counts` (indexed by `as usize`).
    pub fn summary(counts: &[u64; 7]) -> String {
        HoldAction::ALL
            .iter()
            .filter(|a| counts[**a as usize] > 0)
            .map(|a| format!("{} {}", a.as_str(), counts[*a as usize]))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Lower-case name (the Python mirror's).
    pub fn as_str(self) -> &'static str {
        match self {
            HoldAction::NoAnswer => "no_answer",
            HoldAction::Held => "held",
            HoldAction::Raised => "raised",
            HoldAction::Relaxed => "relaxed",
            HoldAction::Ceiling => "ceiling",
            HoldAction::Unreachable => "unreachable",
            HoldAction::Infeasible => "infeasible",
        }
    }
}

/// The hold's state: the set-point in force, the one before its last change and the pose of
/// the answer that changed it, and the time of the last answer.
#[derive(Debug, Clone)]
pub struct F1Hold {
    params: HoldParams,
    setpoint_n: f64,
    previous_n: f64,
    change_pose_sequence: u64,
    last_timestamp_ns: Option<u64>,
}

/// Poses after the one whose answer changed the set-point that may still have been estimated
/// under the previous one: the service applies a set-point from the next pose it takes after
/// it arrives, and the controller publishes within microseconds of the answer, so the pose
/// already being estimated meanwhile is the one at risk.
pub const IN_FLIGHT_POSES: u64 = 1;

impl F1Hold {
    /// A hold starting at the floor (the scene's T_min, in force before any set-point).
    pub fn new(params: HoldParams) -> F1Hold {
        F1Hold {
            setpoint_n: params.floor_n,
            previous_n: params.floor_n,
            change_pose_sequence: 0,
            params,
            last_timestamp_ns: None,
        }
    }

    /// The parameters.
    pub fn params(&self) -> &HoldParams {
        &self.params
    }

    /// The set-point in force, N.
    pub fn setpoint_n(&self) -> f64 {
        self.setpoint_n
    }

    /// Takes one margin answer; returns what it did. The set-point changed (and should be
    /// published) when [`Self::setpoint_n`] differs from before the call.
    pub fn on_answer(&mut self, a: &HoldInput) -> HoldAction {
        let before = self.setpoint_n;
        let action = self.step(a);
        if self.setpoint_n != before {
            self.previous_n = before;
            self.change_pose_sequence = a.pose_sequence;
        }
        action
    }

    fn step(&mut self, a: &HoldInput) -> HoldAction {
        let p = self.params;
        let dt_s = match self.last_timestamp_ns {
            Some(last) => a.timestamp_ns.saturating_sub(last) as f64 * 1e-9,
            None => 0.0,
        };
        self.last_timestamp_ns = Some(a.timestamp_ns.max(self.last_timestamp_ns.unwrap_or(0)));
        if a.tension_infeasible && self.setpoint_n > p.floor_n {
            self.setpoint_n = p.floor_n;
            return HoldAction::Infeasible;
        }
        let t = a.t_min_required_n;
        if !a.ok || t.is_nan() || !(a.f1_hz.is_finite() && a.f1_hz > 0.0) || t <= 0.0 {
            return HoldAction::NoAnswer;
        }
        if t == f64::INFINITY {
            return HoldAction::Unreachable;
        }
        let target = t.clamp(p.floor_n, p.ceiling_n);
        let request_hz = p.request_hz();
        if a.f1_hz < request_hz {
            self.setpoint_n = if a.t_min_required_age_cycles == 0 {
                target
            } else {
                // The answer is of an earlier pose; f1 is of this one. f1 ≈ a·√T_min: the
                // T_min that brings this f1 to the request, which never overshoots within
                // one active set (f1² is concave in T_min there: docs/inverse.md). An f1 of
                // the pose that changed the set-point or of the next [`IN_FLIGHT_POSES`] may
                // be under the set-point before (the same estimate answered twice, a pose
                // estimated before the change applied): the smaller of the two is its base,
                // so the step does not compound.
                let r = request_hz / a.f1_hz;
                let in_flight = a.pose_sequence <= self.change_pose_sequence + IN_FLIGHT_POSES;
                let base = if in_flight {
                    self.setpoint_n.min(self.previous_n)
                } else {
                    self.setpoint_n
                };
                let scaled = (base * (r * r)).min(p.ceiling_n);
                self.setpoint_n.max(target).max(scaled)
            };
            if t > p.ceiling_n || self.setpoint_n >= p.ceiling_n {
                HoldAction::Ceiling
            } else {
                HoldAction::Raised
            }
        } else if a.f1_hz >= p.required_hz + p.relax_band_hz && target < self.setpoint_n {
            self.setpoint_n = target.max(self.setpoint_n - p.relax_rate_n_per_s * dt_s);
            HoldAction::Relaxed
        } else {
            HoldAction::Held
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> HoldParams {
        HoldParams::new(9.5, 60.0, 350.0).unwrap()
    }

    fn answer(f1_hz: f64, t: f64, age: u32, ms: u64) -> HoldInput {
        HoldInput {
            ok: true,
            f1_hz,
            t_min_required_n: t,
            t_min_required_age_cycles: age,
            timestamp_ns: ms * 1_000_000,
            pose_sequence: ms + 1,
            tension_infeasible: false,
        }
    }

    /// Below the guard the set-point steps at once to the answer's T_min or the √T_min step,
    /// whichever is larger; an old answer never lowers it, a fresh one does (f1 is not
    /// monotone in T_min).
    #[test]
    fn raises_at_once_to_the_answer() {
        let mut h = F1Hold::new(params());
        assert_eq!(h.on_answer(&answer(9.0, 95.0, 3, 0)), HoldAction::Raised);
        assert_eq!(h.setpoint_n(), 95.0);
        // Within the guard (9.5 ≤ f1 < 9.6) is still a raise.
        assert_eq!(h.on_answer(&answer(9.52, 99.0, 3, 1)), HoldAction::Raised);
        assert_eq!(h.setpoint_n(), 99.0);
        // An old, lower answer: the √T_min step from this f1 (9.4 Hz at 99 N → 9.6 Hz).
        assert_eq!(h.on_answer(&answer(9.4, 90.0, 2, 2)), HoldAction::Raised);
        let r: f64 = 9.6 / 9.4;
        // Its base is the smaller of the set-point and the one before (95 N): the f1 may be of
        // a pose estimated before 99 N applied.
        assert_eq!(h.setpoint_n(), 95.0 * (r * r));
        assert_eq!(h.on_answer(&answer(9.4, 90.0, 0, 3)), HoldAction::Raised);
        assert_eq!(
            h.setpoint_n(),
            90.0,
            "a fresh answer is the T_min of this pose"
        );
    }

    /// The √T_min step on a model whose f1² is affine in T_min with a positive intercept
    /// (concave, as within one active set; f1² = a + b·T): from stale answers only, the
    /// set-point climbs to the exact T* = (f² − a)/b from below, never above it (the closed
    /// form is the independent check), within 1e-9 relative (the iteration's contraction
    /// a/(a + b·T) ≈ 0.3 per step leaves rounding only after 40 steps).
    #[test]
    fn the_sqrt_step_never_overshoots_a_concave_f1_squared() {
        let (a, b) = (30.0, 1.0); // Hz², Hz²/N: f1(60 N) = 9.49 Hz
        let p = params();
        let f = p.request_hz();
        let t_star = (f * f - a) / b;
        let mut h = F1Hold::new(p);
        // A set-point decided on the answer of pose k applies from pose k + 2 (one pose in
        // flight, the worst case IN_FLIGHT_POSES covers).
        let mut decided = vec![h.setpoint_n(); 2];
        for k in 0..200 {
            let f1 = (a + b * decided[k]).sqrt();
            h.on_answer(&answer(f1, p.floor_n, 5, k as u64));
            decided.push(h.setpoint_n());
            assert!(
                h.setpoint_n() <= t_star * (1.0 + 1e-12),
                "{k}: {}",
                h.setpoint_n()
            );
        }
        assert!(
            (h.setpoint_n() / t_star - 1.0).abs() < 1e-9,
            "{} vs {t_star}",
            h.setpoint_n()
        );
    }

    /// Relaxing: only when f1 ≥ required + band, by at most rate·dt (the answers' clock), never
    /// below the answer's T_min or the floor; inside the band nothing moves (hysteresis).
    #[test]
    fn relaxes_at_the_rate_only_above_the_band() {
        let mut h = F1Hold::new(params());
        h.on_answer(&answer(9.0, 120.0, 1, 0));
        assert_eq!(h.setpoint_n(), 120.0);
        // In the band [9.6, 9.75): held, whatever the answer's T_min.
        assert_eq!(h.on_answer(&answer(9.7, 70.0, 1, 100)), HoldAction::Held);
        assert_eq!(h.setpoint_n(), 120.0);
        // Ample: 20 N/s × 0.5 s = 10 N.
        assert_eq!(h.on_answer(&answer(9.8, 70.0, 1, 600)), HoldAction::Relaxed);
        assert!((h.setpoint_n() - 110.0).abs() < 1e-12, "{}", h.setpoint_n());
        // A long pause: the step stops at the answer's T_min.
        assert_eq!(
            h.on_answer(&answer(9.8, 70.0, 1, 60_000)),
            HoldAction::Relaxed
        );
        assert_eq!(h.setpoint_n(), 70.0);
        // An answer below the floor relaxes to the floor.
        h.on_answer(&answer(9.8, 10.0, 1, 120_000));
        assert_eq!(h.setpoint_n(), 60.0);
        // At the floor, ample f1 holds.
        assert_eq!(
            h.on_answer(&answer(9.9, 10.0, 1, 130_000)),
            HoldAction::Held
        );
        // A clock going back gives no relax step (dt = 0), never a negative one.
        h.on_answer(&answer(9.0, 100.0, 1, 140_000));
        h.on_answer(&answer(9.9, 70.0, 1, 100_000));
        assert_eq!(h.setpoint_n(), 100.0);
    }

    /// The same answer (one estimate answered again, or a pose estimated before the set-point
    /// applied) steps the set-point once: the √T_min step does not compound.
    #[test]
    fn a_repeated_answer_does_not_compound() {
        let mut h = F1Hold::new(params());
        h.on_answer(&answer(9.0, 60.0, 5, 0));
        let once = h.setpoint_n();
        let r: f64 = 9.6 / 9.0;
        assert_eq!(once, 60.0 * (r * r));
        for k in 1..100 {
            let mut again = answer(9.0, 60.0, 5, k);
            again.pose_sequence = 1;
            h.on_answer(&again);
        }
        assert_eq!(h.setpoint_n(), once);
    }

    /// A pose whose tensions are infeasible under the set-point sends it back to the floor;
    /// at the floor the status changes nothing.
    #[test]
    fn infeasible_tensions_go_back_to_the_floor() {
        let mut h = F1Hold::new(params());
        h.on_answer(&answer(9.0, 200.0, 5, 0));
        assert_eq!(h.setpoint_n(), 200.0);
        let mut a = answer(f64::NAN, f64::NAN, 5, 1);
        (a.ok, a.tension_infeasible) = (false, true);
        assert_eq!(h.on_answer(&a), HoldAction::Infeasible);
        assert_eq!(h.setpoint_n(), 60.0);
        assert_eq!(h.on_answer(&a), HoldAction::NoAnswer);
    }

    /// A T_min above the smallest t_max gives the ceiling; an unreachable requirement leaves
    /// the set-point where it is.
    #[test]
    fn clamps_to_the_ceiling() {
        let mut h = F1Hold::new(HoldParams::new(9.5, 60.0, 300.0).unwrap());
        assert_eq!(h.on_answer(&answer(9.0, 320.0, 1, 0)), HoldAction::Ceiling);
        assert_eq!(h.setpoint_n(), 300.0);
        let mut h = F1Hold::new(params());
        h.on_answer(&answer(9.0, 80.0, 1, 0));
        assert_eq!(
            h.on_answer(&answer(9.0, f64::INFINITY, 1, 1)),
            HoldAction::Unreachable
        );
        assert_eq!(h.setpoint_n(), 80.0);
    }

    /// Not ok, NaN (not known yet), a non-positive or non-finite f1: nothing changes.
    #[test]
    fn ignores_answers_without_a_t_min() {
        let mut h = F1Hold::new(params());
        let mut a = answer(9.0, 95.0, 1, 0);
        a.ok = false;
        assert_eq!(h.on_answer(&a), HoldAction::NoAnswer);
        for (f1, t) in [(9.0, f64::NAN), (f64::NAN, 95.0), (9.0, -1.0), (9.0, 0.0)] {
            assert_eq!(h.on_answer(&answer(f1, t, 1, 0)), HoldAction::NoAnswer);
        }
        assert_eq!(h.setpoint_n(), 60.0);
    }

    /// A fixed sequence of answers through every branch (raise, old and fresh answers,
    /// band, relax at the rate and to the target, floor, ceiling, unreachable, not ok, NaN, a
    /// clock going back), its set-points and actions written to
    /// `examples/python/hold_f1_cases.json`, which python/tests/test_hold_f1.py runs through the
    /// Python mirror: the file must be what this implementation produces
    /// (`CABLEVIB_BLESS=1 cargo test --release -p cablevib-service --lib hold` rewrites it).
    #[test]
    fn the_python_mirror_s_cases_are_this_implementation_s() {
        let p = HoldParams {
            relax_rate_n_per_s: 25.0,
            ..HoldParams::new(9.5, 60.0, 300.0).unwrap()
        };
        let mut inputs = vec![
            answer(9.0, f64::NAN, u32::MAX, 0),
            answer(9.1, 90.0, 4, 1),
            answer(9.52, 92.5, 4, 2),
            answer(9.4, 85.0, 3, 3),
            answer(9.4, 85.0, 0, 4),
            answer(9.6, 70.0, 2, 5),
            answer(9.8, 70.0, 2, 105),
            answer(9.8, 70.0, 2, 505),
            answer(9.9, 50.0, 2, 5_000),
            answer(9.9, 50.0, 2, 6_000),
            answer(9.2, 310.0, 2, 6_001),
            answer(9.8, 200.0, 2, 6_002),
            answer(9.8, 200.0, 2, 7_002),
            answer(9.0, f64::INFINITY, 1, 7_003),
            answer(9.8, 65.0, 1, 7_000),
            answer(9.8, 65.0, 1, 8_000),
        ];
        let mut not_ok = answer(8.0, 100.0, 1, 8_001);
        not_ok.ok = false;
        inputs.push(not_ok);
        inputs.push(answer(f64::NAN, 100.0, 1, 8_002));
        inputs.push(answer(9.3, 100.0, 3, 8_003));
        inputs.push(answer(9.3, 100.0, 3, 8_004));
        inputs.push(answer(9.45, 90.0, 3, 8_005));
        let mut infeasible = answer(f64::NAN, f64::NAN, u32::MAX, 8_006);
        (infeasible.ok, infeasible.tension_infeasible) = (false, true);
        inputs.push(infeasible);
        inputs.push(infeasible);
        let num = |x: f64| {
            if x.is_finite() {
                serde_json::json!(x)
            } else {
                serde_json::json!(format!("{x}"))
            }
        };
        let mut h = F1Hold::new(p);
        let steps: Vec<serde_json::Value> = inputs
            .iter()
            .map(|a| {
                let action = h.on_answer(a);
                serde_json::json!({
                    "ok": a.ok,
                    "f1_hz": num(a.f1_hz),
                    "t_min_required_n": num(a.t_min_required_n),
                    "t_min_required_age_cycles": a.t_min_required_age_cycles,
                    "timestamp_ns": a.timestamp_ns,
                    "pose_sequence": a.pose_sequence,
                    "tension_infeasible": a.tension_infeasible,
                    "setpoint_n": h.setpoint_n(),
                    "action": action.as_str(),
                })
            })
            .collect();
        let actions: std::collections::BTreeSet<&str> = steps
            .iter()
            .map(|s| s["action"].as_str().unwrap())
            .collect();
        assert_eq!(actions.len(), 7, "every action occurs: {actions:?}");
        let mut doc = serde_json::json!({
            "about": "F1Hold cases: service/src/hold.rs writes them, examples/python/hold_f1.py must reproduce them",
            "params": {
                "required_hz": p.required_hz,
                "guard_hz": p.guard_hz,
                "relax_band_hz": p.relax_band_hz,
                "relax_rate_n_per_s": p.relax_rate_n_per_s,
                "floor_n": p.floor_n,
                "ceiling_n": p.ceiling_n,
            },
            "steps": steps,
        });
        // Keys in sorted order whatever serde_json's features: `cargo test --workspace` builds
        // it with `preserve_order` (the Python crate's), which keeps insertion order instead.
        doc.sort_all_objects();
        let text = serde_json::to_string_pretty(&doc).unwrap() + "\n";
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/python/hold_f1_cases.json"
        );
        if std::env::var_os("CABLEVIB_BLESS").is_some_and(|v| v == "1") {
            std::fs::write(path, &text).unwrap();
        }
        let stored = match std::fs::read_to_string(path) {
            Ok(s) => s,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
            Err(e) => panic!("{path}: {e}"),
        };
        let first_difference = stored
            .lines()
            .zip(text.lines())
            .position(|(a, b)| a != b)
            .map(|i| {
                let line = |s: &str| s.lines().nth(i).unwrap_or("").to_string();
                format!(
                    "line {}: stored {:?}, produced {:?}",
                    i + 1,
                    line(&stored),
                    line(&text)
                )
            })
            .unwrap_or_else(|| {
                let (a, b) = (stored.lines().count(), text.lines().count());
                format!("{a} lines stored, {b} produced")
            });
        assert!(
            stored == text,
            "{path} is not what F1Hold produces ({first_difference}); rewrite it with \
             CABLEVIB_BLESS=1 cargo test --release -p cablevib-service --lib hold (and check \
             the Python mirror)"
        );
    }

    /// `ALL` is in the order of the `as usize` values the counts are indexed by.
    #[test]
    fn all_actions_are_in_discriminant_order() {
        for (i, a) in HoldAction::ALL.iter().enumerate() {
            assert_eq!(*a as usize, i, "{a:?}");
        }
    }

    /// Bad parameters are one-line errors naming the value.
    #[test]
    fn bad_parameters_are_errors() {
        let p = params();
        for (bad, what) in [
            (
                HoldParams {
                    required_hz: -1.0,
                    ..p
                },
                "hold-f1",
            ),
            (
                HoldParams {
                    required_hz: f64::NAN,
                    ..p
                },
                "hold-f1",
            ),
            (
                HoldParams {
                    guard_hz: -0.1,
                    ..p
                },
                "guard",
            ),
            (
                HoldParams {
                    relax_band_hz: 0.05,
                    ..p
                },
                "relax band",
            ),
            (
                HoldParams {
                    relax_rate_n_per_s: 0.0,
                    ..p
                },
                "relax rate",
            ),
            (
                HoldParams {
                    relax_rate_n_per_s: f64::INFINITY,
                    ..p
                },
                "relax rate",
            ),
            (
                HoldParams {
                    floor_n: 400.0,
                    ..p
                },
                "floor",
            ),
            (
                HoldParams {
                    ceiling_n: f64::NAN,
                    ..p
                },
                "ceiling",
            ),
        ] {
            let e = bad.checked().unwrap_err().to_string();
            assert!(e.contains(what) && !e.contains('\n'), "{e}");
        }
    }
}
