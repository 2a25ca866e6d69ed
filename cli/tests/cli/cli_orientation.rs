//! Orientation on the command line: `--orientation W,X,Y,Z` on analyze, bench and map (a
//! unit quaternion within 1e-3, normalised; refused by point-mass scenes), quaternion
//! columns in trajectory CSVs (the same poses as the flag, bit for bit), `map --tilt-deg`,
//! and the 6 × 6 static stiffness of a rigid end-effector.

use cablevib::estimator::Estimator;
use cablevib::estimator::Tmin;
use cablevib::kinematics::{rotated_about, unit_quaternion, Pose};
use cablevib::scene::Scene;
use cablevib::study::analysis::{analyze, AnalyzeOptions};
use nalgebra::{DMatrix, Vector3};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The rigid 6-DOF scene of the repository.
const BOX: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/box_6dof.toml");
/// A small turn about x (1°, printed to 5 digits): feasible for the box at its pose.
const Q_TILT: &str = "0.99996,0.00873,0,0";

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cablevib"))
        .args(args)
        .output()
        .expect("run cablevib")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("cli-orientation")
        .join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// The stiffness of an `analyze --json` object (square: every row as long as the count).
fn stiffness(j: &serde_json::Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = j["stiffness_n_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect();
    assert!(rows.iter().all(|r| r.len() == rows.len()), "{rows:?}");
    DMatrix::from_fn(rows.len(), rows.len(), |r, c| rows[r][c])
}

/// Q_TILT by the command line's rule.
fn q_tilt() -> [f64; 4] {
    let v: Vec<f64> = Q_TILT.split(',').map(|x| x.parse().unwrap()).collect();
    unit_quaternion([v[0], v[1], v[2], v[3]]).unwrap()
}

#[test]
fn bad_quaternions_are_one_line_usage_errors() {
    for (q, why) in [
        ("1,0.1,0,0", "norm 1.00498"),
        ("nan,0,0,1", "finite"),
        ("1,0,0", "four numbers"),
        ("0,0,0,0", "norm 0"),
    ] {
        for cmd in ["analyze", "bench", "map"] {
            let o = run(&[cmd, BOX, "--orientation", q]);
            assert_eq!(
                o.status.code(),
                Some(2),
                "{cmd} {q}: clap's usage error code"
            );
            assert!(stderr(&o).contains(why), "{cmd} {q}: {}", stderr(&o));
        }
    }
}

#[test]
fn point_mass_scenes_refuse_orientation() {
    for args in [
        &["analyze", "spatial-paper", "--orientation", "1,0,0,0"][..],
        &["bench", "spatial-paper", "--orientation", "1,0,0,0"][..],
        &["map", "spatial-paper", "--orientation", "1,0,0,0"][..],
        &["map", "spatial-paper", "--tilt-deg=-5,5", "--quiet"][..],
    ] {
        let o = run(args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert_eq!(e.trim_end().lines().count(), 1, "{e}");
        assert!(e.contains("point-mass end-effector"), "{args:?}: {e}");
    }
}

#[test]
fn analyze_uses_the_orientation_and_reports_it() {
    let j = json(&run(&["analyze", BOX, "--orientation", Q_TILT, "--json"]));
    let q: Vec<f64> = j["orientation_wxyz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(q, q_tilt(), "normalised as the flag's rule says");
    // The library at the same pose: the same f1, bit for bit (one code path).
    let mut s = Scene::box_6dof();
    s.ee_orientation_wxyz = q_tilt();
    let r = analyze(&s, &AnalyzeOptions::default()).unwrap();
    assert_eq!(j["frequencies_hz"][0].as_f64(), Some(r.frequencies_hz[0]));
    // And the orientation matters: the identity's f1 is another number.
    let j0 = json(&run(&["analyze", BOX, "--json"]));
    assert_ne!(j0["frequencies_hz"][0], j["frequencies_hz"][0]);
}

#[test]
fn rigid_stiffness_is_6x6_symmetric_with_the_translational_block_unchanged() {
    let s = Scene::box_6dof();
    for extra in [&[][..], &["--realtime"][..], &["--solver", "dense"][..]] {
        let mut args = vec!["analyze", BOX, "--json"];
        args.extend(extra);
        let k = stiffness(&json(&run(&args)));
        assert_eq!(k.nrows(), 6, "{extra:?}");
        let scale = k.amax();
        for r in 0..6 {
            for c in 0..6 {
                // The condensed stiffness is symmetric to rounding: 1e-12 of the largest
                // entry allows ~1e4 roundings (8 cables, 10 elements each).
                assert!(
                    (k[(r, c)] - k[(c, r)]).abs() <= 1e-12 * scale,
                    "{extra:?} ({r},{c}): {} vs {}",
                    k[(r, c)],
                    k[(c, r)]
                );
            }
        }
        // The translational block is the 3 × 3 the tool published before (the estimator's
        // `stiffness_n_m`): equal bit for bit on the structured paths; the dense reference
        // condenses the assembled K independently, within 1e-8 (as tests/model/effects_rigid.rs).
        let mut est = Estimator::new(&s).unwrap();
        let e = *est.update(&Pose::in_scene(&s, s.ee_position_m), Tmin::Scene);
        let dense = extra.contains(&"dense");
        for r in 0..3 {
            for c in 0..3 {
                let (got, want) = (k[(r, c)], e.stiffness.translational_n_m()[(r, c)]);
                if dense {
                    assert!((got - want).abs() <= 1e-8 * scale, "({r},{c}) {got} {want}");
                } else {
                    assert_eq!(got, want, "{extra:?} ({r},{c})");
                }
            }
        }
    }
    // A point mass keeps its 3 × 3.
    let k = stiffness(&json(&run(&["analyze", "spatial-paper", "--json"])));
    assert_eq!(k.shape(), (3, 3));
}

#[test]
fn bench_drives_the_circle_at_the_orientation() {
    // The imported IPAnema-like robot: rigid, and feasible along the whole circle.
    let scene = concat!(
        concat!(env!("CARGO_MANIFEST_DIR"), "/.."),
        "/tests/data/caspr/ipanema1.toml"
    );
    let cycles = 20;
    let f1 = |extra: &[&str]| {
        let n = cycles.to_string();
        let mut args = vec![
            "bench",
            scene,
            "--cycles",
            &n,
            "--dense-samples",
            "0",
            "--json",
        ];
        args.extend(extra);
        json(&run(&args))["f1_min_hz"].as_f64().unwrap()
    };
    let tilted = f1(&["--orientation", Q_TILT]);
    assert_ne!(tilted, f1(&[]), "the orientation reaches the estimator");
    // The same cycles through the library at the tilted orientation: bench's warm-up pose
    // 0, then poses 1 ..= cycles, with the service's budget. Bit for bit.
    let mut s = Scene::load(scene).unwrap();
    s.ee_orientation_wxyz = q_tilt();
    let mut est = Estimator::realtime(&s).unwrap();
    est.update(&cablevib::trajectory::circle_pose(&s, 0, 4.0), Tmin::Scene);
    let want = (1..=cycles)
        .map(|k| {
            let pose = cablevib::trajectory::circle_pose(&s, k, 4.0);
            assert_eq!(pose.orientation_wxyz, q_tilt());
            est.update(&pose, Tmin::Scene).f1_hz
        })
        .fold(f64::INFINITY, f64::min);
    assert_eq!(tilted, want);
}

/// The rows of a CSV file (header first).
fn rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn trajectory_quaternion_columns_equal_the_orientation_flag() {
    let d = tmp("traj");
    let (plain, with_q) = (d.join("plain.csv"), d.join("q.csv"));
    let path = [(0.0, 0.0), (0.001, 0.01), (0.002, 0.02)];
    let mut a = String::from("t,x,y,z\n");
    let mut b = String::from("t,x,y,z,qw,qx,qy,qz\n");
    for (t, x) in path {
        a += &format!("{t},{x},0,1.25\n");
        b += &format!("{t},{x},0,1.25,{Q_TILT}\n");
    }
    std::fs::write(&plain, a).unwrap();
    std::fs::write(&with_q, &b).unwrap();
    let out = |name: &str, csv: &Path, extra: &[&str]| {
        let prefix = d.join(name);
        let mut args = vec![
            "trajectory",
            BOX,
            "--csv",
            csv.to_str().unwrap(),
            "--quiet",
            "--out",
            prefix.to_str().unwrap(),
        ];
        args.extend(extra);
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        rows(&prefix.with_extension("csv"))
    };
    let by_flag = out("flag", &plain, &["--orientation", Q_TILT]);
    let by_file = out("file", &with_q, &[]);
    assert_eq!(by_flag, by_file, "the same poses, bit for bit");
    let qw = by_file[0].iter().position(|c| c == "qw").unwrap();
    assert_eq!(by_file[1][qw], q_tilt()[0].to_string());
    assert!(by_file[1..].iter().all(|r| r[qw + 3] == "0"));

    // A bad quaternion names its line (the header is line 1).
    std::fs::write(
        &with_q,
        b.replace("0.002,0.02,0,1.25,0.99996", "0.002,0.02,0,1.25,1.5"),
    )
    .unwrap();
    let o = run(&[
        "trajectory",
        BOX,
        "--csv",
        with_q.to_str().unwrap(),
        "--quiet",
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("q.csv:4:") && e.contains("norm"), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");

    // A point-mass scene reads the columns, and says once that they have no effect.
    std::fs::write(&with_q, &b).unwrap();
    let o = run(&[
        "trajectory",
        "spatial-paper",
        "--csv",
        with_q.to_str().unwrap(),
        "--quiet",
        "--out",
        d.join("pm").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stderr(&o).matches("no effect").count(), 1, "{}", stderr(&o));
}

#[test]
fn map_sweeps_tilt_angles_as_panels() {
    let d = tmp("tilt");
    let map = |name: &str, extra: &[&str]| {
        let prefix = d.join(name);
        let mut args = vec![
            "map",
            BOX,
            "--x=-0.2,0.2",
            "--y=-0.2,0.2",
            "--step",
            "0.2",
            "--quiet",
            "--out",
            prefix.to_str().unwrap(),
        ];
        args.extend(extra);
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        rows(&prefix.with_extension("csv"))
    };
    let tilted = map(
        "tilted",
        &[
            "--tilt-deg=-1,1",
            "--tilt-step-deg",
            "1",
            "--tilt-axis",
            "0,2,0",
        ],
    );
    assert_eq!(tilted.len(), 1 + 3 * 9, "3 tilt angles × 9 grid points");
    let h = &tilted[0];
    let (qw, qy, st) = (
        h.iter().position(|c| c == "qw").unwrap(),
        h.iter().position(|c| c == "qy").unwrap(),
        h.iter().position(|c| c == "status").unwrap(),
    );
    for (k, deg) in [-1.0f64, 0.0, 1.0].iter().enumerate() {
        let q = rotated_about(&[1.0, 0.0, 0.0, 0.0], &Vector3::y(), deg.to_radians());
        let row = &tilted[1 + 9 * k];
        assert_eq!(row[qw], q[0].to_string(), "{deg}°");
        // Closed form of a turn about y: (cos θ/2, 0, sin θ/2, 0); rounding only.
        let half = deg.to_radians() / 2.0;
        let qy_v: f64 = row[qy].parse().unwrap();
        assert!((qy_v - half.sin()).abs() < 1e-15, "{deg}°: {qy_v}");
        assert!(tilted[1 + 9 * k..1 + 9 * (k + 1)]
            .iter()
            .any(|r| r[st] == "ok"));
    }
    // The 0° panel is the map at the scene's orientation, bit for bit.
    let plain = map("plain", &[]);
    assert_eq!(&tilted[10..19], &plain[1..10]);
    // With --orientation the map takes it, and the slice axis must be one value to tilt.
    let o = map("oriented", &["--orientation", Q_TILT]);
    assert_eq!(o[1][qw], q_tilt()[0].to_string());
    let r = run(&["map", BOX, "--z=1,1.25", "--tilt-deg=-1,1", "--quiet"]);
    assert_eq!(r.status.code(), Some(1));
    assert!(stderr(&r).contains("single value"), "{}", stderr(&r));
}
