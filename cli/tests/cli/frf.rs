//! `cablevib frf`: the JSON layout (N × d × d, translations first) checked against the
//! library's receptance (independent of the command's formatting), the exactness check
//! `--dense` on a small model, and hostile ranges and damping values: one-line errors, no
//! panic.

use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

fn run(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("the binary runs")
}

/// The JSON's receptance at each frequency is the library's `ModalSolver::receptance` at the
/// same pose and damping (an independent path: the library called directly).
#[test]
fn json_is_the_library_receptance() {
    let o = run(&[
        "frf",
        "spatial-paper",
        "--elements",
        "10",
        "--loss-factor",
        "0.02",
        "--from-hz",
        "1",
        "--to-hz",
        "40",
        "--points",
        "5",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let f = v["frequencies_hz"].as_array().unwrap();
    assert_eq!(f.len(), 5);
    assert_eq!(f[0].as_f64(), Some(1.0));
    assert_eq!(f[4].as_f64(), Some(40.0));
    let re = v["receptance_re"].as_array().unwrap();
    assert_eq!(re.len(), 5);
    assert_eq!(re[0].as_array().unwrap().len(), 3);
    let mut s = cablevib::scene::Scene::default_scene();
    s.model.element = cablevib::scene::ElementKind::Fem;
    s.model.elements_per_cable = 10;
    let p = cablevib::estimator::PoseModel::new(&s).unwrap();
    let mut solver = cablevib::modal::ModalSolver::new(Default::default());
    p.load(&mut solver);
    let d = cablevib::scene::Damping::LossFactor { eta: 0.02 };
    for (k, fk) in f.iter().enumerate() {
        let w = 2.0 * std::f64::consts::PI * fk.as_f64().unwrap();
        let h = solver.receptance(&d, w).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let r = v["receptance_re"][k][i][j].as_f64().unwrap();
                let im = v["receptance_im"][k][i][j].as_f64().unwrap();
                assert_eq!((r, im), (h[(i, j)].re, h[(i, j)].im), "f {fk} ({i}, {j})");
            }
        }
    }
}

