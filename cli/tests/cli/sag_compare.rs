//! `cablevib sag-compare`: its CSV reads with the csv crate and has the documented columns,
//! and every row equals what `cablevib analyze --json --position … --sag false|true` prints
//! at that pose, bit for bit (the reference is the analyze command itself, a separate
//! process: f1, the tensions, and the sagged fields; numbers are compared as the text each
//! prints, parsed by Rust's correctly rounded `str::parse`, so equality is exact).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cablevib"))
        .args(args)
        .output()
        .expect("run cablevib")
}

fn ok(o: Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("sag-compare");
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// The CSV as (header, rows of fields).
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|x| x.unwrap().iter().map(String::from).collect())
        .collect();
    (header, rows)
}

/// The numbers of the JSON array `key` in `analyze --json`'s text, parsed from their own
/// digits (no JSON float parser in between).
fn json_numbers(text: &str, key: &str) -> Vec<f64> {
    let start = text.find(&format!("\"{key}\":[")).expect(key) + key.len() + 4;
    let end = start + text[start..].find(']').unwrap();
    text[start..end]
        .split(',')
        .map(|x| x.parse::<f64>().unwrap())
        .collect()
}

/// The field `name` of a row, as a number.
fn field(header: &[String], row: &[String], name: &str) -> f64 {
    let i = header.iter().position(|h| h == name).expect(name);
    row[i].parse().unwrap()
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

/// One row of a sag-compare CSV against `analyze` at its pose, both models.
fn row_equals_analyze(scene: &str, element: &str, header: &[String], row: &[String]) {
    let n_cables = header
        .iter()
        .filter(|h| {
            h.starts_with("chord_tension")
                && h.ends_with("_n")
                && h[13..h.len() - 2].parse::<usize>().is_ok()
        })
        .count();
    let pos = format!(
        "{},{},{}",
        row[1],
        row[2],
        row[3] // x_m, y_m, z_m: exact forms, read back to the same f64
    );
    for (prefix, sag) in [("chord", "false"), ("sag", "true")] {
        let text = ok(run(&[
            "analyze",
            scene,
            "--json",
            "--modes",
            "1",
            "--element",
            element,
            "--position",
            &pos,
            "--sag",
            sag,
        ]));
        let col = |c: &str| field(header, row, &format!("{prefix}_{c}"));
        let f1 = json_numbers(&text, "frequencies_hz")[0];
        assert_eq!(col("f1_hz").to_bits(), f1.to_bits(), "{prefix} f1 at {pos}");
        let t: Vec<f64> = (1..=n_cables)
            .map(|i| col(&format!("tension{i}_n")))
            .collect();
        assert_eq!(
            bits(&t),
            bits(&json_numbers(&text, "tensions_n")),
            "{prefix} at {pos}"
        );
        let tmax = t.iter().copied().fold(f64::NAN, f64::max);
        assert_eq!(col("tension_max_n").to_bits(), tmax.to_bits());
        if sag == "true" {
            let l2 = json_numbers(&text, "irvine_lambda2");
            let l2max = l2.iter().copied().fold(f64::NAN, f64::max);
            assert_eq!(
                field(header, row, "sag_irvine_lambda2_max").to_bits(),
                l2max.to_bits()
            );
            let tmin = json_numbers(&text, "tensions_min_n")
                .iter()
                .copied()
                .fold(f64::NAN, f64::min);
            assert_eq!(col("tension_min_n").to_bits(), tmin.to_bits());
        }
    }
}

#[test]
fn csv_columns_and_rows_equal_analyze_bit_for_bit() {
    let out = tmp("s8");
    let o = out.to_str().unwrap();
    ok(run(&[
        "sag-compare",
        "suspended-8",
        "--span-m",
        "-2,2",
        "--points",
        "5",
        "--threads",
        "2",
        "--quiet",
        "--out",
        o,
    ]));
    let (header, rows) = read_csv(&out.with_extension("csv"));
    let mut expected = vec!["offset_m", "x_m", "y_m", "z_m"];
    let model = |p: &str| {
        let mut c: Vec<String> = [
            "status",
            "f1_hz",
            "stiffness_min_n_m",
            "tension_max_n",
            "tension_min_n",
        ]
        .iter()
        .map(|x| format!("{p}_{x}"))
        .collect();
        c.extend((1..=8).map(|i| format!("{p}_tension{i}_n")));
        c
    };
    let (chord, sag) = (model("chord"), model("sag"));
    expected.extend(chord.iter().map(String::as_str));
    expected.extend(sag.iter().map(String::as_str));
    expected.extend(["sag_irvine_lambda2_max", "sag_sag_max_m"]);
    assert_eq!(header, expected);
    assert_eq!(rows.len(), 5);
    // The sidecar documents every column with a unit.
    let side: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.with_extension("csv.json")).unwrap())
            .unwrap();
    assert_eq!(side["command"], "sag-compare");
    assert!(std::fs::metadata(out.with_extension("svg")).unwrap().len() > 0);
    // The centre and one off-centre pose (x = 1 m), both models ok there.
    for row in [&rows[2], &rows[3]] {
        let status = |p: &str| {
            row[header
                .iter()
                .position(|h| h == &format!("{p}_status"))
                .unwrap()]
            .clone()
        };
        assert_eq!((status("chord"), status("sag")), ("ok".into(), "ok".into()));
        row_equals_analyze("suspended-8", "fem", &header, row);
    }
}

#[test]
fn continuous_element_rows_equal_analyze_and_sag_flag_is_refused() {
    let out = tmp("fast-cont");
    let o = out.to_str().unwrap();
    ok(run(&[
        "sag-compare",
        "fast-like",
        "--element",
        "continuous",
        "--axis",
        "y",
        "--span-m",
        "0,20",
        "--points",
        "2",
        "--threads",
        "1",
        "--quiet",
        "--out",
        o,
    ]));
    let (header, rows) = read_csv(&out.with_extension("csv"));
    for row in &rows {
        row_equals_analyze("fast-like", "continuous", &header, row);
    }
    // Both models are evaluated: --sag has no meaning here and is refused, not ignored.
    let r = run(&["sag-compare", "fast-like", "--sag", "true", "--out", o]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("both models"));
}

#[test]
fn spans_beyond_the_offset_bound_are_refused_in_one_line() {
    let out = tmp("huge-span");
    let _ = std::fs::remove_file(out.with_extension("csv"));
    let o = out.to_str().unwrap();
    for span in ["--span-m=-1e308,1e308", "--span-m=0,2e6"] {
        let r = run(&["sag-compare", "spatial-paper", span, "--quiet", "--out", o]);
        let e = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success(), "{span}: exit 0, {e}");
        assert!(
            e.trim().lines().count() == 1 && e.contains("--span-m") && e.contains("±1e6"),
            "{span}: {e}"
        );
        assert!(!e.contains("000000000000"), "compact numbers: {e}");
        assert!(!out.with_extension("csv").exists(), "{span}: no CSV");
    }
}
