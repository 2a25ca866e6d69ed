//! The offline dense reference: assembled K and M, static condensation, and a dense
//! generalized symmetric eigen-solve. Never on the real-time path.

use super::RigidParts;
use super::{lambda_to_hz, ModalError};
use crate::cable::{CableModel, ChainKind};
use crate::kinematics::attach_map;
use nalgebra::{DMatrix, Matrix3, Matrix3x6, Matrix6, SymmetricEigen, Vector3};

/// Assemble the global K (N/m) and M (kg) of the cable models and the end-effector point
/// mass. DOF order: end-effector (0..3), then for each cable its interior nodes from the
/// anchor side, then (a cable with a hidden part behind its pulley) the hidden cable's
/// interior nodes from the drum and the junction at the pulley, one axial DOF each (the
/// pulley holds the junction transversely). Anchors and drums are fixed and carry no DOF.
pub fn assemble(
    models: &[CableModel],
    ee_mass_kg: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
    assemble_dense(models, ee_mass_kg, None)
}

/// Assemble for a rigid end-effector (6 DOF: translation, rotation): cable i's last node is
/// tied to it by G_i = [I, −\[r_i\]×] (arm r_i, m, world frame); `inertia_kg_m2` is the
/// world-frame inertia about the centroid, `k_geo_rot` the tensions' rotational geometric
/// stiffness (N·m/rad, see [`rigid_geometric_stiffness`](crate::kinematics::rigid_geometric_stiffness)).
pub fn assemble_rigid(
    models: &[CableModel],
    ee_mass_kg: f64,
    inertia_kg_m2: &Matrix3<f64>,
    arms_m: &[Vector3<f64>],
    k_geo_rot: &Matrix3<f64>,
) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
    assemble_dense(models, ee_mass_kg, Some((inertia_kg_m2, arms_m, k_geo_rot)))
}

/// Where an assembly's entries go: K (N/m) and M (kg) added into, entry by entry.
pub trait Assembly {
    /// Add `k` to K and `m` to M at row `r`, column `c`.
    fn add(&mut self, r: usize, c: usize, k: f64, m: f64);
}

/// Dense K and M.
pub struct DensePair<'a>(pub &'a mut DMatrix<f64>, pub &'a mut DMatrix<f64>);

impl Assembly for DensePair<'_> {
    fn add(&mut self, r: usize, c: usize, k: f64, m: f64) {
        self.0[(r, c)] += k;
        self.1[(r, c)] += m;
    }
}

/// One addition to K (N/m) and M (kg) at row `row`, column `col`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Entry {
    /// Row.
    pub row: usize,
    /// Column.
    pub col: usize,
    /// Added to K, N/m.
    pub k: f64,
    /// Added to M, kg.
    pub m: f64,
}

/// The additions of an assembly as a list (an entry may come more than once: its sum is
/// the matrix's entry), for a sparse consumer ([`crate::modal::ritz::Pencil`]): O(elements)
/// memory where the dense matrices take O(DOF²).
#[derive(Debug, Clone, Default)]
pub struct Entries {
    /// The matrices' size, DOF.
    pub dof: usize,
    /// The additions.
    pub list: Vec<Entry>,
}

impl Assembly for Entries {
    /// An addition of zero to both is not kept (it changes no sum; the blocks of a cable in
    /// its own frame are mostly zeros).
    fn add(&mut self, row: usize, col: usize, k: f64, m: f64) {
        if k != 0.0 || m != 0.0 {
            self.list.push(Entry { row, col, k, m });
        }
    }
}

impl Entries {
    /// K and M as dense matrices (the sums of the entries).
    pub fn to_dense(&self) -> (DMatrix<f64>, DMatrix<f64>) {
        let mut k = DMatrix::zeros(self.dof, self.dof);
        let mut m = DMatrix::zeros(self.dof, self.dof);
        let mut pair = DensePair(&mut k, &mut m);
        for e in &self.list {
            pair.add(e.row, e.col, e.k, e.m);
        }
        (k, m)
    }
}

