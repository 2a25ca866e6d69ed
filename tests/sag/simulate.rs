//! `simulate` with sag (suspended-8, FEM chains): the residual vibration after a stop must
//! not depend on how often the modal basis is updated at rest. With the end-effector's
//! projection as the only state carried across an update, the cable-borne modes of this
//! robot (end-effector participation ≤ 0.1) lost most of their motion at each update, so the
//! residual p-p fell with the update rate (and died out within 0.1 s of the stop); carried
//! by the mass overlap of the whole shapes (`ModalResponse::set_basis_projected`) it must
//! agree within 1e-3 between updates every 10 and every 40 samples (measured 4.3e-5; the path's
//! acceleration is piecewise linear between the updates either way; what differs is when
//! the frequencies are refreshed during the move).  

use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::scene::{ElementKind, Scene};
use cablevib::study::simulate::{simulate, SampledPath, SimulateConfig};
use cablevib::trajectory::moves::{Move, Profile};
use cablevib_testkit::exact_response::{
    assert_default_within_tolerance, assert_update_policy_within_tolerance,
};

/// suspended-8 with sag (FEM chains, N = 10): `simulate`'s default modes meet its default
/// tolerance at a frozen pose against the exact all-mode integration of the crate's dense
/// sagged model (`Estimator::dense_matrices`, every mode) loaded along the path's field
/// (testkit's `sag_field` reference), ζ = 2 %, Rayleigh with the high modes overdamped and
/// ζ = 1.5 (testkit's `exact_response`).
#[test]
fn sagged_default_modes_meet_the_tolerance_at_a_frozen_pose() {
    let mut scene = Scene::load("scenes/suspended_8.toml").unwrap();
    scene.model.sag = true;
    scene.model.element = ElementKind::Fem;
    scene.model.elements_per_cable = 10;
    let mut est = Estimator::new(&scene).unwrap();
    let e = *est.update(&Pose::in_scene(&scene, scene.ee_position_m), Tmin::Scene);
    assert!(e.is_ok(), "{:?}", e.error);
    let (k, m) = est.dense_matrices().unwrap();
    assert_default_within_tolerance(
        "suspended-8 sag",
        &mut est,
        &k,
        &m,
        nalgebra::Vector3::new(0.3, 0.0, 0.0),
    );
}

/// suspended-8 with sag (FEM chains, N = 10, ζ = 1 %) and its S-curve of 0.3 m along x in
/// 0.5 s, sampled at 1 ms.
fn sagged_s_curve() -> (Scene, SampledPath) {
    let mut scene = Scene::load("scenes/suspended_8.toml").unwrap();
    scene.model.sag = true;
    scene.model.element = ElementKind::Fem;
    scene.model.elements_per_cable = 10;
    scene.damping = cablevib::scene::Damping::ModalRatio { zeta: 0.01 };
    let dt = 1e-3;
    let mv = Move::new(
        scene.ee_position_m,
        nalgebra::Vector3::new(0.3, 0.0, 0.0),
        0.5,
        Profile::SCurve,
    )
    .unwrap();
    let path = SampledPath {
        dt_s: dt,
        positions_m: mv.sampled(dt, 0.0).unwrap().position_m,
        at_rest_ends: true,
    };
    (scene, path)
}

#[test]
fn sagged_residual_does_not_depend_on_the_update_rate() {
    let (scene, path) = sagged_s_curve();
    let mut pp = Vec::new();
    for every in [10usize, 40] {
        let cfg = SimulateConfig {
            modes: Some(8),
            update_every: Some(every),
            settle_s: 1.0,
            ..SimulateConfig::default()
        };
        let r = simulate(&scene, &path, &cfg).unwrap();
        assert!(r.structured);
        let stop = r.stops.last().unwrap();
        pp.push(stop.peak_to_peak_max_m());
    }
    let rel = (pp[0] - pp[1]).abs() / pp[0];
    eprintln!(
        "suspended-8 sag residual p-p: {:.4e} m (every 10), {:.4e} m (every 40), {rel:.2e}",
        pp[0], pp[1]
    );
    assert!(rel < 1e-3, "{pp:?}");
}

mod slow {
    use super::*;