/// `--dense` prints the dense complex solve's difference: below 1e-9 on N = 10.
#[test]
fn dense_check_agrees() {
    let o = run(&[
        "frf",
        "spatial-paper",
        "--elements",
        "10",
        "--rayleigh",
        "0.5,2e-4",
        "--points",
        "20",
        "--dense",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let e = v["dense_max_rel_diff"].as_f64().unwrap();
    assert!(e < 1e-9, "{e}");
}

/// `--dense-modal`: the dense receptance by summation over every mode of the assembled
/// (K, M) (one dense eigendecomposition) at every frequency, and the dense complex LU (an
/// independent formulation: no eigenvectors) at five of them; spatial robot, fem N = 10
/// (219 DOF), 200 frequencies 0.5-50 Hz through the 32.4 Hz resonance.
///
/// Bounds: the summation inherits the dense eigensolver's absolute eigenvalue error
/// ε·λ_max, relative ε·λ_max/|c λ_r − c_M| near a resonance (≈ 1e-10/η at N = 10):
/// 1e-8 asserted for it (4.8e-10 measured on 1 000 frequencies, η = 0.02); the structured
/// receptance against the LU 1e-9, as the `--dense` check (2.5e-14 measured). With modal
/// damping the summation keeps every mode where the structured one keeps those below
/// 4 × 50 Hz and the static correction: 1e-7 (4.5e-9 measured).
#[test]
fn dense_modal_check_agrees() {
    for (damping, modal_bound, lu) in [
        (&["--loss-factor", "0.02"][..], 1e-8, true),
        (&["--rayleigh", "0.5,2e-4"][..], 1e-8, true),
        (&["--modal-ratio", "0.01"][..], 1e-7, false),
    ] {
        let mut args = vec![
            "frf",
            "spatial-paper",
            "--elements",
            "10",
            "--points",
            "200",
        ];
        args.extend_from_slice(damping);
        args.extend_from_slice(&["--dense-modal", "--dense-lu-points", "5", "--json"]);
        let o = run(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["dense_method"], "modal");
        assert_eq!(v["dense_dof"].as_u64(), Some(219));
        assert_eq!(v["dense_rel_diff"].as_array().unwrap().len(), 200);
        let e = v["dense_max_rel_diff"].as_f64().unwrap();
        assert!(e <= modal_bound, "{damping:?}: {e:e}");
        if lu {
            let f = v["dense_lu_frequencies_hz"].as_array().unwrap();
            assert_eq!(f.len(), 5, "{damping:?}");
            assert_eq!((f[0].as_f64(), f[4].as_f64()), (Some(0.5), Some(50.0)));
            let m = v["dense_lu_modal_max_rel_diff"].as_f64().unwrap();
            let s = v["dense_lu_structured_max_rel_diff"].as_f64().unwrap();
            assert!(m <= 1e-8, "{damping:?}: modal against LU {m:e}");
            assert!(s <= 1e-9, "{damping:?}: structured against LU {s:e}");
        } else {
            // modal damping has no matrix to factor: no LU spot check
            assert!(v.get("dense_lu_frequencies_hz").is_none(), "{damping:?}");
        }
    }
}

/// A ≥ B, NaN, 0 or too many points, a damping ratio ≥ 1 or < 0, a bad direction; with
/// sag, the continuous model:
/// exit code 1 and one line naming the cause.
#[test]
fn hostile_inputs_are_one_line_errors() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["--from-hz", "10", "--to-hz", "5"],
            "--to-hz 5 Hz: must be finite and above the lowest frequency, 10 Hz",
        ),
        (
            &["--from-hz", "5", "--to-hz", "5"],
            "--to-hz 5 Hz: must be finite and above",
        ),
        (&["--from-hz", "NaN"], "--from-hz NaN Hz: must be finite and >= 0"),
        (&["--to-hz", "inf"], "--to-hz inf Hz: must be finite"),
        (&["--points", "0"], "--points 0: must be in 1..=100000"),
        (&["--points", "100001"], "--points 100001: must be in 1..=100000"),
        (&["--log", "--from-hz", "0"], "--from-hz 0 Hz: a log-spaced band"),
        // A finite bound (the receptance underflows from ≈ 1e24 Hz, ω²M overflows from
        // ≈ 1e30 Hz): 1e308 gave null receptances and no natural frequency, exit 0.
        (
            &["--to-hz", "1e308"],
            "--to-hz 1e308 Hz: above the highest frequency of a response, 1e12 Hz",
        ),
        (&["--modal-ratio", "1"], "--modal-ratio 1"),
        (&["--modal-ratio", "-0.01"], "--modal-ratio -0.01"),
        (&["--loss-factor", "NaN"], "--loss-factor NaN"),
        (&["--rayleigh", "1,2"], "--rayleigh beta 2"),
        (
            &["--loss-factor", "0.1", "--modal-ratio", "0.1"],
            "give one of",
        ),
        (&["--input", "rx"], "--input `rx`"),
        (
            &["--modal-ratio", "0.01", "--dense"],
            "--dense: modal damping has no damping matrix to assemble (loss factor, Rayleigh or none); use --dense-modal",
        ),
        (
            &["--loss-factor", "0.1", "--rayleigh", "1,0"],
            "give one of --loss-factor, --rayleigh, --modal-ratio, --undamped",
        ),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["frf", "spatial-paper", "--elements", "4"];
        args.extend_from_slice(extra);
        let o = run(&args);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {err}");
        assert!(!err.contains("panicked"), "{extra:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{extra:?}: {err}");
        assert!(err.contains(needle), "{extra:?}: {err}");
    }
    // With sag: the continuous model is refused in one line (modal damping goes by the
    // sagged shapes' modal superposition: tests/sag/frf_modal.rs).
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/suspended_8.toml");
    let (extra, needle) = (
        &["--element", "continuous", "--loss-factor", "0.02"][..],
        "the frequency response with sag takes the fem element",
    );
    let mut args = vec!["frf", scene];
    args.extend_from_slice(extra);
    let o = run(&args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{extra:?}: {err}");
    assert_eq!(err.trim().lines().count(), 1, "{extra:?}: {err}");
    assert!(err.contains(needle), "{extra:?}: {err}");
}

