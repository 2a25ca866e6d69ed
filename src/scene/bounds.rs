//! The one validity rule of a lower tension bound T_min (N), shared by scene validation, the
//! estimator's input check and the service's set-points: a T_min the scene file would refuse
//! is refused everywhere.
//!
//! T_min must be finite, at least [`T_MIN_FLOOR_N`] (positive and not subnormal) and at most
//! T_max. Zero is refused because a cable at zero tension has no transverse stiffness: the
//! structure loses rank and every estimate would fail. Subnormal values are refused because
//! they carry fewer significant digits than the arithmetic assumes (squares and products
//! underflow to 0), which is zero in all but name. Every normal positive value is accepted:
//! the model is exact down to the smallest tensions tested (the √T_min law of a slack cable
//! holds to 1e-9 relative at 1e-9 N), so a larger, physical floor would be a policy of the
//! robot, which belongs in its scene's t_min, not in this rule.

/// Smallest accepted T_min, N: the smallest positive normal `f64` (about 2.2e-308).
pub const T_MIN_FLOOR_N: f64 = f64::MIN_POSITIVE;

/// Why a T_min was refused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum TminRangeError {
    /// NaN or infinite.
    #[error("t_min must be finite, got {t_min_n:?} N")]
    NotFinite {
        /// The value given, N.
        t_min_n: f64,
    },
    /// Zero, negative or subnormal.
    #[error("t_min must be > 0 N and not subnormal (≥ {T_MIN_FLOOR_N:e} N), got {t_min_n:?} N")]
    BelowFloor {
        /// The value given, N.
        t_min_n: f64,
    },
    /// Above the upper bound.
    #[error("t_min = {t_min_n:?} N exceeds t_max = {t_max_n:?} N")]
    AboveTmax {
        /// The value given, N.
        t_min_n: f64,
        /// The upper bound, N.
        t_max_n: f64,
    },
}

/// Checks `t_min_n` (N) against the rule of this module, with the upper bound `t_max_n` (N).
/// A non-finite `t_max_n` refuses every value (as too large).
pub fn check_t_min(t_min_n: f64, t_max_n: f64) -> Result<(), TminRangeError> {
    if !t_min_n.is_finite() {
        return Err(TminRangeError::NotFinite { t_min_n });
    }
    if t_min_n < T_MIN_FLOOR_N {
        return Err(TminRangeError::BelowFloor { t_min_n });
    }
    if !(t_min_n <= t_max_n && t_max_n.is_finite()) {
        return Err(TminRangeError::AboveTmax { t_min_n, t_max_n });
    }
    Ok(())
}

/// Whether `t_min_n` (N) passes [`check_t_min`] with upper bound `t_max_n` (N).
pub fn is_valid_t_min(t_min_n: f64, t_max_n: f64) -> bool {
    check_t_min(t_min_n, t_max_n).is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_subnormal_negative_nan_and_above_t_max_are_refused() {
        let subnormal = f64::MIN_POSITIVE / 2.0;
        assert!(subnormal > 0.0 && !subnormal.is_normal());
        for bad in [0.0, -0.0, subnormal, -1.0, f64::NAN, f64::INFINITY, 351.0] {
            assert!(check_t_min(bad, 350.0).is_err(), "{bad} accepted");
        }
        assert!(matches!(
            check_t_min(0.0, 350.0),
            Err(TminRangeError::BelowFloor { .. })
        ));
        assert!(matches!(
            check_t_min(f64::NAN, 350.0),
            Err(TminRangeError::NotFinite { .. })
        ));
        assert!(check_t_min(10.0, f64::NAN).is_err());
    }

    #[test]
    fn the_floor_and_t_max_themselves_are_accepted() {
        for good in [T_MIN_FLOOR_N, 1e-9, 60.0, 350.0] {
            assert_eq!(check_t_min(good, 350.0), Ok(()), "{good}");
        }
    }
}
