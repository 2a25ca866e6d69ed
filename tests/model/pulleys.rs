//! Swivel pulleys at the anchors (docs/pulleys.md) through the estimator.
//!
//! - **Static stiffness** against central finite differences of the static equilibrium
//!   with the pulley geometry: the cables' resultant Σ T_i(q) s_i(q) with s_i from each
//!   pulley's exit point and T_i(q) = T_i + EA_i/L_i (ℓ_i(q) − ℓ_i) (ℓ_i: the path length
//!   from the anchor, wrap arc plus free length, whose gradient is s_i; the axial spring is
//!   the free cable's, EA/L), h = 1e-6 m: truncation ~h²·EA/L³ and rounding ~ε·EA·ℓ/(L·h)
//!   are both below 1e-9 of ‖K‖, so 1e-6 relative. The pulleys' own term (the exit point
//!   moves with the pose) is checked on its own too: K_fd minus the stiffness of cables
//!   pinned at their exit points, 1e-3 relative to that term (it is ~1e-5 of ‖K‖).
//! - **Dense reference**: the structured f1 with pulleys equals the dense solver's on the
//!   same model (chains pinned at the exit points), within the dense solver's accuracy.
use cablevib::estimator::{reference_analysis, Estimator, Tmin};
use cablevib::kinematics::{Geometry, Pose};
use cablevib::modal::{dense_relative_accuracy, lambda_to_hz};
use cablevib::scene::Scene;
use nalgebra::{Matrix3, Vector3};

fn paper_with_pulleys() -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/spatial_paper_pulleys.toml"
    );
    Scene::from_path(std::path::Path::new(path)).unwrap()
}

/// Σ T_i(q) s_i(q) at position `p` (see the module docs), N.
fn resultant(s: &Scene, g0: &Geometry, t0: &[f64], p: &Vector3<f64>) -> Vector3<f64> {
    let mut g = Geometry::for_scene(s);
    g.update(s.cables.iter().map(|c| &c.anchor_m), p).unwrap();
    let mut f = Vector3::zeros();
    for (i, c) in s.cables.iter().enumerate() {
        let path = |g: &Geometry| g.wrap_arc_m(i) + g.free_length_m(i);
        let t = t0[i] + c.ea_n() / g0.free_length_m(i) * (path(&g) - path(g0));
        f += g.unit[i] * t;
    }
    f
}

#[test]
fn static_stiffness_equals_finite_differences_of_the_equilibrium_with_pulleys() {
    let s = paper_with_pulleys();
    let mut est = Estimator::new(&s).unwrap();
    for p in [
        Vector3::new(0.0, 0.0, 1.25),
        Vector3::new(0.3, 0.2, 1.0),
        Vector3::new(-0.5, 0.4, 1.6),
    ] {
        let e = *est.update(&Pose::at(p), Tmin::Scene);
        assert!(e.is_ok(), "{p}: {:?}", e.status);
        let t0 = &e.tensions_n[..s.n_cables()];
        let mut g0 = Geometry::for_scene(&s);
        g0.update(s.cables.iter().map(|c| &c.anchor_m), &p).unwrap();
        let h = 1e-6;
        let mut k_fd = Matrix3::zeros();
        for j in 0..3 {
            let d = Vector3::ith(j, h);
            let col =
                (resultant(&s, &g0, t0, &(p + d)) - resultant(&s, &g0, t0, &(p - d))) / (2.0 * h);
            k_fd.set_column(j, &col);
        }
        let k = e.stiffness_n_m;
        let rel = (k - k_fd).norm() / k_fd.norm();
        assert!(rel <= 1e-6, "{p}: {rel:e}\n{k}\n{k_fd}");
        // The pulleys' own term.
        let mut pinned = Matrix3::zeros();
        for (i, (c, &ti)) in s.cables.iter().zip(t0).enumerate() {
            let u = g0.unit[i];
            let l = g0.free_length_m(i);
            pinned += u * u.transpose() * (c.ea_n() / l)
                + (Matrix3::identity() - u * u.transpose()) * (ti / l);
        }
        let own = g0
            .pulley_stiffness(t0, 3)
            .fixed_view::<3, 3>(0, 0)
            .into_owned();
        let rel_own = ((k_fd - pinned) - own).norm() / own.norm();
        assert!(own.norm() > 0.1, "{own}");
        assert!(
            rel_own <= 1e-3,
            "{p}: pulley term {rel_own:e}\n{own}\n{}",
            k_fd - pinned
        );
    }
}

