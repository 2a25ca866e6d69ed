//! A model's bordered system ([`Bordered`]: the taut chains' in `taut`, the sagged FEM
//! chains' in `sagged`) and what the mode-shape pipeline (`pipeline`) does with it at one
//! λ, the same for every model (the module docs): the equilibrated null space and its
//! separation test, the M-orthonormalisation within a cluster ordered by end-effector
//! participation, and the consistent mass's element form.

use super::{ModeShape, ModeShapes, ShapeError, ShapeParams};
use crate::modal::lambda_to_hz;
use nalgebra::{DMatrix, DVector, Matrix6, SymmetricEigen, Vector3, Vector6};

/// Largest relative distance of two modes given apart that are taken as one cluster when
/// neither alone is a clean null space of the bordered system (the count's bisection
/// resolves λ to ~ε·λ_max/λ; modes this close are one eigenvalue to the f64 model's
/// accuracy).
pub(super) const MERGE_REL: f64 = 1e-9;

/// Sweeps of Ruiz equilibration (each halves the logarithm of every row's and column's
/// imbalance: 30 sweeps bring a 1e30 spread to within a factor 1 + 1e-7).
const RUIZ_SWEEPS: usize = 30;

/// One model's bordered system (`shapes`' module docs): what the pipeline asks of it.
pub(in crate::modal) trait Bordered {
    /// The chains' solutions at one λ.
    type At;
    /// What the mass form needs of one null vector (its nodes or chain amplitudes).
    type Vector;
    /// 3 (point mass) or 6 (rigid body).
    fn dim(&self) -> usize;
    /// The end-effector's mass matrix, kg and kg·m².
    fn ee_mass(&self) -> Matrix6<f64>;
    /// The chains' solutions at λ.
    fn at(&mut self, lambda: f64) -> Self::At;
    /// The bordered matrix at λ from the chains' solutions there.
    fn matrix(&self, at: &Self::At, lambda: f64) -> DMatrix<f64>;
    /// The parts of null vector `col` (at the λ of `at`) the mass form needs.
    fn vector(&self, at: &Self::At, col: &DVector<f64>) -> Self::Vector;
    /// The cables' part of the mass form of two null vectors, `a` at the λ of `at_a` and
    /// `b` at that of `at_b` (`same`: one λ). None where the model has no exact form across
    /// two λ (the near-cluster repair is then refused).
    fn cable_mass(
        &self,
        at_a: &Self::At,
        a: &Self::Vector,
        at_b: &Self::At,
        b: &Self::Vector,
        same: bool,
    ) -> Option<f64>;
    /// Every cable's node displacements (world frame) of a null vector, and each cable's
    /// hidden cable's nodes (displacement along it, drum to junction; empty without one).
    fn nodes(&self, at: &Self::At, v: &Self::Vector) -> Nodes;
    /// The number of eigenvalues strictly below λ (Wittrick–Williams), for splitting a
    /// cluster.
    fn count(&mut self, lambda: f64) -> u32;
}

/// A shape's node displacements: every cable's (world frame) and each hidden cable's
/// ([`ModeShape::cables`], [`ModeShape::hidden`]).
pub(in crate::modal) type Nodes = (Vec<Vec<Vector3<f64>>>, Vec<Vec<f64>>);

/// The null space of one cluster before normalisation: columns (φ, amplitudes).
pub(super) struct NullSpace {
    pub(super) vectors: DMatrix<f64>,
    pub(super) residual: f64,
}

/// The chains' solutions at λ and the bordered system's m-dimensional null space there.
pub(super) fn solve<B: Bordered>(
    sys: &mut B,
    lambda: f64,
    m: u32,
    params: &ShapeParams,
) -> Result<(B::At, NullSpace), ShapeError> {
    let at = sys.at(lambda);
    let a = sys.matrix(&at, lambda);
    null_of(a, m as usize, lambda, params).map(|null| (at, null))
}