/// With sag (suspended-8, FEM chains on the catenary, N = 6): `--dense` solves the
/// assembled sagged complex problem at every frequency; the command's own comparison is
/// within 1e-8 on an even grid that passes near resonances (η = 0.02 keeps κ ≲ 1e2·1/η;
/// the library test tests/sag/frf.rs holds 1e-9 away from them).
#[test]
fn sagged_frf_matches_its_dense_solve() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/suspended_8.toml");
    let o = run(&[
        "frf",
        scene,
        "--element",
        "fem",
        "--elements",
        "6",
        "--loss-factor",
        "0.02",
        "--points",
        "40",
        "--to-hz",
        "20",
        "--dense",
        "--json",
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let err = v["dense_max_rel_diff"].as_f64().unwrap();
    assert!(err <= 1e-8, "{err:e}");
    assert_eq!(v["receptance_re"].as_array().unwrap().len(), 40);
    assert_eq!(v["dim"].as_u64(), Some(3));
}

/// The frequencies and receptance of `frf spatial-paper --elements 4 EXTRA --json`.
fn frf_json(extra: &[&str]) -> (Vec<f64>, Vec<f64>, serde_json::Value) {
    let mut args = vec!["frf", "spatial-paper", "--elements", "4", "--json"];
    args.extend_from_slice(extra);
    let o = run(&args);
    assert!(
        o.status.success(),
        "{extra:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let nums = |k: &str| -> Vec<f64> {
        v[k].as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap_or(f64::NAN))
            .collect()
    };
    (nums("frequencies_hz"), nums("natural_frequencies_hz"), v)
}

/// Every receptance entry of the JSON, NaN for a `null`.
fn receptance_entries(v: &serde_json::Value) -> Vec<f64> {
    let mut out = Vec::new();
    for part in ["receptance_re", "receptance_im"] {
        for m in v[part].as_array().unwrap() {
            for row in m.as_array().unwrap() {
                for x in row.as_array().unwrap() {
                    out.push(x.as_f64().unwrap_or(f64::NAN));
                }
            }
        }
    }
    out
}

/// A log range whose bounds' ratio overflows (1e-310 .. 1 Hz: 1e310) is computed in ln f:
/// before, its frequencies were `null` and its rows NaN with exit 0. Its first row is the
/// static compliance, the receptance at 0 Hz of the linear range (an independent path:
/// D(0)⁻¹ without any log), to 1e-12 relative; its frequencies increase from exactly
/// 1e-310 to exactly 1. A range up to the bound, 1e12 Hz, keeps the natural frequencies of
/// the default band 0.5 .. 50 Hz (1e308 listed none).
#[test]
fn log_ranges_of_any_ratio_and_the_highest_frequency() {
    let (f, _, v) = frf_json(&[
        "--from-hz",
        "1e-310",
        "--to-hz",
        "1",
        "--log",
        "--points",
        "7",
    ]);
    assert_eq!(f.len(), 7);
    assert_eq!((f[0], f[6]), (1e-310, 1.0));
    assert!(f.windows(2).all(|w| w[0] < w[1]), "{f:?}");
    let h = receptance_entries(&v);
    assert!(h.iter().all(|x| x.is_finite()), "{h:?}");
    let (_, _, v0) = frf_json(&["--from-hz", "0", "--to-hz", "1", "--points", "2"]);
    let h0 = receptance_entries(&v0);
    let (dim2, n0) = (h.len() / 14, h0.len() / 4);
    assert_eq!(dim2, n0);
    // Row 0 of each part: re then im.
    for (a, b) in h[..dim2]
        .iter()
        .zip(&h0[..n0])
        .chain(h[7 * dim2..8 * dim2].iter().zip(&h0[2 * n0..3 * n0]))
    {
        assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-30), "{a} vs {b}");
    }
    let (f, natural, v) = frf_json(&[
        "--from-hz",
        "1",
        "--to-hz",
        "1e12",
        "--log",
        "--points",
        "7",
    ]);
    assert_eq!((f[0], f[6]), (1.0, 1e12));
    let (_, in_default_band, _) = frf_json(&["--points", "2"]);
    assert!(!in_default_band.is_empty());
    for x in &in_default_band {
        assert!(natural.contains(x), "{x} Hz missing from {natural:?}");
    }
    assert!(receptance_entries(&v).iter().all(|x| x.is_finite()));
}
