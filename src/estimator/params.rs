//! [`EstimatorParams`]: solver parameters and the cycle's warm-start and input tolerances.

use crate::modal::ModalParams;
use crate::tension::TensionParams;

/// Parameters of the estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatorParams {
    /// Tension solver parameters.
    pub tension: TensionParams,
    /// Eigen solver parameters.
    pub modal: ModalParams,
    /// A pose step larger than this (m) forces a cold start.
    pub warm_jump_m: f64,
    /// A relative T_min change larger than this forces a cold start.
    pub warm_t_min_change: f64,
    /// Tolerance on the quaternion norm.
    pub quaternion_tol: f64,
    /// Compute the end-effector mode (costs a scan over the string modes below it).
    pub ee_mode: bool,
}

impl Default for EstimatorParams {
    fn default() -> Self {
        EstimatorParams {
            tension: TensionParams::default(),
            modal: ModalParams::default(),
            warm_jump_m: 0.005,
            warm_t_min_change: 1e-3,
            quaternion_tol: 1e-6,
            ee_mode: true,
        }
    }
}
