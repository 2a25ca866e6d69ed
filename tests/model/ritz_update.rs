//! The cheap basis update of a time response along a path (`Estimator::ee_modal_basis_ritz`:
//! subspace iteration from a nearby pose's shapes, Rayleigh–Ritz on the new pose's K and M,
//! a residual bound on every kept mode) against an independent reference: the test's own
//! dense FEM of the paper robot at the new pose (`hidden_cable::dense_ref`, from the
//! scene's numbers, none of the crate's chains or assembly) and its dense generalized
//! eigen-solve (`cablevib_testkit::dense_fem::dense_eig`).

use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::modal::ritz::RitzSchedule;
use cablevib::scene::{ElementKind, Scene};
use cablevib_testkit::dense_fem::dense_eig;
use nalgebra::{Matrix3, Vector3};

use crate::hidden_cable::dense_ref;

/// K of the paper robot's circle at the default tolerance, and the guard modes `simulate`
/// keeps above it (`study::simulate::updates::ritz_guard`).
const K: usize = 39;
const GUARD: usize = 13;
/// The residual bound `simulate` asks at its default tolerance (1e-2 × 1e-3).
const MAX_RESIDUAL: f64 = 1e-5;

/// The end-effector's translation flexibility of the first `k` modes, Σ φ_ee φ_eeᵀ/λ (m/N):
/// what the modes put into the response, the same whatever basis a cluster is given in.
fn modal_flexibility(lambda: &[f64], ee: impl Fn(usize) -> Vector3<f64>, k: usize) -> Matrix3<f64> {
    (0..k).map(|j| ee(j) * ee(j).transpose() / lambda[j]).sum()
}

/// From the basis at `p0` (K + guard structured shapes) to `p1`: the update, when it is
/// made, has every kept λ within ρλ of the dense model's (Weinstein's bound in M⁻¹'s norm,
/// ρ the largest relative residual it reports) and the kept modes' end-effector
/// flexibility within 1e-4 of the dense model's (ρ/g with the gap g ≥ 0.1 in λ above the
/// cut: 1e-4; the FEM models agree to rounding). Returns whether it was made.
fn update_agrees(p0: Vector3<f64>, p1: Vector3<f64>) -> bool {
    let s = Scene::default_scene().with_model(ElementKind::Fem, 10);
    let mut est = Estimator::new(&s).unwrap();
    assert!(est.update(&Pose::at(p0), Tmin::Scene).is_ok());
    let start = est
        .ee_modal_basis(K + GUARD)
        .unwrap()
        .shapes
        .expect("structured shapes");
    assert!(start.modes.len() > K);
    update_from(&mut est, &s, &start, p0, p1, &mut RitzSchedule::default()).is_some()
}

/// The update from the shapes `start` (at `p0`) to `p1` with `schedule`, held against the
/// dense model at `p1` (as [`update_agrees`] says); its whole shapes (the next start block)
/// when it is made.
fn update_from(
    est: &mut Estimator,
    s: &Scene,
    start: &cablevib::modal::ModeShapes,
    p0: Vector3<f64>,
    p1: Vector3<f64>,
    schedule: &mut RitzSchedule,
) -> Option<cablevib::modal::ModeShapes> {
    let e = *est.update(&Pose::at(p1), Tmin::Scene);
    assert!(e.is_ok(), "{p1:?}: {:?}", e.error);
    let r = est
        .ee_modal_basis_ritz(start, K, MAX_RESIDUAL, schedule)
        .unwrap()?;
    assert!(r.residual <= MAX_RESIDUAL, "{}", r.residual);
    let b = &r.basis;
    let kept = b.lambda.len();
    assert!((K..K + 8).contains(&kept), "{kept}");
    let (k, m) = dense_ref(s, &p1, e.tensions(), 10, false);
    let (lam, u) = dense_eig(&k, &m);
    for (j, (ours, dense)) in b.lambda.iter().zip(&lam).enumerate() {
        let rel = (ours - dense).abs() / dense;
        let rho = r.residual;
        assert!(
            rel <= rho,
            "mode {j}: λ {ours} vs dense {dense}: {rel:.2e} over ρ = {rho:.2e}"
        );
    }
    let ours = modal_flexibility(
        &b.lambda,
        |j| b.phi_ee[j].fixed_rows::<3>(0).into_owned(),
        kept,
    );
    let dense = modal_flexibility(
        &lam,
        |j| Vector3::new(u[(0, j)], u[(1, j)], u[(2, j)]),
        kept,
    );
    let rel = (ours - dense).norm() / dense.norm();
    assert!(
        rel <= 1e-4,
        "{p0:?} → {p1:?}: end-effector flexibility {rel:.2e}"
    );
    // The shapes are M-orthonormal on the cables too: their mass overlap is the identity.
    let shapes = b.shapes.as_ref().unwrap();
    let o = shapes.mass_overlap(shapes, &b.ee_mass).unwrap();
    let worst = (0..kept * kept)
        .map(|i| (o[i] - if i % (kept + 1) == 0 { 1.0 } else { 0.0 }).abs())
        .fold(0.0f64, f64::max);
    assert!(
        worst <= 1e-9,
        "mass overlap off the identity by {worst:.2e}"
    );
    Some(r.space)
}

/// A step of the size the circle's updates take (≈ 1 cm) is made and agrees with the dense
/// model at the new pose; a jump of 0.3 m across the workspace is either refused (the
/// residual not met: the structured shapes then) or agrees too — never a wrong basis.
#[test]
fn ritz_update_agrees_with_the_dense_modes_at_the_new_pose() {
    let p0 = Vector3::new(0.3, 0.2, 1.0);
    assert!(
        update_agrees(p0, p0 + Vector3::new(0.008, -0.006, 0.004)),
        "a 1 cm step must be updated"
    );
    update_agrees(p0, Vector3::new(0.0, 0.0, 1.0));
}

/// Along a path, as `simulate` makes them: ten steps of 1 cm, each update started from the
/// last one's whole shapes and first checked where the schedule learned from the last one
/// predicts (`modal::ritz::RitzSchedule`): every update is made and every one agrees with
/// the dense model at its pose.
#[test]
fn ritz_updates_along_a_path_with_a_learned_schedule_agree_with_the_dense_modes() {
    let s = Scene::default_scene().with_model(ElementKind::Fem, 10);
    let mut est = Estimator::new(&s).unwrap();
    let mut p = Vector3::new(0.3, 0.2, 1.0);
    assert!(est.update(&Pose::at(p), Tmin::Scene).is_ok());
    let mut start = est
        .ee_modal_basis(K + GUARD)
        .unwrap()
        .shapes
        .expect("structured shapes");
    let mut schedule = RitzSchedule::default();
    let mut first_checks = Vec::new();
    for i in 0..10 {
        let next = p + Vector3::new(0.008, -0.006, 0.004);
        first_checks.push(schedule.first_check());
        start = update_from(&mut est, &s, &start, p, next, &mut schedule)
            .unwrap_or_else(|| panic!("step {i}: the update must be made"));
        p = next;
    }
    // The schedule moved off its first guess: it learned from the updates.
    assert!(
        first_checks.iter().any(|&c| c != RitzSchedule::FIRST_CHECK),
        "{first_checks:?}"
    );
}
