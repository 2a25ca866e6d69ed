//! Every T_min the one rule accepts (`scene::check_t_min`: down to the smallest normal f64,
//! 2.2e-308 N) gets an answer, in real time and offline.
//!
//! With a cable at a tiny T_min its transverse string modes (end-effector held still) fall
//! to λ ∝ T_min, and the first natural frequency sits a hair below the lowest of them: the
//! end-effector barely takes part (participation ~1e-28 at 1e-12 N), so the root is closer
//! to the pole than f64 resolves. Newton's step then lands on the pole (or, below ~1e-160 N,
//! D'(λ) overflows next to it) and, before the fix, bisection towards the pole spent the
//! whole budget: `not_converged` on every cycle of `demo --t-min-schedule 0:1e-12` and after
//! 200 evaluations offline at 1e-100 N. The root search now probes once inside the
//! collapse width below the pole.
//!
//! Independent checks (closed forms, not the solver): a FEM chain of N consistent-mass
//! elements (spring k = T/l, mass m each) has blocked transverse eigenvalues
//! λ_j = 2k(1 − cos θ_j) / (m (4 + 2 cos θ_j)/6), θ_j = jπ/N; a continuous string
//! (π/L)² T/μ; massless cables leave the 3 × 3 problem K u = λ m u with
//! K = Σ EA/L e eᵀ + T/L (I − e eᵀ) (the massless-spring limit as T → 0).
use cablevib::alloc_count::thread_allocations;
use cablevib::estimator::Tmin;
use cablevib::estimator::{Estimator, Status};
use cablevib::kinematics::Pose;
use cablevib::modal::{hz_to_lambda, Mode};
use cablevib::scene::{ElementKind, Scene, T_MIN_FLOOR_N};
use cablevib::trajectory::{Circle, CIRCLE_RADIUS_M, SAMPLE_PERIOD_S};
use nalgebra::{Matrix3, Vector3};
use std::f64::consts::PI;

/// T_min from 1e-12 N down to the rule's floor: every 8th decade and the floor itself.
fn tiny_t_mins() -> Vec<f64> {
    let mut t: Vec<f64> = (0..38).map(|k| 1e-12 * 10f64.powi(-8 * k)).collect();
    t.retain(|&x| x >= T_MIN_FLOOR_N);
    t.push(T_MIN_FLOOR_N);
    t
}

/// The closed-form λ₁ (rad²/s²) of a point-mass scene at `p` with tensions `t` (N).
fn closed_form_lambda1(s: &Scene, p: &Vector3<f64>, t: &[f64]) -> f64 {
    let n_el = s.model.elements_per_cable as f64;
    let mut k_ee = Matrix3::zeros();
    let mut lowest_pole = f64::INFINITY;
    for (c, &ti) in s.cables.iter().zip(t) {
        let d = p - c.anchor_m;
        let l = d.norm();
        let e = d / l;
        k_ee +=
            c.ea_n() / l * e * e.transpose() + ti / l * (Matrix3::identity() - e * e.transpose());
        let pole = match s.model.element {
            ElementKind::Fem => {
                let (k, m, th) = (
                    ti / (l / n_el),
                    c.mass_per_length_kg_m * l / n_el,
                    PI / n_el,
                );
                2.0 * k * (1.0 - th.cos()) / (m * (4.0 + 2.0 * th.cos()) / 6.0)
            }
            ElementKind::Continuous => (PI / l).powi(2) * ti / c.mass_per_length_kg_m,
            _ => f64::INFINITY,
        };
        lowest_pole = lowest_pole.min(pole);
    }
    if lowest_pole.is_finite() {
        lowest_pole
    } else {
        k_ee.symmetric_eigenvalues().min() / s.ee_mass_kg
    }
}

#[test]
fn every_accepted_tiny_t_min_converges_in_one_cycle_without_allocating() {
    let base = Scene::default_scene();
    for (el, n) in [
        (ElementKind::Fem, 40),
        (ElementKind::Continuous, 1),
        (ElementKind::Massless, 1),
    ] {
        let s = base.with_model(el, n);
        let p = Pose {
            position_m: s.ee_position_m,
            orientation_wxyz: s.ee_orientation_wxyz,
        };
        let mut est = Estimator::realtime(&s).unwrap();
        for t_min in tiny_t_mins() {
            est.reset();
            let before = thread_allocations();
            // A cold cycle, then a warm one at the same pose.
            for cycle in ["cold", "warm"] {
                let e = est.update(&p, Tmin::Uniform(t_min));
                assert_eq!(
                    e.status,
                    Status::Ok,
                    "{el:?} T_min {t_min:e} N {cycle}: {:?}",
                    e.error
                );
                let l = hz_to_lambda(e.f1_hz);
                let want = closed_form_lambda1(&s, &s.ee_position_m, e.tensions());
                // 1e-12: the root search's tolerance (the root is within ~1e-20 of the pole).
                assert!(
                    (l - want).abs() <= 1e-12 * want,
                    "{el:?} T_min {t_min:e} N {cycle}: λ1 {l:e} vs closed form {want:e}"
                );
            }
            assert_eq!(thread_allocations() - before, 0, "{el:?} T_min {t_min:e}");
        }
    }
}

