//! Controller: takes every estimate of a running `cablevib serve`, asks for its vibration margin
//! after each one, and prints f1, the margin and latency percentiles at the end.
//!
//! ```text
//! cargo run --release -- serve --instance demo &
//! cargo run --release --example controller -- --instance demo --seconds 10 --required-hz 8 &
//! cargo run --release --example replay -- --instance demo --seconds 10
//! ```
//!
//! The loop is paced by the estimates (1 kHz when the replay publishes at 1 kHz). A real motion
//! controller publishes the pose at the start of its cycle and takes the estimate (or the
//! margin) before it commands the next set-point; the latency measured here, pose timestamp →
//! estimate received, is what that costs. Ctrl-C stops early.
//!
//! Before it takes an estimate it checks the estimate service's schema-version attribute
//! (`cablevib.schema_version`) and prints the service's attributes (scene, cable model, ...).
//!
//! An outage of the service (no estimate for `--outage-ms`) prints one line when it starts and
//! one when the estimates resume, with its duration; the summary counts the outages, the
//! longest and their total time ([`GapDetector`]).
//!
//! With `--hold-f1 HZ` it also acts on the margin: it asks for HZ + guard and publishes the
//! uniform T_min set-point [`F1Hold`] derives from each answer (the service's
//! `t_min_required_n`, raised at once, relaxed rate-limited above a hysteresis band, between
//! `--hold-floor-n` and `--hold-ceiling-n`; docs/service.md, "Holding f1"):
//!
//! ```text
//! cargo run --release --example controller -- --instance demo --seconds 10 \
//!     --hold-f1 9.5 --hold-floor-n 60 --hold-ceiling-n 350
//! ```

use std::time::{Duration, Instant};

use cablevib_ipc::{
    monotonic_now_ns, status_str, MarginRequest, MeasuredStatus, ServiceNames, TminSetpoint,
};
use cablevib_service::hold::{
    F1Hold, HoldAction, HoldInput, HoldParams, DEFAULT_GUARD_HZ, DEFAULT_RELAX_BAND_HZ,
    DEFAULT_RELAX_RATE_N_PER_S,
};
use cablevib_service::ports::{create_node, EstimateOutput, MarginClient, PoseInput};
use cablevib_service::stats::{GapDetector, GapEvent, SampleLog, StatusHistogram};
use cablevib_service::WaitMode;
use clap::Parser;

/// Default outage threshold, ms: 100 expected periods at the replay's 1 kHz, far above the
/// scheduling jitter of a loaded machine (a few ms), short enough that a controller notices a
/// dead service long before a human would.
const DEFAULT_OUTAGE_MS: f64 = 100.0;
/// Longest block waiting for an estimate: how late at most an outage's start is noticed.
const WAIT_SLICE: Duration = Duration::from_millis(10);

