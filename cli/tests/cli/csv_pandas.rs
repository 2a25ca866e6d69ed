//! Every CSV that `map`, `trajectory`, `sweep-tmin`, `sag-compare` and `accuracy` write reads with plain
//! `pandas.read_csv(path)` — no options — with the columns docs/figures.md documents and one
//! row per evaluated point; each has a `PATH.json` sidecar naming the same columns.
//!
//! A second test checks the columns' values: f2 .. fK are `Estimator::modes`, f1 is
//! unchanged by `--modes`.
//!
//! The test makes its own Python venv under target/ and pip-installs a pinned pandas
//! (PANDAS_VERSION); it needs `python3` with the venv module and PyPI. The expected columns
//! are written out here by hand from the documentation, not taken from the code under test.

use cablevib::estimator::Tmin;
use cablevib_cli::cli;
use clap::Parser;
use std::path::{Path, PathBuf};
use std::process::Command;

/// pandas pinned for the check (installs on Python 3.11).
const PANDAS_VERSION: &str = "2.2.3";

use super::sweep_cli::{AccCli, MapCli, SagCli, TminCli, TrajCli};

fn target_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/..")).join("target")
}

/// The venv's python, created and provisioned on first use.
fn venv_python() -> PathBuf {
    cablevib_testkit::pinned_venv::pinned_venv_python(
        &format!("venv-pandas-{PANDAS_VERSION}"),
        &[("pandas", "pandas", PANDAS_VERSION)],
    )
}

/// Columns of a point row (map; trajectory after t_s, angle_deg), documented in
/// docs/figures.md: position, T_min, status, f1, the end-effector mode, participations,
/// tensions of cables 1..=n, f2..fk, the smallest stiffness.
fn point_columns(n_cables: usize, k: usize) -> Vec<String> {
    let mut c: Vec<String> = [
        "x_m",
        "y_m",
        "z_m",
        "t_min_n",
        "status",
        "f1_hz",
        "ee_mode_hz",
        "f1_ee_participation",
        "ee_mode_participation",
    ]
    .map(String::from)
    .to_vec();
    c.extend((1..=n_cables).map(|i| format!("tension{i}_n")));
    c.extend((2..=k).map(|j| format!("f{j}_hz")));
    c.push("stiffness_min_n_m".into());
    c
}

/// Header and data rows of a CSV with no quoted fields (the point CSVs).
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let split = |l: &str| l.split(',').map(String::from).collect::<Vec<_>>();
    let header = split(lines.next().unwrap());
    (header, lines.map(split).collect())
}

/// One CSV to check: path, expected header, expected row count.
struct Expect {
    path: PathBuf,
    columns: Vec<String>,
    rows: usize,
}