/// [`assemble_general`] into dense matrices, within the dense budget.
fn assemble_dense(
    models: &[CableModel],
    ee_mass_kg: f64,
    rigid: Option<RigidParts<'_>>,
) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
    let ee_dim = if rigid.is_some() { 6 } else { 3 };
    let ndof = assembled_dof(models, ee_dim).ok_or(ModalError::NotAssemblable)?;
    check_dense_budget(ndof)?;
    let mut k = DMatrix::<f64>::zeros(ndof, ndof);
    let mut m = DMatrix::<f64>::zeros(ndof, ndof);
    assemble_general(
        models,
        ee_mass_kg,
        rigid,
        None,
        &mut DensePair(&mut k, &mut m),
    );
    Ok((k, m))
}

/// K and M of [`assemble`] / [`assemble_rigid`] with each cable's interior nodes in its own
/// frame: the orthonormal eigenvectors R_c of its element block K_c (columns, world frame),
/// so that K_c is the diagonal of its eigenvalues there, and the consistent mass, a
/// multiple of the identity, is unchanged. A cable's interior DOFs are then placed by
/// direction (its first direction's nodes from the anchor, then the second's, the third's)
/// rather than by node: each direction is a scalar chain, K and M tridiagonal within it,
/// coupled to the others only through the end-effector (and a pulley's junction). The
/// model is [`assemble`]'s with K_c replaced by R_c diag(d) R_cᵀ (equal to K_c within
/// rounding): a node's world displacement is R_c times its three values here
/// (`frames`).
#[derive(Debug, Clone)]
pub struct CableFrames {
    /// K (N/m) and M (kg), as the assembly's additions (O(elements), no dense matrix).
    pub entries: Entries,
    /// Each cable's frame R_c (orthonormal columns, world frame).
    pub frames: Vec<Matrix3<f64>>,
}

impl CableFrames {
    /// The DOF of a cable's interior node `node` (1 ..= n_el − 1) along its frame's
    /// direction `axis` (0..3), where `base` is the cable's first interior DOF (as in
    /// [`assemble`]: the end-effector's, then the cables' in turn) and `n_el` its elements.
    pub fn dof(base: usize, n_el: usize, node: usize, axis: usize) -> usize {
        base + axis * (n_el - 1) + node - 1
    }
}

/// [`CableFrames`] of a point-mass end-effector (`rigid` None) or a rigid one.
pub fn assemble_in_cable_frames(
    models: &[CableModel],
    ee_mass_kg: f64,
    rigid: Option<RigidParts<'_>>,
) -> Result<CableFrames, ModalError> {
    let frames: Vec<Matrix3<f64>> = models
        .iter()
        .map(|cm| SymmetricEigen::new(0.5 * (cm.kc + cm.kc.transpose())).eigenvectors)
        .collect();
    let ee_dim = if rigid.is_some() { 6 } else { 3 };
    let dof = assembled_dof(models, ee_dim).ok_or(ModalError::NotAssemblable)?;
    let mut entries = Entries {
        dof,
        list: Vec::new(),
    };
    assemble_general(models, ee_mass_kg, rigid, Some(&frames), &mut entries);
    Ok(CableFrames { entries, frames })
}

/// Memory the dense reference may use, bytes: the one budget of the offline work
/// ([`crate::memory_budget::MEMORY_BUDGET_BYTES`], 2 GiB); a dense solve at this size already
/// takes minutes, and beyond it the structured solver is the only sensible path.
pub const DENSE_MEMORY_BUDGET_BYTES: u64 = crate::memory_budget::MEMORY_BUDGET_BYTES;

/// Bytes per DOF² of a dense solve: K and M, the Cholesky factor and its copy, L⁻¹K, C and
/// its symmetrised copy, the eigenvectors, the eigensolver's workspace and the mode shapes
/// (12 n × n f64 matrices at most).
const DENSE_BYTES_PER_DOF2: u64 = 12 * 8;

/// The estimated memory of a dense solve with `dof` degrees of freedom, bytes.
pub fn dense_memory_bytes(dof: usize) -> u64 {
    (dof as u64)
        .saturating_mul(dof as u64)
        .saturating_mul(DENSE_BYTES_PER_DOF2)
}

