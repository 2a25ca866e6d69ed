//! A rigid end-effector's small motions: the attachment map of a cable's end and the
//! rotational geometric stiffness of the cable tensions (used by the estimator's forward
//! model and by the dense and the structured modal solvers).

use nalgebra::{Matrix3, Vector3};

/// G = [I, −\[r\]×] (3 × 6): displacement of an attachment point at arm r (m) for an
/// end-effector translation u and small rotation θ: δx = u + θ × r.
pub fn attach_map(r: &Vector3<f64>) -> nalgebra::Matrix3x6<f64> {
    let mut g = nalgebra::Matrix3x6::zeros();
    g.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&Matrix3::identity());
    g.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(-r.cross_matrix()));
    g
}

/// Rotational geometric stiffness of the tensions on a rigid end-effector (N·m/rad):
/// Σ_i T_i [−(s_i·r_i) I + sym(s_i r_iᵀ)], from the second-order motion of each arm r_i
/// under a rotation while its cable force −T_i s_i stays put.
pub fn rigid_geometric_stiffness(
    units: &[Vector3<f64>],
    arms_m: &[Vector3<f64>],
    tensions_n: &[f64],
) -> Matrix3<f64> {
    let mut k = Matrix3::zeros();
    for ((s, r), t) in units.iter().zip(arms_m).zip(tensions_n) {
        let sr = s * r.transpose();
        k += (Matrix3::identity() * (-s.dot(r)) + (sr + sr.transpose()) * 0.5) * *t;
    }
    k
}
