//! The hidden cable with sagging cables and in the mode shapes.
//!
//! References, built here (not from the crate's chains or its dense assemblies):
//! - sag: an independent dense FEM of the sagged robot: each free cable as N straight
//!   elements between nodes on its elastic catenary (chords `Catenary::chord_between_m`,
//!   axial force the catenary's tension at each element's middle: the statics' profile,
//!   no chain code), its anchor node the junction at the pulley moving along the
//!   catenary's tangent there, (H, V_a)/T_a, held by the hidden cable's N axial elements
//!   from the drum. Frequencies against the structured sagged solver to 1e-9 relative, or
//!   the dense solver's own accuracy 8ε·λ_max/λ when larger (stated per mode); the static
//!   stiffness against the dense static condensation to 1e-9;
//! - mode shapes: the dense FEM's mass-normalised eigenvectors (`dense_ref` of
//!   `hidden_cable`, fem and catenary elements) against the structured shapes, entry by
//!   entry, for every simple mode among the first 80.
use super::hidden_cable::{dense_ref, paper_with_hidden};
use cablevib::estimator::{Estimator, PoseModel, Tmin};
use cablevib::kinematics::Pose;
use cablevib::modal::{
    condense_static, dense_modes, dense_relative_accuracy, ModalParams, ModalSolver, Mode,
    ShapeParams,
};
use cablevib::scene::Scene;
use cablevib_testkit::dense_fem::{dense_eig, dense_with_hidden, FreeCable};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// The independent dense sagged FEM with hidden cables (module docs) of the estimator's
/// last pose: (K, M), DOF 0..3 the end-effector (a point mass at `p`).
fn dense_sagged(est: &Estimator, p: &Vector3<f64>, n: usize) -> (DMatrix<f64>, DMatrix<f64>) {
    let scene = est.scene();
    assert!(!scene.rigid);
    let cats = est.sag_catenaries().expect("sagged");
    let up = -scene.gravity_m_s2 / scene.gravity_m_s2.norm();
    dense_with_hidden(scene, n, |ci, c| {
        let cat = &cats[ci];
        let d = p - c.anchor_m;
        let h = (d - up * d.dot(&up)).normalize();
        let l0 = cat.l0_m / n as f64;
        let ta = cat.h_n.hypot(cat.v_anchor_n);
        let blocks = (0..n)
            .map(|el| {
                let (s0, s1) = (el as f64 * l0, (el + 1) as f64 * l0);
                let ch = cat.chord_between_m(s0, s1);
                let cw = h * ch[0] + up * ch[1];
                let len = cw.norm();
                let cu = cw / len;
                let cc = cu * cu.transpose();
                let axial = cat.tension_at_n(0.5 * (s0 + s1));
                cc * (cat.ea_n / l0) + (Matrix3::identity() - cc) * (axial / len)
            })
            .collect();
        FreeCable {
            blocks,
            element_mass_kg: c.mass_per_length_kg_m * l0,
            junction_dir: h * (cat.h_n / ta) + up * (cat.v_anchor_n / ta),
        }
    })
}

/// The paper robot sagging (fem × n) with 2.5 m of hidden cable behind every anchor.
fn sagged_with_hidden(n: usize) -> Scene {
    let mut s = paper_with_hidden("fem", n, 2.5);
    s.set_sag(true).unwrap();
    s
}

/// The sagged FEM with hidden cables against the independent dense sagged FEM: the first 12
/// modes, f1 and the static stiffness. N = 10 here; N = 40 in
/// [`slow::sagged_hidden_cable_frequencies_at_40_elements_equal_an_independent_dense_fem`].
#[test]
fn sagged_hidden_cable_frequencies_equal_an_independent_dense_fem() {
    sagged_hidden_cable_frequencies_equal_the_dense_fem(10);
}

