//! The structured spectrum engine (`ModalSolver::modes`, `Estimator::modes`) against
//! references that do not share its code: the dense generalised eigensolver on the same
//! assembled K and M (good to ε·λ_max/λ relative, `dense_relative_accuracy`).

use cablevib::estimator::Estimator;
use cablevib::kinematics::Pose;
use cablevib::modal::{dense_relative_accuracy, Mode};
use cablevib::scene::{ElementKind, Scene};

/// Safety factor on the dense solver's backward-error bound ε·λ_max/λ (the constant of a
/// backward-stable eigensolver's error is a modest multiple of ε).
const DENSE_SAFETY: f64 = 8.0;
/// The structured engine's own error, relative (Newton to 1e-14, the chain evaluation and
/// the 3 × 3 eigenvalues of D to a few hundred ε on these scenes).
const STRUCTURED_TOL: f64 = 1e-11;

fn estimator_at_default(s: &Scene) -> Estimator {
    let mut est = Estimator::new(s).unwrap_or_else(|e| panic!("{}: {e}", s.name));
    let pose = Pose {
        position_m: s.ee_position_m,
        orientation_wxyz: s.ee_orientation_wxyz,
    };
    let st = est.update(&pose, s.t_min_n).status;
    assert_eq!(st.as_str(), "ok", "{}", s.name);
    est
}

/// K structured modes and the dense spectrum of the same models: every λ within the dense
/// bound, multiplicities and summed cluster participations equal.
fn check_against_dense(s: &Scene, k: usize) {
    let mut est = estimator_at_default(s);
    let mut out = vec![Mode::default(); k];
    let n = est.modes(k, &mut out).unwrap();
    let d = est.dense_modes(true).unwrap();
    assert_eq!(n, k.min(d.lambda.len()), "{}", s.name);
    for (i, m) in out[..n].iter().enumerate() {
        let l = d.lambda[i];
        let tol = DENSE_SAFETY * dense_relative_accuracy(l, d.lambda_max) + STRUCTURED_TOL;
        let err = (m.lambda - l).abs() / l;
        eprintln!(
            "{} mode {i}: {:.12e} vs dense {:.12e} rel {err:.1e} (tol {tol:.1e}) mult {} p {:.6} vs {:.6}",
            s.name, m.lambda, l, m.multiplicity, m.ee_participation, d.ee_participation[i]
        );
        assert!(
            err <= tol,
            "{} mode {i}: {} vs {l}: {err:.2e} > {tol:.2e}",
            s.name,
            m.lambda
        );
    }
}

#[test]
fn every_model_matches_dense_at_n10() {
    let base = [Scene::default_scene(), Scene::planar_paper()];
    for s in &base {
        for el in [
            ElementKind::Fem,
            ElementKind::Catenary,
            ElementKind::Massless,
        ] {
            check_against_dense(&s.with_model(el, 10), 12);
        }
    }
    check_against_dense(&Scene::box_6dof().with_model(ElementKind::Fem, 10), 12);
}
