//! `analyze --realtime` is the service's first cycle: the estimator with the real-time preset
//! (`EstimatorParams::realtime()`, its per-cycle budget of D(λ) evaluations), so what it
//! prints is what `serve` would publish for the same pose from a cold start. Checked against
//! the library's `Estimator::realtime` at the same pose: every number equal to the bit, the
//! evaluations within the budget (with the offline parameters the paper robot's cold cycle
//! took 79 evaluations and suspended-8's 11 490, and the end-effector mode came out where the
//! service leaves it for the next cycles).

use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::modal::CYCLE_EVALUATIONS;
use cablevib::scene::Scene;
use std::process::Command;

fn realtime_json(scene: &str) -> serde_json::Value {
    let o = Command::new(env!("CARGO_BIN_EXE_cablevib"))
        .args(["analyze", scene, "--realtime", "--json"])
        .output()
        .expect("run cablevib");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("JSON")
}

/// JSON's number (null for a NaN) as f64 bits.
fn bits(v: &serde_json::Value) -> Option<u64> {
    v.as_f64().map(f64::to_bits)
}

#[test]
fn analyze_realtime_is_the_services_cold_cycle() {
    for name in ["spatial-paper", "planar-paper", "suspended-8"] {
        let json = realtime_json(name);
        let scene = Scene::load(name).unwrap();
        let mut est = Estimator::realtime(&scene).unwrap();
        let e = *est.update(&Pose::in_scene(&scene, scene.ee_position_m), Tmin::Scene);
        assert!(e.is_ok(), "{name}: {:?}", e.error);
        let evaluations = json["eigen_evaluations"].as_u64().unwrap();
        assert!(
            evaluations <= u64::from(CYCLE_EVALUATIONS),
            "{name}: {evaluations} evaluations of D(λ), over the cycle's budget {CYCLE_EVALUATIONS}"
        );
        assert_eq!(evaluations, u64::from(e.eigen_evaluations), "{name}");
        assert_eq!(bits(&json["f1_hz"]), Some(e.f1_hz.to_bits()), "{name}: f1");
        let ee = e.ee_mode.map(|m| m.frequency_hz.to_bits());
        assert_eq!(bits(&json["ee_mode_hz"]), ee, "{name}: end-effector mode");
        let age = json["ee_mode_age_cycles"].as_u64();
        assert_eq!(age, e.ee_mode.map(|m| u64::from(m.age_cycles)), "{name}");
        let tensions: Vec<Option<u64>> = json["tensions_n"]
            .as_array()
            .unwrap()
            .iter()
            .map(bits)
            .collect();
        let want: Vec<Option<u64>> = e.tensions().iter().map(|t| Some(t.to_bits())).collect();
        assert_eq!(tensions, want, "{name}: tensions");
    }
}
