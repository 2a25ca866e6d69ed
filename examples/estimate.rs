//! The real-time estimator from Rust: f1 and tensions along a line through the paper's
//! spatial robot (the README's example; `cargo run --release --example estimate`).

use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::scene::Scene;
use nalgebra::Vector3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = Scene::load("spatial-paper")?; // an embedded name or a scene .toml
    let mut est = Estimator::new(&scene)?; // allocates here, never in `update`
    for i in 0..=4 {
        let x = -0.4 + 0.2 * i as f64; // m, along x through the default pose
        let pose = Pose::in_scene(&scene, Vector3::new(x, 0.0, 1.25));
        let e = est.update(&pose, Tmin::Scene); // one control cycle
        let (f1, t) = (e.f1_hz, e.tensions());
        println!("x {x:+.1} m: {:?}, f1 {f1:.4} Hz, T {t:.1?} N", e.status);
    }
    Ok(())
}
