//! Hostile command lines run against the built binary (and the replay example): huge
//! durations, a reader that closes the pipe early, a pose outside the workspace, subnormal
//! numbers in error messages, and where `accuracy` writes by default. None may panic; each
//! must end with a one-line reason that names the real cause.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

/// Exit code of a Rust panic.
const PANIC_EXIT_CODE: i32 = 101;

fn run(args: &[&str]) -> Output {
    run_in(BIN, args, None)
}

fn run_in(bin: &str, args: &[&str], cwd: Option<&Path>) -> Output {
    let mut c = Command::new(bin);
    c.args(args).env("RUST_BACKTRACE", "0");
    if let Some(d) = cwd {
        c.current_dir(d);
    }
    c.output().expect("the binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Exit code not 101 and no panic message.
fn assert_no_panic(what: &str, o: &Output) {
    let err = stderr(o);
    assert_ne!(o.status.code(), Some(PANIC_EXIT_CODE), "{what}: {err}");
    assert!(!err.contains("panicked"), "{what}: {err}");
}

/// A usage error: exit code 1, one line on stderr containing `needle`.
fn assert_usage_error(what: &str, o: &Output, needle: &str) {
    assert_no_panic(what, o);
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{what}: {err}");
    assert!(err.contains(needle), "{what}: `{needle}` not in {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{what}: {err}");
}

#[test]
fn serve_huge_stats_period_is_a_usage_error() {
    let o = run(&[
        "serve",
        "--stats-period-s",
        "1e300",
        "--instance",
        "clih-stats",
    ]);
    assert_usage_error("serve 1e300", &o, "--stats-period-s 1e300 must be");
    // Rounds to a zero period: refused, not a log line every cycle.
    let o = run(&[
        "serve",
        "--stats-period-s",
        "5e-324",
        "--instance",
        "clih-stats",
    ]);
    assert_usage_error("serve 5e-324", &o, "--stats-period-s 5e-324 must be");
}

/// An instance name iceoryx2 would refuse is refused up front with one line naming the
/// allowed characters (before: "InvalidContent" alone, from iceoryx2).
#[test]
fn serve_bad_instance_names_the_allowed_characters() {
    for bad in ["é/ü", "a b", "x:y"] {
        let o = run(&["serve", "--instance", bad, "--max-cycles", "1"]);
        assert_usage_error(
            &format!("serve --instance {bad}"),
            &o,
            "only ASCII letters, digits",
        );
    }
}

/// Waits for `child` and checks it ended quietly: exit 0 or killed by SIGPIPE, no panic.
fn assert_quiet_end(what: &str, child: std::process::Child) {
    let o = child.wait_with_output().expect("wait");
    assert_no_panic(what, &o);
    let by_sigpipe = {
        use std::os::unix::process::ExitStatusExt;
        o.status.signal() == Some(libc::SIGPIPE)
    };
    assert!(
        o.status.success() || by_sigpipe,
        "{what}: {:?}, {}",
        o.status,
        stderr(&o)
    );
}

fn spawn_piped(args: &[&str]) -> std::process::Child {
    Command::new(BIN)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn")
}

#[test]
fn closed_stdout_ends_quietly() {
    let args = ["analyze", "spatial-paper", "--elements", "10", "--json"];
    // `| head -c 600`: read 600 bytes, then close the pipe.
    let mut child = spawn_piped(&args);
    let mut out = child.stdout.take().expect("stdout");
    let mut head = [0u8; 600];
    out.read_exact(&mut head).expect("600 bytes of JSON");
    assert!(head.starts_with(b"{"));
    drop(out);
    assert_quiet_end("head -c 600", child);
    // The reader is gone before anything is written: the write itself meets EPIPE.
    let mut child = spawn_piped(&args);
    drop(child.stdout.take());
    assert_quiet_end("closed before the first write", child);
    // Many lines (the table) into a closed pipe.
    let mut child = spawn_piped(&[
        "analyze",
        "spatial-paper",
        "--elements",
        "10",
        "--modes",
        "500",
    ]);
    drop(child.stdout.take());
    assert_quiet_end("table into a closed pipe", child);
}

#[test]
fn realtime_pose_outside_the_workspace_prints_its_status() {
    let o = run(&[
        "analyze",
        "spatial-paper",
        "--position",
        "5,5,5",
        "--realtime",
        "--json",
    ]);
    assert_no_panic("analyze 5,5,5", &o);
    let json: serde_json::Value =
        serde_json::from_slice(&o.stdout).expect("one JSON object on stdout");
    // No geometric pre-test: the tension distribution refuses it.
    assert_eq!(json["status"], "tension_infeasible");
    assert!(json["f1_hz"].is_null());
    // Documented: a refused pose exits 1, naming the status, not the scene's default pose.
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.contains("tension_infeasible"), "{err}");
    assert!(!err.contains("default pose"), "{err}");
    // The same with the auto model, which is chosen at the scene's own pose.
    let o = run(&[
        "analyze",
        "spatial-paper",
        "--position",
        "5,5,5",
        "--element",
        "auto",
        "--realtime",
        "--json",
    ]);
    assert_no_panic("analyze 5,5,5 auto", &o);
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(json["status"], "tension_infeasible");
    // A good pose still exits 0.
    let o = run(&["analyze", "spatial-paper", "--realtime", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn subnormal_numbers_print_compactly() {
    for (what, args, needle) in [
        (
            "map --step",
            &["map", "spatial-paper", "--step=-5e-324"][..],
            "--step -5e-324",
        ),
        (
            // A subnormal step: an infinite count, not an empty map.
            "map --step 5e-324",
            &["map", "spatial-paper", "--step", "5e-324"][..],
            "--step 5e-324: inf grid values on",
        ),
        (
            "demo --required-hz",
            &["demo", "--required-hz=-5e-324"][..],
            "--required-hz -5e-324",
        ),
        (
            "analyze --t-min",
            &["analyze", "spatial-paper", "--t-min", "1e300"][..],
            "t_min = 1e300 N",
        ),
    ] {
        let o = run(args);
        assert_usage_error(what, &o, needle);
        assert!(stderr(&o).len() < 300, "{what}: {}", stderr(&o));
    }
}

/// A fresh empty directory under the system's temporary directory.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cablevib-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

#[test]
fn accuracy_writes_its_own_directory_by_default() {
    let d = temp_dir("accuracy-default");
    let o = run_in(
        BIN,
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
        Some(&d),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(d.join("accuracy-out/accuracy.md").is_file());
    assert!(d
        .join("accuracy-out/data/accuracy-spatial-paper.csv")
        .is_file());
    assert!(!d.join("docs").exists(), "accuracy wrote into ./docs");
    let _ = std::fs::remove_dir_all(&d);
}

/// The replay example next to the binary (built by `cargo build --all-targets` and by
/// `cargo test`, which builds the examples).
fn replay_example() -> Option<PathBuf> {
    let p = Path::new(BIN).parent()?.join("examples").join("replay");
    p.is_file().then_some(p)
}

#[test]
fn replay_example_bounds_its_durations() {
    let Some(replay) = replay_example() else {
        eprintln!("replay example not built: skipped (its own unit tests cover the parsing)");
        return;
    };
    let replay = replay.to_str().expect("utf-8 path");
    for (args, needle) in [
        (
            &["--wait-for-service-s", "1e300"][..],
            "--wait-for-service-s 1e300 must be",
        ),
        (&["--seconds", "1e300"][..], "--seconds 1e300 must be"),
        (&["--rate-hz", "5e-324"][..], "--rate-hz 5e-324"),
    ] {
        let o = run_in(replay, args, None);
        assert_no_panic("replay", &o);
        assert_ne!(o.status.code(), Some(0), "{args:?}");
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
    }
}

/// Numbers of the user's scale in the tension and estimator messages print compactly
/// (`message_number`, or fixed decimals below 1e6): a 1e307 kg mass's infeasibility residual
/// was 309 digits long (`9810000000000000522839…`), as were the bounds, a required f1 and a
/// position of 1e308. The usual values keep their usual form (`[60, 350] N`, `0.0000`).
#[test]
fn user_scale_numbers_in_tension_and_estimator_messages_print_compactly() {
    let d = temp_dir("heavy");
    let scene = d.join("heavy.toml");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/spatial_paper.toml"),
    )
    .unwrap();
    assert!(text.contains("\nmass = 30.0 "));
    std::fs::write(
        &scene,
        text.replacen("\nmass = 30.0 ", "\nmass = 1e307 ", 1),
    )
    .unwrap();
    let o = run(&["analyze", scene.to_str().unwrap()]);
    assert_no_panic("analyze 1e307 kg", &o);
    let err = stderr(&o);
    assert!(
        err.contains("within [60, 350] N; closest tensions leave a residual force (0.0000, 0.0000, 9.81e307) N")
            && err.len() < 400,
        "{err}"
    );
    use cablevib::estimator::TminQueryError;
    use cablevib::tension::TensionError;
    let msgs = [
        (
            TminQueryError::BadRequirement(1e308).to_string(),
            "required f1 1e308 Hz",
        ),
        (
            TminQueryError::Unreachable {
                required_hz: 1e300,
                f1_max_hz: 12.345678,
                t_min_n: 1e307,
            }
            .to_string(),
            "f1 ≥ 1e300 Hz is unreachable: the most any feasible T_min gives is 12.3457 Hz (at 1e307 N)",
        ),
        (
            TensionError::InvalidBounds {
                t_min_n: -1e308,
                t_max_n: 1e308,
            }
            .to_string(),
            "t_min = -1e308 N, t_max = 1e308 N",
        ),
    ];
    for (msg, want) in msgs {
        assert!(msg.contains(want) && msg.len() < 200, "{msg}");
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// Directions of any scale are normalised by scaling first: `entry_direction = [1e308, 0,
/// 1e308]` is the direction (1, 0, 1) (it was "must be a non-zero direction": its norm
/// overflowed), `--tilt-axis 1e308,1e308,0` is (1, 1, 0) (it was "must be finite and
/// non-zero"). Each gives the same numbers, bit for bit, as the same direction of unit
/// scale; a zero direction is still refused.
#[test]
fn directions_of_any_scale_are_the_same_direction() {
    let d = temp_dir("directions");
    let pulleys = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/spatial_paper_pulleys.toml"),
    )
    .unwrap();
    let analyze = |dir: &str, name: &str| {
        let p = d.join(name);
        let text = pulleys.replace(
            "entry_direction = [0.0, 0.0, 1.0]",
            &format!("entry_direction = {dir}"),
        );
        std::fs::write(&p, text).unwrap();
        run(&["analyze", p.to_str().unwrap(), "--json"])
    };
    // The JSON without its one timing field.
    let numbers = |o: &Output| {
        assert!(o.status.success(), "{}", stderr(o));
        let mut v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v.as_object_mut().unwrap().remove("solve_seconds");
        v
    };
    let big = numbers(&analyze("[1e308, 0.0, 1e308]", "big.toml"));
    assert_eq!(big, numbers(&analyze("[1.0, 0.0, 1.0]", "unit.toml")));
    let zero = analyze("[0.0, 0.0, 0.0]", "zero.toml");
    assert_usage_error(
        "zero entry direction",
        &zero,
        "must be a non-zero direction",
    );

    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/box_6dof.toml");
    let map = |axis: &str, out: &str| {
        let out = d.join(out);
        let o = run(&[
            "map",
            scene.to_str().unwrap(),
            "--tilt-deg",
            "0,10",
            "--tilt-axis",
            axis,
            "--x",
            "0,0",
            "--y",
            "0,0",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ]);
        (o, std::fs::read(out.with_extension("csv")).ok())
    };
    let (o, big) = map("1e308,1e308,0", "big");
    assert!(o.status.success(), "{}", stderr(&o));
    let (o, unit) = map("1,1,0", "unit");
    assert!(o.status.success() && big.is_some() && big == unit);
    let (o, _) = map("0,0,0", "zero");
    assert_usage_error("zero tilt axis", &o, "must be finite and non-zero");
    let _ = std::fs::remove_dir_all(&d);
}

/// `map` and `trajectory` say how many ok points carry no end-effector mode (their
/// `ee_mode_hz` is NaN) instead of leaving the NaN unexplained: on suspended-8 with sag at
/// (−5, −3.4, 2) m no mode reaches the participation threshold within the scan's bounds,
/// at (−4, −3.4, 2) m one does. Before, the summary said only "statuses: ok 2".
#[test]
fn map_counts_ok_points_without_an_end_effector_mode() {
    let d = temp_dir("map-ee-missing");
    let out = d.join("m");
    let out_s = out.to_str().unwrap();
    let map = |extra: &[&str]| {
        let mut args = vec![
            "map",
            "suspended-8",
            "--sag",
            "true",
            "--x=-5,-4",
            "--y=-3.4",
        ];
        args.extend(["--z=2", "--step", "1", "--quiet", "--out", out_s]);
        args.extend(extra);
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let stdout = map(&[]);
    let text = std::fs::read_to_string(out.with_extension("csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|c| *c == n).unwrap();
    let (st, ee) = (col("status"), col("ee_mode_hz"));
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let ok = rows.iter().filter(|r| r[st] == "ok").count();
    let missing = rows
        .iter()
        .filter(|r| r[st] == "ok" && r[ee] == "NaN")
        .count();
    assert_eq!((ok, missing), (2, 1), "{text}");
    assert!(
        stdout
            .contains("end-effector mode: none found within the scan's bounds at 1 of 2 ok points"),
        "{stdout}"
    );
    // Without the end-effector mode asked for, nothing is missing.
    assert!(!map(&["--no-ee-mode"]).contains("end-effector mode:"));
    let _ = std::fs::remove_dir_all(&d);
}

/// `map` keeps grid coordinates to full precision: a grid at x = −1e-12 m is computed and
/// written at −1e-12 m (it was snapped to 0 in the grid, so both the CSV and the pose said
/// 0). Floating-point noise (0.25 + 7 × 0.1) is still written as 0.95.
#[test]
fn map_keeps_user_coordinates_to_full_precision() {
    let d = temp_dir("map-precision");
    let out = d.join("m");
    let o = run(&[
        "map",
        "spatial-paper",
        "--x",
        "-1e-12,-1e-12",
        "--y",
        "0.25,0.95",
        "--step",
        "0.1",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.with_extension("csv")).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 8, "{text}");
    assert!(rows.iter().all(|r| r[0] == "-0.000000000001"), "{text}");
    let ys: Vec<&str> = rows.iter().map(|r| r[1]).collect();
    assert_eq!(
        ys,
        ["0.25", "0.35", "0.45", "0.55", "0.65", "0.75", "0.85", "0.95"]
    );
    let _ = std::fs::remove_dir_all(&d);
}
