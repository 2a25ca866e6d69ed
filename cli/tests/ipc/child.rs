//! The `cablevib` binary as a child process with a bounded wait, as the demo tests run it.

use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The binary under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_cablevib");
/// The longest a demo run may take (a few seconds of poses, start-up, the summary's
/// searches); the child is killed after it.
pub const TIMEOUT: Duration = Duration::from_secs(120);

/// Run `cablevib ARGS` (no backtrace), waiting at most [`TIMEOUT`]: its output, or a panic
/// naming the arguments when it did not finish in time.
pub fn run(args: &[&str]) -> Output {
    let mut child = Command::new(BIN)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn cablevib");
    let deadline = Instant::now() + TIMEOUT;
    while child.try_wait().expect("try_wait").is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("cablevib {args:?} did not finish within {TIMEOUT:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.wait_with_output().expect("output")
}