fn run_commands(d: &Path) -> Vec<Expect> {
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let map = d.join("map");
    let cli = MapCli::try_parse_from([
        "map",
        "spatial-paper",
        "--x=-1,1",
        "--y=-1,1",
        "--z=0.25,1.25",
        "--step",
        "1",
        "--modes",
        "3",
        "--show",
        "f3,k-min",
        "--quiet",
        "--out",
        &s(&map),
    ])
    .unwrap();
    cli::map::run(&cli.a).unwrap();
    let traj = d.join("traj");
    let cli = TrajCli::try_parse_from([
        "trajectory",
        "planar-paper",
        "--t-mins",
        "20,40",
        "--period-s",
        "0.01",
        "--modes",
        "2",
        "--quiet",
        "--out",
        &s(&traj),
    ])
    .unwrap();
    cli::trajectory::run(&cli.a).unwrap();
    let tmin = d.join("tmin");
    let cli = TminCli::try_parse_from([
        "sweep-tmin",
        "planar-paper",
        "--from",
        "20",
        "--to",
        "80",
        "--steps",
        "4",
        "--modes",
        "4",
        "--out",
        &s(&tmin),
    ])
    .unwrap();
    cli::sweep_tmin::run(&cli.a).unwrap();
    let acc = d.join("acc");
    let cli = AccCli::try_parse_from([
        "accuracy",
        "planar-paper",
        "--out-dir",
        &s(&acc),
        "--max-elements",
        "2",
        "--cycles",
        "3",
        "--dense-max",
        "2",
        "--rounds",
        "1",
    ])
    .unwrap();
    cli::accuracy::run(&cli.a).unwrap();

    let sagc = d.join("sagc");
    let cli = SagCli::try_parse_from([
        "sag-compare",
        "suspended-8",
        "--points",
        "3",
        "--quiet",
        "--out",
        &s(&sagc),
    ])
    .unwrap();
    cli::sag_compare::run(&cli.a).unwrap();
    // Its exact header is checked in cli/tests/cli/sag_compare.rs; here pandas must read the same
    // names as the csv crate does.
    let sagc_cols: Vec<String> = csv::Reader::from_path(sagc.with_extension("csv"))
        .unwrap()
        .headers()
        .unwrap()
        .iter()
        .map(String::from)
        .collect();

    let mut traj_cols: Vec<String> = vec!["t_s".into(), "angle_deg".into()];
    traj_cols.extend(point_columns(4, 2));
    let mut tmin_cols: Vec<String> = ["t_min_n", "status", "f1_hz", "ee_mode_hz", "fit_hz"]
        .map(String::from)
        .to_vec();
    tmin_cols.extend(["f2_hz", "f3_hz", "f4_hz", "stiffness_min_n_m"].map(String::from));
    let acc_cols = "model,element,n,geometric_stiffness,status,f1_hz,err_ref,err_continuous,ee_mode_hz,ee_err_ref,f1_p50_ns,f1_p99_ns,ee_p50_ns,ee_p99_ns,evaluations_p50";
    let m3_cols = "element,n,dof,mode1_hz,mode2_hz,mode3_hz,dense_seconds";
    let split = |c: &str| c.split(',').map(String::from).collect::<Vec<_>>();
    vec![
        // 3 × 3 × 2 grid, spatial robot (8 cables).
        Expect {
            path: map.with_extension("csv"),
            columns: point_columns(8, 3),
            rows: 18,
        },
        // 0.01 s circle at 1 ms: 11 poses × 2 T_min values.
        Expect {
            path: traj.with_extension("csv"),
            columns: traj_cols,
            rows: 22,
        },
        Expect {
            path: tmin.with_extension("csv"),
            columns: tmin_cols,
            rows: 4,
        },
        // Massless ×2, continuous, FEM and catenary at N = 1, 2.
        Expect {
            path: acc.join("data/accuracy-planar-paper.csv"),
            columns: split(acc_cols),
            rows: 3 + 2 * 2,
        },
        // Chord and sagged model along a line: 3 poses.
        Expect {
            path: sagc.with_extension("csv"),
            columns: sagc_cols,
            rows: 3,
        },
        // Dense study: FEM and catenary at N = 1, 2.
        Expect {
            path: acc.join("data/mode3-planar-paper.csv"),
            columns: split(m3_cols),
            rows: 4,
        },
    ]
}

/// Reads every CSV with `pandas.read_csv(path)` and its sidecar with `json.load`; prints one
/// line per file: path, row count, the columns joined by `|`, the sidecar's column names and
/// row count, and whether every `_hz` column is numeric.
const READER: &str = r#"
import json, sys
import pandas
for path in sys.argv[1:]:
    df = pandas.read_csv(path)
    side = json.load(open(path + ".json"))
    names = [c["name"] for c in side["columns"]]
    numeric = all(pandas.api.types.is_numeric_dtype(df[c]) for c in df.columns if c.endswith("_hz"))
    print("\t".join([path, str(len(df)), "|".join(df.columns), "|".join(names), str(side["rows"]), str(numeric)]))
"#;

