//! Right answers on the robots people have: each cable's own lower bound reaches every
//! command, and no geometric pre-test refuses a pose the robot can hold.
//!
//! The references share no code with the estimator: the tension QP is solved again by
//! Clarabel (`tension::clarabel_reference_bounds`, an interior-point solver, against the
//! real-time active-set solver), and equilibrium Σ T_i s_i = −m g is summed in this file
//! from the anchors of the scene file. Tolerances: equilibrium 1e-9 of |w| (the active set
//! solves a 3 × 3 system exactly up to rounding); the two QP solvers agree to 1e-6 of T_max
//! (Clarabel's default tolerances are 1e-8 relative on the KKT residual).

use cablevib::estimator::{reference_analysis, Estimator, Status, Tmin};
use cablevib::kinematics::{Geometry, Pose};
use cablevib::scene::Scene;
use cablevib::tension::clarabel_reference_bounds;
use cablevib_testkit::ee_hz;
use nalgebra::Vector3;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The paper's spatial robot with cable 5's lower bound raised to 100 N (the scene's is
/// 60 N): at the centre the uniform answer gives cable 5 about 60 N.
const CABLE5_T_MIN_N: f64 = 100.0;

fn temp_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// scenes/spatial_paper.toml with `t_min = 100.0` on its fifth `[[cables]]` entry.
fn per_cable_scene_file(dir: &Path) -> PathBuf {
    let text = include_str!("../../../scenes/spatial_paper.toml");
    let mut out = String::new();
    let mut k = 0;
    for line in text.lines() {
        out.push_str(line);
        out.push('\n');
        if line.trim() == "[[cables]]" {
            k += 1;
            if k == 5 {
                out.push_str(&format!("t_min = {CABLE5_T_MIN_N:?}\n"));
            }
        }
    }
    assert_eq!(k, 8);
    let p = dir.join("per_cable.toml");
    std::fs::write(&p, out).unwrap();
    p
}

/// Σ T_i (a_i − p)/|a_i − p| + m g, N, from the scene's anchors (point mass).
fn equilibrium_residual_n(s: &Scene, p: &Vector3<f64>, t: &[f64]) -> f64 {
    let mut f = s.gravity_m_s2 * s.ee_mass_kg;
    for (c, ti) in s.cables.iter().zip(t) {
        let d = c.anchor_m - p;
        f += d / d.norm() * *ti;
    }
    f.norm()
}

/// Clarabel's tensions for the scene's own per-cable bounds at `p`.
fn clarabel_tensions(s: &Scene, p: &Vector3<f64>) -> Result<Vec<f64>, String> {
    let mut g = Geometry::new(s.n_cables());
    g.update(s.cables.iter().map(|c| &c.anchor_m), p)
        .map_err(|e| e.to_string())?;
    let w = s.wrench_n();
    let lo: Vec<f64> = (0..s.n_cables()).map(|i| s.cable_t_min_n(i)).collect();
    let hi: Vec<f64> = (0..s.n_cables()).map(|i| s.cable_t_max_n(i)).collect();
    clarabel_reference_bounds(&g, &[w.x, w.y, w.z, 0.0, 0.0, 0.0], &lo, &hi)
        .map_err(|e| e.to_string())
}

fn run(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_cablevib"))
        .args(args)
        .output()
        .expect("run cablevib")
}

fn json_of(args: &[&str]) -> serde_json::Value {
    let o = run(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{args:?}: {e}: {}", String::from_utf8_lossy(&o.stdout)))
}

fn tensions_of(v: &serde_json::Value) -> Vec<f64> {
    v["tensions_n"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// Checks one answer: cable 5 at its own bound or above, every other cable at the scene's,
/// equilibrium, and Clarabel's tensions.
fn check_tensions(label: &str, s: &Scene, p: &Vector3<f64>, t: &[f64], reference: &[f64]) {
    for (i, ti) in t.iter().enumerate() {
        let lo = s.cable_t_min_n(i);
        assert!(
            *ti >= lo * (1.0 - 1e-9),
            "{label}: cable {} at {ti} N < its bound {lo} N",
            i + 1
        );
        assert!(
            *ti <= s.cable_t_max_n(i) * (1.0 + 1e-9),
            "{label}: cable {} above t_max",
            i + 1
        );
    }
    let r = equilibrium_residual_n(s, p, t);
    assert!(
        r <= 1e-9 * s.wrench_n().norm(),
        "{label}: equilibrium residual {r} N"
    );
    for (i, (a, b)) in t.iter().zip(reference).enumerate() {
        assert!(
            (a - b).abs() <= 1e-6 * s.t_max_n,
            "{label}: cable {}: {a} vs Clarabel {b} N",
            i + 1
        );
    }
}

/// Every offline path gives each cable its own lower bound: the estimator (`Tmin::Scene`),
/// the dense reference, `analyze` (structured, dense, `--realtime`), `map`, `trajectory`,
/// `modes` and `bench`; `--t-min` still overrides all of them. Before, every path filled all
/// cables with `[tension] t_min` (cable 5 at ~60 N).
#[test]
fn per_cable_lower_bounds_reach_every_command() {
    let dir = temp_dir("per_cable_bounds");
    let file = per_cable_scene_file(&dir);
    let path = file.to_str().unwrap();
    let s = Scene::load(path).unwrap();
    assert_eq!(s.cable_t_min_n(4), CABLE5_T_MIN_N);
    let p = s.ee_position_m;
    let reference = clarabel_tensions(&s, &p).unwrap();
    assert!(
        reference[4] >= CABLE5_T_MIN_N * (1.0 - 1e-7),
        "{reference:?}"
    );

    // The library.
    let mut est = Estimator::new(&s).unwrap();
    let e = *est.update(&Pose::at(p), Tmin::Scene);
    assert_eq!(e.status, Status::Ok);
    check_tensions("Estimator Tmin::Scene", &s, &p, e.tensions(), &reference);
    let dense = reference_analysis(&s, &p, Tmin::Scene, false).unwrap();
    check_tensions("reference_analysis", &s, &p, &dense.tensions_n, &reference);
    let f1_scene = e.f1_hz;
    // The uniform override is a different answer (cable 5 back near 60 N).
    let u = *est.update(&Pose::at(p), Tmin::Uniform(60.0));
    assert!(u.tensions()[4] < 0.9 * CABLE5_T_MIN_N, "{:?}", u.tensions());

    // analyze, three ways.
    for extra in [&[][..], &["--solver", "dense"][..], &["--realtime"][..]] {
        let mut args = vec!["analyze", path, "--json"];
        args.extend_from_slice(extra);
        let v = json_of(&args);
        check_tensions(
            &format!("analyze {extra:?}"),
            &s,
            &p,
            &tensions_of(&v),
            &reference,
        );
        let f1 = v["f1_hz"]
            .as_f64()
            .or(v["frequencies_hz"][0].as_f64())
            .unwrap();
        assert!(
            (f1 - f1_scene).abs() <= 1e-6 * f1_scene,
            "analyze {extra:?}: f1 {f1} vs {f1_scene}"
        );
    }
    // --t-min overrides every cable.
    let v = json_of(&["analyze", path, "--json", "--t-min", "60"]);
    assert!(tensions_of(&v)[4] < 0.9 * CABLE5_T_MIN_N);

    // map and trajectory CSVs: the tension5_n column.
    let prefix = dir.join("map");
    let o = run(&[
        "map",
        path,
        "--x",
        "-0.2,0.2",
        "--y",
        "-0.2,0.2",
        "--step",
        "0.2",
        "--out",
        prefix.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    check_csv_column(&dir.join("map.csv"), &s, 9);
    let prefix = dir.join("traj");
    let o = run(&[
        "trajectory",
        path,
        "--radius-m",
        "0.3",
        "--quiet",
        "--out",
        prefix.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    check_csv_column(&dir.join("traj.csv"), &s, 100);

    // modes: its f1 is the pose's f1 with cable 5 at its bound.
    let o = run(&["modes", path, "--modes", "1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("T_min 60-100 N per cable"), "{text}");
    let f1: f64 = text
        .lines()
        .find_map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            (w.first() == Some(&"1"))
                .then(|| w[1].parse().ok())
                .flatten()
        })
        .unwrap_or_else(|| panic!("no mode 1 in {text}"));
    assert!(
        (f1 - f1_scene).abs() <= 1e-6 * f1_scene,
        "modes: {f1} vs {f1_scene}"
    );
}

/// The rows of a study CSV: every ok row has cable 5 at its own bound or above; at least
/// `min_ok` ok rows.
fn check_csv_column(csv: &Path, s: &Scene, min_ok: usize) {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("{name} in {header:?}"))
    };
    let (st, t5) = (col("status"), col("tension5_n"));
    let mut ok = 0;
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        if f[st] == "ok" {
            ok += 1;
            let t: f64 = f[t5].parse().unwrap();
            assert!(
                t >= s.cable_t_min_n(4) * (1.0 - 1e-6),
                "{}: {l}",
                csv.display()
            );
        }
    }
    assert!(ok >= min_ok, "{}: {ok} ok rows", csv.display());
}

/// A suspended robot whose anchors differ in height by a few cm (CoGiRo's: 5.387-5.420 m)
/// hangs its platform 3 m below them. Before, a bounding-box pre-test refused every such
/// pose as `outside_workspace`; now the tension distribution decides, and an independent
/// LP-like check (Clarabel's QP with the same bounds) agrees with the status both ways.
#[test]
fn suspended_robot_with_uneven_anchors_is_not_refused() {
    let toml = r#"
name = "suspended-uneven"
gravity = [0.0, 0.0, -9.81]
[end_effector]
mass = 20.0
position = [0.0, 0.0, 2.4]
[cable]
youngs_modulus = 1e11
area = 1e-5
weight_per_length = 0.5
[tension]
t_min = 1.0
t_max = 5000.0
[model]
element = "fem"
elements_per_cable = 10
[effects]
sag = false
[[cables]]
anchor = [7.0, 5.0, 5.387]
[[cables]]
anchor = [-7.0, 5.0, 5.420]
[[cables]]
anchor = [-7.0, -5.0, 5.401]
[[cables]]
anchor = [7.0, -5.0, 5.395]
"#;
    let dir = temp_dir("suspended_uneven");
    let file = dir.join("s.toml");
    std::fs::write(&file, toml).unwrap();
    let path = file.to_str().unwrap();
    let s = Scene::load(path).unwrap();
    let mut est = Estimator::new(&s).expect("the default pose holds");
    let mut seen = [0usize; 2];
    for (x, y, z) in [
        (0.0, 0.0, 2.4),
        (1.0, -0.5, 3.0),
        (3.0, 2.0, 1.0),
        (6.0, 0.0, 5.0),
        (0.0, 0.0, 5.6),
    ] {
        let p = Vector3::new(x, y, z);
        let e = *est.update(&Pose::at(p), Tmin::Scene);
        let qp = clarabel_tensions(&s, &p);
        match e.status {
            Status::Ok => {
                seen[0] += 1;
                check_tensions(&format!("{p:?}"), &s, &p, e.tensions(), &qp.unwrap());
            }
            Status::TensionInfeasible => {
                seen[1] += 1;
                assert!(
                    qp.is_err(),
                    "{p:?}: refused as infeasible, Clarabel finds {qp:?}"
                );
            }
            st => panic!("{p:?}: status {st:?} (Clarabel: {qp:?})"),
        }
    }
    // Inside the anchors' footprint below them: ok; above the anchors: infeasible.
    assert!(seen[0] >= 3 && seen[1] >= 1, "{seen:?}");
    let v = json_of(&["analyze", path, "--json", "--realtime"]);
    assert_eq!(v["status"], "ok", "{v}");
}

/// A platform whose eight attachments all lie on its z axis (CASPR's DrainageService robot,
/// written out here): spinning about that axis moves no attachment point, so by geometry
/// that direction has no stiffness and no frequency. Before, f1 ≈ 0 Hz came out with status
/// ok (1e-14 Hz real time, 3e-5 Hz dense). Now: status `mechanism` naming the spin about
/// z, in the estimator and in `analyze` (structured, dense, `--realtime`); the same robot
/// with its attachments moved 5 cm off the axis is held and answers ok.
#[test]
fn a_free_spin_is_a_mechanism_not_a_frequency() {
    let cables = [
        ([0.08, 3.923, 2.29], -0.5),
        ([3.923, 3.923, 0.103], -0.5),
        ([3.923, 3.923, 2.29], 0.5),
        ([3.922, 0.077, 0.103], -0.5),
        ([3.922, 0.077, 2.29], 0.5),
        ([0.08, 0.075, 0.109], 0.5),
        ([0.08, 0.075, 2.287], -0.5),
        ([0.08, 3.923, 0.105], 0.5),
    ];
    let scene_text = |off_axis: f64| {
        let mut t = String::from(
            "name = \"drainage\"\ngravity = [0.0, 0.0, -9.81]\n[end_effector]\nmass = 1.5\n\
             position = [2.0, 2.0, 0.5]\ninertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]\n\
             [cable]\nyoungs_modulus = 1e11\narea = 1e-5\nweight_per_length = 0.5\n\
             [tension]\nt_min = 1.0\nt_max = 30.0\n[model]\nelement = \"fem\"\nelements_per_cable = 10\n\
             [effects]\nrotation = true\nsag = false\n",
        );
        for (a, z) in cables.iter() {
            // Off the axis: towards the anchor horizontally, so the cable's pull has no
            // moment about z and the pose stays in equilibrium.
            let (dx, dy): (f64, f64) = (a[0] - 2.0, a[1] - 2.0);
            let h = (dx * dx + dy * dy).sqrt();
            let (x, y) = (off_axis * dx / h, off_axis * dy / h);
            t.push_str(&format!(
                "[[cables]]\nanchor = [{}, {}, {}]\nattachment = [{x}, {y}, {z}]\n",
                a[0], a[1], a[2]
            ));
        }
        t
    };
    let dir = temp_dir("mechanism");
    let file = dir.join("drainage.toml");
    std::fs::write(&file, scene_text(0.0)).unwrap();
    let path = file.to_str().unwrap();
    let s = Scene::load(path).unwrap();
    let mut est = Estimator::new(&s).unwrap();
    let e = *est.update(&Pose::in_scene(&s, s.ee_position_m), Tmin::Scene);
    assert_eq!(e.status, Status::Mechanism, "{:?}", e.error);
    assert!(e.f1_hz.is_nan() && ee_hz(&e).is_nan());
    match e.error {
        Some(cablevib::estimator::EstimatorError::Mechanism { direction }) => {
            // Unit rotation about z (the closed form), nothing else.
            assert!((direction[5] - 1.0).abs() <= 1e-9, "{direction:?}");
            assert!(
                direction[..5].iter().all(|x| x.abs() <= 1e-6),
                "{direction:?}"
            );
        }
        other => panic!("{other:?}"),
    }
    // The tensions are still the equilibrium's (they are valid at a mechanism).
    let r =
        cablevib::estimator::reference_analysis(&s, &s.ee_position_m, Tmin::Scene, false).unwrap();
    for (a, b) in e.tensions().iter().zip(&r.tensions_n) {
        assert!((a - b).abs() <= 1e-6 * s.t_max_n, "{a} vs Clarabel {b}");
    }
    for extra in [
        &[][..],
        &["--solver", "dense"][..],
        &["--realtime", "--json"][..],
    ] {
        let mut args = vec!["analyze", path];
        args.extend_from_slice(extra);
        let o = run(&args);
        assert_eq!(o.status.code(), Some(1), "{extra:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("mechanism") && err.contains("rotation about (0.000, 0.000, 1.000)"),
            "{extra:?}: {err}"
        );
    }
    // Every attachment 5 cm off the axis: the spin is held, f1 > 0 and equal to the dense one.
    std::fs::write(&file, scene_text(0.05)).unwrap();
    let s = Scene::load(path).unwrap();
    let mut est = Estimator::new(&s).unwrap();
    let e = *est.update(&Pose::in_scene(&s, s.ee_position_m), Tmin::Scene);
    assert_eq!(e.status, Status::Ok, "{:?}", e.error);
    let r =
        cablevib::estimator::reference_analysis(&s, &s.ee_position_m, Tmin::Scene, false).unwrap();
    let f1_dense = cablevib::modal::lambda_to_hz(r.modes.lambda[0]);
    assert!(
        e.f1_hz > 0.01 && (e.f1_hz - f1_dense).abs() <= 1e-6 * f1_dense,
        "{} vs {f1_dense}",
        e.f1_hz
    );
}

/// `analyze --realtime --json` prints the estimate with its status whatever refuses the
/// pose: a default pose the cables cannot hold (`--t-min 350` on the paper robot, as CASPR's
/// FAST robot at its own pose), a refused orientation of a rigid platform, a `--position`
/// at an anchor. Before, the first two printed no JSON ("at its default pose: ..."). A
/// per-cable t_max behind an infeasibility is named as the cables' own bounds, not one range.
#[test]
fn realtime_json_prints_every_refused_pose_with_its_status() {
    for (args, status) in [
        (
            &["spatial-paper", "--t-min", "350"][..],
            "tension_infeasible",
        ),
        (
            &[
                "scenes/box_6dof.toml",
                "--orientation",
                "0.7071068,0.7071068,0,0",
            ][..],
            "tension_infeasible",
        ),
        (
            &["spatial-paper", "--position", "1.25,1.25,2.5"][..],
            "outside_workspace",
        ),
    ] {
        let mut a = vec!["analyze"];
        a.extend_from_slice(args);
        a.extend_from_slice(&["--realtime", "--json"]);
        let o = Command::new(env!("CARGO_BIN_EXE_cablevib"))
            .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
            .args(&a)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{a:?}");
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
            panic!(
                "{a:?}: no JSON ({e}): {}",
                String::from_utf8_lossy(&o.stderr)
            )
        });
        assert_eq!(v["status"], status, "{a:?}: {v}");
        assert!(v["f1_hz"].is_null(), "{a:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("default pose"), "{a:?}: {err}");
    }
    let dir = temp_dir("own_t_max");
    let text = include_str!("../../../scenes/spatial_paper.toml").replacen(
        "[[cables]]\nanchor = [1.25, 1.25, 0.0]",
        "[[cables]]\nanchor = [1.25, 1.25, 0.0]\nt_max = 101.0",
        1,
    );
    let file = dir.join("own_t_max.toml");
    std::fs::write(&file, text).unwrap();
    let o = run(&[
        "analyze",
        file.to_str().unwrap(),
        "--position",
        "0.9,0.9,0.5",
        "--realtime",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("tension_infeasible") && err.contains("each cable's own bounds"),
        "{err}"
    );
}
