//! The dense checks of a frequency response ([`super::DenseCheckKind`]): the structured
//! receptance checked against the assembled dense problem in the same run.
//!
//! - LU: one complex LU of the assembled c(K − λM) per frequency
//!   ([`crate::modal::dense_receptance`]), O(n³) each.
//! - modal: one generalized symmetric eigendecomposition of the assembled (K, M)
//!   (M = L Lᵀ, L⁻¹ K L⁻ᵀ = Y Λ Yᵀ, mass-normalised shapes u_r = L⁻ᵀ y_r), then at each
//!   frequency the exact dense receptance by summation over every mode: with the damped
//!   dynamic stiffness written c_K K − c_M M (loss factor: c_K = 1 + iη, c_M = ω²; Rayleigh:
//!   c_K = 1 + iωβ, c_M = ω² − iωα; none: 1, ω²), K u_r = λ_r M u_r and u_rᵀ M u_r = 1 give
//!   (c_K K − c_M M)⁻¹ = Σ_r u_r u_rᵀ / (c_K λ_r − c_M); modal damping ζ:
//!   Σ_r u_r u_rᵀ / (λ_r − ω² + 2iζ ω_r ω), every mode kept (no residual term). O(n³) once,
//!   then O(n d²) per frequency, so 1 000 frequencies at 939 DOF run in seconds. The
//!   summation is itself checked against the dense complex LU at a few
//!   frequencies spread over the band (`lu_points`; loss factor, Rayleigh, none; modal damping has no
//!   matrix to factor).

use crate::modal::dense_receptance;
use crate::scene::Damping;
use crate::study::StudyError;
use nalgebra::{DMatrix, Matrix6, SymmetricEigen};
use num_complex::Complex64;
use std::f64::consts::PI;
use std::time::Instant;

/// The dense check of one run.
#[derive(Debug, Clone)]
pub struct DenseCheck {
    /// `lu` (complex LU at every frequency) or `modal` (summation over every dense mode).
    pub method: &'static str,
    /// Largest relative Frobenius difference between the structured receptance and the
    /// dense one over all frequencies.
    pub max_rel_diff: f64,
    /// That difference at each frequency.
    pub rel_diff: Vec<f64>,
    /// Wall time of the dense reference over all frequencies, s (for `modal`: the
    /// eigendecomposition and the summation).
    pub seconds: f64,
    /// Degrees of freedom of the assembled problem.
    pub dof: usize,
    /// `modal`: the eigendecomposition's share of `seconds`.
    pub eig_seconds: Option<f64>,
    /// `modal`: the LU spot check, when one was made.
    pub lu: Option<LuSpot>,
}

/// The complex LU at a few frequencies, against the modal summation and the structured
/// receptance.
#[derive(Debug, Clone)]
pub struct LuSpot {
    /// The frequencies solved, Hz.
    pub frequencies_hz: Vec<f64>,
    /// Largest relative difference of the modal summation from the LU.
    pub modal_rel_diff: f64,
    /// Largest relative difference of the structured receptance from the LU.
    pub structured_rel_diff: f64,
    /// Wall time of the LU solves, s (all of them).
    pub seconds: f64,
}

/// A structured response and the assembled dense problem it is checked against.
#[derive(Debug, Clone, Copy)]
pub struct Checked<'a> {
    /// Stiffness matrix K of the assembled problem (N/m; N·m/rad in rotational rows).
    pub k: &'a DMatrix<f64>,
    /// Mass matrix M of the assembled problem (kg; kg·m² in rotational rows).
    pub m: &'a DMatrix<f64>,
    /// 3 (point mass) or 6 (rigid body): the leading block compared.
    pub dim: usize,
    /// The damping of both.
    pub damping: &'a Damping,
    /// The frequencies, Hz.
    pub freqs: &'a [f64],
    /// The structured receptance at each frequency, m/N.
    pub h: &'a [Matrix6<Complex64>],
}

/// Relative Frobenius difference ‖a − b‖/‖b‖ of the leading `dim` × `dim` blocks.
fn rel_diff(a: &Matrix6<Complex64>, b: &Matrix6<Complex64>, dim: usize) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..dim {
        for j in 0..dim {
            num += (a[(i, j)] - b[(i, j)]).norm_sqr();
            den += b[(i, j)].norm_sqr();
        }
    }
    (num / den).sqrt()
}

/// The dense modes: eigenvalues λ_r (rad²/s²) and the end-effector rows of the
/// mass-normalised shapes (`dim` × n).
struct DenseModes {
    lambda: Vec<f64>,
    ee: DMatrix<f64>,
}

fn dense_modes(k: &DMatrix<f64>, m: &DMatrix<f64>, dim: usize) -> Result<DenseModes, StudyError> {
    let fail = || {
        StudyError::Solve("dense modal summation: the mass matrix is not positive definite".into())
    };
    let n = k.nrows();
    let l = m.clone().cholesky().ok_or_else(fail)?.l();
    let linv_k = l.solve_lower_triangular(k).ok_or_else(fail)?;
    let c = l
        .solve_lower_triangular(&linv_k.transpose())
        .ok_or_else(fail)?;
    let c = (&c + c.transpose()) * 0.5;
    let eig = SymmetricEigen::new(c);
    // Rows 0..dim of L⁻ᵀ are the columns 0..dim of L⁻¹: W = L⁻¹ [e_0 … e_dim−1].
    let mut e = DMatrix::<f64>::zeros(n, dim);
    for i in 0..dim {
        e[(i, i)] = 1.0;
    }
    let w = l.solve_lower_triangular(&e).ok_or_else(fail)?;
    let ee = w.transpose() * &eig.eigenvectors;
    Ok(DenseModes {
        lambda: eig.eigenvalues.iter().copied().collect(),
        ee,
    })
}