/// Refuse a dense problem over [`DENSE_MEMORY_BUDGET_BYTES`] before allocating it.
pub fn check_dense_budget(dof: usize) -> Result<(), ModalError> {
    let bytes = dense_memory_bytes(dof);
    if bytes > DENSE_MEMORY_BUDGET_BYTES {
        return Err(ModalError::DenseTooLarge {
            dof,
            bytes,
            budget: DENSE_MEMORY_BUDGET_BYTES,
        });
    }
    Ok(())
}

/// The degrees of freedom of the model of `models` with an end-effector of `ee_dim` (3 or
/// 6): the end-effector's, 3 per interior node of each cable, and one axial DOF per node of
/// the cable behind a pulley (the hidden cable's interior nodes and the junction, as many
/// as its elements). None for continuous cables (no finite assembly). The one count of the
/// model's DOF: [`assemble`] builds matrices of this size, and the structured solver's
/// reports give it.
pub fn assembled_dof(models: &[CableModel], ee_dim: usize) -> Option<usize> {
    if models.iter().any(|m| {
        m.chains[..m.n_chains].iter().any(|c| match c.kind {
            ChainKind::Continuous { .. } => true,
            ChainKind::Supported { free, hidden } => free.n_el == 0 || hidden.n_el == 0,
            ChainKind::Discrete { .. } => false,
        })
    }) {
        return None;
    }
    let interior: usize = models.iter().map(|m| m.n_el - 1).sum();
    let hidden_dofs: usize = models
        .iter()
        .map(|m| hidden_of(m).map_or(0, |h| h.0.n_el))
        .sum();
    Some(ee_dim + 3 * interior + hidden_dofs)
}

/// The assembly of [`assemble`] and [`assemble_rigid`] (the models assemblable:
/// [`assembled_dof`] is Some), into `out`; with `frames`, each cable's interior nodes in
/// its own frame ([`CableFrames`]).
fn assemble_general<A: Assembly>(
    models: &[CableModel],
    ee_mass_kg: f64,
    rigid: Option<RigidParts<'_>>,
    frames: Option<&[Matrix3<f64>]>,
    out: &mut A,
) {
    let ee_dim = if rigid.is_some() { 6 } else { 3 };
    for i in 0..3 {
        out.add(i, i, 0.0, ee_mass_kg);
    }
    if let Some((inertia, _, kgeo)) = rigid {
        for r in 0..3 {
            for c in 0..3 {
                out.add(3 + r, 3 + c, kgeo[(r, c)], inertia[(r, c)]);
            }
        }
    }
    // A node's map onto the DOFs it is placed at, 3 × (used columns of 6): stack
    // matrices, so that the element loop allocates nothing.
    let i3 = Matrix3x6::from_fn(|r, c| if r == c { 1.0 } else { 0.0 });
    let mut base = ee_dim;
    for (ci, cm) in models.iter().enumerate() {
        let n = cm.n_el;
        // Map of the cable's end node onto the end-effector DOFs (3 × ee_dim).
        let g = match rigid {
            Some((_, arms, _)) => attach_map(&arms[ci]),
            None => i3,
        };
        let me = cm.element_mass_kg;
        let hidden = hidden_of(cm);
        let axial = hidden.map(|h| Matrix3x6::from_fn(|r, c| if c == 0 { h.1[r] } else { 0.0 }));
        // In the cable's frame R (CableFrames): K_c is diag(d) = Rᵀ K_c R with the rounding
        // off its diagonal left out, the maps of the end node and the junction Rᵀ G, Rᵀ a,
        // and a node's DOFs a direction's chain apart.
        let (kc, g, axial, stride) = match frames {
            Some(frames) => {
                let r = frames[ci];
                let d = r.transpose() * cm.kc * r;
                (
                    Matrix3::from_diagonal(&d.diagonal()),
                    r.transpose() * g,
                    axial.map(|a| r.transpose() * a),
                    n - 1,
                )
            }
            None => (cm.kc, g, axial, 1),
        };
        // The junction's axial DOF, after the cable's interior nodes and the hidden ones.
        let junction = base + 3 * (n - 1) + hidden.map_or(0, |h| h.0.n_el - 1);
        // Node j: 0 = anchor (fixed, or the junction), 1..n−1 interior, n = end-effector:
        // its first DOF, its map, the map's columns and the step between its DOFs.
        let place = |j: usize| -> Option<(usize, Matrix3x6<f64>, usize, usize)> {
            if j == n {
                Some((0, g, ee_dim, 1))
            } else if j == 0 {
                axial.map(|a| (junction, a, 1, 1))
            } else if stride == 1 {
                Some((base + 3 * (j - 1), i3, 3, 1))
            } else {
                Some((CableFrames::dof(base, n, j, 0), i3, 3, stride))
            }
        };
        for el in 0..n {
            let nodes = [el, el + 1];
            for (ia, &na) in nodes.iter().enumerate() {
                for (ib, &nb) in nodes.iter().enumerate() {
                    let (Some((ra, la, ca, sa)), Some((rb, lb, cb, sb))) = (place(na), place(nb))
                    else {
                        continue;
                    };
                    let sign = if ia == ib { 1.0 } else { -1.0 };
                    let mcoef = if ia == ib { me / 3.0 } else { me / 6.0 };
                    let kk = la.transpose() * (kc * sign) * lb;
                    let mk = la.transpose() * lb * mcoef;
                    for r in 0..ca {
                        for c in 0..cb {
                            out.add(ra + r * sa, rb + c * sb, kk[(r, c)], mk[(r, c)]);
                        }
                    }
                }
            }
        }
        if let Some((seg, _)) = hidden {
            add_hidden_axial(out, base + 3 * (n - 1), &seg);
            base += seg.n_el;
        }
        base += 3 * (n - 1);
    }
}

