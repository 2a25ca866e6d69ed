//! The rule of every command that writes a file: an output that is one of the command's
//! inputs (the same file: here a hard link, another name for it) is refused before anything
//! is written, with one line naming both, and the input's bytes are unchanged; a run whose
//! writes fail, or that SIGINT interrupts mid-write, leaves no partial output and a file
//! that was at the target before untouched.
//!
//! The path options are read from the command line's own definition (clap): every option
//! whose value is a path must be in [`PATH_OPTIONS`], as an input or with the cases that
//! exercise it as an output, so a new command or option cannot be forgotten here.

use cablevib_cli::cli::Cli;
use clap::CommandFactory;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

/// Which input a case makes its output equal to.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Input {
    /// `{scene}`: a copy of scenes/spatial_paper.toml.
    Scene,
    /// `{traj}`: a trajectory CSV.
    Trajectory,
    /// `{bodies}`: CASPR's bodies XML (with `{cables}`).
    Bodies,
    /// `{rec}`: a measured-acceleration CSV for `identify`.
    Recording,
}

/// One run of a command with an output option.
struct Case {
    /// The command line: `{scene}`, `{traj}`, `{bodies}`, `{cables}`, `{rec}` are the inputs, `{out}`
    /// a prefix in the case's directory, `{dir}` the directory.
    args: &'static [&'static str],
    /// Every file the run writes; the first is the one the option names, made the input.
    writes: &'static [&'static str],
    /// The input the first file is made equal to.
    input: Input,
    /// Runs without a service (the failing-write run applies; the service's commands set
    /// up iceoryx2 files first, and their recording is checked in the monitor tests).
    offline: bool,
}

