//! Point-to-point moves with a stop: the end-effector goes from the scene's position by a
//! displacement `d` (m) in `duration_s` along a straight line, starts and ends at rest, and
//! then holds.
//!
//! - **Trapezoid**: constant acceleration for a third of the time, constant speed, constant
//!   deceleration: peak acceleration 4.5‖d‖/T².
//! - **S-curve**: constant jerk, no plateaus: the acceleration rises linearly to its peak
//!   in T/4, falls to zero at T/2, and mirrors it to decelerate: peak acceleration
//!   8‖d‖/T², continuous acceleration (the jerk is bounded).

use nalgebra::Vector3;

use super::{Samples, TrajectoryError};

/// Most samples a sampled move may have (its duration plus hold over the sample period).
pub const MAX_MOVE_SAMPLES: usize = 10_000_000;

/// The velocity profile of a point-to-point move.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Profile {
    /// Trapezoidal velocity (piecewise-constant acceleration).
    Trapezoid,
    /// S-curve velocity (piecewise-constant jerk).
    SCurve,
}

impl Profile {
    /// The name on the command line (`trapezoid`, `s-curve`).
    pub fn as_str(self) -> &'static str {
        match self {
            Profile::Trapezoid => "trapezoid",
            Profile::SCurve => "s-curve",
        }
    }
}

/// A straight point-to-point move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    /// Start position, m.
    pub start_m: Vector3<f64>,
    /// Displacement, m.
    pub displacement_m: Vector3<f64>,
    /// Time of the move, s (> 0).
    pub duration_s: f64,
    /// Velocity profile.
    pub profile: Profile,
}

impl Move {
    /// A move; refused when a number is not finite, the duration is not > 0 or the
    /// displacement is zero ([`TrajectoryError::ZeroMove`]).
    pub fn new(
        start_m: Vector3<f64>,
        displacement_m: Vector3<f64>,
        duration_s: f64,
        profile: Profile,
    ) -> Result<Move, TrajectoryError> {
        let bad = |what: &'static str, value: f64, bound: &'static str| {
            Err(TrajectoryError::BadCircle { what, value, bound })
        };
        if !(duration_s.is_finite() && duration_s > 0.0) {
            return bad("move duration_s", duration_s, "> 0");
        }
        for v in start_m.iter().chain(displacement_m.iter()) {
            if !v.is_finite() {
                return bad("move coordinate", *v, "finite");
            }
        }
        if displacement_m == Vector3::zeros() {
            return Err(TrajectoryError::ZeroMove);
        }
        Ok(Move {
            start_m,
            displacement_m,
            duration_s,
            profile,
        })
    }

    /// The fraction s(τ) ∈ [0, 1] of the way covered at τ = t/T (0 before, 1 after).
    pub fn fraction(&self, tau: f64) -> f64 {
        if tau <= 0.0 {
            return 0.0;
        }
        if tau >= 1.0 {
            return 1.0;
        }
        match self.profile {
            Profile::Trapezoid => {
                // a = 4.5 on [0, 1/3), 0, −4.5 on [2/3, 1].
                let a = 4.5;
                if tau < 1.0 / 3.0 {
                    0.5 * a * tau * tau
                } else if tau < 2.0 / 3.0 {
                    0.25 + 1.5 * (tau - 1.0 / 3.0)
                } else {
                    let r = 1.0 - tau;
                    1.0 - 0.5 * a * r * r
                }
            }
            Profile::SCurve => {
                // jerk j = 32 on [0, 1/4), −32 on [1/4, 3/4), +32 on [3/4, 1]:
                // peak acceleration 8 at 1/4, peak speed 2 at 1/2.
                let j = 32.0;
                if tau < 0.25 {
                    j * tau.powi(3) / 6.0
                } else if tau <= 0.5 {
                    let u = tau - 0.25;
                    1.0 / 12.0 + u + 4.0 * u * u - j * u.powi(3) / 6.0
                } else {
                    1.0 - Move {
                        profile: Profile::SCurve,
                        ..*self
                    }
                    .fraction(1.0 - tau)
                }
            }
        }
    }

    /// The position at time `t_s`, m.
    pub fn position_at(&self, t_s: f64) -> Vector3<f64> {
        self.start_m + self.displacement_m * self.fraction(t_s / self.duration_s)
    }

