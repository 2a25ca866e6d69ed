//! Property tests over random robots and poses:
//!
//! - the real-time f1 and end-effector mode equal the dense reference within its accuracy
//!   (SAFETY·ε·λ_max/λ + 1e-9, SAFETY = 8, plus SAFETY·ε·EA/T for the catenary element,
//!   whose block is formed in global axes; see testkit/src/hard_cases.rs);
//! - the assembled K and M (`modal::assemble`) are symmetric and positive definite;
//! - frequencies are continuous along small pose steps (1e-6 m), and the warm-started
//!   estimator equals a cold one.
//!
//! Random robots: 4-8 cables, anchors jittered around the corners of a random box (upper and
//! lower rings, or all on the top for a suspended robot), the end-effector inside, random EA,
//! weight per length, end-effector mass, tension bounds, element (FEM, catenary, massless)
//! and N ≤ 10. Fixed seed, no failure persistence: deterministic.

use cablevib::estimator::Tmin;
use cablevib::estimator::{reference_analysis, Estimate, Estimator, EstimatorParams, Status};
use cablevib::kinematics::Pose;
use cablevib::modal::{assemble, hz_to_lambda, lambda_to_hz, DenseModes};
use cablevib::scene::{Cable, ElementKind, Scene};
use cablevib_testkit::hard_cases::{catenary_conditioning, dense_tol};
use cablevib_testkit::{ee_hz, ee_p};
use nalgebra::{DMatrix, Vector3};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

#[derive(Debug, Clone)]
struct Robot {
    scene: Scene,
    /// A unit direction for the continuity step.
    step: Vector3<f64>,
}

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..hi.ln()).prop_map(f64::exp)
}

prop_compose! {
    fn robot()(
        n in 4usize..=8,
        layout in 0u8..3,
        uniform in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0, 0.0f64..1.0), 8),
        half in (0.6f64..2.0, 0.6f64..2.0),
        height in 1.0f64..3.0,
        jitter in proptest::collection::vec((-0.2f64..0.2, -0.2f64..0.2, -0.2f64..0.2), 8),
        twist in 0.0f64..std::f64::consts::TAU,
        ee in (-0.3f64..0.3, -0.3f64..0.3, 0.3f64..0.7),
        ea in log_uniform(1e3, 1e9),
        gamma in log_uniform(1e-3, 1.0),
        mass_ratio in log_uniform(2.0, 200.0),
        t_min in 5.0f64..100.0,
        t_ratio in 3.0f64..30.0,
        element in prop_oneof![Just(ElementKind::Fem), Just(ElementKind::Catenary), Just(ElementKind::Massless)],
        n_el in 1usize..=10,
        step in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
    ) -> Robot {
        let (hx, hy) = half;
        // Start from the shipped scene so that fields this test does not vary keep their
        // defaults (point-mass end-effector, geometric stiffness on).
        let base = Scene::default_scene();
        let template = base.cables[0];
        let upper = n.div_ceil(2);
        let g = 9.81;
        let mut cables = Vec::with_capacity(n);
        let mut cable_mass = 0.0;
        for i in 0..n {
            // layout 0: upper and lower rings; 1: suspended (every anchor on top);
            // 2: anchors anywhere in the box.
            let anchor = if layout == 2 {
                let u = uniform[i];
                Vector3::new(hx * u.0, hy * u.1, height * u.2)
            } else {
                let (ring, k, count) = if layout == 1 {
                    (1.0, i, n)
                } else if i < upper {
                    (1.0, i, upper)
                } else {
                    (0.0, i - upper, n - upper)
                };
                let a = twist + std::f64::consts::TAU * (k as f64 + 0.5 * ring) / count as f64;
                let j = jitter[i];
                Vector3::new(
                    hx * (a.cos() + j.0).clamp(-1.2, 1.2),
                    hy * (a.sin() + j.1).clamp(-1.2, 1.2),
                    height * (ring + j.2 * 0.2),
                )
            };
            cables.push(Cable {
                anchor_m: anchor,
                youngs_modulus_pa: ea / 1e-5,
                area_m2: 1e-5,
                mass_per_length_kg_m: gamma / g,
                ..template
            });
            cable_mass += gamma / g * (2.0 * hx.max(hy) + height);
        }
        let ee_position = if layout == 2 {
            // Inside the anchors' hull: their centroid, nudged.
            cables.iter().fold(Vector3::zeros(), |a, c| a + c.anchor_m) / n as f64
                + Vector3::new(ee.0 * 0.3 * hx, ee.1 * 0.3 * hy, (ee.2 - 0.5) * 0.3 * height)
        } else {
            Vector3::new(ee.0 * hx, ee.1 * hy, ee.2 * height)
        };
        let ee_mass = mass_ratio * cable_mass;
        let t_max = (t_min * t_ratio).max(4.0 * ee_mass * g);
        let mut scene = base.with_model(element, n_el);
        scene.name = "random".into();
        scene.gravity_m_s2 = Vector3::new(0.0, 0.0, -g);
        scene.ee_mass_kg = ee_mass;
        scene.ee_position_m = ee_position;
        scene.weight_carried = true;
        scene.cables = cables;
        scene.t_min_n = t_min;
        scene.t_max_n = t_max;
        scene.model.ee_participation_min = 0.5;
        let s = Vector3::new(step.0, step.1, step.2);
        let step = if s.norm() > 1e-3 { s.normalize() } else { Vector3::x() };
        Robot { scene, step }
    }
}