/// Add a hidden cable's `seg.n_el` scalar axial elements, from the drum (node 0, fixed) to
/// the junction (node `seg.n_el`), to K (N/m) and M (kg): node j ≥ 1 at row `first + j − 1`.
/// Element: seg.k [1 −1; −1 1], (seg.m/6) [2 1; 1 2]. Both dense assemblies (taut and
/// sagged) place their hidden cables with it.
pub(super) fn add_hidden_axial<A: Assembly>(
    out: &mut A,
    first: usize,
    seg: &crate::cable::Segment,
) {
    let at = |j: usize| first + j - 1;
    for el in 0..seg.n_el {
        for (ia, na) in [el, el + 1].into_iter().enumerate() {
            for (ib, nb) in [el, el + 1].into_iter().enumerate() {
                if na == 0 || nb == 0 {
                    continue;
                }
                let same = ia == ib;
                out.add(
                    at(na),
                    at(nb),
                    if same { seg.k } else { -seg.k },
                    seg.m / if same { 3.0 } else { 6.0 },
                );
            }
        }
    }
}

/// A model's hidden segment and junction direction when its axial chain is supported
/// (the massless model folds its hidden spring into the chain's own spring).
fn hidden_of(m: &CableModel) -> Option<(crate::cable::Segment, Vector3<f64>)> {
    let supported = m.chains[..m.n_chains]
        .iter()
        .any(|c| matches!(c.kind, ChainKind::Supported { .. }));
    match m.hidden {
        Some(h) if supported => Some((h.segment, h.direction)),
        _ => None,
    }
}

/// Static condensation of K onto its first `dim` DOFs: K_ee − K_ei K_ii⁻¹ K_ie.
pub fn condense_static(k: &DMatrix<f64>, dim: usize) -> Matrix6<f64> {
    let n = k.nrows();
    let mut out = Matrix6::zeros();
    let kee = k.view((0, 0), (dim, dim)).into_owned();
    let s = if n > dim {
        let kii = k.view((dim, dim), (n - dim, n - dim)).into_owned();
        let kie = k.view((dim, 0), (n - dim, dim)).into_owned();
        match kii.cholesky() {
            Some(ch) => kee - kie.transpose() * ch.solve(&kie),
            None => DMatrix::repeat(dim, dim, f64::NAN),
        }
    } else {
        kee
    };
    for r in 0..dim {
        for c in 0..dim {
            out[(r, c)] = s[(r, c)];
        }
    }
    out
}

/// The full spectrum from the dense reference.
#[derive(Debug, Clone)]
pub struct DenseModes {
    /// λ = ω², ascending, rad²/s².
    pub lambda: Vec<f64>,
    /// End-effector participation of each mode (0 ..= 1); empty when vectors were not asked.
    pub ee_participation: Vec<f64>,
    /// Largest |λ|, rad²/s² (sets the solver's absolute accuracy ε·λ_max).
    pub lambda_max: f64,
}