    /// The move sampled every `dt_s` from 0 to its end plus `hold_s` at rest. The samples
    /// always reach the end: the last is at or after the move's duration (rounding the
    /// sample count down would stop short of the target, and a move shorter than half a
    /// sample period would be dropped whole, its two samples both at the start). A move
    /// faster than the sampling is then the jump it is, which the path's acceleration bound
    /// refuses.
    pub fn sampled(&self, dt_s: f64, hold_s: f64) -> Result<Samples, TrajectoryError> {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            let (what, value, bound) = ("sample period_s", dt_s, "> 0");
            return Err(TrajectoryError::BadCircle { what, value, bound });
        }
        if !(hold_s.is_finite() && hold_s >= 0.0) {
            let (what, value, bound) = ("hold_s", hold_s, "≥ 0");
            return Err(TrajectoryError::BadCircle { what, value, bound });
        }
        // The relative 1e-9 keeps a duration that is a whole number of periods up to
        // rounding (0.5 s / 1 ms) at that number.
        let to_end = (self.duration_s / dt_s * (1.0 - 1e-9)).ceil();
        let n = ((self.duration_s + hold_s) / dt_s).round().max(to_end);
        if !(n < MAX_MOVE_SAMPLES as f64) {
            let (what, value, bound) = ("move samples", n, "below 1e7");
            return Err(TrajectoryError::BadCircle { what, value, bound });
        }
        let n = n as usize;
        let mut s = Samples {
            t_s: Vec::with_capacity(n + 1),
            position_m: Vec::with_capacity(n + 1),
            ..Samples::default()
        };
        for k in 0..=n {
            let t = k as f64 * dt_s;
            s.t_s.push(t);
            s.position_m.push(self.position_at(t));
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn second_difference(m: &Move, t: f64, h: f64) -> f64 {
        (m.fraction((t + h) / m.duration_s) - 2.0 * m.fraction(t / m.duration_s)
            + m.fraction((t - h) / m.duration_s))
            / (h * h)
    }

    #[test]
    fn the_samples_reach_the_end_of_every_move() {
        let start = Vector3::new(0.0, 0.0, 1.25);
        let d = Vector3::new(0.1, 0.0, 0.0);
        let dt = 1e-3;
        // Shorter than dt/2 (dropped whole before), a fraction below .5 of dt over a whole
        // number (its end cut before), whole numbers of dt (unchanged: 2, 11, 501 samples).
        for (duration, samples) in [
            (1e-9, 2),
            (4e-4, 2),
            (1.5e-3, 3),
            (1.04e-2, 12),
            (1e-3, 2),
            (1e-2, 11),
            (0.5, 501),
        ] {
            for profile in [Profile::SCurve, Profile::Trapezoid] {
                let m = Move::new(start, d, duration, profile).unwrap();
                let s = m.sampled(dt, 0.0).unwrap();
                assert_eq!(s.t_s.len(), samples, "{duration} s");
                assert!(*s.t_s.last().unwrap() >= duration, "{duration} s");
                assert_eq!(*s.position_m.last().unwrap(), start + d, "{duration} s");
            }
        }
    }

    #[test]
    fn profiles_are_continuous_and_reach_their_peak_acceleration() {
        for profile in [Profile::Trapezoid, Profile::SCurve] {
            let m = Move::new(Vector3::zeros(), Vector3::x(), 1.0, profile).unwrap();
            let mut last = 0.0;
            for k in 0..=10_000 {
                let s = m.fraction(k as f64 / 10_000.0);
                assert!(
                    s >= last - 1e-15 && (s - last) < 3e-4,
                    "{profile:?} {k}: {s}"
                );
                last = s;
            }
            assert_eq!(m.fraction(1.0), 1.0);
            // mid-move speed: trapezoid 1.5, S-curve 2 (‖d‖/T units)
            let v = (m.fraction(0.5 + 1e-6) - m.fraction(0.5 - 1e-6)) / 2e-6;
            let want = if profile == Profile::Trapezoid {
                1.5
            } else {
                2.0
            };
            assert!((v - want).abs() < 1e-6, "{profile:?}: v {v}");
            let (t, want) = match profile {
                Profile::Trapezoid => (0.1, 4.5),
                Profile::SCurve => (0.2, 6.4), // 8 at 1/4, linear from 0
            };
            let a = second_difference(&m, t, 1e-4);
            assert!((a - want).abs() < 1e-3, "{profile:?}: a {a}");
        }
        assert!(Move::new(Vector3::zeros(), Vector3::x(), 0.0, Profile::SCurve).is_err());
        assert!(matches!(
            Move::new(Vector3::zeros(), Vector3::zeros(), 1.0, Profile::SCurve),
            Err(TrajectoryError::ZeroMove)
        ));
        assert!(Move::new(
            Vector3::zeros(),
            Vector3::x() * f64::NAN,
            1.0,
            Profile::SCurve
        )
        .is_err());
    }
}