/// The end-effector part of a null vector.
pub(super) fn ee_of(col: &DVector<f64>, dim: usize) -> Vector6<f64> {
    let mut ee = Vector6::zeros();
    for r in 0..dim {
        ee[r] = col[r];
    }
    ee
}

/// φ_aᵀ M_ee φ_b of columns a, b of `v`.
fn ee_quad(m6: &Matrix6<f64>, v: &DMatrix<f64>, a: usize, b: usize, dim: usize) -> f64 {
    let mut s = 0.0;
    for r in 0..dim {
        for c in 0..dim {
            s += v[(r, a)] * m6[(r, c)] * v[(c, b)];
        }
    }
    s
}

/// The shapes of one clean cluster (λ, m) from its null space, appended to `out`.
pub(super) fn push_cluster<B: Bordered>(
    sys: &B,
    at: &B::At,
    null: &NullSpace,
    lambda: f64,
    m: u32,
    out: &mut ModeShapes,
) {
    let v = &null.vectors;
    let dim = sys.dim();
    let m6 = sys.ee_mass();
    let cols = v.ncols();
    let vecs: Vec<B::Vector> = (0..cols)
        .map(|c| sys.vector(at, &v.column(c).into_owned()))
        .collect();
    let mut gram = DMatrix::<f64>::zeros(cols, cols);
    let mut ee = DMatrix::<f64>::zeros(cols, cols);
    for a in 0..cols {
        for b in 0..=a {
            let own = ee_quad(&m6, v, a, b, dim);
            // The same λ: every model has the exact form there.
            let cab = sys
                .cable_mass(at, &vecs[a], at, &vecs[b], true)
                .unwrap_or(f64::NAN);
            gram[(a, b)] = own + cab;
            gram[(b, a)] = own + cab;
            ee[(a, b)] = own;
            ee[(b, a)] = own;
        }
    }
    let start = out.modes.len();
    for (col, part) in orthonormalise(v, gram, &ee) {
        let (cables, hidden) = sys.nodes(at, &sys.vector(at, &col));
        out.modes.push(ModeShape {
            lambda,
            frequency_hz: lambda_to_hz(lambda),
            ee: ee_of(&col, dim),
            cables,
            hidden,
            ee_participation: part,
            cluster_start: start,
            multiplicity: m,
            null_residual: null.residual,
        });
    }
}

/// M-orthonormalise the null vectors `v` (columns) from their mass Gram matrix `gram`
/// (vᵀMv) and rotate them to diagonalise the end-effector's mass `ee` (φᵀM_eeφ);
/// returns the columns with their participations, descending.
pub(super) fn orthonormalise(
    v: &DMatrix<f64>,
    gram: DMatrix<f64>,
    ee: &DMatrix<f64>,
) -> Vec<(DVector<f64>, f64)> {
    let m = v.ncols();
    // Symmetric orthonormalisation T1 = Q Λ^{-1/2}, then the end-effector's mass in
    // that basis diagonalised (descending).
    let g = SymmetricEigen::new(gram);
    let mut t1 = g.eigenvectors.clone();
    for (c, &l) in g.eigenvalues.iter().enumerate() {
        let s = 1.0 / l.max(f64::MIN_POSITIVE).sqrt();
        t1.column_mut(c).scale_mut(s);
    }
    let e = SymmetricEigen::new(t1.transpose() * ee * &t1);
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&i, &j| e.eigenvalues[j].total_cmp(&e.eigenvalues[i]));
    let t = &t1 * &e.eigenvectors;
    order
        .iter()
        .map(|&c| {
            let mut col = v * t.column(c);
            // Sign: the largest entry positive (a convention; shapes are ± anyway).
            let imax = col.iamax();
            if col[imax] < 0.0 {
                col.neg_mut();
            }
            (col, e.eigenvalues[c].clamp(0.0, 1.0))
        })
        .collect()
}

/// The m-dimensional null space of the bordered matrix `a` at λ (see the module docs):
/// equilibrated, then the right singular vectors of its m smallest singular values,
/// refused unless σ_m/σ_{m+1} ≤ [`ShapeParams::null_tol`].
fn null_of(
    a: DMatrix<f64>,
    m: usize,
    lambda: f64,
    params: &ShapeParams,
) -> Result<NullSpace, ShapeError> {
    null_within(a, m, m, lambda, params)
}

