//! Long work says so: `frf`, `simulate` and `modes` print an estimate of their time on stderr
//! before a run of more than `study::cost::ANNOUNCE_AFTER_S` (10 s) starts, and draw a
//! progress bar with its ETA when stderr is a terminal (none into a pipe or a file). Each
//! child is stopped once it has said what the test looks for (the runs take minutes to
//! hours). Before, `frf --elements 1000000 --points 100000 --loss-factor 0.02` (17 h here)
//! printed nothing until it ended, and `modes --csv` drew no bar while it built the CSV's
//! text, nearly all of its minute at 10⁵ elements per cable.

use std::io::{BufRead, BufReader, Read};
use std::os::fd::{FromRawFd, OwnedFd};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

/// The first line of `child`'s stderr (piped), then the child is killed.
fn first_stderr_line(mut child: Child) -> String {
    let mut line = String::new();
    let err = child.stderr.take().unwrap();
    BufReader::new(err).read_line(&mut line).unwrap();
    let _ = child.kill();
    let _ = child.wait();
    line
}

fn spawn_piped(args: &[&str]) -> Child {
    Command::new(BIN)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs")
}

/// What `args` write on a pseudo-terminal as stderr until it holds `unit` and "ETA" (a bar)
/// or `wait` has passed, then the child is killed.
fn stderr_on_a_terminal(args: &[&str], unit: &str, wait: Duration) -> String {
    let (mut master, mut slave) = (0, 0);
    // SAFETY: openpty fills two descriptors; null name, termios and window size are allowed.
    let r = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    assert_eq!(r, 0, "openpty");
    // SAFETY: both descriptors are fresh and owned here.
    let (master, slave) = unsafe { (OwnedFd::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) };
    let mut child = Command::new(BIN)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::from(slave))
        .spawn()
        .expect("the binary runs");
    let mut reader = std::fs::File::from(master);
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while let Ok(n) = reader.read(&mut buf) {
            if n == 0 || tx.send(buf[..n].to_vec()).is_err() {
                break;
            }
        }
    });
    let start = Instant::now();
    let mut out = Vec::new();
    while start.elapsed() < wait {
        if let Ok(b) = rx.recv_timeout(Duration::from_millis(100)) {
            out.extend(b);
            let text = String::from_utf8_lossy(&out);
            if text.contains(unit) && text.contains("ETA") {
                break;
            }
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    String::from_utf8_lossy(&out).into_owned()
}

#[test]
fn long_runs_announce_their_estimate_and_draw_a_progress_bar_on_a_terminal() {
    let dir = std::env::temp_dir().join(format!("cablevib-long-work-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("m.csv");
    let sim = dir.join("sim");
    let frf = [
        "frf",
        "spatial-paper",
        "--elements",
        "1000000",
        "--loss-factor",
        "0.02",
        "--points",
        "100000",
    ];
    let simulate = [
        "simulate",
        "spatial-paper",
        "--elements",
        "100000",
        "--move",
        "0.1,0,0",
        "--duration",
        "1",
        "--out",
        sim.to_str().unwrap(),
    ];
    let modes = [
        "modes",
        "spatial-paper",
        "--elements",
        "100000",
        "--modes",
        "12",
        "--csv",
        csv.to_str().unwrap(),
    ];
    for (args, needle) in [
        (
            &frf[..],
            "for 100000 frequencies at 1000000 elements per cable",
        ),
        (
            &simulate[..],
            "for 3001 samples at 100000 elements per cable",
        ),
        (&modes[..], "for 12 modes at 100000 elements per cable"),
    ] {
        let line = first_stderr_line(spawn_piped(args));
        println!("{}: {}", args[0], line.trim_end());
        assert!(
            line.starts_with("cablevib: ") && line.contains("about ") && line.contains(needle),
            "{args:?}: {line}"
        );
    }
    // On a terminal: the estimate, then the bar with its unit and ETA (drawn once the run
    // has gone on for a second; here within ~10 s, 60 s allowed for a loaded machine).
    // `modes`' long part is its CSV's text (~3.5 s per mode at 10⁵ elements per cable, after
    // ~1.5 s of shapes): its bar counts modes written.
    // `simulate`'s first long part is the pilot choosing K (its bases of 24, 48, … modes at
    // three poses, ~2 s per 24 modes at 10⁵ elements per cable): its bar counts the pilot's
    // modes run (before, it had none, and the test waited in vain).
    for (args, unit) in [
        (&frf[..], "frequencies"),
        (&simulate[..], "pilot modes"),
        (&modes[..], "modes written"),
    ] {
        let text = stderr_on_a_terminal(args, unit, Duration::from_secs(60));
        println!("{}: {:?}", args[0], text.lines().last());
        assert!(text.contains("about "), "{args:?}: {text}");
        assert!(
            text.contains(unit) && text.contains("ETA"),
            "{args:?}: no bar in {text:?}"
        );
    }
    // A short run says nothing more than before: no estimate, no bar.
    let o = Command::new(BIN)
        .args(["frf", "spatial-paper", "--points", "100"])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(
        o.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
