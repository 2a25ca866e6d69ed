//! Does a monitor disturb the real-time loop? `bench-ipc`'s measurement (pose published →
//! estimate received, through real iceoryx2 services) without and with a `cablevib monitor`
//! process attached, serving Foxglove and recording to MCAP, alternated in one run; and the
//! monitor's own CPU time while it follows the service.
//!
//! ```text
//! cargo build --release --bin cablevib
//! cargo run --release -p cablevib-monitor --example monitor_overhead -- [SAMPLES] [GAP_US] [ROUNDS]
//! ```
//!
//! Defaults: 5000 samples per arm, a 1000 µs pause after each estimate (≈ 1 kHz of poses, as
//! a controller sends them), 2 rounds of (without, with). The service and the client wait by
//! event (no spinning CPU beside the monitor). The monitor is `target/release/cablevib`.

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Instant;

use cablevib::scene::Scene;
use cablevib_service::bench::bench_mode;
use cablevib_service::{BenchIpcConfig, BenchVibration, WaitMode};

/// utime + stime of process `pid`, s.
fn cpu_s(pid: u32) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    // Fields after the command name (which may hold spaces) end with ')'.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11).and_then(|v| v.parse().ok()).unwrap_or(0.0)
        + f.get(12).and_then(|v| v.parse().ok()).unwrap_or(0.0);
    // SAFETY: sysconf has no preconditions.
    let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) } as f64;
    ticks / hz
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let samples: usize = args.get(1).and_then(|v| v.parse().ok()).unwrap_or(5000);
    let gap_us: u64 = args.get(2).and_then(|v| v.parse().ok()).unwrap_or(1000);
    let rounds: usize = args.get(3).and_then(|v| v.parse().ok()).unwrap_or(2);
    let bin = std::env::current_exe()
        .ok()
        .and_then(|p| Some(p.parent()?.parent()?.join("cablevib")))
        .filter(|p| p.exists())
        .unwrap_or_else(|| PathBuf::from("target/release/cablevib"));
    let scene = Scene::default_scene();
    let cfg = BenchIpcConfig {
        samples,
        wait: Some(WaitMode::Event),
        gap_us,
        cpu: None,
        json: false,
        alloc_pool: true,
        vibration: BenchVibration::Off,
    };
    let instance = format!("cablevib_bench_{}_event", std::process::id());
    let dir = std::env::temp_dir();
    println!(
        "pose → estimate over iceoryx2, scene `{}`, {samples} samples per arm, {gap_us} µs after \
         each estimate, event wait; µs",
        scene.name
    );
    println!(
        "  {:<34} {:>8} {:>8} {:>8} {:>8} {:>9} {:>10}",
        "arm", "p50", "p99", "p99.9", "max", "poses/s", "monitor CPU"
    );
    for round in 0..rounds {
        for with in [false, true] {
            let mut monitor = None;
            let file = dir.join(format!(
                "cablevib-overhead-{}-{round}.mcap",
                std::process::id()
            ));
            let _ = std::fs::remove_file(&file);
            if with {
                let child = Command::new(&bin)
                    .args([
                        "monitor",
                        "--instance",
                        &instance,
                        "--scene",
                        "spatial-paper",
                    ])
                    .args(["--foxglove", "127.0.0.1:0", "--record"])
                    .arg(&file)
                    .stdout(Stdio::null())
                    .spawn()
                    .expect("start the monitor (build target/release/cablevib first)");
                monitor = Some(child);
            }
            let t0 = Instant::now();
            let cpu0 = monitor.as_ref().map_or(0.0, |m| cpu_s(m.id()));
            let r = bench_mode(&scene, WaitMode::Event, &cfg)
                .expect("bench")
                .remove(0);
            let wall = t0.elapsed().as_secs_f64();
            let cpu = monitor.as_ref().map(|m| cpu_s(m.id()) - cpu0);
            if let Some(mut m) = monitor {
                // SAFETY: kill(2) on our own child's pid.
                unsafe {
                    libc::kill(m.id() as libc::pid_t, libc::SIGTERM);
                }
                let _ = m.wait();
            }
            let size = std::fs::metadata(&file).map_or(0, |m| m.len());
            let _ = std::fs::remove_file(&file);
            let p = &r.end_to_end;
            println!(
                "  {:<34} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>9.0} {:>10}",
                if with {
                    format!("with monitor (Foxglove + MCAP {} kB)", size / 1000)
                } else {
                    "without monitor".to_string()
                },
                p.p50_ns as f64 / 1e3,
                p.p99_ns as f64 / 1e3,
                p.p999_ns as f64 / 1e3,
                p.max_ns as f64 / 1e3,
                (p.count as f64) / r.seconds,
                cpu.map_or("-".into(), |c| format!("{:.1} %", 100.0 * c / wall)),
            );
        }
    }
}
