//! The generalized problem K u = λ M u in standard form, for a dense solve whose M is an
//! assembled FEM mass: M = L Lᵀ (Cholesky), C = L⁻¹ K L⁻ᵀ (symmetric, the same λ), and an
//! eigenvector y of C gives u = L⁻ᵀ y, M-orthonormal when the y are orthonormal.
//!
//! An assembled consistent mass couples a node only with its neighbours and the end
//! effector, so L keeps that profile (a few entries per row): it is factored within its
//! envelope ([`super::ritz::Envelope`], no fill outside a row's first nonzero, O(n b²) for
//! rows of b entries instead of n³/3) and the triangular solves
//! skip its zeros: O(n · nnz(row) · columns) instead of O(n³/2) each (on `suspended_8`'s
//! 219 DOF they took a quarter of a basis's dense solve when made densely). The entries
//! skipped are exact zeros of the factor, so the result is that of the dense solves up to
//! the order of the sums' rounding.

use super::ritz::Envelope;
use super::ModalError;
use nalgebra::DMatrix;

/// M's Cholesky factor with its nonzeros by row and by column, and C = L⁻¹ K L⁻ᵀ.
#[derive(Debug, Clone)]
pub struct StandardForm {
    /// C = L⁻¹ K L⁻ᵀ, symmetrised.
    pub c: DMatrix<f64>,
    /// L's diagonal.
    diag: Vec<f64>,
    /// Row i's nonzeros left of the diagonal: (column, L_ik).
    rows: Vec<Vec<(usize, f64)>>,
    /// Column i's nonzeros below the diagonal: (row, L_ki).
    cols: Vec<Vec<(usize, f64)>>,
}

impl StandardForm {
    /// The standard form of the pencil (K, M) (module docs);
    /// [`ModalError::MassNotDefinite`] when M has no Cholesky factor.
    pub fn new(k: &DMatrix<f64>, m: &DMatrix<f64>) -> Result<StandardForm, ModalError> {
        let n = m.nrows();
        let order: Vec<usize> = (0..n).collect();
        let l = Envelope::factor(m, &order).ok_or(ModalError::MassNotDefinite)?;
        let mut rows = vec![Vec::new(); n];
        let mut cols = vec![Vec::new(); n];
        let mut diag = vec![0.0; n];
        for (i, row) in rows.iter_mut().enumerate() {
            let (first, entries) = l.row(i);
            let (off, d) = entries.split_at(entries.len() - 1);
            diag[i] = d[0];
            for (j, &v) in (first..i).zip(off) {
                if v != 0.0 {
                    row.push((j, v));
                    cols[j].push((i, v));
                }
            }
        }
        if diag.iter().any(|d| !(d.is_finite() && *d > 0.0)) {
            return Err(ModalError::MassNotDefinite);
        }
        let mut form = StandardForm {
            c: DMatrix::zeros(0, 0),
            diag,
            rows,
            cols,
        };
        let mut a = k.clone();
        form.solve_lower(&mut a);
        let mut c = a.transpose();
        form.solve_lower(&mut c);
        form.c = (&c + c.transpose()) * 0.5;
        Ok(form)
    }

    /// B ← L⁻¹ B.
    fn solve_lower(&self, b: &mut DMatrix<f64>) {
        for mut col in b.column_iter_mut() {
            for i in 0..col.len() {
                let mut s = col[i];
                for &(j, v) in &self.rows[i] {
                    s -= v * col[j];
                }
                col[i] = s / self.diag[i];
            }
        }
    }

    /// u = L⁻ᵀ y for each column of `y` (eigenvectors of C: the pencil's, M-orthonormal).
    pub fn vectors(&self, y: &DMatrix<f64>) -> DMatrix<f64> {
        let mut u = y.clone();
        for mut col in u.column_iter_mut() {
            for i in (0..col.len()).rev() {
                let mut s = col[i];
                for &(j, v) in &self.cols[i] {
                    s -= v * col[j];
                }
                col[i] = s / self.diag[i];
            }
        }
        u
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against nalgebra's dense triangular solves on a banded pencil with a dense border
    /// (the assembly's shape): C and u within 1e-13 of theirs.
    #[test]
    fn matches_the_dense_solves() {
        let n = 40;
        let mut k = DMatrix::<f64>::zeros(n, n);
        let mut m = DMatrix::<f64>::zeros(n, n);
        for i in 0..n {
            k[(i, i)] = 3.0 + i as f64;
            m[(i, i)] = 4.0 + (i % 3) as f64;
            if i + 3 < n {
                k[(i, i + 3)] = -1.0;
                k[(i + 3, i)] = -1.0;
                m[(i, i + 3)] = 1.0;
                m[(i + 3, i)] = 1.0;
            }
            if i >= 3 {
                // A border: the first 3 DOF coupled with every 7th.
                if i % 7 == 0 {
                    k[(0, i)] = -0.5;
                    k[(i, 0)] = -0.5;
                    m[(1, i)] = 0.5;
                    m[(i, 1)] = 0.5;
                }
            }
        }
        let form = StandardForm::new(&k, &m).unwrap();
        let l = m.clone().cholesky().unwrap().l();
        let a = l.solve_lower_triangular(&k).unwrap();
        let c = l.solve_lower_triangular(&a.transpose()).unwrap();
        let c = (&c + c.transpose()) * 0.5;
        assert!((&form.c - &c).amax() <= 1e-13 * c.amax());
        let y = DMatrix::<f64>::from_fn(n, 5, |i, j| ((i * 7 + j * 3) % 11) as f64 - 5.0);
        let u = l.transpose().solve_upper_triangular(&y).unwrap();
        assert!((form.vectors(&y) - &u).amax() <= 1e-13 * u.amax());
    }
}
