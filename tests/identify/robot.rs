//! cablevib's own robot model under white-noise forcing: the paper's spatial robot (massless
//! cables: the end-effector's three modes) at an unsymmetric pose, its end-effector moved by
//! modal superposition ([`cablevib::modal::response::ModalResponse`], exact for a force
//! linear over each step) under white-noise forces, 60 s at 1 kHz, the three displacements
//! measured with 20 dB sensor noise. The reference: the dense eigen-solve of the pose's
//! assembled (K, M) and the modal damping ratio given to the simulation.

use cablevib::estimator::{Estimator, PoseModel, Tmin};
use cablevib::identify::{identify, IdentifyParams, WindowStatus};
use cablevib::kinematics::Pose;
use cablevib::modal::dense_modes_ee;
use cablevib::modal::response::ModalResponse;
use cablevib::scene::{Damping, Scene};
use cablevib_testkit::modal_record::{check_modes, gauss};
use cablevib_testkit::Rng;
use nalgebra::{Vector3, Vector6};

#[test]
fn spatial_robot_modes_under_white_noise() {
    let root = env!("CARGO_MANIFEST_DIR");
    let text = std::fs::read_to_string(format!("{root}/scenes/spatial_paper.toml")).unwrap();
    let text = text.replace("element = \"fem\"", "element = \"massless\"");
    let mut scene = Scene::from_toml_str(&text, "spatial_paper.toml").unwrap();
    scene.ee_position_m = Vector3::new(0.3, 0.2, 1.0);
    let zeta = 0.01;
    // The reference: the dense model's frequencies.
    let pm = PoseModel::new(&scene).unwrap();
    let (k, m) = pm.dense().unwrap();
    let dm = dense_modes_ee(&k, &m, &pm.ee_mass(), pm.dim(), false).unwrap();
    let truth_hz: Vec<f64> = dm
        .lambda
        .iter()
        .map(|l| l.sqrt() / (2.0 * std::f64::consts::PI))
        .collect();
    println!("dense model: {truth_hz:?} Hz");
    assert_eq!(truth_hz.len(), 3);
    // The simulation: the estimator's modal basis at the pose.
    let mut est = Estimator::new(&scene).unwrap();
    let pose = Pose::in_scene(&scene, scene.ee_position_m);
    assert!(est.update(&pose, Tmin::Scene).status.is_ok());
    let b = est.ee_modal_basis(3).unwrap();
    let mut resp = ModalResponse::new(b.dim);
    resp.set_basis(
        &b.lambda,
        &b.phi_ee,
        &Damping::ModalRatio { zeta },
        &b.flexibility,
        &b.ee_mass,
    )
    .unwrap();
    let (rate, dur) = (1000.0, 60.0);
    let h = 1.0 / rate;
    let n = (rate * dur) as usize;
    let burn = (20.0 * rate) as usize;
    let mut r = Rng(5);
    let force = |r: &mut Rng| Vector6::new(gauss(r), gauss(r), gauss(r), 0.0, 0.0, 0.0);
    let mut f0 = force(&mut r);
    let mut y = Vec::with_capacity(3 * n);
    for k in 0..burn + n {
        let f1 = force(&mut r);
        resp.step(&f0, &f1, h);
        f0 = f1;
        if k >= burn {
            let u = resp.displacement(&f0);
            y.extend([u[0], u[1], u[2]]);
        }
    }
    for c in 0..3 {
        let var = (0..n).map(|k| y[3 * k + c].powi(2)).sum::<f64>() / n as f64;
        let sd = (var / 100.0).sqrt();
        for k in 0..n {
            y[3 * k + c] += sd * gauss(&mut r);
        }
    }
    let t: Vec<f64> = (0..n).map(|k| k as f64 * h).collect();
    let p = IdentifyParams {
        to_hz: 1.5 * truth_hz[2],
        ..IdentifyParams::default()
    };
    let w = identify(&t, &y, 3, &p).unwrap();
    assert_eq!(w[0].status, WindowStatus::Ok);
    check_modes(&w[0].modes, &truth_hz, &[zeta; 3], dur);
}
