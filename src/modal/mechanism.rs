//! Mechanisms: a motion of a rigid end-effector that moves none of its attachment points.
//!
//! A rigid platform's motion (translation t, m; rotation ω, rad) moves attachment i, at b_i
//! (m, world frame, from the reference point), by v_i = t + ω × b_i = J_i (t, ω) with
//! J_i = [I, −[b_i×]]. A motion with every v_i = 0 changes no cable's length or direction:
//! neither the cables' elastic nor their geometric stiffness resists it, so it has no
//! stiffness and no natural frequency at all (the spin about the line through attachments
//! that lie on one axis). Such motions are the null space of G = Σ_i J_iᵀ J_i (6 × 6,
//! symmetric positive semi-definite); [`free_direction`] returns the eigenvector of its
//! smallest eigenvalue when that is ≤ [`MECHANISM_REL`] of its largest. This is geometry
//! alone: a direction that is held only weakly (small tensions' geometric stiffness, a
//! point mass out of a planar robot's plane) is not a mechanism and keeps its small
//! frequency. A point mass has none (J_i = I).
//!
//! The estimator runs the test only when λ₁ passes the cheap pre-test [`may_be_mechanism`].
//! Fixed-size matrices: no allocation.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// The relative size (λ_min / λ_max of G) below which a motion counts as moving no
/// attachment. G is summed from the attachment vectors with rounding ≈ 1e-16 relative, so
/// an exact null motion comes out at ≤ ~1e-15 · λ_max; 1e-12 leaves three orders of margin
/// and calls free only a motion that moves every attachment by less than 1e-6 of the
/// platform's own size per unit rotation.
pub const MECHANISM_REL: f64 = 1e-12;

/// A cheap pre-test for [`free_direction`]: a λ₁ (rad²/s²) at or below this fraction of
/// max_i K_ii / M_ii (leading `dim` × `dim` blocks of the static stiffness and the mass)
/// can belong to a mechanism, so only such cycles pay for the eigen-decomposition. A
/// mechanism's λ₁ is zero up to rounding (≈ 1e-16 of that scale).
pub const MECHANISM_PRETEST_REL: f64 = 1e-9;

/// Whether λ₁ (rad²/s²) is small enough against the diagonal of `k` and `m` for
/// [`free_direction`] to be worth running.
pub fn may_be_mechanism(lambda1: f64, k: &Matrix6<f64>, m: &Matrix6<f64>, dim: usize) -> bool {
    let scale = (0..dim).map(|i| k[(i, i)] / m[(i, i)]).fold(0.0, f64::max);
    !(lambda1 > MECHANISM_PRETEST_REL * scale)
}

/// The motion (t, ω) of a rigid end-effector with attachments at `arms_m` (m, world frame)
/// that moves none of them, scaled to unit length with its largest component positive; None
/// when every motion moves some attachment, or for non-finite input.
pub fn free_direction<'a>(
    arms_m: impl IntoIterator<Item = &'a Vector3<f64>>,
) -> Option<Vector6<f64>> {
    let mut g = Matrix6::zeros();
    for b in arms_m {
        let bx = b.cross_matrix();
        let mut j = nalgebra::Matrix3x6::zeros();
        j.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::identity());
        j.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-bx));
        g += j.transpose() * j;
    }
    let e = g.symmetric_eigen();
    let (imin, lmin) = e.eigenvalues.argmin();
    let lmax = e.eigenvalues.max();
    if !(lmax.is_finite() && lmin.is_finite() && lmax > 0.0) || lmin > MECHANISM_REL * lmax {
        return None;
    }
    let x: Vector6<f64> = e.eigenvectors.column(imin).into_owned();
    let sign = if x[x.iamax()] < 0.0 { -1.0 } else { 1.0 };
    Some(x * (sign / x.norm()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Attachments on one line through the reference point: the spin about that line is
    /// free (closed form: (0, 0, 0, unit axis)); on a line offset from the reference point
    /// the free motion also translates (t = −ω × b); attachments off the line: none.
    #[test]
    fn attachments_on_a_line_leave_the_spin_about_it_free() {
        let on_z = [Vector3::new(0.0, 0.0, 0.5), Vector3::new(0.0, 0.0, -0.5)];
        let d = free_direction(&on_z).expect("free spin");
        assert!(
            (d[5] - 1.0).abs() < 1e-12 && d.rows(0, 5).norm() < 1e-12,
            "{d:?}"
        );
        let offset = [Vector3::new(0.2, 0.0, 0.5), Vector3::new(0.2, 0.0, -0.5)];
        let d = free_direction(&offset).expect("free spin about an offset line");
        let t = Vector3::new(d[0], d[1], d[2]);
        let w = Vector3::new(d[3], d[4], d[5]);
        for b in &offset {
            assert!((t + w.cross(b)).norm() < 1e-12, "{d:?} moves {b:?}");
        }
        let spread = [
            Vector3::new(0.05, 0.0, 0.5),
            Vector3::new(0.0, 0.05, -0.5),
            Vector3::new(-0.05, 0.0, 0.5),
        ];
        assert!(free_direction(&spread).is_none());
    }
}