/// Take estimates and margins from a cablevib service.
#[derive(Debug, Parser)]
struct Args {
    /// Instance name, as given to `cablevib serve --instance` (empty: the bare service names).
    #[arg(long, default_value = "")]
    instance: String,
    /// How long to run, s.
    #[arg(long, default_value_t = 10.0)]
    seconds: f64,
    /// Required first natural frequency, Hz: margin = f1 − required.
    #[arg(long, default_value_t = 8.0)]
    required_hz: f64,
    /// event: block on the wake-controller event (no CPU while waiting); spin: busy-poll
    /// (lowest latency, but needs a CPU of its own besides the service's).
    #[arg(long, default_value_t = WaitMode::Event)]
    wait: WaitMode,
    /// Only take the estimates; do not query the margin.
    #[arg(long)]
    no_margin: bool,
    /// An outage is this long without an estimate, ms.
    #[arg(long, default_value_t = DEFAULT_OUTAGE_MS)]
    outage_ms: f64,
    /// Hold f1 at or above HZ: publish the T_min set-point the margin answers name (raised at
    /// once when f1 < HZ + guard, relaxed at --hold-relax-n-per-s when f1 ≥ HZ + relax band).
    /// The margin is then asked against HZ + guard instead of --required-hz. Needs
    /// --hold-floor-n and --hold-ceiling-n.
    #[arg(long, value_name = "HZ", conflicts_with = "no_margin")]
    hold_f1: Option<f64>,
    /// Lowest set-point the hold relaxes to, N: the scene's T_min.
    #[arg(long, value_name = "N", requires = "hold_f1")]
    hold_floor_n: Option<f64>,
    /// Highest set-point, N: the smallest t_max of the scene's cables (the service refuses a
    /// uniform set-point above any cable's t_max).
    #[arg(long, value_name = "N", requires = "hold_f1")]
    hold_ceiling_n: Option<f64>,
    /// Guard above HZ the hold raises to, Hz (covers f1's drift between two answers).
    #[arg(long, value_name = "HZ", default_value_t = DEFAULT_GUARD_HZ, requires = "hold_f1")]
    hold_guard_hz: f64,
    /// Relax only when f1 ≥ HZ + this, Hz (> the guard: the hysteresis band).
    #[arg(long, value_name = "HZ", default_value_t = DEFAULT_RELAX_BAND_HZ, requires = "hold_f1")]
    hold_relax_band_hz: f64,
    /// Largest decrease of the set-point per second, N/s.
    #[arg(long, value_name = "N_PER_S", default_value_t = DEFAULT_RELAX_RATE_N_PER_S, requires = "hold_f1")]
    hold_relax_n_per_s: f64,
}

/// The hold of `--hold-f1`, checked (one-line errors).
fn hold_params(a: &Args) -> anyhow::Result<Option<HoldParams>> {
    let Some(required_hz) = a.hold_f1 else {
        return Ok(None);
    };
    let (Some(floor_n), Some(ceiling_n)) = (a.hold_floor_n, a.hold_ceiling_n) else {
        anyhow::bail!(
            "--hold-f1 needs --hold-floor-n (the scene's T_min, N) and --hold-ceiling-n (the \
             smallest cable t_max, N)"
        );
    };
    let p = HoldParams {
        required_hz,
        guard_hz: a.hold_guard_hz,
        relax_band_hz: a.hold_relax_band_hz,
        relax_rate_n_per_s: a.hold_relax_n_per_s,
        floor_n,
        ceiling_n,
    };
    Ok(Some(p.checked()?))
}

/// `--hold-f1`: the hold, its T_min publisher and what it did.
struct Hold {
    hold: F1Hold,
    input: PoseInput,
    sequence: u64,
    /// The first answer that carried a T_min (controller's clock, ns): the count starts there.
    start_ns: Option<u64>,
    below: u64,
    counted: u64,
    setpoint_range: (f64, f64),
    actions: [u64; 7],
}

impl Hold {
    fn on_estimate(&mut self, e: &cablevib_ipc::EstimateSample) {
        if let Some(start) = self.start_ns {
            if e.is_ok() && e.receive_timestamp_ns > start {
                self.counted += 1;
                if e.f1_hz < self.hold.params().required_hz {
                    self.below += 1;
                }
            }
        }
    }

    fn on_answer(&mut self, r: &cablevib_ipc::MarginResponse) -> anyhow::Result<()> {
        let before = self.hold.setpoint_n();
        let action = self.hold.on_answer(&HoldInput::from(r));
        self.actions[action as usize] += 1;
        let now = self.hold.setpoint_n();
        if now != before {
            self.sequence += 1;
            let setpoint = TminSetpoint::uniform(self.sequence, monotonic_now_ns(), now);
            self.input.send_t_min(&setpoint)?;
            self.setpoint_range = (
                self.setpoint_range.0.min(now),
                self.setpoint_range.1.max(now),
            );
        }
        if action != HoldAction::NoAnswer && self.start_ns.is_none() {
            self.start_ns = Some(monotonic_now_ns());
        }
        Ok(())
    }
}

/// Longest `--seconds`, s: a day, far beyond any run, keeps the latency log's size finite.
const MAX_SECONDS: f64 = 86_400.0;
/// Most latency samples kept (800 MB); later ones are counted as dropped.
const MAX_LOGGED_SAMPLES: usize = 100_000_000;

