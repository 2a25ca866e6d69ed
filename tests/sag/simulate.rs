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
