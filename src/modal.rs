//! Natural frequencies: the dense reference and the structured real-time solver.
//!
//! The free vibration problem is K u = λ M u, λ = ω² (rad²/s²), f = ω / 2π (Hz)
//! (paper Eqs. 33-35, with K and M in the right places).
//!
//! **Dense reference** ([`assemble`], [`dense_modes`]): the assembled K and M (3 DOF per
//! interior node plus the end-effector node), reduced to a standard symmetric problem
//! with the Cholesky factor of M, solved by a dense symmetric eigensolver. A backward
//! stable solver has absolute eigenvalue error ≈ ε·λ_max, i.e. relative error
//! ε·λ_max/λ on a mode λ ([`dense_relative_accuracy`]). Never on the real-time path.
//!
//! **Structured solver** ([`ModalSolver`]): each cable's interior nodes decouple into
//! scalar chains ([`crate::cable::Chain`]); condensing them onto the end-effector gives
//! its 3 × 3 dynamic stiffness
//!
//! ```text
//!     D(λ) = Σ_chains s_c(λ) P_c − λ m_ee I,
//! ```
//!
//! and the Wittrick-Williams count J(λ) = Σ_chains mult_c · (blocked eigenvalues of c
//! below λ) + (negative eigenvalues of D(λ)) is the exact number of natural frequencies
//! below λ. Below the lowest blocked eigenvalue λ_p every eigenvalue of D decreases
//! (D' = −(mass norm) < 0) from D(0) (the static stiffness, positive definite) to −∞, so
//! the first natural frequency is the unique root of the smallest eigenvalue μ₁(D(λ)) on
//! (0, λ_p). It is found by Newton's method on g(λ) = μ₁(λ)(λ_p − λ) (which removes the
//! pole), safeguarded by the bracket, warm-started from the last cycle, and certified by
//! the count. A mode's end-effector participation is m_ee‖v‖² / vᵀ(−D'(λ))v for the null
//! vector v of D(λ): the share of the mode's kinetic-energy norm carried by the
//! end-effector's own mass.

use crate::cable::{
    eval_discrete_batch, CableModel, Chain, ChainEval, ChainKind, BATCH_MAX_ELEMENTS,
};
use crate::scene::MAX_CABLES;
use nalgebra::{DMatrix, Matrix3, Matrix6, SymmetricEigen, Vector3, Vector6};

/// Errors of the modal solvers.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ModalError {
    /// The static stiffness on the end-effector is not positive definite (slack cables, a
    /// mechanism): there is a zero or negative frequency.
    #[error(
        "static end-effector stiffness is not positive definite (smallest eigenvalue {0:.3e} N/m)"
    )]
    NotPositiveDefinite(f64),
    /// The bounded iteration ran out before the tolerance was met.
    #[error("eigen iteration did not converge in {evaluations} evaluations (bracket [{lo:.6e}, {hi:.6e}] rad²/s²)")]
    NoConvergence {
        /// Evaluations of D(λ) done.
        evaluations: u32,
        /// Lower end of the last bracket, rad²/s².
        lo: f64,
        /// Upper end of the last bracket, rad²/s².
        hi: f64,
    },
    /// No mode with enough end-effector participation within the scan bound.
    #[error("no end-effector mode found within {0} pole intervals")]
    NoEeMode(u32),
    /// The dense mass matrix is not positive definite (bad input).
    #[error("mass matrix is not positive definite")]
    MassNotDefinite,
    /// The model cannot be assembled densely (continuous cables).
    #[error(
        "the continuous model has no finite assembly; use fem or catenary for the dense reference"
    )]
    NotAssemblable,
    /// The Wittrick-Williams certificate disagrees with the root found.
    #[error("eigenvalue count check failed at λ = {0:.6e} rad²/s²")]
    CountMismatch(f64),
}

/// Convert λ = ω² (rad²/s²) to Hz.
#[inline]
pub fn lambda_to_hz(lambda: f64) -> f64 {
    lambda.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
}

/// Convert Hz to λ = ω² (rad²/s²).
#[inline]
pub fn hz_to_lambda(f_hz: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * f_hz;
    w * w
}

/// Assemble the global K (N/m) and M (kg) of the cable models and the end-effector point
/// mass. DOF order: end-effector (0..3), then for each cable its interior nodes from the
/// anchor side. Anchors are fixed and carry no DOF.
pub fn assemble(
    models: &[CableModel],
    ee_mass_kg: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
    assemble_general(models, ee_mass_kg, None)
}

/// Assemble for a rigid end-effector (6 DOF: translation, rotation): cable i's last node is
/// tied to it by G_i = [I, −[r_i]×] (arm r_i, m, world frame); `inertia_kg_m2` is the
/// world-frame inertia about the centroid, `k_geo_rot` the tensions' rotational geometric
/// stiffness (N·m/rad, see [`rigid_geometric_stiffness`]).
pub fn assemble_rigid(
    models: &[CableModel],
    ee_mass_kg: f64,
    inertia_kg_m2: &Matrix3<f64>,
    arms_m: &[Vector3<f64>],
    k_geo_rot: &Matrix3<f64>,
) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
    assemble_general(models, ee_mass_kg, Some((inertia_kg_m2, arms_m, k_geo_rot)))
}

type RigidParts<'a> = (&'a Matrix3<f64>, &'a [Vector3<f64>], &'a Matrix3<f64>);

fn assemble_general(
    models: &[CableModel],
    ee_mass_kg: f64,
    rigid: Option<RigidParts<'_>>,
) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
    if models.iter().any(|m| {
        m.chains[..m.n_chains]
            .iter()
            .any(|c| matches!(c.kind, ChainKind::Continuous { .. }))
    }) {
        return Err(ModalError::NotAssemblable);
    }
    let ee_dim = if rigid.is_some() { 6 } else { 3 };
    let interior: usize = models.iter().map(|m| m.n_el - 1).sum();
    let ndof = ee_dim + 3 * interior;
    let mut k = DMatrix::<f64>::zeros(ndof, ndof);
    let mut mm = DMatrix::<f64>::zeros(ndof, ndof);
    for i in 0..3 {
        mm[(i, i)] += ee_mass_kg;
    }
    if let Some((inertia, _, kgeo)) = rigid {
        for r in 0..3 {
            for c in 0..3 {
                mm[(3 + r, 3 + c)] += inertia[(r, c)];
                k[(3 + r, 3 + c)] += kgeo[(r, c)];
            }
        }
    }
    let i3 = DMatrix::<f64>::identity(3, 3);
    let mut base = ee_dim;
    for (ci, cm) in models.iter().enumerate() {
        let n = cm.n_el;
        // Map of the cable's end node onto the end-effector DOFs (3 × ee_dim).
        let g: DMatrix<f64> = match rigid {
            Some((_, arms, _)) => {
                let g6 = attach_map(&arms[ci]);
                DMatrix::from_fn(3, 6, |r, c| g6[(r, c)])
            }
            None => i3.clone(),
        };
        let me = cm.element_mass_kg;
        let kc = DMatrix::from_fn(3, 3, |r, c| cm.kc[(r, c)]);
        // Node j: 0 = anchor (fixed), 1..n−1 interior, n = end-effector.
        let place = |j: usize| -> (usize, &DMatrix<f64>) {
            if j == n {
                (0, &g)
            } else {
                (base + 3 * (j - 1), &i3)
            }
        };
        for el in 0..n {
            let nodes = [el, el + 1];
            for (ia, &na) in nodes.iter().enumerate() {
                for (ib, &nb) in nodes.iter().enumerate() {
                    if na == 0 || nb == 0 {
                        continue;
                    }
                    let sign = if ia == ib { 1.0 } else { -1.0 };
                    let mcoef = if ia == ib { me / 3.0 } else { me / 6.0 };
                    let (ra, la) = place(na);
                    let (rb, lb) = place(nb);
                    let kk = la.transpose() * (&kc * sign) * lb;
                    let mk = la.transpose() * lb * mcoef;
                    for r in 0..kk.nrows() {
                        for c in 0..kk.ncols() {
                            k[(ra + r, rb + c)] += kk[(r, c)];
                            mm[(ra + r, rb + c)] += mk[(r, c)];
                        }
                    }
                }
            }
        }
        base += 3 * (n - 1);
    }
    Ok((k, mm))
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

