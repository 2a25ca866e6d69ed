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

use std::time::{Duration, Instant};

use cablevib_ipc::{monotonic_now_ns, status_str, MarginRequest, ServiceNames};
use cablevib_service::ports::{create_node, EstimateOutput, MarginClient};
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
    #[arg(long, value_enum, default_value_t = WaitMode::Event)]
    wait: WaitMode,
    /// Only take the estimates; do not query the margin.
    #[arg(long)]
    no_margin: bool,
    /// An outage is this long without an estimate, ms.
    #[arg(long, default_value_t = DEFAULT_OUTAGE_MS)]
    outage_ms: f64,
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
    let names = ServiceNames::new(&a.instance);
    let node = create_node("cablevib-controller")?;
    let estimates = EstimateOutput::open(&node, &names)?;
    let margin = MarginClient::open(&node, &names)?;
    // Whoever created the estimate service (usually `cablevib serve`) defined its schema
    // version as an attribute: refuse to talk across schemas, and say what the service runs.
    let attributes = estimates.attributes();
    attributes.check_schema(&names.estimate, true)?;
    println!(
        "controller: taking estimates from \"{}\" for {} s (wait {}), margin against {} Hz",
        names.estimate, a.seconds, a.wait, a.required_hz
    );
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
        if e.is_ok() {
            f1_min = f1_min.min(e.f1_hz);
            f1_max = f1_max.max(e.f1_hz);
        }
        let (mut margin_hz, mut margin_pose) = (f64::NAN, 0);
        if !a.no_margin {
            request_sequence += 1;
            let t0 = monotonic_now_ns();
            let request = MarginRequest::new(request_sequence, t0, a.required_hz);
            match margin.query(&request, a.wait, Duration::from_millis(5))? {
                Some(r) => {
                    margin_rtt.push(monotonic_now_ns().saturating_sub(t0));
                    margin_pose = r.pose_sequence;
                    if r.is_ok() {
                        margin_hz = r.margin_hz;
                        worst_margin = worst_margin.min(r.margin_hz);
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
        println!(
            "  worst margin against {} Hz: {worst_margin:+.4} Hz",
            a.required_hz
        );
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
