//! 10⁶ elements per cable through the commands that hold something per element: each is
//! refused before it allocates, in one line naming its estimate and the one memory budget
//! (2 GiB, `cablevib::memory_budget`), exit 1, with a small peak resident memory; what stays
//! under the budget still runs. Each child runs with its address space limited to 3 GiB, so
//! that a command that would allocate its estimate fails here instead of taking the machine
//! (before the budget, `modes --elements 1000000 --modes 12` aborted at the limit).
//!
//! The memory estimates themselves are checked against measured peaks in
//! `estimates_bound_the_measured_peak` (within a factor 1.5 either way).

use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");
/// The children's address-space limit, bytes (3 GiB: above the 2 GiB budget).
const AS_LIMIT: u64 = 3 << 30;

/// Runs the binary with `args` under [`AS_LIMIT`]; its output and its own peak resident
/// memory (bytes, from wait4's rusage of that child).
fn run_limited(args: &[&str]) -> (Output, u64) {
    let dir = std::env::temp_dir().join(format!(
        "cablevib-membudget-out-{}-{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let (so, se) = (dir.join("stdout"), dir.join("stderr"));
    let mut cmd = Command::new(BIN);
    cmd.args(args)
        .env("RUST_BACKTRACE", "0")
        .stdout(std::fs::File::create(&so).unwrap())
        .stderr(std::fs::File::create(&se).unwrap());
    // SAFETY: setrlimit is async-signal-safe; the closure touches nothing else.
    unsafe {
        cmd.pre_exec(|| {
            let lim = libc::rlimit {
                rlim_cur: AS_LIMIT,
                rlim_max: AS_LIMIT,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    // Reaped by wait4 below (which also gives the child's peak RSS), not by `Child::wait`.
    #[allow(clippy::zombie_processes)]
    let child = cmd.spawn().expect("the binary runs");
    let mut status = 0;
    // SAFETY: an all-zero rusage is valid; wait4 fills it for our own child.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut ru) };
    assert_eq!(pid, child.id() as libc::pid_t);
    let status = std::process::ExitStatus::from_raw(status);
    let out = Output {
        status,
        stdout: std::fs::read(&so).unwrap(),
        stderr: std::fs::read(&se).unwrap(),
    };
    let _ = std::fs::remove_dir_all(&dir);
    (out, ru.ru_maxrss as u64 * 1024)
}

/// Exit 1, one line on stderr naming the budget and `needle`, no panic or abort.
fn assert_refused(what: &str, o: &Output, needle: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !err.contains("panicked") && !err.contains("memory allocation"),
        "{what}: {err}"
    );
    assert_eq!(o.status.code(), Some(1), "{what}: {err}");
    let refusal: Vec<&str> = err.lines().filter(|l| l.contains("budget")).collect();
    assert_eq!(refusal.len(), 1, "{what}: {err}");
    assert!(
        refusal[0].contains("over the budget of 2.000 GiB") && refusal[0].contains(needle),
        "{what}: {err}"
    );
    // Nothing else but a possible estimate line before it.
    assert!(err.trim_end().lines().count() <= 2, "{what}: {err}");
}

/// `args` refused (`assert_refused` with `needle`) at a small peak resident memory: the
/// scene, the estimator and the refusal, a few MB (the taut model is O(1) in N); the sagged
/// model holds each element's state (1.5 GB for 8 × 10⁶ elements, under the budget:
/// `estimator::SAG_BYTES_PER_ELEMENT`) before its basis is refused.
fn assert_refused_small(args: &[&str], needle: &str) {
    let (o, rss) = run_limited(args);
    let what = args.join(" ");
    assert_refused(&what, &o, needle);
    println!("{what}: refused, peak RSS {:.1} MB", rss as f64 / 1e6);
    let bound = if args.contains(&"--sag") {
        2 << 30
    } else {
        100_000_000
    };
    assert!(rss < bound, "{what}: peak RSS {rss} B");
}

#[test]
fn a_million_elements_per_cable_is_refused_before_allocating() {
    let dir = std::env::temp_dir().join(format!("cablevib-membudget-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("shapes.csv");
    let csv = csv.to_str().unwrap();
    let out = dir.join("sim");
    let out = out.to_str().unwrap();
    let cases: [(&[&str], &str); 5] = [
        (
            &[
                "modes",
                "spatial-paper",
                "--elements",
                "1000000",
                "--modes",
                "12",
                "--csv",
                csv,
            ],
            "mode shapes (12 modes, 1000000 elements per cable)",
        ),
        (
            &[
                "modes",
                "spatial-paper",
                "--elements",
                "100000",
                "--modes",
                "256",
            ],
            "mode shapes (256 modes, 100000 elements per cable)",
        ),
        (
            &[
                "analyze",
                "spatial-paper",
                "--elements",
                "1000000",
                "--shapes",
                csv,
            ],
            "mode shapes (10 modes, 1000000 elements per cable)",
        ),
        (
            &[
                "frf",
                "spatial-paper",
                "--elements",
                "1000000",
                "--modal-ratio",
                "0.02",
            ],
            "frf (1000 frequencies, 1000000 elements per cable)",
        ),
        (
            &[
                "simulate",
                "spatial-paper",
                "--elements",
                "1000000",
                "--move",
                "0.1,0,0",
                "--duration",
                "1",
                "--out",
                out,
            ],
            "simulate (3001 samples, 1000000 elements per cable)",
        ),
    ];
    for (args, needle) in cases {
        assert_refused_small(args, needle);
    }
    assert!(!dir.join("shapes.csv").exists(), "no CSV written");
    assert!(!dir.join("sim.csv").exists(), "no simulate CSV written");
    // Under the budget the same commands run (N = 10⁴: 0.03 .. 0.3 GB).
    for args in [
        &[
            "modes",
            "spatial-paper",
            "--elements",
            "10000",
            "--modes",
            "12",
        ][..],
        &[
            "frf",
            "spatial-paper",
            "--elements",
            "10000",
            "--modal-ratio",
            "0.02",
            "--points",
            "10",
        ],
    ] {
        let (o, _) = run_limited(args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `simulate` of a 0.1 m move in 0.2 s (201 samples, no settling) at `elements` per cable,
/// with `extra` options, writing `out`.
fn simulate_move<'a>(elements: &'a str, extra: &[&'a str], out: &'a str) -> Vec<&'a str> {
    let mut a = vec![
        "simulate",
        "spatial-paper",
        "--elements",
        elements,
        "--move",
        "0.1,0,0",
        "--duration",
        "0.2",
        "--settle",
        "0",
        "--max-acceleration",
        "1e4",
    ];
    a.extend_from_slice(extra);
    a.extend(["--out", out]);
    a
}

/// The estimates the refusals rest on, against the peak resident memory measured under the
/// budget (`modes` at N = 3·10⁴ with 12 and 48 modes, its CSV; `simulate` at N = 10⁴ with
/// its defaults, the K and pilot it chose): each within a factor 1.5 of the measured peak,
/// either way (the process's own few MB included), so the budget refuses what would exceed
/// it and little else. Before, simulate's estimate left out its pilot (0.62 of the peak).
#[test]
fn estimates_bound_the_measured_peak() {
    use cablevib::scene::Scene;
    use cablevib::study::cost::{estimate_cost, Work};
    let scene = |n: usize| {
        let s = Scene::default_scene();
        s.with_model(s.model.element, n)
    };
    let dir = std::env::temp_dir().join(format!("cablevib-membudget-est-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("m.csv");
    let out = dir.join("sim");
    let (csv, out) = (csv.to_str().unwrap(), out.to_str().unwrap());
    let cases: Vec<(Vec<&str>, Work<'static>, usize)> = vec![
        (
            vec![
                "modes",
                "spatial-paper",
                "--elements",
                "30000",
                "--modes",
                "12",
            ],
            Work::Modes {
                modes: 12,
                continuous_samples: 41,
                csv: false,
            },
            30000,
        ),
        (
            vec![
                "modes",
                "spatial-paper",
                "--elements",
                "30000",
                "--modes",
                "48",
            ],
            Work::Modes {
                modes: 48,
                continuous_samples: 41,
                csv: false,
            },
            30000,
        ),
        (
            vec![
                "modes",
                "spatial-paper",
                "--elements",
                "10000",
                "--modes",
                "12",
                "--csv",
                csv,
            ],
            Work::Modes {
                modes: 12,
                continuous_samples: 41,
                csv: true,
            },
            10000,
        ),
    ];
    // simulate with its defaults: K and the pilot's largest basis are chosen as it runs and
    // read from its CSV's sidecar, then the same estimate the run checked before building
    // each (`Work::Simulate`).
    let simulate = simulate_move("10000", &[], out);
    let check = |a: &[&str], work: &dyn Fn() -> Work<'static>, n: usize| {
        let (o, rss) = run_limited(a);
        assert!(
            o.status.success(),
            "{a:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let est = estimate_cost(&scene(n), &work()).memory_bytes;
        let ratio = est as f64 / rss as f64;
        println!(
            "{a:?}: peak RSS {:.1} MB, estimate {:.1} MB ({ratio:.2})",
            rss as f64 / 1e6,
            est as f64 / 1e6
        );
        assert!(
            (1.0 / 1.5..=1.5).contains(&ratio),
            "{a:?}: estimate {est} B, peak {rss} B"
        );
    };
    for (a, work, n) in cases {
        check(&a, &|| work, n);
    }
    let sidecar = dir.join("sim.csv.json");
    check(
        &simulate,
        &|| {
            let meta: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&sidecar).unwrap()).unwrap();
            let run = &meta["residual_vibration"][0];
            let get = |k: &str| run[k].as_u64().unwrap_or_else(|| panic!("{k} in {run}")) as usize;
            println!(
                "simulate chose K = {}, pilot of {} modes",
                get("modes"),
                get("pilot_modes")
            );
            Work::Simulate {
                samples: 201,
                // The memory does not depend on the interval.
                update_every: 1,
                modes: get("modes"),
                pilot_modes: get("pilot_modes"),
            }
        },
        10000,
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `simulate` choosing K grows its pilot basis (24, 48, 96, … modes) until its truncation
/// estimate meets the tolerance: at 1.5·10⁵ elements per cable a tight tolerance wants the
/// 96-mode basis (about 2.9 GiB), over the budget though the first bases and the run at 24
/// modes are under it. Expected: refused before that basis is built, in one line naming the
/// budget and what to change (`--modes`, `--tolerance`), nothing written. Before, the
/// pilot's growth was not estimated: a basis refused by the shapes' own check silently
/// ended the growth, and the run was refused later, naming only fewer elements or modes.
#[test]
fn simulate_refuses_a_pilot_basis_past_the_budget_naming_its_overrides() {
    let dir = std::env::temp_dir().join(format!("cablevib-membudget-pilot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("sim");
    let args = simulate_move("150000", &["--tolerance", "1e-6"], out.to_str().unwrap());
    let (o, rss) = run_limited(&args);
    let what = args.join(" ");
    assert_refused(
        &what,
        &o,
        "simulate (201 samples, 150000 elements per cable)",
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--modes") && err.contains("--tolerance"),
        "{what}: the refusal names the overrides: {err}"
    );
    println!("{what}: refused, peak RSS {:.1} MB", rss as f64 / 1e6);
    // The pilot's bases under the budget ran (48 modes: about 1.6 GB).
    assert!(rss < 2 << 30, "{what}: peak RSS {rss} B");
    assert!(!dir.join("sim.csv").exists(), "no simulate CSV written");
    let _ = std::fs::remove_dir_all(&dir);
}

mod slow {
    use super::*;

    /// The sagged model at 10⁶ elements per cable: its statics and the frequencies up to
    /// the band's end are solved (1.5 GB of element state, under the budget) before the
    /// modal basis of 16 modes × 8 000 010 nodes is refused, about half a minute of CPU;
    /// the taut commands' refusals are in the quick
    /// `a_million_elements_per_cable_is_refused_before_allocating`.
    #[test]
    #[ignore = "slow reference sweep: the sagged model at 10^6 elements per cable"]
    fn a_million_sagged_elements_per_cable_refuse_the_basis() {
        let args = [
            "frf",
            "spatial-paper",
            "--elements",
            "1000000",
            "--sag",
            "true",
            "--modal-ratio",
            "0.02",
            "--to-hz",
            "5",
        ];
        assert_refused_small(&args, "modes × 8000010 nodes");
    }
}