#[test]
fn structured_f1_with_pulleys_equals_the_dense_reference() {
    let s = paper_with_pulleys();
    let mut est = Estimator::new(&s).unwrap();
    for p in [Vector3::new(0.0, 0.0, 1.25), Vector3::new(0.3, 0.2, 1.0)] {
        let e = *est.update(&Pose::at(p), Tmin::Scene);
        assert!(e.is_ok());
        let r = reference_analysis(&s, &p, Tmin::Scene, false).unwrap();
        let lam = &r.modes.lambda;
        let f_dense = lambda_to_hz(lam[0]);
        let tol = 4.0 * dense_relative_accuracy(lam[0], r.modes.lambda_max) + 1e-10;
        assert!(
            (e.f1_hz - f_dense).abs() <= tol * f_dense,
            "{p}: {} vs {f_dense}",
            e.f1_hz
        );
        assert!((e.stiffness_n_m - r.stiffness_n_m).norm() <= 1e-9 * r.stiffness_n_m.norm());
    }
}

/// The rigid platform's pulley term Σ T_i (sin φ/a − 1/L) G_iᵀ n nᵀ G_i (6 × 6) against
/// central differences, on CAROCA with its pulleys: with fixed tensions T_i and the fixed
/// map G_i = [I, −[r_i]×] of the pose, f(q) = Σ T_i G_iᵀ s_i(p + R(θ) R₀ b_i) has the
/// derivative Σ T_i G_iᵀ (∂s_i/∂B) G_i; minus the part of cables pinned at their exit points,
/// (I − s sᵀ)/L, what is left is the pulleys' term. h = 1e-6 (m, rad): 1e-5 relative to
/// that term (rounding ~ε·T/h against a term of ~T·R/(a L) ≈ 1e-2·T).
#[test]
fn the_rigid_pulley_term_equals_finite_differences() {
    use cablevib::kinematics::rotation_of;
    use nalgebra::{Matrix6, Rotation3, Vector6};
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/caroca_with_rotating_pulleys.toml"
    );
    let s = Scene::from_path(std::path::Path::new(path)).unwrap();
    assert!(s.rigid);
    let t: Vec<f64> = (0..s.n_cables()).map(|i| 100.0 + 15.0 * i as f64).collect();
    let p0 = s.ee_position_m + Vector3::new(0.1, -0.05, 0.2);
    let r0 = rotation_of(&[0.98, 0.1, -0.05, 0.15]);
    let geometry = |p: &Vector3<f64>, rot: &Matrix3<f64>| {
        let mut g = Geometry::for_scene(&s);
        g.update_rigid(
            s.cables.iter().map(|c| &c.anchor_m),
            s.cables.iter().map(|c| &c.attachment_m),
            p,
            rot,
        )
        .unwrap();
        g
    };
    let g0 = geometry(&p0, &r0);
    let gmap = |i: usize, s_vec: &Vector3<f64>| {
        let rs = g0.arm_m[i].cross(s_vec);
        Vector6::new(s_vec.x, s_vec.y, s_vec.z, rs.x, rs.y, rs.z)
    };
    let f = |q: &Vector6<f64>| {
        let th = Vector3::new(q[3], q[4], q[5]);
        let rot = Rotation3::new(th).into_inner() * r0;
        let g = geometry(&(p0 + Vector3::new(q[0], q[1], q[2])), &rot);
        (0..s.n_cables()).fold(Vector6::zeros(), |acc, i| acc + gmap(i, &g.unit[i]) * t[i])
    };
    let h = 1e-6;
    let mut fd = Matrix6::zeros();
    for j in 0..6 {
        let d = Vector6::ith(j, h);
        fd.set_column(j, &((f(&d) - f(&-d)) / (2.0 * h)));
    }
    let mut pinned = Matrix6::zeros();
    for (i, &ti) in t.iter().enumerate() {
        let u = g0.unit[i];
        let k3 = (Matrix3::identity() - u * u.transpose()) * (ti / g0.free_length_m(i));
        let mut gi = nalgebra::Matrix3x6::zeros();
        gi.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::identity());
        gi.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(-g0.arm_m[i].cross_matrix()));
        pinned += gi.transpose() * k3 * gi;
    }
    let own = g0.pulley_stiffness(&t, 6);
    let rel = ((fd - pinned) - own).norm() / own.norm();
    assert!(own.norm() > 1.0, "{own}");
    assert!(rel <= 1e-5, "{rel:e}\n{own}\n{}", fd - pinned);
}
