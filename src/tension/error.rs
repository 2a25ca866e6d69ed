//! Errors of the tension distribution; an infeasible wrench carries the closest solution's
//! residual and active bounds.

use crate::input_file::{message_fixed, message_number};

/// Errors of the tension distribution.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum TensionError {
    /// T_min > T_max, or a bound not finite, or T_min < 0.
    #[error(
        "invalid tension bounds: t_min = {} N, t_max = {} N (need 0 ≤ t_min ≤ t_max, finite)",
        message_number(*t_min_n),
        message_number(*t_max_n)
    )]
    InvalidBounds {
        /// Lower bound, N.
        t_min_n: f64,
        /// Upper bound, N.
        t_max_n: f64,
    },
    /// A non-finite wrench or geometry.
    #[error("non-finite wrench or cable geometry")]
    NonFinite,
    /// No tensions within the bounds produce the wrench.
    #[error(
        "tension infeasible: wrench component {} cannot be reached within {}; \
         closest tensions leave a residual force ({}, {}, {}) N, moment ({}, {}, {}) N·m; \
         cables at t_max: {}, at t_min: {}",
        ["f_x", "f_y", "f_z", "m_x", "m_y", "m_z"][*worst_component],
        BoundsFmt(*t_min_n, *t_max_n, *per_cable_bounds),
        Residual(residual_n, 0), Residual(residual_n, 1), Residual(residual_n, 2),
        Residual(residual_n, 3), Residual(residual_n, 4), Residual(residual_n, 5),
        fmt_mask(*at_upper_mask), fmt_mask(*at_lower_mask)
    )]
    Infeasible {
        /// Index (0-2 = force x, y, z; 3-5 = moment x, y, z) of the largest residual.
        worst_component: usize,
        /// A·T_closest − w: force (N) then moment (N·m).
        residual_n: [f64; 6],
        /// Bit i set: cable i at T_max in the closest solution.
        at_upper_mask: u32,
        /// Bit i set: cable i at T_min in the closest solution.
        at_lower_mask: u32,
        /// Lower bound, N (the lowest of the cables' when they differ).
        t_min_n: f64,
        /// Upper bound, N (the highest of the cables' when they differ).
        t_max_n: f64,
        /// The cables' bounds differ: the message then names each cable's own, not one range.
        per_cable_bounds: bool,
    },
    /// The bounded iteration count ran out (should not happen; reported, not hidden).
    #[error("active-set method did not converge in {iterations} iterations")]
    NotConverged {
        /// Iterations done.
        iterations: u32,
    },
    /// The Clarabel reference stopped without a solution or an infeasibility certificate.
    #[error("Clarabel reference stopped with status {status} after {iterations} iterations")]
    ReferenceFailed {
        /// Clarabel's status.
        status: &'static str,
        /// Iterations done.
        iterations: u32,
    },
    /// The Clarabel reference's answer failed its check (equilibrium or bounds) on every
    /// attempt: it is not returned.
    #[error(
        "Clarabel reference rejected its own answer: equilibrium residual {residual_rel:.3e} of the load \
         (tolerance {tol_rel:e}), largest bound excess {bound_violation_n:.3e} N"
    )]
    ReferenceRejected {
        /// ‖A T − w‖∞ relative to the load (NaN for a non-finite answer).
        residual_rel: f64,
        /// The tolerance on `residual_rel`.
        tol_rel: f64,
        /// Largest amount by which a tension left its bounds, N (≤ 0 when none did).
        bound_violation_n: f64,
    },
}

/// Component `.1` of a residual, 4 decimals (compact from 1e6 on: a 1e307 kg mass's
/// residual is `-9.81e307`, not 309 digits).
struct Residual<'a>(&'a [f64; 6], usize);

impl std::fmt::Display for Residual<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&message_fixed(self.0[self.1], 4))
    }
}

struct MaskFmt(u32);
impl std::fmt::Display for MaskFmt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0 == 0 {
            return write!(f, "none");
        }
        let mut first = true;
        for i in 0..32 {
            if self.0 & (1 << i) != 0 {
                if !first {
                    write!(f, ",")?;
                }
                write!(f, "{i}")?;
                first = false;
            }
        }
        Ok(())
    }
}
/// `[60, 350] N` for bounds every cable shares, else the extremes of the cables' own.
struct BoundsFmt(f64, f64, bool);

impl std::fmt::Display for BoundsFmt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.2 {
            false => write!(
                f,
                "[{}, {}] N",
                message_number(self.0),
                message_number(self.1)
            ),
            true => write!(
                f,
                "each cable's own bounds (lowest t_min {} N, highest t_max {} N)",
                message_number(self.0),
                message_number(self.1)
            ),
        }
    }
}

fn fmt_mask(m: u32) -> MaskFmt {
    MaskFmt(m)
}
