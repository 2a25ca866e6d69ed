//! Helpers of the hard-case tests (tests/hard_cases_*.rs): the real-time path against the
//! dense reference, sanity checks of one estimate, and the small robots the cases need.
//!
//! Tolerance of real-time against dense: a backward-stable dense solver has absolute
//! eigenvalue error ≈ ε·λ_max, i.e. relative ε·λ_max/λ on mode λ
//! ([`dense_relative_accuracy`]). We allow `SAFETY` = 8 times that, plus 1e-9 (the
//! real-time path's own Newton tolerance is 1e-12 relative), applied to the frequency
//! (conservative: a relative error δ in λ is δ/2 in f).
use super::rel;
use crate::{ee_hz, ee_p};
use cablevib::estimator::Tmin;
use cablevib::estimator::{
    build_models, reference_analysis, Estimate, Estimator, ReferenceAnalysis, Status,
};
use cablevib::kinematics::{Geometry, Pose};
use cablevib::modal::{
    assemble, dense_modes, dense_relative_accuracy, hz_to_lambda, lambda_to_hz, DenseModes,
};
use cablevib::scene::{ElementKind, Scene};
use nalgebra::Vector3;

/// Safety factor on the dense solver's accuracy estimate.
pub const SAFETY: f64 = 8.0;
pub const EPS: f64 = f64::EPSILON;

/// Tolerance of the real-time path against dense mode `lambda`.
pub fn dense_tol(lambda: f64, modes: &DenseModes) -> f64 {
    SAFETY * dense_relative_accuracy(lambda, modes.lambda_max) + 1e-9
}

/// The real-time estimate of one pose from a fresh (cold) estimator.
pub fn realtime(s: &Scene, p: Vector3<f64>, t_min: f64) -> Estimate {
    let mut est = Estimator::new(s).unwrap_or_else(|e| panic!("{}: {e}", s.name));
    *est.update(&Pose::at(p), Tmin::Uniform(t_min))
}

pub fn dense(s: &Scene, p: Vector3<f64>, t_min: f64) -> ReferenceAnalysis {
    reference_analysis(s, &p, Tmin::Uniform(t_min), true)
        .unwrap_or_else(|e| panic!("{}: dense reference at {p:?}, t_min {t_min}: {e}", s.name))
}

/// The dense spectrum of the scene's model at given tensions (the real-time path's own):
/// separates the eigen comparison from the tension QP (Clarabel, see
/// `clarabel_reference_handles_wide_tension_ranges`).
pub fn dense_with(s: &Scene, p: Vector3<f64>, tensions: &[f64]) -> DenseModes {
    let g = geometry(s, &p);
    let models = build_models(s, &g, tensions).unwrap();
    let (k, m) = assemble(&models, s.ee_mass_kg).unwrap();
    dense_modes(&k, &m, s.ee_mass_kg, true).unwrap()
}

/// The catenary block K_c = −F⁻¹ is formed in global axes and split into chains by an
/// eigen-decomposition; its transverse part (≈ T/l) then carries an absolute error ε·EA/l,
/// i.e. ε·EA/T relative (see `gamma_to_zero_element_is_the_straight_limit_at_every_n`).
/// The real-time path inherits SAFETY·ε·max(EA/T) on the catenary model; FEM chains are
/// built exactly and get nothing.
pub fn catenary_conditioning(s: &Scene, tensions: &[f64]) -> f64 {
    if s.model.element != ElementKind::Catenary {
        return 0.0;
    }
    s.cables
        .iter()
        .zip(tensions)
        .map(|(c, &t)| SAFETY * EPS * c.ea_n() / t)
        .fold(0.0, f64::max)
}

/// Every number of an ok estimate is finite and physical.
pub fn assert_sane(label: &str, e: &Estimate, s: &Scene, t_min: f64) {
    assert_eq!(e.status, Status::Ok, "{label}: {:?}", e.error);
    assert!(
        e.f1_hz.is_finite() && e.f1_hz > 0.0,
        "{label}: f1 {}",
        e.f1_hz
    );
    assert!(
        (0.0..=1.0).contains(&e.f1_ee_participation),
        "{label}: participation {}",
        e.f1_ee_participation
    );
    assert!(e.stiffness.k6.iter().all(|x| x.is_finite()), "{label}");
    let tol = 1e-9 * s.t_max_n.max(1.0);
    for &t in e.tensions() {
        assert!(
            t.is_finite() && t >= t_min - tol && t <= s.t_max_n + tol,
            "{label}: tension {t} outside [{t_min}, {}]",
            s.t_max_n
        );
    }
}