/// The dense sagged FEMs at N = 40 (over 1000 DOF, a dense eigen-solve per pose), run by
/// `.ci/run` (tests/README.md, "Slow reference sweeps").
mod slow {
    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn sagged_hidden_cable_frequencies_at_40_elements_equal_an_independent_dense_fem() {
        super::sagged_hidden_cable_frequencies_equal_the_dense_fem(40);
    }

    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn sagged_continuous_hidden_cable_is_the_dense_fem_limit() {
        super::sagged_continuous_hidden_cable_is_the_dense_fem_limit();
    }
}

/// [`sagged_hidden_cable_frequencies_equal_an_independent_dense_fem`] with `n` elements per
/// free and per hidden cable.
fn sagged_hidden_cable_frequencies_equal_the_dense_fem(n: usize) {
    let scene = sagged_with_hidden(n);
    for p in [Vector3::new(0.0, 0.0, 1.0), Vector3::new(0.3, 0.2, 1.0)] {
        let mut est = Estimator::new(&scene).unwrap();
        let e = *est.update(&Pose::at(p), Tmin::Scene);
        assert!(e.is_ok(), "N {n} {p:?}: {:?}", e.error);
        let (k, m) = dense_sagged(&est, &p, n);
        let dense = dense_modes(&k, &m, scene.ee_mass_kg, false).unwrap();
        let mut solver = est.sag_modal().expect("sagged").clone();
        let count = 12;
        let mut modes = vec![Mode::default(); count];
        let got = solver.modes(count, &mut modes).unwrap();
        assert_eq!(got, count);
        let mut worst = 0.0f64;
        for (j, mode) in modes.iter().enumerate() {
            let ld = dense.lambda[j];
            let tol = 1e-9f64.max(8.0 * dense_relative_accuracy(ld, dense.lambda_max));
            let err = (mode.lambda - ld).abs() / ld;
            assert!(
                err <= tol,
                "N {n} {p:?} mode {j}: {} vs dense {ld}: {err:.2e} > {tol:.2e}",
                mode.lambda
            );
            worst = worst.max(err);
        }
        // f1 of the estimate is the first mode (dense, to the tolerance above).
        let l1 = (2.0 * std::f64::consts::PI * e.f1_hz).powi(2);
        let tol1 = 1e-9f64.max(8.0 * dense_relative_accuracy(dense.lambda[0], dense.lambda_max));
        assert!(
            (l1 - dense.lambda[0]).abs() <= tol1 * dense.lambda[0],
            "N {n} {p:?}: f1 λ {l1} vs dense {}",
            dense.lambda[0]
        );
        // The static stiffness: the dense static condensation.
        let kd = condense_static(&k, 3);
        let kd = Matrix3::from_fn(|r, c| kd[(r, c)]);
        let rel = (e.stiffness.translational_n_m() - kd).norm() / kd.norm();
        assert!(rel <= 1e-9, "N {n} {p:?}: stiffness {rel:.2e}");
        eprintln!(
            "sag N {n} at {p:?}: worst relative λ error over {count} modes {worst:.1e}, stiffness {rel:.1e}"
        );
    }
}

