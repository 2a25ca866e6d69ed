//! `cablevib simulate` and `cablevib shape` on hostile inputs: a trajectory CSV with a jump,
//! with no data rows, with a single row or two rows at the same time (a path of zero
//! duration), with a NaN or an infinity, a CSV that does not exist, a `--move 0,0,0` (a move
//! of zero length), `--duration 0` (and negative), `--dt 0` (and NaN), `--modal-ratio 1`
//! (and NaN, and negative), `--tolerance` 0, 1 or NaN, `--modes` 0 or 257, `--update-every 0`.
//! Each is a one-line error naming the cause, exit code 1, no panic.

use std::path::PathBuf;
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

fn run(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("the binary runs")
}

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("cablevib-simulate-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Exit code 1, one line on stderr containing `needle`, no panic.
fn assert_one_line_error(what: &str, o: &Output, needle: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{what}: {err}");
    assert_eq!(o.status.code(), Some(1), "{what}: {err}");
    assert!(err.contains(needle), "{what}: `{needle}` not in {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{what}: {err}");
}

#[test]
fn simulate_refuses_hostile_inputs_in_one_line() {
    let d = dir();
    let out = d.join("out");
    let out = out.to_str().unwrap();
    let files = [
        (
            "jump.csv",
            "t,x,y,z\n0,0.1,0,1.25\n0.001,0.5,0,1.25\n0.002,0.5,0,1.25\n",
            "the path jumps",
        ),
        ("empty.csv", "t,x,y,z\n", "no data rows"),
        // two rows at the same time: zero duration
        (
            "same_t.csv",
            "t,x,y,z\n0,0.1,0,1.25\n0,0.1,0,1.25\n",
            "does not increase",
        ),
        // one row: a path of zero duration (refused like a move of --duration 0)
        (
            "one.csv",
            "t,x,y,z\n0,0.1,0,1.25\n",
            "needs at least two rows",
        ),
        (
            "nan.csv",
            "t,x,y,z\n0,0.1,0,1.25\n0.001,NaN,0,1.25\n0.002,0.1,0,1.25\n",
            "finite numbers",
        ),
        (
            "inf.csv",
            "t,x,y,z\n0,0.1,0,1.25\n0.001,0.1,inf,1.25\n",
            "finite numbers",
        ),
    ];
    for (name, text, needle) in files {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        let o = run(&[
            "simulate",
            "spatial-paper",
            "--csv",
            p.to_str().unwrap(),
            "--out",
            out,
        ]);
        assert_one_line_error(name, &o, needle);
    }
    // a missing file: the OS's reason once (it used to be printed twice, as the message's
    // end and again as its source)
    let missing = d.join("missing.csv");
    let o = run(&[
        "simulate",
        "spatial-paper",
        "--csv",
        missing.to_str().unwrap(),
    ]);
    assert_one_line_error("missing", &o, "cannot read trajectory CSV");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.matches("os error").count(), 1, "{err}");

    for (args, needle) in [
        (&["--move", "0,0,0"][..], "move of zero length"),
        (
            &["--move", "0.1,0,0", "--duration", "0"][..],
            "--duration 0",
        ),
        (
            &["--move", "0.1,0,0", "--duration", "-1"][..],
            "--duration -1",
        ),
        (&["--move", "0.1,0,0", "--dt", "0"][..], "--dt 0"),
        (&["--move", "0.1,0,0", "--dt", "NaN"][..], "--dt NaN"),
        (
            &["--move", "0.1,0,0", "--modal-ratio", "-0.01"][..],
            "--modal-ratio -0.01",
        ),
        (
            &["--move", "0.1,0,0", "--modal-ratio", "1"][..],
            "--modal-ratio 1",
        ),
        (
            &["--move", "0.1,0,0", "--modal-ratio", "NaN"][..],
            "--modal-ratio NaN",
        ),
        (
            &["--move", "0.1,0,0", "--tolerance", "0"][..],
            "--tolerance 0",
        ),
        (
            &["--move", "0.1,0,0", "--tolerance", "1"][..],
            "--tolerance 1",
        ),
        (
            &["--move", "0.1,0,0", "--tolerance", "NaN"][..],
            "--tolerance NaN",
        ),
        (&["--move", "0.1,0,0", "--modes", "0"][..], "--modes 0"),
        (&["--move", "0.1,0,0", "--modes", "257"][..], "--modes 257"),
        (
            &["--move", "0.1,0,0", "--update-every", "0"][..],
            "--update-every 0: must be ≥ 1",
        ),
    ] {
        let mut all = vec!["simulate", "spatial-paper", "--out", out];
        all.extend_from_slice(args);
        let o = run(&all);
        assert_one_line_error(&format!("{args:?}"), &o, needle);
    }
    // A scene whose damping leaves modes over-damped (Rayleigh β = 0.05 s: ζ = βω/2 = 1.76
    // at 11.2 Hz) is answered, not refused: every damping regime is propagated exactly
    // (tests/model/vibration_exact.rs checks the answer against the test's own integration).
    let scene = d.join("overdamped.toml");
    let text = format!(
        "{}\n[damping]\nrayleigh_beta = 0.05\n",
        cablevib::scene::DEFAULT_SCENE_TOML
    );
    std::fs::write(&scene, text).unwrap();
    let o = run(&[
        "simulate",
        scene.to_str().unwrap(),
        "--move",
        "0.1,0,0",
        "--elements",
        "10",
        "--out",
        out,
    ]);
    assert!(
        o.status.success(),
        "overdamped modes: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// `shape` refuses what `simulate` refuses, before it shapes anything: a jump (a shaped jump
/// is still a jump, half of it at a time with ZV), zero duration, NaN, a move of zero length,
/// a bad damping ratio.
#[test]
fn shape_refuses_hostile_inputs_in_one_line() {
    let d = std::env::temp_dir().join(format!("cablevib-shape-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let out = d.join("shaped.csv");
    let out = out.to_str().unwrap();
    for (name, text, needle) in [
        (
            "jump.csv",
            "t,x,y,z\n0,0.1,0,1.25\n0.001,0.5,0,1.25\n0.002,0.5,0,1.25\n",
            "the path jumps",
        ),
        (
            "one.csv",
            "t,x,y,z\n0,0.1,0,1.25\n",
            "needs at least two rows",
        ),
        (
            "same_t.csv",
            "t,x,y,z\n0,0.1,0,1.25\n0,0.1,0,1.25\n",
            "does not increase",
        ),
        (
            "nan.csv",
            "t,x,y,z\n0,0.1,0,1.25\n0.001,NaN,0,1.25\n0.002,0.1,0,1.25\n",
            "finite numbers",
        ),
    ] {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        let o = run(&["shape", p.to_str().unwrap(), "-o", out]);
        assert_one_line_error(name, &o, needle);
    }
    for (args, needle) in [
        (&["--move", "0,0,0"][..], "move of zero length"),
        (
            &["--move", "0.1,0,0", "--duration", "0"][..],
            "--duration 0",
        ),
        (&["--move", "0.1,0,0", "--dt", "0"][..], "--dt 0"),
        (
            &["--move", "0.1,0,0", "--modal-ratio", "1"][..],
            "--modal-ratio 1",
        ),
        (
            &["--move", "0.1,0,0", "--modal-ratio", "-0.01"][..],
            "--modal-ratio -0.01",
        ),
        (
            &["--move", "0.1,0,0", "--modal-ratio", "NaN"][..],
            "--modal-ratio NaN",
        ),
    ] {
        let mut all = vec!["shape", "-o", out];
        all.extend_from_slice(args);
        let o = run(&all);
        assert_one_line_error(&format!("shape {args:?}"), &o, needle);
    }
    assert!(!std::path::Path::new(out).exists(), "nothing shaped");
    let _ = std::fs::remove_dir_all(&d);
}

/// A move shorter than the sample period is a jump, refused by the one acceleration rule
/// whatever its duration: below half a period (1e-9 s, 4e-4 s) its samples both sat at the
/// start before (`shape` wrote 2 rows at x = 0 and `simulate` reported a peak of 0 mm, exit
/// 0), from half a period on (5e-4 s) it was refused as a jump already.
#[test]
fn a_move_shorter_than_a_sample_is_refused_as_the_jump_it_is() {
    let d = dir();
    let shaped = d.join("short-shaped.csv");
    let out = d.join("short-sim");
    for duration in ["1e-9", "4e-4", "5e-4"] {
        let mv = ["--move", "0.1,0,0", "--duration", duration];
        let mut args = vec!["shape"];
        args.extend(mv);
        args.extend(["-o", shaped.to_str().unwrap()]);
        assert_one_line_error(&args.join(" "), &run(&args), "the path jumps at t = 0");
        let mut args = vec!["simulate", "spatial-paper"];
        args.extend(mv);
        args.extend(["--out", out.to_str().unwrap()]);
        assert_one_line_error(&args.join(" "), &run(&args), "the path jumps at t = 0");
    }
    assert!(!shaped.exists());
    assert!(!d.join("short-sim.csv").exists());
}

/// `shape --help` lists only what `shape` accepts: the circle's options are `simulate`'s
/// (they were listed, and `shape --circle-s 5 --move ...` ignored them with exit 0); given
/// to `shape` they are clap's usage error.
#[test]
fn shape_lists_and_takes_no_circle_options() {
    let help = run(&["shape", "--help"]);
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(help.status.success() && text.contains("--move"), "{text}");
    for opt in ["--circle-s", "--period-s"] {
        assert!(!text.contains(opt), "{opt} in shape --help: {text}");
        let o = run(&["shape", opt, "5", "--move", "0.01,0,0", "-o", "x.csv"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{opt}: {err}");
        assert!(err.contains(opt), "{opt}: {err}");
    }
    let help = run(&["simulate", "--help"]);
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(
        text.contains("--circle-s") && text.contains("--period-s"),
        "{text}"
    );
}