#[test]
fn a_rigid_body_at_tiny_t_min_converges() {
    let s = Scene::box_6dof().with_model(ElementKind::Fem, 10);
    let p = Pose {
        position_m: s.ee_position_m,
        orientation_wxyz: s.ee_orientation_wxyz,
    };
    let mut est = Estimator::realtime(&s).unwrap();
    for t_min in tiny_t_mins() {
        est.reset();
        for _ in 0..2 {
            let e = est.update(&p, Tmin::Uniform(t_min));
            assert_eq!(e.status, Status::Ok, "T_min {t_min:e} N: {:?}", e.error);
            // The count certificate (cold cycle) passed; f1 is at most the lowest pole.
            let l = hz_to_lambda(e.f1_hz);
            assert!(l > 0.0 && l <= est.modal().lowest_pole(), "λ1 {l:e}");
        }
    }
}

#[test]
fn the_demo_circle_at_1e_12_newton_is_ok_on_every_cycle() {
    // What `cablevib demo --t-min-schedule 0:1e-12` runs: the real-time estimator along the
    // paper's circle (1 ms per pose) at T_min = 1e-12 N.
    let s = Scene::default_scene();
    let c = Circle::new(&s, CIRCLE_RADIUS_M, 4.0).unwrap();
    let mut est = Estimator::realtime(&s).unwrap();
    let before = thread_allocations();
    for k in 0..1000 {
        let x = c.position_at(k as f64 * SAMPLE_PERIOD_S);
        let p = Pose {
            position_m: x,
            orientation_wxyz: s.ee_orientation_wxyz,
        };
        let e = est.update(&p, Tmin::Uniform(1e-12));
        assert_eq!(e.status, Status::Ok, "cycle {k}: {:?}", e.error);
        let (l, want) = (
            hz_to_lambda(e.f1_hz),
            closed_form_lambda1(&s, &x, e.tensions()),
        );
        assert!(
            (l - want).abs() <= 1e-12 * want,
            "cycle {k}: {l:e} vs {want:e}"
        );
    }
    assert_eq!(thread_allocations() - before, 0);
}

#[test]
fn offline_modes_at_1e_100_newton_and_the_floor_converge() {
    // `cablevib analyze spatial-paper --t-min 1e-100` (unlimited budget, the first K modes
    // by the count): before, bisection on the count from the end-effector's scale (~1e4
    // rad²/s²) down to the string modes (~1e-98) ran out of its 200 evaluations.
    let s = Scene::default_scene();
    let p = Pose {
        position_m: s.ee_position_m,
        orientation_wxyz: s.ee_orientation_wxyz,
    };
    for t_min in [1e-12, 1e-100, T_MIN_FLOOR_N] {
        let mut est = Estimator::new(&s).unwrap();
        let e = *est.update(&p, Tmin::Uniform(t_min));
        assert_eq!(e.status, Status::Ok, "{:?}", e.error);
        let want = closed_form_lambda1(&s, &s.ee_position_m, e.tensions());
        let l = hz_to_lambda(e.f1_hz);
        assert!((l - want).abs() <= 1e-12 * want, "f1: {l:e} vs {want:e}");
        let mut modes = [Mode::default(); 4];
        let k = est.modes(4, &mut modes).unwrap();
        assert_eq!(k, 4);
        // The first cluster: the string modes of the cables at T_min, two transverse chains
        // per cable, at the closed-form pole (to the count's pole probe, 1e-13 relative).
        let at_t_min = e.tensions().iter().filter(|&&t| t == t_min).count() as u32;
        assert_eq!(modes[0].multiplicity, 2 * at_t_min, "T_min {t_min:e}");
        assert!(
            (modes[0].lambda - want).abs() <= 1e-12 * want,
            "T_min {t_min:e}: mode 1 {:e} vs {want:e}",
            modes[0].lambda
        );
    }
}
