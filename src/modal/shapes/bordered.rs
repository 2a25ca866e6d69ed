//! The one mode-shape pipeline over a model's bordered system ([`Bordered`]: the taut
//! chains' in `taut`, the sagged FEM chains' in `sagged`): the null space at each
//! eigenvalue, the M-orthonormalisation within a cluster, and the repairs of a cluster
//! that is not one clean eigenvalue, the same for every model (the module docs):
//!
//! 1. two modes given apart by at most [`MERGE_REL`] whose bordered system has no clean null
//!    space of its own multiplicity at either λ are one cluster (the count's bisection can
//!    split an exact double by its rounding);
//! 2. a cluster given as one that is not one eigenvalue (modes 1e-10 apart given together)
//!    is split by the count from its λ to 1e-8 above (`count::split_cluster`), each part's
//!    shapes taken;
//! 3. a cluster still not separated from a given neighbour is a near-cluster (`near`):
//!    below the null space's resolution taken with its neighbours as one cluster at their
//!    mean λ under the count's certificate, else resolved with them member by member; the
//!    neighbours' shapes given already are replaced.

use super::count::split_cluster;
use super::near;
use super::{ModeShape, ModeShapes, ShapeError, ShapeParams, MAX_MULTIPLICITY};
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

/// The mass-normalised mode shapes of `sys` at the eigenvalues `modes` = (λ in rad²/s²,
/// multiplicity), appended to `out`: for each, `multiplicity` shapes, M-orthonormal,
/// ordered by descending end-effector participation, with the repairs of the module docs.
pub(in crate::modal) fn mode_shapes<B: Bordered>(
    sys: &mut B,
    modes: &[(f64, u32)],
    params: &ShapeParams,
    out: &mut ModeShapes,
) -> Result<(), ShapeError> {
    for &(lambda, m) in modes {
        if !(lambda.is_finite() && lambda > 0.0) || m == 0 || m > MAX_MULTIPLICITY {
            return Err(ShapeError::BadMode {
                lambda,
                multiplicity: m,
            });
        }
    }
    // The index in `out.modes` where each given mode's shapes start.
    let mut starts = vec![0; modes.len()];
    let mut next_mode = 0;
    while next_mode < modes.len() {
        let first_mode = next_mode;
        starts[next_mode] = out.modes.len();
        let (mut lambda, mut m) = modes[next_mode];
        next_mode += 1;
        let mut got = solve(sys, lambda, m, params);
        // 1. Two modes given apart that are one.
        while let Err(ShapeError::NotAnEigenvalue { .. }) = got {
            match modes.get(next_mode) {
                Some(&(ln, mn))
                    if (ln - lambda).abs() <= MERGE_REL * lambda && m + mn <= MAX_MULTIPLICITY =>
                {
                    lambda = (lambda * m as f64 + ln * mn as f64) / (m + mn) as f64;
                    m += mn;
                    starts[next_mode] = out.modes.len();
                    next_mode += 1;
                    got = solve(sys, lambda, m, params);
                }
                _ => break,
            }
        }
        let e = match got {
            Ok((at, null)) => {
                push_cluster(sys, &at, &null, lambda, m, out);
                continue;
            }
            Err(e @ ShapeError::NotAnEigenvalue { .. }) => e,
            Err(e) => return Err(e),
        };
        // 2. One cluster given that is several eigenvalues: split by the count.
        if m > 1 {
            let mut count = |x: f64| sys.count(x);
            if let Some(parts) = split_cluster(&mut count, lambda, m, params) {
                let solved: Result<Vec<_>, _> = parts
                    .iter()
                    .map(|&(l, k)| solve(sys, l, k, params).map(|s| (s, l, k)))
                    .collect();
                if let Ok(solved) = solved {
                    for ((at, null), l, k) in solved {
                        push_cluster(sys, &at, &null, l, k, out);
                    }
                    continue;
                }
            }
        }
        // 3. Not separated from a given neighbour: a near-cluster (`near`), the
        // neighbours' shapes given already replaced.
        if let Some((group, at, null, mean, total)) =
            near::merged(sys, modes, (first_mode, next_mode), params)
        {
            out.modes.truncate(starts[group.start]);
            starts[group.clone()].fill(out.modes.len());
            push_cluster(sys, &at, &null, mean, total, out);
            next_mode = group.end;
            continue;
        }
        let (group, shapes) =
            near::near_cluster(sys, modes, &starts, (first_mode, next_mode), params).ok_or(e)?;
        out.modes.truncate(starts[group.start]);
        // Each given mode's shapes start at its member's first.
        let mut at = out.modes.len();
        for j in group.clone() {
            starts[j] = shapes[at - out.modes.len()].cluster_start;
            at += modes[j].1 as usize;
        }
        out.modes.extend(shapes);
        next_mode = group.end;
    }
    Ok(())
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

#[cfg(test)]
mod tests {
    //! The pipeline's repairs on a toy model whose eigen-decomposition is known exactly:
    //! no chains, K = Q diag(λ_k) Qᵀ and M = I at the "end-effector" (dim 6), so the bordered
    //! matrix is K − λI, its eigenvectors Q's columns, its count #{λ_k < λ}.
    use super::*;
    use nalgebra::Matrix6;

    struct Toy {
        k: Matrix6<f64>,
        lambdas: [f64; 6],
        q: Matrix6<f64>,
    }

    impl Toy {
        fn new(lambdas: [f64; 6]) -> Toy {
            // A fixed orthogonal Q (QR of a fixed full matrix), so no eigenvector is a
            // coordinate axis.
            let a = Matrix6::from_fn(|r, c| {
                ((r * 7 + c * 3) % 11) as f64 + (r == c) as u8 as f64 * 5.0
            });
            let q = a.qr().q();
            let k = q * Matrix6::from_diagonal(&lambdas.into()) * q.transpose();
            Toy { k, lambdas, q }
        }
    }

    impl Bordered for Toy {
        type At = ();
        type Vector = ();
        fn dim(&self) -> usize {
            6
        }
        fn ee_mass(&self) -> Matrix6<f64> {
            Matrix6::identity()
        }
        fn at(&mut self, _: f64) {}
        fn matrix(&self, _: &(), lambda: f64) -> DMatrix<f64> {
            let a = self.k - Matrix6::identity() * lambda;
            DMatrix::from_fn(6, 6, |r, c| a[(r, c)])
        }
        fn vector(&self, _: &(), _: &DVector<f64>) {}
        fn cable_mass(&self, _: &(), _: &(), _: &(), _: &(), _: bool) -> Option<f64> {
            Some(0.0)
        }
        fn nodes(&self, _: &(), _: &()) -> Nodes {
            (Vec::new(), Vec::new())
        }
        fn count(&mut self, lambda: f64) -> u32 {
            self.lambdas.iter().filter(|&&l| l < lambda).count() as u32
        }
    }

    /// |cos| of the angle between shape `s`'s end-effector part and eigenvector k.
    fn alignment(toy: &Toy, s: &ModeShape, k: usize) -> f64 {
        (s.ee.dot(&toy.q.column(k)) / s.ee.norm()).abs()
    }

    fn run(toy: &mut Toy, modes: &[(f64, u32)]) -> Result<ModeShapes, ShapeError> {
        let mut out = ModeShapes {
            dim: 6,
            ..ModeShapes::default()
        };
        mode_shapes(toy, modes, &ShapeParams::default(), &mut out).map(|_| out)
    }

    #[test]
    fn a_cluster_given_as_one_that_is_several_is_split_by_the_count() {
        // Three eigenvalues 1e-9 apart given as one double: σ₂/σ₃ = 1/2 at λ = 1, not a
        // clean double; the count splits it into 1 and 1 + 1e-9, each clean.
        let mut toy = Toy::new([1.0, 1.0 + 1e-9, 1.0 + 2e-9, 2.0, 3.0, 4.0]);
        let out = run(&mut toy, &[(1.0, 2)]).unwrap();
        assert_eq!(out.modes.len(), 2);
        for (k, s) in out.modes.iter().enumerate() {
            assert_eq!(s.multiplicity, 1);
            // λ from the count's bisection to ~4ε; the shape within the separation σ₁/σ₂
            // (≤ 1e-6 here) of the exact eigenvector.
            assert!((s.lambda - toy.lambdas[k]).abs() <= 1e-14, "{}", s.lambda);
            assert!(1.0 - alignment(&toy, s, k) <= 1e-6, "{k}");
            // Mass-normalised: φᵀMφ = 1 (M = I).
            assert!((s.ee.norm() - 1.0).abs() <= 1e-12);
        }
    }

    #[test]
    fn a_near_cluster_is_resolved_with_its_neighbour() {
        // Two modes 2e-6 apart, each given 1e-8 off: alone, σ₁/σ₂ ≈ 5e-3 > the 1e-3
        // tolerance at either λ; together (σ₂/σ₃ ≈ 2e-6) separated, and each member's own
        // smallest singular vector is its eigenvector to ~1e-8/2e-6.
        let mut toy = Toy::new([1.0, 1.0 + 2e-6, 2.0, 3.0, 4.0, 5.0]);
        let given = [(1.0 + 1e-8, 1), (1.0 + 2e-6 - 1e-8, 1), (2.0, 1)];
        let out = run(&mut toy, &given).unwrap();
        assert_eq!(out.modes.len(), 3);
        for (k, s) in out.modes.iter().enumerate() {
            assert_eq!(s.lambda, given[k].0, "each member keeps its λ");
            assert!(1.0 - alignment(&toy, s, k) <= 1e-4, "{k}");
            assert!((s.ee.norm() - 1.0).abs() <= 1e-12);
        }
        // M-orthogonal after the symmetric orthonormalisation.
        assert!(out.modes[0].ee.dot(&out.modes[1].ee).abs() <= 1e-12);
        // Without the repair the first mode alone is refused.
        let alone = run(&mut toy, &given[..1]);
        assert!(matches!(alone, Err(ShapeError::NotAnEigenvalue { .. })));
    }

    #[test]
    fn a_near_cluster_below_the_resolution_is_one_cluster_at_its_mean() {
        // Three eigenvalues 2e-8 apart (above the 1e-9 of a plain merge), each given 5e-11
        // off (inside the count's 1e-10 window, as rounding leaves a source's λ): alone
        // σ₁/σ₂ ≈ 2.5e-3 > the 1e-3 tolerance; the count certifies exactly three in the
        // group's span, and at the mean the triple's null space is separated (σ₃/σ₄ ≈
        // 2e-8). Expected: one cluster of 3 at the mean spanning the three eigenvectors,
        // the neighbour at 2 on its own.
        let exact = [1.0, 1.0 + 2e-8, 1.0 + 4e-8, 2.0, 3.0, 4.0];
        let mut toy = Toy::new(exact);
        let given = [
            (1.0 + 5e-11, 1),
            (1.0 + 2e-8 - 5e-11, 1),
            (1.0 + 4e-8 + 5e-11, 1),
            (2.0, 1),
        ];
        let alone = solve(&mut toy, given[0].0, 1, &ShapeParams::default());
        assert!(matches!(alone, Err(ShapeError::NotAnEigenvalue { .. })));
        let out = run(&mut toy, &given).unwrap();
        assert_eq!(out.modes.len(), 4);
        let mean = given[..3].iter().map(|g| g.0).sum::<f64>() / 3.0;
        for s in &out.modes[..3] {
            assert_eq!((s.multiplicity, s.cluster_start), (3, 0));
            assert_eq!(s.lambda, mean);
            // Within the triple's eigenspace (Q's first three columns) to the separation
            // σ₃/σ₄ ≈ 2e-8 (squared in the projection).
            let p: f64 = (0..3).map(|k| alignment(&toy, s, k).powi(2)).sum();
            assert!((p - 1.0).abs() <= 1e-9, "{p}");
            assert!((s.ee.norm() - 1.0).abs() <= 1e-12);
        }
        assert_eq!(out.modes[3].multiplicity, 1);
        assert!(1.0 - alignment(&toy, &out.modes[3], 3) <= 1e-12);
        // A group whose span holds more modes than given (the middle one left out) is
        // not merged: the count finds three there, the group has two.
        let short = [given[0], given[2], given[3]];
        let got = run(&mut toy, &short);
        assert!(
            got.as_ref()
                .map_or(true, |o| o.modes.iter().all(|s| s.multiplicity == 1)),
            "{got:?}"
        );
    }

    #[test]
    fn modes_given_apart_that_are_one_are_merged() {
        // An exact double given as two modes 1e-12 apart (a count's rounding): neither
        // alone has a clean 1-dimensional null space; merged, the double's.
        let mut toy = Toy::new([1.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        let out = run(&mut toy, &[(1.0, 1), (1.0 + 1e-12, 1)]).unwrap();
        assert_eq!(out.modes.len(), 2);
        assert!(out.modes.iter().all(|s| s.multiplicity == 2));
        // The pair spans the double's eigenspace: projections onto Q's first two columns.
        for s in &out.modes {
            let p = alignment(&toy, s, 0).powi(2) + alignment(&toy, s, 1).powi(2);
            assert!((p - 1.0).abs() <= 1e-9, "{p}");
        }
    }
}
