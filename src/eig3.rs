//! Small symmetric eigen kernels: the 3 × 3 closed form with its Jacobi fallback, used on
//! every evaluation of a point-mass end-effector's D(λ).

use nalgebra::{Matrix3, Vector3};

/// The closed form needs a spread p = ‖B − qI‖_F/√6 of the scaled matrix above this; below
/// it the eigenvalues nearly coincide and the trigonometric formula loses accuracy.
const CLOSED_FORM_MIN_SPREAD: f64 = 1e-3;
/// ... and adjacent scaled eigenvalues at least this far apart, else the cross-product
/// eigenvectors are inaccurate.
const CLOSED_FORM_MIN_GAP: f64 = 2e-4;
/// Jacobi sweeps at most (cyclic Jacobi converges quadratically: a handful suffice).
const JACOBI_MAX_SWEEPS: usize = 12;
/// Jacobi stops once the squared off-diagonal is below this fraction of the squared norm
/// (ε² ≈ 5e-32: the off-diagonal is then below ε‖A‖).
const JACOBI_OFF_TOL: f64 = 1e-34;

/// Sorted eigen-decomposition of a symmetric 3 × 3 matrix (ascending).
#[derive(Debug, Clone, Copy)]
pub struct Eig3 {
    /// Eigenvalues ascending.
    pub values: [f64; 3],
    /// Matching unit eigenvectors.
    pub vectors: [Vector3<f64>; 3],
}

/// Symmetric 3 × 3 eigen-decomposition, sorted ascending. Closed form (trigonometric
/// eigenvalues, eigenvectors from cross products of rows of A − μI) when the eigenvalues are
/// separated by at least 2e-4 of the largest |entry| of A; Jacobi rotations
/// ([`eig3_jacobi`]) otherwise, where the closed form loses accuracy. No allocation.
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
    if !(p > CLOSED_FORM_MIN_SPREAD) {
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
    if (e_mid - e_lo) < CLOSED_FORM_MIN_GAP || (e_hi - e_mid) < CLOSED_FORM_MIN_GAP {
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
    for _sweep in 0..JACOBI_MAX_SWEEPS {
        let off = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
        if !(off > JACOBI_OFF_TOL * norm2) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SymmetricEigen;

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
