//! The dense reference for sagged cables: the whole robot's K and M assembled in world
//! coordinates, 3 DOF per interior node, each element's 3 × 3 stiffness built from its
//! world chord (not from the in-plane/out-of-plane split the structured solver uses).

use crate::cable::sagged::SagChain;
use crate::kinematics::attach_map;
use crate::modal::dense::{add_hidden_axial, DensePair};
use crate::modal::{check_dense_budget, ModalError};
use nalgebra::{DMatrix, Matrix3, Matrix3x6, Matrix6, Vector3};

/// One cable for the dense assembly.
#[derive(Debug, Clone, Copy)]
pub struct SagDenseCable<'a> {
    /// The cable's chain (set).
    pub chain: &'a SagChain,
    /// Unit horizontal h of its plane, world frame.
    pub h: Vector3<f64>,
    /// Attachment arm from the centroid, world frame, m (rigid end-effector only).
    pub arm_m: Vector3<f64>,
}

/// Assemble K (N/m) and M (kg) of the sagged cables and the end-effector: `m6`, `k6` its
/// mass matrix and geometric stiffness ([`crate::modal::Solver::ee_matrices`]), `dim` 3
/// (point mass: node N of each cable is the end-effector's translation) or 6 (rigid: tied
/// by G_i = [I, −\[r_i\]×]). DOF order: the end-effector (0..dim), then each cable's interior
/// nodes from the anchor, then (a chain on a hidden cable, [`SagChain::set_support`]) the
/// hidden cable's interior nodes from the drum and the junction, one axial DOF each.
/// Element j: K = (EA/l0) c cᵀ + (N_j/l_j)(I − c cᵀ) with the world chord
/// c = h cos + up sin, on [1 −1; −1 1]; M = (m/6)[2I I; I 2I].
pub fn assemble_sagged(
    cables: &[SagDenseCable<'_>],
    up: &Vector3<f64>,
    m6: &Matrix6<f64>,
    k6: &Matrix6<f64>,
    dim: usize,
) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
    let ndof = sagged_assembled_dof(cables.iter().map(|c| c.chain), dim);
    check_dense_budget(ndof)?;
    let mut k = DMatrix::<f64>::zeros(ndof, ndof);
    let mut m = DMatrix::<f64>::zeros(ndof, ndof);
    for r in 0..dim {
        for c in 0..dim {
            k[(r, c)] += k6[(r, c)];
            m[(r, c)] += m6[(r, c)];
        }
    }
    let mut base = dim;
    for cab in cables {
        let n = cab.chain.n_el();
        // Map of the end node onto the end-effector's DOF (3 × dim, the leading columns).
        let g: Matrix3x6<f64> = if dim == 6 {
            attach_map(&cab.arm_m)
        } else {
            let mut g = Matrix3x6::zeros();
            g.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&Matrix3::identity());
            g
        };
        let id = {
            let mut g = Matrix3x6::zeros();
            g.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&Matrix3::identity());
            g
        };
        // The junction at the pulley (a supported chain): one DOF along the anchor
        // tangent, after the cable's interior nodes and the hidden cable's.
        let support = cab.chain.support();
        let junction = support.map(|sp| {
            let d = cab.h * sp.direction[0] + up * sp.direction[1];
            let mut g = Matrix3x6::zeros();
            g.set_column(0, &d);
            let row = base + 3 * n.saturating_sub(1) + sp.hidden.n_el - 1;
            (row, g, 1usize)
        });
        // Node j: 0 anchor (no DOF, or the junction), 1..n−1 interior, n the end (through G).
        let place = |j: usize| -> Option<(usize, Matrix3x6<f64>, usize)> {
            match j {
                0 => junction,
                j if j == n => Some((0, g, dim)),
                j => Some((base + 3 * (j - 1), id, 3)),
            }
        };
        for (j, el) in cab.chain.elements().enumerate() {
            let cw = cab.h * el.chord[0] + up * el.chord[1];
            let cc = cw * cw.transpose();
            let ke = cc * el.k_axial_n_m + (Matrix3::identity() - cc) * (el.axial_n / el.chord_m);
            for (a, na) in [(0usize, j), (1, j + 1)] {
                for (b, nb) in [(0usize, j), (1, j + 1)] {
                    let (Some((ra, la, wa)), Some((rb, lb, wb))) = (place(na), place(nb)) else {
                        continue;
                    };
                    let sg = if a == b { 1.0 } else { -1.0 };
                    let mc = el.mass_kg * if a == b { 1.0 / 3.0 } else { 1.0 / 6.0 };
                    let kk = la.transpose() * (ke * sg) * lb;
                    let mk = la.transpose() * lb * mc;
                    for r in 0..wa {
                        for c in 0..wb {
                            k[(ra + r, rb + c)] += kk[(r, c)];
                            m[(ra + r, rb + c)] += mk[(r, c)];
                        }
                    }
                }
            }
        }
        if let Some(sp) = support {
            add_hidden_axial(
                &mut DensePair(&mut k, &mut m),
                base + 3 * n.saturating_sub(1),
                &sp.hidden,
            );
        }
        base += 3 * n.saturating_sub(1) + hidden_dofs(cab.chain);
    }
    Ok((k, m))
}

/// The degrees of freedom of the sagged model of `chains` with an end-effector of `dim`
/// (3 or 6): [`assemble_sagged`]'s matrix size, the sagged model's DOF count (as
/// [`crate::modal::assembled_dof`] for taut cables).
pub fn sagged_assembled_dof<'a>(chains: impl Iterator<Item = &'a SagChain>, dim: usize) -> usize {
    dim + chains
        .map(|c| 3 * c.n_el().saturating_sub(1) + hidden_dofs(c))
        .sum::<usize>()
}

/// DOFs of a chain's hidden cable: its interior nodes and the junction (0 when the anchor
/// is fixed).
fn hidden_dofs(chain: &SagChain) -> usize {
    chain.support().map_or(0, |s| s.hidden.n_el)
}