/// Sag, the continuous element and hidden cables: the sagged FEM's limit. The independent
/// dense sagged FEM (`dense_sagged`, N elements per free and per hidden cable) at N = 20
/// and 40 against the continuous model (Magnus chain from the junction, exact hidden bar):
/// the FEM's error falls as O(N⁻²) (the ratio of the two errors is 4 within 10 %), and the
/// Richardson extrapolation (4 λ₄₀ − λ₂₀)/3 removes it: what remains is the O(N⁻⁴) term
/// and the continuous mesh's error (offline rule, 1e-9), measured 4.2e-7 at most on the
/// first 6 modes (N = 40 alone: 5.1e-4), so TOL = 2e-6; the static stiffness likewise,
/// measured 1.1e-9 (N = 40 alone: 1.2e-5), so 1e-8. Two dense sagged FEMs per pose (N = 20
/// and 40): in the slow sweeps ([`slow::sagged_continuous_hidden_cable_is_the_dense_fem_limit`]).
fn sagged_continuous_hidden_cable_is_the_dense_fem_limit() {
    const TOL: f64 = 2e-6;
    let count = 6;
    for p in [Vector3::new(0.0, 0.0, 1.0), Vector3::new(0.3, 0.2, 1.0)] {
        let mut sc = paper_with_hidden("continuous", 1, 2.5);
        sc.set_sag(true).unwrap();
        let mut est = Estimator::new(&sc).unwrap();
        let e = *est.update(&Pose::at(p), Tmin::Scene);
        assert!(e.is_ok(), "{p:?}: {:?}", e.error);
        let mut solver = est.sag_modal().expect("sagged").clone();
        let mut modes = vec![Mode::default(); count];
        assert_eq!(solver.modes(count, &mut modes).unwrap(), count);
        let mut lam = Vec::new();
        let mut kst = Vec::new();
        for n in [20, 40] {
            let s = sagged_with_hidden(n);
            let mut est = Estimator::new(&s).unwrap();
            assert!(est.update(&Pose::at(p), Tmin::Scene).is_ok());
            let (k, m) = dense_sagged(&est, &p, n);
            let dense = dense_modes(&k, &m, s.ee_mass_kg, false).unwrap();
            lam.push(dense.lambda[..count].to_vec());
            let kd = condense_static(&k, 3);
            kst.push(Matrix3::from_fn(|r, c| kd[(r, c)]));
        }
        for (j, mode) in modes.iter().enumerate() {
            let (l20, l40, lc) = (lam[0][j], lam[1][j], mode.lambda);
            let ratio = (l20 - lc) / (l40 - lc);
            let rich = (4.0 * l40 - l20) / 3.0;
            let err = (rich - lc).abs() / lc;
            eprintln!(
                "{p:?} mode {j}: cont {lc:.9e} N20 {:.2e} N40 {:.2e} ratio {ratio:.3} richardson {err:.1e}",
                (l20 - lc) / lc,
                (l40 - lc) / lc
            );
            assert!((ratio - 4.0).abs() <= 0.4, "{p:?} mode {j}: ratio {ratio}");
            assert!(err <= TOL, "{p:?} mode {j}: {err:.2e}");
        }
        let rich = (kst[1] * 4.0 - kst[0]) / 3.0;
        let rel = (e.stiffness.translational_n_m() - rich).norm() / rich.norm();
        let rel40 = (e.stiffness.translational_n_m() - kst[1]).norm() / rich.norm();
        eprintln!("{p:?} stiffness: N40 {rel40:.1e} richardson {rel:.1e}");
        assert!(rel <= 1e-8, "{p:?}: stiffness {rel:.2e}");
    }
}

/// With sag, the hidden cable lowers the static stiffness and f1 moves as the taut model's:
/// the same robot with hidden cables of a thousandth of a millimetre is the robot without
/// (within 1e-6), and 2.5 m lowers k_min.
#[test]
fn sagged_hidden_cable_tends_to_none() {
    let p = Pose::at(Vector3::new(0.3, 0.2, 1.0));
    let run = |lh: f64| {
        let mut s = paper_with_hidden("fem", 10, lh);
        s.set_sag(true).unwrap();
        let mut est = Estimator::new(&s).unwrap();
        let e = *est.update(&p, Tmin::Scene);
        assert!(e.is_ok(), "{lh}: {:?}", e.error);
        (
            e.stiffness
                .translational_n_m()
                .symmetric_eigenvalues()
                .min(),
            e.f1_hz,
        )
    };
    let (k0, f0) = run(0.0);
    let (ks, fs) = run(1e-6);
    let (kl, _) = run(2.5);
    assert!((ks - k0).abs() <= 1e-6 * k0 && (fs - f0).abs() <= 1e-6 * f0);
    assert!(kl < 0.9 * k0, "{kl} vs {k0}");
}