fn main() -> anyhow::Result<()> {
    default_sigpipe();
    let a = Args::parse();
    anyhow::ensure!(
        a.seconds.is_finite() && a.seconds > 0.0 && a.seconds <= MAX_SECONDS,
        "--seconds {:?} must be in (0, {MAX_SECONDS}] s",
        a.seconds
    );
    anyhow::ensure!(
        a.outage_ms.is_finite() && a.outage_ms > 0.0,
        "--outage-ms must be finite and > 0"
    );
    let hold_params = hold_params(&a)?;
    let names = ServiceNames::new(&a.instance);
    let node = create_node("cablevib-controller")?;
    let estimates = EstimateOutput::open(&node, &names)?;
    let margin = MarginClient::open(&node, &names)?;
    let mut hold = match hold_params {
        Some(p) => Some(Hold {
            hold: F1Hold::new(p),
            input: PoseInput::open(&node, &names)?,
            sequence: 0,
            start_ns: None,
            below: 0,
            counted: 0,
            setpoint_range: (p.floor_n, p.floor_n),
            actions: [0; 7],
        }),
        None => None,
    };
    let required_hz = hold
        .as_ref()
        .map_or(a.required_hz, |h| h.hold.params().request_hz());
    // Whoever created the estimate service (usually `cablevib serve`) defined its schema
    // version as an attribute: refuse to talk across schemas, and say what the service runs.
    let attributes = estimates.attributes();
    attributes.check_schema(&names.estimate, true)?;
    println!(
        "controller: taking estimates from \"{}\" for {} s (wait {}), margin against {} Hz",
        names.estimate, a.seconds, a.wait, required_hz
    );
    if let Some(h) = &hold {
        let p = h.hold.params();
        println!(
            "controller: holding f1 ≥ {} Hz: T_min raised at once below {} Hz, relaxed at ≤ {} \
             N/s above {} Hz, within [{}, {}] N",
            p.required_hz,
            p.request_hz(),
            p.relax_rate_n_per_s,
            p.required_hz + p.relax_band_hz,
            p.floor_n,
            p.ceiling_n
        );
    }
    println!("controller: service attributes: {attributes}");

    let capacity = ((a.seconds * 20_000.0) as usize + 1000).min(MAX_LOGGED_SAMPLES);
    let mut latency = SampleLog::with_capacity(capacity);
    let mut margin_rtt = SampleLog::with_capacity(capacity);
    let mut status_counts = StatusHistogram::default();
    let (mut f1_min, mut f1_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut worst_margin = f64::INFINITY;
    let (mut stale, mut last_sequence, mut unanswered) = (0u64, 0u64, 0u64);
    let mut request_sequence = 0u64;
    let mut outages = GapDetector::new((a.outage_ms * 1e6) as u64);
    let start = Instant::now();
    let mut next_print = 1.0;
    // `node.wait(0)` does not sleep; it returns an error after SIGINT/SIGTERM.
    while node.wait(Duration::ZERO).is_ok() && start.elapsed().as_secs_f64() < a.seconds {
        let Some(e) = estimates.wait(a.wait, WAIT_SLICE)? else {
            if let Some(GapEvent::Started { silent_ns }) = outages.poll(monotonic_now_ns()) {
                println!(
                    "controller: t = {:.3} s  no estimate for {:.1} ms: service outage",
                    start.elapsed().as_secs_f64(),
                    silent_ns as f64 * 1e-6
                );
            }
            continue;
        };
        let now_ns = monotonic_now_ns();
        if let Some(GapEvent::Ended { duration_ns }) = outages.on_message(now_ns) {
            println!(
                "controller: t = {:.3} s  estimates resumed after {:.1} ms without one",
                start.elapsed().as_secs_f64(),
                duration_ns as f64 * 1e-6
            );
        }
        latency.push(now_ns.saturating_sub(e.pose_timestamp_ns));
        if e.pose_sequence <= last_sequence {
            stale += 1; // the replay restarted, or an old estimate
        }
        last_sequence = e.pose_sequence;
        status_counts.record_wire(e.status);
        if let Some(h) = &mut hold {
            h.on_estimate(&e);
        }
        if e.is_ok() {
            f1_min = f1_min.min(e.f1_hz);
            f1_max = f1_max.max(e.f1_hz);
        }
        let (mut margin_hz, mut margin_pose) = (f64::NAN, 0);
        if !a.no_margin {
            request_sequence += 1;
            let t0 = monotonic_now_ns();
            let request = MarginRequest::new(request_sequence, t0, required_hz);
            match margin.query(&request, a.wait, Duration::from_millis(5))? {
                Some(r) => {
                    margin_rtt.push(monotonic_now_ns().saturating_sub(t0));
                    margin_pose = r.pose_sequence;
                    if r.is_ok() {
                        margin_hz = r.margin_hz;
                        worst_margin = worst_margin.min(r.margin_hz);
                    }
                    if let Some(h) = &mut hold {
                        h.on_answer(&r)?;
                    }
                }
                None => unanswered += 1,
            }
        }
        let t = start.elapsed().as_secs_f64();
        if t >= next_print {
            println!(
                "controller: t = {t:.1} s  pose {}  status {}  f1 {:.4} Hz  margin {:+.4} Hz \
                 (latest pose {margin_pose})",
                e.pose_sequence,
                status_str(e.status),
                e.f1_hz,
                margin_hz
            );
            if e.vibration_samples > 0 {
                let measured_status_str =
                    |c: u32| MeasuredStatus::from_u32(c).map_or("unknown", MeasuredStatus::as_str);
                println!(
                    "controller:   measured: near f1 {:.3} Hz ({}), end-effector mode {:.3} Hz \
                     ({}, model {:.3} Hz); vibration samples {} taken, {} refused, {} lost",
                    e.measured_f1_hz,
                    measured_status_str(e.measured_f1_status),
                    e.measured_ee_mode_hz,
                    measured_status_str(e.measured_ee_mode_status),
                    e.ee_mode_hz,
                    e.vibration_samples,
                    e.vibration_refused,
                    e.vibration_lost
                );
            }
            if let Some(h) = &hold {
                println!("controller: T_min set-point {:.3} N", h.hold.setpoint_n());
            }
            next_print += 1.0;
        }
    }

    outages.finish(monotonic_now_ns());
    println!("controller: {} estimates", latency.len());
    println!(
        "  outages (no estimate for {} ms or more): {}, longest {:.1} ms, total {:.1} ms",
        a.outage_ms,
        outages.outages(),
        outages.longest_ns() as f64 * 1e-6,
        outages.total_ns() as f64 * 1e-6
    );
    if f1_min.is_finite() {
        println!("  f1: {f1_min:.4} … {f1_max:.4} Hz");
    }
    if worst_margin.is_finite() {
        println!("  worst margin against {required_hz} Hz: {worst_margin:+.4} Hz");
    }
    println!("  statuses: {}", status_counts.summary());
    println!(
        "  latency pose timestamp → estimate received: {}",
        latency.percentiles().display_us()
    );
    if !a.no_margin {
        println!(
            "  margin query round trip: {} ({unanswered} unanswered within 5 ms)",
            margin_rtt.percentiles().display_us()
        );
    }
    if let Some(h) = &hold {
        println!(
            "  hold f1 ≥ {} Hz: {} set-points ({:.2}..{:.2} N; actions {}); ok estimates below \
             {} Hz after the first answer: {} of {}",
            h.hold.params().required_hz,
            h.sequence,
            h.setpoint_range.0,
            h.setpoint_range.1,
            HoldAction::summary(&h.actions),
            h.hold.params().required_hz,
            h.below,
            h.counted
        );
    }
    if stale > 0 {
        println!("  {stale} estimates did not advance the pose sequence");
    }
    Ok(())
}

/// Restores the default action of SIGPIPE, as the `cablevib` binary does: `controller | head`
/// ends quietly instead of panicking in `println!`.
fn default_sigpipe() {
    // SAFETY: called first in main, before any thread exists; SIG_DFL is a valid disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