impl DenseModes {
    /// Frequencies in Hz, ascending.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.lambda.iter().map(|&l| lambda_to_hz(l)).collect()
    }
    /// The lowest mode whose end-effector participation is at least `min` (index, λ).
    pub fn first_ee_mode(&self, min: f64) -> Option<(usize, f64)> {
        self.ee_participation
            .iter()
            .position(|&p| p >= min)
            .map(|i| (i, self.lambda[i]))
    }
}

/// Estimated relative accuracy of a dense f64 solve for eigenvalue λ: ε·λ_max/λ.
pub fn dense_relative_accuracy(lambda: f64, lambda_max: f64) -> f64 {
    f64::EPSILON * lambda_max / lambda.abs().max(f64::MIN_POSITIVE)
}

/// Dense generalized symmetric eigen-solve of K u = λ M u via M = L Lᵀ and
/// C = L⁻¹ K L⁻ᵀ. With `vectors`, also each mode's end-effector participation
/// m_ee‖u_ee‖² / uᵀ M u (the first three DOF are the end-effector's).
pub fn dense_modes(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    ee_mass_kg: f64,
    vectors: bool,
) -> Result<DenseModes, ModalError> {
    let mut ee = Matrix6::zeros();
    ee.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Matrix3::identity() * ee_mass_kg));
    dense_modes_ee(k, m, &ee, 3, vectors)
}

