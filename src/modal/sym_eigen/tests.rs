//! The solver against nalgebra's `SymmetricEigen` (an independent implementation: implicit
//! symmetric QR with the whole Q accumulated) and against the matrix itself (residuals,
//! orthonormality), on random, graded and clustered matrices.
//!
//! Bounds: backward stability gives eigenvalues within c·n·ε‖A‖ of exact and residuals
//! ‖A y − λ y‖ ≈ ε‖A‖ with c of order 1; the tests allow c = 4 per row, i.e. 4 n ε ‖A‖_F
//! (‖A‖_F ≥ ‖A‖₂), and orthonormality within 4 n ε (the Cholesky-QR makes the vectors
//! orthonormal to the rounding of n-term sums).

use super::*;
use crate::simd::TestRng;
use nalgebra::{DVector, SymmetricEigen};

/// A random orthogonal matrix (Q of the QR of a random matrix).
fn orthogonal(n: usize, rng: &mut TestRng) -> DMatrix<f64> {
    DMatrix::from_fn(n, n, |_, _| rng.unit() * 2.0 - 1.0)
        .qr()
        .q()
}

/// Q diag(λ) Qᵀ, symmetrised.
fn with_spectrum(lambda: &[f64], rng: &mut TestRng) -> DMatrix<f64> {
    let q = orthogonal(lambda.len(), rng);
    let a = &q * DMatrix::from_diagonal(&DVector::from_column_slice(lambda)) * q.transpose();
    (&a + a.transpose()) * 0.5
}

/// What a check measured: eigenvalue error against nalgebra, residual, orthonormality, each
/// relative to ‖A‖_F (the last to 1).
struct Measured {
    lambda: f64,
    residual: f64,
    orthonormal: f64,
}

/// Solve `a` for its lowest `k` pairs, check them against nalgebra and `a` within the
/// module's bounds, and return what was measured.
fn check(a: &DMatrix<f64>, k: usize, what: &str) -> Measured {
    let n = a.nrows();
    let norm = a.norm().max(f64::MIN_POSITIVE);
    let bound = 4.0 * n as f64 * f64::EPSILON;
    let eig = SymEigen::new(a.clone()).expect("solved");
    let y = eig.lowest_vectors(k).expect("vectors");
    assert_eq!(y.shape(), (n, k.min(n)), "{what}");
    let mut reference: Vec<f64> = SymmetricEigen::new(a.clone())
        .eigenvalues
        .iter()
        .copied()
        .collect();
    reference.sort_by(f64::total_cmp);
    let lambda = eig
        .values()
        .iter()
        .zip(&reference)
        .fold(0.0_f64, |m, (x, r)| m.max((x - r).abs()))
        / norm;
    assert!(
        lambda <= bound,
        "{what}: eigenvalues {lambda:.2e} of ‖A‖ from nalgebra's"
    );
    assert!(
        eig.values().windows(2).all(|w| w[0] <= w[1]),
        "{what}: ascending"
    );
    let mut residual = 0.0_f64;
    for c in 0..y.ncols() {
        let r = a * y.column(c) - y.column(c) * eig.values()[c];
        residual = residual.max(r.norm() / norm);
    }
    assert!(residual <= bound, "{what}: residual {residual:.2e} of ‖A‖");
    let orthonormal = (y.transpose() * &y - DMatrix::identity(y.ncols(), y.ncols())).amax();
    assert!(
        orthonormal <= bound,
        "{what}: orthonormality {orthonormal:.2e}"
    );
    Measured {
        lambda,
        residual,
        orthonormal,
    }
}

#[test]
fn random_symmetric_matrices() {
    let mut rng = TestRng::new(0x5e1f_e16e);
    for &n in &[1, 2, 3, 4, 7, 16, 33, 80, 150] {
        let a = DMatrix::from_fn(n, n, |_, _| rng.unit() * 2.0 - 1.0);
        let a = (&a + a.transpose()) * 0.5;
        for k in [1, n / 2, n] {
            let m = check(&a, k, &format!("random n = {n}, k = {k}"));
            eprintln!(
                "random n = {n:3}, k = {k:3}: λ {:.1e}, residual {:.1e}, orthonormal {:.1e}",
                m.lambda, m.residual, m.orthonormal
            );
        }
    }
}

