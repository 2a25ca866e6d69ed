//! The command line as a tool: completions and the man page come from the parser's own
//! definitions, `--element` is checked by the parser, and `serve` takes its scene as a
//! positional argument like the other commands (with `--scene` still accepted). A sweep
//! whose stderr is not a terminal prints no progress, only its summary on stdout.

use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cablevib"))
        .args(args)
        .output()
        .expect("run cablevib")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn completions_name_every_subcommand() {
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let o = run(&["completions", shell]);
        assert!(
            o.status.success(),
            "{shell}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let text = stdout(&o);
        for sub in [
            "analyze",
            "bench",
            "serve",
            "map",
            "sweep-tmin",
            "completions",
            "man",
        ] {
            assert!(text.contains(sub), "{shell} completions lack `{sub}`");
        }
    }
    let o = run(&["completions", "tcsh"]);
    assert!(!o.status.success(), "an unknown shell is an error");
}

#[test]
fn man_page_is_roff_with_the_subcommands() {
    let o = run(&["man"]);
    assert!(o.status.success());
    let text = stdout(&o);
    assert!(text.contains(".TH cablevib 1"), "no roff title line");
    assert!(text.contains("analyze") && text.contains("serve"));
}

#[test]
fn element_values_come_from_the_parser() {
    let o = run(&["analyze", "spatial-paper", "--element", "spring"]);
    assert_eq!(o.status.code(), Some(2), "clap's usage error code");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("possible values: fem, catenary, continuous, massless, auto"),
        "{err}"
    );
}

#[test]
fn serve_scene_positional_or_option_not_both() {
    for args in [
        &["serve", "no-such-scene", "--max-cycles", "1"][..],
        &["serve", "--scene", "no-such-scene", "--max-cycles", "1"][..],
    ] {
        let o = run(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?}");
        // Both spellings reach the scene loader, which names the scene it could not read.
        assert!(err.contains("no-such-scene"), "{args:?}: {err}");
    }
    let o = run(&["serve", "a.toml", "--scene", "b.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot be used with"));
}

#[test]
fn analyze_writes_the_mode_shapes_with_a_sidecar() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("analyze-shapes");
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("shapes.csv");
    let o = run(&[
        "analyze",
        "planar-paper",
        "--modes",
        "3",
        "--shapes",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(
        text.lines().next(),
        Some("mode,frequency_hz,cable,node,x_m,y_m,z_m,ux,uy,uz")
    );
    let side: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("shapes.csv.json")).unwrap())
            .unwrap();
    assert_eq!(side["command"], "modes");
    assert!(
        side["modes"].as_u64().unwrap() >= 3,
        "clusters are completed"
    );
    // Not with --realtime: the parser says so.
    let o = run(&["analyze", "planar-paper", "--realtime", "--shapes", "x.csv"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn sweeps_print_no_progress_when_stderr_is_not_a_terminal() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("no-progress");
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("m");
    // ~5 000 points with 8 modes on one thread: about 2 s on a quiet machine, over the bar's
    // one-second delay, so a terminal would show the bar; captured stderr must stay empty.
    let t0 = std::time::Instant::now();
    let o = run(&[
        "map",
        "spatial-paper",
        "--step",
        "0.04",
        "--z=1.15,1.25",
        "--modes",
        "8",
        "--threads",
        "1",
        // Explicitly the chord model: no line saying that sag would matter.
        "--sag",
        "false",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        o.stderr.is_empty(),
        "{:?}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = stdout(&o);
    assert!(text.starts_with("map: scene spatial-paper"), "{text}");
    eprintln!("(the sweep took {:.2} s)", t0.elapsed().as_secs_f64());
}

#[test]
fn the_paper_scenes_analyze_without_a_sag_warning() {
    // The paper's robots are its chord model by definition: their files say `sag = false`,
    // so a new user's first command prints no warning.
    for scene in ["spatial-paper", "planar-paper"] {
        let o = run(&["analyze", scene]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(
            o.stderr.is_empty(),
            "{scene}: {:?}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}