/// The summed dense receptance at ω.
fn modal_sum(modes: &DenseModes, dim: usize, damping: &Damping, w: f64) -> Matrix6<Complex64> {
    let one = Complex64::new(1.0, 0.0);
    let mut out = Matrix6::from_element(Complex64::new(0.0, 0.0));
    for (r, &lam) in modes.lambda.iter().enumerate() {
        let den = match *damping {
            Damping::None => Complex64::new(lam - w * w, 0.0),
            Damping::LossFactor { eta } => Complex64::new(lam - w * w, eta * lam),
            Damping::Rayleigh {
                alpha_per_s,
                beta_s,
            } => Complex64::new(lam - w * w, w * beta_s * lam + w * alpha_per_s),
            Damping::ModalRatio { zeta } => {
                Complex64::new(lam - w * w, 2.0 * zeta * lam.max(0.0).sqrt() * w)
            }
        };
        let g = one / den;
        for i in 0..dim {
            let ui = modes.ee[(i, r)];
            for j in 0..dim {
                out[(i, j)] += g * (ui * modes.ee[(j, r)]);
            }
        }
    }
    out
}

impl Checked<'_> {
    /// The dense complex LU's receptance at frequency `i`.
    fn lu_at(&self, i: usize) -> Result<Matrix6<Complex64>, StudyError> {
        let w = 2.0 * PI * self.freqs[i];
        Ok(dense_receptance(self.k, self.m, self.dim, self.damping, w)?)
    }

    /// [`super::DenseCheckKind::Lu`]: the dense complex LU at every frequency (loss factor,
    /// Rayleigh or none; the caller refuses modal damping).
    pub fn lu_every(&self) -> Result<DenseCheck, StudyError> {
        let t0 = Instant::now();
        let diff = (0..self.freqs.len())
            .map(|i| Ok(rel_diff(&self.h[i], &self.lu_at(i)?, self.dim)))
            .collect::<Result<Vec<f64>, StudyError>>()?;
        Ok(DenseCheck {
            method: "lu",
            max_rel_diff: diff.iter().fold(0.0f64, |w, &d| w.max(d)),
            rel_diff: diff,
            seconds: t0.elapsed().as_secs_f64(),
            dof: self.k.nrows(),
            eig_seconds: None,
            lu: None,
        })
    }

    /// [`super::DenseCheckKind::Modal`]: the summation over every dense mode at every
    /// frequency, and the LU at `lu_points` of them (evenly spread indices, both ends
    /// included).
    pub fn modal_every(&self, lu_points: usize) -> Result<DenseCheck, StudyError> {
        let (dim, freqs) = (self.dim, self.freqs);
        let t0 = Instant::now();
        let modes = dense_modes(self.k, self.m, dim)?;
        let eig_seconds = t0.elapsed().as_secs_f64();
        let dense: Vec<Matrix6<Complex64>> = freqs
            .iter()
            .map(|&f| modal_sum(&modes, dim, self.damping, 2.0 * PI * f))
            .collect();
        let seconds = t0.elapsed().as_secs_f64();
        let diff: Vec<f64> = self
            .h
            .iter()
            .zip(&dense)
            .map(|(a, b)| rel_diff(a, b, dim))
            .collect();
        let n = freqs.len();
        let lu = if lu_points == 0 || matches!(self.damping, Damping::ModalRatio { .. }) {
            None
        } else {
            let picks: Vec<usize> = if lu_points >= n {
                (0..n).collect()
            } else if lu_points == 1 {
                vec![n / 2]
            } else {
                (0..lu_points)
                    .map(|i| (i * (n - 1) + (lu_points - 1) / 2) / (lu_points - 1))
                    .collect()
            };
            let t1 = Instant::now();
            let (mut modal_rel_diff, mut structured_rel_diff) = (0.0f64, 0.0f64);
            for &i in &picks {
                let r = self.lu_at(i)?;
                modal_rel_diff = modal_rel_diff.max(rel_diff(&dense[i], &r, dim));
                structured_rel_diff = structured_rel_diff.max(rel_diff(&self.h[i], &r, dim));
            }
            Some(LuSpot {
                frequencies_hz: picks.iter().map(|&i| freqs[i]).collect(),
                modal_rel_diff,
                structured_rel_diff,
                seconds: t1.elapsed().as_secs_f64(),
            })
        };
        Ok(DenseCheck {
            method: "modal",
            max_rel_diff: diff.iter().fold(0.0f64, |w, &d| w.max(d)),
            rel_diff: diff,
            seconds,
            dof: self.k.nrows(),
            eig_seconds: Some(eig_seconds),
            lu,
        })
    }
}
