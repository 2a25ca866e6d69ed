//! Replay publisher: sends end-effector poses to a running `cablevib serve` at a fixed rate —
//! the paper's circle (radius 0.75 m) by default, or a CSV file of `t,x,y,z` rows (s, m) — and
//! optionally a T_min schedule.
//!
//! ```text
//! cargo run --release -- serve --instance demo &
//! cargo run --release --example replay -- --instance demo --seconds 10 --t-min 0:60,5:90
//! ```
//!
//! Each pose is a `PoseSample` with a sequence number (1, 2, ...) and the `CLOCK_MONOTONIC`
//! time it was sent; after each one the wake-service event is notified, so a service running
//! with `--wait event` wakes up. Ctrl-C stops early.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{bail, Context};
use cablevib::service::ports::{create_node, PoseInput};
use cablevib::service::TminSchedule;
use cablevib::trajectory::Trajectory;
use cablevib_ipc::{monotonic_now_ns, PoseSample, ServiceNames, TminSetpoint, IDENTITY_QUATERNION};
use clap::Parser;

/// Publish poses (and T_min set-points) to a cablevib service.
#[derive(Debug, Parser)]
struct Args {
    /// Instance name, as given to `cablevib serve --instance` (empty: the bare service names).
    #[arg(long, default_value = "")]
    instance: String,
    /// Scene whose default position is the circle's centre (file or `spatial-paper`).
    #[arg(long, default_value = "spatial-paper")]
    scene: String,
    /// Replay this CSV file of t,x,y,z rows (s, m) instead of the circle.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Pose rate, Hz.
    #[arg(long, default_value_t = 1000.0)]
    rate_hz: f64,
    /// How long to publish, s (default: 10 s for the circle, the whole file for a CSV).
    #[arg(long)]
    seconds: Option<f64>,
    /// Time per revolution of the circle, s.
    #[arg(long, default_value_t = 4.0)]
    period_s: f64,
    /// T_min schedule SECONDS:NEWTONS,..., e.g. "0:60,2:80" (60 N from the start, 80 N from 2 s).
    #[arg(long)]
    t_min: Option<String>,
    /// Wait up to this long for a service to subscribe before publishing, s (0: do not wait).
    #[arg(long, default_value_t = 5.0)]
    wait_for_service_s: f64,
}

fn main() -> anyhow::Result<()> {
    let a = Args::parse();
    if !(a.rate_hz.is_finite() && a.rate_hz > 0.0 && a.rate_hz <= 100_000.0) {
        bail!("--rate-hz {} must be in (0, 100000] Hz", a.rate_hz);
    }
    let scene = cablevib::scene::Scene::load(&a.scene).context("loading the scene")?;
    let trajectory = match &a.csv {
        Some(path) => Trajectory::from_csv(path)?,
        None => Trajectory::circle(&scene, a.period_s)?,
    };
    let seconds = a.seconds.or(trajectory.duration_s()).unwrap_or(10.0);
    if !(seconds.is_finite() && seconds >= 0.0) {
        bail!("--seconds {seconds} must be finite and ≥ 0");
    }
    let schedule = match &a.t_min {
        Some(s) => TminSchedule::parse(s)?,
        None => TminSchedule::default(),
    };

    let names = ServiceNames::new(&a.instance);
    let node = create_node("cablevib-replay")?;
    let input = PoseInput::open(&node, &names)?;
    let wait_until = Instant::now() + Duration::from_secs_f64(a.wait_for_service_s.max(0.0));
    while !input.service_connected() && Instant::now() < wait_until {
        if node.wait(Duration::from_millis(10)).is_err() {
            return Ok(());
        }
    }
    if !input.service_connected() {
        eprintln!(
            "replay: no service subscribes to \"{}\" yet; publishing anyway",
            names.pose
        );
    }
    println!(
        "replay: {} at {} Hz for {seconds} s on \"{}\"",
        trajectory.describe(),
        a.rate_hz,
        names.pose
    );

    let n = (seconds * a.rate_hz).floor() as u64 + 1;
    let start = Instant::now();
    let mut step = None;
    let (mut sent, mut setpoints, mut late) = (0u64, 0u64, 0u64);
    for k in 0..n {
        let t_s = k as f64 / a.rate_hz;
        let due = start + Duration::from_secs_f64(t_s);
        let now = Instant::now();
        if due > now {
            // Sleeps, and returns an error on SIGINT/SIGTERM.
            if node.wait(due - now).is_err() {
                break;
            }
        } else if now - due > Duration::from_secs_f64(1.0 / a.rate_hz) {
            late += 1;
        }
        let current = schedule.step_at(t_s);
        if current != step {
            if let Some(i) = current {
                let (_, t_min_n) = schedule.steps()[i];
                setpoints += 1;
                input.send_t_min(&TminSetpoint::uniform(
                    setpoints,
                    monotonic_now_ns(),
                    t_min_n,
                ))?;
                println!("replay: t = {t_s:.3} s: T_min set-point {t_min_n} N");
            }
            step = current;
        }
        let Some(p) = trajectory.position_at(t_s) else {
            break;
        };
        let pose = PoseSample::new(
            k + 1,
            monotonic_now_ns(),
            [p.x, p.y, p.z],
            IDENTITY_QUATERNION,
        );
        input.send_pose(&pose)?;
        sent += 1;
        if k % 64 == 0 {
            // Delivers the T_min set-point in force to a service that (re)started since.
            input.update_connections();
        }
    }
    let elapsed = start.elapsed().as_secs_f64();
    println!(
        "replay: sent {sent} poses and {setpoints} T_min set-points in {elapsed:.2} s ({:.1} Hz); \
         {late} ticks more than one period late",
        sent as f64 / elapsed.max(1e-9)
    );
    Ok(())
}
