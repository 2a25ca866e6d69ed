//! Basis-invariant end-effector participations of a cluster: the eigenvalues of
//! M_ee^{1/2} R M_ee^{1/2}, R = Σ_{cluster} φ_ee φ_eeᵀ (mass-normalised modes), from D's
//! null space in a pole-free interval or from the residue of D⁻¹ at a pole.

use crate::modal::dynamic_stiffness::{DynEval, EigD, LoadedChains};
use nalgebra::{Matrix6, SymmetricEigen, Vector6};

/// M_ee as a 6 × 6 positive definite matrix: the unused rows of a point mass (dim 3) hold
/// the identity, which only ever meets zero rows of R.
fn mass_padded(p: &LoadedChains) -> Matrix6<f64> {
    let mut m = p.m6;
    for j in p.dim..6 {
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

/// The participations of a cluster of `mult` modes whose roots are branches `branch`,
/// `branch + 1`, ... of D at the evaluation `e` (pole-free): with V those unit eigenvectors
/// and G = Vᵀ(−D')V, the generalised eigenvalues of (Vᵀ M_ee V, G). A simple mode gets
/// m_ee‖v‖²/vᵀ(−D')v.
pub(super) fn null_space_participations(
    p: &LoadedChains,
    e: &DynEval,
    eg: &EigD,
    branch: usize,
    mult: u32,
) -> [f64; 6] {
    let r = (mult as usize).min(p.dim.saturating_sub(branch));
    let mut g = Matrix6::identity();
    let mut pm = Matrix6::zeros();
    for j in 0..r {
        for l in 0..r {
            let (vj, vl) = (&eg.vectors[branch + j], &eg.vectors[branch + l]);
            g[(j, l)] = -bilinear(vj, &e.dd, vl);
            pm[(j, l)] = bilinear(vj, &p.m6, vl);
        }
    }
    // Generalised eigenvalues of (P, G): eigenvalues of C⁻¹ P C⁻ᵀ, G = C Cᵀ; equal to
    // those of Cᵀ-congruence with G⁻¹ (same spectrum as G⁻¹P).
    let Some(gi) = g.try_inverse() else {
        return [f64::NAN; 6];
    };
    let gi = (gi + gi.transpose()) * 0.5;
    congruent_values(&gi, &pm)
}

/// The participations of the cluster at λ from the residue of D⁻¹, by the symmetric
/// quotient R = ½λh[D(λ(1 − h))⁻¹ − D(λ(1 + h))⁻¹] (`em`, `ep` the two evaluations).
pub(super) fn residue_participations(
    p: &LoadedChains,
    lambda: f64,
    h: f64,
    em: &DynEval,
    ep: &DynEval,
) -> [f64; 6] {
    let pad = |d: &Matrix6<f64>| {
        let mut d = *d;
        for j in p.dim..6 {
            d[(j, j)] = 1.0;
        }
        d
    };
    let (Some(im), Some(ip)) = (pad(&em.d).try_inverse(), pad(&ep.d).try_inverse()) else {
        return [f64::NAN; 6];
    };
    let r = (im - ip) * (0.5 * lambda * h);
    let r = (r + r.transpose()) * 0.5;
    congruent_values(&mass_padded(p), &r)
}