/// [`dense_modes`] with the end-effector's own mass matrix `ee_mass` (its first `dim` rows
/// and columns; the first `dim` DOF are the end-effector's): participation
/// u_eeᵀ M_ee u_ee / uᵀ M u.
pub fn dense_modes_ee(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    ee_mass: &Matrix6<f64>,
    dim: usize,
    vectors: bool,
) -> Result<DenseModes, ModalError> {
    let chol = m.clone().cholesky().ok_or(ModalError::MassNotDefinite)?;
    let l = chol.l();
    let linv_k = l
        .solve_lower_triangular(k)
        .ok_or(ModalError::MassNotDefinite)?;
    let c = l
        .solve_lower_triangular(&linv_k.transpose())
        .ok_or(ModalError::MassNotDefinite)?;
    let c = (&c + c.transpose()) * 0.5;
    if !vectors {
        let mut lambda: Vec<f64> = c.symmetric_eigenvalues().iter().copied().collect();
        lambda.sort_by(|a, b| a.total_cmp(b));
        let lambda_max = lambda.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        return Ok(DenseModes {
            lambda,
            ee_participation: Vec::new(),
            lambda_max,
        });
    }
    let eig = SymmetricEigen::new(c);
    let mut idx: Vec<usize> = (0..eig.eigenvalues.len()).collect();
    idx.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let lt = l.transpose();
    let y = &eig.eigenvectors;
    let u = lt
        .solve_upper_triangular(y)
        .ok_or(ModalError::MassNotDefinite)?;
    let mut lambda = Vec::with_capacity(idx.len());
    let mut part = Vec::with_capacity(idx.len());
    for &i in &idx {
        lambda.push(eig.eigenvalues[i]);
        let col = u.column(i);
        let mut ee = 0.0;
        for r in 0..dim {
            for c in 0..dim {
                ee += col[r] * ee_mass[(r, c)] * col[c];
            }
        }
        let yn = y.column(i).norm_squared(); // = uᵀ M u
        part.push(ee / yn);
    }
    let lambda_max = lambda.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    Ok(DenseModes {
        lambda,
        ee_participation: part,
        lambda_max,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cable::{CableModel, HiddenAxial};
    use crate::scene::ElementKind;

    /// Three taut FEM cables in different directions, the second on a hidden cable behind
    /// its pulley, and a rigid end-effector's parts.
    fn models() -> Vec<CableModel> {
        let frame = Matrix3::identity();
        let dirs = [
            Vector3::new(0.3, -0.5, -0.8),
            Vector3::new(-0.6, 0.2, -0.7),
            Vector3::new(0.1, 0.9, -0.4),
        ];
        dirs.iter()
            .enumerate()
            .map(|(i, d)| {
                let e = d.normalize();
                let (t, ea, mu) = (300.0 + 50.0 * i as f64, 2.0e5, 0.05);
                let mut m = CableModel::build(
                    ElementKind::Fem,
                    4 + i,
                    &e,
                    1.7,
                    t,
                    ea,
                    mu,
                    0.0,
                    &frame,
                    true,
                )
                .unwrap();
                if i == 1 {
                    let hidden = HiddenAxial {
                        length_m: 0.8,
                        ea_n: ea,
                        mu_kg_m: mu,
                    };
                    m.support_on_hidden(ElementKind::Fem, &e, &hidden).unwrap();
                }
                m
            })
            .collect()
    }

    /// The cable-frame assembly is the world-frame one seen through each cable's rotation
    /// and the direction-by-direction DOF order: the test builds that orthogonal change of
    /// basis T itself (block-diagonal node rotations, then the permutation) and compares
    /// Tᵀ K T and Tᵀ M T with `assemble_in_cable_frames` entry by entry (within 1e-13 of
    /// the largest entry: the rotations' rounding), and the directions' chains are apart
    /// (exact zeros between a cable's directions at its interior nodes).
    #[test]
    fn cable_frames_are_the_world_assembly_rotated_and_reordered() {
        let models = models();
        let inertia = Matrix3::from_diagonal(&Vector3::new(0.4, 0.5, 0.6));
        let arms = [
            Vector3::new(0.1, 0.05, 0.0),
            Vector3::new(-0.1, 0.05, 0.02),
            Vector3::new(0.0, -0.1, -0.03),
        ];
        let kgeo = Matrix3::new(3.0, 0.5, 0.0, 0.5, 2.0, 0.1, 0.0, 0.1, 1.0);
        for rigid in [None, Some((&inertia, &arms[..], &kgeo))] {
            let (k, m) = assemble_dense(&models, 2.5, rigid).unwrap();
            let a = assemble_in_cable_frames(&models, 2.5, rigid).unwrap();
            let n = k.nrows();
            assert_eq!(a.entries.dof, n);
            let (ak, am) = a.entries.to_dense();
            let dim = if rigid.is_some() { 6 } else { 3 };
            // T: world DOF (row) of each cable-frame DOF (column).
            let mut t = DMatrix::<f64>::zeros(n, n);
            for i in 0..dim {
                t[(i, i)] = 1.0;
            }
            let mut base = dim;
            let mut interior = Vec::new();
            for (cm, r) in models.iter().zip(&a.frames) {
                let ne = cm.n_el;
                for j in 1..ne {
                    for ax in 0..3 {
                        let col = CableFrames::dof(base, ne, j, ax);
                        interior.push((base, ne, j, ax));
                        for w in 0..3 {
                            t[(base + 3 * (j - 1) + w, col)] = r[(w, ax)];
                        }
                    }
                }
                base += 3 * (ne - 1);
                // The hidden cable's axial DOFs stay where they are.
                if let Some((seg, _)) = hidden_of(cm) {
                    for h in 0..seg.n_el {
                        t[(base + h, base + h)] = 1.0;
                    }
                    base += seg.n_el;
                }
            }
            assert_eq!(base, n);
            let (kt, mt) = (t.transpose() * &k * &t, t.transpose() * &m * &t);
            let (ks, ms) = (k.amax(), m.amax());
            assert!(
                (&kt - &ak).amax() <= 1e-13 * ks,
                "K: {}",
                (&kt - &ak).amax() / ks
            );
            assert!(
                (&mt - &am).amax() <= 1e-13 * ms,
                "M: {}",
                (&mt - &am).amax() / ms
            );
            // Interior DOFs of one cable along different directions never couple.
            for &(b1, ne1, j1, a1) in &interior {
                for &(b2, ne2, j2, a2) in &interior {
                    if b1 == b2 && a1 != a2 {
                        let (r, c) = (
                            CableFrames::dof(b1, ne1, j1, a1),
                            CableFrames::dof(b2, ne2, j2, a2),
                        );
                        assert_eq!(ak[(r, c)], 0.0, "K between directions at {r}, {c}");
                        assert_eq!(am[(r, c)], 0.0, "M between directions at {r}, {c}");
                    }
                }
            }
        }
    }
}
