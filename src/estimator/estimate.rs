//! [`Estimate`], the fixed-size result of one cycle, and its wire [`Status`].

use super::EstimatorError;
use crate::scene::MAX_CABLES;
use nalgebra::{Matrix3, Matrix6};

pub use crate::status::StatusCode as Status;

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
    /// End-effector participation of the first mode (0 ..= 1).
    pub f1_ee_participation: f64,
    /// Frequency of the lowest mode with end-effector participation ≥ the scene's
    /// threshold, Hz (of `ee_mode_age_cycles` cycles ago). NaN when no such mode is known:
    /// none reaches the threshold within the scan's bounds (a very light end-effector, or
    /// its character split across an avoided crossing), the scan is still going on after a
    /// cold start, not ok, or not computed.
    pub ee_mode_hz: f64,
    /// Its participation (≥ the threshold whenever `ee_mode_hz` is a number).
    pub ee_mode_participation: f64,
    /// How many cycles old the end-effector answer is: 0 = computed (and certified) at
    /// this cycle's pose; k > 0 = the answer of k cycles ago, while the work that did not
    /// fit in the cycle's evaluation budget (a band rescan, a cold re-identification) is
    /// continued; `u32::MAX` = none known (`ee_mode_hz` NaN).
    pub ee_mode_age_cycles: u32,
    /// Static end-effector stiffness, translational block, N/m (NaN unless ok).
    pub stiffness_n_m: Matrix3<f64>,
    /// Static end-effector stiffness, 6 × 6 for a rigid body (N/m, N/rad, N·m/rad; the
    /// translational 3 × 3 block for a point mass, zeros elsewhere).
    pub stiffness6: Matrix6<f64>,
    /// 3 (point mass) or 6 (rigid body).
    pub stiffness_dim: usize,
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
            ee_mode_hz: f64::NAN,
            ee_mode_participation: f64::NAN,
            ee_mode_age_cycles: u32::MAX,
            stiffness_n_m: Matrix3::repeat(f64::NAN),
            stiffness6: Matrix6::repeat(f64::NAN),
            stiffness_dim: 3,
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
