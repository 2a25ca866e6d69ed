//! The element stiffness blocks: the straight FEM element and the catenary element in its
//! cancellation-free flexibility form (docs/model.md).

use super::CableError;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// Below this ratio h² / (a² + b²) (horizontal over vertical end-force components squared)
/// a vertical element whose ends pull in opposite vertical senses is treated as slack: the
/// low point would need a horizontal force that is not there.
const SLACK_HORIZONTAL_REL: f64 = 1e-24;
/// Below this |y| = γ·x, asinh(y)/y is taken from its series (1 − y²/6 + 3y⁴/40), exact to
/// rounding there, instead of the library asinh whose quotient loses digits.
const ASINH_SERIES_MAX: f64 = 1e-4;

/// FEM element stiffness block K_c = EA/l e eᵀ + T/l (I − e eᵀ), N/m.
/// `geometric` = false drops the T/l term (axial springs only, the paper's ref. \[7\]).
pub fn fem_block(
    e: &Vector3<f64>,
    length_m: f64,
    ea_n: f64,
    tension_n: f64,
    geometric: bool,
) -> Matrix3<f64> {
    let eet = e * e.transpose();
    let kt = if geometric { tension_n / length_m } else { 0.0 };
    eet * (ea_n / length_m) + (Matrix3::identity() - eet) * kt
}

/// Flexibility matrix F (m/N) of the catenary element in its local frame (z up), in the
/// cancellation-free form of docs/model.md. `f` = (F1, F2, F3) is the force on the
/// element at node I, `l0_m` the unstressed length, `ea_n` = EA, `gamma_n_m` the weight per
/// length γ ≥ 0. Exact for γ = 0 and for vertical elements.
pub fn catenary_flexibility(
    f: &Vector3<f64>,
    l0_m: f64,
    ea_n: f64,
    gamma_n_m: f64,
) -> Result<Matrix3<f64>, CableError> {
    let (f1, f2, f3) = (f.x, f.y, f.z);
    let a = f3;
    let b = f3 - gamma_n_m * l0_m;
    let h2 = f1 * f1 + f2 * f2;
    let ti = (h2 + a * a).sqrt();
    let tj = (h2 + b * b).sqrt();
    let s = ti + tj;
    let q = if a * b >= 0.0 {
        1.0 + (h2 + a * a + b * b) / (ti * tj + a * b)
    } else {
        if h2 <= 0.0 || !(h2 > SLACK_HORIZONTAL_REL * (a * a + b * b)) {
            return Err(CableError::TooSlack {
                tension_n: ti,
                weight_n: gamma_n_m * l0_m,
            });
        }
        (h2 + ti * tj - a * b) / h2
    };
    let den = s * ti * tj;
    let b1 = l0_m * q / den;
    let b2 = l0_m * (a + b) / den;
    let x = l0_m * q / s;
    let y = gamma_n_m * x;
    let lam = if y.abs() < ASINH_SERIES_MAX {
        let y2 = y * y;
        x * (1.0 - y2 / 6.0 + 3.0 * y2 * y2 / 40.0)
    } else {
        x * (y.asinh() / y)
    };
    let c = l0_m / ea_n;
    let f11 = -c - lam + f1 * f1 * b1;
    let f22 = -c - lam + f2 * f2 * b1;
    let f12 = f1 * f2 * b1;
    let f13 = f1 * b2;
    let f23 = f2 * b2;
    let f33 = -c - h2 * b1;
    let m = Matrix3::new(f11, f12, f13, f12, f22, f23, f13, f23, f33);
    if !m.iter().all(|v| v.is_finite()) {
        return Err(CableError::NotDefinite);
    }
    Ok(m)
}