/// The lowest `count` eigenpairs of K u = λ M u, u mass-normalised (dense, independent).
fn dense_pairs(k: &DMatrix<f64>, m: &DMatrix<f64>, count: usize) -> Vec<(f64, DVector<f64>)> {
    let (lambda, u) = dense_eig(k, m);
    (0..count)
        .map(|i| (lambda[i], u.column(i).into_owned()))
        .collect()
}

/// Structured shapes of a model with hidden cables against the dense eigenvectors: the
/// end-effector, every free cable node and the junction (its displacement along the
/// junction's direction), to 1e-7 of the shape's largest entry (λ to ~1e-12 and
/// separations ≥ 1e-4 relative give ~1e-8), for every simple mode among the first 80.
#[test]
fn hidden_cable_mode_shapes_equal_the_dense_eigenvectors() {
    let n = 10;
    for element in ["fem", "catenary"] {
        let scene = paper_with_hidden(element, n, 2.5);
        let p = Vector3::new(0.3, 0.2, 1.0);
        let pm = PoseModel::at(&scene, &Pose::at(p), Tmin::Scene).unwrap();
        let (k, m) = dense_ref(&scene, &p, &pm.tensions_n, n, element == "catenary");
        // The transverse chains come in pairs (double modes): the simple ones are further up.
        let count = 80;
        let dense = dense_pairs(&k, &m, count + 1);
        let mut solver = ModalSolver::new(ModalParams::default());
        pm.load(&mut solver);
        let mut modes = vec![Mode::default(); count];
        assert_eq!(solver.modes(count, &mut modes).unwrap(), count);
        let mut checked = 0;
        for (j, mode) in modes.iter().enumerate() {
            let sep = |i: usize| (dense[i].0 - dense[j].0).abs() > 1e-4 * dense[j].0;
            if mode.multiplicity != 1 || (j > 0 && !sep(j - 1)) || !sep(j + 1) {
                continue;
            }
            let shapes = solver
                .mode_shapes(
                    &pm.models,
                    &[],
                    &[(mode.lambda, 1)],
                    &ShapeParams::default(),
                )
                .unwrap();
            let sh = &shapes.modes[0];
            // The structured shape as the dense DOF vector (hidden interior nodes skipped).
            let u = &dense[j].1;
            let mut pairs: Vec<(f64, f64)> = (0..3).map(|r| (sh.ee[r], u[r])).collect();
            let mut base = 3;
            for (ci, c) in scene.cables.iter().enumerate() {
                let nodes = &sh.cables[ci];
                for jn in 1..n {
                    for r in 0..3 {
                        pairs.push((nodes[jn][r], u[base + 3 * (jn - 1) + r]));
                    }
                }
                if c.hidden.is_some() {
                    let dir = pm.models[ci].hidden.unwrap().direction;
                    let junction = base + 3 * (n - 1) + n - 1;
                    pairs.push((nodes[0].dot(&dir), u[junction]));
                    // Node 0 moves along the junction's direction only.
                    assert!((nodes[0] - dir * nodes[0].dot(&dir)).norm() <= 1e-12);
                }
                base += 3 * (n - 1) + c.hidden.map_or(0, |_| n);
            }
            let dot: f64 = pairs.iter().map(|(a, b)| a * b).sum();
            let sign = dot.signum();
            let scale = pairs.iter().fold(0.0f64, |a, (_, b)| a.max(b.abs()));
            let worst = pairs
                .iter()
                .fold(0.0f64, |a, (x, y)| a.max((x - sign * y).abs()))
                / scale;
            assert!(worst <= 1e-7, "{element} mode {j}: shape error {worst:.2e}");
            checked += 1;
        }
        assert!(
            checked >= 3,
            "{element}: only {checked} simple modes checked"
        );
    }
}