/// A non-ok estimate carries no stale numbers.
pub fn assert_no_numbers(label: &str, e: &Estimate) {
    assert_ne!(e.status, Status::Ok, "{label}");
    assert!(
        e.f1_hz.is_nan(),
        "{label}: f1 {} on {:?}",
        e.f1_hz,
        e.status
    );
    assert!(ee_hz(e).is_nan(), "{label}: ee {}", ee_hz(e));
    assert!(e.stiffness.k6.iter().all(|x| x.is_nan()), "{label}");
}

/// Real-time f1 and end-effector mode against the dense spectrum. Returns the relative
/// error of f1 and its tolerance.
///
/// The end-effector mode: the real-time answer must be a dense mode (within tolerance)
/// whose dense participation is ≥ thr − 1e-3, and no dense mode clearly below it may have
/// participation ≥ thr + 1e-3 (the 1e-3 band absorbs modes whose participation sits on the
/// threshold). If no dense mode reaches the threshold, the real-time answer is a "weak" one:
/// a dense mode with the same participation, below the threshold.
pub fn assert_matches_dense(
    label: &str,
    s: &Scene,
    e: &Estimate,
    r: &ReferenceAnalysis,
) -> (f64, f64) {
    let extra = catenary_conditioning(s, e.tensions());
    assert_matches_modes(label, e, &r.modes, s.model.ee_participation_min, extra)
}

/// [`assert_matches_dense`] on a dense spectrum, with `extra` added to every tolerance (the
/// catenary element's own conditioning, see [`catenary_conditioning`]).
pub fn assert_matches_modes(
    label: &str,
    e: &Estimate,
    m: &DenseModes,
    thr: f64,
    extra: f64,
) -> (f64, f64) {
    let l1 = m.lambda[0];
    let f1 = lambda_to_hz(l1);
    let tol = dense_tol(l1, m) + extra;
    let err = rel(e.f1_hz, f1);
    assert!(
        err <= tol,
        "{label}: real-time f1 {} vs dense {f1}: rel {err:.2e} > tol {tol:.2e}",
        e.f1_hz
    );
    let exists = m.ee_participation.iter().any(|&p| p >= thr - 1e-3);
    if ee_hz(e).is_finite() && ee_p(e) < thr {
        // Weak answer: no mode reached the threshold in the bounded scan; the most
        // end-effector-like mode found is reported with its participation.
        assert!(
            !m.ee_participation.iter().any(|&p| p >= thr + 1e-3),
            "{label}: real-time reports a weak end-effector mode, dense has {:?}",
            m.first_ee_mode(thr).map(|(i, l)| (i, lambda_to_hz(l)))
        );
        let le = hz_to_lambda(ee_hz(e));
        let (idx, _) = m
            .lambda
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - le).abs().total_cmp(&(b.1 - le).abs()))
            .unwrap();
        let tol_w = dense_tol(m.lambda[idx], m) + extra;
        assert!(
            rel(ee_hz(e), lambda_to_hz(m.lambda[idx])) <= tol_w
                && (m.ee_participation[idx] - ee_p(e)).abs() <= 1e-3,
            "{label}: weak end-effector mode {} Hz (p {}) is not the dense mode {} Hz (p {})",
            ee_hz(e),
            ee_p(e),
            lambda_to_hz(m.lambda[idx]),
            m.ee_participation[idx]
        );
        return (err, tol);
    }
    if ee_hz(e).is_nan() {
        assert!(
            !m.ee_participation.iter().any(|&p| p >= thr + 1e-3),
            "{label}: real-time has no end-effector mode, dense has {:?}",
            m.first_ee_mode(thr).map(|(i, l)| (i, lambda_to_hz(l)))
        );
        return (err, tol);
    }
    assert!(
        exists,
        "{label}: real-time end-effector mode {} Hz, dense has none",
        ee_hz(e)
    );
    let le = hz_to_lambda(ee_hz(e));
    let (idx, _) = m
        .lambda
        .iter()
        .enumerate()
        .map(|(i, &l)| (i, (l - le).abs()))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    let fe = lambda_to_hz(m.lambda[idx]);
    let tol_e = dense_tol(m.lambda[idx], m) + extra;
    assert!(
        rel(ee_hz(e), fe) <= tol_e,
        "{label}: real-time ee mode {} vs nearest dense {fe}: rel {:.2e} > {tol_e:.2e}",
        ee_hz(e),
        rel(ee_hz(e), fe)
    );
    // Within a cluster the dense vectors are arbitrary: accept any member of the cluster.
    let cluster_part = m
        .lambda
        .iter()
        .zip(&m.ee_participation)
        .filter(|(&l, _)| rel(lambda_to_hz(l), fe) <= tol_e)
        .map(|(_, &p)| p)
        .fold(0.0f64, f64::max);
    assert!(
        cluster_part >= thr - 1e-3,
        "{label}: real-time ee mode {} Hz has dense participation {cluster_part:.4} < {thr}",
        ee_hz(e)
    );
    for (i, (&l, &p)) in m.lambda.iter().zip(&m.ee_participation).enumerate() {
        if lambda_to_hz(l) < ee_hz(e) * (1.0 - tol_e) - 1e-12 {
            assert!(
                p < thr + 1e-3,
                "{label}: dense mode {i} at {} Hz (participation {p:.4}) is an end-effector mode below the real-time one at {} Hz",
                lambda_to_hz(l),
                ee_hz(e)
            );
        }
    }
    (err, tol)
}