fn config(cases: u32) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(0x0006_CAB1_E71B),
        failure_persistence: None,
        max_shrink_iters: 200,
        max_global_rejects: 4096,
        ..Config::default()
    }
}

/// An estimator with the scene's participation threshold.
fn estimator(s: &Scene) -> Option<Estimator> {
    let mut p = EstimatorParams::default();
    p.modal.ee_participation_min = s.model.ee_participation_min;
    Estimator::with_params(s, p).ok()
}

/// The tolerance on mode `lambda` (see testkit/src/hard_cases.rs) plus `extra`.
fn tol_of(lambda: f64, m: &DenseModes, extra: f64) -> f64 {
    dense_tol(lambda, m) + extra
}

/// Real-time against dense: f1, and the end-effector mode as in testkit/src/hard_cases.rs
/// (a dense mode within tolerance whose participation is ≥ thr − 1e-3, none clearly below it
/// with participation ≥ thr + 1e-3).
fn check_against_dense(
    e: &Estimate,
    m: &DenseModes,
    thr: f64,
    extra: f64,
) -> Result<(), TestCaseError> {
    let l1 = m.lambda[0];
    let tol = tol_of(l1, m, extra);
    let err = (e.f1_hz - lambda_to_hz(l1)).abs() / lambda_to_hz(l1);
    prop_assert!(
        err <= tol,
        "f1 {} vs dense {}: {err:.2e} > {tol:.2e}",
        e.f1_hz,
        lambda_to_hz(l1)
    );
    if ee_hz(e).is_nan() {
        prop_assert!(
            !m.ee_participation.iter().any(|&p| p >= thr + 1e-3),
            "no real-time end-effector mode, dense has {:?}",
            m.first_ee_mode(thr)
        );
        return Ok(());
    }
    let le = hz_to_lambda(ee_hz(e));
    let idx = (0..m.lambda.len())
        .min_by(|&a, &b| {
            (m.lambda[a] - le)
                .abs()
                .total_cmp(&(m.lambda[b] - le).abs())
        })
        .unwrap();
    let fe = lambda_to_hz(m.lambda[idx]);
    let tol_e = tol_of(m.lambda[idx], m, extra);
    prop_assert!(
        (ee_hz(e) - fe).abs() <= tol_e * fe,
        "ee mode {} vs nearest dense {fe}: {:.2e} > {tol_e:.2e}",
        ee_hz(e),
        (ee_hz(e) - fe).abs() / fe
    );
    let part = m
        .lambda
        .iter()
        .zip(&m.ee_participation)
        .filter(|(&l, _)| (lambda_to_hz(l) - fe).abs() <= tol_e * fe)
        .map(|(_, &p)| p)
        .fold(0.0f64, f64::max);
    prop_assert!(
        part >= thr - 1e-3,
        "ee mode {fe} Hz has dense participation {part}"
    );
    for (&l, &p) in m.lambda.iter().zip(&m.ee_participation) {
        if lambda_to_hz(l) < ee_hz(e) * (1.0 - tol_e) - 1e-12 {
            prop_assert!(
                p < thr + 1e-3,
                "dense end-effector mode at {} Hz (participation {p}) below the real-time one at {} Hz",
                lambda_to_hz(l),
                ee_hz(e)
            );
        }
    }
    Ok(())
}

fn symmetric_pd(name: &str, a: &DMatrix<f64>) -> Result<(), TestCaseError> {
    let scale = a.amax();
    let asym = (a - a.transpose()).amax();
    prop_assert!(
        asym <= 1e-15 * scale,
        "{name} not symmetric: {asym:.2e} of {scale:.2e}"
    );
    prop_assert!(
        a.clone().cholesky().is_some(),
        "{name} not positive definite"
    );
    Ok(())
}