    /// The default update policy on suspended-8's sagged S-curve (0.3 m in 0.5 s, ζ = 1 %,
    /// 2 s at rest) against updates at every sample, the same K (2 501 sagged bases of 147
    /// modes: about a minute and a half of CPU). Counting one interval's phase error alone,
    /// 22 updates left 2.05e-3 of the peak (main's binary, the same computation); the
    /// ringing's accumulated phase error counted (`study::simulate::updates`), 162 updates,
    /// 1.4e-4.
    #[test]
    #[ignore = "slow reference sweep: the sagged S-curve updated at every sample"]
    fn sagged_default_update_policy_within_the_tolerance() {
        let (scene, path) = sagged_s_curve();
        assert_update_policy_within_tolerance("suspended-8 sag S-curve", &scene, &path, 2.0, 0.1);
    }
}

/// `simulate_forced`'s external force acts on the end-effector: mode k takes φ_kᵀ P and the
/// static answer is F P (`study::simulate::added_load`), not the inertial load's shapes ψ_k
/// and F_ψ, which stand for a load on every cable node. On the heavy paper robot with sag
/// (cables 50 × the paper's weight, fem × 10, its centre; ζ = 2 %) at rest, a half-sine
/// pulse of 20 N for 30 ms then 0.3 s free, against the exact all-mode response of the
/// crate's dense sagged (K, M) to that force on the end-effector's DOFs (testkit's
/// `exact_response`, every mode, the test's own propagation): within the default tolerance
/// (1e-3 of the peak, `simulate`'s default K and updates). Through ψ (what the loop did
/// before) the response is off by about the cables' share of the quasi-static mass
/// (printed, asserted above 1e-2: the test sees the difference).
#[test]
fn an_end_effector_force_acts_through_the_end_effector_shapes() {
    use cablevib::study::simulate::simulate_forced;
    use cablevib_testkit::exact_response::{crate_response, exact_response, relative_error};
    use cablevib_testkit::sag_cases::{heavy_paper, sagged_fem};
    use nalgebra::{Vector3, Vector6};
    let mut scene = sagged_fem(heavy_paper(), 10);
    let damping = cablevib::scene::Damping::ModalRatio { zeta: 0.02 };
    scene.damping = damping;
    let p = scene.ee_position_m;
    let mut est = Estimator::new(&scene).unwrap();
    let e = *est.update(&Pose::in_scene(&scene, p), Tmin::Scene);
    assert!(e.is_ok(), "{:?}", e.error);
    let (k, m) = est.dense_matrices().unwrap();
    let dt = 1e-3;
    let n = 331;
    let dir = Vector3::new(1.0, 2.0, -1.5).normalize();
    let force = |s: usize| {
        let t = s as f64 * dt;
        let f = if t < 0.03 {
            20.0 * (std::f64::consts::PI * t / 0.03).sin()
        } else {
            0.0
        };
        dir * f
    };
    let path = SampledPath {
        dt_s: dt,
        positions_m: vec![p; n],
        at_rest_ends: true,
    };
    let cfg = SimulateConfig {
        settle_s: 0.0,
        ..SimulateConfig::default()
    };
    let got = simulate_forced(&scene, &path, &cfg, force).unwrap();
    let loads: Vec<Vector6<f64>> = (0..n)
        .map(|s| {
            let f = force(s);
            Vector6::new(f.x, f.y, f.z, 0.0, 0.0, 0.0)
        })
        .collect();
    let (exact, _) = exact_response(&k, &m, 3, &damping, &loads, dt);
    let error = relative_error(&got.response.deviation_m, &exact);
    // The same force through the inertial load's shapes ψ and F_ψ, the modes simulate kept.
    let (through_psi, _) = crate_response(&mut est, got.response.modes, &damping, &loads, dt, true);
    let psi_error = relative_error(&through_psi, &exact);
    let peak = exact.iter().fold(0.0f64, |a, u| a.max(u.norm()));
    println!(
        "heavy paper robot with sag, end-effector pulse: K = {}, peak {peak:.4e} m, simulate_forced {error:.2e} of the peak; through ψ {psi_error:.2e}",
        got.response.modes
    );
    assert!(error <= 1e-3, "{error:e}");
    assert!(psi_error > 1e-2, "{psi_error:e}");
}
