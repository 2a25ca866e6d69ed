//! The sum rules that certify the tracked end-effector mode, against the dense reference.
//!
//! The modes are complete, so the end-effector participation summed over all of them is
//! tr(M_ee M_∞⁻¹) (`ModalSolver::participation_total`) and, weighted by 1/λ, it is
//! tr(M_ee D(0)⁻¹) (`ModalSolver::participation_over_lambda`). The dense solver sums its
//! own participations over the whole spectrum. Tolerance for the plain sum, 1e-9 relative
//! (a sum of O(1) terms; they agree to ~1e-15). For the weighted sum, the dense solver's own
//! accuracy: each term p_k/λ_k is off by up to 8·ε·λ_max/λ_k relative (its λ_k), which on
//! the planar robot (λ_max/λ_1 ~ 1e9) dominates; plus 1e-11 relative.
use cablevib::estimator::Tmin;
use cablevib::estimator::{reference_analysis, Estimator};
use cablevib::kinematics::Pose;
use cablevib::modal::dense_relative_accuracy;
use cablevib::scene::{ElementKind, Scene};
use nalgebra::Vector3;

fn check(label: &str, scene: &Scene, p: Vector3<f64>) {
    let t_min = scene.t_min_n;
    let r = reference_analysis(scene, &p, Tmin::Uniform(t_min), true).expect("feasible pose");
    let m = &r.modes;
    let sum: f64 = m.ee_participation.iter().sum();
    let weighted: f64 = m
        .ee_participation
        .iter()
        .zip(&m.lambda)
        .map(|(p, l)| p / l)
        .sum();
    let mut est = Estimator::new(scene).unwrap();
    let e = *est.update(&Pose::at(p), Tmin::Uniform(t_min));
    assert!(e.is_ok(), "{label}: {:?}", e.status);
    let total = est.modal().participation_total();
    let over = est.modal().participation_over_lambda();
    let err0 = (total - sum).abs() / sum;
    let err1 = (over - weighted).abs() / weighted;
    let tol1 = m
        .ee_participation
        .iter()
        .zip(&m.lambda)
        .map(|(p, l)| p / l * 8.0 * dense_relative_accuracy(*l, m.lambda_max))
        .sum::<f64>()
        / weighted
        + 1e-11;
    eprintln!("{label}: Σp {sum:.15} vs {total:.15} ({err0:.1e}); Σp/λ {weighted:.6e} vs {over:.6e} ({err1:.1e}, tol {tol1:.1e})");
    assert!(err0 <= 1e-9, "{label}: Σp dense {sum} vs sum rule {total}");
    assert!(
        err1 <= tol1,
        "{label}: Σp/λ dense {weighted} vs sum rule {over}: {err1:.1e} > {tol1:.1e}"
    );
}

#[test]
fn sum_rules_match_the_dense_spectrum() {
    let s = Scene::default_scene();
    for (el, n) in [
        (ElementKind::Fem, 10),
        (ElementKind::Fem, 3),
        (ElementKind::Catenary, 6),
        (ElementKind::Massless, 1),
    ] {
        let sc = s.with_model(el, n);
        check(
            &format!("spatial {} N={n}", el.as_str()),
            &sc,
            Vector3::new(0.6, 0.3, 1.25),
        );
        check(
            &format!("spatial {} N={n}, centre", el.as_str()),
            &sc,
            sc.ee_position_m,
        );
    }
    let p = Scene::planar_paper().with_model(ElementKind::Fem, 10);
    check("planar fem N=10", &p, p.ee_position_m);
    let b = Scene::box_6dof();
    check("rigid box (6 DOF)", &b, b.ee_position_m);
}

#[test]
fn continuous_sum_is_the_dimension() {
    // A continuous cable's end carries no lumped mass: the participation sums to 3.
    let s = Scene::default_scene().with_model(ElementKind::Continuous, 1);
    let mut est = Estimator::new(&s).unwrap();
    assert!(est.update(&Pose::at(s.ee_position_m), Tmin::Scene).is_ok());
    assert!((est.modal().participation_total() - 3.0).abs() <= 1e-12);
}
