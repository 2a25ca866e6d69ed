//! Mode shapes of sagging cables ([`SagSystem`], behind
//! [`SagModalSolver::mode_shapes`](crate::modal::SagModalSolver::mode_shapes)): the bordered system of
//! the module docs with the sagged FEM chains ([`crate::cable::sagged`]) in place of the
//! uniform scalar ones.
//!
//! **One chain at λ.** Cable i's element j has the in-plane stiffness K_j (2 × 2 in
//! (h, up)), the out-of-plane one k_j, and the consistent mass (m/6)[2I I; I 2I]; in the
//! cable's frame (h, up, n) they form the 3 × 3 K_j = diag(K_j^in, k_j). Its interior
//! equations at λ, with the anchor held (u₀ = 0),
//!
//! ```text
//!     −(K_{j−1} + λm/6) u_{j−1} + (K_{j−1} + K_j − 2λm/3) u_j − (K_j + λm/6) u_{j+1} = 0
//! ```
//!
//! for j = 1 … N − 1, are solved forward from u₁ (K_j + λm/6 is positive definite, so
//! u_{j+1} always exists): the three columns Y (u₁ = e_h, e_up, e_n; re-orthonormalised at
//! each element, `sag_chain_shape`) span every interior solution, u_j = Y_j a with a free
//! amplitude a ∈ ℝ³. The end value is Y_N a and the force the chain puts on its end node per unit
//! amplitude F = (K_{N−1} − λm/3) Y_N − (K_{N−1} + λm/6) Y_{N−1}; F Y_N⁻¹ is the chain's
//! condensed stiffness S(λ) = diag(S_in, s_out) (the one D(λ) sums).
//!
//! **Bordered system.** With E_i = [h_i up n_i] and G_i the attachment map (I for a point
//! mass), the unknowns (φ, a_1 … a_n) (dim + 3n of them) satisfy
//!
//! ```text
//!     (K_ee − λ M_ee) φ + Σ_i G_iᵀ E_i F_i a_i = 0
//!     σ_i (E_iᵀ G_i φ − Y_N,i a_i)            = 0     for every cable i
//! ```
//!
//! (σ_i the size of the last element's stiffness plus λm/2). Its null space at an eigenvalue
//! λ of multiplicity m is the eigenspace, including modes with the end-effector still
//! (Y_N,i singular: λ is a blocked eigenvalue of cable i) where D(λ) has a pole. It is taken
//! by the taut shapes' equilibrated SVD with the same separation test
//! ([`ShapeParams::null_tol`]).
//!
//! **Hidden cable** ([`SagChain::set_support`]). Node 0 is the junction at the pulley: it
//! moves along the anchor tangent d (in (h, up)) and is held there by the hidden cable's
//! N_h axial elements (k_h, m_h) from the fixed drum. A fourth solution joins the three:
//! the hidden cable from the drum, t_0 = 0, t_1 = 1, β_h t_{j−1} + 2α_h t_j + β_h t_{j+1} = 0
//! (α_h = k_h − λm_h/3, β_h = −k_h − λm_h/6 < 0), puts the junction at z_0 = d t_{N_h}; with
//! z_1 = 0 the same interior equations give z_2 … z_N (t to largest entry 1; z the fourth
//! column of the re-orthonormalised state). Every solution of the chain and its hidden cable is u_j = Y_j a + z_j c
//! (hidden nodes c t_j): the amplitude c is one more unknown, and the junction's own
//! equation along d one more row,
//!
//! ```text
//!     σ_J (dᵀ(K_0 − λm/3) u_0 + dᵀ(−K_0 − λm/6) u_1 + α_h c t_{N_h} + β_h c t_{N_h−1}) = 0
//! ```
//!
//! (the free cable's first element and the hidden cable's last). The end force and end
//! value gain F_z c and z_N c. The columns c and rows of the junctions come after every
//! a_i and end row, so a robot without hidden cables has the same bordered matrix. The
//! shapes draw node 0 as the junction's motion d c t_{N_h} (world frame); the hidden
//! cable's nodes c t_j are given apart (`ModeShape::hidden`, as the taut hidden-cable
//! shapes') and enter the normalisation:
//! (m_h/6) c_a c_b Σ (2t_j² + 2t_j t_{j+1} + 2t_{j+1}²) over the hidden elements.
//!
//! **Normalisation.** The nodes u_j = Y_j a (interior) and E_iᵀ G_i φ (end) of each null
//! vector give the consistent mass's quadratic form exactly (Σ over the elements of
//! (m/6)(2u_j·v_j + u_j·v_{j+1} + u_{j+1}·v_j + 2u_{j+1}·v_{j+1}), plus φᵀM_eeφ: the dense
//! M's, with the hidden cables' term above); a cluster is M-orthonormalised and rotated as
//! the taut shapes are; clusters that are not one clean eigenvalue are repaired as for
//! every model (`pipeline`: merged, split by the count, or resolved as a near-cluster with
//! the element mass form of chain solutions at two λ, exact for the FEM chains).
//!
//! **Accuracy.** The forward solution is exact in exact arithmetic. Above a chain's
//! transverse cut-off the transverse solution grows like sinh(jφ) along it, and solved
//! alone every column turns towards it, the axial one lost in their rounding; the state of
//! the solutions at two neighbouring nodes is therefore re-orthonormalised after each step
//! (`sag_chain_shape`: the same span, kept well conditioned; the amplitudes a are those of
//! the end's basis). The dense eigenvectors are the check (`tests/sag/shapes.rs`, with and
//! without hidden cables; cli/tests/cli/hidden_sag.rs, the frequency response of the large
//! robots above their cut-off against the dense modal sum). Offline: allocates.

