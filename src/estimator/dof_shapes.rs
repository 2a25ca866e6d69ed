//! Whole mode shapes from eigenvectors in the dense assembly's DOF order: the end-effector
//! (0..dim), then each cable's interior nodes from the anchor, 3 world-frame DOF each
//! ([`crate::modal::assemble`], [`crate::modal::assemble_sagged`]). The anchor node is held
//! (zero) and the end node is the end-effector's attachment G_i φ_ee; the shapes carry the
//! element masses of the pose, so their mass form ([`ModeShapes::mass_overlap`]) is the
//! assembled M's. One conversion for the Rayleigh–Ritz update of taut chains
//! ([`super::ritz_basis`]) and the dense basis of sagging ones ([`super::dense_sag_basis`]).

use crate::kinematics::attach_map;
use crate::modal::{ModeShape, ModeShapes};
use nalgebra::{DMatrix, Matrix6, Vector3, Vector6};

/// Relative width within which eigenvalues are one cluster (the structured engine's
/// clusters are exact to rounding; a dense or Ritz pair's λ is within a few ε·λ_max of an
/// exact multiple one, a Ritz value within ρ²λ of its limit).
pub(super) const CLUSTER_REL: f64 = 1e-9;

/// The nodes a DOF vector is read onto: the end-effector's DOF, each cable's node count
/// (N + 1, anchor and end included), fractions and element mass, and each cable's
/// attachment arm (rigid end-effector only).
pub(super) struct DofLayout<'a> {
    /// 3 (point mass) or 6 (rigid body).
    pub dim: usize,
    /// Each cable's node fractions j/N ([`ModeShapes::fractions`]).
    pub fractions: &'a [Vec<f64>],
    /// Each cable's element mass, kg.
    pub element_mass_kg: &'a [f64],
    /// Each cable's attachment arm from the centroid, m (world frame; ignored for a point
    /// mass).
    pub arm_m: &'a [Vector3<f64>],
}

impl DofLayout<'_> {
    /// The DOF a vector of this layout has: dim + 3 (N − 1) per cable.
    pub(super) fn dof(&self) -> usize {
        self.dim
            + self
                .fractions
                .iter()
                .map(|f| 3 * f.len().saturating_sub(2))
                .sum::<usize>()
    }

    /// The shapes of the columns `0..lambda.len()` of `vectors` (M-orthonormal, with the
    /// eigenvalues `lambda` ascending, rad²/s²), their end-effector participations
    /// φ_eeᵀ M_ee φ_ee and clusters (neighbours within [`CLUSTER_REL`] relative plus
    /// `width`, rad²/s²: a dense solve's absolute accuracy); `residual` each one's
    /// [`ModeShape::null_residual`] (NaN where missing).
    pub(super) fn shapes(
        &self,
        lambda: &[f64],
        vectors: &DMatrix<f64>,
        residual: &[f64],
        ee_mass: &Matrix6<f64>,
        width: f64,
    ) -> ModeShapes {
        let dim = self.dim;
        let attach: Vec<_> = (0..self.fractions.len())
            .map(|i| match self.arm_m.get(i) {
                Some(arm) if dim == 6 => attach_map(arm),
                _ => attach_map(&Vector3::zeros()),
            })
            .collect();
        let q = lambda.len();
        let mut space = ModeShapes {
            dim,
            fractions: self.fractions.to_vec(),
            modes: Vec::with_capacity(q),
            element_mass_kg: self.element_mass_kg.to_vec(),
            hidden_element_mass_kg: vec![0.0; self.fractions.len()],
        };
        for (c, &lambda) in lambda.iter().enumerate() {
            let mut ee = Vector6::zeros();
            for r in 0..dim {
                ee[r] = vectors[(r, c)];
            }
            let mut base = dim;
            let mut cables = Vec::with_capacity(self.fractions.len());
            for (i, f) in self.fractions.iter().enumerate() {
                let count = f.len();
                let mut cable = vec![Vector3::zeros(); count];
                for (j, node) in cable.iter_mut().enumerate().take(count - 1).skip(1) {
                    let at = base + 3 * (j - 1);
                    *node =
                        Vector3::new(vectors[(at, c)], vectors[(at + 1, c)], vectors[(at + 2, c)]);
                }
                cable[count - 1] = attach[i] * ee;
                base += 3 * (count - 2);
                cables.push(cable);
            }
            let cluster_start = match space.modes.last() {
                Some(prev) if lambda - prev.lambda <= CLUSTER_REL * lambda + width => {
                    prev.cluster_start
                }
                _ => c,
            };
            space.modes.push(ModeShape {
                lambda,
                frequency_hz: crate::modal::lambda_to_hz(lambda),
                ee,
                cables,
                hidden: vec![Vec::new(); self.fractions.len()],
                ee_participation: (ee.transpose() * ee_mass * ee)[(0, 0)],
                cluster_start,
                multiplicity: 1,
                null_residual: residual.get(c).copied().unwrap_or(f64::NAN),
            });
        }
        // Multiplicities from the clusters.
        for c in 0..q {
            let s = space.modes[c].cluster_start;
            let end = (s..q)
                .find(|&j| j > s && space.modes[j].cluster_start != s)
                .unwrap_or(q);
            space.modes[c].multiplicity = (end - s) as u32;
        }
        space
    }
}