/// Parameters of the structured solver (finite bounds everywhere).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModalParams {
    /// Largest number of D(λ) evaluations for one root.
    pub max_evaluations: u32,
    /// Relative step size at which Newton stops.
    pub rel_tol: f64,
    /// Largest number of pole intervals scanned for the end-effector mode.
    pub max_scan_intervals: u32,
    /// Largest number of D(λ) evaluations one end-effector scan may spend.
    pub max_scan_evaluations: u32,
    /// Smallest end-effector participation of an end-effector mode (0 < x ≤ 1).
    pub ee_participation_min: f64,
    /// Check the first root with the eigenvalue count (two more evaluations) on every cold
    /// start and every 256th warm one.
    pub certify: bool,
    /// Newton accepts its next iterate once a step is below this relative size: with
    /// quadratic convergence the iterate is then within ~(step)² of the root.
    pub newton_accept: f64,
}

impl Default for ModalParams {
    fn default() -> Self {
        ModalParams {
            max_evaluations: 100,
            rel_tol: 1e-12,
            max_scan_intervals: 400,
            max_scan_evaluations: 1500,
            ee_participation_min: 0.5,
            certify: true,
            newton_accept: 1e-9,
        }
    }
}

/// One root found by the structured solver.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Root {
    /// λ = ω², rad²/s².
    pub lambda: f64,
    /// End-effector participation of the mode (0 ..= 1).
    pub ee_participation: f64,
    /// Evaluations of D(λ) spent.
    pub evaluations: u32,
    /// |μ(λ)| / ‖D(λ)‖ at the answer (relative residual of the condensed problem).
    pub residual: f64,
}

/// D(λ), D'(λ) and the blocked count at one λ. D is 3 × 3 (point mass, in the top-left
/// block) or 6 × 6 (rigid body: translation then rotation).
#[derive(Debug, Clone, Copy)]
pub struct DynEval {
    /// Dynamic stiffness D(λ), N/m (N·m/rad in the rotational block).
    pub d: Matrix6<f64>,
    /// dD/dλ, kg (kg·m² in the rotational block).
    pub dd: Matrix6<f64>,
    /// Σ mult · blocked eigenvalues below λ.
    pub below: u32,
    /// 3 or 6.
    pub dim: usize,
}

impl DynEval {
    /// Sorted eigen-decomposition of D.
    pub fn eig(&self) -> EigD {
        if self.dim == 3 {
            let e = eig3(&self.d.fixed_view::<3, 3>(0, 0).into_owned());
            let mut out = EigD {
                values: [f64::INFINITY; 6],
                vectors: [Vector6::zeros(); 6],
                n: 3,
            };
            for k in 0..3 {
                out.values[k] = e.values[k];
                out.vectors[k]
                    .fixed_rows_mut::<3>(0)
                    .copy_from(&e.vectors[k]);
            }
            out
        } else {
            let e = SymmetricEigen::new(self.d);
            let mut idx = [0usize, 1, 2, 3, 4, 5];
            idx.sort_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j]));
            let mut out = EigD {
                values: [0.0; 6],
                vectors: [Vector6::zeros(); 6],
                n: 6,
            };
            for (k, &i) in idx.iter().enumerate() {
                out.values[k] = e.eigenvalues[i];
                out.vectors[k] = e.eigenvectors.column(i).into_owned();
            }
            out
        }
    }
}

/// Sorted eigen-decomposition of D (3 or 6 valid entries).
#[derive(Debug, Clone, Copy)]
pub struct EigD {
    /// Eigenvalues ascending (entries ≥ n are +∞ or unused).
    pub values: [f64; 6],
    /// Matching unit eigenvectors.
    pub vectors: [Vector6<f64>; 6],
    /// Number of valid entries.
    pub n: usize,
}

impl EigD {
    /// Number of negative eigenvalues.
    pub fn negatives(&self) -> usize {
        self.values[..self.n].iter().filter(|&&v| v < 0.0).count()
    }
}

/// Sorted eigen-decomposition of a symmetric 3 × 3 matrix (ascending).
#[derive(Debug, Clone, Copy)]
pub struct Eig3 {
    /// Eigenvalues ascending.
    pub values: [f64; 3],
    /// Matching unit eigenvectors.
    pub vectors: [Vector3<f64>; 3],
}

/// The branch of D(λ) closest to vanishing: the smallest |μ_i| / |μ_i'|.
fn nearest_branch(e: &DynEval, eg: &EigD) -> usize {
    let mut branch = 0;
    let mut best = f64::INFINITY;
    for i in 0..eg.n {
        let v = eg.vectors[i];
        let d = -(v.transpose() * e.dd * v)[(0, 0)];
        let dist = eg.values[i].abs() / d.max(f64::MIN_POSITIVE);
        if dist < best {
            best = dist;
            branch = i;
        }
    }
    branch
}

/// Symmetric 3 × 3 eigen-decomposition, sorted ascending. Closed form (trigonometric
/// eigenvalues, eigenvectors from cross products of rows of A − μI) when the eigenvalues are
/// separated by more than 1e-4 ‖A‖; Jacobi rotations ([`eig3_jacobi`]) otherwise, where the
/// closed form loses accuracy. No allocation.
pub fn eig3(a: &Matrix3<f64>) -> Eig3 {
    let scale = a.abs().max();
    if !(scale > 0.0) || !scale.is_finite() {
        return eig3_jacobi(a);
    }
    let b = a / scale;
    let q = b.trace() / 3.0;
    let (b01, b02, b12) = (b[(0, 1)], b[(0, 2)], b[(1, 2)]);
    let p1 = b01 * b01 + b02 * b02 + b12 * b12;
    let (d0, d1, d2) = (b[(0, 0)] - q, b[(1, 1)] - q, b[(2, 2)] - q);
    let p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    if !(p > 1e-3) {
        return eig3_jacobi(a);
    }
    // det((B − qI)/p) / 2
    let r = (d0 * (d1 * d2 - b12 * b12) - b01 * (b01 * d2 - b12 * b02)
        + b02 * (b01 * b12 - d1 * b02))
        / (2.0 * p * p * p);
    let r = r.clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let third = 2.0 * std::f64::consts::PI / 3.0;
    let e_hi = q + 2.0 * p * phi.cos();
    let e_lo = q + 2.0 * p * (phi + third).cos();
    let e_mid = 3.0 * q - e_hi - e_lo;
    let vals = [e_lo, e_mid, e_hi];
    if (e_mid - e_lo) < 2e-4 || (e_hi - e_mid) < 2e-4 {
        return eig3_jacobi(a);
    }
    let mut vecs = [Vector3::zeros(); 3];
    for (k, &mu) in vals.iter().enumerate() {
        let r0 = Vector3::new(b[(0, 0)] - mu, b01, b02);
        let r1 = Vector3::new(b01, b[(1, 1)] - mu, b12);
        let r2 = Vector3::new(b02, b12, b[(2, 2)] - mu);
        let c01 = r0.cross(&r1);
        let c02 = r0.cross(&r2);
        let c12 = r1.cross(&r2);
        let (n01, n02, n12) = (c01.norm_squared(), c02.norm_squared(), c12.norm_squared());
        let v = if n01 >= n02 && n01 >= n12 {
            c01 / n01.sqrt()
        } else if n02 >= n12 {
            c02 / n02.sqrt()
        } else {
            c12 / n12.sqrt()
        };
        vecs[k] = v;
    }
    // Refine each eigenvalue by its Rayleigh quotient (error O(ε²) in the vector).
    let mut values = [0.0; 3];
    for k in 0..3 {
        values[k] = (vecs[k].transpose() * a * vecs[k])[(0, 0)];
    }
    Eig3 {
        values,
        vectors: vecs,
    }
}

