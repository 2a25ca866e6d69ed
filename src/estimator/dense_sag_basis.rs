//! The shapes of a sagging robot's basis by one dense solve where that is cheaper than the
//! structured shapes: sagged FEM chains without hidden cables, K a large share of the DOF.
//!
//! The structured engine ([`crate::modal::SagModalSolver::mode_shapes`]) finds each cluster
//! by the count and a root search, then its shape from the SVD of the (dim + 3·cables)²
//! bordered system: ~0.24 ms per mode on `suspended_8` (fem × 10, 219 DOF), ~35 ms for its
//! 147-mode basis. The dense model ([`crate::modal::assemble_sagged`]: the same elements,
//! assembled in world coordinates) gives every mode at once: M = LLᵀ, the eigenpairs of
//! L⁻¹KL⁻ᵀ, u = L⁻ᵀy (M-orthonormal), O(n³): ~15 ms at 219 DOF with nalgebra's symmetric QR
//! when the threshold below was measured; the lowest pairs by [`crate::modal::sym_eigen`]
//! now take about 4 ms of it, so the threshold is conservative (it was kept: a lower one
//! moves smaller bases onto the dense path, unmeasured).
//! So the dense solve is taken when n³ ≤ [`DENSE_DOF3_PER_MODE`] · K and n ≤
//! [`MAX_DENSE_SAG_DOF`]: on `suspended_8` at fem × 10 from K ≈ 63 modes on.
//!
//! **Accuracy.** The dense solve's eigenvalues are within a small multiple of ε‖L⁻¹KL⁻ᵀ‖
//! = ε λ_max of exact (backward stable), so the low modes carry an absolute error
//! ~ε λ_max: on `suspended_8` λ_max/λ_1 ≈ 10⁷, 10⁻⁹ of λ_1, a phase error of 10⁻⁸ rad
//! over the 2.5 s of its S-curve. Eigenvalues closer than [`CLUSTER_WIDTH_EPS`] · ε λ_max
//! are one cluster (a cut is never placed inside an exactly multiple eigenvalue the
//! rounding splits). The shapes are read onto the structured shapes' nodes
//! ([`super::dof_shapes`]), so the influence fields, the loads and the mass overlap are
//! formed from them exactly as from the structured ones. tests/sag/dense_basis.rs holds the
//! basis against the structured engine's at the same pose.

use super::dof_shapes::{DofLayout, CLUSTER_REL};
use super::modes::DenseSolve;
use super::{BasisError, Estimator};
use crate::modal::ModeShapes;

/// n³ per mode up to which the dense solve is taken (module docs: 219³ ≈ 1.05·10⁷ for
/// 15 ms against 0.24 ms per structured mode, so the solves cost alike at K ≈ 63 there).
pub const DENSE_DOF3_PER_MODE: f64 = 1.7e5;

/// Largest sagged model solved densely for a basis, DOF (n² doubles for each of K, M and
/// the eigenvectors: 3 × 2.9 MB at the bound; the dense solve then ~0.3 s against the
/// structured shapes of up to [`crate::modal::response::MAX_RESPONSE_MODES`] modes).
pub const MAX_DENSE_SAG_DOF: usize = 600;

/// Width, in units of ε λ_max, within which a dense solve's eigenvalues are one cluster
/// (module docs).
pub const CLUSTER_WIDTH_EPS: f64 = 1e3;

/// Whether the dense solve pays for `modes` modes of a model of `dof` DOF (module docs).
pub fn dense_sag_pays(dof: usize, modes: usize) -> bool {
    dof <= MAX_DENSE_SAG_DOF && (dof as f64).powi(3) <= DENSE_DOF3_PER_MODE * modes as f64
}

impl Estimator {
    /// The first `k` modes (a cluster cut completed) of the sagged FEM model at the last
    /// cycle's pose by the dense solve (module docs), as whole shapes on the structured
    /// shapes' nodes. `Ok(None)` where it does not apply (taut or continuous cables, a
    /// hidden cable, beyond [`MAX_DENSE_SAG_DOF`]) or does not pay ([`dense_sag_pays`]).
    pub(super) fn sag_dense_shapes(&mut self, k: usize) -> Result<Option<ModeShapes>, BasisError> {
        let (ee_mass, dim, _) = self.ee_mass_flexibility();
        let Some((solver, _, _, geometry)) = self.cycle.sag_shapes_input() else {
            return Ok(None);
        };
        if solver.is_continuous() {
            return Ok(None);
        }
        let cables = solver.loaded_cables();
        if (0..cables).any(|i| solver.chain(i).support().is_some()) {
            return Ok(None);
        }
        let fractions: Vec<Vec<f64>> = (0..cables)
            .map(|i| {
                let n = solver.chain(i).n_el().max(1);
                (0..=n).map(|j| j as f64 / n as f64).collect()
            })
            .collect();
        let element_mass_kg: Vec<f64> = (0..cables)
            .map(|i| solver.chain(i).element_mass_kg())
            .collect();
        let arm_m = geometry.arm_m.clone();
        let layout = DofLayout {
            dim,
            fractions: &fractions,
            element_mass_kg: &element_mass_kg,
            arm_m: &arm_m,
        };
        let n = layout.dof();
        if !dense_sag_pays(n, k.max(1)) {
            return Ok(None);
        }
        let (kk, mm) = self
            .cycle
            .dense_matrices(&self.scene)
            .map_err(|e| BasisError::Estimator(e.into()))?;
        if kk.nrows() != n {
            return Ok(None);
        }
        let solve = DenseSolve::new(&kk, &mm).map_err(BasisError::Estimator)?;
        let lambda = &solve.lambda;
        let lambda_max = lambda.last().copied().unwrap_or(0.0).abs();
        let width = CLUSTER_WIDTH_EPS * f64::EPSILON * lambda_max;
        let mut kept = k.clamp(1, n);
        while kept < n && lambda[kept] - lambda[kept - 1] <= CLUSTER_REL * lambda[kept] + width {
            kept += 1;
        }
        let vectors = solve.vectors(kept).map_err(BasisError::Estimator)?;
        Ok(Some(layout.shapes(
            &lambda[..kept],
            &vectors,
            &[],
            &ee_mass,
            width,
        )))
    }
}
