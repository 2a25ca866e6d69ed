//! Standard output that cannot be written (`> /dev/full`): every command that prints ends
//! with one line naming the cause and exit status 1, where `println!` panicked (status
//! 101). The commands are read from clap, so a new one must be added here.

use cablevib_cli::cli::Cli;
use clap::CommandFactory;
use std::path::Path;
use std::process::{Command, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

/// Each command (or option) that prints to standard output, with quick arguments; `{data}`
/// is tests/data, `{dir}` the test's directory (with `record.csv`, a measured record).
const PRINTING: &[&[&str]] = &[
    &["analyze", "spatial-paper"],
    &["analyze", "spatial-paper", "--json"],
    &["analyze", "spatial-paper", "--realtime"],
    &[
        "bench",
        "spatial-paper",
        "--cycles",
        "50",
        "--dense-samples",
        "2",
    ],
    &["bench-ipc", "--samples", "20"],
    &["demo", "--seconds", "0.3"],
    &[
        "accuracy",
        "spatial-paper",
        "--max-elements",
        "4",
        "--cycles",
        "20",
        "--rounds",
        "1",
        "--dense-max",
        "2",
    ],
    &[
        "map",
        "spatial-paper",
        "--x",
        "-0.1,0.1",
        "--y",
        "0,0",
        "--step",
        "0.1",
        "--quiet",
    ],
    &[
        "trajectory",
        "spatial-paper",
        "--period-s",
        "0.01",
        "--quiet",
    ],
    &["sweep-tmin", "spatial-paper", "--steps", "2"],
    &["sag-compare", "spatial-paper", "--points", "3"],
    &["completions", "bash"],
    &["identify", "{dir}/record.csv"],
    &["man"],
    &["--help"],
    &["--version"],
    &[
        "import",
        "caspr",
        "{data}/caspr/planar_nguyen_bodies.xml",
        "{data}/caspr/planar_nguyen_cables.xml",
        "--weight-per-length",
        "1",
        "--area",
        "1e-6",
        "--youngs-modulus",
        "1e11",
        "-o",
        "imported.toml",
    ],
    &["modes", "spatial-paper", "--modes", "2"],
    &["frf", "spatial-paper", "--points", "5"],
    &["frf", "spatial-paper", "--points", "5", "--json"],
    &[
        "simulate",
        "spatial-paper",
        "--move",
        "0.01,0,0",
        "--duration",
        "0.2",
        "--settle",
        "0.05",
        "--modes",
        "2",
    ],
    &[
        "shape",
        "--move",
        "0.01,0,0",
        "--duration",
        "0.2",
        "-o",
        "shaped.csv",
    ],
];

/// Commands not run here, and why.
const NOT_RUN: &[(&str, &str)] = &[
    (
        "calibrate",
        "needs measured modes at several poses; its lines are the same `outln!` \
         (cli/tests/cli/calibrate.rs runs it)",
    ),
    ("serve", "logs to standard error only (tracing)"),
    (
        "monitor",
        "needs a running service; its lines are the same `outln!` (the monitor tests run it)",
    ),
    (
        "replay",
        "needs a running service and a recording (the monitor tests run it)",
    ),
];

#[test]
fn a_full_standard_output_is_a_one_line_error_for_every_command() {
    for sub in Cli::command().get_subcommands() {
        let name = sub.get_name();
        assert!(
            PRINTING.iter().any(|a| a[0] == name) || NOT_RUN.iter().any(|(n, _)| *n == name),
            "`cablevib {name}`: add it to PRINTING (or NOT_RUN, with the reason)"
        );
    }
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data");
    let dir =
        Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("stdout-full-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A measured record for `identify`: 10 s at 1 kHz of a decaying 12 Hz mode rung every 2 s.
    let mut rec = String::from("t,ax\n");
    for i in 0..10_000 {
        let t = i as f64 * 1e-3;
        let w = 2.0 * std::f64::consts::PI * 12.0;
        let a = (-0.02 * w * (t % 2.0)).exp() * (w * (t % 2.0)).sin()
            + 1e-3 * ((i * 7919 % 1000) as f64 / 500.0 - 1.0);
        rec.push_str(&format!("{t},{a}\n"));
    }
    std::fs::write(dir.join("record.csv"), rec).unwrap();
    for args in PRINTING {
        let args: Vec<String> = args
            .iter()
            .map(|a| {
                a.replace("{data}", &data.display().to_string())
                    .replace("{dir}", &dir.display().to_string())
            })
            .collect();
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let o = Command::new(BIN)
            .args(&args)
            .current_dir(&dir)
            .stdin(Stdio::null())
            .stdout(full)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        let what = format!("cablevib {} > /dev/full", args.join(" "));
        assert_eq!(o.status.code(), Some(1), "{what}: {err}");
        assert!(!err.contains("panicked"), "{what}: {err}");
        let ours: Vec<&str> = err.lines().filter(|l| l.starts_with("cablevib:")).collect();
        assert_eq!(
            ours,
            ["cablevib: cannot write to standard output: No space left on device (os error 28)"],
            "{what}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
