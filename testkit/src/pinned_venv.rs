//! A Python venv under target/ with pinned packages, created and provisioned on first use
//! (by `python3 -m venv` and pip, by name and version: nothing installed by hand counts).
//!
//! Tests of one binary run in parallel threads, and several binaries may share a venv, so
//! the check-and-create step runs under an in-process mutex and an exclusive lock on
//! `target/DIR_NAME.lock`: the second caller waits, then finds the venv ready.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

/// Serialises the venv set-up between the threads of one test binary.
static SETUP: Mutex<()> = Mutex::new(());

/// The python of the venv `target/DIR_NAME`, with `packages` — (import name, pip name,
/// version) — installed at exactly those versions; created when it is missing or stale.
pub fn pinned_venv_python(dir_name: &str, packages: &[(&str, &str, &str)]) -> PathBuf {
    let venv = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .join("target")
        .join(dir_name);
    let py = venv.join("bin").join("python");
    let imports: Vec<&str> = packages.iter().map(|p| p.0).collect();
    // The installed distribution's version (importlib.metadata: some packages, pyOMA-2
    // among them, have no `__version__`).
    let stale: Vec<String> = packages
        .iter()
        .map(|(_, name, v)| format!("importlib.metadata.version('{name}') != '{v}'"))
        .collect();
    let check = format!(
        "import sys, importlib.metadata, {}; sys.exit({})",
        imports.join(", "),
        stale.join(" or ")
    );
    let has = |py: &Path| {
        Command::new(py)
            .args(["-c", &check])
            .status()
            .is_ok_and(|s| s.success())
    };
    let _in_process = SETUP.lock().unwrap_or_else(|e| e.into_inner());
    std::fs::create_dir_all(venv.parent().expect("target dir")).expect("create target/");
    let lock = File::create(venv.with_file_name(format!("{dir_name}.lock")))
        .expect("create the venv lock file");
    lock.lock().expect("lock the venv lock file");
    if !has(&py) {
        let st = Command::new("python3")
            .args(["-m", "venv"])
            .arg(&venv)
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
            ])
            .args(packages.iter().map(|(_, name, v)| format!("{name}=={v}")))
            .status()
            .expect("pip install");
        assert!(st.success(), "pip install {packages:?} failed");
        assert!(has(&py), "{packages:?} not importable after install");
    }
    py
}