#[test]
fn every_sweep_csv_reads_with_plain_pandas_read_csv() {
    let d = target_dir().join(format!("csv-pandas-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let expect = run_commands(&d);
    for e in &expect {
        let text = std::fs::read_to_string(&e.path).unwrap();
        assert!(!text.contains('#'), "{}: a comment line", e.path.display());
    }
    let py = venv_python();
    let out = Command::new(py)
        .arg("-c")
        .arg(READER)
        .args(expect.iter().map(|e| e.path.to_str().unwrap()))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "pandas failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), expect.len(), "{stdout}");
    for (e, line) in expect.iter().zip(lines) {
        let f: Vec<&str> = line.split('\t').collect();
        let want = e.columns.join("|");
        assert_eq!(f[0], e.path.to_str().unwrap());
        assert_eq!(f[1], e.rows.to_string(), "{}: rows", f[0]);
        assert_eq!(f[2], want, "{}: pandas columns", f[0]);
        assert_eq!(f[3], want, "{}: sidecar columns", f[0]);
        assert_eq!(f[4], e.rows.to_string(), "{}: sidecar rows", f[0]);
        assert_eq!(f[5], "True", "{}: a _hz column is not numeric", f[0]);
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `--modes K`: the f1 column is the cycle's f1 bit for bit (the same as with `--modes 1`,
/// today's output), f2 .. fK are `Estimator::modes` of a fresh estimator at the same pose,
/// and `stiffness_min_n_m` is the smallest eigenvalue of the stiffness by an independent
/// 3 × 3 solver (cyclic Jacobi, `eig3::eig3_jacobi`, against nalgebra's in the study).
#[test]
fn map_modes_columns_are_the_estimator_modes_and_f1_is_unchanged() {
    const K: usize = 4;
    let d = target_dir().join(format!("csv-modes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let run = |k: usize, name: &str| {
        let out = d.join(name);
        let cli = MapCli::try_parse_from([
            "map",
            "spatial-paper",
            "--x=-1,1",
            "--y=-1,1",
            "--z=0.25,1.25",
            "--step",
            "1",
            "--quiet",
            "--modes",
            &k.to_string(),
            "--out",
            out.to_str().unwrap(),
        ])
        .unwrap();
        cli::map::run(&cli.a).unwrap();
        let (_, m) = cli::map::compute(&cli.a).unwrap();
        (read_csv(&out.with_extension("csv")), m)
    };
    let ((h1, rows1), m1) = run(1, "one");
    let ((hk, rowsk), mk) = run(K, "four");
    let f1 = |h: &[String]| h.iter().position(|c| c == "f1_hz").unwrap();
    assert_eq!(rows1.len(), rowsk.len());
    for (a, b) in rows1.iter().zip(&rowsk) {
        assert_eq!(a[f1(&h1)], b[f1(&hk)], "f1 column text");
    }
    for (a, b) in m1.points.iter().zip(&mk.points) {
        assert_eq!(a.estimate.f1_hz.to_bits(), b.estimate.f1_hz.to_bits());
        assert_eq!(a.estimate.status, b.estimate.status);
    }
    let s = cablevib::scene::Scene::default_scene();
    let mut est = cablevib::estimator::Estimator::new(&s).unwrap();
    let col = |n: &str| hk.iter().position(|c| c == n).unwrap();
    let mut checked = 0;
    for (row, p) in rowsk.iter().zip(&mk.points).step_by(2) {
        let e = *est.update(&cablevib::kinematics::Pose::at(p.position_m), Tmin::Scene);
        assert_eq!(e.status, p.estimate.status);
        if !e.is_ok() {
            assert!(row[col("f2_hz")] == "NaN" && row[col("stiffness_min_n_m")] == "NaN");
            continue;
        }
        let mut modes = [cablevib::modal::Mode::default(); K];
        assert_eq!(est.modes(K, &mut modes).unwrap(), K);
        for (j, m) in modes.iter().enumerate().skip(1) {
            let csv: f64 = row[col(&format!("f{}_hz", j + 1))].parse().unwrap();
            // The CSV prints 9 significant digits (relative rounding ≤ 5e-9); the map's
            // estimator was warm-started along its row, this one cold: both solve the same
            // tensions to rounding and the modes to 1e-14, far inside that.
            assert!(
                (csv - m.frequency_hz).abs() <= 5e-9 * m.frequency_hz,
                "f{}: csv {csv} vs modes {}",
                j + 1,
                m.frequency_hz
            );
            let study = p.modes_hz[j];
            assert!((study - m.frequency_hz).abs() <= 1e-10 * m.frequency_hz);
        }
        // Mode 1 of the spectrum is f1 (same structured engine, its own root search).
        assert!((modes[0].frequency_hz - e.f1_hz).abs() <= 1e-10 * e.f1_hz);
        let jac = cablevib::eig3::eig3_jacobi(&e.stiffness.translational_n_m()).values[0];
        let kmin: f64 = row[col("stiffness_min_n_m")].parse().unwrap();
        // Printed with 7 significant digits; the two eigensolvers agree to ~ε‖K‖.
        assert!((kmin - jac).abs() <= 1e-6 * jac, "{kmin} vs {jac}");
        assert!((p.stiffness_min_n_m - jac).abs() <= 1e-12 * jac);
        checked += 1;
    }
    assert!(checked >= 3, "{checked} ok points checked");
    // --modes out of range, and --show fK beyond --modes, are usage errors.
    let bad = |args: &[&str]| {
        let mut v = vec!["map", "planar-paper", "--quiet"];
        v.extend_from_slice(args);
        cli::map::compute(&MapCli::try_parse_from(v).unwrap().a).is_err()
    };
    assert!(bad(&["--modes", "0"]));
    assert!(bad(&["--modes", "17"]));
    assert!(bad(&["--modes", "2", "--show", "f3"]));
    assert!(MapCli::try_parse_from(["map", "planar-paper", "--show", "f0"]).is_err());
    let _ = std::fs::remove_dir_all(&d);
}
