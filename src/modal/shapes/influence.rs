//! The quasi-static influence field of the end-effector: the static displacement of every
//! cable node when the end-effector is moved by a unit amount in one of its DOFs, the
//! anchors held (the static condensation r = [I; −K_ii⁻¹ K_ie] of the model, column by
//! column), in the layout of the mode shapes ([`ModeShapes`], one "shape" per DOF).
//!
//! It is the chains' solution at λ = 0 of the shapes' bordered system with the end-effector
//! prescribed: each chain's interior equations with the anchor held have the one-parameter
//! family y = C w(0) (`chain_shape`: w_j = j/N on a uniform chain, linear along a
//! continuous one; the supported chain's from the drum), and its end value fixes the
//! amplitude, C = b_kᵀ e_d / g. On a sagging chain (`sag_chain_shape`) the three (four, with
//! a hidden cable) interior solutions at λ = 0 are combined so that the end node has the
//! attachment point's displacement E_iᵀ G_i e_d (and the junction's equation holds):
//! a 3 × 3 (4 × 4) solve per cable and DOF. Exact to rounding for every chain model,
//! O(N) per cable and DOF. A hidden cable's nodes are its axial displacements
//! ([`ModeShape::hidden`]).

use super::bordered::Nodes;
use super::chain_shape::ChainShape;
use super::sag_chain_shape::SagChainShape;
use super::sagged::SagSystem;
use super::taut::TautSystem;
use super::{ModeShape, ModeShapes, ShapeError};
use nalgebra::{DVector, Matrix4, Vector4, Vector6};

/// The field of DOF `d`: a pseudo-shape at λ = 0 with the end-effector's unit displacement.
fn field_shape(d: usize, (cables, hidden): Nodes) -> ModeShape {
    let mut ee = Vector6::zeros();
    ee[d] = 1.0;
    ModeShape {
        lambda: 0.0,
        frequency_hz: 0.0,
        ee,
        cables,
        hidden,
        ee_participation: 0.0,
        cluster_start: d,
        multiplicity: 1,
        null_residual: 0.0,
    }
}

impl TautSystem<'_> {
    /// The influence field of the loaded pose (module docs), appended to `out` (the
    /// system's empty shapes): one entry per end-effector DOF (3, or 6 for a rigid body),
    /// its `ee` the unit displacement (m, or rad), its `cables` every node's static
    /// displacement (m per m, or m per rad).
    pub(in crate::modal) fn influence_field(&self, out: &mut ModeShapes) {
        let dim = self.chains.p.dim;
        let layout = &self.layout;
        let mut shapes = vec![ChainShape::default(); layout.kinds.len()];
        for (sh, kind) in shapes.iter_mut().zip(&layout.kinds) {
            sh.fill(kind, 0.0);
        }
        for d in 0..dim {
            let mut col = DVector::zeros(dim + layout.copies.len());
            col[d] = 1.0;
            for (q, cp) in layout.copies.iter().enumerate() {
                // g = w(N) > 0 at λ = 0 (the static shape rises from the held anchor).
                let g = shapes[cp.chain].g;
                col[dim + q] = if g != 0.0 { cp.b[d] / g } else { 0.0 };
            }
            out.modes
                .push(field_shape(d, self.col_nodes(&shapes, &col)));
        }
    }
}

impl SagSystem<'_> {
    /// The influence field of the loaded pose on its sagging FEM chains (module docs),
    /// appended to `out` as [`TautSystem::influence_field`]. A cable whose static end map
    /// is singular (no stiffness) is [`ShapeError::NotAnEigenvalue`] at λ = 0.
    pub(in crate::modal) fn influence_field(&self, out: &mut ModeShapes) -> Result<(), ShapeError> {
        let dim = self.chains.dim;
        let singular = ShapeError::NotAnEigenvalue {
            lambda: 0.0,
            multiplicity: 1,
            sigma_m: f64::NAN,
            sigma_next: f64::NAN,
        };
        let statics: Vec<SagChainShape> = (0..self.attach.len())
            .map(|i| SagChainShape::fill(&self.chains.chains[i], 0.0))
            .collect();
        for d in 0..dim {
            let mut cables = Vec::with_capacity(self.attach.len());
            let mut hidden = Vec::with_capacity(self.attach.len());
            for (sh, at) in statics.iter().zip(&self.attach) {
                let end = at.frame.transpose() * at.map.column(d);
                // Amplitudes a: the end node's value (and, on a hidden cable, the
                // junction's equation) from the solutions at λ = 0.
                let mut a = Matrix4::identity();
                a.fixed_view_mut::<3, 3>(0, 0)
                    .copy_from(&sh.end.fixed_view::<3, 3>(0, 0));
                let mut rhs = Vector4::new(end.x, end.y, end.z, 0.0);
                if let (4, Some(hs)) = (sh.ncol, &sh.hidden) {
                    a.fixed_view_mut::<3, 1>(0, 3)
                        .copy_from(&sh.end.fixed_view::<3, 1>(0, 3));
                    a.set_row(3, &hs.row.transpose());
                } else {
                    rhs[3] = 0.0;
                }
                let amp = a.lu().solve(&rhs).ok_or(singular)?;
                let (local, c) = sh.nodes(&amp, end);
                cables.push(local.into_iter().map(|x| at.frame * x).collect());
                hidden.push(sh.hidden_nodes(c));
            }
            out.modes.push(field_shape(d, (cables, hidden)));
        }
        Ok(())
    }
}
