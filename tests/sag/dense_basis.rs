//! A sagging robot's time-response basis by one dense solve (`Estimator::ee_modal_basis`
//! where K is a large share of the DOF: `estimator::dense_sag_basis`) against the
//! structured engine's basis at the same pose (an independent formulation: the count, a
//! root search per cluster, each shape from the chains' forward recurrence and the
//! bordered system's null space; none of the assembly or the dense eigen-solve).
//! suspended-8 with sag, fem × 10 (219 DOF), at its centre and off-centre poses: the first
//! K_s modes the structured basis holds (a basis small enough that the dense solve does not
//! pay, so it is the structured engine's) against the first K_s of the dense 147-mode
//! basis (the K `simulate` chooses on its S-curve); and on a rigid platform. Measured
//! (K_s = 40): λ within 5.3e-10, the sums within 1.6e-9, M-orthonormal within 7.3e-15, the
//! span within 4.4e-15 (suspended-8); the platform 6.2e-10, 2.4e-9, 5.7e-15, 3.1e-15.

use cablevib::estimator::{dense_sag_pays, EeModalBasis, Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::scene::{ElementKind, Scene};
use nalgebra::{Matrix6, Vector3};

/// Σ_j a_j b_jᵀ / λ_j over the first `k` modes: what the modes put into the response,
/// whatever basis a cluster is given in (and whatever sign a shape has).
fn modal_sum(
    b: &EeModalBasis,
    a: impl Fn(&EeModalBasis, usize) -> nalgebra::Vector6<f64>,
    c: impl Fn(&EeModalBasis, usize) -> nalgebra::Vector6<f64>,
    k: usize,
) -> Matrix6<f64> {
    (0..k)
        .map(|j| a(b, j) * c(b, j).transpose() / b.lambda[j])
        .sum()
}

/// Relative difference of two matrices in the Frobenius norm.
fn rel(a: &Matrix6<f64>, b: &Matrix6<f64>) -> f64 {
    (a - b).norm() / b.norm()
}

/// `scene` with sag, fem × 10.
fn sagged(file: &str) -> Scene {
    let mut scene = Scene::load(file).unwrap();
    scene.model.sag = true;
    scene.model.element = ElementKind::Fem;
    scene.model.elements_per_cable = 10;
    scene
}

/// At `pose` of `scene` (`dof` DOF): the structured 40-mode basis against the first of the
/// dense `big`-mode one (module docs).
fn check_pose(scene: &Scene, pose: Pose, dof: usize, big: usize) {
    let p = pose.position_m;
    let mut est = Estimator::new(scene).unwrap();
    let e = *est.update(&pose, Tmin::Scene);
    assert!(e.is_ok(), "{p:?}: {:?}", e.error);
    let n = est.dense_matrices().unwrap().0.nrows();
    assert_eq!(n, dof);
    // The structured engine below the break-even, the dense solve above it.
    let s = est.ee_modal_basis(40).unwrap();
    assert!(!dense_sag_pays(n, 40) && s.structured);
    let d = est.ee_modal_basis(big).unwrap();
    assert!(dense_sag_pays(n, big) && !d.structured);
    let ks = s.lambda.len();
    assert!((40..48).contains(&ks), "{ks}");
    assert_eq!(d.lambda.len(), big, "{big} ends a separated cluster");
    // Eigenvalues: the dense solve's absolute error is ~ε λ_max (λ_max/λ_1 ≈ 1e7 here):
    // 1e-8 relative on the lowest.
    let mut worst_lambda = 0.0f64;
    for j in 0..ks {
        let r = (d.lambda[j] - s.lambda[j]).abs() / s.lambda[j];
        assert!(
            r <= 1e-8,
            "{p:?} mode {j}: λ {} vs {}: {r:.2e}",
            d.lambda[j],
            s.lambda[j]
        );
        worst_lambda = worst_lambda.max(r);
    }
    // The end-effector's modal flexibility, the whole robot's load (load shapes) and the
    // convective load of the first K_s modes: the same sums (the shapes' accuracy is
    // ~ε λ_max over the gap to the next mode, here ≥ 2.4e-5 of λ: 1e-6 asserted).
    let phi = |b: &EeModalBasis, j: usize| b.phi_ee[j];
    let psi = |b: &EeModalBasis, j: usize| b.load_ee[j];
    // (No convective load where the path's field does not apply: zeros.)
    let chi = |b: &EeModalBasis, j: usize| {
        b.convective_load
            .get(j)
            .copied()
            .unwrap_or_else(nalgebra::Vector6::zeros)
    };
    let sums = [
        (
            "flexibility",
            modal_sum(&d, phi, phi, ks),
            modal_sum(&s, phi, phi, ks),
        ),
        (
            "load",
            modal_sum(&d, phi, psi, ks),
            modal_sum(&s, phi, psi, ks),
        ),
        (
            "convective",
            modal_sum(&d, phi, chi, ks),
            modal_sum(&s, phi, chi, ks),
        ),
    ];
    let mut worst_sum = 0.0f64;
    for (what, dense, structured) in &sums {
        let r = rel(dense, structured);
        assert!(r <= 1e-6, "{p:?} {what}: {r:.2e}");
        worst_sum = worst_sum.max(r);
    }
    // The quasi-static parts are the pose's, not the modes': identical fields.
    assert!(rel(&d.load_flexibility, &s.load_flexibility) <= 1e-12);
    assert!(rel(&d.quasi_static_mass_kg, &s.quasi_static_mass_kg) <= 1e-12);
    // The whole shapes: M-orthonormal on the structured shapes' nodes (their mass form is
    // the element form, not the assembled M the dense solve normalised with), and each
    // structured shape lies in the span of the dense ones (its mass overlap's column norm 1).
    let ds = d.shapes.as_ref().unwrap();
    let ss = s.shapes.as_ref().unwrap();
    let own = ds.mass_overlap(ds, &d.ee_mass).unwrap();
    let q = ds.modes.len();
    let off = (0..q * q)
        .map(|i| (own[i] - if i % (q + 1) == 0 { 1.0 } else { 0.0 }).abs())
        .fold(0.0f64, f64::max);
    assert!(
        off <= 1e-9,
        "{p:?}: dense shapes' mass overlap off the identity by {off:.2e}"
    );
    let cross = ds.mass_overlap(ss, &d.ee_mass).unwrap();
    let mut worst_span = 0.0f64;
    for j in 0..ks {
        let norm2: f64 = (0..q).map(|i| cross[i * ks + j].powi(2)).sum();
        assert!(
            (norm2 - 1.0).abs() <= 1e-8,
            "{p:?}: structured shape {j} in the dense span by {norm2}"
        );
        worst_span = worst_span.max((norm2 - 1.0).abs());
    }
    eprintln!(
        "{p:?}: K_s = {ks}: λ {worst_lambda:.1e}, sums {worst_sum:.1e}, \
         M-orthonormal {off:.1e}, span {worst_span:.1e}"
    );
}

#[test]
fn dense_sagged_basis_matches_the_structured_one() {
    let scene = sagged("scenes/suspended_8.toml");
    for p in [Vector3::new(0.0, 0.0, 2.0), Vector3::new(4.0, 2.5, 1.5)] {
        check_pose(&scene, Pose::at(p), 219, 147);
    }
}

/// The same on a rigid platform (box_6dof with sag, fem × 10, 222 DOF: the end node of each
/// cable is the platform's attachment G_i φ, its rotation included; K = 126, what
/// `simulate` chooses for a 5 cm S-curve there).
#[test]
fn dense_sagged_basis_matches_the_structured_one_on_a_rigid_platform() {
    let scene = sagged("scenes/box_6dof.toml");
    check_pose(
        &scene,
        Pose::in_scene(&scene, scene.ee_position_m),
        222,
        126,
    );
}
