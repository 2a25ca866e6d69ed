//! The real-time path against the dense reference on random feasible poses, and the
//! tracked (warm) path against cold solves along the paper's trajectory.
//!
//! Tolerance for f1 and the end-effector mode against the dense solver: its own accuracy,
//! 8·ε·λ_max/λ (relative, on λ; half that on f) + 1e-10, computed per pose and mode.
//! Tensions: 1e-9 relative against Clarabel (tolerances 1e-13).
use cablevib::estimator::Tmin;
use cablevib::estimator::{reference_analysis, Estimator};
use cablevib::kinematics::Pose;
use cablevib::modal::{dense_relative_accuracy, lambda_to_hz};
use cablevib::scene::{ElementKind, Scene};
use cablevib::trajectory::circle_pose;
use cablevib_testkit::Rng;
use cablevib_testkit::{ee_hz, ee_p};
use nalgebra::Vector3;

fn random_poses_agree(scene: &Scene, count: usize, seed: u64) -> (usize, f64, f64) {
    let (lo, hi) = scene.frame_bounds_m();
    let mut rng = Rng(seed);
    let mut checked = 0;
    let mut worst_f1 = 0.0f64;
    let mut worst_ee = 0.0f64;
    let thr = scene.model.ee_participation_min;
    let mut attempts = 0;
    // Include the paper's clustered symmetric pose.
    let mut first = true;
    while checked < count && attempts < 20 * count {
        attempts += 1;
        let p = if first {
            first = false;
            scene.ee_position_m
        } else {
            let mut p = Vector3::zeros();
            for i in 0..3 {
                // Stay 10 % inside the frame; planar robots keep their plane.
                let span = hi[i] - lo[i];
                p[i] = if span > 0.0 {
                    lo[i] + span * (0.1 + 0.8 * rng.next())
                } else {
                    lo[i]
                };
            }
            p
        };
        let t_min = scene.t_min_n * (0.5 + rng.next());
        let Ok(r) = reference_analysis(scene, &p, Tmin::Uniform(t_min), true) else {
            continue;
        };
        let mut est = Estimator::new(scene).unwrap();
        let e = *est.update(&Pose::at(p), Tmin::Uniform(t_min));
        assert!(
            e.is_ok(),
            "pose {p:?} t_min {t_min}: dense solved but real-time says {:?}",
            e.error
        );
        for (a, b) in e.tensions().iter().zip(&r.tensions_n) {
            assert!(
                (a - b).abs() <= 1e-9 * b.abs().max(1.0),
                "tension {a} vs clarabel {b} at {p:?}"
            );
        }
        let l1 = r.modes.lambda[0];
        let tol1 = 0.5 * (8.0 * dense_relative_accuracy(l1, r.modes.lambda_max)) + 1e-10;
        let err1 = (e.f1_hz - lambda_to_hz(l1)).abs() / e.f1_hz;
        assert!(
            err1 <= tol1,
            "f1 at {p:?}: {} vs dense {}: {err1:.2e} > {tol1:.2e}",
            e.f1_hz,
            lambda_to_hz(l1)
        );
        worst_f1 = worst_f1.max(err1 / tol1);
        let (k, lee) = r
            .modes
            .first_ee_mode(thr)
            .expect("dense has an end-effector mode");
        // Skip poses where the dense participation is within 1e-3 of the threshold (the
        // mode's character is ambiguous to the dense solver's own accuracy).
        let near = r.modes.ee_participation[..=k]
            .iter()
            .any(|&q| (q - thr).abs() < 1e-3);
        if !near {
            let tol = 0.5 * (8.0 * dense_relative_accuracy(lee, r.modes.lambda_max)) + 1e-10;
            let err = (ee_hz(&e) - lambda_to_hz(lee)).abs() / ee_hz(&e);
            assert!(
                err <= tol,
                "ee mode at {p:?}: {} vs dense {} (mode {}): {err:.2e}",
                ee_hz(&e),
                lambda_to_hz(lee),
                k + 1
            );
            worst_ee = worst_ee.max(err / tol);
        }
        checked += 1;
    }
    assert_eq!(checked, count, "not enough feasible poses");
    (checked, worst_f1, worst_ee)
}

/// Random poses per scene and model in the default suite; [`slow`] checks
/// [`SLOW_POSES`] more (other seeds), so that 1000 per scene and model are checked in CI.
const POSES: usize = 200;
/// The poses of the slow sweeps, per scene and model.
const SLOW_POSES: usize = 800;
/// Added to a test's seed for its slow sweep.
const SLOW_SEED: u64 = 100;