/// Clusters of 4 and 8 eigenvalues, exactly equal and split by 1e-12 … 1e-6 relative,
/// amid well-separated ones; the lowest k cut between clusters. Besides residuals and
/// orthonormality, the span of each whole cluster's vectors is nalgebra's: the part of
/// nalgebra's cluster vectors outside it within (bound) / (gap to the next eigenvalue).
#[test]
fn exact_and_near_multiple_eigenvalues() {
    let mut rng = TestRng::new(0xc1a5_7e25);
    for &split in &[0.0, 1e-12, 1e-9, 1e-6] {
        let mut lambda = Vec::new();
        for c in 0..6 {
            let size = if c % 2 == 0 { 8 } else { 4 };
            let base = 1.0 + c as f64;
            lambda.extend((0..size).map(|t| base * (1.0 + split * t as f64)));
            lambda.push(base + 0.5);
        }
        let n = lambda.len();
        let a = with_spectrum(&lambda, &mut rng);
        let m = check(&a, 26, &format!("clusters split {split:e}"));
        eprintln!(
            "clusters split {split:.0e}: λ {:.1e}, residual {:.1e}, orthonormal {:.1e}",
            m.lambda, m.residual, m.orthonormal
        );
        // Spans: each cluster (sorted order) against nalgebra's.
        let eig = SymEigen::new(a.clone()).unwrap();
        let y = eig.lowest_vectors(n).unwrap();
        let reference = SymmetricEigen::new(a.clone());
        let mut idx: Vec<usize> = (0..n).collect();
        idx.sort_by(|&i, &j| reference.eigenvalues[i].total_cmp(&reference.eigenvalues[j]));
        let mut start = 0;
        for c in 0..6 {
            let size = if c % 2 == 0 { 8 } else { 4 };
            let ours = y.columns(start, size);
            let theirs =
                DMatrix::from_fn(n, size, |r, j| reference.eigenvectors[(r, idx[start + j])]);
            let outside = &theirs - ours * (ours.transpose() * &theirs);
            // Gap 0.5 to the single value above, ‖A‖_F ≈ 20: ε‖A‖/gap ≈ 1e-14.
            assert!(
                outside.amax() <= 1e-12,
                "split {split:e}, cluster {c}: nalgebra's vectors {:.1e} outside ours",
                outside.amax()
            );
            start += size + 1;
        }
    }
}

