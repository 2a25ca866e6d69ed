//! Mechanisms: a direction of the end-effector that the cables do not hold.
//!
//! With the static stiffness K (the end-effector's D(0): N/m, N/rad, N·m/m and N·m/rad
//! blocks) and its mass M_ee (kg; kg·m² in the rotational block), the end-effector's
//! lowest static eigenvalue is λ_min of M_ee^{-1/2} K M_ee^{-1/2} = L⁻¹ K L⁻ᵀ (M_ee = L Lᵀ,
//! Cholesky). When λ_min ≤ [`MECHANISM_REL`] · λ_max the stiffness is singular to within
//! its rounding: that direction (e.g. the spin of a platform whose attachments all lie on
//! one axis) has no stiffness, no natural frequency, and f1 = 0 would be an artefact of the
//! rounding rather than a frequency. [`free_direction`] returns it, as an end-effector
//! displacement x = L⁻ᵀ y (y the eigenvector), scaled to unit length. Fixed-size matrices:
//! no allocation.

use nalgebra::{Matrix3, Matrix6, Vector6};

/// The relative size (λ_min / λ_max of the mass-normalised static stiffness) below which a
/// direction counts as free. K is assembled from terms of size λ_max with rounding ≈ 1e-16
/// relative, so a truly free direction comes out at ≤ ~1e-15 · λ_max; 1e-12 leaves three
/// orders of margin above that and only calls a direction free whose frequency would be
/// below 1e-6 of the stiffest one's.
pub const MECHANISM_REL: f64 = 1e-12;

/// A cheap pre-test for [`free_direction`]: λ₁ (rad²/s²) at or below this fraction of
/// max_i K_ii / M_ii can be a mechanism (the largest diagonal ratio bounds λ_max from below
/// within a factor of the dimension), so only such cycles pay for the eigen-decomposition.
pub const MECHANISM_PRETEST_REL: f64 = 1e-9;

/// Whether λ₁ (rad²/s²) is small enough against the diagonal of `k` and `m` (leading
/// `dim` × `dim` blocks) for [`free_direction`] to be worth running.
pub fn may_be_mechanism(lambda1: f64, k: &Matrix6<f64>, m: &Matrix6<f64>, dim: usize) -> bool {
    let scale = (0..dim).map(|i| k[(i, i)] / m[(i, i)]).fold(0.0, f64::max);
    !(lambda1 > MECHANISM_PRETEST_REL * scale)
}

/// The free direction of the static stiffness `k` with the end-effector mass `m` (leading
/// `dim` × `dim` blocks, dim 3 or 6): a unit displacement (m; rad in the rotational part)
/// along which the mass-normalised stiffness is ≤ [`MECHANISM_REL`] of its largest, or None
/// when every direction is held. Non-finite input or a mass that is not positive definite
/// gives None (the caller's other checks report those).
pub fn free_direction(k: &Matrix6<f64>, m: &Matrix6<f64>, dim: usize) -> Option<Vector6<f64>> {
    let (mut k, mut m) = (0.5 * (k + k.transpose()), *m);
    if dim == 3 {
        // A point mass: pad the rotational block with a held direction of eigenvalue
        // s = max_i K_ii/M_ii (≤ the translational λ_max, so neither extreme changes).
        let s = (0..3).map(|i| k[(i, i)] / m[(i, i)]).fold(0.0, f64::max);
        k.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Matrix3::identity() * s));
        m.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&Matrix3::identity());
        for (r, c) in (0..3).flat_map(|r| (3..6).map(move |c| (r, c))) {
            k[(r, c)] = 0.0;
            k[(c, r)] = 0.0;
            m[(r, c)] = 0.0;
            m[(c, r)] = 0.0;
        }
    }
    let li = m.cholesky()?.l().try_inverse()?;
    let e = (li * k * li.transpose()).symmetric_eigen();
    let (imin, lmin) = e.eigenvalues.argmin();
    let lmax = e.eigenvalues.max();
    if !(lmax.is_finite() && lmin.is_finite()) || lmin > MECHANISM_REL * lmax {
        return None;
    }
    let x = li.transpose() * e.eigenvectors.column(imin);
    // The sign that makes the largest component positive (a direction, not an arrow).
    let sign = if x[x.iamax()] < 0.0 { -1.0 } else { 1.0 };
    Some(x * (sign / x.norm()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mass(m: f64, j: f64) -> Matrix6<f64> {
        let mut mm = Matrix6::zeros();
        mm.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * m));
        mm.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Matrix3::identity() * j));
        mm
    }

    /// A stiffness with an exactly free spin about z (closed form: row and column 5 zero)
    /// is found, whatever the other directions; a soft but held direction (1e-8 of the
    /// stiffest) is not.
    #[test]
    fn a_free_spin_is_found_and_a_soft_direction_is_not() {
        let mut k = Matrix6::from_diagonal(&Vector6::new(1e6, 2e6, 5e5, 3e5, 2e5, 0.0));
        k[(0, 2)] = 1e5;
        k[(2, 0)] = 1e5;
        let m = mass(1.5, 0.1);
        let d = free_direction(&k, &m, 6).expect("free spin");
        assert!((d[5].abs() - 1.0).abs() < 1e-12, "{d:?}");
        assert!(may_be_mechanism(0.0, &k, &m, 6));
        k[(5, 5)] = 1e-8 * 3e5;
        assert!(free_direction(&k, &m, 6).is_none());
        // Point mass: a planar robot's normal.
        let k3 = Matrix6::from_diagonal(&Vector6::new(1e4, 1e4, 0.0, 0.0, 0.0, 0.0));
        let d = free_direction(&k3, &mass(2.0, 1.0), 3).expect("free normal");
        assert!((d[2].abs() - 1.0).abs() < 1e-12, "{d:?}");
    }
}
