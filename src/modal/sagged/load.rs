//! Setting up [`SagChains`] at one pose: each cable's chain (FEM on its catenary, or the
//! continuous chain), its hidden cable and swivel pulley, then the pose loaded. No
//! allocation.

use super::problem::SagChains;
use super::{SagCableFrame, SagEndEffector, SagLoadError};
use crate::cable::sagged::{SagChain, SagContMesh, SagSupport};
use crate::elastic_catenary::Catenary;
use nalgebra::{Matrix3, Vector3};

impl SagChains {
    /// Cable i's chain, to be set (e.g. [`SagChain::set_fem`]) before [`Self::load`].
    pub(in crate::modal) fn chain_mut(&mut self, i: usize) -> &mut SagChain {
        self.loaded = false;
        &mut self.chains[i]
    }

    /// Set cable i's continuous chain on catenary `cat` with mass `mu_kg_m` per unstretched
    /// length (a problem built for continuous chains).
    pub(in crate::modal) fn set_continuous(
        &mut self,
        i: usize,
        cat: &Catenary,
        mu_kg_m: f64,
    ) -> Result<SagContMesh, SagLoadError> {
        self.loaded = false;
        self.check_continuous_index(i)?;
        let mesh = self.cont[i]
            .set(cat, mu_kg_m)
            .map_err(|e| SagLoadError::Continuous(i, e))?;
        self.cont_static[i] = self.cont[i].static_eval();
        Ok(mesh)
    }

    /// Put cable i's continuous chain on the hidden cable `support`.
    pub(in crate::modal) fn support_continuous(
        &mut self,
        i: usize,
        support: Option<SagSupport>,
    ) -> Result<(), SagLoadError> {
        self.loaded = false;
        self.check_continuous_index(i)?;
        self.cont[i]
            .set_support(support)
            .map_err(|e| SagLoadError::Chain(i, e))?;
        self.cont_static[i] = self.cont[i].static_eval();
        Ok(())
    }

    /// Cable i's exit point moves with the end-effector by `map` (None: a fixed anchor);
    /// a map with a non-finite entry is refused (`BadFrame`), a cable index beyond the
    /// problem's (`CableCount`).
    pub(in crate::modal) fn set_exit_motion(
        &mut self,
        i: usize,
        map: Option<Matrix3<f64>>,
    ) -> Result<(), SagLoadError> {
        self.loaded = false;
        let capacity = self.exit_map.len();
        let slot = self.exit_map.get_mut(i).ok_or(SagLoadError::CableCount {
            given: i + 1,
            capacity,
        })?;
        if map.is_some_and(|x| !x.iter().all(|v| v.is_finite())) {
            return Err(SagLoadError::BadFrame(i));
        }
        *slot = map;
        Ok(())
    }

    /// Load `n` cables, cable i's chain set and its frame given by `cable(problem, i)`.
    pub(in crate::modal) fn load_with(
        &mut self,
        n: usize,
        up: &Vector3<f64>,
        ee: &SagEndEffector,
        mut cable: impl FnMut(&mut SagChains, usize) -> Result<SagCableFrame, SagLoadError>,
    ) -> Result<(), SagLoadError> {
        self.loaded = false;
        let capacity = self.chains.len();
        if n > capacity {
            return Err(SagLoadError::CableCount { given: n, capacity });
        }
        self.set_end_effector(ee)?;
        for i in 0..n {
            let frame = cable(self, i)?;
            self.set_cable(i, &frame, up)?;
        }
        self.n = n;
        self.pack();
        self.add_exit_term();
        self.loaded = true;
        Ok(())
    }

    /// Number of cables of the loaded pose (0 before any load).
    pub(in crate::modal) fn loaded_cables(&self) -> usize {
        if self.loaded {
            self.n
        } else {
            0
        }
    }
}
