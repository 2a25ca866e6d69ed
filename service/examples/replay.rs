//! Replay publisher: sends end-effector poses to a running `cablevib serve` at a fixed rate —
//! the paper's circle (radius 0.75 m) by default, or a CSV file of `t,x,y,z` rows (s, m) — and
//! optionally a T_min schedule. With `--shape zv|zvd|ei` it shapes the poses online at the
//! end-effector mode of the latest ok estimate it receives (unshaped until the first one).
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
use cablevib::trajectory::shaping::ShaperKind;
use cablevib::trajectory::Trajectory;
use cablevib_ipc::{monotonic_now_ns, PoseSample, ServiceNames, TminSetpoint, IDENTITY_QUATERNION};
use cablevib_service::demo_shape::DemoShape;
use cablevib_service::ports::{create_node, EstimateOutput, PoseInput};
use cablevib_service::TminSchedule;
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
    /// Shape the poses online (zv, zvd or ei) at the end-effector mode frequency of the latest
    /// ok estimate the service publishes, with the scene's damping there; until the first
    /// estimate with an end-effector mode the poses pass unshaped.
    #[arg(long, value_name = "zv|zvd|ei", value_parser = parse_shaper)]
    shape: Option<ShaperKind>,
}

/// The shaper named by `--shape`.
fn parse_shaper(s: &str) -> Result<ShaperKind, String> {
    ShaperKind::from_name(s).ok_or_else(|| format!("unknown shaper {s:?}: zv, zvd or ei"))
}

/// Longest `--seconds`, s: a day of poses, far beyond any replay, keeps the pose count
/// (seconds × rate) and every due time representable (1e300 s would wrap the count to 0).
const MAX_SECONDS: f64 = 86_400.0;
/// Longest `--wait-for-service-s`, s: an hour is longer than any service start-up, and keeps
/// the deadline a representable `Duration`.
const MAX_WAIT_FOR_SERVICE_S: f64 = 3600.0;
/// Highest `--rate-hz`, Hz: well above the service's 1 kHz control rate.
const MAX_RATE_HZ: f64 = 100_000.0;

/// `--seconds` (or the file's duration, or 10 s) checked against [`MAX_SECONDS`].
fn checked_seconds(seconds: f64) -> anyhow::Result<f64> {
    if !(seconds.is_finite() && (0.0..=MAX_SECONDS).contains(&seconds)) {
        bail!("--seconds {seconds:?} must be in [0, {MAX_SECONDS}] s");
    }
    Ok(seconds)
}

/// `--wait-for-service-s` as a duration (negative: do not wait).
fn checked_wait(wait_s: f64) -> anyhow::Result<Duration> {
    if !(wait_s.is_finite() && wait_s <= MAX_WAIT_FOR_SERVICE_S) {
        bail!("--wait-for-service-s {wait_s:?} must be finite and ≤ {MAX_WAIT_FOR_SERVICE_S} s");
    }
    Duration::try_from_secs_f64(wait_s.max(0.0))
        .with_context(|| format!("--wait-for-service-s {wait_s:?}"))
}

/// The pose period of `--rate-hz`.
fn checked_period(rate_hz: f64) -> anyhow::Result<Duration> {
    if !(rate_hz.is_finite() && rate_hz > 0.0 && rate_hz <= MAX_RATE_HZ) {
        bail!("--rate-hz {rate_hz:?} must be in (0, {MAX_RATE_HZ}] Hz");
    }
    Duration::try_from_secs_f64(1.0 / rate_hz)
        .with_context(|| format!("--rate-hz {rate_hz:?}: its period is not a representable time"))
}

fn main() -> anyhow::Result<()> {
    default_sigpipe();
    let a = Args::parse();
    let period = checked_period(a.rate_hz)?;
    let wait_for_service = checked_wait(a.wait_for_service_s)?;
    if let Some(s) = a.seconds {
        checked_seconds(s)?;
    }
    let scene = cablevib::scene::Scene::load(&a.scene).context("loading the scene")?;
    let trajectory = match &a.csv {
        Some(path) => Trajectory::from_csv(path)?,
        None => Trajectory::circle(&scene, a.period_s)?,
    };
    let seconds = checked_seconds(a.seconds.or(trajectory.duration_s()).unwrap_or(10.0))?;
    let schedule = match &a.t_min {
        Some(s) => TminSchedule::parse(s)?,
        None => TminSchedule::default(),
    };

    let names = ServiceNames::new(&a.instance);
    let node = create_node("cablevib-replay")?;
    let input = PoseInput::open(&node, &names)?;
    let mut shape = match a.shape {
        Some(kind) => Some((
            DemoShape::new(kind, a.rate_hz, &scene)?,
            EstimateOutput::open(&node, &names)?,
        )),
        None => None,
    };
    let mut ee_mode_hz = f64::NAN;
    let wait_until = Instant::now() + wait_for_service;
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
        // t_s ≤ MAX_SECONDS: representable.
        let due = start + Duration::from_secs_f64(t_s);
        let now = Instant::now();
        if due > now {
            // Sleeps, and returns an error on SIGINT/SIGTERM.
            if node.wait(due - now).is_err() {
                break;
            }
        } else if now - due > period {
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
        let Some(mut p) = trajectory.position_at(t_s) else {
            break;
        };
        if let Some((shaper, estimates)) = &mut shape {
            // The latest ok estimate's end-effector mode (bounded: at most a queue's worth).
            for _ in 0..1024 {
                let Some(e) = estimates.try_receive()? else {
                    break;
                };
                if e.is_ok() && e.ee_mode_hz.is_finite() && e.ee_mode_hz > 0.0 {
                    ee_mode_hz = e.ee_mode_hz;
                }
            }
            p = shaper.push(p, ee_mode_hz);
        }
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
    if let Some((shaper, _)) = &shape {
        println!("replay: {}", shaper.summary_line().trim_start());
    }
    Ok(())
}

/// Restores the default action of SIGPIPE, as the `cablevib` binary does: `replay | head`
/// ends quietly instead of panicking in `println!`.
fn default_sigpipe() {
    // SAFETY: called first in main, before any thread exists; SIG_DFL is a valid disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hostile_durations_are_errors_not_panics() {
        let msg = checked_wait(1e300).unwrap_err().to_string();
        assert!(msg.contains("--wait-for-service-s 1e300 must be"), "{msg}");
        assert_eq!(checked_wait(-1.0).unwrap(), Duration::ZERO);
        assert_eq!(checked_wait(5.0).unwrap(), Duration::from_secs(5));
        let msg = checked_seconds(1e300).unwrap_err().to_string();
        assert!(msg.contains("--seconds 1e300 must be"), "{msg}");
        assert!(checked_seconds(f64::NAN).is_err());
        assert_eq!(checked_seconds(10.0).unwrap(), 10.0);
        assert!(checked_period(5e-324).is_err());
        assert!(checked_period(0.0).is_err());
        assert_eq!(checked_period(1000.0).unwrap(), Duration::from_millis(1));
    }
}
