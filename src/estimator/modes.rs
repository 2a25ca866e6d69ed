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
            Status::Ok => match self.cycle.sag.as_mut() {
                Some(sag) => Ok(sag.modal.modes(k, out)?),
                None => Ok(self.cycle.modal.modes(k, out)?),
            },
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
        let (ee, _, dim) = match &self.cycle.sag {
            Some(sag) => {
                let (m6, k6) = sag.modal.ee_matrices();
                (m6, k6, sag.modal.dim())
            }
            None => {
                let (m6, k6) = self.cycle.modal.ee_matrices();
                (m6, k6, self.cycle.modal.dim())
            }
        };
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
        if let Some(sag) = &self.cycle.sag {
            return Ok(sag.dense_matrices(&self.cycle.geometry)?);
        }
        let models = &self.cycle.models;
        let (ee, k6) = self.cycle.modal.ee_matrices();
        Ok(if self.scene.rigid {
            let inertia = ee.fixed_view::<3, 3>(3, 3).into_owned();
            let kgeo = k6.fixed_view::<3, 3>(3, 3).into_owned();
            let arms = &self.cycle.geometry.arm_m;
            modal::assemble_rigid(models, self.scene.ee_mass_kg, &inertia, arms, &kgeo)?
        } else {
            modal::assemble(models, self.scene.ee_mass_kg)?
        })
    }
}
