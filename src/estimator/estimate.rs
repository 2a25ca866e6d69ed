//! [`Estimate`], the fixed-size result of one cycle, its parts ([`EeMode`], [`Stiffness`])
//! and its wire [`Status`]. The wire message (the service's `EstimateSample`) codes an
//! absent end-effector mode as NaN and an age of `u32::MAX`; the service converts at its
//! boundary, this type has no such sentinels.

use super::EstimatorError;
use crate::scene::MAX_CABLES;
use nalgebra::{Matrix3, Matrix6};

pub use crate::status::StatusCode as Status;

/// The end-effector mode of a cycle: the lowest mode with end-effector participation ≥ the
/// scene's threshold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EeMode {
    /// Its frequency, Hz (of `age_cycles` cycles ago).
    pub frequency_hz: f64,
    /// Its end-effector participation (≥ the threshold, ≤ 1).
    pub participation: f64,
    /// How many cycles old the answer is: 0 = computed (and certified) at this cycle's pose;
    /// k > 0 = the answer of k cycles ago, while the work that did not fit in the cycle's
    /// evaluation budget (a band rescan, a cold re-identification) is continued.
    pub age_cycles: u32,
}

/// The static end-effector stiffness K = ∂(restoring wrench)/∂(displacement).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stiffness {
    /// K over the displacement (x, y, z in m, then small rotations θx, θy, θz in rad) and
    /// the wrench (force in N, then moment in N·m): blocks N/m, N/rad, N·m/m, N·m/rad. A
    /// point mass has the translational 3 × 3 block and zeros elsewhere.
    pub k6: Matrix6<f64>,
    /// 3 (point mass) or 6 (rigid body): the leading block of `k6` that is the stiffness.
    pub dim: usize,
}

impl Stiffness {
    /// Every entry NaN, of dimension `dim`.
    pub fn unknown(dim: usize) -> Stiffness {
        Stiffness {
            k6: Matrix6::repeat(f64::NAN),
            dim,
        }
    }
    /// The translational block, N/m.
    pub fn translational_n_m(&self) -> Matrix3<f64> {
        self.k6.fixed_view::<3, 3>(0, 0).into_owned()
    }
}

/// The result of one cycle. Fixed size, Copy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Whether the numbers below are valid for this pose.
    pub status: Status,
    /// The detail when `status` is not ok.
    pub error: Option<EstimatorError>,
    /// Number of cables (valid entries of `tensions_n`).
    pub n_cables: usize,
    /// Cable tensions, N (for `TensionInfeasible`: the closest achievable, flagged).
    pub tensions_n: [f64; MAX_CABLES],
    /// First natural frequency of the whole model, Hz (NaN unless ok).
    pub f1_hz: f64,
    /// End-effector participation of the first mode (0 ..= 1; NaN unless ok).
    pub f1_ee_participation: f64,
    /// The lowest mode with end-effector participation ≥ the scene's threshold, with the
    /// age of its answer; None when no such mode is known: none reaches the threshold
    /// within the scan's bounds (a very light end-effector, or its character split across
    /// an avoided crossing), the scan is still going on after a cold start, not ok, or not
    /// computed (`EstimatorParams::ee_mode` off).
    pub ee_mode: Option<EeMode>,
    /// Static end-effector stiffness (NaN entries unless ok; its dimension is the scene's
    /// even then).
    pub stiffness: Stiffness,
    /// Tension solver: active-set changes in this cycle.
    pub tension_iterations: u32,
    /// Tension solver: the previous active set was optimal again.
    pub tension_warm: bool,
    /// Evaluations of the dynamic stiffness D(λ) in this cycle.
    pub eigen_evaluations: u32,
    /// Relative residual of the first root (dimensionless, [`crate::modal::Root::residual`]):
    /// |μ₁(D(λ))| / (λ·max|D'(λ)|) at the solver's last iterate, to first order its
    /// relative distance to the root (≤ 1e-9 on converged answers).
    pub eigen_residual: f64,
    /// The first-mode iteration started cold.
    pub cold_start: bool,
}

impl Estimate {
    /// No pose yet: every number NaN, `n` cables.
    pub(super) fn empty(n: usize) -> Estimate {
        Estimate {
            status: Status::NoPoseYet,
            error: None,
            n_cables: n,
            tensions_n: [f64::NAN; MAX_CABLES],
            f1_hz: f64::NAN,
            f1_ee_participation: f64::NAN,
            ee_mode: None,
            stiffness: Stiffness::unknown(3),
            tension_iterations: 0,
            tension_warm: false,
            eigen_evaluations: 0,
            eigen_residual: f64::NAN,
            cold_start: true,
        }
    }
    /// Tensions of the cables, N.
    pub fn tensions(&self) -> &[f64] {
        &self.tensions_n[..self.n_cables]
    }
    /// True when the status is ok.
    pub fn is_ok(&self) -> bool {
        self.status == Status::Ok
    }
}
