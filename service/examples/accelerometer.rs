//! Accelerometer publisher: sends `VibrationSample`s to a running `cablevib serve` at a fixed
//! rate, the way a driver of a sensor on the platform would. The signal is synthetic: sines
//! at `--sine-hz` (amplitude `--amplitude-m-s2` each, on the x axis), gravity on z and white
//! noise of `--noise-m-s2` on every axis; replace `sample` with the sensor's reading.
//!
//! ```text
//! cargo run --release -- serve --instance demo &
//! cargo run --release --example replay -- --instance demo --seconds 10 &
//! cargo run --release --example accelerometer -- --instance demo --seconds 10 --sine-hz 29.4
//! ```
//!
//! Each sample carries its sequence number (1, 2, ...: a gap is a lost sample) and the
//! `CLOCK_MONOTONIC` time it was taken, here the time it was due, so the service learns the
//! sample period from the timestamps. The service measures the dominant frequencies near the
//! model's f1 and end-effector mode and publishes them in every estimate (the controller
//! example prints them). No wake-up is notified: the service takes the samples whenever it
//! wakes (at least every 50 ms). Ctrl-C stops early.

use std::time::Duration;

use anyhow::{bail, Context};
use cablevib::rng::SplitMix64;
use cablevib_ipc::{monotonic_now_ns, ServiceNames, VibrationSample};
use cablevib_service::ports::{create_node, open_pubsub, VIBRATION_SETTINGS};
use clap::Parser;

/// Publish accelerometer samples to a cablevib service.
#[derive(Debug, Parser)]
struct Args {
    /// Instance name, as given to `cablevib serve --instance` (empty: the bare service names).
    #[arg(long, default_value = "")]
    instance: String,
    /// Sample rate, Hz, in [10, 4000] (the service's tracker takes up to 4 kHz).
    #[arg(long, default_value_t = 1000.0)]
    rate_hz: f64,
    /// How long to publish, s, in [0, 86400].
    #[arg(long, default_value_t = 10.0)]
    seconds: f64,
    /// Frequencies of the sines on x, Hz (comma-separated), each below half the rate.
    #[arg(long, value_delimiter = ',', default_value = "29.4")]
    sine_hz: Vec<f64>,
    /// Amplitude of each sine, m/s², in [0, 1000].
    #[arg(long, default_value_t = 1.0)]
    amplitude_m_s2: f64,
    /// Standard deviation of the white noise on each axis, m/s², in [0, 1000].
    #[arg(long, default_value_t = 0.02)]
    noise_m_s2: f64,
}

/// Checks every option against its documented range.
fn check(a: &Args) -> anyhow::Result<()> {
    let within = |name: &str, v: f64, lo: f64, hi: f64| {
        if !(v.is_finite() && (lo..=hi).contains(&v)) {
            bail!("--{name} {v:?} must be in [{lo}, {hi}]");
        }
        Ok(())
    };
    within("rate-hz", a.rate_hz, 10.0, 4000.0)?;
    within("seconds", a.seconds, 0.0, 86_400.0)?;
    within("amplitude-m-s2", a.amplitude_m_s2, 0.0, 1000.0)?;
    within("noise-m-s2", a.noise_m_s2, 0.0, 1000.0)?;
    for &f in &a.sine_hz {
        within("sine-hz", f, 0.0, 0.5 * a.rate_hz)?;
    }
    Ok(())
}

/// The reading at `t_s`: the sines on x, gravity on z, noise on every axis, m/s².
fn sample(a: &Args, t_s: f64, rng: &mut SplitMix64) -> [f64; 3] {
    let sines: f64 = a
        .sine_hz
        .iter()
        .map(|f| a.amplitude_m_s2 * (2.0 * core::f64::consts::PI * f * t_s).sin())
        .sum();
    [
        sines + a.noise_m_s2 * rng.normal(),
        a.noise_m_s2 * rng.normal(),
        9.81 + a.noise_m_s2 * rng.normal(),
    ]
}

fn main() -> anyhow::Result<()> {
    let a = Args::parse();
    check(&a)?;
    let names = ServiceNames::new(&a.instance);
    let node = create_node("cablevib-example-accelerometer").context("iceoryx2 node")?;
    let publisher = open_pubsub::<VibrationSample>(&node, &names.vibration, VIBRATION_SETTINGS)
        .context("the vibration service")?
        .publisher_builder()
        .create()
        .map_err(|e| anyhow::anyhow!("the vibration publisher: {e:?}"))?;
    let period_ns = (1e9 / a.rate_hz).round() as u64;
    let count = (a.seconds * a.rate_hz).round() as u64;
    let mut rng = SplitMix64(1);
    let start_ns = monotonic_now_ns();
    let mut sent = 0u64;
    for k in 0..count {
        let due_ns = start_ns + k * period_ns;
        loop {
            let now = monotonic_now_ns();
            if now >= due_ns {
                break;
            }
            // Ctrl-C: iceoryx2's handler makes the node's wait fail.
            if node
                .wait(Duration::from_nanos((due_ns - now).min(200_000)))
                .is_err()
            {
                println!("interrupted after {sent} samples");
                return Ok(());
            }
        }
        let x = sample(&a, k as f64 * period_ns as f64 * 1e-9, &mut rng);
        publisher
            .send_copy(VibrationSample::acceleration(k + 1, due_ns, x))
            .map_err(|e| anyhow::anyhow!("send sample {}: {e:?}", k + 1))?;
        sent += 1;
    }
    println!(
        "sent {sent} samples at {} Hz on {}",
        a.rate_hz, names.vibration
    );
    Ok(())
}