/// Symmetric 3 × 3 eigen-decomposition, sorted ascending, by cyclic Jacobi rotations
/// (at most 12 sweeps; stops when the off-diagonal is below ε² of the norm). Absolute
/// eigenvalue error ≈ ε‖A‖, orthonormal vectors. No allocation.
pub fn eig3_jacobi(a: &Matrix3<f64>) -> Eig3 {
    let mut m = [
        [a[(0, 0)], a[(0, 1)], a[(0, 2)]],
        [a[(1, 0)], a[(1, 1)], a[(1, 2)]],
        [a[(2, 0)], a[(2, 1)], a[(2, 2)]],
    ];
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let norm2: f64 = m.iter().flatten().map(|x| x * x).sum();
    for _sweep in 0..12 {
        let off = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
        if !(off > 1e-34 * norm2) {
            break;
        }
        for &(p, q) in &[(0usize, 1usize), (0, 2), (1, 2)] {
            let apq = m[p][q];
            if apq == 0.0 {
                continue;
            }
            let theta = (m[q][q] - m[p][p]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for k in 0..3 {
                let mkp = m[k][p];
                let mkq = m[k][q];
                m[k][p] = c * mkp - s * mkq;
                m[k][q] = s * mkp + c * mkq;
            }
            for k in 0..3 {
                let mpk = m[p][k];
                let mqk = m[q][k];
                m[p][k] = c * mpk - s * mqk;
                m[q][k] = s * mpk + c * mqk;
            }
            for row in v.iter_mut() {
                let vp = row[p];
                let vq = row[q];
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let d = [m[0][0], m[1][1], m[2][2]];
    let mut idx = [0usize, 1, 2];
    if d[idx[0]] > d[idx[1]] {
        idx.swap(0, 1);
    }
    if d[idx[1]] > d[idx[2]] {
        idx.swap(1, 2);
    }
    if d[idx[0]] > d[idx[1]] {
        idx.swap(0, 1);
    }
    let col = |j: usize| Vector3::new(v[0][j], v[1][j], v[2][j]);
    Eig3 {
        values: [d[idx[0]], d[idx[1]], d[idx[2]]],
        vectors: [col(idx[0]), col(idx[1]), col(idx[2])],
    }
}

const MAX_CHAINS: usize = 3 * MAX_CABLES;

/// G = [I, −[r]×] (3 × 6): displacement of an attachment point at arm r (m) for an
/// end-effector translation u and small rotation θ: δx = u + θ × r.
pub fn attach_map(r: &Vector3<f64>) -> nalgebra::Matrix3x6<f64> {
    let mut g = nalgebra::Matrix3x6::zeros();
    g.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&Matrix3::identity());
    g.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(-r.cross_matrix()));
    g
}

/// Rotational geometric stiffness of the tensions on a rigid end-effector (N·m/rad):
/// Σ_i T_i [−(s_i·r_i) I + sym(s_i r_iᵀ)], from the second-order motion of each arm r_i
/// under a rotation while its cable force −T_i s_i stays put.
pub fn rigid_geometric_stiffness(
    units: &[Vector3<f64>],
    arms_m: &[Vector3<f64>],
    tensions_n: &[f64],
) -> Matrix3<f64> {
    let mut k = Matrix3::zeros();
    for ((s, r), t) in units.iter().zip(arms_m).zip(tensions_n) {
        let sr = s * r.transpose();
        k += (Matrix3::identity() * (-s.dot(r)) + (sr + sr.transpose()) * 0.5) * *t;
    }
    k
}

/// The structured real-time eigen solver. `new` sizes everything; `load` copies the
/// chains of one pose; the root finders never allocate and are bounded.
#[derive(Debug, Clone)]
pub struct ModalSolver {
    params: ModalParams,
    chains: [Chain; MAX_CHAINS],
    /// Rigid body: each chain's projector through the attachment map, Gᵀ P G (6 × 6).
    q6: [Matrix6<f64>; MAX_CHAINS],
    n_chains: usize,
    ee_mass_kg: f64,
    /// 3 (point mass) or 6 (rigid body).
    dim: usize,
    /// Rigid-body mass matrix diag(m I, I_world), kg and kg·m².
    m6: Matrix6<f64>,
    /// Constant rigid-body geometric stiffness (rotational block), N·m/rad.
    k6: Matrix6<f64>,
    next_pole: [usize; MAX_CHAINS],
    /// Chains evaluated together by the batched recurrence: their indices, k and m, and
    /// their common element count (0 when there are none).
    batch_idx: [usize; MAX_CHAINS],
    batch_k: [f64; MAX_CHAINS],
    batch_m: [f64; MAX_CHAINS],
    n_batch: usize,
    batch_n_el: usize,
    /// Per-chain evaluations at the last λ.
    chain_eval: [ChainEval; MAX_CHAINS],
    /// (1 − cos θ_j, cos θ_j) for θ_j = jπ/N, j = 0 ..= N, of the discrete chains'
    /// common element count N = `pole_tab_n` (the blocked eigenvalues without trigonometry).
    pole_tab: Vec<(f64, f64)>,
    pole_tab_n: usize,
    evaluations: u32,
    /// Tracked end-effector mode: (λ, number of modes below it).
    ee_track: Option<(f64, u32)>,
    /// Watched modes at or below the end-effector mode (participation ≥ p_watch at the
    /// last scan): (λ, participation at the last cycle).
    members: [(f64, f64); MAX_MEMBERS],
    /// Each watched mode's λ one cycle earlier (NaN when unknown): the linear predictor.
    member_prev: [f64; MAX_MEMBERS],
    n_members: usize,
    /// Record roots with participation ≥ p_watch during a scan.
    recording: bool,
    /// Why end-effector rescans happened: [cold, lost, drift, order, no answer, count].
    rescans: [u64; 6],
    /// Warm cycles since the last full scan.
    since_scan: u32,
    /// Participation the watched modes have given to unwatched ones since the last scan.
    leak: f64,
    /// Warm cycles left before a failed full scan is retried.
    ee_skip: u32,
    /// First roots solved (schedules the periodic count certificate).
    roots: u64,
}

/// Largest number of watched modes.
const MAX_MEMBERS: usize = 8;
/// Modes up to the end-effector mode with participation ≥ P_WATCH × threshold are watched.
const P_WATCH: f64 = 0.2;
/// The watched modes may leak at most P_LOSS × threshold of participation to unwatched
/// ones since the last scan; an unwatched mode then holds < (P_WATCH + P_LOSS) × threshold.
const P_LOSS: f64 = 0.7;
/// A partial rescan starts this fraction below the failing watched mode (participation
/// moves between modes close in frequency, through avoided crossings).
const WINDOW: f64 = 0.95;
/// A full rescan at least this often (cycles) bounds the slow drift of the total
/// participation with the pose.
const FULL_RESCAN_CYCLES: u32 = 2000;
/// A watched mode is followed by one Newton step from its prediction when that step is
/// below this (relative); its participation is then that of the predicted point.
const CHEAP_ACCEPT: f64 = 1e-5;
/// A watched mode whose approximate participation is within this of the threshold is
/// solved to full accuracy before it is compared with the threshold.
const P_MARGIN: f64 = 0.02;

impl ModalSolver {
    /// A solver with the given parameters.
    pub fn new(params: ModalParams) -> ModalSolver {
        let zero = Chain {
            kind: ChainKind::Discrete {
                k: 0.0,
                m: 0.0,
                n_el: 1,
            },
            mult: 0,
            proj: Matrix3::zeros(),
        };
        ModalSolver {
            params,
            chains: [zero; MAX_CHAINS],
            q6: [Matrix6::zeros(); MAX_CHAINS],
            n_chains: 0,
            ee_mass_kg: 0.0,
            dim: 3,
            m6: Matrix6::zeros(),
            k6: Matrix6::zeros(),
            next_pole: [1; MAX_CHAINS],
            batch_idx: [0; MAX_CHAINS],
            batch_k: [0.0; MAX_CHAINS],
            batch_m: [0.0; MAX_CHAINS],
            n_batch: 0,
            batch_n_el: 0,
            chain_eval: [ChainEval {
                s: 0.0,
                ds: 0.0,
                below: 0,
            }; MAX_CHAINS],
            evaluations: 0,
            pole_tab: Vec::with_capacity(crate::scene::MAX_ELEMENTS_PER_CABLE + 1),
            pole_tab_n: 0,
            ee_track: None,
            members: [(0.0, 0.0); MAX_MEMBERS],
            member_prev: [f64::NAN; MAX_MEMBERS],
            n_members: 0,
            recording: false,
            rescans: [0; 6],
            since_scan: 0,
            leak: 0.0,
            ee_skip: 0,
            roots: 0,
        }
    }

    /// Parameters.
    pub fn params(&self) -> &ModalParams {
        &self.params
    }

    /// Replace the parameters.
    pub fn set_params(&mut self, p: ModalParams) {
        self.params = p;
    }

    /// Load the chains of the cable models at one pose and the end-effector mass (kg).
    /// Chains that contribute nothing (zero spring and zero mass: a switched-off effect)
    /// are not loaded, so they cost nothing per evaluation.
    pub fn load(&mut self, models: &[CableModel], ee_mass_kg: f64) {
        self.load_general(models, ee_mass_kg, None);
    }

    /// Load for a rigid end-effector: cable i's end moves with G_i = [I, −[r_i]×] (arm r_i,
    /// world frame, m); `inertia_kg_m2` is the world-frame inertia about the centroid and
    /// `k_geo_rot` the rotational geometric stiffness (N·m/rad) of the tensions.
    pub fn load_rigid(
        &mut self,
        models: &[CableModel],
        ee_mass_kg: f64,
        inertia_kg_m2: &Matrix3<f64>,
        arms_m: &[Vector3<f64>],
        k_geo_rot: &Matrix3<f64>,
    ) {
        self.load_general(models, ee_mass_kg, Some((inertia_kg_m2, arms_m, k_geo_rot)));
    }

    fn load_general(
        &mut self,
        models: &[CableModel],
        ee_mass_kg: f64,
        rigid: Option<RigidParts<'_>>,
    ) {
        self.n_chains = 0;
        self.ee_mass_kg = ee_mass_kg;
        self.m6 = Matrix6::zeros();
        self.m6
            .fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * ee_mass_kg));
        self.k6 = Matrix6::zeros();
        self.dim = 3;
        if let Some((inertia, _, kgeo)) = rigid {
            self.dim = 6;
            self.m6.fixed_view_mut::<3, 3>(3, 3).copy_from(inertia);
            self.k6.fixed_view_mut::<3, 3>(3, 3).copy_from(kgeo);
        }
        for (i, m) in models.iter().enumerate() {
            let g = rigid.map(|(_, arms, _)| attach_map(&arms[i]));
            for c in &m.chains[..m.n_chains] {
                let idle =
                    matches!(c.kind, ChainKind::Discrete { k, m, .. } if k == 0.0 && m == 0.0);
                if idle || self.n_chains >= MAX_CHAINS {
                    continue;
                }
                self.chains[self.n_chains] = *c;
                if let Some(g) = g {
                    self.q6[self.n_chains] = g.transpose() * c.proj * g;
                }
                self.n_chains += 1;
            }
        }
        // Pole table for the discrete chains' element count (refilled only when it changes;
        // the capacity is reserved in `new`).
        let mut n_tab = 0;
        for c in &self.chains[..self.n_chains] {
            if let ChainKind::Discrete { n_el, .. } = c.kind {
                if (2..=crate::scene::MAX_ELEMENTS_PER_CABLE).contains(&n_el) {
                    n_tab = n_el;
                    break;
                }
            }
        }
        if n_tab != 0 && n_tab != self.pole_tab_n {
            self.pole_tab.clear();
            for j in 0..=n_tab {
                let th = j as f64 * std::f64::consts::PI / n_tab as f64;
                self.pole_tab
                    .push((2.0 * (0.5 * th).sin().powi(2), th.cos()));
            }
            self.pole_tab_n = n_tab;
        }
        // Batch the discrete chains of the most common small element count.
        self.n_batch = 0;
        self.batch_n_el = 0;
        for c in &self.chains[..self.n_chains] {
            if let ChainKind::Discrete { k, m, n_el } = c.kind {
                if k > 0.0 && m > 0.0 && (2..=BATCH_MAX_ELEMENTS).contains(&n_el) {
                    self.batch_n_el = n_el;
                    break;
                }
            }
        }
        for (i, c) in self.chains[..self.n_chains].iter().enumerate() {
            if let ChainKind::Discrete { k, m, n_el } = c.kind {
                if k > 0.0 && m > 0.0 && n_el == self.batch_n_el {
                    self.batch_idx[self.n_batch] = i;
                    self.batch_k[self.n_batch] = k;
                    self.batch_m[self.n_batch] = m;
                    self.n_batch += 1;
                }
            }
        }
    }

    /// Blocked eigenvalue j (1-based; 0 gives 0) of chain i, rad²/s², equal to
    /// [`Chain::pole`] bit for bit (same formula, tabulated cosines).
    #[inline]
    fn chain_pole(&self, i: usize, j: usize) -> f64 {
        if j == 0 {
            return 0.0;
        }
        let c = &self.chains[i];
        if let ChainKind::Discrete { k, m, n_el } = c.kind {
            if n_el == self.pole_tab_n && m > 0.0 && j < n_el {
                let (omc, cth) = self.pole_tab[j];
                return 6.0 * k * omc / (m * (2.0 + cth));
            }
        }
        c.pole(j)
    }

    /// The pole-free interval (a, b) of D around the λ of the last evaluation, from the
    /// chains' blocked counts there.
    fn last_pole_interval(&self) -> (f64, f64) {
        let mut a = 0.0f64;
        let mut b = f64::INFINITY;
        for i in 0..self.n_chains {
            let j = self.chain_eval[i].below as usize;
            a = a.max(self.chain_pole(i, j));
            b = b.min(self.chain_pole(i, j + 1));
        }
        (a, b)
    }

    /// Every chain at λ into `chain_eval`: the batched ones together, the rest one by one.
    #[inline]
    fn eval_chains(&mut self, lambda: f64) {
        let mut batch = [ChainEval {
            s: 0.0,
            ds: 0.0,
            below: 0,
        }; MAX_CHAINS];
        let nb = self.n_batch;
        if nb > 0 {
            eval_discrete_batch(
                &self.batch_k[..nb],
                &self.batch_m[..nb],
                self.batch_n_el,
                lambda,
                &mut batch[..nb],
            );
        }
        let mut j = 0;
        for i in 0..self.n_chains {
            if j < nb && self.batch_idx[j] == i {
                self.chain_eval[i] = batch[j];
                j += 1;
            } else {
                self.chain_eval[i] = self.chains[i].eval(lambda);
            }
        }
    }

    /// D(λ), D'(λ) and the blocked count.
    #[inline]
    pub fn eval(&mut self, lambda: f64) -> DynEval {
        self.evaluations += 1;
        self.eval_chains(lambda);
        let mut below = 0u32;
        if self.dim == 3 {
            let mut d = Matrix3::identity() * (-lambda * self.ee_mass_kg);
            let mut dd = Matrix3::identity() * (-self.ee_mass_kg);
            for (c, e) in self.chains[..self.n_chains].iter().zip(&self.chain_eval) {
                d += c.proj * e.s;
                dd += c.proj * e.ds;
                below += c.mult * e.below;
            }
            let mut d6 = Matrix6::zeros();
            let mut dd6 = Matrix6::zeros();
            d6.fixed_view_mut::<3, 3>(0, 0).copy_from(&d);
            dd6.fixed_view_mut::<3, 3>(0, 0).copy_from(&dd);
            return DynEval {
                d: d6,
                dd: dd6,
                below,
                dim: 3,
            };
        }
        let mut d = self.k6 - self.m6 * lambda;
        let mut dd = -self.m6;
        for ((c, q), e) in self.chains[..self.n_chains]
            .iter()
            .zip(&self.q6)
            .zip(&self.chain_eval)
        {
            d += q * e.s;
            dd += q * e.ds;
            below += c.mult * e.below;
        }
        DynEval {
            d,
            dd,
            below,
            dim: 6,
        }
    }

    /// Number of natural frequencies strictly below λ (Wittrick-Williams).
    pub fn count_below(&mut self, lambda: f64) -> u32 {
        let e = self.eval(lambda);
        e.below + e.eig().negatives() as u32
    }

    /// Static end-effector stiffness D(0), translational block, N/m.
    pub fn static_stiffness(&mut self) -> Matrix3<f64> {
        self.eval(0.0).d.fixed_view::<3, 3>(0, 0).into_owned()
    }

    /// Static end-effector stiffness D(0) (6 × 6 for a rigid body; top-left 3 × 3 else).
    pub fn static_stiffness6(&mut self) -> Matrix6<f64> {
        self.eval(0.0).d
    }

    /// 3 (point mass) or 6 (rigid body).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The lowest blocked eigenvalue over all chains, rad²/s² (∞ when none).
    pub fn lowest_pole(&self) -> f64 {
        self.chains[..self.n_chains]
            .iter()
            .map(|c| c.first_pole())
            .fold(f64::INFINITY, f64::min)
    }

    /// Participation of the mode at root λ with null vector v (unit): the end-effector's
    /// share vᵀ M_ee v / vᵀ(−D'(λ))v of the mode's kinetic-energy norm.
    fn participation(&self, dd: &Matrix6<f64>, v: &Vector6<f64>) -> f64 {
        let kin = -(v.transpose() * dd * v)[(0, 0)];
        let own = (v.transpose() * self.m6 * v)[(0, 0)];
        if kin > 0.0 {
            (own / kin).min(1.0)
        } else {
            0.0
        }
    }

    /// Root of the `branch`-th smallest eigenvalue of D on (lo, hi), where it is positive at
    /// lo and negative at hi. `pole_hi` (≥ hi, may be ∞) is the pole bounding the interval
    /// above; Newton runs on μ(λ)(pole_hi − λ) to remove it. `guess` starts the iteration.
    fn branch_root(
        &mut self,
        branch: usize,
        lo: f64,
        hi: f64,
        pole_hi: f64,
        guess: f64,
    ) -> Result<Root, ModalError> {
        self.branch_root_with(branch, lo, hi, pole_hi, guess, false)
    }

    /// [`Self::branch_root`]; `fast` accepts an iterate once a Newton step is below
    /// [`ModalParams::newton_accept`] (warm starts), else only below `rel_tol`.
    fn branch_root_with(
        &mut self,
        branch: usize,
        mut lo: f64,
        mut hi: f64,
        pole_hi: f64,
        guess: f64,
        fast: bool,
    ) -> Result<Root, ModalError> {
        let start = self.evaluations;
        let mut x = if guess > lo && guess < hi {
            guess
        } else if hi.is_finite() {
            0.5 * (lo + hi)
        } else {
            2.0 * lo.max(1.0)
        };
        let tol = self.params.rel_tol;
        loop {
            if self.evaluations - start >= self.params.max_evaluations {
                return Err(ModalError::NoConvergence {
                    evaluations: self.evaluations - start,
                    lo,
                    hi,
                });
            }
            let e = self.eval(x);
            let eg = e.eig();
            let mu = eg.values[branch];
            let v = eg.vectors[branch];
            let dmu = (v.transpose() * e.dd * v)[(0, 0)];
            if mu > 0.0 {
                lo = lo.max(x);
            } else if mu < 0.0 {
                hi = hi.min(x);
            }
            let scale = e.d.abs().max().max(f64::MIN_POSITIVE);
            let (g, dg) = if pole_hi.is_finite() {
                let w = pole_hi - x;
                (mu * w, dmu * w - mu)
            } else {
                (mu, dmu)
            };
            let mut xn = if dg < 0.0 { x - g / dg } else { f64::NAN };
            let collapsed = hi.is_finite() && (hi - lo) <= 4.0 * f64::EPSILON * x.abs();
            let step = (xn - x).abs();
            let accept = if fast && self.evaluations - start > 1 {
                self.params.newton_accept
            } else {
                tol
            };
            let done =
                mu == 0.0 || collapsed || (xn.is_finite() && step <= accept.max(tol) * x.abs());
            if done {
                let lambda = if mu == 0.0 || !(xn > lo && xn < hi) && collapsed {
                    x
                } else {
                    xn
                };
                return Ok(Root {
                    lambda,
                    ee_participation: self.participation(&e.dd, &v),
                    evaluations: self.evaluations - start,
                    residual: mu.abs() / scale,
                });
            }
            if !(xn > lo && xn < hi) {
                xn = if hi.is_finite() {
                    0.5 * (lo + hi)
                } else {
                    2.0 * x
                };
            }
            x = xn;
        }
    }

    /// The first natural frequency's λ (rad²/s²), warm-started from `warm` when given.
    pub fn first_root(&mut self, warm: Option<f64>) -> Result<Root, ModalError> {
        let start = self.evaluations;
        let e0 = self.eval(0.0);
        let eg0 = e0.eig();
        if !(eg0.values[0] > 0.0) {
            return Err(ModalError::NotPositiveDefinite(eg0.values[0]));
        }
        let lp = self.lowest_pole();
        let guess = match warm {
            Some(w) if w > 0.0 && w < lp => w,
            _ => {
                // Rayleigh estimate from λ = 0: μ(0)/(−μ'(0)).
                let v = eg0.vectors[0];
                let dmu = -(v.transpose() * e0.dd * v)[(0, 0)];
                let g = eg0.values[0] / dmu.max(f64::MIN_POSITIVE);
                if lp.is_finite() {
                    g.min(0.999 * lp)
                } else {
                    g
                }
            }
        };
        let mut hi = lp;
        if !lp.is_finite() {
            // No poles: D = K − λ M_d is linear, μ₁ crosses zero; find an upper bracket.
            let mut h = guess.max(1e-12) * 2.0;
            let mut ok = false;
            for _ in 0..200 {
                let e = self.eval(h);
                if e.eig().values[0] < 0.0 {
                    ok = true;
                    break;
                }
                h *= 4.0;
            }
            if !ok {
                return Err(ModalError::NoConvergence {
                    evaluations: self.evaluations - start,
                    lo: 0.0,
                    hi: h,
                });
            }
            hi = h;
        }
        let fast = warm.is_some();
        let mut r = self.branch_root_with(0, 0.0, hi, lp, guess, fast)?;
        self.roots += 1;
        if self.params.certify && (!fast || self.roots.is_multiple_of(256)) {
            let mut certified = self.certify_first(r.lambda);
            if !certified && fast {
                // A relaxed warm answer may sit outside the certificate's ±1e-10 probe in
                // an ill-conditioned case: solve strictly before reporting anything.
                r = self.branch_root_with(0, 0.0, hi, lp, r.lambda, false)?;
                certified = self.certify_first(r.lambda);
            }
            if !certified {
                return Err(ModalError::CountMismatch(r.lambda));
            }
        }
        r.evaluations = self.evaluations - start;
        Ok(r)
    }

    /// The Wittrick-Williams certificate of a first root: no eigenvalue below λ(1 − 1e-10),
    /// at least one below λ(1 + 1e-10).
    fn certify_first(&mut self, lambda: f64) -> bool {
        self.count_below(lambda * (1.0 - 1e-10)) == 0
            && self.count_below(lambda * (1.0 + 1e-10)) > 0
    }

    /// The lowest mode whose end-effector participation is at least
    /// [`ModalParams::ee_participation_min`]: scans the intervals between the chains'
    /// blocked eigenvalues in ascending order and solves for each root of D in them.
    /// `first` is the already-known first root (not solved again).
    pub fn ee_mode(&mut self, first: &Root) -> Result<Root, ModalError> {
        if first.ee_participation >= self.params.ee_participation_min {
            return Ok(*first);
        }
        self.ee_scan(0.0, first.lambda, f64::INFINITY)
    }

    /// Scan upward from the pole interval containing `start` (rad²/s²) for the first root
    /// with participation ≥ the threshold, skipping roots at or below `skip_to`, and giving up
    /// above `limit`.
    fn ee_scan(&mut self, start: f64, skip_to: f64, limit: f64) -> Result<Root, ModalError> {
        let begin = self.evaluations;
        let thr = self.params.ee_participation_min;
        let mut best: Option<Root> = None;
        let mut a = 0.0f64;
        for i in 0..self.n_chains {
            let (lo, _) = self.chains[i].poles_around(start);
            a = a.max(lo);
            self.next_pole[i] = 1;
        }
        for _ in 0..self.params.max_scan_intervals {
            if self.evaluations - begin > self.params.max_scan_evaluations {
                break;
            }
            // Next distinct pole above a.
            let mut b = f64::INFINITY;
            for i in 0..self.n_chains {
                let mut j = self.next_pole[i];
                let mut p = self.chains[i].pole(j);
                while p <= a * (1.0 + 1e-12) && p.is_finite() {
                    j += 1;
                    p = self.chains[i].pole(j);
                }
                self.next_pole[i] = j;
                b = b.min(p);
            }
            if a > limit {
                break;
            }
            // Evaluation points just inside (a, b): never past the middle of a narrow
            // interval (nearly coincident poles of different chains).
            let inset = |w: f64, x: f64| (1e-9 * x).min(0.25 * w);
            let lo = if a == 0.0 { 0.0 } else { a + inset(b - a, a) };
            let hi_eval = if b.is_finite() {
                b - inset(b - a, b)
            } else {
                f64::INFINITY
            };
            let skip_interval = b.is_finite() && hi_eval <= skip_to * (1.0 + 1e-9);
            if !skip_interval {
                let na = if a == 0.0 {
                    0
                } else {
                    let e = self.eval(lo);
                    e.eig().negatives()
                };
                let nb = if b.is_finite() {
                    let e = self.eval(hi_eval);
                    e.eig().negatives()
                } else {
                    self.dim
                };
                for branch in na..nb {
                    let hi = if b.is_finite() {
                        hi_eval
                    } else {
                        f64::INFINITY
                    };
                    let guess = if hi.is_finite() {
                        0.5 * (lo + hi)
                    } else {
                        2.0 * lo.max(skip_to).max(1.0)
                    };
                    let mut r = self.branch_root_with(branch, lo, hi, b, guess, true)?;
                    if r.lambda <= skip_to * (1.0 + 1e-9) {
                        continue;
                    }
                    if self.recording
                        && r.ee_participation >= P_WATCH * thr
                        && self.n_members < MAX_MEMBERS
                    {
                        self.members[self.n_members] = (r.lambda, r.ee_participation);
                        self.member_prev[self.n_members] = f64::NAN;
                        self.n_members += 1;
                    }
                    if r.ee_participation >= thr {
                        r.evaluations = self.evaluations - begin;
                        return Ok(r);
                    }
                    if best.is_none_or(|b| r.ee_participation > b.ee_participation) {
                        best = Some(r);
                    }
                }
            }
            if !b.is_finite() {
                break;
            }
            a = b;
        }
        // No mode reaches the threshold within the bounds: the most end-effector-like mode
        // found (its participation, below the threshold, says so).
        match best {
            Some(mut r) => {
                r.evaluations = self.evaluations - begin;
                Ok(r)
            }
            None => Err(ModalError::NoEeMode(self.params.max_scan_intervals)),
        }
    }

    /// The pole-free interval (a, b) of D around λ: the nearest blocked eigenvalues of all
    /// chains below and above (0 and ∞ when there are none).
    pub fn pole_interval(&self, lambda: f64) -> (f64, f64) {
        let mut a = 0.0f64;
        let mut b = f64::INFINITY;
        for c in &self.chains[..self.n_chains] {
            let (lo, hi) = c.poles_around(lambda);
            a = a.max(lo);
            b = b.min(hi);
        }
        (a, b)
    }

    /// Forget the tracked end-effector mode (the next [`Self::ee_mode_tracked`] scans).
    pub fn reset_tracking(&mut self) {
        self.ee_track = None;
        self.n_members = 0;
    }

    /// The end-effector mode, tracked from the last cycle when `warm`.
    ///
    /// A full scan ([`Self::ee_mode`]) records every root up to the end-effector mode whose
    /// participation is at least 0.2 × the threshold (the *watched* modes). A warm cycle
    /// follows each watched mode from its linear prediction (last two cycles) by Newton's
    /// method on its branch of D with both bounding poles removed, accepting one step below
    /// 1e-5 (relative) for bookkeeping; a mode whose participation is within 0.02 of the
    /// threshold, and the answer, are solved to full accuracy. When a weakly coupled pole
    /// passed through a mode since the last cycle, the mode is followed into the neighbouring
    /// pole interval. The answer is the lowest watched mode with participation ≥ the
    /// threshold. Participation moves only between neighbouring modes (avoided crossings):
    /// within a run of watched modes that are neighbours in the spectrum (their
    /// Wittrick-Williams counts differ by one) it stays watched, and what a run loses in net
    /// in a cycle is added to a *leak*. A rescan is forced when the leak since the scan
    /// exceeds 0.7 × the threshold (an unwatched mode then holds < 0.9 × the threshold),
    /// when a watched mode is lost or jumps more than 0.2 % from its prediction, when two
    /// collapse onto one root, when none reaches the threshold, or when the count of modes
    /// below the answer changes other than by a mode with low participation arriving or
    /// leaving.
    pub fn ee_mode_tracked(&mut self, first: &Root, warm: bool) -> Result<Root, ModalError> {
        let start = self.evaluations;
        let thr = self.params.ee_participation_min;
        if first.ee_participation >= thr {
            self.ee_track = Some((first.lambda, 0));
            self.n_members = 0;
            self.ee_skip = 0;
            return Ok(*first);
        }
        if !warm {
            self.ee_skip = 0;
        } else if self.ee_skip > 0 {
            // Weak episode: no mode reached the threshold at the last full scan; follow the
            // most end-effector-like mode and rescan fully every 16 cycles.
            self.ee_skip -= 1;
            if self.n_members == 1 {
                let l0 = self.members[0].0;
                let pred = self.predict(0);
                let exact = self.params.newton_accept;
                if let Some((mut r, _, _)) = self.track_root(pred, exact) {
                    if (r.lambda - pred).abs() <= 2e-3 * l0 {
                        self.member_prev[0] = l0;
                        self.members[0].0 = r.lambda;
                        self.members[0].1 = r.ee_participation;
                        if r.ee_participation < thr {
                            r.evaluations = self.evaluations - start;
                            return Ok(r);
                        }
                    }
                }
            }
            self.ee_skip = 0;
        }
        let mut reason = 0;
        if let (true, Some((l_ee, below0))) = (warm, self.ee_track) {
            if self.n_members > 0 {
                match self.track_members(l_ee, below0, thr) {
                    Ok(mut r) => {
                        r.evaluations = self.evaluations - start;
                        return Ok(r);
                    }
                    Err((why, window)) => {
                        // Partial rescan: the watched modes below the window keep their
                        // baselines; everything from the window up is scanned again.
                        self.rescans[why] += 1;
                        if let Some(mut r) = self.partial_rescan(window, 2.0 * l_ee, thr) {
                            r.evaluations = self.evaluations - start;
                            return Ok(r);
                        }
                        reason = 0;
                    }
                }
            }
        }
        self.rescans[reason] += 1;
        self.since_scan = 0;
        self.leak = 0.0;
        self.recording = true;
        self.n_members = 0;
        if first.ee_participation >= P_WATCH * thr {
            self.members[0] = (first.lambda, first.ee_participation);
            self.member_prev[0] = f64::NAN;
            self.n_members = 1;
        }
        let r = self.ee_mode(first);
        self.recording = false;
        let mut r = match r {
            Ok(r) => r,
            Err(e) => {
                self.ee_track = None;
                self.n_members = 0;
                return Err(e);
            }
        };
        if r.ee_participation < thr {
            // Weak: watch only this mode until the next full scan.
            self.members[0] = (r.lambda, r.ee_participation);
            self.member_prev[0] = f64::NAN;
            self.n_members = 1;
            self.ee_skip = 16;
            self.ee_track = None;
            r.evaluations = self.evaluations - start;
            return Ok(r);
        }
        let below = self.count_below(r.lambda * (1.0 - 1e-10));
        self.ee_track = Some((r.lambda, below));
        r.evaluations = self.evaluations - start;
        Ok(r)
    }

    /// The linear predictor of watched mode `i` from its last two λ.
    fn predict(&self, i: usize) -> f64 {
        let l = self.members[i].0;
        let p = self.member_prev[i];
        if p.is_finite() {
            let x = 2.0 * l - p;
            if x > 0.0 {
                return x;
            }
        }
        l
    }

    /// Counters of end-effector rescans by reason: [cold start, watched mode lost,
    /// participation lost, watched modes collapsed, no watched mode above the threshold,
    /// count of modes below changed].
    pub fn rescan_counts(&self) -> [u64; 6] {
        self.rescans
    }

    /// Rescan from `window` (rad²/s²) upward, keeping the watched modes below it. None when
    /// the scan fails (the caller then scans from zero).
    fn partial_rescan(&mut self, window: f64, limit: f64, thr: f64) -> Option<Root> {
        let mut keep = 0;
        while keep < self.n_members && self.members[keep].0 < window {
            keep += 1;
        }
        self.n_members = keep;
        self.leak = 0.0;
        if keep == 0 {
            self.since_scan = 0;
        }
        // A kept mode above the threshold is lower than anything in the window.
        for i in 0..keep {
            if self.members[i].1 >= thr {
                let exact = self.params.newton_accept;
                let (r, _, below) = self.track_root(self.predict(i), exact)?;
                self.ee_track = Some((r.lambda, below));
                return Some(r);
            }
        }
        self.recording = true;
        let r = self.ee_scan(window, window * (1.0 - 1e-12), limit);
        self.recording = false;
        let r = r.ok()?;
        let below = self.count_below(r.lambda * (1.0 - 1e-10));
        self.ee_track = Some((r.lambda, below));
        Some(r)
    }

    /// One warm step of the watched modes; Err((reason, window start)) when a rescan is
    /// needed from that λ upward.
    fn track_members(&mut self, l_ee: f64, below0: u32, thr: f64) -> Result<Root, (usize, f64)> {
        let mut answer: Option<(Root, usize, u32)> = None;
        let mut prev = 0.0f64;
        // Each watched mode's participation at the last cycle and its count of modes below.
        let mut p_last = [0.0f64; MAX_MEMBERS];
        let mut counts = [0u32; MAX_MEMBERS];
        self.since_scan += 1;
        if self.since_scan > FULL_RESCAN_CYCLES {
            return Err((2, 0.0));
        }
        for i in 0..self.n_members {
            let l = self.members[i].0;
            p_last[i] = self.members[i].1;
            let window = WINDOW * l;
            let pred = self.predict(i);
            // One Newton step from the prediction is enough to follow a watched mode; the
            // answer is then solved to full accuracy (one more evaluation).
            let tr = self.track_root(pred, CHEAP_ACCEPT);
            let (mut r, mut branch, mut count) = tr.ok_or((1usize, window))?;
            // Modes move continuously: a root more than 0.2 % away from its prediction is
            // another mode that Newton converged to (an identity jump), not this one.
            if (r.lambda - pred).abs() > 2e-3 * l {
                return Err((1, window.min(WINDOW * r.lambda)));
            }
            if answer.is_none() && r.ee_participation >= thr - P_MARGIN {
                let exact = self.params.newton_accept;
                (r, branch, count) = self.track_root(r.lambda, exact).ok_or((1usize, window))?;
            }
            if r.lambda <= prev * (1.0 + 1e-9) {
                return Err((3, WINDOW * prev.min(r.lambda)));
            }
            prev = r.lambda;
            counts[i] = count;
            self.member_prev[i] = l;
            self.members[i].0 = r.lambda;
            self.members[i].1 = r.ee_participation;
            if answer.is_none() && r.ee_participation >= thr {
                answer = Some((r, branch, count));
            }
        }
        // Participation moves between neighbouring modes (avoided crossings). Within a run
        // of watched modes that are neighbours in the spectrum (their counts of modes below
        // differ by one) it stays watched; what a run loses in net went to an unwatched
        // neighbour. The leak since the scan bounds what any unwatched mode has gained:
        // above P_LOSS × threshold, rescan from just below the leaking run.
        let mut first_leaker = f64::INFINITY;
        let mut i = 0;
        while i < self.n_members {
            let mut j = i;
            while j + 1 < self.n_members && counts[j + 1] == counts[j] + 1 {
                j += 1;
            }
            let change: f64 = (i..=j).map(|k| self.members[k].1 - p_last[k]).sum();
            if change < 0.0 {
                self.leak -= change;
                first_leaker = first_leaker.min(WINDOW * self.members[i].0);
            }
            i = j + 1;
        }
        if self.leak > P_LOSS * thr {
            return Err((2, first_leaker.min(WINDOW * l_ee)));
        }
        let (r, branch, below) = answer.ok_or((4usize, WINDOW * l_ee.min(prev)))?;
        // The watched modes keep their order, so the answer is the same mode as before
        // exactly when it was the end-effector mode at the last cycle.
        let same = (r.lambda - l_ee).abs() <= 1e-3 * l_ee;
        if same && below != below0 {
            if below + 1 == below0 {
                // A mode left upward through the answer: fine.
            } else if below == below0 + 1 {
                // A mode arrived from above: it must carry little participation.
                match self.highest_root_below(r.lambda, branch) {
                    Some(h) if h.ee_participation < P_WATCH * thr => {}
                    _ => return Err((5, WINDOW * r.lambda)),
                }
            } else {
                return Err((5, WINDOW * r.lambda));
            }
        }
        self.ee_track = Some((r.lambda, below));
        Ok(r)
    }

    /// The highest root below the root `l1` of branch `branch`, when it lies in the same
    /// pole interval (branch − 1 changes sign between the interval's lower pole and l1).
    fn highest_root_below(&mut self, l1: f64, branch: usize) -> Option<Root> {
        if branch == 0 {
            return None;
        }
        let (a, b) = self.pole_interval(l1);
        let lo = if a == 0.0 {
            0.0
        } else {
            a + (1e-9 * a).min(0.25 * (l1 - a))
        };
        let e = self.eval(lo);
        if !(e.eig().values[branch - 1] > 0.0) {
            return None;
        }
        let hi = l1 - (1e-13 * l1).min(0.25 * (l1 - lo));
        self.branch_root(branch - 1, lo, hi, b, l1 - (1e-6 * l1).min(0.5 * (l1 - lo)))
            .ok()
    }

    /// Newton from `l0` on the branch of D closest to vanishing there, kept inside the pole
    /// interval of l0; None when it leaves it or does not converge in the bound. The first
    /// step is accepted when it is below `first_accept` (relative), later ones below
    /// [`ModalParams::newton_accept`]. Returns the root, its branch and the number of
    /// natural frequencies below it, read off the last evaluation (Wittrick-Williams count
    /// there, less the root itself when the last iterate lies above it).
    fn track_root(&mut self, l0: f64, first_accept: f64) -> Option<(Root, usize, u32)> {
        let mut x = l0;
        let mut e = self.eval(x);
        let (mut a, mut b) = self.last_pole_interval();
        if !(x > a && x < b) {
            return None;
        }
        let mut eg = e.eig();
        let mut branch = nearest_branch(&e, &eg);
        let mut hopped = false;
        let mut it = 0;
        while it < self.params.max_evaluations.min(12) {
            let v = eg.vectors[branch];
            let mu = eg.values[branch];
            let dmu = (v.transpose() * e.dd * v)[(0, 0)];
            // Newton on μ(λ)(λ − a)(b − λ): both poles removed (a = 0 and b = ∞ add nothing).
            let (mut g, mut dg) = (mu, dmu);
            if b.is_finite() {
                let w = b - x;
                (g, dg) = (g * w, dg * w - g);
            }
            if a > 0.0 {
                let w = x - a;
                (g, dg) = (g * w, dg * w + g);
            }
            if !(dg < 0.0) {
                return None;
            }
            let xn = x - g / dg;
            if !(xn > a && xn < b) {
                // A weakly coupled pole passed through the mode since the last cycle: follow
                // it into the neighbouring interval, once, from the mirror point.
                if hopped {
                    return None;
                }
                hopped = true;
                x = if xn >= b { b + (b - x) } else { a - (x - a) };
                if !(x > 0.0) {
                    return None;
                }
                e = self.eval(x);
                (a, b) = self.last_pole_interval();
                if !(x > a && x < b) {
                    return None;
                }
                eg = e.eig();
                branch = nearest_branch(&e, &eg);
                it += 1;
                continue;
            }
            let accept = if it == 0 {
                first_accept
            } else {
                self.params.newton_accept
            };
            if mu == 0.0 || (xn - x).abs() <= accept.max(self.params.rel_tol) * x {
                let scale = e.d.abs().max().max(f64::MIN_POSITIVE);
                let count = e.below + eg.negatives() as u32 - u32::from(mu < 0.0);
                return Some((
                    Root {
                        lambda: xn,
                        ee_participation: self.participation(&e.dd, &v),
                        evaluations: 0,
                        residual: mu.abs() / scale,
                    },
                    branch,
                    count,
                ));
            }
            x = xn;
            e = self.eval(x);
            eg = e.eig();
            it += 1;
        }
        None
    }

    /// Evaluations of D(λ) since the solver was built (a counter for statistics).
    pub fn evaluations(&self) -> u32 {
        self.evaluations
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eig3_matches_nalgebra_and_handles_clusters() {
        let cases = [
            Matrix3::new(4.0, 1.0, -2.0, 1.0, 3.0, 0.5, -2.0, 0.5, -1.0),
            Matrix3::identity() * 7.0,
            Matrix3::new(1e6, 0.0, 0.0, 0.0, 1e6, 1e-3, 0.0, 1e-3, -2e-4),
            Matrix3::new(2.0, 1.0, 1.0, 1.0, 2.0, 1.0, 1.0, 1.0, 2.0),
        ];
        for a in cases.iter().copied().chain((0..200).map(|i| {
            let x = (i as f64 * 0.37).sin();
            let y = (i as f64 * 1.91).cos();
            let m = Matrix3::new(
                1.0 + x,
                y,
                0.3 * x * y,
                y,
                -2.0 + y,
                1e-3 * x,
                0.3 * x * y,
                1e-3 * x,
                0.5 * x,
            );
            m * 10f64.powi(i % 13 - 6)
        })) {
            let e = eig3(&a);
            let mut r: Vec<f64> = SymmetricEigen::new(a).eigenvalues.iter().copied().collect();
            r.sort_by(|x, y| x.total_cmp(y));
            for i in 0..3 {
                assert!(
                    (e.values[i] - r[i]).abs() <= 16.0 * f64::EPSILON * a.norm(),
                    "{a} {:?} {r:?}",
                    e.values
                );
                let res = a * e.vectors[i] - e.vectors[i] * e.values[i];
                assert!(res.norm() <= 1e-14 * a.norm());
                assert!((e.vectors[i].norm() - 1.0).abs() < 1e-14);
            }
        }
    }
}