proptest! {
    #![proptest_config(config(256))]

    /// Real-time = dense; K and M symmetric positive definite.
    #[test]
    fn realtime_equals_dense_and_k_m_are_spd(r in robot()) {
        let s = &r.scene;
        let Some(mut est) = estimator(s) else {
            // The default pose has no structure matrix (a cable of zero length).
            prop_assume!(false);
            unreachable!()
        };
        let e = *est.update(&Pose::at(s.ee_position_m), Tmin::Scene);
        // The default pose is not tension-feasible for this random robot.
        prop_assume!(e.status != Status::TensionInfeasible);
        prop_assert!(
            e.status == Status::Ok,
            "status {:?} ({:?}) at the pose the estimator was built at",
            e.status,
            e.error
        );
        prop_assert!(e.f1_hz.is_finite() && e.f1_hz > 0.0);
        let (k, m) = assemble(est.cable_models(), s.ee_mass_kg).unwrap();
        symmetric_pd("K", &k)?;
        symmetric_pd("M", &m)?;
        let r = reference_analysis(s, &s.ee_position_m, Tmin::Scene, true);
        let r = match r {
            Ok(r) => r,
            Err(err) => {
                prop_assert!(false, "dense reference failed where the real-time path is ok: {err}");
                unreachable!()
            }
        };
        for (a, b) in e.tensions().iter().zip(&r.tensions_n) {
            prop_assert!((a - b).abs() <= 1e-8 * s.t_max_n, "tension {a} vs Clarabel {b}");
        }
        let extra = catenary_conditioning(s, e.tensions());
        check_against_dense(&e, &r.modes, s.model.ee_participation_min, extra)?;
    }

    /// Continuity along a 1e-6 m step: |Δf|/f ≤ 1e-4 (a Lipschitz constant of 100 per metre),
    /// and the warm-started estimator (previous pose 1e-6 m away) equals a cold one to 1e-9.
    #[test]
    fn frequencies_are_continuous_and_warm_equals_cold(r in robot()) {
        let s = &r.scene;
        let Some(mut warm) = estimator(s) else {
            prop_assume!(false);
            unreachable!()
        };
        let p0 = s.ee_position_m;
        let p1 = p0 + r.step * 1e-6;
        let e0 = *warm.update(&Pose::at(p0), Tmin::Scene);
        let e1 = *warm.update(&Pose::at(p1), Tmin::Scene);
        // The default pose is not tension-feasible for this random robot.
        prop_assume!(e0.status != Status::TensionInfeasible);
        prop_assert!(e0.is_ok(), "{:?}", e0.error);
        prop_assume!(e1.is_ok()); // a step across the feasible boundary
        let c1 = *estimator(s).unwrap().update(&Pose::at(p1), Tmin::Scene);
        prop_assert!(c1.is_ok());
        let d = (e1.f1_hz - e0.f1_hz).abs() / e0.f1_hz;
        prop_assert!(d <= 1e-4, "f1 jumps by {d:.2e} over 1e-6 m: {} -> {}", e0.f1_hz, e1.f1_hz);
        let thr = s.model.ee_participation_min;
        let near_threshold = (ee_p(&e0) - thr).abs() < 1e-3
            || (ee_p(&e1) - thr).abs() < 1e-3;
        if !near_threshold {
            let d = (ee_hz(&e1) - ee_hz(&e0)).abs() / ee_hz(&e0);
            prop_assert!(
                d <= 1e-4,
                "end-effector mode jumps by {d:.2e} over 1e-6 m: {} -> {} (participation {} -> {})",
                ee_hz(&e0), ee_hz(&e1), ee_p(&e0), ee_p(&e1)
            );
        }
        let wc = (e1.f1_hz - c1.f1_hz).abs() / c1.f1_hz;
        prop_assert!(wc <= 1e-9, "warm f1 {} vs cold {}: {wc:.2e}", e1.f1_hz, c1.f1_hz);
        let wc = (ee_hz(&e1) - ee_hz(&c1)).abs() / ee_hz(&c1);
        prop_assert!(wc <= 1e-9, "warm ee mode {} vs cold {}: {wc:.2e}", ee_hz(&e1), ee_hz(&c1));
        for (a, b) in e1.tensions().iter().zip(c1.tensions()) {
            prop_assert!((a - b).abs() <= 1e-9 * s.t_max_n, "warm tension {a} vs cold {b}");
        }
    }
}