/// Graded matrices: a spectrum over seven decades (as a sagging robot's assembled model,
/// whose lowest modes sit ~10⁻⁷ of the highest), with 8-fold near-clusters among the low
/// modes; and D A D with D over six decades (entries graded along the diagonal).
#[test]
fn graded_matrices() {
    let mut rng = TestRng::new(0x06ad_ed00);
    let mut lambda = Vec::new();
    for c in 0..12 {
        let base = (std::f64::consts::TAU * (1.0 + 2.0 * c as f64)).powi(2);
        lambda.extend((0..8).map(|t| base * (1.0 + 1e-9 * t as f64)));
    }
    let top = lambda[lambda.len() - 1];
    for i in 0..60 {
        lambda.push(top * 10f64.powf(4.5 * (i + 1) as f64 / 60.0));
    }
    let a = with_spectrum(&lambda, &mut rng);
    let m = check(&a, 100, "graded spectrum");
    // The low eigenvalues relative to themselves, against the exact spectrum: the QL runs
    // from the block's small end (LAPACK's choice), as accurate as nalgebra's QR (run from
    // the wrong end it was 30× worse here: 4.2e-9 against 1.3e-10).
    let low = 96;
    let relative = |values: &[f64]| {
        values[..low]
            .iter()
            .zip(&lambda)
            .fold(0.0_f64, |m, (x, l)| m.max((x / l - 1.0).abs()))
    };
    let ours = relative(SymEigen::new(a.clone()).unwrap().values());
    let mut theirs: Vec<f64> = SymmetricEigen::new(a.clone())
        .eigenvalues
        .iter()
        .copied()
        .collect();
    theirs.sort_by(f64::total_cmp);
    let theirs = relative(&theirs);
    eprintln!("graded spectrum, lowest {low} relative to themselves: ours {ours:.1e}, nalgebra {theirs:.1e}");
    assert!(
        ours <= 4.0 * theirs.max(f64::EPSILON),
        "{ours:.1e} against nalgebra's {theirs:.1e}"
    );
    eprintln!(
        "graded spectrum: λ {:.1e}, residual {:.1e}, orthonormal {:.1e}",
        m.lambda, m.residual, m.orthonormal
    );
    let n = 90;
    let d = DVector::from_fn(n, |i, _| 10f64.powf(-6.0 * i as f64 / (n - 1) as f64));
    let g = DMatrix::from_fn(n, n, |_, _| rng.unit() * 2.0 - 1.0);
    let g = (&g + g.transpose()) * 0.5;
    let a = DMatrix::from_diagonal(&d) * g * DMatrix::from_diagonal(&d);
    let m = check(&a, 60, "D A D");
    eprintln!(
        "D A D: λ {:.1e}, residual {:.1e}, orthonormal {:.1e}",
        m.lambda, m.residual, m.orthonormal
    );
}

/// Matrices that are already (block) diagonal or tridiagonal: T splits everywhere, or the
/// whole identity is one exactly multiple eigenvalue.
#[test]
fn split_and_degenerate_tridiagonals() {
    check(&DMatrix::identity(12, 12), 12, "identity");
    check(
        &DMatrix::from_diagonal(&DVector::from_fn(9, |i, _| (9 - i) as f64)),
        5,
        "diagonal",
    );
    let t = DMatrix::from_fn(20, 20, |r, c| match r.abs_diff(c) {
        0 => 2.0,
        1 if r.min(c) % 5 != 4 => -1.0,
        _ => 0.0,
    });
    check(&t, 20, "tridiagonal, four equal blocks");
    check(&DMatrix::zeros(5, 5), 5, "zero");
}

#[test]
fn bad_input_is_an_error() {
    assert_eq!(
        SymEigen::new(DMatrix::zeros(3, 4)).err(),
        Some(SymEigenError::NotSquare { rows: 3, cols: 4 })
    );
    let mut a = DMatrix::identity(4, 4);
    a[(2, 1)] = f64::NAN;
    assert_eq!(SymEigen::new(a).err(), Some(SymEigenError::NotFinite));
    let e = SymEigen::new(DMatrix::zeros(0, 0)).unwrap();
    assert!(e.values().is_empty() && e.lowest_vectors(3).unwrap().ncols() == 0);
}

/// Every tier of the reduction kernel the CPU has equals the portable body bit for bit.
#[test]
fn kernel_tiers_agree_bit_for_bit() {
    let mut rng = TestRng::new(0x7135_5eed);
    let n = 37;
    let a0 = DMatrix::from_fn(n, n, |_, _| rng.sign() * rng.decades(-3.0, 3.0));
    let a0: Vec<f64> = ((&a0 + a0.transpose()) * 0.5).data.into();
    let run = |tier: usize| {
        let (mut a, mut tau, mut d, mut e) =
            (a0.clone(), vec![0.0; n - 2], vec![0.0; n], vec![0.0; n - 1]);
        let mut work = vec![0.0; 2 * n];
        reduce_tier(tier, &mut a, n, &mut tau, &mut d, &mut e, &mut work)?;
        Some((a, tau, d, e))
    };
    let portable = run(0).expect("tier 0");
    for tier in 1..=2 {
        if let Some(r) = run(tier) {
            assert!(r == portable, "tier {tier} differs from the portable body");
        }
    }
}