/// As [`null_of`], but the m smallest singular vectors need only be separated from those
/// beyond the `within` smallest (`within ≥ m`): σ_m/σ_{within+1} ≤
/// [`ShapeParams::null_tol`] (a near-cluster's member: its vectors may mix with the
/// cluster's other `within − m` directions, resolved by the caller).
pub(super) fn null_within(
    mut a: DMatrix<f64>,
    m: usize,
    within: usize,
    lambda: f64,
    params: &ShapeParams,
) -> Result<NullSpace, ShapeError> {
    let n = a.ncols();
    let bad = |sigma_m, sigma_next| ShapeError::NotAnEigenvalue {
        lambda,
        multiplicity: m as u32,
        sigma_m,
        sigma_next,
    };
    if m > n || within < m {
        return Err(bad(f64::NAN, f64::NAN));
    }
    let col_scale = equilibrate(&mut a);
    let svd =
        nalgebra::linalg::SVD::try_new(a, false, true, f64::EPSILON, params.svd_max_iterations)
            .ok_or(ShapeError::Svd(lambda))?;
    let vt = svd.v_t.ok_or(ShapeError::Svd(lambda))?;
    let s = &svd.singular_values;
    let smax = s.max();
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&i, &j| s[i].total_cmp(&s[j]));
    let sigma_m = s[idx[m - 1]] / smax;
    let sigma_next = if within < n {
        s[idx[within]] / smax
    } else {
        f64::INFINITY
    };
    // The null space is the m-dimensional one only if σ_m is clearly below σ_{m+1}.
    let separation = sigma_m / sigma_next;
    if !(separation <= params.null_tol) {
        return Err(bad(sigma_m, sigma_next));
    }
    let mut vectors = DMatrix::zeros(n, m);
    for (c, &i) in idx[..m].iter().enumerate() {
        let v = vt.row(i).transpose().component_mul(&col_scale);
        vectors.set_column(c, &(&v / v.norm()));
    }
    Ok(NullSpace {
        vectors,
        residual: separation,
    })
}

/// Ruiz equilibration: scale rows and columns of `a` in place until every row and column
/// has largest entry ≈ 1 (the chains' rows range from T/l to EA/l, and the end-effector's
/// from λ·m to the sum of both: unbalanced, the SVD's backward error ε‖A‖ would swamp the
/// small rows). Returns the column scales c: the null vectors of the original matrix are
/// c ∘ (those of the scaled one).
fn equilibrate(a: &mut DMatrix<f64>) -> DVector<f64> {
    let n = a.ncols();
    let mut cs = DVector::from_element(n, 1.0);
    for _ in 0..RUIZ_SWEEPS {
        for r in 0..a.nrows() {
            let mx = a.row(r).amax();
            if mx > 0.0 {
                a.row_mut(r).scale_mut(1.0 / mx.sqrt());
            }
        }
        for c in 0..n {
            let mx = a.column(c).amax();
            if mx > 0.0 {
                let f = 1.0 / mx.sqrt();
                a.column_mut(c).scale_mut(f);
                cs[c] *= f;
            }
        }
    }
    cs
}

/// The consistent mass's bilinear form of two node sets of one cable (element mass m, kg):
/// Σ over the elements of (m/6)(2u_j·v_j + u_j·v_{j+1} + u_{j+1}·v_j + 2u_{j+1}·v_{j+1}).
pub(super) fn element_mass_form(m: f64, u: &[Vector3<f64>], v: &[Vector3<f64>]) -> f64 {
    let mut s = 0.0;
    for j in 0..u.len().saturating_sub(1) {
        s += 2.0 * u[j].dot(&v[j])
            + u[j].dot(&v[j + 1])
            + u[j + 1].dot(&v[j])
            + 2.0 * u[j + 1].dot(&v[j + 1]);
    }
    m / 6.0 * s
}
