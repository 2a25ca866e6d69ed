//! `cablevib analyze --sag true` with a hidden cable behind every anchor: it answers (exit
//! 0, status ok) and prints the library estimator's f1 and its tensions bit for bit, and
//! the model's size with the hidden cables' DOFs; `simulate`, `frf --modal-ratio` and
//! `shape` with sag and hidden cables answer from the sagged structured shapes; the
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

/// The default scene with 2.5 m of hidden cable under [cable], written for the CLI in
/// `dir`; its text.
fn hidden_scene(dir: &str) -> (std::path::PathBuf, String) {
    let text = DEFAULT_SCENE_TOML.replacen(
        "area = 50.265e-6",
        "area = 50.265e-6\nhidden_length = 2.5",
        1,
    );
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("paper_hidden.toml");
    std::fs::write(&file, &text).unwrap();
    (file, text)
}

/// `simulate --sag true` with hidden cables: its modal basis is the sagged structured
/// shapes with the junctions and the hidden cables (checked against the dense eigenvectors
/// with explicit hidden nodes in the core crate's tests/sag/shapes.rs), not a refusal and
/// not the dense fallback: it answers, says "structured engine" and that the cables'
/// inertia is not applied to sagging cables over pulleys, and writes its CSV.
#[test]
fn simulate_with_sag_and_hidden_cables_uses_the_structured_shapes() {
    let (file, _) = hidden_scene("hidden-sag-simulate");
    let out_base = file.with_file_name("sim");
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
            out_base.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "simulate failed: {err}");
    let printed = String::from_utf8(out.stdout).unwrap();
    assert!(printed.contains("(structured engine)"), "{printed}");
    // Sagging cables over pulleys take the end-effector's load alone, and say so.
    assert!(
        printed.contains("note: cable inertia not applied to sagging cables over pulleys"),
        "{printed}"
    );
    assert!(out_base.with_extension("csv").exists());
}

/// `frf --sag true --modal-ratio` with hidden cables (modal superposition of the sagged
/// structured shapes): it answers and prints the library's modal sum, the estimator's
/// structured basis (`ee_modal_basis`, the sizes the command takes: 16 modes cover
/// 4 × 4 Hz) through `ModalBasis::from_modes`, to 1e-12 relative of the largest entry (the
/// JSON's shortest round-trip digits are exact; the two runs do the same arithmetic).
#[test]
fn frf_with_modal_damping_sag_and_hidden_cables_is_the_librarys_modal_sum() {
    let (file, text) = hidden_scene("hidden-sag-frf");
    let mut s = Scene::from_toml_str(&text, "paper_hidden.toml").unwrap();
    s.set_sag(true).unwrap();
    let args = ["--sag", "true", "--to-hz", "4", "--points", "5"];
    frf_is_the_librarys_modal_sum(&file, &args, &s, 5, &[16]);
}

/// Run `frf FILE --modal-ratio 0.02 --json` with `extra` arguments; it answers with
/// `points` frequencies whose receptance's real part is the library's modal sum of the
/// estimator's structured basis for `scene` at its pose, built through the sizes `sizes`
/// (the last is the command's; each from the state the one before leaves), to 1e-12
/// relative of the largest diagonal entry (same arithmetic, exact JSON digits).
fn frf_is_the_librarys_modal_sum(
    file: &Path,
    extra: &[&str],
    scene: &Scene,
    points: usize,
    sizes: &[usize],
) {
    let zeta = 0.02;
    let out = Command::new(env!("CARGO_BIN_EXE_cablevib"))
        .args([
            "frf",
            file.to_str().unwrap(),
            "--modal-ratio",
            "0.02",
            "--json",
        ])
        .args(extra)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed = String::from_utf8(out.stdout).unwrap();
    let freqs = json_numbers(&printed, "frequencies_hz");
    assert_eq!(freqs.len(), points);
    // N × 3 × 3 nested arrays: the numbers up to the closing "]]]".
    let key = "\"receptance_re\":";
    let start = printed.find(key).unwrap() + key.len();
    let end = start + printed[start..].find("]]]").unwrap();
    let re: Vec<f64> = printed[start..end]
        .split(['[', ']', ','])
        .filter(|x| !x.is_empty())
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(re.len(), points * 9);
    let mut est = Estimator::new(scene).unwrap();
    let e = *est.update(
        &Pose {
            position_m: scene.ee_position_m,
            orientation_wxyz: scene.ee_orientation_wxyz,
        },
        Tmin::Scene,
    );
    assert!(e.is_ok(), "{:?}", e.error);
    let (last, before) = sizes.split_last().unwrap();
    for &k in before {
        est.ee_modal_basis(k).unwrap();
    }
    let b = est.ee_modal_basis(*last).unwrap();
    assert!(b.structured);
    let mb =
        cablevib::modal::ModalBasis::from_modes(b.lambda, b.phi_ee, &b.flexibility, b.dim).unwrap();
    for (q, &f) in freqs.iter().enumerate() {
        let h = mb.receptance(zeta, 2.0 * std::f64::consts::PI * f);
        let scale = (0..3).fold(0.0f64, |a, r| a.max(h[(r, r)].re.abs()));
        for r in 0..3 {
            for c in 0..3 {
                let got = re[9 * q + 3 * r + c];
                assert!(
                    (got - h[(r, c)].re).abs() <= 1e-12 * scale,
                    "{f} Hz H[{r}{c}]: {got} vs {}",
                    h[(r, c)].re
                );
            }
        }
    }
}

