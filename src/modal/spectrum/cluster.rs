//! Basis-invariant end-effector participations of a cluster: the eigenvalues of
//! M_ee^{1/2} R M_ee^{1/2}, R = Σ_{cluster} φ_ee φ_eeᵀ (mass-normalised modes), from D's
//! null space in a pole-free interval or from the residue of D⁻¹ at a pole.

use super::Member;
use crate::modal::engine::{DynEval, EigD};
use nalgebra::{Matrix6, SymmetricEigen, Vector6};

/// M_ee as a 6 × 6 positive definite matrix: the unused rows of a point mass (dim 3) hold
/// the identity, which only ever meets zero rows of R.
fn mass_padded(m6: &Matrix6<f64>, dim: usize) -> Matrix6<f64> {
    let mut m = *m6;
    for j in dim..6 {
        m[(j, j)] = 1.0;
    }
    m
}

/// Eigenvalues of Lᵀ A L (descending, clamped to 0 ..= 1) for M = L Lᵀ positive definite.
fn congruent_values(m: &Matrix6<f64>, a: &Matrix6<f64>) -> [f64; 6] {
    let mut out = [0.0; 6];
    let Some(ch) = m.cholesky() else {
        return [f64::NAN; 6];
    };
    let l = ch.l();
    let b = l.transpose() * a * l;
    let b = (b + b.transpose()) * 0.5;
    let e = SymmetricEigen::new(b);
    for (o, v) in out.iter_mut().zip(e.eigenvalues.iter()) {
        *o = v.clamp(0.0, 1.0);
    }
    out.sort_by(|x, y| y.total_cmp(x));
    out
}

/// uᵀ A w.
fn bilinear(u: &Vector6<f64>, a: &Matrix6<f64>, w: &Vector6<f64>) -> f64 {
    (u.transpose() * a * w)[(0, 0)]
}

/// The end-effector block of the residue of D⁻¹ of the `r` modes whose roots are branches
/// `branch`, `branch + 1`, ... of D at the evaluation `e` (pole-free, the roots equal):
/// R = V G⁻¹ Vᵀ with V those unit eigenvectors and G = Vᵀ(−D')V. For one mode,
/// v vᵀ / vᵀ(−D')v.
pub(super) fn branch_residue(e: &DynEval, eg: &EigD, branch: usize, r: usize) -> Matrix6<f64> {
    let mut g = Matrix6::identity();
    let mut v = Matrix6::zeros();
    for j in 0..r {
        v.set_column(j, &eg.vectors[branch + j]);
        for l in 0..r {
            g[(j, l)] = -bilinear(&eg.vectors[branch + j], &e.dd, &eg.vectors[branch + l]);
        }
    }
    let Some(gi) = g.try_inverse() else {
        return Matrix6::repeat(f64::NAN);
    };
    // Padding columns of V are zero: they add nothing.
    let res = v * gi * v.transpose();
    (res + res.transpose()) * 0.5
}

/// The participations of a cluster from its residue block R: the eigenvalues of
/// M_ee^{1/2} R M_ee^{1/2}, largest first.
pub(super) fn participations(m6: &Matrix6<f64>, dim: usize, r: &Matrix6<f64>) -> [f64; 6] {
    congruent_values(&mass_padded(m6, dim), r)
}

/// The participations of the cluster at λ from the residue of D⁻¹, by the symmetric
/// quotient R = ½λh[D(λ(1 − h))⁻¹ − D(λ(1 + h))⁻¹] (`em`, `ep` the two evaluations).
pub(super) fn residue_participations(
    m6: &Matrix6<f64>,
    dim: usize,
    lambda: f64,
    h: f64,
    em: &DynEval,
    ep: &DynEval,
) -> [f64; 6] {
    let pad = |d: &Matrix6<f64>| {
        let mut d = *d;
        for j in dim..6 {
            d[(j, j)] = 1.0;
        }
        d
    };
    let (Some(im), Some(ip)) = (pad(&em.d).try_inverse(), pad(&ep.d).try_inverse()) else {
        return [f64::NAN; 6];
    };
    let r = (im - ip) * (0.5 * lambda * h);
    let r = (r + r.transpose()) * 0.5;
    congruent_values(&mass_padded(m6, dim), &r)
}

/// Members of a cluster whose roots agree to this (relative) are one numerically degenerate
/// eigenspace: their residue is V G⁻¹ Vᵀ at one root. Members further apart (split by less
/// than the cluster probe) each get theirs at their own root — D' varies fast near a pole,
/// so one evaluation for a split cluster would be off by (split)·D''/D'. Newton's noise
/// on a degenerate root is ~1e-14; a split below 1e-12 changes D' by less than 1e-12·D''/D'.
const DEGENERATE_REL: f64 = 1e-12;

/// The residue block of a pole-free cluster from its solved members: members whose roots
/// agree to [`DEGENERATE_REL`] form one degenerate eigenspace (V G⁻¹ Vᵀ over their branches
/// at the first one's root), the others each their own term at their own root.
pub(super) fn members_residue(members: &[Member]) -> Matrix6<f64> {
    let mut r = Matrix6::zeros();
    let mut g = 0;
    while g < members.len() {
        let (l0, e, eg, b) = &members[g];
        let mut end = g + 1;
        while end < members.len() && (members[end].0 - l0).abs() <= DEGENERATE_REL * l0 {
            end += 1;
        }
        r += branch_residue(e, eg, *b, end - g);
        g = end;
    }
    r
}
