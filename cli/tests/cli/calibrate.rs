//! `cablevib calibrate`: end to end on data from the testkit's dense-FEM truth (the JSON
//! contract, the calibrated scene read back by other commands and by the scene parser with
//! the truth's values, the figure), `identify`'s CSV layout accepted as it is, damping fits,
//! and bad input: one-line errors naming the row or the parameter, nothing written.

use cablevib::scene::Scene;
use cablevib_testkit::calibration_truth::{recovery_data, recovery_scene_toml, recovery_truth};
use cablevib_testkit::Rng;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

fn run(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .current_dir(dir)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("the binary runs")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cablevib-calibrate-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A robot (the recovery scene with the truth's hidden cables) and its measured modes and
/// tensions in `dir`: robot.toml, modes.csv, tensions.csv. Returns the true EA factors and
/// mass.
fn robot(dir: &Path, seed: u64, labelled: bool) -> (Vec<f64>, f64) {
    let mut rng = Rng(seed);
    let (truth, factors, mass, hidden) = recovery_truth(&mut rng);
    let d = recovery_data(&truth, labelled, &mut rng);
    std::fs::write(dir.join("robot.toml"), recovery_scene_toml(Some(&hidden))).unwrap();
    std::fs::write(dir.join("modes.csv"), d.modes_csv).unwrap();
    std::fs::write(dir.join("tensions.csv"), d.tensions_csv).unwrap();
    (factors, mass)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `cablevib calibrate robot.toml ARGS --json` in `dir`: it succeeds; its JSON.
fn calibrate_json(dir: &Path, args: &[&str]) -> serde_json::Value {
    let mut all = vec!["calibrate", "robot.toml"];
    all.extend(args);
    all.push("--json");
    let o = run(dir, &all);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// The JSON holds parameters (name, value, std_error, determined), chi2_per_dof and fits;
/// the estimates are the truth's within 3σ; `-o` writes a scene that the scene parser reads
/// with those EA values and mass and that `analyze` and `modes` run on; the figure is an
/// SVG; the input files are unchanged.
#[test]
fn end_to_end_json_figure_and_calibrated_scene() {
    let d = tmp("e2e");
    let (factors, mass) = robot(&d, 3, false);
    let before: Vec<Vec<u8>> = ["robot.toml", "modes.csv", "tensions.csv"]
        .iter()
        .map(|f| std::fs::read(d.join(f)).unwrap())
        .collect();
    let o = run(
        &d,
        &[
            "calibrate",
            "robot.toml",
            "--data",
            "modes.csv",
            "--tensions",
            "tensions.csv",
            "--fit",
            "ea_factor,ee_mass",
            "-o",
            "out/calibrated.toml",
            "--json",
            "--svg",
            "fit.svg",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["fits"], serde_json::Value::Bool(true), "{}", v["verdict"]);
    assert!(v["chi2_per_dof"].as_f64().unwrap() < 1.5);
    let params = v["parameters"].as_array().unwrap();
    assert_eq!(params.len(), 9);
    let truth: Vec<f64> = factors.iter().copied().chain([mass]).collect();
    for (p, t) in params.iter().zip(&truth) {
        let (value, s) = (
            p["value"].as_f64().unwrap(),
            p["std_error"].as_f64().unwrap(),
        );
        assert_eq!(p["determined"], serde_json::Value::Bool(true));
        assert!(
            (value - t).abs() <= 3.0 * s,
            "{}: {value} ± {s} vs {t}",
            p["name"]
        );
    }
    let calibrated = Scene::load(d.join("out/calibrated.toml").to_str().unwrap()).unwrap();
    let nominal = Scene::load(d.join("robot.toml").to_str().unwrap()).unwrap();
    for (i, (c, n)) in calibrated.cables.iter().zip(&nominal.cables).enumerate() {
        let f = params[i]["value"].as_f64().unwrap();
        assert_eq!(
            c.youngs_modulus_pa,
            n.youngs_modulus_pa * f,
            "cable {}",
            i + 1
        );
        let (h, hn) = (c.hidden.unwrap(), n.hidden.unwrap());
        assert_eq!(
            h.youngs_modulus_pa,
            hn.youngs_modulus_pa * f,
            "hidden {}",
            i + 1
        );
        assert_eq!((h.area_m2, h.length_m), (hn.area_m2, hn.length_m));
    }
    assert_eq!(calibrated.ee_mass_kg, params[8]["value"].as_f64().unwrap());
    let text = std::fs::read_to_string(d.join("out/calibrated.toml")).unwrap();
    assert!(
        text.starts_with("# Calibrated by `cablevib calibrate`"),
        "{text}"
    );
    assert!(text.contains("calibrated ea_factor.3 = "), "{text}");
    for cmd in ["analyze", "modes"] {
        let o = run(&d, &[cmd, "out/calibrated.toml"]);
        assert!(o.status.success(), "{cmd}: {}", stderr(&o));
    }
    let svg = std::fs::read_to_string(d.join("fit.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("after (calibrated)"));
    for (f, b) in ["robot.toml", "modes.csv", "tensions.csv"]
        .iter()
        .zip(&before)
    {
        assert_eq!(&std::fs::read(d.join(f)).unwrap(), b, "{f} unchanged");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `identify`'s CSV (comment lines, its 19 columns, rows whose status is not ok) is read as
/// it is: its unused columns named once, the doubtful rows listed and left out,
/// `frequency_std_hz` taken as σ, `model_mode` shown as a hint.
#[test]
fn identify_csv_is_accepted_as_it_is() {
    let d = tmp("identify");
    robot(&d, 5, false);
    let modes = std::fs::read_to_string(d.join("modes.csv")).unwrap();
    let mut out = String::from("# cablevib identify rec.mcap --scene robot.toml --csv id.csv\n");
    out.push_str("window,t_start_s,t_end_s,x_m,y_m,z_m,qw,qx,qy,qz,identified_mode,frequency_hz,frequency_std_hz,damping_ratio,damping_ratio_std,model_frequency_hz,model_mode,model_ee_participation,status\n");
    for (k, line) in modes.lines().skip(1).enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        let status = if k == 4 { "unstable" } else { "ok" };
        out.push_str(&format!(
            "{},{},{},{},{},{},,,,,{},{},{},0.01,0.002,,{},,{status}\n",
            k / 3,
            10 * (k / 3),
            10 * (k / 3) + 10,
            f[0],
            f[1],
            f[2],
            k % 3 + 1,
            f[3],
            f[4],
            k % 3 + 1
        ));
    }
    std::fs::write(d.join("id.csv"), out).unwrap();
    let o = run(
        &d,
        &[
            "calibrate",
            "robot.toml",
            "--data",
            "id.csv",
            "--tensions",
            "tensions.csv",
            "--fit",
            "ea_factor,ee_mass",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("not used: window, t_start_s, t_end_s, identified_mode, model_frequency_hz, model_ee_participation"), "{text}");
    assert!(
        text.contains("left out of the fit: 1 rows") && text.contains("line 7: status unstable"),
        "{text}"
    );
    assert!(text.contains("59 from frequency_std_hz"), "{text}");
    assert!(text.contains("verdict: fits"), "{text}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Damping: `modal_ratio` fitted to measured ratios is their σ-weighted mean (the least
/// squares of a constant, closed form); `rayleigh` recovers α and β from ratios generated
/// by ζ = α/(2ω) + βω/2 (exact data: to 1e-6).
#[test]
fn damping_fits() {
    let d = tmp("damping");
    robot(&d, 9, false);
    let modes = std::fs::read_to_string(d.join("modes.csv")).unwrap();
    let (alpha, beta) = (0.8, 2.0e-4);
    let mut zetas = Vec::new();
    let mut out =
        String::from("x_m,y_m,z_m,frequency_hz,sigma_hz,damping_ratio,damping_ratio_std\n");
    for (k, line) in modes.lines().skip(1).enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        let w = 2.0 * std::f64::consts::PI * f[3].parse::<f64>().unwrap();
        let z = alpha / (2.0 * w) + beta * w / 2.0;
        let s = 1e-4 * (1.0 + (k % 3) as f64);
        zetas.push((z, s));
        out.push_str(&format!(
            "{},{},{},{},{},{z:?},{s:?}\n",
            f[0], f[1], f[2], f[3], f[4]
        ));
    }
    std::fs::write(d.join("damped.csv"), out).unwrap();
    let v = calibrate_json(&d, &["--data", "damped.csv", "--fit", "rayleigh"]);
    let a = v["parameters"][0]["value"].as_f64().unwrap();
    let b = v["parameters"][1]["value"].as_f64().unwrap();
    assert!(
        (a - alpha).abs() < 1e-6 * alpha && (b - beta).abs() < 1e-6 * beta,
        "α {a}, β {b}"
    );
    let v = calibrate_json(&d, &["--data", "damped.csv", "--fit", "modal_ratio"]);
    let z = v["parameters"][0]["value"].as_f64().unwrap();
    let (num, den) = zetas.iter().fold((0.0, 0.0), |(n, d), (z, s)| {
        (n + z / (s * s), d + 1.0 / (s * s))
    });
    assert!((z - num / den).abs() < 1e-9, "{z} vs {}", num / den);
    let _ = std::fs::remove_dir_all(&d);
}

/// Bad input: one line on stderr naming the row or the parameter, a failed exit, no
/// calibrated scene written, no panic.
#[test]
fn bad_input_is_one_line_naming_the_row_or_parameter() {
    let d = tmp("bad");
    robot(&d, 13, true);
    let modes = std::fs::read_to_string(d.join("modes.csv")).unwrap();
    let lines: Vec<&str> = modes.lines().collect();
    let with = |name: &str, text: String| std::fs::write(d.join(name), text).unwrap();
    // A NaN frequency in line 3; a duplicate of line 2; a pose outside the frame (line 2).
    with(
        "nan.csv",
        modes.replacen(lines[2].split(',').nth(3).unwrap(), "NaN", 1),
    );
    with(
        "dup.csv",
        format!("{}\n{}\n{}\n", lines[0], lines[1], lines[1]),
    );
    let far = lines[1].replacen(lines[1].split(',').next().unwrap(), "9.0", 1);
    with("far.csv", format!("{}\n{far}\n", lines[0]));
    with(
        "two.csv",
        format!("{}\n{}\n{}\n", lines[0], lines[1], lines[2]),
    );
    std::fs::hard_link(d.join("robot.toml"), d.join("link.toml")).unwrap();
    std::os::unix::fs::symlink("modes.csv", d.join("fig.svg")).unwrap();
    // (arguments after the scene, split at spaces; what the one line must contain)
    let cases = [
        (
            "--data nan.csv --fit ee_mass",
            "nan.csv: line 3: frequency_hz = `NaN` is not a finite number",
        ),
        (
            "--data dup.csv --fit ee_mass",
            "dup.csv: line 3: duplicate of line 2",
        ),
        (
            "--data far.csv --fit ee_mass",
            "far.csv: line 2: the nominal model has no answer at the pose (9",
        ),
        (
            "--data two.csv --fit ea_factor",
            "8 parameters but only 2 measurements",
        ),
        (
            "--data modes.csv --fit ee_mass --bounds ee_mass=40:50",
            "parameter `ee_mass`: the bounds [40, 50] kg exclude the nominal value 30",
        ),
        (
            "--data modes.csv --fit ea_factor,ee_mas",
            "parameter `ee_mas`: unknown parameter",
        ),
        (
            "--data modes.csv --fit ea_factor.9",
            "parameter `ea_factor.9`",
        ),
        (
            "--data modes.csv --fit modal_ratio",
            "parameter `modal_ratio`: the data have no measured damping ratio",
        ),
        (
            "--data modes.csv --fit ee_mass --bounds ea_factor=0.5:2",
            "parameter `ea_factor`: is not among the fitted parameters (add it to --fit)",
        ),
        (
            "--data modes.csv --fit ee_mass --prior ee_mass=-1",
            "parameter `ee_mass`: prior standard deviation -1",
        ),
        // Outputs that are inputs (the project's output rule: by device and inode, so a
        // hard link is caught), refused before anything is read.
        (
            "--data modes.csv --fit ee_mass -o modes.csv",
            "modes.csv: is the input modes.csv (the same file)",
        ),
        (
            "--data modes.csv --fit ee_mass -o robot.toml",
            "robot.toml: is the input robot.toml (the same file)",
        ),
        (
            "--data modes.csv --fit ee_mass -o link.toml",
            "link.toml: is the input robot.toml (the same file)",
        ),
        (
            "--data modes.csv --tensions tensions.csv --fit ee_mass -o tensions.csv",
            "tensions.csv: is the input tensions.csv (the same file)",
        ),
        (
            "--data modes.csv --fit ee_mass --svg fig.svg",
            "fig.svg: is the input modes.csv (the same file)",
        ),
        (
            "--data modes.csv --fit ee_mass --position 0,0,1",
            "--position/--orientation",
        ),
    ];
    for (args, needle) in cases {
        let args: Vec<&str> = args.split(' ').collect();
        let mut all = vec!["calibrate", "robot.toml"];
        all.extend(&args);
        if !args.contains(&"-o") {
            all.extend(["-o", "never.toml"]);
        }
        let o = run(&d, &all);
        let e = stderr(&o);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(e.contains(needle), "{args:?}: {e}");
        assert_eq!(e.trim_end().lines().count(), 1, "{args:?}: {e}");
        assert!(!e.contains("panicked"), "{e}");
        assert!(!d.join("never.toml").exists(), "{args:?} wrote the output");
        let parts: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".part"))
            .collect();
        assert!(parts.is_empty(), "{args:?} left {parts:?}");
    }
    assert_eq!(std::fs::read_to_string(d.join("modes.csv")).unwrap(), modes);
    assert_eq!(
        std::fs::read_to_string(d.join("robot.toml")).unwrap(),
        std::fs::read_to_string(d.join("link.toml")).unwrap()
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The hand-over as a user runs it: a recording of the platform's accelerations at 20
/// poses (60 s each at 250 Hz, 20 dB sensor noise), the robot at rest under white-noise
/// forces on the platform, its modes those of the true robot's dense FEM (the testkit's
/// assembly, `dense_modes`: every mode below 45 Hz, its platform shape from the
/// mass-normalised eigenvector, ζ 1 %), simulated exactly (`modal_record`) with the poses
/// in the record's columns; `cablevib identify --window 60 --overlap 0 --csv id.csv` writes
/// the CSV, and `cablevib calibrate --data id.csv` (σ: identify's jackknife
/// `frequency_std_hz`) with the load cells' tensions (1 %) fits the EA factors and the
/// mass. Each estimate is within 3σ of the truth, and the verdict is "fits" (identify's σ
/// describe its errors: measured χ²/dof 1.07, P = 0.23). Rows identify marked `unpaired` or
/// `ambiguous` (its pairing with the nominal model) are used: at least 50 of the 61.
#[test]
fn identify_then_calibrate_recovers_the_truth() {
    use cablevib_testkit::calibration_truth::{
        dense_modes, feasible_poses, measured_tensions_csv, RECOVERY_ELEMENTS,
    };
    use cablevib_testkit::modal_record::{simulate, Modal, Output as Measured};
    use nalgebra::Vector3;
    use std::fmt::Write;
    let d = tmp("handover");
    let mut rng = Rng(17);
    let (truth, factors, mass, hidden) = recovery_truth(&mut rng);
    std::fs::write(d.join("robot.toml"), recovery_scene_toml(Some(&hidden))).unwrap();
    let poses = feasible_poses(
        &truth,
        20,
        Vector3::new(-0.6, -0.6, 0.6),
        Vector3::new(0.6, 0.6, 1.9),
        &mut rng,
    );
    let (rate_hz, seconds, top_hz) = (250.0, 60.0, 45.0);
    let mut rec = String::from("t,ax,ay,az,x_m,y_m,z_m\n");
    let mut k_total = 0usize;
    for (k, p) in poses.iter().enumerate() {
        let modes: Vec<_> = dense_modes(&truth, RECOVERY_ELEMENTS, p, None)
            .unwrap()
            .into_iter()
            .filter(|m| m.frequency_hz < top_hz && m.participation > 1e-3)
            .collect();
        let sys = Modal {
            frequencies_hz: modes.iter().map(|m| m.frequency_hz).collect(),
            zetas: vec![0.01; modes.len()],
            shapes: modes
                .iter()
                .map(|m| {
                    let u = m.ee_direction * (m.participation / truth.ee_mass_kg).sqrt();
                    vec![u.x, u.y, u.z]
                })
                .collect(),
        };
        let r = simulate(
            &sys,
            &[0, 1, 2],
            Measured::Acceleration,
            rate_hz,
            seconds,
            20.0,
            100 + k as u64,
        );
        for s in 0..r.t_s.len() {
            let y = &r.y[3 * s..3 * s + 3];
            let t = k_total as f64 / rate_hz;
            k_total += 1;
            writeln!(
                rec,
                "{t},{},{},{},{},{},{}",
                y[0], y[1], y[2], p.x, p.y, p.z
            )
            .unwrap();
        }
    }
    std::fs::write(d.join("rec.csv"), rec).unwrap();
    let tensions = measured_tensions_csv(&truth, &poses, 0.01, &mut rng);
    std::fs::write(d.join("tensions.csv"), tensions).unwrap();
    let o = run(
        &d,
        &[
            "identify",
            "rec.csv",
            "--scene",
            "robot.toml",
            "--window",
            "60",
            "--overlap",
            "0",
            "--from-hz",
            "5",
            "--to-hz",
            "45",
            "--csv",
            "id.csv",
        ],
    );
    assert!(o.status.success(), "identify: {}", stderr(&o));
    let id = std::fs::read_to_string(d.join("id.csv")).unwrap();
    let rows = id.lines().filter(|l| !l.starts_with('#')).count() - 1;
    println!("identify: {rows} rows");
    let o = run(
        &d,
        &[
            "calibrate",
            "robot.toml",
            "--data",
            "id.csv",
            "--tensions",
            "tensions.csv",
            "--fit",
            "ea_factor,ee_mass",
            "-o",
            "calibrated.toml",
        ],
    );
    let text = String::from_utf8_lossy(&o.stdout);
    println!("{text}");
    assert!(o.status.success(), "calibrate: {}", stderr(&o));
    let v = calibrate_json(
        &d,
        &[
            "--data",
            "id.csv",
            "--tensions",
            "tensions.csv",
            "--fit",
            "ea_factor,ee_mass",
        ],
    );
    let truth_values: Vec<f64> = factors.iter().copied().chain([mass]).collect();
    let mut worst = 0.0f64;
    for (p, t) in v["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .zip(&truth_values)
    {
        let (value, s) = (
            p["value"].as_f64().unwrap(),
            p["std_error"].as_f64().expect("determined"),
        );
        worst = worst.max((value - t).abs() / s);
        assert!(
            (value - t).abs() <= 3.0 * s,
            "{}: {value} ± {s} vs {t}",
            p["name"]
        );
    }
    println!(
        "largest |error|/σ {worst:.2}; χ²/dof {}, fits {}",
        v["chi2_per_dof"], v["fits"]
    );
    assert_eq!(v["fits"], serde_json::Value::Bool(true), "{}", v["verdict"]);
    assert!(
        v["frequencies"].as_u64().unwrap() >= 50,
        "{}",
        v["frequencies"]
    );
    // The calibrated scene runs `demo`'s model: `analyze` reads it as it is.
    let o = run(&d, &["analyze", "calibrated.toml"]);
    assert!(o.status.success(), "analyze: {}", stderr(&o));
    let _ = std::fs::remove_dir_all(&d);
}