use super::bordered::{element_mass_form, Bordered, Nodes};
use super::sag_chain_shape::SagChainShape;
use super::{ModeShapes, ShapeError, ShapeParams};
use crate::kinematics::attach_map;
use crate::modal::engine::Condensed;
use crate::modal::sagged::SagChains;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix3x6, Matrix6, Vector3, Vector4, Vector6};

/// How one loaded cable attaches: its frame E = [h up n] and attachment map (3 × dim).
pub(super) struct Attach {
    pub(super) frame: Matrix3<f64>,
    pub(super) map: Matrix3x6<f64>,
}

impl<'a> SagSystem<'a> {
    /// The bordered system of the loaded `chains` (FEM chains) and the empty shapes with
    /// its node lists; for
    /// [`SagModalSolver::mode_shapes`](crate::modal::SagModalSolver::mode_shapes), whose
    /// `h`, `up` and `arms_m` are the frames the pose was loaded with. Continuous cables:
    /// [`ShapeError::SagContinuous`].
    pub(in crate::modal) fn new(
        chains: &'a mut SagChains,
        h: &[Vector3<f64>],
        up: &Vector3<f64>,
        arms_m: &[Vector3<f64>],
        params: &ShapeParams,
    ) -> Result<(SagSystem<'a>, ModeShapes), ShapeError> {
        params.check()?;
        if chains.continuous {
            return Err(ShapeError::SagContinuous);
        }
        // A FEM chain's hidden cable is discrete (the continuous bar goes with the
        // continuous chain, refused above).
        let n_cables = chains.loaded_cables();
        let chain = |i: usize| &chains.chains[i];
        if (0..n_cables).any(|i| chain(i).support().is_some_and(|s| s.hidden.n_el == 0)) {
            return Err(ShapeError::HiddenCable);
        }
        let dim = chains.dim;
        if h.len() != n_cables || n_cables == 0 {
            return Err(ShapeError::NotLoaded {
                loaded: n_cables,
                given: h.len(),
            });
        }
        if dim == 6 && arms_m.len() < n_cables {
            return Err(ShapeError::MissingArms {
                given: arms_m.len(),
                cables: n_cables,
            });
        }
        let attach: Vec<Attach> = (0..n_cables)
            .map(|i| {
                let n = h[i].cross(up);
                let map = if dim == 6 {
                    attach_map(&arms_m[i])
                } else {
                    attach_map(&Vector3::zeros())
                };
                Attach {
                    frame: Matrix3::from_columns(&[h[i], *up, n]),
                    map,
                }
            })
            .collect();
        let fractions = (0..n_cables)
            .map(|i| {
                let n = chain(i).n_el().max(1);
                (0..=n).map(|j| j as f64 / n as f64).collect()
            })
            .collect();
        let out = ModeShapes {
            dim,
            fractions,
            modes: Vec::new(),
            element_mass_kg: (0..n_cables).map(|i| chain(i).element_mass_kg()).collect(),
            hidden_element_mass_kg: (0..n_cables)
                .map(|i| chain(i).support().map_or(0.0, |s| s.hidden.m))
                .collect(),
        };
        // The columns of the hidden cables' amplitudes c_i, after every a_i.
        let mut next = dim + 3 * n_cables;
        let hcol: Vec<Option<usize>> = (0..n_cables)
            .map(|i| {
                chain(i).support().map(|_| {
                    next += 1;
                    next - 1
                })
            })
            .collect();
        Ok((
            SagSystem {
                chains,
                attach,
                hcol,
            },
            out,
        ))
    }
}

/// The sagged FEM chains' bordered system (module docs): the loaded chains, how each cable
/// attaches and the columns of the hidden cables' amplitudes.
pub(in crate::modal) struct SagSystem<'a> {
    pub(super) chains: &'a mut SagChains,
    pub(super) attach: Vec<Attach>,
    hcol: Vec<Option<usize>>,
}

