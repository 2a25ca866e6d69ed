//! `cablevib analyze --sag true` with a hidden cable behind every anchor: it answers (exit
//! 0, status ok) and prints the library estimator's f1 and its tensions bit for bit, and
//! the model's size with the hidden cables' DOFs; the
//! library's sagged model with hidden cables is checked against an independent dense FEM in
//! the core crate's tests/model/hidden_models.rs.

use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::scene::{Scene, DEFAULT_SCENE_TOML};
use std::path::Path;
use std::process::Command;

/// The numbers of the JSON array `key` in `analyze --json`'s text, parsed from their own
/// digits.
fn json_numbers(text: &str, key: &str) -> Vec<f64> {
    let start = text.find(&format!("\"{key}\":[")).expect(key) + key.len() + 4;
    let end = start + text[start..].find(']').unwrap();
    text[start..end]
        .split(',')
        .map(|x| x.parse::<f64>().unwrap())
        .collect()
}

/// The number of the JSON field `key`, parsed from its own digits.
fn json_number(text: &str, key: &str) -> f64 {
    let start = text.find(&format!("\"{key}\":")).expect(key) + key.len() + 3;
    let end = start + text[start..].find([',', '}']).unwrap();
    text[start..end].parse().unwrap()
}

#[test]
fn analyze_with_sag_and_hidden_cables_answers_as_the_library() {
    let text = DEFAULT_SCENE_TOML.replacen(
        "area = 50.265e-6",
        "area = 50.265e-6\nhidden_length = 2.5",
        1,
    );
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("hidden-sag");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("paper_hidden.toml");
    std::fs::write(&file, &text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_cablevib"))
        .args(["analyze", file.to_str().unwrap(), "--sag", "true", "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed = String::from_utf8(out.stdout).unwrap();
    let mut s = Scene::from_toml_str(&text, "paper_hidden.toml").unwrap();
    assert!(s.has_hidden_cable());
    s.set_sag(true).unwrap();
    let mut est = Estimator::new(&s).unwrap();
    let e = *est.update(
        &Pose {
            position_m: s.ee_position_m,
            orientation_wxyz: s.ee_orientation_wxyz,
        },
        Tmin::Scene,
    );
    assert!(e.is_ok(), "{:?}", e.error);
    // The printed modes are the structured solver's (`modes`), f1 the cycle's first root:
    // the same root to their Newton tolerances (~1e-12).
    let f1 = json_numbers(&printed, "frequencies_hz")[0];
    assert!((f1 - e.f1_hz).abs() <= 1e-10 * f1, "{f1} vs {}", e.f1_hz);
    let t = json_numbers(&printed, "tensions_n");
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&t), bits(e.tensions()));
    // The model's size: the end-effector, 39 interior nodes of 3 DOF per free cable (fem ×
    // 40) and 40 axial DOF per hidden cable (39 interior nodes and the junction). It
    // printed 939, the model without its hidden cables.
    let dof = json_number(&printed, "dof");
    assert_eq!(dof, (3 + 8 * (3 * 39 + 40)) as f64);
}

/// `simulate --sag true` with hidden cables: the sagged mode shapes start every chain at a
/// fixed anchor, so on a hidden cable (a moving junction) they are refused in one line, not
/// drawn wrong.
#[test]
fn simulate_with_sag_and_hidden_cables_is_refused_in_one_line() {
    let text = DEFAULT_SCENE_TOML.replacen(
        "area = 50.265e-6",
        "area = 50.265e-6\nhidden_length = 2.5",
        1,
    );
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("hidden-sag-simulate");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("paper_hidden.toml");
    std::fs::write(&file, &text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_cablevib"))
        .args([
            "simulate",
            file.to_str().unwrap(),
            "--sag",
            "true",
            "--move",
            "0.1,0,0",
            "--duration",
            "0.2",
            "--modes",
            "4",
            "--out",
            dir.join("sim").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "simulate answered: {err}");
    assert!(err.contains("hidden cable"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}
