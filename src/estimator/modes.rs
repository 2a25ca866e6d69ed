//! The first K natural frequencies at the pose of the last successful cycle, by the
//! structured engine ([`crate::modal::ModalSolver::modes`]). Offline use: it spends tens of
//! evaluations of D(λ) per mode and leaves the cycle's warm state alone (the eigen solver
//! keeps its loaded problem; only its evaluation counter moves).

use super::{Estimator, EstimatorError, Status};
use crate::modal::{self, DenseModes, Mode};
use nalgebra::DMatrix;

impl Estimator {
    /// The first `k` natural frequencies (ascending) of the pose of the last successful
    /// [`Estimator::update`] into `out`; returns how many were written (min(k, out.len(),
    /// the model's number of modes)). When the last cycle was not ok, its error; before
    /// any cycle, `Modal(NotLoaded)`.
    pub fn modes(&mut self, k: usize, out: &mut [Mode]) -> Result<usize, EstimatorError> {
        match self.estimate.status {
            Status::Ok => Ok(self.cycle.modes(k, out)?),
            _ => Err(self
                .estimate
                .error
                .unwrap_or(EstimatorError::Modal(crate::modal::ModalError::NotLoaded))),
        }
    }
}

impl Estimator {
    /// The dense reference of exactly the models of the last successful cycle (same
    /// tensions, same end-effector): assembled K and M and every eigenvalue, with
    /// participations when `vectors`. Allocates O(DOF²); refused beyond
    /// [`crate::modal::DENSE_MEMORY_BUDGET_BYTES`]. Offline use.
    pub fn dense_modes(&self, vectors: bool) -> Result<DenseModes, EstimatorError> {
        let (k, m) = self.dense_matrices()?;
        let (ee, dim) = self.cycle.ee_mass();
        Ok(modal::dense_modes_ee(&k, &m, &ee, dim, vectors)?)
    }

    /// The assembled K (N/m) and M (kg) of the last successful cycle's models (DOF order of
    /// [`modal::assemble`]: the end-effector's 3 or 6 first, then each cable's interior
    /// nodes from the anchor).
    pub fn dense_matrices(&self) -> Result<(DMatrix<f64>, DMatrix<f64>), EstimatorError> {
        if self.estimate.status != Status::Ok {
            return Err(self
                .estimate
                .error
                .unwrap_or(EstimatorError::Modal(modal::ModalError::NotLoaded)));
        }
        Ok(self.cycle.dense_matrices(&self.scene)?)
    }
}
