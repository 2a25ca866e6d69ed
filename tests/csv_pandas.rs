//! Every CSV that `map`, `trajectory`, `sweep-tmin` and `accuracy` write reads with plain
//! `pandas.read_csv(path)` — no options — with the columns docs/figures.md documents and one
//! row per evaluated point; each has a `PATH.json` sidecar naming the same columns.
//!
//! The test makes its own Python venv under target/ and pip-installs a pinned pandas
//! (PANDAS_VERSION); it needs `python3` with the venv module and PyPI. The expected columns
//! are written out here by hand from the documentation, not taken from the code under test.

use cablevib::cli;
use cablevib::cli::accuracy::AccuracyArgs;
use cablevib::cli::map::MapArgs;
use cablevib::cli::sweep_tmin::SweepTminArgs;
use cablevib::cli::trajectory::TrajectoryArgs;
use clap::Parser;
use std::path::{Path, PathBuf};
use std::process::Command;

/// pandas pinned for the check (installs on Python 3.11).
const PANDAS_VERSION: &str = "2.2.3";

#[derive(Parser)]
struct MapCli {
    #[command(flatten)]
    a: MapArgs,
}
#[derive(Parser)]
struct TrajCli {
    #[command(flatten)]
    a: TrajectoryArgs,
}
#[derive(Parser)]
struct TminCli {
    #[command(flatten)]
    a: SweepTminArgs,
}
#[derive(Parser)]
struct AccCli {
    #[command(flatten)]
    a: AccuracyArgs,
}

fn target_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target")
}

/// The venv's python, created and provisioned on first use.
fn venv_python() -> PathBuf {
    let venv = target_dir().join(format!("venv-pandas-{PANDAS_VERSION}"));
    let py = venv.join("bin").join("python");
    let has = |py: &Path| {
        Command::new(py)
            .args([
                "-c",
                &format!("import pandas, sys; sys.exit(pandas.__version__ != '{PANDAS_VERSION}')"),
            ])
            .status()
            .is_ok_and(|s| s.success())
    };
    if !has(&py) {
        let st = Command::new("python3")
            .args(["-m", "venv", venv.to_str().unwrap()])
            .status()
            .expect("python3 -m venv");
        assert!(st.success(), "python3 -m venv failed");
        let st = Command::new(&py)
            .args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "--disable-pip-version-check",
                &format!("pandas=={PANDAS_VERSION}"),
            ])
            .status()
            .expect("pip install");
        assert!(st.success(), "pip install pandas=={PANDAS_VERSION} failed");
        assert!(
            has(&py),
            "pandas {PANDAS_VERSION} not importable after install"
        );
    }
    py
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
