//! `cablevib map --shard I/N` run as a batch scheduler's array job would: the shards' CSVs,
//! in order and with the header kept only from the first, are the unsharded CSV byte for
//! byte (the independent check is the unsharded run itself: the same binary without the
//! option); a bad shard spec is a one-line usage error; a shard writes no figure.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cablevib-shard-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("the binary runs")
}

/// `cablevib map GRID.. --out DIR/NAME [EXTRA..]`; the CSV's text.
fn map_csv(grid: &[&str], out: &Path, extra: &[&str]) -> String {
    let out_s = out.to_str().unwrap();
    let mut args = vec!["map"];
    args.extend_from_slice(grid);
    args.extend_from_slice(&["--quiet", "--out", out_s]);
    args.extend_from_slice(extra);
    let o = run(&args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::read_to_string(out.with_extension("csv")).unwrap()
}

/// The shards 1..=n of `grid` concatenated, the header kept from the first only.
fn concatenated(grid: &[&str], d: &Path, n: usize) -> String {
    let mut all = String::new();
    for i in 1..=n {
        let out = d.join(format!("s{i}of{n}"));
        let spec = format!("{i}/{n}");
        let text = map_csv(grid, &out, &["--shard", &spec, "--threads", "1"]);
        assert!(
            !out.with_extension("svg").exists(),
            "shard {spec} wrote a figure"
        );
        let side = std::fs::read_to_string(out.with_extension("csv.json")).unwrap();
        assert!(side.contains("\"shard\""), "{side}");
        if i == 1 {
            all.push_str(&text);
        } else {
            let body = text.split_once('\n').map_or("", |(_, b)| b);
            all.push_str(body);
        }
    }
    all
}

fn check(name: &str, grid: &[&str], counts: &[usize]) {
    let d = dir(name);
    let whole = map_csv(grid, &d.join("whole"), &[]);
    assert!(whole.lines().count() > 2, "{whole}");
    for &n in counts {
        assert!(
            concatenated(grid, &d, n) == whole,
            "{name}: {n} shards differ from the unsharded map"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn shards_concatenate_to_the_unsharded_map_paper_robot() {
    // 5 × 5 × 2 = 50 points in 10 rows: 3 shards of 3, 3 and 4 rows; 12 shards, two empty.
    let grid = [
        "spatial-paper",
        "--x=-0.5,0.5",
        "--y=-0.5,0.5",
        "--z=0.5,0.75",
        "--step",
        "0.25",
        "--modes",
        "3",
    ];
    check("paper", &grid, &[1, 3, 12]);
}

#[test]
fn shards_concatenate_to_the_unsharded_map_sagging_cables() {
    // The suspended robot with its cables on the elastic catenary: 4 × 3 = 12 points.
    let grid = [
        "suspended-8",
        "--x=-3,3",
        "--y=-2,2",
        "--step",
        "2",
        "--no-ee-mode",
    ];
    check("sag", &grid, &[2]);
}

#[test]
fn bad_shard_specs_are_one_line_errors() {
    let d = dir("bad");
    let out = d.join("m");
    for spec in ["0/3", "4/3", "1/0", "a/b", "1/", "/", "2"] {
        let o = run(&[
            "map",
            "spatial-paper",
            "--step",
            "0.5",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
            "--shard",
            spec,
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{spec}: {err}");
        assert!(err.starts_with("cablevib: --shard `"), "{spec}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{spec}: {err}");
        assert!(!out.with_extension("csv").exists(), "{spec}");
    }
    // A shard draws no figure, so the figure options are refused with it.
    let o = run(&[
        "map",
        "spatial-paper",
        "--shard",
        "1/2",
        "--svg",
        d.join("f.svg").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--shard"));
    let _ = std::fs::remove_dir_all(&d);
}