/// `shape --scene FILE` with sag (in the file) and hidden cables: it answers and writes the
/// shaped trajectory.
#[test]
fn shape_with_sag_and_hidden_cables_answers() {
    let (file, text) = hidden_scene("hidden-sag-shape");
    std::fs::write(&file, text.replacen("sag = false", "sag = true", 1)).unwrap();
    let csv = file.with_file_name("shaped.csv");
    let out = Command::new(env!("CARGO_BIN_EXE_cablevib"))
        .args([
            "shape",
            "--scene",
            file.to_str().unwrap(),
            "--move",
            "0.1,0,0",
            "-o",
            csv.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(csv.exists());
}

/// `frf --sag true --modal-ratio 0.02` on the paper robot over the default band (0.5 …
/// 50 Hz, 1000 points): its basis passes the near-doubles at 79.6 Hz (resolved as a
/// near-cluster, not refused) and the printed receptance is the library's modal sum (the
/// estimator's structured basis after the sizes 16 … 256 the command doubles through)
/// to 1e-12 relative of the largest diagonal entry (same arithmetic, exact JSON digits).
#[test]
fn frf_with_modal_damping_and_sag_over_the_default_band_is_the_librarys_modal_sum() {
    let text = DEFAULT_SCENE_TOML.replacen("sag = false", "sag = true", 1);
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("sag-frf-default-band");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("paper_sag.toml");
    std::fs::write(&file, &text).unwrap();
    let s = Scene::from_toml_str(&text, "paper_sag.toml").unwrap();
    // The sizes the command doubles through.
    frf_is_the_librarys_modal_sum(&file, &[], &s, 1000, &[16, 32, 64, 128, 256]);
}

/// `frf --modal-ratio 0.02` with sag on the large robots: suspended-8 over the default band
/// (0.5 … 50 Hz) and fast-like up to 5 Hz. Before, both were refused ("not an eigenvalue
/// of multiplicity 1", then 3 and 6): above a chain's transverse cut-off the shapes'
/// forward solutions all turned towards the growing one and the bordered system lost its
/// null space. Expected: it answers, and its receptance (real and imaginary parts) is the
/// modal sum of the dense eigenpairs (the dense K and M of the same pose, mass-normalised
/// eigenvectors, the static flexibility condensed from the dense K) over as many modes as
/// the command's structured basis holds (the estimator's basis through the sizes the
/// command doubles through), within 1e-6 of the largest diagonal entry at each frequency
/// (the dense eigenvectors of the near-clusters are the least accurate part: measured
/// below 2e-9).
#[test]
fn frf_with_modal_damping_on_the_large_sagging_robots_equals_the_dense_modal_sum() {
    use cablevib::modal::{condense_static, lambda_to_hz, ModalBasis, MAX_FRF_MODES};
    use nalgebra::{Matrix6, Vector6};
    for (name, extra, to_hz) in [
        ("suspended-8", &[][..], 50.0),
        ("fast-like", &["--sag", "true", "--to-hz", "5"][..], 5.0),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_cablevib"))
            .args([
                "frf",
                name,
                "--modal-ratio",
                "0.02",
                "--points",
                "40",
                "--json",
            ])
            .args(extra)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let freqs: Vec<f64> = serde_json::from_value(json["frequencies_hz"].clone()).unwrap();
        let re: Vec<Vec<Vec<f64>>> = serde_json::from_value(json["receptance_re"].clone()).unwrap();
        let im: Vec<Vec<Vec<f64>>> = serde_json::from_value(json["receptance_im"].clone()).unwrap();
        let mut s = Scene::load(name).unwrap();
        s.set_sag(true).unwrap();
        let mut est = Estimator::new(&s).unwrap();
        let e = *est.update(&Pose::at(s.ee_position_m), Tmin::Scene);
        assert!(e.is_ok(), "{name}: {:?}", e.error);
        // The command's basis size: doubling from 16 until a mode lies above 4 × to_hz.
        let (k, m) = est.dense_matrices().unwrap();
        let cap = MAX_FRF_MODES.min(k.nrows()).max(1);
        let mut size = 16usize.min(cap);
        let kept = loop {
            let b = est.ee_modal_basis(size).unwrap();
            if b.lambda.last().map_or(0.0, |&l| lambda_to_hz(l)) > 4.0 * to_hz || size >= cap {
                break b.lambda.len();
            }
            size = (2 * size).min(cap);
        };
        let dim = 3;
        let (lam, u) = cablevib_testkit::dense_fem::dense_eig(&k, &m);
        let phi: Vec<Vector6<f64>> = (0..kept)
            .map(|c| {
                let mut p = Vector6::zeros();
                for r in 0..dim {
                    p[r] = u[(r, c)];
                }
                p
            })
            .collect();
        let kd = condense_static(&k, dim);
        let mut flex = Matrix6::zeros();
        let inv = kd
            .fixed_view::<3, 3>(0, 0)
            .into_owned()
            .try_inverse()
            .unwrap();
        flex.fixed_view_mut::<3, 3>(0, 0).copy_from(&inv);
        let mb = ModalBasis::from_modes(lam[..kept].to_vec(), phi, &flex, dim).unwrap();
        let mut worst = 0.0f64;
        for (q, &f) in freqs.iter().enumerate() {
            let h = mb.receptance(0.02, 2.0 * std::f64::consts::PI * f);
            let scale = (0..3).fold(0.0f64, |a, r| a.max(h[(r, r)].norm()));
            for r in 0..3 {
                for c in 0..3 {
                    let err = (re[q][r][c] - h[(r, c)].re)
                        .abs()
                        .max((im[q][r][c] - h[(r, c)].im).abs())
                        / scale;
                    assert!(err <= 1e-6, "{name} {f} Hz H[{r}{c}]: {err:.2e}");
                    worst = worst.max(err);
                }
            }
        }
        eprintln!(
            "{name}: frf --modal-ratio over {kept} modes within {worst:.2e} of the dense modal sum"
        );
    }
}