impl Bordered for SagSystem<'_> {
    type At = Vec<SagChainShape>;
    type Vector = LocalNodes;

    fn dim(&self) -> usize {
        self.chains.dim
    }

    fn ee_mass(&self) -> Matrix6<f64> {
        self.chains.m6
    }

    fn at(&mut self, lambda: f64) -> Vec<SagChainShape> {
        (0..self.attach.len())
            .map(|i| SagChainShape::fill(&self.chains.chains[i], lambda))
            .collect()
    }

    fn matrix(&self, shapes: &Vec<SagChainShape>, lambda: f64) -> DMatrix<f64> {
        let c = &*self.chains;
        bordered(
            &self.attach,
            shapes,
            &self.hcol,
            &c.m6,
            &c.k6,
            c.dim,
            lambda,
        )
    }

    fn vector(&self, shapes: &Vec<SagChainShape>, col: &DVector<f64>) -> LocalNodes {
        local_nodes(&self.attach, shapes, &self.hcol, col, self.chains.dim)
    }

    fn cable_mass(
        &self,
        at_a: &Vec<SagChainShape>,
        (na, ha): &LocalNodes,
        at_b: &Vec<SagChainShape>,
        (nb, hb): &LocalNodes,
        _same: bool,
    ) -> Option<f64> {
        // The element form is the FEM chains' consistent mass at any two λ.
        Some(
            at_a.iter()
                .zip(at_b)
                .enumerate()
                .map(|(i, (sa, sb))| {
                    element_mass_form(sa.mass_kg, &na[i], &nb[i])
                        + sa.hidden_mass_form(sb, ha[i], hb[i])
                })
                .sum(),
        )
    }

    fn nodes(&self, shapes: &Vec<SagChainShape>, (nodes, amps): &LocalNodes) -> Nodes {
        let cables = nodes
            .iter()
            .zip(&self.attach)
            .map(|(u, at)| u.iter().map(|x| at.frame * x).collect())
            .collect();
        let hidden = shapes
            .iter()
            .zip(amps)
            .map(|(sh, &c)| sh.hidden_nodes(c))
            .collect();
        (cables, hidden)
    }

    fn count(&mut self, lambda: f64) -> u32 {
        self.chains.count(lambda).0
    }
}

/// One null-space vector's shape: each cable's node displacements (m) and its hidden
/// part's amplitudes.
pub(in crate::modal) type LocalNodes = (Vec<Vec<Vector3<f64>>>, Vec<f64>);

/// The bordered matrix at λ (module docs); `hcol` the column of each hidden cable's
/// amplitude (its junction's row the same index).
fn bordered(
    attach: &[Attach],
    shapes: &[SagChainShape],
    hcol: &[Option<usize>],
    m6: &Matrix6<f64>,
    k6: &Matrix6<f64>,
    dim: usize,
    lambda: f64,
) -> DMatrix<f64> {
    let n = dim + 3 * shapes.len() + hcol.iter().flatten().count();
    let mut a = DMatrix::<f64>::zeros(n, n);
    for r in 0..dim {
        for c in 0..dim {
            a[(r, c)] = k6[(r, c)] - lambda * m6[(r, c)];
        }
    }
    for (i, (sh, at)) in shapes.iter().zip(attach).enumerate() {
        let col = dim + 3 * i;
        // G_iᵀ E_i F_i (dim × 4) and σ E_iᵀ G_i (3 × dim).
        let gef = at.map.transpose() * at.frame * sh.force;
        let eg = at.frame.transpose() * at.map;
        // The columns of the amplitudes: the three solutions', then the hidden cable's.
        let cols = [col, col + 1, col + 2, hcol[i].unwrap_or(usize::MAX)];
        for (q, &c) in cols.iter().enumerate().take(sh.ncol) {
            for r in 0..dim {
                a[(r, c)] = gef[(r, q)];
            }
            for r in 0..3 {
                a[(col + r, c)] = -sh.scale * sh.end[(r, q)];
            }
        }
        for r in 0..dim {
            for q in 0..3 {
                a[(col + q, r)] = sh.scale * eg[(q, r)];
            }
        }
        if let (Some(hs), Some(hc)) = (&sh.hidden, hcol[i]) {
            // The junction's row.
            for (q, &c) in cols.iter().enumerate() {
                a[(hc, c)] = hs.scale * hs.row[q];
            }
        }
    }
    a
}

/// Each cable's nodes (cable frame) of a bordered vector, from the anchor or junction on
/// (E_iᵀ G_i φ at the end), and each hidden cable's amplitude (`SagChainShape::nodes`).
fn local_nodes(
    attach: &[Attach],
    shapes: &[SagChainShape],
    hcol: &[Option<usize>],
    col: &DVector<f64>,
    dim: usize,
) -> LocalNodes {
    let mut phi = Vector6::zeros();
    for r in 0..dim {
        phi[r] = col[r];
    }
    shapes
        .iter()
        .zip(attach)
        .enumerate()
        .map(|(i, (sh, at))| {
            let c = hcol[i].map_or(0.0, |r| col[r]);
            let a = Vector4::new(
                col[dim + 3 * i],
                col[dim + 3 * i + 1],
                col[dim + 3 * i + 2],
                c,
            );
            sh.nodes(&a, at.frame.transpose() * (at.map * phi))
        })
        .unzip()
}