/// How a path option is used.
enum Role {
    Input,
    Output(&'static [Case]),
}

const CSV_SIDE: &[&str] = &["{out}.csv", "{out}.csv.json", "{out}.svg"];

/// Every option whose value is a path, by command and clap id.
const PATH_OPTIONS: &[(&str, &str, Role)] = &[
    (
        "analyze",
        "export_matrices",
        Role::Output(&[Case {
            args: &[
                "analyze",
                "{scene}",
                "--elements",
                "2",
                "--export-matrices",
                "{out}",
            ],
            writes: &["{out}.K.mtx", "{out}.M.mtx"],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "analyze",
        "shapes",
        Role::Output(&[Case {
            args: &[
                "analyze",
                "{scene}",
                "--elements",
                "2",
                "--shapes",
                "{out}.csv",
            ],
            writes: &["{out}.csv", "{out}.csv.json"],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "demo",
        "hold_csv",
        Role::Output(&[Case {
            args: &[
                "demo",
                "--scene",
                "{scene}",
                "--seconds",
                "0.5",
                "--hold-f1",
                "8",
                "--hold-csv",
                "{out}.csv",
            ],
            writes: &["{out}.csv", "{out}-f1.svg", "{out}-tmin.svg"],
            input: Input::Scene,
            offline: false,
        }]),
    ),
    (
        "demo",
        "record",
        Role::Output(&[Case {
            args: &[
                "demo",
                "--scene",
                "{scene}",
                "--seconds",
                "0.5",
                "--monitor",
                "--foxglove",
                "127.0.0.1:0",
                "--record",
                "{out}.mcap",
            ],
            writes: &["{out}.mcap"],
            input: Input::Scene,
            offline: false,
        }]),
    ),
    (
        "monitor",
        "record",
        Role::Output(&[Case {
            args: &[
                "monitor",
                "--scene",
                "{scene}",
                "--no-foxglove",
                "--wait-s",
                "1",
                "--record",
                "{out}.mcap",
            ],
            writes: &["{out}.mcap"],
            input: Input::Scene,
            offline: false,
        }]),
    ),
    ("replay", "file", Role::Input),
    (
        "accuracy",
        "out_dir",
        Role::Output(&[Case {
            args: &[
                "accuracy",
                "{scene}",
                "--max-elements",
                "4",
                "--cycles",
                "20",
                "--rounds",
                "1",
                "--dense-max",
                "2",
                "--out-dir",
                "{out}",
            ],
            writes: &[
                "{out}/data/accuracy-spatial-paper.csv",
                "{out}/data/accuracy-spatial-paper.csv.json",
                "{out}/data/mode3-spatial-paper.csv",
                "{out}/data/mode3-spatial-paper.csv.json",
                "{out}/img/accuracy-spatial-paper-error-vs-n.svg",
                "{out}/img/accuracy-spatial-paper-cost.svg",
                "{out}/img/accuracy-spatial-paper-mode3.svg",
                "{out}/accuracy.md",
            ],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "map",
        "out",
        Role::Output(&[Case {
            args: &[
                "map", "{scene}", "--x", "-0.1,0.1", "--y", "0,0", "--step", "0.1", "--quiet",
                "--out", "{out}",
            ],
            writes: CSV_SIDE,
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "map",
        "svg",
        Role::Output(&[Case {
            args: &[
                "map",
                "{scene}",
                "--x",
                "-0.1,0.1",
                "--y",
                "0,0",
                "--step",
                "0.1",
                "--quiet",
                "--show",
                "k-min",
                "--out",
                "{dir}/m",
                "--svg",
                "{out}.svg",
            ],
            writes: &[
                "{out}.svg",
                "{out}-k-min.svg",
                "{dir}/m.csv",
                "{dir}/m.csv.json",
            ],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    ("trajectory", "csv", Role::Input),
    (
        "trajectory",
        "out",
        Role::Output(&[
            Case {
                args: &[
                    "trajectory",
                    "{scene}",
                    "--period-s",
                    "0.01",
                    "--quiet",
                    "--out",
                    "{out}",
                ],
                writes: CSV_SIDE,
                input: Input::Scene,
                offline: true,
            },
            // The case that destroyed a user's trajectory: the input CSV is PREFIX.csv.
            Case {
                args: &[
                    "trajectory",
                    "{scene}",
                    "--csv",
                    "{traj}",
                    "--quiet",
                    "--out",
                    "{out}",
                ],
                writes: CSV_SIDE,
                input: Input::Trajectory,
                offline: true,
            },
        ]),
    ),
    (
        "trajectory",
        "svg",
        Role::Output(&[Case {
            args: &[
                "trajectory",
                "{scene}",
                "--period-s",
                "0.01",
                "--quiet",
                "--out",
                "{dir}/t",
                "--svg",
                "{out}.svg",
            ],
            writes: &["{out}.svg", "{dir}/t.csv", "{dir}/t.csv.json"],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "sweep-tmin",
        "out",
        Role::Output(&[Case {
            args: &["sweep-tmin", "{scene}", "--steps", "2", "--out", "{out}"],
            writes: CSV_SIDE,
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "sweep-tmin",
        "svg",
        Role::Output(&[Case {
            args: &[
                "sweep-tmin",
                "{scene}",
                "--steps",
                "2",
                "--out",
                "{dir}/s",
                "--svg",
                "{out}.pdf",
            ],
            writes: &["{out}.pdf", "{dir}/s.csv", "{dir}/s.csv.json"],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "sag-compare",
        "out",
        Role::Output(&[Case {
            args: &["sag-compare", "{scene}", "--points", "3", "--out", "{out}"],
            writes: CSV_SIDE,
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "sag-compare",
        "svg",
        Role::Output(&[Case {
            args: &[
                "sag-compare",
                "{scene}",
                "--points",
                "3",
                "--out",
                "{dir}/c",
                "--svg",
                "{out}.png",
            ],
            writes: &["{out}.png", "{dir}/c.csv", "{dir}/c.csv.json"],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "import caspr",
        "output",
        Role::Output(&[Case {
            args: &[
                "import",
                "caspr",
                "{bodies}",
                "{cables}",
                "--weight-per-length",
                "1",
                "--area",
                "1e-6",
                "--youngs-modulus",
                "1e11",
                "-o",
                "{out}.toml",
            ],
            writes: &["{out}.toml"],
            input: Input::Bodies,
            offline: true,
        }]),
    ),
    ("identify", "recording", Role::Input),
    (
        "identify",
        "csv",
        Role::Output(&[Case {
            args: &["identify", "{rec}", "--csv", "{out}.csv"],
            writes: &["{out}.csv", "{out}.csv.json"],
            input: Input::Recording,
            offline: true,
        }]),
    ),
    (
        "identify",
        "svg",
        Role::Output(&[Case {
            args: &["identify", "{rec}", "--svg", "{out}.svg"],
            writes: &["{out}.svg"],
            input: Input::Recording,
            offline: true,
        }]),
    ),
    ("import caspr", "bodies", Role::Input),
    ("import caspr", "cables", Role::Input),
    (
        "modes",
        "csv",
        Role::Output(&[Case {
            args: &[
                "modes",
                "{scene}",
                "--elements",
                "2",
                "--modes",
                "2",
                "--csv",
                "{out}.csv",
            ],
            writes: &["{out}.csv", "{out}.csv.json"],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "modes",
        "svg",
        Role::Output(&[Case {
            args: &[
                "modes",
                "{scene}",
                "--elements",
                "2",
                "--modes",
                "2",
                "--svg",
                "{out}.svg",
            ],
            writes: &["{out}.svg"],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "frf",
        "csv",
        Role::Output(&[Case {
            args: &[
                "frf",
                "{scene}",
                "--elements",
                "2",
                "--points",
                "5",
                "--csv",
                "{out}.csv",
            ],
            writes: &["{out}.csv", "{out}.csv.json"],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    (
        "frf",
        "svg",
        Role::Output(&[Case {
            args: &[
                "frf",
                "{scene}",
                "--elements",
                "2",
                "--points",
                "5",
                "--svg",
                "{out}.svg",
            ],
            writes: &["{out}.svg"],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    ("simulate", "csv", Role::Input),
    (
        "simulate",
        "out",
        Role::Output(&[Case {
            args: &[
                "simulate",
                "{scene}",
                "--move",
                "0.01,0,0",
                "--duration",
                "0.2",
                "--settle",
                "0.05",
                "--modes",
                "2",
                "--out",
                "{out}",
            ],
            writes: CSV_SIDE,
            input: Input::Scene,
            offline: true,
        }]),
    ),
    ("shape", "trajectory", Role::Input),
    ("shape", "csv", Role::Input),
    (
        "shape",
        "output",
        Role::Output(&[
            Case {
                args: &[
                    "shape",
                    "--scene",
                    "{scene}",
                    "--move",
                    "0.01,0,0",
                    "--duration",
                    "0.2",
                    "-o",
                    "{out}.csv",
                ],
                writes: &["{out}.csv", "{out}.csv.json"],
                input: Input::Scene,
                offline: true,
            },
            Case {
                args: &["shape", "{traj}", "--scene", "{scene}", "-o", "{out}.csv"],
                writes: &["{out}.csv", "{out}.csv.json"],
                input: Input::Trajectory,
                offline: true,
            },
        ]),
    ),
    (
        "shape",
        "sensitivity",
        Role::Output(&[Case {
            args: &["shape", "--scene", "{scene}", "--sensitivity", "{out}.svg"],
            writes: &["{out}.svg"],
            input: Input::Scene,
            offline: true,
        }]),
    ),
    ("calibrate", "data", Role::Input),
    ("calibrate", "tensions", Role::Input),
    // Not `offline`: a run needs measured modes, which none of the table's inputs is (here
    // the trajectory stands for the data file); the refusal comes before any file is read.
    (
        "calibrate",
        "output",
        Role::Output(&[Case {
            args: &[
                "calibrate",
                "{scene}",
                "--data",
                "{traj}",
                "--fit",
                "ee_mass",
                "-o",
                "{out}.toml",
            ],
            writes: &["{out}.toml"],
            input: Input::Scene,
            offline: false,
        }]),
    ),
    (
        "calibrate",
        "svg",
        Role::Output(&[Case {
            args: &[
                "calibrate",
                "{scene}",
                "--data",
                "{traj}",
                "--fit",
                "ee_mass",
                "--svg",
                "{out}.svg",
            ],
            writes: &["{out}.svg"],
            input: Input::Trajectory,
            offline: false,
        }]),
    ),
];

/// (command path, clap id) of every option or positional whose value is a path.
fn path_options() -> Vec<(String, String)> {
    fn walk(cmd: &clap::Command, prefix: &str, out: &mut Vec<(String, String)>) {
        for sub in cmd.get_subcommands() {
            let name = if prefix.is_empty() {
                sub.get_name().to_string()
            } else {
                format!("{prefix} {}", sub.get_name())
            };
            for arg in sub.get_arguments() {
                if matches!(
                    arg.get_value_hint(),
                    clap::ValueHint::AnyPath | clap::ValueHint::FilePath | clap::ValueHint::DirPath
                ) {
                    out.push((name.clone(), arg.get_id().to_string()));
                }
            }
            walk(sub, &name, out);
        }
    }
    let mut out = Vec::new();
    walk(&Cli::command(), "", &mut out);
    out
}

/// A fresh directory for one case under target/.
fn case_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("outputs")
        .join(format!("{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A trajectory CSV of `rows` poses 1 ms apart: 1 cm along x from the paper's pose, from
/// rest to rest (smoothstep; at 50 rows the peak acceleration is 25 m/s²).
fn trajectory_text(rows: usize) -> String {
    let mut s = String::from("t,x,y,z\n");
    for i in 0..rows {
        let u = i as f64 / (rows - 1) as f64;
        let x = 0.01 * u * u * (3.0 - 2.0 * u);
        s.push_str(&format!("{},{x},0,1.25\n", i as f64 * 1e-3));
    }
    s
}

/// A measured-acceleration record for `identify`: 20 s at 1 kHz of two lightly damped
/// modes (12 and 31 Hz) rung by impulses every 2 s, with a small deterministic dither.
fn recording_text() -> String {
    let mut s = String::from("t,ax\n");
    for i in 0..20_000 {
        let t = i as f64 * 1e-3;
        let tau = t % 2.0;
        let w1 = 2.0 * std::f64::consts::PI * 12.0;
        let w2 = 2.0 * std::f64::consts::PI * 31.0;
        let a = (-0.02 * w1 * tau).exp() * (w1 * tau).sin()
            + 0.5 * (-0.02 * w2 * tau).exp() * (w2 * tau).sin()
            + 1e-3 * ((i * 7919 % 1000) as f64 / 500.0 - 1.0);
        s.push_str(&format!("{t},{a}\n"));
    }
    s
}

/// The inputs of a case in `dir`: (placeholder, path).
fn make_inputs(dir: &Path, rows: usize) -> Vec<(&'static str, PathBuf)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = dir.join("scene.toml");
    std::fs::copy(root.join("scenes/spatial_paper.toml"), &scene).unwrap();
    let traj = dir.join("path.csv");
    std::fs::write(&traj, trajectory_text(rows)).unwrap();
    let rec = dir.join("record.csv");
    std::fs::write(&rec, recording_text()).unwrap();
    let mut v = vec![("{scene}", scene), ("{traj}", traj), ("{rec}", rec)];
    for (key, name) in [("{bodies}", "bodies"), ("{cables}", "cables")] {
        let p = dir.join(format!("{name}.xml"));
        std::fs::copy(
            root.join(format!("tests/data/caspr/planar_nguyen_{name}.xml")),
            &p,
        )
        .unwrap();
        v.push((key, p));
    }
    v
}

fn fill(text: &str, dir: &Path, inputs: &[(&str, PathBuf)]) -> String {
    let mut s = text.replace("{out}", &dir.join("o").display().to_string());
    s = s.replace("{dir}", &dir.display().to_string());
    for (k, p) in inputs {
        s = s.replace(k, &p.display().to_string());
    }
    s
}

/// Every file under `dir` with its bytes.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let bytes = std::fs::read(&p).unwrap();
                out.push((p, bytes));
            }
        }
    }
    out.sort();
    out
}

fn input_path(inputs: &[(&str, PathBuf)], which: Input) -> PathBuf {
    let key = match which {
        Input::Scene => "{scene}",
        Input::Trajectory => "{traj}",
        Input::Bodies => "{bodies}",
        Input::Recording => "{rec}",
    };
    inputs.iter().find(|(k, _)| *k == key).unwrap().1.clone()
}

fn run(args: &[String], limit_file_bytes: Option<u64>) -> Output {
    let mut c = Command::new(BIN);
    c.args(args).stdin(Stdio::null());
    if let Some(limit) = limit_file_bytes {
        // SAFETY: only async-signal-safe calls between fork and exec. SIGXFSZ ignored (kept
        // across exec) turns a write past the limit into an EFBIG error instead of a kill.
        unsafe {
            c.pre_exec(move || {
                libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
                let r = libc::rlimit {
                    rlim_cur: limit,
                    rlim_max: limit,
                };
                if libc::setrlimit(libc::RLIMIT_FSIZE, &r) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
    }
    c.output().unwrap()
}

fn cases() -> impl Iterator<Item = (&'static str, &'static str, usize, &'static Case)> {
    PATH_OPTIONS.iter().flat_map(|(cmd, id, role)| {
        match role {
            Role::Input => [].iter().enumerate(),
            Role::Output(cases) => cases.iter().enumerate(),
        }
        .map(move |(k, c)| (*cmd, *id, k, c))
    })
}

#[test]
fn every_path_option_of_every_command_is_in_the_table() {
    let found = path_options();
    assert!(found.len() >= 20, "{found:?}");
    for (cmd, id) in &found {
        assert!(
            PATH_OPTIONS.iter().any(|(c, i, _)| c == cmd && i == id),
            "`cablevib {cmd}` has the path option `{id}`: add it to PATH_OPTIONS (an input, \
             or an output with a case)"
        );
    }
    for (cmd, id, _) in PATH_OPTIONS {
        assert!(
            found.iter().any(|(c, i)| c == cmd && i == id),
            "PATH_OPTIONS names `{cmd} {id}`, which clap does not have"
        );
    }
}

#[test]
fn an_output_that_is_an_input_is_refused_and_the_input_unchanged() {
    for (cmd, id, k, case) in cases() {
        let dir = case_dir(&format!("same-{}-{id}-{k}", cmd.replace(' ', "-")));
        let inputs = make_inputs(&dir, 50);
        let input = input_path(&inputs, case.input);
        let first = PathBuf::from(fill(case.writes[0], &dir, &inputs));
        std::fs::create_dir_all(first.parent().unwrap()).unwrap();
        std::fs::hard_link(&input, &first).unwrap();
        let before = snapshot(&dir);
        let args: Vec<String> = case.args.iter().map(|a| fill(a, &dir, &inputs)).collect();
        let o = run(&args, None);
        let err = String::from_utf8_lossy(&o.stderr);
        let what = format!("cablevib {}", args.join(" "));
        assert_eq!(o.status.code(), Some(1), "{what}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{what}: {err}");
        assert!(
            err.contains("is the input")
                && err.contains(&first.display().to_string())
                && err.contains(&input.display().to_string()),
            "{what}: {err}"
        );
        // Nothing written: every file as before (the input too), nothing new.
        assert!(snapshot(&dir) == before, "{what}: files changed");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn a_run_whose_writes_fail_leaves_every_earlier_file_untouched() {
    for (cmd, id, k, case) in cases().filter(|c| c.3.offline) {
        let dir = case_dir(&format!("fail-{}-{id}-{k}", cmd.replace(' ', "-")));
        let inputs = make_inputs(&dir, 50);
        for w in case.writes {
            let p = PathBuf::from(fill(w, &dir, &inputs));
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(&p, format!("an earlier {w}\n")).unwrap();
        }
        let before = snapshot(&dir);
        let args: Vec<String> = case.args.iter().map(|a| fill(a, &dir, &inputs)).collect();
        let what = format!("cablevib {}", args.join(" "));
        // Without the limit the run succeeds and replaces every file it names.
        let o = run(&args, Some(0));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{what}: {err}");
        assert!(err.contains("File too large"), "{what}: {err}");
        assert!(snapshot(&dir) == before, "{what}: files changed: {err}");
        let o = run(&args, None);
        assert!(
            o.status.success(),
            "{what}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        for w in case.writes {
            let p = PathBuf::from(fill(w, &dir, &inputs));
            let now = std::fs::read(&p).unwrap();
            assert_ne!(now, format!("an earlier {w}\n").into_bytes(), "{what}: {w}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// The `.part` files in `dir`.
fn parts(dir: &Path) -> Vec<PathBuf> {
    snapshot(dir)
        .into_iter()
        .map(|(p, _)| p)
        .filter(|p| p.extension().is_some_and(|e| e == "part"))
        .collect()
}

/// A large trajectory CSV interrupted mid-write by SIGINT, and cut by a failing write after
/// 1 MiB: the earlier CSV at the target untouched, no temporary file left.
#[test]
fn an_interrupted_large_trajectory_leaves_the_earlier_csv_untouched() {
    let dir = case_dir("interrupted-trajectory");
    let inputs = make_inputs(&dir, 200_000);
    let traj = input_path(&inputs, Input::Trajectory);
    let out = dir.join("o");
    let csv = dir.join("o.csv");
    std::fs::write(&csv, "an earlier trajectory CSV\n").unwrap();
    let args: Vec<String> = [
        "trajectory",
        "spatial-paper",
        "--csv",
        traj.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]
    .map(String::from)
    .to_vec();
    let before = snapshot(&dir);

    // Cut after 1 MiB: a write error mid-way.
    let o = run(&args, Some(1 << 20));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("File too large"), "{err}");
    assert!(snapshot(&dir) == before, "files changed: {err}");

    // What an uninterrupted run writes, elsewhere: the output of a run the signal reaches
    // only after it has finished writing must be this, whole.
    let ref_dir = case_dir("interrupted-trajectory-reference");
    let mut ref_args = args.clone();
    let n = ref_args.len();
    ref_args[n - 1] = ref_dir.join("o").to_str().unwrap().to_string();
    let o = run(&ref_args, None);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let whole = std::fs::read(ref_dir.join("o.csv")).unwrap();
    let _ = std::fs::remove_dir_all(&ref_dir);

    // SIGINT once the temporary CSV holds data. On a loaded machine the run can finish its
    // writing between the poll that sees the data and the signal; such an attempt tests
    // nothing about an interrupted write, so its (whole) output is checked, the earlier
    // files are put back and it is tried again: at most 5 attempts, one interrupted
    // mid-write required.
    let mut interrupted = false;
    for _attempt in 0..5 {
        let mut child = Command::new(BIN)
            .args(&args)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let t0 = Instant::now();
        let part = loop {
            if let Some(p) = parts(&dir)
                .into_iter()
                .find(|p| std::fs::metadata(p).is_ok_and(|m| m.len() > 0))
            {
                break Some(p);
            }
            assert!(
                t0.elapsed() < Duration::from_secs(120),
                "no temporary CSV with data appeared"
            );
            if child.try_wait().unwrap().is_some() {
                break None;
            }
            std::thread::sleep(Duration::from_millis(2));
        };
        if part.is_some() {
            // SAFETY: kill(2) on the pid of a child this test spawned and has not reaped.
            unsafe {
                libc::kill(child.id() as libc::pid_t, libc::SIGINT);
            }
        }
        let status = child.wait().unwrap();
        assert!(parts(&dir).is_empty(), "{:?}", parts(&dir));
        if let Some(part) = &part {
            assert!(!part.exists(), "{} left", part.display());
        }
        if snapshot(&dir) == before {
            assert_eq!(status.signal(), Some(libc::SIGINT), "{status:?}");
            interrupted = true;
            break;
        }
        // The writing finished first: the target holds the whole new CSV.
        assert!(
            std::fs::read(&csv).unwrap() == whole,
            "a changed CSV that is not whole"
        );
        for (p, _) in snapshot(&dir) {
            if !before.iter().any(|(q, _)| *q == p) {
                std::fs::remove_file(&p).unwrap();
            }
        }
        std::fs::write(&csv, "an earlier trajectory CSV\n").unwrap();
        assert!(snapshot(&dir) == before, "earlier files not restored");
    }
    assert!(
        interrupted,
        "5 runs finished writing before the SIGINT reached them"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
