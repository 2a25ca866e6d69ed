//! Swivel pulleys at the anchors (docs/pulleys.md) through the estimator.
//!
//! - **Static stiffness** against central finite differences of the static equilibrium
//!   with the pulley geometry: the cables' resultant Σ T_i(q) s_i(q) with s_i from each
//!   pulley's exit point and T_i(q) = T_i + EA_i/ℓ_i (ℓ_i(q) − ℓ_i) (ℓ_i: the path length
//!   from the anchor, wrap arc plus free length, whose gradient is s_i; the whole path
//!   stretches with the tension, so the axial spring is EA/ℓ: the free cable in series
//!   with the wrapped arc), h = 1e-6 m: truncation ~h²·EA/L³ and rounding ~ε·EA·ℓ/(L·h)
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
        let t = t0[i] + c.ea_n() / path(g0) * (path(&g) - path(g0));
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
        let k = e.stiffness.translational_n_m();
        let rel = (k - k_fd).norm() / k_fd.norm();
        assert!(rel <= 1e-6, "{p}: {rel:e}\n{k}\n{k_fd}");
        // The pulleys' own term.
        let mut pinned = Matrix3::zeros();
        for (i, (c, &ti)) in s.cables.iter().zip(t0).enumerate() {
            let u = g0.unit[i];
            let l = g0.free_length_m(i);
            let path = l + g0.wrap_arc_m(i);
            pinned += u * u.transpose() * (c.ea_n() / path)
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
        assert!(
            (e.stiffness.translational_n_m() - r.stiffness_n_m).norm()
                <= 1e-9 * r.stiffness_n_m.norm()
        );
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

/// The scene at `rel` (from the repository root) with `n` fem elements per cable.
fn scene_fem(rel: &str, n: usize) -> Scene {
    let path = format!("{}/{rel}", env!("CARGO_MANIFEST_DIR"));
    Scene::from_path(std::path::Path::new(&path))
        .unwrap()
        .with_model(cablevib::scene::ElementKind::Fem, n)
}

/// The structured engine's D(0) with pulleys equals the static stiffness (the cables'
/// static condensation plus the pulleys' own term): the point mass against the estimate's
/// stiffness (sum of the models plus the term, 1e-12 relative: the chains' static
/// stiffness by the recurrence at λ = 0 against k/N), the rigid body against the dense
/// reference's condensation of K with the term; both 1e-12 relative (rounding: 2e-16 and
/// 2e-15 measured). Without the term in D(λ) they differ by it (~7e-6 of ‖K‖ on both).
#[test]
fn d_of_zero_is_the_static_stiffness_with_pulleys() {
    use cablevib::estimator::{reference_analysis_at, PoseModel};
    use cablevib::modal::{ModalParams, ModalSolver};
    let tol = 1e-12;
    for rel in [
        "scenes/spatial_paper_pulleys.toml",
        "scenes/caroca_with_rotating_pulleys.toml",
    ] {
        let s = scene_fem(rel, 10);
        let pose = Pose {
            position_m: s.ee_position_m,
            orientation_wxyz: s.ee_orientation_wxyz,
        };
        let pm = PoseModel::at(&s, &pose, Tmin::Scene).unwrap();
        let dim = pm.dim();
        let mut solver = ModalSolver::new(ModalParams::default());
        pm.load(&mut solver);
        let d0 = solver.eval(0.0).d;
        let d0 = d0.view((0, 0), (dim, dim)).into_owned();
        let k_static = if dim == 3 {
            let mut est = Estimator::new(&s).unwrap();
            let e = *est.update(&pose, Tmin::Scene);
            assert!(e.is_ok(), "{rel}: {:?}", e.status);
            e.stiffness.k6.view((0, 0), (3, 3)).into_owned()
        } else {
            let r = reference_analysis_at(&s, &pose, Tmin::Scene, false).unwrap();
            r.stiffness6.view((0, 0), (6, 6)).into_owned()
        };
        let term = pm.end_effector.k_pulley.view((0, 0), (dim, dim)).norm();
        let rel_err = (&d0 - &k_static).norm() / k_static.norm();
        eprintln!(
            "{rel}: D(0) vs static {rel_err:.1e}; pulley term / ‖K‖ {:.1e}",
            term / k_static.norm()
        );
        assert!(term > 1e3 * tol * k_static.norm(), "{rel}: term {term}");
        assert!(rel_err <= tol, "{rel}: {rel_err:e}\n{d0}\n{k_static}");
    }
}

/// The structured modes with pulleys against an independent dense eigen-solve of the
/// assembled K, M (the chains pinned at the exit points, the wrapped arcs' axial elements)
/// with the pulleys' own term added at the end-effector's DOFs
/// ([`Geometry::pulley_stiffness`], checked against finite differences above): the paper
/// robot (point mass, first 64 modes: its end-effector modes lie among the strings' third
/// harmonics, ~32 Hz) and CAROCA (rigid, first 12: six platform modes), relative 4 × the
/// dense solver's accuracy + 1e-10. The test shows it can see the term: some dense mode
/// without it differs from the one with it by more than twice that tolerance (107 × on the
/// paper robot, 3 × on CAROCA, whose stiff short cables make the dense solve's own
/// accuracy ε·λ_max/λ coarser).
#[test]
fn modes_with_pulleys_equal_a_dense_solve_with_the_pulley_term() {
    use cablevib::estimator::PoseModel;
    use cablevib::modal::{assemble, assemble_rigid, dense_modes_ee, ModalParams, ModalSolver};
    for (rel, count) in [
        ("scenes/spatial_paper_pulleys.toml", 64),
        ("scenes/caroca_with_rotating_pulleys.toml", 12),
    ] {
        let s = scene_fem(rel, 10);
        let pose = Pose {
            position_m: s.ee_position_m + Vector3::new(0.05, -0.03, 0.02),
            orientation_wxyz: s.ee_orientation_wxyz,
        };
        let pm = PoseModel::at(&s, &pose, Tmin::Scene).unwrap();
        let ee = &pm.end_effector;
        let dim = pm.dim();
        let (mut k, m) = if ee.rigid {
            assemble_rigid(
                &pm.models,
                ee.mass_kg,
                &ee.inertia_kg_m2,
                &pm.geometry.arm_m,
                &ee.k_geo_rot,
            )
            .unwrap()
        } else {
            assemble(&pm.models, ee.mass_kg).unwrap()
        };
        let without = dense_modes_ee(&k, &m, &pm.ee_mass(), dim, false).unwrap();
        let term = pm.geometry.pulley_stiffness(&pm.tensions_n, dim);
        for r in 0..dim {
            for c in 0..dim {
                k[(r, c)] += term[(r, c)];
            }
        }
        let dense = dense_modes_ee(&k, &m, &pm.ee_mass(), dim, false).unwrap();
        let mut solver = ModalSolver::new(ModalParams::default());
        pm.load(&mut solver);
        let mut out = vec![cablevib::modal::Mode::default(); count];
        let n = solver.modes(count, &mut out).unwrap();
        assert_eq!(n, count);
        let mut worst: f64 = 0.0;
        let mut shift_over_tol: f64 = 0.0;
        for (j, md) in out.iter().enumerate() {
            let ld = dense.lambda[j];
            let tol = 4.0 * cablevib::modal::dense_relative_accuracy(ld, dense.lambda_max) + 1e-10;
            let e = (md.lambda - ld).abs() / ld;
            worst = worst.max(e / tol);
            shift_over_tol = shift_over_tol.max((without.lambda[j] - ld).abs() / ld / tol);
            assert!(
                e <= tol,
                "{rel} mode {}: {} vs {ld} ({e:.1e})",
                j + 1,
                md.lambda
            );
        }
        eprintln!(
            "{rel}: worst error / tolerance {worst:.2} over {count} modes; the term moves \
             a mode by {shift_over_tol:.0} × the tolerance"
        );
        assert!(shift_over_tol > 2.0, "{rel}: {shift_over_tol}");
    }
}

/// The model's DOF count is one number whatever the solver: the size of the assembled K
/// (the end-effector's 3, 3 per interior node, and one axial DOF per node of the cable
/// wrapped on each pulley: its elements' interior nodes and the junction). Before, the
/// structured solver reported 219 on the paper robot with pulleys at N = 10 (the free
/// cables only) and the dense one 299; with sag both said 219 while the sagged dense K has
/// 299 rows.
#[test]
fn every_solver_reports_the_assembled_models_dof() {
    use cablevib::study::analysis::{analyze, assembled_matrices, AnalyzeOptions, SolverChoice};
    for sag in [false, true] {
        let mut s = scene_fem("scenes/spatial_paper_pulleys.toml", 10);
        s.model.sag = sag;
        let want = 3 + 8 * 3 * 9 + 8 * 10;
        let (k, m) = assembled_matrices(&s).unwrap();
        assert_eq!((k.nrows(), m.nrows()), (want, want), "sag {sag}");
        for solver in [SolverChoice::Structured, SolverChoice::Dense] {
            let opts = AnalyzeOptions {
                modes: 3,
                solver,
                compare_dense: false,
            };
            let r = analyze(&s, &opts).unwrap();
            assert_eq!(r.dof, Some(want), "sag {sag}, {solver:?}");
        }
    }
}