fn spatial_fem_n10(count: usize, seed: u64) {
    let s = Scene::default_scene().with_model(ElementKind::Fem, 10);
    let (n, a, b) = random_poses_agree(&s, count, seed);
    eprintln!("spatial FEM N=10: {n} poses, worst error / tolerance: f1 {a:.2e}, ee {b:.2e}");
}

fn spatial_catenary_n4(count: usize, seed: u64) {
    let s = Scene::default_scene().with_model(ElementKind::Catenary, 4);
    let (n, a, b) = random_poses_agree(&s, count, seed);
    eprintln!("spatial catenary N=4: {n} poses, worst error / tolerance: f1 {a:.2e}, ee {b:.2e}");
}

fn planar_fem_and_catenary_n10(count: usize, seed: u64) {
    for el in [ElementKind::Fem, ElementKind::Catenary] {
        let s = Scene::planar_paper().with_model(el, 10);
        let (n, a, b) = random_poses_agree(&s, count, seed);
        eprintln!("planar {el:?} N=10: {n} poses, worst error / tolerance: f1 {a:.2e}, ee {b:.2e}");
    }
}

#[test]
fn spatial_random_poses_fem_n10() {
    spatial_fem_n10(POSES, 1);
}

#[test]
fn spatial_random_poses_catenary_n4() {
    spatial_catenary_n4(POSES, 2);
}

#[test]
fn planar_random_poses_fem_and_catenary_n10() {
    planar_fem_and_catenary_n10(POSES, 3);
}

/// The random-pose checks on [`SLOW_POSES`] more poses per scene and model (a dense
/// eigen-solve with vectors per pose: minutes), run by `.ci/run` (tests/README.md, "Slow
/// reference sweeps").
mod slow {
    use super::*;

    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn spatial_random_poses_fem_n10() {
        spatial_fem_n10(SLOW_POSES, 1 + SLOW_SEED);
    }

    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn spatial_random_poses_catenary_n4() {
        spatial_catenary_n4(SLOW_POSES, 2 + SLOW_SEED);
    }

    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn spatial_random_poses_fem_n40_sample() {
        spatial_fem_n40(10, 4 + SLOW_SEED);
    }

    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn planar_random_poses_fem_and_catenary_n10() {
        planar_fem_and_catenary_n10(SLOW_POSES, 3 + SLOW_SEED);
    }
}

/// N = 40 (939 DOF: a dense solve with vectors takes ~0.7 s in release): the clustered
/// symmetric pose and one random pose here, 10 more in [`slow`].
fn spatial_fem_n40(count: usize, seed: u64) {
    let s = Scene::default_scene();
    let (n, a, b) = random_poses_agree(&s, count, seed);
    eprintln!("spatial FEM N=40: {n} poses, worst error / tolerance: f1 {a:.2e}, ee {b:.2e}");
}

#[test]
fn spatial_random_poses_fem_n40_sample() {
    spatial_fem_n40(2, 4);
}

#[test]
fn tracked_path_equals_cold_path_along_the_circle() {
    for (scene, n) in [
        (Scene::default_scene(), 40),
        (Scene::default_scene(), 10),
        (Scene::planar_paper(), 10),
    ] {
        for el in [
            ElementKind::Fem,
            ElementKind::Continuous,
            ElementKind::Catenary,
        ] {
            let s = scene.with_model(el, n);
            let mut warm = Estimator::new(&s).unwrap();
            let mut cold = Estimator::new(&s).unwrap();
            let mut warm_cycles = 0;
            for k in 0..4000 {
                let pose = circle_pose(&s, k, 4.0);
                let w = *warm.update(&pose, Tmin::Scene);
                cold.reset();
                let c = *cold.update(&pose, Tmin::Scene);
                assert!(w.is_ok() && c.is_ok());
                warm_cycles += (!w.cold_start) as usize;
                assert!(
                    (w.f1_hz - c.f1_hz).abs() <= 1e-11 * c.f1_hz,
                    "{el:?} N={n} cycle {k}: f1 {} vs {}",
                    w.f1_hz,
                    c.f1_hz
                );
                assert!(
                    (ee_hz(&w) - ee_hz(&c)).abs() <= 1e-10 * ee_hz(&c),
                    "{el:?} N={n} cycle {k}: ee {} (p {}) vs cold {} (p {})",
                    ee_hz(&w),
                    ee_p(&w),
                    ee_hz(&c),
                    ee_p(&c)
                );
                for (a, b) in w.tensions().iter().zip(c.tensions()) {
                    assert!((a - b).abs() <= 1e-10 * b);
                }
            }
            assert!(
                warm_cycles > 3990,
                "warm start should be used along a smooth trajectory"
            );
        }
    }
}