pub fn geometry(s: &Scene, p: &Vector3<f64>) -> Geometry {
    let mut g = Geometry::new(s.n_cables());
    g.update(s.cables.iter().map(|c| &c.anchor_m), p).unwrap();
    g
}

/// A five-cable robot with two exactly vertical cables (anchor 1 m above and 1 m below the
/// end-effector) and three horizontal ones at 120°, all 1 m long at the default pose.
pub fn vertical_scene(element: &str, n: usize) -> Scene {
    let text = format!(
        r#"
name = "vertical-5"
gravity = [0.0, 0.0, -9.81]
[end_effector]
mass = 10.0
position = [0.0, 0.0, 1.0]
[cable]
youngs_modulus = 2.01e10
area = 50.265e-6
weight_per_length = 0.251
[tension]
t_min = 50.0
t_max = 2000.0
[model]
element = "{element}"
elements_per_cable = {n}
[[cables]]
anchor = [0.0, 0.0, 2.0]
[[cables]]
anchor = [0.0, 0.0, 0.0]
[[cables]]
anchor = [1.0, 0.0, 1.0]
[[cables]]
anchor = [-0.5, 0.8660254037844386, 1.0]
[[cables]]
anchor = [-0.5, -0.8660254037844386, 1.0]
"#
    );
    Scene::from_toml_str(&text, "vertical-5.toml").unwrap()
}

/// A suspended four-cable robot: anchors at the corners of a 2 m square at z = 2, the
/// end-effector hanging at z = 1. Its structure matrix loses rank when the end-effector
/// reaches the plane of the anchors.
pub fn suspended_scene() -> Scene {
    let text = r#"
name = "suspended-4"
gravity = [0.0, 0.0, -9.81]
[end_effector]
mass = 10.0
position = [0.0, 0.0, 1.0]
[cable]
youngs_modulus = 2.01e10
area = 50.265e-6
weight_per_length = 0.251
[tension]
t_min = 10.0
t_max = 5000.0
[model]
element = "fem"
elements_per_cable = 10
[[cables]]
anchor = [1.0, 1.0, 2.0]
[[cables]]
anchor = [-1.0, 1.0, 2.0]
[[cables]]
anchor = [-1.0, -1.0, 2.0]
[[cables]]
anchor = [1.0, -1.0, 2.0]
"#;
    Scene::from_toml_str(text, "suspended-4.toml").unwrap()
}