/// Catenary element stiffness in modal form: K_c = Σ_r k_r v_r v_rᵀ (N/m, global frame) for
/// an element with chord `chord_m` from node I to node J, tension `t0_n`, EA and weight per
/// length γ, in the frame `frame` from [`up_frame`](crate::kinematics::up_frame). The decomposition is done on
/// G = F + (L0/EA) I in the local frame (F = G − (L0/EA) I shares its eigenvectors), so
/// k_r = 1/(L0/EA − g_r): the transverse stiffnesses (≈ T/L0) come out with relative
/// accuracy ε instead of the ε·EA/T of decomposing K itself.
pub fn catenary_modes(
    chord_m: &Vector3<f64>,
    t0_n: f64,
    ea_n: f64,
    gamma_n_m: f64,
    frame: &Matrix3<f64>,
) -> Result<([f64; 3], [Vector3<f64>; 3]), CableError> {
    if !(t0_n.is_finite() && t0_n > 0.0) {
        return Err(CableError::BadTension(t0_n));
    }
    let l0 = chord_m.norm();
    let local = frame.transpose() * chord_m;
    let f = -local * (t0_n / l0);
    let flex = catenary_flexibility(&f, l0, ea_n, gamma_n_m)?;
    let c = l0 / ea_n;
    let g = flex + Matrix3::identity() * c;
    let eig = SymmetricEigen::new(g);
    let mut k = [0.0; 3];
    let mut v = [Vector3::zeros(); 3];
    for r in 0..3 {
        let d = c - eig.eigenvalues[r];
        if !(d > 0.0 && d.is_finite()) {
            return Err(CableError::NotDefinite);
        }
        k[r] = 1.0 / d;
        v[r] = frame * eig.eigenvectors.column(r);
    }
    Ok((k, v))
}

/// Catenary element stiffness block (N/m, global frame, positive definite): Σ k_r v_r v_rᵀ
/// of [`catenary_modes`].
pub fn catenary_block(
    chord_m: &Vector3<f64>,
    t0_n: f64,
    ea_n: f64,
    gamma_n_m: f64,
    frame: &Matrix3<f64>,
) -> Result<Matrix3<f64>, CableError> {
    let (k, v) = catenary_modes(chord_m, t0_n, ea_n, gamma_n_m, frame)?;
    Ok((0..3).fold(Matrix3::zeros(), |acc, r| {
        acc + v[r] * v[r].transpose() * k[r]
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::up_frame;

    #[test]
    fn catenary_tends_to_straight_cable() {
        // γ → 0: K = EA/L0 e eᵀ + T/(L0 (1 + T/EA)) (I − e eᵀ) (docs/model.md).
        let frame = up_frame(&Vector3::new(0.0, 0.0, -9.81));
        let e = Vector3::new(0.3, -0.5, 0.8).normalize();
        let (l0, t, ea) = (0.25, 120.0, 1.0e6);
        let exact = {
            let eet = e * e.transpose();
            eet * (ea / l0) + (Matrix3::identity() - eet) * (t / (l0 * (1.0 + t / ea)))
        };
        for gamma in [0.0, 1e-15, 1e-12, 1e-9] {
            let k = catenary_block(&(e * l0), t, ea, gamma, &frame).unwrap();
            let err = (k - exact).norm() / exact.norm();
            assert!(err < 1e-12 + gamma * 1e2, "gamma {gamma}: {err}");
        }
    }

    #[test]
    fn vertical_catenary_is_finite_both_ways() {
        let frame = up_frame(&Vector3::new(0.0, 0.0, -9.81));
        for dir in [1.0, -1.0] {
            let e = Vector3::new(0.0, 0.0, dir);
            let k = catenary_block(&(e * 0.5), 100.0, 1e6, 0.25, &frame).unwrap();
            assert!(k.iter().all(|v| v.is_finite()));
            assert!(k.cholesky().is_some());
            // No coupling between horizontal and vertical directions.
            assert!(k[(0, 2)].abs() < 1e-9 * k.norm() && k[(1, 2)].abs() < 1e-9 * k.norm());
        }
    }
}
